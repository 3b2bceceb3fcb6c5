"""The compiled search on certainly-free configurations (toolkit.planning.certain and
kernels): its test is the pre-filter's FREE and never passes a configuration coal finds
colliding; its edges test the configurations the Python edge checker would; its plans are
checked again here at a quarter degree by coal on every pair; a goal the covers cannot
clear is left by a short edge checked exactly, or else the exact search answers."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit.collision import bound_kernels, gap_kernels
from toolkit.collision.bound_kernels import FREE
from toolkit.planning import PlannerSettings, certain, kernels, records, value_bounds
from toolkit.planning.edges import EdgeChecker, shortcut
from toolkit.robot import checker_for
from toolkit.robot.plans import certain_test

from .test_planning import UR5, WALL, A, B, dense, free_everywhere

DEFAULTS = PlannerSettings()

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
    passed = _test(robot, scene).free(robot.joints.angles(Q))
    np.testing.assert_array_equal(passed, checker.bounds.decide(Q) == FREE)
    assert 20 < passed.sum() < len(Q)  # both answers occur
    for q in Q[passed]:  # coal on every pair, one configuration at a time
        assert checker.first_collision(q) is None
    test, work = _test(robot, scene), _test(robot, scene)._work()
    first, second = test.packed.first, test.packed.second
    index = {(p.first, p.second): k for k, p in enumerate(checker.geom.collisionPairs)}
    data, gdata = robot.model.createData(), pin.GeometryData(checker.geom)
    rate = np.ones(len(first))  # every pair moves, one metre per unit of the stretch
    short = 1.0 - 1e-9  # the hair each pair's stretch is taken short

    def gaps_at(q, span, closest=0.0, moving=rate):
        until = np.full(len(first), -1.0)  # nothing carried: every pair measured
        ahead = gap_kernels.pair_gaps(q, test.packed, work.W, work.P, until, moving, 0.0,
                                      span, closest)  # fmt: skip
        return ahead, until / short

    for q in Q[passed][:40]:  # each pair's gap is a lower bound of coal's distance
        # a stretch no gap carries: every bound is asked, not only the cheap ones
        ahead, gaps = gaps_at(q, np.inf)
        pin.computeDistances(robot.model, data, checker.geom, gdata, q)
        exact = np.array([gdata.distanceResults[index[(int(f), int(g))]].min_distance
                          for f, g in zip(first, second, strict=True)])  # fmt: skip
        assert (0.0 < gaps).all() and (gaps <= exact + 1e-9).all()
        assert ahead == pytest.approx(gaps.min() * short, rel=1e-12)  # the nearest pair's
    for q in Q[~passed][:40]:
        assert gaps_at(q, 1.0)[0] == -1
    for q in Q[passed][:40]:  # a stretch of 1 mm, which the spheres about both boxes settle mostly
        ahead, gaps = gaps_at(q, 1e-3)
        pin.computeDistances(robot.model, data, checker.geom, gdata, q)
        exact = np.array([gdata.distanceResults[index[(int(f), int(g))]].min_distance
                          for f, g in zip(first, second, strict=True)])  # fmt: skip
        assert (1e-3 <= gaps * (1 + 1e-12)).all() and (gaps <= exact + 1e-9).all()
        assert ahead >= 1e-3 * short  # every pair carried the whole stretch, or further
        if exact.min() > 2e-3:  # no pair can keep a gap under the least one asked
            assert gaps_at(q, 1e-3, exact.min() + 1e-3)[0] == -1
        # nothing moves: no stretch is bounded, and the least gap asked binds no pair
        assert gaps_at(q, 1.0, 1.0, 0 * rate)[0] == np.inf
    # a pair whose last gap carries it past the stretch asked is not measured again: at a
    # configuration that collides, pairs all carried to 0.35 answer 0.35 - t, not -1
    inside = Q[~passed][0]
    until = np.full(len(first), 0.35)
    assert gap_kernels.pair_gaps(inside, test.packed, work.W, work.P, until, rate, 0.1, 0.2,
                                 0.0) == pytest.approx(0.25)  # fmt: skip
    until[:] = 0.25  # every pair must be measured again: the collision is found
    assert gap_kernels.pair_gaps(inside, test.packed, work.W, work.P, until, rate, 0.1, 0.2,
                                 0.0) == -1  # fmt: skip


@pytest.mark.parametrize("size", [1, 2, 255, 256, 257, 1000])
def test_the_nearest_node_is_the_one_a_plain_scan_finds(size):
    """The nearest-node scan over a tree's float32 copy, in blocks, finds the node a plain
    float64 scan finds (random nodes: no two as near), at and across block edges."""
    from numba import njit

    @njit
    def nearest(near, size, x, d):
        return kernels._nearest(near, size, x, d)

    rng = np.random.default_rng(size)
    nodes = rng.uniform(-3, 3, size=(size + 7, 7))  # room past the tree's size, unread
    near = np.ascontiguousarray(nodes.T, dtype=np.float32)
    d = np.empty(kernels.BLOCK, np.float32)
    for x in rng.uniform(-3, 3, size=(50, 7)):
        plain = np.linalg.norm(nodes[:size] - x, axis=1)
        got = nearest(near, size, x, d)
        assert 0 <= got < size
        assert plain[got] <= plain.min() * (1 + 1e-5) + 1e-6  # float32: ties within rounding


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
    got = kernels.edge_free(a, b, resolution, test._space(), work, np.empty(6), False)
    assert got == bool(test.free(points).all())
    if got:  # every configuration tested once, no more
        assert work.tested[0] == len(points)
    work = test._work()  # the end known free (a path's waypoint): every configuration but it
    got = kernels.edge_free(a, b, resolution, test._space(), work, np.empty(6), True)
    assert got == bool(test.free(points[:-1]).all())
    if got:
        assert work.tested[0] == len(points) - 1


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
    assert result.swept  # no escape: every edge certified over its whole motion
    assert free_everywhere(UR5, result.path, WALL)
    again = UR5.plan(A, B, scene=WALL, seed=1)
    np.testing.assert_array_equal(result.path, again.path)


def test_a_swept_path_is_certified_by_its_sweep_alone_and_coal_finds_it_free(monkeypatch):
    """The sweep on the covers is the final check of a swept path: the exact checker is
    not asked again (it is for a path that is not swept), and coal on every pair at a
    quarter degree finds the path free all the same."""
    checker = checker_for(UR5, WALL)
    asked: list[int] = []
    exact = checker.in_collision_many
    monkeypatch.setattr(checker, "in_collision_many", lambda Q: asked.append(len(Q)) or exact(Q))
    result = UR5.plan(A, B, scene=WALL, seed=1)
    assert result.success and result.verified and result.swept, result.reason
    assert asked == []  # neither the ends (the covers passed them) nor the path
    assert free_everywhere(UR5, result.path, WALL)
    monkeypatch.setattr(certain.CertainTest, "swept", lambda self, path: (False, 0))
    monkeypatch.setattr(certain.CertainTest, "sweeps", property(lambda self: False))
    again = UR5.plan(A, B, scene=WALL, seed=1)
    assert again.success and again.verified and not again.swept, again.reason
    assert sum(asked) >= len(again.path)  # the whole path, again on the exact shapes


def test_an_end_the_covers_pass_is_not_asked_of_coal_and_one_they_refuse_is(monkeypatch):
    """An end the covers refuse is asked of the batch check (coal on its undecided pairs);
    the single check, which names a pair, only where that finds a collision."""
    checker = checker_for(UR5, WALL)
    asked: list[np.ndarray] = []
    named: list[np.ndarray] = []
    many, first = checker.in_collision_many, checker.first_collision
    monkeypatch.setattr(checker, "in_collision_many", lambda Q: asked.append(Q) or many(Q))
    monkeypatch.setattr(checker, "first_collision", lambda q: named.append(q) or first(q))
    UR5.plan(A, B, scene=WALL, seed=1)
    assert asked == [] and named == []
    test = _test(UR5, WALL)
    # toward the wall from A: the first configuration the covers refuse is free on coal
    line = [(1 - t) * A + t * B for t in np.linspace(0.0, 1.0, 2000)]
    near = next(q for q in line if not test.free(UR5.joints.angles(q)[None])[0])
    assert not checker.in_collision(near)
    result = UR5.plan(near, A, scene=WALL, seed=1, time_limit=2.0)
    assert result.success, result.reason
    assert len(asked[0]) == 1 and np.array_equal(asked[0][0], near) and named == []
    inside = next(q for q in line if checker.in_collision(q))
    with pytest.raises(toolkit.InvalidParameterError, match=r"start collides: .* with wall"):
        UR5.plan(inside, A, scene=WALL, seed=1)
    assert len(named) == 1 and np.array_equal(named[0], inside)


def test_the_covers_search_checks_edges_coarser_where_its_path_is_certified_whole(monkeypatch):
    """Start and goal pass the covers: the search checks its edges at ``covers_coarser`` times
    the resolution, and the path it returns is certified over its whole motion all the
    same (free on coal at a quarter degree). With an end the covers refuse, at the
    resolution itself; the escape's segment was checked on the exact shapes, and the rest
    certified whole: nothing else is asked of them (every configuration coal saw lies
    within an escape's length of that end)."""
    import toolkit.planning as planning

    seen: list[float] = []
    real = certain.search
    monkeypatch.setattr(planning, "search", lambda *a, **k: seen.append(k["resolution"])
                        or real(*a, **k))  # fmt: skip
    result = UR5.plan(A, B, scene=WALL, seed=1)
    assert result.success and result.swept and result.escapes == 0, result.reason
    assert seen and all(r == DEFAULTS.covers_coarser * result.resolution for r in seen)
    assert free_everywhere(UR5, result.path, WALL)
    test, checker = _test(UR5, WALL), checker_for(UR5, WALL)
    line = [(1 - t) * A + t * B for t in np.linspace(0.0, 1.0, 2000)]
    near = next(q for q in line if not test.free(UR5.joints.angles(q)[None])[0])
    assert not checker.in_collision(near)
    seen.clear()
    asked: list[np.ndarray] = []
    exact = checker.in_collision_many
    monkeypatch.setattr(checker, "in_collision_many", lambda Q: asked.append(Q) or exact(Q))
    again = UR5.plan(near, A, scene=WALL, seed=1, time_limit=2.0)
    assert again.success and again.swept and again.escapes == 1, again.reason  # left by one
    assert seen and all(r == again.resolution for r in seen)
    coal = np.concatenate(asked)
    assert np.linalg.norm(coal - near, axis=1).max() <= max(DEFAULTS.escapes) + 1e-9
    assert np.linalg.norm(again.values[1] - again.values[0]) <= max(DEFAULTS.escapes) + 1e-12
    assert free_everywhere(UR5, again.path, WALL)


def test_a_covers_path_the_exact_check_refuses_is_planned_again_on_the_exact_shapes(
    monkeypatch,
):
    import toolkit.planning as planning

    calls: list[bool] = []
    real = planning._checked_whole

    def refuse_first(path, edges, collides, segments=None):
        ok, n = real(path, edges, collides, segments)
        calls.append(ok)
        return (False, n) if len(calls) == 1 else (ok, n)

    monkeypatch.setattr(planning, "_checked_whole", refuse_first)
    monkeypatch.setattr(certain.CertainTest, "swept", lambda self, path: (False, 0))
    monkeypatch.setattr(certain.CertainTest, "sweeps", property(lambda self: False))
    result = UR5.plan(A, B, scene=WALL, seed=1, time_limit=5.0)
    assert result.success and result.verified and result.search == "exact", result.reason
    assert len(calls) == 2 and not result.swept
    assert free_everywhere(UR5, result.path, WALL)


def test_a_search_past_its_node_budget_starts_again_and_stays_reproducible(monkeypatch):
    seen: list[int] = []
    real = certain._fresh_trees
    monkeypatch.setattr(certain, "_fresh_trees", lambda *a: seen.append(1) or real(*a))
    small = PlannerSettings(restart_nodes=16, chunk=4)  # the budget is looked at between chunks
    one = UR5.plan(A, B, scene=WALL, seed=3, simplify=False, settings=small)
    assert one.success and one.search == "covers", one.reason
    assert len(seen) >= 2  # the first trees, then at least one restart
    assert free_everywhere(UR5, one.path, WALL)
    again = UR5.plan(A, B, scene=WALL, seed=3, simplify=False, settings=small)
    np.testing.assert_array_equal(one.path, again.path)
    assert again.nodes == one.nodes  # every restart's nodes counted, the same each time


def test_the_search_stops_past_its_most_nodes():
    """No sample leaves the start (bounds closed there) and the wall blocks the straight
    line: only ``most`` ends the search, after the chunk that passes it (a search that
    ignored it would grow until its deadline, 20 s, many chunks)."""
    import time

    test = _test(UR5, WALL)
    a, b = UR5.joints.angles(A), UR5.joints.angles(B)
    path, goal, nodes, _ = certain.search(
        test, a, b[None], (a, a.copy()), deadline=time.perf_counter() + 20.0, seed=1,
        resolution=0.02, settings=DEFAULTS, simplify=False, most=3,
    )  # fmt: skip
    assert path is None and goal == -1 and 3 <= nodes <= 3 + 2 * DEFAULTS.chunk


def test_a_search_whose_trees_stop_growing_gives_up_after_stalled_calls(monkeypatch):
    """No sample leaves the start (bounds closed there) and the wall blocks the straight
    line: after the first call (the start's tree grows by the sample, the start itself)
    neither tree grows, and the search gives up after ``stalled`` calls of the compiled search
    in a row, not at its deadline (a minute here)."""
    import time

    calls: list[int] = []
    real = kernels.grow
    monkeypatch.setattr(kernels, "grow", lambda *a: calls.append(1) or real(*a))
    test = _test(UR5, WALL)
    a, b = UR5.joints.angles(A), UR5.joints.angles(B)
    begin = time.perf_counter()
    path, goal, nodes, _ = certain.search(
        test, a, b[None], (a, a.copy()), deadline=begin + 60.0, seed=1, resolution=0.02,
        settings=PlannerSettings(stalled=4), simplify=False,
    )  # fmt: skip
    assert path is None and goal == -1 and nodes == 3 and len(calls) == 1 + 4


def test_trees_that_fill_their_room_get_more():
    result = UR5.plan(A, B, scene=WALL, seed=1, simplify=False,
                      settings=PlannerSettings(capacity=4))  # fmt: skip
    assert result.success and result.search == "covers" and result.nodes > 4
    assert free_everywhere(UR5, result.path, WALL)


def _close_goal() -> np.ndarray:
    """A UR5 configuration free on the meshes that the covers do not clear (beside the wall)."""
    checker = checker_for(UR5, WALL)
    Q = UR5.random_q(4000, seed=12)
    close = Q[(checker.bounds.decide(Q) != FREE) & ~checker.in_collision_many(Q)]
    assert len(close), "no configuration free on the meshes but not on the covers"
    assert not _test(UR5, WALL).free(UR5.joints.angles(close[:1]))[0]
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
    assert np.linalg.norm(result.values[inner] - far) <= max(DEFAULTS.escapes) + 1e-12
    assert _test(UR5, WALL).free(result.values[[inner]])[0]
    assert result.swept and result.escapes == 1  # the rest certified whole, the escape not
    middle = result.values[:-1] if end == "goal" else result.values[1:]
    assert _test(UR5, WALL).swept(middle)[0]
    assert not _test(UR5, WALL).swept(result.values)[0]  # the escape's segment is not
    assert free_everywhere(UR5, result.path, WALL)


def test_where_no_escape_is_found_the_exact_search_answers():
    goal = _close_goal()
    result = UR5.plan(A, goal, scene=WALL, seed=2, time_limit=20,
                      settings=PlannerSettings(escapes=()))  # fmt: skip
    assert result.success and result.search == "exact", result.reason
    assert free_everywhere(UR5, result.path, WALL)


class _Counting:
    """A stand-in for the covers' test and the exact edges in :func:`certain.escape`: every
    try passes the test; the exact checker refuses its first ``refuse`` edges."""

    def __init__(self, refuse: int) -> None:
        self.refuse, self.sizes, self.edges = refuse, [], []

    def free(self, a: np.ndarray, b: np.ndarray | None = None) -> object:
        if b is None:  # the test: a batch of tries
            self.sizes.append(len(a))
            return np.ones(len(a), dtype=bool)
        self.edges.append(float(np.linalg.norm(b - a)))
        return len(self.edges) > self.refuse


def _escape(
    refuse: int, deadline: float = math.inf, settings: PlannerSettings = DEFAULTS
) -> tuple[np.ndarray | None, _Counting]:
    fake, q = _Counting(refuse), np.zeros(6)
    bounds = (np.full(6, -10.0), np.full(6, 10.0))
    out = certain.escape(fake, fake, q, bounds, np.random.default_rng(0), deadline,  # type: ignore[arg-type]
                         settings)  # fmt: skip
    return out, fake


def test_an_escape_tries_the_lengths_shortest_first_then_wider_rounds_of_directions():
    rounds = DEFAULTS.directions
    out, fake = _escape(refuse=0)  # the first try of the shortest length
    assert out is not None and fake.sizes == [rounds[0]] and len(fake.edges) == 1
    assert fake.edges[0] == pytest.approx(min(DEFAULTS.escapes))
    out, fake = _escape(refuse=rounds[0])  # the first length's tries refused: the next one
    assert out is not None and fake.sizes == [rounds[0]] * 2
    assert fake.edges[-1] == pytest.approx(sorted(DEFAULTS.escapes)[1])
    assert list(DEFAULTS.escapes) == sorted(DEFAULTS.escapes)
    assert list(rounds) == sorted(rounds)


def test_an_escape_asks_the_exact_checker_a_bounded_number_of_edges_and_stops_at_its_deadline():
    out, fake = _escape(refuse=10**9)  # the exact checker refuses everything
    assert out is None and len(fake.edges) == DEFAULTS.escape_edges
    out, fake = _escape(refuse=0, deadline=0.0)  # past its deadline: nothing asked
    assert out is None and fake.sizes == [] and fake.edges == []


def test_a_wider_round_of_directions_runs_after_the_first_round_fails():
    wide = PlannerSettings(escapes=(0.1,), escape_edges=10**6)
    out, fake = _escape(refuse=wide.directions[0], settings=wide)  # round one refused
    assert out is not None and fake.sizes == list(wide.directions[:2])
    assert len(fake.edges) == wide.directions[0] + 1


def test_an_arm_with_continuous_joints_plans_on_its_covers():
    test = _test(KINOVA, SHELF)
    Q = KINOVA.random_q(200, seed=3)
    q0, q1 = Q[test.free(KINOVA.joints.angles(Q))][:2]
    result = KINOVA.plan(q0, q1, scene=SHELF, seed=0)
    assert result.success and result.search == "covers", result.reason
    fine = KINOVA.joints.q_from_angles(dense(result.values, math.radians(0.25)))
    assert not any(KINOVA.collision_checker(SHELF).collisions(q) for q in fine)
    np.testing.assert_allclose(KINOVA.joints.q_from_angles(result.values), result.path, atol=1e-15)


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


PANDA = toolkit.load_example("panda")


def _tilted_arm() -> toolkit.Robot:
    """Three revolute joints about tilted axes (Pinocchio's RevoluteUnaligned), each child
    placed partly along its parent's axis, boxes as links."""
    import tempfile

    joints, links = [], ['<link name="base"/>']
    axes = ["0 0.6 0.8", "0.7071 0.7071 0", "0.2 -0.4 0.8944"]
    for i, axis in enumerate(axes):
        parent = "base" if i == 0 else f"l{i - 1}"
        joints.append(
            f'<joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="0.05 0.1 0.3" rpy="0.3 -0.2 0.5"/><axis xyz="{axis}"/>'
            '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        )
        links.append(
            f'<link name="l{i}"><collision><origin xyz="0.02 0.0 0.15" rpy="0.1 0 0"/>'
            '<geometry><box size="0.06 0.08 0.3"/></geometry></collision></link>'
        )
    urdf = f'<robot name="tilted">{"".join(links)}{"".join(joints)}</robot>'
    with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as f:
        f.write(urdf)
    robot = toolkit.load_urdf(f.name)
    kinds = {j.shortname() for j in robot.model.joints[1:]}
    assert kinds == {"JointModelRevoluteUnaligned"}, kinds
    return robot


TILTED = _tilted_arm()


@pytest.mark.parametrize("robot", [UR5, PANDA, KINOVA, TILTED],
                         ids=["ur5", "panda", "kinova", "tilted"])  # fmt: skip
@settings(max_examples=30, deadline=None)
@given(data=st.data())
def test_no_point_of_a_shape_moves_farther_along_an_edge_than_its_reach_says(robot, data):
    """Every corner of every robot shape's box (the box holds the shape, and a corner is
    the farthest of its points from any axis and origin) travels along a straight edge in
    joint values no farther than the reach's bound: the sum of each joint's step times the
    shape's distance from that joint's axis (origin, for a slide's 1 per step)."""
    lo, hi = value_bounds(robot)
    values = st.lists(st.floats(0, 1), min_size=len(lo), max_size=len(lo))
    a = lo + np.array(data.draw(values)) * (hi - lo)
    b = lo + np.array(data.draw(values)) * (hi - lo)
    test = _test(robot, WALL)
    checker = checker_for(robot, WALL)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    fine = robot.joints.q_from_angles(a + np.linspace(0, 1, 201)[:, None] * (b - a))
    for g, obj in enumerate(checker.geom.geometryObjects[: checker.robot_count]):
        box = checker.bounds.box[g]  # every corner of every robot shape's box
        local = box[:3] + (corners * box[12:]) @ box[3:12].reshape(3, 3).T
        track = np.array([_joint_points(robot, obj.parentJoint, q, local) for q in fine])
        travelled = np.linalg.norm(np.diff(track, axis=0), axis=2).sum(axis=0)
        moved = np.where(test.moves[g], test.reach[g], 0.0)  # the joints that move it
        bound = float(np.abs(b - a) @ moved)  # how far its points can move
        assert travelled.max() <= bound * (1 + 1e-9) + 1e-12  # + the FK's rounding


def test_an_edge_certified_swept_is_free_at_every_fine_step_on_the_meshes():
    test, checker = _test(UR5, WALL), checker_for(UR5, WALL)
    rng = np.random.default_rng(5)
    Q = UR5.random_q(400, seed=6)
    V = UR5.joints.angles(Q[test.free(UR5.joints.angles(Q))])
    certified = 0
    for a in V[:80]:
        b = a + rng.uniform(-0.4, 0.4, 6)
        ok, checked = test.swept(np.array([a, b]))
        assert checked >= 1
        if ok:  # certified: coal finds nothing at 0.05 degree steps
            certified += 1
            fine = UR5.joints.q_from_angles(dense(np.array([a, b]), math.radians(0.05)))
            assert not checker.in_collision_many(fine).any()
    assert 10 <= certified < 80  # both answers occur
    blocked = np.array([A, [0.0, -1.0, 1.5, -1.9, -1.57, 0.0]])  # into the wall
    assert not test.swept(UR5.joints.angles(blocked))[0]


def _joint_points(
    robot: toolkit.Robot, joint: int, q: np.ndarray, local: np.ndarray
) -> np.ndarray:  # fmt: skip
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    M = data.oMi[joint]
    return local @ M.rotation.T + M.translation


def _shortened(path: np.ndarray, got: np.ndarray, passes) -> None:
    """``got`` keeps ``path``'s ends and some of its waypoints in order, every cut (a
    segment that skips waypoints) passes, and it is no longer."""
    kept = [int(np.flatnonzero((path == w).all(axis=1))[0]) for w in got]
    assert kept[0] == 0 and kept[-1] == len(path) - 1 and kept == sorted(set(kept))
    cuts = [(i, j) for i, j in itertools.pairwise(kept) if j > i + 1]
    assert all(passes(path[i], path[j]) for i, j in cuts)
    length = lambda P: np.linalg.norm(np.diff(P, axis=0), axis=1).sum()  # noqa: E731
    assert length(got) <= length(path) + 1e-12


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_shortcut_keeps_waypoints_in_order_and_every_cut_passes(seed):
    """A path of random free waypoints around the wall (not itself free between them):
    the compiled and the Python shortcut keep its ends and some waypoints in order, every
    cut passes their check, and the first cuts go from each waypoint kept to the farthest
    one it sees, in both."""
    test, rng = _test(UR5, WALL), np.random.default_rng(seed)
    samples = rng.uniform(-np.pi, np.pi, size=(400, 6))
    path = np.concatenate([[A], samples[test.free(samples)][:12], [B]])
    resolution, space = math.radians(2.0), test._space()

    def passes(a, b):
        return bool(kernels.edge_free(a, b, resolution, space, test._work(), np.empty(6), True))

    got = kernels.shortcut(path, 0, resolution, space, test._work(), np.array([seed], np.uint64))
    _shortened(path, got, passes)
    kept = [int(np.flatnonzero((path == w).all(axis=1))[0]) for w in got]
    for i, j in itertools.pairwise(kept):  # none farther than j seen from i
        assert not any(passes(path[i], path[m]) for m in range(j + 1, len(path)))
    again = kernels.shortcut(path, 30, resolution, space, test._work(),
                             np.array([seed], np.uint64))  # fmt: skip
    _shortened(path, again, passes)
    edges = EdgeChecker(lambda V: ~test.free(V), resolution)
    plain = shortcut(path, edges, np.random.default_rng(seed), deadline=math.inf, tries=0)
    np.testing.assert_array_equal(plain, got)  # the same first cuts, the same check


@settings(max_examples=60, deadline=None)
@given(pairs=st.lists(st.tuples(st.integers(0, 5), st.integers(0, 9)), max_size=40))
def test_the_pair_runs_cover_every_pair_once_each_run_one_shape_against_consecutive_others(
    pairs,
):
    first = np.array([p[0] for p in pairs], dtype=np.int64)
    second = np.array([p[1] for p in pairs], dtype=np.int64)
    runs = bound_kernels.pair_runs(first, second)
    assert runs.shape == (len(runs), 2) and runs.dtype == np.int64
    covered = [k for start, length in runs.tolist() for k in range(start, start + length)]
    assert covered == list(range(len(pairs)))  # in order, each pair once
    for start, length in runs.tolist():
        assert length >= 1
        assert (first[start : start + length] == first[start]).all()
        assert (second[start : start + length] == second[start] + np.arange(length)).all()
        end = start + length  # maximal: the next pair would not extend the run
        assert end == len(pairs) or not (
            first[end] == first[start] and second[end] == second[start] + length
        )


def test_a_test_without_pairs_passes_every_configuration_and_the_runs_agree_with_pairs():
    """No checked pair (nothing to collide with): every configuration passes; and the test
    on runs gives the pre-filter's answer whatever order the pairs come in (shuffled: runs
    of one)."""
    test = _test(UR5, WALL)
    packed = test.packed.with_pairs(test.packed.first[:0], test.packed.second[:0])
    empty = certain.CertainTest(test.qcol, test.circle, test.nq, packed)
    V = UR5.joints.angles(UR5.random_q(50, seed=2))
    assert len(empty.runs) == 0 and empty.free(V).all()
    order = np.random.default_rng(5).permutation(len(test.packed.first))
    packed = test.packed.with_pairs(test.packed.first[order], test.packed.second[order])
    shuffled = certain.CertainTest(test.qcol, test.circle, test.nq, packed)
    assert len(shuffled.runs) > len(test.runs)
    V = UR5.joints.angles(UR5.random_q(300, seed=3))
    np.testing.assert_array_equal(shuffled.free(V), test.free(V))


def test_a_helical_joint_leaves_the_reach_unbounded_and_no_motion_certified():
    """A joint that both turns and slides (Pinocchio's helical; no URDF has one): the
    bound knows neither, so the shapes it moves get an infinite reach, and a certain test
    made on it certifies no whole motion (its paths are checked at configurations)."""
    from types import SimpleNamespace

    from toolkit.planning import reach

    model = pin.Model()
    first = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "turn")
    second = model.addJoint(first, pin.JointModelHZ(0.05),
                            pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.3])), "screw")  # fmt: skip
    box = np.zeros((2, 15))
    box[:, 3:12] = np.eye(3).ravel()
    box[:, :3] = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.2]]
    box[:, 12:15] = 0.05  # a cube of 0.1 m around a ball of 0.05 m: the ball bounds closer
    shapes = [SimpleNamespace(parentJoint=first), SimpleNamespace(parentJoint=second)]
    checker = SimpleNamespace(bounds=SimpleNamespace(box=box, radius=np.full((2, 2), 0.05)),
                              parts=SimpleNamespace(objects=shapes),
                              robot_count=2)  # fmt: skip
    robot = SimpleNamespace(model=model)
    far, moves = reach(robot, checker)
    assert moves.tolist() == [[True, False], [True, True]]
    assert far[0, 0] == pytest.approx(0.1 + 0.05)  # off the first axis: its box's centre
    assert far[1, 1] == math.inf  # the screw: no bound
    assert far[0, 1] == math.inf  # nor for a shape beside it, fixed to its parent
    # through the screw's origin, placed on the first axis: its distance from that origin
    assert far[1, 0] == pytest.approx(math.hypot(0.1, 0.2) + 0.05)
    t = _test(UR5, WALL)  # a test whose reach is not finite certifies no whole motion
    unbounded = t.reach.copy()
    unbounded[int(np.flatnonzero(t.moves[:, 0])[0]), 0] = math.inf  # a shape it moves
    test = certain.CertainTest(t.qcol, t.circle, t.nq, t.packed, unbounded, t.moves)
    assert t.sweeps and not test.sweeps
    assert test.swept(UR5.joints.angles(UR5.random_q(2, seed=1))) == (False, 0)


