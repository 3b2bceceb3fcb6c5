"""The closed-form families, one key each (:class:`Family`): its name as shown, how many
joints it solves, whether it places a point (a 3-joint chain: targets are positions) and
its place among the compiled families. The family's record (its Python form, its compiled
kernels) is :data:`toolkit.ik.analytic.registry.REGISTRY`; which chain it fits is read by
:func:`toolkit.ik.analytic.structure.find_structure`. No other module spells a family's
name: they name its key.
"""

from __future__ import annotations

from enum import Enum

__all__ = ["COMPILED", "Family"]


class Family(str, Enum):
    """A closed-form family of the analytic IK; the value is its name as shown (a ``str``,
    so ``structure.family == "three parallel"`` holds)."""

    THREE_PARALLEL = "three parallel"
    SPHERICAL_WRIST = "spherical wrist"
    MEETING_SHOULDER = "spherical wrist, meeting shoulder"
    FIVE_R_PARALLEL = "5R, axes 2, 3, 4 parallel"
    OUTER_PARALLEL = "6R, axes 1, 2, 3 parallel"
    THREE_R_MEETING = "3R, axes 1, 2 meeting"
    THREE_R_PARALLEL = "3R, axes 2, 3 parallel"
    THREE_R_GENERAL = "3R, general"
    PPP = "PPP"
    RPP = "RPP"
    RRP_MEETING = "RRP, axes 1, 2 meeting"
    RRP_PARALLEL = "RRP, axes 1, 2 parallel"
    MEETING_PAIRS = "meeting pairs, search"

    def __str__(self) -> str:
        return str(self.value)

    def __format__(self, spec: str) -> str:
        return format(str(self.value), spec)

    @property
    def joints(self) -> int:
        """How many joints the family solves."""
        return _JOINTS[self]

    @property
    def places_point(self) -> bool:
        """Whether its targets are positions (a 3-joint chain places its frame's origin)."""
        return _JOINTS[self] == 3

    @property
    def compiled(self) -> bool:
        """Whether a compiled kernel solves it (:data:`COMPILED`)."""
        return self in COMPILED

    def label(self, roots: tuple[int, ...], reversed_: bool = False) -> str:
        """A branch's label from the roots its subproblems took (each 0, 1, ... or -1 where
        the subproblem had one): "shoulder +, elbow -, wrist +" for a 6R family, the words
        of its own steps for a 3-joint one ("side -", "extension +, shoulder -", "root 2"),
        "reversed: " before it for a family solved from the frame's end."""
        words = _WORDS[self]
        if self is Family.THREE_R_GENERAL:
            text = f"root {roots[0] + 1}"
        elif self is Family.MEETING_PAIRS:  # the curve (elbow, shoulder), its root's index
            text = f"elbow {_sign(roots[0])}, shoulder {_sign(roots[1])}, root {roots[2] + 1}"
        elif self is Family.OUTER_PARALLEL:  # the wrist's pair of SP6 (up to 4), the elbow
            wrist = "" if roots[0] < 0 else f" {roots[0] + 1}"
            text = f"wrist{wrist}, elbow {_sign(roots[1])}".replace(" ,", ",").rstrip()
        else:
            text = ", ".join(f"{word} {_sign(r)}" for word, r in zip(words, roots, strict=False))
        return ("reversed: " if reversed_ else "") + text

    def roots_of(self, label: str) -> tuple[int, int, int]:
        """The roots a branch's :meth:`label` names (its inverse; -1 past the family's)."""
        if self is Family.OUTER_PARALLEL:
            at = label.find("wrist ")
            digit = label[at + 6 : at + 7] if at >= 0 else ""
            sign = label[label.find("elbow ") + 6 :][:1] if "elbow " in label else ""
            elbow = 0 if sign == "+" else 1 if sign == "-" else -1
            return (int(digit) - 1 if digit.isdigit() else -1), elbow, -1
        if self in (Family.THREE_R_GENERAL, Family.MEETING_PAIRS):
            at = label.find("root ")
            index = int(label[at + 5 :]) - 1 if at >= 0 else -1
            if self is Family.THREE_R_GENERAL:
                return index, -1, -1
            return int("elbow -" in label), int("shoulder -" in label), index
        out = [-1, -1, -1]
        for k, word in enumerate(_WORDS[self]):
            at = label.find(word + " ")
            sign = label[at + len(word) + 1 : at + len(word) + 2] if at >= 0 else ""
            out[k] = 0 if sign == "+" else 1 if sign == "-" else -1
        return out[0], out[1], out[2]

    @property
    def searched(self) -> bool:
        """Whether its branches come from a search (slower than the numeric ``ik`` of one
        target, so ``method="auto"`` leaves one target to it; batches and maps still take
        every branch)."""
        return self is Family.MEETING_PAIRS

    @property
    def kernel_index(self) -> int:
        """Its index among :data:`COMPILED`: the family argument of the compiled door."""
        return COMPILED.index(self)


_JOINTS = {
    Family.THREE_PARALLEL: 6, Family.SPHERICAL_WRIST: 6, Family.MEETING_SHOULDER: 6,
    Family.FIVE_R_PARALLEL: 5, Family.OUTER_PARALLEL: 6, Family.THREE_R_MEETING: 3,
    Family.THREE_R_PARALLEL: 3, Family.THREE_R_GENERAL: 3, Family.PPP: 3, Family.RPP: 3,
    Family.RRP_MEETING: 3, Family.RRP_PARALLEL: 3, Family.MEETING_PAIRS: 6,
}  # fmt: skip


def _sign(root: int) -> str:
    """A root as a label shows it: "+" (0), "-" (1), blank (-1: one root)."""
    return "" if root < 0 else ("+" if root == 0 else "-")


_WRIST, _ARM = ("shoulder", "elbow", "wrist"), ("shoulder", "elbow")
_WORDS: dict[Family, tuple[str, ...]] = {
    Family.THREE_PARALLEL: _WRIST, Family.SPHERICAL_WRIST: _WRIST,
    Family.MEETING_SHOULDER: _WRIST, Family.FIVE_R_PARALLEL: _ARM,
    Family.THREE_R_MEETING: _ARM, Family.THREE_R_PARALLEL: _ARM, Family.THREE_R_GENERAL: (),
    Family.PPP: (), Family.RPP: ("side",), Family.RRP_MEETING: ("extension", "shoulder"),
    Family.RRP_PARALLEL: ("elbow",), Family.MEETING_PAIRS: ("elbow", "shoulder"),
    Family.OUTER_PARALLEL: ("wrist", "elbow"),
}  # fmt: skip
"""The steps whose roots name a family's branches, in the order of its roots."""

COMPILED = (
    Family.THREE_PARALLEL,
    Family.SPHERICAL_WRIST,
    Family.MEETING_SHOULDER,
    Family.FIVE_R_PARALLEL,
    Family.OUTER_PARALLEL,
    Family.MEETING_PAIRS,
    Family.PPP,
    Family.RPP,
    Family.RRP_MEETING,
    Family.RRP_PARALLEL,
    Family.THREE_R_MEETING,
    Family.THREE_R_PARALLEL,
    Family.THREE_R_GENERAL,
)
"""The families solved compiled, in the order of the compiled door's dispatch
(:attr:`Family.kernel_index`; the search
(:mod:`toolkit.ik.analytic.search_kernels`) after the closed-form 6R and 5R families, the
families placing a point last, in :mod:`toolkit.ik.analytic.position_kernels`'s order)."""
