"""The bookkeeping of ``Robot.ik_all``, compiled (numba): every turn of each joint within its
limits, branches equal up to whole turns, and the errors of branch poses against a target.
:mod:`toolkit.ik.analytic.branches` calls them; ``tests/ik/test_analytic_ik.py`` holds them equal to
their definitions on random rows."""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ...kinematics import inline_kernel, kernel, twin_kernel
from ...kinematics import kernels as kinematics_kernels
from ..checks import pose_errors

TWO_PI = 2.0 * math.pi
SAME = 1e-9
"""Rows closer than this (rad or m, every joint, up to whole turns) are the same branch."""
EDGE = 1e-12
"""A limit is inclusive to this [rad]."""


@inline_kernel
def wrap(a):
    """The angle a in [-pi, pi): a itself where it is there already (no rounding added)."""
    return a if -math.pi <= a < math.pi else (a + math.pi) % TWO_PI - math.pi


@kernel
def turn_counts(A, lo, hi, turn):
    """(A with revolute angles wrapped to [-pi, pi), the first turn (B, n), how many turns
    (B, n), how many rows they give in all (a float: it may overflow an integer)) of rows
    A (B, n): per joint the k of a + 2 pi k within [lo, hi]; one (k = 0, the wrapped angle)
    where none fits or the joint is unbounded or prismatic (``turn`` False)."""
    B, n = A.shape
    a = A.copy()
    first = np.zeros((B, n))
    counts = np.ones((B, n), np.int64)
    total = 0.0
    for b in range(B):
        rows = 1.0
        for j in range(n):
            if not turn[j]:
                continue
            x = wrap(a[b, j])
            a[b, j] = x
            if math.isfinite(lo[j]) and math.isfinite(hi[j]):
                f = math.ceil((lo[j] - EDGE - x) / TWO_PI)
                last = math.floor((hi[j] + EDGE - x) / TWO_PI)
                if last >= f:
                    first[b, j] = f
                    counts[b, j] = int(min(last - f + 1.0, 2.0**53))
                    rows *= counts[b, j]
        total += rows
    return a, first, counts, total


@kernel
def expand_turns(a, first, counts):
    """(rows (K, n), owner (K,)): each row of a (B, n) with every combination of its joints'
    turns (``first``, ``counts`` of :func:`turn_counts`), the last joint's changing fastest."""
    B, n = a.shape
    per = np.ones(B, np.int64)
    for b in range(B):
        for j in range(n):
            per[b] *= counts[b, j]
    rows = np.empty((per.sum(), n))
    owner = np.empty(per.sum(), np.int64)
    k = 0
    for b in range(B):
        for m in range(per[b]):
            local = m
            for j in range(n - 1, -1, -1):
                c = counts[b, j]
                rows[k, j] = a[b, j] + TWO_PI * (first[b, j] + local % c)
                local //= c
            owner[k] = b
            k += 1
    return rows, owner


@kernel
def distinct_rows(A, sliding):
    """(B,) True for each row of A (B, n) farther than :data:`SAME` (the largest joint's
    difference, up to whole turns where not ``sliding``) from every earlier row."""
    B, n = A.shape
    keep = np.ones(B, np.bool_)
    for i in range(B):
        for k in range(i):
            same = True
            for j in range(n):  # every joint within SAME; the first that is not decides
                d = abs(A[i, j] - A[k, j])
                if not sliding[j] and d > math.pi:
                    d = abs((A[i, j] - A[k, j] + math.pi) % TWO_PI - math.pi)
                if not d < SAME:  # a NaN is never the same
                    same = False
                    break
            if same:
                keep[i] = False
                break
    return keep


@kernel
def errors_rows(F, T, use_rot):
    """(position errors (B,), orientation errors (B,)) of poses F (B, 4, 4) against T
    (:func:`~toolkit.ik.checks.pose_errors`); the orientation's 0 unless ``use_rot``."""
    B = F.shape[0]
    pos = np.empty(B)
    rot = np.zeros(B)
    for b in range(B):
        p, r = pose_errors(F[b], T)
        pos[b] = p
        if use_rot:
            rot[b] = r
    return pos, rot


@kernel
def distinct_batch(A, sliding):
    """:func:`distinct_rows` of each target's rows A (N, B, n) (N, B); NaN rows (past a
    target's branches) are never the same as another."""
    N, B = A.shape[0], A.shape[1]
    keep = np.empty((N, B), np.bool_)
    for i in range(N):
        keep[i] = distinct_rows(A[i], sliding)
    return keep