DOMAIN = (4.0, 1.0, DEFAULTS.domain[2])
"""The kernel's domain in radians (PlannerSettings.radii gives these on the Panda's box)."""


def _grow_once(test, trees, sizes, sample, side):
    """One round of the compiled search with every sample at ``sample`` (bounds closed
    there): (the status, the configurations tested)."""
    space, work = test._space(), test._work()
    rng, found, s = np.zeros(1, np.uint64), np.zeros(2, int), np.array([side])
    status = kernels.grow(trees, sizes, (sample, sample.copy()), (0.5, 0.02, DOMAIN),
                          space, work, rng, 1, s, found)  # fmt: skip
    return status, int(work.tested[0]), int(s[0])


def _trees(start, goals, cap=64):
    nodes, parent = np.zeros((2, cap, len(start))), np.full((2, cap), -1)
    nodes[0, 0], nodes[1, : len(goals)] = start, goals
    near = np.ascontiguousarray(nodes.transpose(0, 2, 1), dtype=np.float32)
    root = np.zeros((2, cap), int)
    root[1, : len(goals)] = np.arange(len(goals))
    trees = records.Trees(nodes, parent, root, near, np.full((2, cap), np.inf))
    return trees, np.array([1, len(goals)])


def test_the_compiled_search_extends_a_tree_again_while_it_is_at_most_half_the_other():
    test = _test(UR5, WALL)
    a, b = UR5.joints.angles(A), UR5.joints.angles(B)
    goals = b + 0.01 * np.arange(5)[:, None]  # 5 goals beyond the wall: their tree is larger
    turn = np.array([0.3, 0, 0, 0, 0, 0])  # the base turned away from the wall: free
    sample = a - turn
    assert test.free(np.linspace(a, sample, 20)).all()
    trees, sizes = _trees(a, goals)
    _, checks, side = _grow_once(test, trees, sizes, sample, side=1)  # tree 1's turn, but...
    np.testing.assert_array_equal(trees.nodes[0, 1], sample)  # ...the start's grew (1 <= 5 / 2)
    assert sizes[0] == 2 and checks > 0 and side == 1
    trees, sizes = _trees(a, goals[:1])  # trees of one node each: tree 1's turn kept
    assert test.free(np.linspace(b, b + turn, 20)).all()
    _grow_once(test, trees, sizes, b + turn, side=1)
    np.testing.assert_array_equal(trees.nodes[1, 1], b + turn)


