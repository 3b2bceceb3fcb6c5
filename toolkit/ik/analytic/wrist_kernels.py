"""The spherical-wrist families of :mod:`toolkit.ik.analytic.families` compiled (numba): axes 4, 5,
6 through one point W (the wrist centre), which fixes W from the target; joints 1-3 place
W (q1 by SP4, q3 by SP3, q2 by SP1; or, where axes 1 and 2 meet, q3 by SP3 and q1, q2 by
SP2), the wrist turns by what is left (q4, q5 by SP2, q6 by SP1). The same subproblems
and the same peeling as the Python form, step for step; ``tests/ik/test_analytic_ik.py``
holds both equal. Parameters as in :mod:`toolkit.ik.analytic.family_kernels`: ``pref`` (6,) the
angles of joints left free at a singular pose, out-parameters ``out`` (8, 6), ``roots``
(8, 3), ``free`` (8,)."""

from __future__ import annotations

import math

import numpy as np

from ...kinematics import inline_kernel, kernel
from . import subproblem_kernels as sk

__all__ = [
    "meeting_shoulder",
    "sp2",
    "spherical_wrist",
]


@inline_kernel
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@inline_kernel
def _off_axis(k, p):
    """|p - k (k . p)|: how far p lies from the axis k."""
    d = sk.dot(k, p)
    x, y, z = p[0] - k[0] * d, p[1] - k[1] * d, p[2] - k[2] * d
    return math.sqrt(x * x + y * y + z * z)


@inline_kernel
def sp2(p1, p2, k1, k2, pairs, work, R, v1, v2):
    """(count, flag, free) of SP2, R(k1, t1) p1 = R(k2, t2) p2 (see
    :func:`toolkit.ik.analytic.subproblems.sp2`): the pairs into ``pairs`` (2, 2); ``work`` (4, 3)
    and ``R`` (3, 3) scratch. Where a point lies on its own axis that angle is free
    (flag INFINITE): it takes ``v1`` (t1) or ``v2`` (t2), and ``free`` says which (1: t1,
    2: t2, 3: both, the axes parallel)."""
    n, base, c, x = work[0], work[1], work[2], work[3]
    _cross(k1, k2, n)
    s2 = sk.dot(n, n)
    if s2 < sk.ZERO * sk.ZERO:
        pairs[0, 0], pairs[0, 1] = v1, v2
        return 1, sk.INFINITE, 3
    on1, on2 = _off_axis(k1, p1) < sk.SINGULAR, _off_axis(k2, p2) < sk.SINGULAR
    if on1 or on2:  # a point on its own axis: that angle is free, the other is SP1
        if on2:
            t1, f1 = sk.sp1(p1, p2, k1)
            pairs[0, 0], pairs[0, 1] = t1, v2
            return 1, (sk.INFINITE if f1 != sk.LEAST_SQUARES else sk.LEAST_SQUARES), 2
        t2, f2 = sk.sp1(p2, p1, k2)
        pairs[0, 0], pairs[0, 1] = v1, t2
        return 1, (sk.INFINITE if f2 != sk.LEAST_SQUARES else sk.LEAST_SQUARES), 1
    a1, a2, g = sk.dot(k1, p1), sk.dot(k2, p2), sk.dot(k1, k2)
    det = 1.0 - g * g
    xa, ya = (a1 - g * a2) / det, (a2 - g * a1) / det
    for i in range(3):
        base[i] = xa * k1[i] + ya * k2[i]
    rest = 0.5 * (sk.dot(p1, p1) + sk.dot(p2, p2)) - sk.dot(base, base)  # z^2 |n|^2
    kind = sk.EXACT
    if abs(sk.dot(p1, p1) - sk.dot(p2, p2)) > 1e-9 or rest < -1e-12:
        kind = sk.LEAST_SQUARES
    z = math.sqrt(max(rest, 0.0) / s2)
    count = 2 if z > 1e-12 else 1
    for m in range(count):
        zz = z if m == 0 else -z
        for i in range(3):
            c[i] = base[i] + zz * n[i]
        t1, f1 = sk.sp1(p1, c, k1)
        sk.rotation(k1, t1, R)
        sk.mv(R, p1, x)  # onto the point p1 reached: consistent pairs
        t2, f2 = sk.sp1(p2, x, k2)
        if f1 == sk.INFINITE or f2 == sk.INFINITE:
            kind = sk.INFINITE
        pairs[m, 0], pairs[m, 1] = t1, t2
    return count, kind, 0


