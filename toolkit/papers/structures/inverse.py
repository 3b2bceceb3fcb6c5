"""[P3]'s inverse problem: every joint solution that puts point M on a target point."""

from __future__ import annotations

import numpy as np

from ...common import validate as _validate
from ...errors import InvalidParameterError
from ...robot import Robot
from .._planar import two_link, wrap
from .models import dimensions, point_m

__all__ = ["closed_form_ik"]


def _circle(r: float, offset: float) -> list[float]:
    """Values h with offset^2 + h^2 = r^2 (two signs, one when tangent)."""
    h2 = r * r - offset * offset
    if h2 < -1e-12:
        return []
    h = float(np.sqrt(max(h2, 0.0)))
    return [h] if h < 1e-12 else [h, -h]


def _raw_solutions(name, a, b, c, rho, p) -> list[tuple[float, float, float]]:
    x, y, z = p
    rx, ry, rz = rho
    r = float(np.hypot(x, y))
    sols = []
    if name == "cartesian":  # M = (f1 - b + rx, f2 + c + ry, a + f3 + rz)
        return [(x + b - rx, y - c - ry, z - a - rz)]
    if name == "cylindrical":  # M = Rz(f1) (rx, f3 - rz, a + f2 + ry)
        f2 = z - a - ry
        for w in _circle(r, rx):
            f1 = np.arctan2(y, x) - np.arctan2(w, rx)
            sols.append((wrap(float(f1)), f2, w + rz))
        return sols
    if name == "spherical":  # M = Rz(f1) (ry, c2 L - s2 rx, a + s2 L + c2 rx), L = f3 + rz
        for h in _circle(r, ry):
            f1 = np.arctan2(y, x) - np.arctan2(h, ry)
            v = z - a
            for L in _circle(float(np.hypot(h, v)), rx):
                f2 = np.arctan2(v, h) - np.arctan2(rx, L)
                sols.append((wrap(float(f1)), wrap(float(f2)), L - rz))
        return sols
    if name == "scara":  # M = Rz(f1)(0, b, a) + Rz(f1 + f2)(rx, c + ry, 0) + (0, 0, f3 + rz)
        f3 = z - a - rz
        l2 = float(np.hypot(rx, c + ry))
        # Rz(f1)(0, b) is the vector b at angle f1 + pi/2; the second at f12 + beta
        beta = np.arctan2(c + ry, rx)
        for t1, elbow in two_link(x, y, b, l2):
            f1 = t1 - np.pi / 2
            f2 = t1 + elbow - beta - f1
            sols.append((wrap(float(f1)), wrap(float(f2)), f3))
        return sols
    # anthropomorphic: M = Rz(f1)(rz, h, a + v), (h, v) = Rot(f2)(wx, wy),
    # w = (b + c3 rx - s3 ry, s3 rx + c3 ry)
    rxy = float(np.hypot(rx, ry))
    gamma = np.arctan2(ry, rx)
    for h in _circle(r, rz):
        f1 = np.arctan2(y, x) - np.arctan2(h, rz)
        v = z - a
        if rxy < 1e-12:
            if abs(np.hypot(h, v) - b) > 1e-9:
                continue
            elbows = [0.0]
        else:
            k = (h * h + v * v - b * b - rxy * rxy) / (2 * b * rxy)
            if abs(k) > 1 + 1e-12:
                continue
            e = float(np.arccos(np.clip(k, -1.0, 1.0)))
            elbows = [e - gamma] if e < 1e-12 else [e - gamma, -e - gamma]
        for f3 in elbows:
            wx = b + np.cos(f3) * rx - np.sin(f3) * ry
            wy = np.sin(f3) * rx + np.cos(f3) * ry
            f2 = np.arctan2(v, h) - np.arctan2(wy, wx)
            sols.append((wrap(float(f1)), wrap(float(f2)), wrap(float(f3))))
    return sols


def closed_form_ik(
    robot: Robot, target: object, rho: object | None = None, *, respect_limits: bool = True
) -> list[np.ndarray]:
    """Every (f1, f2, f3) that puts point M (``rho`` in frame 4) on ``target``.

    Solutions: Cartesian 1; cylindrical 2 (arm on either side of the column);
    spherical up to 4 (boom front/back, extended either way); SCARA 2 (left/right
    arm); anthropomorphic up to 4 (shoulder front/back, elbow up/down). With
    ``respect_limits`` only solutions inside the joint ranges are kept (an empty
    list means unreachable). Each solution is checked by FK before it is returned.
    """
    respect_limits = _validate.flag(respect_limits, "respect_limits")
    name, a, b, c = dimensions(robot)
    rho_ = point_m(robot, rho)
    p = _validate.vector3(target, "target", InvalidParameterError)
    out: list[np.ndarray] = []
    for sol in _raw_solutions(name, a, b, c, rho_, p):
        q: np.ndarray | None = np.array(sol, dtype=float)
        if respect_limits and not robot.joints.within_limits(q, tol=1e-9):  # type: ignore[arg-type]
            q = _into_range(robot, q)  # type: ignore[arg-type]
        if q is None:  # a revolute angle one turn away from its range, and not inside
            continue
        T = robot.fk(q)
        if np.linalg.norm(T[:3, :3] @ rho_ + T[:3, 3] - p) > 1e-9 * max(1.0, np.abs(p).max()):
            continue
        if not any(np.allclose(q, o, atol=1e-10) for o in out):
            out.append(q)
    return out


def _into_range(robot: Robot, q: np.ndarray) -> np.ndarray | None:
    """q with each revolute angle shifted by a turn into its range, or None if impossible."""
    q = q.copy()
    revolute = [robot.model.joints[j].shortname().startswith("JointModelR") for j in range(1, 4)]
    for i in range(3):
        if revolute[i]:
            for shift in (0.0, 2 * np.pi, -2 * np.pi):
                if robot.joints.lower[i] - 1e-9 <= q[i] + shift <= robot.joints.upper[i] + 1e-9:
                    q[i] += shift
                    break
    return (
        np.clip(q, robot.joints.lower, robot.joints.upper)
        if robot.joints.within_limits(q, tol=1e-9)
        else None
    )
