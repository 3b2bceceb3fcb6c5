"""The collision checker of one robot and one scene (see :mod:`toolkit.collision`), and the
collision-free IK behind ``Robot.ik(..., collision_free=True)``."""

from __future__ import annotations

import os
import threading
import warnings
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ._bound_states import CLOSE, HIT
from ._bounds import Bounds
from ._scene import CollisionGeometryWarning, Scene
from ._shared import PerThread, caller_level
from ._task import PoseTask
from .descriptions import PackageResolver, read_description
from .engine import CompiledBackend, parallel
from .errors import FrameNotFoundError, InvalidParameterError, ModelLoadError
from .ik import IKOptions, IKResult, kernel_seed, solve_ik, verify

if TYPE_CHECKING:
    from .robot import Robot

__all__ = ["Checker", "CollisionQueries", "checker_for", "single_solver", "solve_collision_free"]

_LOCK = threading.Lock()
EVERY_PAIR = False
"""``stopAtFirstCollision`` of every check: each pair is tested at every configuration.
Stopping at the first collision leaves the later pairs' coal state behind, and a later
configuration 0.7 mm deep in contact was then called free (found on the Katana 6M180, in
both Pinocchio's serial and parallel checks); testing every pair costs little, because
the pre-filter clears most configurations before coal sees them."""


def _robot_geometry(robot: Robot) -> tuple[pin.GeometryModel, bool]:
    """The robot's collision shapes (its visual ones, with a warning, when it has none),
    and whether they are the visual stand-ins."""
    if robot.urdf_path is None:
        raise ModelLoadError(f"{robot.name}: no URDF file, so no collision shapes")
    text = read_description(robot.urdf_path)
    text = PackageResolver(None, robot.urdf_path).absolute_uris(text)
    for kind in (pin.GeometryType.COLLISION, pin.GeometryType.VISUAL):
        try:
            geom = pin.buildGeomFromUrdfString(robot.model, text, kind)
        except (ValueError, RuntimeError) as exc:
            raise ModelLoadError(f"{robot.name}: cannot load its shapes: {exc}") from exc
        if geom.ngeoms:
            visual = kind == pin.GeometryType.VISUAL
            if visual:
                warnings.warn(
                    f"{robot.name}: the description has no <collision> shapes; its visual "
                    "shapes stand in for them (pairs that touch at the neutral "
                    "configuration are not checked)",
                    CollisionGeometryWarning,
                    stacklevel=caller_level(),
                )
            return geom, visual
    return geom, False


