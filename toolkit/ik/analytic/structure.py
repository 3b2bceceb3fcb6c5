"""What makes a robot's IK solvable in closed form, read from its joint axes.

:func:`chain_of` reads the revolute joints from the base to a frame at the zero
configuration: each joint's axis ``h`` and a point on it, in the base frame (the
product-of-exponentials form: the frame's pose is ``R(h1, q1) ... R(hn, qn)`` times its
pose at zero, about lines through those points). :func:`find_structure` then looks for a
family the toolkit solves by subproblems (:mod:`toolkit.ik.analytic.families`):

* ``"three parallel"``: 6 joints, axes 2, 3, 4 parallel and axes 5, 6 meeting (the UR
  arms): up to 8 branches (shoulder, wrist, elbow);
* ``"spherical wrist"``: 6 joints, axes 4, 5, 6 through one point and axes 2, 3 parallel
  (most industrial arms: PUMA, KUKA, ABB, Fanuc): up to 8 branches;
* ``"spherical wrist, meeting shoulder"``: 6 joints, axes 4, 5, 6 through one point and
  axes 1, 2 meeting: up to 8 branches;
* ``"6R, axes 1, 2, 3 parallel"``: 6 joints, the first three axes parallel (EAIK's outer
  case; reversed, the last three): up to 8 branches.

A 5-joint chain with axes 2, 3, 4 parallel (``"5R, axes 2, 3, 4 parallel"``: the Katana
6M180, the catalogue's arm5dof) reaches the poses of a 5-dimensional set: up to 4 branches
of a target pose it can take (of one it cannot: branches that miss, with their residual).

A 3-joint chain places a point: ``"3R, axes 1, 2 meeting"`` and ``"3R, axes 2, 3
parallel"`` (up to 4 branches; targets are positions), and ``"3R, general"`` for any other
axes (SP5: a quartic).

A 6-joint chain that fits none is tried reversed (:func:`reverse`: the frame as the base), so that
three axes meeting at the start (a spherical shoulder, as in the Panda with joint 7 locked)
count as a spherical wrist; the structure then says ``reversed=True``. With ``lock``,
:func:`chain_of` leaves joints out at fixed values (a 7-joint arm becomes a 6-joint one).

An arm whose axes meet or are parallel only to within :data:`NEAR` (a calibrated arm, a
description rounded to 0.1 mm) gets the family with ``exact=False``: its branches are
solved on the nearest exact geometry and polished on the real model. Anything else gets
``family=None`` and a ``reason`` that says what was found and what is missing.
"""

from __future__ import annotations

import math

import numpy as np

from . import chain as _chain
from .chain import COMPILED as COMPILED
from .chain import EXACT_TOL as EXACT_TOL
from .chain import NEAR as NEAR
from .chain import Chain as Chain
from .chain import Structure as Structure
from .chain import chain_of as chain_of
from .chain import exact_for as exact_for
from .chain import retipped as retipped
from .chain import reverse as reverse
from .family import Family as Family

__all__ = [*_chain.__all__, "find_structure"]  # the chain's names, re-exported


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """How far two axes are from parallel [rad] (either sense)."""
    (a0, a1, a2), (b0, b1, b2) = a.tolist(), b.tolist()
    c0, c1, c2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    return math.asin(min(1.0, math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)))


def _meet(hs: list[np.ndarray], ps: list[np.ndarray]) -> tuple[np.ndarray, float]:
    """The point closest to every line (h, p) in least squares (sum (I - h h^T) (x - p) = 0),
    and its largest distance from one of them (0 when they all pass through it)."""
    H, P = np.array(hs, dtype=float), np.array(ps, dtype=float)
    A = len(H) * np.eye(3) - H.T @ H
    b = P.sum(axis=0) - H.T @ np.einsum("ij,ij->i", H, P)
    x = np.linalg.lstsq(A, b, rcond=None)[0]
    D = x - P
    off = D - H * np.einsum("ij,ij->i", H, D)[:, None]  # each line's perpendicular to x
    return x, float(np.sqrt(np.einsum("ij,ij->i", off, off)).max())


