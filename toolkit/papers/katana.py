"""Katana 6M: modified-DH tables, closed-form forward kinematics, drive torques ([P1]).

Frames follow [P1]: frame 0 at the shoulder (on the joint-2 axis) with z0
along joint 1; ``i-1 A_i = RotX(alpha_i) TransX(a_i) RotZ(theta_i) TransZ(d_i)``
(eq. 2). The catalogue models ``katana_6m180``, ``katana_6m90a`` and
``katana_6m90b`` carry these frames as links ``link0`` ... ``link6``; their
base_link lies ``base_height`` below frame 0. Lengths default to the Katana 450
(docs/references.md, "Katana 450 data"). This module registers the three catalogue
models, with the drives' nominal torques (eq. 1) as their ``nominal_torque`` fact.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import astuple, dataclass

import numpy as np

from ..common import validate as _validate
from ..descriptions import ModelSpec, register
from ..errors import ConfigurationError, InvalidParameterError
from ._planar import point3, unique_within, wrap, yaw_pitch_branches

__all__ = [
    "DH_TABLES",
    "DRIVES",
    "VARIANTS",
    "DHRow",
    "Drive",
    "KatanaLengths",
    "closed_form_fk",
    "dh_fk",
    "dh_table",
    "mdh_transform",
    "nominal_torques",
]

VARIANTS = ("6m180", "6m90a", "6m90b")


@dataclass(frozen=True)
class KatanaLengths:
    """Link lengths [m] of [P1]'s symbols (defaults: Katana 450, docs/references.md)."""

    a2: float = 0.190
    a3: float = 0.139
    a4: float = 0.1473
    a5: float = 0.1555
    base_height: float = 0.2015

    def __post_init__(self) -> None:
        for name in ("a2", "a3", "a4", "a5", "base_height"):
            value = _validate.number(getattr(self, name), f"length {name}", lower=0.0, strict=True)
            object.__setattr__(self, name, value)

    @classmethod
    def for_variant(cls, variant: str) -> KatanaLengths:
        """Katana 450 lengths: a5 = 0.1555 m (6M180) or 0.1505 m (6M90A/B)."""
        _check_variant(variant)
        return cls() if variant == "6m180" else cls(a5=0.1505)


@dataclass(frozen=True)
class DHRow:
    """One row of [P1]'s Table 2: d_i, a_i [m], alpha_i and the joint limits [rad]."""

    d: float
    a: float
    alpha: float
    lower: float
    upper: float


def _check_variant(variant: str) -> None:
    _validate.one_of(variant, "Katana variant", VARIANTS)


def _lengths(lengths: KatanaLengths | Sequence[float] | None, variant: str) -> KatanaLengths:
    if lengths is None:
        return KatanaLengths.for_variant(variant)
    if isinstance(lengths, KatanaLengths):
        return lengths
    values = _validate.array(lengths, "lengths (a2, a3, a4, a5) [m]", shape=(4,))
    return KatanaLengths(*values.tolist())


def dh_table(
    variant: str = "6m180", lengths: KatanaLengths | Sequence[float] | None = None
) -> tuple[DHRow, ...]:
    """[P1]'s Table 2 for one configuration, with numbers for the length symbols.

    6M180: five rows, d5 = a4 + a5. 6M90A/B: six rows, d5 = a4, d6 = a5,
    alpha6 = -90 deg (A) or +90 deg (B).
    """
    _check_variant(variant)
    L = _lengths(lengths, variant)
    deg = np.radians
    rows = [
        DHRow(0.0, 0.0, 0.0, deg(-169.5), deg(169.5)),
        DHRow(0.0, 0.0, np.pi / 2, deg(-30.0), deg(102.0)),
        DHRow(0.0, L.a2, 0.0, deg(-122.5), deg(122.5)),
        DHRow(0.0, L.a3, 0.0, deg(-112.0), deg(112.0)),
    ]
    if variant == "6m180":
        rows.append(DHRow(L.a4 + L.a5, 0.0, -np.pi / 2, deg(-168.0), deg(168.0)))
    else:
        rows.append(DHRow(L.a4, 0.0, -np.pi / 2, deg(-168.0), deg(168.0)))
        alpha6 = -np.pi / 2 if variant == "6m90a" else np.pi / 2
        rows.append(DHRow(L.a5, 0.0, alpha6, deg(-29.5), deg(299.5)))
    return tuple(DHRow(*(float(x) for x in astuple(r))) for r in rows)


DH_TABLES: dict[str, tuple[DHRow, ...]] = {v: dh_table(v) for v in VARIANTS}
"""[P1]'s Table 2 with the Katana 450 lengths, per configuration."""


