"""Backlash layer (paper 1, eqs. 16-17): offsets, torques, fixed point, compensation."""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import backlash
from toolkit import backlash as bl
from toolkit.errors import ConfigurationError, InvalidParameterError

G = 9.81


@pytest.fixture(scope="module")
def katana():
    return toolkit.load("katana_6m180")


@pytest.fixture(scope="module")
def layer(katana):
    return bl.Backlash(katana, payload=0.5)


# ---------------------------------------------------------------- eq. 17
def test_offset_values_of_eq17():
    # delta (1/2 sign M + k_H M / M_H) with delta = 0.035, k_H = 0.2, M_H = 4
    assert bl.offset(2.0, 4.0) == pytest.approx(0.035 * (0.5 + 0.2 * 0.5))
    assert bl.offset(-2.0, 4.0) == pytest.approx(-0.035 * (0.5 + 0.2 * 0.5))
    assert bl.offset(1.0, 2.0, delta=0.01, k_h=0.4) == pytest.approx(0.01 * (0.5 + 0.2))
    assert bl.offset(0.0, 4.0) == 0.0  # sign(0) = 0: the dead zone
    assert bl.offset(1e-12, 4.0) == 0.0


def test_offset_broadcasts_per_joint():
    torque = np.array([[1.0, -2.0, 0.0], [3.0, 0.5, -0.1]])
    nominal = np.array([2.0, 4.0, 1.0])
    got = bl.offset(torque, nominal, delta=np.array([0.01, 0.02, 0.03]), k_h=0.1)
    want = np.array([0.01, 0.02, 0.03]) * (0.5 * np.sign(torque) + 0.1 * torque / nominal)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-15)


def test_offset_rejects_bad_parameters():
    with pytest.raises(InvalidParameterError, match="nominal_torque"):
        bl.offset(1.0, 0.0)
    with pytest.raises(InvalidParameterError, match="delta"):
        bl.offset(1.0, 1.0, delta=-0.1)
    with pytest.raises(InvalidParameterError, match="NaN"):
        bl.offset(np.nan, 1.0)


def test_hysteresis_keeps_the_last_contact_side():
    torques = np.array([[1.0], [0.0], [0.0], [-1.0], [0.0]])
    got = bl.hysteresis_offsets(torques, [2.0], delta=0.02, k_h=0.0)
    np.testing.assert_allclose(got[:, 0], [0.01, 0.01, 0.01, -0.01, -0.01])
    # before any contact the joint sits in the middle of its gap
    start = bl.hysteresis_offsets(np.array([[0.0], [2.0]]), [2.0], delta=0.02, k_h=0.5)
    np.testing.assert_allclose(start[:, 0], [0.0, 0.02 * (0.5 + 0.5)])
    with pytest.raises(InvalidParameterError, match=r"\(T, n\)"):
        bl.hysteresis_offsets([1.0, 2.0], [1.0, 1.0])


# ---------------------------------------------------------------- compiled fixed point
def test_compiled_fixed_point_equals_the_reference_solver():
    """The compiled per-command fixed point and settling agree with the NumPy forms (the
    bracketing iteration, then Newton's method with Pinocchio's gravity derivatives)."""
    from toolkit.backlash.fixed_point import needs_settling, settle, solve_fixed_point

    robot = toolkit.load("katana_6m180")
    layer = bl.Backlash(robot, payload=0.5)
    q = robot.random_q(3000, seed=9)
    fast = layer.solve(q)
    ref = solve_fixed_point(
        q,
        q.copy(),
        layer.delta,
        lambda th, _: layer._static_torques(th),
        layer._offsets,
        1e-12,
        100,
    )
    rows = needs_settling(ref)
    assert rows.size  # commands with a joint in its gap: the settling is exercised
    ref = settle(
        q, ref, layer._law, lambda th, _: layer._static_torques(th), layer._gravity_jacobian,
        1e-12, rows, layer._potential_energy,
    )  # fmt: skip
    np.testing.assert_allclose(fast.theta, ref.theta, rtol=0, atol=1e-11)
    np.testing.assert_array_equal(fast.in_gap, ref.in_gap)
    assert fast.converged.all() and ref.converged.all()
    assert fast.in_gap.any()  # some commands do rest inside a gap: both routes meet


