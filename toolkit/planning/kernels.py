"""RRT-Connect and path shortcutting compiled (numba) on a conservative collision test.

The test is the checker's compiled pre-filter read strictly
(:func:`toolkit.collision.bound_kernels.certainly_free`): a configuration passes only when
every checked pair is certainly apart, its boxes or sphere covers (which hold every point
of the shapes' surfaces) apart. A configuration it passes is free on the exact shapes; one
it refuses may be free too (coal would have to say). No coal call is made here, so a
search and its shortcuts run at the speed of the kinematics and the bounds.

The steps are those of :mod:`~toolkit.planning.trees` and :mod:`~toolkit.planning.edges`:
uniform samples within the bounds, extension by at most ``step``, connection of the other
tree, every edge checked at configurations at most ``resolution`` apart (its end, every
:data:`~toolkit.planning.edges.RAKE`-th, then the rest). The random numbers are
splitmix64's (Steele, Lea and Flood, 2014), seeded by the caller, so a search is the same
for the same seed on every thread and process (the generator of the numeric IK's restarts,
:func:`toolkit.kinematics.kernels.uniform`).

Arguments shared by the kernels: ``space`` (:class:`~toolkit.planning.records.Space`: what
is free, and how edges are checked), ``work`` (:class:`~toolkit.planning.records.Work`:
scratch and counts) and, for :func:`grow`, ``trees``
(:class:`~toolkit.planning.records.Trees`); the kernels read them by position, Python by
name.
"""

from __future__ import annotations

import math

import numpy as np

from ..collision import bound_kernels, gap_kernels
from ..kinematics import inline_kernel, kernel, kernels
from .edges import RAKE

__all__ = [
    "CLOSEST",
    "FULL",
    "GROWTH",
    "MET",
    "RUNNING",
    "cut_corners",
    "edge",
    "edge_free",
    "edge_swept",
    "free_rows",
    "grow",
    "shortcut",
    "step_ahead",
    "uniform",
]

CLOSEST = 1e-4
"""[m] The least gap :func:`edge_swept` advances from between two shapes that move relative
to each other (closer, the edge is refused: the steps would shrink without end)."""
GROWTH = 1.2
"""How much longer than the last stretch :func:`edge_swept` asks the bounds to carry a pair
at its next configuration. Asking less lets the cheapest bound (the spheres about both
boxes) prove more pairs; the stretches taken are set by the gaps found and stay the same.
On 563 certified edges of the seven MotionBenchMaker scenarios (Panda, ad hoc): twice the
last stretch (the earlier choice) checked 58,642 configurations in 212-217 ms; 1.2 times,
58,674 in 157-167 ms; asking no more than the last stretch, 148,360 (the stretches never
grow)."""
WORTH = 0.003
"""A corner :func:`cut_corners` cuts only where the cut would shorten the path by at least
this share of its length."""
RUNNING, MET, FULL = 0, 1, 2
"""What :func:`grow` returns: its rounds done without a meeting; the trees met (the nodes in
``found``); a tree is full (the caller gives it room and calls again)."""


uniform = kernels.uniform
"""A number in [0, 1) from SplitMix64's state (a (1,) uint64 array, advanced): the stream
the numeric IK's restarts draw from (:func:`toolkit.kinematics.kernels.uniform`)."""


@inline_kernel
def _free(v, space, work):
    """Whether joint values v are certainly free (module doc: every checked pair more than
    the pre-filter's margin apart), counted."""
    qcol, circle, packed, runs = space[0], space[1], space[2], space[6]
    q, W, P, count = work[0], work[1], work[2], work[3]
    _to_q(v, qcol, circle, q)
    count[0] += 1
    return bound_kernels.certainly_free(q, packed, runs, W, P, count[1:], work[6])


@inline_kernel
def _to_q(v, qcol, circle, q):
    """Joint values v into q (a continuous joint's angle as its (cos, sin) pair)."""
    for c in range(v.shape[0]):
        if circle[c]:
            q[qcol[c]], q[qcol[c] + 1] = math.cos(v[c]), math.sin(v[c])
        else:
            q[qcol[c]] = v[c]


