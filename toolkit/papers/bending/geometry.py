"""[P4]'s element geometry (:class:`Geometry`), the rolling transform of neighbouring
elements (eq. 5, corrected) and the poses of links and chains built from it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...common import validate as _validate
from ...descriptions import ModelSpec, register
from ...errors import ConfigurationError, GeometryError, InvalidParameterError
from .._planar import wrap

__all__ = [
    "MAX_ELEMENTS",
    "Geometry",
    "angles_to_q",
    "chain_pose",
    "element_transform",
    "link_pose",
    "paper_eq5_centre",
    "q_to_angles",
    "shape",
]


MAX_ELEMENTS = 100
"""The most elements per link the functions take (the catalogue model: at most 40)."""


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
        R, d = _validate.number(self.R, "R"), _validate.number(self.d, "d")
        if R <= 0 or d <= 0:
            raise GeometryError(f"R and d must be > 0 (got R={R}, d={d})")
        if d >= 2 * R:
            raise GeometryError(
                f"the hole circle must fit on the sphere: d < 2R required (got d={d}, R={R})"
            )
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "d", d)
        if self.h0 is not None:
            h0 = _validate.number(self.h0, "h0")
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
        signed = _validate.flag(signed, "signed")
        a = _validate.number(alpha, "alpha")
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
    if values["n"] > 40:  # the render grows quadratically (about 1 s at n = 40)
        raise GeometryError("bending: at most 40 elements per link in the model")


register(
    ModelSpec(
        name="bending",
        template="bending.urdf.xacro",
        description="cable-driven bending manipulator, n rolling elements per link ([P4])",
        positive=frozenset({"R", "d", "h0", "m_element", "alpha_fraction"}),
        nonnegative=frozenset({"L_t"}),
        integers=frozenset({"n", "links"}),
        tip="tool",
        mimic=True,
        check=_check_model,
    )
)


def element_transform(alpha: float, psi: float, R: float, h0: float) -> np.ndarray:
    """Pose of element i in the frame of element i-1 (4x4), exact rolling geometry.

    alpha [rad] within [-pi, pi] (a bending angle; [0, alpha_m] in the papers' range) and
    psi [rad] within +-1e6 (an azimuth; beyond, its sine has no digit left)."""
    a = _validate.number(alpha, "alpha [rad]", lower=-np.pi, upper=np.pi, error=GeometryError)
    p = _validate.number(psi, "psi [rad]", lower=-1e6, upper=1e6, error=GeometryError)
    k = _validate.number(R, "R") - _validate.number(h0, "h0")
    u = np.array([np.sin(a) * np.cos(p), np.sin(a) * np.sin(p), -np.cos(a)])
    T = np.eye(4)
    T[:3, :3] = pin.exp3(np.array([np.sin(p), -np.cos(p), 0.0]) * (2 * a))
    T[:3, 3] = (2 * R - 2 * k * np.cos(a)) * u
    return T


def paper_eq5_centre(
    alpha: float, psi: float, R: float, h0: float, alpha0: float = np.pi
) -> np.ndarray:
    """Centre O1 as printed in [P4]'s eq. 5 (kept to document its sign erratum)."""
    alpha, psi, R, h0, alpha0 = (
        _validate.number(v, k)
        for v, k in ((alpha, "alpha"), (psi, "psi"), (R, "R"), (h0, "h0"), (alpha0, "alpha0"))
    )
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
    n = _validate.count(n, "n", maximum=MAX_ELEMENTS, error=GeometryError)
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
    T = np.eye(4)
    for a, p in zip(*_pairs(alphas, psis), strict=True):
        T = T @ link_pose(a, p, n, R, h0)
    tool = np.eye(4)
    tool[2, 3] = -_validate.number(L_t, "L_t")
    return T @ tool


def shape(
    alphas: Sequence[float], psis: Sequence[float], n: int, R: float, h0: float
) -> np.ndarray:
    """Element centres O_0 .. O_{links n} of a chain, shape (links n + 1, 3)."""
    n = _validate.count(n, "n", maximum=MAX_ELEMENTS, error=GeometryError)
    T = np.eye(4)
    pts = [T[:3, 3].copy()]
    for a, p in zip(*_pairs(alphas, psis), strict=True):
        A = element_transform(a, p, R, h0)
        for _ in range(n):
            T = T @ A
            pts.append(T[:3, 3].copy())
    return np.array(pts)


def _pairs(alphas: Sequence[float], psis: Sequence[float]) -> tuple[list[float], list[float]]:
    """One alpha and one psi per link, as checked lists of equal length >= 1."""
    a = _validate.array(alphas, "alphas")
    p = _validate.array(psis, "psis")
    if a.ndim != 1 or a.shape != p.shape or len(a) < 1:
        raise InvalidParameterError(
            f"alphas and psis must be 1-D of the same length >= 1, got {a.shape} and {p.shape}"
        )
    return a.tolist(), p.tolist()


def angles_to_q(alphas: Sequence[float], psis: Sequence[float]) -> np.ndarray:
    """Configuration of the ``bending`` model: q = (psi_1, alpha_1, psi_2, alpha_2, ...).

    The model's alpha is signed (range [-alpha_m, alpha_m]) and psi in [-pi, pi], so
    (alpha, psi) and (-alpha, psi + pi) are the same pose; psi is wrapped into (-pi, pi].
    """
    q = []
    for a, p in zip(*_pairs(alphas, psis), strict=True):
        q += [wrap(p), a]
    return np.array(q)


def q_to_angles(q: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """(alphas >= 0, psis in [0, 2 pi)) of a model configuration (inverse of angles_to_q)."""
    arr = _validate.array(q, "q", error=ConfigurationError)
    if arr.ndim != 1 or len(arr) % 2:
        raise ConfigurationError(
            f"q must hold (psi, alpha) pairs, shape (2 links,), got {arr.shape}"
        )
    arr = arr.reshape(-1, 2)
    psi, alpha = arr[:, 0], arr[:, 1]
    psi = np.where(alpha < 0, psi + np.pi, psi) % (2 * np.pi)
    return np.abs(alpha), psi
