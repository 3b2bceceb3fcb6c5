"""The tip's pose alone, for verifications: of one configuration in a running frame
(:func:`chain_pose`), and of many at once with each stage a plain loop over them, which
vectorizes (:func:`chain_poses`). Both take :mod:`toolkit.kinematics.kernels`' packed chain
and give its :func:`~toolkit.kinematics.kernels.frames` and
:func:`~toolkit.kinematics.kernels.tip`'s products in their order (equal to the last bit:
``tests/kinematics/test_poses.py``)."""

from __future__ import annotations

from ..common import inline_kernel, kernel
from . import kernels
from .joints import CIRCLE, PRISMATIC, REVOLUTE
from .trig import REDUCED, sincos, sincos_reduced

__all__ = ["chain_pose", "chain_poses", "serial"]


@inline_kernel
def serial(ints):
    """Whether the chain is serial (each joint's parent the joint before it, the first's the
    base) of revolute, continuous and prismatic joints: what :func:`chain_pose` follows
    without ``W``."""
    n = ints.shape[0]
    for k in range(n):
        kind = ints[k, 1]
        if ints[k, 0] != (k - 1 if k > 0 else n) or not (
                kind == REVOLUTE or kind == CIRCLE or kind == PRISMATIC):  # fmt: skip
            return False
    return True


@kernel
def chain_pose(q, ints, flts, tip_pl, W, H):  # long: one running frame, in registers
    """The tip's pose H (4, 4) at configuration q: :func:`frames` then :func:`tip`, the
    same products in the same order, kept in one running frame on a :func:`serial` chain
    (no joint's world frame or axis kept: what a verification needs); through ``W``
    otherwise."""
    n = ints.shape[0]
    if not serial(ints):
        kernels.frames(q, ints, flts, W)
        kernels.tip(W, tip_pl, H[:3, :3], H[:3, 3])
        H[3, 0], H[3, 1], H[3, 2], H[3, 3] = 0.0, 0.0, 0.0, 1.0
        return
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
    p0, p1, p2 = 0.0, 0.0, 0.0
    for k in range(n + 1):
        f = flts[k] if k < n else tip_pl  # the joint's placement, then the tip's
        p0 = ((p0 + r00 * f[9]) + r01 * f[10]) + r02 * f[11]  # the frames' order of sums
        p1 = ((p1 + r10 * f[9]) + r11 * f[10]) + r12 * f[11]
        p2 = ((p2 + r20 * f[9]) + r21 * f[10]) + r22 * f[11]
        if k == n or ints[k, 5] == 0:
            r00, r01, r02 = (r00 * f[0] + r01 * f[3] + r02 * f[6], r00 * f[1] + r01 * f[4]
                             + r02 * f[7], r00 * f[2] + r01 * f[5] + r02 * f[8])  # fmt: skip
            r10, r11, r12 = (r10 * f[0] + r11 * f[3] + r12 * f[6], r10 * f[1] + r11 * f[4]
                             + r12 * f[7], r10 * f[2] + r11 * f[5] + r12 * f[8])  # fmt: skip
            r20, r21, r22 = (r20 * f[0] + r21 * f[3] + r22 * f[6], r20 * f[1] + r21 * f[4]
                             + r22 * f[7], r20 * f[2] + r21 * f[5] + r22 * f[8])  # fmt: skip
        if k == n:
            break
        kind, qi, a = ints[k, 1], ints[k, 2], ints[k, 4]
        x, y, z = f[12], f[13], f[14]
        if kind == PRISMATIC:
            v = f[15] * q[qi] + f[16]
            p0 += (r00 * x + r01 * y + r02 * z) * v
            p1 += (r10 * x + r11 * y + r12 * z) * v
            p2 += (r20 * x + r21 * y + r22 * z) * v
            continue
        if kind == REVOLUTE:
            s, c = sincos(f[15] * q[qi] + f[16])
        else:  # (cos, sin) as stored
            c, s = q[qi], q[qi + 1]
        if a < 0:  # Rodrigues' formula, as kernels._rotate
            t = 1.0 - c
            m00, m01, m02 = c + t * x * x, t * x * y - s * z, t * x * z + s * y
            m10, m11, m12 = t * x * y + s * z, c + t * y * y, t * y * z - s * x
            m20, m21, m22 = t * x * z - s * y, t * y * z + s * x, c + t * z * z
            r00, r01, r02 = (r00 * m00 + r01 * m10 + r02 * m20, r00 * m01 + r01 * m11
                             + r02 * m21, r00 * m02 + r01 * m12 + r02 * m22)  # fmt: skip
            r10, r11, r12 = (r10 * m00 + r11 * m10 + r12 * m20, r10 * m01 + r11 * m11
                             + r12 * m21, r10 * m02 + r11 * m12 + r12 * m22)  # fmt: skip
            r20, r21, r22 = (r20 * m00 + r21 * m10 + r22 * m20, r20 * m01 + r21 * m11
                             + r22 * m21, r20 * m02 + r21 * m12 + r22 * m22)  # fmt: skip
            continue
        s *= f[12 + a]  # about +-x, +-y or +-z: two columns turn, as kernels._turn
        if a == 2:  # columns 0, 1
            r00, r01 = c * r00 + s * r01, c * r01 - s * r00
            r10, r11 = c * r10 + s * r11, c * r11 - s * r10
            r20, r21 = c * r20 + s * r21, c * r21 - s * r20
        elif a == 1:  # columns 2, 0
            r02, r00 = c * r02 + s * r00, c * r00 - s * r02
            r12, r10 = c * r12 + s * r10, c * r10 - s * r12
            r22, r20 = c * r22 + s * r20, c * r20 - s * r22
        else:  # columns 1, 2
            r01, r02 = c * r01 + s * r02, c * r02 - s * r01
            r11, r12 = c * r11 + s * r12, c * r12 - s * r11
            r21, r22 = c * r21 + s * r22, c * r22 - s * r21
    H[0, 0], H[0, 1], H[0, 2], H[0, 3] = r00, r01, r02, p0
    H[1, 0], H[1, 1], H[1, 2], H[1, 3] = r10, r11, r12, p1
    H[2, 0], H[2, 1], H[2, 2], H[2, 3] = r20, r21, r22, p2
    H[3, 0], H[3, 1], H[3, 2], H[3, 3] = 0.0, 0.0, 0.0, 1.0


