"""mplib's planner (its OMPL RRT-Connect on FCL and the robot's meshes) on one robot,
problem after problem, in mplib's own environment (mplib pins numpy < 2: a virtual
environment of its own, ``pip install mplib "numpy<2" pyyaml trimesh``), driven by
``benchmarks/planning_corpus.py --mplib PYTHON``. This file imports neither the toolkit nor
anything of the benchmarks: it reads JSON lines on its standard input and answers one JSON
line each.

The first line names the robot: ``{"urdf": path, "srdf": path, "move_group": link}``; the
answer is ``{"joints": [name, ...]}`` (the order of mplib's configurations) or
``{"error": why}``. mplib's mesh loader refuses a face with two vertices (MBM's Panda OBJ
files have them): where it refuses a mesh, every OBJ mesh of the description is read by
trimesh and written again as STL into a temporary folder, and the URDF read from a copy
naming those. Each next line is a problem: ``{"scene": path of a MoveIt scene YAML,
"start": q, "goal": q}``; the answer ``{"path": [q, ...] or null, "seconds": float}``: the
wall time of ``planner.planner.plan`` (RRT-Connect and its simplification: what
``Planner.plan_qpos`` calls before its time parameterization, which is left out), with
``plan_qpos``'s default range of 0.1 and a time limit of 10 s.
"""

from __future__ import annotations

import json
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from mplib import Planner, Pose
from mplib.collision_detection import fcl

RANGE = 0.1  # Planner.plan_qpos's default rrt_range
LIMIT = 10.0  # [s]


def _pose(item: dict | None) -> np.ndarray:
    """A MoveIt pose written as lists (position; orientation x, y, z, w) as a 4x4 matrix."""
    T = np.eye(4)
    if item is None:
        return T
    x, y, z, w = (float(v) for v in item["orientation"])
    n = x * x + y * y + z * z + w * w
    s = 2.0 / n
    T[:3, :3] = [[1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
                 [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
                 [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)]]  # fmt: skip
    T[:3, 3] = [float(v) for v in item["position"]]
    return T


def _shape(kind: object, dims: list[float]):
    if kind in ("box", 1):
        return fcl.Box(np.array(dims[:3]))
    if kind in ("sphere", 2):
        return fcl.Sphere(dims[0])
    if kind in ("cylinder", 3):  # MoveIt: (height, radius)
        return fcl.Cylinder(dims[1], dims[0])
    raise ValueError(f"mplib_worker: no primitive {kind!r}")


def _objects(path: str) -> list:
    """The scene file's boxes, cylinders and spheres as mplib's objects (the object's pose
    times each primitive's)."""
    with open(path, encoding="utf-8") as f:
        data = yaml.safe_load(f)
    world = data.get("world") or data.get("planning_scene_world") or {}
    out = []
    for co in world.get("collision_objects") or []:
        base = _pose(co.get("pose"))
        shapes, poses = [], []
        for prim, pose in zip(co["primitives"], co["primitive_poses"], strict=True):
            shapes.append(fcl.CollisionObject(_shape(prim["type"], prim["dimensions"])))
            poses.append(Pose(base @ _pose(pose)))
        out.append(fcl.FCLObject(co["id"], Pose(), shapes, poses))
    return out


def _reexported(urdf: Path, work: Path) -> Path:
    """A copy of ``urdf`` whose OBJ meshes are read by trimesh and written as STL in
    ``work`` (mplib then loads them: a two-vertex face is gone)."""
    import trimesh

    text = urdf.read_text()
    for name in sorted(set(re.findall(r'filename="([^"]+\.obj)"', text))):
        source = urdf.parent / name.removeprefix("package://")
        target = work / (name.removeprefix("package://").replace("/", "_")[:-4] + ".stl")
        trimesh.load(source, force="mesh").export(target)
        text = text.replace(f'filename="{name}"', f'filename="{target.name}"')
    copy = work / urdf.name
    copy.write_text(text)
    for item in urdf.parent.iterdir():  # the description's other files, where it names them
        if not (work / item.name).exists():
            (work / item.name).symlink_to(item)
    return copy


def _planner(first: dict, work: Path) -> Planner:
    urdf, srdf = Path(first["urdf"]), first["srdf"]
    try:
        return Planner(str(urdf), first["move_group"], srdf=srdf)
    except ValueError:  # a mesh mplib refuses
        return Planner(str(_reexported(urdf, work)), first["move_group"], srdf=srdf)


def _answers():
    """The driver's channel: this process's standard output as it was; everything else
    printed from here on (mplib prints "invalid start state" to standard output) goes to
    standard error, where it cannot break the JSON lines."""
    import os

    channel = os.fdopen(os.dup(1), "w")
    sys.stdout.flush()
    os.dup2(2, 1)
    return channel


def main() -> None:
    answers = _answers()
    first = json.loads(sys.stdin.readline())
    with tempfile.TemporaryDirectory() as work:
        try:
            planner = _planner(first, Path(work))
        except Exception as error:  # said to the driver, which goes on
            print(json.dumps({"error": f"{type(error).__name__}: {error}"}), file=answers,
                  flush=True)  # fmt: skip
            return
        names = list(planner.user_joint_names)
        group = [names[i] for i in planner.move_group_joint_indices]
        print(json.dumps({"joints": group}), file=answers, flush=True)
        world = planner.planning_world
        for line in sys.stdin:
            ask = json.loads(line)
            for name in world.get_object_names():
                world.remove_object(name)
            for obj in _objects(ask["scene"]):
                world.add_object(obj)
            # MBM's Fetch goals put wrist_roll at pi, 2.7e-6 rad past the URDF's limit:
            # brought onto it (mplib calls such a start invalid), as the toolkit does
            limits = planner.joint_limits[planner.move_group_joint_indices]
            start = np.clip(ask["start"], limits[:, 0], limits[:, 1])
            goal = np.clip(ask["goal"], limits[:, 0], limits[:, 1])
            full = np.zeros(len(names))
            full[planner.move_group_joint_indices] = start
            planner.robot.set_qpos(full, True)  # the joints it does not plan at zero
            t0 = time.perf_counter()
            status, path = planner.planner.plan(start, [goal], time=LIMIT, range=RANGE)
            seconds = time.perf_counter() - t0
            found = status.startswith("Exact solution") and len(path)
            print(json.dumps({"path": np.asarray(path).tolist() if found else None,
                              "seconds": seconds, "status": status}), file=answers,
                  flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
