"""Cable-driven bending manipulator of rigid elements rolling on spherical surfaces ([P4]).

A link is a stack of n identical elements. Element 0 is fixed; each next element hangs
below and rolls without slipping on the one above; the contact surfaces are spheres of
radius R. Four cables (XP, YP, XN, YN) run through holes on a circle of diameter d.
Each pair of neighbours is described by the contact angle ``alpha`` and the bending-plane
angle ``psi`` (psi = 0 bends towards +X, the side of the XP cable).

Geometry (derived from rolling, see docs/bending.md): with k = R - h0 and
u = (sin a cos psi, sin a sin psi, -cos a), element i in the frame of element i-1 is

    R_i = Rot(l, 2 alpha),  l = (sin psi, -cos psi, 0)                (eq. 5, rotation)
    O_i = (0, 0, k) + 2R u + R_i (0, 0, k) = (2R - 2k cos alpha) u       (eq. 5, corrected)

so every segment O_{i-1} O_i makes the angle alpha with the axis of element i-1, and
the chord of n elements makes n alpha with the base axis (the paper's G = n alpha).

Conventions: lengths in metres, angles in radians; cable changes are positive for
shortening (the paper's sign); psi is returned in [0, 2 pi). The element geometry is a
:class:`Geometry` (validated once); this module also registers the ``bending`` catalogue
model, whose arguments are checked by the same class.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pinocchio as pin

from .. import _validate
from .._validate import vector3
from ..catalogue import ModelSpec, register
from ..errors import GeometryError, InvalidParameterError
from ._planar import wrap

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from mpl_toolkits.mplot3d import Axes3D

Shapes5 = list[tuple[str, list[float], list[float], np.ndarray]]
Shapes4 = list[tuple[float, np.ndarray]]

__all__ = [
    "CABLES",
    "Geometry",
    "InverseResult",
    "angles_from_cables",
    "angles_to_q",
    "cable_lengths_exact",
    "cables_from_angles",
    "chain_pose",
    "draw_figure4",
    "draw_figure5",
    "element_transform",
    "figure4",
    "figure5",
    "inverse",
    "link_pose",
    "paper_eq5_centre",
    "paper_inverse",
    "q_to_angles",
    "shape",
]

CABLES = ("XP", "YP", "XN", "YN")
_HOLE_ANGLE = {"XP": 0.0, "YP": np.pi / 2, "XN": np.pi, "YN": 3 * np.pi / 2}


# ---------------------------------------------------------------------- geometry
def _number(value: object, what: str) -> float:
    return _validate.number(value, what)


def _count(n: object, what: str = "n") -> int:
    return _validate.count(n, what, error=GeometryError)


@dataclass(frozen=True)
class Geometry:
    """Element geometry: sphere radius R, hole-circle diameter d, centre-to-surface h0 [m].

    ``h0`` may be left out (None) by the cable relations, which do not depend on it.
    Raises :class:`~toolkit.errors.GeometryError` for R <= 0, d <= 0, d >= 2R or h0 <= 0.
    """

    R: float
    d: float
    h0: float | None = None

    def __post_init__(self) -> None:
        R, d = _number(self.R, "R"), _number(self.d, "d")
        if R <= 0 or d <= 0:
            raise GeometryError(f"R and d must be > 0 (got R={R}, d={d})")
        if d >= 2 * R:
            raise GeometryError(
                f"the hole circle must fit on the sphere: d < 2R required (got d={d}, R={R})"
            )
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "d", d)
        if self.h0 is not None:
            h0 = _number(self.h0, "h0")
            if h0 <= 0:
                raise GeometryError(f"h0 must be > 0 (got {h0})")
            object.__setattr__(self, "h0", h0)

    @property
    def k(self) -> float:
        """R - h0: the sphere centre's distance from the element frame [m]."""
        if self.h0 is None:
            raise GeometryError("this relation needs h0 (the centre-to-surface distance)")
        return self.R - self.h0

    @property
    def alpha_m(self) -> float:
        """Largest tilt of one element, arcsin(d / 2R) [rad]."""
        return float(np.arcsin(self.d / (2 * self.R)))

    @property
    def L0(self) -> float:
        """Cable segment between neighbours at alpha = 0: 2R (1 - cos alpha_m) [m]."""
        return float(2 * self.R * (1 - np.cos(self.alpha_m)))

    @property
    def r(self) -> float:
        """Distance from a sphere centre to a cable exit point: sqrt(R^2 - (d/2)^2) [m]."""
        return float(np.sqrt(self.R**2 - (self.d / 2) ** 2))

    def check_alpha(self, alpha: float, signed: bool = False) -> float:
        """alpha as a float within [0, alpha_m] ([-alpha_m, alpha_m] when ``signed``)."""
        a = _number(alpha, "alpha")
        lo = -self.alpha_m if signed else 0.0
        if a < lo - 1e-12 or a > self.alpha_m + 1e-12:
            raise GeometryError(
                f"alpha = {a:.6g} rad is outside [{lo:.6g}, alpha_m = {self.alpha_m:.6g}] rad"
            )
        return a


