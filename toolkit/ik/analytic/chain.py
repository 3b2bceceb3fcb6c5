"""A chain of joints as the analytic IK reads it (:func:`chain_of`: each axis and a point on
it in the base frame at zero, the frame's pose there), and what :func:`toolkit.ik.analytic.structure
.find_structure` makes of it (:class:`Structure`). See :mod:`toolkit.ik.analytic.structure`."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ...errors import UnsupportedModelError
from .family import COMPILED, Family

__all__ = [
    "COMPILED",
    "EXACT_TOL",
    "NEAR",
    "Chain",
    "Structure",
    "chain_of",
    "exact_for",
    "retipped",
    "reverse",
]

EXACT_TOL = 1e-9
"""Axes within this [rad, m] are parallel or meet exactly."""
NEAR = {"angle": 0.01, "distance": 0.005}
"""How far [rad, m] axes may be from parallel or from meeting for an arm to be treated as
near its family (a calibrated arm is about 0.0035 rad and 0.001 m away)."""


@dataclass(frozen=True)
class Chain:
    """The revolute joints from the base to a frame, at the zero configuration."""

    joints: tuple[int, ...]  # Pinocchio joint ids, base to frame
    names: tuple[str, ...]
    columns: tuple[int, ...]  # each joint's index in the one-value-per-joint vector
    axes: np.ndarray  # (n, 3) unit axes in the base frame
    points: np.ndarray  # (n, 3) a point on each axis (the joint's origin)
    tip: np.ndarray  # (4, 4) the frame's pose at zero
    prismatic: tuple[bool, ...] = ()  # per joint: slides along its axis (empty: none does)

    @property
    def sliding(self) -> np.ndarray:
        """(n,) True for each prismatic joint."""
        return np.array(self.prismatic or (False,) * len(self.joints), dtype=bool)


@dataclass(frozen=True)
class Structure:
    """What makes the IK of a chain solvable in closed form (or why not)."""

    family: Family | None
    joints: tuple[str, ...]
    reason: str
    exact: bool = True
    deviation: float = 0.0  # the largest miss [rad or m] of the family's conditions
    points: np.ndarray | None = None  # the points on the axes the family solves with
    reversed: bool = False  # the family fits the reversed chain (:func:`reverse`)

    def __bool__(self) -> bool:
        return self.family is not None

    @property
    def places_point(self) -> bool:
        """Whether its targets are positions (a family of 3-joint chains)."""
        return self.family is not None and Family(self.family).places_point

    @property
    def compiled(self) -> bool:
        """Whether a compiled kernel solves this family (:data:`COMPILED`; a reversed one
        on the chain seen from its frame)."""
        return self.family in COMPILED  # a str name (pickled before the keys) compares too


def exact_for(found: Structure, tol: float) -> bool:
    """Whether ``found``'s branches, solved on its exact geometry, pass ``tol`` [m, rad] on
    the real arm without a polish: its conditions hold to :data:`EXACT_TOL` and their miss
    times the arm's size (its axis points' distance from the base, at least 1 m) stays a
    tenth of ``tol`` below. Otherwise every branch is polished on the real model, so no
    arm sits between the two (pi/2 written as 1.570796325 is exact to 1e-9, not to 1e-10)."""
    if not found.exact:
        return False
    size = 1.0 if found.points is None else max(1.0, float(np.abs(found.points).max()))
    return found.deviation * size <= 0.1 * tol


def retipped(chain: Chain, found: Structure, tip: np.ndarray) -> tuple[Chain, Structure]:
    """``chain`` and its ``found`` structure with the frame at ``tip`` (4, 4) instead: what a
    joint locked after every chain joint gives at another angle. The axes and points stay;
    a family's conditions on them hold as before, and the points of a family found on the
    reversed chain (in the frame's pose at zero) move with the frame."""
    G = np.linalg.inv(tip) @ chain.tip
    points = found.points
    if found.reversed and points is not None:
        points = points @ G[:3, :3].T + G[:3, 3]
    moved = Chain(chain.joints, chain.names, chain.columns, chain.axes, chain.points,
                  np.array(tip, dtype=float), chain.prismatic)  # fmt: skip
    return moved, replace(found, points=points)


def reverse(chain: Chain) -> Chain:
    """The chain seen from its frame: joint i of the result is joint n + 1 - i, its axis and
    point in the frame's pose at zero M, the frame M^-1. Its pose at angles q' is T^-1 where
    T is the original's at q = -q' reversed."""
    M = chain.tip
    R, inv = M[:3, :3], np.linalg.inv(M)
    return Chain(
        chain.joints[::-1], chain.names[::-1], chain.columns[::-1],
        (chain.axes @ R)[::-1], (chain.points @ inv[:3, :3].T + inv[:3, 3])[::-1], inv,
        chain.prismatic[::-1],
    )  # fmt: skip


def chain_of(model: pin.Model, frame_id: int, lock: dict[int, float] | None = None) -> Chain:
    """The chain to ``frame_id``; an :class:`UnsupportedModelError` for a joint that is not
    a 1-DoF revolute or prismatic one (mimic, floating, spherical). ``lock`` {joint id: angle
    [rad]}: those joints are held at their angle and left out (the others' axes and the
    frame are read there)."""
    lock = lock or {}
    q = pin.neutral(model)
    for j, angle in lock.items():
        joint = model.joints[j]
        if joint.nq == 2:
            q[joint.idx_q : joint.idx_q + 2] = (np.cos(angle), np.sin(angle))
        else:
            q[joint.idx_q] = angle
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    tip = np.array(pin.updateFramePlacement(model, data, frame_id).homogeneous)
    path = []
    j = int(model.frames[frame_id].parentJoint)
    while j > 0:
        path.append(j)
        j = int(model.parents[j])
    path.reverse()
    outside = [model.names[j] for j in lock if j not in path]
    if outside:
        raise UnsupportedModelError(
            f"lock: joint(s) {outside} are not between the base and {model.frames[frame_id].name}"
        )
    for j in lock:
        S = np.asarray(data.joints[j].S, dtype=float).reshape(6, -1)
        if model.joints[j].nv != 1 or np.linalg.norm(S[:3, 0]) > 1e-12:
            raise UnsupportedModelError(f"lock: joint {model.names[j]!r} is not revolute")
    path = [j for j in path if j not in lock]
    axes, points, sliding = [], [], []
    for j in path:
        joint, short = model.joints[j], model.joints[j].shortname()
        S = np.asarray(data.joints[j].S, dtype=float).reshape(6, -1)
        v, w = (S[:3, 0], S[3:, 0]) if S.shape[1] else (np.zeros(3), np.zeros(3))
        turning, moving = np.linalg.norm(w) > 1e-12, np.linalg.norm(v) > 1e-12
        if joint.nv != 1 or short == "JointModelMimic" or (turning and moving):
            raise UnsupportedModelError(
                f"joint {model.names[j]!r} ({short}) is neither a revolute nor a prismatic "
                "joint: the analytic families take chains of those"
            )
        axis = w if turning else v
        axes.append(data.oMi[j].rotation @ (axis / np.linalg.norm(axis)))
        points.append(np.array(data.oMi[j].translation))
        sliding.append(not turning)
    return Chain(
        tuple(path),
        tuple(model.names[j] for j in path),
        tuple(int(model.joints[j].idx_v) for j in path),
        np.array(axes).reshape(-1, 3),
        np.array(points).reshape(-1, 3),
        tip,
        tuple(sliding) if any(sliding) else (),
    )
