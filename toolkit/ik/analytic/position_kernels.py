"""The families of 3-joint chains placing a point, compiled (numba): the industrial
positioning structures (:mod:`toolkit.ik.analytic.prismatic`: PPP, RPP, RRP with axes 1, 2
meeting or parallel) and the 3R chains with axes 1, 2 meeting, axes 2, 3 parallel or axes in
general position (by SP5, :mod:`toolkit.ik.analytic.sp5_kernels`;
:mod:`toolkit.ik.analytic.families`). The same subproblems and the same peeling as the
Python forms, step for step; ``tests/ik/test_position_kernels.py`` holds both equal.

Parameters as in :mod:`toolkit.ik.analytic.family_kernels`: the target is the position
``T[:3, 3]`` (its rotation is not read), ``pref`` (3,) the angles of joints left free at a
singular point (the point on an axis: every angle of that joint reaches it), out-parameters
``out`` (8, 3), ``roots`` (8, 3) and ``free`` (8,). The roots each family names
(:meth:`toolkit.ik.analytic.family.Family.label`): RPP its side; RRP meeting its
extension, then its shoulder; RRP parallel its elbow; the 3R families their shoulder, then
their elbow (the general 3R: its SP5 root, 0-3). Where the Python form keeps a
least-squares answer of an arm only near its family as it is, so does its kernel (only the
3R with axes 2, 3 parallel splits one into two starts, as the 6R families do).
"""

from __future__ import annotations

import math

import numpy as np

from ...kinematics import inline_kernel, kernel
from .sp5_kernels import sp5
from .subproblem_kernels import (
    EXACT,
    INFINITE,
    LEAST_SQUARES,
    dot,
    first_turn,
    free_angle,
    free_roots,
    mtv,
    mv,
    planar_elbows,
    rotation,
    sp1,
    sp4,
)
from .wrist_kernels import sp2

__all__ = [
    "ppp",
    "rpp",
    "rrp_meeting",
    "rrp_parallel",
    "three_r_general",
    "three_r_meeting",
    "three_r_parallel",
]


@inline_kernel
def _quadratic(a, b, c):
    """(count, first, second) real roots of a x^2 + 2 b x + c = 0 (a > 0), as
    :func:`toolkit.ik.analytic.prismatic._quadratic`: one at a tangent, none beyond."""
    disc = b * b - a * c
    scale = max(b * b, abs(a * c), 1e-30)
    if disc < -1e-12 * scale:
        return 0, 0.0, 0.0
    if disc <= 1e-12 * scale:
        return 1, -b / a, -b / a
    r = math.sqrt(disc)
    return 2, (-b + r) / a, (-b - r) / a


@inline_kernel
def _plain_roots(n, a, b, flag, near, value):
    """A subproblem's roots as the position families take them: exact, least squares where
    the arm is only near its family (kept as they are), every angle (INFINITE: one root at
    ``value``, the joint free): (count, first, second, usable, free)."""
    if flag == INFINITE:
        return 1, value, value, True, True
    if flag == EXACT or (near and flag == LEAST_SQUARES):
        return n, a, b, True, False
    return 0, a, b, False, False


@inline_kernel
def _root(i, n):
    """A branch's root as its label reads it: -1 where the subproblem had one."""
    return i if n == 2 else -1


@inline_kernel
def _put(out, roots, free, count, q1, q2, q3, r0, r1, bits):
    out[count, 0], out[count, 1], out[count, 2] = q1, q2, q3
    roots[count, 0], roots[count, 1], roots[count, 2] = r0, r1, -1
    free[count] = bits
    return count + 1


@inline_kernel
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@kernel
def ppp(h, o, tip_R, tip_p, T, near, pref, out, roots, free):
    """The one branch of three slides: ``p = p0 + q1 h1 + q2 h2 + q3 h3`` by Cramer's rule."""
    d = np.empty(3)
    for i in range(3):
        d[i] = T[i, 3] - tip_p[i]
    c12 = np.empty(3)
    c23, c31 = np.empty(3), np.empty(3)
    _cross(h[1], h[2], c23)
    _cross(h[2], h[0], c31)
    _cross(h[0], h[1], c12)
    det = dot(h[0], c23)
    return _put(out, roots, free, 0, dot(d, c23) / det, dot(d, c31) / det, dot(d, c12) / det,
                -1, -1, 0)  # fmt: skip


