"""The fast door of a compiled family: everything about an arm's chain that does not change
between calls, packed once, so that ``Robot.ik_all`` of one target and ``ik_all_batch`` of N
run the same compiled call (the family's door kernel,
:func:`toolkit.ik.analytic.batch_kernels.door_of`) with Python only at the door."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...kinematics import poses
from . import door_kernels, registry
from .batch_kernels import LATER
from .chain import Chain, Structure, exact_for, reverse
from .family import Family

__all__ = ["BranchDoor", "branch_label", "chain_angles", "packed_family"]


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


def chain_angles(layout: tuple[np.ndarray, ...], rest: np.ndarray) -> np.ndarray:
    """The chain's angles (n,) in a checked configuration ``rest`` (nq,): its joints'
    values, a (cos, sin) pair's angle (``layout``: a door's, its first two arrays each chain
    joint's place in q and whether it is a (cos, sin) pair)."""
    qcol, circle = layout[0], layout[1]
    pref: np.ndarray = np.asarray(rest[qcol], dtype=float)  # a copy: indexed by an array
    if circle.any():
        at = qcol[circle]
        pref[circle] = np.arctan2(rest[at + 1], rest[at])
    return pref


def packed_family(chain: Chain, found: Structure) -> tuple[np.ndarray, ...]:
    """A compiled family kernel's fixed arrays for ``chain`` (as solved: the reversed chain
    of a reversed structure is the caller's to pass): axes, points, the frame's rotation
    and position at zero."""
    assert found.points is not None
    return tuple(np.ascontiguousarray(a, dtype=float) for a in (
        chain.axes, found.points, chain.tip[:3, :3], chain.tip[:3, 3]))  # fmt: skip


@dataclass(frozen=True)
class BranchDoor:
    """A compiled family's chain packed for its door kernel
    (:func:`~toolkit.ik.analytic.batch_kernels.door_of`).

    ``chain``, ``found``: the chain and its structure; ``layout``: per chain joint its place
    in q, (cos, sin) pair or not, limits (lower, upper; infinite for a continuous joint),
    then q's limits, then per chain joint prismatic or not; ``fk``: the kinematics
    kernels' chain to the frame; ``mid``: the middle of the limits (the default rest
    configuration) and ``mid_pref`` its chain angles (``mid2``, ``mid_pref2``: the same
    with a leading axis of one); ``places``: the family places a point (its targets are
    positions); ``serial_chain``: its kinematics chain is serial (its rows of many targets
    verified at once, :func:`~toolkit.ik.analytic.door_kernels.verified_rows`);
    ``searched``: its branches come from a search (16 rows of branches a target,
    packed with the arm, where a closed form has 8); ``batch``, ``serial``: the
    family's door kernel (:class:`~toolkit.ik.analytic.registry.FamilyRecord`), and on one
    core; ``names``, ``named_at``: the label of each roots' code, and of each tuple of codes
    seen (kept)."""

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
    named_at: dict[tuple[float, ...], list[str]] = field(init=False, default_factory=dict)
    places: bool = field(init=False)
    serial_chain: bool = field(init=False)
    searched: bool = field(init=False)
    batch: Any = field(init=False)
    serial: Any = field(init=False)

    def __post_init__(self) -> None:
        family = self.found.family
        assert family is not None and self.found.compiled and self.found.points is not None
        solved = reverse(self.chain) if self.found.reversed else self.chain
        geometry, index = packed_family(solved, self.found), Family(family).kernel_index
        record = registry.REGISTRY[Family(family)]
        most = 16 if record.key.searched else 8  # a 6R arm: 16 at most
        packed = door_kernels.pack(geometry, self.layout, self.fk, index, self.found.reversed,
                                   most)  # fmt: skip
        object.__setattr__(self, "batch", record.door)
        object.__setattr__(self, "serial", record.door.serial)
        object.__setattr__(self, "packed", packed)
        object.__setattr__(self, "mid2", self.mid[None])
        object.__setattr__(self, "mid_pref2", self.mid_pref[None])
        object.__setattr__(self, "names", _label_table(Family(family), self.found.reversed))
        object.__setattr__(self, "places", Family(family).places_point)
        object.__setattr__(self, "serial_chain", bool(poses.serial(self.fk[0])))
        object.__setattr__(self, "searched", Family(family).searched)

    def exact(self, tol: float) -> bool:
        """:func:`~toolkit.ik.analytic.chain.exact_for` of the structure at ``tol``, kept per
        tol."""
        found = self.exact_at.get(tol)
        if found is None:
            found = self.exact_at[tol] = exact_for(self.found, tol)
        return found

    def pref_of(self, rest: np.ndarray) -> np.ndarray:
        """The chain's angles (n,) in a checked configuration ``rest`` (nq,)
        (:func:`chain_angles`)."""
        return chain_angles(self.layout, rest)

    def call(
        self, Ts: np.ndarray, tol: float, rest: np.ndarray, pref: np.ndarray, *,
        near: bool = False, spread: bool = False, first: bool = False,
    ) -> np.ndarray:  # fmt: skip
        """The family's door kernel (:func:`~toolkit.ik.analytic.batch_kernels.door_of`) of
        poses Ts (N, 4, 4) (C-contiguous float64) with the other joints at ``rest`` (1 or N,
        nq) and the chain's preferred angles ``pref`` (1 or N, n): its one array P;
        ``near``: wrapped rows of an arm only near its family, to be polished; ``spread``:
        over the cores; ``first``: only the nearest verified row is wanted."""
        floats, ints = self.packed
        later = not first and len(Ts) >= LATER and self.serial_chain  # verified vectorized
        if not spread:  # one core: the serial kernel called directly (a single target's door)
            P = self.serial(floats, ints, near, tol, first, later, Ts, rest, pref)
        else:
            P = self.batch(True, floats, ints, near, tol, first, later, Ts, rest, pref)
        if later:  # the rows the kernel left
            door_kernels.verified_rows(spread, P, Ts, *self.fk, tol, near, self.places)
        return P  # type: ignore[no-any-return]

    def rows(
        self, Ts: np.ndarray, tol: float, rest: np.ndarray, pref: np.ndarray, *,
        near: bool = False, spread: bool = False,
    ) -> tuple[np.ndarray, ...]:  # fmt: skip
        """:meth:`call` read as (Q, E, K, S, C) (:func:`~toolkit.ik.analytic.door_kernels.split`);
        ``rest`` and ``pref`` may be one row each ((nq,), (n,))."""
        if rest.ndim == 1:
            rest, pref = rest[None], pref[None]
        P = self.call(Ts, tol, rest, pref, near=near, spread=spread)
        return door_kernels.split(P, spread)

    def labels(self, roots: np.ndarray) -> list[str]:
        """The label of each branch of ``roots`` (B, 3) (ints, or floats holding them)."""
        codes = [door_kernels.label_code(r) for r in roots.astype(int).tolist()]
        return self.named(np.array(codes, dtype=float))

    def named(self, codes: np.ndarray) -> list[str]:
        """The label of each branch of its roots' codes (B,)
        (:func:`~toolkit.ik.analytic.door_kernels.label_code`); kept per tuple of codes."""
        key = tuple(codes.tolist())
        found = self.named_at.get(key)
        if found is None:
            found = list(map(self.names.__getitem__, key))
            if len(self.named_at) < 4096:  # a door's branch sets are few; a bound all the same
                self.named_at[key] = found
        return found.copy()
