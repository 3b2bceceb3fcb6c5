"""``Robot.plan``: a robot's joint values, limits, exact collision checker and goals (joint
configurations, or tool poses solved by every analytic branch or by numeric IK) handed to
:func:`toolkit.planning.plan_values`."""

from __future__ import annotations

import dataclasses
import os
import threading
import time
import weakref
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..collision import Checker, CheckerTimeout, Scene
from ..common import validate as _validate
from ..errors import InvalidParameterError, UnsupportedModelError
from ..kinematics import compile_seconds
from ..planning import (
    RESOLUTION,
    CertainTest,
    ExactSweep,
    PlannerSettings,
    PlanResult,
    joint_facts,
    plan_values,
    reach,
    value_bounds,
)
from .checkers import checker_for
from .deferral import deferred_pairs, end_pairs, robot_convex

__all__ = ["certain_test", "plan"]

GOAL_SEEDS = 8
"""Numeric IK starts per pose where the arm has no analytic structure."""


_NONE = dict.fromkeys(("nodes", "checks", "certain", "swept", "escapes"), 0.0)
"""The search's figures where no search ran."""

_TESTS: weakref.WeakKeyDictionary[Checker, CertainTest | None] = weakref.WeakKeyDictionary()
_TESTS_LOCK = threading.Lock()


def _fresh_lock() -> None:
    """In a forked child, the lock of the kept tests anew (a thread of the parent may have
    held it at the fork: ``toolkit.planning.plan_many`` forks)."""
    global _TESTS_LOCK
    _TESTS_LOCK = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_fresh_lock)


def certain_test(robot: Any, checker: Checker) -> CertainTest | None:
    """The checker's conservative test for the compiled search (its pre-filter read
    strictly, with the robot's :func:`reach` to certify whole motions), or None where it has
    none (the Pinocchio back end, no shapes); made once per checker (a checker is one
    robot's among one scene) and kept while the checker lives."""
    with _TESTS_LOCK:
        if checker in _TESTS:
            return _TESTS[checker]
    test = _certain_test(robot, checker)
    with _TESTS_LOCK:
        _TESTS[checker] = test
    return test


def _certain_test(
    robot: Any, checker: Checker, extra: np.ndarray | None = None
) -> CertainTest | None:
    """The test of :func:`certain_test`, with the ``extra`` pairs left out as well."""
    if checker.bounds is None or checker.base_hits:
        return None
    facts = joint_facts(robot)
    packed = checker.bounds.packed()
    deferred = deferred_pairs(robot, checker)
    if extra is not None:
        deferred = np.union1d(deferred, extra).astype(np.int64)
    if deferred.size:  # the search's test leaves them out (certified after it)
        keep = np.ones(len(packed.first), dtype=bool)
        keep[deferred] = False
        packed = packed.with_pairs(packed.first[keep], packed.second[keep])
    first, second = packed.first, packed.second
    # a blocked configuration is most often the hand in the scene: the scene's pairs first,
    # the links farthest down the chain (the highest shapes) first among them
    scene_pair = np.maximum(first, second) >= checker.robot_count
    order = np.lexsort((-np.minimum(first, second), ~scene_pair))
    packed = packed.with_pairs(first[order], second[order])
    far, moves = reach(robot, checker)
    finite = bool(np.isfinite(far[moves]).all())
    return CertainTest(facts["qcol"], facts["circle"], robot.nq, packed,
                       far if finite else None, moves if finite else None,
                       deferred)  # fmt: skip


def _refusal(
    robot: Any, checker: Checker, q: np.ndarray, what: str, test: CertainTest | None
) -> str | None:
    """Why ``q`` cannot start or end a plan (None: it can): free where the conservative
    ``test`` passes it, else asked of the exact checker (the batch check, then the single
    one, which names the pair)."""
    joints = robot.joints  # q is checked and within the limits (onto_limits): angles unchecked
    if (test is not None and not test.deferred.size  # left-out pairs: coal decides
            and test.free(joints.raw_angles(q[None], joints.name))[0]):  # fmt: skip
        return None
    if not checker.in_collision_many(q[None])[0]:  # coal on the undecided pairs only
        return None
    hit = checker.first_collision(q)
    return None if hit is None else f"{what} collides: {hit[0]} with {hit[1]}"


def _held(robot: Any, hold: object) -> np.ndarray:
    """The q indices (into nq) of the joints named in ``hold``."""
    if hold is None:
        return np.zeros(0, np.int64)
    names = [hold] if isinstance(hold, str) else hold
    if not isinstance(names, list | tuple) or not all(isinstance(n, str) for n in names):
        raise InvalidParameterError(f"hold must be joint names, got {hold!r:.80}")
    columns = joint_facts(robot)["columns"]
    cols: list[int] = []
    for name in names:
        if name not in columns:
            raise InvalidParameterError(f"hold: no joint {name!r}; joints: {robot.joints.names}")
        cols += columns[name]
    return np.array(sorted(set(cols)), np.int64)


