"""The compiled door of ``ik_all`` and ``ik_all_batch``: one row per branch by default (the
turn nearest ``q_rest``), every turn on request, single and batch equal row for row, and the
door equal to the general path (the Python forms on the Pinocchio back end)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import random_spherical_shoulder, same_up_to_turns

import toolkit
from toolkit import Robot


def _arms():
    katana = toolkit.load("katana_6m180")
    return {
        "ur5": toolkit.load_example("ur5"),
        "kinova": toolkit.load_example("kinova"),
        "katana_6m180": katana,
        "reversed": toolkit.load_urdf(random_spherical_shoulder(np.random.default_rng(7))),
    }


ARMS = _arms()


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_default_rows_are_each_branch_at_the_turn_nearest_q_rest(name):
    """Against every turn (``turns=True``): the same branches, and each default row is the
    turn of its branch within the limits nearest q_rest by sum |dq| (the turns are
    independent per joint), from random rests."""
    robot = ARMS[name]
    for seed in range(6):
        T = robot.fk(robot.random_q(seed=seed))
        rest = robot.random_q(seed=100 + seed) if seed % 2 else None
        one = robot.ik_all(T, q0=rest)
        every = robot.ik_all(T, q0=rest, turns=True)
        assert sorted(one.labels) == sorted(set(every.labels))
        assert one.branch.tolist() == list(range(len(one.q)))
        centre = robot.joints.angles(robot._numeric.ik_state.mid if rest is None else rest)
        for i, label in enumerate(one.labels):
            mine = every.q[[k for k, lb in enumerate(every.labels) if lb == label]]
            assert any(np.abs(row - one.q[i]).max() < 1e-9 for row in mine)
            inside = mine[every.within_limits[[k for k, lb in enumerate(every.labels)
                                               if lb == label]]]  # fmt: skip
            if len(inside):
                far = np.abs(robot.joints.angles(inside) - centre).sum(axis=1)
                gap = np.abs(robot.joints.angles(one.q[i][None])[0] - centre).sum()
                assert gap <= far.min() + 1e-9
        assert one.success.sum() == len(set(np.asarray(every.labels)[every.success]))


@pytest.mark.parametrize("name", sorted(ARMS))
def test_single_and_batch_are_equal_row_for_row(name):
    robot = ARMS[name]
    Q = robot.random_q(25, seed=3)
    Ts = robot.fk(Q)
    rest = robot.random_q(seed=4)
    door = robot._analytic._door(robot.frames.id(None))
    for q_rest in (None, rest):
        batch = robot.ik_all_batch(Ts, q0=q_rest)
        for i, T in enumerate(Ts):
            single = robot.ik_all(T, q0=q_rest)
            k = batch.found[i]
            assert k == len(single.q)
            np.testing.assert_array_equal(batch.q[i, :k], single.q)
            np.testing.assert_array_equal(batch.success[i, :k], single.success)
            np.testing.assert_array_equal(batch.position_error[i, :k], single.position_error)
            assert door.labels(batch.roots[i, :k]) == single.labels
            _assert_same_rows(batch.target(i), single)


def _assert_same_rows(
    one: toolkit.ik.IKAllResult, single: toolkit.ik.IKAllResult, polished: bool = False
) -> None:
    """A batch's target read as ``ik_all``'s answer: every field but ``lost`` and ``reason``
    (``polished``: the batch's compiled polish and the single call's each reach round-off,
    the rows then equal to 1e-9 and both verified to 1e-10)."""
    for field in ("success", "within_limits", "branch"):
        np.testing.assert_array_equal(getattr(one, field), getattr(single, field), err_msg=field)
    for field in ("q", "position_error", "orientation_error"):
        a, b = getattr(one, field), getattr(single, field)
        if polished:
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 if field == "q" else 1e-10)
        else:
            np.testing.assert_array_equal(a, b, err_msg=field)
    assert (one.labels, one.free, one.structure) == (single.labels, single.free, single.structure)
    assert (one.polished, one.target_moved) == (single.polished, single.target_moved)


@pytest.mark.parametrize("how", ["calibrated", "locked", "float32", "point"])
def test_a_batch_target_reads_as_ik_all_on_every_path(how):
    """``IKAllBatchResult.target(i)`` equals ``ik_all`` of target i on the batch's other
    paths: an arm only near its family (polished), a locked arm (target by target), rounded
    rotations (moved to the nearest), a family placing a point."""
    from toolkit import calibration as cal

    ur5, panda = ARMS["ur5"], toolkit.load_example("panda")
    lock, frame = None, None
    if how == "calibrated":
        robot = toolkit.load_urdf(cal.perturb(ur5, seed=2).urdf_text, tip=ur5.tip)
    elif how == "locked":
        robot, lock = panda, {"panda_joint7": 0.3}
    elif how == "point":
        robot, frame = toolkit.load("anthropomorphic"), "point_m"
    else:
        robot = ur5
    Q = robot.random_q(6, seed=11)
    if lock:
        Q[:, 6] = 0.3
    Ts = robot.fk(Q, frame)
    targets = Ts[:, :3, 3] if how == "point" else Ts
    if how == "float32":
        targets = targets.astype(np.float32).astype(float)
    batch = robot.ik_all_batch(targets, lock=lock, frame=frame)
    assert (batch.target_moved > 0).all() == (how == "float32")
    for i, T in enumerate(targets):
        single = robot.ik_all(T, lock=lock, frame=frame)
        _assert_same_rows(batch.target(i), single, how == "calibrated")
    assert batch.target(-1).q.shape == batch.target(len(targets) - 1).q.shape
    with pytest.raises(toolkit.InvalidParameterError, match="index into the 6 targets"):
        batch.target(6)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_door_equals_the_general_path(name):
    """The compiled door (a float64 array on the compiled back end) against the general
    path: the same robot on the Pinocchio back end (the families' Python forms, Pinocchio's
    forward kinematics) given the targets as lists."""
    robot = ARMS[name]
    other = Robot(robot.model, tip=robot.tip, backend="pinocchio")
    assert robot._analytic._door(robot.frames.id(None)) is not None
    assert other._analytic._door(other.frames.id(None)) is None
    for seed in range(8):
        T = robot.fk(robot.random_q(seed=seed))
        fast = robot.ik_all(T)
        slow = other.ik_all(T.tolist())
        assert sorted(fast.labels) == sorted(slow.labels)
        for q, label, ok in zip(fast.q, fast.labels, fast.success, strict=True):
            k = slow.labels.index(label)
            assert same_up_to_turns(robot.joints.angles(q), robot.joints.angles(slow.q[k]), 1e-8)
            np.testing.assert_allclose(q, slow.q[k], atol=1e-8)
            assert ok == slow.success[k]


def test_a_float32_target_goes_through_the_door_projected():
    ur5 = ARMS["ur5"]
    T = ur5.fk(ur5.random_q(seed=9))
    rounded = T.astype(np.float32).astype(np.float64)
    answer = ur5.ik_all(rounded)
    exact = ur5.ik_all(T)
    assert answer.target_moved > 0 and answer.success.all()
    assert answer.labels == exact.labels and exact.target_moved == 0.0
    np.testing.assert_allclose(answer.q, exact.q, atol=1e-6)


def test_bad_targets_at_the_door_get_the_general_paths_errors():
    ur5 = ARMS["ur5"]
    T = ur5.fk(ur5.random_q(seed=9))
    for bad, match in ((np.full((4, 4), np.nan), "finite|NaN"), (T * 2.0, "rotation|last row")):
        with pytest.raises(toolkit.InvalidParameterError, match=match):
            ur5.ik_all(bad)
    with pytest.raises(toolkit.InvalidParameterError):
        ur5.ik_all(T, turns=True, tol=0.5)


def test_ik_all_batch_takes_lock_as_ik_all_does():
    """The Panda with joint 7 locked (a reversed family): the batch's rows are ik_all's."""
    panda = toolkit.load_example("panda")
    lock = {"panda_joint7": 0.4}
    Q = panda.random_q(12, seed=8)
    Q[:, 6] = 0.4
    Ts = panda.fk(Q)
    batch = panda.ik_all_batch(Ts, lock=lock)
    assert batch.success.any(axis=1).all()
    for i, T in enumerate(Ts):
        single = panda.ik_all(T, lock=lock)
        k = batch.found[i]
        assert k == len(single.q)
        np.testing.assert_allclose(batch.q[i, :k], single.q, atol=1e-12)
        assert (np.abs(batch.q[i, :k, 6] - 0.4) < 1e-12).all()
    with pytest.raises(toolkit.InvalidParameterError, match="no joint named"):
        panda.ik_all_batch(Ts, lock={"nope": 0.1})


def test_turns_must_be_a_flag():
    ur5 = ARMS["ur5"]
    T = ur5.fk(ur5.random_q(seed=9))
    for bad in (1, "yes", np.ones(2), None):
        with pytest.raises(toolkit.InvalidParameterError, match="turns"):
            ur5.ik_all(T, turns=bad)


def test_a_batch_projects_only_the_targets_that_need_it():
    ur5 = ARMS["ur5"]
    Ts = ur5.fk(ur5.random_q(10, seed=12))
    rounded = Ts.copy()
    rounded[::2] = Ts[::2].astype(np.float32).astype(np.float64)
    batch = ur5.ik_all_batch(rounded)
    assert (batch.target_moved[::2] > 0).all() and (batch.target_moved[1::2] == 0).all()
    exact = ur5.ik_all_batch(Ts)
    np.testing.assert_array_equal(batch.found, exact.found)
    np.testing.assert_array_equal(batch.q[1::2], exact.q[1::2])
    live = ~np.isnan(exact.q[::2])
    np.testing.assert_allclose(batch.q[::2][live], exact.q[::2][live], atol=1e-5)
    assert batch.success.sum() == exact.success.sum()


@pytest.mark.parametrize("name", ["ur5", "kinova", "katana_6m180"])
def test_ik_batch_by_branches_is_ik_by_branches_target_by_target(name):
    """One start for all and one per target: each row is the single analytic ik's."""
    robot = ARMS[name]
    Ts = robot.fk(robot.random_q(20, seed=21))
    Q0 = robot.random_q(20, seed=22)
    for q0 in (None, Q0[0], Q0):
        batch = robot.ik_batch(Ts, q0, method="analytic")
        assert batch.success.all() and (batch.iterations == 0).all()
        for i, T in enumerate(Ts):
            start = None if q0 is None else (q0 if q0.ndim == 1 else q0[i])
            single = robot.ik(T, start, method="analytic")
            np.testing.assert_allclose(batch.q[i], single.q, atol=1e-12)
            assert np.abs(robot.fk(batch.q[i]) - T).max() < 1e-9


