"""One record per family (:class:`FamilyRecord`), in one registry keyed by
:class:`~toolkit.ik.analytic.family.Family`: its Python form (the oracle of its compiled
form), its compiled kernels (one target, N targets), and :func:`solve`, which runs a
structure's family's Python form on a target."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...kinematics import Twin
from . import (
    batch_kernels,
    families,
    family_kernels,
    outer,
    outer_kernels,
    position_kernels,
    prismatic,
    search,
    search_kernels,
    wrist_kernels,
)
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
    families tried in turn): its Python form (the tests' oracle), its compiled kernel of one
    target (branches into ``out``; the implementation) and its door: that kernel and the
    verification of its branches for N targets in one compiled call, over the cores or on
    one (:func:`~toolkit.ik.analytic.batch_kernels.door_of`; ``door.serial`` is called
    without the ``spread`` flag)."""

    key: Family
    python: PythonForm
    kernel: Callable[..., Any]
    door: Twin = field(init=False)

    def __post_init__(self) -> None:
        name = self.key.name.lower()
        object.__setattr__(self, "door", batch_kernels.door_of(self.kernel, name))

    @property
    def places_point(self) -> bool:
        """Whether its targets are positions."""
        return self.key.places_point


_fk, _wk, _pk, _sk = family_kernels, wrist_kernels, position_kernels, search_kernels
REGISTRY: dict[Family, FamilyRecord] = {
    r.key: r
    for r in (
        FamilyRecord(Family.THREE_PARALLEL, families.three_parallel, _fk.three_parallel),
        FamilyRecord(Family.SPHERICAL_WRIST, families.spherical_wrist, _wk.spherical_wrist),
        FamilyRecord(Family.MEETING_SHOULDER, families.meeting_shoulder, _wk.meeting_shoulder),
        FamilyRecord(Family.FIVE_R_PARALLEL, families.five_r_parallel, _fk.five_r_parallel),
        FamilyRecord(Family.OUTER_PARALLEL, outer.outer_parallel, outer_kernels.outer_parallel),
        FamilyRecord(Family.MEETING_PAIRS, search.meeting_pairs, _sk.meeting_pairs),
        FamilyRecord(Family.PPP, prismatic.ppp, _pk.ppp),
        FamilyRecord(Family.RPP, prismatic.rpp, _pk.rpp),
        FamilyRecord(Family.RRP_MEETING, prismatic.rrp_meeting, _pk.rrp_meeting),
        FamilyRecord(Family.RRP_PARALLEL, prismatic.rrp_parallel, _pk.rrp_parallel),
        FamilyRecord(Family.THREE_R_MEETING, families.three_r_meeting, _pk.three_r_meeting),
        FamilyRecord(Family.THREE_R_PARALLEL, families.three_r_parallel, _pk.three_r_parallel),
        FamilyRecord(Family.THREE_R_GENERAL, families.three_r_general, _pk.three_r_general),
    )
}
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
