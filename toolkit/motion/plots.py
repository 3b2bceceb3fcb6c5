"""A trajectory drawn against time: joint values, speeds, accelerations and torques, one
line per joint, each limit it has drawn dashed in the joint's colour (matplotlib)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import InvalidParameterError
from .profiles import limit_of
from .trajectory import Trajectory

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot"]


def plot(
    trajectory: Trajectory, robot: Any, *, rate: float = 500.0,
    acceleration: ArrayLike | None = None, payload: object = None,
) -> Figure:  # fmt: skip
    """Four panels against time [s]: joint values [rad or m] with the joint limits, speeds
    with the description's velocity limits, accelerations (with ``acceleration`` limits
    when given) and torques by inverse dynamics (``payload`` as for
    :func:`toolkit.dynamics.inverse_dynamics`) with the description's effort limits;
    sampled at ``rate`` [Hz]. Returns the figure."""
    import matplotlib.pyplot as plt

    if not isinstance(trajectory, Trajectory):
        raise InvalidParameterError(f"plot takes a Trajectory, got {trajectory!r:.80}")
    rate = _validate.number(rate, "rate [Hz]", lower=0.0, strict=True, upper=100_000.0)
    samples, tau = trajectory.torques(robot, rate, payload=payload)
    model = robot.model
    position = [
        (robot.joints.lower[j.idx_q], robot.joints.upper[j.idx_q])
        if j.nq == 1
        else (np.nan, np.nan)
        for j in model.joints[1:]
    ]  # the robot's limits: an unlimited joint's are inf
    given = limit_of(robot, acceleration, "acceleration", None)
    accel = np.full(robot.joints.nv, np.nan) if given is None else given
    panels = (
        ("value [rad or m]", samples.angles, np.array(position)),
        ("speed [rad/s or m/s]", samples.qd, _both(model.velocityLimit)),
        ("acceleration [rad/s^2 or m/s^2]", samples.qdd, _both(accel)),
        ("torque [N m or N]", tau, _both(model.effortLimit)),
    )
    figure, axes = plt.subplots(4, 1, figsize=(9, 10), sharex=True)
    for ax, (label, values, limits) in zip(axes, panels, strict=True):
        for j, name in enumerate(robot.joints.names):
            (line,) = ax.plot(samples.t, values[:, j], label=name)
            for bound in limits[j]:
                if np.isfinite(bound):
                    ax.axhline(bound, color=line.get_color(), ls="--", lw=0.8, alpha=0.7)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    axes[0].set_title(f"{robot.name}: {trajectory.kind} trajectory, {trajectory.duration:.3g} s"
                      " (dashed: limits)")  # fmt: skip
    figure.tight_layout()
    return figure


def _both(limit: ArrayLike) -> np.ndarray:
    """(n, 2) lower and upper bounds of symmetric limits (NaN where none)."""
    arr = np.asarray(limit, dtype=float)
    arr = np.where(np.isfinite(arr) & (arr > 0), arr, np.nan)
    return np.stack([-arr, arr], axis=1)