class Checker:
    """Exact collision queries of one robot among the objects of one scene."""

    def __init__(self, robot: Robot, scene: Scene | None, *, srdf: bool = True) -> None:
        model = robot.model
        self.model = model
        geom, visual = _robot_geometry(robot)
        self.robot_count = geom.ngeoms
        geom.addAllCollisionPairs()
        self.shaped_parent = self._shaped_parents(geom)
        self._drop_adjacent(geom)
        if visual:  # visual shapes overlap at the joints: what touches at rest is design
            self._drop_touching(geom, robot.neutral())
        if srdf and robot.srdf_path is not None:
            pin.removeCollisionPairs(model, geom, str(robot.srdf_path))
        self.names = [self._link_name(g) for g in geom.geometryObjects]
        for obj in scene or Scene():
            self._add_object(robot, geom, obj)
        self.geom = geom
        self._data = PerThread(model.createData)
        self._gdata = PerThread(geom.createData)
        self._pool: Any = None
        self._pool_lock = threading.Lock()
        backend = robot._backend
        self.bounds = Bounds(geom, backend) if isinstance(backend, CompiledBackend) else None

    def _link_name(self, g: Any) -> str:
        frame = int(g.parentFrame)
        if 0 <= frame < len(self.model.frames):
            return str(self.model.frames[frame].name)
        return str(self.model.names[int(g.parentJoint)])

    def _drop_adjacent(self, geom: pin.GeometryModel) -> None:
        """Links joined by a joint touch by design: their pairs are never checked. Links
        without shapes do not count, so two shaped links joined through shapeless ones
        (a universal joint built of two joints) are adjacent too."""
        keep = [
            pair
            for pair in geom.collisionPairs
            if not self.adjacent(
                int(geom.geometryObjects[pair.first].parentJoint),
                int(geom.geometryObjects[pair.second].parentJoint),
            )
        ]
        geom.removeAllCollisionPairs()
        for pair in keep:
            geom.addCollisionPair(pair)

    def _shaped_parents(self, geom: pin.GeometryModel) -> list[int]:
        """Per joint, its nearest ancestor joint that carries a shape (0: the base)."""
        shaped = {int(g.parentJoint) for g in geom.geometryObjects}
        parents = self.model.parents
        found = [0] * self.model.njoints
        for j in range(1, self.model.njoints):
            p = int(parents[j])
            while p != 0 and p not in shaped:
                p = int(parents[p])
            found[j] = p
        return found

    def adjacent(self, a: int, b: int) -> bool:
        """Whether the bodies of joints a and b are the same or joined (see above)."""
        up = self.shaped_parent
        return a == b or up[a] == b or up[b] == a

    def _drop_touching(self, geom: pin.GeometryModel, q: np.ndarray) -> None:
        data, gdata = self.model.createData(), geom.createData()
        pin.computeCollisions(self.model, data, geom, gdata, q, False)
        keep = [
            pair
            for pair, result in zip(geom.collisionPairs, gdata.collisionResults, strict=True)
            if not result.isCollision()
        ]
        geom.removeAllCollisionPairs()
        for pair in keep:
            geom.addCollisionPair(pair)

    def _add_object(self, robot: Robot, geom: pin.GeometryModel, obj: Any) -> None:
        placement = obj.shape_placement
        joint = 0
        if obj.link:
            try:
                frame = robot.model.frames[robot.frame_id(obj.link)]
            except FrameNotFoundError as exc:
                raise InvalidParameterError(f"attached object {obj.name!r}: {exc}") from None
            joint = int(frame.parentJoint)
            placement = frame.placement * placement
        index = geom.addGeometryObject(pin.GeometryObject(obj.name, joint, placement, obj.shape()))
        self.names.append(obj.name)
        for i in range(self.robot_count):
            other = int(geom.geometryObjects[i].parentJoint)
            if obj.link:  # not its own link, nor the links joined to it
                if self.adjacent(other, joint):
                    continue
            elif other == 0:  # shapes fixed to the base never move: a floor under them is no news
                continue
            geom.addCollisionPair(pin.CollisionPair(i, index))
        for k in range(self.robot_count, index):  # attached objects against the scene
            if bool(obj.link) != bool(geom.geometryObjects[k].parentJoint):
                geom.addCollisionPair(pin.CollisionPair(k, index))

    # ------------------------------------------------------------------ queries
    def pair_flags(self, q: np.ndarray) -> np.ndarray:
        """Per checked pair, 1 where it collides at q (0 otherwise)."""
        data, gdata = self._data.get(), self._gdata.get()
        pin.computeCollisions(self.model, data, self.geom, gdata, q, False)
        return np.array([r.isCollision() for r in gdata.collisionResults], dtype=np.int64)

    def pair_names(self, k: int) -> tuple[str, str]:
        """The link or object names of checked pair k."""
        pair = self.geom.collisionPairs[k]
        return self.names[pair.first], self.names[pair.second]

    def in_collision(self, q: np.ndarray) -> bool:
        data, gdata = self._data.get(), self._gdata.get()
        return bool(pin.computeCollisions(self.model, data, self.geom, gdata, q, EVERY_PAIR))

    def in_collision_many(self, Q: np.ndarray) -> np.ndarray:
        """Flags (N,) for configurations Q (N, nq). The compiled pre-filter
        (:mod:`toolkit._bounds`) decides the configurations whose pairs are certainly
        apart, or certainly overlap; coal checks the others: over every core by Pinocchio's
        ``computeCollisionsInParallel`` from :data:`~toolkit.engine.PARALLEL_MIN` rows on
        (one batch at a time), one by one below that or inside ``engine.serial()``."""
        if self.bounds is None or not len(Q):
            return self._exact_many(Q)
        state = self.bounds.decide(Q)
        flags = state == HIT
        close = state == CLOSE
        if close.any():
            flags[close] = self._exact_many(Q[close])
        return flags

    def _exact_many(self, Q: np.ndarray) -> np.ndarray:
        if not parallel(len(Q)):
            return np.array([self.in_collision(q) for q in Q], dtype=bool)
        threads = max(1, os.cpu_count() or 1)
        with self._pool_lock:
            if self._pool is None:
                self._pool = pin.GeometryPool(self.model, self.geom, threads)
            flags = pin.computeCollisionsInParallel(
                threads, self._pool, np.asfortranarray(Q.T), EVERY_PAIR
            )
        return np.asarray(flags, dtype=bool)

    def collisions(self, q: np.ndarray) -> list[tuple[str, str]]:
        """Every colliding pair, by link or object name."""
        found = [self.pair_names(k) for k in np.flatnonzero(self.pair_flags(q)).tolist()]
        return list(dict.fromkeys(found))

    def first_collision(self, q: np.ndarray) -> tuple[str, str] | None:
        data, gdata = self._data.get(), self._gdata.get()
        if not pin.computeCollisions(self.model, data, self.geom, gdata, q, EVERY_PAIR):
            return None
        for k, result in enumerate(gdata.collisionResults):
            if result.isCollision():
                return self.pair_names(k)
        return None  # pragma: no cover - computeCollisions said there was one

    def min_distance(self, q: np.ndarray) -> tuple[float, tuple[str, str]]:
        """The smallest distance [m] over the checked pairs (negative: penetration)."""
        if not len(self.geom.collisionPairs):
            return float("inf"), ("", "")
        data, gdata = self._data.get(), self._gdata.get()
        k = int(pin.computeDistances(self.model, data, self.geom, gdata, q))
        return float(gdata.distanceResults[k].min_distance), self.pair_names(k)


