"""Planar geometry shared by the paper modules: the angle wrap and the two-link solver.

* :func:`wrap`: one convention for every angle the toolkit wraps, (-pi, pi].
* :func:`two_link`: the planar two-link inverse problem (law of cosines), used by paper
  2's geometric method, the Katana 6M180's closed form and [P3]'s SCARA.
* :func:`yaw_pitch_branches` and :func:`unique_within`: [P2]'s geometric method
  ([P2], eqs. 1-3) for any arm with a base yaw, three parallel pitch joints and a
  roll, on plain floats.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, overload

import numpy as np

__all__ = ["MERGE_TOL", "point3", "two_link", "unique_within", "wrap", "yaw_pitch_branches"]

TWO_PI = 2 * math.pi
MERGE_TOL = 1e-9
"""Two solutions closer than this in every angle (on the circle) are one [rad]."""


@overload
def wrap(angle: float) -> float: ...
@overload
def wrap(angle: np.ndarray) -> np.ndarray: ...
def wrap(angle: float | np.ndarray) -> float | np.ndarray:
    """Angle(s) wrapped to (-pi, pi] (plain floats stay plain floats)."""
    if isinstance(angle, float | int):
        return math.pi - (math.pi - angle) % TWO_PI  # Python's % is >= 0 for TWO_PI > 0
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), TWO_PI)


def point3(value: Any) -> list[float] | None:
    """Three finite real numbers as floats, fast (a tuple, a list or a float array), or None
    when ``value`` is anything else (the caller then checks it for a clear error)."""
    try:
        px, py, pz = value
        point = [float(px), float(py), float(pz)]
    except (TypeError, ValueError, OverflowError):
        return None
    if any(isinstance(v, bool | str | bytes) for v in (px, py, pz)):
        return None
    return point if math.isfinite(point[0] + point[1] + point[2]) else None


def two_link(x: float, y: float, l1: float, l2: float) -> list[tuple[float, float]]:
    """Planar two-link IK: every (t1, e) with l1 (cos t1, sin t1) + l2 (cos(t1 + e),
    sin(t1 + e)) = (x, y). Elbow e >= 0 first, then -e; [] when out of reach (the two
    coincide for a stretched or folded arm)."""
    c = (x * x + y * y - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    if abs(c) > 1 + 1e-12:
        return []
    c = min(1.0, max(-1.0, c))
    s = math.sqrt(max(0.0, 1.0 - c * c))
    base = math.atan2(y, x)
    out = []
    for e in (math.atan2(s, c), math.atan2(-s, c)):
        out.append((base - math.atan2(l2 * math.sin(e), l1 + l2 * math.cos(e)), e))
    return out


def yaw_pitch_branches(
    x: float,
    y: float,
    z: float,
    phi: float,
    lengths: Sequence[float],
    base_yaw: float,
) -> tuple[list[tuple[float, ...]], float]:
    """[P2]'s geometric method for one target, on plain floats ([P2], eqs. 1-3).

    ``lengths`` = (base_offset, upper_arm, forearm, gripper); ``phi`` is the pitch of the
    last link. Returns the branches (theta1..theta4, theta5 = 0) in the order (front,
    elbow +), (front, elbow -), (back, elbow +), (back, elbow -), wrapped to (-pi, pi],
    and how far the wrist point lies outside the elbow's annulus (0 when reachable).
    """
    b, l2, l3, l4 = lengths
    r = math.hypot(x, y)
    t1 = base_yaw if r < 1e-12 else math.atan2(y, x)
    z -= b
    out: list[tuple[float, ...]] = []
    reach = 0.0
    for side in (0, 1):  # the back branch: theta1 + pi, r -> -r, phi -> pi - phi
        rr, ph, yaw = (r, phi, t1) if side == 0 else (-r, math.pi - phi, t1 + math.pi)
        x4, z4 = rr - l4 * math.cos(ph), z - l4 * math.sin(ph)
        if side == 0:
            d = math.hypot(x4, z4)
            reach = max(d - (l2 + l3), abs(l2 - l3) - d, 0.0)
        pi = math.pi  # wrap() inlined: this loop runs for every closed-form solve
        for t2, t3 in two_link(x4, z4, l2, l3):
            t4 = ph - t2 - t3
            out.append(
                (
                    pi - (pi - yaw) % TWO_PI,
                    pi - (pi - t2) % TWO_PI,
                    pi - (pi - t3) % TWO_PI,
                    pi - (pi - t4) % TWO_PI,
                    0.0,
                )
            )
    return out, reach


def unique_within(
    candidates: Sequence[tuple[float, ...]],
    lower: Sequence[float] | None,
    upper: Sequence[float] | None,
) -> list[tuple[float, ...]]:
    """The candidates inside [lower, upper] (1e-12 slack), duplicates on the circle merged."""
    lo = None if lower is None else [float(v) - 1e-12 for v in lower]
    hi = None if upper is None else [float(v) + 1e-12 for v in upper]
    kept: list[tuple[float, ...]] = []
    for cand in candidates:
        if lo is not None and any(c < v for c, v in zip(cand, lo, strict=False)):
            continue
        if hi is not None and any(c > v for c, v in zip(cand, hi, strict=False)):
            continue
        for other in kept:
            if _same_on_circle(cand, other):
                break
        else:
            kept.append(cand)
    return kept


def _same_on_circle(a: Sequence[float], b: Sequence[float]) -> bool:
    for u, v in zip(a, b, strict=True):
        d = abs(u - v)
        if min(d, TWO_PI - d) > MERGE_TOL:
            return False
    return True