def _pose_goals(
    robot: Any, pose: object, frame: str | None, scene: Scene | None, checker: Checker,
    start: tuple[np.ndarray, int, np.ndarray],
) -> np.ndarray:  # fmt: skip
    """Every configuration within the limits and free of collision that puts ``frame`` on
    one of the poses (4, 4) or (P, 4, 4): every analytic branch where the arm has a
    structure, else numeric IK from :data:`GOAL_SEEDS` random starts."""
    poses = _validate.real_array(pose, "pose")
    if poses.shape == (4, 4):
        poses = poses[None]
    if poses.ndim != 3 or poses.shape[1:] != (4, 4) or not len(poses):
        raise InvalidParameterError(f"pose must be (4, 4) or (P, 4, 4), got {poses.shape}")
    found: list[np.ndarray] = []
    q0, seed, held = start
    rng = np.random.default_rng(seed)
    for T in poses:
        try:  # the joints outside the chain (fingers) keep their start values
            rows = robot.ik_all(T, frame=frame, q0=q0)
            Q = rows.q[rows.success]
        except UnsupportedModelError:  # no structure: numeric IK from random starts
            answers = [robot.ik(T, q0=robot.random_q(seed=rng), frame=frame, scene=scene,
                                collision_free=True) for _ in range(GOAL_SEEDS)]  # fmt: skip
            Q = np.array([a.q for a in answers if a.success]).reshape(-1, robot.nq)
            if len(Q) and len(held):  # held joints back at the start: still on the pose?
                Q[:, held] = q0[held]
                F = robot.fk(Q, frame).reshape(-1, 4, 4)
                Q = Q[np.abs(F - T).max(axis=(1, 2)) <= 1e-6]
        if len(Q):
            found.extend(Q[~np.asarray(checker.in_collision_many(Q), dtype=bool)])
    if not found:
        raise InvalidParameterError(
            "no configuration within the limits and free of collision reaches the pose"
            f"{'s' if len(poses) > 1 else ''}: nothing to plan to"
        )
    return np.array(found)


def _goals(
    robot: Any, goal: ArrayLike | None, pose: object, frame: str | None, scene: Scene | None,
    checker: Checker, start: tuple[np.ndarray, int, np.ndarray],
) -> np.ndarray:  # fmt: skip
    """The goal configurations, free and within the limits, the held joints (``start``:
    the start q, the seed, the held q indices) at their start values."""
    q0, seed, held = start
    if (goal is None) == (pose is None):
        raise InvalidParameterError("give a goal configuration or a tool pose (one of them)")
    if pose is not None:
        return _pose_goals(robot, pose, frame, scene, checker, (q0, seed, held))
    goals = robot.joints.check(goal, batch=True)
    goals = goals[None] if goals.ndim == 1 else goals
    if not len(goals):
        raise InvalidParameterError("goal holds no configuration")
    goals = robot.joints.onto_limits(goals, "goal")
    moved = (goals[:, held] != q0[held]).any(axis=1)
    if moved.any():
        raise InvalidParameterError(
            f"goal {int(np.argmax(moved))} moves a held joint from its start"
        )
    test = certain_test(robot, checker)
    why = [_refusal(robot, checker, g, f"goal {i}", test) for i, g in enumerate(goals)]
    if all(why):
        raise InvalidParameterError("; ".join(w for w in why if w))
    kept: np.ndarray = goals[[w is None for w in why]]
    return kept


def plan(
    robot: Any, start: ArrayLike, goal: ArrayLike | None = None, *, pose: object = None,
    scene: Scene | None = None, frame: str | None = None, hold: object = None,
    time_limit: float = 5.0, seed: int = 0, resolution: float = RESOLUTION,
    simplify: bool = True, settings: PlannerSettings | None = None,
) -> PlanResult:  # fmt: skip
    """:meth:`toolkit.Robot.plan` (its docstring)."""
    clock = (time.perf_counter(), compile_seconds())  # the time budget's start (:func:`_spent`)
    q0 = robot.joints.onto_limits(robot.joints.check(start), "start")
    robot.frames.id(frame)  # validates
    time_limit = _validate.number(time_limit, "time_limit [s]", lower=0.0, strict=True,
                                  upper=3600.0)  # fmt: skip
    resolution = _validate.number(resolution, "resolution [rad]", lower=0.0, strict=True,
                                  upper=0.5)  # fmt: skip
    seed = _validate.count(seed, "seed", minimum=0, maximum=2**63 - 1)
    simplify = _validate.flag(simplify, "simplify")
    held = _held(robot, hold)
    settings = PlannerSettings.of(settings)  # refused before the scene is built
    lo, hi = value_bounds(robot)
    try:
        checker = checker_for(robot, scene, until=lambda: _spent(clock) > time_limit)
    except CheckerTimeout as exc:  # nothing searched: the scene's checker took the time
        empty = robot.joints.check(np.zeros((0, robot.nq)), batch=True)
        result = _result(robot, (None, -1, _NONE), (q0, empty), (time_limit, 0.0), clock,
                         resolution)  # fmt: skip
        return dataclasses.replace(result, reason=f"no path found within {time_limit:g} s: {exc}")
    test = certain_test(robot, checker)
    why = _refusal(robot, checker, q0, "start", test)
    if why:
        raise InvalidParameterError(why)
    goals = _goals(robot, goal, pose, frame, scene, checker, (q0, seed, held))
    test = _with_end_pairs(robot, checker, test, np.vstack([q0[None], goals]))
    fixed = robot.joints.angles(q0)  # a held joint's value is its start's: lower = upper there
    kept = np.zeros(robot.nq, dtype=bool)
    kept[held] = True
    facts = joint_facts(robot)
    at = facts["vcol"][kept[facts["qcol"]]]
    lo[at] = hi[at] = fixed[at]

    def collides(values: np.ndarray) -> np.ndarray:
        return np.asarray(checker.in_collision_many(robot.joints.q_from_angles(values)), dtype=bool)

    sweep, deferred = _sweeps(robot, checker, test)
    if test is not None:
        test.ready()  # compiled (first use) before the budget is read
    spent = _spent(clock)
    left = time_limit - spent
    if left > 0:
        values, g, fig = plan_values(
            collides, fixed, robot.joints.angles(goals), (lo, hi), time_limit=left,
            seed=seed, resolution=resolution, simplify=simplify, certain=test, sweep=sweep,
            deferred=deferred, settings=settings,
        )  # fmt: skip
    else:
        values, g, fig = None, -1, _NONE
    return _result(robot, (values, g, fig), (q0, goals), (time_limit, spent), clock, resolution)


