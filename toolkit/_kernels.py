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
# ruff: noqa: NPY002


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


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def fk_batch(Q, ints, flts, tip_pl):
    """Tip poses (N, 4, 4) of configurations Q (N, nq)."""
    N, n = Q.shape[0], ints.shape[0]
    out = np.zeros((N, 4, 4))
    for i in prange(N):
        W = np.empty((n + 1, 15))
        R = np.empty((3, 3))
        p = np.empty(3)
        frames(Q[i], ints, flts, W)
        tip(W, tip_pl, R, p)
        out[i, :3, :3] = R
        out[i, :3, 3] = p
        out[i, 3, 3] = 1.0
    return out


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def jacobian_batch(Q, ints, flts, tip_pl, nv):
    """Tip Jacobians (N, 6, nv), LOCAL_WORLD_ALIGNED."""
    N, n = Q.shape[0], ints.shape[0]
    out = np.empty((N, 6, nv))
    for i in prange(N):
        W = np.empty((n + 1, 15))
        R = np.empty((3, 3))
        p = np.empty(3)
        frames(Q[i], ints, flts, W)
        tip(W, tip_pl, R, p)
        jacobian(W, ints, flts, p, out[i])
    return out


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
        frames(Q[i], ints, flts, W)
        sub = np.zeros((n + 1, 4))  # per subtree: mass, sum of m c
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
            out[i, ints[k, 3]] -= flts[k, 15] * tau
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def log3(R, out):
    """Rotation vector of a rotation matrix into out (3), robust near 0 and pi."""
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    c = min(1.0, max(-1.0, c))
    theta = np.arccos(c)
    wx, wy, wz = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    if theta < 1e-4:
        f = 0.5 * (1.0 + theta * theta / 6.0)
    elif theta < np.pi - 1e-4:
        f = theta / (2.0 * np.sin(theta))
    else:  # near pi: the axis from the symmetric part, its sign from the skew part
        a = np.empty(3)
        for i in range(3):
            a[i] = np.sqrt(max(0.0, (R[i, i] - c) / (1.0 - c)))
        k = 0
        for i in range(1, 3):
            if a[i] > a[k]:
                k = i
        for i in range(3):
            if i != k:
                a[i] = np.copysign(a[i], R[i, k] + R[k, i])
        w = (wx, wy, wz)[k]
        norm = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
        sign = -1.0 if w < 0.0 else 1.0
        for i in range(3):
            out[i] = sign * theta * a[i] / norm
        return
    out[0], out[1], out[2] = f * wx, f * wy, f * wz


@njit(cache=True, nogil=True, error_model="numpy")
def residual(q, ints, flts, tip_pl, R_t, p_t, use_rot, W, R, p, J, e, tmp):
    """Fill e (6) with the pose residual [p_t - p ; log3(R^T R_t)] and J with
    J_e = [J_v ; R^T J_w] (6, nv), on the buffers W, R, p and tmp (3, 3)."""
    frames(q, ints, flts, W)
    tip(W, tip_pl, R, p)
    jacobian(W, ints, flts, p, J)
    for i in range(3):
        e[i] = p_t[i] - p[i]
    if use_rot:
        for i in range(3):
            for j in range(3):
                tmp[i, j] = R[0, i] * R_t[0, j] + R[1, i] * R_t[1, j] + R[2, i] * R_t[2, j]
        rv = np.empty(3)
        log3(tmp, rv)
        e[3], e[4], e[5] = rv[0], rv[1], rv[2]
        for c in range(J.shape[1]):
            w0, w1, w2 = J[3, c], J[4, c], J[5, c]
            J[3, c] = R[0, 0] * w0 + R[1, 0] * w1 + R[2, 0] * w2
            J[4, c] = R[0, 1] * w0 + R[1, 1] * w1 + R[2, 1] * w2
            J[5, c] = R[0, 2] * w0 + R[1, 2] * w1 + R[2, 2] * w2
    else:
        e[3] = e[4] = e[5] = 0.0


@njit(cache=True, nogil=True, error_model="numpy")
def _step(J, w, e, lam, A, b, L, dq):
    """dq solving (J^T W J + lam I) dq = J^T W e by Cholesky (all buffers given)."""
    nv = J.shape[1]
    for i in range(nv):
        s = 0.0
        for r in range(6):
            s += J[r, i] * w[r] * e[r]
        b[i] = s
        for j in range(i + 1):
            s = 0.0
            for r in range(6):
                s += J[r, i] * w[r] * J[r, j]
            A[i, j] = s
        A[i, i] += lam
    for i in range(nv):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                L[i, i] = np.sqrt(max(s, 1e-300))
            else:
                L[i, j] = s / L[j, j]
    for i in range(nv):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * dq[k]
        dq[i] = s / L[i, i]
    for i in range(nv - 1, -1, -1):
        s = dq[i]
        for k in range(i + 1, nv):
            s -= L[k, i] * dq[k]
        dq[i] = s / L[i, i]