@inline_kernel
def _wrist(h, R03, R06, near, q1, q2, q3, root1, root3, out, roots, count, M, V, pref, free,
           free123):  # fmt: skip
    """The branches of a spherical wrist turning by R36 = R03^T R06 after joints 1-3 at
    (q1, q2, q3): q4, q5 by SP2 (where axis 6 points; q4 = ``pref[3]`` where axes 4 and 6
    line up), q6 by SP1; appended to ``out``, ``roots`` and ``free`` (joints 1-3's free
    bits ``free123`` and the wrist's) from row ``count``; returns the new count. M (6, 3,
    3), V (9, 3) scratch (the caller's; slots 2, 4 and 1, 2, 7, 8 are used here)."""
    R36, Rt = M[4], M[2]
    tmp, w, x, perp = V[1], V[2], V[7], V[8]
    sk.mtm(R03, R06, R36)
    sk.perp_unit(h[5], perp)
    sk.mv(R36, h[5], tmp)
    pairs, work = np.empty((2, 2)), np.empty((4, 3))
    n45, f45, which = sp2(tmp, h[5], h[3], h[4], pairs, work, Rt, -pref[3], pref[4])
    if not (sk.usable(f45, near) or f45 == sk.INFINITE):
        return count
    bits = free123
    if f45 == sk.INFINITE:
        bits |= (8 if which & 1 else 0) | (16 if which & 2 else 0)
    for j4 in range(n45):
        q4, q5 = -pairs[j4, 0], pairs[j4, 1]
        sk.mv(R36, perp, tmp)  # x' = R(h5, -q5) R(h4, -q4) R36 x
        sk.rotation(h[3], -q4, Rt)
        sk.mv(Rt, tmp, w)
        sk.rotation(h[4], -q5, Rt)
        sk.mv(Rt, w, x)
        q6, f6 = sk.sp1(perp, x, h[5])
        if not sk.usable(f6, near):
            continue
        out[count, 0], out[count, 1], out[count, 2] = q1, q2, q3
        out[count, 3], out[count, 4], out[count, 5] = q4, q5, q6
        roots[count, 0], roots[count, 1] = root1, root3
        roots[count, 2] = j4 if n45 == 2 else -1
        free[count] = bits
        count += 1
    return count


@kernel
def spherical_wrist(h, o, tip_R, tip_p, T, near, pref, out, roots, free):  # long: one peeling
    """Branches of the spherical-wrist family
    (:func:`toolkit.ik.analytic.families.spherical_wrist`)."""
    M = np.empty((6, 3, 3))  # slots 2, 4 and vectors 1, 2, 7, 8 are _wrist's scratch too
    V = np.empty((9, 3))
    E = np.empty((2, 4))  # the elbow's rows
    R06, R01, Rt, R03, Rw = M[0], M[1], M[2], M[3], M[5]
    v, tmp, w, u, p12, p23, p3W = V[0], V[1], V[2], V[3], V[4], V[5], V[6]
    sk.mmt(T, tip_R, R06)
    for i in range(3):
        tmp[i] = tip_p[i] - o[3, i]
    sk.mv(R06, tmp, w)
    for i in range(3):
        v[i] = T[i, 3] - w[i] - o[0, i]  # the wrist centre seen from o1
        p12[i], p23[i], p3W[i] = o[1, i] - o[0, i], o[2, i] - o[1, i], o[3, i] - o[2, i]
        tmp[i] = o[3, i] - o[0, i]
    n1, a1, b1, f1 = sk.sp4(h[1], v, h[0], sk.dot(h[1], tmp))  # every q1: W on axis 1
    n1, a1, b1, ok, free1 = sk.free_roots(n1, a1, b1, f1, near, -pref[0])
    if not ok:
        return 0
    count = 0
    for i1 in range(n1):
        q1 = sk.first_turn(h[0], a1, b1, i1, R01)
        sk.mtv(R01, v, u)
        for i in range(3):
            u[i] -= p12[i]
        k3, _ = sk.planar_elbows(u, p23, p3W, h[1], h[2], near, pref[1], E, Rt, w, tmp)
        for e in range(k3):
            q3, q2 = E[e, 0], E[e, 1]
            sk.rotation(h[2], q3, Rt)
            sk.rotation(h[1], q2, Rw)
            sk.mm(Rw, Rt, R03)
            sk.mm(R01, R03, Rw)
            root1, root3 = (i1 if n1 == 2 else -1), int(E[e, 3])
            bits = (1 if free1 else 0) | (2 if E[e, 2] else 0)
            count = _wrist(h, Rw, R06, near, q1, q2, q3, root1, root3, out, roots, count, M, V,
                           pref, free, bits)  # fmt: skip
    return count


