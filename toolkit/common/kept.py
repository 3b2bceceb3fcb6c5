"""What an object keeps once computed (a robot's collision checkers, its IK's structures
and doors): per object (never per module), made with the object, each under the object's
own lock, which a forked child makes anew."""

from __future__ import annotations

import os
import threading
import weakref

__all__ = ["Kept"]


class Kept:
    """The base of a cache holder: ``lock`` guards what a subclass keeps (one per object).
    It is reentrant: one kept value may be made from another under it (a robot's deferred
    pairs read its sphere covers, which a first call makes then)."""

    def __init__(self) -> None:
        self.lock = threading.RLock()
        _ALL.add(self)


_ALL: weakref.WeakSet[Kept] = weakref.WeakSet()


def _fresh_locks() -> None:
    """In a forked child, every holder's lock anew: a lock another thread of the parent held
    at the fork would stay held in the child, and its first cached query would wait for
    ever (``toolkit.planning.plan_many`` forks its workers)."""
    for kept in list(_ALL):
        kept.lock = threading.RLock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_fresh_locks)
