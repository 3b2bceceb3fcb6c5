"""One record per closed-form family (:class:`FamilyRecord`), in one registry keyed by
:class:`~toolkit.ik.analytic.family.Family`: its Python form (the oracle of its compiled
form, and the solver of the families not compiled), its compiled kernels (one target, N
targets), and :func:`solve`, which runs a structure's family on a target."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import (
    families,
    family_kernels,
    position_kernels,
    prismatic,
    search,
    search_kernels,
    wrist_kernels,
)
from .door_kernels import FIRST_POSITION
from .family import Family
from .structure import Chain, Structure, reverse

__all__ = ["REGISTRY", "FamilyRecord", "PythonForm", "solve"]

PythonForm = Callable[[Chain, np.ndarray, np.ndarray, tuple[str, ...]], list[families.Branch]]
"""A family in Python: (chain, the points it solves with, target T (4, 4), the subproblem
kinds a branch may rest on) -> [(angles, label)]."""


@dataclass(frozen=True)
class FamilyRecord:
    """Everything the toolkit knows of one family but which chain it fits (that is read by
    :func:`~toolkit.ik.analytic.structure.find_structure`, whose tests share the checks of
    families tried in turn)."""

    key: Family
    python: PythonForm
    kernel: Callable[..., Any] | None = None  # compiled, one target (branches into ``out``)
    batch: Callable[..., Any] | None = None  # compiled, N targets over the cores

    @property
    def serial_batch(self) -> Callable[..., Any]:
        """:attr:`batch` on one core, called without the ``spread`` flag (a single target's
        door keeps its Python short)."""
        batch: Any = self.batch
        if hasattr(batch, "serial"):  # a Twin
            return batch.serial  # type: ignore[no-any-return]
        return functools.partial(batch, False)

    @property
    def places_point(self) -> bool:
        """Whether its targets are positions."""
        return self.key.places_point


_fk, _wk, _pk = family_kernels, wrist_kernels, position_kernels


def _point(key: Family) -> Callable[..., Any]:
    """The N-target kernel of a family placing a point:
    :func:`~toolkit.ik.analytic.position_kernels.position_batch` at its index, called as
    the others are (``batch(spread, h, o, tip_R, tip_p, Ts, near, pref)``)."""
    index = key.kernel_index - FIRST_POSITION
    twin = position_kernels.position_batch

    def batch(spread: bool, *args: Any) -> Any:
        return twin(spread, index, *args)

    batch.serial = functools.partial(twin.serial, index)  # type: ignore[attr-defined]
    return batch


REGISTRY: dict[Family, FamilyRecord] = {
    r.key: r
    for r in (
        FamilyRecord(Family.THREE_PARALLEL, families.three_parallel, _fk.three_parallel,
                     _fk.three_parallel_batch),
        FamilyRecord(Family.SPHERICAL_WRIST, families.spherical_wrist, _wk.spherical_wrist,
                     _wk.spherical_wrist_batch),
        FamilyRecord(Family.MEETING_SHOULDER, families.meeting_shoulder, _wk.meeting_shoulder,
                     _wk.meeting_shoulder_batch),
        FamilyRecord(Family.FIVE_R_PARALLEL, families.five_r_parallel, _fk.five_r_parallel,
                     _fk.five_r_parallel_batch),
        FamilyRecord(Family.MEETING_PAIRS, search.meeting_pairs, search_kernels.meeting_pairs,
                     search_kernels.meeting_pairs_batch),
        FamilyRecord(Family.PPP, prismatic.ppp, _pk.ppp, _point(Family.PPP)),
        FamilyRecord(Family.RPP, prismatic.rpp, _pk.rpp, _point(Family.RPP)),
        FamilyRecord(Family.RRP_MEETING, prismatic.rrp_meeting, _pk.rrp_meeting,
                     _point(Family.RRP_MEETING)),
        FamilyRecord(Family.RRP_PARALLEL, prismatic.rrp_parallel, _pk.rrp_parallel,
                     _point(Family.RRP_PARALLEL)),
        FamilyRecord(Family.THREE_R_MEETING, families.three_r_meeting, _pk.three_r_meeting,
                     _point(Family.THREE_R_MEETING)),
        FamilyRecord(Family.THREE_R_PARALLEL, families.three_r_parallel, _pk.three_r_parallel,
                     _point(Family.THREE_R_PARALLEL)),
        FamilyRecord(Family.THREE_R_GENERAL, families.three_r_general, _pk.three_r_general,
                     _pk.three_r_general_batch),
    )
}  # fmt: skip
"""Every family's record (a test holds it to :class:`Family` and the compiled ones to
:data:`~toolkit.ik.analytic.family.COMPILED`, the door's order)."""


def solve(
    chain: Chain, found: Structure, T: np.ndarray, ok: tuple[str, ...]
) -> list[families.Branch]:
    """The branches of ``found``'s family at target ``T`` in Python; for a structure found
    on the reversed chain (``found.reversed``), solved there at T^-1 and turned back."""
    assert found.family is not None and found.points is not None
    python = REGISTRY[found.family].python
    if not found.reversed:
        return python(chain, found.points, T, ok)
    back = python(reverse(chain), found.points, np.linalg.inv(T), ok)
    return [(-angles[::-1], f"reversed: {label}") for angles, label in back]
