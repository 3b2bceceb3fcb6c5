"""Every branch of a 3-joint chain with prismatic joints placing a point (the industrial
positioning structures: Cartesian, cylindrical, spherical, SCARA).

In the product-of-exponentials form of :mod:`toolkit.ik.analytic.families`, a prismatic joint i
moves everything after it by ``q_i h_i`` (``h_i`` its axis at zero, turned by the joints
before it); ``p0`` is the frame's origin at zero, ``p`` the target:

* **PPP**: ``p = p0 + q1 h1 + q2 h2 + q3 h3``, one linear solve (1 branch);
* **RPP**: ``p - o1 = R(h1, q1) (p0 - o1 + q2 h2 + q3 h3)``: the height along h1 is linear
  in (q2, q3) and the distance from o1 quadratic, so one slide follows from the other and
  the other from a quadratic (2 roots: the arm on either side), then q1 by SP1;
* **RRP, axes 1, 2 meeting** at S: ``|p - S| = |p0 - S + q3 h3|`` gives q3 (a quadratic,
  2 roots: the slide extended either way), then (q1, q2) by SP2 (up to 4 branches);
* **RRP, axes 1, 2 parallel**: the height along h1 gives q3 (linear), then q2 by SP3 and q1
  by SP1 in the plane (2 branches: the elbow either side).
"""

from __future__ import annotations

import math

import numpy as np

from .structure import Chain
from .subproblems import EXACT, rot, sp1, sp2, sp3

__all__ = ["ppp", "rpp", "rrp_meeting", "rrp_parallel"]

Branch = tuple[np.ndarray, str]


def _sign(k: int, count: int) -> str:
    return "" if count == 1 else ("+" if k == 0 else "-")


def _quadratic(a: float, b: float, c: float) -> list[float]:
    """The real roots of a x^2 + 2 b x + c = 0 (a > 0); one at a tangent, none beyond."""
    disc = b * b - a * c
    scale = max(b * b, abs(a * c), 1e-30)
    if disc < -1e-12 * scale:
        return []
    if disc <= 1e-12 * scale:
        return [-b / a]
    r = math.sqrt(disc)
    return [(-b + r) / a, (-b - r) / a]


def ppp(chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)) -> list[Branch]:
    """The one branch of three slides (module doc)."""
    q = np.linalg.solve(chain.axes.T, T[:3, 3] - chain.tip[:3, 3])
    return [(q, "")]


def rpp(chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)) -> list[Branch]:
    """The branches of a turn and two slides (module doc): the slide that moves the height
    along h1 most follows from the height, the other from the distance."""
    h, c = chain.axes, chain.tip[:3, 3] - o[0]
    u = T[:3, 3] - o[0]
    a = np.array([float(h[0] @ h[1]), float(h[0] @ h[2])])
    first = int(np.argmax(np.abs(a)))  # solved from the height: slide 2 or 3
    other = 1 - first
    hf, ho = h[1 + first], h[1 + other]
    # slide f = (height - a_o x) / a_f with x the other slide: w(x) = w0 + x d
    w0 = c + hf * float(h[0] @ u - h[0] @ c) / a[first]
    d = ho - hf * a[other] / a[first]
    out: list[Branch] = []
    roots = _quadratic(float(d @ d), float(w0 @ d), float(w0 @ w0 - u @ u))
    for k, x in enumerate(roots):
        sf = float(h[0] @ u - h[0] @ c - a[other] * x) / a[first]
        q1, f1 = sp1(c + sf * hf + x * ho, u, h[0])
        if f1 in ok:
            q = np.array([q1, 0.0, 0.0])
            q[1 + first], q[1 + other] = sf, x
            out.append((q, f"side {_sign(k, len(roots))}"))
    return out


def rrp_meeting(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """The branches of two turns about axes meeting at S (o1 = o2 = S) and a slide."""
    h, S = chain.axes, o[0]
    c, y = chain.tip[:3, 3] - S, T[:3, 3] - S
    out: list[Branch] = []
    roots = _quadratic(1.0, float(c @ h[2]), float(c @ c - y @ y))
    for k, q3 in enumerate(roots):
        pairs, f12 = sp2(c + q3 * h[2], y, h[1], h[0])  # R(h2, q2) x = R(h1, -q1) y
        if f12 in ok:
            out += [(np.array([-t1, q2, q3]), f"extension {_sign(k, len(roots))}, shoulder "
                     f"{_sign(i, len(pairs))}") for i, (q2, t1) in enumerate(pairs)]  # fmt: skip
    return out


def rrp_parallel(
    chain: Chain, o: np.ndarray, T: np.ndarray, ok: tuple[str, ...] = (EXACT,)
) -> list[Branch]:
    """The branches of two turns about parallel axes and a slide (SCARA)."""
    h, p0 = chain.axes, chain.tip[:3, 3]
    u, p12 = T[:3, 3] - o[0], o[1] - o[0]
    q3 = float(h[0] @ (T[:3, 3] - p0)) / float(h[0] @ h[2])
    x = p0 - o[1] + q3 * h[2]
    q2s, f2 = sp3(x, -p12, h[1], float(np.linalg.norm(u)))
    if f2 not in ok:
        return []
    out: list[Branch] = []
    for k, q2 in enumerate(q2s):
        q1, f1 = sp1(p12 + rot(h[1], q2) @ x, u, h[0])
        if f1 in ok:
            out.append((np.array([q1, q2, q3]), f"elbow {_sign(k, len(q2s))}"))
    return out