# ---------------------------------------------------------------- torques
def test_gravity_of_the_stretched_arm_by_hand(katana):
    """Case 19 (arm stretched along x0): joint-2 torque = -g * sum(m_i x_i), data/katana.md."""
    a2, a3, a4, a5 = 0.190, 0.139, 0.1473, 0.1555
    masses_and_x = [
        (0.80175, 0.092420),  # upper arm, com 92.4 mm along it
        (0.79242, a2 + 0.058036),  # forearm
        (0.69149, a2 + a3 + 0.050401),  # wrist
        (0.25623, a2 + a3 + a4 - 0.001680),  # wrist roll, 1.7 mm before the wrist point
        (0.05521 + 2 * 0.02517, a2 + a3 + a4 + a5 / 2),  # gripper lumped at mid-length
    ]
    hand = -G * sum(m * x for m, x in masses_and_x)
    layer0 = bl.Backlash(katana, payload=0.0)
    torque = layer0.torques([0, 0, 0, -np.pi / 2, 0])
    assert torque[1] == pytest.approx(hand, rel=2e-3)
    assert torque[0] == 0.0  # vertical joint 1 carries no gravity torque
    # the payload adds m g times its lever arm a2 + a3 + a4 + a5
    with_payload = bl.Backlash(katana, payload=0.5).torques([0, 0, 0, -np.pi / 2, 0])
    assert with_payload[1] - torque[1] == pytest.approx(-0.5 * G * (a2 + a3 + a4 + a5), rel=1e-9)


def test_payload_torque_is_jacobian_transpose_of_its_weight(katana):
    light, heavy = bl.Backlash(katana), bl.Backlash(katana, payload=0.7)
    gravity = np.array(katana.model.gravity.linear)
    for q in katana.random_q(20, seed=3):
        Jv = katana.jacobian(q)[:3]
        np.testing.assert_allclose(
            heavy.torques(q) - light.torques(q), Jv.T @ (0.7 * gravity), atol=1e-12
        )


def test_trajectory_torques_are_minus_inverse_dynamics(layer, katana):
    rng = np.random.default_rng(0)
    for q in katana.random_q(10, seed=5):
        v, a = rng.normal(size=5), rng.normal(size=5)
        M = pin.crba(layer.model, layer.data, q)
        M = np.triu(M) + np.triu(M, 1).T
        nle = pin.nonLinearEffects(layer.model, layer.data, q, v)
        np.testing.assert_allclose(layer.torques(q, v, a), -(M @ a + nle), atol=1e-10)
    np.testing.assert_allclose(layer.torques(q, np.zeros(5), None), layer.torques(q), atol=1e-12)


def test_batched_torques_equal_single_calls(layer, katana):
    q = katana.random_q(50, seed=9)
    batch = layer.torques(q)
    for i in range(len(q)):
        np.testing.assert_allclose(batch[i], layer.torques(q[i]), atol=1e-12)


# ---------------------------------------------------------------- fixed point
def test_fixed_point_residual(layer, katana):
    q = katana.random_q(500, seed=11)
    out = layer.solve(q)
    assert out.converged.all()
    assert out.residual.max() < 1e-9
    # recheck the contact joints with single Pinocchio calls
    for i in range(0, 500, 25):
        torque = -pin.computeGeneralizedGravity(layer.model, layer.data, out.theta[i])
        contact = ~out.in_gap[i]
        expected = q[i] + bl.offset(torque, layer.nominal_torque, 0.035, 0.2)
        np.testing.assert_allclose(out.theta[i][contact], expected[contact], atol=1e-9)


