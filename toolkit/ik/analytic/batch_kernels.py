"""Each family's batch kernel, made from one body: its one-target kernel (the family's
compiled body) over N targets, spread over the cores (:func:`batch_of`). Each is compiled
as a kernel of its own (a family compiles on its first use, not with the others), under
its own name in numba's cache."""

from __future__ import annotations

import types
from collections.abc import Callable
from typing import Any

from numba import prange

from ...kinematics import Twin, twin_kernel
from .subproblem_kernels import finite

__all__ = ["batch_of"]


def _each(h, o, tip_R, tip_p, Ts, near, pref, out, roots, counts, free):  # pragma: no cover
    """The family kernel ``SOLVE`` (a global of each copy) for N targets Ts (N, 4, 4), into
    ``out`` (N, B, n) angles, ``roots`` (N, B, 3), ``counts`` (N,) (0 where a target is not
    finite: the door flags it) and ``free`` (N, B) bits; ``pref`` (1 or N, n): the free
    joints' angles, one row for all targets or one each."""
    N = Ts.shape[0]
    each = 1 if pref.shape[0] > 1 else 0  # numba's prange takes no conditional index
    for i in prange(N):
        counts[i] = 0
        if finite(Ts[i]):
            counts[i] = SOLVE(h, o, tip_R, tip_p, Ts[i], near, pref[i * each], out[i],  # type: ignore[name-defined]  # noqa: F821
                              roots[i], free[i])  # fmt: skip


def batch_of(solve: Callable[..., Any], name: str) -> Twin:
    """The batch kernel of the one-target family kernel ``solve`` (its signature:
    ``solve(h, o, tip_R, tip_p, T, near, pref, out, roots, free) -> count``), named
    ``<name>_batch``: :func:`_each` with ``solve`` as its ``SOLVE``."""
    names = dict(_each.__globals__, SOLVE=solve)
    body = types.FunctionType(_each.__code__, names, f"{name}_batch")
    body.__qualname__ = f"{name}_batch"
    body.__module__, body.__doc__ = _each.__module__, _each.__doc__
    return twin_kernel(body)
