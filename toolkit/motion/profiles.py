"""Trajectories through joint waypoints (see :mod:`toolkit.motion`): quintic segments at rest
at every waypoint, a cubic spline through them at rest at both ends, and trapezoidal
velocity within joint velocity and acceleration limits."""

from __future__ import annotations

import importlib
import itertools
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import InstallationError, InvalidParameterError
from ..robot import as_robot
from .trajectory import Trajectory

__all__ = ["cubic", "extra_module", "limit_of", "quintic", "trapezoidal", "waypoint_values"]

QUINTIC_VELOCITY = 15.0 / 8.0
"""The peak speed of a rest-to-rest quintic over a move d in time T is 15/8 d / T."""
QUINTIC_ACCELERATION = 10.0 / math.sqrt(3.0)
"""... and its peak acceleration 10 / sqrt(3) d / T^2."""


def extra_module(name: str, feature: str) -> Any:
    """The module ``name`` of the ``motion`` extra, or an InstallationError naming it."""
    try:
        return importlib.import_module(name)
    except ImportError:  # pragma: no cover - the test extra installs it
        raise InstallationError(f"{feature} needs the {name.split('.')[0]} package: pip "
                                "install 'manipulator-toolkit[motion]'") from None  # fmt: skip


def waypoint_values(robot: Any, waypoints: ArrayLike) -> np.ndarray:
    """(K, n) one value per joint of K >= 2 configurations (N, nq) within the joint limits;
    a continuous joint's angle unwrapped so that it takes the short way round."""
    Q = as_robot(robot).joints.check(waypoints, batch=True)
    if Q.ndim != 2 or len(Q) < 2:
        raise InvalidParameterError("waypoints: at least 2 configurations (K, nq)")
    outside = np.flatnonzero(
        ((Q < robot.joints.lower - 1e-9) | (Q > robot.joints.upper + 1e-9)).any(axis=1)
    )
    if len(outside):
        raise InvalidParameterError(
            f"waypoint {int(outside[0])} is outside {robot.name}'s joint limits"
        )
    A = robot.joints.angles(Q)
    for j in range(robot.model.njoints - 1):
        joint = robot.model.joints[j + 1]
        if joint.nq == 2 and joint.nv == 1:
            A[:, joint.idx_v] = np.unwrap(A[:, joint.idx_v])
    return np.asarray(A)


def limit_of(robot: Any, value: ArrayLike | None, what: str, default: np.ndarray | None) -> (
    np.ndarray | None
):  # fmt: skip
    """A per-joint limit (nv,) > 0 [rad/s, rad/s^2 or m/s, m/s^2] (a number for all), or the
    robot's own (``default``) where that is finite and positive, or None."""
    if value is None:
        if default is None or not np.all(np.isfinite(default)) or np.any(default <= 0):
            return None
        return np.asarray(default, dtype=float)
    given = _validate.real_array(value, what)
    if given.size not in (1, robot.joints.nv) or given.ndim > 1:
        raise InvalidParameterError(f"{what}: one value or {robot.joints.nv} (one per joint), got "
                                    f"shape {given.shape}")  # fmt: skip
    arr = np.broadcast_to(given.reshape(-1), (robot.joints.nv,)).astype(float)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise InvalidParameterError(f"{what} must be finite and > 0 for every joint")
    return arr


def _times(times: ArrayLike | None, count: int) -> np.ndarray | None:
    if times is None:
        return None
    t = _validate.real_array(times, "times [s]").reshape(-1)
    if t.shape != (count,) or not np.all(np.isfinite(t)) or t[0] != 0 or np.any(np.diff(t) <= 0):
        raise InvalidParameterError(
            f"times must be {count} finite times [s] from 0, strictly increasing"
        )
    return t


