"""Compiled kernels of the chain engine (numba): plain loops on packed arrays.

A chain is a list of 1-DoF joints in tree order, packed by :mod:`toolkit.engine` into

* ``ints`` (n, 4): parent row (``n`` for the base), kind (0 revolute, 1 prismatic), the
  q index and the v index that drive the joint;
* ``flts`` (n, 17): placement rotation in the parent joint's frame (9, row-major),
  placement translation (3), unit axis in the joint's own frame (3), and the mimic
  relation ``value = scale * q[qi] + offset`` (2; 1 and 0 for an ordinary joint);
* ``tip`` (12): the tip frame's placement in the last joint's frame (rotation, translation).

``W`` (n + 1, 15) receives, per joint, its world rotation after its motion (9), its origin
(3) and its world axis (3); row n is the base (identity). Nothing allocates inside the
loops, so one IK iteration of a 6-joint arm costs well under a microsecond.

Pinocchio is the reference: ``tests/test_engine.py`` compares every kernel with it.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

# Matrices keep their mathematical names (R, J, A); numba offers only the legacy np.random.


@njit(cache=True, nogil=True, error_model="numpy")
def frames(q, ints, flts, W):
    """Fill W with every joint's world rotation, origin and axis at configuration q."""
    n = ints.shape[0]
    W[n, :] = 0.0
    W[n, 0] = W[n, 4] = W[n, 8] = 1.0
    for k in range(n):
        par = ints[k, 0]
        # R = R_parent @ placement rotation; p = p_parent + R_parent @ placement translation
        for i in range(3):
            for j in range(3):
                s = 0.0
                for m in range(3):
                    s += W[par, 3 * i + m] * flts[k, 3 * m + j]
                W[k, 3 * i + j] = s
            s = W[par, 9 + i]
            for m in range(3):
                s += W[par, 3 * i + m] * flts[k, 9 + m]
            W[k, 9 + i] = s
        x, y, z = flts[k, 12], flts[k, 13], flts[k, 14]
        ax = W[k, 0] * x + W[k, 1] * y + W[k, 2] * z
        ay = W[k, 3] * x + W[k, 4] * y + W[k, 5] * z
        az = W[k, 6] * x + W[k, 7] * y + W[k, 8] * z
        W[k, 12], W[k, 13], W[k, 14] = ax, ay, az
        value = flts[k, 15] * q[ints[k, 2]] + flts[k, 16]
        if ints[k, 1] == 0:  # R = R @ Rot(axis, value), Rodrigues' formula
            s, c = np.sin(value), np.cos(value)
            t = 1.0 - c
            r00, r01, r02 = c + t * x * x, t * x * y - s * z, t * x * z + s * y
            r10, r11, r12 = t * x * y + s * z, c + t * y * y, t * y * z - s * x
            r20, r21, r22 = t * x * z - s * y, t * y * z + s * x, c + t * z * z
            for i in range(3):
                a0, a1, a2 = W[k, 3 * i], W[k, 3 * i + 1], W[k, 3 * i + 2]
                W[k, 3 * i] = a0 * r00 + a1 * r10 + a2 * r20
                W[k, 3 * i + 1] = a0 * r01 + a1 * r11 + a2 * r21
                W[k, 3 * i + 2] = a0 * r02 + a1 * r12 + a2 * r22
        else:  # the frame slides along its axis
            W[k, 9] += ax * value
            W[k, 10] += ay * value
            W[k, 11] += az * value


@njit(cache=True, nogil=True, error_model="numpy")
def tip(W, tip_pl, R, p):
    """The tip frame's rotation R (3, 3) and position p (3) from the last joint of W."""
    last = W.shape[0] - 2  # row n - 1 (n - 1 = -1 when the tip hangs on the base: row n)
    if last < 0:
        last = W.shape[0] - 1
    for i in range(3):
        for j in range(3):
            s = 0.0
            for m in range(3):
                s += W[last, 3 * i + m] * tip_pl[3 * m + j]
            R[i, j] = s
        s = W[last, 9 + i]
        for m in range(3):
            s += W[last, 3 * i + m] * tip_pl[9 + m]
        p[i] = s


