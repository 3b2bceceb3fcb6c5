"""Collision-free IK: the same starts as the plain solve, one at a time, until a solution
that is reached, valid and free of collision, as judged by a checker (any object with
``first_collision`` and ``in_collision_many``: :class:`toolkit.collision.Checker`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Protocol

import numpy as np

from .batch import IKBatchResult, verified
from .loops import NumericIK, solve_ik
from .options import IKOptions
from .solver import IKResult, kernel_seed, verify
from .task import PoseTask

__all__ = [
    "Collides",
    "single_solver",
    "solve_batch_collision_free",
    "solve_collision_free",
]


class Collides(Protocol):
    """What the collision-free IK asks of a collision checker."""

    def first_collision(self, q: np.ndarray) -> tuple[str, str] | None:
        """A colliding pair at q (link or object names), or None."""
        ...

    def in_collision_many(self, Q: np.ndarray) -> np.ndarray:
        """Flags (N,) of configurations Q (N, nq)."""
        ...


def solve_collision_free(
    robot: NumericIK, task: PoseTask, q0: np.ndarray | None, opts: IKOptions, checker: Collides
) -> IKResult:
    """The IK, one start at a time (the same starts as without collisions), until a
    solution that is reached, valid and collision-free; otherwise the best reached one,
    with the pair that collides (or the best unreached one)."""
    state, loop = robot.ik_state, robot.ik_loop
    seed = kernel_seed(opts.seed)
    single = replace(opts, restarts=0, time_limit=None)
    first: IKResult | None = None
    best: IKResult | None = None
    origin = state.mid if q0 is None else q0
    for attempt in range(opts.restarts + 1):
        start = origin if attempt == 0 else state.restart(seed, attempt)
        q, iters, _ = loop.solve(task, start, state, single, seed)
        q = state.held(task.frame_id, q, origin)  # the joints that do not move the frame
        res = verify(state, task, q, opts.tol, iters, attempt)
        if not res.success:
            if best is None or res.position_error < best.position_error:
                best = res
            continue
        pair = checker.first_collision(res.q)
        if pair is None:
            return res
        if first is None:
            first = res._replace(success=False, collision=pair)
    return (
        first
        if first is not None
        else (best if best is not None else verify(state, task, state.mid, opts.tol))
    )


def single_solver(
    robot: NumericIK, checker: Collides | None
) -> Callable[[PoseTask, np.ndarray | None, IKOptions], IKResult]:
    """The robot's single IK from a start (None: mid-range), collision-free when a checker
    is given: what ``Robot.ik`` and each step of ``Robot.ik_path`` run."""

    def solve(task: PoseTask, q: np.ndarray | None, opts: IKOptions) -> IKResult:
        if checker is not None:
            return solve_collision_free(robot, task, q, opts, checker)
        return solve_ik(robot.ik_loop, robot.ik_state, task, q, opts)

    return solve


def solve_batch_collision_free(
    robot: NumericIK,
    tasks: list[PoseTask],
    Q0: np.ndarray,
    result: IKBatchResult,
    opts: IKOptions,
    checker: Collides,
) -> None:
    """Rows of a batch result whose solution collides, solved again collision-free (in
    place): the starts of :func:`solve_collision_free` (attempt 0 from the row's start,
    then the row's restart stream), one attempt per round for every pending row at once,
    each round's solutions checked in one batch. A row with no collision-free solution
    keeps, as that function answers, its first reached (colliding) solution, success False.
    ``opts.seed`` is the batch's kernel seed."""
    colliding = np.zeros(len(tasks), dtype=bool)
    if result.success.any():
        colliding[result.success] = checker.in_collision_many(result.q[result.success])
    base = int(opts.seed or 0)
    state, loop = robot.ik_state, robot.ik_loop
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
        qs, iters = loop.solve_batch(rows, starts, state, single, 0)
        qs = state.held(rows[0].frame_id, qs, Q0[pending])  # as the plain batch keeps them
        found = verified(robot, rows, qs, iters, opts.tol)
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