def _check_model(values: Mapping[str, float]) -> None:
    """The catalogue model's geometry check, on its resolved xacro arguments."""
    Geometry(values["R"], values["d"], values["h0"])
    if values["alpha_fraction"] > 1:
        raise GeometryError("bending: alpha_fraction must be in (0, 1]")
    if values["links"] > 8:
        raise GeometryError("bending: at most 8 links")


register(
    ModelSpec(
        name="bending",
        template="bending.urdf.xacro",
        description="cable-driven bending manipulator, n rolling elements per link (paper 4)",
        positive=frozenset({"R", "d", "h0", "m_element", "alpha_fraction"}),
        nonnegative=frozenset({"L_t"}),
        integers=frozenset({"n", "links"}),
        tip="tool",
        mimic=True,
        check=_check_model,
    )
)


# ---------------------------------------------------------------------- poses


def element_transform(alpha: float, psi: float, R: float, h0: float) -> np.ndarray:
    """Pose of element i in the frame of element i-1 (4x4), exact rolling geometry."""
    a, p = _number(alpha, "alpha"), _number(psi, "psi")
    k = _number(R, "R") - _number(h0, "h0")
    u = np.array([np.sin(a) * np.cos(p), np.sin(a) * np.sin(p), -np.cos(a)])
    T = np.eye(4)
    T[:3, :3] = pin.exp3(np.array([np.sin(p), -np.cos(p), 0.0]) * (2 * a))
    T[:3, 3] = (2 * R - 2 * k * np.cos(a)) * u
    return T


def paper_eq5_centre(alpha: float, psi: float, R: float, h0: float, alpha0: float = np.pi):
    """Centre O1 as printed in paper 4's eq. 5 (kept to document its sign erratum)."""
    radial = 2 * R * np.sin(alpha + alpha0) - (R - h0) * np.sin(2 * alpha + alpha0)
    z = 2 * R * np.cos(alpha + alpha0) - (R - h0) * np.cos(2 * alpha + alpha0) + (R - h0)
    return np.array([radial * np.cos(psi), radial * np.sin(psi), z])


def link_pose(
    alpha: float, psi: float, n: int, R: float, h0: float, d: float | None = None
) -> np.ndarray:
    """Frame of the last element of an n-element link in the frame of element 0 (eq. 6).

    T_n = A(alpha, psi)^n: identical elements bend the same way. Given ``d``, alpha is
    checked against [0, alpha_m].
    """
    n = _count(n)
    if d is not None:
        Geometry(R, d, h0).check_alpha(alpha)
    return np.linalg.matrix_power(element_transform(alpha, psi, R, h0), n)


def chain_pose(
    alphas: Sequence[float],
    psis: Sequence[float],
    n: int,
    R: float,
    h0: float,
    L_t: float = 0.0,
) -> np.ndarray:
    """Tool pose of a chain of links (each with its own alpha_j, psi_j, psi in the frame of
    the previous link's last element); the tool sits L_t beyond the last element's centre
    along its axis (-z)."""
    if len(alphas) != len(psis) or len(alphas) < 1:
        raise InvalidParameterError("alphas and psis must have the same length >= 1")
    T = np.eye(4)
    for a, p in zip(alphas, psis, strict=True):
        T = T @ link_pose(a, p, n, R, h0)
    tool = np.eye(4)
    tool[2, 3] = -_number(L_t, "L_t")
    return T @ tool


def shape(
    alphas: Sequence[float], psis: Sequence[float], n: int, R: float, h0: float
) -> np.ndarray:
    """Element centres O_0 .. O_{links n} of a chain, shape (links n + 1, 3)."""
    n = _count(n)
    T = np.eye(4)
    pts = [T[:3, 3].copy()]
    for a, p in zip(alphas, psis, strict=True):
        A = element_transform(a, p, R, h0)
        for _ in range(n):
            T = T @ A
            pts.append(T[:3, 3].copy())
    return np.array(pts)