def _durations(
    robot: Any, A: np.ndarray, times: ArrayLike | None, velocity: ArrayLike | None,
    acceleration: ArrayLike | None,
) -> np.ndarray:  # fmt: skip
    """Each segment's duration: from ``times``, else the shortest a rest-to-rest quintic needs
    within the velocity (default the description's) and acceleration limits."""
    t = _times(times, len(A))
    if t is not None:
        return np.diff(t)
    v = limit_of(robot, velocity, "velocity", np.asarray(robot.model.velocityLimit))
    a = limit_of(robot, acceleration, "acceleration", None)
    if v is None and a is None:
        raise InvalidParameterError(
            f"{robot.name}: no times given and no velocity limits in its description: pass "
            "times=, velocity= or acceleration="
        )
    d = np.abs(np.diff(A, axis=0))
    T = np.zeros(len(d))
    if v is not None:
        T = np.maximum(T, (QUINTIC_VELOCITY * d / v).max(axis=1))
    if a is not None:
        T = np.maximum(T, np.sqrt(QUINTIC_ACCELERATION * d / a).max(axis=1))
    if np.any(T <= 0):
        raise InvalidParameterError(
            f"waypoints {int(np.flatnonzero(T <= 0)[0])} and the next are the same: no motion"
        )
    return T


def quintic(
    robot: Any, waypoints: ArrayLike, times: ArrayLike | None = None, *,
    velocity: ArrayLike | None = None, acceleration: ArrayLike | None = None,
) -> Trajectory:  # fmt: skip
    """A quintic per segment, at rest (zero velocity and acceleration) at every waypoint (the
    Robotics Toolbox's ``jtraj`` segment by segment). ``times`` (K,) from 0 [s], or each
    segment as short as the ``velocity`` (default: the description's) and ``acceleration``
    limits allow."""
    A = waypoint_values(robot, waypoints)
    T = _durations(robot, A, times, velocity, acceleration)
    d = np.diff(A, axis=0)
    c = np.zeros((len(d), A.shape[1], 6))
    c[:, :, 0] = A[:-1]
    c[:, :, 3] = 10 * d / T[:, None] ** 3
    c[:, :, 4] = -15 * d / T[:, None] ** 4
    c[:, :, 5] = 6 * d / T[:, None] ** 5
    breaks = np.concatenate([[0.0], np.cumsum(T)])
    return Trajectory(breaks, c, A, breaks.copy(), "quintic")


def tridiagonal(
    lower: np.ndarray, diagonal: np.ndarray, upper: np.ndarray, rhs: np.ndarray
) -> np.ndarray:
    """x (m, n) of the tridiagonal system with ``diagonal`` (m,), ``lower`` (m - 1,) below
    it and ``upper`` (m - 1,) above, right-hand sides ``rhs`` (m, n): Thomas' algorithm, in
    O(m) time and memory (a dense solve of 100,000 knots asked for 75 GiB). Stable for a
    diagonally dominant matrix, as a spline's is (2 (h0 + h1) > h0 + h1)."""
    m = len(diagonal)
    low, up, diag = lower.tolist(), upper.tolist(), diagonal.tolist()
    scale, weight = [diag[0]] * m, [0.0] * m
    for i in range(1, m):  # forward: eliminate the lower diagonal (plain floats: fast)
        weight[i] = low[i - 1] / scale[i - 1]
        scale[i] = diag[i] - weight[i] * up[i - 1]
    columns = np.asarray(rhs, dtype=float).T.tolist()
    for x in columns:
        for i in range(1, m):
            x[i] -= weight[i] * x[i - 1]
        x[m - 1] /= scale[m - 1]
        for i in range(m - 2, -1, -1):  # back
            x[i] = (x[i] - up[i] * x[i + 1]) / scale[i]
    return np.array(columns).T.reshape(np.shape(rhs))


