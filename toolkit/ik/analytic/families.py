"""Every IK branch of an arm whose axes allow it, by subproblem decomposition.

The chain (:func:`toolkit.ik.analytic.structure.chain_of`) is in product-of-exponentials form with
every axis ``h_i`` and a point ``o_i`` on it in the base frame at zero: the frame's pose is
``R_0T = R(h1, q1) ... R(h6, q6) R_T0`` and
``p_0T = o1 + R01 (o2 - o1) + ... + R06 (p_T0 - o6)`` (``R0i`` the product up to joint i).
Each family (:func:`toolkit.ik.analytic.structure.find_structure`) picks the points that make terms
vanish (the meeting point of axes 5 and 6, or the wrist centre) and peels the joints off
one subproblem at a time (:mod:`toolkit.ik.analytic.subproblems`):

* **three parallel** (axes 2-4 parallel, 5 and 6 meet): q1 by SP4 (the component along
  h2 is untouched by joints 2-4), q5 by SP4, q6 by SP1, q2 + q3 + q4 by SP1, then q3 by
  SP3 and q2 by SP1 in the plane of the three parallel axes;
* **spherical wrist** (axes 4-6 meet at the wrist centre W, axes 2, 3 parallel): W from
  the target, q1 by SP4, q3 by SP3, q2 by SP1, then q4, q5 by SP2 and q6 by SP1;
* **spherical wrist, meeting shoulder** (axes 4-6 meet at W, axes 1, 2 meet at S): q3 by
  SP3 (the distance from S to W), q1, q2 by SP2, then the wrist as above.

A 5-joint chain (**5R, axes 2, 3, 4 parallel**: the Katana 6M180, the catalogue's arm5dof) reaches a
5-dimensional set of poses: the point on axis 5 is placed (q1 by SP4 along h2, then q3 by
SP3 and q2 by SP1), q5 turns h2 to where the target's orientation needs it (SP1) and
q2 + q3 + q4 follows (SP1); up to 4 branches. A target whose orientation the arm cannot
take gets the roll and pitch each of those steps comes nearest with (least squares); the
verification says how far the branch misses. Without the Katana's symmetry (every axis
in one plane) the second root of q1 generally misses too: 6 equations, 5 joints.

A 3-joint chain places a point (the frame's origin; targets are positions): **3R, axes 1,
2 meeting** (q3 by SP3, q1, q2 by SP2) and **3R, axes 2, 3 parallel** (q1 by SP4, q3 by
SP3, q2 by SP1), up to 4 branches each; axes in general position, **3R, general**, by SP5 at
once (up to 4).

A 6-joint chain none of them fits is tried reversed (the frame as the base, T^-1 as the target,
each angle negated): a spherical "shoulder" (axes 1-3 meeting, as in a 7-joint arm with
its last joint locked) is then a spherical wrist.

Each returns up to 8 branches with the roots they took ("shoulder +", "elbow -", ...);
only branches whose every subproblem had an exact solution are kept (the 5R orientation
steps excepted, above; for an arm only near its family, least-squares answers too: the
branches are then polished on the real model).
"""

from __future__ import annotations

import math

import numpy as np

from .structure import Chain
from .subproblems import EXACT, INFINITE, LEAST_SQUARES, cross, rot, sp1, sp2, sp3, sp4, sp5

__all__ = [
    "EXACT_ONLY",
    "NEAR_OK",
    "Branch",
    "five_r_parallel",
    "meeting_shoulder",
    "perp_unit",
    "planar_elbow",
    "three_r_general",
    "three_r_meeting",
    "three_r_parallel",
]

EXACT_ONLY = (EXACT,)
NEAR_OK = (EXACT, LEAST_SQUARES)
"""What a branch of an arm only near its family may rest on."""

Branch = tuple[np.ndarray, str]
"""Six joint angles [rad] of the chain and the branch's label."""


