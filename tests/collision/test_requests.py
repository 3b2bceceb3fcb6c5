"""The exact checker's answers are coal's signed distance's sign, whatever was checked before
(``toolkit.collision.checker.exact_requests``), and the batch check asks coal only for
the pairs the pre-filter leaves undecided (``Checker._listed_collide``)."""

from __future__ import annotations

import warnings

import coal
import numpy as np
import pinocchio as pin
import pytest

import toolkit
import toolkit.robot
from toolkit import Scene
from toolkit.collision.bound_kernels import CLOSE, NEAR

GRASP = np.array([0.0, 0.3, 0.0, -2.0, 0.0, 2.3, 0.8, 0.035, 0.035])
# A 22 x 8.8 x 3.8 mm box wholly inside a 4 cm wall, 25 mm deep (its pose in the wall's
# frame): coal 3's box-box test with Pinocchio's default request (no contacts) calls it
# free. Found in MotionBenchMaker's box scene, the Panda's finger inside a side wall.
INSIDE = np.array([[0.087688, 0.995853, -0.024238, -0.079694],
                   [0.981159, -0.082138, 0.174871, -0.006668],
                   [0.172155, -0.039116, -0.984293, -0.089109],
                   [0.0, 0.0, 0.0, 1.0]])  # fmt: skip
INSIDE[:3, :3] = pin.Quaternion(INSIDE[:3, :3]).normalized().matrix()


@pytest.fixture(scope="module")
def panda():
    return toolkit.load_example("panda")


def _signed(checker, Q):
    """Per configuration, whether some checked pair's signed distance is negative, by coal's
    distance on a GeometryData of Pinocchio's own (not the checker's requests)."""
    model, geom = checker.model, checker.geom
    data, gdata = model.createData(), pin.GeometryData(geom)
    out = []
    for q in Q:
        pin.computeDistances(model, data, geom, gdata, q)
        out.append(min(r.min_distance for r in gdata.distanceResults) < 0)
    return np.array(out)


def test_a_box_wholly_inside_a_wall_collides(panda):
    """A peg held 0.3 m from the hand, placed wholly inside a wall: the single and the batch
    check say it collides and name the pair; the signed distance says 25 mm deep."""
    peg = np.eye(4)
    peg[:3, 3] = [0.3, 0.0, 0.0]
    wall = panda.fk(GRASP, "panda_hand") @ peg @ np.linalg.inv(INSIDE)
    scene = (Scene().attach("peg", "panda_hand", "box", [0.022, 0.0088, 0.0038], peg)
             .add_box("wall", [0.7, 0.04, 0.7], wall))  # fmt: skip
    checker = toolkit.robot.checker_for(panda, scene)
    depth, pair = checker.min_distance(GRASP)
    assert depth == pytest.approx(-0.0248, abs=5e-4) and pair == ("peg", "wall")
    assert checker.in_collision(GRASP)
    assert checker.in_collision_many(np.array([GRASP, GRASP])).all()
    assert checker.collisions(GRASP) == [("peg", "wall")]
    assert checker.first_collision(GRASP) == ("peg", "wall")
    assert panda.in_collision(GRASP, scene)


def _cell(panda):
    """A can between the Panda's fingers at GRASP, on a table."""
    hand = panda.fk(GRASP, "panda_hand")
    tip = hand[:3, 3] + hand[:3, 2] * 0.1
    return (Scene().add_cylinder("can", 0.03, 0.14, tip)
            .add_box("table", [0.4, 0.6, 0.05], [0.7, 0.0, tip[2] - 0.095]))  # fmt: skip


def test_answers_near_contact_are_the_signed_distances_in_any_order(panda):
    """Around a grasp (most configurations touch the can or the table): the batch check, and
    the single check in both orders, equal the sign of coal's signed distance."""
    checker = toolkit.robot.checker_for(panda, _cell(panda))
    rng = np.random.default_rng(3)
    Q = GRASP + rng.normal(0.0, 0.08, (600, panda.nq))
    Q[:, -2:] = GRASP[-2:]
    Q = np.clip(Q, panda.joints.lower, panda.joints.upper)
    truth = _signed(checker, Q)
    assert 0.2 < truth.mean() < 0.95  # both answers well represented
    np.testing.assert_array_equal(checker.in_collision_many(Q), truth)
    np.testing.assert_array_equal([checker.in_collision(q) for q in Q], truth)
    np.testing.assert_array_equal([checker.in_collision(q) for q in Q[::-1]], truth[::-1])
    np.testing.assert_array_equal(checker.in_collision_many(Q[::-1]), truth[::-1])


def test_the_listed_pairs_hold_every_colliding_pair(panda):
    """Where the pre-filter leaves a configuration undecided and lists its pairs (at most
    NEAR), every pair coal finds colliding there is listed; so coal on the listed pairs
    answers as coal on every pair."""
    checker = toolkit.robot.checker_for(panda, _cell(panda))
    rng = np.random.default_rng(4)  # most that collide are proved so by surface points:
    Q = GRASP + rng.normal(0.0, 0.1, (2500, panda.nq))  # many, for 100 left to coal
    Q[:, -2:] = GRASP[-2:]
    Q = np.clip(Q, panda.joints.lower, panda.joints.upper)
    state, listed = checker.bounds.decide_pairs(Q)
    assert np.array_equal(state, checker.bounds.decide(Q))
    rows = np.flatnonzero((state == CLOSE) & (listed[:, 0] <= NEAR))
    assert len(rows) > 100
    colliding = 0
    for i in rows:
        hit = set(np.flatnonzero(checker.pair_flags(Q[i])).tolist())
        assert hit <= set(listed[i, 1 : 1 + listed[i, 0]].tolist())
        assert 1 <= listed[i, 0] and len(set(listed[i, 1 : 1 + listed[i, 0]])) == listed[i, 0]
        colliding += bool(hit)
    assert 0 < colliding < len(rows)
    np.testing.assert_array_equal(checker.in_collision_many(Q), checker._exact_many(Q))


def test_the_parallel_pool_uses_the_same_requests(panda):
    """coal over every core (a batch of every pair's checks) answers as the single check."""
    checker = toolkit.robot.checker_for(panda, _cell(panda))
    rng = np.random.default_rng(5)
    Q = GRASP + rng.normal(0.0, 0.1, (300, panda.nq))
    Q[:, -2:] = GRASP[-2:]
    Q = np.clip(Q, panda.joints.lower, panda.joints.upper)
    np.testing.assert_array_equal(checker._exact_many(Q), [checker.in_collision(q) for q in Q])
    pool = checker.parts._pools[0]  # 300 rows go over every core
    datas = [pool.getGeometryData(k) for k in range(len(pool.getGeometryDatas()))]
    for gdata in [checker.parts._gdata[0].get(), *datas]:
        requests = gdata.collisionRequests
        assert len(requests) == len(checker.geom.collisionPairs)
        assert all(r.enable_contact for r in requests)
        assert all(r.gjk_initial_guess == coal.GJKInitialGuess.DefaultGuess for r in requests)
        with warnings.catch_warnings():  # the old switch is deprecated (read only here)
            warnings.simplefilter("ignore", DeprecationWarning)
            assert not any(r.enable_cached_gjk_guess for r in requests)
