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
from .fixed_point import FLAT

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


@inline_kernel
def _rest_state(th, Q, i, law, tree, W, sub, g, m, f, stiff):
    """The torque m = -g(th), the gap's reading of eq. 17 f = G(th - q) - m, each joint's
    stiffness dG/do and the energy (the links' potential energy plus the joints' c/2
    (|o| - delta/2)^2 past their ends) of command i at th; see fixed_point._Joints."""
    ints, flts, body, gravity = tree
    gravity_row(th, ints, flts, body, gravity, W, sub, g)
    n = ints.shape[0]
    value = 0.0
    for r in range(3):
        value -= gravity[r] * sub[n, 1 + r]
    for j in range(th.shape[0]):
        m[j] = -g[j]
        d, k = law[1, j], law[2, j]
        o = th[j] - Q[i, j]
        past = abs(o) - d / 2
        c = law[0, j] / (d * k) if d > 0.0 and k > 0.0 else 0.0
        if past > 0.0 and c > 0.0:
            f[j] = c * past * (1.0 if o > 0.0 else -1.0) - m[j]
            stiff[j] = c
            value += 0.5 * c * past * past
        else:
            f[j] = -m[j]
            stiff[j] = 0.0
    return value


@inline_kernel
def _clip_rest(th, Q, i, law):
    """Fixed joints (delta = 0) at their command, rigid ones (k_H = 0) within their ends."""
    for j in range(th.shape[0]):
        d = law[1, j]
        if d <= 0.0:
            th[j] = Q[i, j]
        elif law[2, j] <= 0.0:
            th[j] = min(max(th[j], Q[i, j] - d / 2), Q[i, j] + d / 2)


@inline_kernel
def _descent(h, f, free, step, a):
    """step = -(H + lambda I)^-1 f on the free joints, lambda >= 0 the least (doubled from
    1e-9 |H|) that makes the matrix positive definite (Cholesky); False if none did."""
    nv = f.shape[0]
    scale = 0.0
    for r in range(nv):
        for c in range(nv):
            scale = max(scale, abs(h[r, c]))
    lam = 0.0
    for _ in range(80):
        a[:, :] = 0.0
        ok = True
        for r in range(nv):
            if not free[r]:
                continue
            for c in range(r + 1):
                if not free[c]:
                    continue
                s = 0.5 * (h[r, c] + h[c, r]) + (lam if r == c else 0.0)
                for k in range(c):
                    if free[k]:
                        s -= a[r, k] * a[c, k]
                if r == c:
                    if s <= 0.0:
                        ok = False
                        break
                    a[r, r] = np.sqrt(s)
                else:
                    a[r, c] = s / a[c, c]
            if not ok:
                break
        if ok:
            for r in range(nv):  # forward: a y = -f
                if free[r]:
                    s = -f[r]
                    for k in range(r):
                        if free[k]:
                            s -= a[r, k] * step[k]
                    step[r] = s / a[r, r]
                else:
                    step[r] = 0.0
            for r in range(nv - 1, -1, -1):  # back: a^T x = y
                if free[r]:
                    s = step[r]
                    for k in range(r + 1, nv):
                        if free[k]:
                            s -= a[k, r] * step[k]
                    step[r] = s / a[r, r]
            return True
        lam = max(2.0 * lam, 1e-9 * max(scale, 1e-12))
    return False


@inline_kernel
def _torque_jacobian(th, tree, W, sub, g, probe, jac):
    """dM/dtheta (nv, nv) of the static torque M = -g(th) into ``jac``, by central
    differences of gravity (steps of 1e-6 rad), on buffers W, sub, g and probe."""
    eps = 1e-6
    for c in range(th.shape[0]):
        probe[:] = th
        probe[c] = th[c] + eps
        gravity_row(probe, tree[0], tree[1], tree[2], tree[3], W, sub, g)
        for r in range(th.shape[0]):
            jac[r, c] = -g[r]
        probe[c] = th[c] - eps
        gravity_row(probe, tree[0], tree[1], tree[2], tree[3], W, sub, g)
        for r in range(th.shape[0]):
            jac[r, c] = (jac[r, c] + g[r]) / (2 * eps)


