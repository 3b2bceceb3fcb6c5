"""The compiled search on certainly-free configurations (toolkit.planning.certain and
kernels): its test is the pre-filter's FREE and never passes a configuration coal finds
colliding; its edges test the configurations the Python edge checker would; its plans are
checked again here at a quarter degree by coal on every pair; a goal the covers cannot
clear is left by a short edge checked exactly, or else the exact search answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit.collision.bound_kernels import FREE
from toolkit.planning import certain, kernels
from toolkit.planning.edges import EdgeChecker
from toolkit.robot import checker_for
from toolkit.robot.plans import certain_test

from .test_planning import UR5, WALL, A, B, dense, free_everywhere

KINOVA = toolkit.load_example("kinova")  # continuous joints: (cos, sin) pairs in q
SHELF = toolkit.Scene().add_box("shelf", [0.3, 0.6, 0.04], [0.45, 0.0, 0.3])


def _test(robot: toolkit.Robot, scene: toolkit.Scene) -> certain.CertainTest:
    found = certain_test(robot, checker_for(robot, scene))
    assert found is not None
    return found


@pytest.mark.parametrize(("robot", "scene"), [(UR5, WALL), (KINOVA, SHELF)])
def test_the_test_is_the_prefilters_free_and_coal_finds_no_collision_where_it_passes(robot, scene):
    checker = checker_for(robot, scene)
    Q = robot.random_q(400, seed=7)
    passed = _test(robot, scene).free(robot.angles(Q))
    np.testing.assert_array_equal(passed, checker.bounds.decide(Q) == FREE)
    assert 20 < passed.sum() < len(Q)  # both answers occur
    for q in Q[passed]:  # coal on every pair, one configuration at a time
        assert checker.first_collision(q) is None


@settings(max_examples=80, deadline=None)
@given(
    a=st.lists(st.floats(-3, 3), min_size=6, max_size=6),
    b=st.lists(st.floats(-3, 3), min_size=6, max_size=6),
    resolution=st.floats(0.01, 0.5),
)
def test_an_edge_passes_exactly_when_every_configuration_of_the_edge_checker_does(a, b, resolution):
    test = _test(UR5, WALL)
    a, b = np.array(a), np.array(b)
    points = EdgeChecker(lambda V: V[:, 0] > 0, resolution).points(a, b)
    work = test._work()
    got = kernels.edge_free(a, b, resolution, test._space(), work, np.empty(6))
    assert got == bool(test.free(points).all())
    if got:  # every configuration tested once, no more
        assert work[3][0] == len(points)


def test_the_random_numbers_are_uniform_and_the_same_for_the_same_seed():
    from numba import njit

    @njit
    def draws(seed, n):
        state, out = np.array([seed], dtype=np.uint64), np.empty(n)
        for i in range(n):
            out[i] = kernels.uniform(state)
        return out

    x = draws(3, 20_000)
    assert 0.0 <= x.min() and x.max() < 1.0
    assert abs(x.mean() - 0.5) < 0.01 and abs(x.var() - 1 / 12) < 0.005
    np.testing.assert_array_equal(x, draws(3, 20_000))
    assert not np.array_equal(x, draws(4, 20_000))


def test_a_plan_around_the_wall_is_found_on_the_covers_and_free_on_the_meshes():
    result = UR5.plan(A, B, scene=WALL, seed=1)
    assert result.success and result.verified and result.search == "covers", result.reason
    assert free_everywhere(UR5, result.path, WALL)
    again = UR5.plan(A, B, scene=WALL, seed=1)
    np.testing.assert_array_equal(result.path, again.path)


def test_trees_that_fill_their_room_get_more(monkeypatch):
    monkeypatch.setattr(certain, "CAPACITY", 4)
    result = UR5.plan(A, B, scene=WALL, seed=1, simplify=False)
    assert result.success and result.search == "covers" and result.nodes > 4
    assert free_everywhere(UR5, result.path, WALL)


def _close_goal() -> np.ndarray:
    """A UR5 configuration free on the meshes that the covers do not clear (beside the wall)."""
    checker = checker_for(UR5, WALL)
    Q = UR5.random_q(4000, seed=12)
    close = Q[(checker.bounds.decide(Q) != FREE) & ~checker.in_collision_many(Q)]
    assert len(close), "no configuration free on the meshes but not on the covers"
    assert not _test(UR5, WALL).free(UR5.angles(close[:1]))[0]
    return close[0]


@pytest.mark.parametrize("end", ["goal", "start"])
def test_an_end_the_covers_cannot_clear_is_left_by_a_short_edge_checked_exactly(end):
    close = _close_goal()
    start, goal = (A, close) if end == "goal" else (close, A)
    result = UR5.plan(start, goal, scene=WALL, seed=2)
    assert result.success and result.search == "covers", result.reason
    np.testing.assert_array_equal(result.path[[0, -1]], [start, goal])
    inner = -2 if end == "goal" else 1  # the escape's other end
    far = result.values[-1 if end == "goal" else 0]
    assert np.linalg.norm(result.values[inner] - far) <= max(certain.ESCAPES) + 1e-12
    assert _test(UR5, WALL).free(result.values[[inner]])[0]
    assert free_everywhere(UR5, result.path, WALL)


def test_where_no_escape_is_found_the_exact_search_answers(monkeypatch):
    monkeypatch.setattr(certain, "ESCAPES", ())
    goal = _close_goal()
    result = UR5.plan(A, goal, scene=WALL, seed=2, time_limit=20)
    assert result.success and result.search == "exact", result.reason
    assert free_everywhere(UR5, result.path, WALL)


def test_an_arm_with_continuous_joints_plans_on_its_covers():
    test = _test(KINOVA, SHELF)
    Q = KINOVA.random_q(200, seed=3)
    q0, q1 = Q[test.free(KINOVA.angles(Q))][:2]
    result = KINOVA.plan(q0, q1, scene=SHELF, seed=0)
    assert result.success and result.search == "covers", result.reason
    fine = KINOVA.q_from_angles(dense(result.values, math.radians(0.25)))
    assert not any(KINOVA.collisions(q, SHELF) for q in fine)
    np.testing.assert_allclose(KINOVA.q_from_angles(result.values), result.path, atol=1e-15)


@pytest.mark.slow
def test_the_first_plan_after_installing_compiles_before_its_clock_starts(tmp_path):
    """In a fresh process with an empty kernel cache, a plan of 1 s still finds its path on
    the covers: the search's kernels compile before the time limit starts to run."""
    import os
    import subprocess
    import sys

    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    code = (
        "import numpy as np, toolkit\n"
        "ur5 = toolkit.load_example('ur5')\n"
        "wall = toolkit.Scene().add_box('wall', [0.1, 1.2, 0.8], [0.45, 0.0, 0.4])\n"
        f"r = ur5.plan(np.array({A.tolist()}), np.array({B.tolist()}), scene=wall, "
        "time_limit=1.0)\n"
        "print(r.success, r.search)\n"
    )
    env = {**os.environ, "TOOLKIT_CACHE_DIR": str(cache)}
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=600, check=True)  # fmt: skip
    assert out.stdout.split() == ["True", "covers"], out.stdout + out.stderr
