"""``toolkit plan``: a collision-free motion (:meth:`toolkit.Robot.plan`) from a MoveIt
motion plan request or from start and goal values, in a MoveIt planning scene (YAML) or a
toolkit scene (JSON), printed and written as a timed MoveIt joint trajectory."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING, Any

from ..errors import InvalidParameterError

if TYPE_CHECKING:  # imported when the command runs, not for ``--help``
    from .. import planning
    from ..collision import Scene
    from ..robot import Robot
from .inputs import SCENE_HELP, add_model_arguments, q_of, robot_from_args, scene_of, shown_values

__all__ = ["add_plan"]


def _solve(
    args: argparse.Namespace, robot: Robot, scene: Scene | None
) -> tuple[Robot, planning.PlanResult]:
    from .. import planning

    options: dict[str, Any] = {"seed": args.seed, "resolution": math.radians(args.resolution)}
    if args.time_limit is not None:
        options["time_limit"] = args.time_limit
    if args.request:
        if args.start or args.goal:
            raise InvalidParameterError("give --request or --start and --goal, not both")
        request = planning.read_request(args.request)
        if args.hold:
            raise InvalidParameterError("--hold: a request holds the joints its goals leave out")
        robot = request.robot_for(robot)  # the request's group, where the SRDF has it
        result: planning.PlanResult = request.plan(robot, scene, **options)
        return robot, result
    if not (args.start and args.goal):
        raise InvalidParameterError("give --request FILE, or --start and --goal joint values")
    start, goal = q_of(robot, args.start, args.deg), q_of(robot, args.goal, args.deg)
    return robot, robot.plan(start, goal, scene=scene, hold=args.hold or None, **options)


SWEPT = "verified free over its whole motion (certified on the covers, which hold the shapes)"


def _certified(result: planning.PlanResult) -> str:
    """How the plan's segments were certified free, as the command prints it."""
    if result.swept and result.escapes:
        return (f"{SWEPT}; its {result.escapes} escape segment{'s' * (result.escapes > 1)} "
                f"from the ends on the exact shapes at {math.degrees(result.resolution):g} "
                "deg steps")  # fmt: skip
    if result.swept:
        return SWEPT
    if not result.verified:
        return "NOT verified"
    return f"verified free on the exact shapes at {math.degrees(result.resolution):g} deg steps"


SEARCHES = {"covers": "the sphere covers (compiled)", "exact": "the exact shapes"}


def _cmd_plan(args: argparse.Namespace) -> int:
    robot = robot_from_args(args)
    import numpy as np

    from ..common import validate as _validate

    _validate.number(args.acceleration, "--acceleration", lower=0.0, strict=True)
    _validate.number(args.rate, "--rate [Hz]", lower=0.0, strict=True)
    robot, result = _solve(args, robot, scene_of(robot, args.scene))
    ms = 1e3 * result.time_s
    if not result.success:
        print(f"{robot.name}: NOT solved in {ms:.0f} ms ({result.checks:,} configurations "
              f"checked): {result.reason}")  # fmt: skip
        return 1
    print(f"{robot.name}: solved in {ms:.0f} ms: {len(result.path)} waypoints, length "
          f"{result.length:.3f} (joint values), goal {result.goal}; {result.checks:,} "
          f"configurations checked, {result.nodes:,} tree nodes, searched on "
          f"{SEARCHES[result.search]}; every segment {_certified(result)}")  # fmt: skip
    values, names = shown_values(robot, result.path, args.deg)
    print(f"waypoints ({names}):")
    with np.printoptions(precision=4, suppress=True, linewidth=100):
        print(values)
    if args.output:
        _write(args, robot, result)
    return 0


def _write(args: argparse.Namespace, robot: Robot, result: planning.PlanResult) -> None:
    from .. import planning
    from ..motion import trapezoidal

    timed = trapezoidal(robot, result.path, acceleration=args.acceleration)
    samples = timed.at_rate(robot, args.rate)
    out = planning.write_joint_trajectory(
        args.output, robot.joints.names, samples.t, samples.angles, samples.qd, samples.qdd
    )
    print(f"wrote {out}: {len(samples.t)} points at {args.rate:g} Hz over {timed.duration:.2f} s "
          f"(trapezoidal, at rest at every waypoint, within the description's velocity limits "
          f"and {args.acceleration:g} rad/s^2)")  # fmt: skip


def add_plan(sub: Any) -> None:
    """The ``plan`` subcommand's arguments."""
    p = sub.add_parser(
        "plan", help="plan a collision-free motion (a MoveIt request, or start and goal)",
        description="Plan a collision-free joint motion (RRT-Connect, every segment checked on "
        "the exact shapes). From a MoveIt motion plan request (--request, YAML) or from "
        "--start and --goal values; obstacles from a MoveIt planning scene (YAML) or a "
        "toolkit scene (JSON). Exit 0 solved, 1 not solved, 2 bad input.",
    )  # fmt: skip
    p.add_argument("name", help="catalogue model, example robot, or .urdf/.xacro file")
    p.add_argument("--request", metavar="FILE", help="a MoveIt motion plan request (YAML)")
    p.add_argument("--scene", metavar="FILE", help=SCENE_HELP)
    p.add_argument(
        "--start",
        nargs="+",
        type=float,
        metavar="V",
        help="start joint values (all, or those of the joints moving the tool)",
    )
    p.add_argument("--goal", nargs="+", type=float, metavar="V", help="goal joint values, the same")
    p.add_argument("--deg", action="store_true", help="revolute joint values in degrees")
    p.add_argument("--hold", nargs="+", metavar="JOINT", help="joints kept at their start")
    p.add_argument("--time-limit", type=float, help="seconds (default: the request's, else 5)")
    p.add_argument("--seed", type=int, default=0, help="seed of the search (0)")
    p.add_argument(
        "--resolution", type=float, default=1.0,
        help="[deg] the largest joint step between configurations checked (1)",
    )  # fmt: skip
    p.add_argument("-o", "--output", metavar="FILE",
                   help="write the plan as a timed MoveIt joint trajectory (YAML)")  # fmt: skip
    p.add_argument("--acceleration", type=float, default=2.0,
                   help="[rad/s^2 or m/s^2] for --output's timing (2)")  # fmt: skip
    p.add_argument("--rate", type=float, default=100.0, help="[Hz] points of --output (100)")
    add_model_arguments(p)
    p.set_defaults(func=_cmd_plan)
