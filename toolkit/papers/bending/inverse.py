"""[P4]'s inverse problem: the bending angles and cables that put a link's working point
on a target (exact, both regimes), and the paper's own eqs. 7-10 for comparison."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ...common import validate as _validate
from ...errors import GeometryError, InvalidParameterError
from .cables import cable_lengths_exact, cables_from_angles
from .geometry import MAX_ELEMENTS, Geometry

__all__ = ["InverseResult", "inverse", "paper_inverse"]


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


Plane = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def _bisect(plane: Plane, lo: float, hi: float, g_lo: float, ref: float, goal: float) -> float:
    """alpha in [lo, hi] where the working point's angle from -Z0 (unwrapped near ``ref``)
    equals ``goal``; 80 halvings of the bracket."""
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        r_, z_ = plane(np.array([mid]))
        gm = float(np.arctan2(r_[0], -z_[0]))
        gm = gm + 2 * np.pi * np.round((ref - gm) / (2 * np.pi)) - goal
        if np.sign(gm) == np.sign(g_lo):
            lo, g_lo = mid, gm
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _best_root(
    plane: Plane,
    grid: np.ndarray,
    theta: np.ndarray,
    p: np.ndarray,
    psi0: float,
    theta_t: float,
) -> tuple[float, float, float] | None:
    """(residual, alpha, psi) of the root closest to the target, over both bending
    half-planes and every turn of the unwrapped angle; None when there is no root."""
    best: tuple[float, float, float] | None = None
    for psi, goal in ((psi0, theta_t), (psi0 + np.pi, 2 * np.pi - theta_t)):
        for m in range(-1, int(np.ceil(theta.max() / (2 * np.pi))) + 1):
            turn_goal = goal + 2 * np.pi * m
            g = theta - turn_goal
            for i in np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0]:
                a = _bisect(plane, grid[i], grid[i + 1], g[i], theta[i], turn_goal)
                r_, z_ = plane(np.array([a]))
                reached = np.array([r_[0] * np.cos(psi), r_[0] * np.sin(psi), z_[0]])
                res = float(np.linalg.norm(reached - p))
                if best is None or res < best[0]:
                    best = (res, float(a), float(psi % (2 * np.pi)))
    return best


def inverse(
    target: ArrayLike,
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
    tol = _validate.number(tol, "tol [m]", lower=0.0, strict=True)
    n = _validate.count(n, "n", maximum=MAX_ELEMENTS, error=GeometryError)
    geo = Geometry(R, d, h0)
    h = geo.R - geo.k  # h0, checked (never None here)
    L_t = _validate.number(L_t, "L_t")
    if L_t < 0:
        raise GeometryError(f"L_t must be >= 0, got {L_t}")
    p = _validate.vector3(target, "target", InvalidParameterError)
    rho = float(np.hypot(p[0], p[1]))
    psi0 = float(np.arctan2(p[1], p[0])) if rho > 1e-15 else 0.0
    theta_t = float(np.arctan2(rho, -p[2]))  # angle from -Z0, in [0, pi]
    grid = np.linspace(0.0, geo.alpha_m, 2001)
    radial, z = _planar(grid, n, geo.R, h, L_t)
    theta = np.unwrap(np.arctan2(radial, -z))

    def plane(alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return _planar(alpha, n, geo.R, h, L_t)

    best = _best_root(plane, grid, theta, p, psi0, theta_t)
    if best is None:  # direction not reachable: report the closest end of the range
        r_, z_ = plane(grid)
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
    target: ArrayLike, n: int, L_t: float = 0.0, *, working_point: bool = True
) -> tuple[float, float]:
    """(alpha, psi) by the paper's eqs. 7-10 (case 1 hanging, case 2 curled).

    With ``working_point`` the paper's eqs. 9-10 subtract L_t from z only; otherwise
    eqs. 7-8 for the centre p_n. Eq. 9 turns out exact while the shifted point
    p_t - L_t e_z stays on the chord's side of the base axis (chord + 2 L_t cos(n alpha)
    > 0): the last element's axis is at 2 n alpha and the chord at n alpha, so the
    shift closes an isosceles triangle. Beyond that (a long tool on a link curled past
    90 deg) it fails; :func:`inverse` does not.
    """
    n = _validate.count(n, "n", maximum=MAX_ELEMENTS, error=GeometryError)
    x, y, z = _validate.vector3(target, "target", InvalidParameterError).tolist()
    if _validate.flag(working_point, "working_point"):
        z = z - _validate.number(L_t, "L_t")
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
