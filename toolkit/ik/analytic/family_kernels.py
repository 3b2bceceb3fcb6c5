"""The analytic families of :mod:`toolkit.ik.analytic.families`, compiled (numba): the same
subproblems and the same peeling, step for step, on small arrays, for one target or N at
once. ``tests/ik/test_analytic_ik.py`` holds both forms equal.

A family kernel fills ``out`` (8, n) with the branches' joint angles (n = 6, or 5 for the
5R family), ``roots`` (8, 3) with the root each took (shoulder, elbow, wrist: 0 or 1; -1
where the subproblem had one root) and ``free`` (8,) with the joints left free (bit j: the
chain's joint j), and returns how many it found. Where a subproblem has infinitely many
answers (a singular pose: the wrist with axes 4 and 6 on one line, the wrist centre on axis
1 or 2) the free joint takes its angle in ``pref`` (n,) and the branch is a representative
of its family of solutions. ``near``: least-squares
subproblem answers are accepted (a single one split into two starts
:data:`~toolkit.ik.analytic.families.SPLIT` apart). The subproblems themselves are in
:mod:`toolkit.ik.analytic.subproblem_kernels`.
"""

from __future__ import annotations

import math

import numpy as np

from ...kinematics import inline_kernel, kernel
from .subproblem_kernels import (
    INFINITE,
    dot,
    first_turn,
    free_angle,
    free_roots,
    mm,
    mmt,
    mtm,
    mtv,
    mv,
    perp_unit,
    planar_elbows,
    rotation,
    sp1,
    sp1_xy,
    sp4,
    turn_vector,
)

FREE_TRIALS = 64
"""At the three-parallel wrist singularity, the q6 values tried (a whole turn in this many
steps, the nearest the preferred angle first)."""


