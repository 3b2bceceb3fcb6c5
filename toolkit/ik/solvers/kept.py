"""What a robot's analytic IK keeps once computed (:class:`BranchCaches`), per robot."""

from __future__ import annotations

from typing import Any

from ...common import Kept

__all__ = ["LOCKED_KEPT", "BranchCaches"]

LOCKED_KEPT = 64
"""Entries for locked joints kept per cache (a sweep of a locked angle keeps the latest)."""


class BranchCaches(Kept):
    """``structures`` (the analytic structure per frame and locked joints), ``doors`` (the
    compiled family's door per frame and locked joints), ``chain_layouts`` (a chain's limits
    and coordinates), ``families`` (per frame and set of locked joints, the family found
    at one of their angles: tried first at the next); ``lock`` guards them."""

    def __init__(self) -> None:
        super().__init__()
        self.structures: dict[object, Any] = {}
        self.doors: dict[object, Any] = {}
        self.chain_layouts: dict[tuple[int, ...], Any] = {}
        self.families: dict[object, tuple[str, bool]] = {}

    def keep(self, cache: dict[Any, Any], key: object, value: object) -> None:
        """``cache[key] = value`` under the lock, the oldest entries of locked joints (tuple
        keys) dropped beyond :data:`LOCKED_KEPT`."""
        with self.lock:
            locked = [k for k in cache if isinstance(k, tuple)]
            for old in locked[: max(0, len(locked) + 1 - LOCKED_KEPT)]:
                del cache[old]
            cache[key] = value
