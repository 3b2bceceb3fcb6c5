"""The ``toolkit`` command line: ``list``, ``urdf``, ``fk``, ``ik``, ``view``, ``map``,
``place``, ``plan``, ``calibrate``, ``report``, ``warmup``.

Run ``toolkit --help`` or ``toolkit COMMAND --help``.
"""

from __future__ import annotations

import argparse
import os
import sys
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .._version import __version__
from ..errors import InvalidParameterError, ToolkitError
from .calibrate import add_calibrate
from .inputs import SCENE_HELP, q_of, robot_from_args, scene_of, shown_values, trajectory_of
from .inputs import add_model_arguments as _add_set
from .inputs import parse_sets as _parse_sets
from .map import add_map
from .place import add_place
from .plan import add_plan

__all__ = ["main"]


def _catalogue() -> Any:
    """:mod:`toolkit.descriptions`, with the papers' models registered in its catalogue
    (imported when a command runs: ``toolkit --help`` loads nothing of the package)."""
    from .. import descriptions, papers  # noqa: F401 - papers registers its catalogue models

    return descriptions


def _cmd_list(args: argparse.Namespace) -> int:
    d = _catalogue()
    available_models, MODELS, EXAMPLE_ROBOTS = d.available_models, d.MODELS, d.EXAMPLE_ROBOTS
    example_robots = d.example_robots
    if args.names:
        print("\n".join(available_models()))
        return 0
    print("Catalogue models (toolkit.load(NAME); any command takes NAME):")
    for name in available_models():
        print(f"  {name:<16} {MODELS[name].description}")
    print("Example robots from example-robot-data (toolkit.load_example(NAME)):")
    print("  " + ", ".join(EXAMPLE_ROBOTS) + " (tool frames chosen)")
    others = sorted(set(example_robots()) - set(EXAMPLE_ROBOTS))
    print(textwrap.fill(", ".join(others), width=88, initial_indent="  ", subsequent_indent="  "))
    return 0


def _cmd_urdf(args: argparse.Namespace) -> int:
    d = _catalogue()
    available_models, MODELS, urdf_source, urdf_text = (
        d.available_models,
        d.MODELS,
        d.urdf_source,
        d.urdf_text,
    )
    names = available_models() if args.all else [args.name]
    if args.all and not args.output:
        raise InvalidParameterError("--all needs -o DIR")
    if not args.all and args.name is None:
        raise InvalidParameterError("give a model NAME or --all")
    params = _parse_sets(args.set)
    for name in names:
        if Path(name).suffix in (".urdf", ".xacro") and name not in MODELS:
            # a description file: rendered with its xacro arguments and packages resolved
            text = urdf_source(name, list(args.package_dir) or None, params)[1]
        else:
            text = urdf_text(name, **params)
        if args.output is None:
            sys.stdout.write(text)
            continue
        out = Path(args.output)
        if args.all:
            out.mkdir(parents=True, exist_ok=True)
            out = out / f"{name}.urdf"
        out.write_text(text, encoding="utf-8")
        print(f"wrote {out}")
    return 0


def _cmd_fk(args: argparse.Namespace) -> int:
    import numpy as np

    robot = robot_from_args(args)
    q = q_of(robot, args.q, args.deg, args.frame)
    T = robot.fk(q, args.frame)
    frame = args.frame or robot.tip
    np.set_printoptions(precision=6, suppress=True)
    print(f"pose of frame {frame!r} of {robot.name} in the base frame:")
    print(T)
    return 0


def _cmd_ik(args: argparse.Namespace) -> int:
    import numpy as np
    import pinocchio as pin

    robot = robot_from_args(args)
    position = np.array(args.xyz, dtype=float)
    if args.rpy is None:
        target: np.ndarray = position
    else:
        rpy = np.radians(args.rpy) if args.deg else np.array(args.rpy, dtype=float)
        target = np.eye(4)
        target[:3, :3] = pin.rpy.rpyToMatrix(*(float(a) for a in rpy))
        target[:3, 3] = position
    scene = scene_of(robot, args.scene)
    free_of = bool(args.collision_free or scene is not None)
    res = robot.ik(target, frame=args.frame, seed=args.seed, mask=args.mask, scene=scene,
                   collision_free=free_of, method=args.method)  # fmt: skip
    values, names = shown_values(robot, res.q, args.deg)
    np.set_printoptions(precision=6, suppress=True)
    verdict = "solved" if res.success else "NOT solved"
    how = ("by its analytic branches (the verified one nearest the start)"
           if res.method == "analytic"
           else f"after {res.iterations} iterations, {res.restarts} restarts")  # fmt: skip
    print(f"{robot.name}: {verdict} {how}")
    print(f"joint values ({names}):")
    print(values)
    free = args.rpy is None or (args.mask is not None and not any(args.mask[3:]))
    rot = "orientation free" if free else f"orientation error {res.orientation_error:.3g} rad"
    print(f"position error {res.position_error:.3g} m, {rot}")
    if res.collision is not None:
        print(f"reached, but {res.collision[0]} hits {res.collision[1]}")
    return 0 if res.success else 1


