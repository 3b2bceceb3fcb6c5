"""Measurements as the CSV file ``toolkit calibrate`` reads (docs/calibration.md): a header
row; one column per joint (the commanded angle [rad] or stroke [m]); ``x``, ``y``, ``z`` a
tool position [m]; ``<link>:gx``, ``<link>:gy``, ``<link>:gz`` the direction of gravity in
that link's frame. An empty cell is "not measured in this row". The standard deviations
are not columns: the reader takes them (as the CLI's ``--sigma-position`` and
``--sigma-gravity``), so a file written and read back keeps every value and its row, and
the sigmas given to the reader."""

from __future__ import annotations

import csv
import io
import math
import os
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..common import tables as _tables
from ..errors import InvalidParameterError
from ..robot import Robot
from ._measure import Measurements

__all__ = ["GRAVITY", "read_measurements", "write_measurements"]

GRAVITY = ("gx", "gy", "gz")


def read_measurements(
    robot: Robot, path: str | os.PathLike[str], sigma_position: float = 2e-5,
    sigma_gravity: float = 1e-3,
) -> tuple[np.ndarray, Measurements]:  # fmt: skip
    """(commanded q (N, nq), the measurements) of a calibration CSV file (module doc);
    ``sigma_position`` [m] and ``sigma_gravity`` (per axis) their standard deviations. A
    column that is neither a joint nor a measurement, a missing joint, a cell that is not a
    number and a partial position or gravity triple are refused, naming the file, row and
    column."""
    path = os.fspath(path)
    header, rows = _tables.read_csv(path)
    joints = robot.joints.names
    unknown = [
        h
        for h in header
        if h not in {*joints, "x", "y", "z"} and h.rpartition(":")[2] not in GRAVITY
    ]
    missing = [j for j in joints if j not in header]  # fmt: skip
    if unknown or missing:
        problems = [f"{what} {', '.join(repr(c) for c in cols[:5])}"
                    for what, cols in (("unknown column(s)", unknown),
                                       ("missing joint column(s)", missing)) if cols]  # fmt: skip
        raise InvalidParameterError(
            f"{path}: {'; '.join(problems)} (joints: {', '.join(joints)}; measurements: "
            "x, y, z, <link>:gx, :gy, :gz)"
        )
    cols = {h: _tables.csv_column(rows, k, h, path) for k, h in enumerate(header)}
    Q = np.column_stack([cols[j] for j in joints])
    if np.isnan(Q).any():
        raise InvalidParameterError(f"{path}: every row needs every joint value")
    Q = robot.joints.check(robot.joints.q_from_angles(Q), batch=True)
    meas = Measurements()
    groups: dict[str, list[str]] = {"": ["x", "y", "z"]}
    for h in header:
        link, sep, _ = h.rpartition(":")
        if sep:
            groups.setdefault(link, [f"{link}:{g}" for g in GRAVITY])
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
            meas = meas + Measurements.gravity(link, values[have], sigma_gravity, at=at)
        else:
            meas = meas + Measurements.positions(values[have], sigma_position, at=at)
    if not meas.blocks:
        raise InvalidParameterError(f"{path}: no measurement column (x, y, z or <link>:gx ...)")
    return Q, meas


def write_measurements(
    path: str | os.PathLike[str], robot: Robot, q: ArrayLike, measurements: Measurements
) -> Path:
    """Write commanded ``q`` (N, nq) and ``measurements`` (positions and gravity
    directions; a pose block has no columns and is refused) as the CSV file
    :func:`read_measurements` and ``toolkit calibrate`` read; every number as Python's
    shortest exact form, so reading it back gives the same values. Returns the path."""
    if not isinstance(measurements, Measurements):
        raise InvalidParameterError(f"measurements must be Measurements, got {measurements!r:.80}")
    Q = robot.joints.check(q, batch=True)
    table = {name: robot.joints.angles(Q)[:, k] for k, name in enumerate(robot.joints.names)}
    for name, values in measurements.columns(len(Q)).items():
        if name in table:
            raise InvalidParameterError(f"a measurement column is named like a joint: {name!r}")
        table[name] = values
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(list(table))
    for i in range(len(Q)):
        writer.writerow(
            ["" if math.isnan(v) else repr(float(v)) for v in (c[i] for c in table.values())]
        )
    target = Path(path)
    target.write_text(out.getvalue(), encoding="utf-8")
    return target
