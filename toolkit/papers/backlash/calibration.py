"""Calibration of [P1]'s backlash parameters (delta, k_H) from measurements.

Nonlinear least squares by Levenberg-Marquardt on central finite-difference Jacobians;
standard errors from the Gauss-Newton covariance s^2 (J^T J)^-1. Parameters the data
cannot see (a joint whose torque never leaves the dead zone, e.g. a vertical axis) are
frozen at their start values and reported with an infinite standard error.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ...common import validate as _validate
from ...errors import InvalidParameterError
from ...robot import Robot, as_robot
from .layer import Backlash

__all__ = ["Calibration", "calibrate"]

Predict = Callable[[np.ndarray], np.ndarray]


class Calibration(NamedTuple):
    """Estimated backlash parameters with their standard errors."""

    delta: np.ndarray | float  # [rad], per joint when calibrated per joint
    k_h: np.ndarray | float
    delta_stderr: np.ndarray | float
    k_h_stderr: np.ndarray | float
    rms: float  # residual RMS [m] (tip positions) or [rad] (joint angles)
    iterations: int
    converged: bool


def _measurements(
    q: np.ndarray, tips: ArrayLike | None, angles: ArrayLike | None
) -> tuple[np.ndarray, bool]:
    """(measurements, they are joint angles) checked against the commands' shape."""
    if (tips is None) == (angles is None):
        raise InvalidParameterError("give exactly one of measured_tip_positions, measured_angles")
    if angles is not None:
        measured, want = _validate.array(angles, "measured_angles"), q.shape
    else:
        measured, want = _validate.array(tips, "measured_tip_positions"), (len(q), 3)
    if measured.shape != want:
        raise InvalidParameterError(f"measurements must have shape {want}, got {measured.shape}")
    return measured, angles is not None


def _jacobian(predict: Predict, params: np.ndarray, rows: int) -> np.ndarray:
    """Central finite differences of the predictions with respect to the parameters."""
    J = np.empty((rows, len(params)))
    for i in range(len(params)):
        h = 1e-7 * max(1.0, abs(params[i]))
        dp = np.zeros_like(params)
        dp[i] = h
        J[:, i] = (predict(params + dp) - predict(params - dp)) / (2 * h)
    return J


class _Fit(NamedTuple):
    params: np.ndarray
    residual: np.ndarray
    JtJ: np.ndarray
    free: np.ndarray
    iterations: int
    converged: bool


def _levenberg_marquardt(
    predict: Predict, params: np.ndarray, target: np.ndarray, max_iter: int
) -> _Fit:
    """Minimise |predict(p) - target|^2 from ``params``; unidentifiable parameters stay put."""
    residual = predict(params) - target
    cost, lam = float(residual @ residual), 1e-3
    converged, iterations = False, 0
    free = np.ones(len(params), dtype=bool)
    JtJ = np.zeros((len(params), len(params)))
    for iterations in range(1, max_iter + 1):  # noqa: B007 - reported below
        J = _jacobian(predict, params, len(residual))
        norms = np.linalg.norm(J, axis=0)
        free = norms > 1e-9 * norms.max()
        Jf = J[:, free]
        JtJ, g = Jf.T @ Jf, Jf.T @ residual
        improved, rel, step = False, 0.0, np.zeros_like(params)
        while lam < 1e10:
            step = np.zeros_like(params)
            step[free] = np.linalg.solve(JtJ + lam * np.diag(np.diag(JtJ) + 1e-12), -g)
            r_new = predict(params + step) - target
            c_new = float(r_new @ r_new)
            if c_new < cost:
                improved, rel = True, (cost - c_new) / max(cost, 1e-300)
                params, residual, cost = params + step, r_new, c_new
                lam = max(lam / 10, 1e-12)
                break
            lam *= 10
        if not improved or rel < 1e-12 or np.max(np.abs(step)) < 1e-12:
            converged = True
            break
    return _Fit(params, residual, JtJ, free, iterations, converged)


def _standard_errors(fit: _Fit) -> tuple[np.ndarray, float]:
    """Standard errors from s^2 (J^T J)^-1 (infinite for the frozen parameters), and the
    residual RMS."""
    cost = float(fit.residual @ fit.residual)
    s2 = cost / max(len(fit.residual) - len(fit.params), 1)
    stderr = np.full(len(fit.params), np.inf)  # unidentifiable parameters: infinite error
    try:
        stderr[fit.free] = np.sqrt(np.clip(np.diag(s2 * np.linalg.inv(fit.JtJ)), 0, None))
    except np.linalg.LinAlgError:
        pass
    return stderr, float(np.sqrt(cost / len(fit.residual)))


def calibrate(
    robot: Robot,
    commands: ArrayLike,
    measured_tip_positions: ArrayLike | None = None,
    *,
    measured_angles: ArrayLike | None = None,
    payload: float = 0.0,
    nominal_torque: ArrayLike | None = None,
    per_joint: bool = False,
    initial: tuple[float, float] = (0.02, 0.1),
    max_iter: int = 50,
) -> Calibration:
    """Estimate delta and k_H by nonlinear least squares (Levenberg-Marquardt).

    Args:
        robot: the robot model.
        commands: commanded configurations, shape (N, n), N >= 2.
        measured_tip_positions: tool positions [m] from an external tracker, (N, 3).
        measured_angles: joint-output angles [rad] (inclinometers), (N, n); give this
            or ``measured_tip_positions``.
        payload: payload [kg] during the measurements.
        per_joint: estimate one (delta, k_H) pair per joint instead of a shared pair
            (joints whose torque never leaves the dead zone are not identifiable).
        max_iter: Levenberg-Marquardt iterations, >= 1.

    Returns:
        :class:`Calibration` with the estimates, their standard errors and the residual
        RMS; ``converged`` says whether the iteration settled within ``max_iter``.
    """
    q = as_robot(robot).joints.check(commands, batch=True)
    per_joint = _validate.flag(per_joint, "per_joint")
    if q.ndim != 2 or len(q) < 2:
        raise InvalidParameterError("commands must have shape (N, n) with N >= 2")
    measured, by_angles = _measurements(q, measured_tip_positions, measured_angles)
    max_iter = _validate.count(max_iter, "max_iter")
    start = [_validate.number(v, "initial", lower=0.0, strict=True) for v in initial]
    groups = robot.nq if per_joint else 1
    base = Backlash(robot, nominal_torque=nominal_torque, payload=payload)

    def predict(p: np.ndarray) -> np.ndarray:
        if per_joint:
            layer = base.with_parameters(np.abs(p[:groups]), np.abs(p[groups:]))
        else:
            layer = base.with_parameters(abs(p[0]), abs(p[1]))
        theta = layer.solve(q).theta  # trial parameters may not converge: a worse cost
        return (theta if by_angles else layer.tips(theta)).ravel()

    params = np.concatenate([np.full(groups, start[0]), np.full(groups, start[1])])
    fit = _levenberg_marquardt(predict, params, measured.ravel(), max_iter)
    stderr, rms = _standard_errors(fit)
    est = np.abs(fit.params)
    if per_joint:
        values = (est[:groups], est[groups:], stderr[:groups], stderr[groups:])
        return Calibration(*values, rms, fit.iterations, fit.converged)
    shared = (float(est[0]), float(est[1]), float(stderr[0]), float(stderr[1]))
    return Calibration(*shared, rms, fit.iterations, fit.converged)