@njit(cache=True, nogil=True, error_model="numpy")
def jacobian(W, ints, flts, p, J):
    """Frame Jacobian J (6, nv) at the tip position p, LOCAL_WORLD_ALIGNED (filled in place)."""
    J[:, :] = 0.0
    for k in range(ints.shape[0]):
        col = ints[k, 3]
        s = flts[k, 15]
        ax, ay, az = W[k, 12], W[k, 13], W[k, 14]
        if ints[k, 1] == 0:
            rx, ry, rz = p[0] - W[k, 9], p[1] - W[k, 10], p[2] - W[k, 11]
            J[0, col] += s * (ay * rz - az * ry)
            J[1, col] += s * (az * rx - ax * rz)
            J[2, col] += s * (ax * ry - ay * rx)
            J[3, col] += s * ax
            J[4, col] += s * ay
            J[5, col] += s * az
        else:
            J[0, col] += s * ax
            J[1, col] += s * ay
            J[2, col] += s * az


@njit(cache=True, nogil=True, error_model="numpy")
def pose(q, ints, flts, tip_pl):
    """(W, R, p): every joint's frame, and the tip's rotation and position at q."""
    W = np.empty((ints.shape[0] + 1, 15))
    R = np.empty((3, 3))
    p = np.empty(3)
    frames(q, ints, flts, W)
    tip(W, tip_pl, R, p)
    return W, R, p


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def fk_batch(Q, ints, flts, tip_pl):
    """Tip poses (N, 4, 4) of configurations Q (N, nq)."""
    N = Q.shape[0]
    out = np.zeros((N, 4, 4))
    for i in prange(N):
        _, R, p = pose(Q[i], ints, flts, tip_pl)
        out[i, :3, :3] = R
        out[i, :3, 3] = p
        out[i, 3, 3] = 1.0
    return out


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def jacobian_batch(Q, ints, flts, tip_pl, nv):
    """Tip Jacobians (N, 6, nv), LOCAL_WORLD_ALIGNED."""
    N = Q.shape[0]
    out = np.empty((N, 6, nv))
    for i in prange(N):
        W, _, p = pose(Q[i], ints, flts, tip_pl)
        jacobian(W, ints, flts, p, out[i])
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def gravity_row(q, ints, flts, body, gravity, W, sub, out):
    """Generalized gravity g(q) of one configuration into out (nv), on buffers W and sub."""
    n = ints.shape[0]
    frames(q, ints, flts, W)
    sub[:, :] = 0.0  # per subtree: mass, sum of m c
    out[:] = 0.0
    for k in range(n - 1, -1, -1):
        m = body[k, 0]
        sub[k, 0] += m
        for r in range(3):
            c = W[k, 9 + r]
            for j in range(3):
                c += W[k, 3 * r + j] * body[k, 1 + j]
            sub[k, 1 + r] += m * c
        par = ints[k, 0]
        for r in range(4):
            sub[par, r] += sub[k, r]
    for k in range(n):
        ax, ay, az = W[k, 12], W[k, 13], W[k, 14]
        if ints[k, 1] == 0:  # axis . sum m (c - o) x g
            x = sub[k, 1] - sub[k, 0] * W[k, 9]
            y = sub[k, 2] - sub[k, 0] * W[k, 10]
            z = sub[k, 3] - sub[k, 0] * W[k, 11]
            mx = y * gravity[2] - z * gravity[1]
            my = z * gravity[0] - x * gravity[2]
            mz = x * gravity[1] - y * gravity[0]
            tau = ax * mx + ay * my + az * mz
        else:
            tau = sub[k, 0] * (ax * gravity[0] + ay * gravity[1] + az * gravity[2])
        out[ints[k, 3]] -= flts[k, 15] * tau


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def gravity_batch(Q, ints, flts, body, gravity, nv):
    """Generalized gravity g(q) (N, nv) of Pinocchio's ``computeGeneralizedGravity``.

    The joint list is the whole tree; ``body[k]`` = (mass, centre of mass in the joint's
    frame) of the body joint k carries.
    """
    N, n = Q.shape[0], ints.shape[0]
    out = np.zeros((N, nv))
    for i in prange(N):
        W = np.empty((n + 1, 15))
        sub = np.empty((n + 1, 4))
        gravity_row(Q[i], ints, flts, body, gravity, W, sub, out[i])
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _offset(m, m_h, d, k, torque_tol):
    """[P1]'s eq. 17 for one joint (the dead zone |m| <= torque_tol gives 0)."""
    if abs(m) <= torque_tol:
        return 0.0
    return d * (0.5 * (1.0 if m > 0.0 else -1.0) + k * m / m_h)


