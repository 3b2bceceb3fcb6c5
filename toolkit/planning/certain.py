"""The search on certainly-free configurations (:func:`search`): RRT-Connect and its
shortcuts compiled (:mod:`~toolkit.planning.kernels`), tested by the checker's bounds and
sphere covers alone, without coal. What it returns is free on the exact shapes at every
configuration it checked; where the covers close a passage the exact shapes leave open,
it finds nothing and the caller plans on the exact checker."""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..collision import Packed, bound_kernels
from . import kernels
from .edges import EdgeChecker
from .records import Space, Trees, Work
from .settings import PlannerSettings

__all__ = ["CertainTest", "escape", "search"]


@dataclass(frozen=True)
class CertainTest:
    """A robot's conservative collision test for the compiled search: per joint value its
    column in q and whether it is a (cos, sin) pair (``qcol``, ``circle``), q's length, the
    checker's pre-filter arrays (``packed``: :meth:`toolkit.collision.Bounds.packed`) and,
    per shape and joint value, how far [m] the shape's points lie from that joint's axis
    (``reach``, :func:`~toolkit.planning.reach`: 1 for a slide; where the joint does not
    move the shape, its distance from the axis it rides with, else inf; None where a slide
    has no limit) and whether the joint moves it (``moves``), by which every edge is
    certified over its whole motion (:func:`~toolkit.planning.kernels.edge_swept`)."""

    qcol: np.ndarray
    circle: np.ndarray
    nq: int
    packed: Packed
    reach: np.ndarray | None = None
    moves: np.ndarray | None = None
    deferred: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    """The checker's pairs (indices into its pair list) left out of ``packed``: the
    robot's own pairs its bounds seldom decide (:func:`toolkit.robot.plans.deferred_pairs`),
    certified on the exact shapes after the search
    (:class:`~toolkit.planning.sweep.ExactSweep`)."""
    runs: np.ndarray = field(init=False)
    """The pairs as runs of one shape against consecutive others
    (:func:`~toolkit.collision.bound_kernels.pair_runs`)."""

    def __post_init__(self) -> None:
        runs = bound_kernels.pair_runs(self.packed.first, self.packed.second)
        object.__setattr__(self, "runs", runs)

    @property
    def sweeps(self) -> bool:
        """Whether edges are certified over their whole motion (a finite ``reach`` wherever
        a joint moves a shape)."""
        return self.reach is not None and self.moves is not None and bool(
            np.isfinite(self.reach[self.moves]).all())  # fmt: skip

    def _space(self, swept: bool = False) -> Space:
        """The kernels' ``space``; ``swept``: every edge certified over its whole motion."""
        shapes, n = len(self.packed.row), len(self.qcol)
        reach = self.reach if self.reach is not None else np.zeros((shapes, n))
        moves = self.moves if self.moves is not None else np.zeros((shapes, n), dtype=bool)
        return Space(self.qcol, self.circle, self.packed, reach, moves,
                     swept and self.sweeps, self.runs)  # fmt: skip

    def _work(self) -> Work:
        ints, row, pairs = self.packed.ints, self.packed.row, len(self.packed.first)
        return Work(np.zeros(self.nq), np.empty((ints.shape[0] + 1, 15)),
                    np.full((row.shape[0], 12), np.nan), np.zeros(2, np.int64),
                    np.zeros(pairs), np.zeros(pairs),
                    np.zeros(max(1, pairs), np.bool_))  # fmt: skip

    def ready(self) -> None:
        """Compile the search's kernels with calls that do nothing (on the first use after
        an installation: seconds, then loaded from the cache), so that a plan's clock does
        not start before them; once per process and kind of arrays the kernels take (every
        test of the same dtypes and dimensions shares them: the calls cost 0.13 ms, a
        tenth of a plan among the shelves)."""
        if self.__dict__.get("_ready"):
            return
        kind = kind_of((self.qcol, self.circle, self.packed, self.reach, self.moves, self.runs))
        if kind in READY:  # (the work arrays' kinds are fixed by :meth:`_work`)
            object.__setattr__(self, "_ready", True)
            return
        space, work, n = self._space(True), self._work(), len(self.qcol)  # values: any
        x, rng = np.zeros(n), np.zeros(1, np.uint64)
        kernels.free_rows(np.zeros((1, n)), space, work, np.zeros(1, dtype=bool))
        kernels.edge(x, x.copy(), 1.0, space, work, np.empty(n), False)
        trees = Trees(np.zeros((2, 2, n)), np.full((2, 2), -1), np.zeros((2, 2), int),
                      np.zeros((2, n, 2), np.float32), np.full((2, 2), np.inf))  # fmt: skip
        kernels.grow(trees, np.ones(2, int), (x, x.copy()), (0.5, 1.0, PlannerSettings().domain),
                     space,
                     work, rng,
                     0, np.zeros(1, int), np.zeros(2, int))  # fmt: skip
        kernels.shortcut(np.zeros((2, n)), 0, 1.0, space, work, rng)
        kernels.cut_corners(np.zeros((2, n)), 0, space, work)
        object.__setattr__(self, "_ready", True)  # a frozen record: a flag beside its fields
        READY.add(kind)

    def free(self, values: np.ndarray) -> np.ndarray:
        """(N,) whether each row of joint values (N, n) passes the test."""
        out = np.zeros(len(values), dtype=bool)
        kernels.free_rows(np.ascontiguousarray(values, dtype=float), self._space(),
                          self._work(), out)  # fmt: skip
        return out

    def swept(self, path: np.ndarray) -> tuple[bool, int]:
        """(whether every segment of ``path`` (K, n) is free over its whole motion, by
        :func:`~toolkit.planning.kernels.edge_swept`; the configurations it checked). False
        without a finite ``reach``."""
        if not self.sweeps:
            return False, 0
        space, work, x = self._space(True), self._work(), np.empty(path.shape[1])
        P = np.ascontiguousarray(path, dtype=float)
        ok = all(kernels.edge_swept(a, b, space, work, x) for a, b in itertools.pairwise(P))
        return ok, int(work.tested[0])

    def cut_corners(self, path: np.ndarray, passes: int) -> tuple[np.ndarray, int]:
        """(``path``, whose every segment :meth:`swept` passes, with its corners cut
        ``passes`` times (:attr:`~toolkit.planning.settings.PlannerSettings.corners`;
        :func:`~toolkit.planning.kernels.cut_corners`: the cuts certified the same way);
        the configurations it checked)."""
        if not self.sweeps or len(path) < 3 or passes < 1:
            return path, 0
        space, work = self._space(True), self._work()
        P = np.ascontiguousarray(path, dtype=float)
        return kernels.cut_corners(P, passes, space, work), int(work.tested[0])