def _result(
    robot: Any, found: tuple[np.ndarray | None, int, dict[str, float]],
    ends: tuple[np.ndarray, np.ndarray], budget: tuple[float, float],
    clock: tuple[float, float], resolution: float,
) -> PlanResult:  # fmt: skip
    """The plan's :class:`PlanResult` from the search's ``found`` (values, goal, figures),
    its ``ends`` (start, goals), ``budget`` (time limit, seconds spent before the search)."""
    (values, g, fig), (q0, goals), (time_limit, spent) = found, ends, budget
    ok = values is not None and bool(fig["verified"])
    if values is None:
        reason = f"no path found within {time_limit:g} s ({int(fig['nodes'])} nodes grown)"
        if spent > 0.5 * time_limit:
            reason += f"; the scene, start and goals took {spent:.3g} s of it"
    elif not ok:  # pragma: no cover - every kept edge passed the same check
        reason = "the path found failed its final check"
    else:
        reason = f"solved: {len(values)} waypoints"
    if not ok or values is None:
        values, path = np.zeros((0, robot.joints.nv)), np.zeros((0, robot.nq))
    else:
        path = robot.joints.q_from_angles(values)
        path[0], path[-1] = q0, goals[g]  # the caller's own start and goal, bit for bit
    return PlanResult(
        success=ok, path=path, goal=g if ok else -1, goals=goals, time_s=_spent(clock),
        checks=int(fig["checks"]), nodes=int(fig["nodes"]), reason=reason, verified=ok,
        resolution=resolution, values=values, search="covers" if fig["certain"] else "exact",
        swept=ok and bool(fig["swept"]), escapes=int(fig["escapes"]) if ok else 0,
        certificate=_certificate(fig) if ok else "",
    )  # fmt: skip


def _spent(clock: tuple[float, float]) -> float:
    """Seconds since ``clock`` (its start: a time and :func:`compile_seconds` then), less
    those spent compiling kernels meanwhile (a first use's, once an installation)."""
    return time.perf_counter() - clock[0] - (compile_seconds() - clock[1])


def _with_end_pairs(
    robot: Any, checker: Checker, test: CertainTest | None, ends: np.ndarray
) -> CertainTest | None:
    """``test``, or where only the robot's own pairs keep a start or goal from the covers'
    search (:func:`~toolkit.robot.deferral.end_pairs`), a test leaving those out as well."""
    if test is None:
        return None
    extra = end_pairs(checker, test.deferred, ends)
    return _certain_test(robot, checker, extra) if extra.size else test


def _sweeps(
    robot: Any, checker: Checker, test: CertainTest | None
) -> tuple[ExactSweep | None, ExactSweep | None]:
    """The exact shapes' whole-motion certificates of a plan: of every pair, and of the
    pairs the compiled search leaves out (None where there are none, or no motion bound)."""
    if test is None or not test.sweeps:
        return None, None
    convex = robot_convex(robot, checker)
    sweep = ExactSweep(checker, test, robot.joints.q_from_angles, convex=convex)
    if not test.deferred.size:
        return sweep, None
    return sweep, ExactSweep(checker, test, robot.joints.q_from_angles, test.deferred, convex)


def _certificate(fig: dict[str, float]) -> str:
    """How a plan's path was certified (:attr:`PlanResult.certificate`)."""
    if not fig["swept"]:
        return "samples"
    if not fig["exact_segments"]:
        return "covers"
    return "exact" if not fig["certain"] else "covers+exact"
