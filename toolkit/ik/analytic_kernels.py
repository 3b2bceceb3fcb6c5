"""The analytic families of :mod:`toolkit.ik.analytic`, compiled (numba): the same
subproblems and the same peeling, step for step, on small arrays, for one target or N at
once. ``tests/test_analytic_ik.py`` holds both forms equal.

A family kernel fills ``out`` (8, 6) with the branches' joint angles and ``roots`` (8, 3)
with the root each took (shoulder, elbow, wrist: 0 or 1; -1 where the subproblem had one
root), and returns how many it found. ``near``: least-squares subproblem answers are
accepted (a single one split into two starts :data:`~toolkit.ik.analytic.SPLIT` apart).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..kinematics import inline_kernel, kernel, kernels, twin_kernel

EXACT, LEAST_SQUARES, INFINITE = 0, 1, 2
SPLIT = 0.1
TOL = 1e-9
ZERO = 1e-12


@inline_kernel
def _rot(k, t, R):
    """R = R(k, t) (Rodrigues)."""
    c, s = math.cos(t), math.sin(t)
    v = 1.0 - c
    x, y, z = k[0], k[1], k[2]
    R[0, 0], R[0, 1], R[0, 2] = c + v * x * x, v * x * y - s * z, v * x * z + s * y
    R[1, 0], R[1, 1], R[1, 2] = v * x * y + s * z, c + v * y * y, v * y * z - s * x
    R[2, 0], R[2, 1], R[2, 2] = v * x * z - s * y, v * y * z + s * x, c + v * z * z


@inline_kernel
def _mv(R, p, out):
    for i in range(3):
        out[i] = R[i, 0] * p[0] + R[i, 1] * p[1] + R[i, 2] * p[2]


@inline_kernel
def _mtv(R, p, out):
    """out = R^T p."""
    for i in range(3):
        out[i] = R[0, i] * p[0] + R[1, i] * p[1] + R[2, i] * p[2]


@inline_kernel
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@inline_kernel
def _sp1(p1, p2, k):
    """(theta, flag) of SP1: R(k, theta) p1 = p2 (see toolkit.ik.subproblems.sp1)."""
    d1, d2 = _dot(k, p1), _dot(k, p2)
    a0, a1, a2 = p1[0] - k[0] * d1, p1[1] - k[1] * d1, p1[2] - k[2] * d1
    b0, b1, b2 = p2[0] - k[0] * d2, p2[1] - k[1] * d2, p2[2] - k[2] * d2
    na = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    nb = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
    same = abs(d1 - d2) < TOL
    if na < ZERO or nb < ZERO:
        if na < ZERO and nb < ZERO and same:
            return 0.0, INFINITE
        return 0.0, LEAST_SQUARES
    cx, cy, cz = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    t = math.atan2(k[0] * cx + k[1] * cy + k[2] * cz, a0 * b0 + a1 * b1 + a2 * b2)
    return t, (EXACT if abs(na - nb) < TOL and same else LEAST_SQUARES)


@inline_kernel
def _sp4(h, p, k, d):
    """(count, theta_a, theta_b, flag) of SP4: h^T R(k, theta) p = d."""
    kp, hk = _dot(k, p), _dot(h, k)
    A = _dot(h, p) - hk * kp
    cx = k[1] * p[2] - k[2] * p[1]
    cy = k[2] * p[0] - k[0] * p[2]
    cz = k[0] * p[1] - k[1] * p[0]
    B = h[0] * cx + h[1] * cy + h[2] * cz
    c = d - hk * kp
    r = math.hypot(A, B)
    if r < ZERO:
        return 1, 0.0, 0.0, (INFINITE if abs(c) < TOL else LEAST_SQUARES)
    phi = math.atan2(B, A)
    ratio = c / r
    scale = math.sqrt(_dot(h, h) * _dot(p, p))
    if abs(c) - r > 1e-12 * max(1.0, scale):  # beyond reach by more than rounding
        t = phi if ratio > 0 else phi + math.pi
        return 1, t, t, LEAST_SQUARES
    delta = math.acos(max(-1.0, min(1.0, ratio)))
    if delta < 1e-12:
        return 1, phi, phi, EXACT
    return 2, phi + delta, phi - delta, EXACT


@inline_kernel
def _roots(n, a, b, flag, near):
    """The roots a branch loop runs over: (count, first, second, usable)."""
    if flag == EXACT:
        return n, a, b, True
    if flag == LEAST_SQUARES and near:
        if n == 1:
            return 2, a + SPLIT, a - SPLIT, True
        return n, a, b, True
    return 0, a, b, False


@kernel
def three_parallel(h, o, tip_R, tip_p, T, near, out, roots):  # long: one peeling
    """Branches of the three-parallel family (:func:`toolkit.ik.analytic.three_parallel`)."""
    M = np.empty((6, 3, 3))  # the 3x3 and 3-vector scratch: two allocations per call
    V = np.empty((11, 3))
    R06, R01, R5, R6, R14, Rt = M[0], M[1], M[2], M[3], M[4], M[5]
    p6T, v, tmp, w, x, d = V[0], V[1], V[2], V[3], V[4], V[5]
    p12, p23, p34, p45, perp = V[6], V[7], V[8], V[9], V[10]
    for i in range(3):
        for j in range(3):
            R06[i, j] = T[i, 0] * tip_R[j, 0] + T[i, 1] * tip_R[j, 1] + T[i, 2] * tip_R[j, 2]
    for i in range(3):
        p6T[i] = tip_p[i] - o[5, i]
    _mv(R06, p6T, tmp)
    for i in range(3):
        v[i] = T[i, 3] - o[0, i] - tmp[i]
    s3 = 1.0 if _dot(h[2], h[1]) > 0 else -1.0
    s4 = 1.0 if _dot(h[3], h[1]) > 0 else -1.0
    for i in range(3):
        tmp[i] = o[4, i] - o[0, i]
    n1, a1, b1, f1 = _sp4(h[1], v, h[0], _dot(h[1], tmp))
    n1, a1, b1, ok = _roots(n1, a1, b1, f1, near)
    for i in range(3):
        p12[i], p23[i] = o[1, i] - o[0, i], o[2, i] - o[1, i]
        p34[i], p45[i] = o[3, i] - o[2, i], o[4, i] - o[3, i]
    _perp_unit(h[1], perp)
    count = 0
    if not ok:
        return 0
    for i1 in range(n1):
        q1 = -(a1 if i1 == 0 else b1)
        _rot(h[0], q1, R01)
        _mv(R06, h[5], tmp)
        _mtv(R01, tmp, w)
        n5, a5, b5, f5 = _sp4(h[1], h[5], h[4], _dot(h[1], w))
        n5, a5, b5, ok5 = _roots(n5, a5, b5, f5, near)
        if not ok5:
            continue
        for i5 in range(n5):
            q5 = a5 if i5 == 0 else b5
            _rot(h[4], -q5, R5)
            _mv(R5, h[1], tmp)
            _mv(R01, h[1], x)
            _mtv(R06, x, w)
            t6, f6 = _sp1(tmp, w, h[5])
            if not (f6 == EXACT or (near and f6 == LEAST_SQUARES)):
                continue
            q6 = -t6
            # R14 = R01^T R06 R(h6, -q6) R(h5, -q5)
            _rot(h[5], -q6, R6)
            for i in range(3):
                for j in range(3):
                    Rt[i, j] = R6[i, 0] * R5[0, j] + R6[i, 1] * R5[1, j] + R6[i, 2] * R5[2, j]
            for i in range(3):
                for j in range(3):
                    R14[i, j] = R06[i, 0] * Rt[0, j] + R06[i, 1] * Rt[1, j] + R06[i, 2] * Rt[2, j]
            for i in range(3):
                for j in range(3):
                    Rt[i, j] = R01[0, i] * R14[0, j] + R01[1, i] * R14[1, j] + R01[2, i] * R14[2, j]
            _mv(Rt, perp, tmp)
            t14, _ = _sp1(perp, tmp, h[1])
            _mtv(R01, v, d)
            _mv(Rt, p45, tmp)
            for i in range(3):
                d[i] = d[i] - p12[i] - tmp[i]
            for i in range(3):
                tmp[i] = -p23[i]
            nd = math.sqrt(_dot(d, d))
            target = 0.5 * (_dot(p34, p34) + _dot(tmp, tmp) - nd * nd)
            n3, a3, b3, f3 = _sp4(tmp, p34, h[2], target)
            n3, a3, b3, ok3 = _roots(n3, a3, b3, f3, near)
            if not ok3:
                continue
            for i3 in range(n3):
                q3 = a3 if i3 == 0 else b3
                _rot(h[2], q3, Rt)
                _mv(Rt, p34, w)
                for i in range(3):
                    w[i] += p23[i]
                q2, f2 = _sp1(w, d, h[1])
                if not (f2 == EXACT or (near and f2 == LEAST_SQUARES)):
                    continue
                q4 = s4 * (t14 - q2 - s3 * q3)
                out[count, 0], out[count, 1], out[count, 2] = q1, q2, q3
                out[count, 3], out[count, 4], out[count, 5] = q4, q5, q6
                roots[count, 0] = i1 if n1 == 2 else -1
                roots[count, 1] = i3 if n3 == 2 else -1
                roots[count, 2] = i5 if n5 == 2 else -1
                count += 1
    return count


@inline_kernel
def _perp_unit(h, out):
    """A unit vector perpendicular to h into out."""
    x0, x1, x2 = 0.0, h[2], -h[1]  # h x e_x
    if x1 * x1 + x2 * x2 < 0.25:
        x0, x1, x2 = -h[2], 0.0, h[0]  # h x e_y
    n = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    out[0], out[1], out[2] = x0 / n, x1 / n, x2 / n


@twin_kernel
def three_parallel_batch(h, o, tip_R, tip_p, Ts, near):
    """:func:`three_parallel` for N targets: (N, 8, 6) angles, (N, 8, 3) roots, (N,) counts."""
    N = Ts.shape[0]
    out = np.zeros((N, 8, 6))
    roots = np.full((N, 8, 3), -1, np.int64)
    counts = np.zeros(N, np.int64)
    for i in prange(N):
        counts[i] = three_parallel(h, o, tip_R, tip_p, Ts[i], near, out[i], roots[i])
    return out, roots, counts


frames, tip = kernels.frames, kernels.tip


@kernel
def _verify_rows(A, counts, rest, qcol, circle, ints, flts, tip_pl, Ts, Q, pos, rot, start, stop):
    """Rows start .. stop - 1: each branch's q (the chain's angles into ``rest``) and its
    errors by the kinematics kernels' forward kinematics (no code shared with the
    subproblems)."""
    W = np.empty((ints.shape[0] + 1, 15))
    R = np.empty((3, 3))
    p = np.empty(3)
    for i in range(start, stop):
        for b in range(counts[i]):
            q = Q[i, b]
            q[:] = rest
            for c in range(qcol.shape[0]):
                a = A[i, b, c]
                a -= 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))  # [-pi, pi)
                if circle[c]:
                    q[qcol[c]], q[qcol[c] + 1] = math.cos(a), math.sin(a)
                else:
                    q[qcol[c]] = a
            frames(q, ints, flts, W)
            tip(W, tip_pl, R, p)
            e = 0.0
            chord = 0.0
            for r in range(3):
                e += (p[r] - Ts[i, r, 3]) ** 2
                for s in range(3):
                    chord += (R[r, s] - Ts[i, r, s]) ** 2
            pos[i, b] = math.sqrt(e)
            rot[i, b] = 2.0 * math.asin(min(1.0, math.sqrt(chord) / (2.0 * math.sqrt(2.0))))


@twin_kernel
def verify_batch(A, counts, rest, qcol, circle, ints, flts, tip_pl, Ts):
    """(Q (N, 8, nq), position errors (N, 8), orientation errors (N, 8)) of the branches
    ``A`` (N, 8, 6) of targets Ts (N, 4, 4); NaN past each target's count."""
    N = A.shape[0]
    Q = np.full((N, 8, rest.shape[0]), np.nan)
    pos = np.full((N, 8), np.nan)
    rot = np.full((N, 8), np.nan)
    chunk = 256
    for c in prange((N + chunk - 1) // chunk):
        _verify_rows(A, counts, rest, qcol, circle, ints, flts, tip_pl, Ts, Q, pos, rot,
                     c * chunk, min(N, (c + 1) * chunk))  # fmt: skip
    return Q, pos, rot


@inline_kernel
def _mm(A, B, out):
    """out = A B (3 x 3)."""
    for i in range(3):
        for m in range(3):
            out[i, m] = A[i, 0] * B[0, m] + A[i, 1] * B[1, m] + A[i, 2] * B[2, m]


@inline_kernel
def _mtm(A, B, out):
    """out = A^T B (3 x 3)."""
    for i in range(3):
        for m in range(3):
            out[i, m] = A[0, i] * B[0, m] + A[1, i] * B[1, m] + A[2, i] * B[2, m]


@kernel
def pair_curves(h, o, tip_R, tip_p, T, q6s, E, Q, RX):  # long: one peeling per trial q6
    """The curves of :mod:`toolkit.ik.search` at each trial q6: E (N, 4) the residual (NaN
    where the curve does not exist), Q (N, 4, 3) its q1, q2, q3, RX (N, 3, 3) the rotation
    ``R(h1, q1) ... R(h5, q5)`` the target asks of joints 1-5."""
    RTM = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            RTM[i, j] = T[i, 0] * tip_R[j, 0] + T[i, 1] * tip_R[j, 1] + T[i, 2] * tip_R[j, 2]
    V = np.empty((8, 3))
    a, b, n, y, x, t, base, meet = V[0], V[1], V[2], V[3], V[4], V[5], V[6], V[7]
    M = np.empty((6, 3, 3))
    R6, R1, R2, R3, R12, Rr = M[0], M[1], M[2], M[3], M[4], M[5]
    for i in range(3):
        a[i], b[i] = o[3, i] - o[2, i], o[0, i] - o[2, i]
    n[0] = h[1, 1] * h[0, 2] - h[1, 2] * h[0, 1]
    n[1] = h[1, 2] * h[0, 0] - h[1, 0] * h[0, 2]
    n[2] = h[1, 0] * h[0, 1] - h[1, 1] * h[0, 0]
    hb, ha, g, s2 = _dot(b, h[2]), _dot(h[2], a), _dot(h[1], h[0]), _dot(n, n)
    A = _dot(b, a) - hb * ha
    B = (b[0] * (h[2, 1] * a[2] - h[2, 2] * a[1]) + b[1] * (h[2, 2] * a[0] - h[2, 0] * a[2])
         + b[2] * (h[2, 0] * a[1] - h[2, 1] * a[0]))  # fmt: skip
    r, phi, h45, det = math.hypot(A, B), math.atan2(B, A), _dot(h[3], h[4]), 1.0 - g * g
    for j in range(q6s.shape[0]):
        _rot(h[5], -q6s[j], R6)
        for i in range(3):
            t[i] = o[3, i] - o[5, i]
        _mv(R6, t, x)
        for i in range(3):
            t[i] = o[5, i] + x[i] - tip_p[i]
        _mv(RTM, t, y)
        for i in range(3):
            y[i] += T[i, 3] - o[0, i]
        _mm(RTM, R6, RX[j])
        E[j, :] = np.nan
        ratio = (0.5 * (_dot(a, a) + _dot(b, b) - _dot(y, y)) - hb * ha) / r
        if abs(ratio) > 1.0 + 1e-12:
            continue
        delta = math.acos(max(-1.0, min(1.0, ratio)))
        for k in range(2):
            q3 = phi + delta if k == 0 else phi - delta
            _rot(h[2], q3, R3)
            _mv(R3, a, t)
            for i in range(3):
                x[i] = o[2, i] - o[0, i] + t[i]
            a1, a2 = _dot(x, h[1]), _dot(y, h[0])
            for i in range(3):
                base[i] = (a1 - g * a2) / det * h[1, i] + (a2 - g * a1) / det * h[0, i]
            rest = 0.5 * (_dot(x, x) + _dot(y, y)) - _dot(base, base)
            if rest < -1e-12:
                continue
            z = math.sqrt(max(rest, 0.0) / s2)
            for s in range(2):
                for i in range(3):
                    meet[i] = base[i] + (z if s == 0 else -z) * n[i]
                q2 = _sp1(x, meet, h[1])[0]
                q1 = -_sp1(y, meet, h[0])[0]
                _rot(h[0], q1, R1)
                _rot(h[1], q2, R2)
                _mm(R1, R2, R12)
                _mm(R12, R3, R1)  # R1 = R(h1, q1) R(h2, q2) R(h3, q3)
                _mtm(R1, RX[j], Rr)
                _mv(Rr, h[4], t)
                E[j, 2 * k + s] = _dot(h[3], t) - h45
                Q[j, 2 * k + s, 0], Q[j, 2 * k + s, 1], Q[j, 2 * k + s, 2] = q1, q2, q3
