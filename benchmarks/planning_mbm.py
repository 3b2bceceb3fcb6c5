"""Planning on MotionBenchMaker's Panda problems (MoveIt scene and request YAML, as shipped
in the ``vamp-planner`` source distribution's ``resources/panda/problems.tar.bz2``), the
toolkit's ``Robot.plan`` beside OMPL's RRT-Connect driven from Python with plain
Pinocchio's exact checks on the same shapes and pairs (what a toolkit user would write with
OMPL today), in the same run.

The robot is example-robot-data's Panda (its meshes and SRDF), not the MBM model: a
problem whose start or goal collides on these meshes is counted as invalid and skipped.
The fingers are held at their start opening (clamped to the limits). Every returned path
is re-checked here at 1 degree steps, configuration by configuration (coal on every pair,
without the batch pre-filter), and the colliding ones counted.

    curl -sO <the vamp-planner sdist URL from PyPI> && tar xzf vamp_planner-*.tar.gz
    mkdir mbm && tar xjf vamp_planner-*/resources/panda/problems.tar.bz2 -C mbm
    python benchmarks/planning_mbm.py mbm/problems [--per 10] [--json out.json]
        [--vamp VAMP_PYTHON VAMP_SCRIPTS] [--pyroboplan PYROBOPLAN_PYTHON]

pyroboplan pins an older Pinocchio than the toolkit's: give it a virtual environment of
its own (``python -m venv pr && pr/bin/pip install pyroboplan``) and its interpreter here;
it plans in ``benchmarks/pyroboplan_worker.py``, on the same URDF, meshes and SRDF.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import time
from pathlib import Path

import numpy as np

import toolkit
from toolkit import Scene, planning
from toolkit.robot import checker_for

try:  # run as a script (python benchmarks/planning_mbm.py) or from the benchmarks folder
    from machine import begin, write_json
    from ompl_peer import plain_free, rrt_connect
    from planning import dense
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json
    from benchmarks.ompl_peer import plain_free, rrt_connect
    from benchmarks.planning import dense

SCENARIOS = ("table_pick", "table_under_pick", "box", "bookshelf_small", "bookshelf_tall",
             "bookshelf_thin", "cage")  # fmt: skip
FINGERS = ("panda_finger_joint1", "panda_finger_joint2")


def load_scene(path: Path) -> Scene:
    """A MoveIt planning scene's collision objects as a Scene (``toolkit.planning.read_scene``)."""
    return planning.read_scene(path)


def load_problem(folder: Path, k: int, panda: toolkit.Robot) -> tuple | None:
    """Problem k of a scenario's folder: (scene, start, goal, the robot's checker for the
    scene), or None where it is invalid here (the goal outside the limits, or the start or
    goal colliding on these meshes)."""
    scene = load_scene(folder / f"scene{k:04d}.yaml")
    start, goal = load_request(folder / f"request{k:04d}.yaml", panda)
    checker = checker_for(panda, scene)
    if (not panda.joints.within_limits(goal) or checker.in_collision(start)
            or checker.in_collision(goal)):  # fmt: skip
        return None
    return scene, start, goal, checker


def load_request(path: Path, robot: toolkit.Robot) -> tuple[np.ndarray, np.ndarray]:
    """(start, goal) q of a MoveIt motion plan request with joint goal constraints, read by
    ``toolkit.planning.read_request`` (the fingers, held, brought within their limits)."""
    request = planning.read_request(path)
    return request.start_q(robot), request.goal_q(robot)[0]


def ompl_plan(robot: toolkit.Robot, checker, start, goal, limit: float, seed: int):
    """OMPL's RRT-Connect over the arm's 7 joints (fingers fixed;
    :func:`ompl_peer.rrt_connect`): (path (K, nq) or None, seconds). Its validity check is
    plain Pinocchio (``computeCollisions`` on the checker's shapes and pairs, with
    Pinocchio's default requests: what a user writes), not the toolkit's checker."""
    arm = [robot.model.joints[robot.model.getJointId(f"panda_joint{i}")].idx_q for i in range(1, 8)]
    q = start.copy()
    clear = plain_free(checker)  # the checker's shapes and pairs, plain Pinocchio

    def valid(state) -> bool:
        for i, c in enumerate(arm):
            q[c] = state[i]
        return clear(q)

    found, elapsed = rrt_connect(robot.joints.lower[arm], robot.joints.upper[arm], start[arm],
                                 goal[arm], valid, limit)  # fmt: skip
    if found is None:
        return None, elapsed
    out = np.tile(start, (len(found), 1))
    out[:, arm] = found
    return out, elapsed