@kernel
def pair_rates(a, b, first, second, reach, moves, rate):
    """Into ``rate`` (pairs,): how fast [m per unit of the segment a -> b, joint values] each
    pair's distance can change: over the joints that move one shape and not the other, each
    joint's step times the lesser of the two shapes' distances from its axis (``reach``:
    inf for the shape it does not move unless that one rides the axis).

    Why the lesser: for points p of the moved shape and p' of the other, the joint turns p
    about its axis (through o along w) at w x (p - o) = w x (p - p') + w x (p' - o). The
    first term is square to p - p', so |p - p'| changes at no more than |w x (p' - o)|, the
    distance of p' from the axis; no more than that of p either. The distance of the
    shapes, the least |p - p'|, then closes no faster than the sum over the joints."""
    for k in range(first.shape[0]):
        f, s = first[k], second[k]
        r = 0.0
        for c in range(a.shape[0]):
            if moves[s, c] != moves[f, c]:
                r += abs(b[c] - a[c]) * min(reach[f, c], reach[s, c])
        rate[k] = r


@kernel
def step_ahead(gaps, rate, closest):
    """The stretch [units of the segment] the pairs' ``gaps`` [m] carry a segment on which
    their distances change by at most ``rate`` [m per unit]: the least gap / rate of the
    pairs that move, a hair (1e-9 of it) short; -1 where a pair that moves is within
    ``closest`` or one that does not has no gap; inf where none moves."""
    ahead = np.inf
    for k in range(gaps.shape[0]):
        if rate[k] > 0.0:
            if gaps[k] <= closest:
                return -1.0
            ahead = min(ahead, gaps[k] / rate[k])
        elif gaps[k] <= 0.0:
            return -1.0
    return ahead * (1.0 - 1e-9)


@kernel
def edge_swept(a, b, space, work, x):
    """Whether the whole motion a -> b (a straight line in joint values) is free, by
    conservative advancement: per checked pair, D bounds how fast the distance between its
    two shapes can change over the edge (the joints that move one relative to the other:
    each joint's step times how far the shape's points lie from its axis, ``reach``); at a
    configuration where every pair's distance is at least its gap
    (:func:`~toolkit.collision.gap_kernels.pair_gaps`), no pair closes before the edge
    has gone the least gap / D further, where the next configuration is checked, and so
    on to b; a pair whose last gap still carries it past the stretch asked is not measured
    again there (Baxter's 1,071 pairs: most are far, and were measured at every one). The
    bounds are asked for gaps :data:`GROWTH` times as wide as the last stretch needed (the
    cheap ones mostly prove those). False where the gap of a pair that moves falls below
    :data:`CLOSEST`, or after 100,000 configurations."""
    qcol, circle, packed, reach, moves = space[0], space[1], space[2], space[3], space[4]
    q, W, P, count, until, rate = work[:6]
    first, second = packed[5], packed[6]
    pair_rates(a, b, first, second, reach, moves, rate)
    until[:] = -1.0  # nothing carried yet
    t, aim = 0.0, 0.125  # aim: the stretch asked of the bounds (GROWTH times the last one)
    for _ in range(100_000):
        for c in range(a.shape[0]):
            x[c] = b[c] if t >= 1.0 else a[c] + t * (b[c] - a[c])
        _to_q(x, qcol, circle, q)
        count[0] += 1
        ahead = gap_kernels.pair_gaps(q, packed, W, P, until, rate, t, min(1.0 - t, aim),
                                      CLOSEST)  # fmt: skip
        if ahead < 0.0:
            return False
        if t >= 1.0:
            return True
        t = min(1.0, t + ahead)
        aim = GROWTH * ahead
    return False


@kernel
def cut_corners(path, passes, space, work):
    """``path`` (K, n), every segment of which :func:`edge_swept` passes, with its corners
    cut ``passes`` times (Chaikin's scheme): each inner waypoint replaced by the two points
    half way (else a quarter of the way) to its neighbours where :func:`edge_swept` passes
    the cut between them; a corner whose cut would save less than :data:`WORTH` of the
    path's length is kept untried. The rest of each segment is part of a segment already
    passed, so the path returned passes whole too. Returns it (a new array)."""
    n = path.shape[1]
    P, m = path.copy(), path.shape[0]
    x, a, b = np.empty(n), np.empty(n), np.empty(n)
    whole = 0.0
    for i in range(m - 1):
        whole += _distance(P[i], P[i + 1])
    for _ in range(passes):
        Q = np.empty((2 * m, n))
        Q[0] = P[0]
        k = 1
        for i in range(1, m - 1):
            cut = False
            for share in (0.5, 0.25):
                for c in range(n):
                    a[c] = P[i, c] + share * (Q[k - 1, c] - P[i, c])
                    b[c] = P[i, c] + share * (P[i + 1, c] - P[i, c])
                gain = _distance(a, P[i]) + _distance(P[i], b) - _distance(a, b)
                if gain < WORTH * whole:  # a corner nearly straight: not worth its check
                    break
                if edge_swept(a, b, space, work, x):
                    Q[k], Q[k + 1] = a, b
                    k, cut = k + 2, True
                    break
            if not cut:
                Q[k] = P[i]
                k += 1
        Q[k] = P[m - 1]
        P, m = Q, k + 1
    return P[:m].copy()