@kernel
def three_parallel(h, o, tip_R, tip_p, T, near, pref, out, roots, free):  # long: one peeling
    """Branches of the three-parallel family
    (:func:`toolkit.ik.analytic.families.three_parallel`)."""
    M = np.empty((6, 3, 3))  # the 3x3 and 3-vector scratch, the elbow's rows
    V = np.empty((11, 3))
    E = np.empty((2, 4))
    R06, R01, R5, R6, R14, Rt = M[0], M[1], M[2], M[3], M[4], M[5]
    p6T, v, tmp, w, x, d = V[0], V[1], V[2], V[3], V[4], V[5]
    p12, p23, p34, p45, perp = V[6], V[7], V[8], V[9], V[10]
    mmt(T, tip_R, R06)
    for i in range(3):
        p6T[i] = tip_p[i] - o[5, i]
    mv(R06, p6T, tmp)
    for i in range(3):
        v[i] = T[i, 3] - o[0, i] - tmp[i]
    s3 = 1.0 if dot(h[2], h[1]) > 0 else -1.0
    s4 = 1.0 if dot(h[3], h[1]) > 0 else -1.0
    for i in range(3):
        tmp[i] = o[4, i] - o[0, i]
    n1, a1, b1, f1 = sp4(h[1], v, h[0], dot(h[1], tmp))
    n1, a1, b1, ok, free1 = free_roots(n1, a1, b1, f1, near, -pref[0])
    for i in range(3):
        p12[i], p23[i] = o[1, i] - o[0, i], o[2, i] - o[1, i]
        p34[i], p45[i] = o[3, i] - o[2, i], o[4, i] - o[3, i]
    perp_unit(h[1], perp)
    count = 0
    if not ok:
        return 0
    for i1 in range(n1):
        q1 = first_turn(h[0], a1, b1, i1, R01)
        mv(R06, h[5], tmp)
        mtv(R01, tmp, w)
        n5, a5, b5, f5 = sp4(h[1], h[5], h[4], dot(h[1], w))
        n5, a5, b5, ok5, free5 = free_roots(n5, a5, b5, f5, near, pref[4])
        if not ok5:
            continue
        for i5 in range(n5):
            q5 = a5 if i5 == 0 else b5
            rotation(h[4], -q5, R5)
            mv(R5, h[1], tmp)
            mv(R01, h[1], x)
            mtv(R06, x, w)
            t6, f6 = sp1(tmp, w, h[5])  # every q6 where axes 4 and 6 line up (q5 = 0)
            t6, ok6, free6 = free_angle(t6, f6, near, -pref[5])
            if not ok6:
                continue
            # axes 2, 3, 4 and 6 parallel: a planar 4R whose q6 moves the wrist, so only an
            # arc of q6 reaches; the trial nearest pref[5] (steps of 2 pi / FREE_TRIALS)
            # where the elbow reaches is the representative
            for trial in range(FREE_TRIALS if free6 else 1):
                step = (trial + 1) // 2 if trial % 2 == 1 else -(trial // 2)
                q6 = pref[5] + step * (2.0 * math.pi / FREE_TRIALS) if free6 else -t6
                # R14 = R01^T R06 R(h6, -q6) R(h5, -q5)
                rotation(h[5], -q6, R6)
                mm(R6, R5, Rt)
                mm(R06, Rt, R14)
                mtm(R01, R14, Rt)
                mv(Rt, perp, tmp)
                t14, _ = sp1(perp, tmp, h[1])
                mtv(R01, v, d)
                mv(Rt, p45, tmp)
                for i in range(3):
                    d[i] = d[i] - p12[i] - tmp[i]
                k3, n3 = planar_elbows(d, p23, p34, h[1], h[2], near, pref[1], E, Rt, w, tmp)
                if n3 == 0:
                    continue
                for e in range(k3):
                    q3, q2 = E[e, 0], E[e, 1]
                    out[count, 0], out[count, 1], out[count, 2] = q1, q2, q3
                    out[count, 3], out[count, 4] = s4 * (t14 - q2 - s3 * q3), q5
                    out[count, 5] = q6
                    roots[count, 0] = i1 if n1 == 2 else -1
                    roots[count, 1] = int(E[e, 3])
                    roots[count, 2] = i5 if n5 == 2 else -1
                    free[count] = ((1 if free1 else 0) | (2 if E[e, 2] else 0)
                                   | (16 if free5 else 0) | (32 if free6 else 0))  # fmt: skip
                    count += 1
                break
    return count


@kernel
def five_r_parallel(h, o, tip_R, tip_p, T, near, pref, out, roots, free):  # long: one peeling
    """Branches of a 5R chain whose axes 2, 3, 4 are parallel
    (:func:`toolkit.ik.analytic.families.five_r_parallel`) into ``out`` (8, 5); the wrist
    root is -1."""
    M = np.empty((4, 3, 3))
    V = np.empty((10, 3))
    E = np.empty((2, 4))
    R05, R01, R5, Rt = M[0], M[1], M[2], M[3]
    v, tmp, w, x, d, p12, p23, p34, p45, perp = (
        V[0],
        V[1],
        V[2],
        V[3],
        V[4],
        V[5],
        V[6],
        V[7],
        V[8],
        V[9],
    )
    mmt(T, tip_R, R05)
    for i in range(3):
        tmp[i] = tip_p[i] - o[4, i]
    mv(R05, tmp, w)
    for i in range(3):
        v[i] = T[i, 3] - w[i] - o[0, i]  # o5 moved, seen from o1
        p12[i], p23[i] = o[1, i] - o[0, i], o[2, i] - o[1, i]
        p34[i], p45[i] = o[3, i] - o[2, i], o[4, i] - o[3, i]
        tmp[i] = o[4, i] - o[0, i]
    s3 = 1.0 if dot(h[2], h[1]) > 0 else -1.0
    s4 = 1.0 if dot(h[3], h[1]) > 0 else -1.0
    n1, a1, b1, f1 = sp4(h[1], v, h[0], dot(h[1], tmp))
    n1, a1, b1, ok, free1 = free_roots(n1, a1, b1, f1, near, -pref[0])
    if not ok:
        return 0
    perp_unit(h[1], perp)
    count = 0
    for i1 in range(n1):
        q1 = first_turn(h[0], a1, b1, i1, R01)
        mv(R01, h[1], tmp)
        mtv(R05, tmp, w)  # R(h5, -q5) h2 = R05^T R01 h2
        t5, f5 = sp1(h[1], w, h[4])
        if f5 == INFINITE:
            continue
        q5 = -t5
        rotation(h[4], -q5, R5)
        mv(R5, perp, tmp)
        mv(R05, tmp, w)
        mtv(R01, w, x)
        t14, _ = sp1(perp, x, h[1])
        rotation(h[1], t14, Rt)
        mv(Rt, p45, tmp)
        mtv(R01, v, d)
        for i in range(3):
            d[i] = d[i] - p12[i] - tmp[i]
        k3, _ = planar_elbows(d, p23, p34, h[1], h[2], near, pref[1], E, Rt, w, tmp)
        for e in range(k3):
            q3, q2 = E[e, 0], E[e, 1]
            out[count, 0], out[count, 1], out[count, 2] = q1, q2, q3
            out[count, 3], out[count, 4] = s4 * (t14 - q2 - s3 * q3), q5
            roots[count, 0], roots[count, 1], roots[count, 2] = (
                i1 if n1 == 2 else -1,
                int(E[e, 3]),
                -1,
            )
            free[count] = (1 if free1 else 0) | (2 if E[e, 2] else 0)
            count += 1
    return count