def test_joint_hanging_inside_its_gap(layer):
    """Stretched arm: the roll joint's small load changes sign inside its gap."""
    out = layer.solve([0, 0, 0, -np.pi / 2, 0])
    assert out.converged and out.residual < 1e-9
    assert out.in_gap.tolist() == [False, False, False, False, True]
    assert abs(out.theta[4]) <= 0.035 / 2
    assert abs(out.torque[4]) < 1e-9


# the command where the bracketing alone left joint 3 in its gap with +0.0227 N m and
# called it converged (an outside audit; round five's code)
AUDIT_COMMAND = [
    -1.9812966151776987, 0.4350304921094029, -1.8676384388304126, -1.853978811633444,
    -0.9813521357393178,
]  # fmt: skip


def _rest_holds(layer, q, out):
    """Independent check with Pinocchio: per joint, eq. 17 in contact, no torque in the
    gap (within TORQUE_TOL) and the output within its gap there."""
    rows = np.atleast_2d(out.theta)
    torque = -np.array([pin.computeGeneralizedGravity(layer.model, layer.data, t) for t in rows])
    torque = torque.reshape(out.theta.shape)
    np.testing.assert_allclose(out.torque, torque, rtol=0, atol=1e-12)
    offset = out.theta - q
    gap = out.in_gap
    assert np.all(np.abs(torque[gap]) <= bl.TORQUE_TOL)
    delta = np.broadcast_to(layer.delta, offset.shape)
    assert np.all(np.abs(offset[gap]) <= delta[gap] / 2)
    law = bl.offset(torque, layer.nominal_torque, layer.delta, layer.k_h)
    np.testing.assert_allclose(offset[~gap], law[~gap], rtol=0, atol=1e-11)


def test_audit_command_rests_where_its_torque_vanishes(katana):
    layer = bl.Backlash(katana, delta=0.035, k_h=0.2, payload=0.5)
    out = layer.solve(AUDIT_COMMAND)
    assert out.converged and out.in_gap[2]
    assert abs(out.torque[2]) <= bl.TORQUE_TOL  # was +0.0227 N m
    assert out.theta[2] - AUDIT_COMMAND[2] == pytest.approx(0.00461, abs=1e-5)
    _rest_holds(layer, np.asarray(AUDIT_COMMAND), out)
    theta, residual = bl.dynamic_outputs(layer, AUDIT_COMMAND, np.zeros(5), np.zeros(5))
    np.testing.assert_allclose(out.theta, theta, rtol=0, atol=1e-12)
    assert residual < 1e-10


@settings(max_examples=25, deadline=None)
@given(
    name=st.sampled_from(["katana_6m180", "katana_6m90a", "katana_6m90b"]),
    payload=st.floats(0.0, 1.0),
    delta=st.floats(0.005, 0.08),
    k_h=st.floats(0.05, 0.4),
    seed=st.integers(0, 2**16),
)
@example(name="katana_6m90b", payload=0.03125, delta=0.025390625, k_h=0.125, seed=252)
def test_every_rest_holds_and_is_the_dynamic_rest(name, payload, delta, k_h, seed):
    """Random commands, payloads and gaps: every joint in its gap carries no torque, every
    joint in contact obeys eq. 17, ``converged`` is true, and the static answer is the rest
    of the motion's reading at zero velocity and acceleration."""
    robot = toolkit.load(name)
    layer = bl.Backlash(robot, delta=delta, k_h=k_h, payload=payload)
    q = robot.random_q(400, seed=seed)
    out = layer.solve(q)
    assert out.converged.all()
    _rest_holds(layer, q, out)
    some = np.flatnonzero(out.in_gap.any(axis=1))[:5]
    for i in some:
        theta, residual = bl.dynamic_outputs(layer, q[i], np.zeros(robot.nq), np.zeros(robot.nq))
        # the same rest: a joint in contact to 1e-9 rad; a joint in its gap is placed to
        # TORQUE_TOL (1e-9 N m), which on a nearly balanced wrist leaves play: 2.2e-6 rad
        # for the Katana 6M90B's wrist at 6e-11 N m (the example above; both are rests)
        gap = out.in_gap[i]
        np.testing.assert_allclose(out.theta[i][~gap], theta[~gap], rtol=0, atol=1e-9)
        np.testing.assert_allclose(out.theta[i][gap], theta[gap], rtol=0, atol=1e-5)
        assert residual < 1e-10


