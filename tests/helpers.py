"""Independent reference routes used by several tests (no toolkit code inside)."""

from __future__ import annotations

import numpy as np


def rot_log(R: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix (for finite differences of orientation)."""
    cos = np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(cos)
    if angle < 1e-12:
        return np.zeros(3)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return angle * w / (2.0 * np.sin(angle))


def fd_jacobian(fk, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central finite-difference Jacobian (rows vx vy vz wx wy wz, base-aligned) of a pose map."""
    cols = []
    for i in range(len(q)):
        dq = np.zeros_like(q)
        dq[i] = h
        Tp, Tm = fk(q + dq), fk(q - dq)
        v = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        w = rot_log(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
        cols.append(np.concatenate([v, w]))
    return np.array(cols).T


class Judge:
    """An FK that shares no code with the toolkit's solvers: yourdfpy on the robot's URDF
    file (mimic joints applied by yourdfpy), with its own check of q's validity (limits,
    (cos, sin) pairs and quaternions of norm 1)."""

    def __init__(self, robot) -> None:
        import yourdfpy

        self.robot = robot
        self.urdf = yourdfpy.URDF.load(
            str(robot.urdf_path), load_meshes=False, build_scene_graph=True
        )
        model = robot.model
        self.columns = []  # (yourdfpy joint, q index, kind) per joint that owns coordinates
        for name in self.urdf.actuated_joint_names:
            if not model.existJointName(name):
                continue  # a mimic joint: yourdfpy follows its master
            joint = model.joints[model.getJointId(name)]
            self.columns.append((name, int(joint.idx_q), int(joint.nq)))
        self.root = self.urdf.base_link
        self.tip = robot.tip

    def valid(self, q: np.ndarray) -> bool:
        lo, hi = self.robot.joints.lower, self.robot.joints.upper
        if np.any(q < lo - 1e-12) or np.any(q > hi + 1e-12):
            return False
        pairs = [q[i : i + 2] for _, i, n in self.columns if n == 2]
        return all(abs(float(c * c + s * s) - 1.0) <= 1e-9 for c, s in pairs)

    def pose(self, q: np.ndarray) -> np.ndarray:
        cfg = {}
        for name, i, n in self.columns:
            cfg[name] = float(np.arctan2(q[i + 1], q[i])) if n == 2 else float(q[i])
        self.urdf.update_cfg(cfg)
        return np.asarray(self.urdf.get_transform(self.tip, self.root))

    def errors(self, q: np.ndarray, p_t: np.ndarray, R_t: np.ndarray | None) -> tuple[float, float]:
        T = self.pose(q)
        pos = float(np.linalg.norm(T[:3, 3] - p_t))
        rot = 0.0 if R_t is None else float(np.linalg.norm(rot_log(T[:3, :3].T @ R_t)))
        return pos, rot


def audit_ik(robot, n: int, seed: int, tol: float = 1e-6, method: str = "auto") -> dict:
    """Solve ``n`` targets with ``robot.ik`` (half reachable poses, a quarter reachable
    positions, a quarter far out of reach) and count the successes that an independent
    check refutes: yourdfpy recomputes the pose from the URDF file (:class:`Judge`), and
    q must lie within the limits with its (cos, sin) pairs on the circle."""
    rng = np.random.default_rng(seed)
    judge = Judge(robot)
    tips = robot.fk(robot.random_q(200, seed=rng))[:, :3, 3]
    reach = float(np.linalg.norm(tips, axis=1).max())
    out = {"queries": n, "successes": 0, "false_successes": 0, "worst_claimed_error": 0.0}
    for i in range(n):
        T = robot.fk(robot.random_q(seed=rng))
        if i % 4 in (0, 1):
            R_t, p_t, target = T[:3, :3], T[:3, 3], T
        else:
            if i % 4 == 2:
                p_t = T[:3, 3]
            else:  # beyond the reach of the arm
                direction = rng.normal(size=3)
                p_t = 3 * reach * direction / np.linalg.norm(direction)
            R_t, target = None, p_t
        res = robot.ik(target, tol=tol, restarts=3, seed=i, method=method)
        if not res.success:
            continue
        out["successes"] += 1
        pos, rot = judge.errors(res.q, p_t, R_t)
        out["worst_claimed_error"] = max(out["worst_claimed_error"], pos, rot)
        out["false_successes"] += int(pos > tol or rot > tol or not judge.valid(res.q))
    return out


def unit(v):
    return v / np.linalg.norm(v)


def _xyz(v):
    return " ".join(repr(float(x)) for x in v)


def chain_urdf(axes, points, tip, name="random6r", kinds=None):
    """An nR URDF whose joint i turns about axes[i] through points[i] (base frame, every
    link frame parallel to the base at zero), and a tool at ``tip``; ``kinds`` (a string
    of R and P) makes joints prismatic (sliding along axes[i], +-2 m)."""
    kinds = kinds or "R" * len(axes)
    links = "".join(f'<link name="l{i}"/>' for i in range(len(axes) + 1)) + '<link name="lt"/>'
    joints, prev = [], np.zeros(3)
    for i, (h, p) in enumerate(zip(axes, points, strict=True)):
        d = p - prev
        kind, bound = ("prismatic", 2.0) if kinds[i] == "P" else ("revolute", 3.14159)
        joints.append(
            f'<joint name="j{i + 1}" type="{kind}"><parent link="l{i}"/>'
            f'<child link="l{i + 1}"/><origin xyz="{_xyz(d)}"/><axis xyz="{_xyz(h)}"/>'
            f'<limit lower="{-bound}" upper="{bound}" effort="1" velocity="1"/></joint>'
        )
        prev = p
    d = tip - prev
    joints.append(
        f'<joint name="tool" type="fixed"><parent link="l{len(axes)}"/><child link="lt"/>'
        f'<origin xyz="{_xyz(d)}" rpy="0.3 -0.2 0.1"/></joint>'
    )
    return f'<robot name="{name}">{links}{"".join(joints)}</robot>'


def same_up_to_turns(a, b, close=1e-6):
    return np.abs(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi).max() < close


def random_spherical_shoulder(rng: np.random.Generator) -> str:
    """A random 6R URDF with axes 1-3 through one point and axes 4, 5 parallel: a spherical
    wrist read from the frame (the chain reversed)."""
    h = [unit(rng.normal(size=3)) for _ in range(6)]
    h[4] = -h[3] if rng.random() < 0.5 else h[3]
    S = rng.normal(size=3) * 0.2
    o = [S - 0.1 * h[0], S, S + 0.2 * h[2], *(rng.normal(size=3) * 0.3 for _ in range(3))]
    return chain_urdf(h, o, o[5] + rng.normal(size=3) * 0.1)


POSITION_KINDS = ("PPP", "RPP", "RRP meeting", "RRP parallel", "3R meeting", "3R parallel",
                  "3R general")  # fmt: skip
"""The 3-joint chains placing a point that :func:`random_position_chain` builds."""


def random_position_chain(kind: str, rng: np.random.Generator) -> str:
    """A random 3-joint URDF of one of :data:`POSITION_KINDS` (random axes and points; the
    meeting axes through one point, the parallel ones parallel or opposed)."""
    h = [unit(rng.normal(size=3)) for _ in range(3)]
    o = [rng.normal(size=3) * 0.3 for _ in range(3)]
    if kind.endswith("meeting"):
        o[1] = o[0] = rng.normal(size=3) * 0.2
    if kind == "RRP parallel":
        h[1] = h[0] if rng.random() < 0.5 else -h[0]
    if kind == "3R parallel":
        h[2] = -h[1] if rng.random() < 0.5 else h[1]
    kinds = kind.split()[0] if kind[0] != "3" else None
    return chain_urdf(h, o, rng.normal(size=3) * 0.4, "chain3", kinds)


def random_outer_parallel(rng: np.random.Generator, last: bool = False) -> str:
    """A random 6R URDF with axes 1, 2, 3 parallel (each axis 2, 3 with or against axis 1)
    and axes 4-6 random; ``last``: axes 4, 5, 6 parallel instead (the family read from the
    frame)."""
    h = [unit(rng.normal(size=3)) for _ in range(6)]
    first = 3 if last else 0
    for i in (first + 1, first + 2):
        h[i] = h[first] * (1.0 if rng.random() < 0.5 else -1.0)
    o = [rng.normal(size=3) * 0.3 for _ in range(6)]
    return chain_urdf(h, o, o[5] + rng.normal(size=3) * 0.1)


def numeric_among_branches(robot, T, rows, starts) -> int:
    """Assert that every solution the numeric IK converges to from ``starts`` (to 1e-10,
    no restarts) is one of ``rows`` up to whole turns (to 1e-6, or 1e-9 over the Jacobian's
    smallest singular value near a singularity, where the pose fixes the angles only that
    loosely); the count of numeric solutions compared."""
    compared = 0
    for start in starts:
        found = robot.ik(T, q0=start, tol=1e-10, restarts=0, method="numeric")
        if found.success:
            sigma = np.linalg.svd(robot.jacobian(found.q), compute_uv=False)[-1]
            close = max(1e-6, 10 * 1e-10 / sigma)
            assert any(same_up_to_turns(r, found.q, close) for r in rows)
            compared += 1
    return compared
