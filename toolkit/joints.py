"""The joint-coordinate layer: what each coordinate of Pinocchio's q means, and its limits.

Pinocchio stores a configuration ``q`` (size nq) that is not always one number per joint:
a **continuous** joint (an unbounded revolute, URDF ``type="continuous"``) takes two
coordinates, ``(cos theta, sin theta)``, and free-flyer or spherical joints store a
quaternion. :class:`JointLayout` reads a model once and knows, per joint, its kind and
its coordinates, so that

* a configuration is checked for what it must be (finite, the right length, every
  (cos, sin) pair on the unit circle), with messages that say which joints take two
  numbers and why;
* users can think in one value per joint (:meth:`JointLayout.q_from_angles`,
  :meth:`JointLayout.angles`), as URDF and the papers do;
* random configurations are valid for every joint type;
* limits are what the toolkit enforces: a revolute or prismatic joint whose URDF limits
  are not finite or have lower > upper (pybullet's "unlimited" convention) is treated as
  **unlimited**; a continuous joint's two coordinates are bounded by [-1, 1].
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pinocchio as pin

from .errors import ConfigurationError, UnsupportedModelError

__all__ = ["CIRCLE_TOL", "JointInfo"]
# JointLayout is reached as ``robot.joints``; its methods take arrays Robot has checked.

CIRCLE_TOL = 1e-9
"""How far cos^2 + sin^2 of a continuous joint may be from 1 before q is refused."""
UNLIMITED_PRISMATIC = 1.0
"""Half-range [m] in which an unlimited prismatic joint is sampled by random_q."""


class JointInfo(NamedTuple):
    """One joint that owns coordinates of q."""

    name: str
    kind: str  # "revolute", "prismatic", "continuous" or "other" (free flyer, spherical, ...)
    idx_q: int
    nq: int
    idx_v: int
    nv: int


def _kind(joint: pin.JointModel) -> str:
    short = joint.shortname()
    if joint.nq == 2 and joint.nv == 1 and ("RUB" in short or "Unbounded" in short):
        return "continuous"
    if joint.nq == 1 and short.startswith("JointModelR"):
        return "revolute"
    if joint.nq == 1 and short.startswith("JointModelP"):
        return "prismatic"
    return "other"


class JointLayout:
    """Per-joint kinds, coordinates and effective limits of a Pinocchio model."""

    def __init__(self, model: pin.Model) -> None:
        self.model = model
        self.joints = [
            JointInfo(
                str(model.names[j]),
                _kind(model.joints[j]),
                int(model.joints[j].idx_q),
                int(model.joints[j].nq),
                int(model.joints[j].idx_v),
                int(model.joints[j].nv),
            )
            for j in range(1, model.njoints)
            if model.joints[j].nq > 0 and model.joints[j].idx_q >= 0
        ]
        lower = np.array(model.lowerPositionLimit, dtype=float)
        upper = np.array(model.upperPositionLimit, dtype=float)
        self.unlimited = np.zeros(model.nq, dtype=bool)
        prismatic = np.zeros(model.nq, dtype=bool)
        cos_i, sin_i, circle_v = [], [], []
        plain_q, plain_v = [], []
        for j in self.joints:
            sl = slice(j.idx_q, j.idx_q + j.nq)
            if j.kind == "continuous":
                lower[sl], upper[sl] = -1.0, 1.0
                cos_i.append(j.idx_q)
                sin_i.append(j.idx_q + 1)
                circle_v.append(j.idx_v)
            elif j.kind in ("revolute", "prismatic"):
                lo, hi = lower[j.idx_q], upper[j.idx_q]
                if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                    lower[sl], upper[sl] = -np.inf, np.inf
                    self.unlimited[sl] = True
                plain_q.append(j.idx_q)
                plain_v.append(j.idx_v)
                prismatic[sl] = j.kind == "prismatic"
        for arr in (lower, upper):
            arr.setflags(write=False)
        self.lower, self.upper = lower, upper
        self.cos_index, self.sin_index = np.array(cos_i, int), np.array(sin_i, int)
        self.circle_v = np.array(circle_v, int)
        self.plain_q, self.plain_v = np.array(plain_q, int), np.array(plain_v, int)
        self.has_other = any(j.kind == "other" for j in self.joints)
        half = np.where(prismatic, UNLIMITED_PRISMATIC, np.pi)
        self.sample_lower = np.where(np.isfinite(lower), lower, -half)
        self.sample_upper = np.where(np.isfinite(upper), upper, half)

    # ------------------------------------------------------------------ facts
    @property
    def continuous(self) -> list[str]:
        """Names of the continuous joints (two coordinates each: cos, sin)."""
        return [j.name for j in self.joints if j.kind == "continuous"]

    @property
    def revolute_mask_v(self) -> np.ndarray:
        """Per velocity coordinate (one per 1-DOF joint): True where the joint turns."""
        mask = np.zeros(self.model.nv, dtype=bool)
        for j in self.joints:
            if j.kind in ("revolute", "continuous"):
                mask[j.idx_v] = True
        return mask

    def length_hint(self) -> str:
        """What to say when q has the wrong length (which joints take two numbers)."""
        names = self.continuous
        if not names:
            return ""
        return (
            f"; continuous joints {names} take two numbers each, (cos theta, sin theta): "
            "for one value per joint use robot.q_from_angles(values)"
        )

    # ------------------------------------------------------------------ checks
    def check_circle(self, q: np.ndarray, who: str) -> None:
        """Refuse (cos, sin) pairs of continuous joints that are off the unit circle."""
        if not len(self.cos_index):
            return
        radius = q[..., self.cos_index] ** 2 + q[..., self.sin_index] ** 2
        off = np.abs(radius - 1.0) > CIRCLE_TOL
        if off.any():
            bad = sorted({self.continuous[k] for k in np.nonzero(off)[-1].tolist()})
            raise ConfigurationError(
                f"{who}: continuous joints {bad} store (cos theta, sin theta), which must lie "
                f"on the unit circle (cos^2 + sin^2 = 1 within {CIRCLE_TOL:g}); use "
                "robot.q_from_angles(values) to give one angle per joint"
            )

    def _one_dof(self, who: str) -> None:
        if self.has_other:
            others = [j.name for j in self.joints if j.kind == "other"]
            raise UnsupportedModelError(
                f"{who}: joints {others} have several degrees of freedom (free flyer, "
                "spherical, planar): they have no single value per joint"
            )

    # ------------------------------------------------------------------ conversions
    def q_from_angles(self, values: np.ndarray, who: str) -> np.ndarray:
        """q (nq,) or (N, nq) from one value per joint, shape (nv,) or (N, nv)."""
        self._one_dof(who)
        q = np.zeros((*values.shape[:-1], self.model.nq))
        q[..., self.plain_q] = values[..., self.plain_v]
        angle = values[..., self.circle_v]
        q[..., self.cos_index], q[..., self.sin_index] = np.cos(angle), np.sin(angle)
        return q

    def angles(self, q: np.ndarray, who: str) -> np.ndarray:
        """One value per joint, (nv,) or (N, nv), from q; continuous joints in (-pi, pi]."""
        self._one_dof(who)
        out = np.zeros((*q.shape[:-1], self.model.nv))
        out[..., self.plain_v] = q[..., self.plain_q]
        out[..., self.circle_v] = np.arctan2(q[..., self.sin_index], q[..., self.cos_index])
        return out

    def sample(self, rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
        """Random configurations of ``shape`` (..., nq), valid for every joint type.

        1-DOF joints: uniform within their limits (unlimited: [-pi, pi] rad or [-1, 1] m);
        continuous joints: a uniform angle stored as (cos, sin); other joints: uniform
        within finite bounds, then Pinocchio's ``normalize`` (unit quaternions).
        """
        q = rng.uniform(self.sample_lower, self.sample_upper, size=shape)
        if len(self.cos_index):
            angle = rng.uniform(-np.pi, np.pi, size=(*shape[:-1], len(self.cos_index)))
            q[..., self.cos_index], q[..., self.sin_index] = np.cos(angle), np.sin(angle)
        if self.has_other:
            flat = q.reshape(-1, self.model.nq)
            for row in flat:
                row[:] = pin.normalize(self.model, row)
            q = flat.reshape(shape)
        return q
