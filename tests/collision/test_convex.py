"""Compiled lower bounds of two convex point sets' distance (toolkit.collision.convex_kernels)
and a robot's shapes as such sets (toolkit.collision.convex): the bound never exceeds the
distance coal finds (on random point clouds; on every pair of a robot's own meshes at
random configurations), reaches it where the sets are apart, and spares the exact
certificate coal's calls."""

from __future__ import annotations

import coal
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit.collision import convex_kernels, gap_kernels
from toolkit.collision.convex import convex_sets, has_set
from toolkit.collision.pieces import convex_hull
from toolkit.planning.sweep import ExactSweep
from toolkit.robot import checker_for
from toolkit.robot.plans import certain_test

UR10 = toolkit.load_example("ur10")
PANDA = toolkit.load_example("panda")


def _placed(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """A frame table of two rows, row 0 at (R, t), row 1 the world's."""
    W = np.zeros((2, 15))
    W[0, :9], W[0, 9:12] = R.ravel(), t
    W[1, :9] = np.eye(3).ravel()
    return W


def _coal_distance(A: np.ndarray, B: np.ndarray) -> float:
    ha, hb = convex_hull(A), convex_hull(B)
    result = coal.DistanceResult()
    coal.distance(ha, coal.Transform3s(), hb, coal.Transform3s(), coal.DistanceRequest(), result)
    return float(result.min_distance)


def _rotation(rng: np.random.Generator) -> np.ndarray:
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31), st.floats(-0.3, 1.5))
def test_the_bound_never_exceeds_the_distance_and_reaches_it_when_apart(seed, offset):
    """Two random clouds (one in a turned, moved frame) at any offset, overlapping or
    apart: the bound is at most coal's distance of their hulls, and within 1e-6 of it where
    they are apart (GJK run to its end: no target)."""
    rng = np.random.default_rng(seed)
    A, B = rng.normal(size=(rng.integers(4, 60), 3)), rng.normal(size=(rng.integers(4, 60), 3))
    R, t = _rotation(rng), np.array([2.0 + 4.0 * offset, 0.3, -0.2])
    W = _placed(R, t)
    verts = np.ascontiguousarray(np.concatenate([A, B]))
    d = np.zeros(3)
    lower = convex_kernels.set_lower(W, 0, 1, verts, 0, len(A), len(A), len(A) + len(B), d,
                                     np.inf, convex_kernels.scratch())  # fmt: skip
    exact = _coal_distance(A @ R.T + t, B)
    assert lower <= max(exact, 0.0) + 1e-9
    if exact > 1e-3:
        assert lower >= exact - 1e-6
        assert abs(np.linalg.norm(d) - 1.0) < 1e-12  # the direction kept is a unit one


def test_a_target_stops_the_search_early_with_a_bound_above_it():
    """Asked only to prove a small gap, the bound stops at or above it (and below the
    distance)."""
    rng = np.random.default_rng(3)
    A, B = rng.normal(size=(40, 3)), rng.normal(size=(40, 3)) + np.array([6.0, 0, 0])
    W = _placed(np.eye(3), np.zeros(3))
    verts = np.ascontiguousarray(np.concatenate([A, B]))
    lower = convex_kernels.set_lower(W, 0, 0, verts, 0, 40, 40, 80, np.zeros(3), 0.5,
                                     convex_kernels.scratch())  # fmt: skip
    assert 0.5 <= lower <= _coal_distance(A, B) + 1e-9


def _bounded_ratios(robot, checker, sets, ks: np.ndarray, Q: np.ndarray) -> list[float]:
    """At each configuration of Q, the compiled bound of each pair of ``ks`` (run to its
    end: no need) against coal's distance of the shapes themselves: asserted never above
    it; the bound's share of the distance where the pair is more than a millimetre apart."""
    packed = checker.bounds.packed()
    K = len(packed.first)
    W, P = np.empty((packed.ints.shape[0] + 1, 15)), np.full((len(packed.row), 12), np.nan)
    dirs = np.zeros((K, 1 + convex_kernels.PIECES**2, 3))
    ratios: list[float] = []
    for q in Q:
        gap_kernels.pair_bounds(q, packed, W, P, np.empty(K), np.zeros(K))
        gaps = np.full(K, -np.inf)
        convex_kernels.convex_gaps(W, packed.row, P, sets, packed.first, packed.second, ks,
                                   np.full(K, np.inf), gaps, dirs)  # fmt: skip
        exact = checker.parts.distances(q, ks)
        assert np.all(gaps[ks] <= np.maximum(exact, 0.0)), robot.name
        apart = exact > 1e-3
        ratios += list(gaps[ks][apart] / exact[apart])
    return ratios


@pytest.mark.parametrize("robot", [UR10, PANDA], ids=["ur10", "panda"])
def test_a_robots_meshes_bounds_never_exceed_coals_distance(robot):
    """Every pair of the robot's own shapes that are both convex sets, at 80 random
    configurations: the compiled bound (hulls, then pieces) is at most coal's distance of
    the meshes (less nothing), and where the pair is more than a millimetre apart the
    bound is positive at the median and within 0.9 of the distance at the median."""
    checker = checker_for(robot, toolkit.Scene())
    packed = checker.bounds.packed()
    sets = convex_sets(checker.parts.shapes, checker.robot_count)
    ks = np.flatnonzero(has_set(sets, packed.first) & has_set(sets, packed.second))
    assert ks.size >= 0.8 * len(packed.first)
    ratios = _bounded_ratios(robot, checker, sets, ks, robot.random_q(80, seed=5))
    assert np.median(ratios) >= 0.9


