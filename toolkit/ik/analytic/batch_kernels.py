"""Each family's door kernel, made from one body: its one-target kernel (the family's
compiled body) and the verification of its branches, for N targets in one compiled call
spread over the cores (:func:`door_of`); ``Robot.ik_all`` of one target is a call of one.
Each is compiled as a kernel of its own (a family compiles on its first use, not with the
others), under its own name in numba's cache."""

from __future__ import annotations

import types
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import prange

from ...kinematics import Twin, twin_kernel
from .door_kernels import MANY as _MANY
from .door_kernels import WIDE, pose_flag, reversed_target, target_rows, unpack

__all__ = ["door_of"]


LATER = 8
"""From this many targets on (a chain that is :func:`~toolkit.kinematics.poses.serial`,
every row wanted), the door kernel leaves the rows' verification to
:func:`~toolkit.ik.analytic.door_kernels.verified_rows`, which verifies 64 targets' rows at
once (vectorized; one compilation for every family: inside each door kernel it doubled
the door's compile time); below, row by row (a single ``ik_all``: 0.5 us less)."""


def _each(F, J, near, tol, first, later, Ts, rest, pref):  # pragma: no cover
    """Every branch of targets Ts (N, 4, 4), verified, by the family kernel ``SOLVE`` (a
    global of each copy), in one array P: see :func:`door_of`."""
    N = Ts.shape[0]
    n = pref.shape[1]
    nq = rest.shape[1]
    per = rest.shape[0] > 1  # one rest per target, else one for all
    # a parallel loop takes arrays, not tuples of them: unpacked here, packed in each chunk
    (h, o, tip_R, tip_p), layout, (ints, flts, tip_pl), (family, rev, B) = unpack(F, J)
    qcol, circle, lo, hi, qlo, qhi, sliding = layout
    P = np.empty((N, B + 1, nq + WIDE))  # filled target by target, over the cores
    chunk = 64
    for c in prange((N + chunk - 1) // chunk):
        work = (np.zeros((B, n)), np.zeros(B, np.int64), np.empty((ints.shape[0] + 1, 15)),
                np.zeros((4, 4)))  # fmt: skip
        out, roots, free = np.empty((B, n)), np.empty((B, 3), np.int64), np.empty(B, np.int64)
        Ti, back = np.empty((4, 4)), np.empty(n)
        arm = ((qcol, circle, lo, hi, qlo, qhi, sliding), (ints, flts, tip_pl))
        for i in range(c * chunk, min(N, (c + 1) * chunk)):
            r = i if per else 0
            Pi = P[i]
            Pi[:, : nq + 3] = np.nan
            Pi[:, nq + 3 :] = 0.0
            Pi[:B, nq + 3 : nq + 6] = -1.0
            Pi[B, :] = 0.0
            Pi[B, 2] = -1.0
            T = Ts[i]
            flag = pose_flag(T)
            if flag != 0:
                Pi[B, 1] = flag
                continue
            if rev:
                reversed_target(T, pref[r], Ti, back)
                found = SOLVE(h, o, tip_R, tip_p, Ti, near, back, out, roots, free)  # type: ignore[name-defined]  # noqa: F821
            else:
                found = SOLVE(h, o, tip_R, tip_p, T, near, pref[r], out, roots, free)  # type: ignore[name-defined]  # noqa: F821
            if found < 0:
                Pi[B, 1] = _MANY
                continue
            target_rows(arm, (family, rev, near, tol, first, later), T, rest[r], pref[r],
                        (out, roots, found, free), Pi, work)  # fmt: skip
    return P


def door_of(solve: Callable[..., Any], name: str) -> Twin:
    """The door kernel of the one-target family kernel ``solve`` (its signature:
    ``solve(h, o, tip_R, tip_p, T, near, pref, out, roots, free) -> count``, -1 where a
    target has more branches than ``out``'s rows), named ``<name>_door``: :func:`_each`
    with ``solve`` as its ``SOLVE``; called ``door(spread, F, J, near, tol, first, later,
    Ts, rest, pref) -> P``.

    Every branch of targets Ts (N, 4, 4), verified, in one array P (N, B + 1, nq + 10)
    (one boxed result: a call returning five arrays took 3 us more).

    Rows 0 to B - 1 are branches: q (nq), position [m] and orientation [rad] errors, the
    sum of the chain's |angle - pref| [rad], the roots (shoulder, elbow, wrist: 0, 1 or
    -1), the free bits, within the limits (1 or 0), verified to ``tol`` and within (1 or
    0), the roots as one number (:func:`~toolkit.ik.analytic.door_kernels.label_code`); NaN
    past each target's count, its roots -1 and the rest 0. Row B holds the target's count
    of branches, its flags (:data:`~toolkit.ik.analytic.door_kernels.MOVE`, ``ROUGH_ROWS``,
    ``NOT_POSE``, ``MANY``), the verified row nearest ``pref`` (the least sum of |angle
    - pref|, the first of equals; -1 where none is), the free bits of every row or-ed
    (0: no row is a singular pose's representative), and that nearest verified row's
    position and orientation errors (one read for ``Robot.ik``).
    :func:`~toolkit.ik.analytic.door_kernels.split` reads P as five arrays.

    Per target: the pose is checked, the family solves it (on the reversed chain at T^-1
    where the family was found from the frame's end), branches equal up to whole turns are
    dropped, each is written into a full configuration with every revolute joint at its
    turn within the limits nearest ``pref`` (the wrapped angle in [-pi, pi) where none
    fits) and verified by the kinematics' forward kinematics (which share no code with the
    subproblems) row by row, or, with ``later``, left unverified for
    :func:`~toolkit.ik.analytic.door_kernels.verified_rows`, which
    :meth:`~toolkit.ik.analytic.door.BranchDoor.call` runs next (it decides: from
    :data:`LATER` targets on, without ``first``, on a serial chain).

    ``F``, ``J``: the arm (:func:`~toolkit.ik.analytic.door_kernels.pack`); ``near``: the
    arm is only near its family (rows wrapped, to be polished; none flagged rough);
    ``first``: verify the rows within the limits nearest ``pref`` first and stop at the
    first verified (the others keep NaN errors: what ``Robot.ik`` needs); ``rest`` (1 or
    N, nq): the other joints' values, one for all targets or one each; ``pref`` (1 or N,
    n): the chain's angles in it."""
    names = dict(_each.__globals__, SOLVE=solve)
    body = types.FunctionType(_each.__code__, names, f"{name}_door")
    body.__qualname__ = f"{name}_door"
    body.__module__, body.__doc__ = _each.__module__, _each.__doc__
    return twin_kernel(body)
