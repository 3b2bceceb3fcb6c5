"""Compiled IK kernels: the damped-least-squares loop of :mod:`toolkit.ik` on the packed
chains of :mod:`toolkit._kernels` (no allocation inside the loop)."""

from __future__ import annotations

import numpy as np
from numba import prange

from ._kernels import frames, integrate, jacobian, restart_sample, tip
from ._numba import kernel, parallel_kernel

# Matrices keep their mathematical names (R, J, A).


@kernel
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


@kernel
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


@kernel
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


@kernel
def _run(q, ints, flts, tip_pl, R_t, p_t, w, use_rot, layout, tol, max_iter, settings, best_q):
    """Damped least squares from q, in place (the same loop as toolkit.ik's Pinocchio back
    end): best_q receives the best iterate; returns (its cost, iterations, converged)."""
    damping, lambda_min, stall = settings
    qlay, lo, hi = layout[0], layout[1], layout[2]
    nv, n = layout[5], ints.shape[0]
    W = np.empty((n + 1, 15))
    R, tmp = np.empty((3, 3)), np.empty((3, 3))
    p, e = np.empty(3), np.empty(6)
    J, A, L = np.empty((6, nv)), np.empty((nv, nv)), np.zeros((nv, nv))
    b, dq = np.empty(nv), np.empty(nv)
    wmax = 1.0
    for i in range(6):
        wmax = max(wmax, w[i])
    tol2 = tol * tol * wmax
    for i in range(q.shape[0]):
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
        integrate(q, dq, qlay, lo, hi)
    return best_cost, max_iter, False


@kernel
def solve(R_t, p_t, w, use_rot, q0, layout, tol, max_iter, attempts, seed, settings, chain):
    """Restarts ``attempts[0]`` .. ``attempts[1] - 1`` (attempt 0 starts at q0, the others
    at :func:`toolkit._kernels.restart_sample`): (best q, cost, iterations, last attempt,
    converged). ``layout`` = (qlay, clip lower, clip upper, sample lower, sample upper, nv).
    Seeding by (seed, attempt) makes the answer independent of how the attempts are split
    between calls (the time budget is checked between calls)."""
    ints, flts, tip_pl = chain
    qlay, s_lo, s_hi = layout[0], layout[3], layout[4]
    nq = q0.shape[0]
    best_q, q, cand = q0.copy(), np.empty(nq), np.empty(nq)
    best_cost = np.inf
    total = 0
    attempt = attempts[0]
    for attempt in range(attempts[0], attempts[1]):
        if attempt == 0:
            q[:] = q0
        else:
            restart_sample(seed, attempt, qlay, s_lo, s_hi, q)
        cost, iters, ok = _run(
            q, ints, flts, tip_pl, R_t, p_t, w, use_rot, layout, tol, max_iter, settings, cand
        )
        total += iters
        if cost < best_cost:
            best_q[:] = cand
            best_cost = cost
        if ok:
            return best_q, best_cost, total, attempt, True
    return best_q, best_cost, total, attempt, False


@parallel_kernel
def solve_batch(Rs, ps, w, use_rot, Q0, layout, tol, max_iter, restarts, seed, settings, chain):
    """:func:`solve` for N targets over the machine's cores (target i uses seed + i)."""
    N, nq = ps.shape[0], Q0.shape[1]
    q_out = np.empty((N, nq))
    iters = np.empty(N, np.int64)
    tries = np.empty(N, np.int64)
    for i in prange(N):
        q, _, it, att, _ = solve(
            Rs[i], ps[i], w, use_rot, Q0[i], layout, tol, max_iter,
            (0, restarts + 1), seed + i, settings, chain,
        )  # fmt: skip
        q_out[i] = q
        iters[i] = it
        tries[i] = att
    return q_out, iters, tries


@kernel
def solve_batch_serial(
    Rs, ps, w, use_rot, Q0, layout, tol, max_iter, restarts, seed, settings, chain
):
    """:func:`solve_batch` on one core (a few targets, or a thread of a thread pool)."""
    N, nq = ps.shape[0], Q0.shape[1]
    q_out = np.empty((N, nq))
    iters = np.empty(N, np.int64)
    tries = np.empty(N, np.int64)
    for i in range(N):
        q, _, it, att, _ = solve(
            Rs[i], ps[i], w, use_rot, Q0[i], layout, tol, max_iter,
            (0, restarts + 1), seed + i, settings, chain,
        )  # fmt: skip
        q_out[i] = q
        iters[i] = it
        tries[i] = att
    return q_out, iters, tries
