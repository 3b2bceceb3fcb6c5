"""What a :class:`~toolkit.robot.Robot` keeps once computed: per robot (never per module),
made with the robot (never added to it lazily), each filled by the code that reads it,
under the robot's own lock."""

from __future__ import annotations

import threading
from typing import Any

__all__ = ["LOCKED_KEPT", "Caches"]

LOCKED_KEPT = 64
"""Entries for locked joints kept per cache (a sweep of a locked angle keeps the latest)."""


class Caches:
    """A robot's caches: ``structures`` (its analytic structure per frame and locked
    joints), ``doors`` (the compiled family's door per frame and locked joints),
    ``chain_layouts`` (a chain's limits and coordinates) and ``checkers`` (a collision
    checker per scene content); ``lock`` guards them (one per robot)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.structures: dict[object, Any] = {}
        self.doors: dict[object, Any] = {}
        self.chain_layouts: dict[tuple[int, ...], Any] = {}
        self.checkers: dict[str, Any] = {}

    def keep(self, cache: dict[Any, Any], key: object, value: object) -> None:
        """``cache[key] = value`` under the lock, the oldest entries of locked joints (tuple
        keys) dropped beyond :data:`LOCKED_KEPT`."""
        with self.lock:
            locked = [k for k in cache if isinstance(k, tuple)]
            for old in locked[: max(0, len(locked) + 1 - LOCKED_KEPT)]:
                del cache[old]
            cache[key] = value
