"""Collision-free motion planning in joint space: bidirectional RRT-Connect from a start
to any of several goals (:mod:`~toolkit.planning.trees`), every edge checked at
configurations at most ``resolution`` apart (:mod:`~toolkit.planning.edges`), the path
shortened by straight cuts that pass the same check, then certified whole (over its whole
motion on the covers, else again by the exact checker).

The package plans on arrays and a collision test; :meth:`toolkit.Robot.plan` gives it a
robot's joint values, limits and exact collision checker (coal, on the description's
meshes), and goals as configurations or tool poses. Where the checker has its compiled
pre-filter, the plan is first searched for compiled (:mod:`~toolkit.planning.kernels`,
:mod:`~toolkit.planning.certain`) on configurations the bounds and sphere covers alone
prove free, without coal; the search on the exact checker runs where that finds nothing.

MoveIt's formats (:mod:`~toolkit.planning.moveit`, :mod:`~toolkit.planning.requests`):
:func:`read_scene` reads a planning scene's obstacles into a Scene, :func:`read_request` a
motion plan request into a :class:`MotionRequest` (its ``plan(robot, scene)`` plans it),
:func:`write_joint_trajectory` and :func:`read_joint_trajectory` a joint trajectory.
:func:`plan_many` plans a dataset of problems on a pool of threads.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from ..common import caller_level
from .certain import CertainTest, escape, search
from .edges import RESOLUTION, EdgeChecker, Sweep, SweptEdges, shortcut
from .geometry import joint_facts, reach, value_bounds
from .many import plan_many
from .moveit import fixed_frames, read_scene
from .requests import (
    JointTrajectory,
    MotionRequest,
    read_joint_trajectory,
    read_request,
    write_joint_trajectory,
)
from .results import PlanResult
from .settings import PlannerSettings
from .sweep import ExactSweep
from .trees import rrt_connect

__all__ = [
    "RESOLUTION",
    "CertainTest",
    "ExactSweep",
    "JointTrajectory",
    "MotionRequest",
    "PlanResult",
    "PlannerSettings",
    "fixed_frames",
    "joint_facts",
    "plan_many",
    "plan_values",
    "reach",
    "read_joint_trajectory",
    "read_request",
    "read_scene",
    "value_bounds",
    "write_joint_trajectory",
]


def plan_values(  # long: the two searches and the certificates under one time budget
    collides: Callable[[np.ndarray], np.ndarray], start: np.ndarray, goals: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray], *, time_limit: float, seed: int,
    resolution: float = RESOLUTION, simplify: bool = True,
    certain: CertainTest | None = None, sweep: Sweep | None = None,
    deferred: Sweep | None = None, settings: PlannerSettings | None = None,
    step: float | None = None,
) -> tuple[np.ndarray | None, int, dict[str, float]]:  # fmt: skip
    """(path (K, n) of joint values or None, the goal reached (-1), figures: seconds,
    checks, nodes, whether the path was verified, whether the compiled search on ``certain``
    found it, the segments the exact shapes' certificate passed) from ``start`` (n,) to any
    of ``goals`` (G, n), free by ``collides`` ((N, n) -> (N,) flags); inputs checked.

    With ``certain`` (a conservative test: :class:`~toolkit.planning.certain.CertainTest`),
    the compiled search on it runs first, for at most ``settings.certain_share`` of the time,
    from the start to the goals that pass it; where it finds nothing (a start or goal the
    covers do not clear, a passage they close), the search on ``collides`` takes the rest
    of the time. The path is certified free in the end over its whole motion, every
    segment: on the covers where the compiled search certified it (``swept``), else by
    ``sweep`` (:class:`~toolkit.planning.sweep.ExactSweep`: conservative advancement on
    the exact shapes), after ``collides`` passed its configurations ``resolution`` apart;
    the pairs ``certain`` leaves out (:attr:`~toolkit.planning.certain.CertainTest.deferred`)
    by ``deferred`` on the segments the covers certified. A path that fails is not
    returned. Without ``sweep`` (no bound on how far the shapes' points move), the
    configurations ``resolution`` apart are the final check (``swept`` 0). ``settings``:
    :class:`~toolkit.planning.settings.PlannerSettings` (None: the defaults; ``step=``, the
    old name of its ``max_edge``, warns)."""
    settings = _settings(settings, step)
    if certain is not None:
        certain.ready()  # compiled before the clock starts
    begin = time.perf_counter()
    deadline = begin + time_limit
    path, goal, nodes, checks, swept = None, -1, 0, 0, False
    escaped: list[int] = []
    edges = EdgeChecker(collides, resolution)
    exact = 0  # segments the exact shapes' certificate passed
    if certain is not None:
        path, goal, nodes, checks, swept, escaped = _certain_first(
            certain, edges, start, goals, bounds,
            deadline=begin + settings.certain_share * time_limit, seed=seed,
            resolution=resolution, settings=settings, simplify=simplify,
        )  # fmt: skip
    found_certain, verified = path is not None, False
    if path is not None:
        verified, tested, exact, refused = _certified_covers_path(
            path, swept, escaped, edges, collides, (sweep, deferred), deadline
        )
        checks += tested
        if refused:  # searched again on the covers, with the next seeds
            options = dict(resolution=resolution, settings=settings, simplify=simplify)
            again = _reseeded(certain, edges, start, goals, bounds, (sweep, deferred),
                              (begin + settings.certain_share * time_limit, deadline), seed,
                              options)  # fmt: skip
            nodes, checks = nodes + again[1], checks + again[2]
            if again[0] is not None:
                (path, goal, swept, escaped, exact), refused, verified = again[0], [], True
        if refused:  # only the pairs the covers left out refused segments: mended there
            path, verified, mend = _mended(
                path, refused, edges, bounds, np.random.default_rng(seed), sweep,
                (begin + settings.search_share * time_limit, deadline), settings, simplify,
            )  # fmt: skip
            nodes, checks, exact = nodes + mend[0], checks + mend[1], exact + mend[2]
        swept = verified and (swept or sweep is not None)
        if not verified:  # the exact search below, in the time left
            path, found_certain, swept = None, False, False
    if path is None:
        path, goal, grown, tested, exact, edges = _search_exact(
            start, goals, bounds, edges, np.random.default_rng(seed), sweep,
            (begin + settings.search_share * time_limit, deadline), settings, simplify,
        )  # fmt: skip
        nodes, checks, verified = nodes + grown, checks + tested, path is not None
        swept = verified and sweep is not None
    found = path is not None
    figures = {"time_s": time.perf_counter() - begin, "checks": float(checks + edges.checks),
               "nodes": float(nodes), "verified": float(verified and found),
               "certain": float(found_certain), "swept": float(found and swept),
               "exact_segments": float(exact if found else 0),
               "escapes": float(len(escaped) if found_certain and swept else 0)}  # fmt: skip
    return path, goal, figures


def _reseeded(
    certain: CertainTest | None, edges: EdgeChecker, start: np.ndarray, goals: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray], sweeps: tuple[Sweep | None, Sweep | None],
    deadlines: tuple[float, float], seed: int, options: dict[str, Any],
) -> tuple[tuple[np.ndarray, int, bool, list[int], int] | None, int, int]:  # fmt: skip
    """:func:`_certain_first` again with the seeds after ``seed``, ``settings.reseeds``
    times at most (until the first of ``deadlines``, the covers' search's), each path
    certified as the first was (:func:`_certified_covers_path`): ((the first path every
    pair passes, its goal, swept, its escapes, the segments certified on the exact shapes)
    or None, nodes, configurations checked)."""
    nodes = checks = 0
    settings: PlannerSettings = options["settings"]
    for k in range(1, settings.reseeds + 1):
        if certain is None or time.perf_counter() >= deadlines[0]:
            break
        path, goal, grown, tested, swept, escaped = _certain_first(
            certain, edges, start, goals, bounds, deadline=deadlines[0], seed=seed + k, **options
        )
        nodes, checks = nodes + grown, checks + tested
        if path is None:
            continue
        ok, tested, exact, refused = _certified_covers_path(
            path, swept, escaped, edges, edges.collides, sweeps, deadlines[1]
        )
        checks += tested
        if ok and not refused:
            return (path, goal, swept, escaped, exact), nodes, checks
    return None, nodes, checks


def _search_exact(
    start: np.ndarray, goals: np.ndarray, bounds: tuple[np.ndarray, np.ndarray],
    edges: EdgeChecker, rng: np.random.Generator, sweep: Sweep | None,
    deadlines: tuple[float, float], settings: PlannerSettings, simplify: bool,
) -> tuple[np.ndarray | None, int, int, int, int, EdgeChecker]:  # fmt: skip
    """RRT-Connect on the exact checker (``edges``), shortcut, then certified whole
    (:func:`_certified`), until a path passes or the first of ``deadlines`` (the second
    bounds the shortcuts and the certificate): a path the certificate refuses is searched
    again with every edge so certified (:class:`~toolkit.planning.edges.SweptEdges`: the
    samples missed what lay between them). (path or None, the goal, nodes, configurations
    checked by the certificates, the segments ``sweep`` passed, the edges the search ended
    with)."""
    nodes = checks = 0
    while time.perf_counter() < deadlines[0]:
        path, goal, grown = rrt_connect(start, goals, bounds, edges, rng, deadlines[0], settings)
        nodes += grown
        if path is None:
            break
        if simplify:
            path = shortcut(path, edges, rng, deadlines[1])
        todo = list(range(len(path) - 1))
        ok, tested, exact = _certified(path, todo, edges, edges.collides, sweep, deadlines[1])
        checks += tested
        if ok:
            return path, goal, nodes, checks, exact, edges
        if sweep is not None and not isinstance(edges, SweptEdges):
            checks += edges.checks
            edges = SweptEdges(edges.collides, edges.resolution, sweep, deadlines[0])
    return None, -1, nodes, checks, 0, edges


def _certified_covers_path(
    path: np.ndarray, swept: bool, escaped: list[int], edges: EdgeChecker,
    collides: Callable[[np.ndarray], np.ndarray], sweeps: tuple[Sweep | None, Sweep | None],
    deadline: float,
) -> tuple[bool, int, int, list[int]]:  # fmt: skip
    """:func:`_certified` of the covers' search's path: its ``escaped`` segments where the
    covers' certificate passed the others (``swept``), else every segment; and the pairs
    the covers left out (``sweeps[1]``) on the others: (verified, configurations checked,
    segments certified on the exact shapes, the segments only those pairs refused)."""
    sweep, deferred = sweeps
    todo = escaped if swept else list(range(len(path) - 1))
    verified, tested, exact = _certified(path, todo, edges, collides, sweep, deadline)
    refused: list[int] = []
    if verified and swept and deferred is not None:
        rest = [k for k in range(len(path) - 1) if k not in escaped]
        refused = [k for k in rest if not deferred(path[k], path[k + 1], deadline)]
        verified = not refused
        exact += len(rest) - len(refused)
    return verified, tested, exact, refused


def _mended(
    path: np.ndarray, refused: list[int], edges: EdgeChecker,
    bounds: tuple[np.ndarray, np.ndarray], rng: np.random.Generator, sweep: Sweep | None,
    deadlines: tuple[float, float], settings: PlannerSettings, simplify: bool,
) -> tuple[np.ndarray, bool, tuple[int, int, int]]:  # fmt: skip
    """``path`` with each stretch the left-out pairs refused searched again on the exact
    checker (:func:`_search_exact`, certified whole), from the last waypoint before it that
    is free to the first after it (a waypoint may collide on those pairs): a search between
    two near configurations instead of the whole plan's (MBM's UR5: its forearm against its
    wrist). (the path, whether every stretch was mended, (nodes, checks, segments
    certified on the exact shapes))."""
    free = ~np.asarray(edges.collides(path), dtype=bool)
    stretches: list[list[int]] = []
    for k in refused:
        i, j = k, k + 1
        while i > 0 and not free[i]:  # the start and the goals are free: checked
            i -= 1
        while j < len(path) - 1 and not free[j]:
            j += 1
        if stretches and i <= stretches[-1][1]:
            stretches[-1][1] = max(stretches[-1][1], j)
        else:
            stretches.append([i, j])
    pieces, last, nodes, checks, exact = [], 0, 0, len(path), 0
    for i, j in stretches:
        found, _, grown, tested, certified, _ = _search_exact(
            path[i], path[j][None], bounds, edges, rng, sweep, deadlines, settings, simplify
        )
        nodes, checks, exact = nodes + grown, checks + tested, exact + certified
        if found is None:
            return path, False, (nodes, checks, exact)
        pieces += [path[last:i], found[:-1]]
        last = j
    return np.concatenate([*pieces, path[last:]]), True, (nodes, checks, exact)


def _certified(
    path: np.ndarray, segments: list[int], edges: EdgeChecker,
    collides: Callable[[np.ndarray], np.ndarray], sweep: Sweep | None, deadline: float,
) -> tuple[bool, int, int]:  # fmt: skip
    """(whether every one of ``segments`` of ``path`` passes: its configurations
    ``resolution`` apart by ``collides``, then its whole motion by ``sweep`` where there is
    one; the configurations checked; the segments ``sweep`` passed)."""
    if not segments:
        return True, 0, 0
    free, tested = _checked_whole(path, edges, collides, segments)
    if not free or sweep is None:
        return free, tested, 0
    for k in segments:
        if not sweep(path[k], path[k + 1], deadline):
            return False, tested, 0
    return True, tested, len(segments)


def _checked_whole(
    path: np.ndarray, edges: EdgeChecker, collides: Callable[[np.ndarray], np.ndarray],
    segments: list[int] | None = None,
) -> tuple[bool, int]:  # fmt: skip
    """(whether every configuration of ``path`` (of its ``segments``, default all) at most
    the edges' resolution apart is free by ``collides``, in one batch and a fresh count;
    how many)."""
    ks = range(len(path) - 1) if segments is None else segments
    parts = [edges.points(path[k], path[k + 1]) for k in ks]
    points = np.concatenate([path[:1], *parts])
    return not bool(np.any(collides(points))), len(points)


def _escapes(
    certain: CertainTest, edges: EdgeChecker, bounds: tuple[np.ndarray, np.ndarray], seed: int,
    deadline: float, settings: PlannerSettings,
) -> Callable[[np.ndarray], np.ndarray | None]:  # fmt: skip
    """:func:`~toolkit.planning.certain.escape` from an end, all of a plan's escapes drawing
    on one random stream of ``seed``, made at the first (most plans escape nothing)."""
    stream: list[np.random.Generator] = []

    def away(end: np.ndarray) -> np.ndarray | None:
        if not stream:
            stream.append(np.random.default_rng(seed))
        return escape(certain, edges, end, bounds, stream[0], deadline, settings)

    return away


def _certain_first(
    certain: CertainTest, edges: EdgeChecker, start: np.ndarray, goals: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray], **options: Any,
) -> tuple[np.ndarray | None, int, int, int, bool, list[int]]:  # fmt: skip
    """:func:`~toolkit.planning.certain.search` from ``start`` to ``goals``: an end the
    test does not pass (a grasp beside its object, within the covers' excess) is first
    left by a short straight edge that ``edges`` (the exact checker) passes, to one the
    test passes (:func:`~toolkit.planning.certain.escape`; for the first
    ``settings.escaped_goals`` such goals). (path or None, the goal
    reached, nodes, configurations tested, whether every segment but the escapes' is free
    over its whole motion: :meth:`~toolkit.planning.certain.CertainTest.swept`, the escapes'
    segments in the path (their indices: 0, 1 or 2 of them); where the path found is not
    swept and no end was escaped, the search runs again to its goal with every edge so
    certified, in the time left and for at most four times the nodes the first search grew, or
    ``settings.restart_nodes``; without it, the first path is checked
    on the exact shapes: in the cage of MotionBenchMaker, searching again took up to 8x
    the exact check of an escaped path.)"""
    ends = certain.free(np.concatenate([start[None], goals]))
    settings: PlannerSettings = options["settings"]
    away = _escapes(certain, edges, bounds, options["seed"], options["deadline"], settings)
    first = start if ends[0] else away(start)
    kept: list[int] = []  # the goals aimed at, where the search aims, escaped or not
    aims: list[np.ndarray] = []
    escaped: list[bool] = []
    tried = 0
    for i, goal in enumerate(goals):
        aim: np.ndarray | None = goal
        if not ends[i + 1]:
            aim, tried = None, tried + 1
            if tried <= settings.escaped_goals:
                aim = away(goal)
        if aim is not None:
            kept.append(i)
            aims.append(aim)
            escaped.append(not ends[i + 1])
    if first is None or not kept:
        return None, -1, 0, len(ends), False, []
    whole = ends[0] and not any(escaped)  # no escape: the path will be certified whole
    if certain.sweeps and whole:  # the certificate the final check: searched coarser
        options = dict(options, resolution=settings.covers_coarser * options["resolution"])
    path, g, nodes, checks = search(certain, first, np.array(aims), bounds, **options)
    if path is None:
        return None, -1, nodes, checks + len(ends), False, []
    swept, tested = certain.swept(path)  # an escape's segment is not in it: checked already
    checks += tested
    if not swept and whole and certain.sweeps and time.perf_counter() < options["deadline"]:
        again = search(certain, first, np.array(aims[g : g + 1]), bounds, swept=True,
                       most=max(settings.restart_nodes, 4 * nodes), **options)  # fmt: skip
        checks += again[3]
        if again[0] is not None:
            path, swept = again[0], True
    if swept and options["simplify"]:  # corners cut, each cut certified the same way
        path, tested = certain.cut_corners(path, settings.corners)
        checks += tested
    head = [] if ends[0] else [start]  # the escapes' edges, checked at configurations only
    tail = [goals[kept[g]]] if escaped[g] else []
    path = np.array([*head, *path, *tail])
    escaped_segments = ([0] if head else []) + ([len(path) - 2] if tail else [])
    return path, kept[g], nodes, checks + len(ends), bool(swept), escaped_segments


def _settings(settings: PlannerSettings | None, step: float | None) -> PlannerSettings:
    """``settings`` (None: the defaults), with the old ``step=`` (warned) as its
    ``max_edge``."""
    settings = PlannerSettings.of(settings)
    if step is None:
        return settings
    warnings.warn(
        "plan_values: step= is now settings=PlannerSettings(max_edge=...); the old name "
        "goes in the next release",
        DeprecationWarning,
        stacklevel=caller_level(),
    )
    return dataclasses.replace(settings, max_edge=step)
