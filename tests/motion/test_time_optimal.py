"""Time-optimal trajectories (toolkit.motion.time_optimal, TOPP-RA through toppra): within
the limits when sampled, at rest at both ends, on the path, faster than the profiles, and
the exact pieces equal toppra's own evaluation of its answer."""

from __future__ import annotations

import numpy as np
import pytest

import toolkit
from toolkit import dynamics, motion

toppra = pytest.importorskip("toppra")  # the motion extra; the test extra installs it

KATANA = toolkit.load("katana_6m180")
VMAX = np.asarray(KATANA.model.velocityLimit)
AMAX = 2.0
W = KATANA.random_q(4, seed=3)
FAST = motion.time_optimal(KATANA, W, acceleration=AMAX)


def _kilohertz(trajectory: motion.Trajectory) -> tuple[np.ndarray, ...]:
    t = np.arange(0.0, trajectory.duration, 1e-3) + 3.7e-4  # off the pieces' breaks
    return trajectory.evaluate(np.append(t[t < trajectory.duration], trajectory.duration))


def test_the_limits_hold_at_a_kilohertz_and_the_motion_rests_at_both_ends():
    _, qd, qdd = _kilohertz(FAST)
    assert (np.abs(qd) / VMAX).max() <= 1 + 1e-6
    assert np.abs(qdd).max() <= AMAX * (1 + 1e-6)
    _, v0, _ = FAST.evaluate([0.0, FAST.duration])
    np.testing.assert_allclose(v0, 0.0, atol=1e-12)
    np.testing.assert_allclose(FAST.evaluate([0.0])[0][0], KATANA.joints.angles(W[0]), atol=1e-12)
    np.testing.assert_allclose(FAST.evaluate([FAST.duration])[0][0], KATANA.joints.angles(W[-1]),
                               atol=1e-12)  # fmt: skip


def test_it_is_bang_bang_a_limit_is_reached_almost_all_the_time():
    _, qd, qdd = _kilohertz(FAST)
    tight = np.maximum(np.abs(qd) / VMAX, np.abs(qdd) / AMAX).max(axis=1)
    assert (tight > 0.97).mean() > 0.85


def test_it_is_faster_than_the_profiles_within_the_same_limits():
    rest = motion.quintic(KATANA, W, acceleration=AMAX)
    trapezoid = motion.trapezoidal(KATANA, W, acceleration=AMAX)
    assert FAST.duration < min(rest.duration, trapezoid.duration)


def test_a_long_path_is_as_fast_as_toppra_on_a_fine_grid_and_holds_its_limits():
    """A UR5 tool circle through 300 waypoints (its chords' sum rounds below 1, and TOPP-RA's
    default grid passes the acceleration limit 1.3 times between its points): the motion
    holds every limit at 1 kHz, reaches one (no slack left by tightening), and lasts no
    longer than 1.01 times toppra's own answer on 4,000 grid points and every knot."""
    ur5 = toolkit.load_example("ur5")
    q0 = np.array([0.3, -1.2, 1.4, -1.8, -1.57, 0.4])
    s = np.linspace(0.0, 1.0, 300)
    targets = np.repeat(ur5.fk(q0)[None], len(s), axis=0)
    targets[:, 0, 3] += 0.15 * (np.cos(2 * np.pi * s) - 1.0)
    targets[:, 1, 3] += 0.15 * np.sin(2 * np.pi * s)
    W = np.asarray(ur5.ik_path(targets, q0).q)
    v, a = np.asarray(ur5.model.velocityLimit), np.full(ur5.joints.nv, AMAX)
    fast = motion.time_optimal(ur5, W, acceleration=AMAX)
    _, qd, qdd = _kilohertz(fast)
    peak = max((np.abs(qd) / v).max(), (np.abs(qdd) / a).max())
    assert 0.997 <= peak <= 1 + 1e-6
    chord = np.linalg.norm(np.diff(W, axis=0), axis=1)
    knots = np.concatenate([[0.0], np.cumsum(chord)]) / chord.sum()
    knots[-1] = 1.0
    path = toppra.SplineInterpolator(knots, W, bc_type="clamped")
    limits = [toppra.constraint.JointVelocityConstraint(np.stack([-v, v], axis=1)),
              toppra.constraint.JointAccelerationConstraint(np.stack([-a, a], axis=1))]  # fmt: skip
    grid = np.union1d(np.linspace(0.0, 1.0, 4000), knots)
    theirs = toppra.algorithm.TOPPRA(limits, path, gridpoints=grid,
                                     parametrizer="ParametrizeConstAccel")  # fmt: skip
    assert fast.duration <= 1.01 * theirs.compute_trajectory(0.0, 0.0).duration


