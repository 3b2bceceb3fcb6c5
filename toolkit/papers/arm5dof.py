"""The 5-DOF arm of [P2] and its geometric inverse kinematics, with all solutions.

The arm: base yaw theta1 about the vertical axis; shoulder theta2, elbow theta3 and
wrist pitch theta4 about parallel horizontal axes; wrist roll theta5 about the
gripper axis. Angles of the pitch joints are measured in the vertical plane of the
arm, theta2 from the horizontal, theta3 and theta4 relative to the previous link,
positive upwards; the pitch of the last link is ``phi = theta2 + theta3 + theta4``
([P2]'s formula; its printed table uses another sign for theta4, see docs/errata.md).

Geometric method ([P2], eqs. 1-3): the top view gives theta1 = atan2(Y, X); in
the side plane (horizontal coordinate r = sqrt(X^2 + Y^2), vertical z measured from
the shoulder axis) the wrist point is ``(r - l4 cos phi, z - l4 sin phi)`` and the
two-link problem gives theta3 = +/- acos(c3) and theta2. The branch reaching over the
back (theta1 + pi, r -> -r, phi -> pi - phi) gives two more solutions with the same
gripper position and the same approach direction.

Lengths (:class:`Arm5Lengths`: base_offset, upper_arm, forearm, gripper) are in any one
unit; [P2]'s table gives (3, 50, 25, 5) with no unit stated. The catalogue model
``arm5dof`` reads them as centimetres and is built in metres: :data:`MODEL_LENGTHS`.
Every function also takes the four lengths as a plain sequence.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import astuple, dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..descriptions import ModelSpec, register
from ..errors import ConfigurationError, InvalidParameterError
from ._planar import point3, unique_within, wrap, yaw_pitch_branches

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = [
    "MODEL_LENGTHS",
    "PAPER_LENGTHS",
    "Arm5Lengths",
    "GeometricIK",
    "draw_solutions",
    "forward",
    "geometric_ik",
    "geometric_ik_batch",
    "joint_points",
    "solve",
]


@dataclass(frozen=True)
class Arm5Lengths:
    """[P2]'s lengths: base-to-shoulder offset, upper arm, forearm, wrist-to-gripper point.

    Validated on construction: upper_arm and forearm > 0, base_offset and gripper >= 0,
    all finite. Unpacks like the tuple (base_offset, upper_arm, forearm, gripper).
    """

    base_offset: float
    upper_arm: float
    forearm: float
    gripper: float

    def __post_init__(self) -> None:
        for name, lower, strict in (
            ("base_offset", 0.0, False),
            ("upper_arm", 0.0, True),
            ("forearm", 0.0, True),
            ("gripper", 0.0, False),
        ):
            value = _validate.number(getattr(self, name), name, lower=lower, strict=strict)
            object.__setattr__(self, name, value)

    def __iter__(self) -> Iterator[float]:
        return iter(astuple(self))


PAPER_LENGTHS = Arm5Lengths(3.0, 50.0, 25.0, 5.0)
"""[P2]'s table: base-to-shoulder offset, upper arm, forearm, wrist-to-gripper point."""

MODEL_LENGTHS = Arm5Lengths(0.03, 0.50, 0.25, 0.05)
"""The same lengths in metres ([P2]'s units read as centimetres): the ``arm5dof`` model."""

register(
    ModelSpec(
        name="arm5dof",
        template="arm5dof.urdf.xacro",
        description="5-DOF arm of [P2] (geometric IK; lengths 3/50/25/5 read as cm)",
        positive=frozenset(
            {"upper_arm", "forearm", "m_base", "m_link1", "m_upper_arm", "m_forearm"}
            | {"m_wrist", "m_gripper", "base_offset", "gripper"}
        ),
        limit_pairs=tuple((f"j{i}_lower", f"j{i}_upper") for i in range(1, 6)),
    )
)

LengthsLike = Arm5Lengths | Sequence[float]


