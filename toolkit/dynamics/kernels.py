"""Compiled inverse dynamics (numba): the recursive Newton-Euler algorithm on the chain
engine's packed tree (:mod:`toolkit.kinematics.kernels`), in world coordinates, for trees
of revolute, prismatic and continuous joints, many configurations at once.

Per joint k (tree order, parents first) with world rotation R, origin o, world axis z
after the joint's motion (the kinematics' ``frames``), velocity v = s qd[i] and
acceleration a = s qdd[i] (s its multiplier, 1 here):

* forward: angular velocity w = w_p + z v and acceleration dw = dw_p + z a + w_p x z v
  (a revolute joint; a prismatic one keeps its parent's), the origin's linear
  acceleration acc = acc_p + dw_p x r + w_p x (w_p x r) with r = o - o_p (plus z a +
  2 w_p x z v for a prismatic joint), from the base's acc = -gravity;
* per body (mass m, centre of mass c = R lever from o, inertia I about c in the joint's
  axes): the force f = m (acc + dw x c + w x (w x c)) and the moment about o,
  n = R (I R^T dw + R^T w x I R^T w) + c x f;
* backward (children first): each body's f and n added to its parent's (n moved by
  r x f), and the joint torque tau[i] = s z . n (revolute) or s z . f (prismatic), plus
  the armature's share armature[i] * qdd[i], as Pinocchio's ``rnea``.

Pinocchio is the reference: ``tests/dynamics/test_dynamics.py`` compares them on every kind of arm.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..kinematics import inline_kernel, joints, kernel, kernels, twin_kernel

__all__ = ["crba_batch", "rnea_batch"]

_CHUNK = 256  # rows per work item of a parallel batch: one set of buffers each
PRISMATIC = joints.PRISMATIC  # the joint codes of the packed tree (revolute and circle turn)


@inline_kernel
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@inline_kernel
def _forward(k, par, W, ints, flts, v, a, S):
    """Joint k's angular velocity S[k, 0:3], angular acceleration S[k, 3:6] and origin
    acceleration S[k, 6:9] from its parent's (row ``par``)."""
    zx, zy, zz = W[k, 12], W[k, 13], W[k, 14]
    wx, wy, wz = S[par, 0], S[par, 1], S[par, 2]
    dx, dy, dz = S[par, 3], S[par, 4], S[par, 5]
    rx, ry, rz = W[k, 9] - W[par, 9], W[k, 10] - W[par, 10], W[k, 11] - W[par, 11]
    ex, ey, ez = _cross(wx, wy, wz, rx, ry, rz)
    fx, fy, fz = _cross(wx, wy, wz, ex, ey, ez)
    gx, gy, gz = _cross(dx, dy, dz, rx, ry, rz)
    ax, ay, az = S[par, 6] + gx + fx, S[par, 7] + gy + fy, S[par, 8] + gz + fz
    cx, cy, cz = _cross(wx, wy, wz, zx * v, zy * v, zz * v)  # w_p x z v
    if ints[k, 1] == PRISMATIC:
        S[k, 0], S[k, 1], S[k, 2] = wx, wy, wz
        S[k, 3], S[k, 4], S[k, 5] = dx, dy, dz
        S[k, 6] = ax + zx * a + 2.0 * cx
        S[k, 7] = ay + zy * a + 2.0 * cy
        S[k, 8] = az + zz * a + 2.0 * cz
    else:
        S[k, 0], S[k, 1], S[k, 2] = wx + zx * v, wy + zy * v, wz + zz * v
        S[k, 3], S[k, 4], S[k, 5] = dx + zx * a + cx, dy + zy * a + cy, dz + zz * a + cz
        S[k, 6], S[k, 7], S[k, 8] = ax, ay, az