class Pyroboplan:
    """pyroboplan's RRT-Connect and shortcutting in its own interpreter (``PYTHON``: a
    virtual environment with ``pip install pyroboplan``, which pins an older Pinocchio),
    one worker process for the run (``benchmarks/pyroboplan_worker.py``), on the same
    description files as the toolkit's Panda."""

    def __init__(self, python: str, robot: toolkit.Robot) -> None:
        import subprocess

        worker = Path(__file__).with_name("pyroboplan_worker.py")
        self.proc = subprocess.Popen([python, str(worker)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True)  # fmt: skip
        urdf = Path(robot.urdf_path)
        packages = [str(urdf.parents[4])]  # share/, which holds example-robot-data/
        self._send({"urdf": str(urdf), "packages": packages, "srdf": str(robot.srdf_path)})
        self.held = [int(robot.model.joints[robot.model.getJointId(n)].idx_q) for n in FINGERS]
        self.ends_collide = 0  # problems whose start or goal pyroboplan's check finds colliding

    def _send(self, line: dict) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(line) + "\n")
        self.proc.stdin.flush()

    def plan(self, scene: Scene, start, goal, limit: float, seed: int):
        """(path (K, nq) or None, seconds: pyroboplan's planning and shortcutting)."""
        objects = [{"kind": o.kind, "size": list(o.size), "pose": list(o.pose)}
                   for o in scene.objects]  # fmt: skip
        self._send({"objects": objects, "start": start.tolist(), "goal": goal.tolist(),
                    "held": self.held, "limit": limit, "seed": seed})  # fmt: skip
        assert self.proc.stdout is not None
        answer = json.loads(self.proc.stdout.readline())
        path = None if answer["path"] is None else np.array(answer["path"])
        self.ends_collide += any(answer["ends_collide"])
        return path, float(answer["seconds"])

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)


def _summary(run: dict, n: int) -> dict:
    t = np.array(run["t"]) * 1e3 if run["t"] else np.array([np.nan])
    inside = float(np.median(run["inside"])) * 1e3 if run["inside"] else None
    return {"valid_problems": n, "solved": run["ok"], "median_ms": float(np.median(t)),
            "median_ms_inside_plan_values": inside,
            "p95_ms": float(np.percentile(t, 95)), "paths_colliding_at_1deg": run["bad"],
            "found_on_covers": run["covers"], "swept": run["swept"],
            "swept_but_escapes": run["escaped"]}  # fmt: skip


def _length(path: np.ndarray | None) -> float | None:
    return None if path is None else float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())


def vamp_scenario(python: str, scripts: str, scenario: str) -> dict | None:
    """VAMP's own MotionBenchMaker evaluation of one scenario (RRT-Connect, one trial per
    problem, its own sphere model and problem files), run by its interpreter: (solved,
    valid, total, median and 95th percentile planning and simplification times [us])."""
    import re
    import subprocess

    out = subprocess.run(
        [python, "evaluate_mbm.py", "--robot", "panda", "--planner", "rrtc", "--trials", "1",
         "--problem", scenario], cwd=scripts, capture_output=True, text=True, check=False,
    ).stdout  # fmt: skip
    rows = {}
    for line in out.splitlines():
        m = re.match(r"\|\s*(50%|95%)\s*\|\s*([\d.]+)\s*\|\s*([\d.]+)\s*\|", line)
        if m and m.group(1) not in rows:
            rows[m.group(1)] = (float(m.group(2)), float(m.group(3)))
    counts = re.search(r"Problems: (\d+) / (\d+) / (\d+)", out)
    if counts is None or "50%" not in rows:
        print(f"VAMP on {scenario}: no table in its output")
        return None
    solved, valid, total = (int(x) for x in counts.groups())
    return {"solved": solved, "valid_problems": valid, "problems": total,
            "median_plan_us": rows["50%"][0], "p95_plan_us": rows["95%"][0],
            "median_simplify_us": rows["50%"][1]}  # fmt: skip


