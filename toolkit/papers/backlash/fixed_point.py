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

from .law import TORQUE_TOL, eq17

__all__ = [
    "FLAT",
    "SETTLE_ITERATIONS",
    "OutputAngles",
    "needs_settling",
    "settle",
    "solve_fixed_point",
]

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


Jacobian = Callable[[np.ndarray, int], np.ndarray]

SETTLE_ITERATIONS = 60
"""Newton steps :func:`settle` takes at most per command."""
FLAT = 1e-8
"""A joint whose row and column of the energy's Hessian are below this share of its largest
entry, and whose torque is within TORQUE_TOL, is one no load turns (a vertical axis): it
stays where it is (the compiled form's differences of gravity leave it ~1e-10, not 0)."""
Energy = Callable[[np.ndarray], float]


def needs_settling(out: OutputAngles) -> np.ndarray:
    """The rows (indices) whose iterate :func:`settle` must finish: a joint in its gap
    (the bracket's torques are taken with the other joints elsewhere, so its answer is
    not yet a rest) or an iteration that did not converge."""
    gap = np.atleast_2d(out.in_gap).any(axis=1)
    return np.flatnonzero(gap | ~np.atleast_1d(out.converged))


class _Joints:
    """Eq. 17 read the other way: the torque G(o) a joint bears at offset o = theta - q.

    G = 0 inside the gap (|o| < delta/2), c (|o| - delta/2) sign(o) past it, with
    c = M_H / (delta k_H). A joint with delta = 0 is held at its command (``fixed``); one
    with k_H = 0 is rigid at its ends (``boxed``: o within +-delta/2)."""

    def __init__(self, law: np.ndarray) -> None:
        m_h, self.d, self.k = law
        self.fixed = self.d <= 0.0
        self.boxed = ~self.fixed & (self.k <= 0.0)
        soft = ~(self.fixed | self.boxed)
        self.c = np.zeros_like(self.d)
        self.c[soft] = m_h[soft] / (self.d[soft] * self.k[soft])
        self.m_h = m_h

    def load(self, o: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """G(o), dG/do and the energy sum of c/2 (|o| - delta/2)^2 past the ends."""
        past = np.maximum(np.abs(o) - self.d / 2, 0.0)
        return (
            self.c * past * np.sign(o),
            np.where(past > 0, self.c, 0.0),
            float(0.5 * np.sum(self.c * past**2)),
        )

    def clip(self, theta: np.ndarray, q: np.ndarray) -> np.ndarray:
        """theta with the fixed joints at q and the boxed ones within their ends."""
        lo, hi = q - self.d / 2, q + self.d / 2
        out = np.where(self.boxed, np.clip(theta, lo, hi), theta)
        return np.where(self.fixed, q, out)


def _descent(h: np.ndarray, f: np.ndarray) -> np.ndarray | None:
    """-(H + lambda I)^-1 f with lambda >= 0 the least (doubled from 1e-9 |H|) that makes
    the symmetric part of H positive definite: Newton's step where the energy curves up,
    a step downhill where it does not."""
    sym, scale, lam = 0.5 * (h + h.T), max(float(np.max(np.abs(h))), 1e-12), 0.0
    eye = np.eye(len(f))
    for _ in range(80):
        try:
            low = np.linalg.cholesky(sym + lam * eye)
        except np.linalg.LinAlgError:
            lam = max(2.0 * lam, 1e-9 * scale)
            continue
        return -np.linalg.solve(low.T, np.linalg.solve(low, f))
    return None


def settle(  # long: the NumPy form of _kernels.settle_batch, step for step
    q: np.ndarray,
    out: OutputAngles,
    law: np.ndarray,
    torques: Torques,
    jacobian: Jacobian,
    tol: float,
    rows: np.ndarray,
    energy: Energy | None = None,
    max_iter: int = SETTLE_ITERATIONS,
) -> OutputAngles:
    """The rest of each of ``rows`` of commands q (N, n), started from ``out``'s iterate:
    every joint past an end of its gap obeys eq. 17 (theta = q + delta (sign(M)/2 +
    k_H M / M_H)), every joint inside its gap carries no torque (|M| <= TORQUE_TOL).

    A rest is where the torque each joint bears, G(theta - q) (:class:`_Joints`), equals
    the torque M(theta) acting on it. For a static arm (``energy``: the potential energy
    of the links, whose gradient is -M) it is a minimum of that energy plus the joints'
    c/2 (|o| - delta/2)^2: Newton's method with the Hessian shifted until positive definite
    (:func:`_descent`: a load that pushes a joint away from the middle of its gap sends it
    to the end, never to the unstable balance point) and a step cut by 4 until the energy
    falls. Along a motion (no energy) Newton's step on G - M, cut until |G - M| falls.
    ``torques(theta_rows, rows)``, ``jacobian(theta, row)``: M and dM/dtheta (n, n).
    ``converged`` is true only where every joint's equation holds.
    """
    theta, torque = out.theta.copy(), out.torque.copy()
    residual = np.array(out.residual, dtype=float, copy=True)
    converged, in_gap = np.array(out.converged, copy=True), out.in_gap.copy()
    joints = _Joints(law)
    moving = ~joints.fixed
    iterations = out.iterations

    def measure(th: np.ndarray, i: int) -> tuple[np.ndarray, np.ndarray, float]:
        m = torques(th[None], np.array([i]))[0]
        bear, _, spring = joints.load(th - q[i])
        f = bear - m  # the gradient of the energy where there is one
        return m, f, (energy(th) + spring) if energy is not None else 0.5 * float(f @ f)

    for i in rows:
        qi = q[i]
        lo, hi = qi - joints.d / 2, qi + joints.d / 2
        th = joints.clip(theta[i].copy(), qi)
        m, f, value = measure(th, i)
        for it in range(1, max_iter + 1):
            iterations = max(iterations, it)
            # boxed joints at an end that the load presses on stay there
            held = joints.boxed & (((th <= lo) & (f > 0)) | ((th >= hi) & (f < 0)))
            _, stiff, _ = joints.load(th - qi)
            h = np.diag(stiff) - jacobian(th, int(i))
            # a joint that no load turns (a vertical axis) stays where it is
            scale = max(float(np.max(np.abs(h))), 1e-300)
            indifferent = (
                (np.max(np.abs(h), axis=0) <= FLAT * scale)
                & (np.max(np.abs(h), axis=1) <= FLAT * scale)
                & (np.abs(f) <= TORQUE_TOL)
            )
            free = moving & ~held & ~indifferent
            if not free.any():
                break
            hf, ff = h[np.ix_(free, free)], f[free]
            step = np.zeros_like(th)
            if energy is not None:
                descent = _descent(hf, ff)
                if descent is None:
                    break
                step[free] = descent
            else:
                step[free] = np.linalg.lstsq(hf, -ff, rcond=None)[0]
            if not np.all(np.isfinite(step)):
                break
            alpha, accepted, size = 1.0, False, float(np.max(np.abs(step)))
            for _ in range(30):
                trial = joints.clip(th + alpha * step, qi)
                m_t, f_t, value_t = measure(trial, i)
                # a step of 1e-9 rad or less is inside the quadratic basin: the energy's
                # rounding no longer tells a better point
                if value_t <= value or alpha * size <= 1e-9:
                    accepted = True
                    break
                alpha /= 4
            if not accepted:
                break
            moved = float(np.max(np.abs(trial - th)))
            th, m, f, value = trial, m_t, f_t, value_t
            if moved <= tol:
                break
        o = th - qi
        inside = moving & (np.abs(o) < joints.d / 2)
        gap = inside & ((o != 0.0) | in_gap[i])
        contact = np.abs(o - eq17(m, joints.m_h, joints.d, joints.k))
        # inside the gap: the distance to the zero torque at the local stiffness, none
        # where the torque is within TORQUE_TOL (the dead zone: it counts as zero)
        stiffness = np.abs(np.diag(jacobian(th, int(i))))
        with np.errstate(divide="ignore", invalid="ignore"):
            gap_r = np.where(np.abs(m) <= TORQUE_TOL, 0.0, np.abs(m) / stiffness)
        r = float(np.max(np.where(inside, gap_r, contact))) if len(th) else 0.0
        ok = np.isfinite(r) and r <= max(10 * tol, 1e-10)
        ok = ok and bool(np.all(~inside | (np.abs(m) <= TORQUE_TOL)))
        theta[i], torque[i], residual[i] = th, m, r
        converged[i], in_gap[i] = bool(ok), gap
    return OutputAngles(theta, torque, residual, iterations, converged, in_gap)
