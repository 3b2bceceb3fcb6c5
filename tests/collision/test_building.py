"""A checker made for a new scene (toolkit.collision.checker and bounds): what it reads
fast gives what the plain reading gives. The pairs from Pinocchio's pair table equal the
pairs read one by one; the shapes' rows made in one pass equal each shape's placement
applied to its box; the robot's rows kept across scenes equal rows made afresh; the fixed
pairs asked of coal only where the spheres about their boxes overlap give the hits and
the nearest distance that coal gives on every fixed pair."""

from __future__ import annotations

import coal
import numpy as np
import pytest

import toolkit
from toolkit import Scene
from toolkit.collision import bounds as _bounds
from toolkit.collision.checker import TOUCH, Checker
from toolkit.collision.scene import SUPPORT_SLACK

UR5 = toolkit.load_example("ur5")
PANDA = toolkit.load_example("panda")


def _scene(seed: int, near: float = 0.4) -> Scene:
    """Boxes, spheres and cylinders, some fixed about the base (some supports, some
    inside it), one attached to the tool."""
    rng = np.random.default_rng(seed)
    scene = Scene()
    if seed % 3 == 0:  # a floor (a half-space: no finite box), entered or not
        scene.add_floor(float(rng.uniform(-0.02, 0.01)))
    for i in range(int(rng.integers(3, 9))):
        kind = i % 3
        centre = rng.uniform(-near, near, 3)
        if kind == 0:
            support = bool(rng.random() < 0.4)
            scene.add_box(f"box{i}", rng.uniform(0.02, 0.4, 3), centre, support=support)
        elif kind == 1:
            scene.add_sphere(f"ball{i}", float(rng.uniform(0.02, 0.2)), centre)
        else:
            scene.add_cylinder(f"can{i}", float(rng.uniform(0.02, 0.1)),
                               float(rng.uniform(0.05, 0.3)), centre)  # fmt: skip
    return scene


def _plain_static(checker: Checker) -> tuple[list[tuple[str, str]], tuple[float, tuple[str, str]]]:
    """Every fixed pair asked of coal, as the checker did before it skipped any."""
    hits, nearest = [], (float("inf"), ("", ""))
    for i, k, support in checker._static:
        a, b = checker.geom.geometryObjects[i], checker.geom.geometryObjects[k]
        result = coal.DistanceResult()
        where = [coal.Transform3s(o.placement.rotation, o.placement.translation) for o in (a, b)]
        coal.distance(a.geometry, where[0], b.geometry, where[1], coal.DistanceRequest(), result)
        d, pair = float(result.min_distance), (checker.names[i], checker.names[k])
        if d < (-SUPPORT_SLACK if support else -TOUCH):
            hits.append(pair)
        if not support or d < -SUPPORT_SLACK:
            nearest = min(nearest, (d, pair))
    return list(dict.fromkeys(hits)), nearest


@pytest.mark.parametrize("robot", [UR5, PANDA], ids=["ur5", "panda"])
@pytest.mark.parametrize("seed", range(12))
def test_a_new_scenes_checker_reads_what_the_plain_reading_gives(robot, seed):
    scene = _scene(seed)
    checker = robot.collision_checker(scene)
    geom = checker.geom
    first, second = _bounds.pair_arrays(geom)  # the pair table
    plain = np.array([(p.first, p.second) for p in geom.collisionPairs]).reshape(-1, 2)
    np.testing.assert_array_equal(first, plain[:, 0])
    np.testing.assert_array_equal(second, plain[:, 1])
    bounds = checker.bounds
    np.testing.assert_array_equal(bounds.first, plain[:, 0])
    afresh = _bounds.Bounds(geom, robot.kinematics, checker.robot_count)  # no rows kept
    for kept, made in zip((bounds.row, bounds.box, bounds.radius),
                          (afresh.row, afresh.box, afresh.radius), strict=True):  # fmt: skip
        np.testing.assert_array_equal(kept, made)
    for g, obj in enumerate(geom.geometryObjects):  # each row: the box placed by hand
        low, high = _bounds.local_box(obj.geometry)
        M = obj.placement
        np.testing.assert_allclose(bounds.box[g, :3], M.act((low + high) / 2), atol=1e-15)
        np.testing.assert_array_equal(bounds.box[g, 3:12], np.asarray(M.rotation).ravel())
        np.testing.assert_array_equal(bounds.box[g, 12:], (high - low) / 2)
        assert bounds.radius[g, 0] == pytest.approx(np.linalg.norm(high - low) / 2, rel=1e-15)
    hits, nearest = _plain_static(checker)
    assert list(checker.base_hits) == hits
    assert checker.base_distance == nearest


def test_the_fixed_pairs_cover_every_case():
    """Across the scenes above: fixed pairs that collide, supports entered and touched,
    pairs whose spheres overlap and pairs far apart all occur (the test above is not
    passing on one kind alone)."""
    kinds = set()
    for seed in range(12):
        for robot in (UR5, PANDA):
            checker = robot.collision_checker(_scene(seed))
            gaps = checker._static_gaps()
            for n, (_, _, support) in enumerate(checker._static):
                kinds.add(("support" if support else "plain", bool(gaps[n] < 0)))
            kinds.add(("hit", bool(checker.base_hits)))
    assert kinds >= {("support", True), ("support", False), ("plain", True), ("plain", False),
                     ("hit", True), ("hit", False)}  # fmt: skip


