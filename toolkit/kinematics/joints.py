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
  **unlimited**; a continuous joint's two coordinates are bounded by [-1, 1];
* a **free flyer** (a floating base: translation, then a unit quaternion x, y, z, w) keeps
  Pinocchio's infinite translation limits, but random configurations and IK restarts draw
  its translation from a box of +-:data:`FREE_FLYER_BOX` m (or its finite limits), never
  from infinite ones; a quaternion off the unit sphere is refused like a (cos, sin) pair
  off the unit circle.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import ConfigurationError, InvalidParameterError, UnsupportedModelError

__all__ = ["CIRCLE_TOL", "FREE_FLYER_BOX", "LIMIT_TOLERANCE", "JointInfo"]
# JointLayout is reached as ``robot.joints``: its public methods check what they are given;
# ``raw_angles``, ``raw_q``, ``check_circle`` and ``sample`` take arrays already checked.

CIRCLE_TOL = 1e-9
"""How far cos^2 + sin^2 of a continuous joint may be from 1 before q is refused."""
UNLIMITED_PRISMATIC = 1.0
"""Half-range [m] in which an unlimited prismatic joint is sampled by random_q."""
FREE_FLYER_BOX = 1.0
"""Half-width [m] of the box around the origin in which a free flyer's unlimited
translation is sampled (random_q, IK restarts)."""
LIMIT_TOLERANCE = 1e-5
"""[rad or m] How far outside its limits a joint value given to a plan may lie and still be
taken, put on the limit (:meth:`JointLayout.onto_limits`): files write pi where a
description's limit reads 3.14159 (MotionBenchMaker's Fetch problems, 2.7e-6 apart)."""
NO_LIMIT = 1e10
"""A limit beyond this magnitude [m or rad] counts as none (Pinocchio writes +-1.8e308)."""
REVOLUTE, PRISMATIC, CIRCLE, FREE_FLYER, OTHER = 0, 1, 2, 3, 4
"""Joint kind codes of the compiled kernels (:mod:`toolkit.kinematics.kernels`) and of ``qlay``:
CIRCLE is a continuous joint stored as (cos, sin); OTHER a joint only Pinocchio handles.
In ``qlay`` a revolute or prismatic joint is one scalar coordinate (code 0)."""
_QLAY_KIND = {
    "revolute": REVOLUTE,
    "prismatic": REVOLUTE,
    "continuous": CIRCLE,
    "free_flyer": FREE_FLYER,
    "other": OTHER,
}


class JointInfo(NamedTuple):
    """One joint that owns coordinates of q."""

    name: str
    kind: str  # "revolute", "prismatic", "continuous", "free_flyer" or "other" (spherical, ...)
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
    if short == "JointModelFreeFlyer":
        return "free_flyer"
    return "other"


def _unit_groups(
    model: pin.Model, joints: list[JointInfo], lower: np.ndarray, upper: np.ndarray
) -> tuple[list[list[int]], np.ndarray]:
    """The coordinate groups that must have norm 1 (quaternions, a planar joint's
    (cos, sin)), and the free flyers' translation coordinates; a free flyer's limits are
    set in place (translation: none beyond NO_LIMIT; quaternion: [-1, 1])."""
    units: list[list[int]] = []
    free = np.zeros(model.nq, dtype=bool)
    for j in joints:
        short = model.joints[model.getJointId(j.name)].shortname()
        if j.kind == "free_flyer":
            units.append(list(range(j.idx_q + 3, j.idx_q + 7)))
            free[j.idx_q : j.idx_q + 3] = True
            box_lo, box_hi = lower[j.idx_q : j.idx_q + 3], upper[j.idx_q : j.idx_q + 3]
            finite = (np.abs(box_lo) < NO_LIMIT) & (np.abs(box_hi) < NO_LIMIT) & (box_lo <= box_hi)
            box_lo[~finite], box_hi[~finite] = -np.inf, np.inf
            lower[j.idx_q + 3 : j.idx_q + 7], upper[j.idx_q + 3 : j.idx_q + 7] = -1.0, 1.0
        elif short == "JointModelSpherical":
            units.append(list(range(j.idx_q, j.idx_q + 4)))
        elif short == "JointModelPlanar":
            units.append([j.idx_q + 2, j.idx_q + 3])
    return units, free


