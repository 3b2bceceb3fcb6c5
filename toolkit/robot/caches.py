"""What a :class:`~toolkit.robot.Robot`'s collision queries keep once computed: per robot
(never per module), made with the robot, under its own lock (made anew in a forked
child). Its IK keeps its own (:class:`toolkit.ik.BranchCaches`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..common import Kept

__all__ = ["Caches"]


class Caches(Kept):
    """A robot's collision caches: ``checkers`` (a collision checker per scene content),
    ``covers`` (the sphere covers of its collision shapes), ``shapes`` (those shapes and
    their checked pairs), which its checkers share, and ``reach`` (what the planner's
    whole-motion bound reads of its joints and shapes, the same in every scene); ``lock``
    guards them."""

    def __init__(self) -> None:
        super().__init__()
        self.checkers: dict[str, Any] = {}
        self.covers: Any = None
        self.shapes: dict[bool, Any] = {}
        self.reach: dict[Any, Any] = {}

    def kept_covers(self, make: Callable[[], Any]) -> Any:
        """The robot's shapes' sphere covers and surface points, packed for the collision
        pre-filter (:mod:`toolkit.collision.bounds`), made by ``make`` the first time (under
        the lock) and shared by its checkers of every scene."""
        with self.lock:
            if self.covers is None:
                self.covers = make()
            return self.covers

    def kept_shapes(self, srdf: bool, make: Callable[[], Any]) -> Any:
        """The robot's collision shapes and the pairs checked among them (with the SRDF's
        disabled pairs dropped or not), made by ``make`` the first time (under the lock)
        and copied by its checkers of every scene."""
        with self.lock:
            if srdf not in self.shapes:
                self.shapes[srdf] = make()
            return self.shapes[srdf]

    def kept_reach(self, key: Any, make: Callable[[], Any]) -> Any:
        """What the planner's bound reads under ``key`` (its joints' facts, or its shapes'
        rows per shape set: :func:`toolkit.planning.geometry.reach`), made by ``make`` the first
        time (under the lock) and shared by its checkers of every scene."""
        with self.lock:
            if key not in self.reach:
                self.reach[key] = make()
            return self.reach[key]
