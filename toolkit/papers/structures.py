"""The five 3-DOF positioning structures of [P3]: matrices, point motion, IK, workspaces.

[P3] gives each structure as T14 = T12 T23 T34 (eq. 1) with the adjacent matrices of
eqs. 5-9 (frame 1 = the stand, frame 4 = the end link), and a point M of the end link
with constant local coordinates rho: r_M = T14 rho, V_M = dT14/dt rho,
a_M = d2T14/dt2 rho (eqs. 2-4).

* :func:`paper_transforms` writes the paper's matrices literally (an independent route
  to the xacro models, which the tests compare with Pinocchio).
* :func:`euler_zxz` is the paper's general adjacent transform; :func:`zxz_to_origin` and
  :func:`origin_to_zxz` convert it to and from a URDF ``origin xyz/rpy``.
* :func:`closed_form_ik` returns every joint solution that puts M on a target point.
* :func:`point_history` and :func:`resolved_rate` are the forward and inverse time
  problems; :func:`workspace` and :func:`workspace_volume` the reach space.

This module registers the five catalogue models; each carries its structure's name as
the ``structure`` fact, which is how the functions here recognise a paper 3 model.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pinocchio as pin

from .._validate import vector3
from ..catalogue import ModelSpec, register
from ..errors import ConfigurationError, InvalidParameterError, UnknownModelError
from ..robot import Robot
from ._planar import two_link, wrap

if TYPE_CHECKING:
    from matplotlib.axes import Axes

STRUCTURES = ("cartesian", "cylindrical", "spherical", "scara", "anthropomorphic")
"""The five structures of [P3], in its order (Cartesian PPP ... anthropomorphic RRR)."""
for _name, _pairs in zip(STRUCTURES, ("PPP", "RPP", "RRP", "RRP", "RRR"), strict=True):
    register(
        ModelSpec(
            name=_name,
            template=f"{_name}.urdf.xacro",
            description=f"{_name} 3-DOF positioning structure ({_pairs}; paper 3)",
            positive=frozenset({"a", "b", "c", "d", "m1", "m2", "m3", "m4"}),
            limit_pairs=tuple((f"j{i}_lower", f"j{i}_upper") for i in range(1, 4)),
            tip="link4",
            facts={"structure": _name},
        )
    )

__all__ = [
    "STRUCTURES",
    "History",
    "RateResult",
    "Workspace",
    "analytic_volume",
    "closed_form_ik",
    "default_rho",
    "draw_workspace",
    "euler_zxz",
    "origin_to_zxz",
    "paper_T14",
    "paper_transforms",
    "point_history",
    "resolved_rate",
    "rpy_matrix",
    "workspace",
    "workspace_volume",
    "zxz_to_origin",
]


# ---------------------------------------------------------------------- paper's matrices
def _rz(f: float) -> np.ndarray:
    c, s = np.cos(f), np.sin(f)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _tz(f: float) -> np.ndarray:
    return np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, f], [0, 0, 0, 1.0]])


def _p(f: float, h: float) -> np.ndarray:
    return np.array([[0, 0, 1, f], [1, 0, 0, 0], [0, 1, 0, h], [0, 0, 0, 1.0]])


def _structure(name: str) -> str:
    if name not in STRUCTURES:
        raise UnknownModelError(str(name), STRUCTURES, what="structure")
    return name


def paper_transforms(
    name: str, f: Sequence[float], a: float, b: float, c: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(T12, T23, T34) of paper 3, eqs. 5-9, written out as printed (consistent version)."""
    _structure(name)
    f1, f2, f3 = (float(x) for x in f)
    c2, s2 = np.cos(f2), np.sin(f2)
    elev = np.array([[0, 0, 1, 0], [c2, -s2, 0, 0], [s2, c2, 0, a], [0, 0, 0, 1.0]])
    if name == "cartesian":  # eq. 5
        return _p(f1, a), _p(f2, -b), _p(f3, c)
    if name == "cylindrical":  # eq. 6
        t34 = np.array([[1, 0, 0, 0], [0, 0, -1, f3], [0, 1, 0, a], [0, 0, 0, 1.0]])
        return _rz(f1), _tz(f2), t34
    if name == "spherical":  # eq. 7
        t34 = np.array([[0, 0, 1, f3], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1.0]])
        return _rz(f1), elev, t34
    if name == "scara":  # eq. 8
        t23 = np.array([[c2, -s2, 0, 0], [s2, c2, 0, b], [0, 0, 1, a], [0, 0, 0, 1.0]])
        t34 = np.array([[1, 0, 0, 0], [0, 1, 0, c], [0, 0, 1, f3], [0, 0, 0, 1.0]])
        return _rz(f1), t23, t34
    c3, s3 = np.cos(f3), np.sin(f3)  # anthropomorphic, eq. 9
    t34 = np.array([[c3, -s3, 0, b], [s3, c3, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    return _rz(f1), elev, t34


def paper_T14(name: str, f: Sequence[float], a: float, b: float, c: float) -> np.ndarray:
    """T14 = T12 T23 T34 (paper 3, eq. 1)."""
    t12, t23, t34 = paper_transforms(name, f, a, b, c)
    return t12 @ t23 @ t34


# ---------------------------------------------------------------------- z-x-z helper
def euler_zxz(
    psi: float, theta: float, phi: float, a: float = 0.0, b: float = 0.0, c: float = 0.0
) -> np.ndarray:
    """The paper's general adjacent transform: R = Rz(psi) Rx(theta) Rz(phi), O_i at (a, b, c)."""
    cps, sps = np.cos(psi), np.sin(psi)
    cth, sth = np.cos(theta), np.sin(theta)
    cph, sph = np.cos(phi), np.sin(phi)
    return np.array(
        [
            [cps * cph - sps * sph * cth, -cps * sph - sps * cph * cth, sps * sth, a],
            [sps * cph + cps * sph * cth, -sps * sph + cps * cph * cth, -cps * sth, b],
            [sph * sth, cph * sth, cth, c],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    """URDF rpy: R = Rz(y) Ry(p) Rx(r) (Pinocchio's ``rpy.rpyToMatrix``)."""
    return np.array(pin.rpy.rpyToMatrix(float(r), float(p), float(y)))


def zxz_to_origin(
    psi: float, theta: float, phi: float, a: float = 0.0, b: float = 0.0, c: float = 0.0
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """URDF ``origin`` (xyz, rpy) of the z-x-z transform (rpy with pitch in [-pi/2, pi/2])."""
    R = euler_zxz(psi, theta, phi)[:3, :3]
    pitch = float(np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0])))
    if np.hypot(R[0, 0], R[1, 0]) < 1e-12:  # gimbal lock: put all yaw into roll
        roll, yaw = float(np.arctan2(-R[1, 2], R[1, 1])), 0.0
    else:
        roll = float(np.arctan2(R[2, 1], R[2, 2]))
        yaw = float(np.arctan2(R[1, 0], R[0, 0]))
    return (float(a), float(b), float(c)), (roll, pitch, yaw)


def origin_to_zxz(
    xyz: Sequence[float], rpy: Sequence[float]
) -> tuple[float, float, float, float, float, float]:
    """(psi, theta, phi, a, b, c) of a URDF origin, theta in [0, pi].

    For theta = 0 or pi only psi + phi (or psi - phi) is defined: phi is set to 0.
    """
    R = rpy_matrix(*rpy)
    theta = float(np.arccos(np.clip(R[2, 2], -1.0, 1.0)))
    if np.sin(theta) > 1e-12:
        psi = float(np.arctan2(R[0, 2], -R[1, 2]))
        phi = float(np.arctan2(R[2, 0], R[2, 1]))
    else:
        psi, phi = float(np.arctan2(R[1, 0], R[0, 0])), 0.0
        if R[2, 2] < 0:
            psi = float(np.arctan2(-R[0, 1], R[0, 0]))
    x, y, z = (float(v) for v in xyz)
    return psi, theta, phi, x, y, z


# ---------------------------------------------------------------------- point M
def default_rho(robot: Robot) -> np.ndarray:
    """Coordinates of the model's ``point_m`` frame in the end link (frame 4)."""
    fid = robot.frame_id("point_m")
    return np.array(robot.model.frames[fid].placement.translation)


def _kind(robot: Robot) -> str:
    """The structure a paper 3 model carries in its facts (not inferred from its name)."""
    kind = robot.facts.get("structure") if isinstance(robot, Robot) else None
    if not isinstance(kind, str):
        raise UnknownModelError(
            getattr(robot, "name", repr(robot)), STRUCTURES, what="paper 3 structure"
        )
    return kind


def _dims(robot: Robot) -> tuple[str, float, float, float]:
    name = _kind(robot)
    p = robot.params
    return name, float(p["a"]), float(p["b"]), float(p["c"])


def _rho(robot: Robot, rho: object | None) -> np.ndarray:
    """rho as given, else the model's point M (paper 3 models) or the tip's origin."""
    if rho is not None:
        return vector3(rho, "rho")
    return default_rho(robot) if "point_m" in robot.frame_names else np.zeros(3)


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
    name, a, b, c = _dims(robot)
    rho_ = _rho(robot, rho)
    p = vector3(target, "target", InvalidParameterError)
    out: list[np.ndarray] = []
    for sol in _raw_solutions(name, a, b, c, rho_, p):
        q = np.array(sol, dtype=float)
        if respect_limits:
            if not robot.within_limits(q, tol=1e-9):
                # a revolute angle may sit one turn away from its range
                q = _into_range(robot, q)
                if q is None:
                    continue
        T = robot.fk(q)
        if np.linalg.norm(T[:3, :3] @ rho_ + T[:3, 3] - p) > 1e-9 * max(1.0, np.abs(p).max()):
            continue
        if not any(np.allclose(q, o, atol=1e-10) for o in out):
            out.append(q)
    return out


def _into_range(robot: Robot, q: np.ndarray) -> np.ndarray | None:
    q = q.copy()
    revolute = [robot.model.joints[j].shortname().startswith("JointModelR") for j in range(1, 4)]
    for i in range(3):
        if revolute[i]:
            for shift in (0.0, 2 * np.pi, -2 * np.pi):
                if robot.lower[i] - 1e-9 <= q[i] + shift <= robot.upper[i] + 1e-9:
                    q[i] += shift
                    break
    q = np.clip(q, robot.lower, robot.upper) if robot.within_limits(q, tol=1e-9) else None
    return q


# ---------------------------------------------------------------------- time histories
class History(NamedTuple):
    """r_M(t), V_M(t), a_M(t) of a point along joint trajectories f(t)."""

    t: np.ndarray  # (T,)
    q: np.ndarray  # (T, nq)
    qd: np.ndarray
    qdd: np.ndarray
    r: np.ndarray  # (T, 3) [m]
    v: np.ndarray  # (T, 3) [m/s]
    a: np.ndarray  # (T, 3) [m/s^2]


def _trajectory(f, t: np.ndarray, nq: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if callable(f) or (isinstance(f, Sequence) and all(callable(g) for g in f)):
        funcs: list[Callable[[float], float]] = (
            [lambda s, i=i: np.asarray(f(s), dtype=float)[i] for i in range(nq)]
            if callable(f)
            else list(f)
        )
        if len(funcs) != nq:
            raise ConfigurationError(f"need {nq} functions f_i(t), got {len(funcs)}")
        h = 1e-4
        q = np.array([[g(s) for g in funcs] for s in t], dtype=float)
        qp = np.array([[g(s + h) for g in funcs] for s in t], dtype=float)
        qm = np.array([[g(s - h) for g in funcs] for s in t], dtype=float)
        return q, (qp - qm) / (2 * h), (qp - 2 * q + qm) / (h * h)
    q = np.asarray(f, dtype=float)
    if q.shape != (len(t), nq):
        raise ConfigurationError(f"sampled f must have shape ({len(t)}, {nq}), got {q.shape}")
    qd = np.gradient(q, t, axis=0, edge_order=2)
    qdd = np.gradient(qd, t, axis=0, edge_order=2)
    return q, qd, qdd


def point_history(robot: Robot, f, t: Sequence[float], rho: object | None = None) -> History:
    """Position, velocity and acceleration of point M along f(t) (paper 3, eqs. 2-4).

    ``f`` is one callable returning the joint vector, a list of callables f_i(t), or an
    array (T, nq) sampled at the times ``t`` (then differentiated numerically, second
    order). ``rho`` defaults to the model's ``point_m`` frame for the paper 3 models and
    to the tip's origin otherwise.
    """
    times = np.asarray(t, dtype=float)
    if times.ndim != 1 or len(times) < 3 or np.any(np.diff(times) <= 0):
        raise ConfigurationError("t must be at least 3 increasing times")
    rho_ = _rho(robot, rho)
    q, qd, qdd = _trajectory(f, times, robot.nq)
    out = [robot.point_kinematics(*row, rho_) for row in zip(q, qd, qdd, strict=True)]
    r, v, a = (np.array(x) for x in zip(*out, strict=True))
    return History(times, q, qd, qdd, r, v, a)


class RateResult(NamedTuple):
    """Resolved-rate tracking of a Cartesian path by point M."""

    t: np.ndarray
    q: np.ndarray  # (T, nq) joint values
    r: np.ndarray  # (T, 3) achieved positions of M
    error: np.ndarray  # (T,) |r - path| [m]
    success: bool  # every error within tol and every q within the limits


def resolved_rate(
    robot: Robot,
    path: object,
    t: Sequence[float],
    q0: object,
    rho: object | None = None,
    *,
    gain: float = 20.0,
    tol: float = 1e-4,
    damping: float = 1e-6,
    substeps: int = 10,
) -> RateResult:
    """Drive M along a sampled Cartesian path by integrating joint rates (paper 3's inverse).

    qd = J_M^+ (dp/dt + gain (p_path - r_M)), with J_M the Jacobian of point M and a
    small damping in the pseudo-inverse; explicit Euler with ``substeps`` per sample,
    clipped to the joint limits.
    """
    times = np.asarray(t, dtype=float)
    pts = np.asarray(path, dtype=float)
    if pts.shape != (len(times), 3):
        raise ConfigurationError(f"path must have shape ({len(times)}, 3), got {pts.shape}")
    rho_ = _rho(robot, rho)
    q = robot.check_q(q0).copy()
    vel = np.gradient(pts, times, axis=0, edge_order=2)

    def point_and_jacobian(qq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        T = robot.fk(qq)
        J = robot.jacobian(qq)
        arm = T[:3, :3] @ rho_
        skew = np.array([[0, -arm[2], arm[1]], [arm[2], 0, -arm[0]], [-arm[1], arm[0], 0]])
        return T[:3, 3] + arm, J[:3] - skew @ J[3:]

    qs, rs = [q.copy()], [point_and_jacobian(q)[0]]
    for k in range(1, len(times)):
        dt = (times[k] - times[k - 1]) / substeps
        for s in range(substeps):
            frac = (s + 0.5) / substeps
            p_des = pts[k - 1] + frac * (pts[k] - pts[k - 1])
            v_des = vel[k - 1] + frac * (vel[k] - vel[k - 1])
            r, J = point_and_jacobian(q)
            cmd = v_des + gain * (p_des - r)
            qd = J.T @ np.linalg.solve(J @ J.T + damping * np.eye(3), cmd)
            q = np.clip(q + dt * qd, robot.lower, robot.upper)
        qs.append(q.copy())
        rs.append(point_and_jacobian(q)[0])
    r_all = np.array(rs)
    err = np.linalg.norm(r_all - pts, axis=1)
    return RateResult(times, np.array(qs), r_all, err, bool(np.all(err <= tol)))


# ---------------------------------------------------------------------- workspaces
class Workspace(NamedTuple):
    """Sampled reach space of a point."""

    points: np.ndarray  # (N, 3)
    volume: float  # [m^3]
    method: str


def workspace(
    robot: Robot, n: int = 20_000, rho: object | None = None, seed: int = 0
) -> np.ndarray:
    """Point cloud (n, 3) of M (or the tip origin) over uniform random joint values."""
    rho_ = _rho(robot, rho)
    q = robot.random_q(int(n), seed=seed)
    T = robot.fk(q)
    return T[:, :3, 3] + T[:, :3, :3] @ rho_


def workspace_volume(
    robot: Robot, n: int = 200_000, rho: object | None = None, seed: int = 0
) -> Workspace:
    """Volume of the reach space [m^3].

    Paper 3 structures: Monte Carlo over the cloud's bounding box with exact membership
    by :func:`closed_form_ik` (a point belongs when a solution within the limits exists);
    relative standard error about sqrt((1 - p) / (p n)). Other robots: occupied voxels
    of a sampled cloud (edge = extent / 40), a coarse estimate.
    """
    cloud = workspace(robot, min(n, 50_000), rho, seed)
    lo, hi = cloud.min(axis=0), cloud.max(axis=0)
    pad = 0.02 * (hi - lo).max()
    lo, hi = lo - pad, hi + pad
    if robot.facts.get("structure") in STRUCTURES and robot.params:
        rng = np.random.default_rng(seed + 1)
        m = max(int(n) // 10, 1000)
        pts = rng.uniform(lo, hi, size=(m, 3))
        inside = sum(bool(closed_form_ik(robot, p, rho)) for p in pts)
        return Workspace(
            cloud, float(np.prod(hi - lo) * inside / m), "monte-carlo + closed-form IK"
        )
    edge = (hi - lo).max() / 40
    keys = np.unique(np.floor((cloud - lo) / edge).astype(np.int64), axis=0)
    return Workspace(cloud, float(len(keys) * edge**3), "voxels")


def analytic_volume(robot: Robot) -> float | None:
    """Exact reach-space volume of M for the Cartesian (box), cylindrical (hollow cylinder)
    and spherical (spherical shell) structures at their default point M; None otherwise."""
    name = robot.facts.get("structure")
    lo, hi = robot.lower, robot.upper
    if name == "cartesian":
        return float(np.prod(hi - lo))
    if name == "cylindrical":
        # M = Rz(f1)(0, f3 + d, a + f2) with rho = (0, 0, -d): radius f3 + d, full turn
        d = -float(default_rho(robot)[2])
        turn = min(hi[0] - lo[0], 2 * np.pi) / (2 * np.pi)
        return float(turn * np.pi * ((hi[2] + d) ** 2 - (lo[2] + d) ** 2) * (hi[1] - lo[1]))
    if name == "spherical":
        d = float(default_rho(robot)[2])
        full = hi[0] - lo[0] >= 2 * np.pi - 1e-9 and hi[1] - lo[1] >= np.pi - 1e-9
        if not full:
            return None
        return float(4 / 3 * np.pi * ((hi[2] + d) ** 3 - (lo[2] + d) ** 3))
    return None


def draw_workspace(robot: Robot, n: int = 5000, ax: Axes | None = None) -> Axes:
    """Scatter plot of the reach space (3-D axes); returns the axes."""
    import matplotlib.pyplot as plt

    pts = workspace(robot, n)
    if ax is None:
        fig = plt.figure(figsize=(5, 5))
        ax = fig.add_subplot(projection="3d")
    ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], s=1, alpha=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"{robot.name}: reach space of M", fontsize=9)
    return ax
