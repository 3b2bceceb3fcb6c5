"""A robot's inverse kinematics (a part of :class:`~toolkit.robot.Robot`): ``ik``,
``ik_batch`` and ``ik_path`` on the numeric solvers and the robot's :class:`AnalyticIK`,
collision-free with the checker the robot gives for a scene."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from ...collision import Checker, Scene
from ...common import caller_level
from ...common import validate as _validate
from ...errors import InvalidParameterError, UnreachableTargetsWarning
from ..analytic import BranchDoor
from ..numeric import (
    IKBatchResult,
    IKOptions,
    IKResult,
    PathResult,
    PoseTask,
    batch_starts,
    batch_targets,
    single_solver,
    solve_batch,
    solve_batch_collision_free,
    solve_ik,
    solve_ik_path,
)
from . import doors
from .batches import AnalyticIK

__all__ = ["BRANCH_TOL", "IKRequest", "RobotIK"]

BRANCH_TOL = 1e-9
"""[m, rad] An analytic answer of ``ik`` and ``ik_batch`` is verified to this, or to the
options' tol where that is tighter."""


_METHODS = ("numeric", "analytic", "auto")


def _method(value: object) -> str:
    """``value`` if it is one of the IK methods, else the error listing them."""
    if type(value) is str and value in _METHODS:
        return value
    return _validate.one_of(value, "method", _METHODS)


def _plain(method: object, overrides: Mapping[str, object], *rest: object) -> bool:
    """A single IK the compiled door may answer as it is: the method ``"auto"`` or
    ``"analytic"``, no ``overrides``, and no mask, options, scene or collision setting
    (``rest``); :func:`toolkit.ik.solvers.doors.door_pose` then decides on the target (a
    float64 array: a 4x4 pose, or a position)."""
    if type(method) is not str or (method != "auto" and method != "analytic") or overrides:
        return False
    for r in rest:
        if r is not None:
            return False
    return True


@dataclass(frozen=True)
class IKRequest:
    """What ``ik``, ``ik_batch`` and ``ik_path`` share, checked once: the frame, the options
    (with their keyword overrides applied) and the collision checker (None: none asked)."""

    frame_id: int
    options: IKOptions
    checker: Checker | None


