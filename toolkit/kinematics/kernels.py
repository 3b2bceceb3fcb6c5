"""Compiled kernels of the chain engine (numba): plain loops on packed arrays.

A chain is a list of joints in tree order, packed by :mod:`toolkit.kinematics.backends` into

* ``ints`` (n, 6): parent row (``n`` for the base), kind (the codes of
  :mod:`toolkit.kinematics.joints`: REVOLUTE, PRISMATIC, CIRCLE: a continuous joint stored as
  (cos, sin), FREE_FLYER: translation and unit quaternion (x, y, z, w), six velocities in the
  joint's own frame), the first q index and the first v index of the joint (for a mimic
  joint, those of the joint it copies), and two shortcuts of :func:`frames`: the index of
  an axis along +-x, +-y or +-z (else -1) and 1 for a placement without rotation;
* ``flts`` (n, 17): placement rotation in the parent joint's frame (9, row-major),
  placement translation (3), unit axis in the joint's own frame (3), and the mimic
  relation ``value = scale * q[qi] + offset`` (2; 1 and 0 for an ordinary joint);
* ``tip`` (12): the tip frame's placement in the last joint's frame (rotation, translation).

``W`` (n + 1, 15) receives, per joint, its world rotation after its motion (9), its origin
(3) and its world axis (3); row n is the base (identity). Nothing allocates in the loops.

Pinocchio is the reference: ``tests/kinematics/test_engine.py`` compares every kernel with it.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..common import inline_kernel, kernel, twin_kernel
from .joints import CIRCLE, FREE_FLYER, OTHER, PRISMATIC, REVOLUTE
from .trig import sincos

# Matrices keep their mathematical names (R, J, A).


@inline_kernel
def _rotate(W, k, x, y, z, c, s):
    """W[k]'s rotation times Rot(axis (x, y, z), angle with cosine c and sine s)."""
    t = 1.0 - c
    r00, r01, r02 = c + t * x * x, t * x * y - s * z, t * x * z + s * y
    r10, r11, r12 = t * x * y + s * z, c + t * y * y, t * y * z - s * x
    r20, r21, r22 = t * x * z - s * y, t * y * z + s * x, c + t * z * z
    _times(W, k, r00, r01, r02, r10, r11, r12, r20, r21, r22)


@inline_kernel
def _times(W, k, r00, r01, r02, r10, r11, r12, r20, r21, r22):
    """W[k]'s rotation times the rotation matrix (r00 .. r22), in place."""
    for i in range(3):
        a0, a1, a2 = W[k, 3 * i], W[k, 3 * i + 1], W[k, 3 * i + 2]
        W[k, 3 * i] = a0 * r00 + a1 * r10 + a2 * r20
        W[k, 3 * i + 1] = a0 * r01 + a1 * r11 + a2 * r21
        W[k, 3 * i + 2] = a0 * r02 + a1 * r12 + a2 * r22


@inline_kernel
def _free_flyer(W, k, q, qi):
    """W[k] moved by a free-flyer's translation q[qi:qi+3] and quaternion q[qi+3:qi+7]."""
    tx, ty, tz = q[qi], q[qi + 1], q[qi + 2]
    x, y, z, w = q[qi + 3], q[qi + 4], q[qi + 5], q[qi + 6]
    for i in range(3):
        W[k, 9 + i] += W[k, 3 * i] * tx + W[k, 3 * i + 1] * ty + W[k, 3 * i + 2] * tz
    r00, r01, r02 = 1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)
    r10, r11, r12 = 2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)
    r20, r21, r22 = 2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)
    _times(W, k, r00, r01, r02, r10, r11, r12, r20, r21, r22)