@inline_kernel
def curve_constants(h, o, tip_R, T):
    """What every trial q6 of one target shares: the target's rotation times the tool's,
    transposed (3, 3), the vectors a = o4 - o3, b = o1 - o3 and n = h2 x h1 (rows of a
    (3, 3)), and SP3's and SP2's scalars (hb, ha, g, s2, r, phi, h45, det)."""
    RTM = np.empty((3, 3))
    mmt(T, tip_R, RTM)
    C = np.empty((3, 3))
    a, b, n = C[0], C[1], C[2]
    for i in range(3):
        a[i], b[i] = o[3, i] - o[2, i], o[0, i] - o[2, i]
    n[0] = h[1, 1] * h[0, 2] - h[1, 2] * h[0, 1]
    n[1] = h[1, 2] * h[0, 0] - h[1, 0] * h[0, 2]
    n[2] = h[1, 0] * h[0, 1] - h[1, 1] * h[0, 0]
    hb, ha, g, s2 = dot(b, h[2]), dot(h[2], a), dot(h[1], h[0]), dot(n, n)
    A = dot(b, a) - hb * ha
    B = (b[0] * (h[2, 1] * a[2] - h[2, 2] * a[1]) + b[1] * (h[2, 2] * a[0] - h[2, 0] * a[2])
         + b[2] * (h[2, 0] * a[1] - h[2, 1] * a[0]))  # fmt: skip
    r, phi, h45, det = math.hypot(A, B), math.atan2(B, A), dot(h[3], h[4]), 1.0 - g * g
    return RTM, C, (hb, ha, g, s2, r, phi, h45, det)


@inline_kernel
def curve_ratio(h, o, tip_p, T, shared, q6, V, R6, RX):
    """At trial q6: y = X(W) - S into V[0] and the rotation joints 1-5 must make into RX;
    returns the cosine of SP3's elbow half gap (beyond 1 in size: no elbow root)."""
    RTM, C, S = shared
    hb, ha, r = S[0], S[1], S[4]
    y, x, t = V[0], V[1], V[2]
    rotation(h[5], -q6, R6)
    for i in range(3):
        t[i] = o[3, i] - o[5, i]
    mv(R6, t, x)
    for i in range(3):
        t[i] = o[5, i] + x[i] - tip_p[i]
    mv(RTM, t, y)
    for i in range(3):
        y[i] += T[i, 3] - o[0, i]
    mm(RTM, R6, RX)
    return (0.5 * (dot(C[0], C[0]) + dot(C[1], C[1]) - dot(y, y)) - hb * ha) / r


