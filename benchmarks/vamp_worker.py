"""VAMP's RRT-Connect and its simplification on one robot, problem after problem, in VAMP's
own environment (built from its source: ``../shared/bench/build-vamp.sh``), driven by
``benchmarks/planning_corpus.py --vamp PYTHON``. This file imports neither the toolkit nor
anything of the benchmarks: it reads JSON lines on its standard input and answers one JSON
line each.

The first line names the robot: ``{"robot": "panda" | "ur5" | "fetch" | "baxter"}``; the
answer is ``{"joints": [name, ...]}``, the order of VAMP's configurations. Each next line
is a problem: ``{"scene": path of a MoveIt scene YAML, "scenario": its MBM scenario's short
name, "start": q, "goal": q}``, q in VAMP's joint order. The answer: ``{"path": [q, ...] or
null, "seconds": float, "plan_ns": int, "simplify_ns": int}``: the wall time of the
planner's and the simplifier's calls together, as a user calls them from Python, and
VAMP's own counts of each. The scene's boxes, cylinders and spheres become VAMP's
primitives through its ``problem_dict_to_vamp`` (as its MotionBenchMaker evaluation
builds them; a cylinder of the ``box`` scenario as a box about it).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
import vamp
import yaml
from vamp.transformations import euler_from_matrix, quaternion_matrix


def _pose(item: dict | None) -> np.ndarray:
    """A MoveIt pose (position, orientation as x, y, z, w) as a 4x4 matrix."""
    T = np.eye(4)
    if item is None:
        return T
    o = item.get("orientation", {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0})
    q = [o["x"], o["y"], o["z"], o["w"]] if isinstance(o, dict) else list(o)
    T = quaternion_matrix(q)  # x, y, z, w: VAMP's transformations take that order
    p = item.get("position", {"x": 0.0, "y": 0.0, "z": 0.0})
    T[:3, 3] = [p["x"], p["y"], p["z"]] if isinstance(p, dict) else list(p)
    return T


def _problem(path: str, scenario: str) -> dict:
    """The scene file's primitives as ``problem_dict_to_vamp`` takes them."""
    with open(path, encoding="utf-8") as f:
        data = yaml.safe_load(f)
    world = data.get("world") or data.get("planning_scene_world") or {}
    out: dict = {"sphere": [], "cylinder": [], "box": [], "problem": scenario}
    for co in world.get("collision_objects", []):
        for k, prim in enumerate(co.get("primitives", [])):
            T = _pose(co.get("pose")) @ _pose(co["primitive_poses"][k])
            kind = {1: "box", 2: "sphere", 3: "cylinder"}.get(prim["type"], prim["type"])
            dims = [float(x) for x in prim["dimensions"]]
            obj = {"name": f"{co['id']}_{k}", "position": T[:3, 3].tolist(),
                   "orientation_euler_xyz": list(euler_from_matrix(T))}  # fmt: skip
            if kind == "box":
                obj["half_extents"] = [x / 2 for x in dims]
            elif kind == "sphere":
                obj["radius"] = dims[0]
            elif kind == "cylinder":
                obj["length"], obj["radius"] = dims[0], dims[1]
            else:
                raise ValueError(f"vamp_worker: no primitive {kind!r}")
            out[kind].append(obj)
    return out


def main() -> None:
    first = json.loads(sys.stdin.readline())
    robot = first["robot"]
    module, planner, plan_settings, simplify_settings = (
        vamp.configure_robot_and_planner_with_kwargs(robot, "rrtc")
    )
    sampler = module.halton()
    print(json.dumps({"joints": list(module.joint_names())}), flush=True)
    for line in sys.stdin:
        ask = json.loads(line)
        env = vamp.problem_dict_to_vamp(_problem(ask["scene"], ask["scenario"]))
        sampler.reset()
        t0 = time.perf_counter()
        result = planner(ask["start"], [ask["goal"]], env, plan_settings, sampler)
        if not result.solved:
            answer = {"path": None, "seconds": time.perf_counter() - t0,
                      "plan_ns": int(result.nanoseconds), "simplify_ns": 0}  # fmt: skip
        else:
            simple = module.simplify(result.path, env, simplify_settings, sampler)
            seconds = time.perf_counter() - t0
            answer = {"path": np.asarray(simple.path.numpy()).tolist(), "seconds": seconds,
                      "plan_ns": int(result.nanoseconds),
                      "simplify_ns": int(simple.nanoseconds)}  # fmt: skip
        print(json.dumps(answer), flush=True)


if __name__ == "__main__":
    main()