@pytest.mark.slow
@pytest.mark.parametrize("name", ["katana_6m180", "katana_6m90a", "katana_6m90b"])
@pytest.mark.parametrize("payload", [0.0, 0.5])
def test_no_joint_in_its_gap_carries_torque_over_100000_commands(name, payload):
    robot = toolkit.load(name)
    layer = bl.Backlash(robot, delta=0.035, k_h=0.2, payload=payload)
    q = robot.random_q(100_000, seed=17)
    out = layer.solve(q)
    assert out.converged.all()
    assert out.in_gap.any(axis=1).sum() > 500  # the case is common: about 1 % of commands
    assert np.abs(out.torque[out.in_gap]).max() <= bl.TORQUE_TOL
    sample = np.concatenate([np.flatnonzero(out.in_gap.any(axis=1))[:200], np.arange(200)])
    for i in sample:
        one = out._replace(theta=out.theta[i], torque=out.torque[i], in_gap=out.in_gap[i])
        _rest_holds(layer, q[i], one)


def test_sag_follows_the_load(layer, katana):
    q = katana.random_q(300, seed=13)
    out = layer.solve(q)
    moved = out.theta - q
    loaded = (np.abs(out.torque) > 1e-6) & ~out.in_gap
    assert np.all(np.sign(moved[loaded]) == np.sign(out.torque[loaded]))
    # the weight does positive work on the offsets: the arm goes down
    assert np.all(np.sum(out.torque * moved, axis=1) > 0)


def test_stretched_arm_sags_more_with_payload(katana):
    q = np.array([0.0, 0.0, 0.0, -np.pi / 2, 0.0])
    ideal_z = katana.fk(q)[2, 3]
    drops = [ideal_z - bl.Backlash(katana, payload=m).fk(q)[2, 3] for m in (0.0, 0.25, 0.5, 1.0)]
    assert drops[0] > 0.01  # the sign term alone: about delta/2 per joint over 0.63 m
    assert all(b > a for a, b in itertools.pairwise(drops))


# ---------------------------------------------------------------- compensation
def test_compensation_hits_the_target_the_naive_command_misses(layer, katana):
    rng = np.random.default_rng(21)
    for _ in range(5):
        q_true = katana.random_q(seed=rng)
        target = katana.fk(q_true)
        naive = katana.ik(target, mask=[1, 1, 1, 1, 1, 0])
        assert naive.success
        naive_miss = np.linalg.norm(layer.fk(naive.q)[:3, 3] - target[:3, 3])
        assert naive_miss > 1e-3
        res = layer.compensate(target, mask=[1, 1, 1, 1, 1, 0])
        assert res.success, res
        actual = layer.fk(res.q)
        assert np.linalg.norm(actual[:3, 3] - target[:3, 3]) < 1e-6
        assert katana.joints.within_limits(res.q)


def test_compensation_of_an_unreachable_target_fails(layer):
    res = layer.compensate([2.0, 0.0, 0.3], restarts=3)
    assert not res.success
    assert res.position_error > 0.5


# ---------------------------------------------------------------- calibration
def _simulated(katana, n=60, noise=1e-4, seed=0, payload=0.5, **truth):
    rng = np.random.default_rng(seed)
    q = katana.random_q(n, seed=rng)
    truth_layer = bl.Backlash(katana, payload=payload, **truth)
    tips = truth_layer.tip_positions(q) + rng.normal(scale=noise, size=(n, 3))
    return q, tips, truth_layer