# ---------------------------------------------------------------------- q mapping
def angles_to_q(alphas: Sequence[float], psis: Sequence[float]) -> np.ndarray:
    """Configuration of the ``bending`` model: q = (psi_1, alpha_1, psi_2, alpha_2, ...).

    The model's alpha is signed (range [-alpha_m, alpha_m]) and psi in [-pi, pi], so
    (alpha, psi) and (-alpha, psi + pi) are the same pose; psi is wrapped into (-pi, pi].
    """
    q = []
    for a, p in zip(alphas, psis, strict=True):
        q += [wrap(float(p)), float(a)]
    return np.array(q)


def q_to_angles(q: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """(alphas >= 0, psis in [0, 2 pi)) of a model configuration (inverse of angles_to_q)."""
    arr = np.asarray(q, dtype=float).reshape(-1, 2)
    psi, alpha = arr[:, 0], arr[:, 1]
    psi = np.where(alpha < 0, psi + np.pi, psi) % (2 * np.pi)
    return np.abs(alpha), psi


# ---------------------------------------------------------------------- cables
def _per_pair_change(alpha_signed: float, geo: Geometry) -> tuple[float, float]:
    """Shortening of the (positive, negative) cable of one axis for one pair (eqs. 1, 3)."""
    a_m = geo.alpha_m
    pos = geo.L0 - 2 * geo.R * (1 - np.cos(a_m - alpha_signed))
    neg = geo.L0 - 2 * geo.R * (1 - np.cos(a_m + alpha_signed))
    return float(pos), float(neg)


def cables_from_angles(alpha: float, psi: float, n: int, R: float, d: float) -> dict[str, float]:
    """Cable changes of a link [m], positive = shortening (paper 4, eqs. 1-4 and inverse part).

    The bending is split into the X and Y planes: alpha1 = arcsin(sin alpha cos psi),
    alpha2 = arcsin(sin alpha sin psi) (the chord a = R sin alpha projected), and each
    cable changes by n times the per-pair change of eqs. 1 and 3 for its plane. Also
    returns ``"side"``: the change of each side cable in the one-leading-cable case,
    -n 2r (1 - cos alpha) (eq. 4; the side cables lengthen).
    """
    n = _count(n)
    geo = Geometry(R, d)
    a = geo.check_alpha(alpha)
    p = _number(psi, "psi")
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
    n = _count(n)
    geo = Geometry(R, d)
    unknown = set(cables) - set(CABLES) - {"side"}
    if unknown:
        raise InvalidParameterError(f"unknown cable names {sorted(unknown)}; use {CABLES}")
    c = {k: _number(cables.get(k, 0.0), k) for k in CABLES}

    def plane(pos: str, neg: str) -> float:
        if c[pos] <= 0 and c[neg] <= 0:
            return 0.0
        if c[pos] >= c[neg]:
            return _alpha_from_lead(c[pos], n, geo)
        return -_alpha_from_lead(c[neg], n, geo)

    a1, a2 = plane("XP", "XN"), plane("YP", "YN")
    s = float(np.hypot(np.sin(a1), np.sin(a2)))
    if s > np.sin(geo.alpha_m) + 1e-12:
        raise GeometryError("these cable changes ask for alpha > alpha_m")
    alpha = float(np.arcsin(min(s, 1.0)))
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


# ---------------------------------------------------------------------- inverse problem
class InverseResult(NamedTuple):
    """Solution of the inverse problem for one link."""

    success: bool
    alpha: float  # [rad], in [0, alpha_m]
    psi: float  # [rad], in [0, 2 pi)
    cables: dict[str, float]  # changes [m], positive = shortening
    residual: float  # distance from the reached working point to the target [m]
    regime: str  # "hanging" (working point below the base plane) or "curled" (above)
    cables_exact: dict[str, float]  # the same changes from the exact rolling geometry


def _planar(alpha: np.ndarray, n: int, R: float, h0: float, L_t: float):
    """Working point in the bending plane: (radial, z) for an array of alpha."""
    k = R - h0
    seg = 2 * R - 2 * k * np.cos(alpha)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(np.abs(alpha) < 1e-9, n, np.sin(n * alpha) / np.sin(alpha))
    chord = seg * ratio
    radial = chord * np.sin(n * alpha) + L_t * np.sin(2 * n * alpha)
    z = -chord * np.cos(n * alpha) - L_t * np.cos(2 * n * alpha)
    return radial, z


def inverse(
    target: Sequence[float],
    n: int,
    R: float,
    d: float,
    h0: float,
    L_t: float = 0.0,
    *,
    tol: float = 1e-9,
) -> InverseResult:
    """Bending angles and cable changes that put the working point on ``target``.

    The working point lies L_t beyond the centre of the last element along its axis.
    Its direction from O_0 fixes psi (the bending plane) and alpha: the angle of the
    working point from -Z0 must equal the target's. For L_t = 0 that is n alpha
    (G = n alpha, exact for both regimes: hanging and curled above the base plane); for
    L_t > 0 the 1-D equation is solved by bracketing and bisection. A link has two
    degrees of freedom, so only a surface is reachable: ``residual`` is the remaining
    distance and ``success`` is False when it exceeds ``tol``.
    """
    n = _count(n)
    geo = Geometry(R, d, h0)
    h = geo.R - geo.k  # h0, checked (never None here)
    L_t = _number(L_t, "L_t")
    if L_t < 0:
        raise GeometryError(f"L_t must be >= 0, got {L_t}")
    p = vector3(target, "target", InvalidParameterError)
    rho = float(np.hypot(p[0], p[1]))
    psi0 = float(np.arctan2(p[1], p[0])) if rho > 1e-15 else 0.0
    theta_t = float(np.arctan2(rho, -p[2]))  # angle from -Z0, in [0, pi]
    grid = np.linspace(0.0, geo.alpha_m, 2001)
    radial, z = _planar(grid, n, geo.R, h, L_t)
    theta = np.unwrap(np.arctan2(radial, -z))
    best: tuple[float, float, float] | None = None  # (residual, alpha, psi)
    for psi, goal in ((psi0, theta_t), (psi0 + np.pi, 2 * np.pi - theta_t)):
        for m in range(-1, int(np.ceil(theta.max() / (2 * np.pi))) + 1):
            g = theta - goal - 2 * np.pi * m
            idx = np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0]
            for i in idx:
                lo, hi = grid[i], grid[i + 1]
                glo = g[i]
                for _ in range(80):
                    mid = 0.5 * (lo + hi)
                    r_, z_ = _planar(np.array([mid]), n, geo.R, h, L_t)
                    gm = np.arctan2(r_[0], -z_[0])
                    gm = gm + 2 * np.pi * np.round((theta[i] - gm) / (2 * np.pi))
                    gm -= goal + 2 * np.pi * m
                    if np.sign(gm) == np.sign(glo):
                        lo, glo = mid, gm
                    else:
                        hi = mid
                a = 0.5 * (lo + hi)
                r_, z_ = _planar(np.array([a]), n, geo.R, h, L_t)
                reached = np.array([r_[0] * np.cos(psi), r_[0] * np.sin(psi), z_[0]])
                res = float(np.linalg.norm(reached - p))
                if best is None or res < best[0]:
                    best = (res, float(a), float(psi % (2 * np.pi)))
    if best is None:  # direction not reachable: report the closest end of the range
        r_, z_ = _planar(grid, n, geo.R, h, L_t)
        pts = np.stack([r_ * np.cos(psi0), r_ * np.sin(psi0), z_], axis=1)
        i = int(np.argmin(np.linalg.norm(pts - p, axis=1)))
        best = (float(np.linalg.norm(pts[i] - p)), float(grid[i]), float(psi0 % (2 * np.pi)))
    res, alpha, psi = best
    cables = cables_from_angles(alpha, psi, n, geo.R, geo.d)
    exact = cable_lengths_exact(alpha, psi, geo.R, geo.d)
    cables_exact = {k: n * (geo.L0 - v) for k, v in exact.items()}
    regime = "curled" if p[2] > 0 else "hanging"
    return InverseResult(bool(res <= tol), alpha, psi, cables, res, regime, cables_exact)


