"""The checker's broad phase: a sphere no point of the robot leaves
(:func:`robot_reach`), and whether a fixed scene object can come near it
(:func:`within_reach`). A scene's objects beyond it are never built into the checker:
Pinocchio's geometry model grows by a square matrix a shape (3,000 shapes took 20 s to
add, 5,000 boxes 96 s before this), and a scene of thousands of objects, most far from
the arm, builds only the near ones."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from .bounds import local_box

__all__ = ["robot_reach", "within_reach"]


def _sphere(shape: Any, placement: pin.SE3) -> tuple[np.ndarray, float]:
    """(centre, radius) of the sphere about a shape's bounding box, placed."""
    low, high = local_box(shape)
    centre = placement.act(np.asarray((low + high) / 2, dtype=float))
    return np.asarray(centre), float(np.linalg.norm(high - low) / 2)


def robot_reach(model: pin.Model, geom: pin.GeometryModel) -> tuple[np.ndarray, float] | None:
    """(centre, radius) of a sphere no point of the robot's shapes leaves at any
    configuration (None: no such bound, a slide without limits or a floating base): each
    moving shape's box sphere, its distance from its joint's origin grown by every joint
    placement and slide travel up to a joint fixed to the world, whose origin is fixed;
    the spheres of those roots and of the shapes fixed to the base enclosed in one."""
    if model.joints[1].shortname() == "JointModelFreeFlyer" if model.njoints > 1 else False:
        return None
    lower, upper = model.lowerPositionLimit, model.upperPositionLimit
    balls: list[tuple[np.ndarray, float]] = []
    for g in geom.geometryObjects:
        centre, radius = _sphere(g.geometry, g.placement)
        k = int(g.parentJoint)
        if k == 0:
            balls.append((centre, radius))
            continue
        d = float(np.linalg.norm(centre)) + radius
        while int(model.parents[k]) != 0:
            joint = model.joints[k]
            if joint.shortname().startswith("JointModelP"):
                travel = max(abs(float(lower[joint.idx_q])), abs(float(upper[joint.idx_q])))
                if not np.isfinite(travel) or travel >= 1e9:
                    return None
                d += travel
            elif not joint.shortname().startswith(("JointModelR", "JointModelMimic")):
                return None
            d += float(np.linalg.norm(model.jointPlacements[k].translation))
            k = int(model.parents[k])
        joint = model.joints[k]
        if not joint.shortname().startswith(("JointModelR", "JointModelMimic")):
            return None  # a root that slides or floats: its origin moves
        balls.append((np.asarray(model.jointPlacements[k].translation, dtype=float), d))
    if not balls:
        return None
    centre = np.mean([c for c, _ in balls], axis=0)
    return centre, max(float(np.linalg.norm(c - centre)) + r for c, r in balls)


def within_reach(reach: tuple[np.ndarray, float] | None, shape: Any, placement: pin.SE3) -> bool:
    """Whether a fixed scene object's shape may come near the robot (within 1 cm of its
    reach): a broad phase, so that a scene of thousands of objects far and near builds
    only the near ones into the checker (Pinocchio's geometry model grows by a square
    matrix a shape: 3,000 shapes took 20 s to add)."""
    if reach is None:
        return True
    centre, radius = _sphere(shape, placement)
    if not np.isfinite(radius) or not np.all(np.isfinite(centre)):
        return True
    return bool(np.linalg.norm(centre - reach[0]) <= reach[1] + radius + 0.01)
