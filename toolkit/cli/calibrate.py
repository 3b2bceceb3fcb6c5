"""``toolkit calibrate``: a robot's calibration from a CSV file of joint values and
measurements (see :mod:`toolkit.calibration` and docs/calibration.md).

The CSV file has a header row. Columns named like the robot's joints hold the commanded
joint values (one per joint: angle [rad] or stroke [m]; every joint is needed); ``x``,
``y``, ``z`` a tool position [m] (a laser tracker's); ``<link>:gx``, ``<link>:gy``,
``<link>:gz`` the direction of gravity in that link's frame (an accelerometer's or an
inclinometer's, any length). An empty cell
means "not measured in this row". Other columns are refused.
:func:`toolkit.calibration.read_measurements` and
:func:`~toolkit.calibration.write_measurements` read and write such files from Python.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .inputs import add_model_arguments, robot_from_args

__all__ = ["add_calibrate"]


KINDS = ("offsets", "geometry", "base", "tool", "compliance")
"""The parameter kinds ``--parameters`` takes: :data:`toolkit.calibration.KINDS` but the
backlash (a test keeps the two in step; the help is made without importing calibration)."""


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from .. import calibration as cal

    robot = robot_from_args(args)
    kinds = [k.strip() for k in args.parameters.split(",") if k.strip()]
    Q, meas = cal.read_measurements(robot, args.csv, args.sigma_position, args.sigma_gravity)
    result = cal.identify(robot, Q, meas, parameters=kinds)
    lines = [str(result), "", f"{'parameter':36s} {'value':>14s} {'std':>10s}"]
    for name, value in result.parameters.items():
        if name not in result.identifiability.fixed:
            lines.append(f"{name:36s} {value:14.6g} {result.std[name]:10.2g}")
    if args.validate:
        Qv, mv = cal.read_measurements(robot, args.validate, args.sigma_position,
                                       args.sigma_gravity)  # fmt: skip
        lines += ["", f"held-out ({len(Qv)} rows, m or rad): {result.validate(Qv, mv)}"]
    text = "\n".join(lines)
    print(text)
    if args.output:
        Path(args.output).write_text(result.urdf_text, encoding="utf-8")
        print(f"wrote the calibrated URDF to {args.output}")
    if args.report:
        Path(args.report).write_text(text + "\n", encoding="utf-8")
    return 0 if result.converged else 1


def add_calibrate(sub: Any) -> None:
    """The ``calibrate`` subcommand's arguments."""
    p = sub.add_parser("calibrate", help="identify a robot's errors from a CSV of measurements")
    p.add_argument("name", help="catalogue model, example robot, or .urdf/.xacro file")
    p.add_argument("csv", help="joint values and measurements (see docs/calibration.md)")
    p.add_argument(
        "--parameters",
        default="offsets,geometry,base,tool",
        help=f"comma-separated kinds from {', '.join(KINDS)}",
    )
    p.add_argument("--sigma-position", type=float, default=2e-5, help="[m] (default 2e-5)")
    p.add_argument("--sigma-gravity", type=float, default=1e-3, help="per axis (default 1e-3)")
    p.add_argument("--validate", metavar="CSV", help="held-out rows to measure the gain on")
    p.add_argument("-o", "--output", help="write the calibrated URDF here")
    p.add_argument("--report", help="write the printed report here too")
    add_model_arguments(p)
    p.set_defaults(func=_cmd_calibrate)
