"""Planning on example-robot-data's arms in scenes built here: the Panda, UR5, UR10, Kinova
(continuous joints), Z1 and xArm7, each loaded as a user loads it (``toolkit.load_example``:
its URDF and the SRDF beside it), in three scenes scaled to its reach and written as
MoveIt scene YAML: a table with a block on it, a slotted shelf (three boards, a back, two
sides and a divider) and a cage of 2 cm bars. Problems: start and goal configurations free
of collision whose straight line collides (both by the independent checker), ``--per``
per scene, the same for every planner.

Every path is re-checked by the independent checker of ``planning_corpus.py`` (Pinocchio's
URDF and geometry parsers, the SRDF's disabled pairs, the scene's boxes as coal shapes,
``pinocchio.computeCollisions`` every ``--step`` degrees). ``--peers`` runs OMPL's
RRT-Connect from Python (``ompl_peer``) on each problem. Prints and writes per robot:
solved, median and slowest plan, how the paths were certified, paths rejected, and
``missed``: problems the toolkit did not solve where OMPL found a path the independent
checker accepts (the others may have none: a problem is not known to be solvable); for
OMPL the same and its per-problem ratio to the toolkit over the problems both solved.
``--mplib`` runs mplib (its own interpreter: ``benchmarks/mplib_worker.py``) on every
problem too, where the chain it plans (to the robot's tip) is the joints planned.

    python benchmarks/planning_built.py [--per 5] [--robots panda ur5 ...] [--step 0.05]
        [--peers] [--mplib mplib-venv/bin/python]
        [--json toolkit/report/planning_built_benchmark.json]
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml

import toolkit
from toolkit import planning
from toolkit.descriptions import example_robot_data_dir

try:  # run as a script (python benchmarks/planning_built.py) or from the benchmarks folder
    import planning_corpus as corpus
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks import planning_corpus as corpus
    from benchmarks.machine import begin, write_json

Independent, Mplib, example_robot = corpus.Independent, corpus.Mplib, corpus.example_robot
ompl_between, stepped, summary = corpus.ompl_between, corpus.stepped, corpus.summary
_peer_figures = corpus._peer_figures

ROBOTS = {"panda": "arm", "ur5": None, "ur10": None, "kinova": None, "z1": None,
          "xarm7": "xarm7"}  # fmt: skip
"""Each robot and the SRDF group it plans (None: every joint but those held at 0)."""

Box = tuple[str, tuple[float, float, float], tuple[float, float, float]]


def scenes(reach: float, height: float) -> dict[str, list[Box]]:
    """(name, size, centre) boxes [m] of the three scenes for an arm of ``reach`` [m] whose
    shoulder stands ``height`` [m] above its base, in front of it along x."""
    r, h = reach, height
    table = [("top", (0.6 * r, 1.4 * r, 0.04), (0.65 * r, 0.0, h - 0.35 * r)),
             ("block", (0.12 * r, 0.3 * r, 0.3 * r), (0.6 * r, 0.0, h - 0.18 * r))]  # fmt: skip
    depth, width, x = 0.35 * r, 0.9 * r, 0.7 * r
    shelf = [(f"board{k}", (depth, width, 0.02), (x, 0.0, h + z * r))
             for k, z in enumerate((-0.45, -0.05, 0.35))]  # fmt: skip
    shelf += [("back", (0.02, width, 0.9 * r), (x + depth / 2, 0.0, h - 0.05 * r)),
              ("left", (depth, 0.02, 0.9 * r), (x, width / 2, h - 0.05 * r)),
              ("right", (depth, 0.02, 0.9 * r), (x, -width / 2, h - 0.05 * r)),
              ("divider", (depth, 0.02, 0.4 * r), (x, 0.0, h - 0.25 * r))]  # fmt: skip
    bar = 0.02
    cage = [(f"post{k}", (bar, bar, 1.2 * r), (0.55 * r, y * r, h))
            for k, y in enumerate(np.linspace(-0.6, 0.6, 7))]  # fmt: skip
    cage += [(f"rail{k}", (bar, 1.2 * r, bar), (0.55 * r, 0.0, h + z * r))
             for k, z in enumerate((-0.3, 0.15))]  # fmt: skip
    cage += [(f"side{k}", (0.5 * r, bar, bar), (0.3 * r, s * 0.6 * r, h + z * r))
             for k, (s, z) in enumerate(itertools.product((-1, 1), (-0.3, 0.15)))]  # fmt: skip
    return {"table": table, "shelf": shelf, "cage": cage}


def write_scene(path: Path, boxes: list[Box]) -> None:
    """``boxes`` as a MoveIt planning scene (world frame) at ``path``."""
    objects = [{"id": name, "header": {"frame_id": ""},
                "primitives": [{"type": "box", "dimensions": [float(v) for v in size]}],
                "primitive_poses": [{"position": [float(v) for v in centre],
                                     "orientation": [0.0, 0.0, 0.0, 1.0]}]}
               for name, size, centre in boxes]  # fmt: skip
    path.write_text(yaml.safe_dump({"name": path.stem, "world": {"collision_objects": objects}}))


def full_q(check: Independent, robot, q: np.ndarray) -> np.ndarray:
    """The independent model's configuration of the toolkit robot's ``q``, joint by joint
    by name (a continuous joint as its cosine and sine)."""
    out = pin.neutral(check.model)
    for name, value in zip(robot.joints.names, robot.joints.angles(q), strict=True):
        joint = check.model.joints[check.model.getJointId(name)]
        if joint.nq == 2:
            out[joint.idx_q : joint.idx_q + 2] = math.cos(value), math.sin(value)
        else:
            out[joint.idx_q] = value
    return out


def collides_along(check: Independent, robot, geom, gdata, path: np.ndarray, step: float) -> bool:
    """Whether the independent checker finds a contact along ``path`` (the toolkit robot's
    configurations), ``step`` degrees apart on every segment (joint angles interpolated:
    :func:`planning_corpus.stepped`)."""
    angles = np.array([robot.joints.angles(q) for q in path])
    return any(check.collides(geom, gdata, full_q(check, robot, robot.joints.q_from_angles(x)))
               for x in stepped(angles, step))  # fmt: skip


def make_problems(check, robot, geom, gdata, per: int, seed: int) -> list[tuple]:
    """``per`` (start, goal) pairs free of collision whose straight line collides."""
    rng = np.random.default_rng(seed)
    found: list[tuple] = []
    pool = robot.random_q(4000, seed=int(rng.integers(2**31)))
    free = [q for q in pool if not check.collides(geom, gdata, full_q(check, robot, q))]
    for a, b in itertools.combinations(free, 2):
        if len(found) == per:
            break
        if collides_along(check, robot, geom, gdata, np.array([a, b]), 2.0):
            found.append((a, b))
    return found


def ompl(robot, scene, start, goal, limit: float):
    """OMPL's RRT-Connect over every joint's angle (:func:`planning_corpus.ompl_between`):
    (path (K, nq) or None, seconds)."""
    joints = robot.joints
    return ompl_between(robot, scene, joints.angles(start), joints.angles(goal),
                        list(range(len(joints.names))), limit)  # fmt: skip


def adjacent_disabled(urdf: str, srdf: str | Path | None) -> str:
    """The SRDF ``srdf`` (None: one with nothing in it) with every pair of links a joint
    joins disabled, as MoveIt's setup assistant writes them and the independent checker
    (and the toolkit) leave them out: mplib checks them, and takes the UR5's wrist 3 and
    its ``ee_link`` (joined by a fixed joint, touching) for a collision at every start."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(Path(srdf).read_text() if srdf else '<robot name="robot"/>')
    for joint in ET.fromstring(urdf).iter("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is not None and child is not None:
            ET.SubElement(root, "disable_collisions", link1=parent.get("link", ""),
                          link2=child.get("link", ""), reason="Adjacent")  # fmt: skip
    return ET.tostring(root, encoding="unicode")


def mplib_worker(python: str, robot, planned, work: Path) -> Mplib:
    """mplib (``benchmarks/mplib_worker.py``, in its own interpreter ``python``) on the
    robot's description (a copy naming its meshes by path: mplib does not resolve
    example-robot-data's ``package://`` names) and its SRDF with adjacent links' pairs
    disabled (:func:`adjacent_disabled`), planning the chain to the robot's tip; its
    ``error`` says why not where that chain is not the joints planned (the Z1's gripper is
    outside it)."""
    robots = example_robot_data_dir()
    urdf = Path(robot.urdf_path)
    copy = work / f"mplib_{urdf.name}"
    where = os.path.relpath(robots, work)  # mplib reads a mesh's path from the URDF's folder
    copy.write_text(urdf.read_text().replace("package://example-robot-data/robots/",
                                             f"{where}/"))  # fmt: skip
    srdf = work / f"mplib_{urdf.stem}.srdf"
    srdf.write_text(adjacent_disabled(urdf.read_text(), robot.srdf_path))
    worker = Mplib.of(python, copy, srdf, robot.tip)
    if worker.error is None and sorted(worker.joints) != sorted(planned.joints.names):
        worker.close()
        worker.error = (f"mplib plans the chain to {robot.tip} ({', '.join(worker.joints)}), "
                        f"the problems move {', '.join(planned.joints.names)}")  # fmt: skip
    return worker


def run_robot(  # long: one loop over the problems, the planners interleaved
    name: str, per: int, step: float, work: Path, peers: bool, mplib: str | None = None
) -> dict:
    robot, check = example_robot(name)
    planned = robot.group(ROBOTS[name]) if ROBOTS[name] else robot
    worker = mplib_worker(mplib, robot, planned, work) if mplib else None
    if worker is not None and worker.error is not None:
        print(f"  mplib: {worker.error}")
    mplib_rows: list[dict] = []
    tips = robot.fk(robot.random_q(500, seed=1))[:, :3, 3]
    base = robot.fk(robot.random_q(1, seed=1)[0], planned.model.frames[1].name)[:3, 3]
    reach = float(np.percentile(np.linalg.norm(tips - base, axis=1), 90))
    rows: list[dict] = []
    ompl_rows: list[dict] = []
    for label, boxes in scenes(reach, float(base[2])).items():
        scene_file = work / f"{name}_{label}.yaml"
        write_scene(scene_file, boxes)
        geom, gdata = check.scene(scene_file)
        for k, (start, goal) in enumerate(make_problems(check, planned, geom, gdata, per, 7)):
            scene = planning.read_scene(scene_file, frames=planning.fixed_frames(robot))
            t0 = time.perf_counter()
            result = planned.plan(start, goal, scene=scene, time_limit=10.0, seed=0)
            seconds = time.perf_counter() - t0
            bad = result.success and collides_along(check, planned, geom, gdata, result.path,
                                                     step)  # fmt: skip
            rows.append({"scenario": label, "problem": k, "success": result.success,
                         "seconds": seconds, "certificate": result.certificate,
                         "search": result.search, "rejected": bad})  # fmt: skip
            line = (f"  {name} {label} {k}: {result.success} {1e3 * seconds:.1f} ms "
                    f"{result.certificate}{' REJECTED' if bad else ''}")  # fmt: skip
            if peers:  # on every problem: where the toolkit found no path, is there one?
                path, took = ompl(planned, scene, start, goal, 10.0)
                theirs = path is not None and collides_along(check, planned, geom, gdata, path,
                                                             step)  # fmt: skip
                ompl_rows.append({"scenario": label, "problem": k, "success": path is not None,
                                  "seconds": took, "rejected": theirs})  # fmt: skip
                rows[-1]["missed"] = not result.success and path is not None and not theirs
                line += f" | ompl {path is not None} {1e3 * took:.1f} ms"
                line += " REJECTED" if theirs else ""
            if worker is not None and worker.error is None:
                angles = planned.joints.angles
                path, took = worker.between(planned, angles(start), angles(goal),
                                            {"scene": str(scene_file)})  # fmt: skip
                theirs = path is not None and collides_along(check, planned, geom, gdata, path,
                                                             step)  # fmt: skip
                mplib_rows.append({"scenario": label, "problem": k, "success": path is not None,
                                   "seconds": took, "rejected": theirs})  # fmt: skip
                line += f" | mplib {path is not None} {1e3 * took:.1f} ms"
                line += " REJECTED" if theirs else ""
            print(line, flush=True)
    figures = {**summary(rows), "reach_m": reach, "joints": planned.nq,
               "missed": sum(bool(r.get("missed")) for r in rows)}  # fmt: skip
    figures["certificates"] = {c: sum(r["certificate"] == c for r in rows if r["success"])
                               for c in ("covers", "covers+exact", "exact", "samples")}  # fmt: skip
    figures["rows"] = rows
    print(f"{name}: {figures['solved']} of {figures['problems']} solved "
          f"({figures['missed']} missed where OMPL found a sound path), median "
          f"{figures['median_ms'] or float('nan'):.1f} ms, slowest "
          f"{figures['slowest_ms'] or float('nan'):.0f} ms, {figures['rejected']} rejected "
          f"at {step} degrees; {figures['certificates']}")  # fmt: skip
    if peers:
        figures["ompl"] = _peer_figures("ompl", rows, ompl_rows)
    if worker is not None:
        if worker.error is None:
            worker.close()
            figures["mplib"] = _peer_figures("mplib", rows, mplib_rows)
        else:
            figures["mplib"] = {"error": worker.error}
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per", type=int, default=5, help="problems per scene")
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--step", type=float, default=0.05, help="re-check step [degrees]")
    corpus.peer_arguments(parser)
    args, info = begin(parser)
    toolkit.warmup()  # compiled before any clock (loaded from the cache after the first run)
    figures: dict[str, object] = {"per_scene": args.per, "step_degrees": args.step,
                                  "peers": args.peers, "mplib": bool(args.mplib)}  # fmt: skip
    with tempfile.TemporaryDirectory() as work:
        for name in args.robots:
            figures[name] = run_robot(name, args.per, args.step, Path(work), args.peers,
                                      args.mplib)  # fmt: skip
    write_json(args.json, {**info, **figures})


if __name__ == "__main__":
    main()