@inline_kernel
def _body(k, W, body, S, F):
    """Body k's force F[k, 0:3] and moment about its joint's origin F[k, 3:6]."""
    m = body[k, 0]
    cx = W[k, 0] * body[k, 1] + W[k, 1] * body[k, 2] + W[k, 2] * body[k, 3]
    cy = W[k, 3] * body[k, 1] + W[k, 4] * body[k, 2] + W[k, 5] * body[k, 3]
    cz = W[k, 6] * body[k, 1] + W[k, 7] * body[k, 2] + W[k, 8] * body[k, 3]
    wx, wy, wz = S[k, 0], S[k, 1], S[k, 2]
    dx, dy, dz = S[k, 3], S[k, 4], S[k, 5]
    ex, ey, ez = _cross(wx, wy, wz, cx, cy, cz)
    fx, fy, fz = _cross(wx, wy, wz, ex, ey, ez)
    gx, gy, gz = _cross(dx, dy, dz, cx, cy, cz)
    Fx, Fy, Fz = m * (S[k, 6] + gx + fx), m * (S[k, 7] + gy + fy), m * (S[k, 8] + gz + fz)
    # in the joint's axes: w_l = R^T w, dw_l = R^T dw; N_l = I dw_l + w_l x I w_l
    lwx = W[k, 0] * wx + W[k, 3] * wy + W[k, 6] * wz
    lwy = W[k, 1] * wx + W[k, 4] * wy + W[k, 7] * wz
    lwz = W[k, 2] * wx + W[k, 5] * wy + W[k, 8] * wz
    ldx = W[k, 0] * dx + W[k, 3] * dy + W[k, 6] * dz
    ldy = W[k, 1] * dx + W[k, 4] * dy + W[k, 7] * dz
    ldz = W[k, 2] * dx + W[k, 5] * dy + W[k, 8] * dz
    iwx = body[k, 4] * lwx + body[k, 5] * lwy + body[k, 6] * lwz
    iwy = body[k, 7] * lwx + body[k, 8] * lwy + body[k, 9] * lwz
    iwz = body[k, 10] * lwx + body[k, 11] * lwy + body[k, 12] * lwz
    qx, qy, qz = _cross(lwx, lwy, lwz, iwx, iwy, iwz)
    nx = body[k, 4] * ldx + body[k, 5] * ldy + body[k, 6] * ldz + qx
    ny = body[k, 7] * ldx + body[k, 8] * ldy + body[k, 9] * ldz + qy
    nz = body[k, 10] * ldx + body[k, 11] * ldy + body[k, 12] * ldz + qz
    mx, my, mz = _cross(cx, cy, cz, Fx, Fy, Fz)
    F[k, 0], F[k, 1], F[k, 2] = Fx, Fy, Fz
    F[k, 3] = W[k, 0] * nx + W[k, 1] * ny + W[k, 2] * nz + mx
    F[k, 4] = W[k, 3] * nx + W[k, 4] * ny + W[k, 5] * nz + my
    F[k, 5] = W[k, 6] * nx + W[k, 7] * ny + W[k, 8] * nz + mz


@inline_kernel
def rnea_row(q, qd, qdd, ints, flts, body, gravity, armature, W, S, F, tau):
    """tau (nv) = M(q) qdd + C(q, qd) qd + g(q) of one configuration, on buffers W
    (n + 1, 15), S (n + 1, 9) and F (n + 1, 6)."""
    n = ints.shape[0]
    kernels.frames(q, ints, flts, W)
    S[n, :] = 0.0
    S[n, 6], S[n, 7], S[n, 8] = -gravity[0], -gravity[1], -gravity[2]
    for k in range(n):
        vi, s = ints[k, 3], flts[k, 15]
        _forward(k, ints[k, 0], W, ints, flts, s * qd[vi], s * qdd[vi], S)
        _body(k, W, body, S, F)
    for i in range(tau.shape[0]):
        tau[i] = armature[i] * qdd[i]
    for k in range(n - 1, -1, -1):
        zx, zy, zz = W[k, 12], W[k, 13], W[k, 14]
        off = 0 if ints[k, 1] == PRISMATIC else 3
        tau[ints[k, 3]] += flts[k, 15] * (zx * F[k, off] + zy * F[k, off + 1] + zz * F[k, off + 2])
        par = ints[k, 0]
        if par < n:
            rx, ry, rz = W[k, 9] - W[par, 9], W[k, 10] - W[par, 10], W[k, 11] - W[par, 11]
            mx, my, mz = _cross(rx, ry, rz, F[k, 0], F[k, 1], F[k, 2])
            for c in range(3):
                F[par, c] += F[k, c]
            F[par, 3] += F[k, 3] + mx
            F[par, 4] += F[k, 4] + my
            F[par, 5] += F[k, 5] + mz