@kernel
def free_rows(V, space, work, out):
    """Into ``out`` (N,): whether each row of joint values V (N, n) passes the test."""
    for i in range(V.shape[0]):
        out[i] = _free(V[i], space, work)


@inline_kernel
def _at(a, b, i, k, x):
    """Configuration i of k on a -> b into x (b itself at i = k)."""
    t = i / k
    for c in range(a.shape[0]):
        x[c] = b[c] if i == k else a[c] + t * (b[c] - a[c])


@kernel
def edge(a, b, resolution, space, work, x, known):
    """:func:`edge_free`, then where ``space`` says so (its last item) :func:`edge_swept`."""
    if not edge_free(a, b, resolution, space, work, x, known):
        return False  # most blocked edges end here, at a configuration or two
    return not space[5] or edge_swept(a, b, space, work, x)


@kernel
def edge_free(a, b, resolution, space, work, x, known):
    """Whether every configuration of a -> b at most ``resolution`` apart per joint value
    (``a`` excluded: a tree's node) passes the test: the end (not where it is ``known``
    to: a waypoint of a path), then every RAKE-th, then the rest. ``x``: (n,) scratch."""
    d = 0.0
    for c in range(a.shape[0]):
        d = max(d, abs(b[c] - a[c]))
    k = max(1, math.ceil(d / resolution))
    if not known:
        _at(a, b, k, k, x)
        if not _free(x, space, work):
            return False
    for i in range(RAKE, k, RAKE):
        _at(a, b, i, k, x)
        if not _free(x, space, work):
            return False
    for i in range(1, k):
        if i % RAKE:
            _at(a, b, i, k, x)
            if not _free(x, space, work):
                return False
    return True


@inline_kernel
def _nearest(near, size, x, d):
    """The node nearest x (Euclidean; the first of equals) among the first ``size`` of a
    tree's float32 copy ``near`` (n, cap), in blocks of :data:`BLOCK` nodes joint by joint
    (loops the compiler turns into vector instructions, on a block that stays in the
    fastest cache); ``d`` (BLOCK,) float32 scratch."""
    best, least = 0, np.float32(np.inf)
    n = x.shape[0]
    for start in range(0, size, BLOCK):
        m = min(BLOCK, size - start)
        for i in range(m):
            d[i] = 0.0
        for c in range(n):
            xc = np.float32(x[c])
            row = near[c, start : start + m]
            for i in range(m):
                t = row[i] - xc
                d[i] += t * t
        for i in range(m):
            if d[i] < least:
                best, least = start + i, d[i]
    return best


BLOCK = 256
"""The nodes a nearest-node scan measures at a time (:func:`_nearest`)."""


@inline_kernel
def _distance(a, b):
    """The Euclidean distance between a and b."""
    d = 0.0
    for c in range(a.shape[0]):
        d += (b[c] - a[c]) ** 2
    return math.sqrt(d)


@inline_kernel
def _toward(q, target, step, out):
    """q moved toward ``target`` by at most ``step`` into out; whether it reached it."""
    d = _distance(q, target)
    if d <= step:
        out[:] = target
        return True
    for c in range(q.shape[0]):
        out[c] = q[c] + (target[c] - q[c]) * (step / d)
    return False


@inline_kernel
def _add(trees, sizes, t, x, parent_node):
    """Node x added to tree t under ``parent_node`` (and to its float32 copy); its index."""
    nodes, parent, root, near, radius = trees
    i = sizes[t]
    nodes[t, i] = x
    for c in range(x.shape[0]):
        near[t, c, i] = x[c]
    parent[t, i] = parent_node
    root[t, i] = root[t, parent_node]
    radius[t, i] = np.inf
    sizes[t] = i + 1
    return i