def main() -> None:  # long: one interleaved loop over the problems and both planners
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("problems", help="the folder of MBM's *_panda problem folders")
    parser.add_argument("--per", type=int, default=10, help="problems per scenario")
    parser.add_argument("--limit", type=float, default=10.0, help="seconds per attempt")
    parser.add_argument("--scenarios", nargs="*", default=list(SCENARIOS))
    parser.add_argument("--vamp", nargs=2, metavar=("PYTHON", "SCRIPTS"),
                        help="VAMP's interpreter and its scripts folder (built by "
                             "../shared/bench/build-vamp.sh): its evaluation per scenario, "
                             "in the same run")  # fmt: skip
    parser.add_argument("--pyroboplan", metavar="PYTHON",
                        help="an interpreter with pyroboplan installed (a virtual "
                             "environment of its own): its RRT-Connect and shortcutting on "
                             "the same problems, interleaved")  # fmt: skip
    args, info = begin(parser)
    panda = toolkit.load_example("panda")
    figures: dict[str, dict] = {}
    peer = Pyroboplan(args.pyroboplan, panda) if args.pyroboplan else None
    toolkit.warmup()  # every kernel compiled or loaded before any clock (an escape's exact
    # checks compiled inside a timed plan took 2 s once the cache was fresh)
    first = Path(args.problems) / f"{args.scenarios[0]}_panda"  # warm: kernels loaded, untimed
    warm = next(p for k in range(1, 101) if (p := load_problem(first, k, panda)) is not None)
    with contextlib.suppress(toolkit.errors.ToolkitError):  # a valid problem: the search runs
        panda.plan(warm[1], warm[2], scene=warm[0], hold=list(FINGERS))
    names = ("toolkit", "ompl", "pyroboplan") if peer else ("toolkit", "ompl")
    for scenario in args.scenarios:
        folder = Path(args.problems) / f"{scenario}_panda"
        runs: dict[str, dict] = {name: {"t": [], "ok": 0, "bad": 0, "length": [], "covers": 0,
                                        "swept": 0, "escaped": 0, "inside": []}
                                 for name in names}  # fmt: skip
        valid = invalid = 0
        for k in range(1, args.per + 1):
            problem = load_problem(folder, k, panda)
            if problem is None:
                invalid += 1
                continue
            scene, start, goal, checker = problem
            valid += 1
            lengths = []
            for name in names:  # interleaved, the same problem
                run = runs[name]
                if name == "toolkit":  # the whole call, its checks of the ends included
                    t0 = time.perf_counter()
                    r = panda.plan(start, goal, scene=scene, hold=list(FINGERS), seed=k,
                                   time_limit=args.limit)  # fmt: skip
                    path, took = (r.path if r.success else None), time.perf_counter() - t0
                    run["inside"].append(r.time_s)
                    run["covers"] += r.success and r.search == "covers"
                    run["swept"] += r.success and r.swept and not r.escapes
                    run["escaped"] += r.success and r.swept and r.escapes > 0
                elif name == "ompl":
                    path, took = ompl_plan(panda, checker, start, goal, args.limit, k)
                else:
                    assert peer is not None
                    path, took = peer.plan(scene, start, goal, args.limit, k)
                run["t"].append(took)
                lengths.append(_length(path))
                if path is not None:
                    run["ok"] += 1
                    run["bad"] += any(checker.first_collision(q) is not None
                                      for q in dense(path, math.radians(1.0)))  # fmt: skip
            if None not in lengths[:2]:
                runs["toolkit"]["length"].append(lengths[0] / lengths[1])
        for name, run in runs.items():
            f = _summary(run, valid)
            f["invalid_problems"] = invalid
            figures[f"{scenario} {name}"] = f
            print(f"{scenario:17s} {name:8s} {f['solved']}/{valid} solved ({invalid} invalid "
                  f"here), median {f['median_ms']:.1f} ms, p95 {f['p95_ms']:.0f} ms, "
                  f"{f['paths_colliding_at_1deg']} paths colliding at 1 deg")  # fmt: skip
        ours, theirs = figures[f"{scenario} toolkit"], figures[f"{scenario} ompl"]
        ratio = theirs["median_ms"] / ours["median_ms"]
        # the toolkit's simplified path length over OMPL's, per problem solved by both
        mine = runs["toolkit"]["length"]
        length_ratio = float(np.median(mine)) if mine else float("nan")
        figures[f"{scenario} ompl / toolkit median"] = {
            "ratio": ratio,
            "length_ratio_median": length_ratio,
        }
        if peer is not None:
            mark = figures[f"{scenario} pyroboplan"]["median_ms"] / ours["median_ms"]
            figures[f"{scenario} pyroboplan / toolkit median"] = {"ratio": mark}
            figures[f"{scenario} pyroboplan"]["ends_colliding_on_its_check"] = peer.ends_collide
            print(f"{scenario:17s} pyroboplan's median / the toolkit's: {mark:.1f}; its own "
                  f"check finds the start or goal colliding on {peer.ends_collide}")  # fmt: skip
            peer.ends_collide = 0
        print(f"{scenario:17s} OMPL's median / the toolkit's: {ratio:.1f}; path length, "
              f"toolkit / OMPL (median): {length_ratio:.2f}; found on the covers: "
              f"{ours['found_on_covers']} of {ours['solved']}, certified over their whole "
              f"motion: {ours['swept']}, and but for escape segments checked exactly: "
              f"{ours['swept_but_escapes']}")  # fmt: skip
        if args.vamp:
            v = vamp_scenario(args.vamp[0], args.vamp[1], scenario)
            if v is not None:
                v["toolkit_over_vamp"] = (
                    ours["median_ms"] * 1e3 / (v["median_plan_us"] + v["median_simplify_us"])
                )
                figures[f"{scenario} vamp"] = v
                print(f"{scenario:17s} vamp     {v['solved']}/{v['valid_problems']} solved, "
                      f"median {v['median_plan_us']:.0f} us (+ {v['median_simplify_us']:.0f} us "
                      f"simplifying); the toolkit's median is {v['toolkit_over_vamp']:.0f}x "
                      f"its planning + simplifying")  # fmt: skip
    if peer is not None:
        peer.close()
    write_json(args.json, {"machine": info, "figures": figures})


if __name__ == "__main__":
    main()