@kernel
def meeting_shoulder(h, o, tip_R, tip_p, T, near, pref, out, roots, free):  # long: one peeling
    """Branches of a spherical wrist whose axes 1, 2 meet
    (:func:`toolkit.ik.analytic.families.meeting_shoulder`): q3 by SP3 (joints 1, 2 keep the
    distance from the shoulder point S = o1 to the wrist centre W = o4), q1, q2 by SP2, then the
    wrist."""
    M = np.empty((6, 3, 3))  # slots 2, 4 and vectors 1, 2, 7, 8 are _wrist's scratch too
    V = np.empty((9, 3))
    R06, R01, Rt, R03, Rw = M[0], M[1], M[2], M[3], M[5]
    y, tmp, w, a, b, x = V[0], V[1], V[2], V[3], V[4], V[5]
    sk.mmt(T, tip_R, R06)
    for i in range(3):
        tmp[i] = tip_p[i] - o[3, i]
    sk.mv(R06, tmp, w)
    for i in range(3):
        y[i] = T[i, 3] - w[i] - o[0, i]  # the wrist centre seen from S
        a[i], b[i] = o[3, i] - o[2, i], o[0, i] - o[2, i]
    ny = math.sqrt(sk.dot(y, y))
    n3, a3, b3, f3 = sk.sp4(b, a, h[2], 0.5 * (sk.dot(a, a) + sk.dot(b, b) - ny * ny))
    n3, a3, b3, ok, free3 = sk.free_roots(n3, a3, b3, f3, near, pref[2])
    if not ok:
        return 0
    pairs, work = np.empty((2, 2)), np.empty((4, 3))
    count = 0
    for i3 in range(n3):
        q3 = a3 if i3 == 0 else b3
        sk.rotation(h[2], q3, Rt)
        sk.mv(Rt, a, w)
        for i in range(3):
            x[i] = o[2, i] - o[0, i] + w[i]
        # R(h2, q2) x = R(h1, -q1) y; q1 free where W lies on axis 1, q2 where on axis 2
        n12, f12, which = sp2(x, y, h[1], h[0], pairs, work, R03, pref[1], -pref[0])
        if not (sk.usable(f12, near) or f12 == sk.INFINITE):
            continue
        bits = 4 if free3 else 0
        if f12 == sk.INFINITE:
            bits |= (2 if which & 1 else 0) | (1 if which & 2 else 0)
        for i1 in range(n12):
            q2, q1 = pairs[i1, 0], -pairs[i1, 1]
            sk.rotation(h[2], q3, Rt)  # again: _wrist uses Rt as scratch
            sk.rotation(h[1], q2, Rw)
            sk.mm(Rw, Rt, R03)
            sk.rotation(h[0], q1, R01)
            sk.mm(R01, R03, Rw)
            root1, root3 = (i1 if n12 == 2 else -1), (i3 if n3 == 2 else -1)
            count = _wrist(h, Rw, R06, near, q1, q2, q3, root1, root3, out, roots, count, M, V,
                           pref, free, bits)  # fmt: skip
    return count
