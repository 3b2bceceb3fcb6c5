"""Point M in motion ([P3], eqs. 2-4): its position, velocity and acceleration along
joint trajectories, and the inverse time problem (resolved-rate tracking)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ...common import validate as _validate
from ...errors import ConfigurationError
from ...robot import Robot
from .models import point_m

__all__ = ["History", "RateResult", "point_history", "resolved_rate"]


class History(NamedTuple):
    """r_M(t), V_M(t), a_M(t) of a point along joint trajectories f(t)."""

    t: np.ndarray  # (T,)
    q: np.ndarray  # (T, nq)
    qd: np.ndarray
    qdd: np.ndarray
    r: np.ndarray  # (T, 3) [m]
    v: np.ndarray  # (T, 3) [m/s]
    a: np.ndarray  # (T, 3) [m/s^2]


Trajectory = Callable[[float], ArrayLike] | Sequence[Callable[[float], float]] | ArrayLike


def _component(f: Callable[[float], ArrayLike], i: int) -> Callable[[float], float]:
    return lambda s: float(np.asarray(f(s), dtype=float)[i])


def _trajectory(f: Trajectory, t: np.ndarray, nq: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, qd, qdd) at the times t: callables differentiated by central differences
    (h = 1e-4 s), samples by second-order finite differences."""
    if callable(f) or (isinstance(f, Sequence) and all(callable(g) for g in f)):
        funcs: list[Callable[[float], float]] = (
            [_component(f, i) for i in range(nq)] if callable(f) else list(f)  # type: ignore[arg-type]
        )
        if len(funcs) != nq:
            raise ConfigurationError(f"need {nq} functions f_i(t), got {len(funcs)}")
        h = 1e-4

        def sample(shift: float) -> np.ndarray:
            values = [[g(s + shift) for g in funcs] for s in t]
            return _validate.array(values, "f(t)", error=ConfigurationError)

        q, qp, qm = sample(0.0), sample(h), sample(-h)
        return q, (qp - qm) / (2 * h), (qp - 2 * q + qm) / (h * h)
    q = _validate.array(f, "f", error=ConfigurationError)
    if q.shape != (len(t), nq):
        raise ConfigurationError(f"sampled f must have shape ({len(t)}, {nq}), got {q.shape}")
    qd = np.gradient(q, t, axis=0, edge_order=2)
    qdd = np.gradient(qd, t, axis=0, edge_order=2)
    return q, qd, qdd


def _times(t: ArrayLike) -> np.ndarray:
    times = _validate.array(t, "t", error=ConfigurationError)
    if times.ndim != 1 or len(times) < 3 or np.any(np.diff(times) <= 0):
        raise ConfigurationError("t must be at least 3 increasing times")
    return times


def point_history(
    robot: Robot, f: Trajectory, t: Sequence[float], rho: object | None = None
) -> History:
    """Position, velocity and acceleration of point M along f(t) ([P3], eqs. 2-4).

    ``f`` is one callable returning the joint vector, a list of callables f_i(t), or an
    array (T, nq) sampled at the times ``t`` (then differentiated numerically, second
    order). ``rho`` defaults to the model's ``point_m`` frame for the [P3] models and
    to the tip's origin otherwise.
    """
    times = _times(t)
    rho_ = point_m(robot, rho)
    q, qd, qdd = _trajectory(f, times, robot.nq)
    out = [robot.point_kinematics(*row, rho_) for row in zip(q, qd, qdd, strict=True)]
    r, v, a = (np.array(x) for x in zip(*out, strict=True))
    return History(times, q, qd, qdd, r, v, a)


class RateResult(NamedTuple):
    """Resolved-rate tracking of a Cartesian path by point M."""

    t: np.ndarray
    q: np.ndarray  # (T, nq) joint values
    r: np.ndarray  # (T, 3) achieved positions of M
    error: np.ndarray  # (T,) |r - path| [m]
    success: bool  # every error within tol and every q within the limits


def resolved_rate(
    robot: Robot,
    path: object,
    t: Sequence[float],
    q0: ArrayLike,
    rho: object | None = None,
    *,
    gain: float = 20.0,
    tol: float = 1e-4,
    damping: float = 1e-6,
    substeps: int = 10,
) -> RateResult:
    """Drive M along a sampled Cartesian path by integrating joint rates ([P3]'s inverse).

    qd = J_M^+ (dp/dt + gain (p_path - r_M)), with J_M the Jacobian of point M and a
    small damping in the pseudo-inverse; explicit Euler with ``substeps`` per sample,
    clipped to the joint limits.
    """
    times = _times(t)
    pts = _validate.array(path, "path", error=ConfigurationError)
    if pts.shape != (len(times), 3):
        raise ConfigurationError(f"path must have shape ({len(times)}, 3), got {pts.shape}")
    rho_ = point_m(robot, rho)
    gain = _validate.number(gain, "gain [1/s]", lower=0.0, strict=True)
    tol = _validate.number(tol, "tol [m]", lower=0.0, strict=True)
    damping = _validate.number(damping, "damping", lower=0.0)
    substeps = _validate.count(substeps, "substeps", maximum=10_000)
    q = robot.joints.check(q0).copy()
    vel = np.gradient(pts, times, axis=0, edge_order=2)

    def point_and_jacobian(qq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        T = robot.fk(qq)
        J = robot.jacobian(qq)
        arm = T[:3, :3] @ rho_
        skew = np.array([[0, -arm[2], arm[1]], [arm[2], 0, -arm[0]], [-arm[1], arm[0], 0]])
        return T[:3, 3] + arm, J[:3] - skew @ J[3:]

    qs, rs = [q.copy()], [point_and_jacobian(q)[0]]
    for k in range(1, len(times)):
        dt = (times[k] - times[k - 1]) / substeps
        for s in range(substeps):
            frac = (s + 0.5) / substeps
            p_des = pts[k - 1] + frac * (pts[k] - pts[k - 1])
            v_des = vel[k - 1] + frac * (vel[k] - vel[k - 1])
            r, J = point_and_jacobian(q)
            cmd = v_des + gain * (p_des - r)
            qd = J.T @ np.linalg.solve(J @ J.T + damping * np.eye(3), cmd)
            q = np.clip(q + dt * qd, robot.joints.lower, robot.joints.upper)
        qs.append(q.copy())
        rs.append(point_and_jacobian(q)[0])
    r_all = np.array(rs)
    err = np.linalg.norm(r_all - pts, axis=1)
    return RateResult(times, np.array(qs), r_all, err, bool(np.all(err <= tol)))
