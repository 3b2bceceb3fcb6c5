"""The IK loop on each kinematics back end: restarts, time budget and batches.

A loop takes a :class:`~toolkit.ik.numeric.task.PoseTask`, a start, the thread's
:class:`~toolkit.ik.numeric.solver.SolverState`, the options and a kernel seed, and returns the
best q it reached; it never judges success (:func:`solve_ik` has the answer verified
independently). :func:`loop_for` picks the loop of a back end:

* :class:`CompiledLoop` on :class:`~toolkit.kinematics.CompiledBackend`: the whole loop
  in numba (:mod:`toolkit.ik.numeric.kernels`) on the back end's packed chain;
* :class:`PinocchioLoop` on any other back end: :func:`~toolkit.ik.numeric.solver.run_pinocchio`,
  one Pinocchio call per iteration.

Both draw restarts from one stream (:meth:`SolverState.restart`), so a seed gives the same
starts on either.
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin

from ...common import PerThread
from ...kinematics import Backend, CompiledBackend, JointLayout, parallel
from . import kernels as _ik_kernels
from .options import IKOptions
from .solver import (
    DAMPING,
    LAMBDA_MIN,
    STALL,
    IKResult,
    SolverState,
    kernel_seed,
    run_pinocchio,
    verify,
)
from .task import PoseTask

__all__ = [
    "CompiledLoop",
    "IKLoop",
    "NumericIK",
    "PinocchioLoop",
    "loop_for",
    "solve_ik",
]


class IKLoop:
    """The IK with restarts on one back end (see the module doc)."""

    name = ""

    def solve(
        self, task: PoseTask, q_start: np.ndarray, state: SolverState, opts: IKOptions, seed: int
    ) -> tuple[np.ndarray, int, int]:
        """The IK with restarts: (best q, iterations, last attempt)."""
        raise NotImplementedError

    def solve_batch(
        self, tasks: list[PoseTask], Q0: np.ndarray, state: SolverState, opts: IKOptions, seed: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """N solves of one frame and mask (target i seeded seed + i): (qs, iterations);
        one after another unless the loop has a faster way."""
        qs = np.empty_like(Q0)
        iters = np.empty(len(tasks), np.int64)
        for i, task in enumerate(tasks):
            qs[i], iters[i], _ = self.solve(task, Q0[i], state, opts, seed + i)
        return qs, iters

    def solve_poses(
        self, frame_id: int, poses: np.ndarray, weights: np.ndarray, Q0: np.ndarray,
        state: SolverState, opts: IKOptions, seed: int, owner: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """:meth:`solve_batch` of checked C-contiguous ``poses`` (N, 4, 4), one mask; with
        ``owner`` (M,) int64, M starts Q0 (M, nq), start i toward poses[owner[i]]."""
        if owner is not None:
            poses = np.ascontiguousarray(poses[owner])
        return self.solve_batch(PoseTask.many(frame_id, poses, weights), Q0, state, opts, seed)


class PinocchioLoop(IKLoop):
    """:func:`~toolkit.ik.numeric.solver.run_pinocchio` from each start (any joint type)."""

    name = "pinocchio"

    def solve(
        self, task: PoseTask, q_start: np.ndarray, state: SolverState, opts: IKOptions, seed: int
    ) -> tuple[np.ndarray, int, int]:
        deadline = None if opts.time_limit is None else time.perf_counter() + opts.time_limit
        best_q, best_cost, total, attempt = q_start, np.inf, 0, 0
        for attempt in range(opts.restarts + 1):
            start = q_start if attempt == 0 else state.restart(seed, attempt)
            q, cost, iters, converged = run_pinocchio(state, task, start, opts.tol, opts.max_iter)
            total += iters
            if cost < best_cost:
                best_q, best_cost = q, cost
            if converged or (deadline is not None and time.perf_counter() > deadline):
                break
        return best_q, total, attempt


class CompiledLoop(IKLoop):
    """The loop of :func:`~toolkit.ik.numeric.solver.run_pinocchio`, step for step, compiled on a
    :class:`~toolkit.kinematics.CompiledBackend`'s packed chain."""

    name = "compiled"

    def __init__(self, backend: CompiledBackend) -> None:
        self.backend = backend
        self._packs: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def solve(
        self, task: PoseTask, q_start: np.ndarray, state: SolverState, opts: IKOptions, seed: int
    ) -> tuple[np.ndarray, int, int]:
        """(best q, iterations, last attempt). With a ``time_limit`` the attempts run in growing
        chunks and the clock is read between chunks; seeding by (seed, attempt) keeps the
        answer independent of the chunking."""
        ibuf, fbuf = self._packs.get(task.frame_id) or self.pack(task.frame_id, state)
        last, limit = opts.restarts + 1, opts.time_limit
        deadline = 0.0 if limit is None else time.perf_counter() + limit
        stop = last if limit is None else min(last, 2)
        tol, max_iter, T, w = opts.tol, opts.max_iter, task.pose, task.weights
        q, cost, iters, attempt, ok = _ik_kernels.solve(
            T, w, q_start, ibuf, fbuf, tol, max_iter, 0, stop, seed
        )
        if ok or stop == last:
            return q, int(iters), int(attempt)
        best_q, best_cost, total, chunk = q, cost, int(iters), 4
        while stop < last and time.perf_counter() <= deadline:
            start, stop = stop, min(last, stop + chunk)
            q, cost, iters, attempt, ok = _ik_kernels.solve(
                T, w, q_start, ibuf, fbuf, tol, max_iter, start, stop, seed
            )
            total += int(iters)
            if cost < best_cost:
                best_q, best_cost = q, cost
            if ok:
                break
            chunk = min(chunk * 2, 64)
        return best_q, total, int(attempt)

    def solve_batch(
        self, tasks: list[PoseTask], Q0: np.ndarray, state: SolverState, opts: IKOptions, seed: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """Every target in one compiled call (over the cores unless the batch is small: a
        thread launch costs more than a few solves)."""
        first = tasks[0]
        Ts = np.array([t.pose for t in tasks]).reshape(-1, 4, 4)
        return self.solve_poses(first.frame_id, Ts, first.weights, Q0, state, opts, seed)

    def solve_poses(
        self, frame_id: int, poses: np.ndarray, weights: np.ndarray, Q0: np.ndarray,
        state: SolverState, opts: IKOptions, seed: int, owner: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """Every start in one compiled call (no task objects, no copy of a pose per start
        where ``owner`` names each start's pose)."""
        ibuf, fbuf = self._packs.get(frame_id) or self.pack(frame_id, state)
        if owner is None:
            owner = np.arange(len(poses), dtype=np.int64)
        args = (poses, owner, weights, np.ascontiguousarray(Q0), ibuf, fbuf)
        tail = (opts.tol, opts.max_iter, opts.restarts, seed)
        qs, iters, _ = _ik_kernels.solve_batch(parallel(8 * len(Q0)), *args, *tail)
        return qs, iters

    def pack(self, frame_id: int, state: SolverState) -> tuple[np.ndarray, np.ndarray]:
        """The IK kernels' two arrays for a frame: integers (sizes, the stall count, the
        coordinate layout, the chain's joints) and floats (the damping, the clip and sample
        bounds, the tip placement, the joints' placements): a kernel call costs time per
        argument, so everything fixed travels in these two (unpacked in
        :func:`toolkit.ik.numeric.kernels._unpack`)."""
        backend = self.backend
        ints, flts, tip = backend.chain(frame_id)
        qlay = state.layout.qlay
        head = [len(ints), backend.nq, backend.nv, STALL, len(qlay)]
        ibuf = np.concatenate([np.array(head, np.int64), ints.ravel(), qlay.ravel()])
        bounds = [state.clip_lower, state.clip_upper, state.sample_lower, state.sample_upper]
        floats = [np.array([DAMPING, LAMBDA_MIN], float), *bounds, tip, flts.ravel()]
        packed = (ibuf, np.concatenate(floats))
        self._packs[frame_id] = packed
        return packed


def loop_for(backend: Backend) -> IKLoop:
    """The IK loop of a kinematics back end: compiled on the compiled one, else Pinocchio's."""
    if isinstance(backend, CompiledBackend):
        return CompiledLoop(backend)
    return PinocchioLoop()


def solve_ik(
    loop: IKLoop,
    state: SolverState,
    task: PoseTask,
    q0: np.ndarray | None = None,
    options: IKOptions | None = None,
    seed: int | None = None,
) -> IKResult:
    """Solve ``task`` from ``q0`` (default: mid-range) with seeded restarts on ``loop``, then
    verify the answer (:func:`~toolkit.ik.numeric.solver.verify`).

    The public entry point is :meth:`toolkit.Robot.ik`. ``options.time_limit`` [s] stops
    starting new restarts once that much time has passed (the TRAC-IK benchmark protocol).
    ``seed``, when given (a checked int), replaces ``options.seed``: a loop with ``seed=i``
    then needs no new options per call.
    """
    opts = IKOptions() if options is None else options
    q_start = state.mid if q0 is None else q0
    stream = kernel_seed(opts.seed if seed is None else seed)
    q, iterations, attempt = loop.solve(task, q_start, state, opts, stream)
    q = state.held(task.frame_id, q, q_start)  # the joints that do not move the frame
    return verify(state, task, q, opts.tol, iterations, attempt)


class NumericIK:
    """A robot's numeric IK (``Robot`` holds one): its model, its joint space's checks, the
    IK loop on its kinematics back end and each thread's :class:`SolverState`; what the
    batch, path and collision-free solvers take."""

    def __init__(self, model: pin.Model, joints: JointLayout, backend: Backend) -> None:
        self.model, self.joints = model, joints
        self.ik_loop: IKLoop = loop_for(backend)
        self._state = PerThread(lambda: SolverState(model, joints, joints.neutral()))

    @property
    def nq(self) -> int:
        return int(self.model.nq)

    @property
    def ik_state(self) -> SolverState:
        """The workspace of the calling thread."""
        return self._state.get()
