"""A straight line of the tool in Cartesian space (the Robotics Toolbox's ``ctraj``): the
position along the segment, the orientation along the shortest rotation between the ends,
both on a quintic time scaling (rest at both ends), through the IK along the path that
keeps its branch."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import renames
from ..common import validate as _validate
from ..errors import InvalidParameterError
from ..ik import parse_target
from ..robot import as_robot
from .profiles import cubic
from .trajectory import Trajectory

__all__ = ["MAX_STEPS", "cartesian", "line_poses", "scaling"]

MAX_STEPS = 100_000
"""The most IK steps along a line."""


def scaling(u: np.ndarray) -> np.ndarray:
    """The quintic time scaling s(u) = 10 u^3 - 15 u^4 + 6 u^5 of u in [0, 1]: from rest to
    rest, 0 to 1."""
    return np.asarray(u**3 * (10 - 15 * u + 6 * u**2))


def line_poses(start: np.ndarray, goal: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Poses (M, 4, 4) at fractions s (M,) of the line from ``start`` to ``goal``: the
    position along the segment, the rotation R0 exp(s log(R0^T R1))."""
    w = pin.log3(start[:3, :3].T @ goal[:3, :3])
    out = np.repeat(np.eye(4)[None], len(s), axis=0)
    for k, f in enumerate(np.asarray(s, dtype=float)):
        out[k, :3, :3] = start[:3, :3] @ pin.exp3(f * w)
        out[k, :3, 3] = start[:3, 3] + f * (goal[:3, 3] - start[:3, 3])
    return out


def _pose(value: object, what: str) -> np.ndarray:
    """``value`` checked as IK targets are (:func:`toolkit.ik.parse_target`), a 4x4 pose."""
    R, p, position_only = parse_target(value)
    if position_only:
        raise InvalidParameterError(f"{what} must be a 4x4 pose, not a position")
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


@renames.renamed(start="start_pose", goal="goal_pose")
def cartesian(
    robot: Any, start_pose: ArrayLike, goal_pose: ArrayLike, duration: float, *,
    q0: ArrayLike | None = None, steps: int = 50, frame: str | None = None,
    method: str = "auto",
) -> Trajectory:  # fmt: skip
    """The tool (``frame``) on the straight line from ``start_pose`` to ``goal_pose`` in
    ``duration`` [s], at rest at both ends: ``steps`` + 1 poses at equal fractions of the
    line, each solved by :meth:`~toolkit.Robot.ik_path` from ``q0`` (``method`` as there:
    the analytic branch nearest the previous answer where the arm has a structure, so the
    line keeps its shoulder, elbow and wrist), timed on a quintic scaling and joined by a
    cubic spline (:func:`~toolkit.motion.cubic`). Between the poses the tool leaves the line
    by the spline's interpolation error (more ``steps``: closer). A pose the IK does not
    reach, or a joint jump of more than 0.5 rad between neighbours, is refused naming the
    step."""
    robot = as_robot(robot)
    T0, T1 = _pose(start_pose, "start_pose"), _pose(goal_pose, "goal_pose")
    duration = _validate.number(duration, "duration [s]", lower=0.0, strict=True)
    steps = _validate.count(steps, "steps", minimum=2, maximum=MAX_STEPS)
    s = np.linspace(0.0, 1.0, steps + 1)
    path = robot.ik_path(line_poses(T0, T1, s), q0, frame=frame, method=method)
    if not path.success.all():
        k = int(np.flatnonzero(~path.success)[0])
        raise InvalidParameterError(
            f"the line leaves {robot.name}'s reach at step {k} of {steps} (fraction "
            f"{s[k]:.3f}): position error {path.position_error[k]:.2e} m"
        )
    if path.jumps:
        raise InvalidParameterError(
            f"the line needs a joint jump of {path.max_step:.3f} rad at step {path.jumps[0]} "
            f"of {steps} (a branch change or a singularity on the way)"
        )
    times = _inverse_scaling(s) * duration
    out = cubic(robot, path.q, times)
    return Trajectory(out.breaks, out.coefficients, out.waypoints, out.times, "cartesian")


def _inverse_scaling(s: np.ndarray) -> np.ndarray:
    """u in [0, 1] with :func:`scaling` (u) = s, by bisection (s is increasing in u)."""
    lo, hi = np.zeros_like(s), np.ones_like(s)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = scaling(mid) < s
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    u = np.asarray(0.5 * (lo + hi))
    u[0], u[-1] = 0.0, 1.0
    return u
