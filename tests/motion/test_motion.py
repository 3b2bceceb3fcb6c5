"""Joint trajectories (toolkit.motion): through their waypoints at their times, at rest where
they say, their derivatives equal to finite differences of their values, within the limits
they were built for when sampled at 1 kHz, the torques along them those of inverse
dynamics, and [P3]'s point velocity and acceleration along one equal to finite differences
of the forward kinematics."""

from __future__ import annotations

import os

import numpy as np
import pinocchio as pin
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
    np.testing.assert_allclose(q, katana.joints.angles(W), atol=1e-12)
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
            q, qd, qdd = (robot.joints.q_from_angles(x[0]) if i == 0 else x[0]
                          for i, x in enumerate(tr.evaluate([t])))  # fmt: skip
            r, v, a = robot.point_kinematics(q, qd, qdd, rho=rho)

            def point(s, robot=robot, tr=tr, rho=rho):
                T = robot.fk(robot.joints.q_from_angles(tr.evaluate([s])[0][0]))
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
    outside[1, 1] = katana.joints.upper[1] + 0.5
    with pytest.raises(InvalidParameterError, match="waypoint 1 is outside"):
        motion.quintic(katana, outside)
    with pytest.raises(ConfigurationError):
        motion.quintic(katana, np.full((2, 5), np.nan))
    tr = motion.quintic(katana, W)
    with pytest.raises(InvalidParameterError, match="within"):
        tr.evaluate([tr.duration + 1.0])
    with pytest.raises(InvalidParameterError, match="rate"):
        tr.at_rate(katana, 1e9)


# ---------------------------------------------------------------- CSV
def test_a_trajectory_written_to_csv_reads_back_as_itself(katana, tmp_path):
    """write_csv's samples (17 digits) read back as the piecewise quintic through them:
    equal at the samples and, between them, to the original within the interpolation's
    error; the torques column is inverse dynamics at the samples."""
    W = katana.random_q(3, seed=4)
    traj = motion.quintic(katana, W, velocity=np.full(katana.joints.nv, 0.8), acceleration=2.0)
    path = motion.write_csv(traj, katana, tmp_path / "motion.csv", rate=200.0)
    back = motion.read_trajectory(path, katana)
    assert back.kind == "csv" and back.duration == pytest.approx(traj.duration, abs=1e-12)
    samples, tau = traj.torques(katana, 200.0)
    q, qd, qdd = back.evaluate(samples.t)
    np.testing.assert_allclose(q, samples.angles, atol=1e-12)
    # the last interval is a remainder (0.18 ms here): its quintic is ill-conditioned, so
    # the end's derivatives are checked more loosely
    np.testing.assert_allclose(qd[:-1], samples.qd[:-1], atol=1e-9)
    np.testing.assert_allclose(qdd[:-1], samples.qdd[:-1], atol=1e-7)
    np.testing.assert_allclose(qd[-1], samples.qd[-1], atol=1e-6)
    np.testing.assert_allclose(qdd[-1], samples.qdd[-1], atol=1e-2)
    t = np.random.default_rng(1).uniform(0, traj.duration, 300)
    # between samples: the interpolation's error (largest across a waypoint, where the
    # original's third derivative jumps): 2e-8 rad at 200 Hz
    np.testing.assert_allclose(back.evaluate(t)[0], traj.evaluate(t)[0], atol=1e-7)
    header = path.read_text().splitlines()[0].split(",")
    assert header[0] == "t" and header[1] == f"q:{katana.joints.names[0]}"
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 1 + 3 * katana.joints.nv :], tau, rtol=1e-15, atol=1e-15)


def test_a_csv_of_positions_only_is_a_cubic_at_rest(katana, tmp_path):
    W = katana.random_q(4, seed=5)
    names = katana.joints.names
    rows = ["t," + ",".join(f"q:{n}" for n in reversed(names))]  # any column order
    for t, a in zip([2.0, 3.0, 4.5, 6.0], katana.joints.angles(W), strict=True):
        rows.append(f"{t}," + ",".join(repr(float(x)) for x in reversed(a)))
    path = tmp_path / "positions.csv"
    path.write_text("\ufeff" + "\n".join(rows) + "\n\n")  # a BOM and blank lines, as spreadsheets
    traj = motion.read_trajectory(path, katana)
    assert traj.duration == pytest.approx(4.0)
    q, qd, _ = traj.evaluate(np.array([0.0, 1.0, 2.5, 4.0]))
    np.testing.assert_allclose(q, katana.joints.angles(W), atol=1e-12)
    np.testing.assert_allclose(qd[[0, -1]], 0.0, atol=1e-12)