def paper_inverse(
    target: Sequence[float], n: int, L_t: float = 0.0, *, working_point: bool = True
) -> tuple[float, float]:
    """(alpha, psi) by the paper's eqs. 7-10 (case 1 hanging, case 2 curled).

    With ``working_point`` the paper's eqs. 9-10 subtract L_t from z only; otherwise
    eqs. 7-8 for the centre p_n. Eq. 9 turns out exact while the shifted point
    p_t - L_t e_z stays on the chord's side of the base axis (chord + 2 L_t cos(n alpha)
    > 0): the last element's axis is at 2 n alpha and the chord at n alpha, so the
    shift closes an isosceles triangle. Beyond that (a long tool on a link curled past
    90 deg) it fails; :func:`inverse` does not.
    """
    n = _count(n)
    x, y, z = vector3(target, "target", InvalidParameterError).tolist()
    if working_point:
        z = z - _number(L_t, "L_t")
    rho = float(np.hypot(x, y))
    if z <= 0:  # case 1
        alpha = abs(np.arctan(rho / z)) / n if z != 0 else np.pi / 2 / n
    else:  # case 2: G = pi/2 + gamma0, tan gamma0 = |z| / rho
        alpha = (np.pi / 2 + np.arctan2(abs(z), rho)) / n
    if x == 0:
        psi = np.pi / 2 if y > 0 else (3 * np.pi / 2 if y < 0 else 0.0)
    else:
        psi = np.arctan(y / x) + (np.pi if x < 0 else 0.0)  # eq. 8, the quadrant restored
    return float(alpha), float(psi % (2 * np.pi))


