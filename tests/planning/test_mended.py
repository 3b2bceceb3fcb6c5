"""A path found on the covers whose stretches only the pairs the covers left out refuse is
mended there (toolkit.planning._mended): searched again on the exact checker between the
free waypoints around each stretch, the rest of the path kept."""

from __future__ import annotations

import itertools
import time

import numpy as np

from toolkit import planning
from toolkit.planning import PlannerSettings
from toolkit.planning.edges import EdgeChecker

BOUNDS = (np.array([-2.0, -2.0]), np.array([2.0, 2.0]))


def _disc(values: np.ndarray) -> np.ndarray:
    """A disc of radius 0.3 about the origin blocks the plane."""
    return np.linalg.norm(np.atleast_2d(values), axis=1) < 0.3


def _mend(path: np.ndarray, refused: list[int]):
    edges = EdgeChecker(_disc, 0.01)
    later = time.perf_counter() + 5.0
    return planning._mended(path, refused, edges, BOUNDS, np.random.default_rng(0), None,
                            (later, later), PlannerSettings(), True)  # fmt: skip


def _free(path: np.ndarray) -> bool:
    dense = np.concatenate([np.linspace(a, b, 400) for a, b in itertools.pairwise(path)])
    return not _disc(dense).any()


def test_a_refused_segment_is_searched_again_and_the_rest_kept():
    path = np.array([[-1.5, 1.0], [-1.0, 0.0], [1.0, 0.0], [1.5, 1.0]])  # the middle crosses
    assert not _free(path)
    mended, ok, (nodes, checks, _) = _mend(path, [1])
    assert ok and _free(mended) and nodes > 0 and checks > 0
    np.testing.assert_array_equal(mended[:2], path[:2])  # the start and the segment before
    np.testing.assert_array_equal(mended[-2:], path[-2:])  # the segment after and the goal


def test_a_stretch_runs_from_the_last_free_waypoint_to_the_next():
    """A waypoint inside the disc: the two segments about it are one stretch, mended from
    the free waypoint before to the free one after; the colliding waypoint is gone."""
    path = np.array([[-1.0, 0.0], [0.0, 0.1], [1.0, 0.0]])
    mended, ok, _ = _mend(path, [0, 1])
    assert ok and _free(mended)
    assert not any(np.array_equal(p, path[1]) for p in mended)
    np.testing.assert_array_equal(mended[[0, -1]], path[[0, 2]])


def test_a_stretch_with_no_way_round_is_not_mended():
    """The goal walled in: the mend fails and says so, leaving the path as it was."""
    walled = lambda v: _disc(v) | (np.atleast_2d(v)[:, 0] > 0.9)  # noqa: E731
    edges = EdgeChecker(walled, 0.01)
    path = np.array([[-1.0, 0.0], [1.0, 0.0]])
    soon = time.perf_counter() + 0.3
    mended, ok, _ = planning._mended(path, [0], edges, BOUNDS, np.random.default_rng(0), None,
                                     (soon, soon), PlannerSettings(), True)  # fmt: skip
    assert not ok and mended is path


def test_a_path_the_left_out_pairs_refuse_is_searched_again_on_the_covers_first(monkeypatch):
    """Where the pairs the covers' search left out refuse a segment of its path, the search
    runs again with the next seeds (PlannerSettings.reseeds) and its path, certified the
    same way, is returned: nothing is mended on the exact checker. With no reseeds, the
    refused stretch is mended. (A stand-in certificate of the left-out pairs refuses the
    first path's segments.)"""
    import pytest

    import toolkit
    from toolkit.robot import plans

    from .test_planning import UR5, WALL, A, B

    real = plans._sweeps
    asked: list[int] = []

    def sweeps(robot, checker, test):
        sweep, _ = real(robot, checker, test)

        def deferred(a, b, deadline=None):
            asked.append(1)
            return len(asked) > 1  # the first segment asked is refused

        return sweep, deferred

    mended: list[list[int]] = []

    def mend(path, refused, *rest):
        mended.append(refused)
        return path, True, (0, 0, 0)

    monkeypatch.setattr(plans, "_sweeps", sweeps)
    monkeypatch.setattr(planning, "_mended", mend)
    result = UR5.plan(A, B, scene=WALL, seed=1)
    assert result.success and result.search == "covers" and mended == [] and len(asked) > 1
    asked.clear()
    again = UR5.plan(A, B, scene=WALL, seed=1, settings=PlannerSettings(reseeds=0))
    assert again.success and mended == [[0]]
    with pytest.raises(toolkit.InvalidParameterError, match="reseeds"):
        PlannerSettings(reseeds=-1)