def _judged(name: Family, chain: Chain, misses: list[float], points: np.ndarray, why: str) -> (
    Structure | str
):  # fmt: skip
    worst = max(misses)
    if worst <= EXACT_TOL:
        return Structure(
            family=name, joints=chain.names, reason=why, exact=True, deviation=worst, points=points
        )
    if worst <= max(NEAR.values()) and all(m <= max(NEAR.values()) for m in misses):
        return Structure(
            family=name,
            joints=chain.names,
            reason=f"{why}, to within {worst:.2g}",
            exact=False,
            deviation=worst,
            points=points,
        )
    return f"{name}: {why} misses by {worst:.3g}"


def find_structure(chain: Chain, hint: tuple[str, bool] | None = None) -> Structure:
    """The family of a chain (module doc), or ``family=None`` with the reason.

    ``hint``: (family, reversed) of a 6R chain found before at another angle of the same
    locked joints; that family is tried first, and kept where its conditions hold here (a
    sweep of a locked angle keeps its family; the other families are tried where it
    fails)."""
    n = len(chain.joints)
    if hint is not None and n == 6 and not any(chain.prismatic):
        named, turned = hint
        kept = (_searched if named == Family.MEETING_PAIRS else _families)(
            reverse(chain) if turned else chain
        )
        if isinstance(kept, Structure) and kept.family == named:
            return _seen_from(kept, chain, turned)
    if any(chain.prismatic):
        return _with_prismatic(chain)
    if n == 3:
        three = _three_r(chain)
        if isinstance(three, Structure):
            return three
        return Structure(
            family=None, joints=chain.names, reason="no 3R family fits: " + "; ".join(three)
        )
    if n == 5:
        five = _five_r(chain)
        if isinstance(five, Structure):
            return five
        return Structure(
            family=None, joints=chain.names, reason="no 5R family fits: " + "; ".join(five)
        )
    if n != 6:
        return Structure(
            family=None, joints=chain.names,
            reason=f"{n} revolute joints to the frame: the analytic families here take 6 (lock "
            "joints of a longer arm), 5 or 3 (positions)",
        )  # fmt: skip
    tried: list[str] = []
    for family in (_families, _searched):  # closed forms first, either way round
        for flip in (False, True):
            found = family(reverse(chain) if flip else chain)
            if isinstance(found, list):
                tried += found if not flip else []
                continue
            return _seen_from(found, chain, flip)
    return Structure(family=None, joints=chain.names, reason="no family fits: " + "; ".join(tried))


def _seen_from(found: Structure, chain: Chain, flip: bool) -> Structure:
    """A family found on the chain (``flip`` False) or on its reverse, as the chain's."""
    if not flip:
        return found
    return Structure(
        family=found.family,
        joints=chain.names,
        reason=f"reversed (from the frame): {found.reason}",
        exact=found.exact,
        deviation=found.deviation,
        points=found.points,
        reversed=True,
    )


def _searched(chain: Chain) -> Structure | list[str]:
    """The family solved by a search on q6 (:mod:`toolkit.ik.analytic.search`): axes 1, 2 meeting
    and axes 4, 5 meeting, or why it does not fit."""
    h, p = chain.axes, chain.points
    S, miss12 = _meet([h[0], h[1]], [p[0], p[1]])
    W, miss45 = _meet([h[3], h[4]], [p[3], p[4]])
    pts = p.copy()
    pts[0] = pts[1] = S
    pts[3] = pts[4] = W
    crossing = min(_angle(h[0], h[1]), _angle(h[3], h[4])) > NEAR["angle"]
    tried: list[str] = []
    found = _attempt(
        tried, crossing and max(miss12, miss45) <= NEAR["distance"], Family.MEETING_PAIRS,
        chain, [miss12, miss45], pts, "axes 1, 2 meeting and axes 4, 5 meeting (q6 by a search)",
        f"meeting pairs: axes 1, 2 {miss12:.3g} m apart, axes 4, 5 {miss45:.3g} m apart",
    )  # fmt: skip
    return tried if found is None else found