def test_it_follows_the_spline_through_the_waypoints():
    from scipy.interpolate import CubicSpline

    A = KATANA.joints.angles(W)
    chord = np.linalg.norm(np.diff(A, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(chord)]) / chord.sum()
    dense = CubicSpline(s, A, bc_type="clamped")(np.linspace(0.0, 1.0, 40_001))
    q, _, _ = _kilohertz(FAST)
    gaps = [np.abs(dense - row).max(axis=1).min() for row in q[::23]]
    assert max(gaps) <= np.abs(np.diff(dense, axis=0)).max() / 2 + 1e-9  # the grid's own


def test_the_exact_pieces_equal_toppras_own_evaluation():
    from toolkit.motion.optimal import exact_pieces

    A = KATANA.joints.angles(W)
    chord = np.linalg.norm(np.diff(A, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(chord)]) / chord.sum()
    path = toppra.SplineInterpolator(s, A, bc_type="clamped")
    con = toppra.constraint
    limits = [con.JointVelocityConstraint(np.stack([-VMAX, VMAX], axis=1)),
              con.JointAccelerationConstraint(np.full((5, 2), [-AMAX, AMAX]))]  # fmt: skip
    solver = toppra.algorithm.TOPPRA(limits, path, parametrizer="ParametrizeConstAccel")
    theirs = solver.compute_trajectory(0.0, 0.0)
    data = solver.problem_data
    breaks, c = exact_pieces(path.cspl, np.asarray(data.gridpoints), np.asarray(data.sd_vec))
    ours = motion.Trajectory(breaks, c, A, breaks[[0, -1]], "time-optimal")
    assert ours.duration == pytest.approx(theirs.duration, rel=1e-12)
    t = np.random.default_rng(4).uniform(0.0, ours.duration, 2000)
    q, qd, qdd = ours.evaluate(t)
    np.testing.assert_allclose(q, theirs(t), atol=1e-10)
    np.testing.assert_allclose(qd, theirs(t, 1), atol=1e-8)
    np.testing.assert_allclose(qdd, theirs(t, 2), atol=1e-6)


@pytest.mark.slow
def test_torque_limits_hold_by_an_independent_route_and_cost_time():
    free = motion.time_optimal(KATANA, W, acceleration=5.0)
    s, tau = free.torques(KATANA, 1000.0)
    hold = np.abs(KATANA.gravity(s.q)).max(axis=0)  # what holding the arm needs, at most
    limit = hold + 0.5 * (np.abs(tau).max(axis=0) - hold) + 1e-3  # the motion's share halved
    held = motion.time_optimal(KATANA, W, acceleration=5.0, torque=limit)
    q, qd, qdd = _kilohertz(held)
    need = dynamics.inverse_dynamics(KATANA, KATANA.joints.q_from_angles(q), qd, qdd)
    assert (np.abs(need) / limit).max() <= 1 + 1e-6
    assert held.duration > free.duration


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"acceleration": -1.0}, "acceleration"),
        ({"acceleration": [1.0, 2.0]}, "acceleration"),
        ({"acceleration": 1.0, "velocity": 0.0}, "velocity"),
        ({"acceleration": 1.0, "torque": [1e-3] * 5}, "no timing"),
        ({"acceleration": 1.0, "waypoints": [W[0], W[0], W[1]]}, "are the same"),
        ({"acceleration": 1.0, "waypoints": [W[0]]}, "at least 2"),
    ],
)
def test_bad_requests_are_refused(kwargs, message):
    waypoints = kwargs.pop("waypoints", W)
    with pytest.raises(toolkit.ToolkitError, match=message):
        motion.time_optimal(KATANA, waypoints, **kwargs)


