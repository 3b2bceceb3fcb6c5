"""The canonical subproblems of analytic IK (Paden-Kahan 1-3, and 4), every solution and
the least-squares answer where none is exact.

Each takes unit axes ``k`` and vectors in one frame and returns the angles with a flag:

* :func:`sp1`: theta with ``R(k, theta) p1 = p2``;
* :func:`sp2`: (theta1, theta2) with ``R(k1, theta1) p1 = R(k2, theta2) p2``;
* :func:`sp3`: theta with ``|| R(k, theta) p1 - p2 || = d``;
* :func:`sp4`: theta with ``h^T R(k, theta) p = d``.

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

__all__ = ["EXACT", "INFINITE", "LEAST_SQUARES", "cross", "rot", "sp1", "sp2", "sp3", "sp4"]

EXACT, LEAST_SQUARES, INFINITE = "exact", "least squares", "infinite"
ZERO = 1e-12
"""Below this a length or a determinant counts as zero (the inputs are unit axes and
vectors of a robot's size, metres)."""


def rot(k: np.ndarray, theta: float) -> np.ndarray:
    """The rotation matrix R(k, theta) about the unit axis k (Rodrigues)."""
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.asarray(np.eye(3) + math.sin(theta) * K + (1.0 - math.cos(theta)) * (K @ K))


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
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
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
    if abs(c) - r > 1e-12 * max(1.0, float(np.linalg.norm(h) * np.linalg.norm(p))):
        return [phi if ratio > 0 else phi + math.pi], LEAST_SQUARES
    delta = math.acos(max(-1.0, min(1.0, ratio)))  # a tangent within rounding: one angle
    if delta < 1e-12:
        return [phi], EXACT
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
        if on2:
            t1, f1 = sp1(p1, p2, k1)
            return [(t1, 0.0)], INFINITE if f1 != LEAST_SQUARES else LEAST_SQUARES
        t2, f2 = sp1(p2, p1, k2)
        return [(0.0, t2)], INFINITE if f2 != LEAST_SQUARES else LEAST_SQUARES
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
