"""A checker's shapes and pairs held in parts, each a Pinocchio ``GeometryModel``
(:class:`Parts`), and the exact queries over them.

Pinocchio's ``GeometryModel`` takes time quadratic in its size for every object added (it
resizes an n x n table of its pairs): in one model, the checker of 2,000 boxes within the
Panda's reach built in 4.5 s and of 5,000 in 77 s (measured before the parts; with them,
``benchmarks/scene_scale.py``). A scene of more than :data:`PART` fixed objects within
reach is therefore held in several models, each with the robot's shapes and at most
:data:`PART` of the scene's objects; the first holds the robot's own pairs too. The
scene's attached objects come first and every part holds them (they pair with every
fixed object). The objects are numbered one after the other (the robot's shapes, the
attached objects, then each part's own), the pairs likewise (each part's in its order):
the numbering the pre-filter (:class:`~toolkit.collision.bounds.Bounds`) and the
planner's certificates read, the same as one model's where there is one part.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator
from typing import Any

import numpy as np
import pinocchio as pin

from ..common import PerThread
from .pieces import FLAT, Pieces, convex_hull, kept_for, pieces_distance, pieces_of

__all__ = [
    "EVERY_PAIR",
    "FLAT",
    "HULL_FIT",
    "PART",
    "AllShapes",
    "Parts",
    "exact_requests",
    "hull_of",
    "pairs_of",
]

PART = 512
"""The most scene objects one part takes (beside the attached ones every part holds)."""

HULL_FIT = 0.5
"""The share of a pair's last distance on its shapes that its convex hulls' distance must
keep to be taken in its place (:meth:`Parts.lower_bounds`): a matter of speed, not
soundness (the hulls' distance is a lower bound whatever it is)."""

EVERY_PAIR = False
"""``stopAtFirstCollision`` of every check over every pair: each pair is tested at every
configuration. With Pinocchio's default requests, stopping at the first collision once
called a configuration 0.7 mm deep in contact free (the Katana 6M180): GJK then started
from where a pair's last check, at another configuration, had ended, and what a check
answered depended on what was checked before. :func:`exact_requests` now starts every
check afresh; the full checks still test every pair, and the batch check tests the
pre-filter's undecided pairs to the first that collides."""


def exact_requests(gdata: pin.GeometryData) -> pin.GeometryData:
    """``gdata`` with every pair's collision request coal's own default instead of
    Pinocchio's, so that coal's answer is its signed distance's sign, whatever was checked
    before. The two differ in two settings:

    * contacts computed (``enable_contact``): without them, coal 3's box-box test called
      the Panda's finger box free while wholly inside a 4 cm wall, 25 mm deep, and missed
      penetrations of 0.1-5.5 mm in MotionBenchMaker's bookshelf and table scenes (ad hoc:
      1-2 pairs in 3,000 configurations near the scenes' grasps; with contacts, none in
      8,000 against coal's signed distance, at the same speed);
    * GJK started from coal's default guess, not from where the pair's last check ended
      (Pinocchio's cached guess): from a check at another configuration, the finger 0.8 mm
      inside a cylinder was called free after 3,000 other checks, colliding when checked
      alone.

    Fresh requests are copied in (setting the deprecated cached-guess switch would warn,
    and silencing the warning is not thread-safe). ``tests/collision/test_requests.py``."""
    import coal

    request = coal.CollisionRequest()
    request.enable_contact = True
    request.gjk_initial_guess = coal.GJKInitialGuess.DefaultGuess
    requests = gdata.collisionRequests
    for k in range(len(requests)):
        requests[k] = request
    return gdata


def pairs_of(geom: pin.GeometryModel) -> tuple[np.ndarray, np.ndarray]:
    """(first, second) (pairs,): each pair's two shapes, the lower first, in the pairs'
    order (Pinocchio's pair table read at once; pair by pair where it is out of step)."""
    count, n = len(geom.collisionPairs), int(geom.ngeoms)
    table = np.asarray(geom.collisionPairMapping)
    if table.shape == (n, n) and int((table >= 0).sum()) == 2 * count:
        first, second = np.nonzero(np.triu(table >= 0, 1))
        index = table[first, second]
        if np.array_equal(np.sort(index), np.arange(count)):
            out = np.empty((2, count), np.int64)
            out[0, index], out[1, index] = first, second
            return out[0], out[1]
    pairs = geom.collisionPairs
    return (np.array([min(p.first, p.second) for p in pairs], np.int64),
            np.array([max(p.first, p.second) for p in pairs], np.int64))  # fmt: skip


def hull_of(shape: Any) -> Any:
    """The convex hull of a mesh shape (a coal ``ConvexBase`` holding every vertex); None
    for any other shape, and for a mesh of fewer than 4 vertices or a flat one
    (:data:`FLAT`)."""
    import coal

    if not isinstance(shape, coal.BVHModelBase):
        return None
    return convex_hull(np.asarray(shape.vertices(), dtype=float))


def _transform(M: pin.SE3) -> Any:
    """A placement as coal's transform."""
    import coal

    return coal.Transform3s(M.rotation, M.translation)


def _data_of(geom: pin.GeometryModel) -> Any:
    """A maker of ``geom``'s data with :func:`exact_requests`."""
    return lambda: exact_requests(geom.createData())


class AllShapes:
    """Every object and pair of the parts, numbered as one model (what
    :class:`~toolkit.collision.bounds.Bounds` reads of a ``GeometryModel``: its objects,
    and its pairs as two arrays, :func:`~toolkit.collision.bounds.pair_arrays`)."""

    def __init__(self, objects: list[Any], first: np.ndarray, second: np.ndarray) -> None:
        self.geometryObjects = objects
        self.ngeoms = len(objects)
        self.first, self.second = first, second


class Parts:
    """The parts of one checker (module doc): ``parts`` (the first holds the robot's own
    pairs), ``robot_count`` shapes of the robot at the head of each."""

    def __init__(
        self, model: pin.Model, parts: list[pin.GeometryModel], robot_count: int, shared: int = 0
    ) -> None:
        """``shared``: the objects after the robot's shapes that every part holds (copies
        in the others: the scene's attached objects, first in the first part)."""
        self.model, self.parts, self.robot_count = model, parts, robot_count
        self.objects = list(parts[0].geometryObjects)
        head = robot_count + shared  # local numbers below this are the first part's
        firsts, seconds, part, local = [], [], [], []
        for p, geom in enumerate(parts):
            offset = len(self.objects) - head if p else 0
            if p:
                self.objects += list(geom.geometryObjects)[head:]
            a, b = pairs_of(geom)
            firsts.append(np.where(a >= head, a + offset, a))
            seconds.append(np.where(b >= head, b + offset, b))
            part.append(np.full(len(a), p, np.int64))
            local.append(np.arange(len(a), dtype=np.int64))
        self.first, self.second = np.concatenate(firsts), np.concatenate(seconds)
        self.part, self.local = np.concatenate(part), np.concatenate(local)
        self._ends = [pairs_of(g) for g in parts]  # each part's pairs' objects, its numbers
        self._hulls: dict[int, Any] = {}  # object -> its mesh's convex hull (None: no mesh)
        self._piece_sets: dict[int, Pieces | None] = {}  # object -> its convex pieces
        self._hull_lock = threading.Lock()
        self._last: dict[int, float] = {}  # pair -> its last distance on the shapes themselves
        self._data = PerThread(model.createData)
        self._gdata = [PerThread(_data_of(g)) for g in parts]
        self._pools: list[Any] = []
        self._pool_lock = threading.Lock()

    @property
    def shapes(self) -> Any:
        """What the pre-filter reads: the one model itself, or :class:`AllShapes`."""
        if len(self.parts) == 1:
            return self.parts[0]
        return AllShapes(self.objects, self.first, self.second)

    def flags(self, q: np.ndarray) -> np.ndarray:
        """Per pair, 1 where it collides at q (0 otherwise)."""
        data, out = self._data.get(), []
        for geom, gdata in zip(self.parts, self._gdata, strict=True):
            gd = gdata.get()
            pin.computeCollisions(self.model, data, geom, gd, q, False)
            out += [r.isCollision() for r in gd.collisionResults]
        return np.array(out, dtype=np.int64)

    def any(self, q: np.ndarray) -> bool:
        """Whether a pair collides at q."""
        data = self._data.get()
        return any(pin.computeCollisions(self.model, data, geom, gdata.get(), q, EVERY_PAIR)
                   for geom, gdata in zip(self.parts, self._gdata, strict=True))  # fmt: skip

    def first_hit(self, q: np.ndarray) -> int | None:
        """The first pair that collides at q (None: none)."""
        data, start = self._data.get(), 0
        for geom, gdata in zip(self.parts, self._gdata, strict=True):
            gd = gdata.get()
            if pin.computeCollisions(self.model, data, geom, gd, q, EVERY_PAIR):
                for k, result in enumerate(gd.collisionResults):
                    if result.isCollision():
                        return start + k
            start += len(geom.collisionPairs)
        return None

    def nearest(self, q: np.ndarray) -> tuple[float, int]:
        """(the smallest distance [m] over the pairs at q, its pair) ((inf, -1): none)."""
        data, start, best = self._data.get(), 0, (float("inf"), -1)
        for geom, gdata in zip(self.parts, self._gdata, strict=True):
            if len(geom.collisionPairs):
                gd = gdata.get()
                k = int(pin.computeDistances(self.model, data, geom, gd, q))
                best = min(best, (float(gd.distanceResults[k].min_distance), start + k))
            start += len(geom.collisionPairs)
        return best

    def listed_collide(self, Q: np.ndarray, rows: np.ndarray, listed: np.ndarray) -> np.ndarray:
        """Per row i of Q in ``rows``: whether one of the pairs ``listed[i]`` names collides,
        to the first that does (each part placed when one of its pairs is first asked)."""
        data = self._data.get()
        model, parts, gdatas = self.model, self.parts, [g.get() for g in self._gdata]
        out = np.zeros(len(rows), dtype=bool)
        for j, i in enumerate(rows.tolist()):
            placed = [False] * len(parts)
            for k in listed[i, 1 : 1 + listed[i, 0]].tolist():
                p = int(self.part[k])
                if not placed[p]:
                    pin.updateGeometryPlacements(model, data, parts[p], gdatas[p], Q[i])
                    placed[p] = True
                if pin.computeCollision(parts[p], gdatas[p], int(self.local[k])):
                    out[j] = True
                    break
        return out

    def _placed(self, q: np.ndarray, pairs: np.ndarray) -> Iterator[tuple[int, int, int, Any]]:
        """Per pair k of ``pairs`` (its n-th): (n, k, its part, that part's data), each
        part placed at q when one of its pairs is first reached."""
        data = self._data.get()
        gdatas = [g.get() for g in self._gdata]
        placed = [False] * len(self.parts)
        for n, k in enumerate(np.asarray(pairs).tolist()):
            p = int(self.part[k])
            if not placed[p]:
                pin.updateGeometryPlacements(self.model, data, self.parts[p], gdatas[p], q)
                placed[p] = True
            yield n, k, p, gdatas[p]

    def distances(self, q: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """Coal's distances [m] of ``pairs`` at q (each part placed once)."""
        out = np.empty(len(pairs))
        for n, k, p, gd in self._placed(q, pairs):
            out[n] = pin.computeDistance(self.parts[p], gd, int(self.local[k])).min_distance
        return out

    def lower_bounds(self, q: np.ndarray, pairs: np.ndarray, need: np.ndarray) -> np.ndarray:
        """Per pair of ``pairs``, a lower bound [m] of coal's distance at q: the distance of
        the convex hulls of its meshes where that reaches the pair's ``need`` [m], else the
        least distance of their convex pieces where that does
        (:func:`~toolkit.collision.pieces.pieces_distance`), else coal's distance on the
        shapes themselves (each part placed once). Where the hulls or the pieces fall
        short of ``need`` but keep :data:`HULL_FIT` of the pair's last distance on its
        shapes, their answer is taken too: a lower bound either way; a certificate
        walking a segment then takes steps a little shorter, each far cheaper.

        A mesh lies inside its convex hull, so the hulls are no nearer than the meshes; on
        MBM's UR5 the hulls of the forearm and wrist 2 (220 and 180 points) answered in 9 us
        where the meshes (1,050 and 702 triangles) took 190 us, at 0.98 of their distance
        (the median over 200 random configurations, ad hoc)."""
        import coal

        out = np.empty(len(pairs))
        request = coal.DistanceRequest()
        for n, k, p, gd in self._placed(q, pairs):
            local = int(self.local[k])
            a, b = int(self._ends[p][0][local]), int(self._ends[p][1][local])
            ha, hb = self._hull(int(self.first[k]), p, a), self._hull(int(self.second[k]), p, b)
            if ha is not None or hb is not None:
                objects = self.parts[p].geometryObjects
                shapes = (ha if ha is not None else objects[a].geometry,
                          hb if hb is not None else objects[b].geometry)  # fmt: skip
                result = coal.DistanceResult()
                coal.distance(shapes[0], _transform(gd.oMg[a]), shapes[1],
                              _transform(gd.oMg[b]), request, result)  # fmt: skip
                hull = result.min_distance
                if hull >= need[n] or hull >= HULL_FIT * self._last.get(k, np.inf):
                    out[n] = hull
                    continue
            pa, pb = self._pieces(int(self.first[k]), p, a), self._pieces(int(self.second[k]), p, b)
            if pa is not None and pb is not None and len(pa.hulls) + len(pb.hulls) > 2:
                lower = pieces_distance(pa, gd.oMg[a], pb, gd.oMg[b])
                if lower >= need[n] or lower >= HULL_FIT * self._last.get(k, np.inf):
                    out[n] = lower
                    continue
            out[n] = pin.computeDistance(self.parts[p], gd, local).min_distance
            self._last[k] = out[n]
        return out

    def _pieces(self, obj: int, part: int, local: int) -> Pieces | None:
        """:func:`~toolkit.collision.pieces.pieces_of` object ``obj``'s shape, made once."""
        return self._made_once(self._piece_sets, pieces_of, obj, part, local)

    def _hull(self, obj: int, part: int, local: int) -> Any:
        """:func:`hull_of` object ``obj``'s shape (``local`` in ``part``), made once."""
        return self._made_once(self._hulls, hull_of, obj, part, local)

    def _made_once(
        self, kept: dict[int, Any], make: Any, obj: int, part: int, local: int
    ) -> Any:  # fmt: skip
        """``make`` of object ``obj``'s shape (``local`` in ``part``), kept in ``kept``: made
        once (two threads may both make it; the first kept is the one answered), and per
        shape object for the process (:func:`~toolkit.collision.pieces.kept_for`: a robot's
        links in every scene's checker are the same objects)."""
        if obj in kept:
            return kept[obj]
        made = kept_for(self.parts[part].geometryObjects[local].geometry, make.__name__, make)
        with self._hull_lock:
            return kept.setdefault(obj, made)

    def many(self, Q: np.ndarray) -> np.ndarray:
        """Flags (N,) by coal on every pair of every part, over every core."""
        threads = max(1, os.cpu_count() or 1)
        with self._pool_lock:
            if not self._pools:
                for geom in self.parts:
                    pool = pin.GeometryPool(self.model, geom, threads)
                    for k in range(threads):  # its data in place (no template data built)
                        exact_requests(pool.getGeometryData(k))
                    self._pools.append(pool)
            flags = np.zeros(len(Q), dtype=bool)
            for pool in self._pools:
                flags |= np.asarray(pin.computeCollisionsInParallel(
                    threads, pool, np.asfortranarray(Q.T), EVERY_PAIR), dtype=bool)  # fmt: skip
        return flags
