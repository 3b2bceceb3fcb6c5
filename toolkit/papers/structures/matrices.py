"""[P3]'s matrices: the adjacent transforms of eqs. 5-9 written out as printed, the
general z-x-z transform and its conversion to and from a URDF origin."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ...common import validate as _validate
from ...errors import InvalidParameterError, UnknownModelError
from .models import STRUCTURES

__all__ = [
    "euler_zxz",
    "origin_to_zxz",
    "paper_T14",
    "paper_transforms",
    "rpy_matrix",
    "zxz_to_origin",
]


def _rz(f: float) -> np.ndarray:
    c, s = np.cos(f), np.sin(f)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _tz(f: float) -> np.ndarray:
    return np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, f], [0, 0, 0, 1.0]])


def _p(f: float, h: float) -> np.ndarray:
    return np.array([[0, 0, 1, f], [1, 0, 0, 0], [0, 1, 0, h], [0, 0, 0, 1.0]])


def _numbers(**values: object) -> list[float]:
    """Each keyword as a checked finite real number, in order."""
    return [_validate.number(v, k) for k, v in values.items()]


def _structure(name: str) -> str:
    if not isinstance(name, str) or name not in STRUCTURES:
        raise UnknownModelError(repr(name)[:60], STRUCTURES, what="structure")
    return name


def paper_transforms(
    name: str, f: Sequence[float], a: float, b: float, c: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(T12, T23, T34) of [P3], eqs. 5-9, written out as printed (consistent version)."""
    _structure(name)
    f1, f2, f3 = _validate.array(f, "f (joint values)", shape=(3,)).tolist()
    a, b, c = (_validate.number(v, k) for v, k in ((a, "a"), (b, "b"), (c, "c")))
    c2, s2 = np.cos(f2), np.sin(f2)
    elev = np.array([[0, 0, 1, 0], [c2, -s2, 0, 0], [s2, c2, 0, a], [0, 0, 0, 1.0]])
    if name == "cartesian":  # eq. 5
        return _p(f1, a), _p(f2, -b), _p(f3, c)
    if name == "cylindrical":  # eq. 6
        t34 = np.array([[1, 0, 0, 0], [0, 0, -1, f3], [0, 1, 0, a], [0, 0, 0, 1.0]])
        return _rz(f1), _tz(f2), t34
    if name == "spherical":  # eq. 7
        t34 = np.array([[0, 0, 1, f3], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1.0]])
        return _rz(f1), elev, t34
    if name == "scara":  # eq. 8
        t23 = np.array([[c2, -s2, 0, 0], [s2, c2, 0, b], [0, 0, 1, a], [0, 0, 0, 1.0]])
        t34 = np.array([[1, 0, 0, 0], [0, 1, 0, c], [0, 0, 1, f3], [0, 0, 0, 1.0]])
        return _rz(f1), t23, t34
    c3, s3 = np.cos(f3), np.sin(f3)  # anthropomorphic, eq. 9
    t34 = np.array([[c3, -s3, 0, b], [s3, c3, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    return _rz(f1), elev, t34


def paper_T14(name: str, f: Sequence[float], a: float, b: float, c: float) -> np.ndarray:
    """T14 = T12 T23 T34 ([P3], eq. 1)."""
    t12, t23, t34 = paper_transforms(name, f, a, b, c)
    return t12 @ t23 @ t34


def euler_zxz(
    psi: float, theta: float, phi: float, a: float = 0.0, b: float = 0.0, c: float = 0.0
) -> np.ndarray:
    """The paper's general adjacent transform: R = Rz(psi) Rx(theta) Rz(phi), O_i at (a, b, c)."""
    psi, theta, phi, a, b, c = _numbers(psi=psi, theta=theta, phi=phi, a=a, b=b, c=c)
    cps, sps = np.cos(psi), np.sin(psi)
    cth, sth = np.cos(theta), np.sin(theta)
    cph, sph = np.cos(phi), np.sin(phi)
    return np.array(
        [
            [cps * cph - sps * sph * cth, -cps * sph - sps * cph * cth, sps * sth, a],
            [sps * cph + cps * sph * cth, -sps * sph + cps * cph * cth, -cps * sth, b],
            [sph * sth, cph * sth, cth, c],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    """URDF rpy: R = Rz(y) Ry(p) Rx(r) (Pinocchio's ``rpy.rpyToMatrix``)."""
    return np.array(pin.rpy.rpyToMatrix(*_numbers(r=r, p=p, y=y)))


def zxz_to_origin(
    psi: float, theta: float, phi: float, a: float = 0.0, b: float = 0.0, c: float = 0.0
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """URDF ``origin`` (xyz, rpy) of the z-x-z transform (rpy with pitch in [-pi/2, pi/2])."""
    psi, theta, phi, a, b, c = _numbers(psi=psi, theta=theta, phi=phi, a=a, b=b, c=c)
    R = euler_zxz(psi, theta, phi)[:3, :3]
    pitch = float(np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0])))
    if np.hypot(R[0, 0], R[1, 0]) < 1e-12:  # gimbal lock: put all yaw into roll
        roll, yaw = float(np.arctan2(-R[1, 2], R[1, 1])), 0.0
    else:
        roll = float(np.arctan2(R[2, 1], R[2, 2]))
        yaw = float(np.arctan2(R[1, 0], R[0, 0]))
    return (float(a), float(b), float(c)), (roll, pitch, yaw)


def origin_to_zxz(
    xyz: Sequence[float], rpy: Sequence[float]
) -> tuple[float, float, float, float, float, float]:
    """(psi, theta, phi, a, b, c) of a URDF origin, theta in [0, pi].

    For theta = 0 or pi only psi + phi (or psi - phi) is defined: phi is set to 0.
    """
    R = rpy_matrix(*_validate.vector3(rpy, "rpy", InvalidParameterError).tolist())
    x, y, z = _validate.vector3(xyz, "xyz", InvalidParameterError).tolist()
    theta = float(np.arccos(np.clip(R[2, 2], -1.0, 1.0)))
    if np.sin(theta) > 1e-12:
        psi = float(np.arctan2(R[0, 2], -R[1, 2]))
        phi = float(np.arctan2(R[2, 0], R[2, 1]))
    else:
        psi, phi = float(np.arctan2(R[1, 0], R[0, 0])), 0.0
        if R[2, 2] < 0:
            psi = float(np.arctan2(-R[0, 1], R[0, 0]))
    return psi, theta, phi, x, y, z