def cubic(
    robot: Any, waypoints: ArrayLike, times: ArrayLike | None = None, *,
    velocity: ArrayLike | None = None, acceleration: ArrayLike | None = None,
) -> Trajectory:  # fmt: skip
    """A cubic spline through the waypoints, continuous in acceleration, at rest (zero
    velocity) at both ends; ``times`` as for :func:`quintic` (default: the quintic's
    segment times). It does not stop at the waypoints between, and between them it may
    overshoot: check :meth:`~toolkit.motion.Trajectory.peaks` against the limits."""
    A = waypoint_values(robot, waypoints)
    h = _durations(robot, A, times, velocity, acceleration)
    K, n = A.shape
    V = np.zeros((K, n))
    if K > 2:  # the knot velocities: a tridiagonal system, clamped to 0 at both ends
        lower, upper = h[2:], h[:-2]  # row r: h[r+1] left of the diagonal, h[r] right of it
        diagonal = 2 * (h[:-1] + h[1:])
        d = np.diff(A, axis=0)
        rhs = 3 * (h[:-1, None] / h[1:, None] * d[1:] + h[1:, None] / h[:-1, None] * d[:-1])
        V[1:-1] = tridiagonal(lower, diagonal, upper, rhs)
    d = np.diff(A, axis=0)
    H = h[:, None]
    c = np.zeros((K - 1, n, 6))
    c[:, :, 0], c[:, :, 1] = A[:-1], V[:-1]
    c[:, :, 2] = (3 * d / H - 2 * V[:-1] - V[1:]) / H
    c[:, :, 3] = (-2 * d / H + V[:-1] + V[1:]) / H**2
    breaks = np.concatenate([[0.0], np.cumsum(h)])
    return Trajectory(breaks, c, A, breaks.copy(), "cubic")


def trapezoidal(
    robot: Any, waypoints: ArrayLike, *, velocity: ArrayLike | None = None,
    acceleration: ArrayLike,
) -> Trajectory:  # fmt: skip
    """Trapezoidal velocity (MATLAB's ``trapveltraj``), at rest at every waypoint: each
    segment as short as the joint ``velocity`` (default: the description's) and
    ``acceleration`` limits allow, every joint accelerating, cruising and braking over the
    same phases (so the slowest joint sets them and the others stay within their limits)."""
    A = waypoint_values(robot, waypoints)
    v = limit_of(robot, velocity, "velocity", np.asarray(robot.model.velocityLimit))
    a = limit_of(robot, acceleration, "acceleration", None)
    if v is None or a is None:
        raise InvalidParameterError(
            f"trapezoidal needs velocity and acceleration limits ({robot.name}'s description "
            "has no usable velocity limits: pass velocity=)" if v is None else
            "trapezoidal needs acceleration= (per joint or one for all)"
        )  # fmt: skip
    breaks, pieces, times = [0.0], [], [0.0]
    for q0, q1 in itertools.pairwise(A):
        d = q1 - q0
        need_a = float((np.abs(d) / a).max())  # ta (T - ta) >= |d| / a for every joint
        need_v = float((np.abs(d) / v).max())  # T - ta >= |d| / v
        if need_a <= 0:
            raise InvalidParameterError("two consecutive waypoints are the same: no motion")
        cruise_end = max(need_v, math.sqrt(need_a))  # T - ta
        ta = need_a / cruise_end
        speed, acc = d / cruise_end, d / cruise_end / ta
        start = breaks[-1]
        pieces.append(_piece(q0, 0.0 * d, acc / 2))
        q_ta = q0 + acc * ta**2 / 2
        if cruise_end - ta > 1e-12:
            pieces.append(_piece(q_ta, speed, 0.0 * d))
            breaks.append(start + ta)
        q_brake = q_ta + speed * (cruise_end - ta)
        pieces.append(_piece(q_brake, speed, -acc / 2))
        breaks += [start + cruise_end, start + cruise_end + ta]
        times.append(start + cruise_end + ta)
    return Trajectory(np.array(breaks), np.array(pieces), A, np.array(times), "trapezoidal")


def _piece(c0: np.ndarray, c1: np.ndarray, c2: np.ndarray) -> np.ndarray:
    out = np.zeros((len(c0), 6))
    out[:, 0], out[:, 1], out[:, 2] = c0, c1, c2
    return out
