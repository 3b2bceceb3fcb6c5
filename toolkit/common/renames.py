"""Keywords renamed for one vocabulary across the API (docs/conventions.md): the old name
still works for one release, with a :class:`DeprecationWarning` that names the new one.

:data:`RENAMED` lists every such keyword (a test calls each by its old name)."""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable, Mapping
from typing import ParamSpec, TypeVar

from ..errors import InvalidParameterError
from .shared import caller_level

__all__ = ["RENAMED", "rename_keys", "renamed", "warn_renamed"]

P = ParamSpec("P")
R = TypeVar("R")

RENAMED: list[tuple[str, str, str]] = []
"""(function, old keyword, new keyword) of every keyword renamed."""


def warn_renamed(where: str, old: str, new: str) -> None:
    """The :class:`DeprecationWarning` of an old name ``old`` now ``new``, at the user's
    line."""
    warnings.warn(
        f"{where}: the keyword {old}= is now {new}=; the old name goes in the next release",
        DeprecationWarning,
        stacklevel=caller_level(),
    )


def rename_keys(where: str, kwargs: dict[str, object], pairs: Mapping[str, str]) -> None:
    """In place: each old keyword of ``pairs`` (old -> new) in ``kwargs`` warned
    (:func:`warn_renamed`) and moved to its new name; both names at once refused. For a
    call that takes its keywords as a mapping; :func:`renamed` decorates the others."""
    for old, new in pairs.items():
        if old in kwargs:
            if new in kwargs:
                raise InvalidParameterError(f"{where}: give {new}= only ({old}= is its old name)")
            warn_renamed(where, old, new)
            kwargs[new] = kwargs.pop(old)


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
                rename_keys(where, kwargs, pairs)
            return func(*args, **kwargs)

        return wrapper

    return decorate