def test_a_blocked_extension_gives_its_node_a_domain_and_samples_outside_it_are_not_tried():
    test = _test(UR5, WALL)
    b = UR5.joints.angles(B)
    # a free configuration whose step of 0.5 rad is blocked (found here, not assumed)
    rng = np.random.default_rng(4)
    for _ in range(2000):
        q = rng.uniform(-np.pi, np.pi, 6)
        d = rng.normal(size=6)
        ahead = q + 0.5 * d / np.linalg.norm(d)
        line = np.linspace(q, ahead, 30)
        if test.free(q[None])[0] and not test.free(line).all():
            break
    else:  # pragma: no cover - the wall blocks many steps
        pytest.fail("no blocked step found")
    trees, sizes = _trees(q, b[None])
    far = q + 10.0 * (ahead - q)  # the same direction, 5 rad away: stepped toward by 0.5
    status, checks, _ = _grow_once(test, trees, sizes, far, side=0)
    assert status == kernels.RUNNING and checks > 0 and sizes[0] == 1
    assert trees.radius[0, 0] == DOMAIN[0]  # the node's domain after its first block
    _, again, _ = _grow_once(test, trees, sizes, far, side=0)  # 5 rad > 4 rad: not tried
    assert again == 0 and sizes[0] == 1 and trees.radius[0, 0] == DOMAIN[0]
    inside = q + 6.0 * (ahead - q)  # 3 rad: tried, blocked again, the domain shrinks
    _, tried, _ = _grow_once(test, trees, sizes, inside, side=0)
    shrunk = DOMAIN[0] * (1 - DOMAIN[2])
    assert tried > 0 and trees.radius[0, 0] == pytest.approx(shrunk)
    trees.radius[0, 0] = 0.05  # a small domain: even a free sample beyond it is not tried
    away = q - 0.2 * (ahead - q)
    assert test.free(np.linspace(q, away, 10)).all()
    _, none, _ = _grow_once(test, trees, sizes, away, side=0)
    assert none == 0 and sizes[0] == 1
    trees.radius[0, 0] = 1.0  # within it: tried, passes, and the domain grows
    _, some, _ = _grow_once(test, trees, sizes, away, side=0)
    assert some > 0 and sizes[0] == 2 and trees.radius[0, 0] == pytest.approx(1 + DOMAIN[2])
    assert trees.radius[0, 1] == np.inf  # a new node's domain is unbounded