def test_a_scene_far_from_the_base_asks_coal_nothing(monkeypatch):
    """An object within the arm's reach but apart from its base: coal is not asked about
    the fixed pair when the checker is built, only at the first ``base_distance``; one
    beyond the arm's reach is not built into the checker at all."""
    calls = []
    monkeypatch.setattr(Checker, "_static_distance", lambda self, n: calls.append(n) or 1.0)
    near = Scene().add_box("near", [0.1, 0.1, 0.1], [0.7, 0.0, 0.0])
    checker = UR5.collision_checker(near)
    assert checker.base_hits == [] and calls == [] and not checker.out_of_reach
    assert checker.base_distance[1] == ("base_link", "near") and calls == [0]
    far = Scene().add_box("far", [0.1, 0.1, 0.1], [3.0, 0.0, 0.0])
    beyond = UR5.collision_checker(far)
    assert beyond.out_of_reach == ["far"] and beyond.base_distance[0] == np.inf
    assert calls == [0]


CUBE = toolkit.load_urdf(
    """<robot name="cube">
  <link name="base">
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
  <link name="arm">
    <collision><origin xyz="0 0 0.5"/><geometry><box size="0.05 0.05 0.3"/></geometry></collision>
  </link>
  <joint name="turn" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>""",
    tip="arm",
)


@pytest.mark.parametrize("depth", [0.001, -0.001, 0.0, 0.03])
@pytest.mark.parametrize("support", [False, True])
def test_cubes_corner_to_corner_are_hits_exactly_where_coal_says(depth, support):
    """A cube on the base's cube, corner to corner along their common diagonal, entering it
    by ``depth`` (negative: apart): the spheres about the two boxes then overlap by just
    ``depth``, the case where skipping coal is closest to wrong."""
    half = 0.05  # the scene's cube; the base's is 0.1 a side
    diagonal = np.ones(3) / np.sqrt(3)
    centre = diagonal * ((0.1 + half) * np.sqrt(3) - depth)
    scene = Scene().add_box("cube", [2 * half] * 3, centre, support=support)
    checker = CUBE.collision_checker(scene)
    hits, nearest = _plain_static(checker)
    assert list(checker.base_hits) == hits
    assert checker.base_distance == nearest
    assert checker._static_gaps()[0] == pytest.approx(-depth, abs=1e-8)
    entered = depth > (SUPPORT_SLACK if support else 0.0)
    assert bool(hits) == entered


def test_a_fixed_pair_without_a_finite_bound_is_asked_of_coal(monkeypatch):
    """A shape whose box is not finite (a gap of NaN) is never taken as apart."""
    monkeypatch.setattr(Checker, "_static_gaps", lambda self: np.full(len(self._static), np.nan))
    hit = False
    for seed in range(6):
        checker = Checker(UR5, _scene(seed))  # made here, not one the robot keeps
        hits, nearest = _plain_static(checker)
        hit = hit or bool(hits)
        assert list(checker.base_hits) == hits
        assert checker.base_distance == nearest
    assert hit


def _scattered(count: int, seed: int) -> Scene:
    rng = np.random.default_rng(seed)
    scene = Scene()
    for i in range(count):
        centre = rng.uniform([-3.0, -3.0, -0.5], [3.0, 3.0, 2.5])
        scene.add_box(f"b{i}", rng.uniform(0.02, 0.3, 3), centre)
    return scene


def test_objects_out_of_the_robots_reach_are_left_out_and_change_no_answer(monkeypatch):
    """The broad phase: a fixed object whose bounding sphere lies beyond every point the
    robot's shapes can reach (each shape's sphere grown by the joint placements up to the
    base) is never checked; the answers equal those of a checker that keeps every object,
    on random configurations and on configurations reaching out to the near boxes."""
    import toolkit.collision.checker as checker_module

    scene = _scattered(400, 5)
    near = Checker(UR5, scene)
    assert 0 < len(near.out_of_reach) < len(scene)  # some far, some near
    centre, radius = checker_module.robot_reach(UR5.model, near.geom)
    for q in UR5.random_q(300, seed=1):  # the reach bound holds at the tool
        assert np.linalg.norm(UR5.fk(q)[:3, 3] - centre) <= radius
    monkeypatch.setattr(checker_module, "robot_reach", lambda model, geom: None)
    every = Checker(UR5, scene)
    assert not every.out_of_reach
    assert len(every.geom.geometryObjects) > len(near.geom.geometryObjects)
    Q = UR5.random_q(600, seed=2)
    np.testing.assert_array_equal(near.in_collision_many(Q), every.in_collision_many(Q))
    assert near.in_collision_many(Q).any() and not near.in_collision_many(Q).all()


def test_a_scene_of_5000_boxes_builds_only_what_the_robot_can_reach():
    scene = _scattered(5000, 6)
    checker = UR5.collision_checker(scene)
    kept = len(checker.geom.geometryObjects) - checker.robot_count
    assert kept + len(checker.out_of_reach) == 5000 and kept < 1500
