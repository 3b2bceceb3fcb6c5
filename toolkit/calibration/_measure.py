"""Measurements for calibration (see :mod:`toolkit.calibration`): tool positions, tool
poses and link gravity directions, each with its uncertainty, one row per configuration."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import renames
from ..common import validate as _validate
from ..errors import InvalidParameterError

__all__ = ["Block", "Measurements"]


@dataclass(frozen=True)
class Block:
    """One kind of measurement at configurations ``at`` (indices into the q of the
    identification): ``kind`` "position" (values (N, 3) [m]), "pose" ((N, 4, 4)) or
    "gravity" ((N, 3) unit vectors in ``link``'s frame); ``sigma`` (N, 3) for positions and
    gravity, (N, 6) for poses (position [m], then rotation [rad])."""

    kind: str
    values: np.ndarray
    sigma: np.ndarray
    link: str = ""
    at: np.ndarray | None = None

    @property
    def rows(self) -> int:
        """Residual rows per configuration."""
        return 6 if self.kind == "pose" else 3


def _sigma(value: ArrayLike, n: int, width: int, what: str) -> np.ndarray:
    arr = _validate.array(value, what)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,) or not np.all(arr > 0):
        raise InvalidParameterError(
            f"{what} must be one value > 0 or one per measurement ({n},), got {arr.shape}"
        )
    return np.repeat(arr[:, None], width, axis=1)


def _at(at: ArrayLike | None, n: int) -> np.ndarray | None:
    if at is None:
        return None
    idx = _validate.array(at, "at")
    if idx.shape != (n,) or not np.all(idx == np.round(idx)) or np.any(idx < 0):
        raise InvalidParameterError(f"at must be {n} configuration indices >= 0")
    return idx.astype(np.int64)


class Measurements:
    """A set of measurement blocks; ``a + b`` joins two sets (module doc)."""

    def __init__(self, blocks: tuple[Block, ...] = ()) -> None:
        self.blocks = tuple(blocks)

    def __add__(self, other: object) -> Measurements:
        if not isinstance(other, Measurements):
            return NotImplemented
        return Measurements(self.blocks + other.blocks)

    def __len__(self) -> int:
        return sum(len(b.values) for b in self.blocks)

    def __repr__(self) -> str:
        parts = [f"{len(b.values)} {b.kind}{'@' + b.link if b.link else ''}" for b in self.blocks]
        return f"Measurements({', '.join(parts) or 'empty'})"

    def columns(self, rows: int) -> dict[str, np.ndarray]:
        """The values as columns over ``rows`` configurations (NaN where a row has no such
        measurement): ``x``, ``y``, ``z`` [m] for tool positions, ``<link>:gx``, ``:gy``,
        ``:gz`` for gravity directions (as the calibration CSV file names them). A pose
        block has no such columns (refused); two blocks measuring the same thing in one row
        are refused."""
        out: dict[str, np.ndarray] = {}
        for b in self.blocks:
            if b.kind == "pose":
                raise InvalidParameterError(
                    "tool poses have no CSV columns (positions and gravity directions do); "
                    "keep them with numpy (np.save of q and T)"
                )
            names = ["x", "y", "z"] if b.kind == "position" else [f"{b.link}:g{a}" for a in "xyz"]
            at = np.arange(len(b.values)) if b.at is None else b.at
            if len(at) and at.max() >= rows:
                raise InvalidParameterError(f"{b.kind} rows reach {int(at.max())}; rows={rows}")
            for k, name in enumerate(names):
                column = out.setdefault(name, np.full(rows, np.nan))
                if not np.isnan(column[at]).all():
                    raise InvalidParameterError(f"two measurements of {name!r} in one row")
                column[at] = b.values[:, k]
        return out

    @classmethod
    def positions(
        cls, points: ArrayLike, sigma: ArrayLike = 2e-5, at: ArrayLike | None = None
    ) -> Measurements:
        """Tool positions (N, 3) [m] in the world (base) frame, e.g. from a laser tracker,
        with standard deviation ``sigma`` [m] per axis."""
        p = _validate.array(points, "points")
        if p.ndim != 2 or p.shape[1] != 3 or not len(p):
            raise InvalidParameterError(f"points must have shape (N >= 1, 3), got {p.shape}")
        sig = _sigma(sigma, len(p), 3, "sigma [m]")
        return cls((Block("position", p, sig, "", _at(at, len(p))),))

    @classmethod
    def poses(
        cls,
        T: ArrayLike,
        sigma_position: ArrayLike = 1e-4,
        sigma_rotation: ArrayLike = 1e-3,
        at: ArrayLike | None = None,
    ) -> Measurements:
        """Tool poses (N, 4, 4) (camera, optical tracker); standard deviations [m] and
        [rad] (per axis of the rotation vector)."""
        arr = _validate.array(T, "T")
        if arr.ndim != 3 or arr.shape[1:] != (4, 4) or not len(arr):
            raise InvalidParameterError(f"T must have shape (N >= 1, 4, 4), got {arr.shape}")
        for M in arr:
            R = M[:3, :3]
            if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
                raise InvalidParameterError("each pose's rotation must be orthonormal")
        n = len(arr)
        sig = np.hstack([_sigma(sigma_position, n, 3, "sigma_position [m]"),
                         _sigma(sigma_rotation, n, 3, "sigma_rotation [rad]")])  # fmt: skip
        return cls((Block("pose", arr, sig, "", _at(at, n)),))

    @classmethod
    @renames.renamed(link="frame")
    def gravity(
        cls, frame: str, directions: ArrayLike, sigma: ArrayLike = 1e-3, at: ArrayLike | None = None
    ) -> Measurements:
        """Directions of gravity (N, 3) in ``frame``'s axes, from an accelerometer or an
        inclinometer fixed to that link (normalised here); ``sigma`` per component."""
        if not isinstance(frame, str) or not frame:
            raise InvalidParameterError(f"frame must be a frame name, got {frame!r:.80}")
        d = _validate.array(directions, "directions")
        if d.ndim != 2 or d.shape[1] != 3 or not len(d):
            raise InvalidParameterError(f"directions must have shape (N >= 1, 3), got {d.shape}")
        norms = np.linalg.norm(d, axis=1)
        if np.any(norms < 1e-9):
            raise InvalidParameterError("a gravity direction is zero")
        sig = _sigma(sigma, len(d), 3, "sigma")
        return cls((Block("gravity", d / norms[:, None], sig, frame, _at(at, len(d))),))


def rotation_residual(measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """The world-frame rotation vector from the predicted to the measured rotation."""
    return np.asarray(pin.log3(measured @ predicted.T))
