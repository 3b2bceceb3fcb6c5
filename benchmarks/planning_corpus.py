"""Planning on MotionBenchMaker's problems with each robot's own description: the Panda,
UR5, Fetch and Baxter URDF, SRDF and meshes of the ``vamp-planner`` source distribution
(``resources/<robot>/``), their MoveIt scene and request YAML read by
``toolkit.planning.read_scene`` and ``read_request``, planned by ``MotionRequest.plan``
as a user would (a new scene each problem, ``time_limit`` 10 s).

Every returned path is re-checked here by an independent checker that shares no code with
the toolkit: Pinocchio's URDF and geometry parsers, the SRDF's disabled pairs removed by
Pinocchio, the scene's boxes, cylinders and spheres built from the YAML here as coal
shapes, and ``pinocchio.computeCollisions`` at configurations ``--step`` degrees apart
along every segment. Prints per robot: solved, median and slowest plan, how the paths were
certified, and how many the independent check rejects; writes them with the machine and
commit to ``--json``.

    curl -sO <the vamp-planner sdist URL from PyPI> && tar xzf vamp_planner-*.tar.gz
    python benchmarks/planning_corpus.py vamp_planner-0.6.4/resources [--per 5]
        [--robots panda ur5 fetch baxter] [--step 0.25] [--json out.json]
        [--example] [--peers] [--vamp vamp-build/venv/bin/python]
        [--mplib mplib-venv/bin/python]

``--example`` plans the Panda's problems with example-robot-data's description too (its
own independent checker): a description is not a benchmark setting.
``--peers`` runs OMPL's RRT-Connect from Python on each problem the toolkit solved;
``--vamp`` VAMP (built from its source) the same way, ``--mplib`` mplib (in a virtual
environment of its own: it pins numpy < 2); each peer's path is re-checked by the same
independent checker.
"""

from __future__ import annotations

import argparse
import itertools
import math
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml

import toolkit
from toolkit import planning
from toolkit.errors import ConfigurationError, InvalidParameterError

try:  # run as a script (python benchmarks/planning_corpus.py) or from the benchmarks folder
    from machine import begin, write_json
    from ompl_peer import plain_free, rrt_connect
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json
    from benchmarks.ompl_peer import plain_free, rrt_connect

ROBOTS = ("panda", "ur5", "fetch", "baxter")


