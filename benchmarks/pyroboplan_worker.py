"""pyroboplan's RRT-Connect on one robot, problem after problem, in pyroboplan's own
environment (it pins a Pinocchio older than the toolkit's, so it runs in a virtual
environment of its own, driven by ``benchmarks/planning_mbm.py --pyroboplan PYTHON``).
This file imports neither the toolkit nor anything of the benchmarks: it reads JSON lines
on its standard input and answers one JSON line each.

The first line names the robot: ``{"urdf": path, "packages": [folder, ...], "srdf": path}``
(Pinocchio's models from the URDF, every pair of collision shapes checked but those the
SRDF disables, as pyroboplan's examples do). Each next line is a problem: ``{"objects":
[{"kind": "box" | "sphere" | "cylinder", "size": [...], "pose": 16 row-major floats}, ...],
"start": q, "goal": q, "held": [q index, ...], "limit": seconds, "seed": int}``; the held
joints stay at the start's values (their limits closed there). The answer: ``{"path": [q,
...] or null, "seconds": float, "ends_collide": [start, goal]}``: the time of
``RRTPlanner.plan`` (bidirectional RRT-Connect, pyroboplan's default edge step of 0.05 rad)
and ``shortcut_path`` (its default 100 tries) together, and whether pyroboplan's own check
finds the start and the goal colliding (asked after the clock).
"""

from __future__ import annotations

import json
import sys
import time

import coal
import numpy as np
import pinocchio as pin
from pyroboplan.core.utils import check_collisions_at_state
from pyroboplan.planning.path_shortcutting import shortcut_path
from pyroboplan.planning.rrt import RRTPlanner, RRTPlannerOptions


def _robot(line: dict) -> tuple[pin.Model, pin.GeometryModel]:
    model, collision, _ = pin.buildModelsFromUrdf(line["urdf"], package_dirs=line["packages"])
    collision.addAllCollisionPairs()
    pin.removeCollisionPairs(model, collision, line["srdf"])
    return model, collision


def _shape(obj: dict) -> coal.CollisionGeometry:
    size = obj["size"]
    if obj["kind"] == "box":
        return coal.Box(*size)
    if obj["kind"] == "sphere":
        return coal.Sphere(size[0])
    if obj["kind"] == "cylinder":
        return coal.Cylinder(size[0], size[1])
    raise ValueError(f"pyroboplan_worker: no shape for a {obj['kind']!r}")


def _with_objects(model: pin.Model, robot: pin.GeometryModel, objects: list) -> pin.GeometryModel:
    """A copy of the robot's collision model with the scene's objects, each paired with
    every robot shape."""
    geom = robot.copy()
    shapes = geom.ngeoms
    for i, obj in enumerate(objects):
        pose = np.array(obj["pose"], dtype=float).reshape(4, 4)
        placement = pin.SE3(pose[:3, :3], pose[:3, 3])
        k = geom.addGeometryObject(pin.GeometryObject(f"obstacle_{i}", 0, 0, placement,
                                                      _shape(obj)))  # fmt: skip
        for g in range(shapes):
            geom.addCollisionPair(pin.CollisionPair(g, k))
    return geom


def main() -> None:
    answers, sys.stdout = sys.stdout, sys.stderr  # pyroboplan's own prints: on stderr
    model, robot = _robot(json.loads(sys.stdin.readline()))
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    for line in sys.stdin:
        problem = json.loads(line)
        start, goal = np.array(problem["start"]), np.array(problem["goal"])
        model.lowerPositionLimit, model.upperPositionLimit = lower.copy(), upper.copy()
        for c in problem["held"]:
            model.lowerPositionLimit[c] = model.upperPositionLimit[c] = start[c]
        geom = _with_objects(model, robot, problem["objects"])
        options = RRTPlannerOptions(rrt_connect=True, bidirectional_rrt=True,
                                    max_planning_time=problem["limit"],
                                    rng_seed=problem["seed"])  # fmt: skip
        t0 = time.perf_counter()
        path = RRTPlanner(model, geom, options).plan(start, goal)
        if path is not None and len(path):  # out of time: an empty path
            path = shortcut_path(model, geom, path)
        else:
            path = None
        seconds = time.perf_counter() - t0
        out = None if path is None else [list(map(float, q)) for q in path]
        ends = [bool(check_collisions_at_state(model, geom, q)) for q in (start, goal)]
        print(json.dumps({"path": out, "seconds": seconds, "ends_collide": ends}), file=answers,
              flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
