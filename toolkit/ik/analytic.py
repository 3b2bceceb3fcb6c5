"""Every IK branch of an arm whose axes allow it, by subproblem decomposition.

The chain (:func:`toolkit.ik.structure.chain_of`) is in product-of-exponentials form with
every axis ``h_i`` and a point ``o_i`` on it in the base frame at zero: the frame's pose is
``R_0T = R(h1, q1) ... R(h6, q6) R_T0`` and
``p_0T = o1 + R01 (o2 - o1) + ... + R06 (p_T0 - o6)`` (``R0i`` the product up to joint i).
Each family (:func:`toolkit.ik.structure.find_structure`) picks the points that make terms
vanish (the meeting point of axes 5 and 6, or the wrist centre) and peels the joints off
one subproblem at a time (:mod:`toolkit.ik.subproblems`):

* **three parallel** (axes 2-4 parallel, 5 and 6 meet): q1 by SP4 (the component along
  h2 is untouched by joints 2-4), q5 by SP4, q6 by SP1, q2 + q3 + q4 by SP1, then q3 by
  SP3 and q2 by SP1 in the plane of the three parallel axes;
* **spherical wrist** (axes 4-6 meet at the wrist centre W, axes 2, 3 parallel): W from
  the target, q1 by SP4, q3 by SP3, q2 by SP1, then q4, q5 by SP2 and q6 by SP1.

Each returns up to 8 branches with the roots they took ("shoulder +", "elbow -", ...);
only branches whose every subproblem had an exact solution are kept (for an arm only near
its family, least-squares answers too: the branches are then polished on the real model).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .structure import Chain
from .subproblems import EXACT, LEAST_SQUARES, cross, rot, sp1, sp2, sp3, sp4

__all__ = ["EXACT_ONLY", "FAMILIES", "NEAR_OK", "Branch"]

EXACT_ONLY = (EXACT,)
NEAR_OK = (EXACT, LEAST_SQUARES)
"""What a branch of an arm only near its family may rest on."""

Branch = tuple[np.ndarray, str]
"""Six joint angles [rad] of the chain and the branch's label."""


def _perp_unit(h: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to h."""
    x = cross(h, np.array([1.0, 0.0, 0.0]))
    if np.linalg.norm(x) < 0.5:
        x = cross(h, np.array([0.0, 1.0, 0.0]))
    return np.asarray(x / np.linalg.norm(x))


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


def _elbow(
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
            x = _perp_unit(h[1])
            t14, _ = sp1(x, R14 @ x, h[1])
            d = R01.T @ v - p12 - R14 @ p45
            elbows, n3 = _elbow(d, p23, p34, h[1], h[2], ok)
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
        elbows, n3 = _elbow(u, p23, p3W, h[1], h[2], ok)
        for k, q2, q3 in elbows:
            R36 = (R01 @ rot(h[1], q2) @ rot(h[2], q3)).T @ R06
            pairs, f45 = sp2(R36 @ h[5], h[5], h[3], h[4])
            if f45 not in ok:
                continue
            for j, (t4, q5) in enumerate(pairs):
                q4 = -t4
                x = _perp_unit(h[5])
                q6, f6 = sp1(x, rot(h[4], -q5) @ rot(h[3], -q4) @ R36 @ x, h[5])
                if f6 not in ok:
                    continue
                label = (f"shoulder {_sign(i, n1)}, elbow {_sign(k, n3)}, "
                         f"wrist {_sign(j, len(pairs))}")  # fmt: skip
                out.append((np.array([q1, q2, q3, q4, q5, q6]), label))
    return out


FAMILIES: dict[str, Callable[[Chain, np.ndarray, np.ndarray, tuple[str, ...]], list[Branch]]] = {
    "three parallel": three_parallel,
    "spherical wrist": spherical_wrist,
}
"""The solver of each family of :func:`toolkit.ik.structure.find_structure`."""