class Independent:
    """A collision checker built from Pinocchio's parsers and coal alone."""

    def __init__(
        self, urdf: Path, srdf: Path | None, package_dirs: list[str], adjacent: bool = True
    ) -> None:
        """``adjacent`` False: shapes of a link and of its parent or child link are never
        paired (MoveIt's rule where the SRDF does not list them), nor two of one link."""
        self.model = pin.buildModelFromUrdf(str(urdf))
        self.robot_geom = pin.buildGeomFromUrdf(
            self.model, str(urdf), pin.GeometryType.COLLISION, package_dirs=package_dirs
        )
        self.robot_geom.addAllCollisionPairs()
        if srdf is not None:
            pin.removeCollisionPairs(self.model, self.robot_geom, str(srdf))
        if not adjacent:
            objects, parents = self.robot_geom.geometryObjects, self.model.parents
            for pair in list(self.robot_geom.collisionPairs):
                a, b = objects[pair.first].parentJoint, objects[pair.second].parentJoint
                if a == b or parents[a] == b or parents[b] == a:
                    self.robot_geom.removeCollisionPair(pair)
        self.self_pairs = [(p.first, p.second) for p in self.robot_geom.collisionPairs]
        self.frames = {f.name: f for f in self.model.frames}
        self.data = self.model.createData()
        pin.framesForwardKinematics(self.model, self.data, pin.neutral(self.model))

    @classmethod
    def mbm(cls, folder: Path, name: str) -> Independent:
        """MotionBenchMaker's ``<folder>/<name>.urdf`` and ``.srdf``, meshes below it."""
        return cls(folder / f"{name}.urdf", folder / f"{name}.srdf", [str(folder)])

    def _frame(self, name: str) -> pin.SE3:
        if not name or name not in self.frames:
            return pin.SE3.Identity()
        return self.data.oMf[self.model.getFrameId(name)]

    @staticmethod
    def _pose(pose: dict | None) -> pin.SE3:
        """A MoveIt pose written as lists (position; orientation x, y, z, w) as an SE3."""
        if pose is None:
            return pin.SE3.Identity()
        x, y, z, w = pose["orientation"]
        return pin.SE3(pin.Quaternion(w, x, y, z).matrix(), np.array(pose["position"], float))

    def scene(self, path: Path) -> tuple[pin.GeometryModel, pin.GeometryData]:
        import coal

        doc = yaml.safe_load(path.read_text())
        world = doc.get("world", doc.get("planning_scene_world", doc))
        geom = pin.GeometryModel()
        for g in self.robot_geom.geometryObjects:
            geom.addGeometryObject(g)
        robot_count = len(geom.geometryObjects)
        for obj in world.get("collision_objects") or []:
            base = self._frame((obj.get("header") or {}).get("frame_id", ""))
            base = base * self._pose(obj.get("pose"))  # the object's pose: its shapes' frame
            for k, (prim, pose) in enumerate(zip(obj["primitives"], obj["primitive_poses"],
                                                 strict=True)):  # fmt: skip
                kind, d = prim["type"], prim["dimensions"]
                if kind in ("box", 1):
                    shape = coal.Box(*d)
                elif kind in ("sphere", 2):
                    shape = coal.Sphere(d[0])
                else:  # cylinder (height, radius)
                    shape = coal.Cylinder(d[1], d[0])
                M = base * self._pose(pose)
                geom.addGeometryObject(pin.GeometryObject(f"{obj['id']}_{k}", 0, 0, M, shape))
        for a, b in self.self_pairs:
            geom.addCollisionPair(pin.CollisionPair(a, b))
        for i in range(robot_count):
            if geom.geometryObjects[i].parentJoint == 0:
                continue
            for k in range(robot_count, len(geom.geometryObjects)):
                geom.addCollisionPair(pin.CollisionPair(i, k))
        return geom, pin.GeometryData(geom)

    def q_of(self, names: list[str], values: np.ndarray) -> np.ndarray:
        """This model's q with the named (1-value) joints at ``values``, the rest neutral."""
        q = pin.neutral(self.model)
        for name, value in zip(names, values, strict=True):
            q[self.model.joints[self.model.getJointId(name)].idx_q] = value
        return q

    def collides(self, geom: pin.GeometryModel, gdata: pin.GeometryData, q: np.ndarray) -> bool:
        return bool(pin.computeCollisions(self.model, self.data, geom, gdata, q, True))


def problems(resources: Path, robot: str, workdir: Path) -> Path:
    """The folder of the robot's problems, unpacked from its problems.tar.bz2 once."""
    out = workdir / robot
    if not out.exists():
        with tarfile.open(resources / robot / "problems.tar.bz2", "r:bz2") as archive:
            archive.extractall(out, filter="data")
    return out / "problems"


def stepped(path: np.ndarray, step: float):
    """Every configuration the independent check visits along ``path`` (K, n) of joint
    angles: each straight segment at points at most ``step`` degrees apart per joint, its
    ends included."""
    for a, b in itertools.pairwise(np.asarray(path, dtype=float)):
        n = max(2, math.ceil(float(np.abs(b - a).max()) / math.radians(step)) + 1)
        for s in np.linspace(0.0, 1.0, n):
            yield a + s * (b - a)


def rejected(check: Independent, robot, request, scene_file: Path, path, step: float) -> bool:
    """Whether the independent checker finds a contact along ``path`` (the request's
    group's configurations; the robot's other joints at the request's start), stepping
    ``step`` degrees along every segment."""
    planned = request.robot_for(robot)
    geom, gdata = check.scene(scene_file)
    q = check.q_of(robot.joints.names, robot.joints.angles(request.start_q(robot)))
    to_model = [check.model.getJointId(n) for n in planned.joints.names]
    for x in stepped(np.array([planned.joints.angles(p) for p in path]), step):
        for j, value in zip(to_model, x, strict=True):
            q[check.model.joints[j].idx_q] = value
        if check.collides(geom, gdata, q):
            return True
    return False


