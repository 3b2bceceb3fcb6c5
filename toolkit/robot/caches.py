"""What a :class:`~toolkit.robot.Robot` keeps once computed: per robot (never per module),
made with the robot (never added to it lazily), each filled by the code that reads it,
under the robot's own lock (made anew in a forked child)."""

from __future__ import annotations

import os
import threading
import weakref
from collections.abc import Callable
from typing import Any

__all__ = ["LOCKED_KEPT", "Caches"]

LOCKED_KEPT = 64
"""Entries for locked joints kept per cache (a sweep of a locked angle keeps the latest)."""


class Caches:
    """A robot's caches: ``structures`` (its analytic structure per frame and locked
    joints), ``doors`` (the compiled family's door per frame and locked joints),
    ``chain_layouts`` (a chain's limits and coordinates), ``checkers`` (a collision
    checker per scene content), ``covers`` (the sphere covers of its collision shapes)
    and ``shapes`` (those shapes and their checked pairs), which its checkers share;
    ``lock`` guards them (one per robot)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        _ALL.add(self)
        self.structures: dict[object, Any] = {}
        self.doors: dict[object, Any] = {}
        self.chain_layouts: dict[tuple[int, ...], Any] = {}
        self.checkers: dict[str, Any] = {}
        self.covers: list[Any] | None = None
        self.shapes: dict[bool, Any] = {}

    def kept_covers(self, make: Callable[[], list[Any]]) -> list[Any]:
        """The robot's shapes' sphere covers, made by ``make`` the first time (under the
        lock) and shared by its checkers of every scene."""
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

    def keep(self, cache: dict[Any, Any], key: object, value: object) -> None:
        """``cache[key] = value`` under the lock, the oldest entries of locked joints (tuple
        keys) dropped beyond :data:`LOCKED_KEPT`."""
        with self.lock:
            locked = [k for k in cache if isinstance(k, tuple)]
            for old in locked[: max(0, len(locked) + 1 - LOCKED_KEPT)]:
                del cache[old]
            cache[key] = value


_ALL: weakref.WeakSet[Caches] = weakref.WeakSet()


def _fresh_locks() -> None:
    """In a forked child, every robot's lock anew: a lock another thread of the parent held
    at the fork would stay held in the child, and its first cached query would wait for
    ever (``toolkit.planning.plan_many`` forks its workers)."""
    for caches in list(_ALL):
        caches.lock = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_fresh_locks)
