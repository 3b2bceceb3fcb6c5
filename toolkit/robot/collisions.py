"""A robot's collision queries (a part of :class:`~toolkit.robot.Robot`), each on the
checker of its scene, built once per scene content and kept on the robot."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..collision import Checker, CollisionSubject, Scene
from ..errors import InvalidParameterError
from ..kinematics import JointLayout
from ..planning import RESOLUTION, PlannerSettings, PlanResult
from . import plans
from .checkers import checker_for

__all__ = ["CollisionQueries", "checker_for"]


class CollisionQueries:
    """A robot's collisions and plans (a part of :class:`~toolkit.robot.Robot`:
    ``robot.in_collision``, ``collision_checker`` and ``plan`` are its methods)."""

    def __init__(self, robot: CollisionSubject, joints: JointLayout) -> None:
        self.robot, self.joints = robot, joints

    def checker(self, scene: Scene | None, collision_free: bool | None) -> Checker | None:
        """The checker an IK call asks for: ``collision_free`` None means "when a scene is
        given"; a scene without ``collision_free`` is refused (it would be ignored)."""
        if collision_free is None:
            collision_free = scene is not None
        if not isinstance(collision_free, bool):
            raise InvalidParameterError(
                f"collision_free must be True, False or None, got {collision_free!r}"
            )
        if collision_free:
            return checker_for(self.robot, scene)
        if scene is not None:
            raise InvalidParameterError("a scene is used with collision_free=True only")
        return None

    def collision_checker(
        self, scene: Scene | None = None, collision_free: bool | None = True
    ) -> Checker | None:
        """The exact checker of this robot among ``scene``'s objects (built once per scene
        content, kept on the robot; its ``in_collision_many`` checks many configurations at
        once), or None when ``collision_free`` is False; None means "when a scene is
        given", as for :meth:`ik`."""
        return self.checker(scene, collision_free)

    def in_collision(self, q: ArrayLike, scene: Scene | None = None) -> bool | np.ndarray:
        """True if the robot at q hits itself (pairs as in :mod:`toolkit.collision`) or an
        object of ``scene``; q of shape (N, nq) gives (N,) flags."""
        arr = self.joints.check(q, batch=True)
        checker = checker_for(self.robot, scene)
        if arr.ndim == 1:
            return checker.in_collision(arr)
        return checker.in_collision_many(arr)

    def base_collisions(self, scene: Scene | None) -> list[tuple[str, str]]:
        """The pairs (link, object) of the shapes fixed to the base that collide with
        ``scene``'s fixed objects: the same at every configuration (a base inside a table);
        a support (a floor, ``add_box(..., support=True)``) may be touched and entered by
        :data:`~toolkit.collision.SUPPORT_SLACK`."""
        return list(checker_for(self.robot, scene).base_hits)

    def collisions(self, q: ArrayLike, scene: Scene | None = None) -> list[tuple[str, str]]:
        """The colliding pairs at q (one configuration), by link or object name."""
        return checker_for(self.robot, scene).collisions(self.joints.check(q))

    def min_distance(
        self, q: ArrayLike, scene: Scene | None = None
    ) -> tuple[float, tuple[str, str]] | tuple[np.ndarray, list[tuple[str, str]]]:
        """(distance [m], pair) of the closest checked pair at q, negative when shapes
        penetrate; q of shape (N, nq) gives ((N,) distances, N pairs)."""
        arr = self.joints.check(q, batch=True)
        checker = checker_for(self.robot, scene)
        if arr.ndim == 1:
            return checker.min_distance(arr)
        rows = [checker.min_distance(row) for row in arr]
        return np.array([d for d, _ in rows]), [p for _, p in rows]

    def plan(
        self, start: ArrayLike, goal: ArrayLike | None = None, *, pose: object = None,
        scene: Scene | None = None, frame: str | None = None, hold: object = None,
        time_limit: float = 5.0, seed: int = 0, resolution: float = RESOLUTION,
        simplify: bool = True, settings: PlannerSettings | None = None,
    ) -> PlanResult:  # fmt: skip
        """A path free of collision (with the robot itself and ``scene``, on the exact
        shapes) from ``start`` to ``goal``: one configuration (nq,) or several (G, nq), any
        of them; or to a tool ``pose`` of ``frame`` (4, 4), or any of several (P, 4, 4),
        whose goals are every analytic branch within the limits and free of collision
        (numeric IK from random starts where the arm has no structure). ``hold``: joint
        names (fingers) kept at their start values all along. Bidirectional
        RRT-Connect in joint values (``seed``: the same plan for the same inputs), the path
        shortened by straight cuts (``simplify``), every straight segment between waypoints
        checked at configurations at most ``resolution`` [rad or m per joint] apart. The
        search runs first compiled on what the sphere covers prove free, and a path it finds
        is certified over its whole motion where it can be (``swept``: the certificate is
        then the final check; a short segment leaving an end the covers do not clear,
        ``escapes``, is checked on the exact shapes); any other path is checked again
        whole on the exact shapes, and the exact checker's search takes over where the
        covers' finds nothing (``search`` says which). The call returns within
        ``time_limit`` [s], building the scene's checker and solving a pose's goals
        included (a first use's compiling of kernels is not counted; ``time_s`` is the
        time so counted); without a path, ``success`` is False and
        ``reason`` says why. A start or goal outside the limits or in collision is refused
        naming the pair. ``settings``: the searches' tunables
        (:class:`toolkit.planning.PlannerSettings`; None: the defaults).
        See :class:`toolkit.planning.PlanResult` and docs/planning.md."""
        return plans.plan(self.robot, start, goal, pose=pose, scene=scene, frame=frame, hold=hold,
                          time_limit=time_limit, seed=seed, resolution=resolution,
                          simplify=simplify, settings=settings)  # fmt: skip