@kernel
def grow(trees, sizes, bounds, steps, space, work, rng, rounds, side, found):  # long: one loop
    """Up to ``rounds`` rounds of RRT-Connect on two trees (tree 0 from the start, tree 1 from the
    goals): a uniform sample within ``bounds`` (lower, upper), tree ``side[0]`` extended toward
    it, the other tree connected to the new node; the sides swap each round, except that a tree
    at most half the other's size is extended again. ``trees``
    (:class:`~toolkit.planning.records.Trees`); ``sizes`` (2,); ``steps`` = (step, resolution,
    domain): the dynamic domain (Yershova et al., ICRA 2005;
    :attr:`~toolkit.planning.settings.PlannerSettings.domain`): a sample farther
    from its nearest node than that node's radius (inf at first) is not tried; a blocked
    extension sets the node's radius to ``domain[0]`` [rad], then shrinks it by the factor 1 -
    ``domain[2]`` down to ``domain[1]``, and a free one grows a finite radius by 1 +
    ``domain[2]``; ``found`` (2,): the meeting nodes of trees 0 and 1. Returns :data:`MET`,
    :data:`FULL` or :data:`RUNNING`."""
    nodes, near, radius = trees[0], trees[3], trees[4]
    cap, n = nodes.shape[1], nodes.shape[2]
    d = np.empty(BLOCK, np.float32)
    lo, hi = bounds
    step, resolution, domain = steps
    sample, new, other, x = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for _ in range(rounds):
        if sizes[0] + 1 >= cap or sizes[1] + 1 >= cap:
            return FULL
        A = side[0]
        if 2 * sizes[1 - A] <= sizes[A]:  # the other tree is at most half this one: again
            A = 1 - A
        B = 1 - A
        side[0] = B
        for c in range(n):
            sample[c] = lo[c] + uniform(rng) * (hi[c] - lo[c])
        i = _nearest(near[A], sizes[A], sample, d)
        r = radius[A, i]
        if r < np.inf and _distance(nodes[A, i], sample) > r:
            continue
        _toward(nodes[A, i], sample, step, new)
        if not edge(nodes[A, i], new, resolution, space, work, x, False):
            radius[A, i] = domain[0] if r == np.inf else max(r * (1.0 - domain[2]), domain[1])
            continue
        if r < np.inf:
            radius[A, i] = r * (1.0 + domain[2])
        j = _add(trees, sizes, A, new, i)
        k = _nearest(near[B], sizes[B], new, d)
        while sizes[B] + 1 < cap:
            reached = _toward(nodes[B, k], new, step, other)
            if not edge(nodes[B, k], other, resolution, space, work, x, False):
                break
            k = _add(trees, sizes, B, other, k)
            if reached:
                found[A], found[B] = j, k
                return MET
    return RUNNING


@kernel
def shortcut(path, tries, resolution, space, work, rng):
    """``path`` (K, n) shortened by straight cuts that pass the test (the steps of
    :func:`toolkit.planning.edges.shortcut`): from each waypoint kept, from the start on,
    a cut to the farthest waypoint it sees (the farthest tried first), then ``tries`` cuts
    between random waypoints two or more apart. The waypoints are free: a cut's end is not
    checked again. Returns the shorter path (a new array)."""
    P = path.copy()
    m, n = P.shape[0], P.shape[1]
    x = np.empty(n)
    i = 0
    while i < m - 2:  # from each kept waypoint, the farthest one it sees
        j = m - 1
        while j > i + 1:
            if edge(P[i], P[j], resolution, space, work, x, True):
                cut = j - i - 1
                P[i + 1 : m - cut] = P[j:m].copy()
                m -= cut
                break
            j -= 1
        i += 1
    for _ in range(tries):
        if m < 3:
            break
        i = min(m - 1, int(uniform(rng) * m))
        j = min(m - 1, int(uniform(rng) * m))
        i, j = min(i, j), max(i, j)
        if j - i < 2:
            continue
        if edge(P[i], P[j], resolution, space, work, x, True):
            cut = j - i - 1
            P[i + 1 : m - cut] = P[j:m].copy()
            m -= cut
    return P[:m].copy()
