"""A robot with one estimate of its errors (see :mod:`toolkit.calibration`)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from ..common import renames
from ..robot import Robot
from ._identify import as_matrix
from ._jacobian import GRAVITY, predict
from ._model import Errors, ParameterSet
from ._urdf import corrected_urdf

__all__ = ["DEFAULT", "ArmModel"]

DEFAULT = ("offsets", "geometry", "base", "tool")


@dataclass
class ArmModel:
    """A robot with one estimate of its errors: what it predicts, its corrected URDF."""

    pset: ParameterSet
    errors: Errors

    @property
    def robot(self) -> Robot:
        """The nominal robot these errors apply to."""
        return self.pset.robot

    def values(self) -> dict[str, float]:
        """Every parameter's value by name."""
        return dict(zip(self.pset.names, self.pset.values(self.errors).tolist(), strict=True))

    def fk(self, q: ArrayLike, frame: str | None = None) -> np.ndarray:
        """World poses (N, 4, 4) of ``frame`` (default: the tool) at commands q (N, nq)."""
        Q = as_matrix(q, self.robot, "q")
        return predict(self.pset, self.errors, Q, self.robot.frames.id(frame))

    def positions(self, q: ArrayLike) -> np.ndarray:
        """Tool positions (N, 3) [m] at commands q."""
        return self.fk(q)[:, :3, 3]

    @renames.renamed(link="frame")
    def gravity(self, q: ArrayLike, frame: str) -> np.ndarray:
        """Directions of gravity (N, 3) in ``frame``'s axes at commands q."""
        return np.asarray(np.einsum("nji,j->ni", self.fk(q, frame)[:, :3, :3], GRAVITY))

    @cached_property
    def urdf_text(self) -> str:
        """The URDF with the geometric errors and offsets folded in (:mod:`._urdf`)."""
        return corrected_urdf(self.pset, self.errors)
