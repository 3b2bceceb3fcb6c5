"""The compiled subproblems (numba) the analytic families' kernels are built from
(:mod:`toolkit.ik.analytic.family_kernels`): Paden-Kahan's SP1 and SP4 (SP3 is SP4 of a squared
length), the roots a branch loop runs over, and the small 3-vector and 3x3 products, each
inlined into its caller. Their Python forms are :mod:`toolkit.ik.analytic.subproblems`."""

from __future__ import annotations

import math

from ...kinematics import inline_kernel, trig

__all__ = [
    "EXACT",
    "INFINITE",
    "LEAST_SQUARES",
    "SINGULAR",
    "SPLIT",
    "TANGENT",
    "TOL",
    "ZERO",
    "dot",
    "elbow_q2",
    "elbow_roots",
    "first_turn",
    "free_angle",
    "free_roots",
    "mm",
    "mmt",
    "mtm",
    "mtv",
    "mv",
    "perp_unit",
    "rotation",
    "sp1",
    "sp1_xy",
    "sp4",
    "turn_vector",
    "usable",
    "usable_roots",
]

EXACT, LEAST_SQUARES, INFINITE = 0, 1, 2
SPLIT = 0.1
TOL = 1e-9
ZERO = 1e-12
TANGENT = 1e-14
"""SP3 and SP4 have one root where the cosine of the half gap between their two is within
this of 1: a tangent, up to the rounding of the cosine (which alone would split one root
into two ~1e-8 rad apart; two roots closer than ~1.4e-7 rad are one to 1e-14)."""
SINGULAR = 1e-9
"""A subproblem whose every angle solves to within this (a vector this close to the axis,
a coefficient this small: a singular pose, up to rounding) answers INFINITE: the family
kernels then give a representative with the free joint at its preferred angle, which the
verification checks (and the door polishes where rounding leaves it above ``tol``)."""


@inline_kernel
def rotation(k, t, R):
    """R = R(k, t) (Rodrigues)."""
    s, c = trig.sincos(t)
    v = 1.0 - c
    x, y, z = k[0], k[1], k[2]
    R[0, 0], R[0, 1], R[0, 2] = c + v * x * x, v * x * y - s * z, v * x * z + s * y
    R[1, 0], R[1, 1], R[1, 2] = v * x * y + s * z, c + v * y * y, v * y * z - s * x
    R[2, 0], R[2, 1], R[2, 2] = v * x * z - s * y, v * y * z + s * x, c + v * z * z


@inline_kernel
def first_turn(k, a, b, i, R):
    """Joint 1's angle at root i of the SP4 that solves it (its first or second angle,
    negated: the subproblem turns the target back to the joint), its rotation about k
    into R."""
    t = -(a if i == 0 else b)
    rotation(k, t, R)
    return t


@inline_kernel
def mv(R, p, out):
    for i in range(3):
        out[i] = R[i, 0] * p[0] + R[i, 1] * p[1] + R[i, 2] * p[2]


@inline_kernel
def mtv(R, p, out):
    """out = R^T p."""
    for i in range(3):
        out[i] = R[0, i] * p[0] + R[1, i] * p[1] + R[2, i] * p[2]


@inline_kernel
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@inline_kernel
def sp1_xy(p1, p2, k):
    """(y, x, flag) of SP1 (R(k, theta) p1 = p2, theta = atan2(y, x); see
    toolkit.ik.analytic.subproblems.sp1): the angle's sine and cosine times |a| |b| (a, b the
    parts of p1, p2 across k), (0, 1) where the angle is 0 by convention."""
    d1, d2 = dot(k, p1), dot(k, p2)
    a0, a1, a2 = p1[0] - k[0] * d1, p1[1] - k[1] * d1, p1[2] - k[2] * d1
    b0, b1, b2 = p2[0] - k[0] * d2, p2[1] - k[1] * d2, p2[2] - k[2] * d2
    na = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    nb = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
    same = abs(d1 - d2) < TOL
    if na < SINGULAR and nb < SINGULAR and same:  # both on the axis: every angle solves
        return 0.0, 1.0, INFINITE
    if na < ZERO or nb < ZERO:
        return 0.0, 1.0, LEAST_SQUARES
    cx, cy, cz = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    y, x = k[0] * cx + k[1] * cy + k[2] * cz, a0 * b0 + a1 * b1 + a2 * b2
    return y, x, (EXACT if abs(na - nb) < TOL and same else LEAST_SQUARES)


