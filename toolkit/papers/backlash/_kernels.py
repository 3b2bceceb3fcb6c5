"""[P1]'s backlash fixed point, compiled (numba): eq. 17 and the iteration of
:mod:`.fixed_point`, step for step, on the core engine's packed tree.

The NumPy form (:func:`.fixed_point.solve_fixed_point`) and this one stand side by side;
``tests/papers/test_backlash.py`` holds them equal. Gravity comes from the core's
:func:`toolkit.kinematics.kernels.gravity_row` on the payload model's
:attr:`toolkit.kinematics.CompiledBackend.tree`.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ...kinematics import inline_kernel, kernel, kernels, twin_kernel

gravity_row = kernels.gravity_row


@inline_kernel
def _offset(m, m_h, d, k, torque_tol):
    """[P1]'s eq. 17 for one joint (the dead zone |m| <= torque_tol gives 0)."""
    if abs(m) <= torque_tol:
        return 0.0
    return d * (0.5 * (1.0 if m > 0.0 else -1.0) + k * m / m_h)


@inline_kernel
def _gap_step(j, th, m, br):
    """One Illinois (regula falsi) step of joint j towards its zero torque inside the gap
    (the same rule as :class:`toolkit.backlash.fixed_point._Brackets`).

    ``br`` (7, nv): lo, hi, f_lo, f_hi, kept, in_gap, and the side of the last iterate.
    """
    lo, hi = br[0, j], br[1, j]
    clipped = min(max(th, lo), hi)
    if m > 0.0:  # pulls up: the lower end moves; halve the stale upper end's torque
        if br[4, j] > 0.0:
            br[3, j] *= 0.5
        br[0, j], br[2, j], br[4, j] = clipped, m, 1.0
    else:
        if br[4, j] < 0.0:
            br[2, j] *= 0.5
        br[1, j], br[3, j], br[4, j] = clipped, m, -1.0
    lo, hi, flo, fhi = br[0, j], br[1, j], br[2, j], br[3, j]
    if np.isfinite(flo) and np.isfinite(fhi) and flo - fhi > 0.0:
        return (lo * (-fhi) + hi * flo) / (flo - fhi)
    return 0.5 * (lo + hi)


@kernel
def _backlash_rows(start, stop, Q, out, law, tol, max_iter, torque_tol, tree):  # long: one loop
    """The fixed point of commands start .. stop - 1 (see :func:`backlash_batch`) on one
    set of buffers (one function: a helper's array arguments would cost reference counts
    per command).

    Plain iteration while every joint stays in contact; a joint whose torque changes sign
    between iterates rests inside its gap, and is placed at its zero torque by the
    bracketing of :mod:`toolkit.backlash.fixed_point`, step for step the same."""
    nv, n = Q.shape[1], tree[0].shape[0]
    W, sub = np.empty((n + 1, 15)), np.empty((n + 1, 4))
    g, cur, new = np.empty(nv), np.empty(nv), np.empty(nv)
    prev_t, prev_m, br = np.empty(nv), np.empty(nv), np.empty((7, nv))
    theta, torque, residual, iters, in_gap = out
    ints, flts, body, gravity = tree
    for i in range(start, stop):
        for j in range(nv):
            prev_t[j], prev_m[j], cur[j] = Q[i, j], 0.0, theta[i, j]
            br[0, j] = Q[i, j] - law[1, j] / 2
            br[1, j] = Q[i, j] + law[1, j] / 2
            br[2, j] = br[3, j] = np.nan
            br[4, j] = br[5, j] = br[6, j] = 0.0
        settled = False
        for it in range(1, max_iter + 1):
            gravity_row(cur, ints, flts, body, gravity, W, sub, g)
            step = 0.0
            for j in range(nv):
                th, m = cur[j], -g[j]
                side = 0.0 if abs(m) <= torque_tol else (1.0 if m > 0.0 else -1.0)
                if side * br[6, j] < 0.0 and br[5, j] == 0.0:  # entering: bracket the zero
                    if prev_m[j] > 0.0:
                        br[0, j], br[2, j], br[1, j], br[3, j] = prev_t[j], prev_m[j], th, m
                    else:
                        br[0, j], br[2, j], br[1, j], br[3, j] = th, m, prev_t[j], prev_m[j]
                    br[5, j] = 1.0
                    br[4, j] = 0.0
                br[6, j], prev_t[j], prev_m[j] = side, th, m
                if br[5, j] != 0.0:
                    new[j] = _gap_step(j, th, m, br)
                else:
                    new[j] = Q[i, j] + _offset(m, law[0, j], law[1, j], law[2, j], torque_tol)
                step = max(step, abs(new[j] - th))
            iters[i] = it
            if step <= tol:  # keep this iterate, whose torque g holds (as the NumPy form)
                settled = True
                break
            for j in range(nv):
                cur[j] = new[j]
        if not settled:  # stopped by max_iter: the torque at the last iterate
            gravity_row(cur, ints, flts, body, gravity, W, sub, g)
        worst = 0.0
        for j in range(nv):
            theta[i, j] = cur[j]
            m = -g[j]
            torque[i, j] = m
            if br[5, j] != 0.0:
                in_gap[i, j] = True
                slope = abs(br[2, j] - br[3, j]) / max(br[1, j] - br[0, j], 1e-300)
                r = abs(m) / slope if np.isfinite(slope) and slope > 0.0 else br[1, j] - br[0, j]
            else:
                off = _offset(m, law[0, j], law[1, j], law[2, j], torque_tol)
                r = abs(cur[j] - Q[i, j] - off)
            worst = max(worst, r)
        residual[i] = worst


@kernel
def _backlash_outputs(start):
    """(theta from start, torque, residual, iterations, in_gap) for N commands."""
    N, nv = start.shape
    theta, torque = start.copy(), np.empty((N, nv))
    return theta, torque, np.empty(N), np.zeros(N, np.int64), np.zeros((N, nv), np.bool_)


@twin_kernel
def backlash_batch(Q, start, law, tol, max_iter, torque_tol, tree):
    """The fixed point theta = q + dtheta(-g(theta)) of [P1]'s eqs. 16-17, per command.

    ``law`` (3, n) holds M_H, delta and k_H per joint; ``tree`` = (ints, flts, body,
    gravity) of the payload model. Returns theta, the torque at theta, the residual and the
    iterations per row, and ``in_gap`` (N, n): the joints resting inside their gap (placed
    at zero torque by bracketing). A twin: rows over the cores, or on the calling thread.
    """
    out = _backlash_outputs(start)
    N, chunk = Q.shape[0], 256
    for c in prange((N + chunk - 1) // chunk):
        _backlash_rows(
            c * chunk, min(N, (c + 1) * chunk), Q, out, law, tol, max_iter, torque_tol, tree
        )
    return out
