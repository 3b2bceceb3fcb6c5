"""Many IK targets at once: :func:`solve_batch` behind :meth:`toolkit.Robot.ik_batch`, and
:func:`solve_ik_path` (warm-started along a path) behind :meth:`toolkit.Robot.ik_path`.

Both go through the robot's back end (:mod:`toolkit.engine`): on the compiled one the
targets are spread over the machine's cores, on Pinocchio they are solved one after
another. Either way every answer is verified by an independent Pinocchio forward
kinematics, as for single solves.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from . import _validate
from ._collide import Checker
from ._task import PoseTask, parse_mask
from .errors import InvalidParameterError
from .ik import IKOptions, IKResult, PathResult, SolverState, kernel_seed

if TYPE_CHECKING:
    from .engine import Backend
    from .robot import Robot

__all__ = ["IKBatchResult"]  # solve_batch and solve_ik_path are Robot's


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


def _targets(targets: object) -> tuple[np.ndarray, bool]:
    """(new poses (N, 4, 4), position_only) of (N, 4, 4) poses or (N, 3) positions."""
    arr = _validate.array(targets, "targets")
    if arr.ndim == 2 and arr.shape[1] == 3:
        poses = np.broadcast_to(np.eye(4), (len(arr), 4, 4)).copy()
        poses[:, :3, 3] = arr
        return poses, True
    if arr.ndim != 3 or arr.shape[1:] != (4, 4):
        raise InvalidParameterError(
            f"targets must have shape (N, 4, 4) (poses) or (N, 3) (positions), got {arr.shape}"
        )
    R = arr[:, :3, :3]
    if np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)).max(initial=0.0) > 1e-6 or np.any(
        np.linalg.det(R) < 0
    ):
        raise InvalidParameterError("targets: a 3x3 block is not a rotation matrix")
    if np.abs(arr[:, 3] - [0, 0, 0, 1]).max(initial=0.0) > 1e-12:
        raise InvalidParameterError("targets: the last row of a pose must be (0, 0, 0, 1)")
    return np.array(arr, order="C"), False


def solve_batch(
    robot: Robot,
    targets: object,
    q0: ArrayLike | None,
    fid: int,
    mask: object,
    opts: IKOptions,
    backend: Backend,
    checker: Checker | None = None,
) -> IKBatchResult:
    """N solves of the same frame and mask (see :meth:`toolkit.Robot.ik_batch`); with a
    collision ``checker``, a solution that collides is solved again one start at a time
    (:func:`toolkit._collide.solve_collision_free`) until a collision-free one is found."""
    if opts.timeout is not None:
        raise InvalidParameterError("ik_batch takes no timeout: restarts bound each solve")
    poses, position_only = _targets(targets)
    w = parse_mask(mask, position_only)  # type: ignore[arg-type]
    N = len(poses)
    state: SolverState = robot.ik_state
    if q0 is None:
        Q0 = np.broadcast_to(state.mid, (N, robot.nq)).copy()
    else:
        Q0 = robot.check_q(q0, batch=True)
        Q0 = np.broadcast_to(Q0, (N, robot.nq)).copy() if Q0.ndim == 1 else Q0
        if len(Q0) != N:
            raise InvalidParameterError(f"q0 must hold 1 or {N} configurations, got {len(Q0)}")
    tasks = PoseTask.many(fid, poses, w)
    if not N:
        return _verified(robot, tasks, Q0, np.zeros(0, np.int64), opts.tol, state)
    seed = kernel_seed(opts.seed)
    qs, iters = backend.solve_batch(tasks, Q0, state, opts, seed)
    result = _verified(robot, tasks, qs, iters, opts.tol, state)
    if checker is not None:
        _collision_free(robot, tasks, Q0, result, replace(opts, seed=seed), checker)
    return result


def _collision_free(
    robot: Robot,
    tasks: list[PoseTask],
    Q0: np.ndarray,
    result: IKBatchResult,
    opts: IKOptions,
    checker: Checker,
) -> None:
    """Rows whose solution collides, solved again collision-free (in place): the starts of
    :func:`toolkit._collide.solve_collision_free` (attempt 0 from the row's start, then
    the row's restart stream), one attempt per round for every pending row at once, each
    round's solutions checked in one batch. A row with no collision-free solution keeps,
    as that function answers, its first reached (colliding) solution, success False."""
    colliding = np.zeros(len(tasks), dtype=bool)
    if result.success.any():
        colliding[result.success] = checker.in_collision_many(result.q[result.success])
    base = int(opts.seed or 0)
    state, backend = robot.ik_state, robot._backend
    single = replace(opts, restarts=0)
    pending = np.flatnonzero(colliding)
    result.success[pending] = False  # until a collision-free solution is found
    first = np.zeros(len(tasks), dtype=bool)  # rows whose first colliding solution is kept
    for attempt in range(opts.restarts + 1):
        if not len(pending):
            return
        rows = [tasks[i] for i in pending]
        if attempt == 0:
            starts = Q0[pending]
        else:
            seeds = [kernel_seed(base + int(i)) for i in pending]
            starts = np.array([state.restart(seed, attempt) for seed in seeds])
        qs, iters = backend.solve_batch(rows, starts, state, single, 0)
        found = _verified(robot, rows, qs, iters, opts.tol, state)
        free = found.success.copy()
        if free.any():
            free[free] = ~checker.in_collision_many(found.q[free])
        result.iterations[pending] += found.iterations
        keep = free | (found.success & ~first[pending])  # free, or the first reached one
        for j in np.flatnonzero(keep).tolist():
            i = int(pending[j])
            result.q[i], result.success[i] = found.q[j], bool(free[j])
            result.position_error[i] = found.position_error[j]
            result.orientation_error[i] = found.orientation_error[j]
            first[i] = True
        pending = pending[~free]


def _verified(
    robot: Robot,
    tasks: list[PoseTask],
    qs: np.ndarray,
    iters: np.ndarray,
    tol: float,
    state: SolverState,
) -> IKBatchResult:
    """Every answer checked by a Pinocchio FK on a Data object the solvers never touch."""
    data = pin.Data(robot.model)
    pos = np.empty(len(tasks))
    rot = np.empty(len(tasks))
    for i, task in enumerate(tasks):
        pos[i], rot[i] = task.errors(robot.model, data, qs[i])
    ok = state.valid_rows(qs) & (pos <= tol) & (rot <= tol)
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
    no_restart = replace(options, restarts=0, timeout=None)
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