@inline_kernel
def frames(q, ints, flts, W):
    """Fill W with every joint's world rotation, origin and axis at configuration q."""
    n = ints.shape[0]
    W[n, :] = 0.0
    W[n, 0] = W[n, 4] = W[n, 8] = 1.0
    for k in range(n):
        par = ints[k, 0]
        # R = R_parent @ placement rotation; p = p_parent + R_parent @ placement translation
        for i in range(3):
            if ints[k, 5]:  # no placement rotation
                for j in range(3):
                    W[k, 3 * i + j] = W[par, 3 * i + j]
            else:
                for j in range(3):
                    s = 0.0
                    for m in range(3):
                        s += W[par, 3 * i + m] * flts[k, 3 * m + j]
                    W[k, 3 * i + j] = s
            s = W[par, 9 + i]
            for m in range(3):
                s += W[par, 3 * i + m] * flts[k, 9 + m]
            W[k, 9 + i] = s
        x, y, z = flts[k, 12], flts[k, 13], flts[k, 14]
        ax = W[k, 0] * x + W[k, 1] * y + W[k, 2] * z
        ay = W[k, 3] * x + W[k, 4] * y + W[k, 5] * z
        az = W[k, 6] * x + W[k, 7] * y + W[k, 8] * z
        W[k, 12], W[k, 13], W[k, 14] = ax, ay, az
        kind, qi = ints[k, 1], ints[k, 2]
        if kind == REVOLUTE or kind == CIRCLE:
            if kind == REVOLUTE:
                s, c = sincos(flts[k, 15] * q[qi] + flts[k, 16])
            else:  # (cos, sin) as stored, as Pinocchio uses them
                c, s = q[qi], q[qi + 1]
            a = ints[k, 4]
            if a < 0:  # R = R @ Rot(axis, angle), Rodrigues' formula
                _rotate(W, k, x, y, z, c, s)
            else:  # about +-x, +-y or +-z: two columns of R turn
                _turn(W, k, (a + 1) % 3, (a + 2) % 3, c, s * flts[k, 12 + a])
        elif kind == PRISMATIC:  # the frame slides along its axis
            value = flts[k, 15] * q[qi] + flts[k, 16]
            W[k, 9] += ax * value
            W[k, 10] += ay * value
            W[k, 11] += az * value
        else:
            _free_flyer(W, k, q, qi)


@inline_kernel
def _turn(W, k, a, b, c, s):
    """W[k]'s rotation times a turn (c, s) about its own axis e_a x e_b (columns a, b move)."""
    for i in range(3):
        ra, rb = W[k, 3 * i + a], W[k, 3 * i + b]
        W[k, 3 * i + a] = c * ra + s * rb
        W[k, 3 * i + b] = c * rb - s * ra


@inline_kernel
def tip(W, tip_pl, R, p):
    """The tip frame's rotation R (3, 3) and position p (3) from the last joint of W."""
    last = W.shape[0] - 2  # row n - 1 (n - 1 = -1 when the tip hangs on the base: row n)
    if last < 0:
        last = W.shape[0] - 1
    for i in range(3):
        for j in range(3):
            s = 0.0
            for m in range(3):
                s += W[last, 3 * i + m] * tip_pl[3 * m + j]
            R[i, j] = s
        s = W[last, 9 + i]
        for m in range(3):
            s += W[last, 3 * i + m] * tip_pl[9 + m]
        p[i] = s


@inline_kernel
def jacobian(W, ints, flts, p, J):
    """Frame Jacobian J (6, nv) at the tip position p, LOCAL_WORLD_ALIGNED (filled in place).

    A free flyer's six columns are three slides and three turns about its own axes (the
    columns of its rotation), Pinocchio's local velocity convention."""
    J[:, :] = 0.0
    for k in range(ints.shape[0]):
        col, kind = ints[k, 3], ints[k, 1]
        if kind == FREE_FLYER:
            rx, ry, rz = p[0] - W[k, 9], p[1] - W[k, 10], p[2] - W[k, 11]
            for c in range(3):
                ax, ay, az = W[k, c], W[k, 3 + c], W[k, 6 + c]
                J[0, col + c] += ax
                J[1, col + c] += ay
                J[2, col + c] += az
                J[0, col + 3 + c] += ay * rz - az * ry
                J[1, col + 3 + c] += az * rx - ax * rz
                J[2, col + 3 + c] += ax * ry - ay * rx
                J[3, col + 3 + c] += ax
                J[4, col + 3 + c] += ay
                J[5, col + 3 + c] += az
            continue
        s = flts[k, 15]
        ax, ay, az = W[k, 12], W[k, 13], W[k, 14]
        if kind == PRISMATIC:
            J[0, col] += s * ax
            J[1, col] += s * ay
            J[2, col] += s * az
        else:
            rx, ry, rz = p[0] - W[k, 9], p[1] - W[k, 10], p[2] - W[k, 11]
            J[0, col] += s * (ay * rz - az * ry)
            J[1, col] += s * (az * rx - ax * rz)
            J[2, col] += s * (ax * ry - ay * rx)
            J[3, col] += s * ax
            J[4, col] += s * ay
            J[5, col] += s * az


