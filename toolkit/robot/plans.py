"""``Robot.plan``: a robot's joint values, limits, exact collision checker and goals (joint
configurations, or tool poses solved by every analytic branch or by numeric IK) handed to
:func:`toolkit.planning.plan_values`."""

from __future__ import annotations

import math
import os
import threading
import weakref
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..collision import Checker, Scene
from ..common import validate as _validate
from ..errors import InvalidParameterError, UnsupportedModelError
from ..planning import RESOLUTION, CertainTest, ExactSweep, PlanResult, plan_values
from .caches import Caches
from .deferral import deferred_pairs, end_pairs

__all__ = ["certain_test", "plan", "reach", "value_bounds"]

GOAL_SEEDS = 8
"""Numeric IK starts per pose where the arm has no analytic structure."""


def value_bounds(robot: Any) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) per joint value (nv,) the planner samples within: ``random_q``'s box
    (the limits; an unlimited revolute joint [-pi, pi], an unlimited slide [-1, 1] m), a
    continuous joint's angle within [-pi, pi]."""
    facts = _joint_facts(robot)
    if facts["refused"]:
        raise UnsupportedModelError(facts["refused"])
    box, circle, qcol = robot.joints, facts["circle"], facts["qcol"]
    lo = np.where(circle, -math.pi, box.sample_lower[qcol]).astype(float)
    hi = np.where(circle, math.pi, box.sample_upper[qcol]).astype(float)
    return lo, hi


def _joint_facts(robot: Any) -> dict[str, Any]:
    """Per joint of the robot's model, what a plan reads of it, read once (and kept with a
    robot's caches): its value's q column (``qcol``) and its column among the values
    (``vcol``), whether it is a continuous joint (``circle``), each joint's q columns by
    name (``columns``), and why the planner cannot take the model (``refused``, "" where it
    can: a joint moving in more than one value)."""
    caches = getattr(robot, "_caches", None)
    if isinstance(caches, Caches):
        return caches.kept_reach("joints", lambda: _read_joints(robot.model))  # type: ignore[no-any-return]
    return _read_joints(robot.model)


def _read_joints(model: Any) -> dict[str, Any]:
    joints = list(model.joints)[1:]
    refused = next((f"plan: joint {model.names[j]} ({joint.shortname()}) moves in "
                    f"{joint.nv} values; plans take 1-DoF joints"
                    for j, joint in enumerate(joints, start=1)
                    if joint.nv != 1 or joint.nq not in (1, 2)), "")  # fmt: skip
    return {
        "qcol": np.array([j.idx_q for j in joints], dtype=np.int64),
        "vcol": np.array([j.idx_v for j in joints], dtype=np.int64),
        "circle": np.array([j.nq == 2 for j in joints], dtype=bool),
        "columns": {name: list(range(j.idx_q, j.idx_q + j.nq))
                    for name, j in zip(list(model.names)[1:], joints, strict=True)},
        "refused": refused,
    }  # fmt: skip


def reach(robot: Any, checker: Checker) -> tuple[np.ndarray, np.ndarray]:
    """Per shape of the checker and joint value: how far [m] the shape's points can lie from
    that joint's axis (1 for a slide: a point moves by its step; 0 where the joint does not
    move the shape; inf where a slide between them has no limit, or where the joint is
    neither a slide nor a revolute joint, a helical one: no motion is certified then), and
    whether the joint moves it. A point turned by
    dq about an axis moves by at most |dq| times its distance from the axis. The bound adds
    up the shape's box (its centre and outer radius in its joint's frame) and every joint
    placement and slide travel between; the last placement counts only by its distance
    from the axis (a child joint placed along its parent's axis, as the Panda's second
    above its first, adds nothing for the first). A robot's own shapes' rows are made once
    per shape set and kept in its caches (the same in every scene's checker)."""
    bounds = checker.bounds
    assert bounds is not None
    objects = checker.geom.geometryObjects
    count, nv = checker.robot_count, robot.model.nv
    caches = getattr(robot, "_caches", None)
    if not isinstance(caches, Caches):  # another subject than a Robot: nothing kept
        facts = _chain_facts(robot)
        return _reach_rows(facts, bounds, objects, range(len(objects)), nv)
    facts = caches.kept_reach("chain", lambda: _chain_facts(robot))
    key = (count, bounds.box[:count].tobytes(), bounds.radius[:count, 0].tobytes(),
           tuple(int(objects[g].parentJoint) for g in range(count)))  # fmt: skip
    own = caches.kept_reach(key, lambda: _reach_rows(facts, bounds, objects, range(count), nv))
    rest = _reach_rows(facts, bounds, objects, range(count, len(objects)), nv)
    return np.concatenate([own[0], rest[0]]), np.concatenate([own[1], rest[1]])