def ompl_plan(planned, request, scene, limit: float):
    """OMPL's RRT-Connect over the angles of the joints the request plans (the held ones
    at the start's): :func:`ompl_between`."""
    joints = planned.joints
    held = set(request.held(planned))
    free = [k for k, name in enumerate(joints.names) if name not in held]
    return ompl_between(planned, scene, joints.angles(request.start_q(planned)),
                        joints.angles(request.goal_q(planned)[0]), free, limit)  # fmt: skip


def ompl_between(planned, scene, start: np.ndarray, goal: np.ndarray, free: list[int],
                 limit: float):  # fmt: skip
    """OMPL's RRT-Connect (:func:`ompl_peer.rrt_connect`) from the joint angles ``start``
    to ``goal``, over the joints ``free`` (the others at the start's), a state valid where
    plain Pinocchio (``computeCollisions`` on the toolkit checker's shapes and pairs)
    finds no contact: (path (K, nq) or None, seconds)."""
    joints = planned.joints
    lower, upper = planning.value_bounds(planned)  # the toolkit's sampling box, the same
    # MBM's Fetch goals put wrist_roll at -pi, 2.7e-6 rad past the URDF's limit: brought
    # onto it, as the toolkit does within its stated tolerance
    start, goal = np.clip(start, lower, upper), np.clip(goal, lower, upper)
    clear = plain_free(planned.collision_checker(scene))
    values = start.copy()

    def valid(state) -> bool:
        for i, k in enumerate(free):
            values[k] = state[i]
        return clear(joints.q_from_angles(values))

    found, seconds = rrt_connect(lower[free], upper[free], start[free], goal[free], valid,
                                 limit)  # fmt: skip
    if found is None:
        return None, seconds
    out = np.tile(start, (len(found), 1))
    out[:, free] = found
    return np.asarray(joints.q_from_angles(out)), seconds


def _refused(check: Independent, robot, request, scenario: Path, k: int, error) -> dict:
    """The row of a problem the toolkit refused, with whether the independent checker
    finds its start or a goal in collision too (the problem is then not valid)."""
    planned = request.robot_for(robot)
    ends = [request.start_q(planned), *request.goal_q(planned)]
    invalid = any(rejected(check, robot, request, scenario / f"scene{k:04d}.yaml",
                           np.array([q, q]), 1.0) for q in ends)  # fmt: skip
    print(f"  {robot.name} {scenario.name} {k}: refused ({error}); "
          f"{'invalid' if invalid else 'VALID'} by the independent checker")  # fmt: skip
    return {"scenario": scenario.name, "problem": k, "success": False, "seconds": 0.0,
            "certificate": "", "search": "", "rejected": False, "refused": str(error),
            "invalid": invalid}  # fmt: skip


def summary(rows: list[dict]) -> dict:
    """Solved, median and slowest plan [ms], rejected paths of one planner's rows; the
    problems refused as invalid (a start or goal in collision by the toolkit and by the
    independent checker), and refused though the independent checker finds them valid."""
    solved = [r["seconds"] for r in rows if r["success"]]
    return {
        "problems": len(rows), "solved": len(solved),
        "invalid": sum(bool(r.get("invalid")) for r in rows),
        "refused_valid": sum("refused" in r and not r["invalid"] for r in rows),
        "median_ms": 1e3 * float(np.median(solved)) if solved else None,
        "slowest_ms": 1e3 * float(np.max(solved)) if solved else None,
        "rejected": sum(r["rejected"] for r in rows),
    }  # fmt: skip


