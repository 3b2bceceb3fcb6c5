"""All IK branches as a result: the analytic branches of a family, each turned into a q,
repeated for every equivalent angle (q + 2 pi k) inside a joint's limits, deduplicated and
verified (``Robot.ik_all``)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ...errors import InvalidParameterError
from . import branch_kernels
from .family import Family
from .structure import Structure

__all__ = [
    "MAX_TURN_ROWS",
    "IKAllBatchResult",
    "IKAllResult",
    "distinct",
    "distinct_each",
    "errors",
    "free_joints",
    "reverse_bits",
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
    only near its family (or exact only to more than ``tol``) and each branch was polished
    on the real model; ``lost``: branches of the nearest exact geometry that did not
    converge on the real model or merged with another; ``branch`` (B,): the branch each row
    is a turn of (rows with the same number differ by whole turns of joints); ``free``
    (B,): per row, the joints left free at a singular pose (every angle of them, with the
    others following, puts the frame on the target; the row is the representative whose
    free joints take ``q0``'s angles), () for a regular row; ``target_moved`` [rad]:
    how far the target's rotation was moved to the nearest rotation matrix before solving
    (0 for an orthonormal one; float32 and rounded targets are projected, and the errors
    are measured against the projection); ``reason``: why no row succeeds (out of reach,
    with how far the numeric IK's nearest pose stays; an orientation a 5-joint arm cannot
    hold, with the nearest row; outside the joint limits, naming the joints), "" when a
    row succeeds.
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
    branch: np.ndarray = np.zeros(0, np.int64)
    free: tuple[tuple[str, ...], ...] = ()
    target_moved: float = 0.0
    reason: str = ""

    @property
    def solved(self) -> int:
        """How many distinct branches have a successful row (rows are turns of a branch:
        see :attr:`rows_solved`)."""
        return len(set(self.branch[self.success].tolist()))

    @property
    def rows_solved(self) -> int:
        """How many rows succeeded (every turn of every branch)."""
        return int(np.count_nonzero(self.success))

    @property
    def singular(self) -> np.ndarray:
        """(B,) True where the row is a singular pose's representative (:attr:`free`)."""
        return np.array([bool(f) for f in self.free], dtype=bool)


class IKAllBatchResult(NamedTuple):
    """Every branch of N targets (``Robot.ik_all_batch``): up to B branches each.

    ``q`` (N, B, nq), NaN past the branches a target has (``found``, (N,)); ``success`` (N, B):
    verified by
    the kinematics back end's forward kinematics (which shares no code with the
    subproblems) to ``tol`` and within the joint limits, each revolute joint's angle the
    lowest of its turns within the limits (one of the rows ``ik_all`` lists; the wrapped
    angle in [-pi, pi) where no turn fits, and the row is then outside); ``position_error`` [m],
    ``orientation_error`` [rad] (N, B); ``roots`` (N, B, 3): the roots each branch took, in
    its family's order (a 6R arm's shoulder, elbow and wrist; 0 or 1, -1 where that
    subproblem had one root; :meth:`~toolkit.ik.analytic.family.Family.label` names them);
    ``free`` (N, B): the chain joints left free at a singular pose (bit j: the chain's
    joint j; 0 for a regular branch), their angles taken from ``q0``; ``target_moved``
    (N,) [rad]: how far each target's rotation was moved to the nearest rotation matrix;
    ``within_limits`` (N, B). :meth:`target` reads one target's rows as :class:`IKAllResult`.
    """

    q: np.ndarray
    found: np.ndarray
    success: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    roots: np.ndarray
    structure: Structure
    polished: bool = False
    free: np.ndarray = np.zeros((0, 0), np.int64)
    target_moved: np.ndarray = np.zeros(0)
    within_limits: np.ndarray = np.zeros((0, 0), bool)

    def target(self, i: int) -> IKAllResult:
        """Target ``i``'s rows as :meth:`toolkit.Robot.ik_all` gives them for that target
        alone (one row per branch, the same rows in the same order), labelled in the
        family's words; ``lost`` (0 here) and ``reason`` ("") are ``ik_all``'s own."""
        if not isinstance(i, int | np.integer) or not -len(self.found) <= i < len(self.found):
            raise InvalidParameterError(
                f"target must be an index into the {len(self.found)} targets, got {i!r:.40}"
            )
        k, found = int(self.found[i]), self.structure
        family = Family(found.family)
        roots = self.roots[i, :k].tolist()
        return IKAllResult(
            q=self.q[i, :k],
            success=self.success[i, :k],
            within_limits=self.within_limits[i, :k],
            labels=[family.label(tuple(r), found.reversed) for r in roots],
            position_error=self.position_error[i, :k],
            orientation_error=self.orientation_error[i, :k],
            structure=found,
            polished=self.polished,
            branch=np.arange(k, dtype=np.int64),
            free=tuple(free_joints(int(b), found.joints) for b in self.free[i, :k].tolist()),
            target_moved=float(self.target_moved[i]),
        )


def free_joints(bits: int, names: tuple[str, ...]) -> tuple[str, ...]:
    """The names of the chain joints (``names``) whose bits are set in ``bits`` (bit j:
    joint j): the joints a singular pose leaves free."""
    return tuple(name for j, name in enumerate(names) if bits >> j & 1)


def reverse_bits(bits: np.ndarray, n: int) -> np.ndarray:
    """Free-joint bits of a chain read from its frame
    (:func:`toolkit.ik.analytic.structure.reverse`) as bits of the chain from its base
    (joint j is joint n - 1 - j)."""
    out = np.zeros_like(bits)
    for j in range(n):
        out |= ((bits >> j) & 1) << (n - 1 - j)
    return out


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
    (:mod:`toolkit.ik.analytic.branch_kernels`); an :class:`~toolkit.errors.InvalidParameterError`
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
    (compiled: :func:`toolkit.ik.analytic.branch_kernels.distinct_rows`)."""
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