@kernel
def rpp(h, o, tip_R, tip_p, T, near, pref, out, roots, free):
    """A turn and two slides: the slide that moves the height along h1 most follows from
    the height, the other from the distance to o1 (a quadratic), then q1 by SP1."""
    V = np.empty((5, 3))
    c, u, w0, d, x = V[0], V[1], V[2], V[3], V[4]
    for i in range(3):
        c[i], u[i] = tip_p[i] - o[0, i], T[i, 3] - o[0, i]
    a1, a2 = dot(h[0], h[1]), dot(h[0], h[2])
    first = 0 if abs(a1) >= abs(a2) else 1  # slide 2 or 3 solved from the height
    af, ao = (a1, a2) if first == 0 else (a2, a1)
    hf, ho = h[1 + first], h[2 - first]
    height = dot(h[0], u) - dot(h[0], c)
    for i in range(3):
        w0[i] = c[i] + hf[i] * height / af
        d[i] = ho[i] - hf[i] * ao / af
    n, ra, rb = _quadratic(dot(d, d), dot(w0, d), dot(w0, w0) - dot(u, u))
    count = 0
    for k in range(n):
        s = ra if k == 0 else rb
        sf = (height - ao * s) / af
        for i in range(3):
            x[i] = c[i] + sf * hf[i] + s * ho[i]
        t1, f1 = sp1(x, u, h[0])
        q1, ok, free1 = free_angle(t1, f1, near, pref[0])
        if ok:
            q2, q3 = (sf, s) if first == 0 else (s, sf)
            count = _put(out, roots, free, count, q1, q2, q3, _root(k, n), -1,
                         1 if free1 else 0)  # fmt: skip
    return count


@kernel
def rrp_meeting(h, o, tip_R, tip_p, T, near, pref, out, roots, free):
    """Two turns about axes meeting at S = o1 and a slide: ``|p - S| = |p0 - S + q3 h3|``
    gives q3 (a quadratic), then (q1, q2) by SP2."""
    V = np.empty((7, 3))
    c, y, x = V[0], V[1], V[2]
    work, pairs, R = V[3:7], np.empty((2, 2)), np.empty((3, 3))
    for i in range(3):
        c[i], y[i] = tip_p[i] - o[0, i], T[i, 3] - o[0, i]
    n3, ra, rb = _quadratic(1.0, dot(c, h[2]), dot(c, c) - dot(y, y))
    count = 0
    for k in range(n3):
        q3 = ra if k == 0 else rb
        for i in range(3):
            x[i] = c[i] + q3 * h[2, i]
        m, flag, bits = sp2(x, y, h[1], h[0], pairs, work, R, pref[1], -pref[0])
        if not (flag == EXACT or flag == INFINITE or (near and flag == LEAST_SQUARES)):
            continue
        for i in range(m):  # R(h2, q2) x = R(h1, -q1) y
            free_bits = (2 if bits & 1 else 0) | (1 if bits & 2 else 0)
            count = _put(out, roots, free, count, -pairs[i, 1], pairs[i, 0], q3, _root(k, n3),
                         _root(i, m), free_bits)  # fmt: skip
    return count


@kernel
def rrp_parallel(h, o, tip_R, tip_p, T, near, pref, out, roots, free):
    """Two turns about parallel axes and a slide (SCARA): the height along h1 gives q3
    (linear), then q2 by SP3 and q1 by SP1 in the plane."""
    V = np.empty((6, 3))
    u, p12, x, m12, w, t = V[0], V[1], V[2], V[3], V[4], V[5]
    R = np.empty((3, 3))
    for i in range(3):
        u[i], p12[i] = T[i, 3] - o[0, i], o[1, i] - o[0, i]
        t[i] = T[i, 3] - tip_p[i]
    q3 = dot(h[0], t) / dot(h[0], h[2])
    for i in range(3):
        x[i] = tip_p[i] - o[1, i] + q3 * h[2, i]
        m12[i] = -p12[i]
    nu = math.sqrt(dot(u, u))
    n2, a2, b2, f2 = sp4(m12, x, h[1], 0.5 * (dot(x, x) + dot(m12, m12) - nu * nu))  # SP3
    n2, a2, b2, ok, free2 = _plain_roots(n2, a2, b2, f2, near, pref[1])
    count = 0
    if not ok:
        return 0
    for k in range(n2):
        q2 = a2 if k == 0 else b2
        rotation(h[1], q2, R)
        mv(R, x, w)
        for i in range(3):
            w[i] += p12[i]
        t1, f1 = sp1(w, u, h[0])
        q1, ok1, free1 = free_angle(t1, f1, near, pref[0])
        if ok1:
            bits = (1 if free1 else 0) | (2 if free2 else 0)
            count = _put(out, roots, free, count, q1, q2, q3, _root(k, n2), -1, bits)
    return count


