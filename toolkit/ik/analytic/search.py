"""Every branch of a 6R chain whose axes 1, 2 meet and whose axes 4, 5 meet, by a search
along the last joint's angle (as IK-Geo solves the cases no closed form covers): the Panda
with joint 3 locked.

In the form of :mod:`toolkit.ik.analytic.families` (``T = E1 ... E6 M``), with S where axes 1, 2
meet and W where axes 4, 5 meet: for a trial q6, ``X = T M^-1 E6(q6)^-1 = E1 ... E5`` is
known, and so is ``X(W) = E1 E2 E3 (W)`` (joints 4, 5 leave W in place). Joints 1, 2 keep
the distance from S, so q3 follows by SP3 (2 roots), then (q1, q2) by SP2 (2 pairs): 4
curves. What is left, ``R(h4, q4) R(h5, q5) = (R1 R2 R3)^T R_X``, has a solution only where
that rotation keeps the angle between h4 and h5, ``e(q6) = h4^T R_r h5 - h4^T h5 = 0``.
Each curve's e is sampled at :data:`SAMPLES` angles of q6 (a compiled kernel) and inside
every stretch where the elbow has roots (its ends are exact: the squared distance from S to
X(W) is a sinusoid in q6); every sign change is bisected and finished by regula falsi to
round-off, the stretch between a curve's edge and its nearest sample is sub-sampled (e goes
as a square root there), and q4, q5 follow by SP1 at each root.

What can still be missed: a root where e only touches zero (a double root: a singular
target), and a branch that exists over a stretch of q6 shorter than the sampling away from
the elbow's ends (the shoulder near its tangent); the numeric IK's answers are compared
against the branches in the tests and benchmarks.
"""

from __future__ import annotations

import numpy as np

from . import family_kernels, search_kernels, subproblem_kernels
from .structure import Chain
from .subproblems import EXACT, INFINITE, LEAST_SQUARES, rot

__all__ = ["SAMPLES", "meeting_pairs", "roots", "search_grid"]

SAMPLES = search_kernels.SAMPLES
"""How many angles of q6 each curve is sampled at before its sign changes are refined."""
BISECTIONS, SECANTS = search_kernels.BISECTIONS, search_kernels.SECANTS
EDGE_BISECTIONS, EDGE_SAMPLES = search_kernels.EDGE_BISECTIONS, search_kernels.EDGE_SAMPLES
"""Each bracket is halved BISECTIONS times, then refined SECANTS times by regula falsi
(Illinois); a curve's edge is found by EDGE_BISECTIONS halvings, and the stretch from it to
the nearest sample sub-sampled at EDGE_SAMPLES points (in the compiled search)."""

Branch = tuple[np.ndarray, str]
FLAGS = {subproblem_kernels.EXACT: EXACT, subproblem_kernels.LEAST_SQUARES: LEAST_SQUARES,
         subproblem_kernels.INFINITE: INFINITE}  # fmt: skip
"""The compiled subproblems' flags (:mod:`toolkit.ik.analytic.subproblem_kernels`) by name."""


