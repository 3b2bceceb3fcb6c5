"""Subproblem 5 compiled (numba): three rotations closing a loop, ``p0 + R(k1, t1) p1 =
R(k2, t2) (p2 + R(k3, t3) p3)``, through the pair of circle equations ``A1 u(t1) + A2 u(t2)
= d`` (u(t) = (cos t, sin t)). The same steps and thresholds as the Python forms
(:func:`toolkit.ik.analytic.subproblems.sp5`, :func:`~toolkit.ik.analytic.subproblems.circle_pair`):
the better-conditioned matrix's angle follows from the other's, which must put it on the
unit circle (a quartic solved on the unit circle: numpy's companion matrix, then Newton);
a matrix of rank 1 is solved one equation at a time. Each returns its count and flag
(:data:`~toolkit.ik.analytic.subproblem_kernels.EXACT`, ``LEAST_SQUARES``, ``INFINITE``)
and writes its answers into an array it is given."""

from __future__ import annotations

import math

import numpy as np

from ...kinematics import inline_kernel, kernel
from .subproblem_kernels import EXACT, INFINITE, LEAST_SQUARES, TANGENT, dot, rotation, sp1

__all__ = ["circle_pair", "sp5", "trig_row"]

TWO_PI = 2.0 * math.pi


@inline_kernel
def _det(A):
    return A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]


@inline_kernel
def _flat(A):
    """0 for a 2x2 matrix of rank 1, 1 for a rotation."""
    return abs(_det(A)) / max(A[0, 0] ** 2 + A[0, 1] ** 2 + A[1, 0] ** 2 + A[1, 1] ** 2, 1e-300)


@inline_kernel
def _wrap(t):
    """t in [-pi, pi] (as ``math.remainder(t, 2 pi)``, ties aside)."""
    return t - TWO_PI * round(t / TWO_PI)


@kernel
def _one_equation(r0, r1, c, tiny, out):
    """Every t with (r0, r1) . u(t) = c into ``out`` (2,): (count, flag); the closest
    beyond reach, INFINITE when (r0, r1) = 0 and c = 0."""
    size = math.hypot(r0, r1)
    if size < tiny:
        out[0] = 0.0
        return 1, (INFINITE if abs(c) < tiny else LEAST_SQUARES)
    phi, ratio = math.atan2(r1, r0), c / size
    if abs(ratio) > 1.0 + 1e-9:
        out[0] = phi if ratio > 0 else phi + math.pi
        return 1, LEAST_SQUARES
    if 1.0 - abs(ratio) < TANGENT:  # a tangent within rounding: one angle (as SP4)
        out[0] = phi if ratio > 0 else phi + math.pi
        return 1, EXACT
    delta = math.acos(max(-1.0, min(1.0, ratio)))
    out[0], out[1] = phi + delta, phi - delta
    return 2, EXACT


@kernel
def _singular_pair(A1, A2, d, tiny, pairs):
    """:func:`circle_pair` when A1 has rank 1 or less: the combination of the rows free of
    t1 gives t2, then the other row t1 (pairs (4, 2): (t1, t2))."""
    U = np.linalg.svd(A1)[0]
    w0, w1, v0, v1 = U[0, 1], U[1, 1], U[0, 0], U[1, 0]  # w^T A1 = 0
    t2s, t1s, closest = np.empty(2), np.empty(2), np.empty((4, 2))
    n2, kind = _one_equation(w0 * A2[0, 0] + w1 * A2[1, 0], w0 * A2[0, 1] + w1 * A2[1, 1],
                             w0 * d[0] + w1 * d[1], tiny, t2s)  # fmt: skip
    r10, r11 = v0 * A1[0, 0] + v1 * A1[1, 0], v0 * A1[0, 1] + v1 * A1[1, 1]
    r20, r21 = v0 * A2[0, 0] + v1 * A2[1, 0], v0 * A2[0, 1] + v1 * A2[1, 1]
    c = v0 * d[0] + v1 * d[1]
    if kind == INFINITE:  # one equation left in both angles: a family, if it is reachable
        pairs[0, 0], pairs[0, 1] = 0.0, 0.0
        reach = math.hypot(r10, r11) + math.hypot(r20, r21)
        return 1, (INFINITE if abs(c) <= reach + tiny else LEAST_SQUARES)
    exact = near = 0
    for i in range(n2):
        t2 = t2s[i]
        rest = c - r20 * math.cos(t2) - r21 * math.sin(t2)
        n1, k1 = _one_equation(r10, r11, rest, tiny, t1s)
        if k1 == INFINITE:
            pairs[0, 0], pairs[0, 1] = 0.0, t2
            return 1, INFINITE
        for j in range(n1):
            if k1 == EXACT and kind == EXACT:
                pairs[exact, 0], pairs[exact, 1] = t1s[j], t2
                exact += 1
            else:
                closest[near, 0], closest[near, 1] = t1s[j], t2
                near += 1
    if exact:
        return exact, EXACT
    pairs[:near] = closest[:near]
    return near, LEAST_SQUARES


