"""Compiled IK kernels: the damped-least-squares loop of :mod:`toolkit.ik` on the packed
chains of :mod:`toolkit.kinematics.kernels` (no allocation inside the loop)."""

from __future__ import annotations

import numpy as np
from numba import prange

from ...kinematics import inline_kernel, kernel, kernels, twin_kernel

frames, integrate, jacobian = kernels.frames, kernels.integrate, kernels.jacobian
restart_sample, tip = kernels.restart_sample, kernels.tip

# Matrices keep their mathematical names (R, J, A).


@inline_kernel
def log3(R, out, at=0):
    """Rotation vector of a rotation matrix into out[at:at + 3], robust near 0 and pi."""
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
            out[at + i] = sign * theta * a[i] / norm
        return
    out[at], out[at + 1], out[at + 2] = f * wx, f * wy, f * wz


@inline_kernel
def residual(q, ints, flts, tip_pl, T_t, use_rot, W, R, p, J, e, tmp):
    """Fill e (6) with the pose residual [p_t - p ; log3(R^T R_t)] of the target pose T_t
    (4, 4) and J with
    J_e = [J_v ; R^T J_w] (6, nv), on the buffers W, R, p and tmp (3, 3)."""
    frames(q, ints, flts, W)
    tip(W, tip_pl, R, p)
    jacobian(W, ints, flts, p, J)
    for i in range(3):
        e[i] = T_t[i, 3] - p[i]
    if use_rot:
        for i in range(3):
            for j in range(3):
                tmp[i, j] = R[0, i] * T_t[0, j] + R[1, i] * T_t[1, j] + R[2, i] * T_t[2, j]
        log3(tmp, e, 3)
        for c in range(J.shape[1]):
            w0, w1, w2 = J[3, c], J[4, c], J[5, c]
            J[3, c] = R[0, 0] * w0 + R[1, 0] * w1 + R[2, 0] * w2
            J[4, c] = R[0, 1] * w0 + R[1, 1] * w1 + R[2, 1] * w2
            J[5, c] = R[0, 2] * w0 + R[1, 2] * w1 + R[2, 2] * w2
    else:
        e[3] = e[4] = e[5] = 0.0


@inline_kernel
def _step(J, w, e, lam, A, dq):
    """dq solving (J^T W J + lam I) dq = J^T W e by an in-place Cholesky factorisation of A
    (its lower triangle becomes L, its diagonal 1 / L[i, i]); dq holds J^T W e first."""
    nv = J.shape[1]
    for i in range(nv):
        s = 0.0
        for r in range(6):
            s += J[r, i] * w[r] * e[r]
        dq[i] = s
        for j in range(i + 1):
            s = 0.0
            for r in range(6):
                s += J[r, i] * w[r] * J[r, j]
            A[i, j] = s
        A[i, i] += lam
    for j in range(nv):
        s = A[j, j]
        for k in range(j):
            s -= A[j, k] * A[j, k]
        d = 1.0 / np.sqrt(max(s, 1e-300))
        A[j, j] = d
        for i in range(j + 1, nv):
            s = A[i, j]
            for k in range(j):
                s -= A[i, k] * A[j, k]
            A[i, j] = s * d
    for i in range(nv):  # L y = b
        s = dq[i]
        for k in range(i):
            s -= A[i, k] * dq[k]
        dq[i] = s * A[i, i]
    for i in range(nv - 1, -1, -1):  # L^T dq = y
        s = dq[i]
        for k in range(i + 1, nv):
            s -= A[k, i] * dq[k]
        dq[i] = s * A[i, i]


@kernel
def _workspace(n, nv):
    """The buffers of one IK call (W, R, tmp, p, e, J, A, dq), made once per call."""
    return (
        np.empty((n + 1, 15)),
        np.empty((3, 3)),
        np.empty((3, 3)),
        np.empty(3),
        np.empty(6),
        np.empty((6, nv)),
        np.empty((nv, nv)),
        np.empty(nv),
    )