_CHUNK = 256  # rows per work item of a parallel batch: one set of buffers each


@kernel
def _chain_rows(Q, ints, flts, tip_pl, poses, jacobians, start, stop):
    """Rows start .. stop - 1 on one set of buffers: the tip poses into ``poses`` and the
    tip Jacobians into ``jacobians`` (each skipped when it has no rows)."""
    W = np.empty((ints.shape[0] + 1, 15))
    R = np.empty((3, 3))
    p = np.empty(3)
    for i in range(start, stop):
        frames(Q[i], ints, flts, W)
        tip(W, tip_pl, R, p)
        if jacobians.shape[0]:
            jacobian(W, ints, flts, p, jacobians[i])
        if poses.shape[0]:
            for r in range(3):
                for c in range(3):
                    poses[i, r, c] = R[r, c]
                poses[i, r, 3] = p[r]
                poses[i, 3, r] = 0.0
            poses[i, 3, 3] = 1.0


@twin_kernel
def fk_batch(Q, ints, flts, tip_pl):
    """Tip poses (N, 4, 4) of configurations Q (N, nq). Like every ``*_batch`` kernel here,
    a :class:`~toolkit.common.compiler.Twin`: ``fk_batch(spread, Q, ints, flts, tip_pl)``
    runs over every core when ``spread`` is true, else on the calling thread."""
    N = Q.shape[0]
    out, none = np.empty((N, 4, 4)), np.empty((0, 6, 0))
    for c in prange((N + _CHUNK - 1) // _CHUNK):
        _chain_rows(Q, ints, flts, tip_pl, out, none, c * _CHUNK, min(N, (c + 1) * _CHUNK))
    return out


@twin_kernel
def jacobian_batch(Q, ints, flts, tip_pl, nv):
    """Tip Jacobians (N, 6, nv), LOCAL_WORLD_ALIGNED."""
    N = Q.shape[0]
    out, none = np.empty((N, 6, nv)), np.empty((0, 4, 4))
    for c in prange((N + _CHUNK - 1) // _CHUNK):
        _chain_rows(Q, ints, flts, tip_pl, none, out, c * _CHUNK, min(N, (c + 1) * _CHUNK))
    return out


@inline_kernel
def _torque(W, k, sub, gravity, ax, ay, az, turns):
    """Gravity torque of joint k's subtree about (turns) or along an axis."""
    if not turns:
        return sub[k, 0] * (ax * gravity[0] + ay * gravity[1] + az * gravity[2])
    x = sub[k, 1] - sub[k, 0] * W[k, 9]  # axis . sum m (c - o) x g
    y = sub[k, 2] - sub[k, 0] * W[k, 10]
    z = sub[k, 3] - sub[k, 0] * W[k, 11]
    mx = y * gravity[2] - z * gravity[1]
    my = z * gravity[0] - x * gravity[2]
    mz = x * gravity[1] - y * gravity[0]
    return ax * mx + ay * my + az * mz


@inline_kernel
def gravity_row(q, ints, flts, body, gravity, W, sub, out):
    """Generalized gravity g(q) of one configuration into out (nv), on buffers W and sub."""
    n = ints.shape[0]
    frames(q, ints, flts, W)
    sub[:, :] = 0.0  # per subtree: mass, sum of m c
    out[:] = 0.0
    for k in range(n - 1, -1, -1):
        m = body[k, 0]
        sub[k, 0] += m
        for r in range(3):
            c = W[k, 9 + r]
            for j in range(3):
                c += W[k, 3 * r + j] * body[k, 1 + j]
            sub[k, 1 + r] += m * c
        par = ints[k, 0]
        for r in range(4):
            sub[par, r] += sub[k, r]
    for k in range(n):
        kind, col = ints[k, 1], ints[k, 3]
        if kind == FREE_FLYER:
            for c in range(3):
                ax, ay, az = W[k, c], W[k, 3 + c], W[k, 6 + c]
                out[col + c] -= _torque(W, k, sub, gravity, ax, ay, az, False)
                out[col + 3 + c] -= _torque(W, k, sub, gravity, ax, ay, az, True)
        else:
            tau = _torque(W, k, sub, gravity, W[k, 12], W[k, 13], W[k, 14], kind != PRISMATIC)
            out[col] -= flts[k, 15] * tau


@kernel
def _gravity_rows(Q, ints, flts, body, gravity, out, start, stop):
    n = ints.shape[0]
    W = np.empty((n + 1, 15))
    sub = np.empty((n + 1, 4))
    for i in range(start, stop):
        gravity_row(Q[i], ints, flts, body, gravity, W, sub, out[i])


@twin_kernel
def gravity_batch(Q, ints, flts, body, gravity, nv):
    """Generalized gravity g(q) (N, nv) of Pinocchio's ``computeGeneralizedGravity``.

    The joint list is the whole tree; ``body[k]`` = (mass, centre of mass in the joint's
    frame) of the body joint k carries.
    """
    N = Q.shape[0]
    out = np.empty((N, nv))
    for c in prange((N + _CHUNK - 1) // _CHUNK):
        _gravity_rows(Q, ints, flts, body, gravity, out, c * _CHUNK, min(N, (c + 1) * _CHUNK))
    return out


# ---------------------------------------------------------------- configurations
# ``qlay`` (m, 4): per joint that owns coordinates, (kind, q index, v index, nq); the kind
# codes of toolkit.kinematics.joints, OTHER for joints only Pinocchio handles (sampled in their box,
# then normalised by Pinocchio).


@inline_kernel
def integrate(q, dq, qlay, lo, hi):
    """q <- q (+) dq on every joint's own manifold, then clipped to [lo, hi] (in place).

    Scalars add; a (cos, sin) pair turns by dq; a free flyer moves by exp6(dq) in its own
    frame (Pinocchio's ``integrate``), its quaternion renormalised."""
    for r in range(qlay.shape[0]):
        kind, qi, vi = qlay[r, 0], qlay[r, 1], qlay[r, 2]
        if kind == CIRCLE:
            s, c = sincos(dq[vi])
            a, b = q[qi], q[qi + 1]
            q[qi], q[qi + 1] = a * c - b * s, b * c + a * s
        elif kind == FREE_FLYER:
            _se3_step(q, qi, dq, vi)
        else:
            q[qi] = min(max(q[qi] + dq[vi], lo[qi]), hi[qi])


@inline_kernel
def _se3_step(q, qi, dq, vi):
    """Free flyer q[qi:qi+7] <- q * exp6(dq[vi:vi+6]) (local velocity: linear, angular)."""
    vx, vy, vz = dq[vi], dq[vi + 1], dq[vi + 2]
    wx, wy, wz = dq[vi + 3], dq[vi + 4], dq[vi + 5]
    th2 = wx * wx + wy * wy + wz * wz
    th = np.sqrt(th2)
    if th < 1e-6:  # series of (1 - cos)/th^2 and (th - sin)/th^3
        a, b = 0.5 - th2 / 24.0, 1.0 / 6.0 - th2 / 120.0
        half_sin, half_cos = 0.5 - th2 / 48.0, 1.0 - th2 / 8.0
    else:
        a, b = (1.0 - np.cos(th)) / th2, (th - np.sin(th)) / (th2 * th)
        half_sin, half_cos = np.sin(0.5 * th) / th, np.cos(0.5 * th)
    # p = V v, V = I + a [w]x + b [w]x^2
    cx, cy, cz = wy * vz - wz * vy, wz * vx - wx * vz, wx * vy - wy * vx
    dx, dy, dz = wy * cz - wz * cy, wz * cx - wx * cz, wx * cy - wy * cx
    px, py, pz = vx + a * cx + b * dx, vy + a * cy + b * dy, vz + a * cz + b * dz
    x, y, z, w = q[qi + 3], q[qi + 4], q[qi + 5], q[qi + 6]
    # translation += R(quat) p
    q[qi] += (1.0 - 2.0 * (y * y + z * z)) * px + 2.0 * (x * y - z * w) * py
    q[qi] += 2.0 * (x * z + y * w) * pz
    q[qi + 1] += 2.0 * (x * y + z * w) * px + (1.0 - 2.0 * (x * x + z * z)) * py
    q[qi + 1] += 2.0 * (y * z - x * w) * pz
    q[qi + 2] += 2.0 * (x * z - y * w) * px + 2.0 * (y * z + x * w) * py
    q[qi + 2] += (1.0 - 2.0 * (x * x + y * y)) * pz
    # quat <- quat * (half_sin w, half_cos)
    bx, by, bz, bw = half_sin * wx, half_sin * wy, half_sin * wz, half_cos
    nx = w * bx + x * bw + y * bz - z * by
    ny = w * by - x * bz + y * bw + z * bx
    nz = w * bz + x * by - y * bx + z * bw
    nw = w * bw - x * bx - y * by - z * bz
    norm = np.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
    q[qi + 3], q[qi + 4], q[qi + 5], q[qi + 6] = nx / norm, ny / norm, nz / norm, nw / norm


@kernel
def uniform(state):
    """The next uniform number in [0, 1) of a SplitMix64 stream (state: uint64 (1,))."""
    state[0] += np.uint64(0x9E3779B97F4A7C15)
    z = state[0]
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@kernel
def restart_sample(seed, attempt, qlay, lo, hi, out):
    """The start of restart ``attempt`` under ``seed``: the one restart stream of both back
    ends (a pure function of (seed, attempt), so chunking the attempts changes nothing).

    Scalars uniform in [lo, hi]; a (cos, sin) pair from a uniform angle; a free flyer's
    translation uniform in its box and a uniform unit quaternion (Shoemake); OTHER joints'
    coordinates uniform in their box (normalised by the caller)."""
    state = np.empty(1, np.uint64)
    state[0] = np.uint64(seed) * np.uint64(0xD1B54A32D192ED03) + np.uint64(attempt)
    uniform(state)
    for r in range(qlay.shape[0]):
        kind, qi = qlay[r, 0], qlay[r, 1]
        if kind == CIRCLE:
            angle = np.pi * (2.0 * uniform(state) - 1.0)
            out[qi], out[qi + 1] = np.cos(angle), np.sin(angle)
        elif kind == FREE_FLYER:
            for i in range(3):
                out[qi + i] = lo[qi + i] + (hi[qi + i] - lo[qi + i]) * uniform(state)
            u1, u2, u3 = uniform(state), uniform(state), uniform(state)
            a, b = np.sqrt(1.0 - u1), np.sqrt(u1)
            out[qi + 3], out[qi + 4] = a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2)
            out[qi + 5], out[qi + 6] = b * np.sin(2 * np.pi * u3), b * np.cos(2 * np.pi * u3)
        elif kind == OTHER:
            for i in range(qlay[r, 3]):
                out[qi + i] = lo[qi + i] + (hi[qi + i] - lo[qi + i]) * uniform(state)
        else:
            out[qi] = lo[qi] + (hi[qi] - lo[qi]) * uniform(state)
