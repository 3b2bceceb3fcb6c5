"""``toolkit calibrate``: a robot's calibration from a CSV file of joint values and
measurements (see :mod:`toolkit.calibration` and docs/calibration.md).

The CSV file has a header row. Columns named like the robot's joints hold the commanded
joint values (one per joint: angle [rad] or stroke [m]; every joint is needed); ``x``,
``y``, ``z`` a tool position [m] (a laser tracker's); ``<link>:gx``, ``<link>:gy``,
``<link>:gz`` the direction of gravity in that link's frame (an accelerometer's or an
inclinometer's, any length). An empty cell
means "not measured in this row". Other columns are refused.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from .. import calibration as cal
from ..errors import InvalidParameterError
from ..robot import Robot
from .inputs import add_model_arguments, csv_column, read_csv, robot_from_args

__all__ = ["add_calibrate"]

GRAVITY = ("gx", "gy", "gz")


def read_measurements(
    robot: Robot, path: str, sigma_position: float, sigma_gravity: float
) -> tuple[np.ndarray, cal.Measurements]:
    """Commanded joint values (N, nq) and the measurements of a calibration CSV file."""
    header, rows = read_csv(path)
    joints = robot.joint_names
    known = {*joints, "x", "y", "z"}
    unknown = [h for h in header if h not in known and h.rpartition(":")[2] not in GRAVITY]
    missing = [j for j in joints if j not in header]
    if unknown or missing:
        problems = [f"{what} {', '.join(repr(c) for c in cols[:5])}"
                    for what, cols in (("unknown column(s)", unknown),
                                       ("missing joint column(s)", missing)) if cols]  # fmt: skip
        raise InvalidParameterError(
            f"{path}: {'; '.join(problems)} (joints: {', '.join(joints)}; measurements: "
            "x, y, z, <link>:gx, :gy, :gz)"
        )
    cols = {h: csv_column(rows, k, h, path) for k, h in enumerate(header)}
    Q = np.column_stack([cols[j] for j in joints])
    if np.isnan(Q).any():
        raise InvalidParameterError(f"{path}: every row needs every joint value")
    Q = robot.check_q(robot.q_from_angles(Q), batch=True)
    meas = cal.Measurements()
    groups: dict[str, list[str]] = {"": ["x", "y", "z"]}
    for h in header:
        link, sep, _ = h.rpartition(":")
        if sep:
            groups.setdefault(link, [f"{link}:gx", f"{link}:gy", f"{link}:gz"])
    for link, names in groups.items():
        if not any(n in cols for n in names):
            continue
        if not all(n in cols for n in names):
            raise InvalidParameterError(f"{path}: columns {names} come together")
        values = np.column_stack([cols[n] for n in names])
        have = ~np.isnan(values).any(axis=1)
        if not have.any():
            continue
        at = np.flatnonzero(have)
        if link:
            meas = meas + cal.Measurements.gravity(link, values[have], sigma_gravity, at=at)
        else:
            meas = meas + cal.Measurements.positions(values[have], sigma_position, at=at)
    if not meas.blocks:
        raise InvalidParameterError(f"{path}: no measurement column (x, y, z or <link>:gx ...)")
    return Q, meas


def _cmd_calibrate(args: argparse.Namespace) -> int:
    robot = robot_from_args(args)
    kinds = [k.strip() for k in args.parameters.split(",") if k.strip()]
    Q, meas = read_measurements(robot, args.csv, args.sigma_position, args.sigma_gravity)
    result = cal.identify(robot, Q, meas, parameters=kinds)
    lines = [str(result), "", f"{'parameter':36s} {'value':>14s} {'std':>10s}"]
    for name, value in result.parameters.items():
        if name not in result.identifiability.fixed:
            lines.append(f"{name:36s} {value:14.6g} {result.std[name]:10.2g}")
    if args.validate:
        Qv, mv = read_measurements(robot, args.validate, args.sigma_position, args.sigma_gravity)
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
        help=f"comma-separated kinds from {', '.join(k for k in cal.KINDS if k != 'backlash')}",
    )
    p.add_argument("--sigma-position", type=float, default=2e-5, help="[m] (default 2e-5)")
    p.add_argument("--sigma-gravity", type=float, default=1e-3, help="per axis (default 1e-3)")
    p.add_argument("--validate", metavar="CSV", help="held-out rows to measure the gain on")
    p.add_argument("-o", "--output", help="write the calibrated URDF here")
    p.add_argument("--report", help="write the printed report here too")
    add_model_arguments(p)
    p.set_defaults(func=_cmd_calibrate)