@inline_kernel
def chain_poses(Q, count, ints, flts, tip_pl, X, S):
    """The tip's pose at each of the first ``count`` rows of Q (B, nq) into X (12, B) (per
    column its rotation row-major (9), then its position (3)): :func:`chain_pose`'s products
    in its order, each stage a plain loop over the rows (vectorized); S (2, B) is scratch.
    The chain must be :func:`serial` (the caller checks; :func:`chain_pose` row by row
    otherwise)."""
    n = ints.shape[0]
    for b in range(count):
        X[0, b], X[1, b], X[2, b] = 1.0, 0.0, 0.0
        X[3, b], X[4, b], X[5, b] = 0.0, 1.0, 0.0
        X[6, b], X[7, b], X[8, b] = 0.0, 0.0, 1.0
        X[9, b], X[10, b], X[11, b] = 0.0, 0.0, 0.0
    for k in range(n):
        f = flts[k]
        kind, qi, a = ints[k, 1], ints[k, 2], ints[k, 4]
        _placed_rows(X, count, f, ints[k, 5] != 0)
        if kind == PRISMATIC:
            x, y, z, scale, offset = f[12], f[13], f[14], f[15], f[16]
            for b in range(count):
                v = scale * Q[b, qi] + offset
                X[9, b] += (X[0, b] * x + X[1, b] * y + X[2, b] * z) * v
                X[10, b] += (X[3, b] * x + X[4, b] * y + X[5, b] * z) * v
                X[11, b] += (X[6, b] * x + X[7, b] * y + X[8, b] * z) * v
            continue
        if kind == REVOLUTE:
            _sines(Q, count, qi, f[15], f[16], S)
        else:  # (cos, sin) as stored
            for b in range(count):
                S[0, b], S[1, b] = Q[b, qi + 1], Q[b, qi]
        if a < 0:
            _rodrigues_rows(X, count, f[12], f[13], f[14], S)
        else:
            _turn_rows(X, count, (a + 1) % 3, (a + 2) % 3, f[12 + a], S)
    _placed_rows(X, count, tip_pl, False)