def test_the_robots_reach_rows_are_made_once_and_each_scenes_own_every_time(monkeypatch):
    """``reach`` keeps the robot's own shapes' rows (the same in every scene's checker):
    a second scene makes only its own rows, the kept rows equal rows made afresh, and an
    object attached to a link (a scene's shape that a joint moves) gets its rows."""
    from toolkit.planning import geometry

    robot = toolkit.load_example("ur5")
    monkeypatch.setattr(robot._caches, "reach", {})  # nothing kept yet
    held = toolkit.Scene().add_box("wall", [0.1, 1.2, 0.8], [0.45, 0.0, 0.4])  # WALL's own
    held.attach("tool", "wrist_3_link", "box", [0.05, 0.05, 0.2], np.eye(4))  # (not WALL)
    made: list[int] = []
    real = geometry._reach_rows

    def counted(facts, bounds, objects, shapes, nv):
        made.append(len(shapes))
        return real(facts, bounds, objects, shapes, nv)

    monkeypatch.setattr(geometry, "_reach_rows", counted)
    first = checker_for(robot, WALL)
    far, moves = geometry.reach(robot, first)
    count = first.robot_count
    assert made == [count, len(far) - count]  # the robot's rows, then the scene's
    made.clear()
    second = checker_for(robot, held)
    far2, moves2 = geometry.reach(robot, second)
    assert made == [len(far2) - count]  # the robot's rows kept
    np.testing.assert_array_equal(far2[:count], far[:count])
    np.testing.assert_array_equal(moves2[:count], moves[:count])
    facts = geometry._chain_facts(robot)
    fresh = real(facts, second.bounds, second.geom.geometryObjects, range(len(far2)), 6)
    np.testing.assert_array_equal(fresh[0], far2)
    np.testing.assert_array_equal(fresh[1], moves2)
    tool = [o.name for o in second.geom.geometryObjects].index("tool")
    assert moves2[tool].all() and (far2[tool] > 0).all()  # every joint moves the tool