class JointLayout:
    """A robot's joint space (``robot.joints``): per joint its kind, coordinates and
    effective limits; configurations checked, converted to one value per joint and back.

    ``name`` (default: the model's) names the robot in error messages."""

    def __init__(self, model: pin.Model, name: str | None = None) -> None:
        self.model = model
        self.name = str(model.name if name is None else name)
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
        units, free = _unit_groups(model, self.joints, lower, upper)
        for j in self.joints:
            sl = slice(j.idx_q, j.idx_q + j.nq)
            if j.kind == "continuous":
                lower[sl], upper[sl] = -1.0, 1.0
                cos_i.append(j.idx_q)
                sin_i.append(j.idx_q + 1)
                circle_v.append(j.idx_v)
            elif j.kind in ("revolute", "prismatic"):
                lo, hi = lower[j.idx_q], upper[j.idx_q]
                if not (abs(lo) < NO_LIMIT and abs(hi) < NO_LIMIT and lo <= hi):
                    lower[sl], upper[sl] = -np.inf, np.inf
                    self.unlimited[sl] = True
                plain_q.append(j.idx_q)
                plain_v.append(j.idx_v)
                prismatic[sl] = j.kind == "prismatic"
        lower[np.abs(lower) >= NO_LIMIT], upper[np.abs(upper) >= NO_LIMIT] = -np.inf, np.inf
        for arr in (lower, upper):
            arr.setflags(write=False)
        self.lower, self.upper = lower, upper
        self.cos_index, self.sin_index = np.array(cos_i, int), np.array(sin_i, int)
        self.circle_v = np.array(circle_v, int)
        self.plain_q, self.plain_v = np.array(plain_q, int), np.array(plain_v, int)
        self.has_other = any(j.kind == "other" for j in self.joints)
        self.units = units + [[c, s] for c, s in zip(cos_i, sin_i, strict=True)]
        half = np.where(prismatic, UNLIMITED_PRISMATIC, np.pi)
        half = np.where(free, FREE_FLYER_BOX, half)
        for g in units:  # unit vectors: their box is [-1, 1]
            half[g] = 1.0
        self.sample_lower = np.where(np.isfinite(lower), lower, -half)
        self.sample_upper = np.where(np.isfinite(upper), upper, half)
        # per joint owning coordinates: (kind code of toolkit.kinematics.kernels, idx_q, idx_v, nq)
        self.qlay = np.array(
            [(_QLAY_KIND[j.kind], j.idx_q, j.idx_v, j.nq) for j in self.joints], np.int64
        ).reshape(-1, 4)
        self.scalar_q = np.zeros(model.nq, dtype=bool)
        self.scalar_q[self.plain_q] = True
        self._several, self._plain_only = self._shortcuts()

    def _shortcuts(self) -> tuple[list[str], bool]:
        """(the joints with several degrees of freedom, whether a value per joint is q
        itself: one coordinate per joint, in v's order)."""
        several = [j.name for j in self.joints if j.kind in ("other", "free_flyer")]
        nq, nv = self.model.nq, self.model.nv
        plain = nq == nv == len(self.plain_q) and bool(
            (self.plain_q == np.arange(nq)).all() and (self.plain_v == np.arange(nv)).all()
        )
        return several, plain

    # ------------------------------------------------------------------ facts
    @property
    def nq(self) -> int:
        """Size of the configuration vector q."""
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        """Size of the velocity vector: one value per degree of freedom (the Jacobian's
        columns)."""
        return int(self.model.nv)

    @property
    def names(self) -> list[str]:
        """Names of the joints that own coordinates of q, in q's order."""
        return [j.name for j in self.joints]

    def neutral(self) -> np.ndarray:
        """Pinocchio's neutral configuration (zero angles for revolute joints)."""
        return np.array(pin.neutral(self.model))

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
            "for one value per joint use robot.joints.q_from_angles(values)"
        )

    # ------------------------------------------------------------------ checks
    def check(self, q: ArrayLike, *, batch: bool = False) -> np.ndarray:
        """q as a float64 array of shape (nq,) (or (N, nq) with ``batch=True``).

        Raises :class:`~toolkit.errors.ConfigurationError` naming the problem: non-numeric
        entries, the wrong length (saying which joints take two numbers), NaN or infinite
        values, a continuous joint's (cos, sin) off the unit circle."""
        if batch is not False and batch is not True:
            _validate.flag(batch, "batch")
        arr = self._checked(q, self.model.nq, "q", batch)
        self.check_circle(arr, self.name)
        return arr

    def check_v(self, v: ArrayLike, what: str = "v", *, batch: bool = False) -> np.ndarray:
        """A velocity-like vector (one value per degree of freedom): shape (nv,) or (N, nv).
        ``what`` names the argument in error messages."""
        if not isinstance(what, str):
            raise InvalidParameterError(f"what must be a name (str), got {what!r:.100}")
        return self._checked(v, self.model.nv, what, _validate.flag(batch, "batch"))

    def _checked(self, value: ArrayLike, n: int, what: str, batch: bool) -> np.ndarray:
        arr = _validate.real_array(value, f"{self.name}: {what}", ConfigurationError)
        if not (arr.ndim == 1 or (batch and arr.ndim == 2)) or arr.shape[-1] != n:
            want = f"({n},)" + (f" or (N, {n})" if batch else "")
            hint = self.length_hint() if what == "q" else ""
            raise ConfigurationError(
                f"{self.name}: {what} must have shape {want} for joints {self.names}, "
                f"got shape {arr.shape}{hint}"
            )
        bad = ~np.isfinite(arr)
        if bad.any():
            columns = sorted(set(np.nonzero(bad)[-1].tolist()))
            raise ConfigurationError(
                f"{self.name}: {what} has NaN or infinite entries at index {columns}"
            )
        return arr

    def within_limits(self, q: ArrayLike, tol: float = 1e-12) -> bool:
        """True if every coordinate of q ((nq,) or (N, nq)) lies inside [lower - tol,
        upper + tol] (tol >= 0)."""
        arr = self.check(q, batch=True)
        return self.raw_within_limits(arr, _validate.number(tol, "tol", lower=0.0))

    def raw_within_limits(self, q: np.ndarray, tol: float = 1e-12) -> bool:
        """:meth:`within_limits` of a checked q, with a checked ``tol`` (unchecked)."""
        return bool(np.all(q >= self.lower - tol) and np.all(q <= self.upper + tol))

    def onto_limits(self, q: np.ndarray, what: str, tol: float = LIMIT_TOLERANCE) -> np.ndarray:
        """A checked q ((nq,) or (N, nq)) with every coordinate within ``tol`` [rad or m]
        outside its limits put on the limit (a file's pi against a description's 3.14159);
        a :class:`~toolkit.errors.ConfigurationError` naming the joint, its value and its
        limits for one farther out (``what`` names q in it: "start", "goal 2")."""
        low, high = self.lower - tol, self.upper + tol
        out = (q < low) | (q > high)
        if out.any():
            where = np.argwhere(out)[0]
            k = int(where[-1])
            value = float(q[tuple(where)])
            row = f" (configuration {int(where[0])})" if q.ndim == 2 else ""
            unit = "m" if self._owner_prismatic(k) else "rad"
            raise ConfigurationError(
                f"{what}{row}: joint {self._owner(k)!r} is {value:.6g} {unit}, outside its "
                f"limits [{self.lower[k]:.6g}, {self.upper[k]:.6g}] {unit} (by "
                f"{max(self.lower[k] - value, value - self.upper[k]):.3g}; values within "
                f"{tol:g} of a limit are put on it)"
            )
        return np.asarray(np.clip(q, self.lower, self.upper))

    def _owner_prismatic(self, index: int) -> bool:
        for j in self.joints:
            if j.idx_q <= index < j.idx_q + j.nq:
                return j.kind == "prismatic"
        return False  # pragma: no cover - every coordinate has an owner

    def q_from_angles(self, values: ArrayLike) -> np.ndarray:
        """Pinocchio's q from one value per joint (angle [rad] or stroke [m]), shape (nv,)
        or (N, nv): a continuous joint's angle becomes its (cos, sin) pair."""
        return self.raw_q(self.check_v(values, "values", batch=True), self.name)

    def angles(self, q: ArrayLike) -> np.ndarray:
        """One value per joint (shape (nv,) or (N, nv)) of a configuration q; continuous
        joints' angles in (-pi, pi]."""
        return self.raw_angles(self.check(q, batch=True), self.name)

    def off_manifold(self, q: np.ndarray) -> np.ndarray:
        """Per unit group (see ``units``), True where q's group is off the unit sphere."""
        if not self.units:
            return np.zeros((*q.shape[:-1], 0), dtype=bool)
        # summed group by group, not as a product with a 0/1 matrix: a large product runs
        # on OpenBLAS's threads, which then spin for a while and halve the compiled batch
        # launched next on a 2-core machine (the Kinova's batch RNEA ran at 0.6x its speed)
        quaternions = len(self.units) - len(self.cos_index)  # the groups before the pairs
        radius = np.empty((*q.shape[:-1], len(self.units)))
        for k, g in enumerate(self.units[:quaternions]):
            radius[..., k] = (q[..., g] * q[..., g]).sum(axis=-1)
        c, s = q[..., self.cos_index], q[..., self.sin_index]  # copies: squared in place
        c *= c
        s *= s
        c += s
        radius[..., quaternions:] = c
        radius -= 1.0
        return np.asarray(np.abs(radius, out=radius) > CIRCLE_TOL)

    def check_circle(self, q: np.ndarray, who: str) -> None:
        """Refuse (cos, sin) pairs and quaternions off the unit circle / sphere."""
        if not self.units:
            return
        off = self.off_manifold(q)
        if not off.any():
            return
        groups = sorted(set(np.nonzero(off)[-1].tolist()))
        names = [self._owner(self.units[g][0]) for g in groups]
        pairs = [n for n, g in zip(names, groups, strict=True) if len(self.units[g]) == 2]
        if pairs:
            raise ConfigurationError(
                f"{who}: joints {pairs} store (cos theta, sin theta), which must lie on the "
                f"unit circle (cos^2 + sin^2 = 1 within {CIRCLE_TOL:g}); use "
                "robot.joints.q_from_angles(values) to give one angle per joint"
            )
        raise ConfigurationError(
            f"{who}: joints {names} store a quaternion (x, y, z, w) in q whose norm must be 1 "
            f"within {CIRCLE_TOL:g}: normalise it"
        )

    def _owner(self, index: int) -> str:
        for j in self.joints:
            if j.idx_q <= index < j.idx_q + j.nq:
                return j.name
        return f"q[{index}]"  # pragma: no cover - every coordinate has an owner

    def _one_dof(self, who: str) -> None:
        if self._several:
            raise UnsupportedModelError(
                f"{who}: joints {self._several} have several degrees of freedom (free flyer, "
                "spherical, planar): they have no single value per joint"
            )

    # ------------------------------------------------------------------ conversions
    def raw_q(self, values: np.ndarray, who: str) -> np.ndarray:
        """q (nq,) or (N, nq) from one value per joint, shape (nv,) or (N, nv) (unchecked)."""
        self._one_dof(who)
        if self._plain_only:
            return np.array(values, dtype=float)
        q = np.zeros((*values.shape[:-1], self.model.nq))
        q[..., self.plain_q] = values[..., self.plain_v]
        angle = values[..., self.circle_v]
        q[..., self.cos_index], q[..., self.sin_index] = np.cos(angle), np.sin(angle)
        return q

    def raw_angles(self, q: np.ndarray, who: str) -> np.ndarray:
        """One value per joint, (nv,) or (N, nv), from a checked q; continuous joints in
        (-pi, pi]."""
        self._one_dof(who)
        if self._plain_only:
            return np.array(q, dtype=float)
        out = np.zeros((*q.shape[:-1], self.model.nv))
        out[..., self.plain_v] = q[..., self.plain_q]
        out[..., self.circle_v] = np.arctan2(q[..., self.sin_index], q[..., self.cos_index])
        return out

    def sample(self, rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
        """Random configurations of ``shape`` (..., nq), valid for every joint type.

        1-DOF joints: uniform within their limits (unlimited: [-pi, pi] rad or [-1, 1] m);
        continuous joints: a uniform angle stored as (cos, sin); a free flyer: translation
        uniform in its box, a uniform unit quaternion; other joints: uniform within finite
        bounds, then Pinocchio's ``normalize`` (unit quaternions).
        """
        q = rng.uniform(self.sample_lower, self.sample_upper, size=shape)
        for kind, qi, _, _ in self.qlay.tolist():
            if kind == FREE_FLYER:
                quat = rng.standard_normal((*shape[:-1], 4))
                q[..., qi + 3 : qi + 7] = quat / np.linalg.norm(quat, axis=-1, keepdims=True)
        if len(self.cos_index):
            angle = rng.uniform(-np.pi, np.pi, size=(*shape[:-1], len(self.cos_index)))
            q[..., self.cos_index], q[..., self.sin_index] = np.cos(angle), np.sin(angle)
        if self.has_other:
            flat = q.reshape(-1, self.model.nq)
            for row in flat:
                row[:] = pin.normalize(self.model, row)
            q = flat.reshape(shape)
        return q