def _curves(
    chain: Chain, o: np.ndarray, T: np.ndarray, q6: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """At each trial q6 (N,): the residual e of the 4 curves (N, 4), NaN where the curve does
    not exist (SP3 or SP2 without a real root), their q1, q2, q3 (N, 4, 3) and the rotation
    joints 1-5 must make (N, 3, 3) (compiled:
    :func:`toolkit.ik.analytic.family_kernels.pair_curves`)."""
    N = len(q6)
    E, Q, RX = np.empty((N, 4)), np.zeros((N, 4, 3)), np.empty((N, 3, 3))
    tip = chain.tip
    family_kernels.pair_curves(
        np.ascontiguousarray(chain.axes), np.ascontiguousarray(o),
        np.ascontiguousarray(tip[:3, :3]), np.ascontiguousarray(tip[:3, 3]),
        np.ascontiguousarray(T), np.ascontiguousarray(q6, dtype=float), E, Q, RX,
    )  # fmt: skip
    return E, Q, RX


def _elbow_edges(chain: Chain, o: np.ndarray, T: np.ndarray) -> np.ndarray:
    """The middle of each stretch of q6 between the angles where q3 (SP3) begins or ends to
    have a root: the squared distance from S to X(W) is a sinusoid in q6, so those angles
    are exact, and a short stretch of roots (an elbow near its tangent) gets a sample."""
    h, M = chain.axes, chain.tip
    RTM = T[:3, :3] @ M[:3, :3].T
    S, W = o[0], o[3]
    d2 = []
    for t in (0.0, np.pi / 2, np.pi):
        y = RTM @ (o[5] + rot(h[5], -t) @ (W - o[5]) - M[:3, 3]) + T[:3, 3] - S
        d2.append(float(y @ y))
    c0, c1, c2 = 0.5 * (d2[0] + d2[2]), 0.5 * (d2[0] - d2[2]), d2[1] - 0.5 * (d2[0] + d2[2])
    a, b = W - o[2], S - o[2]
    hb, ha = float(b @ h[2]), float(h[2] @ a)
    r = float(np.hypot(float(b @ a) - hb * ha, b @ np.cross(h[2], a)))
    amp, psi = float(np.hypot(c1, c2)), float(np.arctan2(c2, c1))
    found = []
    for sign in (1.0, -1.0):  # ||y||^2 at the elbow's two tangents
        level = float(a @ a + b @ b) - 2 * hb * ha - 2 * sign * r
        if amp > 1e-15 and abs(level - c0) <= amp:
            half = float(np.arccos((level - c0) / amp))
            found += [psi + half, psi - half]
    ends = np.sort(np.remainder(np.array(found) + np.pi, 2 * np.pi) - np.pi)
    middles = 0.5 * (ends + np.append(ends[1:], ends[:1] + 2 * np.pi)) if len(ends) else ends
    return np.remainder(middles + np.pi, 2 * np.pi) - np.pi


def roots(
    chain: Chain, o: np.ndarray, T: np.ndarray, grid: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(q6 (K,), curve (K,)) of every root the search finds on the trial angles ``grid``
    (module doc), in one compiled call
    (:func:`toolkit.ik.analytic.search_kernels.search_roots`)."""
    out = np.empty((8 * len(grid), 2))
    tip = chain.tip
    count = search_kernels.search_roots(
        np.ascontiguousarray(chain.axes), np.ascontiguousarray(o),
        np.ascontiguousarray(tip[:3, :3]), np.ascontiguousarray(tip[:3, 3]),
        np.ascontiguousarray(T), np.ascontiguousarray(grid, dtype=float), out,
    )  # fmt: skip
    return out[:count, 0].copy(), out[:count, 1].astype(np.int64)


def search_grid(chain: Chain, o: np.ndarray, T: np.ndarray) -> np.ndarray:
    """The trial angles of q6: :data:`SAMPLES` over the turn, and the middle of each
    stretch between the elbow's tangents."""
    grid = np.linspace(-np.pi, np.pi, SAMPLES, endpoint=False)
    return np.unique(np.concatenate([grid, _elbow_edges(chain, o, T)]))


def meeting_pairs(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """The branches (module doc); ``o`` the points on the axes (o1 = o2 = S, o4 = o5 = W)."""
    q6, curve = roots(chain, o, T, search_grid(chain, o, T))
    if not len(q6):
        return []
    rows = np.empty((len(q6), 8))
    tip = chain.tip
    search_kernels.search_rows(
        np.ascontiguousarray(chain.axes), np.ascontiguousarray(o),
        np.ascontiguousarray(tip[:3, :3]), np.ascontiguousarray(tip[:3, 3]),
        np.ascontiguousarray(T), q6, curve, rows,
    )  # fmt: skip
    out: list[Branch] = []
    seen = [0, 0, 0, 0]
    for j in np.flatnonzero(rows[:, 7]).tolist():
        f4, f5 = FLAGS[int(rows[j, 5])], FLAGS[int(rows[j, 6])]
        if f4 in ok and f5 in ok:
            c = int(curve[j])
            seen[c] += 1
            label = f"elbow {'+-'[c // 2]}, shoulder {'+-'[c % 2]}, root {seen[c]}"
            out.append((np.append(rows[j, :5], q6[j]), label))
    return out