@kernel
def _settle_rows(start, stop, rows, Q, theta, torque, residual, converged,  # long: one loop
                 in_gap, law, tol, max_iter, torque_tol, tree):  # fmt: skip
    """The rest of commands rows[start:stop] (see :func:`settle_batch`), in place."""
    nv, n = Q.shape[1], tree[0].shape[0]
    W, sub = np.empty((n + 1, 15)), np.empty((n + 1, 4))
    g, m, f, stiff = np.empty(nv), np.empty(nv), np.empty(nv), np.empty(nv)
    m_t, f_t, st_t, gp = np.empty(nv), np.empty(nv), np.empty(nv), np.empty(nv)
    h, a, jac = np.empty((nv, nv)), np.empty((nv, nv)), np.empty((nv, nv))
    th, trial, step, probe = np.empty(nv), np.empty(nv), np.empty(nv), np.empty(nv)
    free = np.empty(nv, np.bool_)
    for i in rows[start:stop]:
        for j in range(nv):
            th[j] = theta[i, j]
        _clip_rest(th, Q, i, law)
        value = _rest_state(th, Q, i, law, tree, W, sub, g, m, f, stiff)
        for _it in range(max_iter):
            _torque_jacobian(th, tree, W, sub, gp, probe, jac)  # the Hessian: diag(stiff) - jac
            big = 0.0
            for r in range(nv):
                for c in range(nv):
                    h[r, c] = (stiff[r] if r == c else 0.0) - jac[r, c]
                    big = max(big, abs(h[r, c]))
            any_free = False
            for j in range(nv):
                d = law[1, j]
                lo, hi = Q[i, j] - d / 2, Q[i, j] + d / 2
                pressed = (th[j] <= lo and f[j] > 0) or (th[j] >= hi and f[j] < 0)
                held = law[2, j] <= 0.0 and pressed
                flat = abs(f[j]) <= torque_tol
                for c in range(nv):
                    flat = flat and abs(h[j, c]) <= FLAT * big and abs(h[c, j]) <= FLAT * big
                free[j] = d > 0.0 and not held and not flat
                any_free = any_free or free[j]
            if not any_free or not _descent(h, f, free, step, a):
                break
            size = 0.0
            for j in range(nv):
                size = max(size, abs(step[j]))
            alpha, accepted, value_t = 1.0, False, value
            for _ in range(30):
                for j in range(nv):
                    trial[j] = th[j] + alpha * step[j]
                _clip_rest(trial, Q, i, law)
                value_t = _rest_state(trial, Q, i, law, tree, W, sub, g, m_t, f_t, st_t)
                if value_t <= value or alpha * size <= 1e-9:
                    accepted = True
                    break
                alpha /= 4
            if not accepted:
                break
            moved = 0.0
            for j in range(nv):
                moved = max(moved, abs(trial[j] - th[j]))
                th[j], m[j], f[j], stiff[j] = trial[j], m_t[j], f_t[j], st_t[j]
            value = value_t
            if moved <= tol:
                break
        # the answer's residual: eq. 17 past the ends, the torque inside the gap
        _torque_jacobian(th, tree, W, sub, gp, probe, jac)
        worst, ok = 0.0, True
        for j in range(nv):
            d = law[1, j]
            o = th[j] - Q[i, j]
            inside = d > 0.0 and abs(o) < d / 2
            if inside:
                miss = 0.0 if abs(m[j]) <= torque_tol else abs(m[j]) / abs(jac[j, j])
                ok = ok and abs(m[j]) <= torque_tol
                in_gap[i, j] = o != 0.0 or in_gap[i, j]
            else:
                miss = abs(o - _offset(m[j], law[0, j], d, law[2, j], torque_tol))
                in_gap[i, j] = False
            if not np.isfinite(miss):
                miss = np.inf
            worst = max(worst, miss)
            theta[i, j], torque[i, j] = th[j], m[j]
        residual[i] = worst
        converged[i] = ok and worst <= max(10 * tol, 1e-10)


@twin_kernel
def settle_batch(rows, Q, theta, torque, residual, converged, in_gap, law, tol, max_iter,
                 torque_tol, tree):  # fmt: skip
    """The rest of each command in ``rows``, from its iterate in ``theta``: Newton's method
    on the energy of :func:`toolkit.backlash.fixed_point.settle` (the NumPy form, step for
    step the same but for dM/dtheta, here by central differences of gravity), in place. A
    twin: rows over the cores, or on the calling thread."""
    N, chunk = rows.shape[0], 16
    for c in prange((N + chunk - 1) // chunk):
        _settle_rows(
            c * chunk, min(N, (c + 1) * chunk), rows, Q, theta, torque, residual, converged,
            in_gap, law, tol, max_iter, torque_tol, tree,
        )  # fmt: skip