@inline_kernel
def _run(q, ints, flts, tip_pl, T_t, w, use_rot, layout, tol, max_iter, settings, best_q, ws):
    """Damped least squares from q, in place (the same loop as toolkit.ik's Pinocchio back
    end), on the buffers ``ws`` of :func:`_workspace`: best_q receives the best iterate;
    returns (its cost, iterations, converged)."""
    damping, lambda_min, stall = settings
    qlay, lo, hi = layout[0], layout[1], layout[2]
    W, R, tmp, p, e, J, A, dq = ws
    wmax = 1.0
    for i in range(6):
        wmax = max(wmax, w[i])
    tol2 = tol * tol * wmax
    for i in range(q.shape[0]):
        q[i] = min(max(q[i], lo[i]), hi[i])
    best_cost = np.inf
    since_best = 0
    for it in range(1, max_iter + 1):
        residual(q, ints, flts, tip_pl, T_t, use_rot, W, R, p, J, e, tmp)
        cost = 0.0
        for i in range(6):
            cost += w[i] * e[i] * e[i]
        cost *= 0.5
        since_best = 0 if cost < best_cost * (1.0 - 1e-3) else since_best + 1
        if cost < best_cost:
            for i in range(q.shape[0]):
                best_q[i] = q[i]
            best_cost = cost
        if cost <= tol2:
            pos = rot = 0.0
            for i in range(3):
                if w[i] > 0.0:
                    pos += e[i] * e[i]
                if w[i + 3] > 0.0:
                    rot += e[i + 3] * e[i + 3]
            if np.sqrt(pos) <= tol and np.sqrt(rot) <= tol:
                for i in range(q.shape[0]):  # this iterate, even if an earlier one cost less
                    best_q[i] = q[i]
                return cost, it, True
        if since_best >= stall:
            return best_cost, it, False
        _step(J, w, e, damping * cost + lambda_min, A, dq)
        integrate(q, dq, qlay, lo, hi)
    return best_cost, max_iter, False


@inline_kernel
def _solve(T_t, w, q0, layout, tol, max_iter, first, stop, seed, settings, chain):
    """Restarts ``first`` .. ``stop - 1`` (attempt 0 starts at q0, the others at
    :func:`toolkit.kinematics.kernels.restart_sample`): (best q, cost, iterations, last attempt,
    converged). Seeding by (seed, attempt) makes the answer independent of how the attempts
    are split between calls (the time budget is checked between calls)."""
    ints, flts, tip_pl = chain
    qlay, s_lo, s_hi = layout[0], layout[3], layout[4]
    use_rot = w[3] > 0.0 or w[4] > 0.0 or w[5] > 0.0
    nq = q0.shape[0]
    best_q, q, cand = q0.copy(), np.empty(nq), np.empty(nq)
    ws = _workspace(ints.shape[0], layout[5])
    best_cost = np.inf
    total = 0
    attempt = first
    for attempt in range(first, stop):
        if attempt == 0:
            q[:] = q0
        else:
            restart_sample(seed, attempt, qlay, s_lo, s_hi, q)
        cost, iters, ok = _run(
            q, ints, flts, tip_pl, T_t, w, use_rot, layout, tol, max_iter, settings, cand, ws
        )
        total += iters
        if cost < best_cost:
            best_q[:] = cand
            best_cost = cost
        if ok:
            return best_q, best_cost, total, attempt, True
    return best_q, best_cost, total, attempt, False


@inline_kernel
def _unpack(ibuf, fbuf):
    """(layout, settings, chain) of the two packed arrays of
    :meth:`toolkit.ik.numeric.loops.CompiledLoop.pack` (few arguments: each costs a call time)."""
    n, nq, nv, stall, rows = ibuf[0], ibuf[1], ibuf[2], ibuf[3], ibuf[4]
    ints = ibuf[5 : 5 + 6 * n].reshape((n, 6))
    qlay = ibuf[5 + 6 * n : 5 + 6 * n + 4 * rows].reshape((rows, 4))
    bounds = fbuf[2 : 2 + 4 * nq].reshape((4, nq))
    tip_pl = fbuf[2 + 4 * nq : 14 + 4 * nq]
    flts = fbuf[14 + 4 * nq : 14 + 4 * nq + 17 * n].reshape((n, 17))
    layout = (qlay, bounds[0], bounds[1], bounds[2], bounds[3], nv)
    return layout, (fbuf[0], fbuf[1], stall), (ints, flts, tip_pl)


@kernel
def solve(T_t, w, q0, ibuf, fbuf, tol, max_iter, first, stop, seed):
    """The IK of target pose T_t (4, 4) with weights w (6), restarts ``first`` ..
    ``stop - 1`` (see :func:`_solve`)."""
    layout, settings, chain = _unpack(ibuf, fbuf)
    return _solve(T_t, w, q0, layout, tol, max_iter, first, stop, seed, settings, chain)


@twin_kernel
def solve_batch(Ts, owner, w, Q0, ibuf, fbuf, tol, max_iter, restarts, seed):
    """:func:`solve` for N starts Q0 (N, nq), start i toward target Ts[owner[i]] (several
    starts may share a target: no copy of the targets made per start) and seeded seed + i;
    a twin: over the machine's cores or on one (a few targets, or a thread of a thread
    pool)."""
    layout, settings, chain = _unpack(ibuf, fbuf)
    N, nq = Q0.shape[0], Q0.shape[1]
    q_out = np.empty((N, nq))
    iters = np.empty(N, np.int64)
    tries = np.empty(N, np.int64)
    for i in prange(N):
        q, _, it, att, _ = _solve(
            Ts[owner[i]], w, Q0[i], layout, tol, max_iter, 0, restarts + 1, seed + i,
            settings, chain,
        )  # fmt: skip
        q_out[i] = q
        iters[i] = it
        tries[i] = att
    return q_out, iters, tries
