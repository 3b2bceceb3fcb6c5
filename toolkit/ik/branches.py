"""All IK branches as a result: the analytic branches of a family, each turned into a q,
repeated for every equivalent angle (q + 2 pi k) inside a joint's limits, deduplicated and
verified (``Robot.ik_all``)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .structure import Structure

__all__ = ["IKAllBatchResult", "IKAllResult", "distinct", "turns", "turns_of"]


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
    a = np.remainder(angles + np.pi, 2 * np.pi) - np.pi
    bounded = np.isfinite(lower) & np.isfinite(upper)
    first = np.where(bounded, np.ceil((lower - 1e-12 - a) / (2 * np.pi)), 0.0)
    last = np.where(bounded, np.floor((upper + 1e-12 - a) / (2 * np.pi)), 0.0)
    empty = last < first  # no turn of this joint fits: keep the wrapped angle
    first[empty] = last[empty] = 0.0
    if (first == last).all():  # one turn per joint (most arms): no grid to build
        return (a + 2 * np.pi * first)[None]
    choices = [
        a_j + 2 * np.pi * np.arange(f, l_ + 1) for a_j, f, l_ in zip(a, first, last, strict=True)
    ]
    grid = np.meshgrid(*choices, indexing="ij")
    return np.stack([g.ravel() for g in grid], axis=1)


def turns_of(row: np.ndarray, lo: np.ndarray, hi: np.ndarray, sliding: np.ndarray) -> np.ndarray:
    """:func:`turns` of the revolute joints of a chain's row; prismatic
    ones (``sliding``) keep their value."""
    turn = ~sliding
    chosen = turns(row[turn], lo[turn], hi[turn])
    out = np.repeat(row[None], len(chosen), axis=0)
    out[:, turn] = chosen
    return out


def distinct(A: np.ndarray, sliding: np.ndarray) -> np.ndarray:
    """(B,) True for each row of joint vectors A (B, n) not equal, up to whole turns of the
    revolute joints (to 1e-9 rad or m; ``sliding`` marks prismatic ones), to an earlier row."""
    D = A[:, None] - A[None]
    D = np.where(sliding, D, np.remainder(D + np.pi, 2 * np.pi) - np.pi)
    gap = np.abs(D).max(axis=2)
    same = (gap < 1e-9) & np.tril(np.ones((len(A), len(A)), dtype=bool), -1)
    return np.asarray(~same.any(axis=1))
