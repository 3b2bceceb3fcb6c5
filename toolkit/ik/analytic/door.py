"""The fast door of a compiled family: everything about an arm's chain that does not change
between calls, packed once, so that ``Robot.ik_all`` of one target and ``ik_all_batch`` of N
run the same compiled call (:func:`toolkit.ik.analytic.door_kernels.branch_rows`) with
Python only at the door."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import door_kernels
from .chain import Chain, Structure, exact_for, reverse
from .family import Family

__all__ = ["BranchDoor", "branch_label", "packed_family"]


def branch_label(roots: tuple[int, ...], wrist: bool = True, reversed_: bool = False) -> str:
    """ "shoulder +, elbow -, wrist +" of a 6R (or, without the ``wrist``, a 5R) arm's
    branch (:meth:`~toolkit.ik.analytic.family.Family.label`)."""
    family = Family.THREE_PARALLEL if wrist else Family.FIVE_R_PARALLEL
    return family.label(roots, reversed_)


class _Labels(dict[float, str]):
    """The label of each roots' code (:func:`~toolkit.ik.analytic.door_kernels.label_code`),
    made the first time a code is read (doors of one family share it)."""

    def __init__(self, family: Family, reversed_: bool) -> None:
        super().__init__()
        self.family, self.reversed_ = family, reversed_

    def __missing__(self, code: float) -> str:
        label = self[code] = self.family.label(door_kernels.code_roots(code), self.reversed_)
        return label


@functools.cache
def _label_table(family: Family, reversed_: bool) -> _Labels:
    return _Labels(family, reversed_)


def packed_family(chain: Chain, found: Structure) -> tuple[np.ndarray, ...]:
    """A compiled family kernel's fixed arrays for ``chain`` (as solved: the reversed chain
    of a reversed structure is the caller's to pass): axes, points, the frame's rotation
    and position at zero."""
    assert found.points is not None
    return tuple(np.ascontiguousarray(a, dtype=float) for a in (
        chain.axes, found.points, chain.tip[:3, :3], chain.tip[:3, 3]))  # fmt: skip


@dataclass(frozen=True)
class BranchDoor:
    """A compiled family's chain packed for :func:`~toolkit.ik.analytic.door_kernels.branch_rows`.

    ``chain``, ``found``: the chain and its structure; ``layout``: per chain joint its place
    in q, (cos, sin) pair or not, limits (lower, upper; infinite for a continuous joint),
    then q's limits, then per chain joint prismatic or not; ``fk``: the kinematics
    kernels' chain to the frame; ``mid``: the middle of the limits (the default rest
    configuration) and ``mid_pref`` its chain angles (``mid2``, ``mid_pref2``: the same
    with a leading axis of one); ``places``: the family places a point (its targets are
    positions); ``searched``: its branches come from a search."""

    chain: Chain
    found: Structure
    layout: tuple[np.ndarray, ...]
    fk: tuple[np.ndarray, np.ndarray, np.ndarray]
    mid: np.ndarray
    mid_pref: np.ndarray
    packed: tuple[np.ndarray, np.ndarray] = field(init=False)
    mid2: np.ndarray = field(init=False)
    mid_pref2: np.ndarray = field(init=False)
    exact_at: dict[float, bool] = field(init=False, default_factory=dict)
    names: dict[float, str] = field(init=False)
    places: bool = field(init=False)
    searched: bool = field(init=False)

    def __post_init__(self) -> None:
        family = self.found.family
        assert family is not None and self.found.compiled and self.found.points is not None
        solved = reverse(self.chain) if self.found.reversed else self.chain
        geometry, index = packed_family(solved, self.found), Family(family).kernel_index
        packed = door_kernels.pack(geometry, self.layout, self.fk, index, self.found.reversed)
        object.__setattr__(self, "packed", packed)
        object.__setattr__(self, "mid2", self.mid[None])
        object.__setattr__(self, "mid_pref2", self.mid_pref[None])
        object.__setattr__(self, "names", _label_table(Family(family), self.found.reversed))
        object.__setattr__(self, "places", Family(family).places_point)
        object.__setattr__(self, "searched", Family(family).searched)

    def exact(self, tol: float) -> bool:
        """:func:`~toolkit.ik.analytic.chain.exact_for` of the structure at ``tol``, kept per
        tol."""
        found = self.exact_at.get(tol)
        if found is None:
            found = self.exact_at[tol] = exact_for(self.found, tol)
        return found

    def pref_of(self, rest: np.ndarray) -> np.ndarray:
        """The chain's angles (n,) in a checked configuration ``rest`` (nq,): its joints'
        values, a (cos, sin) pair's angle."""
        qcol, circle = self.layout[0], self.layout[1]
        pref: np.ndarray = rest[qcol]
        if circle.any():
            at = qcol[circle]
            pref[circle] = np.arctan2(rest[at + 1], rest[at])
        return pref

    @property
    def floats(self) -> np.ndarray:
        """The arm's packed floats (:func:`~toolkit.ik.analytic.door_kernels.pack`)."""
        return self.packed[0]

    @property
    def ints(self) -> np.ndarray:
        """The arm's packed integers (:func:`~toolkit.ik.analytic.door_kernels.pack`)."""
        return self.packed[1]

    @property
    def kernel(self) -> Any:
        """:func:`~toolkit.ik.analytic.door_kernels.branch_rows` on one core, called
        directly: the door of one target (``Robot.ik``) keeps its Python short."""
        return door_kernels.branch_rows.serial

    def call(
        self, Ts: np.ndarray, tol: float, rest: np.ndarray, pref: np.ndarray, *,
        near: bool = False, spread: bool = False, first: bool = False,
    ) -> np.ndarray:  # fmt: skip
        """:func:`~toolkit.ik.analytic.door_kernels.branch_rows` of poses Ts (N, 4, 4)
        (C-contiguous float64) with the other joints at ``rest`` (1 or N, nq) and the
        chain's preferred angles ``pref`` (1 or N, n): its one array P; ``near``: wrapped
        rows of an arm only near its family, to be polished; ``spread``: over the cores;
        ``first``: only the nearest verified row is wanted."""
        floats, ints = self.packed
        return door_kernels.branch_rows(spread, floats, ints, near, tol, first, Ts, rest, pref)  # type: ignore[no-any-return]

    def rows(
        self, Ts: np.ndarray, tol: float, rest: np.ndarray, pref: np.ndarray, *,
        near: bool = False, spread: bool = False,
    ) -> tuple[np.ndarray, ...]:  # fmt: skip
        """:meth:`call` read as (Q, E, K, S, C) (:func:`~toolkit.ik.analytic.door_kernels.split`);
        ``rest`` and ``pref`` may be one row each ((nq,), (n,))."""
        if rest.ndim == 1:
            rest, pref = rest[None], pref[None]
        return door_kernels.split(self.call(Ts, tol, rest, pref, near=near, spread=spread))

    def labels(self, roots: np.ndarray) -> list[str]:
        """The label of each branch of ``roots`` (B, 3) (ints, or floats holding them)."""
        codes = [door_kernels.label_code(r) for r in roots.astype(int).tolist()]
        return self.named(np.array(codes, dtype=float))

    def named(self, codes: np.ndarray) -> list[str]:
        """The label of each branch of its roots' codes (B,)
        (:func:`~toolkit.ik.analytic.door_kernels.label_code`)."""
        return list(map(self.names.__getitem__, codes.tolist()))
