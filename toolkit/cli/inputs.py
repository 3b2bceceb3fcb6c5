"""The command line's model arguments: ``--set``/``--arg``, ``--package-dir``, ``--tip``,
and the robot they name (a catalogue model, an example robot, or a URDF/xacro file)."""

from __future__ import annotations

import argparse
import csv
import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..descriptions import MODELS, example_robots
from ..errors import InvalidParameterError, UnknownModelError
from ..robot import Robot, load, load_example, load_urdf

__all__ = [
    "add_model_arguments",
    "csv_column",
    "load_model",
    "parse_sets",
    "read_csv",
    "robot_from_args",
]

MAX_CSV_BYTES = 64 * 1024 * 1024


def parse_sets(items: Sequence[str]) -> dict[str, str]:
    params = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise InvalidParameterError(f"--set expects NAME=VALUE, got {item!r}")
        params[key.strip()] = value.strip()
    return params


def load_model(
    name: str, sets: Sequence[str], package_dirs: Sequence[str] = (), tip: str | None = None
) -> Robot:
    """A catalogue model, an example robot, or a URDF/xacro file (``--set`` = xacro args).

    Known names come first: a file in the current folder named like a model does not
    shadow it (give it as ``./name``, or with its ``.urdf``/``.xacro`` suffix)."""
    if Path(name).suffix not in (".urdf", ".xacro"):
        if name in MODELS:
            return _with_tip(load(name, **parse_sets(sets)), tip)
        if name in example_robots():
            if sets:
                raise InvalidParameterError(
                    f"--set applies to catalogue models only, not to {name!r}"
                )
            return _with_tip(load_example(name), tip)
        if not Path(name).is_file():
            raise UnknownModelError(name, [*MODELS, *example_robots()])
    dirs = list(package_dirs) or None
    return load_urdf(name, package_dirs=dirs, args=parse_sets(sets), tip=tip)


def add_model_arguments(p: argparse.ArgumentParser, packages: bool = True) -> None:
    """``--set``/``--arg``, and for commands that load a robot ``--package-dir`` and ``--tip``."""
    p.add_argument(
        "--set",
        "--arg",
        dest="set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a xacro argument (repeatable): a catalogue model's, or a .xacro file's",
    )
    if not packages:
        return
    p.add_argument(
        "--package-dir",
        action="append",
        default=[],
        metavar="DIR",
        help="a folder holding ROS packages, for $(find ...) and package:// (repeatable)",
    )
    p.add_argument(
        "--tip",
        default=None,
        metavar="FRAME",
        help="the tool frame (default: the model's; for files, the end of the arm)",
    )


def _with_tip(robot: Robot, tip: str | None) -> Robot:
    if tip is None:
        return robot
    robot.frame_id(tip)  # an unknown frame lists the valid ones
    return Robot(
        robot.model,
        name=robot.name,
        tip=tip,
        urdf_path=robot.urdf_path,
        params=robot.params,
        facts=robot.facts,
    )


def robot_from_args(args: argparse.Namespace) -> Robot:
    """The robot of a command's NAME, ``--set``, ``--package-dir`` and ``--tip``."""
    return load_model(args.name, args.set, args.package_dir, getattr(args, "tip", None))


def read_csv(path: str) -> tuple[list[str], list[list[str]]]:
    """(header, rows) of a CSV file with a header row and at least one data row."""
    file = Path(path)
    if not file.is_file():
        raise InvalidParameterError(f"no such CSV file: {path}")
    if file.stat().st_size > MAX_CSV_BYTES:
        raise InvalidParameterError(f"{path}: larger than {MAX_CSV_BYTES >> 20} MiB")
    try:  # utf-8-sig: a byte-order mark (as spreadsheets write) is not part of the header
        text = file.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidParameterError(f"cannot read {path}: {exc}") from None
    rows = list(csv.reader(io.StringIO(text)))
    while rows and not any(cell.strip() for cell in rows[-1]):
        rows.pop()  # trailing blank lines
    if len(rows) < 2:
        raise InvalidParameterError(f"{path}: a header row and at least one data row needed")
    header = [h.strip() for h in rows[0]]
    for i, row in enumerate(rows[1:]):
        extra = [cell for cell in row[len(header) :] if cell.strip()]
        if extra:
            raise InvalidParameterError(
                f"{path}, row {i + 2}: {len(row)} cells, the header has {len(header)} "
                f"(extra: {', '.join(repr(c[:20]) for c in extra[:3])})"
            )
    return header, rows[1:]


def csv_column(rows: list[list[str]], k: int, name: str, path: str) -> np.ndarray:
    """Column ``k`` of ``rows`` as numbers (NaN where empty); a cell that is not a finite
    number is refused, naming its row and column."""
    out = np.full(len(rows), np.nan)
    for i, row in enumerate(rows):
        cell = row[k].strip() if k < len(row) else ""
        if cell:
            try:
                out[i] = float(cell)
            except ValueError:
                raise InvalidParameterError(
                    f"{path}, row {i + 2}, column {name!r}: not a number: {cell[:40]!r}"
                ) from None
            if not np.isfinite(out[i]):
                raise InvalidParameterError(f"{path}, row {i + 2}, column {name!r}: {cell!r}")
    return out