@kernel
def _smallest_eigen(M, out_vec):
    """The smallest eigenvalue of the symmetric matrix M (n, n) by cyclic Jacobi rotations
    (M is overwritten), its unit eigenvector into ``out_vec``."""
    n = M.shape[0]
    V = np.eye(n)
    scale = 0.0
    for p in range(n):
        scale += M[p, p] * M[p, p]
    for _ in range(30):
        off = 0.0
        for p in range(n):
            for q in range(p + 1, n):
                off += M[p, q] * M[p, q]
        if off <= 1e-30 * scale:  # the eigenvalues to ~1e-15 of the largest
            break
        for p in range(n):
            for q in range(p + 1, n):
                if abs(M[p, q]) < 1e-300:
                    continue
                theta = (M[q, q] - M[p, p]) / (2.0 * M[p, q])
                t = (1.0 if theta >= 0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):  # columns p, q of M J
                    mkp, mkq = M[k, p], M[k, q]
                    M[k, p], M[k, q] = c * mkp - s * mkq, s * mkp + c * mkq
                for k in range(n):  # rows p, q of J^T (M J)
                    mpk, mqk = M[p, k], M[q, k]
                    M[p, k], M[q, k] = c * mpk - s * mqk, s * mpk + c * mqk
                for k in range(n):
                    vkp, vkq = V[k, p], V[k, q]
                    V[k, p], V[k, q] = c * vkp - s * vkq, s * vkp + c * vkq
    best = 0
    for k in range(1, n):
        if M[k, k] < M[best, best]:
            best = k
    for k in range(n):
        out_vec[k] = V[k, best]
    return M[best, best]


@twin_kernel
def smallest_singular(J):
    """(the smallest singular value (B,), its right singular vector (B, n)) of each
    Jacobian J (B, m, n): the smallest eigenpair of J^T J by Jacobi rotations, over the
    cores (numpy's batched ``eigh`` runs 6x6 matrices one by one, several times slower)."""
    B, m, n = J.shape
    sigma = np.empty(B)
    vec = np.empty((B, n))
    for b in prange(B):
        M = np.empty((n, n))
        for i in range(n):
            for j in range(i, n):
                acc = 0.0
                for k in range(m):
                    acc += J[b, k, i] * J[b, k, j]
                M[i, j] = acc
                M[j, i] = acc
        sigma[b] = math.sqrt(max(_smallest_eigen(M, vec[b]), 0.0))
    return sigma, vec


@twin_kernel
def singular_at_least(J, s):
    """(B,) True where the smallest singular value of J[b] (m, n) is at least ``s``, proven
    by a Cholesky factorisation of J^T J - s^2 I (positive definite exactly then): a screen
    that spares :func:`smallest_singular`'s Jacobi sweeps on the rows far from a
    singularity (every pivot must stay above a rounding margin, so a row within rounding
    of ``s`` is left to the exact computation)."""
    B, n = J.shape[0], J.shape[2]
    out = np.empty(B, dtype=np.bool_)
    for b in prange(B):
        out[b] = _at_least(J[b], s, np.empty((n, n)))
    return out


@twin_kernel
def singular_at_least_at(Q, chain, rows, cols, s):
    """:func:`singular_at_least` of the chain Jacobians at configurations Q (B, nq),
    made here row by row (``chain`` = (ints, flts, tip_pl, nv): the compiled kinematics'
    arrays; the Jacobian's first ``rows`` rows, its columns ``cols``): no (B, 6, nv) array
    is made (for 160,000 rows, 46 MB that took longer to fill than the screen)."""
    ints, flts, tip_pl, nv = chain
    B, n = Q.shape[0], cols.shape[0]
    out = np.empty(B, dtype=np.bool_)
    for c in prange((B + _ROWS - 1) // _ROWS):
        W, R, p = np.empty((ints.shape[0] + 1, 15)), np.empty((3, 3)), np.empty(3)
        J, Jc, L = np.empty((6, nv)), np.empty((rows, n)), np.empty((n, n))
        for b in range(c * _ROWS, min(B, (c + 1) * _ROWS)):
            kinematics_kernels.frames(Q[b], ints, flts, W)
            kinematics_kernels.tip(W, tip_pl, R, p)
            kinematics_kernels.jacobian(W, ints, flts, p, J)
            for i in range(rows):
                for j in range(n):
                    Jc[i, j] = J[i, cols[j]]
            out[b] = _at_least(Jc, s, L)
    return out


_ROWS = 256
"""Rows per work item of :func:`singular_at_least_at` (one set of buffers each)."""


@inline_kernel
def _at_least(J, s, L):
    """Whether the smallest singular value of J (m, n) is at least ``s``
    (:func:`singular_at_least`); L (n, n) scratch."""
    m, n = J.shape
    scale = 0.0
    for i in range(n):
        for j in range(i + 1):
            acc = 0.0
            for k in range(m):
                acc += J[k, i] * J[k, j]
            L[i, j] = acc
        scale = max(scale, L[i, i])
    margin = 1e-12 * scale + 1e-300
    for i in range(n):
        L[i, i] -= s * s
    for j in range(n):
        d = L[j, j]
        for k in range(j):
            d -= L[j, k] * L[j, k]
        if d <= margin:
            return False
        d = math.sqrt(d)
        L[j, j] = d
        for i in range(j + 1, n):
            acc = L[i, j]
            for k in range(j):
                acc -= L[i, k] * L[j, k]
            L[i, j] = acc / d
    return True
