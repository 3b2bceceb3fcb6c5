"""Keywords renamed for one vocabulary across the API (docs/conventions.md): the old name
still works for one release, with a :class:`DeprecationWarning` that names the new one.

:data:`RENAMED` lists every such keyword (a test calls each by its old name)."""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from typing import ParamSpec, TypeVar

from ..errors import InvalidParameterError
from .shared import caller_level

__all__ = ["RENAMED", "renamed"]

P = ParamSpec("P")
R = TypeVar("R")

RENAMED: list[tuple[str, str, str]] = []
"""(function, old keyword, new keyword) of every keyword renamed."""


def renamed(**pairs: str) -> Callable[[Callable[P, R]], Callable[P, R]]:
    """Decorate a function whose keywords ``old="new"`` were renamed: a call by the old
    name warns (``DeprecationWarning``, at the user's line) and passes the value on under
    the new one; both names at once are refused. The signature shown is the new one."""

    def decorate(func: Callable[P, R]) -> Callable[P, R]:
        where = func.__qualname__
        for old, new in pairs.items():
            RENAMED.append((f"{func.__module__}.{where}", old, new))

        @functools.wraps(func)
        def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
            if kwargs:
                for old, new in pairs.items():
                    if old in kwargs:
                        if new in kwargs:
                            raise InvalidParameterError(
                                f"{where}: give {new}= only ({old}= is its old name)"
                            )
                        warnings.warn(
                            f"{where}: the keyword {old}= is now {new}=; the old name goes "
                            "in the next release",
                            DeprecationWarning,
                            stacklevel=caller_level(),
                        )
                        kwargs[new] = kwargs.pop(old)
            return func(*args, **kwargs)

        return wrapper

    return decorate