def test_bad_csv_trajectories_are_refused(katana, tmp_path):
    names = katana.joints.names
    q = ",".join(f"q:{n}" for n in names)
    zeros = ",".join("0" for _ in names)
    cases = {
        "no_t.csv": f"time,{q}\n0,{zeros}\n1,{zeros}\n",
        "one_row.csv": f"t,{q}\n0,{zeros}\n",
        "back.csv": f"t,{q}\n1,{zeros}\n0,{zeros}\n",
        "missing.csv": f"t,{q.rsplit(',', 1)[0]}\n0,{zeros[2:]}\n1,{zeros[2:]}\n",
        "nan.csv": f"t,{q}\n0,{zeros}\n1,nan{zeros[1:]}\n",
        "qd_only.csv": f"t,{q},{q.replace('q:', 'qd:')}\n0,{zeros},{zeros}\n1,{zeros},{zeros}\n",
    }
    for name, text in cases.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(InvalidParameterError):
            motion.read_trajectory(tmp_path / name, katana)
    with pytest.raises(InvalidParameterError, match=r"regular file|directory"):
        motion.read_trajectory(tmp_path, katana)
    os.mkfifo(tmp_path / "pipe.csv")  # refused at once, not waited on
    with pytest.raises(InvalidParameterError, match="regular file"):
        motion.read_trajectory(tmp_path / "pipe.csv", katana)
    with pytest.raises(InvalidParameterError, match="no such"):
        motion.read_trajectory(tmp_path / "absent.csv", katana)


# ---------------------------------------------------------------- Cartesian line
def test_a_cartesian_line_keeps_the_tool_on_the_line_and_its_branch():
    """The UR5's tool from one pose to another 0.25 m away: at 1 kHz every sample's tool
    position within 0.1 mm of the segment and its rotation within 1e-3 rad of the slerp at
    the same fraction of the way; the ends exact and at rest; one branch all along."""
    ur5 = toolkit.load_example("ur5")
    q0 = ur5.random_q(seed=31)
    T0 = ur5.fk(q0)
    T1 = T0.copy()
    T1[:3, 3] += [0.15, -0.1, 0.17]
    T1[:3, :3] = T0[:3, :3] @ pin.exp3(np.array([0.2, 0.1, -0.3]))
    traj = motion.cartesian(ur5, T0, T1, 2.0, q0=q0, steps=60)
    assert traj.kind == "cartesian" and traj.duration == pytest.approx(2.0)
    s = traj.at_rate(ur5, 1000.0)
    F = ur5.fk(s.q)
    p0, d = T0[:3, 3], T1[:3, 3] - T0[:3, 3]
    f = np.clip((F[:, :3, 3] - p0) @ d / (d @ d), 0, 1)
    off = np.linalg.norm(F[:, :3, 3] - (p0 + f[:, None] * d), axis=1)
    assert off.max() < 1e-4
    ideal = motion.lines.line_poses(T0, T1, f)
    angle = [
        np.linalg.norm(pin.log3(a[:3, :3].T @ b[:3, :3])) for a, b in zip(F, ideal, strict=True)
    ]
    assert max(angle) < 1e-3
    np.testing.assert_allclose(F[0], T0, atol=1e-9)
    np.testing.assert_allclose(F[-1], T1, atol=1e-9)
    np.testing.assert_allclose(s.qd[[0, -1]], 0.0, atol=1e-12)
    assert np.abs(np.diff(s.angles, axis=0)).max() < 0.05  # no branch change at 1 kHz
    # the time scaling: slow at the ends, the line's midpoint at half the duration
    mid = ur5.fk(traj.sample(ur5, [1.0]).q[0])[:3, 3]
    assert np.linalg.norm(mid - (p0 + 0.5 * d)) < 1e-4


def test_a_cartesian_line_out_of_reach_is_refused_naming_the_step():
    ur5 = toolkit.load_example("ur5")
    q0 = ur5.random_q(seed=31)
    T0 = ur5.fk(q0)
    T1 = T0.copy()
    T1[:3, 3] += [3.0, 0.0, 0.0]
    with pytest.raises(InvalidParameterError, match="reach at step"):
        motion.cartesian(ur5, T0, T1, 2.0, q0=q0, steps=20)
    for bad in ({"duration": 0.0}, {"steps": 1}, {"steps": 2.5}):
        kw = {"duration": 1.0, "steps": 10, **bad}
        with pytest.raises(InvalidParameterError):
            motion.cartesian(ur5, T0, T0, kw["duration"], q0=q0, steps=kw["steps"])
    with pytest.raises(InvalidParameterError, match="4x4"):
        motion.cartesian(ur5, T0[:3], T0, 1.0, q0=q0)