def test_a_test_of_arrays_already_made_ready_for_does_not_call_the_kernels_again(monkeypatch):
    """``ready`` calls the kernels once per kind of arrays they take (a new scene's test
    of the same robot is of the same kind), and where the kind was not seen."""
    first = _test(UR5, WALL)
    first.ready()
    calls: list[int] = []
    real = kernels.free_rows
    monkeypatch.setattr(kernels, "free_rows", lambda *a: calls.append(1) or real(*a))
    fresh = certain.CertainTest(first.qcol, first.circle, first.nq, first.packed, first.reach,
                                first.moves)  # fmt: skip
    fresh.ready()
    assert calls == []
    monkeypatch.setattr(certain, "READY", set())  # no kind made ready yet in this process
    again = certain.CertainTest(first.qcol, first.circle, first.nq, first.packed, first.reach,
                                first.moves)  # fmt: skip
    again.ready()
    assert calls == [1] and len(certain.READY) == 1


def _length(P: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())


def test_cut_corners_keep_the_ends_shorten_the_path_and_stay_certified():
    """A certified zigzag around the wall: its corners cut (Chaikin's points, half or a
    quarter of the way) where the cut is certified over its whole motion; the path keeps
    its ends, is no longer (shorter here), every segment is certified again, and coal finds
    it free at a quarter degree. Zero passes give the path back."""
    test = _test(UR5, WALL)
    result = UR5.plan(A, B, scene=WALL, seed=1, simplify=False)
    assert result.success and result.swept
    path = UR5.joints.angles(result.path)
    assert len(path) >= 3
    cut, checked = test.cut_corners(path, 2)
    assert checked > 0
    np.testing.assert_array_equal(cut[[0, -1]], path[[0, -1]])
    assert _length(cut) < _length(path) - 1e-6
    assert test.swept(cut)[0]
    assert free_everywhere(UR5, UR5.joints.q_from_angles(cut), WALL)
    same, none = test.cut_corners(path, 0)
    assert same is path and none == 0


