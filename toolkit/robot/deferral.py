"""Which pairs of a robot's own shapes the compiled search leaves out
(:func:`deferred_pairs`), to be certified after it on the exact shapes."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from ..collision import Checker, pieces
from ..collision import convex as sets
from .caches import Caches

__all__ = ["DEFER_SAMPLES", "DEFER_SHARE", "deferred_pairs", "end_pairs", "robot_convex"]

DEFER_SHARE = 0.25
"""A pair of the robot's own shapes that the bounds and covers leave to coal at more than
this share of random configurations (and that collides at fewer than a third of those) is
left out of the compiled search's test and certified on the exact shapes after it
(:func:`deferred_pairs`)."""
DEFER_SAMPLES = 256
"""Random configurations :func:`deferred_pairs` looks at (once per robot and shape set)."""


def deferred_pairs(robot: Any, checker: Checker) -> np.ndarray:
    """The checker's pairs (indices) of the robot's own shapes that its bounds and covers
    seldom decide, each alone: two links a joint or two apart whose meshes keep 2 cm apart
    (MotionBenchMaker's Panda SRDF checks link 5 against link 7 and the hand, which
    example-robot-data's disables; a cover of 8 spheres of 8-11 cm cannot prove 2 cm).
    The compiled search leaves them out (with them, it found no certainly-free passage and
    gave half the time limit to the exact search: 2.5-5 s plans); the path it finds is
    certified for them on the exact shapes, by :class:`~toolkit.planning.sweep.ExactSweep`.
    Found once per robot and shape set at :data:`DEFER_SAMPLES` random configurations."""
    bounds = checker.bounds
    assert bounds is not None
    count = checker.robot_count
    own = np.flatnonzero((bounds.first < count) & (bounds.second < count))
    if not own.size:
        return own

    def find() -> np.ndarray:
        Q = robot.random_q(DEFER_SAMPLES, seed=0)
        state, listed = bounds.decide_pairs(Q)
        rows = np.flatnonzero((state != 2) & (listed[:, 0] <= listed.shape[1] - 1))
        undecided = np.zeros(len(bounds.first), np.int64)
        for r in rows:
            undecided[listed[r, 1 : 1 + listed[r, 0]]] += 1
        often = own[undecided[own] > DEFER_SHARE * max(len(rows), 1)]
        kept = []
        data, gdata = checker.model.createData(), pin.GeometryData(checker.geom)
        for k in often:  # pairs that do collide often are the search's to avoid
            hits = 0
            for r in rows:
                if k in listed[r, 1 : 1 + listed[r, 0]]:
                    pin.updateGeometryPlacements(checker.model, data, checker.geom, gdata, Q[r])
                    hits += bool(pin.computeCollision(checker.geom, gdata, int(k)))
            if hits < undecided[k] / 3:
                kept.append(int(k))
        return np.array(kept, np.int64)

    caches = getattr(robot, "_caches", None)
    if not isinstance(caches, Caches):
        return find()
    key = ("deferred", count, bounds.box[:count].tobytes(), bounds.first[own].tobytes(),
           bounds.second[own].tobytes())  # fmt: skip
    found: np.ndarray = caches.kept_reach(key, find)
    return found


def end_pairs(checker: Checker, deferred: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """The robot's own pairs (indices, not in ``deferred``) that alone keep a start or goal
    (free: checked on coal) from the covers' test (Baxter's goal with its elbows 2 cm from
    its torso): left out of the search and certified after it like
    :func:`deferred_pairs`, instead of the whole plan going to the exact search."""
    bounds = checker.bounds
    if bounds is None:
        return np.zeros(0, np.int64)
    state, listed = bounds.decide_pairs(ends)
    count, extra = checker.robot_count, set[int]()
    for row, st in zip(listed, state, strict=True):
        pairs = row[1 : 1 + row[0]]
        if st != 0 or row[0] >= listed.shape[1]:
            continue
        if ((bounds.first[pairs] < count) & (bounds.second[pairs] < count)).all():
            extra.update(int(k) for k in pairs)
    return np.array(sorted(extra - set(deferred.tolist())), np.int64)


def robot_convex(robot: Any, checker: Checker) -> sets.ConvexSets:
    """The checker's shapes as convex sets (:func:`~toolkit.collision.convex.convex_sets`),
    on which the exact shapes' certificates step: the robot's made once per robot and
    shape set (3.4 ms a plan on MotionBenchMaker's Panda when made per plan), the scene's
    added."""
    count = checker.robot_count

    def make() -> sets.ConvexSets:
        return sets.convex_sets(checker.parts.shapes, count)

    caches, bounds = getattr(robot, "_caches", None), checker.bounds
    shapes = checker.parts.shapes
    if not isinstance(caches, Caches) or bounds is None:
        return sets.convex_sets(shapes, len(shapes.geometryObjects), make())
    # the shapes themselves by coal's addresses (kept alive by the robot's shapes): sets
    # that hold other shapes than the checker's would bound the wrong distances
    objects = shapes.geometryObjects[:count]
    addresses = tuple(pieces.address(o.geometry) for o in objects)
    key = ("convex", count, bounds.box[:count].tobytes(), bounds.row[:count].tobytes(), addresses)
    found: sets.ConvexSets = caches.kept_reach(key, make)
    return sets.convex_sets(shapes, len(shapes.geometryObjects), found)