def test_a_trajectory_plots_against_time_with_its_limits_dashed():
    import matplotlib

    matplotlib.use("Agg")
    from toolkit import motion as mo

    katana = toolkit.load("katana_6m180")
    move = mo.quintic(katana, katana.random_q(3, seed=5))
    figure = mo.plot(move, katana, acceleration=2.0, rate=100)
    value, speed, accel, torque = figure.axes[:4]
    assert "[s]" in torque.get_xlabel() and all("[" in a.get_ylabel() for a in figure.axes[:4])
    for ax, limits in ((value, 10), (speed, 10), (accel, 10), (torque, 10)):
        dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
        assert len(dashed) == limits  # a lower and an upper bound per joint
        assert len(ax.get_lines()) - len(dashed) == katana.joints.nv
    speeds = sorted({abs(line.get_ydata()[0]) for line in speed.get_lines()
                     if line.get_linestyle() == "--"})  # fmt: skip
    np.testing.assert_allclose(speeds, sorted(set(np.asarray(katana.model.velocityLimit))))
    bare = mo.plot(move, katana, rate=100)
    assert not [line for line in bare.axes[2].get_lines() if line.get_linestyle() == "--"]
    with pytest.raises(toolkit.ToolkitError, match="Trajectory"):
        mo.plot(np.zeros((2, 5)), katana)
    with pytest.raises(toolkit.ToolkitError, match="acceleration"):
        mo.plot(move, katana, acceleration=[1.0, 2.0])


def test_the_cubic_spline_of_100000_waypoints_is_banded_and_continuous(katana):
    """Its knot velocities solve a tridiagonal system in O(K) (a dense solve asked for 75
    GiB): the spline is C2 at every knot, which only the right velocities give, and on a
    short path the banded answer equals a dense solve of the same system."""
    from toolkit.motion.profiles import tridiagonal

    rng = np.random.default_rng(2)
    for m in (1, 2, 3, 40):
        low, up = rng.uniform(0.1, 1.0, m - 1), rng.uniform(0.1, 1.0, m - 1)
        diag = 2 * (np.concatenate([[0.0], low]) + np.concatenate([up, [0.0]])) + 0.1
        rhs = rng.normal(size=(m, 3))
        dense = np.diag(diag) + np.diag(low, -1) + np.diag(up, 1)
        np.testing.assert_allclose(tridiagonal(low, diag, up, rhs), np.linalg.solve(dense, rhs),
                                   rtol=1e-12, atol=1e-12)  # fmt: skip
    W = katana.joints.neutral() + np.cumsum(rng.normal(0.0, 0.002, (100_000, 5)), axis=0)
    W = np.clip(W, katana.joints.lower + 0.1, katana.joints.upper - 0.1)
    spline = motion.cubic(katana, W)
    c, h = spline.coefficients, np.diff(spline.breaks)[:, None]
    end_acc = 2 * c[:-1, :, 2] + 6 * c[:-1, :, 3] * h[:-1]  # each piece's acceleration at its end
    np.testing.assert_allclose(
        end_acc, 2 * c[1:, :, 2], rtol=1e-7, atol=1e-7 * np.abs(end_acc).max()
    )
    end_vel = c[:-1, :, 1] + 2 * c[:-1, :, 2] * h[:-1] + 3 * c[:-1, :, 3] * h[:-1] ** 2
    np.testing.assert_allclose(end_vel, c[1:, :, 1], atol=1e-9)
    assert np.all(c[0, :, 1] == 0.0)  # at rest at the start


def test_time_optimal_and_jerk_limited_refuse_more_waypoints_than_they_take_at_once(katana):
    from toolkit.motion import jerk, optimal

    for fn, most, kw in ((motion.time_optimal, optimal.MOST_WAYPOINTS, {}),
                         (motion.jerk_limited, jerk.MOST_WAYPOINTS, {"jerk": 20.0})):  # fmt: skip
        W = np.linspace(katana.joints.neutral(), katana.joints.neutral() + 0.5, most + 1)
        with pytest.raises(InvalidParameterError, match=f"at most {most:,} waypoints"):
            fn(katana, W, acceleration=2.0, **kw)


def test_a_cartesian_line_refused_as_out_of_reach_is_out_of_reach_by_two_other_routes():
    """UR10 lines between random poses (an outside audit left one refusal unverified):
    where ``cartesian`` refuses a step as out of reach, no analytic branch reaches that
    pose (``ik_all``) and numeric IK from 16 random starts gets no closer than 0.1 mm."""
    from toolkit.motion.lines import line_poses

    ur10 = toolkit.load_example("ur10")
    refused = 0
    for seed in range(24):
        rng = np.random.default_rng(seed)
        q0, q1 = ur10.random_q(seed=rng), ur10.random_q(seed=rng)
        try:
            motion.cartesian(ur10, ur10.fk(q0), ur10.fk(q1), 2.0, q0=q0, steps=60)
            continue
        except InvalidParameterError as exc:
            if "leaves" not in str(exc):
                continue  # a jump between branches, not a reach
            k = int(str(exc).split("step ")[1].split(" ")[0])
        refused += 1
        T = line_poses(ur10.fk(q0), ur10.fk(q1), np.linspace(0.0, 1.0, 61))[k]
        assert not np.asarray(ur10.ik_all(T).success).any()
        best = min(ur10.ik(T, ur10.random_q(seed=s), method="numeric").position_error
                   for s in range(16))  # fmt: skip
        assert best > 1e-4
    assert refused >= 3  # the case does occur on these lines