@inline_kernel
def curve_elbow(h, o, shared, q3, V, R3):
    """For elbow angle q3 (R3 = R(h3, q3)): x = X(o3 + R3 a) - S into V[1] and the foot of
    SP2's two circles' meeting line into V[3]; returns what is left of |x|^2 beyond it
    (below -1e-12: the circles do not meet)."""
    C, g, det = shared[1], shared[2][2], shared[2][7]
    y, x, t, base = V[0], V[1], V[2], V[3]
    rotation(h[2], q3, R3)
    mv(R3, C[0], t)
    for i in range(3):
        x[i] = o[2, i] - o[0, i] + t[i]
    a1, a2 = dot(x, h[1]), dot(y, h[0])
    for i in range(3):
        base[i] = (a1 - g * a2) / det * h[1, i] + (a2 - g * a1) / det * h[0, i]
    return 0.5 * (dot(x, x) + dot(y, y)) - dot(base, base)


@inline_kernel
def curve_residual(h, shared, z, V, R3, RX, M):
    """(e, y1, x1, y2, x2) of the curve through the meeting point base + z n (V as
    :func:`curve_elbow` left it): joints 1, 2 by SP1 on it (q1 = -atan2(y1, x1), q2 =
    atan2(y2, x2)), and e the residual of the angle between h4 and h5 that joints 4, 5 must
    keep, ``e = h4^T (R1 R2 R3)^T RX h5 - h4^T h5``: RX h5 turned back through joints 1, 2
    (by their angles' sines and cosines, no angle) and 3."""
    C, h45 = shared[1], shared[2][6]
    y, x, t, base, meet = V[0], V[1], V[2], V[3], V[4]
    u, w = M[0][0], M[0][1]
    for i in range(3):
        meet[i] = base[i] + z * C[2, i]
    y2, x2, _ = sp1_xy(x, meet, h[1])
    y1, x1, _ = sp1_xy(y, meet, h[0])
    mv(RX, h[4], t)
    turn_vector(h[0], y1, x1, t, u)  # R1^T = R(h1, -q1)
    turn_vector(h[1], -y2, x2, u, w)  # R2^T = R(h2, -q2)
    mtv(R3, w, t)
    return dot(h[3], t) - h45, y1, x1, y2, x2


@kernel
def pair_curves(h, o, tip_R, tip_p, T, q6s, E, Q, RX):
    """The curves of :mod:`toolkit.ik.analytic.search` at each trial q6: E (N, 4) the residual (NaN
    where the curve does not exist), Q (N, 4, 3) its q1, q2, q3, RX (N, 3, 3) the rotation
    ``R(h1, q1) ... R(h5, q5)`` the target asks of joints 1-5."""
    shared = curve_constants(h, o, tip_R, T)
    phi, s2 = shared[2][5], shared[2][3]
    V, M = np.empty((5, 3)), np.empty((6, 3, 3))
    angles = Q.shape[0] > 0
    for j in range(q6s.shape[0]):
        E[j, :] = np.nan
        ratio = curve_ratio(h, o, tip_p, T, shared, q6s[j], V, M[4], RX[j])
        if abs(ratio) > 1.0 + 1e-12:
            continue
        delta = math.acos(max(-1.0, min(1.0, ratio)))
        for k in range(2):
            q3 = phi + delta if k == 0 else phi - delta
            rest = curve_elbow(h, o, shared, q3, V, M[5])
            if rest < -1e-12:
                continue
            z = math.sqrt(max(rest, 0.0) / s2)
            for s in range(2):
                e, y1, x1, y2, x2 = curve_residual(h, shared, z if s == 0 else -z, V, M[5],
                                                   RX[j], M)  # fmt: skip
                E[j, 2 * k + s] = e
                if angles:
                    Q[j, 2 * k + s, 0] = -math.atan2(y1, x1)
                    Q[j, 2 * k + s, 1], Q[j, 2 * k + s, 2] = math.atan2(y2, x2), q3