def test_a_jerk_limited_motion_rests_at_every_waypoint_within_its_limits():
    ruckig = pytest.importorskip("ruckig")
    move = motion.jerk_limited(KATANA, W, acceleration=AMAX, jerk=20.0)
    assert move.kind == "jerk-limited" and len(move.times) == len(W)
    q, qd, qdd = move.evaluate(move.times)
    np.testing.assert_allclose(q, KATANA.joints.angles(W), atol=1e-12)
    np.testing.assert_allclose(qd, 0.0, atol=1e-12)
    np.testing.assert_allclose(qdd, 0.0, atol=1e-12)
    _, qd, qdd = _kilohertz(move)
    assert (np.abs(qd) / VMAX).max() <= 1 + 1e-9 and np.abs(qdd).max() <= AMAX * (1 + 1e-9)
    assert (6 * np.abs(move.coefficients[:, :, 3])).max() <= 20.0 * (1 + 1e-9)  # jerk
    # each segment equals Ruckig's own evaluation of it (a separate route: its at_time)
    given = ruckig.InputParameter(5)
    a, b = KATANA.joints.angles(W[0]), KATANA.joints.angles(W[1])
    given.current_position, given.target_position = a.tolist(), b.tolist()
    given.max_velocity, given.max_acceleration, given.max_jerk = (
        VMAX.tolist(), [AMAX] * 5, [20.0] * 5)  # fmt: skip
    theirs = ruckig.Trajectory(5)
    ruckig.Ruckig(5).calculate(given, theirs)
    assert theirs.duration == pytest.approx(move.times[1], rel=1e-12)
    for t in np.random.default_rng(3).uniform(0.0, theirs.duration, 50):
        p, v, acc = theirs.at_time(t)
        ours = move.evaluate([t])
        for mine, ref in zip(ours, (p, v, acc), strict=True):
            np.testing.assert_allclose(mine[0], ref, atol=1e-10)
    # a looser jerk limit approaches the trapezoidal profile's time from above
    loose = motion.jerk_limited(KATANA, W, acceleration=AMAX, jerk=1e5)
    trapezoid = motion.trapezoidal(KATANA, W, acceleration=AMAX)
    assert trapezoid.duration <= loose.duration < move.duration
    assert loose.duration == pytest.approx(trapezoid.duration, rel=1e-3)
    with pytest.raises(toolkit.ToolkitError, match="jerk"):
        motion.jerk_limited(KATANA, W, acceleration=AMAX, jerk=-1.0)
    with pytest.raises(toolkit.ToolkitError, match="the same"):
        motion.jerk_limited(KATANA, [W[0], W[0]], acceleration=AMAX, jerk=10.0)


def _online(start, acceleration=3.0, jerk=30.0, dt=0.004):
    ur5 = toolkit.load_example("ur5")
    return ur5, motion.Online(ur5, dt, acceleration=acceleration, jerk=jerk,
                              start=ur5.joints.q_from_angles(start))  # fmt: skip


def test_online_motion_reaches_its_target_at_rest_within_every_limit():
    """Cycle by cycle: velocity, acceleration and jerk (the acceleration's change over a
    cycle) within their limits; the last state is the target, at rest; the positions are
    the integral of the velocities (trapezoids, to the cycle's order)."""
    ur5, online = _online([0.0, -1.2, 1.2, -1.5, -1.5, 0.0])
    target = ur5.joints.q_from_angles([1.0, -1.0, 1.0, -1.2, -1.5, 0.5])
    s = online.run(target)
    v, a, j = online.limits
    assert (np.abs(s["qd"]) <= v * (1 + 1e-9)).all() and (np.abs(s["qdd"]) <= a * (1 + 1e-9)).all()
    assert (np.abs(np.diff(s["qdd"], axis=0)) <= j * online.dt * (1 + 1e-6)).all()
    np.testing.assert_allclose(s["values"][-1], ur5.joints.angles(target), atol=1e-12)
    assert np.abs(s["qd"][-1]).max() < 1e-12 and np.abs(s["qdd"][-1]).max() < 1e-12
    moved = np.diff(s["values"], axis=0)
    mean_v = 0.5 * (s["qd"][1:] + s["qd"][:-1]) * online.dt
    np.testing.assert_allclose(moved, mean_v, atol=2 * a.max() * online.dt**2)
    np.testing.assert_allclose(online.q, target, atol=1e-12)