def test_calibration_recovers_delta_and_kh(katana):
    q, tips, _ = _simulated(katana, delta=0.035, k_h=0.2)
    cal = bl.calibrate(katana, q, tips, payload=0.5)
    assert cal.converged
    assert cal.delta == pytest.approx(0.035, rel=0.05)
    assert cal.k_h == pytest.approx(0.2, rel=0.2)
    assert 0.5e-4 < cal.rms < 2e-4  # the simulated 0.1 mm noise
    assert 0 < cal.delta_stderr < 0.0035 and 0 < cal.k_h_stderr < 0.1


def test_calibration_from_joint_angles(katana):
    rng = np.random.default_rng(3)
    q = katana.random_q(40, seed=rng)
    theta = bl.Backlash(katana, delta=0.03, k_h=0.3).output_angles(q)
    measured = theta + rng.normal(scale=1e-4, size=theta.shape)
    cal = bl.calibrate(katana, q, measured_angles=measured)
    assert cal.delta == pytest.approx(0.03, rel=0.02)
    assert cal.k_h == pytest.approx(0.3, rel=0.1)


def test_calibration_per_joint(katana):
    delta = np.array([0.035, 0.03, 0.04, 0.02, 0.035])
    q, tips, _ = _simulated(katana, n=80, noise=1e-5, seed=4, delta=delta, k_h=0.2)
    cal = bl.calibrate(katana, q, tips, payload=0.5, per_joint=True)
    # joint 1 carries no gravity torque: it is not identifiable, its stderr says so
    np.testing.assert_allclose(cal.delta[1:4], delta[1:4], rtol=0.05)
    np.testing.assert_allclose(cal.k_h[1:4], 0.2, rtol=0.05)
    assert cal.delta_stderr.shape == (5,)
    assert np.isinf(cal.delta_stderr[0]) and np.isinf(cal.k_h_stderr[0])
    assert np.all(np.isfinite(cal.delta_stderr[1:4]))


def test_calibration_rejects_bad_measurements(katana):
    q = katana.random_q(5, seed=0)
    with pytest.raises(InvalidParameterError, match="shape"):
        bl.calibrate(katana, q, np.zeros((4, 3)))
    with pytest.raises(InvalidParameterError, match="exactly one"):
        bl.calibrate(katana, q)


# ---------------------------------------------------------------- construction
def test_other_robots_need_nominal_torques():
    ur5 = toolkit.load_example("ur5")
    with pytest.raises(InvalidParameterError, match="nominal_torque"):
        bl.Backlash(ur5)
    layer = bl.Backlash(ur5, nominal_torque=[150, 150, 150, 28, 28, 28], payload=1.0)
    out = layer.solve(ur5.random_q(100, seed=1))
    assert out.converged.all()


def test_constructor_arguments_are_readable_and_checked(katana):
    layer = bl.Backlash(katana, delta=[0.01, 0.02, 0.03, 0.04, 0.05], k_h=0.1, payload=0.2)
    assert layer.delta.tolist() == [0.01, 0.02, 0.03, 0.04, 0.05]
    assert layer.k_h.tolist() == [0.1] * 5
    np.testing.assert_allclose(layer.nominal_torque, toolkit.katana.nominal_torques()[:5])
    assert layer.payload == 0.2
    with pytest.raises(InvalidParameterError, match="shape"):
        bl.Backlash(katana, delta=[0.1, 0.2])
    with pytest.raises(InvalidParameterError, match="payload"):
        bl.Backlash(katana, payload=-1)
    with pytest.raises(InvalidParameterError, match="k_h"):
        bl.Backlash(katana, k_h=-0.1)
    with pytest.raises(ConfigurationError):
        layer.output_angles([0, 0, np.nan, 0, 0])