@kernel
def _quartic_pairs(X1, X2, d, pairs):  # long: the quartic on the unit circle
    """:func:`circle_pair` where X2 is the better-conditioned matrix: pairs (t1, t2) with
    X1 u(t1) + X2 u(t2) = d, t1 from the quartic, t2 following."""
    det = _det(X2)
    a00, a01, a10, a11 = X2[1, 1], -X2[0, 1], -X2[1, 0], X2[0, 0]  # adj(X2)
    N = np.empty((2, 2))
    for c in range(2):
        N[0, c] = a00 * X1[0, c] + a01 * X1[1, c]
        N[1, c] = a10 * X1[0, c] + a11 * X1[1, c]
    n0, n1 = a00 * d[0] + a01 * d[1], a10 * d[0] + a11 * d[1]
    S00 = N[0, 0] ** 2 + N[1, 0] ** 2
    S11 = N[0, 1] ** 2 + N[1, 1] ** 2
    q = N[0, 0] * N[0, 1] + N[1, 0] * N[1, 1]
    c0 = 0.5 * (S00 + S11) + n0 * n0 + n1 * n1 - det * det
    p = 0.5 * (S00 - S11)
    a = -2.0 * (N[0, 0] * n0 + N[1, 0] * n1)
    b = -2.0 * (N[0, 1] * n0 + N[1, 1] * n1)
    size = S00 + S11 + n0 * n0 + n1 * n1 + det * det
    coeffs = np.array([(p - 1j * q) / 2, (a - 1j * b) / 2, c0 + 0j, (a + 1j * b) / 2,
                       (p + 1j * q) / 2])  # fmt: skip
    if np.abs(coeffs).max() < 1e-12 * size:  # u(t2) on the circle whatever t1 is
        pairs[0, 0], pairs[0, 1] = 0.0, math.atan2(n1 * det, n0 * det)
        return 1, INFINITE
    found, count, kind = np.empty(4), 0, EXACT
    for z in np.roots(coeffs):
        t = math.atan2(z.imag, z.real)
        for _ in range(40):  # Newton on the trigonometric polynomial (slow at double roots)
            value, slope = _trig(t, c0, a, b, p, q)
            if abs(value) < 1e-17 * size or abs(slope) < 1e-14 * size:
                break
            t -= value / slope
        t = _wrap(t)
        new = True
        for k in range(count):
            if abs(_wrap(t - found[k])) <= 1e-7:
                new = False
        if abs(_trig(t, c0, a, b, p, q)[0]) < 1e-9 * size and new:
            found[count] = t
            count += 1
    if count == 0:  # no angle puts u(t2) on the circle: the closest one
        best, kind = math.inf, LEAST_SQUARES
        for g in range(721):
            t = -math.pi + g * (TWO_PI / 720)
            value = abs(_trig(t, c0, a, b, p, q)[0])
            if value < best:
                best, found[0] = value, t
        count = 1
    for k in range(count):
        t = found[k]
        u0 = (n0 - N[0, 0] * math.cos(t) - N[0, 1] * math.sin(t)) * det
        u1 = (n1 - N[1, 0] * math.cos(t) - N[1, 1] * math.sin(t)) * det
        pairs[k, 0], pairs[k, 1] = t, math.atan2(u1, u0)
    return count, kind


@inline_kernel
def _trig(t, c0, a, b, p, q):
    """(f, f') of f(t) = c0 + a cos t + b sin t + p cos 2t + q sin 2t."""
    c, s, c2, s2 = math.cos(t), math.sin(t), math.cos(2 * t), math.sin(2 * t)
    return c0 + a * c + b * s + p * c2 + q * s2, -a * s + b * c - 2 * p * s2 + 2 * q * c2


@inline_kernel
def _swap(pairs, count):
    for k in range(count):
        pairs[k, 0], pairs[k, 1] = pairs[k, 1], pairs[k, 0]


@kernel
def _raw_pairs(A1, A2, d, pairs):
    """:func:`circle_pair` before its answers are put back into the equations."""
    scale = max(1.0, np.abs(A1).max(), np.abs(A2).max())
    f1, f2 = _flat(A1), _flat(A2)
    if f2 < 1e-9 and f2 <= f1:  # A2 of rank 1: its null row gives t1
        count, kind = _singular_pair(A2, A1, d, 1e-9 * scale, pairs)
        _swap(pairs, count)
        return count, kind
    if f1 < 1e-9:  # A1 of rank 1: its null row gives t2
        return _singular_pair(A1, A2, d, 1e-9 * scale, pairs)
    if abs(_det(A1)) > abs(_det(A2)):
        count, kind = _quartic_pairs(A2, A1, d, pairs)
        _swap(pairs, count)
        return count, kind
    return _quartic_pairs(A1, A2, d, pairs)


