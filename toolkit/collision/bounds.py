"""The collision checker's compiled pre-filter (see :mod:`toolkit.collision.bound_kernels`): the
bounding boxes and spheres of its shapes, packed for the kernels."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from ..kinematics import CompiledBackend, parallel
from . import bound_kernels

__all__ = ["Bounds"]


def _inner(shape: Any) -> float:
    """The radius of the largest sphere about a primitive's centre inside it (0 for
    anything else, meshes included)."""
    import coal

    if isinstance(shape, coal.Sphere):
        return float(shape.radius)
    if isinstance(shape, coal.Box):
        return float(np.min(shape.halfSide))
    if isinstance(shape, coal.Cylinder):
        return float(min(shape.radius, shape.halfLength))
    return 0.0


class Bounds:
    """Bounding volumes of a GeometryModel's shapes on a robot's compiled kinematics."""

    def __init__(self, geom: pin.GeometryModel, backend: CompiledBackend) -> None:
        ints, flts, _, _ = backend.tree
        self.ints, self.flts = ints, flts
        n = len(geom.geometryObjects)
        self.row = np.empty(n, np.int64)
        self.box = np.empty((n, 15))
        self.radius = np.zeros((n, 2))
        for g, obj in enumerate(geom.geometryObjects):
            shape = obj.geometry
            shape.computeLocalAABB()
            low, high = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
            placement = obj.placement
            half = (high - low) / 2
            self.row[g] = backend.joint_row(int(obj.parentJoint))
            self.box[g, :3] = placement.act((high + low) / 2)
            self.box[g, 3:12] = np.asarray(placement.rotation).ravel()
            self.box[g, 12:] = half
            self.radius[g] = float(np.linalg.norm(half)), _inner(shape)
        pairs = geom.collisionPairs
        self.first = np.array([p.first for p in pairs], np.int64)
        self.second = np.array([p.second for p in pairs], np.int64)

    def decide(self, Q: np.ndarray) -> np.ndarray:
        """(N,) states: CLOSE (coal must decide), FREE (every checked pair certainly
        apart) or HIT (the inner spheres of a checked pair overlap)."""
        Q = np.ascontiguousarray(Q, dtype=float)
        args: tuple[Any, ...] = (Q, self.ints, self.flts, self.row, self.box, self.radius,
                                 self.first, self.second)  # fmt: skip
        return np.asarray(bound_kernels.decide_batch(parallel(len(Q)), *args))