# ---------------------------------------------------------------- figure 6 and maps
def test_figure6_paths(katana):
    data = bl.figure6(steps=21)
    base = 0.2015
    np.testing.assert_allclose(data.ideal_b[0], [0.329, 0, base + 0.3028], atol=1e-12)  # case 18
    np.testing.assert_allclose(data.ideal_b[-1], [0.6318, 0, base], atol=1e-12)  # case 19
    np.testing.assert_allclose(data.ideal_b2[-1], [0, 0, base + 0.6318], atol=1e-12)  # case 20
    assert data.actual_b[-1, 2] < data.ideal_b[-1, 2] - 0.01  # horizontal arm sags
    assert 0.005 < data.max_deviation_b < 0.1 and 0.005 < data.max_deviation_b2 < 0.1


def test_figure6_draws(tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    ax = bl.draw_figure6(bl.figure6(steps=11))
    ax.figure.savefig(tmp_path / "fig6.png")
    assert (tmp_path / "fig6.png").stat().st_size > 10_000
    assert len(ax.lines) >= 4


def test_error_map_and_grid(layer, katana):
    emap = bl.error_map(layer, 2000, seed=1)
    assert emap.error.shape == (2000,)
    assert 0 < emap.median <= emap.p95 <= emap.max
    # the vectorised route equals per-configuration Pinocchio FK
    for i in range(0, 2000, 200):
        actual = katana.fk(layer.output_angles(emap.q[i]))[:3, 3]
        assert np.linalg.norm(actual - katana.fk(emap.q[i])[:3, 3]) == pytest.approx(
            emap.error[i], abs=1e-12
        )
    a, b, err = bl.error_grid(layer, joints=(1, 2), steps=7)
    assert (
        err.shape == (7, 7) and a[0] == katana.joints.lower[1] and b[-1] == katana.joints.upper[2]
    )
    with pytest.raises(InvalidParameterError):
        bl.error_grid(layer, joints=(1, 1))


@settings(max_examples=30, deadline=None)
@given(st.floats(-50, 50), st.floats(0.1, 20), st.floats(0, 0.1), st.floats(0, 0.5))
def test_offset_is_odd_and_bounded(m, m_h, delta, k_h):
    off = bl.offset(m, m_h, delta, k_h)
    assert bl.offset(-m, m_h, delta, k_h) == pytest.approx(-off, abs=1e-15)
    assert abs(off) <= delta * (0.5 + k_h * abs(m) / m_h) + 1e-15


def test_two_equilibria_depend_on_the_approach_side(layer, katana):
    """A load pushing away from the middle of the gap has an equilibrium on each side."""
    found = 0
    for theta in katana.random_q(40, seed=2):
        q_cmd = layer.command_for(theta)
        plain = layer.solve(q_cmd)
        hinted = layer.solve(q_cmd, start=theta)
        assert plain.converged and hinted.converged
        np.testing.assert_allclose(hinted.theta, theta, atol=1e-9)
        if np.abs(plain.theta - theta).max() > 1e-3:
            found += 1
            flipped = np.abs(plain.theta - theta) > 1e-3
            # the other equilibrium lies on the other side of the same gap
            assert np.all(np.sign(plain.torque[flipped]) != np.sign(hinted.torque[flipped]))
    assert found >= 1


def test_hysteresis_checks_its_parameters_like_offset():
    with pytest.raises(InvalidParameterError, match="nominal_torque"):
        bl.hysteresis_offsets([[1.0]], [0.0])
    with pytest.raises(InvalidParameterError, match="delta"):
        bl.hysteresis_offsets([[1.0]], [1.0], delta=-0.1)


def test_eq17_with_torques_and_nominal_torques_of_other_lengths():
    with pytest.raises(toolkit.InvalidParameterError, match="number of joints"):
        backlash.offset(np.ones(5), np.ones(3))