@njit(cache=True, nogil=True, error_model="numpy")
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


@njit(cache=True, nogil=True, error_model="numpy")
def _backlash_row(i, Q, out, law, tol, max_iter, torque_tol, tree):
    """The fixed point of command i (see :func:`backlash_batch`), written into ``out``.

    Plain iteration while every joint stays in contact; a joint whose torque changes sign
    between iterates rests inside its gap, and is placed at its zero torque by the
    bracketing of :mod:`toolkit.backlash.fixed_point`, step for step the same."""
    theta, torque, residual, iters, in_gap_out = out
    ints, flts, body, gravity = tree
    nv, n = Q.shape[1], ints.shape[0]
    W, sub = np.empty((n + 1, 15)), np.empty((n + 1, 4))
    g, new = np.empty(nv), np.empty(nv)
    prev_t, prev_m = Q[i].copy(), np.zeros(nv)
    br = np.zeros((7, nv))
    for j in range(nv):
        br[0, j] = Q[i, j] - law[1, j] / 2
        br[1, j] = Q[i, j] + law[1, j] / 2
        br[2, j] = br[3, j] = np.nan
    for it in range(1, max_iter + 1):
        gravity_row(theta[i], ints, flts, body, gravity, W, sub, g)
        step = 0.0
        for j in range(nv):
            th, m = theta[i, j], -g[j]
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
        theta[i] = new
        iters[i] = it
        if step <= tol:
            break
    gravity_row(theta[i], ints, flts, body, gravity, W, sub, g)
    worst = 0.0
    for j in range(nv):
        m = -g[j]
        torque[i, j] = m
        if br[5, j] != 0.0:
            in_gap_out[i, j] = True
            slope = abs(br[2, j] - br[3, j]) / max(br[1, j] - br[0, j], 1e-300)
            if np.isfinite(slope) and slope > 0.0:
                r = abs(m) / slope
            else:
                r = br[1, j] - br[0, j]
        else:
            off = _offset(m, law[0, j], law[1, j], law[2, j], torque_tol)
            r = abs(theta[i, j] - Q[i, j] - off)
        worst = max(worst, r)
    residual[i] = worst


@njit(cache=True, nogil=True, error_model="numpy")
def _backlash_outputs(start):
    """(theta from start, torque, residual, iterations, in_gap) for N commands."""
    N, nv = start.shape
    theta, torque = start.copy(), np.empty((N, nv))
    return theta, torque, np.empty(N), np.zeros(N, np.int64), np.zeros((N, nv), np.bool_)


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def backlash_batch(Q, start, law, tol, max_iter, torque_tol, tree):
    """The fixed point theta = q + dtheta(-g(theta)) of [P1]'s eqs. 16-17, per command.

    ``law`` (3, n) holds M_H, delta and k_H per joint; ``tree`` = (ints, flts, body,
    gravity) of the payload model. Returns theta, the torque at theta, the residual and the
    iterations per row, and ``in_gap`` (N, n): the joints resting inside their gap (placed
    at zero torque by bracketing). Rows run in parallel over the cores.
    """
    out = _backlash_outputs(start)
    for i in prange(Q.shape[0]):
        _backlash_row(i, Q, out, law, tol, max_iter, torque_tol, tree)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def backlash_serial(Q, start, law, tol, max_iter, torque_tol, tree):
    """:func:`backlash_batch` on one core: no thread start, for a few commands."""
    out = _backlash_outputs(start)
    for i in range(Q.shape[0]):
        _backlash_row(i, Q, out, law, tol, max_iter, torque_tol, tree)
    return out