class Worker:
    """A peer planner in its own interpreter (``python``), one worker process per robot
    answering JSON lines (``benchmarks/<script>``), on the same problem files; its
    configurations mapped to the toolkit's by joint name. ``first``: the line that names
    the robot; a worker that answers ``{"error": ...}`` plans nothing (its rows say so)."""

    def __init__(self, python: str, script: str, first: dict) -> None:
        import json
        import subprocess

        self._json = json
        worker = Path(__file__).with_name(script)
        self.proc = subprocess.Popen([python, str(worker)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True)  # fmt: skip
        answer = self._ask(first)
        self.error: str | None = answer.get("error")
        self.joints: list[str] = answer.get("joints", [])

    def _ask(self, line: dict) -> dict:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(self._json.dumps(line) + "\n")
        self.proc.stdin.flush()
        answer: dict = self._json.loads(self.proc.stdout.readline())
        return answer

    def solve(self, planned, request, line: dict):
        """(path (K, nq) of the planned robot or None, seconds) of the problem ``line``
        (start and goal added, in the worker's joint order)."""
        start = planned.joints.angles(request.start_q(planned))
        goal = planned.joints.angles(request.goal_q(planned)[0])
        return self.between(planned, start, goal, line)

    def between(self, planned, start: np.ndarray, goal: np.ndarray, line: dict):
        """:meth:`solve` from the joint angles ``start`` to ``goal`` of ``planned``."""
        if self.error is not None:
            return None, 0.0
        names = list(planned.joints.names)
        at = [names.index(j) for j in self.joints]
        answer = self._ask({**line, "start": start[at].tolist(), "goal": goal[at].tolist()})
        if answer["path"] is None:
            return None, float(answer["seconds"])
        found = np.asarray(answer["path"], dtype=float)
        out = np.tile(start, (len(found), 1))
        out[:, at] = found
        return np.asarray(planned.joints.q_from_angles(out)), float(answer["seconds"])

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)


class Vamp(Worker):
    """VAMP's RRT-Connect and simplification (``benchmarks/vamp_worker.py``) in the virtual
    environment ``../shared/bench/build-vamp.sh`` builds."""

    def __init__(self, python: str, robot_name: str) -> None:
        super().__init__(python, "vamp_worker.py", {"robot": robot_name})
        self.robot_name = robot_name

    def __call__(self, planned, request, scene, scene_file: Path):
        scenario = scene_file.parent.name.removesuffix(f"_{self.robot_name}")
        return self.solve(planned, request, {"scene": str(scene_file), "scenario": scenario})


MOVE_GROUPS = {"panda": "panda_hand", "ur5": "ee_link", "fetch": "gripper_link"}
"""The link mplib plans to (it plans the chain of joints to one link: Baxter's two arms at
once are no such chain, and mplib is not run on them)."""


class Mplib(Worker):
    """mplib's planner (``benchmarks/mplib_worker.py``) in an environment of its own."""

    def __init__(self, python: str, resources: Path, robot_name: str) -> None:
        folder = resources / robot_name
        if robot_name not in MOVE_GROUPS:
            self.error, self.joints = "two arms: no chain to one link", []
            self.proc = None  # type: ignore[assignment]
            return
        self.start(python, folder / f"{robot_name}.urdf", folder / f"{robot_name}.srdf",
                   MOVE_GROUPS[robot_name])  # fmt: skip

    def start(self, python: str, urdf: Path, srdf: Path | None, move_group: str) -> None:
        """The worker for the description ``urdf`` (its ``srdf``, None: mplib's own rule)
        planning the chain to the link ``move_group``."""
        super().__init__(python, "mplib_worker.py", {
            "urdf": str(urdf), "srdf": None if srdf is None else str(srdf),
            "move_group": move_group})  # fmt: skip

    @classmethod
    def of(cls, python: str, urdf: Path, srdf: Path | None, move_group: str) -> Mplib:
        """A worker for any description (:meth:`start`)."""
        worker = cls.__new__(cls)
        worker.start(python, urdf, srdf, move_group)
        return worker

    def __call__(self, planned, request, scene, scene_file: Path):
        return self.solve(planned, request, {"scene": str(scene_file)})

    def close(self) -> None:
        if self.proc is not None:
            super().close()