@inline_kernel
def _sines(Q, count, qi, scale, offset, S):
    """(sin, cos) of each row's joint value scale * Q[b, qi] + offset into S (2, B)."""
    big = 0.0
    for b in range(count):
        v = scale * Q[b, qi] + offset
        S[0, b] = v
        big = max(big, abs(v))
    if big < REDUCED:  # (NaN fails too) every one vectorized
        for b in range(count):
            S[0, b], S[1, b] = sincos_reduced(S[0, b])
    else:
        for b in range(count):
            S[0, b], S[1, b] = sincos(S[0, b])


@inline_kernel
def _placed_rows(X, count, f, bare):
    """Each column of X times a placement ``f`` (as :func:`chain_pose`'s)."""
    t0, t1, t2 = f[9], f[10], f[11]
    for b in range(count):
        X[9, b] = ((X[9, b] + X[0, b] * t0) + X[1, b] * t1) + X[2, b] * t2
        X[10, b] = ((X[10, b] + X[3, b] * t0) + X[4, b] * t1) + X[5, b] * t2
        X[11, b] = ((X[11, b] + X[6, b] * t0) + X[7, b] * t1) + X[8, b] * t2
    if bare:
        return
    f0, f1, f2, f3, f4, f5, f6, f7, f8 = f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8]
    for i in range(3):
        for b in range(count):
            x0, x1, x2 = X[3 * i, b], X[3 * i + 1, b], X[3 * i + 2, b]
            X[3 * i, b] = x0 * f0 + x1 * f3 + x2 * f6
            X[3 * i + 1, b] = x0 * f1 + x1 * f4 + x2 * f7
            X[3 * i + 2, b] = x0 * f2 + x1 * f5 + x2 * f8


@inline_kernel
def _turn_rows(X, count, u, v, sign, S):
    """Each column's rotation turned about its axis e_u x e_v (``sign``: +-), by S's
    (sin, cos) (as kernels._turn)."""
    for i in range(3):
        for b in range(count):
            c, s = S[1, b], S[0, b] * sign
            ra, rb = X[3 * i + u, b], X[3 * i + v, b]
            X[3 * i + u, b] = c * ra + s * rb
            X[3 * i + v, b] = c * rb - s * ra


@inline_kernel
def _rodrigues_rows(X, count, x, y, z, S):
    """Each column's rotation times Rot(axis (x, y, z)) by S's (sin, cos) (as
    kernels._rotate)."""
    for i in range(3):
        for b in range(count):
            s, c = S[0, b], S[1, b]
            t = 1.0 - c
            a0, a1, a2 = X[3 * i, b], X[3 * i + 1, b], X[3 * i + 2, b]
            X[3 * i, b] = a0 * (c + t * x * x) + a1 * (t * x * y + s * z) + a2 * (t * x * z - s * y)
            X[3 * i + 1, b] = (a0 * (t * x * y - s * z) + a1 * (c + t * y * y)
                               + a2 * (t * y * z + s * x))  # fmt: skip
            X[3 * i + 2, b] = (a0 * (t * x * z + s * y) + a1 * (t * y * z - s * x)
                               + a2 * (c + t * z * z))  # fmt: skip
