"""The fast door of a compiled family: everything about an arm's chain that does not change
between calls, packed once, so that ``Robot.ik_all`` of one target and ``ik_all_batch`` of N
run the same compiled call (:func:`toolkit.ik.analytic.door_kernels.branch_rows`) with
Python only at the door."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import door_kernels
from .chain import Chain, Structure, exact_for, reverse
from .family import Family

__all__ = ["BranchDoor", "branch_label", "packed_family"]

_LABELS: dict[tuple[int, ...], str] = {}


def branch_label(roots: tuple[int, ...], wrist: bool = True, reversed_: bool = False) -> str:
    """ "shoulder +, elbow -, wrist +" of a branch's roots (shoulder, elbow, wrist: 0 for +,
    1 for -, -1 blank where the subproblem had one root; no wrist for a 5R arm), "reversed: "
    before it for a family solved from the frame's end."""
    key = (*roots, int(wrist), int(reversed_))
    label = _LABELS.get(key)
    if label is None:
        signs = ["" if r < 0 else ("+" if r == 0 else "-") for r in roots[:3]]
        label = f"shoulder {signs[0]}, elbow {signs[1]}" + (f", wrist {signs[2]}" if wrist else "")
        label = _LABELS[key] = ("reversed: " if reversed_ else "") + label
    return label


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
    then q's limits; ``fk``: the kinematics kernels' chain to the frame; ``mid``: the
    middle of the limits (the default rest configuration) and ``mid_pref`` its chain
    angles."""

    chain: Chain
    found: Structure
    layout: tuple[np.ndarray, ...]
    fk: tuple[np.ndarray, np.ndarray, np.ndarray]
    mid: np.ndarray
    mid_pref: np.ndarray
    geometry: tuple[np.ndarray, ...] = field(init=False)
    family: int = field(init=False)
    exact_at: dict[float, bool] = field(init=False, default_factory=dict)
    names: list[list[list[str]]] = field(init=False)

    def __post_init__(self) -> None:
        family = self.found.family
        assert family is not None and self.found.compiled and self.found.points is not None
        solved = reverse(self.chain) if self.found.reversed else self.chain
        object.__setattr__(self, "geometry", packed_family(solved, self.found))
        object.__setattr__(self, "family", Family(family).kernel_index)
        wrist, rev = len(self.chain.joints) == 6, self.found.reversed
        table = [[[branch_label((a, b, c), wrist, rev) for c in (-1, 0, 1)] for b in (-1, 0, 1)]
                 for a in (-1, 0, 1)]  # fmt: skip
        object.__setattr__(self, "names", table)

    def exact(self, tol: float) -> bool:
        """:func:`~toolkit.ik.analytic.chain.exact_for` of the structure at ``tol``, kept per
        tol."""
        found = self.exact_at.get(tol)
        if found is None:
            found = self.exact_at[tol] = exact_for(self.found, tol)
        return found

    def rows(
        self, Ts: np.ndarray, tol: float, rest: np.ndarray, pref: np.ndarray, *,
        near: bool = False, spread: bool = False,
    ) -> tuple[np.ndarray, ...]:  # fmt: skip
        """:func:`~toolkit.ik.analytic.door_kernels.branch_rows` of poses Ts (N, 4, 4) (C-contiguous
        float64) with the other joints at ``rest`` (nq,) and the chain's preferred angles
        ``pref`` (n,), or one of each per target ((N, nq), (N, n)): (Q, E, K, S, C) as it
        gives them; ``near``: wrapped rows of an arm only near its family, to be polished;
        ``spread``: over the cores."""
        setup = (self.family, self.found.reversed, near, tol)
        if rest.ndim == 1:
            rest, pref = rest[None], pref[None]
        arm = (self.geometry, self.layout, self.fk)
        return door_kernels.branch_rows(spread, arm, setup, Ts, rest, pref)  # type: ignore[no-any-return]

    def labels(self, roots: np.ndarray) -> list[str]:
        """The label of each branch of ``roots`` (B, 3)."""
        table = self.names
        return [table[a + 1][b + 1][c + 1] for a, b, c in roots.tolist()]