def _families(chain: Chain) -> Structure | list[str]:
    """The first family that fits the chain, or why each does not."""
    h, p = chain.axes, chain.points
    tried: list[str] = []
    # three parallel: h2 || h3 || h4, h5 and h6 meet
    w56, miss56 = _meet([h[4], h[5]], [p[4], p[5]])
    par = [_angle(h[1], h[2]), _angle(h[2], h[3])]
    pts = p.copy()
    pts[4] = pts[5] = w56
    found = _attempt(
        tried, max(par) <= NEAR["angle"] and miss56 <= NEAR["distance"],
        Family.THREE_PARALLEL, chain, [*par, miss56], pts,
        "axes 2, 3, 4 parallel and axes 5, 6 meeting",
        f"three parallel: axes 2-4 within {max(par):.3g} rad of parallel, axes 5, 6 "
        f"{miss56:.3g} m apart",
    )  # fmt: skip
    if found is not None:
        return _unless_degenerate(found, chain, [
            ((0, 1), "four parallel axes (1-4)"), ((1, 4), "four parallel axes (2-5)"),
            ((4, 5), "axes 5 and 6 on one line"),
        ], [(1, 2, "axes 2 and 3"), (2, 3, "axes 3 and 4")])  # fmt: skip
    # spherical wrist: h4, h5, h6 meet at W, h2 || h3
    w, miss = _meet([h[3], h[4], h[5]], [p[3], p[4], p[5]])
    elbow = _angle(h[1], h[2])
    pts = p.copy()
    pts[3] = pts[4] = pts[5] = w
    found = _attempt(
        tried, miss <= NEAR["distance"] and elbow <= NEAR["angle"], Family.SPHERICAL_WRIST,
        chain, [miss, elbow], pts, "axes 4, 5, 6 through one point and axes 2, 3 parallel",
        f"spherical wrist: axes 4-6 miss one point by {miss:.3g} m, axes 2, 3 are "
        f"{elbow:.3g} rad from parallel",
    )  # fmt: skip
    if found is not None:
        return _unless_degenerate(found, chain, [
            ((0, 1), "axis 1 parallel to axis 2"), ((3, 4), "axes 4 and 5 on one line"),
            ((4, 5), "axes 5 and 6 on one line"),
        ], [(1, 2, "axes 2 and 3")])  # fmt: skip
    # spherical wrist with a meeting shoulder: h4, h5, h6 meet at W, h1 and h2 meet at S
    S, miss12 = _meet([h[0], h[1]], [p[0], p[1]])
    pts = pts.copy()
    pts[0] = pts[1] = S
    found = _attempt(
        tried, miss <= NEAR["distance"] and miss12 <= NEAR["distance"],
        Family.MEETING_SHOULDER, chain, [miss, miss12], pts,
        "axes 4, 5, 6 through one point and axes 1, 2 meeting",
        f"meeting shoulder: axes 1, 2 {miss12:.3g} m apart",
    )  # fmt: skip
    if found is not None:
        return _unless_degenerate(found, chain, [
            ((0, 1), "axes 1 and 2 on one line"), ((3, 4), "axes 4 and 5 on one line"),
            ((4, 5), "axes 5 and 6 on one line"),
        ], [])  # fmt: skip
    return _outer(chain, tried)


