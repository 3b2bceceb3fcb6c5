"""The families of 3-joint chains placing a point, compiled: each kernel against its Python
form (the oracle) on random chains and on [P3]'s five positioning structures, exact and
perturbed; ``ik_all`` of one point and ``ik_all_batch`` of many equal row for row; ``ik``
answering from the nearest verified branch; a point on an axis (every angle of that joint
reaches it) answered by a verified representative with the joint named free."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import random_position_chain

import toolkit
from toolkit import calibration as cal
from toolkit.ik import Family, families, registry
from toolkit.ik.analytic.door import packed_family

rng = np.random.default_rng(41)

KINDS = {
    "PPP": ("cartesian", Family.PPP),
    "RPP": ("cylindrical", Family.RPP),
    "RRP meeting": ("spherical", Family.RRP_MEETING),
    "RRP parallel": ("scara", Family.RRP_PARALLEL),
    "3R meeting": ("anthropomorphic", Family.THREE_R_MEETING),
    "3R parallel": (None, Family.THREE_R_PARALLEL),
    "3R general": (None, Family.THREE_R_GENERAL),
}
"""Each compiled position family: the [P3] structure that has it (if any) and its key."""


def _robots(kind: str) -> list[tuple[toolkit.Robot, str | None]]:
    """(robot, frame): three random chains of ``kind``, its [P3] structure and that
    structure perturbed (only near its family) where one has it."""
    name, _ = KINDS[kind]
    out = [(toolkit.load_urdf(random_position_chain(kind, rng)), None) for _ in range(3)]
    if name is not None:
        nominal = toolkit.load(name)
        truth = cal.perturb(nominal, seed=2, parameters=("offsets", "geometry", "base"))
        out += [(nominal, "point_m"),
                (toolkit.load_urdf(truth.urdf_text, tip=nominal.tip), "point_m")]  # fmt: skip
    return out


@pytest.mark.parametrize("kind", list(KINDS))
def test_each_compiled_position_family_equals_its_python_form(kind):
    """Every branch's angles, its label (named from the kernel's roots) and count, on exact
    chains and on a chain only near its family (least-squares answers kept as the Python
    form keeps them)."""
    family = KINDS[kind][1]
    record = registry.REGISTRY[family]
    assert family.compiled and record.kernel is not None
    out, roots, free = np.zeros((8, 3)), np.full((8, 3), -1, np.int64), np.zeros(8, np.int64)
    total = 0
    for robot, frame in _robots(kind):
        chain, found = robot._analytic._chain_structure(robot.frames.id(frame))
        assert found.family is family and not found.reversed
        packed = packed_family(chain, found)
        ok = families.EXACT_ONLY if found.exact else families.NEAR_OK
        for seed in range(25):
            T = np.eye(4)
            T[:3, 3] = robot.fk(robot.random_q(seed=seed), frame)[:3, 3]
            n = record.kernel(*packed, T, not found.exact, np.zeros(3), out, roots, free)
            python = record.python(chain, found.points, T, ok)
            assert n == len(python), (robot.name, seed)
            for k, (angles, label) in enumerate(python):
                np.testing.assert_allclose(out[k], angles, atol=1e-9)
                assert family.label(tuple(roots[k].tolist())) == label
                assert family.roots_of(label) == tuple(roots[k].tolist())
            assert not free[:n].any()  # random targets: no singular point
            total += n
    assert total >= 25 * 3  # every target has a branch


@pytest.mark.parametrize("kind", list(KINDS))
def test_ik_all_of_one_point_is_the_batch_of_one_row_for_row(kind):
    for robot, frame in _robots(kind)[:1] + _robots(kind)[3:4]:
        P = robot.fk(robot.random_q(12, seed=5), frame)[:, :3, 3]
        batch = robot.ik_all_batch(P, frame=frame)
        for n, p in enumerate(P):
            one = robot.ik_all(p, frame=frame)
            k = int(batch.found[n])
            assert len(one.q) == k and one.solved >= 1
            np.testing.assert_array_equal(one.q, batch.q[n, :k])
            np.testing.assert_array_equal(one.success, batch.success[n, :k])
            np.testing.assert_array_equal(one.position_error, batch.position_error[n, :k])
            assert (one.orientation_error == 0.0).all()
            family = Family(one.structure.family)
            assert [family.roots_of(lb) for lb in one.labels] == [
                tuple(r) for r in batch.roots[n, :k].tolist()]  # fmt: skip
            for q in one.q[one.success]:  # an independent check: Pinocchio's FK
                np.testing.assert_allclose(robot.fk(q, frame)[:3, 3], p, atol=1e-9)


@pytest.mark.parametrize("name", ["cartesian", "cylindrical", "spherical", "scara",
                                  "anthropomorphic"])  # fmt: skip
def test_ik_of_a_point_answers_from_the_verified_branch_nearest_its_start(name):
    robot = toolkit.load(name)
    for q in robot.random_q(5, seed=9):
        p = robot.fk(q, "point_m")[:3, 3]
        start = q + 0.05
        answer = robot.ik(p, q0=start, frame="point_m")
        assert answer.success and answer.iterations == 0 and answer.method == "analytic"
        rows = robot.ik_all(p, frame="point_m", q0=start)
        good = rows.q[rows.success]
        nearest = good[
            np.argmin(np.abs(robot.joints.angles(good) - robot.joints.angles(start)).sum(axis=1))
        ]
        np.testing.assert_array_equal(answer.q, nearest)
        numeric = robot.ik(p, q0=start, frame="point_m", method="numeric")
        assert numeric.success and numeric.iterations > 0


def test_a_pose_for_an_arm_that_places_a_point_is_not_answered_by_its_position():
    scara = toolkit.load("scara")
    T = scara.fk(scara.random_q(seed=3), "point_m")
    T[:3, :3] = np.eye(3)[[1, 2, 0]]  # a rotation the SCARA cannot hold
    answer = scara.ik(T, frame="point_m", restarts=2)
    assert not answer.success and answer.orientation_error > 1.0


def test_a_point_on_the_first_axis_is_reached_with_that_joint_free():
    """The anthropomorphic arm's point on axis 1 (every q1 reaches it): each branch's
    representative takes q1 from q0, is verified, and names joint 1 free (the Python form
    found no branch there)."""
    robot = toolkit.load("anthropomorphic")
    chain, found = robot._analytic._chain_structure(robot.frames.id("point_m"))
    for height in (0.2, 0.3, 0.45):
        p = found.points[0] + height * chain.axes[0]
        for q1 in (-1.0, 0.4):
            q0 = np.array([q1, 0.1, 0.2])
            result = robot.ik_all(p, frame="point_m", q0=q0)
            assert len(result.q) == 2 and result.solved >= 1 and result.reason == ""
            assert (result.success == result.within_limits).all()  # reached, limits aside
            assert all(free == (chain.names[0],) for free in result.free)
            np.testing.assert_allclose(robot.joints.angles(result.q)[:, 0], q1, atol=1e-12)
            for q in result.q:
                np.testing.assert_allclose(robot.fk(q, "point_m")[:3, 3], p, atol=1e-12)


def test_ik_batch_of_points_is_ik_of_each_and_a_pose_batch_is_never_judged_by_position():
    scara = toolkit.load("scara")
    Q = scara.random_q(10, seed=4)
    P = scara.fk(Q, "point_m")[:, :3, 3]
    starts = Q + 0.05
    batch = scara.ik_batch(P, starts, frame="point_m")
    assert batch.success.all() and (batch.iterations == 0).all()
    for i, p in enumerate(P):
        one = scara.ik(p, q0=starts[i], frame="point_m")
        np.testing.assert_array_equal(batch.q[i], one.q)
    poses = scara.fk(Q, "point_m")
    poses[:, :3, :3] = np.eye(3)[[1, 2, 0]]  # rotations the SCARA cannot hold
    with pytest.warns(toolkit.UnreachableTargetsWarning, match="give \\(N, 3\\) positions"):
        judged = scara.ik_batch(poses, starts, frame="point_m", restarts=1)
    assert not judged.success.any() and (judged.orientation_error > 1.0).all()
    with pytest.raises(toolkit.InvalidParameterError, match="needs positions"):
        scara.ik_batch(poses, frame="point_m", method="analytic")


@pytest.mark.parametrize("kind", list(KINDS))
def test_the_records_door_is_the_one_target_kernel_on_each_verified(kind):
    """The record's door kernel (serial and spread) answers each target with the one-target
    kernel's branches: the same roots, the same angles up to whole turns, each verified."""
    record = registry.REGISTRY[KINDS[kind][1]]
    robot = toolkit.load_urdf(random_position_chain(kind, rng))
    chain, found = robot._analytic._chain_structure(robot.frames.id(None))
    door = robot._analytic._door(robot.frames.id(None))
    packed = packed_family(chain, found)
    Ts = robot.fk(robot.random_q(7, seed=1))
    Ts[:, :3, :3] = np.eye(3)  # a family placing a point: a position as a pose
    cols = list(chain.columns)
    turn = ~chain.sliding
    for spread in (False, True):
        Q, E, K, _, C = door.rows(Ts, 1e-9, door.mid, door.mid_pref, spread=spread)
        for i, T in enumerate(Ts):
            one, r1 = np.zeros((8, 3)), np.full((8, 3), -1, np.int64)
            n = record.kernel(*packed, T, False, np.zeros(3), one, r1, np.zeros(8, np.int64))
            assert C[i, 0] == n >= 1 and C[i, 1] == 0
            roots = [tuple(r) for r in r1[:n].tolist()]
            assert sorted(map(tuple, K[i, :n, :3].tolist())) == sorted(roots)
            for b in range(n):
                d = robot.joints.angles(Q[i, b])[cols] - one[roots.index(tuple(K[i, b, :3]))]
                d[turn] = np.remainder(d[turn] + np.pi, 2 * np.pi) - np.pi
                assert np.abs(d).max() < 1e-12
            assert (E[i, :n, 0] < 1e-9).all()