@inline_kernel
def sp1(p1, p2, k):
    """(theta, flag) of SP1: R(k, theta) p1 = p2 (see toolkit.ik.analytic.subproblems.sp1)."""
    y, x, flag = sp1_xy(p1, p2, k)
    return math.atan2(y, x), flag


@inline_kernel
def turn_vector(k, y, x, v, out):
    """out = R(k, atan2(y, x)) v (Rodrigues, from the angle's (y, x) without the angle:
    no atan2, cos or sin); ``out`` not ``v``."""
    r = math.sqrt(x * x + y * y)
    c, s = (x / r, y / r) if r > 0.0 else (1.0, 0.0)
    kv = (k[0] * v[0] + k[1] * v[1] + k[2] * v[2]) * (1.0 - c)
    out[0] = c * v[0] + s * (k[1] * v[2] - k[2] * v[1]) + k[0] * kv
    out[1] = c * v[1] + s * (k[2] * v[0] - k[0] * v[2]) + k[1] * kv
    out[2] = c * v[2] + s * (k[0] * v[1] - k[1] * v[0]) + k[2] * kv


@inline_kernel
def sp4(h, p, k, d):
    """(count, theta_a, theta_b, flag) of SP4: h^T R(k, theta) p = d."""
    kp, hk = dot(k, p), dot(h, k)
    A = dot(h, p) - hk * kp
    cx = k[1] * p[2] - k[2] * p[1]
    cy = k[2] * p[0] - k[0] * p[2]
    cz = k[0] * p[1] - k[1] * p[0]
    B = h[0] * cx + h[1] * cy + h[2] * cz
    c = d - hk * kp
    r = math.hypot(A, B)
    if r < SINGULAR and abs(c) < TOL:  # every angle solves (to rounding)
        return 1, 0.0, 0.0, INFINITE
    if r < ZERO:
        return 1, 0.0, 0.0, LEAST_SQUARES
    phi = math.atan2(B, A)
    ratio = c / r
    scale = math.sqrt(dot(h, h) * dot(p, p))
    if abs(c) - r > 1e-12 * max(1.0, scale):  # beyond reach by more than rounding
        t = phi if ratio > 0 else phi + math.pi
        return 1, t, t, LEAST_SQUARES
    delta = math.acos(max(-1.0, min(1.0, ratio)))
    if 1.0 - abs(ratio) < TANGENT:  # a tangent within rounding: one angle
        t = phi if ratio > 0 else phi + math.pi
        return 1, t, t, EXACT
    return 2, phi + delta, phi - delta, EXACT


@inline_kernel
def usable_roots(n, a, b, flag, near):
    """The roots a branch loop runs over: (count, first, second, usable)."""
    if flag == EXACT:
        return n, a, b, True
    if flag == LEAST_SQUARES and near:
        if n == 1:
            return 2, a + SPLIT, a - SPLIT, True
        return n, a, b, True
    return 0, a, b, False


@inline_kernel
def free_roots(n, a, b, flag, near, value):
    """:func:`usable_roots`, where an INFINITE answer (every angle solves: a singular
    pose) is one root at ``value`` (the free joint's preferred angle): (count, first,
    second, usable, free)."""
    if flag == INFINITE:
        return 1, value, value, True, True
    n, a, b, ok = usable_roots(n, a, b, flag, near)
    return n, a, b, ok, False


@inline_kernel
def free_angle(t, flag, near, value):
    """(angle, usable, free) of an SP1 answer: an INFINITE one (every angle solves) is
    ``value``, the free joint's preferred angle."""
    if flag == INFINITE:
        return value, True, True
    return t, usable(flag, near), False