READY: set[tuple[object, ...]] = set()
"""The kinds of arrays (:func:`kind_of`) the planner's kernels were made ready for (the
search's, :meth:`CertainTest.ready`; the exact certificate's,
:class:`~toolkit.planning.sweep.ExactSweep`)."""


def kind_of(value: object) -> tuple[object, ...]:
    """What numba types a nest of tuples of arrays and scalars by: each array's dtype,
    dimensions and layout, each other item's type."""
    if isinstance(value, tuple):
        return tuple(kind_of(v) for v in value)
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.ndim, value.flags.c_contiguous)
    return (type(value),)


def escape(
    test: CertainTest, edges: EdgeChecker, q: np.ndarray, bounds: tuple[np.ndarray, ...],
    rng: np.random.Generator, deadline: float = math.inf,
    settings: PlannerSettings | None = None,
) -> np.ndarray | None:  # fmt: skip
    """A configuration at one of the ``settings``' ``escapes`` from ``q`` (within
    ``bounds``) that ``test`` passes and that ``edges`` (the exact checker) passes the
    straight edge from ``q`` to, in rounds of its ``directions`` random directions; None
    where none of the tries is, after its ``escape_edges`` edges asked of ``edges``, or
    past ``deadline`` (a ``time.perf_counter`` value). ``settings``: None, the defaults
    (:class:`~toolkit.planning.settings.PlannerSettings`)."""
    settings = PlannerSettings.of(settings)
    lo, hi = bounds
    asked = 0
    for directions in settings.directions:
        for length in settings.escapes:
            if time.perf_counter() > deadline:
                return None
            d = rng.normal(size=(directions, len(q)))
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            tries = np.clip(q + length * d, lo, hi)
            for aim in tries[test.free(tries)]:
                if asked == settings.escape_edges:
                    return None
                asked += 1
                if edges.free(q, aim):
                    return np.asarray(aim)
    return None


def _branch(nodes: np.ndarray, parent: np.ndarray, i: int) -> np.ndarray:
    out = []
    while i >= 0:
        out.append(nodes[i])
        i = int(parent[i])
    return np.array(out)