def test_a_corner_is_cut_at_half_else_a_quarter_else_kept_as_its_sweeps_say():
    """Corners a -> c -> b of plans around the wall whose two segments are certified: the
    corner is replaced by the points half way to A and B where
    that cut is certified, else a quarter of the way, else kept; both a cut and a kept
    corner occur."""
    test = _test(UR5, WALL)
    assert not test.swept(UR5.joints.angles(np.array([A, B])))[0]
    seen = set()
    corners = []
    for seed in range(1, 5):  # corners of waypoints of plans around the wall, unshortened
        raw = UR5.plan(A, B, scene=WALL, seed=seed, simplify=False)
        P = UR5.joints.angles(raw.path)
        corners += [P[[i, j, k]] for i, j, k in itertools.combinations(range(len(P)), 3)]
    for a, c, b in corners:
        if not test.swept(np.array([a, c, b]))[0]:
            continue
        want = np.array([a, c, b])
        whole = _length(want)
        for share in (0.5, 0.25):
            p, q = c + share * (a - c), c + share * (b - c)
            if _length(np.array([p, c, q])) - _length(np.array([p, q])) < kernels.WORTH * whole:
                break
            if test.swept(np.array([p, q]))[0]:
                want = np.array([a, p, q, b])
                break
        got, _ = test.cut_corners(np.array([a, c, b]), 1)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-15)
        seen.add(len(got))
        if seen == {3, 4}:
            break
    assert seen == {3, 4}