@njit(cache=True, nogil=True, error_model="numpy")
def _run(q, ints, flts, tip_pl, R_t, p_t, w, use_rot, lo, hi, tol, max_iter, settings, best_q):
    """Damped least squares from q, in place (the same loop as toolkit.ik's Pinocchio back
    end): best_q receives the best iterate; returns (its cost, iterations, converged)."""
    damping, lambda_min, stall = settings
    nv, n = q.shape[0], ints.shape[0]
    W = np.empty((n + 1, 15))
    R, tmp = np.empty((3, 3)), np.empty((3, 3))
    p, e = np.empty(3), np.empty(6)
    J, A, L = np.empty((6, nv)), np.empty((nv, nv)), np.zeros((nv, nv))
    b, dq = np.empty(nv), np.empty(nv)
    wmax = 1.0
    for i in range(6):
        wmax = max(wmax, w[i])
    tol2 = tol * tol * wmax
    for i in range(nv):
        q[i] = min(max(q[i], lo[i]), hi[i])
    best_cost = np.inf
    since_best = 0
    for it in range(1, max_iter + 1):
        residual(q, ints, flts, tip_pl, R_t, p_t, use_rot, W, R, p, J, e, tmp)
        cost = 0.0
        for i in range(6):
            cost += w[i] * e[i] * e[i]
        cost *= 0.5
        since_best = 0 if cost < best_cost * (1.0 - 1e-3) else since_best + 1
        if cost < best_cost:
            best_q[:] = q
            best_cost = cost
        if cost <= tol2:
            pos = rot = 0.0
            for i in range(3):
                if w[i] > 0.0:
                    pos += e[i] * e[i]
                if w[i + 3] > 0.0:
                    rot += e[i + 3] * e[i + 3]
            if np.sqrt(pos) <= tol and np.sqrt(rot) <= tol:
                best_q[:] = q
                return cost, it, True
        if since_best >= stall:
            return best_cost, it, False
        _step(J, w, e, damping * cost + lambda_min, A, b, L, dq)
        for i in range(nv):
            q[i] = min(max(q[i] + dq[i], lo[i]), hi[i])
    return best_cost, max_iter, False


@njit(cache=True, nogil=True, error_model="numpy")
def solve(R_t, p_t, w, use_rot, q0, bounds, tol, max_iter, attempts, seed, settings, chain):
    """Restarts ``attempts[0]`` .. ``attempts[1] - 1`` (attempt 0 starts at q0, the others
    at seeded uniform samples of the sampling bounds): (best q, cost, iterations, last
    attempt, converged). Seeding by (seed, attempt) makes the answer independent of how the
    attempts are split between calls (the time budget is checked between calls)."""
    ints, flts, tip_pl = chain
    lo, hi, s_lo, s_hi = bounds
    nq = q0.shape[0]
    best_q, q, cand = q0.copy(), np.empty(nq), np.empty(nq)
    best_cost = np.inf
    total = 0
    attempt = attempts[0]
    for attempt in range(attempts[0], attempts[1]):
        if attempt == 0:
            q[:] = q0
        else:
            np.random.seed((seed * 1_000_003 + attempt) % 4294967295)
            for i in range(nq):
                q[i] = np.random.uniform(s_lo[i], s_hi[i])
        cost, iters, ok = _run(
            q, ints, flts, tip_pl, R_t, p_t, w, use_rot, lo, hi, tol, max_iter, settings, cand
        )
        total += iters
        if cost < best_cost:
            best_q[:] = cand
            best_cost = cost
        if ok:
            return best_q, best_cost, total, attempt, True
    return best_q, best_cost, total, attempt, False


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def solve_batch(Rs, ps, w, use_rot, Q0, bounds, tol, max_iter, restarts, seed, settings, chain):
    """:func:`solve` for N targets over the machine's cores (target i uses seed + i)."""
    N, nq = ps.shape[0], Q0.shape[1]
    q_out = np.empty((N, nq))
    iters = np.empty(N, np.int64)
    tries = np.empty(N, np.int64)
    for i in prange(N):
        q, _, it, att, _ = solve(
            Rs[i], ps[i], w, use_rot, Q0[i], bounds, tol, max_iter,
            (0, restarts + 1), seed + i, settings, chain,
        )  # fmt: skip
        q_out[i] = q
        iters[i] = it
        tries[i] = att
    return q_out, iters, tries
