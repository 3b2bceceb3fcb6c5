"""A robot's packed sphere covers kept on disk between processes (:func:`stored_covers`).

Making the covers is most of a robot's first plan in a process: 0.67 of 1.07 s for
MotionBenchMaker's UR5 (its gripper's meshes of 40,000-56,000 triangles; ad hoc). They are
kept in the toolkit's private cache folder (:func:`toolkit.common.cache.kept_bytes`: an
entry is read only from a folder no one else can write, and only where it matches its
SHA-256 sidecar) under a key of everything they are made from:

* the digest of the module that makes them and of every package file it imports
  (:func:`toolkit.common.sources.module_digest`: a change to the covers' code makes them
  anew);
* per robot shape, its kind and placement, and for a mesh the SHA-256 of its file and its
  scale (the mesh is what Pinocchio loads from that file), for a box, sphere, cylinder,
  capsule, cone or ellipsoid its local bounding box (which fixes its dimensions).

A shape of any other kind (a convex hull, a mesh built in memory, an octree) keeps its
robot's covers out of the store: they are made each process. What is read is checked for
its arrays' kinds and shapes; anything else is made anew, never used.
"""

from __future__ import annotations

import hashlib
import io
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..common import cache, sources

__all__ = ["covers_key", "stored_covers"]

_BOXED = ("Box", "Sphere", "Cylinder", "Capsule", "Cone", "Ellipsoid")
"""Shapes whose kind and local bounding box fix them."""
_NAMES = ("cstart", "csphere", "hold", "wstart", "wpoint")


def covers_key(geom: pin.GeometryModel, count: int) -> str | None:
    """The store's key of the covers of ``geom``'s first ``count`` shapes (module doc), or
    None where a shape cannot be keyed."""
    import coal

    code = sources.module_digest("toolkit.collision.bounds")
    if code is None:
        return None
    h = hashlib.sha256(f"{code}:{count}".encode())
    for obj in geom.geometryObjects[:count]:
        shape, kind = obj.geometry, type(obj.geometry).__name__
        h.update(kind.encode() + np.asarray(obj.placement.homogeneous, dtype=float).tobytes())
        if isinstance(shape, coal.BVHModelBase):
            try:
                data = Path(obj.meshPath).read_bytes() if obj.meshPath else None
            except OSError:
                data = None
            if data is None:
                return None
            h.update(hashlib.sha256(data).digest())
            h.update(np.asarray(obj.meshScale, dtype=float).tobytes())
        elif kind in _BOXED:
            shape.computeLocalAABB()
            box = np.concatenate([shape.aabb_local.min_, shape.aabb_local.max_])
            h.update(np.asarray(box, dtype=float).tobytes())
        else:
            return None
    return h.hexdigest()[:40]


def stored_covers(
    geom: pin.GeometryModel, count: int, make: Callable[[], tuple[np.ndarray, ...]]
) -> tuple[np.ndarray, ...]:
    """The packed covers (cstart, csphere, hold, wstart, wpoint) of ``geom``'s first
    ``count`` shapes: from the store where its entry for them is whole, else ``make()``'s
    (stored for the next process)."""
    key = covers_key(geom, count)
    if key is None:
        return make()
    made: list[tuple[np.ndarray, ...]] = []

    def fresh() -> bytes:
        made.append(make())
        out = io.BytesIO()
        cstart, csphere, hold, wstart, wpoint = made[0]
        np.savez(out, cstart=cstart, csphere=csphere, hold=hold, wstart=wstart, wpoint=wpoint)
        return out.getvalue()

    data = cache.kept_bytes(f"covers-{key}.npz", fresh)
    if made:
        return made[0]
    read = _read(data, count)
    return read if read is not None else make()


def _read(data: bytes, count: int) -> tuple[np.ndarray, ...] | None:
    """The five arrays of a stored entry, or None where they are not what was stored: the
    names, kinds and shapes :func:`~toolkit.collision.bounds._packed` makes, finite."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as entry:
            arrays = tuple(np.asarray(entry[name]) for name in _NAMES)
    except (OSError, ValueError, KeyError):
        return None
    cstart, csphere, hold, wstart, wpoint = arrays
    spheres = len(csphere)
    fits = (
        cstart.shape == (count + 1,) and cstart.dtype == np.int64
        and csphere.ndim == 2 and csphere.shape[1] == 4 and hold.shape == (count, 4)
        and wstart.shape == (spheres + 1,) and wstart.dtype == np.int64 and wpoint.ndim == 2
        and wpoint.shape[1] == 3 and int(cstart[0]) == 0 and int(cstart[-1]) == spheres
        and int(wstart[0]) == 0 and int(wstart[-1]) == len(wpoint)
        and bool(np.all(np.diff(cstart) >= 0)) and bool(np.all(np.diff(wstart) >= 0))
        and all(a.dtype == np.float64 and np.isfinite(a).all() for a in (csphere, hold, wpoint))
    )  # fmt: skip
    return arrays if fits else None
