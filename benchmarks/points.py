"""Point clouds as obstacles (``Scene.add_points``): the UR5 against a wall of random points
in front of it, checked in batches, beside a box of the same extent (the cells' box) and,
for the agreement, the same cells added as boxes. Prints its figures (best of three for
the rates); nothing is asserted.

    python benchmarks/points.py [--n 5000] [--points 20000] [--json out.json]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import toolkit
from toolkit import Scene

try:  # run as a script (python benchmarks/points.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json

RESOLUTION = 0.02
"""[m] The cloud's cell edge."""


def _rate(robot: toolkit.Robot, Q: np.ndarray, scene: Scene) -> tuple[float, np.ndarray]:
    """(configurations/s, best of three; the flags)."""
    robot.in_collision(Q[:50], scene)  # the checker built and its kernels loaded
    best, flags = float("inf"), np.zeros(0, bool)
    for _ in range(3):
        t0 = time.perf_counter()
        flags = np.asarray(robot.in_collision(Q, scene), dtype=bool)
        best = min(best, time.perf_counter() - t0)
    return len(Q) / best, flags


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=5_000, help="configurations")
    parser.add_argument("--points", type=int, default=20_000)
    args, info = begin(parser)
    ur5 = toolkit.load_example("ur5")
    rng = np.random.default_rng(0)
    low, high = np.array([0.35, -0.4, 0.0]), np.array([0.37, 0.4, 0.9])
    wall = rng.uniform(low, high, (args.points, 3))
    cloud = Scene().add_points("wall", wall, RESOLUTION)
    keys = np.unique(np.floor(wall / RESOLUTION).astype(np.int64), axis=0)
    lo, hi = keys.min(axis=0) * RESOLUTION, (keys.max(axis=0) + 1) * RESOLUTION
    box = Scene().add_box("wall", hi - lo, (hi + lo) / 2)
    Q = ur5.random_q(args.n, seed=1)
    t0 = time.perf_counter()
    cloud.objects[0].shape()
    build = time.perf_counter() - t0
    cloud_rate, hits = _rate(ur5, Q, cloud)
    box_rate, box_hits = _rate(ur5, Q, box)
    cells = Scene()
    for i, k in enumerate(keys):
        cells.add_box(f"cell{i}", [RESOLUTION] * 3, (k + 0.5) * RESOLUTION)
    few = Q[: min(len(Q), 500)]
    same = int((np.asarray(ur5.in_collision(few, cells), dtype=bool) == hits[: len(few)]).sum())
    print(
        f"UR5 against a wall of {args.points:,} points ({len(keys):,} cells of "
        f"{RESOLUTION * 100:g} cm; octree built in {build * 1e3:.1f} ms), {args.n:,} "
        f"configurations: {cloud_rate:,.0f}/s ({hits.mean():.1%} colliding); a box of the "
        f"cells' extent {box_rate:,.0f}/s ({box_hits.mean():.1%}); the same answer as the "
        f"cells added as {len(keys):,} boxes on {same} of {len(few)}"
    )
    write_json(args.json, {**info, "points": args.points, "cells": len(keys),
                           "resolution": RESOLUTION, "configurations": args.n,
                           "octree_build_s": build, "cloud_per_s": cloud_rate,
                           "box_per_s": box_rate, "cloud_colliding": float(hits.mean()),
                           "box_colliding": float(box_hits.mean()),
                           "cells_compared": len(few), "same_as_cells": same})  # fmt: skip


if __name__ == "__main__":
    main()