@kernel
def circle_pair(A1, A2, d, pairs):
    """Every (t1, t2) with ``A1 u(t1) + A2 u(t2) = d`` (A1, A2 (2, 2)) into ``pairs`` (4, 2):
    (count, flag), LEAST_SQUARES (the closest pair) when none solves both equations to 1e-8
    of their size (:func:`toolkit.ik.analytic.subproblems.circle_pair`)."""
    count, kind = _raw_pairs(A1, A2, d, pairs)
    if kind != EXACT:
        return count, kind
    size = max(1.0, np.abs(A1).sum() + np.abs(A2).sum() + np.abs(d).sum())
    good, best, worst = 0, 0, math.inf
    for k in range(count):
        c1, s1, c2, s2 = (math.cos(pairs[k, 0]), math.sin(pairs[k, 0]), math.cos(pairs[k, 1]),
                          math.sin(pairs[k, 1]))  # fmt: skip
        e0 = A1[0, 0] * c1 + A1[0, 1] * s1 + A2[0, 0] * c2 + A2[0, 1] * s2 - d[0]
        e1 = A1[1, 0] * c1 + A1[1, 1] * s1 + A2[1, 0] * c2 + A2[1, 1] * s2 - d[1]
        miss = max(abs(e0), abs(e1))
        if miss < worst:
            best, worst = k, miss
        if miss <= 1e-8 * size:
            pairs[good, 0], pairs[good, 1] = pairs[k, 0], pairs[k, 1]
            good += 1
    if good:
        return good, EXACT
    pairs[0, 0], pairs[0, 1] = pairs[best, 0], pairs[best, 1]
    return 1, LEAST_SQUARES


@inline_kernel
def trig_row(h, k, p, r):
    """h^T R(k, theta) p = c + r . u(theta): c, with r into ``r`` (2,)."""
    kp = dot(k, p)
    r[0] = dot(h, p) - dot(h, k) * kp
    r[1] = (h[0] * (k[1] * p[2] - k[2] * p[1]) + h[1] * (k[2] * p[0] - k[0] * p[2])
            + h[2] * (k[0] * p[1] - k[1] * p[0]))  # fmt: skip
    return dot(h, k) * kp


@kernel
def sp5(p0, p1, p2, p3, k1, k2, k3, out):
    """Every (t1, t2, t3) with ``p0 + R(k1, t1) p1 = R(k2, t2) (p2 + R(k3, t3) p3)`` into
    ``out`` (4, 3): (count, flag) (:func:`toolkit.ik.analytic.subproblems.sp5`): the
    component along k2 and the length, which joint 2 keeps, give (t1, t3)
    (:func:`circle_pair`), then t2 by SP1."""
    A1, A3, d, r = np.empty((2, 2)), np.empty((2, 2)), np.empty(2), np.empty(2)
    c1 = trig_row(k2, k1, p1, r)
    A1[0, 0], A1[0, 1] = r[0], r[1]
    c3 = trig_row(k2, k3, p3, r)
    A3[0, 0], A3[0, 1] = -r[0], -r[1]
    n1 = trig_row(p0, k1, p1, r)
    A1[1, 0], A1[1, 1] = 2 * r[0], 2 * r[1]
    n3 = trig_row(p2, k3, p3, r)
    A3[1, 0], A3[1, 1] = -2 * r[0], -2 * r[1]
    d[0] = dot(k2, p2) - dot(k2, p0) + c3 - c1
    d[1] = dot(p2, p2) + dot(p3, p3) - dot(p0, p0) - dot(p1, p1) + 2 * (n3 - n1)
    pairs = np.empty((4, 2))
    count, kind = circle_pair(A1, A3, d, pairs)
    V, R, closest = np.empty((2, 3)), np.empty((3, 3)), np.empty((4, 3))
    x, y = V[0], V[1]
    exact = near = 0
    for m in range(count):
        t1, t3 = pairs[m, 0], pairs[m, 1]
        rotation(k3, t3, R)
        for i in range(3):
            x[i] = p2[i] + R[i, 0] * p3[0] + R[i, 1] * p3[1] + R[i, 2] * p3[2]
        rotation(k1, t1, R)
        for i in range(3):
            y[i] = p0[i] + R[i, 0] * p1[0] + R[i, 1] * p1[1] + R[i, 2] * p1[2]
        t2, f2 = sp1(x, y, k2)
        if f2 != LEAST_SQUARES:
            out[exact, 0], out[exact, 1], out[exact, 2] = t1, t2, t3
            exact += 1
        else:
            closest[near, 0], closest[near, 1], closest[near, 2] = t1, t2, t3
            near += 1
    if exact:
        return exact, kind
    out[:near] = closest[:near]
    return near, (kind if kind != EXACT else LEAST_SQUARES)