@inline_kernel
def perp_unit(h, out):
    """A unit vector perpendicular to h into out."""
    x0, x1, x2 = 0.0, h[2], -h[1]  # h x e_x
    if x1 * x1 + x2 * x2 < 0.25:
        x0, x1, x2 = -h[2], 0.0, h[0]  # h x e_y
    n = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    out[0], out[1], out[2] = x0 / n, x1 / n, x2 / n


@inline_kernel
def mm(A, B, out):
    """out = A B (3 x 3)."""
    for i in range(3):
        for m in range(3):
            out[i, m] = A[i, 0] * B[0, m] + A[i, 1] * B[1, m] + A[i, 2] * B[2, m]


@inline_kernel
def mtm(A, B, out):
    """out = A^T B (3 x 3)."""
    for i in range(3):
        for m in range(3):
            out[i, m] = A[0, i] * B[0, m] + A[1, i] * B[1, m] + A[2, i] * B[2, m]


@inline_kernel
def mmt(A, B, out):
    """out = A B^T over the 3x3 blocks (a target's rotation times the tool's at zero,
    transposed: A may be the 4x4 target)."""
    for i in range(3):
        for m in range(3):
            out[i, m] = A[i, 0] * B[m, 0] + A[i, 1] * B[m, 1] + A[i, 2] * B[m, 2]


@inline_kernel
def usable(flag, near):
    """Whether a branch may rest on a subproblem answer of this flag: exact, or least
    squares for an arm only near its family."""
    return flag == EXACT or (near and flag == LEAST_SQUARES)


@inline_kernel
def elbow_roots(d, p23, p3x, k, near, tmp):
    """The roots (count, first, second, usable) of q3 with ||p23 + R(k, q3) p3x|| = ||d||
    (SP3, as SP4 of the squared length); ``tmp`` 3-vector scratch."""
    for i in range(3):
        tmp[i] = -p23[i]
    nd = math.sqrt(dot(d, d))
    n, a, b, flag = sp4(tmp, p3x, k, 0.5 * (dot(p3x, p3x) + dot(tmp, tmp) - nd * nd))
    return usable_roots(n, a, b, flag, near)


@inline_kernel
def elbow_q2(q3, d, p23, p3x, h2, h3, near, R, w, value):
    """(q2, usable, free) with R(h2, q2) (p23 + R(h3, q3) p3x) = d by SP1 (q2 = ``value``
    where the point lies on axis 2: every q2 solves); leaves R(h3, q3) in ``R``; ``w``
    3-vector scratch."""
    rotation(h3, q3, R)
    mv(R, p3x, w)
    for i in range(3):
        w[i] += p23[i]
    q2, flag = sp1(w, d, h2)
    return free_angle(q2, flag, near, value)


@inline_kernel
def planar_elbows(d, p23, p3x, h2, h3, near, value, E, R, w, tmp):
    """The elbow R(h2, q2) (p23 + R(h3, q3) p3x) = d: q3 by SP3 (:func:`elbow_roots`), then
    q2 by SP1 (:func:`elbow_q2`; ``value`` where every q2 solves), into the rows of E (2, 4):
    q3, q2, 1.0 where q2 is free (else 0.0), q3's root (0, 1; -1 where SP3 had one). Returns
    (rows, SP3's roots: 0 where it has no usable answer); ``R``, ``w``, ``tmp`` 3x3 and
    3-vector scratch."""
    n3, a3, b3, ok3 = elbow_roots(d, p23, p3x, h3, near, tmp)
    if not ok3:
        return 0, 0
    k = 0
    for i3 in range(n3):
        q3 = a3 if i3 == 0 else b3
        q2, ok2, free2 = elbow_q2(q3, d, p23, p3x, h2, h3, near, R, w, value)
        if ok2:
            E[k, 0], E[k, 1], E[k, 2] = q3, q2, 1.0 if free2 else 0.0
            E[k, 3] = i3 if n3 == 2 else -1
            k += 1
    return k, n3
