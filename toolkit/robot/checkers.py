"""A robot's collision checker per scene, built once per scene content and kept on the
robot (:class:`~toolkit.robot.caches.Caches`)."""

from __future__ import annotations

from collections.abc import Callable

from ..collision import Checker, CollisionSubject, Scene
from ..errors import InvalidParameterError
from .caches import Caches

__all__ = ["checker_for"]


def checker_for(
    robot: CollisionSubject, scene: Scene | None, until: Callable[[], bool] | None = None
) -> Checker:
    """The robot's checker for ``scene`` (built once per scene content, then shared);
    ``until``: the build's clock (:class:`~toolkit.collision.Checker`: a build it stops
    raises :class:`~toolkit.collision.CheckerTimeout` and keeps nothing)."""
    if scene is not None and not isinstance(scene, Scene):
        raise InvalidParameterError(f"scene must be a toolkit Scene or None, got {scene!r:.80}")
    key = "" if scene is None else scene.digest()
    caches = getattr(robot, "_caches", None)
    if not isinstance(caches, Caches):  # another subject than a Robot: nothing kept
        return Checker(robot, scene, until=until)
    with caches.lock:
        found: Checker | None = caches.checkers.get(key)
    if found is None:  # built outside the lock (it takes the lock for the shapes it shares);
        # two threads may both build one: the first kept is every caller's
        made = Checker(robot, scene, robot_covers=caches.kept_covers,
                       robot_shapes=caches.kept_shapes, until=until)  # fmt: skip
        with caches.lock:
            found = caches.checkers.setdefault(key, made)
    return found
