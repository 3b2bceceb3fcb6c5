"""The 6R family with three parallel axes at the base (axes 1, 2, 3; EAIK's "outer" case),
in Python: the oracle of its compiled form (:mod:`toolkit.ik.analytic.outer_kernels`). A
chain with its last three axes parallel is this family read from the frame (reversed).

With h = h1 (axes 2 and 3 parallel or opposed to it), joints 1-3 turn about h by
theta = q1 + s2 q2 + s3 q3 (s the senses), so ``R06 = R(h, theta) R4 R5 R6`` and, with
g = R06^T h, ``R5^T R4^T h = R6 g``. Two equations then hold q4 and q6 alone: the
component along h of the position (which joints 1-3 leave as it is),
``h^T R(h4, q4) p45 + g^T R(h6, -q6) p56 = h^T v - h^T (p12 + p23 + p34)``, and the
component along h5 of the equation above (which joint 5 keeps),
``h^T R(h4, q4) h5 - g^T R(h6, -q6) h5 = 0``: SP6, up to 4 pairs. Then q5 by SP1, theta by
SP1 (R(h, theta) = R06 (R4 R5 R6)^T), and the planar elbow of joints 1, 2 (q2 by SP3, q1
by SP1) places what is left of the position; q3 = s3 (theta - q1 - s2 q2). Up to 8
branches, labelled by the wrist's pair (1-4) and the elbow.
"""

from __future__ import annotations

import numpy as np

from .families import Branch, perp_unit, planar_elbow
from .family import Family
from .structure import Chain
from .subproblems import EXACT, INFINITE, rot, sp1, sp6

__all__ = ["outer_parallel"]


def outer_parallel(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """Branches of the family (module doc); ``o`` the points on the axes; ``ok`` the
    subproblem answers a branch may rest on (least-squares ones too for an arm only near
    the family: its branches are polished)."""
    h = chain.axes
    a = h[0]
    R06 = T[:3, :3] @ chain.tip[:3, :3].T
    p12, p23, p34, p45, p56 = (o[i + 1] - o[i] for i in range(5))
    v = T[:3, 3] - o[0] - R06 @ (chain.tip[:3, 3] - o[5])
    s2, s3 = (1.0 if float(h[i] @ a) > 0 else -1.0 for i in (1, 2))
    g = R06.T @ a
    d1 = float(a @ v - a @ (p12 + p23 + p34))
    pairs, kind = sp6((a, g, a, -g), (h[3], h[5], h[3], h[5]), (p45, p56, h[4], h[4]), (d1, 0.0))
    if kind not in ok or kind == INFINITE:
        return []
    out: list[Branch] = []
    many = len(pairs) > 1
    for i, (q4, t6) in enumerate(pairs):
        q6 = -t6
        R4, R6 = rot(h[3], q4), rot(h[5], q6)
        t5, f5 = sp1(R4.T @ a, R6 @ g, h[4])  # R(h5, -q5) R4^T h = R6 g
        if f5 not in ok:
            continue
        q5 = -t5
        R45 = R4 @ rot(h[4], q5)
        x = perp_unit(a)
        theta, _ = sp1(x, R06 @ (R45 @ R6).T @ x, a)
        w = v - rot(a, theta) @ (p34 + R4 @ p45 + R45 @ p56)
        elbows, n2 = planar_elbow(w, p12, p23, h[0], h[1], ok)  # R(h1, q1) (p12 + R(h2, q2) p23)
        for k, q1, q2 in elbows:
            q3 = s3 * (theta - q1 - s2 * q2)
            label = Family.OUTER_PARALLEL.label((i if many else -1, k if n2 > 1 else -1, -1))
            out.append((np.array([q1, q2, q3, q4, q5, q6]), label))
    return out