def _peer_figures(name: str, rows: list[dict], peer_rows: list[dict]) -> dict:
    """A peer's summary, with its median ratio to the toolkit over the problems both
    solved (the peer's seconds over the toolkit's)."""
    figures = {**summary(peer_rows), "rows": peer_rows}
    ours = {(r["scenario"], r["problem"]): r["seconds"] for r in rows if r["success"]}
    both = [(ours[(r["scenario"], r["problem"])], r["seconds"]) for r in peer_rows
            if r["success"] and (r["scenario"], r["problem"]) in ours]  # fmt: skip
    if both:
        figures[f"median_ratio_{name}_to_toolkit"] = float(np.median([b / a for a, b in both]))
    print(f"  {name}: {figures['solved']} of {figures['problems']} solved, median "
          f"{figures['median_ms'] or float('nan'):.1f} ms, {figures['rejected']} rejected; "
          f"{name} / toolkit per problem (median) "
          f"{figures.get(f'median_ratio_{name}_to_toolkit', float('nan')):.2f}x")  # fmt: skip
    return figures


def example_robot(name: str):
    """example-robot-data's ``name`` as a user loads it, and the independent checker of its
    own description (its SRDF's pairs, a link's pairs with its parent and child left out)."""
    from toolkit.descriptions import example_robot_data_dir

    robot = toolkit.load_example(name)
    robots = example_robot_data_dir()  # package://example-robot-data/robots/... or below it
    srdf = Path(robot.srdf_path) if robot.srdf_path else None
    check = Independent(Path(robot.urdf_path), srdf, [str(robots.parents[1]), str(robots)],
                        adjacent=False)  # fmt: skip
    return robot, check


def run_robot(  # long: one loop over the problems, the planners interleaved
    resources: Path,
    robot_name: str,
    per: int,
    step: float,
    workdir: Path,
    peers: dict,
    example: bool = False,
) -> dict:
    """The toolkit on each problem, then each of ``peers`` (name -> (planned robot,
    request, scene, scene file) -> (path or None, seconds)) on those the toolkit solved;
    ``example``: with example-robot-data's description of the robot instead of MBM's."""
    folder = resources / robot_name
    if example:
        robot, check = example_robot(robot_name)
    else:
        robot = toolkit.load_urdf(folder / f"{robot_name}.urdf",
                                  srdf=folder / f"{robot_name}.srdf")  # fmt: skip
        check = Independent.mbm(folder, robot_name)
    rows: list[dict] = []
    peer_rows: dict[str, list[dict]] = {name: [] for name in peers}
    for scenario in sorted(problems(resources, robot_name, workdir).iterdir()):
        for k in range(1, per + 1):
            request = planning.read_request(scenario / f"request{k:04d}.yaml")
            scene_file = scenario / f"scene{k:04d}.yaml"
            scene = planning.read_scene(scene_file, frames=planning.fixed_frames(robot))
            t0 = time.perf_counter()
            try:
                result = request.plan(robot, scene, time_limit=10.0, seed=0)
            except InvalidParameterError as refused:  # a start or goal in collision
                rows.append(_refused(check, robot, request, scenario, k, refused))
                continue
            except ConfigurationError as outside:  # another description's joint limits
                print(f"  {robot.name} {scenario.name} {k}: refused ({outside})")
                rows.append({"scenario": scenario.name, "problem": k, "success": False,
                             "seconds": 0.0, "certificate": "", "search": "",
                             "rejected": False, "refused": str(outside), "invalid": True,
                             "outside_limits": True})  # fmt: skip
                continue
            seconds = time.perf_counter() - t0
            bad = result.success and rejected(check, robot, request, scene_file, result.path, step)
            rows.append({"scenario": scenario.name, "problem": k, "success": result.success,
                         "seconds": seconds, "certificate": result.certificate,
                         "search": result.search, "rejected": bad})  # fmt: skip
            line = (f"  {robot_name} {scenario.name} {k}: {result.success} "
                    f"{1e3 * seconds:.1f} ms {result.certificate}"
                    f"{' REJECTED' if bad else ''}")  # fmt: skip
            for name, peer in peers.items() if result.success else ():
                if getattr(peer, "error", None) is not None:  # a worker that cannot plan it
                    continue
                path, took = peer(request.robot_for(robot), request, scene, scene_file)
                theirs = path is not None and rejected(check, robot, request, scene_file,
                                                       path, step)  # fmt: skip
                peer_rows[name].append({"scenario": scenario.name, "problem": k,
                                        "success": path is not None, "seconds": took,
                                        "rejected": theirs})  # fmt: skip
                line += f" | {name} {path is not None} {1e3 * took:.1f} ms"
                line += " REJECTED" if theirs else ""
            print(line, flush=True)
    figures = summary(rows)
    figures["certificates"] = {c: sum(r["certificate"] == c for r in rows if r["success"])
                               for c in ("covers", "covers+exact", "exact", "samples")}  # fmt: skip
    figures["exact_search"] = sum(r["search"] == "exact" for r in rows if r["success"])
    figures["rows"] = rows
    print(f"{robot_name}: {figures['solved']} of {figures['problems'] - figures['invalid']} "
          f"valid problems solved ({figures['invalid']} invalid), median "
          f"{figures['median_ms']:.1f} ms, slowest {figures['slowest_ms']:.0f} ms, "
          f"{figures['rejected']} rejected at {step} degrees; "
          f"{figures['certificates']}")  # fmt: skip
    for name in peers:
        figures[name] = _peer_figures(name, rows, peer_rows[name])
    return figures