def _chain_facts(robot: Any) -> dict[str, Any]:
    """Per joint of the robot's model, read once (and kept with a robot's caches): its
    value's column, whether it slides, how far, its axis (revolute), its parent, its
    placement's length and its distance from the parent's axis."""
    model = robot.model
    joints = list(model.joints)
    slides = [j.shortname().startswith("JointModelP") for j in joints]
    axis = [_axis(j) for j in joints]
    lower, upper = model.lowerPositionLimit, model.upperPositionLimit
    parents = [int(k) for k in model.parents]
    placed = [np.array(M.translation, dtype=float) for M in model.jointPlacements]
    return {
        "column": [j.idx_v for j in joints], "slides": slides, "axis": axis,
        "travel": [max(abs(float(lower[j.idx_q])), abs(float(upper[j.idx_q]))) if s else 0.0
                   for j, s in zip(joints, slides, strict=True)],
        "parents": parents, "length": [float(np.linalg.norm(t)) for t in placed],
        "aside": [_off_axis(placed[k], axis[parents[k]]) if k else 0.0
                  for k in range(len(placed))],
    }  # fmt: skip


def _reach_rows(
    facts: dict[str, Any], bounds: Any, objects: Any, shapes: range, nv: int
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`reach`'s rows of ``shapes`` (far, moves), from the model's ``facts``."""
    column, slides, axis = facts["column"], facts["slides"], facts["axis"]
    travel, parents, length, aside = (facts[k] for k in ("travel", "parents", "length",
                                                          "aside"))  # fmt: skip
    far, moves = np.zeros((len(shapes), nv)), np.zeros((len(shapes), nv), dtype=bool)
    for i, g in enumerate(shapes):
        k = int(objects[g].parentJoint)
        if k == 0:  # fixed to the base: no joint moves it
            continue
        centre, outer = bounds.box[g, :3], float(bounds.radius[g, 0])
        d = float(np.linalg.norm(centre)) + outer  # from joint k's origin
        lever = _off_axis(centre, axis[k]) + outer  # from joint k's axis
        while k > 0:  # a joint neither sliding nor turning about a known axis: no bound
            bound = 1.0 if slides[k] else (lever if axis[k] is not None else math.inf)
            far[i, column[k]], moves[i, column[k]] = bound, True
            lever = d + travel[k] + aside[k]  # from the parent's axis, through k's origin
            d += travel[k] + length[k]
            k = parents[k]
    return far, moves


_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def _axis(joint: Any) -> np.ndarray | None:
    """A revolute joint's unit axis in its own frame (the line through its origin it turns
    about); None for any other joint (its bound stays the distance from its origin)."""
    name = joint.shortname()
    for prefix in ("JointModelRUB", "JointModelR"):
        if name.startswith(prefix) and name[len(prefix) :] in _AXES:
            return np.array(_AXES[name[len(prefix) :]])
    if name in ("JointModelRevoluteUnaligned", "JointModelRevoluteUnboundedUnaligned"):
        concrete = joint.extract() if hasattr(joint, "extract") else joint  # the model's variant
        a: np.ndarray = np.array(concrete.axis, dtype=float)
        return a / float(np.linalg.norm(a))
    return None


def _off_axis(point: np.ndarray, axis: np.ndarray | None) -> float:
    """The distance of ``point`` from the line through the origin along ``axis`` (from the
    origin itself without one)."""
    if axis is None:
        return float(np.linalg.norm(point))
    return float(np.linalg.norm(point - np.dot(point, axis) * axis))


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
    facts = _joint_facts(robot)
    packed = list(checker.bounds.packed())
    deferred = deferred_pairs(robot, checker)
    if extra is not None:
        deferred = np.union1d(deferred, extra).astype(np.int64)
    if deferred.size:  # the search's test leaves them out (certified after it)
        keep = np.ones(len(packed[5]), dtype=bool)
        keep[deferred] = False
        packed[5], packed[6] = packed[5][keep], packed[6][keep]
    first, second = packed[5], packed[6]
    # a blocked configuration is most often the hand in the scene: the scene's pairs first,
    # the links farthest down the chain (the highest shapes) first among them
    scene_pair = np.maximum(first, second) >= checker.robot_count
    order = np.lexsort((-np.minimum(first, second), ~scene_pair))
    packed[5], packed[6] = first[order].copy(), second[order].copy()
    far, moves = reach(robot, checker)
    finite = bool(np.isfinite(far).all())
    return CertainTest(facts["qcol"], facts["circle"], robot.nq, tuple(packed),
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
    columns = _joint_facts(robot)["columns"]
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
    simplify: bool = True,
) -> PlanResult:  # fmt: skip
    """:meth:`toolkit.Robot.plan` (its docstring)."""
    q0 = robot.joints.onto_limits(robot.joints.check(start), "start")
    robot.frames.id(frame)  # validates
    time_limit = _validate.number(time_limit, "time_limit [s]", lower=0.0, strict=True,
                                  upper=3600.0)  # fmt: skip
    resolution = _validate.number(resolution, "resolution [rad]", lower=0.0, strict=True,
                                  upper=0.5)  # fmt: skip
    seed = _validate.count(seed, "seed", minimum=0, maximum=2**63 - 1)
    simplify = _validate.flag(simplify, "simplify")
    held = _held(robot, hold)
    lo, hi = value_bounds(robot)
    checker = robot.collision_checker(scene, True)
    test = certain_test(robot, checker)
    why = _refusal(robot, checker, q0, "start", test)
    if why:
        raise InvalidParameterError(why)
    goals = _goals(robot, goal, pose, frame, scene, checker, (q0, seed, held))
    test = _with_end_pairs(robot, checker, test, np.vstack([q0[None], goals]))
    fixed = robot.joints.angles(q0)  # a held joint's value is its start's: lower = upper there
    kept = np.zeros(robot.nq, dtype=bool)
    kept[held] = True
    facts = _joint_facts(robot)
    at = facts["vcol"][kept[facts["qcol"]]]
    lo[at] = hi[at] = fixed[at]

    def collides(values: np.ndarray) -> np.ndarray:
        return np.asarray(checker.in_collision_many(robot.joints.q_from_angles(values)), dtype=bool)

    sweep, deferred = _sweeps(robot, checker, test)
    values, g, fig = plan_values(
        collides, fixed, robot.joints.angles(goals), (lo, hi), time_limit=time_limit,
        seed=seed, resolution=resolution, simplify=simplify, certain=test, sweep=sweep,
        deferred=deferred,
    )  # fmt: skip
    ok = values is not None and bool(fig["verified"])
    if values is None:
        reason = f"no path found within {time_limit:g} s ({int(fig['nodes'])} nodes grown)"
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
        success=ok, path=path, goal=g if ok else -1, goals=goals, time_s=fig["time_s"],
        checks=int(fig["checks"]), nodes=int(fig["nodes"]), reason=reason, verified=ok,
        resolution=resolution, values=values, search="covers" if fig["certain"] else "exact",
        swept=ok and bool(fig["swept"]), escapes=int(fig["escapes"]) if ok else 0,
        certificate=_certificate(fig) if ok else "",
    )  # fmt: skip


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
    sweep = ExactSweep(checker, test, robot.joints.q_from_angles)
    if not test.deferred.size:
        return sweep, None
    return sweep, ExactSweep(checker, test, robot.joints.q_from_angles, test.deferred)


def _certificate(fig: dict[str, float]) -> str:
    """How a plan's path was certified (:attr:`PlanResult.certificate`)."""
    if not fig["swept"]:
        return "samples"
    if not fig["exact_segments"]:
        return "covers"
    return "exact" if not fig["certain"] else "covers+exact"
