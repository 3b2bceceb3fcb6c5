"""The 6R family with axes 1, 2, 3 parallel (:mod:`toolkit.ik.analytic.outer`), compiled: the
same steps on small arrays (SP6 for q4, q6 by :func:`~toolkit.ik.analytic.sp5_kernels.circle_pair`,
SP1 for q5 and for the angle of joints 1-3 together, the planar elbow of joints 1, 2).
The kernel's signature is the other families' (:mod:`toolkit.ik.analytic.family_kernels`);
``tests/ik/test_outer_family.py`` holds it equal to the Python form."""

from __future__ import annotations

import math

import numpy as np

from ...kinematics import kernel
from . import subproblem_kernels as sk
from .sp5_kernels import circle_pair, trig_row

__all__ = ["outer_parallel"]


@kernel
def _sp6(a, g, h, p45, p56, d1, pairs):
    """(count, flag) of the SP6 of q4 and -q6 (module doc of
    :mod:`toolkit.ik.analytic.outer`) into ``pairs`` (4, 2)."""
    A1, A2, d, r, m = np.empty((2, 2)), np.empty((2, 2)), np.empty(2), np.empty(2), np.empty(3)
    c1 = trig_row(a, h[3], p45, r)
    A1[0, 0], A1[0, 1] = r[0], r[1]
    c2 = trig_row(g, h[5], p56, r)
    A2[0, 0], A2[0, 1] = r[0], r[1]
    c3 = trig_row(a, h[3], h[4], r)
    A1[1, 0], A1[1, 1] = r[0], r[1]
    for i in range(3):
        m[i] = -g[i]
    c4 = trig_row(m, h[5], h[4], r)
    A2[1, 0], A2[1, 1] = r[0], r[1]
    d[0], d[1] = d1 - c1 - c2, -c3 - c4
    size = max(1.0, np.abs(A1).max(), abs(d[0]), abs(d[1]))
    if np.abs(A2).max() <= 1e-9 * size:  # axis 6 along axis 1 (g || h6): q6 is free
        return _q4_alone(A1, d, size, pairs), sk.INFINITE
    return circle_pair(A1, A2, d, pairs)


@kernel
def _q4_alone(A1, d, size, pairs):
    """Where q6 drops out of the SP6 (axis 6 along axis 1: every q6, with joints 1-3
    turning back, holds the pose), every q4 with A1 u(q4) = d into ``pairs[:, 0]``: the
    larger row's roots that the other row keeps (to 1e-8 of ``size``); their count."""
    k = 0 if A1[0, 0] ** 2 + A1[0, 1] ** 2 >= A1[1, 0] ** 2 + A1[1, 1] ** 2 else 1
    r = math.hypot(A1[k, 0], A1[k, 1])
    if r <= 1e-12 * size or abs(d[k]) > r * (1.0 + 1e-9):
        return 0
    phi, delta = math.atan2(A1[k, 1], A1[k, 0]), math.acos(max(-1.0, min(1.0, d[k] / r)))
    count = 0
    for t in (phi + delta, phi - delta):
        miss = A1[1 - k, 0] * math.cos(t) + A1[1 - k, 1] * math.sin(t) - d[1 - k]
        if abs(miss) <= 1e-8 * size and (count == 0 or abs(t - pairs[0, 0]) > 1e-12):
            pairs[count, 0], pairs[count, 1] = t, 0.0
            count += 1
    return count


@kernel
def outer_parallel(h, o, tip_R, tip_p, T, near, pref, out, roots, free):  # long: one peeling
    """Branches of the family (:func:`toolkit.ik.analytic.outer.outer_parallel`) into ``out``
    (8, 6): roots (the wrist's SP6 pair, the elbow, -1), free bits (joint 1 where the
    elbow's point lies on axis 1, joint 5 where R4^T h1 lies on axis 5, joint 6 where axis
    6 lies along axis 1, as at the home pose of an arm built so: their angles in ``pref``);
    the count."""
    M = np.empty((6, 3, 3))
    V = np.empty((13, 3))
    E = np.empty((2, 4))  # the elbow's rows
    R06, R4, R5, R6, Rt, Rq = M[0], M[1], M[2], M[3], M[4], M[5]
    v, g, x, y, w, tmp, s = V[0], V[1], V[2], V[3], V[4], V[5], V[6]
    p12, p23, p34, p45, p56, z = V[7], V[8], V[9], V[10], V[11], V[12]
    a = h[0]
    sk.mmt(T, tip_R, R06)
    for i in range(3):
        tmp[i] = tip_p[i] - o[5, i]
    sk.mv(R06, tmp, x)
    for i in range(3):
        v[i] = T[i, 3] - o[0, i] - x[i]
        p12[i], p23[i], p34[i] = o[1, i] - o[0, i], o[2, i] - o[1, i], o[3, i] - o[2, i]
        p45[i], p56[i] = o[4, i] - o[3, i], o[5, i] - o[4, i]
        tmp[i] = p12[i] + p23[i] + p34[i]
    s2 = 1.0 if sk.dot(h[1], a) > 0 else -1.0
    s3 = 1.0 if sk.dot(h[2], a) > 0 else -1.0
    sk.mtv(R06, a, g)  # g = R06^T h1
    pairs = np.empty((4, 2))
    n46, kind = _sp6(a, g, h, p45, p56, sk.dot(a, v) - sk.dot(a, tmp), pairs)
    free6 = kind == sk.INFINITE  # q6 at its angle in pref (a representative)
    if not (free6 or sk.usable(kind, near)):
        return 0
    count = 0
    for i in range(n46):
        q4, q6 = pairs[i, 0], (pref[5] if free6 else -pairs[i, 1])
        sk.rotation(h[3], q4, R4)
        sk.rotation(h[5], q6, R6)
        sk.mtv(R4, a, x)  # R(h5, -q5) R4^T h1 = R6 g
        sk.mv(R6, g, y)
        t5, f5 = sk.sp1(x, y, h[4])
        t5, ok5, free5 = sk.free_angle(t5, f5, near, -pref[4])
        if not ok5:
            continue
        q5 = -t5
        sk.rotation(h[4], q5, R5)
        sk.mm(R4, R5, Rt)
        sk.mv(Rt, p56, tmp)  # p34 + R4 p45 + R4 R5 p56, before R(h1, theta)
        sk.mv(R4, p45, s)
        for k in range(3):
            z[k] = p34[k] + s[k] + tmp[k]
        sk.mm(Rt, R6, Rq)
        sk.mmt(R06, Rq, Rt)  # R(h1, theta) = R06 (R4 R5 R6)^T
        sk.perp_unit(a, x)
        sk.mv(Rt, x, y)
        theta, _ = sk.sp1(x, y, a)
        sk.mv(Rt, z, tmp)
        for k in range(3):
            w[k] = v[k] - tmp[k]
        k2, _ = sk.planar_elbows(w, p12, p23, h[0], h[1], near, pref[0], E, Rq, s, tmp)
        for e in range(k2):  # the elbow of joints 1, 2: q2 (E's first), then q1
            q2, q1 = E[e, 0], E[e, 1]
            out[count, 0], out[count, 1], out[count, 2] = q1, q2, s3 * (theta - q1 - s2 * q2)
            out[count, 3], out[count, 4], out[count, 5] = q4, q5, q6
            roots[count, 0], roots[count, 1], roots[count, 2] = i if n46 > 1 else -1, E[e, 3], -1
            free[count] = (1 if E[e, 2] else 0) | (16 if free5 else 0) | (32 if free6 else 0)
            count += 1
    return count