def _ompl_peer(planned, request, scene, scene_file):
    return ompl_plan(planned, request, scene, 10.0)


def peer_arguments(parser: argparse.ArgumentParser) -> None:
    """The planning benchmarks' ``--peers`` (OMPL from Python) and ``--mplib`` (mplib's
    interpreter)."""
    parser.add_argument("--peers", action="store_true",
                        help="also OMPL's RRT-Connect from Python (pip install ompl)")  # fmt: skip
    parser.add_argument("--mplib", metavar="PYTHON",
                        help="also mplib, in this interpreter (its own venv)")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("resources", type=Path, help="the sdist's resources/ folder")
    parser.add_argument("--per", type=int, default=5, help="problems per scenario")
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=ROBOTS)
    parser.add_argument("--step", type=float, default=0.25, help="re-check step [degrees]")
    peer_arguments(parser)
    parser.add_argument("--vamp", metavar="PYTHON",
                        help="also VAMP, in this interpreter (its build's venv)")  # fmt: skip
    parser.add_argument("--example", action="store_true",
                        help="also the Panda with example-robot-data's description")  # fmt: skip
    args, info = begin(parser)
    toolkit.warmup()  # compiled before any clock (loaded from the cache after the first run)
    figures: dict[str, object] = {
        "per_scenario": args.per,
        "step_degrees": args.step,
        "peers": args.peers,
    }
    if args.example:  # the same problems, the description users of Pinocchio have
        with tempfile.TemporaryDirectory() as work:
            figures["panda_example"] = run_robot(args.resources, "panda", args.per, args.step,
                                                 Path(work), {}, example=True)  # fmt: skip
    figures["vamp"] = bool(args.vamp)
    figures["mplib"] = bool(args.mplib)
    with tempfile.TemporaryDirectory() as work:
        for name in args.robots:
            peers: dict = {"ompl": _ompl_peer} if args.peers else {}
            workers: dict[str, Worker] = {}
            if args.vamp:
                workers["vamp"] = Vamp(args.vamp, name)
            if args.mplib:
                workers["mplib"] = Mplib(args.mplib, args.resources, name)
            try:
                figures[name] = run_robot(args.resources, name, args.per, args.step, Path(work),
                                          {**peers, **workers})  # fmt: skip
                for peer, worker in workers.items():
                    if worker.error is not None:  # it planned nothing: why
                        figures[name][peer]["error"] = worker.error
            finally:
                for worker in workers.values():
                    worker.close()
    write_json(args.json, {**info, **figures})


if __name__ == "__main__":
    main()