def test_ik_batch_auto_falls_back_to_numeric_where_no_branch_serves():
    ur5 = ARMS["ur5"]
    Ts = ur5.fk(ur5.random_q(6, seed=23))
    far = Ts.copy()
    far[::2, :3, 3] += 5.0  # out of reach: no branch; the numeric solver reports its best
    auto = ur5.ik_batch(far, method="auto")
    numeric = ur5.ik_batch(far, method="numeric")
    assert auto.success.tolist() == [False, True] * 3 == numeric.success.tolist()
    assert (auto.iterations[1::2] == 0).all() and (auto.iterations[::2] > 0).all()
    assert (auto.position_error[::2] > 4.0).all()  # the numeric solver's best, reported
    positions = ur5.ik_batch(Ts[:, :3, 3], method="auto")  # positions: numeric
    assert positions.success.all() and (positions.iterations > 0).any()
    with pytest.raises(toolkit.InvalidParameterError, match="full poses"):
        ur5.ik_batch(Ts[:, :3, 3], method="analytic")
    with pytest.raises(toolkit.InvalidParameterError, match="method"):
        ur5.ik_batch(Ts, method="closed")


def test_ik_batch_by_branches_avoids_collisions():
    """A box where the nearest branch's elbow is: the batch answers another branch, free,
    as the single ik does."""
    from toolkit.collision import Scene

    ur5 = ARMS["ur5"]
    q = ur5.random_q(seed=24)
    T = ur5.fk(q)
    scene = Scene()
    elbow = ur5.fk(q, "forearm_link")[:3, 3]
    scene.add_box("crate", [0.12, 0.12, 0.12], elbow)
    batch = ur5.ik_batch(T[None], q, method="analytic", scene=scene)
    single = ur5.ik(T, q, method="analytic", scene=scene)
    np.testing.assert_allclose(batch.q[0], single.q, atol=1e-12)
    if batch.success[0]:
        assert not ur5.in_collision(batch.q[0], scene)
        assert np.abs(batch.q[0] - q).max() > 1e-6  # not the configuration inside the box