def _fresh_trees(start: np.ndarray, goals: np.ndarray, capacity: int) -> tuple[np.ndarray, ...]:
    """(nodes, parent, root, near, domain radii, sizes): a tree of the start and one of the
    goals, with room for ``capacity`` nodes each (or twice the goals)."""
    n, cap = len(start), max(capacity, 2 * len(goals))
    nodes, parent, root = np.empty((2, cap, n)), np.full((2, cap), -1), np.zeros((2, cap), int)
    near = np.empty((2, n, cap), np.float32)  # the nodes joint by joint, for the nearest scans
    nodes[0, 0], nodes[1, : len(goals)] = start, goals
    near[0, :, 0], near[1, :, : len(goals)] = start, goals.T
    root[1, : len(goals)] = np.arange(len(goals))
    return nodes, parent, root, near, np.full((2, cap), np.inf), np.array([1, len(goals)])


def search(
    test: CertainTest, start: np.ndarray, goals: np.ndarray, bounds: tuple[np.ndarray, ...],
    *, deadline: float, seed: int, resolution: float, settings: PlannerSettings,
    simplify: bool, swept: bool = False, most: int | None = None,
) -> tuple[np.ndarray | None, int, int, int]:  # fmt: skip
    """(path (K, n) of joint values or None by ``deadline`` (or past ``most`` nodes grown
    in all, or once ``settings.stalled`` calls in a row grew no node), the goal reached
    (-1), nodes grown, configurations tested) from ``start`` (n,) to any of ``goals``
    (G, n), all of which must pass the test; shortened when ``simplify``; with ``swept``,
    every edge certified over its whole motion as well (``settings``:
    :class:`~toolkit.planning.settings.PlannerSettings`)."""
    space, work = test._space(swept), test._work()
    start, goals = (
        np.ascontiguousarray(start, dtype=float),
        np.ascontiguousarray(goals, dtype=float),
    )
    n = len(start)
    rng = np.array([seed], dtype=np.uint64)
    x = np.empty(n)
    lo, hi = (np.ascontiguousarray(b, dtype=float) for b in bounds)
    for g, goal in enumerate(goals):  # a straight line first
        if kernels.edge(start, goal, resolution, space, work, x, True):  # ends: passed
            return np.array([start, goal]), g, 2, int(work.tested[0])
    nodes, parent, root, near, radius, sizes = _fresh_trees(start, goals, settings.capacity)
    side, found = np.zeros(1, int), np.zeros(2, int)
    status, grown, budget, still = kernels.RUNNING, 0, settings.restart_nodes, 0
    steps = (settings.max_edge, resolution, settings.radii((lo, hi)))
    while time.perf_counter() < deadline and (most is None or grown + sizes.sum() < most):
        before = int(sizes.sum())
        status = kernels.grow(Trees(nodes, parent, root, near, radius), sizes, (lo, hi),
                              steps, space, work, rng, settings.chunk, side, found)  # fmt: skip
        if status == kernels.MET:
            break
        still = still + 1 if sizes.sum() == before else 0
        if still == settings.stalled:  # neither tree grows: an end in a pocket the test closes
            break
        if sizes.sum() >= budget:  # start again, the random stream going on; twice the budget
            grown, budget = grown + int(sizes.sum()), 2 * budget
            nodes, parent, root, near, radius, sizes = _fresh_trees(start, goals, settings.capacity)
        elif status == kernels.FULL:  # twice the room, the trees as they were
            nodes = np.concatenate([nodes, np.empty_like(nodes)], axis=1)
            parent = np.concatenate([parent, np.full_like(parent, -1)], axis=1)
            root = np.concatenate([root, np.zeros_like(root)], axis=1)
            near = np.concatenate([near, np.empty_like(near)], axis=2)
            radius = np.concatenate([radius, np.full_like(radius, np.inf)], axis=1)
    grown += int(sizes.sum())
    if status != kernels.MET:
        return None, -1, grown, int(work.tested[0])
    path = np.concatenate([_branch(nodes[0], parent[0], int(found[0]))[::-1],
                           _branch(nodes[1], parent[1], int(found[1]))[1:]])  # fmt: skip
    if simplify:
        path = kernels.shortcut(path, settings.tries, resolution, space, work, rng)
    return path, int(root[1, found[1]]), grown, int(work.tested[0])
