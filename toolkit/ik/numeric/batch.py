"""Many IK targets at once: :func:`solve_batch` behind :meth:`toolkit.Robot.ik_batch`, and
:func:`solve_ik_path` (warm-started along a path) behind :meth:`toolkit.Robot.ik_path`.

Both go through the robot's back end (:mod:`toolkit.kinematics.backends`): on the compiled one the
targets are spread over the machine's cores, on Pinocchio they are solved one after
another. Either way every answer is verified by an independent Pinocchio forward
kinematics, as for single solves.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ...common import validate as _validate
from ...errors import InvalidParameterError
from ..targets import parse_mask
from .loops import NumericIK
from .options import IKOptions
from .solver import IKResult, PathResult, SolverState, kernel_seed
from .task import PoseTask

__all__ = [
    "IKBatchResult",
    "batch_targets",
    "check_poses",
    "solve_batch",
    "solve_ik_path",
    "verified",
]


class IKBatchResult(NamedTuple):
    """Outcome of N IK solves; each row means what an :class:`toolkit.ik.IKResult` means."""

    q: np.ndarray  # (N, nq)
    success: np.ndarray  # (N,) bool
    position_error: np.ndarray  # (N,) [m]
    orientation_error: np.ndarray  # (N,) [rad]
    iterations: np.ndarray  # (N,) int

    @property
    def success_rate(self) -> float:
        return float(np.mean(self.success)) if len(self.success) else 0.0


def batch_targets(targets: object, *, rotations: bool = True) -> tuple[np.ndarray, bool]:
    """(new poses (N, 4, 4), position_only) of (N, 4, 4) poses or (N, 3) positions, every
    pose checked (:func:`check_poses`; not with ``rotations=False``: for a caller whose
    compiled path checks each pose itself and calls :func:`check_poses` where one fails)."""
    arr = _validate.array(targets, "targets")
    if arr.ndim == 2 and arr.shape[1] == 3:
        poses = np.broadcast_to(np.eye(4), (len(arr), 4, 4)).copy()
        poses[:, :3, 3] = arr
        return poses, True
    if arr.ndim != 3 or arr.shape[1:] != (4, 4):
        raise InvalidParameterError(
            f"targets must have shape (N, 4, 4) (poses) or (N, 3) (positions), got {arr.shape}"
        )
    if rotations:
        check_poses(arr)
    return np.array(arr, order="C"), False


def check_poses(arr: np.ndarray) -> None:
    """An :class:`InvalidParameterError` where a pose of (N, 4, 4) finite ``arr`` has a 3x3
    block that is not a rotation (R^T R = I within 1e-6, det R > 0) or a last row that is
    not (0, 0, 0, 1) within 1e-12 (the compiled :func:`toolkit.ik.checks.check_pose`'s
    criteria)."""
    R = arr[:, :3, :3]
    if np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)).max(initial=0.0) > 1e-6 or np.any(
        np.linalg.det(R) < 0
    ):
        raise InvalidParameterError("targets: a 3x3 block is not a rotation matrix")
    if np.abs(arr[:, 3] - [0, 0, 0, 1]).max(initial=0.0) > 1e-12:
        raise InvalidParameterError("targets: the last row of a pose must be (0, 0, 0, 1)")


def batch_starts(robot: NumericIK, q0: ArrayLike | None, n: int) -> np.ndarray:
    """(n, nq) starts of a batch: q0 (checked) for all, default mid-range, or one each."""
    if q0 is None:
        return np.broadcast_to(robot.ik_state.mid, (n, robot.nq)).copy()
    Q0 = robot.joints.check(q0, batch=True)
    Q0 = np.broadcast_to(Q0, (n, robot.nq)).copy() if Q0.ndim == 1 else Q0
    if len(Q0) != n:
        raise InvalidParameterError(f"q0 must hold 1 or {n} configurations, got {len(Q0)}")
    return np.ascontiguousarray(Q0, dtype=float)


def solve_batch(
    robot: NumericIK, targets: object, q0: ArrayLike | None, fid: int, mask: object, opts: IKOptions
) -> tuple[IKBatchResult, list[PoseTask], np.ndarray, int]:
    """N solves of the same frame and mask (see :meth:`toolkit.Robot.ik_batch`): the
    verified result, the tasks, the starts and the kernel seed (what a collision-free pass,
    :func:`toolkit.ik.numeric.collision_free.solve_batch_collision_free`, starts from)."""
    if opts.time_limit is not None:
        raise InvalidParameterError("ik_batch takes no time_limit: restarts bound each solve")
    poses, position_only = batch_targets(targets)
    w = parse_mask(mask, position_only)  # type: ignore[arg-type]
    N = len(poses)
    state: SolverState = robot.ik_state
    Q0 = batch_starts(robot, q0, N)
    tasks = PoseTask.many(fid, poses, w)
    seed = kernel_seed(opts.seed)
    if not N:
        return verified(robot, tasks, Q0, np.zeros(0, np.int64), opts.tol), tasks, Q0, seed
    qs, iters = robot.ik_loop.solve_batch(tasks, Q0, state, opts, seed)
    qs = state.held(fid, qs, Q0)  # the joints that do not move the frame at their starts
    return verified(robot, tasks, qs, iters, opts.tol), tasks, Q0, seed


def verified(
    robot: NumericIK, tasks: list[PoseTask], qs: np.ndarray, iters: np.ndarray, tol: float
) -> IKBatchResult:
    """Every answer checked by a Pinocchio FK on a Data object the solvers never touch."""
    data = pin.Data(robot.model)
    pos = np.empty(len(tasks))
    rot = np.empty(len(tasks))
    for i, task in enumerate(tasks):
        pos[i], rot[i] = task.errors(robot.model, data, qs[i])
    ok = robot.ik_state.valid_rows(qs) & (pos <= tol) & (rot <= tol)
    return IKBatchResult(qs, ok, pos, rot, iters)


def solve_ik_path(
    solve: Callable[[PoseTask, np.ndarray, IKOptions], IKResult],
    state: SolverState,
    tasks: Sequence[PoseTask],
    q0: np.ndarray | None,
    options: IKOptions,
    max_jump: float,
) -> PathResult:
    """Warm-started IK along tasks: each solve starts from the previous answer.

    ``solve(task, start, options)`` is the robot's single IK (collision-free or not). A
    neighbour is first solved with no restart (so the branch is kept); only if that fails
    are seeded restarts tried. Any step whose largest joint change exceeds ``max_jump`` is
    reported in ``jumps``; the first step whose best q collides, in ``collision_step``.
    """
    q_prev = state.mid if q0 is None else q0
    no_restart = replace(options, restarts=0, time_limit=None)
    results = []
    for k, task in enumerate(tasks):
        res = solve(task, q_prev, no_restart)
        if not res.success and options.restarts > 0:
            retry = solve(task, q_prev, options)
            res = retry if retry.success or k == 0 else res
        results.append(res)
        q_prev = res.q
    qs = np.array([r.q for r in results])
    steps = np.abs(np.diff(qs, axis=0)).max(axis=1) if len(qs) > 1 else np.zeros(0)
    return PathResult(
        q=qs,
        success=np.array([r.success for r in results]),
        position_error=np.array([r.position_error for r in results]),
        orientation_error=np.array([r.orientation_error for r in results]),
        jumps=[int(i) + 1 for i in np.nonzero(steps > max_jump)[0]],
        max_step=float(steps.max()) if len(steps) else 0.0,
        collision_step=next((k for k, r in enumerate(results) if r.collision), None),
    )
