"""[P1]'s backlash along a motion: the motion's torques (checked by the dynamics package's
own route), the static reading where the arm rests, compensation, and where they part."""

from __future__ import annotations

import numpy as np
import pytest

import toolkit
from toolkit import backlash as bl
from toolkit import dynamics

KATANA = toolkit.load("katana_6m180")
LAYER = bl.Backlash(KATANA, payload=0.5)
MOTION = bl.pick_and_place()
DATA = bl.along(LAYER, MOTION, 100.0)
Z2 = np.zeros((2, 5))


def test_the_dynamic_outputs_satisfy_eq16_with_torques_from_an_independent_route():
    s = MOTION.at_rate(KATANA, 100.0)
    theta = DATA.theta_dynamic
    tau = dynamics.inverse_dynamics(KATANA, theta, s.qd, s.qdd, payload=0.5)
    offset = bl.offset(-tau, LAYER.nominal_torque, LAYER.delta, LAYER.k_h)
    contact = np.abs(theta - s.q - offset)
    gap = np.abs(theta - s.q) <= LAYER.delta / 2 + 1e-12
    # every joint is in contact (eq. 17 holds) or rests inside its gap where its torque
    # changes sign (then the torque there is ~0 against its size elsewhere)
    resting = gap & (np.abs(tau) <= 1e-6 * np.abs(tau).max(axis=0))
    assert np.all((contact <= 1e-9) | resting)
    assert np.all(contact[:, 1:4] <= 1e-9)  # the joints gravity loads: always in contact
    assert DATA.converged.all() and DATA.residual.max() <= 1e-10


def test_a_simulation_through_the_gaps_confirms_the_dynamic_reading_where_gravity_loads():
    """Another route (forward dynamics of the links, driven through their gaps by springs
    of eq. 17's stiffness, no fixed point): on the 2 s pick and place the joints gravity
    loads (2-4, always in contact) follow the dynamic reading to 1e-3 rad, at most half the
    static reading's distance from it (root mean square: the springs' lag and ringing where
    the reading is instant make the rest); the unloaded joints (1 and 5) stay
    within 1.5 times the widest offset the reading gives them; a motion at rest stays at rest."""
    fast = bl.pick_and_place(2.0)
    reading = bl.along(LAYER, fast, 200.0)
    sim = bl.simulate(LAYER, fast, rate=200.0)
    assert sim.theta.shape == reading.theta_dynamic.shape
    np.testing.assert_allclose(sim.t, reading.t, atol=1e-9)
    loaded = [1, 2, 3]
    off = (sim.theta - reading.theta_dynamic)[:, loaded]
    moved = (reading.theta_static - reading.theta_dynamic)[:, loaded]
    assert np.abs(off).max() <= 1e-3
    assert np.all(np.sqrt((off**2).mean(axis=0)) <= 0.5 * np.sqrt((moved**2).mean(axis=0)))
    free = [0, 4]  # within their gap and the largest spring the reading predicts, and more
    widest = np.abs(reading.theta_dynamic - reading.q)[:, free].max(axis=0)
    assert np.all(np.abs(sim.theta - sim.q)[:, free] <= 1.5 * widest)
    still = toolkit.motion.cubic(KATANA, [reading.q[0], reading.q[0] + 1e-12], [0.0, 0.5])
    rest = bl.simulate(LAYER, still, rate=20.0)
    np.testing.assert_allclose(
        rest.theta, np.broadcast_to(rest.theta[0], rest.theta.shape), atol=1e-6
    )


def test_where_the_arm_rests_the_two_readings_agree():
    at_rest = np.isin(np.round(DATA.t, 9), np.round(MOTION.times, 9))
    assert at_rest.sum() == len(MOTION.times)
    np.testing.assert_allclose(DATA.theta_dynamic[at_rest], DATA.theta_static[at_rest],
                               atol=1e-12)  # fmt: skip
    moving = ~at_rest
    assert np.abs(DATA.theta_dynamic[moving] - DATA.theta_static[moving]).max() > 1e-3


