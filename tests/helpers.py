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


def audit_ik(robot, n: int, seed: int, tol: float = 1e-6) -> dict:
    """Solve ``n`` targets with ``robot.ik`` (half reachable poses, a quarter reachable
    positions, a quarter far out of reach) and count the successes that an independent
    check refutes: a fresh Pinocchio Data object recomputes the pose, and q must lie
    within the limits."""
    import pinocchio as pin

    rng = np.random.default_rng(seed)
    data = robot.model.createData()
    fid = robot.frame_id(None)
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
        res = robot.ik(target, tol=tol, restarts=3, seed=i)
        if not res.success:
            continue
        out["successes"] += 1
        pin.forwardKinematics(robot.model, data, res.q)
        M = pin.updateFramePlacement(robot.model, data, fid)
        pos = float(np.linalg.norm(M.translation - p_t))
        rot = 0.0 if R_t is None else float(np.linalg.norm(pin.log3(M.rotation.T @ R_t)))
        inside = np.all(res.q >= robot.lower - 1e-12) and np.all(res.q <= robot.upper + 1e-12)
        out["worst_claimed_error"] = max(out["worst_claimed_error"], pos, rot)
        out["false_successes"] += int(pos > tol or rot > tol or not inside)
    return out
