"""All IK branches as a result: the analytic branches of a family, each turned into a q,
repeated for every equivalent angle (q + 2 pi k) inside a joint's limits, deduplicated and
verified (``Robot.ik_all``)."""

from __future__ import annotations

import itertools
import math
from typing import NamedTuple

import numpy as np

from .structure import Structure

__all__ = ["IKAllResult", "turns"]


class IKAllResult(NamedTuple):
    """Every branch that puts the frame on the target.

    ``q`` (B, nq) one row per branch; ``success`` (B,) True where the branch is verified by
    an independent forward kinematics to ``tol`` and lies within the joint limits;
    ``within_limits`` (B,); ``labels`` the branch of each row ("shoulder +, elbow -, wrist
    +"; rows that differ by whole turns of a joint share it); ``position_error`` [m] and
    ``orientation_error`` [rad] (B,); the arm's ``structure``; ``polished``: the arm is
    only near its family and each branch was polished on the real model; ``lost``:
    branches of the nearest exact geometry that did not converge on the real model or
    merged with another.
    """

    q: np.ndarray
    success: np.ndarray
    within_limits: np.ndarray
    labels: list[str]
    position_error: np.ndarray
    orientation_error: np.ndarray
    structure: Structure
    polished: bool = False
    lost: int = 0

    @property
    def solved(self) -> int:
        """How many branches succeeded."""
        return int(np.count_nonzero(self.success))


def turns(angles: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(K, n): every vector equal to ``angles`` up to whole turns of each joint within
    [lower, upper] (per joint, inclusive to 1e-12); a joint with no such angle keeps its
    angle wrapped to (-pi, pi] (the row then lies outside the limits)."""
    choices = []
    for a, lo, hi in zip(angles.tolist(), lower.tolist(), upper.tolist(), strict=True):
        a = math.remainder(a, 2 * math.pi)
        if not (math.isfinite(lo) and math.isfinite(hi)):
            choices.append([a])
            continue
        first = math.ceil((lo - 1e-12 - a) / (2 * math.pi))
        last = math.floor((hi + 1e-12 - a) / (2 * math.pi))
        inside = [a + 2 * math.pi * k for k in range(first, last + 1)]
        choices.append(inside or [a])
    return np.array(list(itertools.product(*choices)), dtype=float).reshape(-1, len(choices))
