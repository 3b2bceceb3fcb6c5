"""[P4]'s cables: changes of the four cable lengths from the bending angles (eqs. 1-4)
and back, and the exact segment lengths from the rolling geometry."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ...common import validate as _validate
from ...errors import GeometryError, InvalidParameterError
from .geometry import MAX_ELEMENTS, Geometry, element_transform

__all__ = ["CABLES", "angles_from_cables", "cable_lengths_exact", "cables_from_angles"]

CABLES = ("XP", "YP", "XN", "YN")
_HOLE_ANGLE = {"XP": 0.0, "YP": np.pi / 2, "XN": np.pi, "YN": 3 * np.pi / 2}


def _per_pair_change(alpha_signed: float, geo: Geometry) -> tuple[float, float]:
    """Shortening of the (positive, negative) cable of one axis for one pair (eqs. 1, 3)."""
    a_m = geo.alpha_m
    pos = geo.L0 - 2 * geo.R * (1 - np.cos(a_m - alpha_signed))
    neg = geo.L0 - 2 * geo.R * (1 - np.cos(a_m + alpha_signed))
    return float(pos), float(neg)


def cables_from_angles(alpha: float, psi: float, n: int, R: float, d: float) -> dict[str, float]:
    """Cable changes of a link [m], positive = shortening ([P4], eqs. 1-4 and inverse part).

    The bending is split into the X and Y planes: alpha1 = arcsin(sin alpha cos psi),
    alpha2 = arcsin(sin alpha sin psi) (the chord a = R sin alpha projected), and each
    cable changes by n times the per-pair change of eqs. 1 and 3 for its plane. Also
    returns ``"side"``: the change of each side cable in the one-leading-cable case,
    -n 2r (1 - cos alpha) (eq. 4; the side cables lengthen).
    """
    n = _validate.count(n, "n", maximum=MAX_ELEMENTS, error=GeometryError)
    geo = Geometry(R, d)
    a = geo.check_alpha(alpha)
    p = _validate.number(psi, "psi")
    alpha1 = float(np.arcsin(np.sin(a) * np.cos(p)))
    alpha2 = float(np.arcsin(np.sin(a) * np.sin(p)))
    xp, xn = _per_pair_change(alpha1, geo)
    yp, yn = _per_pair_change(alpha2, geo)
    side = -2 * geo.r * (1 - np.cos(a))
    return {"XP": n * xp, "YP": n * yp, "XN": n * xn, "YN": n * yn, "side": n * float(side)}


def _alpha_from_lead(change: float, n: int, geo: Geometry) -> float:
    """Eq. 2: alpha = alpha_m - arccos(1 - (L0 - dL_lead / n) / 2R)."""
    arg = 1 - (geo.L0 - change / n) / (2 * geo.R)
    if arg > 1 + 1e-12 or arg < np.cos(geo.alpha_m) - 1e-12:
        raise GeometryError(
            f"a leading cable cannot shorten by {change:.6g} m over {n} elements "
            f"(range 0 .. {n * geo.L0:.6g} m)"
        )
    return float(geo.alpha_m - np.arccos(np.clip(arg, -1.0, 1.0)))


def angles_from_cables(
    cables: Mapping[str, float], n: int, R: float, d: float
) -> tuple[float, float]:
    """(alpha, psi) of a link from its cable changes (positive = shortening).

    In each axis (X: XP/XN, Y: YP/YN) the cable that shortens more is the leading one;
    eq. 2 gives its plane angle, signed towards that cable (alpha1 for X, alpha2 for Y).
    Then alpha = arcsin(sqrt(sin^2 alpha1 + sin^2 alpha2)) and psi = atan2(sin alpha2,
    sin alpha1) in [0, 2 pi). This covers one leading cable (psi = 0, 90, 180, 270 deg)
    and two leading cables in every quadrant. The paper prints psi = atan(a1 / a2) +
    k pi/2; its arguments are swapped (see docs/errata.md).
    """
    n = _validate.count(n, "n", maximum=MAX_ELEMENTS, error=GeometryError)
    geo = Geometry(R, d)
    if not isinstance(cables, Mapping):
        raise InvalidParameterError(f"cables must map cable names to changes, got {cables!r:.100}")
    unknown = set(cables) - set(CABLES) - {"side"}
    if unknown:
        raise InvalidParameterError(f"unknown cable names {sorted(unknown)}; use {CABLES}")
    c = {k: _validate.number(cables.get(k, 0.0), k) for k in CABLES}

    def plane(pos: str, neg: str) -> float:
        if c[pos] <= 0 and c[neg] <= 0:
            return 0.0
        if c[pos] >= c[neg]:
            return _alpha_from_lead(c[pos], n, geo)
        return -_alpha_from_lead(c[neg], n, geo)

    a1, a2 = plane("XP", "XN"), plane("YP", "YN")
    s = float(np.hypot(np.sin(a1), np.sin(a2)))
    if s > np.sin(geo.alpha_m) + 1e-9:  # beyond the rounding of a cable round trip at alpha_m
        raise GeometryError("these cable changes ask for alpha > alpha_m")
    alpha = float(np.arcsin(min(s, np.sin(geo.alpha_m))))
    psi = float(np.arctan2(np.sin(a2), np.sin(a1)) % (2 * np.pi)) if s > 0 else 0.0
    return alpha, psi


def cable_lengths_exact(alpha: float, psi: float, R: float, d: float) -> dict[str, float]:
    """Length of each cable segment between two neighbouring elements, from the rolling
    geometry: the distance between the hole exit points on the two spheres [m].

    The distance does not depend on h0 (where each element's frame sits on its axis), so
    the frames are put at the sphere centres (h0 = R, k = 0).
    """
    geo = Geometry(R, d)
    a = geo.check_alpha(alpha)
    k = 0.0
    T = element_transform(a, psi, geo.R, geo.R)
    upper_centre = np.array([0.0, 0.0, k])  # bottom sphere of element 0
    lower_centre = np.array([0.0, 0.0, -k])  # top sphere of element 1, in its own frame
    out = {}
    s, c = np.sin(geo.alpha_m), np.cos(geo.alpha_m)
    for name, phi in _HOLE_ANGLE.items():
        radial = np.array([s * np.cos(phi), s * np.sin(phi), 0.0]) * geo.R
        top = upper_centre + radial + np.array([0, 0, -c * geo.R])
        own = lower_centre + radial + np.array([0, 0, c * geo.R])
        bottom = T[:3, :3] @ own + T[:3, 3]
        out[name] = float(np.linalg.norm(bottom - top))
    return out
