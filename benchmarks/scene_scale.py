"""Scenes at scale around the Panda's arm (example-robot-data, its SRDF's ``arm`` group):
boxes by the thousand within its reach, a 2-million-triangle mesh and a 100,000-point
cloud (each a 1 m x 1 m wall 0.3 m in front of it, which the arm's swing from joint 1 at
-1.2 rad to +1.2 rad crosses). Prints and writes: the seconds to add each to a Scene, to
build the robot's checker of it, and a plan around it (``time_limit`` 10 s; 3 s for
20,000 boxes, the checker built within the plan's limit or the plan stopped at it, saying
so).

    python benchmarks/scene_scale.py [--json toolkit/report/scene_scale_benchmark.json]
"""

from __future__ import annotations

import argparse
import struct
import tempfile
import time
from pathlib import Path

import numpy as np

import toolkit

try:  # run as a script (python benchmarks/scene_scale.py) or from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def boxes(n: int) -> toolkit.Scene:
    """``n`` 1 cm boxes within the arm's reach, 0.6-1.1 m from its axis."""
    rng = np.random.default_rng(0)
    scene = toolkit.Scene()
    for i in range(n):
        angle, radius, z = rng.uniform(-np.pi, np.pi), rng.uniform(0.6, 1.1), rng.uniform(0, 1)
        scene.add_box(f"b{i}", [0.01] * 3, [radius * np.cos(angle), radius * np.sin(angle), z])
    return scene


def wall_stl(path: Path, triangles: int) -> int:
    """A binary STL of a 1 m x 1 m wall at x = 0.3 m of about ``triangles`` triangles."""
    m = int(np.sqrt(triangles / 2))
    Y, Z = np.meshgrid(np.linspace(-0.5, 0.5, m + 1), np.linspace(0.0, 1.0, m + 1))
    V = np.stack([np.full_like(Y, 0.3), Y, Z], -1)
    a, b, c, d = V[:-1, :-1], V[:-1, 1:], V[1:, :-1], V[1:, 1:]
    T = np.concatenate([np.stack([a, b, d], -2).reshape(-1, 3, 3),
                        np.stack([a, d, c], -2).reshape(-1, 3, 3)])  # fmt: skip
    rec = np.zeros(len(T), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["v"] = T
    path.write_bytes(b"\0" * 80 + struct.pack("<I", len(T)) + rec.tobytes())
    return len(T)


def measure(arm: toolkit.Robot, build, start, goal, limit: float) -> dict:
    """Seconds to add the objects, to build the checker, and the plan's figures."""
    t0 = time.perf_counter()
    scene = build()
    added = time.perf_counter() - t0
    row: dict = {"objects": len(scene), "add_s": added}
    if limit >= 5.0:  # the checker alone (kept on the robot: the plan reuses it)
        t0 = time.perf_counter()
        arm.collision_checker(scene)
        row["checker_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    result = arm.plan(start, goal, scene=scene, time_limit=limit, seed=0)
    row.update(plan_s=time.perf_counter() - t0, success=result.success, reason=result.reason,
               certificate=result.certificate, time_limit=limit)  # fmt: skip
    print(f"{row['objects']:>6} objects: add {added:.2f} s, checker "
          f"{row.get('checker_s', float('nan')):.2f} s, plan {row['plan_s']:.3f} s "
          f"({result.reason}; {result.certificate or 'none'})", flush=True)  # fmt: skip
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args, info = begin(parser)
    toolkit.warmup()  # compiled before any clock
    arm = toolkit.load_example("panda").group("arm")
    start = arm.states["default"].copy()
    start[0] = -1.2
    goal = start.copy()
    goal[0] = 1.2
    arm.plan(start, goal, time_limit=5.0)  # the robot's own covers and reach, made once
    figures: dict[str, object] = {}
    for n in (500, 1000, 2000, 5000):
        figures[f"boxes_{n}"] = measure(arm, lambda n=n: boxes(n), start, goal, 10.0)
    figures["boxes_20000"] = measure(arm, lambda: boxes(20_000), start, goal, 3.0)
    with tempfile.TemporaryDirectory() as work:
        stl = Path(work) / "wall.stl"
        triangles = wall_stl(stl, 2_000_000)
        row = measure(arm, lambda: toolkit.Scene().add_mesh("wall", stl), start, goal, 10.0)
        figures["mesh"] = {**row, "triangles": triangles}
    rng = np.random.default_rng(0)
    n = 100_000
    cloud = np.column_stack([0.3 + rng.normal(0.0, 0.005, n), rng.uniform(-0.5, 0.5, n),
                             rng.uniform(0.0, 1.0, n)])  # fmt: skip
    row = measure(arm, lambda: toolkit.Scene().add_points("cloud", cloud, 0.01), start, goal, 10.0)
    figures["cloud"] = {**row, "points": len(cloud)}
    write_json(args.json, {**info, **figures})


if __name__ == "__main__":
    main()
