"""Joint trajectories (toolkit.motion): through their waypoints at their times, at rest where
they say, their derivatives equal to finite differences of their values, within the limits
they were built for when sampled at 1 kHz, the torques along them those of inverse
dynamics, and [P3]'s point velocity and acceleration along one equal to finite differences
of the forward kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import dynamics, motion
from toolkit.errors import ConfigurationError, InvalidParameterError

KINDS = ("quintic", "cubic", "trapezoidal")


@pytest.fixture(scope="module")
def katana():
    return toolkit.load("katana_6m180")


def _build(kind, robot, W, **kw):
    if kind == "trapezoidal":
        return motion.trapezoidal(robot, W, acceleration=kw.pop("acceleration", 2.0), **kw)
    return getattr(motion, kind)(robot, W, **kw)


@pytest.mark.parametrize("kind", KINDS)
def test_it_passes_its_waypoints_at_its_times_and_starts_and_ends_at_rest(katana, kind):
    W = katana.random_q(5, seed=1)
    tr = _build(kind, katana, W)
    q, qd, qdd = tr.evaluate(tr.times)
    np.testing.assert_allclose(q, katana.angles(W), atol=1e-12)
    assert np.abs(qd[[0, -1]]).max() < 1e-12
    if kind != "cubic":  # quintic and trapezoid stop at every waypoint
        assert np.abs(qd).max() < 1e-12
    if kind == "quintic":
        assert np.abs(qdd).max() < 1e-9
    s = tr.at_rate(katana, 1000)
    assert s.t[0] == 0 and s.t[-1] == pytest.approx(tr.duration)
    np.testing.assert_allclose(s.q[-1], W[-1], atol=1e-12)
    assert np.all(np.diff(s.t) > 0)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), kind=st.sampled_from(KINDS), u=st.floats(0.01, 0.99))
def test_its_derivatives_are_those_of_its_values(seed, kind, u):
    robot = toolkit.load("katana_6m180")
    tr = _build(kind, robot, robot.random_q(3, seed=seed % 1000))
    t, h = u * tr.duration, 1e-5
    _, qd, qdd = (x[0] for x in tr.evaluate([t]))
    (qp, qdp, _), (qm, qdm, _) = (tuple(x[0] for x in tr.evaluate([t + s])) for s in (h, -h))
    np.testing.assert_allclose(qd, (qp - qm) / (2 * h), atol=1e-5 * (1 + np.abs(qd).max()))
    scale = 1 + np.abs(qdd).max()
    if not np.any(np.abs(tr.breaks - t) < 2 * h):  # a trapezoid's acceleration jumps at breaks
        np.testing.assert_allclose(qdd, (qdp - qdm) / (2 * h), atol=1e-4 * scale)


@pytest.mark.parametrize("kind", ["quintic", "trapezoidal"])
def test_it_stays_within_the_limits_it_was_built_for(katana, kind):
    v, a = np.array([1.0, 0.6, 0.8, 1.5, 2.0]), np.array([2.0, 1.0, 1.5, 3.0, 4.0])
    tr = _build(kind, katana, katana.random_q(6, seed=4), velocity=v, acceleration=a)
    s = tr.at_rate(katana, 1000)
    assert np.all(np.abs(s.qd) <= v * (1 + 1e-9))
    assert np.all(np.abs(s.qdd) <= a * (1 + 1e-9))
    peak_v, peak_a = tr.peaks()
    # each segment as short as the limits allow: some joint reaches one of them
    assert np.max(np.maximum(peak_v / v, peak_a / a)) > 0.99


def test_without_limits_given_the_descriptions_velocities_hold(katana):
    tr = motion.quintic(katana, katana.random_q(3, seed=7))
    assert np.all(tr.peaks()[0] <= np.asarray(katana.model.velocityLimit) * (1 + 1e-9))


def test_the_torques_along_it_are_inverse_dynamics_at_its_samples(katana):
    tr = motion.quintic(katana, katana.random_q(3, seed=2))
    s, tau = tr.torques(katana, rate=200, payload=0.5)
    k = len(s.t) // 3
    np.testing.assert_allclose(
        tau[k], dynamics.inverse_dynamics(katana, s.q[k], s.qd[k], s.qdd[k], payload=0.5)
    )
    at_rest = dynamics.inverse_dynamics(katana, s.q[0], np.zeros(5), np.zeros(5), payload=0.5)
    np.testing.assert_allclose(tau[0], at_rest, atol=1e-9)  # a quintic starts at rest


def test_p3_point_kinematics_along_a_trajectory_are_those_of_its_motion():
    """[P3] eqs. 3-4 (Robot.point_kinematics) along a trajectory of each positioning
    structure equal central differences of the point's forward kinematics in time."""
    for name in ("cartesian", "cylindrical", "spherical", "scara", "anthropomorphic"):
        robot = toolkit.load(name)
        tr = motion.quintic(robot, robot.random_q(3, seed=5), times=[0.0, 1.0, 2.5])
        rho = np.array([0.01, -0.02, 0.03])
        h = 1e-5
        for t in (0.3, 1.2, 2.0):
            q, qd, qdd = (robot.q_from_angles(x[0]) if i == 0 else x[0]
                          for i, x in enumerate(tr.evaluate([t])))  # fmt: skip
            r, v, a = robot.point_kinematics(q, qd, qdd, rho=rho)

            def point(s, robot=robot, tr=tr, rho=rho):
                T = robot.fk(robot.q_from_angles(tr.evaluate([s])[0][0]))
                return T[:3, :3] @ rho + T[:3, 3]

            np.testing.assert_allclose(r, point(t), atol=1e-12)
            np.testing.assert_allclose(v, (point(t + h) - point(t - h)) / (2 * h), atol=1e-6)
            fd = (point(t + h) - 2 * point(t) + point(t - h)) / h**2
            np.testing.assert_allclose(a, fd, atol=2e-3 * (1 + np.abs(a).max()))


def test_bad_input_is_refused(katana):
    W = katana.random_q(3, seed=1)
    with pytest.raises(InvalidParameterError, match="at least 2"):
        motion.quintic(katana, W[:1])
    with pytest.raises(InvalidParameterError, match="strictly increasing"):
        motion.quintic(katana, W, times=[0.0, 1.0, 1.0])
    with pytest.raises(InvalidParameterError, match="times"):
        motion.cubic(katana, W, times=[0.0, 1.0])
    with pytest.raises(InvalidParameterError, match="acceleration"):
        motion.trapezoidal(katana, W, acceleration=[1.0, -1.0, 1.0, 1.0, 1.0])
    with pytest.raises(InvalidParameterError, match="no motion"):
        motion.quintic(katana, np.stack([W[0], W[0]]))
    outside = W.copy()
    outside[1, 1] = katana.upper[1] + 0.5
    with pytest.raises(InvalidParameterError, match="waypoint 1 is outside"):
        motion.quintic(katana, outside)
    with pytest.raises(ConfigurationError):
        motion.quintic(katana, np.full((2, 5), np.nan))
    tr = motion.quintic(katana, W)
    with pytest.raises(InvalidParameterError, match="within"):
        tr.evaluate([tr.duration + 1.0])
    with pytest.raises(InvalidParameterError, match="rate"):
        tr.at_rate(katana, 1e9)