def mdh_transform(alpha: float, a: float, theta: float, d: float) -> np.ndarray:
    """Modified-DH adjacent transform ``RotX(alpha) TransX(a) RotZ(theta) TransZ(d)`` (eq. 2)."""
    alpha, a = _validate.number(alpha, "alpha"), _validate.number(a, "a")
    theta, d = _validate.number(theta, "theta"), _validate.number(d, "d")
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array(
        [
            [ct, -st, 0.0, a],
            [ca * st, ca * ct, -sa, -d * sa],
            [sa * st, sa * ct, ca, d * ca],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_fk(
    q: Sequence[float] | np.ndarray,
    variant: str = "6m180",
    lengths: KatanaLengths | Sequence[float] | None = None,
) -> np.ndarray:
    """Tool pose in frame 0 as the product of eq. 2 over the rows of Table 2 (eqs. 10-11)."""
    rows = dh_table(variant, lengths)
    q = _check_q(q, len(rows))
    if q.ndim != 1:
        raise ConfigurationError("dh_fk takes one configuration; use closed_form_fk for batches")
    T = np.eye(4)
    for row, theta in zip(rows, q, strict=True):
        T = T @ mdh_transform(row.alpha, row.a, theta, row.d)
    return T


def _check_q(q: Sequence[float] | np.ndarray, n: int) -> np.ndarray:
    arr = _validate.array(q, "q", error=ConfigurationError)
    if arr.ndim not in (1, 2) or arr.shape[-1] != n:
        raise ConfigurationError(f"q must have shape ({n},) or (N, {n}), got {arr.shape}")
    return arr


def closed_form_fk(
    q: Sequence[float] | np.ndarray, lengths: KatanaLengths | Sequence[float] | None = None
) -> np.ndarray:
    """Closed-form tool pose of the Katana 6M180 in frame 0 ([P1], eqs. 12-15).

    With ``t234 = theta2 + theta3 + theta4`` the rotation is
    ``RotZ(theta1) RotY(-t234) RotZ(theta5)``, i.e. the columns

    * n = (c1 c234 c5 - s1 s5, s1 c234 c5 + c1 s5, s234 c5)
    * s = (-c1 c234 s5 - s1 c5, -s1 c234 s5 + c1 c5, -s234 s5)
    * a = (-c1 s234, -s1 s234, c234)
    * p = (c1 rho, s1 rho, a2 s2 + a3 s23 + (a4 + a5) c234),
      rho = a2 c2 + a3 c23 - (a4 + a5) s234

    Args:
        q: joint angles theta1..theta5 [rad], shape (5,) or (N, 5).
        lengths: ``KatanaLengths`` or (a2, a3, a4, a5) [m]; default Katana 450.

    Returns:
        4x4 homogeneous matrix [n s a p] (or an (N, 4, 4) stack).
    """
    L = _lengths(lengths, "6m180")
    q = _check_q(q, 5)
    t1, t2, t3, t4, t5 = np.moveaxis(q, -1, 0)
    t23, t234 = t2 + t3, t2 + t3 + t4
    c1, s1, c5, s5 = np.cos(t1), np.sin(t1), np.cos(t5), np.sin(t5)
    c234, s234 = np.cos(t234), np.sin(t234)
    d5 = L.a4 + L.a5
    rho = L.a2 * np.cos(t2) + L.a3 * np.cos(t23) - d5 * s234
    T = np.zeros((*q.shape[:-1], 4, 4))
    T[..., 0, 0] = c1 * c234 * c5 - s1 * s5
    T[..., 1, 0] = s1 * c234 * c5 + c1 * s5
    T[..., 2, 0] = s234 * c5
    T[..., 0, 1] = -c1 * c234 * s5 - s1 * c5
    T[..., 1, 1] = -s1 * c234 * s5 + c1 * c5
    T[..., 2, 1] = -s234 * s5
    T[..., 0, 2] = -c1 * s234
    T[..., 1, 2] = -s1 * s234
    T[..., 2, 2] = c234
    T[..., 0, 3] = c1 * rho
    T[..., 1, 3] = s1 * rho
    T[..., 2, 3] = L.a2 * np.sin(t2) + L.a3 * np.sin(t23) + d5 * c234
    T[..., 3, 3] = 1.0
    return T


@dataclass(frozen=True)
class Drive:
    """One row of [P1]'s drive table: motor and Harmonic Drive data of a joint."""

    power: float  # motor power P [W]
    speed_rpm: float  # motor speed n [rpm]
    motor_efficiency: float  # eta_M
    gear_ratio: float  # i_R
    gear_efficiency: float  # eta_R

    @property
    def nominal_torque(self) -> float:
        """Nominal output torque ``M = P / omega * eta_M * i_R * eta_R`` [N m] (eq. 1)."""
        omega = 2.0 * np.pi * self.speed_rpm / 60.0
        return self.power / omega * self.motor_efficiency * self.gear_ratio * self.gear_efficiency


DRIVES: tuple[Drive, ...] = (
    Drive(44.5, 6400, 0.84, 100, 0.80),
    Drive(47.9, 6400, 0.85, 371, 0.80),
    Drive(23.2, 6400, 0.79, 371, 0.80),
    Drive(44.5, 6400, 0.84, 100, 0.80),
    Drive(3.88, 7800, 0.81, 100, 0.80),
    Drive(3.88, 7800, 0.81, 100, 0.80),
)
"""[P1]'s drive table of the 6M180 (merged cells repeat the value above)."""


def nominal_torques() -> np.ndarray:
    """Nominal output torques M_H of joints 1..6 [N m] from eq. 1 and the drive table."""
    return np.array([d.nominal_torque for d in DRIVES])


def closed_form_ik(
    position: Sequence[float] | np.ndarray,
    pitch: float,
    lengths: KatanaLengths | Sequence[float] | None = None,
    *,
    roll: float = 0.0,
    respect_limits: bool = True,
) -> list[np.ndarray]:
    """Every 6M180 configuration whose tool point is ``position`` with approach pitch ``pitch``.

    The 6M180 has [P2]'s structure (base yaw, three parallel pitch joints, roll), so
    the geometric method solves it: with the approach vector
    ``a = (-c1 s234, -s1 s234, c234)`` (eqs. 12-15), its elevation above the horizontal,
    seen from the front, is ``pitch = theta2 + theta3 + theta4 + pi/2``; the planar chain
    has links a2, a3 and a4 + a5. Up to four solutions (elbow up/down, and over the
    back), filtered by Table 2's limits unless ``respect_limits=False``.

    Args:
        position: tool point in frame 0 (the shoulder) [m].
        pitch: elevation of the approach axis above the horizontal [rad].
        roll: theta5 of every solution [rad].
    """
    L = _lengths(lengths, "6m180") if lengths is not None else _DEFAULT_6M180
    point = point3(position)
    if point is None:
        point = _validate.vector3(position, "position", InvalidParameterError).tolist()
    x, y, z = point
    planar = (0.0, L.a2, L.a3, L.a4 + L.a5)
    roll = _validate.number(roll, "roll")
    (l1, l2, l3, l4, l5), (h1, h2, h3, h4, h5) = _LO_6M180, _HI_6M180
    if respect_limits and not l5 <= roll <= h5:
        return []
    branches, _ = yaw_pitch_branches(x, y, z, _validate.number(pitch, "pitch"), planar, 0.0)
    out = []
    for t1, t2, t3, t4, _ in unique_within(branches, None, None):
        t4 = wrap(t4 - math.pi / 2)
        if respect_limits and not (
            l1 <= t1 <= h1 and l2 <= t2 <= h2 and l3 <= t3 <= h3 and l4 <= t4 <= h4
        ):
            continue
        out.append(np.array((t1, t2, t3, t4, roll)))
    return out


# Table 2's limits do not depend on the lengths.
_LOWER_6M180 = np.array([r.lower for r in DH_TABLES["6m180"]])
_UPPER_6M180 = np.array([r.upper for r in DH_TABLES["6m180"]])
_LO_6M180 = [float(v) - 1e-12 for v in _LOWER_6M180]
_HI_6M180 = [float(v) + 1e-12 for v in _UPPER_6M180]
_DEFAULT_6M180 = KatanaLengths.for_variant("6m180")


# --------------------------------------------------------------------------- catalogue
_KATANA_LIMITS = tuple((f"j{i}_lower", f"j{i}_upper") for i in range(1, 7))
_KATANA_POSITIVE = frozenset(
    {"base_height", "a2", "a3", "a4", "a5"}
    | {f"m_link{i}" for i in range(1, 6)}
    | {"m_base", "m_gripper"}
)
for _variant, _dof, _what in (
    ("6m180", 5, "gripper coaxial with link 5"),
    ("6m90a", 6, "angled gripper, alpha6 = -90 deg"),
    ("6m90b", 6, "angled gripper, alpha6 = +90 deg"),
):
    register(
        ModelSpec(
            name=f"katana_{_variant}",
            template="katana.urdf.xacro",
            description=f"Katana {_variant.upper()} ({_dof} DOF, {_what}; [P1])",
            fixed={"variant": _variant},
            hidden=frozenset({"j6_lower", "j6_upper"}) if _dof == 5 else frozenset(),
            positive=_KATANA_POSITIVE,
            limit_pairs=_KATANA_LIMITS[:_dof],
            facts={"nominal_torque": tuple(nominal_torques()[:_dof].tolist())},
        )
    )