def test_a_box_is_its_corners_and_a_sphere_has_no_set():
    """A box shape's set is its 8 corners in its joint's frame; a sphere gets none (coal
    answers for it)."""
    import pinocchio as pin

    geom = pin.GeometryModel()
    M = pin.SE3(np.eye(3), np.array([0.1, 0.2, 0.3]))
    geom.addGeometryObject(pin.GeometryObject("box", 0, M, coal.Box(0.2, 0.4, 0.6)))
    geom.addGeometryObject(pin.GeometryObject("ball", 0, M, coal.Sphere(0.1)))
    sets = convex_sets(geom, 2)
    assert sets.sets[1, 0] == -1 and sets.sets[0, 0] == 0
    corners = sets.verts[sets.vstart[0] : sets.vstart[1]]
    assert corners.shape == (8, 3)
    assert np.allclose(corners.min(axis=0), [0.0, 0.0, 0.0])
    assert np.allclose(corners.max(axis=0), [0.2, 0.4, 0.6])


def test_the_exact_certificate_asks_coal_less_with_the_sets():
    """The UR10's whole-motion certificate over random segments among its own pairs: the
    same answers with the convex sets as without them (an empty set list), and far fewer
    pairs asked of coal. Fails where the sets are not read."""
    checker = checker_for(UR10, toolkit.Scene())
    test = certain_test(UR10, checker)
    assert test is not None and test.sweeps
    none = convex_sets(checker.parts.shapes, 0)
    with_sets = ExactSweep(checker, test, UR10.joints.q_from_angles)
    without = ExactSweep(checker, test, UR10.joints.q_from_angles, convex=none)
    Q = UR10.random_q(24, seed=8)
    for a, b in zip(Q[::2], Q[1::2], strict=True):
        a, b = UR10.joints.angles(a), UR10.joints.angles(b)
        step = 0.3 * (b - a) / max(np.linalg.norm(b - a), 1e-9)
        assert with_sets(a, a + step) == without(a, a + step)
    assert with_sets.asked < 0.5 * without.asked, (with_sets.asked, without.asked)


def test_a_scenes_boxes_and_cylinders_are_sets_and_their_bounds_never_exceed_coals():
    """A scene's box and cylinder (a prism about it, which holds it) are convex sets beside
    the robot's (kept per robot): the bound of every robot-scene pair at 60 random
    configurations is at most coal's distance of the shapes themselves, and within 2 % of
    it at the median where they are apart (the prism's corners lie 1.9 % outside the
    circle)."""
    from toolkit.robot.deferral import robot_convex

    scene = (toolkit.Scene().add_box("block", [0.3, 0.2, 0.4], [0.6, 0.2, 0.3])
             .add_cylinder("can", 0.05, 0.3, [0.2, -0.6, 0.4]))  # fmt: skip
    checker = checker_for(UR10, scene)
    sets = robot_convex(UR10, checker)
    packed = checker.bounds.packed()
    count = checker.robot_count
    scene_pairs = np.flatnonzero(np.maximum(packed.first, packed.second) >= count)
    ks = scene_pairs[has_set(sets, packed.first[scene_pairs])
                     & has_set(sets, packed.second[scene_pairs])]  # fmt: skip
    assert has_set(sets, np.array([count, count + 1])).all()  # the block and the can
    assert len(ks) >= 0.8 * len(scene_pairs)
    ratios = _bounded_ratios(UR10, checker, sets, ks, UR10.random_q(60, seed=2))
    assert np.median(ratios) >= 0.98


def test_a_robots_sets_are_made_once_for_every_scene_and_hold_its_own_shapes():
    """The robot's convex sets are kept per robot and shape set (one entry whatever the
    scene), under a key naming its shapes themselves, and the sets of a scene's checker
    begin with them."""
    from toolkit.robot.deferral import robot_convex

    robot = toolkit.load_example("ur5")
    scenes = (toolkit.Scene(), toolkit.Scene().add_box("b", [0.1] * 3, [0.5, 0.5, 0.5]))
    made = [robot_convex(robot, checker_for(robot, scene)) for scene in scenes]
    keys = [k for k in robot._caches.reach if isinstance(k, tuple) and k[0] == "convex"]
    assert len(keys) == 1
    checker = checker_for(robot, toolkit.Scene())
    addresses = [int(o.geometry.id()) for o in checker.geom.geometryObjects[: checker.robot_count]]
    assert list(keys[0][-1]) == addresses
    count = len(made[0].sets)
    np.testing.assert_array_equal(made[1].sets[:count], made[0].sets)
    np.testing.assert_array_equal(made[1].verts[: len(made[0].verts)], made[0].verts)
    assert has_set(made[1], np.array([count]))[0]  # the box: a set of the scene's