def _cmd_view(args: argparse.Namespace) -> int:
    import time

    from ..common import validate as _validate
    from ..viz import Viewer

    robot = robot_from_args(args)
    seconds = None if args.seconds is None else _validate.number(args.seconds, "--seconds", lower=0)
    scene = scene_of(robot, args.scene)
    motion = None
    if args.trajectory:
        if args.q:
            raise InvalidParameterError("give --q or --trajectory, not both")
        robot, motion = trajectory_of(robot, args.trajectory)
    q = q_of(robot, args.q, args.deg) if args.q else None
    with Viewer(robot, open=args.open, q=q) as viewer:
        print(f"viewer: {viewer.url}", flush=True)
        if motion is not None:
            frames = viewer.play(motion, scene=scene, rate=args.rate)
            print(f"playing {args.trajectory}: {motion.duration:.2f} s, {frames} frames at "
                  f"{args.rate:g} frames/s (the browser's Animations panel replays it)",
                  flush=True)  # fmt: skip
        elif scene is not None:
            viewer.show_scene(scene)
        try:
            if seconds is not None:
                time.sleep(seconds)
            else:
                print("press Ctrl-C to stop", flush=True)
                while True:
                    time.sleep(3600)
        except KeyboardInterrupt:
            pass
    return 0


def _cmd_warmup(args: argparse.Namespace) -> int:
    from .precompile import warmup

    return 0 if warmup(verbose=True) else 1


def _compile_estimate() -> str:
    """How long compiling every kernel takes, as ``benchmarks/first_use.py`` last measured
    it (toolkit/report/first_use_benchmark.json, installed with the package)."""
    import json
    import statistics

    path = Path(__file__).resolve().parents[1] / "report" / "first_use_benchmark.json"
    try:
        figures = json.loads(path.read_text(encoding="utf-8"))
        compile_s = statistics.median(figures["compile_s"])
        cached_s = statistics.median(figures["cached_s"])
    except (OSError, ValueError, KeyError, TypeError, statistics.StatisticsError):
        return "minutes the first time after an install, seconds after"
    return (
        f"about {compile_s / 60:.0f} minutes on an idle 2-core machine the first time after "
        f"an install, longer on a busy one; about {cached_s:.0f} s after"
    )


def _cmd_report(args: argparse.Namespace) -> int:
    import time

    from ..report import run_report
    from .precompile import warmup

    if not args.quiet:  # the first run after an install compiles every kernel: say so
        print(f"compiling the toolkit's kernels ({_compile_estimate()}) ...", end=" ", flush=True)
    start = time.perf_counter()
    warmup()
    if not args.quiet:
        print(f"done in {time.perf_counter() - start:.1f} s", flush=True)
    return run_report(Path(args.output), quiet=args.quiet)


