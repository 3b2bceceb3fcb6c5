"""The canonical subproblems of analytic IK (Paden-Kahan 1-3, and 4), every solution and
the least-squares answer where none is exact.

Each takes unit axes ``k`` and vectors in one frame and returns the angles with a flag:

* :func:`sp1`: theta with ``R(k, theta) p1 = p2``;
* :func:`sp2`: (theta1, theta2) with ``R(k1, theta1) p1 = R(k2, theta2) p2``;
* :func:`sp3`: theta with ``|| R(k, theta) p1 - p2 || = d``;
* :func:`sp4`: theta with ``h^T R(k, theta) p = d``;
* :func:`sp5`: (theta1, theta2, theta3) with
  ``p0 + R(k1, theta1) p1 = R(k2, theta2) (p2 + R(k3, theta3) p3)``;
* :func:`sp6`: (theta1, theta2) with ``h1^T R(k1, theta1) p1 + h2^T R(k2, theta2) p2 = d1``
  and ``h3^T R(k3, theta1) p3 + h4^T R(k4, theta2) p4 = d2``.

SP5 and SP6 come down to two equations linear in (cos, sin) of each of two angles: one
pair follows from the other, which must then lie on the unit circle, a trigonometric
polynomial of degree 2 (up to 4 roots, found as those of a quartic on the unit circle).

``R(k, theta)`` turns by theta about k (right hand). The flag is :data:`EXACT`,
:data:`LEAST_SQUARES` (no exact solution: the angle(s) that come closest) or
:data:`INFINITE` (every angle solves it, e.g. ``p1`` on the axis; one representative, 0, is
returned). Nothing here divides by a zero it did not check first. The forms follow Elias &
Wen, "IK-Geo: unified robot inverse kinematics using subproblem decomposition" (2024),
see docs/references.md; the code is the toolkit's own.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "EXACT", "INFINITE", "LEAST_SQUARES", "cross", "rot", "sp1", "sp2", "sp3", "sp4", "sp5", "sp6",
]  # fmt: skip

EXACT, LEAST_SQUARES, INFINITE = "exact", "least squares", "infinite"
ZERO = 1e-12
"""Below this a length or a determinant counts as zero (the inputs are unit axes and
vectors of a robot's size, metres)."""
TANGENT = 1e-14
"""SP3, SP4: one root where the half gap's cosine is within this of 1 (a tangent, to the
cosine's rounding; as :data:`toolkit.ik.analytic.subproblem_kernels.TANGENT`)."""


def rot(k: np.ndarray, theta: float) -> np.ndarray:
    """The rotation matrix R(k, theta) about the unit axis k (Rodrigues, entry by entry: a
    few times faster than the matrix form for one small matrix)."""
    x, y, z = float(k[0]), float(k[1]), float(k[2])
    c, s = math.cos(theta), math.sin(theta)
    v = 1.0 - c
    return np.array([
        [c + v * x * x, v * x * y - s * z, v * x * z + s * y],
        [v * x * y + s * z, c + v * y * y, v * y * z - s * x],
        [v * x * z - s * y, v * y * z + s * x, c + v * z * z],
    ])  # fmt: skip


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b of two 3-vectors (numpy's cross costs ~20x more for one pair)."""
    a0, a1, a2 = float(a[0]), float(a[1]), float(a[2])
    b0, b1, b2 = float(b[0]), float(b[1]), float(b[2])
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def _perp(k: np.ndarray, p: np.ndarray) -> np.ndarray:
    return p - k * float(k @ p)


def sp1(p1: np.ndarray, p2: np.ndarray, k: np.ndarray) -> tuple[float, str]:
    """theta with R(k, theta) p1 = p2; when no angle does (p1 and p2 not on one circle
    about k), the angle minimising ||R p1 - p2||."""
    a, b = _perp(k, p1), _perp(k, p2)
    na, nb = math.sqrt(float(a @ a)), math.sqrt(float(b @ b))
    same_height = abs(float(k @ (p1 - p2))) < 1e-9
    if na < ZERO or nb < ZERO:  # a point on the axis: every angle is as good as any
        return 0.0, INFINITE if na < ZERO and nb < ZERO and same_height else LEAST_SQUARES
    theta = math.atan2(float(k @ cross(a, b)), float(a @ b))
    return theta, EXACT if abs(na - nb) < 1e-9 and same_height else LEAST_SQUARES


def sp4(h: np.ndarray, p: np.ndarray, k: np.ndarray, d: float) -> tuple[list[float], str]:
    """Every theta with h^T R(k, theta) p = d (two, one at a tangent, or the least-squares
    one when |d| is out of reach)."""
    a = _perp(k, p)
    A = float(h @ a)  # cos coefficient
    B = float(h @ cross(k, p))  # sin coefficient
    c = d - float(h @ k) * float(k @ p)
    r = math.hypot(A, B)
    if r < ZERO:
        return [0.0], INFINITE if abs(c) < 1e-9 else LEAST_SQUARES
    phi = math.atan2(B, A)
    ratio = c / r
    # beyond reach by more than rounding (c is a difference of terms of size |h| |p|)
    if abs(c) - r > 1e-12 * max(1.0, math.sqrt(float(h @ h) * float(p @ p))):
        return [phi if ratio > 0 else phi + math.pi], LEAST_SQUARES
    delta = math.acos(max(-1.0, min(1.0, ratio)))
    if 1.0 - abs(ratio) < TANGENT:  # a tangent within rounding: one angle
        return [phi if ratio > 0 else phi + math.pi], EXACT
    return [phi + delta, phi - delta], EXACT


def sp3(p1: np.ndarray, p2: np.ndarray, k: np.ndarray, d: float) -> tuple[list[float], str]:
    """Every theta with ||R(k, theta) p1 - p2|| = d, d >= 0 (the least-squares one when no
    angle reaches d)."""
    # ||R p1 - p2||^2 = |p1|^2 + |p2|^2 - 2 p2^T R p1
    target = 0.5 * (float(p1 @ p1) + float(p2 @ p2) - d * d)
    return sp4(p2, p1, k, target)


def sp2(
    p1: np.ndarray, p2: np.ndarray, k1: np.ndarray, k2: np.ndarray
) -> tuple[list[tuple[float, float]], str]:
    """Every (theta1, theta2) with R(k1, theta1) p1 = R(k2, theta2) p2 (two, one, or the
    least-squares pair when the circles do not meet). Parallel axes: INFINITE (the pair is
    then a one-parameter family; the caller's structure must avoid it)."""
    n = cross(k1, k2)
    s2 = float(n @ n)
    if s2 < ZERO**2:
        return [(0.0, 0.0)], INFINITE
    on1 = float(np.linalg.norm(_perp(k1, p1))) < ZERO
    on2 = float(np.linalg.norm(_perp(k2, p2))) < ZERO
    if on1 or on2:  # a point on its own axis: that angle is free, the other is SP1
        # solved when SP1 says so or its pair meets to rounding (both points within ZERO of
        # an axis, SP1's own thresholds can disagree with ours)
        if on2:
            t1, f1 = sp1(p1, p2, k1)
            met = f1 != LEAST_SQUARES or float(np.linalg.norm(rot(k1, t1) @ p1 - p2)) < 1e-9
            return [(t1, 0.0)], INFINITE if met else LEAST_SQUARES
        t2, f2 = sp1(p2, p1, k2)
        met = f2 != LEAST_SQUARES or float(np.linalg.norm(rot(k2, t2) @ p2 - p1)) < 1e-9
        return [(0.0, t2)], INFINITE if met else LEAST_SQUARES
    # the common point c = x k1 + y k2 + z (k1 x k2): k1^T c = k1^T p1, k2^T c = k2^T p2
    a1, a2, g = float(k1 @ p1), float(k2 @ p2), float(k1 @ k2)
    det = 1.0 - g * g
    x = (a1 - g * a2) / det
    y = (a2 - g * a1) / det
    base = x * k1 + y * k2
    rest = 0.5 * (float(p1 @ p1) + float(p2 @ p2)) - float(base @ base)  # z^2 |n|^2
    kind = EXACT
    if abs(float(p1 @ p1) - float(p2 @ p2)) > 1e-9:
        kind = LEAST_SQUARES
    if rest < -1e-12:
        kind = LEAST_SQUARES
    rest = max(rest, 0.0)
    z = math.sqrt(rest / s2)
    out = []
    for zz in (z, -z) if z > 1e-12 else (0.0,):
        c = base + zz * n
        t1, f1 = sp1(p1, c, k1)
        t2, f2 = sp1(p2, rot(k1, t1) @ p1, k2)  # onto the point p1 reached: consistent pairs
        if INFINITE in (f1, f2):
            kind = INFINITE
        out.append((t1, t2))
    return out, kind


def _row(h: np.ndarray, k: np.ndarray, p: np.ndarray) -> tuple[float, np.ndarray]:
    """h^T R(k, theta) p = c + r . (cos theta, sin theta): (c, r)."""
    return float(h @ k) * float(k @ p), np.array([float(h @ _perp(k, p)), float(h @ cross(k, p))])


def circle_pair(
    A1: np.ndarray, A2: np.ndarray, d: np.ndarray
) -> tuple[list[tuple[float, float]], str]:
    """Every (t1, t2) with ``A1 u(t1) + A2 u(t2) = d``, u(t) = (cos t, sin t), A1, A2 (2, 2):
    the pair of the better-conditioned matrix follows from the other's, which must lie on
    the unit circle. INFINITE when neither matrix can be solved for (a family of answers),
    LEAST_SQUARES (the closest) when no pair solves both equations to 1e-8 of their size;
    each pair is put back into them before it counts as exact. A matrix within 1e-9 of
    rank 1 is treated as of rank 1; one merely close to it loses digits, and its answers
    may then be flagged least squares."""
    pairs, kind = _circle_pair(A1, A2, d)
    if kind != EXACT:
        return pairs, kind
    size = max(1.0, float(np.abs(A1).sum() + np.abs(A2).sum() + np.abs(d).sum()))

    def miss(pair: tuple[float, float]) -> float:
        u1 = np.array([math.cos(pair[0]), math.sin(pair[0])])
        u2 = np.array([math.cos(pair[1]), math.sin(pair[1])])
        return float(np.abs(A1 @ u1 + A2 @ u2 - d).max())

    good = [pair for pair in pairs if miss(pair) <= 1e-8 * size]
    return (good, EXACT) if good else ([min(pairs, key=miss)], LEAST_SQUARES)


def _circle_pair(
    A1: np.ndarray, A2: np.ndarray, d: np.ndarray
) -> tuple[list[tuple[float, float]], str]:
    scale = max(1.0, float(np.abs(A1).max()), float(np.abs(A2).max()))

    def flat(A: np.ndarray) -> float:  # 0 for a matrix of rank 1, 1 for a rotation
        return abs(float(np.linalg.det(A))) / max(float((A * A).sum()), 1e-300)

    if flat(A2) < 1e-9 and flat(A2) <= flat(A1):  # A2 of rank 1: its null row gives t1
        pairs, kind = _singular_pair(A2, A1, d, 1e-9 * scale)
        return [(b, a) for a, b in pairs], kind
    if flat(A1) < 1e-9:  # A1 of rank 1: its null row gives t2
        return _singular_pair(A1, A2, d, 1e-9 * scale)
    if abs(np.linalg.det(A1)) > abs(np.linalg.det(A2)):
        pairs, kind = _circle_pair(A2, A1, d)
        return [(b, a) for a, b in pairs], kind
    # A2 u2 = d - A1 u1 with |u2| = 1, without dividing by det A2 (small when A2 is nearly
    # of rank 1): adj(A2) (d - A1 u1) = det(A2) u2, so |n - N u1|^2 = det(A2)^2
    det = float(np.linalg.det(A2))
    adj = np.array([[A2[1, 1], -A2[0, 1]], [-A2[1, 0], A2[0, 0]]])
    N, n = adj @ A1, adj @ d
    S = N.T @ N
    c0 = 0.5 * (S[0, 0] + S[1, 1]) + float(n @ n) - det * det
    p, q = 0.5 * (S[0, 0] - S[1, 1]), S[0, 1]
    a, b = -2.0 * (N.T @ n)
    size = float(S[0, 0] + S[1, 1] + n @ n + det * det)

    def f(t: float) -> tuple[float, float]:
        c, s, c2, s2 = math.cos(t), math.sin(t), math.cos(2 * t), math.sin(2 * t)
        return c0 + a * c + b * s + p * c2 + q * s2, -a * s + b * c - 2 * p * s2 + 2 * q * c2

    coeffs = [(p - 1j * q) / 2, (a - 1j * b) / 2, c0, (a + 1j * b) / 2, (p + 1j * q) / 2]
    if max(abs(x) for x in coeffs) < 1e-12 * size:  # u(t2) on the circle whatever t1 is
        return [(0.0, math.atan2(n[1] * det, n[0] * det))], INFINITE
    found: list[float] = []
    for z in np.roots(coeffs):
        t = float(np.angle(z))
        for _ in range(40):  # Newton on the trigonometric polynomial (slow at double roots)
            value, slope = f(t)
            if abs(value) < 1e-17 * size or abs(slope) < 1e-14 * size:
                break
            t -= value / slope
        t = math.remainder(t, 2 * math.pi)
        new = all(abs(math.remainder(t - u, 2 * math.pi)) > 1e-7 for u in found)  # double: once
        if abs(f(t)[0]) < 1e-9 * size and new:
            found.append(t)
    kind = EXACT
    if not found:  # no angle puts u(t2) on the circle: the closest one
        grid = np.linspace(-math.pi, math.pi, 721)
        found, kind = [float(grid[np.argmin([abs(f(float(t))[0]) for t in grid])])], LEAST_SQUARES
    out = []
    for t in found:
        u2 = (n - N @ np.array([math.cos(t), math.sin(t)])) * det  # det(A2)^2 u2
        out.append((t, math.atan2(u2[1], u2[0])))
    return out, kind


def _one_equation(r: np.ndarray, c: float, tiny: float) -> tuple[list[float], str]:
    """Every t with r . (cos t, sin t) = c (two, one at a tangent, the closest beyond reach;
    INFINITE when r = 0 and c = 0)."""
    size = math.hypot(r[0], r[1])
    if size < tiny:
        return [0.0], INFINITE if abs(c) < tiny else LEAST_SQUARES
    phi, ratio = math.atan2(r[1], r[0]), c / size
    if abs(ratio) > 1.0 + 1e-9:
        return [phi if ratio > 0 else phi + math.pi], LEAST_SQUARES
    if 1.0 - abs(ratio) < TANGENT:  # a tangent within rounding: one angle (as SP4)
        return [phi if ratio > 0 else phi + math.pi], EXACT
    delta = math.acos(max(-1.0, min(1.0, ratio)))
    return [phi + delta, phi - delta], EXACT


def _singular_pair(
    A1: np.ndarray, A2: np.ndarray, d: np.ndarray, tiny: float
) -> tuple[list[tuple[float, float]], str]:
    """:func:`circle_pair` when neither matrix can be inverted (each of rank 1 or less): the
    combination of the rows free of t1 gives t2, then the other row t1."""
    U = np.linalg.svd(A1)[0]
    w, v = U[:, 1], U[:, 0]  # w^T A1 = 0 (A1 of rank 1 or less)
    t2s, kind = _one_equation(w @ A2, float(w @ d), tiny)
    if kind == INFINITE:  # one equation left in both angles: a family, if it is reachable
        r1, r2, c = v @ A1, v @ A2, float(v @ d)
        reach = math.hypot(*r1) + math.hypot(*r2)
        return [(0.0, 0.0)], INFINITE if abs(c) <= reach + tiny else LEAST_SQUARES
    exact: list[tuple[float, float]] = []
    closest: list[tuple[float, float]] = []
    for t2 in t2s:
        rest = float(v @ (d - A2 @ np.array([math.cos(t2), math.sin(t2)])))
        t1s, k1 = _one_equation(v @ A1, rest, tiny)
        if k1 == INFINITE:
            return [(0.0, t2)], INFINITE
        (exact if k1 == EXACT and kind == EXACT else closest).extend((t1, t2) for t1 in t1s)
    return (exact, EXACT) if exact else (closest, LEAST_SQUARES)


def sp5(
    p0: np.ndarray, p1: np.ndarray, p2: np.ndarray, p3: np.ndarray, k1: np.ndarray,
    k2: np.ndarray, k3: np.ndarray,
) -> tuple[list[tuple[float, float, float]], str]:  # fmt: skip
    """Every (theta1, theta2, theta3) with ``p0 + R(k1, theta1) p1 = R(k2, theta2) (p2 +
    R(k3, theta3) p3)``: the component along k2 and the length, which joint 2 keeps, give
    (theta1, theta3) (:func:`circle_pair`), then theta2 by SP1."""
    c1, r1 = _row(k2, k1, p1)
    c3, r3 = _row(k2, k3, p3)
    n1, s1 = _row(p0, k1, p1)
    n3, s3 = _row(p2, k3, p3)
    A1 = np.array([r1, 2 * s1])
    A3 = np.array([-r3, -2 * s3])
    d = np.array([
        float(k2 @ p2) - float(k2 @ p0) + c3 - c1,
        float(p2 @ p2 + p3 @ p3 - p0 @ p0 - p1 @ p1) + 2 * (n3 - n1),
    ])  # fmt: skip
    pairs, kind = circle_pair(A1, A3, d)
    out: list[tuple[float, float, float]] = []
    closest: list[tuple[float, float, float]] = []
    for t1, t3 in pairs:
        t2, f2 = sp1(p2 + rot(k3, t3) @ p3, p0 + rot(k1, t1) @ p1, k2)
        (out if f2 != LEAST_SQUARES else closest).append((t1, t2, t3))
    if out or kind != EXACT:
        return (out or closest), kind
    return closest, LEAST_SQUARES


def sp6(
    h: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    k: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    p: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    d: tuple[float, float],
) -> tuple[list[tuple[float, float]], str]:
    """Every (theta1, theta2) with ``h1^T R(k1, theta1) p1 + h2^T R(k2, theta2) p2 = d1`` and
    ``h3^T R(k3, theta1) p3 + h4^T R(k4, theta2) p4 = d2`` (:func:`circle_pair`)."""
    rows = [_row(h[i], k[i], p[i]) for i in range(4)]
    A1 = np.array([rows[0][1], rows[2][1]])
    A2 = np.array([rows[1][1], rows[3][1]])
    rhs = np.array([d[0] - rows[0][0] - rows[1][0], d[1] - rows[2][0] - rows[3][0]])
    return circle_pair(A1, A2, rhs)
