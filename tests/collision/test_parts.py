"""A scene of more objects than one part takes (toolkit.collision.parts): the checker in
parts answers every query as the checker in one part, pair for pair, and plans the same,
certified the same way (PART made small here, so that 40 boxes make five parts)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import toolkit
from toolkit.collision import Checker, parts

UR5 = toolkit.load_example("ur5")


def _scene() -> toolkit.Scene:
    """40 small boxes around the UR5, within its reach, and a floor."""
    rng = np.random.default_rng(3)
    scene = toolkit.Scene().add_floor(-0.01)
    for i in range(40):
        angle, radius, z = rng.uniform(-np.pi, np.pi), rng.uniform(0.35, 0.7), rng.uniform(0, 0.8)
        scene.add_box(f"b{i}", [0.04] * 3, [radius * np.cos(angle), radius * np.sin(angle), z])
    return scene


@pytest.fixture(scope="module")
def both() -> tuple[Checker, Checker]:
    scene = _scene()
    one = Checker(UR5, scene)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(parts, "PART", 8)
        patch.setattr(toolkit.collision.checker, "PART", 8)
        many = Checker(UR5, scene)
    return one, many


def test_the_parts_hold_the_same_objects_and_pairs(both):
    one, many = both
    assert len(one.parts.parts) == 1 and len(many.parts.parts) == 6  # 41 objects in
    assert one.names == many.names and one.out_of_reach == many.out_of_reach
    pairs = lambda c: {c.pair_names(k) for k in range(len(c.parts.first))}  # noqa: E731
    assert pairs(one) == pairs(many) and len(one.parts.first) == len(many.parts.first)
    np.testing.assert_array_equal(one.bounds.box, many.bounds.box)
    assert sorted(zip(one.bounds.first, one.bounds.second, strict=True)) == sorted(
        zip(many.bounds.first, many.bounds.second, strict=True))  # fmt: skip


def test_every_query_answers_as_one_part(both):
    one, many = both
    Q = UR5.random_q(300, seed=4)
    flags = one.in_collision_many(Q)
    assert 0 < flags.sum() < len(Q)
    np.testing.assert_array_equal(flags, many.in_collision_many(Q))
    np.testing.assert_array_equal(one._exact_many(Q), many._exact_many(Q))
    for q in Q[:60]:
        assert one.in_collision(q) == many.in_collision(q)
        assert sorted(one.collisions(q)) == sorted(many.collisions(q))
        assert (one.first_collision(q) is None) == (many.first_collision(q) is None)
        d1, d2 = one.min_distance(q), many.min_distance(q)
        assert d1[0] == pytest.approx(d2[0], abs=1e-12)


def _plan(checker: Checker, start: np.ndarray, goal: np.ndarray):
    """``UR5.plan`` on ``checker`` (the robot's own, for the scene, stood in)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(toolkit.robot.plans, "checker_for", lambda robot, scene, until=None: checker)
        return UR5.plan(start, goal, scene=_scene(), seed=0, time_limit=5.0)


def test_a_plan_among_the_parts_is_the_same_and_certified(both):
    """The same start and goal, planned on either checker: the same path (the same
    answers, the same random stream), certified over its whole motion, and free when
    sampled at a quarter degree."""
    one, many = both
    Q = UR5.random_q(400, seed=5)
    free = Q[~one.in_collision_many(Q)]
    start = free[0]
    near = free[np.argsort(np.linalg.norm(free - start, axis=1))[1:]]
    line = lambda g: np.linspace(start, g, 200)  # noqa: E731
    goal = next(g for g in near if one.in_collision_many(line(g)).any())  # a detour needed
    first, second = _plan(one, start, goal), _plan(many, start, goal)
    assert first.success and first.swept, first.reason
    np.testing.assert_array_equal(first.path, second.path)
    assert second.certificate == first.certificate
    step = np.radians(0.25)
    for a, b in zip(second.path[:-1], second.path[1:], strict=True):
        k = max(2, int(np.ceil(np.abs(b - a).max() / step)) + 1)
        assert not many.in_collision_many(np.linspace(a, b, k)).any()


def _unordered(pairs: list[tuple[str, str]]) -> list[tuple[str, ...]]:
    return sorted(tuple(sorted(p)) for p in pairs)


def test_attached_objects_are_in_every_part():
    """A tool attached to the wrist pairs with every fixed object, whichever part holds
    it: the parts put the attached objects first, a copy in each part, and answer as one
    model (the same pairs by name, the same flags, collisions and distances)."""
    scene = _scene().attach("tool", "tool0", "cylinder", [0.03, 0.2], [0.0, 0.0, 0.1])
    one = Checker(UR5, scene)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(toolkit.collision.checker, "PART", 8)
        many = Checker(UR5, scene)
    assert len(many.parts.parts) == 6 and many.names[many.robot_count] == "tool"
    assert all(p.ngeoms > many.robot_count for p in many.parts.parts)
    names = lambda c: sorted(tuple(sorted(c.pair_names(k)))  # noqa: E731
                             for k in range(len(c.parts.first)))  # fmt: skip
    assert names(one) == names(many)
    assert sum("tool" in pair for pair in names(many)) > 40  # the tool against every box
    Q = UR5.random_q(300, seed=6)
    np.testing.assert_array_equal(one.in_collision_many(Q), many.in_collision_many(Q))
    hits = 0
    for q in Q[:80]:
        assert _unordered(one.collisions(q)) == _unordered(many.collisions(q))
        d1, d2 = one.min_distance(q)[0], many.min_distance(q)[0]
        if d1 > 0:  # coal's answer depends on which shape it is handed first: within its
            assert d2 == pytest.approx(d1, abs=1e-6)  # GJK tolerance (1e-6) when apart
        else:  # a penetration's depth, more so
            assert d2 <= 0
        hits += any("tool" in pair for pair in one.collisions(q))
    assert hits  # the tool meets something at some of them


def test_the_hulls_lower_bounds_never_exceed_coals_distances(both):
    """Parts.lower_bounds: the distance of two meshes' convex hulls is taken where it
    carries what is asked (a mesh lies in its hull: never more than the meshes' own
    distance), and coal's distance on the shapes where it does not; in parts as in one."""
    one, _ = both
    Q = UR5.random_q(40, seed=9)
    pairs = np.arange(len(one.parts.first))
    hulled = 0
    for q in Q:
        exact = one.parts.distances(q, pairs)
        for checker in both:
            low = checker.parts.lower_bounds(q, pairs, np.zeros(len(pairs)))
            assert np.all(low <= exact + 2e-6 + 2e-6 * exact)  # GJK's, as the sweep takes off
            hulled += int(np.sum(low < exact - 1e-6))
        # asked for more than any distance, a fresh pair answers coal's own distance
        fresh = Checker(UR5, toolkit.Scene()) if q is Q[0] else None
        if fresh is not None:
            own = np.arange(len(fresh.parts.first))
            np.testing.assert_allclose(fresh.parts.lower_bounds(q, own, np.full(len(own), 9.0)),
                                       fresh.parts.distances(q, own), atol=1e-12)  # fmt: skip
    assert hulled > 0  # the hulls answered some pairs, nearer than the meshes


def _mesh(points: np.ndarray, triangles: np.ndarray):
    import coal

    mesh = coal.BVHModelOBBRSS()
    mesh.beginModel(len(triangles), len(points))
    mesh.addVertices(points)
    mesh.addTriangles(triangles)
    mesh.endModel()
    return mesh


def test_a_hull_is_made_of_a_solid_mesh_and_not_of_a_flat_one():
    """hull_of: a cube's mesh gives its 8 corners; a flat mesh (qhull crashed the process on
    one) and a shape that is not a mesh give none."""
    import coal

    corners = np.array(list(itertools.product([0.0, 1.0], repeat=3)))
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7],
                      [1, 7, 3]])  # fmt: skip
    hull = parts.hull_of(_mesh(corners, faces))
    assert hull is not None and hull.num_points == 8
    flat = corners[:4]  # the face x = 0: four points in a plane
    assert parts.hull_of(_mesh(flat, np.array([[0, 1, 3], [0, 3, 2]]))) is None
    assert parts.hull_of(coal.Box(1.0, 1.0, 1.0)) is None
