"""What :class:`~toolkit.robot.Robot` and :class:`~toolkit.backlash.Backlash` share: values
made once per thread, and pickling, equality and hashing by their constructor arguments."""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from types import FrameType
from typing import Any, Generic, TypeVar

import numpy as np

__all__ = ["ByArguments", "PerThread", "caller_level"]

T = TypeVar("T")


class PerThread(Generic[T]):
    """A value that each thread makes for itself with ``make`` the first time it asks."""

    def __init__(self, make: Callable[[], T]) -> None:
        self._make = make
        self._local = threading.local()

    def get(self) -> T:
        """This thread's value."""
        value: T | None = getattr(self._local, "value", None)
        if value is None:
            value = self._local.value = self._make()
        return value


def _same(a: object, b: object) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return bool(np.array_equal(np.asarray(a), np.asarray(b)))
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        return dict(a) == dict(b)
    return bool(a == b)


class ByArguments:
    """Pickles as, compares by and hashes on the constructor arguments in ``_arguments``.

    Unpickling calls ``__init__`` again, so per-thread caches and derived state are
    rebuilt in the receiving process (a process pool, a Dask worker).
    """

    _arguments: tuple[str, ...] = ()

    def _argument(self, name: str) -> object:
        """The value of constructor argument ``name`` (by default the attribute so named)."""
        return getattr(self, name)

    def __getstate__(self) -> dict[str, Any]:
        state = {name: self._argument(name) for name in self._arguments}
        return {k: dict(v) if isinstance(v, Mapping) else v for k, v in state.items()}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(**state)  # type: ignore[misc]

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_same(self._argument(n), other._argument(n)) for n in self._arguments)

    def __hash__(self) -> int:
        simple = [self._argument(n) for n in self._arguments]
        return hash((type(self).__name__, *(v for v in simple if isinstance(v, str | int | float))))


def caller_level() -> int:
    """The ``stacklevel`` of the first frame outside the toolkit (the user's own line is
    the one a warning shows, never a line of the toolkit's source)."""
    package = str(Path(__file__).resolve().parents[1])  # the toolkit package
    level = 2  # 1 is the function that warns; its caller is frame 2 from here
    frame: FrameType | None = sys._getframe(2)
    while frame is not None and str(Path(frame.f_code.co_filename).resolve()).startswith(package):
        level, frame = level + 1, frame.f_back
    return level