@pytest.mark.parametrize("first", [False, True])
def test_the_targets_row_holds_its_nearest_verified_rows_errors_and_every_rows_free_bits(first):
    """The door's row of a target: count, flags, the nearest verified row, the free bits
    of its rows or-ed, and that row's errors (what ``Robot.ik`` reads alone), on random
    and singular (q5 = 0: wrist free) UR5 targets, with and without ``first``."""
    from toolkit.ik.analytic import door_kernels

    ur5 = toolkit.load_example("ur5")
    door = ur5._analytic._door(ur5.frames.id(None))
    Q = ur5.random_q(40, seed=3)
    Q[::2, 4] = 0.0
    P = door.call(ur5.fk(Q), 1e-10, door.mid2, door.mid_pref2, first=first)
    nq = ur5.nq
    Qs, E, K, S, C = door_kernels.split(P)
    loose = 0
    for i in range(len(Q)):
        head, k = P[i, -1], int(C[i, 0])
        bits = np.bitwise_or.reduce(K[i, :k, 3]) if k else 0
        assert int(head[3]) == bits
        loose |= bits
        best = int(head[2])
        assert best >= 0  # each target has a verified branch
        assert S[i, best, 1] and head[4] == E[i, best, 0] and head[5] == E[i, best, 1]
        verified = np.flatnonzero(S[i, :k, 1])
        far = E[i, verified, 2]
        assert E[i, best, 2] == far.min() and best == verified[np.argmin(far)]
        np.testing.assert_allclose(ur5.fk(Qs[i, best]), ur5.fk(Q[i]), atol=1e-9)
        assert Qs[i, best].shape == (nq,)
    assert loose  # the singular targets have free joints


def test_a_batch_holding_one_target_that_is_not_a_pose_is_refused_saying_why():
    """The door checks each pose in its kernel (the batch's numpy check skipped there): one
    bad target among good ones is refused as the general path refuses it, naming the fault;
    NaN is refused before either."""
    ur5 = ARMS["ur5"]
    good = ur5.fk(ur5.random_q(5, seed=1)).reshape(-1, 4, 4)
    skew, flip, row, nan = (good.copy() for _ in range(4))
    skew[3, 0, 1] += 1e-4  # R^T R off by 1e-4
    flip[2, :3, 2] *= -1.0  # a reflection: det R = -1
    row[4, 3, 0] = 1e-9  # the last row
    nan[0, 1, 3] = np.nan
    for bad, message in ((skew, "not a rotation"), (flip, "not a rotation"),
                         (row, "last row"), (nan, "finite|NaN|nan")):  # fmt: skip
        with pytest.raises(toolkit.InvalidParameterError, match=message):
            ur5.ik_all_batch(bad)
    assert ur5.ik_all_batch(good).success.any(axis=1).all()  # the good ones pass