class GeometricIK(NamedTuple):
    """All solutions of one target, and by how much it is out of reach.

    ``solutions``: (k, 5) array, k in 0..4 (theta5 = 0); ``out_of_reach``: how far [length
    unit] the wrist point lies outside the annulus |l2 - l3| <= d <= l2 + l3 (0 when
    reachable); ``base_axis``: the target is on the base axis, so theta1 is arbitrary
    (infinitely many solutions; those returned use theta1 = ``base_yaw``).
    """

    solutions: np.ndarray
    out_of_reach: float
    base_axis: bool


def _lengths(lengths: LengthsLike | None) -> Arm5Lengths:
    if lengths is None:
        return PAPER_LENGTHS
    if isinstance(lengths, Arm5Lengths):
        return lengths
    try:
        values = [float(v) for v in lengths]
    except (TypeError, ValueError):
        values = []
    if len(values) != 4:
        raise InvalidParameterError(
            "lengths must be four finite numbers (base_offset, upper_arm, forearm, gripper), "
            f"got {lengths!r}"
        )
    return Arm5Lengths(*values)


def forward(q: Sequence[float] | np.ndarray, lengths: LengthsLike | None = None) -> np.ndarray:
    """Gripper point (x, y, z) of joint values q (5,) or (N, 5): the closed-form FK."""
    b, l2, l3, l4 = _lengths(lengths)
    q = _validate.array(q, "q", error=ConfigurationError)
    if q.ndim not in (1, 2) or q.shape[-1] != 5:
        raise ConfigurationError(
            f"q must be 5 finite joint values, shape (5,) or (N, 5), got shape {q.shape}"
        )
    t1, t2, t3, t4 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r = l2 * np.cos(t2) + l3 * np.cos(t2 + t3) + l4 * np.cos(t2 + t3 + t4)
    z = b + l2 * np.sin(t2) + l3 * np.sin(t2 + t3) + l4 * np.sin(t2 + t3 + t4)
    return np.stack([r * np.cos(t1), r * np.sin(t1), z], axis=-1)


