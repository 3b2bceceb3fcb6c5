"""Branches near a singularity of an arm only near its analytic family (a calibrated arm):
the polish of the exact geometry's branches lands on one point of what is, on the real arm,
a curve of near-solutions; its other solutions on that curve are sought from points along
it (``Robot.ik_all`` and ``ik_all_batch`` of a polished structure)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...kinematics import CompiledBackend, parallel
from ..analytic import branch_kernels, branches
from ..analytic import structure as arm
from ..numeric import IKOptions, PoseTask

__all__ = [
    "NEAR_SINGULAR",
    "SWEEP",
    "SWEEP_ITER",
    "closeness",
    "missed_branches",
    "sigma",
    "sweep_starts",
    "turn_gap",
]

NEAR_SINGULAR = 0.005
"""A polished branch whose chain Jacobian's smallest singular value is below this has its
neighbourhood searched for the real arm's other branches (:meth:`BranchQueries._near_singular`)."""
SWEEP = np.linspace(-np.pi, np.pi, 9)[np.r_[0:4, 5:9]]
"""The steps [rad] along a near-singular branch's curve its neighbours are sought from."""


SWEEP_ITER = 20
"""The iterations a sweep start gets: one near a solution converges in a few; the others
would only spend the full budget of a polish (50)."""


def turn_gap(a: np.ndarray, b: np.ndarray, sliding: np.ndarray) -> float:
    """The largest joint difference of two rows, up to whole turns of the revolute joints."""
    d = a - b
    d = np.where(sliding, d, np.remainder(d + np.pi, 2 * np.pi) - np.pi)
    return float(np.abs(d).max())


def closeness(tol: float, small: ArrayLike) -> np.ndarray:
    """How close [rad, m] two solutions must be to count as one, where the pose fixes them
    to ``tol`` and the smallest singular value is ``small``: 10 tol / sigma, at least 1e-6."""
    sigma_min = np.maximum(np.asarray(small, dtype=float), 1e-12)
    return np.asarray(np.maximum(1e-6, 10 * tol / sigma_min))


def sweep_starts(
    A: np.ndarray, seeds: np.ndarray, direction: np.ndarray, cols: list[int]
) -> tuple[np.ndarray, np.ndarray]:
    """(starts (S * len(SWEEP), nv), the seed of each): each seed row of A moved along its
    ``direction`` (on the chain columns ``cols``) by every step of :data:`SWEEP`."""
    starts = np.repeat(A[seeds], len(SWEEP), axis=0)
    steps = direction[seeds][:, None, :] * SWEEP[None, :, None]
    starts[:, cols] += steps.reshape(-1, len(cols))
    return starts, np.repeat(seeds, len(SWEEP))


def missed_branches(
    analytic: Any, kept: list[tuple[np.ndarray, str, int]], failed: list[tuple[np.ndarray, str]],
    task: PoseTask, tol: float, chain: arm.Chain,
) -> list[tuple[np.ndarray, str, int]]:  # fmt: skip
    """Branches of an arm only near its family that the polish of the exact geometry's
    branches misses near a singularity: there the exact arm's family of solutions is
    the real arm's curve of near-solutions, on which its solutions lie apart (the audit:
    a calibrated UR5 with q5 near +-pi). From each polished branch, and each start that
    did not converge, whose chain Jacobian's smallest singular value is below
    :data:`NEAR_SINGULAR`, the IK runs from points along that curve's direction (the
    last right singular vector) over a whole turn (:data:`SWEEP`; all in one compiled
    batch); each new solution (farther from every listed one than the angles are fixed
    there, 10 tol / sigma, at least 1e-6) is listed."""
    cols = list(chain.columns)
    rows = 6 if task.weights[3:].any() else 3
    A = np.array([v for v, _, _ in kept] + [v for v, _ in failed]).reshape(-1, analytic.model.nv)
    if not len(A):
        return []
    labels = [label for _, label, _ in kept] + [label for _, label in failed]
    small, direction = sigma(analytic, A, task.frame_id, cols, rows)
    seeds = np.flatnonzero(small < NEAR_SINGULAR)
    if not len(seeds):
        return []
    starts, owner = sweep_starts(A, seeds, direction, cols)
    if rows == 3 or len(cols) != analytic.model.nv:  # a point, or locked joints: the chain's
        done = [analytic._newton(v, task, cols) for v in starts]  # own joints alone
        Q = np.array([r.q for r in done]).reshape(-1, analytic.model.nq)
    else:
        opts = IKOptions(tol=tol, max_iter=SWEEP_ITER, restarts=0)
        poses = np.ascontiguousarray(np.broadcast_to(task.pose, (len(starts), 4, 4)))
        Q0 = analytic.joints.q_from_angles(starts)
        numeric = analytic.numeric
        Q, _ = numeric.ik_loop.solve_poses(task.frame_id, poses, np.ones(6), Q0, numeric.ik_state,
                                           opts, 0)  # fmt: skip
    pos, rot = branches.errors(analytic.kinematics.fk(Q, task.frame_id), task.pose, rows == 6)
    good = np.flatnonzero((pos <= tol) & (rot <= tol))
    if not len(good):
        return []
    B = analytic.joints.angles(Q[good])
    near, _ = sigma(analytic, B, task.frame_id, cols, rows)
    listed = list(zip(A[: len(kept)], closeness(tol, small[: len(kept)]), strict=True))
    out: list[tuple[np.ndarray, str, int]] = []
    for a, sg, k in zip(B, near, owner[good].tolist(), strict=True):
        if any(turn_gap(a[cols], b[cols], chain.sliding) < close for b, close in listed):
            continue
        listed.append((a, float(closeness(tol, sg))))
        out.append((a, f"{labels[k]}, near-singular {len(out) + 1}", 0))
    return out


def sigma(
    analytic: Any, A: np.ndarray, frame_id: int, cols: list[int], rows: int,
    below: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(smallest singular values (B,), their right singular vectors (B, n)) of the chain
    Jacobians at rows A (B, nv) (one value per joint), by the kinematics back end
    (compiled: :func:`toolkit.ik.analytic.branch_kernels.smallest_singular`). With
    ``below``, the rows proven to have a smallest singular value of at least ``below``
    (:func:`~toolkit.ik.analytic.branch_kernels.singular_at_least`) get inf and a zero
    vector instead: only the others are computed."""
    Q = np.ascontiguousarray(analytic.joints.q_from_angles(A), dtype=float)
    backend = analytic.kinematics
    if below is None:
        J = np.ascontiguousarray(backend.jacobian(Q, frame_id)[:, :rows, cols])
        small, vec = branch_kernels.smallest_singular(parallel(len(J)), J)
        return small, vec
    if isinstance(backend, CompiledBackend):  # the screen makes each Jacobian itself
        chain = (*backend.chain(frame_id), int(backend.nv))
        far = np.asarray(branch_kernels.singular_at_least_at(
            parallel(len(Q)), Q, chain, rows, np.asarray(cols, np.int64), float(below)
        ))  # fmt: skip
    else:
        J = np.ascontiguousarray(backend.jacobian(Q, frame_id)[:, :rows, cols])
        far = np.asarray(branch_kernels.singular_at_least(parallel(len(J)), J, float(below)))
    small, vec = np.full(len(Q), np.inf), np.zeros((len(Q), len(cols)))
    near = np.flatnonzero(~far)
    if len(near):
        J = np.ascontiguousarray(backend.jacobian(Q[near], frame_id)[:, :rows, cols])
        small[near], vec[near] = branch_kernels.smallest_singular(parallel(len(near)), J)
    return small, vec