@kernel
def three_r_meeting(h, o, tip_R, tip_p, T, near, pref, out, roots, free):
    """A 3R chain whose axes 1, 2 meet at S = o1: q3 by SP3 (the distance from S to the
    point), then q1, q2 by SP2."""
    V = np.empty((9, 3))
    y, a, b, x = V[0], V[1], V[2], V[3]
    work, pairs, R = V[4:8], np.empty((2, 2)), np.empty((3, 3))
    for i in range(3):
        y[i] = T[i, 3] - o[0, i]
        a[i], b[i] = tip_p[i] - o[2, i], o[0, i] - o[2, i]  # SP3: |R(h3, q3) a - b| = |y|
    ny = math.sqrt(dot(y, y))
    n3, a3, b3, f3 = sp4(b, a, h[2], 0.5 * (dot(a, a) + dot(b, b) - ny * ny))
    n3, a3, b3, ok, free3 = _plain_roots(n3, a3, b3, f3, near, pref[2])
    count = 0
    if not ok:
        return 0
    for k in range(n3):
        q3 = a3 if k == 0 else b3
        rotation(h[2], q3, R)
        mv(R, a, x)
        for i in range(3):
            x[i] -= b[i]
        m, flag, bits = sp2(x, y, h[1], h[0], pairs, work, R, pref[1], -pref[0])
        if not (flag == EXACT or flag == INFINITE or (near and flag == LEAST_SQUARES)):
            continue
        for i in range(m):
            free_bits = (2 if bits & 1 else 0) | (1 if bits & 2 else 0) | (4 if free3 else 0)
            count = _put(out, roots, free, count, -pairs[i, 1], pairs[i, 0], q3, _root(i, m),
                         _root(k, n3), free_bits)  # fmt: skip
    return count


@kernel
def three_r_parallel(h, o, tip_R, tip_p, T, near, pref, out, roots, free):
    """A 3R chain whose axes 2, 3 are parallel: q1 by SP4 (the component along axis 2),
    then q3 by SP3 and q2 by SP1 in the plane of axes 2, 3."""
    V = np.empty((7, 3))
    v, t, d, p12, p23, p3x, w = V[0], V[1], V[2], V[3], V[4], V[5], V[6]
    R01, Rt, E = np.empty((3, 3)), np.empty((3, 3)), np.empty((2, 4))
    for i in range(3):
        v[i], t[i] = T[i, 3] - o[0, i], tip_p[i] - o[0, i]
        p12[i], p23[i], p3x[i] = o[1, i] - o[0, i], o[2, i] - o[1, i], tip_p[i] - o[2, i]
    n1, a1, b1, f1 = sp4(h[1], v, h[0], dot(h[1], t))
    n1, a1, b1, ok, free1 = free_roots(n1, a1, b1, f1, near, -pref[0])
    count = 0
    if not ok:
        return 0
    for i1 in range(n1):
        q1 = first_turn(h[0], a1, b1, i1, R01)
        mtv(R01, v, d)
        for i in range(3):
            d[i] -= p12[i]
        k3, _ = planar_elbows(d, p23, p3x, h[1], h[2], near, pref[1], E, Rt, w, w)
        for e in range(k3):
            bits = (1 if free1 else 0) | (2 if E[e, 2] else 0)
            count = _put(out, roots, free, count, q1, E[e, 1], E[e, 0], _root(i1, n1),
                         int(E[e, 3]), bits)  # fmt: skip
    return count


@kernel
def three_r_general(h, o, tip_R, tip_p, T, near, pref, out, roots, free):
    """A 3R chain with axes in general position, by SP5 (up to 4 roots, each its own
    branch): ``R(h1, -q1) (p - o1) - (o2 - o1) = R(h2, q2) ((o3 - o2) + R(h3, q3) (p0 -
    o3))``."""
    V = np.empty((4, 3))
    p0, p1, p2, p3 = V[0], V[1], V[2], V[3]
    for i in range(3):
        p0[i], p1[i] = o[0, i] - o[1, i], T[i, 3] - o[0, i]
        p2[i], p3[i] = o[2, i] - o[1, i], tip_p[i] - o[2, i]
    found = np.empty((4, 3))
    n, flag = sp5(p0, p1, p2, p3, h[0], h[1], h[2], found)
    if not (flag == EXACT or (near and flag == LEAST_SQUARES)):
        return 0
    for i in range(n):
        out[i, 0], out[i, 1], out[i, 2] = -found[i, 0], found[i, 1], found[i, 2]
        roots[i, 0], roots[i, 1], roots[i, 2] = i, -1, -1
        free[i] = 0
    return n