def _add_ik(sub: Any) -> None:
    """The ``ik`` subcommand's arguments."""
    p = sub.add_parser("ik", help="solve the inverse kinematics of a model for a target")
    p.add_argument("name", help="catalogue model, example robot, or .urdf/.xacro file")
    p.add_argument("xyz", nargs=3, type=float, metavar="X", help="target position x y z [m]")
    p.add_argument(
        "--rpy",
        nargs=3,
        type=float,
        metavar="A",
        help="target orientation: roll pitch yaw [rad, or deg with --deg] about the fixed "
        "base axes X, then Y, then Z (R = Rz(yaw) Ry(pitch) Rx(roll), as a URDF rpy); "
        "without it the target is the position alone",
    )
    p.add_argument("--deg", action="store_true", help="angles in and out in degrees")
    p.add_argument("--frame", help="frame name (default: the tool frame)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random restarts")
    p.add_argument(
        "--mask",
        nargs=6,
        type=float,
        metavar="W",
        help="weights of x y z rx ry rz (rotations about the tool axes); 1 1 1 1 1 0 frees "
        "the roll about the tool z axis",
    )
    p.add_argument("--scene", metavar="FILE", help=SCENE_HELP)
    p.add_argument("--collision-free", action="store_true", help="no self-collision either")
    p.add_argument(
        "--method",
        choices=("auto", "numeric", "analytic"),
        default="auto",
        help="auto (default): the verified analytic branch nearest the start where the arm "
        "has a compiled family and the target is a full pose, the numeric solver elsewhere",
    )
    _add_set(p)
    p.set_defaults(func=_cmd_ik)


def _add_view(sub: Any) -> None:
    p = sub.add_parser("view", help="show a model in the meshcat browser viewer")
    p.add_argument("name", help="catalogue model, example robot, or .urdf/.xacro file")
    p.add_argument("--q", nargs="+", type=float, help="joint values to show")
    p.add_argument("--deg", action="store_true", help="joint values in degrees")
    p.add_argument("--open", action="store_true", help="open the default web browser")
    p.add_argument(
        "--seconds", type=float, help="keep the viewer up this long (default: until Ctrl-C)"
    )
    p.add_argument(
        "--trajectory",
        metavar="FILE",
        help="play a trajectory: a MoveIt joint trajectory (.yaml, as `toolkit plan -o` "
        "writes) or a CSV file (t, q:<joint>...); one of some joints moves those joints alone",
    )
    p.add_argument("--rate", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument("--scene", metavar="FILE", help=SCENE_HELP)
    _add_set(p)
    p.set_defaults(func=_cmd_view)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``toolkit`` command."""
    parser = argparse.ArgumentParser(
        prog="toolkit", description="Kinematics of robot manipulators on Pinocchio."
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("list", help="list the catalogue models and example robots")
    p.add_argument("--names", action="store_true", help="print bare catalogue names, one a line")
    p.set_defaults(func=_cmd_list)

    p = sub.add_parser("urdf", help="render a catalogue model's (or a .xacro file's) URDF")
    p.add_argument("name", nargs="?", help="catalogue model name, or a .urdf/.xacro file")
    _add_set(p)
    p.add_argument("-o", "--output", help="output file (or folder with --all); default stdout")
    p.add_argument("--all", action="store_true", help="render every catalogue model into -o DIR")
    p.set_defaults(func=_cmd_urdf)

    p = sub.add_parser("fk", help="print the tool pose of a model at a joint configuration")
    p.add_argument("name", help="catalogue model, example robot, or .urdf/.xacro file")
    p.add_argument("q", nargs="+", type=float, help="joint values [rad, or deg with --deg]")
    p.add_argument("--frame", help="frame name (default: the tool frame)")
    p.add_argument("--deg", action="store_true", help="joint angles in degrees")
    _add_set(p)
    p.set_defaults(func=_cmd_fk)

    _add_ik(sub)

    _add_view(sub)

    add_map(sub)
    add_place(sub)
    add_plan(sub)
    add_calibrate(sub)

    p = sub.add_parser("report", help="run the paper-reproduction report")
    p.add_argument("-o", "--output", default="report", help="output folder (default: report)")
    p.add_argument("-q", "--quiet", action="store_true", help="print only the summary")
    p.set_defaults(func=_cmd_report)

    warm = sub.add_parser("warmup", help="compile every kernel now (first use costs seconds)")
    warm.set_defaults(func=_cmd_warmup)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``toolkit`` console script."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except BrokenPipeError:  # the reader (head, less) has gone: end quietly, as Unix tools do
        _quiet_stdout()
        return 141  # 128 + SIGPIPE, what a shell reports for a tool ended by a closed pipe
    except ToolkitError as exc:
        print(f"toolkit: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # an output file or folder that cannot be written
        print(f"toolkit: error: {exc.strerror or exc}: {exc.filename or ''}", file=sys.stderr)
        return 2


def _quiet_stdout() -> None:
    """Point standard output at the null device, so that the interpreter's last flush of a
    closed pipe does not print a second error."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # no file descriptor (a captured stream): nothing to flush
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
