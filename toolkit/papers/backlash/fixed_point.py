"""The fixed point theta = q_cmd + dtheta(M(theta)) of [P1]'s eq. 16, for N commands at once.

Plain iteration converges in a few steps because delta k_H |dM/dtheta| / M_H is far below
1. A joint whose torque changes sign inside its gap makes it flip between the two contact
sides; :class:`_Brackets` detects that and finds the zero torque inside the gap by the
Illinois variant of regula falsi.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from .law import TORQUE_TOL

__all__ = ["OutputAngles", "solve_fixed_point"]

Torques = Callable[[np.ndarray, np.ndarray], np.ndarray]
Offsets = Callable[[np.ndarray], np.ndarray]


class OutputAngles(NamedTuple):
    """The solved fixed point theta = q_cmd + dtheta(M(theta)) of one or N commands."""

    theta: np.ndarray  # joint-output angles, (n,) or (N, n) [rad]
    torque: np.ndarray  # torque acting on each joint at theta [N m]
    residual: np.ndarray | float  # max |theta - q_cmd - dtheta(M(theta))| [rad]
    iterations: int  # the most iterations any configuration needed
    converged: np.ndarray | bool
    in_gap: np.ndarray  # joints resting inside their gap (torque zero there), bool


class _Brackets:
    """Per joint and command: the bracket [lo, hi] of a zero torque inside the gap.

    M > 0 pulls theta up, so a stable equilibrium inside the gap lies above a point where
    M > 0: that point is the lower end (``f_lo`` > 0), the other the upper (``f_hi`` <= 0).
    """

    def __init__(self, q: np.ndarray, delta: np.ndarray) -> None:
        self.lo, self.hi = q - delta / 2, q + delta / 2
        self.f_lo = np.full(q.shape, np.nan)  # torque at lo (> 0) once known
        self.f_hi = np.full(q.shape, np.nan)  # torque at hi (<= 0) once known
        self.kept = np.zeros(q.shape)  # Illinois: +1 if lo moved last, -1 if hi moved last
        self.in_gap = np.zeros(q.shape, dtype=bool)
        self.side_prev = np.zeros(q.shape)
        self.theta_prev = q.copy()
        self.torque_prev = np.zeros(q.shape)

    def update(self, active: np.ndarray, th: np.ndarray, torque: np.ndarray) -> np.ndarray:
        """Record this iterate; returns which joints are in their gap (bool, like th)."""
        side = np.where(np.abs(torque) > TORQUE_TOL, np.sign(torque), 0.0)
        entering = (side * self.side_prev[active] < 0) & ~self.in_gap[active]
        if entering.any():  # the previous iterate lies on the other side: bracket the zero
            prev_t, prev_m = self.theta_prev[active], self.torque_prev[active]
            pos_prev = entering & (prev_m > 0)  # previous point pulls up: lower end
            for ends, vals, here, there in (
                ((self.lo, self.f_lo), (prev_t, prev_m), (th, torque), pos_prev),
                ((self.hi, self.f_hi), (th, torque), (prev_t, prev_m), pos_prev),
            ):
                for end, first, second in zip(ends, vals, here, strict=True):
                    end[active] = np.where(there, first, np.where(entering, second, end[active]))
        gap: np.ndarray = self.in_gap[active] | entering
        self.side_prev[active] = side
        self.theta_prev[active], self.torque_prev[active] = th, torque
        return gap

    def step(self, active: np.ndarray, gap: np.ndarray, th: np.ndarray, torque: np.ndarray):
        """One Illinois step towards the zero torque of the joints in their gap."""
        lo_a, hi_a = self.lo[active], self.hi[active]
        flo, fhi, kept = self.f_lo[active], self.f_hi[active], self.kept[active]
        clipped = np.clip(th, lo_a, hi_a)
        up, down = gap & (torque > 0), gap & (torque <= 0)
        # Illinois: halve the stale end's torque when the same end moves twice
        fhi = np.where(up & (kept > 0), fhi / 2, fhi)
        flo = np.where(down & (kept < 0), flo / 2, flo)
        lo_a, flo = np.where(up, clipped, lo_a), np.where(up, torque, flo)
        hi_a, fhi = np.where(down, clipped, hi_a), np.where(down, torque, fhi)
        kept = np.where(up, 1.0, np.where(down, -1.0, kept))
        self.lo[active], self.hi[active], self.f_lo[active] = lo_a, hi_a, flo
        self.f_hi[active], self.kept[active] = fhi, kept
        self.in_gap[active] = gap
        known = np.isfinite(flo) & np.isfinite(fhi) & (flo - fhi > 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            secant = (lo_a * (-fhi) + hi_a * flo) / (flo - fhi)
        return np.where(known, secant, (lo_a + hi_a) / 2)

    def gap_residual(self, torque: np.ndarray) -> np.ndarray:
        """Distance to the zero torque estimated by the bracket's slope (or its width)."""
        slope = np.abs(self.f_lo - self.f_hi) / np.maximum(self.hi - self.lo, 1e-300)
        usable = np.isfinite(slope) & (slope > 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(usable, np.abs(torque) / slope, self.hi - self.lo)


def solve_fixed_point(
    q: np.ndarray,
    start: np.ndarray,
    delta: np.ndarray,
    torques: Torques,
    offsets: Offsets,
    tol: float,
    max_iter: int,
) -> OutputAngles:
    """theta = q + offsets(torques(theta)) for commands q (N, n), from ``start`` (N, n);
    ``torques(theta_rows, rows)`` is told which commands the rows are (their indices in q:
    torques that depend on each command's velocities use them; gravity's ignore them).

    ``residual`` is the fixed-point residual of the joints in contact and the distance to
    the zero torque of the joints in their gap; ``converged`` means residual <= max(10 tol,
    1e-10) [rad].
    """
    theta = start.copy()
    torque = np.zeros_like(theta)
    brackets = _Brackets(q, delta)
    active = np.arange(len(q))
    iterations = 0
    for iterations in range(1, max_iter + 1):  # noqa: B007 - reported below
        th = theta[active]
        m = torques(th, active)
        gap = brackets.update(active, th, m)
        new = q[active] + offsets(m)
        if gap.any():
            new = np.where(gap, brackets.step(active, gap, th, m), new)
        done = np.max(np.abs(new - th), axis=1) <= tol
        # a converged row keeps the iterate whose torque is known (the next one is within
        # tol of it): no torque evaluation after the loop for it
        theta[active] = np.where(done[:, None], th, new)
        torque[active[done]] = m[done]
        active = active[~done]
        if active.size == 0:
            break
    if active.size:  # rows stopped by max_iter: the torque at their last iterate
        rest = theta[active]
        torque[active] = torques(rest, active)
    contact = np.abs(theta - q - offsets(torque))
    residual = np.max(np.where(brackets.in_gap, brackets.gap_residual(torque), contact), axis=1)
    converged = residual <= max(10 * tol, 1e-10)
    return OutputAngles(theta, torque, residual, iterations, converged, brackets.in_gap)