def test_any_acceleration_pushes_the_unloaded_base_joint_to_one_side_of_its_gap():
    """Joint 1 turns about the vertical: gravity never loads it, so it rests mid-gap, and
    the motion's torque puts it at +-delta/2 (plus the small k_H term) while it accelerates."""
    s = MOTION.at_rate(KATANA, 100.0)
    static_offset = DATA.theta_static[:, 0] - s.q[:, 0]
    np.testing.assert_allclose(static_offset, 0.0, atol=1e-12)
    pushing = np.abs(s.qdd[:, 0]) > 0.05
    dyn_offset = DATA.theta_dynamic[pushing, 0] - s.q[pushing, 0]
    assert pushing.sum() > 20
    half = LAYER.delta[0] / 2  # plus the k_H term, small: the torque is far below M_H
    assert np.all(np.abs(dyn_offset) >= half - 1e-12) and np.all(np.abs(dyn_offset) <= 1.1 * half)


def test_compensated_commands_put_the_outputs_on_the_intended_motion():
    t, commands = bl.compensate_motion(LAYER, MOTION, 100.0)
    s = MOTION.at_rate(KATANA, 100.0)
    np.testing.assert_array_equal(t, s.t)
    reached, residual = bl.dynamic_outputs(LAYER, commands, s.qd, s.qdd)
    assert residual.max() <= 1e-10
    np.testing.assert_allclose(reached, s.q, atol=1e-9)
    assert np.abs(commands - s.q).max() > 0.01  # a real correction, not the identity


def test_the_readings_part_more_as_the_same_motion_goes_faster():
    durations, gaps, speed = bl.parting(LAYER, [10.0, 5.0, 1.0])
    assert list(durations) == [10.0, 5.0, 1.0]
    assert gaps[0] > 1e-3  # the base joint's side, at any speed
    assert gaps[0] < gaps[1] < gaps[2] and gaps[2] > 5 * gaps[1]
    np.testing.assert_allclose(speed, speed[0] * np.array([1, 2, 10]), rtol=1e-6)
    assert speed[1] <= 1.0 < speed[2]  # 5 s is within the velocity limits, 1 s is not


def test_the_figure_reads_with_units(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    ax = bl.draw_motion_backlash(DATA)
    assert "[s]" in ax.get_xlabel() and "[mm]" in ax.get_ylabel()
    other = bl.draw_parting(bl.parting(LAYER, [5.0, 1.0]))
    assert "[mm]" in other.get_ylabel() and "limit" in other.get_xlabel()
    ax.figure.savefig(tmp_path / "motion.png")
    assert (tmp_path / "motion.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: bl.along("katana", MOTION), "Backlash layer"),
        (lambda: bl.along(LAYER, np.zeros((3, 5))), "Trajectory"),
        (lambda: bl.along(LAYER, MOTION, rate=0), "rate"),
        (lambda: bl.compensate_motion(LAYER, MOTION, rate=np.nan), "rate"),
        (lambda: bl.pick_and_place(-1.0), "duration"),
        (lambda: bl.parting(LAYER, []), "durations"),
        (lambda: bl.dynamic_outputs(LAYER, Z2, np.zeros((3, 5)), Z2), "one shape"),
        (lambda: bl.draw_motion_backlash("data"), "along"),
        (lambda: bl.simulate("katana", MOTION), "Backlash layer"),
        (lambda: bl.simulate(LAYER, "motion"), "Trajectory"),
        (lambda: bl.simulate(LAYER, MOTION, step=0.0), "step"),
        (lambda: bl.simulate(LAYER, MOTION, step=0.5), "step"),
        (lambda: bl.simulate(LAYER, MOTION, rate=-1.0), "rate"),
        (lambda: bl.simulate(LAYER, MOTION, damping=np.nan), "damping"),
        (lambda: bl.simulate(LAYER, MOTION, start=[0.0, 1.0]), "shape"),
    ],
)
def test_bad_input_is_refused(call, message):
    with pytest.raises(toolkit.ToolkitError, match=message):
        call()