def _outer(chain: Chain, tried: list[str]) -> Structure | list[str]:
    """Three parallel axes at the base, h1 || h2 || h3 (EAIK's "outer" case; reversed: the
    last three), or ``tried`` with why not."""
    h = chain.axes
    par = [_angle(h[0], h[1]), _angle(h[0], h[2])]
    found = _attempt(
        tried, max(par) <= NEAR["angle"], Family.OUTER_PARALLEL, chain, par, chain.points.copy(),
        "axes 1, 2, 3 parallel", f"axes 1-3 within {max(par):.3g} rad of parallel",
    )  # fmt: skip
    if found is None:
        return tried
    return _unless_degenerate(found, chain, [((0, 3), "four parallel axes (1-4)")],
                              [(0, 1, "axes 1 and 2"), (1, 2, "axes 2 and 3")])  # fmt: skip


DEGENERATE = 1e-6
"""[rad, m] Axes this close to parallel, or a link this close to zero length, make a
family degenerate (below, its subproblems have infinitely many answers for every target)."""


def _unless_degenerate(
    found: Structure, chain: Chain, parallel: list[tuple[tuple[int, int], str]],
    links: list[tuple[int, int, str]],
) -> Structure:  # fmt: skip
    """``found``, or no family with the reason where the arm is a degenerate case of it: a
    pair of axes in ``parallel`` that stays parallel whatever the joints do, or a link in
    ``links`` (between parallel axes a and b) of zero length (the two on one line):
    then where a target is reached at all, infinitely many configurations reach it."""
    h = chain.axes
    why = [text for (a, b), text in parallel if _angle(h[a], h[b]) <= DEGENERATE]
    pts = found.points if found.points is not None else chain.points
    for a, b, text in links:
        gap = pts[b] - pts[a]
        if np.linalg.norm(gap - (gap @ h[a]) * h[a]) <= DEGENERATE:
            why.append(f"{text} on one line")
    if not why:
        return found
    return Structure(
        family=None, joints=chain.names,
        reason=f"{found.family}, degenerate: {'; '.join(why)}: infinitely many solutions where any "
        "exist (use ik(), numeric, which picks one)",
    )  # fmt: skip


def _attempt(
    tried: list[str], fits: bool, name: Family, chain: Chain, misses: list[float],
    points: np.ndarray, why: str, why_not: str,
) -> Structure | None:  # fmt: skip
    """Family ``name`` if its conditions hold (``fits``, judged exact or near by
    ``misses``), else None with the reason appended to ``tried`` (``why_not`` when the
    conditions are not even near)."""
    if not fits:
        tried.append(why_not)
        return None
    found = _judged(name, chain, misses, points, why)
    if isinstance(found, Structure):
        return found
    tried.append(found)
    return None


def _five_r(chain: Chain) -> Structure | list[str]:
    """The 5R family of a 5-joint chain, or why it does not fit."""
    h = chain.axes
    par = [_angle(h[1], h[2]), _angle(h[2], h[3])]
    tried: list[str] = []
    turning = min(_angle(h[0], h[1]), _angle(h[4], h[1]))
    found = _attempt(
        tried, max(par) <= NEAR["angle"] and turning > NEAR["angle"],
        Family.FIVE_R_PARALLEL, chain, par, chain.points.copy(), "axes 2, 3, 4 parallel",
        f"axes 2-4 within {max(par):.3g} rad of parallel, axes 1 and 5 "
        f"{turning:.3g} rad from them at least (5R, axes 2, 3, 4 parallel needs axes 1 "
        "and 5 across them)",
    )  # fmt: skip
    return tried if found is None else found


def _meeting_12(chain: Chain, name: Family, tried: list[str]) -> Structure | None:
    """Family ``name`` of a 3-joint chain whose axes 1, 2 meet (and are not parallel), or
    None with the reason appended to ``tried``."""
    h, p = chain.axes, chain.points
    S, miss12 = _meet([h[0], h[1]], [p[0], p[1]])
    pts = p.copy()
    pts[0] = pts[1] = S
    return _attempt(
        tried, miss12 <= NEAR["distance"] and _angle(h[0], h[1]) > NEAR["angle"], name, chain,
        [miss12], pts, "axes 1, 2 meeting", f"axes 1, 2 {miss12:.3g} m apart",
    )  # fmt: skip


