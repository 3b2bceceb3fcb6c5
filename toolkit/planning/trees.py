"""Bidirectional RRT-Connect (Kuffner and LaValle, ICRA 2000) in joint values: a tree from
the start and one from every goal at once, each extension checked as a segment by an
:class:`~toolkit.planning.edges.EdgeChecker`; the smaller tree extended while it is at
most half the other, and each node's dynamic domain (Yershova et al., ICRA 2005): the
steps of the compiled search, :func:`toolkit.planning.kernels.grow`."""

from __future__ import annotations

import math
import time

import numpy as np

from .edges import EdgeChecker
from .settings import PlannerSettings

__all__ = ["Tree", "rrt_connect"]


class Tree:
    """Nodes (joint values), each with its parent (-1 at a root), its root and its domain's
    radius (inf until an extension from it is blocked)."""

    def __init__(self, roots: np.ndarray) -> None:
        r, n = roots.shape
        self.nodes = np.empty((max(64, 2 * r), n))
        self.parent = np.full(len(self.nodes), -1, np.int64)
        self.root = np.zeros(len(self.nodes), np.int64)
        self.radius = np.full(len(self.nodes), np.inf)
        self.nodes[:r], self.root[:r] = roots, np.arange(r)
        self.size: int = int(r)

    def nearest(self, q: np.ndarray) -> int:
        """The node nearest q (Euclidean in joint values)."""
        d = self.nodes[: self.size] - q
        return int(np.argmin(np.einsum("ij,ij->i", d, d)))

    def add(self, q: np.ndarray, parent: int) -> int:
        if self.size == len(self.nodes):
            grow = len(self.nodes)
            self.nodes = np.concatenate([self.nodes, np.empty_like(self.nodes)])
            self.parent = np.concatenate([self.parent, np.full(grow, -1, np.int64)])
            self.root = np.concatenate([self.root, np.zeros(grow, np.int64)])
            self.radius = np.concatenate([self.radius, np.full(grow, np.inf)])
        i = self.size
        self.nodes[i], self.parent[i], self.root[i] = q, parent, self.root[parent]
        self.size += 1
        return i

    def branch(self, i: int) -> np.ndarray:
        """The nodes from node i back to its root ((k, n), i first)."""
        out = []
        while i >= 0:
            out.append(self.nodes[i])
            i = int(self.parent[i])
        return np.array(out)


def _toward(tree: Tree, i: int, target: np.ndarray, step: float) -> np.ndarray:
    q = tree.nodes[i]
    d = target - q
    dist = math.sqrt(float(d @ d))
    return target.copy() if dist <= step else q + d * (step / dist)


def _extend(
    tree: Tree, target: np.ndarray, edges: EdgeChecker, step: float, domain: tuple[float, ...]
) -> int | None:
    """The node ``tree`` grew toward ``target``, or None: the edge was blocked, or the target
    lies outside its nearest node's domain (not tried). The domain's radius follows
    (``domain``: :meth:`~toolkit.planning.settings.PlannerSettings.radii`, in radians)."""
    i = tree.nearest(target)
    r = float(tree.radius[i])
    if r < math.inf and math.dist(tree.nodes[i], target) > r:
        return None
    new = _toward(tree, i, target, step)
    if not edges.free(tree.nodes[i], new):
        tree.radius[i] = domain[0] if r == math.inf else max(r * (1.0 - domain[2]), domain[1])
        return None
    if r < math.inf:
        tree.radius[i] = r * (1.0 + domain[2])
    return tree.add(new, i)


def _connect(
    tree: Tree, target: np.ndarray, edges: EdgeChecker, step: float, deadline: float
) -> int | None:
    """Extend ``tree`` toward ``target`` until it reaches it (its node) or is blocked."""
    i = tree.nearest(target)
    while time.perf_counter() < deadline:
        new = _toward(tree, i, target, step)
        if not edges.free(tree.nodes[i], new):
            return None
        i = tree.add(new, i)
        if np.array_equal(new, target):
            return i
    return None


def rrt_connect(
    start: np.ndarray, goals: np.ndarray, bounds: tuple[np.ndarray, np.ndarray],
    edges: EdgeChecker, rng: np.random.Generator, deadline: float,
    settings: PlannerSettings | None = None,
) -> tuple[np.ndarray | None, int, int]:  # fmt: skip
    """(path (K, n) from ``start`` to one of ``goals`` (G, n), or None by ``deadline``; the
    goal reached (-1 for none); the nodes grown). Samples uniformly within ``bounds``
    (lower, upper); every edge of the path passed ``edges``; edges at most
    ``settings.max_edge`` long (:class:`~toolkit.planning.settings.PlannerSettings`; None:
    the defaults)."""
    settings = PlannerSettings.of(settings)
    step, domain = settings.max_edge, settings.radii(bounds)
    for g, goal in enumerate(goals):  # a straight line first
        if edges.free(start, goal):
            return np.array([start, goal]), g, 2
    forest = [Tree(start[None]), Tree(goals)]  # the start's tree, the goals'
    a = 0  # the tree extended this round (0: the start's)
    while time.perf_counter() < deadline:
        if 2 * forest[1 - a].size <= forest[a].size:  # the last one extended, at most half: again
            a = 1 - a
        A, B = forest[a], forest[1 - a]
        new = _extend(A, rng.uniform(*bounds), edges, step, domain)
        if new is not None:
            met = _connect(B, A.nodes[new], edges, step, deadline)
            if met is not None:
                from_start, from_goal = (new, met) if a == 0 else (met, new)
                path = np.concatenate([forest[0].branch(from_start)[::-1],
                                       forest[1].branch(from_goal)[1:]])  # fmt: skip
                return path, int(forest[1].root[from_goal]), forest[0].size + forest[1].size
        a = 1 - a
    return None, -1, forest[0].size + forest[1].size