def checker_for(robot: Robot, scene: Scene | None) -> Checker:
    """The robot's checker for ``scene`` (built once per scene content, then shared)."""
    if scene is not None and not isinstance(scene, Scene):
        raise InvalidParameterError(f"scene must be a toolkit Scene or None, got {scene!r:.80}")
    key = "" if scene is None else scene.digest()
    cache: dict[str, Checker] = robot.__dict__.setdefault("_checkers", {})
    with _LOCK:
        found = cache.get(key)
        if found is None:
            found = cache[key] = Checker(robot, scene)
    return found


def solve_collision_free(
    robot: Robot, task: PoseTask, q0: np.ndarray | None, opts: IKOptions, checker: Checker
) -> IKResult:
    """The IK, one start at a time (the same starts as without collisions), until a
    solution that is reached, valid and collision-free; otherwise the best reached one,
    with the pair that collides (or the best unreached one)."""
    state, backend = robot.ik_state, robot._backend
    seed = kernel_seed(opts.seed)
    single = replace(opts, restarts=0, timeout=None)
    first: IKResult | None = None
    best: IKResult | None = None
    for attempt in range(opts.restarts + 1):
        start = (state.mid if q0 is None else q0) if attempt == 0 else state.restart(seed, attempt)
        q, iters, _ = backend.solve(task, start, state, single, seed)
        res = verify(state, task, q, opts.tol, iters, attempt)
        if not res.success:
            if best is None or res.position_error < best.position_error:
                best = res
            continue
        pair = checker.first_collision(res.q)
        if pair is None:
            return res
        if first is None:
            first = res._replace(success=False, collision=pair)
    return (
        first
        if first is not None
        else (best if best is not None else verify(state, task, state.mid, opts.tol))
    )


def single_solver(
    robot: Robot, checker: Checker | None
) -> Callable[[PoseTask, np.ndarray | None, IKOptions], IKResult]:
    """The robot's single IK from a start (None: mid-range), collision-free when a checker
    is given: what ``Robot.ik`` and each step of ``Robot.ik_path`` run."""

    def solve(task: PoseTask, q: np.ndarray | None, opts: IKOptions) -> IKResult:
        if checker is not None:
            return solve_collision_free(robot, task, q, opts, checker)
        return solve_ik(robot._backend, robot.ik_state, task, q, opts)

    return solve


class CollisionQueries:
    """The collision queries of :class:`~toolkit.robot.Robot` (mixed into it)."""

    def _checker(self, scene: Scene | None, collision_free: bool | None) -> Checker | None:
        """The checker an IK call asks for: ``collision_free`` None means "when a scene is
        given"; a scene without ``collision_free`` is refused (it would be ignored)."""
        robot: Robot = self  # type: ignore[assignment]
        if collision_free is None:
            collision_free = scene is not None
        if not isinstance(collision_free, bool):
            raise InvalidParameterError(
                f"collision_free must be True, False or None, got {collision_free!r}"
            )
        if collision_free:
            return checker_for(robot, scene)
        if scene is not None:
            raise InvalidParameterError("a scene is used with collision_free=True only")
        return None

    def in_collision(self, q: ArrayLike, scene: Scene | None = None) -> bool | np.ndarray:
        """True if the robot at q hits itself (pairs as in :mod:`toolkit.collision`) or an
        object of ``scene``; q of shape (N, nq) gives (N,) flags."""
        robot: Robot = self  # type: ignore[assignment]
        arr = robot.check_q(q, batch=True)
        checker = checker_for(robot, scene)
        if arr.ndim == 1:
            return checker.in_collision(arr)
        return checker.in_collision_many(arr)

    def collisions(self, q: ArrayLike, scene: Scene | None = None) -> list[tuple[str, str]]:
        """The colliding pairs at q (one configuration), by link or object name."""
        robot: Robot = self  # type: ignore[assignment]
        return checker_for(robot, scene).collisions(robot.check_q(q))

    def min_distance(
        self, q: ArrayLike, scene: Scene | None = None
    ) -> tuple[float, tuple[str, str]] | tuple[np.ndarray, list[tuple[str, str]]]:
        """(distance [m], pair) of the closest checked pair at q, negative when shapes
        penetrate; q of shape (N, nq) gives ((N,) distances, N pairs)."""
        robot: Robot = self  # type: ignore[assignment]
        arr = robot.check_q(q, batch=True)
        checker = checker_for(robot, scene)
        if arr.ndim == 1:
            return checker.min_distance(arr)
        rows = [checker.min_distance(row) for row in arr]
        return np.array([d for d, _ in rows]), [p for _, p in rows]