def perp_unit(h: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to h."""
    x = cross(h, np.array([1.0, 0.0, 0.0]))
    if float(x @ x) < 0.25:
        x = cross(h, np.array([0.0, 1.0, 0.0]))
    return np.asarray(x / math.sqrt(float(x @ x)))


SPLIT = 0.1
"""[rad] For an arm only near its family, a least-squares root of SP3 or SP4 (the target
just beyond a tangent of the nearest exact geometry) becomes two starts this far either
side: the real arm's two roots, if it has them, lie on both sides (the polish finds them)."""


def _roots(angles: list[float], flag: str, ok: tuple[str, ...]) -> list[float]:
    if flag == LEAST_SQUARES and LEAST_SQUARES in ok and len(angles) == 1:
        return [angles[0] + SPLIT, angles[0] - SPLIT]
    return angles


def _shoulder(
    v: np.ndarray, h: np.ndarray, d: float, ok: tuple[str, ...]
) -> tuple[list[tuple[int, float, np.ndarray]], int]:
    """((root, q1, R01) with h2^T R(h1, -q1) v = d, how many roots): SP4, the component
    along axis 2 that the joints after joint 1 leave untouched."""
    q1s, f1 = sp4(h[1], v, h[0], d)
    if f1 not in ok:
        return [], 0
    q1s = _roots(q1s, f1, ok)
    return [(i, -t, rot(h[0], -t)) for i, t in enumerate(q1s)], len(q1s)


def planar_elbow(
    d: np.ndarray, p23: np.ndarray, p3x: np.ndarray, h2: np.ndarray, h3: np.ndarray,
    ok: tuple[str, ...],
) -> tuple[list[tuple[int, float, float]], int]:  # fmt: skip
    """((root, q2, q3) with R(h2, q2) (p23 + R(h3, q3) p3x) = d, how many roots q3 had):
    q3 by SP3 (the length), then q2 by SP1 (the direction)."""
    q3s, f3 = sp3(p3x, -p23, h3, float(np.linalg.norm(d)))
    if f3 not in ok:
        return [], 0
    q3s = _roots(q3s, f3, ok)
    out = []
    for k, q3 in enumerate(q3s):
        q2, f2 = sp1(p23 + rot(h3, q3) @ p3x, d, h2)
        if f2 in ok:
            out.append((k, q2, q3))
    return out, len(q3s)


def _sign(k: int, count: int) -> str:
    return "" if count == 1 else ("+" if k == 0 else "-")


def three_parallel(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """Branches of the three-parallel family (module doc); ``o`` the points on the axes
    (o5 = o6 where axes 5 and 6 meet); ``ok`` the subproblem answers a branch may rest on
    (least-squares ones too for an arm only near the family: its branches are polished)."""
    h = chain.axes
    R06 = T[:3, :3] @ chain.tip[:3, :3].T
    p6T = chain.tip[:3, 3] - o[5]
    p12, p23, p34, p45 = o[1] - o[0], o[2] - o[1], o[3] - o[2], o[4] - o[3]
    v = T[:3, 3] - o[0] - R06 @ p6T
    s3, s4 = (1.0 if float(h[i] @ h[1]) > 0 else -1.0 for i in (2, 3))
    out: list[Branch] = []
    shoulders, n1 = _shoulder(v, h, float(h[1] @ (p12 + p23 + p34 + p45)), ok)
    for i, q1, R01 in shoulders:
        q5s, f5 = sp4(h[1], h[5], h[4], float(h[1] @ R01.T @ R06 @ h[5]))
        if f5 not in ok:
            continue
        q5s = _roots(q5s, f5, ok)
        for j, q5 in enumerate(q5s):
            t6, f6 = sp1(rot(h[4], -q5) @ h[1], R06.T @ R01 @ h[1], h[5])
            if f6 not in ok:
                continue
            q6 = -t6
            R14 = R01.T @ R06 @ rot(h[5], -q6) @ rot(h[4], -q5)
            x = perp_unit(h[1])
            t14, _ = sp1(x, R14 @ x, h[1])
            d = R01.T @ v - p12 - R14 @ p45
            elbows, n3 = planar_elbow(d, p23, p34, h[1], h[2], ok)
            for k, q2, q3 in elbows:
                q4 = s4 * (t14 - q2 - s3 * q3)  # axes 3, 4 may point against axis 2
                label = (f"shoulder {_sign(i, n1)}, elbow {_sign(k, n3)}, "
                         f"wrist {_sign(j, len(q5s))}")  # fmt: skip
                out.append((np.array([q1, q2, q3, q4, q5, q6]), label))
    return out


def spherical_wrist(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """Branches of the spherical-wrist family (module doc); ``o`` the points on the axes
    (o4 = o5 = o6 = the wrist centre); ``ok`` as for :func:`three_parallel`."""
    h = chain.axes
    R06 = T[:3, :3] @ chain.tip[:3, :3].T
    W = o[3]
    p12, p23, p3W = o[1] - o[0], o[2] - o[1], W - o[2]
    v = T[:3, 3] - R06 @ (chain.tip[:3, 3] - W) - o[0]
    out: list[Branch] = []
    shoulders, n1 = _shoulder(v, h, float(h[1] @ (p12 + p23 + p3W)), ok)
    for i, q1, R01 in shoulders:
        u = R01.T @ v - p12
        elbows, n3 = planar_elbow(u, p23, p3W, h[1], h[2], ok)
        for k, q2, q3 in elbows:
            R03 = R01 @ rot(h[1], q2) @ rot(h[2], q3)
            head = f"shoulder {_sign(i, n1)}, elbow {_sign(k, n3)}"
            out += _with_wrist(h, (q1, q2, q3), R03.T @ R06, head, ok)
    return out


def _with_wrist(
    h: np.ndarray, q123: tuple[float, float, float], R36: np.ndarray, head: str,
    ok: tuple[str, ...],
) -> list[Branch]:  # fmt: skip
    """The branches of a spherical wrist turning by R36 after joints 1-3 at ``q123``,
    labelled ``head`` and the wrist's root."""
    return [(np.array([*q123, q4, q5, q6]), f"{head}, wrist {_sign(j, count)}")
            for j, count, q4, q5, q6 in _wrist(h, R36, ok)]  # fmt: skip


def _wrist(
    h: np.ndarray, R36: np.ndarray, ok: tuple[str, ...]
) -> list[tuple[int, int, float, float, float]]:
    """(root, roots, q4, q5, q6) of a spherical wrist turning by R36: q4, q5 by SP2 (where
    axis 6 points), q6 by SP1."""
    pairs, f45 = sp2(R36 @ h[5], h[5], h[3], h[4])
    if f45 not in ok:
        return []
    out = []
    for j, (t4, q5) in enumerate(pairs):
        q4 = -t4
        x = perp_unit(h[5])
        q6, f6 = sp1(x, rot(h[4], -q5) @ rot(h[3], -q4) @ R36 @ x, h[5])
        if f6 in ok:
            out.append((j, len(pairs), q4, q5, q6))
    return out


def meeting_shoulder(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """Branches of a spherical wrist whose axes 1, 2 meet (module doc); ``o`` the points on
    the axes (o1 = o2 = the shoulder point S, o4 = o5 = o6 = the wrist centre W): q3 by SP3
    (joints 1, 2 keep the distance from S to W), q1, q2 by SP2, then the wrist."""
    h = chain.axes
    R06 = T[:3, :3] @ chain.tip[:3, :3].T
    S, W = o[0], o[3]
    y = T[:3, 3] - R06 @ (chain.tip[:3, 3] - W) - S  # the wrist centre seen from S
    q3s, f3 = sp3(W - o[2], S - o[2], h[2], float(np.linalg.norm(y)))
    if f3 not in ok:
        return []
    q3s = _roots(q3s, f3, ok)
    out: list[Branch] = []
    for k, q3 in enumerate(q3s):
        x = o[2] - S + rot(h[2], q3) @ (W - o[2])
        pairs, f12 = sp2(x, y, h[1], h[0])  # R(h2, q2) x = R(h1, -q1) y
        if f12 not in ok:
            continue
        for i, (q2, t1) in enumerate(pairs):
            q1 = -t1
            R03 = rot(h[0], q1) @ rot(h[1], q2) @ rot(h[2], q3)
            head = f"shoulder {_sign(i, len(pairs))}, elbow {_sign(k, len(q3s))}"
            out += _with_wrist(h, (q1, q2, q3), R03.T @ R06, head, ok)
    return out


def three_r_meeting(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """Branches of a 3R position chain whose axes 1, 2 meet at S (o1 = o2 = S): q3 by SP3
    (the distance from S to the point), q1, q2 by SP2."""
    h, p0, S = chain.axes, chain.tip[:3, 3], o[0]
    y = T[:3, 3] - S
    q3s, f3 = sp3(p0 - o[2], S - o[2], h[2], float(np.linalg.norm(y)))
    if f3 not in ok:
        return []
    out: list[Branch] = []
    for k, q3 in enumerate(q3s):
        x = o[2] - S + rot(h[2], q3) @ (p0 - o[2])
        pairs, f12 = sp2(x, y, h[1], h[0])
        if f12 in ok:
            out += [(np.array([-t1, q2, q3]), f"shoulder {_sign(i, len(pairs))}, elbow "
                     f"{_sign(k, len(q3s))}") for i, (q2, t1) in enumerate(pairs)]  # fmt: skip
    return out


def three_r_parallel(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """Branches of a 3R position chain whose axes 2, 3 are parallel: q1 by SP4 (the
    component along axis 2), then q3 by SP3 and q2 by SP1 in the plane of axes 2, 3."""
    h, p0 = chain.axes, chain.tip[:3, 3]
    v = T[:3, 3] - o[0]
    shoulders, n1 = _shoulder(v, h, float(h[1] @ (p0 - o[0])), ok)
    out: list[Branch] = []
    for i, q1, R01 in shoulders:
        elbows, n3 = planar_elbow(R01.T @ v - (o[1] - o[0]), o[2] - o[1], p0 - o[2], h[1], h[2], ok)
        out += [(np.array([q1, q2, q3]), f"shoulder {_sign(i, n1)}, elbow {_sign(k, n3)}")
                for k, q2, q3 in elbows]  # fmt: skip
    return out


def five_r_parallel(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """Branches of a 5R chain whose axes 2, 3, 4 are parallel (module doc); ``o`` the
    points on the axes. The orientation steps (q5, q2 + q3 + q4) take the nearest angle
    when the target's orientation is out of the arm's reach."""
    h = chain.axes
    R05 = T[:3, :3] @ chain.tip[:3, :3].T
    v = T[:3, 3] - R05 @ (chain.tip[:3, 3] - o[4]) - o[0]  # o5 moved, seen from o1
    p12, p23, p34, p45 = o[1] - o[0], o[2] - o[1], o[3] - o[2], o[4] - o[3]
    s3, s4 = (1.0 if float(h[i] @ h[1]) > 0 else -1.0 for i in (2, 3))
    out: list[Branch] = []
    shoulders, n1 = _shoulder(v, h, float(h[1] @ (p12 + p23 + p34 + p45)), ok)
    for i, q1, R01 in shoulders:
        t5, f5 = sp1(h[1], R05.T @ R01 @ h[1], h[4])  # R(h5, -q5) h2 = R05^T R01 h2
        if f5 == INFINITE:
            continue
        q5 = -t5
        x = perp_unit(h[1])
        t14, _ = sp1(x, R01.T @ R05 @ rot(h[4], -q5) @ x, h[1])
        d = R01.T @ v - p12 - rot(h[1], t14) @ p45
        elbows, n3 = planar_elbow(d, p23, p34, h[1], h[2], ok)
        for k, q2, q3 in elbows:
            q4 = s4 * (t14 - q2 - s3 * q3)
            label = f"shoulder {_sign(i, n1)}, elbow {_sign(k, n3)}"
            out.append((np.array([q1, q2, q3, q4, q5]), label))
    return out


def three_r_general(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """Branches of a 3R position chain with axes in general position, by SP5:
    ``R(h1, -q1) (p - o1) - (o2 - o1) = R(h2, q2) ((o3 - o2) + R(h3, q3) (p0 - o3))``
    (up to 4)."""
    h, p0 = chain.axes, chain.tip[:3, 3]
    found, kind = sp5(o[0] - o[1], T[:3, 3] - o[0], o[2] - o[1], p0 - o[2], h[0], h[1], h[2])
    if kind not in ok:
        return []
    return [(np.array([-t1, t2, t3]), f"root {i + 1}") for i, (t1, t2, t3) in enumerate(found)]