def geometric_ik_batch(
    positions: np.ndarray,
    pitches: np.ndarray,
    lengths: LengthsLike | None = None,
    base_yaw: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised geometric IK for N targets at once.

    Returns ``(q, valid)``: q of shape (N, 4, 5) holding the four branches in the order
    (front, elbow +), (front, elbow -), (back, elbow +), (back, elbow -), with NaN where a
    target is out of reach, and ``valid`` (N, 4) bool. Merged branches are not removed
    here (see :func:`solve`). Angles are wrapped to (-pi, pi].
    """
    L = _lengths(lengths)
    P = _validate.array(positions, "positions")
    if P.ndim not in (1, 2) or P.shape[-1] != 3:
        raise InvalidParameterError(f"positions must have shape (3,) or (N, 3), got {P.shape}")
    P = P.reshape(-1, 3)
    phi = _validate.array(pitches, "pitches")
    if phi.shape not in ((), (len(P),)):
        raise InvalidParameterError(f"pitches must be one angle or {len(P)}, got {phi.shape}")
    phi = np.broadcast_to(phi, (len(P),))
    base_yaw = _validate.number(base_yaw, "base_yaw")
    out = np.empty((len(P), 4, 5))
    chunk = 32_768  # keeps the temporaries in cache
    for start in range(0, len(P), chunk):
        part = slice(start, start + chunk)
        out[part] = _batch_chunk(P[part], phi[part], L, base_yaw)
    return out, ~np.isnan(out[..., 0])


def _batch_chunk(P: np.ndarray, phi: np.ndarray, L: Arm5Lengths, base_yaw: float) -> np.ndarray:
    """The four branches of :func:`yaw_pitch_branches`, vectorised over a chunk of targets."""
    b, l2, l3, l4 = L
    x, y, z = P[:, 0], P[:, 1], P[:, 2] - b
    r = np.hypot(x, y)
    t1 = np.where(r < 1e-12, base_yaw, np.arctan2(y, x))
    # the back branch (theta1 + pi, phi -> pi - phi) mirrors the wrist point: x4 -> -x4,
    # z4 and the elbow triangle unchanged, so the trigonometry is shared by all branches
    x4 = r - l4 * np.cos(phi)
    z4 = z - l4 * np.sin(phi)
    c3 = (x4 * x4 + z4 * z4 - l2 * l2 - l3 * l3) / (2 * l2 * l3)
    ok = np.abs(c3) <= 1 + 1e-12
    c3 = np.clip(c3, -1.0, 1.0)
    s3 = np.sqrt(1.0 - c3 * c3)
    t3 = np.arctan2(s3, c3)  # elbow +; elbow - is -t3
    beta = np.arctan2(l3 * s3, l2 + l3 * c3)  # beta(-t3) = -beta(t3)
    gamma = np.arctan2(z4, x4)  # the back branch sees atan2(z4, -x4) = pi - gamma
    angles = np.empty((len(P), 4, 4))
    angles[:, 0] = np.stack([t1, gamma - beta, t3, phi - gamma + beta - t3], axis=1)
    angles[:, 1] = np.stack([t1, gamma + beta, -t3, phi - gamma - beta + t3], axis=1)
    back_phi, back_gamma = np.pi - phi, np.pi - gamma
    angles[:, 2] = np.stack(
        [t1 + np.pi, back_gamma - beta, t3, back_phi - back_gamma + beta - t3], axis=1
    )
    angles[:, 3] = np.stack(
        [t1 + np.pi, back_gamma + beta, -t3, back_phi - back_gamma - beta + t3], axis=1
    )
    out = np.zeros((len(P), 4, 5))
    out[..., :4] = wrap(angles)
    out[~ok] = np.nan
    return out


def solve(
    position: Sequence[float] | np.ndarray,
    pitch: float,
    lengths: LengthsLike | None = None,
    *,
    lower: ArrayLike | None = None,
    upper: ArrayLike | None = None,
    base_yaw: float = 0.0,
) -> GeometricIK:
    """Every solution of one target (duplicates merged), filtered by optional limits.

    Args:
        position: gripper point (x, y, z) in the base frame, unit of ``lengths``.
        pitch: angle phi of the last link above the horizontal [rad] (front view).
        lengths: (base_offset, upper_arm, forearm, gripper); default [P2]'s table.
        lower, upper: joint limits (5,) to filter the solutions by.
        base_yaw: theta1 used when the target is on the base axis.
    """
    sols, out_of_reach, on_axis = _solve_tuples(position, pitch, lengths, lower, upper, base_yaw)
    return GeometricIK(np.array(sols, dtype=float).reshape(-1, 5), out_of_reach, on_axis)


def _finite_float(value: object) -> bool:
    return isinstance(value, float) and math.isfinite(value)


def _solve_tuples(
    position: Sequence[float] | np.ndarray,
    pitch: float,
    lengths: LengthsLike | None,
    lower: ArrayLike | None,
    upper: ArrayLike | None,
    base_yaw: float,
) -> tuple[list[tuple[float, ...]], float, bool]:
    """The work of :func:`solve` on plain floats: (solutions as tuples, reach, on_axis)."""
    point = point3(position)
    if point is None:
        point = _validate.vector3(position, "position (x, y, z)", InvalidParameterError).tolist()
    x, y, z = point
    phi = pitch if _finite_float(pitch) else _validate.number(pitch, "pitch")
    yaw = base_yaw if _finite_float(base_yaw) else _validate.number(base_yaw, "base_yaw")
    L = _lengths(lengths)
    lengths_ = (L.base_offset, L.upper_arm, L.forearm, L.gripper)
    branches, out_of_reach = yaw_pitch_branches(x, y, z, phi, lengths_, yaw)
    lo = None if lower is None else _validate.array(lower, "lower", shape=(5,)).tolist()
    hi = None if upper is None else _validate.array(upper, "upper", shape=(5,)).tolist()
    return unique_within(branches, lo, hi), out_of_reach, math.hypot(x, y) < 1e-12


def geometric_ik(
    position: Sequence[float] | np.ndarray,
    pitch: float,
    lengths: LengthsLike | None = None,
    *,
    lower: ArrayLike | None = None,
    upper: ArrayLike | None = None,
) -> list[np.ndarray]:
    """All joint vectors (theta5 = 0) that put the gripper point at ``position`` with pitch phi.

    Elbow up/down and the reach-over-the-back branch: up to four solutions, fewer when
    branches merge (stretched or folded arm) or joint limits exclude them, none when the
    target is out of reach (:func:`solve` says by how much). [P2], eqs. 1-3.
    """
    sols = _solve_tuples(position, pitch, lengths, lower, upper, 0.0)[0]
    return [np.array(sol) for sol in sols]


def joint_points(q: Sequence[float] | np.ndarray, lengths: LengthsLike | None = None) -> np.ndarray:
    """Base, shoulder, elbow, wrist and gripper points (5, 3) of one configuration."""
    b, l2, l3, l4 = _lengths(lengths)
    t1, t2, t3, t4, _ = _validate.array(q, "q", shape=(5,), error=ConfigurationError).tolist()
    angles = np.cumsum([t2, t3, t4])
    radial = np.concatenate([[0.0, 0.0], np.cumsum([l2, l3, l4] * np.cos(angles))])
    height = np.concatenate([[0.0, b], b + np.cumsum([l2, l3, l4] * np.sin(angles))])
    return np.stack([radial * np.cos(t1), radial * np.sin(t1), height], axis=1)


def draw_solutions(
    position: Sequence[float] = (40.0, 10.0, 30.0),
    pitch: float = 0.2,
    lengths: LengthsLike | None = None,
    axes: Sequence[Axes] | None = None,
) -> Sequence[Axes]:
    """[P2]'s figures 3-4: every solution drawn in the XZ and YZ planes (matplotlib).

    ``axes``: two matplotlib axes to draw into (default: a new figure). Returns them.
    """
    import matplotlib.pyplot as plt

    position = tuple(_validate.vector3(position, "position", InvalidParameterError).tolist())
    _validate.axes(axes, "axes", count=2)
    sols = geometric_ik(position, pitch, lengths)
    if axes is None:
        _, new_axes = plt.subplots(1, 2, figsize=(10, 4.5))
        axes = list(new_axes)
    fig: Any = axes[0].figure  # a Figure (or SubFigure): both take suptitle, tight_layout
    for (i, j, label), ax in zip(((0, 2, "XZ"), (1, 2, "YZ")), axes, strict=True):
        for k, q in enumerate(sols):
            pts = joint_points(q, lengths)
            back = k >= 2  # the reach-over-the-back branch retraces the front shapes
            ax.plot(
                pts[:, i],
                pts[:, j],
                "o--" if back else "o-",
                lw=1.5 if back else 5,
                alpha=1.0 if back else 0.4,
                label=f"solution {k + 1}",
            )
        ax.plot(position[i], position[j], "k*", ms=12, label="target")
        ax.set_xlabel(f"{label[0]} [length unit]")
        ax.set_ylabel(f"{label[1]} [length unit]")
        ax.set_aspect("equal")
        ax.grid(True, alpha=0.3)
        ax.set_title(f"{label} plane", fontsize=9)
    axes[0].legend(fontsize=8)
    fig.suptitle(
        f"5-DOF arm [P2]: all solutions for {tuple(position)}, pitch {pitch} rad\n"
        "(dashed: the back branch, theta1 + pi, passes through the same points)",
        fontsize=10,
    )
    fig.tight_layout()
    return axes
