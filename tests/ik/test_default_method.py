"""``method="auto"``, the default of ``ik``, ``ik_batch`` and ``ik_path``: an arm with an
exact compiled family answers a full pose by its verified branch nearest ``q0`` (one
compiled call, ``iterations`` 0); every other arm, target, mask or calibrated arm gets the
numeric solver, as ``method="numeric"`` does."""

from __future__ import annotations

import numpy as np
import pytest

import toolkit
from toolkit import Robot
from toolkit import calibration as cal


def _arms():
    return {
        "ur5": toolkit.load_example("ur5"),
        "kinova": toolkit.load_example("kinova"),
        "katana_6m180": toolkit.load("katana_6m180"),
    }


ARMS = _arms()


def _distance(robot: Robot, Q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """The sum of |angle - q0's angle| over the joints (rows of Q)."""
    return np.abs(robot.joints.angles(np.atleast_2d(Q)) - robot.joints.angles(q0)).sum(axis=1)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_ik_by_default_answers_the_nearest_verified_branch(name):
    """Against every turn of every branch (``ik_all(turns=True)``) and a forward kinematics
    on the Pinocchio back end: the answer reaches the target, lies within the limits and
    no verified row is nearer ``q0``."""
    robot = ARMS[name]
    reference = Robot(robot.model, tip=robot.tip, backend="pinocchio")
    rng = np.random.default_rng(31)
    Ts = robot.fk(robot.random_q(12, seed=rng))
    for i, T in enumerate(Ts):
        q0 = None if i % 3 == 0 else robot.random_q(seed=rng)
        start = robot._numeric.ik_state.mid if q0 is None else q0
        answer = robot.ik(T, q0)
        assert answer.success and answer.iterations == 0 and answer.method == "analytic"
        assert np.abs(reference.fk(answer.q) - T).max() < 1e-9
        assert robot.joints.within_limits(answer.q)
        every = robot.ik_all(T, q0=start, turns=True)
        nearest = _distance(robot, every.q[every.success], start).min()
        assert _distance(robot, answer.q, start)[0] <= nearest + 1e-9
        np.testing.assert_allclose(answer.q, robot.ik(T, q0, method="analytic").q, atol=1e-12)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_ik_batch_by_default_is_ik_target_by_target(name):
    robot = ARMS[name]
    Ts = robot.fk(robot.random_q(10, seed=32))
    Q0 = robot.random_q(10, seed=33)
    batch = robot.ik_batch(Ts, Q0)
    assert batch.success.all() and (batch.iterations == 0).all()
    for i, T in enumerate(Ts):
        np.testing.assert_allclose(batch.q[i], robot.ik(T, Q0[i]).q, atol=1e-12)


def _same(a, b) -> None:
    np.testing.assert_array_equal(a.q, b.q)
    assert (a.success, a.iterations, a.restarts) == (b.success, b.iterations, b.restarts)
    assert a.method == b.method == "numeric"


def test_ik_by_default_is_numeric_where_no_compiled_family_answers():
    """The Panda (no family), a mask, a position, a calibrated UR5 (only near its family)
    and a target out of reach: the default's answer is the numeric solver's, bit for bit."""
    panda = toolkit.load_example("panda")
    T = panda.fk(panda.random_q(seed=34))
    _same(panda.ik(T), panda.ik(T, method="numeric"))
    ur5 = ARMS["ur5"]
    T = ur5.fk(ur5.random_q(seed=35))
    mask = [1, 1, 1, 1, 1, 0]
    _same(ur5.ik(T, mask=mask), ur5.ik(T, mask=mask, method="numeric"))
    _same(ur5.ik(T[:3, 3]), ur5.ik(T[:3, 3], method="numeric"))
    calibrated = toolkit.load_urdf(cal.perturb(ur5, seed=36).urdf_text, tip=ur5.tip)
    _same(calibrated.ik(T), calibrated.ik(T, method="numeric"))
    far = T.copy()
    far[:3, 3] += 5.0
    out = ur5.ik(far)
    _same(out, ur5.ik(far, method="numeric"))
    assert not out.success and out.iterations > 0 and out.position_error > 4.0


@pytest.mark.parametrize("name", [*sorted(ARMS), "panda j7"])
def test_the_kernels_first_verified_row_is_the_nearest_of_all_verified(name):
    """``first=True`` verifies the rows nearest ``pref`` until one passes: the same row,
    the same q and errors as verifying every row (the Panda with joint 7 locked: a family
    solved on the reversed chain)."""
    if name == "panda j7":
        robot = toolkit.load_example("panda")
        lock = ((int(robot.model.getJointId("panda_joint7")), 0.4),)
        door = robot._analytic._door(robot.frames.id(None), lock)
    else:
        robot = ARMS[name]
        door = robot._analytic._door(robot.frames.id(None))
    rng = np.random.default_rng(37)
    Q0 = robot.random_q(200, seed=rng)
    Q = robot.random_q(200, seed=rng)
    if name == "panda j7":
        Q0[:, 6] = Q[:, 6] = 0.4
    Ts = np.ascontiguousarray(robot.fk(Q))
    cols = list(door.chain.columns)
    pref = np.ascontiguousarray(robot.joints.angles(Q0)[:, cols])
    full = door.call(Ts, 1e-9, Q0, pref)
    first = door.call(Ts, 1e-9, Q0, pref, first=True)
    best = full[:, 8, 2].astype(int)
    assert (best >= 0).all()
    np.testing.assert_array_equal(first[:, 8, 2], full[:, 8, 2])
    rows = np.arange(len(Ts))
    np.testing.assert_array_equal(first[rows, best], full[rows, best])
    far = np.where(full[:, :8, -2] == 1.0, full[:, :8, robot.nq + 2], np.inf)
    np.testing.assert_array_equal(np.argmin(far, axis=1), best)
    assert np.isnan(first[:, :8, robot.nq]).sum() > 0  # the others were not verified


def test_the_cli_says_how_it_solved(capsys):
    from toolkit.cli.main import main

    assert main(["ik", "ur5", "0.4", "0.1", "0.4", "--rpy", "3.14", "0", "0"]) == 0
    assert "solved by its analytic branches" in capsys.readouterr().out
    assert main(["ik", "ur5", "0.4", "0.1", "0.4", "--rpy", "3.14", "0", "0",
                 "--method", "numeric"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "solved after" in out and "iterations" in out
    with pytest.raises(SystemExit):
        main(["ik", "ur5", "0.4", "0.1", "0.4", "--method", "closed"])


def test_a_float32_pose_is_solved_by_default():
    """Its branches reach the nearest rotation, not the float32 one to 1e-9: the numeric
    solver answers (it was refused as unsolved once the default became "auto")."""
    for robot in (ARMS["ur5"], ARMS["kinova"]):
        T = robot.fk(robot.random_q(seed=43)).astype(np.float32)
        for method in ("auto", "analytic"):
            answer = robot.ik(T, method=method)
            assert answer.success, (robot.name, method)
            assert max(answer.position_error, answer.orientation_error) <= 1e-6
