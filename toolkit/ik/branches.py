"""All IK branches as a result: the analytic branches of a family, each turned into a q,
repeated for every equivalent angle (q + 2 pi k) inside a joint's limits, deduplicated and
verified (``Robot.ik_all``)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import InvalidParameterError
from . import branch_kernels
from .structure import Structure

__all__ = [
    "MAX_TURN_ROWS",
    "IKAllBatchResult",
    "IKAllResult",
    "distinct",
    "distinct_each",
    "errors",
    "turns",
    "turns_many",
    "turns_of",
]


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


MAX_TURN_ROWS = 1_000_000
"""The most rows the turns of a set of branches may give (joint ranges of many turns
multiply); more is refused with an error naming the joints."""


def turns_many(
    A: np.ndarray, lo: np.ndarray, hi: np.ndarray, sliding: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`turns` of every row of A (B, n) at once: (rows (K, n), the row of A each came
    from (K,)), each row's turns together, the last joint's turn changing fastest.
    Prismatic joints (``sliding``) keep their value. Compiled
    (:mod:`toolkit.ik.branch_kernels`); an :class:`~toolkit.errors.InvalidParameterError`
    when the limits allow more than :data:`MAX_TURN_ROWS` rows."""
    a = np.ascontiguousarray(A, dtype=float)
    turn = ~np.asarray(sliding, dtype=bool)
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    a, first, counts, total = branch_kernels.turn_counts(a, lo, hi, turn)
    if total > MAX_TURN_ROWS:
        wide = [j for j in range(a.shape[1]) if counts[:, j].max() > 1]
        raise InvalidParameterError(
            f"the joint limits give {total:.3g} equivalent configurations (whole turns of "
            f"chain joints {wide}), more than {MAX_TURN_ROWS:,}: narrow the limits"
        )
    rows, owner = branch_kernels.expand_turns(a, first, counts)
    return rows, owner


def distinct(A: np.ndarray, sliding: np.ndarray) -> np.ndarray:
    """(B,) True for each row of joint vectors A (B, n) not equal, up to whole turns of the
    revolute joints (to 1e-9 rad or m; ``sliding`` marks prismatic ones), to an earlier row
    (compiled: :func:`toolkit.ik.branch_kernels.distinct_rows`)."""
    A = np.ascontiguousarray(A, dtype=float)
    return np.asarray(branch_kernels.distinct_rows(A, np.asarray(sliding, dtype=bool)))


def distinct_each(A: np.ndarray, sliding: np.ndarray) -> np.ndarray:
    """:func:`distinct` of each target's rows A (N, B, n): (N, B); NaN rows (past a target's
    branches) are never the same as another (compiled)."""
    A = np.ascontiguousarray(A, dtype=float)
    return np.asarray(branch_kernels.distinct_batch(A, np.asarray(sliding, dtype=bool)))


def errors(F: np.ndarray, target: np.ndarray, use_rot: bool) -> tuple[np.ndarray, np.ndarray]:
    """(position errors [m] (B,), orientation errors [rad] (B,)) of poses F (B, 4, 4)
    against a target (4, 4), the angle from the chord (exact to rounding near 0); the
    orientation's 0 unless ``use_rot`` (compiled)."""
    F = np.ascontiguousarray(F, dtype=float)
    pos, rot = branch_kernels.errors_rows(F, np.ascontiguousarray(target, dtype=float), use_rot)
    return np.asarray(pos), np.asarray(rot)
