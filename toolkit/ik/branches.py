"""All IK branches as a result: the analytic branches of a family, each turned into a q,
repeated for every equivalent angle (q + 2 pi k) inside a joint's limits, deduplicated and
verified (``Robot.ik_all``)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .structure import Structure

__all__ = ["IKAllBatchResult", "IKAllResult", "distinct", "turns", "turns_many", "turns_of"]


class IKAllResult(NamedTuple):
    """Every branch that puts the frame on the target.

    ``q`` (B, nq) one row per branch; ``success`` (B,) True where the branch is verified by
    an independent forward kinematics to ``tol`` and lies within the joint limits;
    ``within_limits`` (B,); ``labels`` the branch of each row ("shoulder +, elbow -, wrist
    +"; rows that differ by whole turns of a joint share it); ``position_error`` [m] and
    ``orientation_error`` [rad] (B,); the arm's ``structure``; ``polished``: the arm is
    only near its family and each branch was polished on the real model; ``lost``:
    branches of the nearest exact geometry that did not converge on the real model or
    merged with another.
    """

    q: np.ndarray
    success: np.ndarray
    within_limits: np.ndarray
    labels: list[str]
    position_error: np.ndarray
    orientation_error: np.ndarray
    structure: Structure
    polished: bool = False
    lost: int = 0

    @property
    def solved(self) -> int:
        """How many branches succeeded."""
        return int(np.count_nonzero(self.success))


class IKAllBatchResult(NamedTuple):
    """Every branch of N targets (``Robot.ik_all_batch``): up to B branches each.

    ``q`` (N, B, nq), NaN past the branches a target has (``found``, (N,)); ``success`` (N, B):
    verified by
    the kinematics back end's forward kinematics (which shares no code with the
    subproblems) to ``tol`` and within the joint limits, with each joint's angle in
    (-pi, pi] (the turns ``ik_all`` lists are left out); ``position_error`` [m],
    ``orientation_error`` [rad] (N, B); ``roots`` (N, B, 3): the shoulder, elbow and wrist
    root each branch took (0 or 1; -1 where that subproblem had one root).
    """

    q: np.ndarray
    found: np.ndarray
    success: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    roots: np.ndarray
    structure: Structure
    polished: bool = False


def turns(angles: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(K, n): every vector equal to ``angles`` up to whole turns of each joint within
    [lower, upper] (per joint, inclusive to 1e-12); a joint with no such angle keeps its
    angle wrapped to (-pi, pi] (the row then lies outside the limits)."""
    angles = np.asarray(angles, dtype=float)
    return turns_many(angles[None], lower, upper, np.zeros(len(angles), dtype=bool))[0]


def turns_of(row: np.ndarray, lo: np.ndarray, hi: np.ndarray, sliding: np.ndarray) -> np.ndarray:
    """:func:`turns` of the revolute joints of a chain's row; prismatic ones (``sliding``)
    keep their value."""
    return turns_many(np.asarray(row, dtype=float)[None], lo, hi, sliding)[0]


def turns_many(
    A: np.ndarray, lo: np.ndarray, hi: np.ndarray, sliding: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`turns` of every row of A (B, n) at once: (rows (K, n), the row of A each came
    from (K,)), each row's turns together, the last joint's turn changing fastest.
    Prismatic joints (``sliding``) keep their value."""
    turn = ~np.asarray(sliding, dtype=bool)
    a = np.array(A, dtype=float)
    a[:, turn] = np.remainder(a[:, turn] + np.pi, 2 * np.pi) - np.pi
    bounded = np.isfinite(lo) & np.isfinite(hi) & turn
    first = np.where(bounded, np.ceil((lo - 1e-12 - a) / (2 * np.pi)), 0.0)
    last = np.where(bounded, np.floor((hi + 1e-12 - a) / (2 * np.pi)), 0.0)
    empty = last < first  # no turn of this joint fits: keep the wrapped angle
    first[empty] = last[empty] = 0.0
    counts = (last - first + 1).astype(np.int64)  # (B, n)
    per = counts.prod(axis=1)
    owner = np.repeat(np.arange(len(a)), per)
    local = np.arange(len(owner)) - np.repeat(np.cumsum(per) - per, per)
    steps = np.empty((len(owner), a.shape[1]))
    for j in range(a.shape[1] - 1, -1, -1):  # mixed-radix digits, the last joint fastest
        c = counts[owner, j]
        steps[:, j] = local % c
        local //= c
    return a[owner] + 2 * np.pi * (first[owner] + steps), owner


def distinct(A: np.ndarray, sliding: np.ndarray) -> np.ndarray:
    """(B,) True for each row of joint vectors A (B, n) not equal, up to whole turns of the
    revolute joints (to 1e-9 rad or m; ``sliding`` marks prismatic ones), to an earlier row."""
    D = A[:, None] - A[None]
    D = np.where(sliding, D, np.remainder(D + np.pi, 2 * np.pi) - np.pi)
    gap = np.abs(D).max(axis=2)
    same = (gap < 1e-9) & np.tril(np.ones((len(A), len(A)), dtype=bool), -1)
    return np.asarray(~same.any(axis=1))
