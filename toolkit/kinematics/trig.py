"""A sine and cosine at once for the compiled kernels (:func:`sincos`): within a unit in the
last place of the C library's (two near |x| = 1e5), 2-3x faster one at a time, and a plain
loop of it vectorizes (:func:`toolkit.kinematics.poses.chain_poses`)."""

from __future__ import annotations

import math

from ..common import inline_kernel

__all__ = ["REDUCED", "sincos", "sincos_reduced"]

_PIO2 = (1.5707963267341256, 6.077100506303966e-11, 2.0222662487959506e-21)
"""pi / 2 as three doubles (the first two of 33 significant bits, so k times them is exact
for |k| < 2^20): x - k pi / 2 to about 1e-21 for |x| < :data:`REDUCED`."""
REDUCED = 1e5
"""[rad] The largest |x| :func:`sincos` reduces itself (beyond: the C library's sin, cos)."""
_S = tuple((-1) ** k / math.factorial(2 * k + 1) for k in range(1, 9))
_C = tuple((-1) ** k / math.factorial(2 * k) for k in range(1, 9))
# Taylor's coefficients to x^17 and x^16: on |r| <= pi / 4 the first term left out is below
# 3e-18 of the result


@inline_kernel
def sincos(x):
    """(sin x, cos x) within one unit in the last place of the C library's for |x| < 50, two
    up to :data:`REDUCED` (tests/kinematics/test_trig.py), 2-3x faster: both from one reduction
    to r = x - k pi / 2, |r| <= pi / 4, and Taylor polynomials in r; the C library's beyond
    |x| = :data:`REDUCED` (NaN and infinities: NaN)."""
    if not abs(x) < REDUCED:
        return math.sin(x), math.cos(x)
    return sincos_reduced(x)


@inline_kernel
def sincos_reduced(x):
    """:func:`sincos` of |x| < :data:`REDUCED`, without a branch: a plain loop of it
    vectorizes (:func:`toolkit.kinematics.poses.chain_poses`)."""
    k = math.floor(x * (2.0 / math.pi) + 0.5)
    r = ((x - k * _PIO2[0]) - k * _PIO2[1]) - k * _PIO2[2]
    z = r * r
    s3, s5, s7, s9, s11, s13, s15, s17 = _S
    c2, c4, c6, c8, c10, c12, c14, c16 = _C
    s = s13 + z * (s15 + z * s17)
    s = r + r * z * (s3 + z * (s5 + z * (s7 + z * (s9 + z * (s11 + z * s)))))
    c = c12 + z * (c14 + z * c16)
    c = 1.0 + z * (c2 + z * (c4 + z * (c6 + z * (c8 + z * (c10 + z * c)))))
    quarter = int(k)  # which quarter turn: (s, c), (c, -s), (-s, -c), (-c, s), by selects
    odd = (quarter & 1) != 0
    a = c if odd else s
    b = s if odd else c
    a = -a if (quarter & 2) != 0 else a
    b = -b if ((quarter + 1) & 2) != 0 else b
    return a, b