class RobotIK:
    """A robot's IK (``robot.ik``, ``ik_batch``, ``ik_path`` are its methods): the numeric
    solvers of :mod:`toolkit.ik` and the analytic branches of the robot's
    :class:`~toolkit.ik.solvers.batches.AnalyticIK`, collision-free on its checkers (``checker_of``:
    the robot's checker for a scene and a ``collision_free`` setting)."""

    def __init__(
        self,
        analytic: AnalyticIK,
        checker_of: Callable[[Scene | None, bool | None], Checker | None],
    ) -> None:
        self.analytic, self.checker_of, self.numeric = analytic, checker_of, analytic.numeric
        self.model, self.name = analytic.model, analytic.name
        self.joints, self.frames = analytic.joints, analytic.frames
        self._plain_doors: dict[tuple[str | None, str], BranchDoor | None] = {}

    def _by_branches(
        self, task: PoseTask, start: np.ndarray | None, opts: IKOptions, method: str,
        checker: Checker | None,
    ) -> IKResult | None:  # fmt: skip
        """The analytic answer of ``ik`` (None: leave it to the numeric solver): the verified
        branch nearest ``start``, collision-free with a checker. A full pose on an exact
        compiled family goes through its door first (``ik_path``'s targets, one after
        another, keep their Python short)."""
        tol = min(opts.tol, BRANCH_TOL)
        door = self._exact_door(task.frame_id, tol, method)
        if door is None and method == "auto":  # no exact family: the numeric solver answers
            return None
        w = task.weights
        if door is not None:  # a full pose, or a point for a family placing one
            places = door.places
            if bool(w[:3].all()) and (not w[3:].any() if places else bool(w[3:].all())):
                answered, answer = doors.nearest_verified(self.analytic, door, task.pose,
                                                          start, tol, checker)  # fmt: skip
                if answered:  # else: to polish or to project, as ik_all does
                    return answer
        found = self.analytic.structure_of(self.model.frames[task.frame_id].name)
        places = found.places_point  # a 3-joint arm: its targets are points
        fits = bool(w[:3].all()) and (not w[3:].any() if places else bool(w[3:].all()))
        if method == "analytic" and not fits:
            raise InvalidParameterError(
                f"method='analytic' needs a {'position' if places else 'full pose'}, without a mask"
            )
        if method == "auto" and not (fits and door is not None):
            return None
        try:
            return self.analytic._analytic_ik(task, start, tol, checker)
        except InvalidParameterError:  # limits of too many turns to list: auto goes numeric
            if method == "auto":
                return None
            raise

    def _exact_door(self, fid: int, tol: float, method: str = "auto") -> BranchDoor | None:
        """The door of the frame's chain where it has an exact compiled family at ``tol``
        (for ``method="auto"`` a closed-form one: where it answers by branches), else None."""
        door = self.analytic._door(fid)
        if door is None or not door.exact(tol) or (method == "auto" and door.searched):
            return None
        return door

    def _door_ik(
        self, pose: np.ndarray, q0: ArrayLike | None, frame: str | None, method: str
    ) -> IKResult | None:
        """``ik`` of a plain pose (:func:`_plain`) in one compiled call where the frame's
        chain has an exact compiled family: its nearest verified branch; None otherwise. The
        door of each frame asked by name is kept here (a dictionary read, no lock)."""
        named = frame is None or type(frame) is str
        key = (frame, method)
        if named and key in self._plain_doors:
            door = self._plain_doors[key]
        else:
            door = self._exact_door(self.frames.id(frame), BRANCH_TOL, method)
            if named:  # a checked name: kept
                self._plain_doors[key] = door
        target = None if door is None else doors.door_pose(door, pose)
        if door is None or target is None:  # e.g. a pose for an arm placing a point
            return None
        return doors.nearest_verified(self.analytic, door, target, q0, BRANCH_TOL)[1]

    def _solver(
        self, method: object, checker: Checker | None
    ) -> Callable[[PoseTask, np.ndarray | None, IKOptions], IKResult]:
        """The single IK ``method`` asks for: numeric, or analytic (the branch nearest the
        start, numeric when no branch succeeds)."""
        method = _method(method)
        numeric = single_solver(self.numeric, checker)
        if method == "numeric":
            return numeric

        def solve(task: PoseTask, start: np.ndarray | None, opts: IKOptions) -> IKResult:
            answer = self._by_branches(task, start, opts, method, checker)
            return numeric(task, start, opts) if answer is None else answer

        return solve

    def _request(
        self,
        frame: str | None,
        options: IKOptions | None,
        scene: Scene | None,
        collision_free: bool | None,
        overrides: Mapping[str, object] | None = None,
    ) -> IKRequest:
        opts = IKOptions.build(options, **(overrides or {}))
        checker = self.checker_of(scene, collision_free)
        return IKRequest(self.frames.id(frame), opts, checker)

    # ------------------------------------------------------------------ inverse kinematics
    def ik(
        self,
        target: object,
        q0: ArrayLike | None = None,
        *,
        frame: str | None = None,
        mask: ArrayLike | None = None,
        options: IKOptions | None = None,
        scene: Scene | None = None,
        collision_free: bool | None = None,
        method: str = "auto",
        **overrides: object,
    ) -> IKResult:
        """Joint values that put ``frame`` (default: the tip) on ``target``.

        By default an arm with an exact closed-form family (not the search) answers a full
        pose (a position, for a family placing a point) by its branch nearest ``q0``,
        verified by an independent forward kinematics to 1e-9 (or a tighter ``tol``) and
        within the limits (``iterations`` 0); anything else goes to the numeric solver:
        damped least squares with adaptive (Levenberg-Marquardt) damping on Pinocchio's
        frame Jacobian, steps within the joint limits, a stalled start restarted from seeded
        random configurations (same ``seed``, same answer). See :mod:`toolkit.ik`, docs/ik.md.

        Args:
            target: 4x4 pose in the base frame, or a 3-vector position (position only).
            q0: start configuration (default: the middle of the joint ranges).
            mask: six weights (x, y, z, rx, ry, rz); positions in base axes, rotations
                about the tool frame's own axes, so ``(1, 1, 1, 1, 1, 0)`` frees the roll
                about the tool z axis.
            options: an :class:`~toolkit.ik.IKOptions`; keyword ``overrides`` set its
                fields one by one: ``tol`` (1e-6, on position [m] and orientation [rad]),
                ``max_iter`` (100, per start), ``restarts`` (500), ``seed`` (0) and
                ``time_limit`` (None: the seconds after which no restart begins).
            method: ``"auto"`` (the default, as above; numeric where no branch is
                verified), ``"numeric"`` (the solution the numeric solver converges to
                from ``q0``) or ``"analytic"`` (the verified branch of :meth:`ik_all`
                nearest ``q0`` on any arm with a structure, calibrated arms included; an
                error without one). With a scene, the nearest collision-free branch, then
                the numeric collision-free solver.

        Returns:
            :class:`toolkit.ik.IKResult`; an unreachable target gives ``success=False`` with
            the best q found and its residuals (it never raises for that)."""
        plain = _plain(method, overrides, mask, options, scene, collision_free)
        if plain and (answer := self._door_ik(target, q0, frame, method)):  # type: ignore[arg-type]
            return answer
        method = _method(method)
        opts, seed = IKOptions.split(options, overrides)
        task = PoseTask.from_target(self.frames.id(frame), target, mask)
        start = None if q0 is None else self.joints.check(q0)
        if method != "numeric":
            checker = self.checker_of(scene, collision_free)
            if (answer := self._by_branches(task, start, opts, method, checker)) is not None:
                return answer
        if scene is None and collision_free is None:  # the plain solve, without a checker
            return solve_ik(self.numeric.ik_loop, self.numeric.ik_state, task, start, opts, seed)
        if seed is not None:
            opts = IKOptions.build(opts, seed=seed)
        checker = self.checker_of(scene, collision_free)
        return single_solver(self.numeric, checker)(task, start, opts)

    def ik_batch(
        self,
        targets: ArrayLike,
        q0: ArrayLike | None = None,
        *,
        frame: str | None = None,
        mask: ArrayLike | None = None,
        options: IKOptions | None = None,
        scene: Scene | None = None,
        collision_free: bool | None = None,
        method: str = "auto",
        **overrides: object,
    ) -> IKBatchResult:
        """N targets at once ((N, 4, 4) poses or (N, 3) positions): an
        :class:`~toolkit.ik.IKBatchResult` of arrays. Options, ``scene`` and
        ``collision_free`` as for :meth:`ik` (no ``time_limit``); target i is restarted from
        seed + i. Spread over the machine's cores on the compiled engine; every answer
        verified as in :meth:`ik`. ``method`` as for :meth:`ik`: ``"analytic"`` and
        ``"auto"`` answer each target with its verified branch nearest its start (q0, one
        for all or one per target) from one compiled call on an exact compiled family
        (``iterations`` 0), the targets without one numerically; ``"analytic"`` on another
        arm with a structure solves target by target as :meth:`ik` does."""
        method = _method(method)
        r = self._request(frame, options, scene, collision_free, overrides)
        if method != "numeric":
            where = (scene, collision_free)
            answer = self._batch_by_branches(targets, q0, mask, r, method, where)
            if answer is not None:
                return answer
        robot = self.numeric
        result, tasks, Q0, seed = solve_batch(robot, targets, q0, r.frame_id, mask, r.options)
        if r.checker is not None and len(tasks):
            opts = replace(r.options, seed=seed)
            solve_batch_collision_free(robot, tasks, Q0, result, opts, r.checker)
        if len(tasks) and not result.success.all():
            self._warn_if_too_few_joints(r.frame_id, tasks[0].weights, result)
        return result

    def _batch_by_branches(
        self, targets: ArrayLike, q0: ArrayLike | None, mask: ArrayLike | None, r: IKRequest,
        method: str, where: tuple[Scene | None, bool | None],
    ) -> IKBatchResult | None:  # fmt: skip
        """:meth:`ik_batch` by branches (None: leave it to the numeric solver); ``where``:
        the scene and collision_free arguments as given."""
        poses, position_only = batch_targets(targets)
        tol = min(r.options.tol, BRANCH_TOL)
        door = self._exact_door(r.frame_id, tol, method)
        frame = self.model.frames[r.frame_id].name
        places = self.analytic.structure_of(frame).places_point  # its targets are points
        if mask is not None or position_only != places or door is None:
            if method == "auto":
                return None
            if position_only != places or mask is not None:
                raise InvalidParameterError(
                    f"method='analytic' needs {'positions' if places else 'full poses'}, "
                    "without a mask"
                )
            Q0 = batch_starts(self.numeric, q0, len(poses))
            rows = [self.ik(T[:3, 3] if places else T, q, frame=frame, options=r.options,
                            method="analytic", scene=where[0], collision_free=where[1])
                    for T, q in zip(poses, Q0, strict=True)]  # fmt: skip
            return IKBatchResult(np.array([a.q for a in rows]).reshape(len(poses), -1),
                                 np.array([a.success for a in rows], dtype=bool),
                                 np.array([a.position_error for a in rows], dtype=float),
                                 np.array([a.orientation_error for a in rows], dtype=float),
                                 np.array([a.iterations for a in rows], np.int64))  # fmt: skip
        Q0 = batch_starts(self.numeric, q0, len(poses))
        q, found, pos, rot = doors.nearest_branches(self.analytic, door, poses, Q0, tol, r.checker)
        result = IKBatchResult(q, found, pos, rot, np.zeros(len(poses), np.int64))
        missing = np.flatnonzero(~found)
        if len(missing):  # no verified (collision-free) branch: the numeric solver
            again = poses[missing][:, :3, 3] if places else poses[missing]
            rest = self.ik_batch(again, Q0[missing], frame=frame, options=r.options,
                                 scene=where[0], collision_free=where[1],
                                 method="numeric")  # fmt: skip
            for whole, part in zip(result, rest, strict=True):
                whole[missing] = part
        return result

    def _warn_if_too_few_joints(self, fid: int, weights: np.ndarray, result: IKBatchResult) -> None:
        frame = self.model.frames[fid].name
        rank, fixed = self.frames.rank(frame), int(np.count_nonzero(weights))
        if rank < fixed:
            warnings.warn(
                f"{len(result.success) - int(result.success.sum())} of {len(result.success)} "
                f"targets not reached: {self.name}'s joints move {frame} in {rank} independent "
                f"directions, fewer than the {fixed} each target fixes: give (N, 3) positions, "
                f"or a mask that frees {fixed - rank} direction(s) its joints do not control",
                UnreachableTargetsWarning,
                stacklevel=caller_level(),
            )

    def ik_path(
        self,
        targets: Sequence[object] | np.ndarray,
        q0: ArrayLike | None = None,
        *,
        frame: str | None = None,
        mask: ArrayLike | None = None,
        max_jump: float = 0.5,
        options: IKOptions | None = None,
        scene: Scene | None = None,
        collision_free: bool | None = None,
        method: str = "auto",
        **overrides: object,
    ) -> PathResult:
        """Warm-started IK along a sequence of targets (see :func:`toolkit.ik.solve_ik_path`).

        Options, ``scene``, ``collision_free`` and ``method`` as for :meth:`ik`: with
        ``"analytic"`` (or ``"auto"`` on an arm with a structure) each target takes the
        verified branch nearest the previous answer, so the path keeps its branch (shoulder,
        elbow, wrist) and changes it only where that branch leaves the limits or collides;
        a target no branch reaches is solved numerically. Returns a
        :class:`toolkit.ik.PathResult`: q per target, success flags, residuals, the indices
        where a joint jumped by more than ``max_jump`` [rad or m], and the first colliding
        step.
        """
        r = self._request(frame, options, scene, collision_free, overrides)
        max_jump = _validate.number(max_jump, "max_jump", lower=0.0, strict=True)
        if isinstance(targets, str | bytes) or not hasattr(targets, "__iter__"):
            raise InvalidParameterError(f"targets must be a sequence of poses, got {targets!r}")
        tasks = [PoseTask.from_target(r.frame_id, t, mask) for t in targets]
        if not tasks:
            raise InvalidParameterError("ik_path needs at least one target")
        start = None if q0 is None else self.joints.check(q0)
        solve = self._solver(method, r.checker)
        return solve_ik_path(solve, self.numeric.ik_state, tasks, start, r.options, max_jump)
