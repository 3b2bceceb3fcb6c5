"""Trajectories to and from CSV: ``t, q:<joint>..., qd:<joint>..., qdd:<joint>..., tau:<joint>...``
(one value per joint, [s], [rad or m], [/s], [/s^2], [N m or N]), as a spreadsheet or another
tool reads and writes them."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..common import tables as _tables
from ..common import validate as _validate
from ..errors import InvalidParameterError
from .profiles import cubic
from .trajectory import Trajectory

__all__ = ["hermite", "read_trajectory", "write_csv"]


def write_csv(
    trajectory: Trajectory, robot: Any, path: str | Path, rate: float = 1000.0, *,
    payload: object = None,
) -> Path:  # fmt: skip
    """Write ``trajectory`` sampled at ``rate`` [Hz] with the joint torques along it
    (:meth:`Trajectory.torques`, ``payload`` as there) to ``path``: a header ``t, q:<joint>,
    ..., qd:<joint>, ..., qdd:<joint>, ..., tau:<joint>, ...`` and one row per sample, each
    number to 17 significant digits (read back exactly). Returns the path."""
    if not isinstance(trajectory, Trajectory):
        raise InvalidParameterError(f"write_csv takes a Trajectory, got {trajectory!r:.80}")
    if not isinstance(path, str | Path) or not str(path) or "\0" in str(path):
        raise InvalidParameterError(f"path must be a file name, got {path!r:.80}")
    samples, tau = trajectory.torques(robot, rate, payload=payload)
    names = list(robot.joints.names)
    header = ["t"] + [f"{kind}:{n}" for kind in ("q", "qd", "qdd", "tau") for n in names]
    data = np.column_stack([samples.t, samples.angles, samples.qd, samples.qdd, tau])
    out = Path(path)
    try:
        with open(out, "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(header)
            writer.writerows([[f"{x:.17g}" for x in row] for row in data.tolist()])
    except OSError as exc:
        raise InvalidParameterError(f"cannot write {path}: {exc}") from None
    return out


def hermite(times: ArrayLike, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Trajectory:
    """The piecewise quintic through samples (K,) times [s] from 0 with their values,
    velocities and accelerations (K, n): on each interval the one quintic that matches both
    ends to the second derivative (so the trajectory is continuous in acceleration)."""
    times = _validate.real_array(times, "times [s]").reshape(-1)
    if len(times) < 2 or not np.all(np.isfinite(times)) or times[0] != 0 or np.any(
            np.diff(times) <= 0):  # fmt: skip
        raise InvalidParameterError("times must be 2 or more finite times [s] from 0, rising")
    q, qd, qdd = (_validate.real_array(a, w) for a, w in ((q, "q"), (qd, "qd"), (qdd, "qdd")))
    if q.ndim != 2 or q.shape[0] != len(times) or qd.shape != q.shape or qdd.shape != q.shape:
        raise InvalidParameterError(f"q, qd and qdd must be ({len(times)}, n): a row a time")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(qdd))):
        raise InvalidParameterError("q, qd and qdd must be finite")
    h = np.diff(times)[:, None]
    p0, p1, v0, v1, a0, a1 = q[:-1], q[1:], qd[:-1], qd[1:], qdd[:-1], qdd[1:]
    c = np.zeros((len(h), q.shape[1], 6))
    c[:, :, 0], c[:, :, 1], c[:, :, 2] = p0, v0, a0 / 2
    c[:, :, 3] = (20 * (p1 - p0) - (8 * v1 + 12 * v0) * h - (3 * a0 - a1) * h**2) / (2 * h**3)
    c[:, :, 4] = (30 * (p0 - p1) + (14 * v1 + 16 * v0) * h + (3 * a0 - 2 * a1) * h**2) / (2 * h**4)
    c[:, :, 5] = (12 * (p1 - p0) - 6 * (v1 + v0) * h - (a1 - a0) * h**2) / (2 * h**5)
    return Trajectory(times.copy(), c, q.copy(), times.copy(), "csv")


def read_trajectory(path: str | Path, robot: Any) -> Trajectory:
    """A trajectory of ``robot`` from a CSV file: a column ``t`` [s] (strictly increasing;
    shifted to start at 0), ``q:<joint>`` for every joint of the robot (any order; other
    columns, such as ``tau:``, are ignored), and optionally ``qd:<joint>`` and
    ``qdd:<joint>`` for every joint (both or neither). With them the trajectory is the
    piecewise quintic matching every sample to the acceleration (:func:`hermite`; a file
    :func:`write_csv` wrote reads back as the trajectory it sampled); without them, the
    cubic spline through the samples at rest at both ends (:func:`toolkit.motion.cubic`)."""
    header, rows = _tables.read_csv(path)
    where = {h: k for k, h in enumerate(header)}
    if "t" not in where:
        raise InvalidParameterError(f"{path}: no column 't' [s] (the header has {header[:8]})")
    if len(rows) < 2:
        raise InvalidParameterError(f"{path}: a trajectory needs at least 2 rows")
    names = list(robot.joints.names)

    def block(kind: str) -> np.ndarray | None:
        wanted = [f"{kind}:{n}" for n in names]
        missing = [w for w in wanted if w not in where]
        if len(missing) == len(wanted) and kind != "q":
            return None
        if missing:
            raise InvalidParameterError(f"{path}: no column {missing[0]!r} ({robot.name})")
        cols = [_tables.csv_column(rows, where[w], w, str(path)) for w in wanted]
        out = np.column_stack(cols)
        if np.isnan(out).any():
            raise InvalidParameterError(f"{path}: an empty cell in the {kind!r} columns")
        return out

    t = _tables.csv_column(rows, where["t"], "t", str(path))
    if np.isnan(t).any() or np.any(np.diff(t) <= 0):
        raise InvalidParameterError(f"{path}: the times 't' must be given and strictly increase")
    t = t - t[0]
    q, qd, qdd = block("q"), block("qd"), block("qdd")
    assert q is not None
    if (qd is None) != (qdd is None):
        raise InvalidParameterError(f"{path}: give both 'qd:' and 'qdd:' columns, or neither")
    if qd is None or qdd is None:
        return cubic(robot, robot.joints.q_from_angles(q), t)
    return hermite(t, q, qd, qdd)