def _three_r(chain: Chain) -> Structure | list[str]:
    """The 3R family of a 3-joint chain (its frame's origin placed), or why none fits."""
    h, p = chain.axes, chain.points
    off = chain.tip[:3, 3] - p[2]
    if np.linalg.norm(off - (off @ h[2]) * h[2]) <= EXACT_TOL:
        why = f"the frame's origin lies on axis 3 ({chain.names[2]} does not move it: any angle"
        return [why + " of it solves); choose a frame off that axis, e.g. the tool point"]
    tried: list[str] = []
    found = _meeting_12(chain, Family.THREE_R_MEETING, tried)
    if found is not None:
        return found
    par = _angle(h[1], h[2])
    found = _attempt(
        tried, par <= NEAR["angle"], Family.THREE_R_PARALLEL, chain, [par], p.copy(),
        "axes 2, 3 parallel", f"axes 2, 3 {par:.3g} rad from parallel",
    )  # fmt: skip
    if found is not None:
        return found
    return Structure(
        family=Family.THREE_R_GENERAL,
        joints=chain.names,
        reason="axes in general position (SP5, a quartic): " + "; ".join(tried),
        exact=True,
        deviation=0.0,
        points=p.copy(),
    )


def _with_prismatic(chain: Chain) -> Structure:
    """The family of a 3-joint chain with prismatic joints (its frame's origin placed), or
    why none fits: PPP, RPP (any axes), RRP with axes 1, 2 meeting or parallel."""
    kinds = "".join("P" if s else "R" for s in chain.prismatic)
    slides = [n for n, s in zip(chain.names, chain.prismatic, strict=True) if s]
    if len(chain.joints) != 3:
        return Structure(
            family=None,
            joints=chain.names,
            reason=f"prismatic joint(s) {slides}: the families with "
            "prismatic joints take 3-joint chains placing a point",
        )
    h, p = chain.axes, chain.points
    pts = p.copy()
    why_not = _degenerate(kinds, h)
    if why_not:
        return Structure(family=None, joints=chain.names, reason=f"{kinds}: {why_not}")
    if kinds in (Family.PPP, Family.RPP):
        return Structure(
            family=Family(kinds),
            joints=chain.names,
            reason=f"{kinds}: a point placed by "
            + ("three slides" if kinds == Family.PPP else "a turn and two slides"),
            exact=True,
            deviation=0.0,
            points=pts,
        )
    if kinds != "RRP":
        return Structure(
            family=None,
            joints=chain.names,
            reason=f"joints {kinds} (R revolute, P prismatic): the "
            "families with prismatic joints here are PPP, RPP and RRP",
        )
    tried: list[str] = []
    found = _meeting_12(chain, Family.RRP_MEETING, tried)
    par = _angle(h[0], h[1])
    found = found or _attempt(
        tried, par <= NEAR["angle"], Family.RRP_PARALLEL, chain, [par], p.copy(),
        "axes 1, 2 parallel", f"axes 1, 2 {par:.3g} rad from parallel",
    )  # fmt: skip
    return found or Structure(
        family=None, joints=chain.names, reason="no RRP family fits: " + "; ".join(tried)
    )


def _degenerate(kinds: str, h: np.ndarray) -> str:
    """Why a chain of these joint kinds cannot place a point everywhere near it ("" when it
    can)."""
    if kinds == Family.PPP and abs(float(np.linalg.det(h))) < 1e-6:
        return "the three slides do not span space"
    if kinds == Family.RPP:
        if max(abs(float(h[0] @ h[1])), abs(float(h[0] @ h[2]))) < 1e-6:
            return "both slides lie across axis 1: the height along it is fixed"
        if _angle(h[1], h[2]) < 1e-6:
            return "the two slides are parallel"
    if kinds == "RRP" and _angle(h[0], h[1]) <= NEAR["angle"] and abs(float(h[0] @ h[2])) < 1e-6:
        return "the slide lies across the parallel axes 1, 2: the height along them is fixed"
    return ""