def test_a_target_changed_mid_motion_is_followed_smoothly():
    """After 100 cycles toward one target, another: the acceleration never jumps by more
    than the jerk limit allows in a cycle, the new target is reached at rest."""
    ur5, online = _online([0.0, -1.2, 1.2, -1.5, -1.5, 0.0])
    first = ur5.joints.q_from_angles([1.2, -1.0, 1.0, -1.2, -1.5, 0.5])
    second = ur5.joints.q_from_angles([-0.8, -1.4, 1.4, -1.6, -1.3, -0.4])
    accelerations = []
    for _ in range(100):
        assert not online.step(first)
        accelerations.append(online.qdd.copy())
    assert np.abs(online.qd).max() > 0.1  # moving when the target changes
    s = online.run(second)
    qdd = np.vstack([accelerations, s["qdd"]])
    assert (np.abs(np.diff(qdd, axis=0)) <= online.limits[2] * online.dt * (1 + 1e-6)).all()
    np.testing.assert_allclose(s["values"][-1], ur5.joints.angles(second), atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"dt": 0.0}, "dt"), ({"jerk": -1.0}, "jerk"), ({"acceleration": [1.0, 2.0]}, "acceleration")],
)
def test_bad_online_settings_are_refused(kwargs, message):
    ur5 = toolkit.load_example("ur5")
    settings = {"dt": 0.004, "acceleration": 3.0, "jerk": 30.0, **kwargs}
    with pytest.raises(toolkit.InvalidParameterError, match=message):
        motion.Online(ur5, settings.pop("dt"), **settings)
    online = motion.Online(ur5, 0.004, acceleration=3.0, jerk=30.0)
    with pytest.raises(toolkit.ToolkitError, match="NaN"):
        online.step(np.full(ur5.nq, np.nan))
    with pytest.raises(toolkit.InvalidParameterError, match="outside"):
        online.step(np.full(ur5.nq, 9.0))


def test_binding_torque_limits_with_a_payload_match_toppras_own_torque_constrained_answer():
    """Torque limits that bind (holding the arm and its 0.5 kg payload plus half of what the
    free motion adds): the answer reaches a torque limit (a ratio of at least 0.99), holds
    every limit at 1 kHz by inverse dynamics with the payload, and lasts no longer than
    1.02 times toppra's own answer with its JointTorqueConstraint on 4,000 grid points."""
    payload = 0.5
    free = motion.time_optimal(KATANA, W, acceleration=5.0)
    s, tau = free.torques(KATANA, 1000.0, payload=payload)
    hold = np.abs(dynamics.gravity(KATANA, s.q, payload=payload)).max(axis=0)
    limit = hold + 0.5 * (np.abs(tau).max(axis=0) - hold) + 1e-3
    held = motion.time_optimal(KATANA, W, acceleration=5.0, torque=limit, payload=payload)
    q, qd, qdd = _kilohertz(held)
    need = dynamics.inverse_dynamics(KATANA, KATANA.joints.q_from_angles(q), qd, qdd,
                                     payload=payload)  # fmt: skip
    ratio = (np.abs(need) / limit).max()
    assert 0.99 <= ratio <= 1 + 1e-6  # the torque limits bind, and hold
    v, a = VMAX, np.full(KATANA.joints.nv, 5.0)
    chord = np.linalg.norm(np.diff(W, axis=0), axis=1)
    knots = np.concatenate([[0.0], np.cumsum(chord)]) / chord.sum()
    knots[-1] = 1.0
    path = toppra.SplineInterpolator(knots, W, bc_type="clamped")

    def inverse(qs, qds, qdds):
        return dynamics.inverse_dynamics(KATANA, qs, qds, qdds, payload=payload)

    torque = toppra.constraint.JointTorqueConstraint(
        inverse, np.stack([-limit, limit], axis=1), np.zeros(KATANA.joints.nv)
    )
    limits = [toppra.constraint.JointVelocityConstraint(np.stack([-v, v], axis=1)),
              toppra.constraint.JointAccelerationConstraint(np.stack([-a, a], axis=1)),
              torque]  # fmt: skip
    grid = np.union1d(np.linspace(0.0, 1.0, 4000), knots)
    theirs = toppra.algorithm.TOPPRA(limits, path, gridpoints=grid,
                                     parametrizer="ParametrizeConstAccel")  # fmt: skip
    assert held.duration <= 1.02 * theirs.compute_trajectory(0.0, 0.0).duration
