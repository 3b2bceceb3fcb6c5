"""The planner's geometry of a robot: the box its joint values are sampled in, each
joint's columns, and how far each shape's points lie from each joint's axis (what bounds
how far they move: the certificates' motion bound)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..collision import Checker
from ..errors import UnsupportedModelError

__all__ = ["joint_facts", "reach", "value_bounds"]


def _kept(robot: Any) -> Callable[[object, Callable[[], Any]], Any] | None:
    """Where a :class:`~toolkit.Robot` keeps what is read of its model once (its caches'
    ``kept_reach``); None for another subject (read every time)."""
    kept = getattr(getattr(robot, "_caches", None), "kept_reach", None)
    return kept if callable(kept) else None


def value_bounds(robot: Any) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) per joint value (nv,) the planner samples within: ``random_q``'s box
    (the limits; an unlimited revolute joint [-pi, pi], an unlimited slide [-1, 1] m), a
    continuous joint's angle within [-pi, pi]."""
    facts = joint_facts(robot)
    if facts["refused"]:
        raise UnsupportedModelError(facts["refused"])
    box, circle, qcol = robot.joints, facts["circle"], facts["qcol"]
    lo = np.where(circle, -math.pi, box.sample_lower[qcol]).astype(float)
    hi = np.where(circle, math.pi, box.sample_upper[qcol]).astype(float)
    return lo, hi


def joint_facts(robot: Any) -> dict[str, Any]:
    """Per joint of the robot's model, what a plan reads of it, read once (and kept with a
    robot's caches): its value's q column (``qcol``) and its column among the values
    (``vcol``), whether it is a continuous joint (``circle``), each joint's q columns by
    name (``columns``), and why the planner cannot take the model (``refused``, "" where it
    can: a joint moving in more than one value)."""
    kept = _kept(robot)
    if kept is not None:
        return kept("joints", lambda: _read_joints(robot.model))
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
    that joint's axis, and whether the joint moves it.

    Where the joint moves the shape: 1 for a slide (a point moves by its step); inf where
    a slide between them has no limit, or where the joint is neither a slide nor a revolute
    joint (a helical one: no motion is certified then). A point turned by dq about an axis
    moves by at most |dq| times its distance from the axis. The bound adds up the shape's
    box (its centre and outer radius in its joint's frame) and every joint placement and
    slide travel between; the last placement counts only by its distance from the axis (a
    child joint placed along its parent's axis, as the Panda's second above its first, adds
    nothing for the first).

    Where the joint does not move the shape: the distance from the joint's axis where the
    shape is fixed to that axis (it rides the joint's parent body, as the base under the
    first joint), else inf. A pair's distance changes by at most the lesser of its two
    shapes' values per unit of a joint that moves one of them
    (:func:`~toolkit.planning.kernels.pair_rates`).

    A robot's own shapes' rows are made once per shape set and kept in its caches (the
    same in every scene's checker)."""
    bounds = checker.bounds
    assert bounds is not None
    objects = checker.parts.objects  # every part's (toolkit.collision.parts)
    count, nv = checker.robot_count, robot.model.nv
    kept = _kept(robot)
    if kept is None:  # another subject than a Robot: nothing kept
        facts = _chain_facts(robot)
        return _reach_rows(facts, bounds, objects, range(len(objects)), nv)
    facts = kept("chain", lambda: _chain_facts(robot))
    key = (count, bounds.box[:count].tobytes(), bounds.radius[:count, 0].tobytes(),
           tuple(int(objects[g].parentJoint) for g in range(count)))  # fmt: skip
    own = kept(key, lambda: _reach_rows(facts, bounds, objects, range(count), nv))
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
    lines = [None] + [_line(M, axis[k]) if not slides[k] else None
                      for k, M in enumerate(model.jointPlacements) if k]  # fmt: skip
    return {
        "column": [j.idx_v for j in joints], "slides": slides, "axis": axis, "lines": lines,
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
    far, moves = np.full((len(shapes), nv), math.inf), np.zeros((len(shapes), nv), dtype=bool)
    for i, g in enumerate(shapes):
        k = int(objects[g].parentJoint)
        box, outer = bounds.box[g], float(bounds.radius[g, 0])
        centre = box[:3]
        corners = centre + (_CORNERS * box[12:15]) @ box[3:12].reshape(3, 3).T
        for j, line in enumerate(facts["lines"]):  # the joints whose axis it rides with
            if line is not None and parents[j] == k:
                far[i, column[j]] = _farthest(corners, centre, outer, *line)
        if k == 0:  # fixed to the base: no joint moves it
            continue
        d = _farthest(corners, centre, outer, _ORIGIN, None)  # from joint k's origin
        lever = _farthest(corners, centre, outer, _ORIGIN, axis[k])  # from joint k's axis
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


_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
_ORIGIN = np.zeros(3)


def _farthest(corners: np.ndarray, centre: np.ndarray, outer: float, point: np.ndarray,
              direction: np.ndarray | None) -> float:  # fmt: skip
    """How far a shape's points can lie from the line through ``point`` along ``direction``
    (from ``point`` itself without one): the farthest corner of its box (a distance from a
    line or point is convex, so it peaks at a corner), or its centre's distance and outer
    radius, whichever is less."""
    off = corners - point
    if direction is not None:  # the corners' offsets square to the line
        off = off - np.outer(off @ direction, direction)
    corner = float(np.sqrt((off * off).sum(axis=1).max()))
    return min(corner, _off_axis(centre - point, direction) + outer)


def _line(placement: Any, axis: np.ndarray | None) -> tuple[np.ndarray, np.ndarray] | None:
    """A revolute joint's axis in its parent's frame: (a point of it, its unit direction);
    None for any other joint."""
    if axis is None:
        return None
    return np.array(placement.translation, dtype=float), np.array(placement.rotation) @ axis


def _off_axis(point: np.ndarray, axis: np.ndarray | None) -> float:
    """The distance of ``point`` from the line through the origin along ``axis`` (from the
    origin itself without one)."""
    if axis is None:
        return float(np.linalg.norm(point))
    return float(np.linalg.norm(point - np.dot(point, axis) * axis))