@kernel
def _rnea_rows(Q, V, A, ints, flts, body, gravity, armature, out, start, stop):
    n = ints.shape[0]
    W = np.empty((n + 1, 15))
    S = np.empty((n + 1, 9))
    F = np.empty((n + 1, 6))
    for i in range(start, stop):
        rnea_row(Q[i], V[i], A[i], ints, flts, body, gravity, armature, W, S, F, out[i])


@twin_kernel
def rnea_batch(Q, V, A, ints, flts, body, gravity, armature):
    """Joint torques (N, nv) of configurations Q (N, nq), velocities V and accelerations
    A (N, nv): Pinocchio's ``rnea`` row by row. ``body`` (n, 13): per joint of the tree
    the mass, the centre of mass in the joint's frame (3) and the inertia about it in the
    joint's axes (9, row-major)."""
    N = Q.shape[0]
    out = np.empty((N, V.shape[1]))
    for c in prange((N + _CHUNK - 1) // _CHUNK):
        _rnea_rows(Q, V, A, ints, flts, body, gravity, armature, out, c * _CHUNK,
                   min(N, (c + 1) * _CHUNK))  # fmt: skip
    return out


@inline_kernel
def _about_origin(k, W, body, C):
    """Body k's mass, first moment m c and inertia about the world's origin (world axes)
    into C[k]: R I R^T + m (|c|^2 E - c c^T)."""
    m = body[k, 0]
    cx = W[k, 9] + W[k, 0] * body[k, 1] + W[k, 1] * body[k, 2] + W[k, 2] * body[k, 3]
    cy = W[k, 10] + W[k, 3] * body[k, 1] + W[k, 4] * body[k, 2] + W[k, 5] * body[k, 3]
    cz = W[k, 11] + W[k, 6] * body[k, 1] + W[k, 7] * body[k, 2] + W[k, 8] * body[k, 3]
    C[k, 0] = m
    C[k, 1], C[k, 2], C[k, 3] = m * cx, m * cy, m * cz
    cc = cx * cx + cy * cy + cz * cz
    c3 = (cx, cy, cz)
    for a in range(3):  # T = I R^T (into C[k, 4:13] for a moment)
        for s in range(3):
            C[k, 4 + 3 * a + s] = (body[k, 4 + 3 * a] * W[k, 3 * s]
                                   + body[k, 5 + 3 * a] * W[k, 3 * s + 1]
                                   + body[k, 6 + 3 * a] * W[k, 3 * s + 2])  # fmt: skip
    for s in range(3):  # R T + m (|c|^2 E - c c^T), a column at a time
        t0, t1, t2 = C[k, 4 + s], C[k, 7 + s], C[k, 10 + s]
        for r in range(3):
            acc = W[k, 3 * r] * t0 + W[k, 3 * r + 1] * t1 + W[k, 3 * r + 2] * t2
            acc -= m * c3[r] * c3[s]
            if r == s:
                acc += m * cc
            C[k, 4 + 3 * r + s] = acc


@inline_kernel
def crba_row(q, ints, flts, body, armature, W, C, out):
    """M(q) (nv, nv) of one configuration into ``out``, on buffers W (n + 1, 15) and C
    (n + 1, 19): the composite rigid body algorithm in world coordinates about the world's
    origin, where inertias add as they are. Per subtree C holds the mass, its first moment
    h = sum m c (3) and its inertia about the origin (9), then its joint's motion about the
    origin (a, l) (6): (z, o x z) turning (z its world axis through o), (0, z) sliding; the
    subtree's momentum under it, L = I a + h x l, p = m l + a x h; M[i, j] for j on the
    path to the root is joint j's motion . (L, p)."""
    n = ints.shape[0]
    kernels.frames(q, ints, flts, W)
    C[:, :] = 0.0
    for k in range(n):  # each body about the origin, in world axes
        _about_origin(k, W, body, C)
    for k in range(n - 1, -1, -1):  # composites: children into their parents
        par = ints[k, 0]
        if par < n:
            for c in range(13):
                C[par, c] += C[k, c]
    for k in range(n):  # each joint's motion about the origin: (a, l) in C[k, 13:19]
        zx, zy, zz = W[k, 12], W[k, 13], W[k, 14]
        if ints[k, 1] == PRISMATIC:
            C[k, 13], C[k, 14], C[k, 15], C[k, 16], C[k, 17], C[k, 18] = 0.0, 0.0, 0.0, zx, zy, zz
        else:
            vx, vy, vz = _cross(W[k, 9], W[k, 10], W[k, 11], zx, zy, zz)
            C[k, 13], C[k, 14], C[k, 15], C[k, 16], C[k, 17], C[k, 18] = zx, zy, zz, vx, vy, vz
    out[:, :] = 0.0
    for k in range(n):
        ax, ay, az, lx, ly, lz = C[k, 13], C[k, 14], C[k, 15], C[k, 16], C[k, 17], C[k, 18]
        m, hx, hy, hz = C[k, 0], C[k, 1], C[k, 2], C[k, 3]
        ex, ey, ez = _cross(hx, hy, hz, lx, ly, lz)  # L = I a + h x l, p = m l + a x h
        Lx = C[k, 4] * ax + C[k, 5] * ay + C[k, 6] * az + ex
        Ly = C[k, 7] * ax + C[k, 8] * ay + C[k, 9] * az + ey
        Lz = C[k, 10] * ax + C[k, 11] * ay + C[k, 12] * az + ez
        gx, gy, gz = _cross(ax, ay, az, hx, hy, hz)
        px, py, pz = m * lx + gx, m * ly + gy, m * lz + gz
        i, j = ints[k, 3], k
        while j < n:  # k itself, then every joint on its path to the root
            value = (C[j, 13] * Lx + C[j, 14] * Ly + C[j, 15] * Lz
                     + C[j, 16] * px + C[j, 17] * py + C[j, 18] * pz)  # fmt: skip
            out[i, ints[j, 3]] = value
            out[ints[j, 3], i] = value
            j = ints[j, 0]
        out[i, i] += armature[i]


@kernel
def _crba_rows(Q, ints, flts, body, armature, out, start, stop):
    n = ints.shape[0]
    W = np.empty((n + 1, 15))
    C = np.empty((n + 1, 19))
    for i in range(start, stop):
        crba_row(Q[i], ints, flts, body, armature, W, C, out[i])


@twin_kernel
def crba_batch(Q, ints, flts, body, armature, nv):
    """The mass matrices (N, nv, nv) of configurations Q (N, nq): Pinocchio's ``crba``
    (made symmetric) row by row; ``body`` as for :func:`rnea_batch`."""
    N = Q.shape[0]
    out = np.empty((N, nv, nv))
    for c in prange((N + _CHUNK - 1) // _CHUNK):
        _crba_rows(Q, ints, flts, body, armature, out, c * _CHUNK, min(N, (c + 1) * _CHUNK))
    return out
