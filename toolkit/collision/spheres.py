"""A robot's collision shapes covered by spheres (:func:`sphere_model`): every point of every
shape's surface inside a sphere, a few spheres per shape, the trade-off between their count
and their excess volume set by ``per_shape``.

The cover is conservative by construction: a shape's surface is cut into triangles (a
mesh's own; a box's faces; a cylinder, cone or capsule inside a circumscribed prism), the
triangles are grouped by k-means on their centroids, and each group gets the sphere about
its triangles' bounding-box centre that holds all of their corners. A triangle lies in the
convex hull of its corners, so inside its group's sphere. A sphere primitive is itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..common import validate as _validate
from ..errors import InvalidParameterError
from .checker import CollisionSubject, robot_geometry
from .covers import shape_cover, surface_triangles

__all__ = ["SphereModel", "sphere_model", "surface_triangles"]


@dataclass(frozen=True)
class SphereModel:
    """Spheres covering a robot's collision shapes: per sphere its shape's name, the joint
    that carries it (Pinocchio's index), its centre in that joint's frame (S, 3) [m] and its
    radius (S,) [m]; ``excess``: per shape, the volume of the spheres' union over the
    shape's own (Monte Carlo, 20,000 points: near 1 is a close fit)."""

    shapes: tuple[str, ...]
    joints: np.ndarray
    centers: np.ndarray
    radii: np.ndarray
    excess: dict[str, float]

    def __len__(self) -> int:
        return len(self.radii)

    def world(self, model: pin.Model, q: np.ndarray) -> np.ndarray:
        """The centres (S, 3) in the base frame at configuration q."""
        data = model.createData()
        pin.forwardKinematics(model, data, q)
        out = np.empty_like(self.centers)
        for j in np.unique(self.joints).tolist():
            at = self.joints == j
            M = data.oMi[j]
            out[at] = self.centers[at] @ M.rotation.T + M.translation
        return out


def _volume(triangles: np.ndarray) -> float:
    """The shape's volume [m^3] (a closed mesh's by its signed tetrahedra)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    return abs(float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0)


def _union(centers: np.ndarray, radii: np.ndarray, rng: np.random.Generator) -> float:
    """The volume [m^3] of the union of spheres, by 20,000 points in their bounding box."""
    lo = (centers - radii[:, None]).min(axis=0)
    hi = (centers + radii[:, None]).max(axis=0)
    P = rng.uniform(lo, hi, (20_000, 3))
    inside = np.zeros(len(P), dtype=bool)
    for c, r in zip(centers, radii, strict=True):
        inside |= ((P - c) ** 2).sum(axis=1) <= r * r
    return float(inside.mean() * np.prod(hi - lo))


def sphere_model(robot: CollisionSubject, per_shape: int = 8, seed: int = 0) -> SphereModel:
    """At most ``per_shape`` spheres covering each collision shape of ``robot`` (module
    doc): more spheres fit closer (less excess volume), fewer check faster."""
    if not isinstance(robot, CollisionSubject):
        raise InvalidParameterError(f"robot must be a toolkit Robot, got {robot!r:.80}")
    per_shape = _validate.count(per_shape, "per_shape", minimum=1, maximum=256)
    rng = np.random.default_rng(_validate.count(seed, "seed", minimum=0))
    geom, _ = robot_geometry(robot)
    names, joints, centers, radii, excess = [], [], [], [], {}
    for obj in geom.geometryObjects:
        c, r, tris = shape_cover(obj.geometry, per_shape, rng)
        own = 4 / 3 * math.pi * r[0] ** 3 if tris is None else _volume(tris)  # None: a sphere
        M = obj.placement
        centers.append(c @ M.rotation.T + M.translation)
        radii.append(r)
        names += [obj.name] * len(r)
        joints += [obj.parentJoint] * len(r)
        excess[obj.name] = _union(c, r, rng) / own if own > 0 else math.inf
    return SphereModel(tuple(names), np.array(joints, np.int64), np.concatenate(centers),
                       np.concatenate(radii), excess)  # fmt: skip