# ---------------------------------------------------------------------- figures
def figure5(R: float = 0.02, d: float = 0.016, h0: float = 0.008, n: int = 5) -> Shapes5:
    """Shapes of 2-, 3- and 4-link manipulators (paper 4, Fig. 5) for sample angles.

    Returns a list of (title, alphas, psis, centres (links n + 1, 3)).
    """
    a_m = Geometry(R, d, h0).alpha_m
    cases = [
        ("2 links", [0.8 * a_m, 0.8 * a_m], [0.0, np.pi]),
        ("3 links", [0.6 * a_m, 0.9 * a_m, 0.5 * a_m], [0.0, np.pi / 2, np.pi]),
        ("4 links", [0.5 * a_m, 0.7 * a_m, 0.9 * a_m, 0.6 * a_m], [0.0, 0.0, np.pi / 2, np.pi]),
    ]
    return [(t, a, p, shape(a, p, n, R, h0)) for t, a, p in cases]


def figure4(R: float = 0.02, d: float = 0.016, h0: float = 0.008, n: int = 10) -> Shapes4:
    """A 10-element link curling above its base plane (paper 4, Fig. 4): shapes for
    alpha = 3, 6, 9, 12 and 16 deg (those within alpha_m), in the X-Z plane.
    Returns [(alpha, centres)]."""
    a_m = Geometry(R, d, h0).alpha_m
    alphas = [a for a in np.radians([3.0, 6.0, 9.0, 12.0, 16.0]) if a <= a_m]
    return [(float(a), shape([a], [0.0], n, R, h0)) for a in alphas]


def draw_figure5(
    data: Shapes5 | None = None, axes: Sequence[Axes3D] | None = None
) -> Sequence[Axes3D]:
    """Draw Fig. 5 (3-D shapes, equal axis scales, mm) into ``axes`` (one 3-D axes per
    manipulator; default: a new figure); returns the axes."""
    import matplotlib.pyplot as plt

    data = figure5() if data is None else data
    if axes is None:
        fig = plt.figure(figsize=(12, 4.2))
        axes = [fig.add_subplot(1, len(data), i + 1, projection="3d") for i in range(len(data))]
    for ax, (title, alphas, psis, pts) in zip(axes, data, strict=True):
        mm = pts * 1e3
        ax.plot(mm[:, 0], mm[:, 1], mm[:, 2], "o-", ms=3)
        ax.set_title(
            f"{title}: alpha = {', '.join(f'{np.degrees(a):.0f}' for a in alphas)} deg;\n"
            f"psi = {', '.join(f'{np.degrees(p):.0f}' for p in psis)} deg",
            fontsize=8,
        )
        centre, half = mm.mean(axis=0), max(np.ptp(mm, axis=0).max() / 2, 1.0)
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_zlim(centre[2] - half, centre[2] + half)
        ax.set_box_aspect((1, 1, 1))
        ax.set_xlabel("X [mm]")
        ax.set_ylabel("Y [mm]")
        ax.set_zlabel("Z [mm]")
    axes[0].figure.tight_layout()
    return axes


def draw_figure4(data: Shapes4 | None = None, ax: Axes | None = None) -> Axes:
    """Draw Fig. 4 (X-Z plane, mm) into ``ax`` (default: a new figure); returns the axes."""
    import matplotlib.pyplot as plt

    data = figure4() if data is None else data
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    for alpha, pts in data:
        ax.plot(
            pts[:, 0] * 1e3,
            pts[:, 2] * 1e3,
            "o-",
            ms=3,
            label=f"alpha = {np.degrees(alpha):.1f} deg",
        )
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("X0 [mm]")
    ax.set_ylabel("Z0 [mm]")
    ax.set_aspect("equal")
    ax.legend(fontsize=8)
    ax.set_title("10-element link curling above its base plane ([P4], Fig. 4)", fontsize=9)
    return ax
