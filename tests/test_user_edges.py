"""What a new user and an adversarial user hit on landed main (issue: rough edges of round
four), each fixed with a test that fails on the code before the fix."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import toolkit
from toolkit import backlash, maps
from toolkit import calibration as cal


def test_a_calibrated_robot_keeps_the_nominal_joints_names_and_order():
    """The Panda's second finger is a mimic joint in its file; example-robot-data robots are
    loaded with mimic joints independent, and the calibrated robot must be too."""
    panda = toolkit.load_example("panda")
    truth = cal.perturb(panda, seed=1)
    Q = panda.random_q(60, seed=2)
    fit = cal.identify(panda, Q, cal.simulate(truth, Q))
    assert fit.robot.joint_names == panda.joint_names and fit.robot.nq == panda.nq
    assert fit.robot.fk(Q).shape == (60, 4, 4)
    np.testing.assert_allclose(fit.robot.fk(Q)[:, :3, 3], fit.model.positions(Q), atol=1e-9)


@pytest.mark.slow
def test_a_correction_larger_than_an_arm_stops_the_fit_and_names_the_units():
    ur5 = toolkit.load_example("ur5")
    truth = cal.perturb(ur5, seed=1)
    Q = ur5.random_q(40, seed=2)
    points = truth.positions(Q)
    fit = cal.identify(ur5, Q, cal.Measurements.positions(points))  # metres: accepted
    assert max(abs(v) for k, v in fit.parameters.items() if k.startswith("geometry")) < 0.01
    in_mm = cal.Measurements.positions(1000 * points, sigma=0.02)
    with pytest.raises(toolkit.InvalidParameterError, match="millimetres") as info:
        cal.identify(ur5, Q, in_mm)
    assert "allow_large=True" in str(info.value) and "mm (beyond 50 mm)" in str(info.value)
    allowed = cal.identify(ur5, Q, in_mm, allow_large=True)  # the user says it is real
    assert isinstance(allowed, cal.Calibration)
    with pytest.raises(toolkit.InvalidParameterError, match="allow_large"):
        cal.identify(ur5, Q, in_mm, allow_large="yes")


def test_a_joint_zero_off_by_more_than_five_degrees_is_refused():
    ur5 = toolkit.load_example("ur5")
    Q = ur5.random_q(40, seed=3)
    shifted = Q.copy()
    shifted[:, 1] += np.radians(20)  # the commands the user logged are 20 degrees off
    points = ur5.fk(shifted)[:, :3, 3]
    with pytest.raises(toolkit.InvalidParameterError, match=r"offset\.shoulder_lift_joint"):
        cal.identify(ur5, Q, cal.Measurements.positions(points), parameters=("offsets",))


def test_motion_rank_counts_the_directions_the_joints_move_the_tool():
    assert toolkit.load_example("ur5").motion_rank() == 6
    assert toolkit.load_example("panda").motion_rank() == 6  # 7 joints, 6 directions
    assert toolkit.load("katana_6m180").motion_rank() == 5
    assert toolkit.load("scara").motion_rank() == 3
    assert toolkit.load("katana_6m180").motion_rank("base_link") == 0


def test_a_map_that_could_reach_nothing_is_refused_with_the_advice():
    layer = backlash.Backlash(toolkit.load("katana_6m180"))
    with pytest.raises(toolkit.InvalidParameterError, match="position_only=True") as info:
        maps.backlash_accuracy(layer, voxel=0.12, orientations=6)
    assert "5 independent directions, fewer than the 6" in str(info.value)
    with pytest.raises(toolkit.InvalidParameterError, match="mask"):
        maps.reachability(toolkit.load("katana_6m180"), voxel=0.2, orientations=2)
    # five directions fixed, five moved, but not the same five (the Katana cannot roll its
    # approach out of the vertical plane): the map is empty, and says so
    with pytest.warns(toolkit.UnreachableTargetsWarning, match="no voxel of the map"):
        freed = maps.reachability(
            toolkit.load("katana_6m180"), voxel=0.2, orientations=2, mask=[1, 1, 1, 1, 1, 0],
            collision_free=False, workers=1,
        )  # fmt: skip
    assert np.nanmax(freed.index) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the arm's reach, as docs/maps.md says: no warning
        reach = maps.reachability(
            toolkit.load("katana_6m180"), voxel=0.2, position_only=True, collision_free=False,
            workers=1,
        )  # fmt: skip
    assert np.nanmax(reach.index) == 1


def test_ik_batch_on_too_few_joints_says_why_targets_were_missed():
    katana, ur5 = toolkit.load("katana_6m180"), toolkit.load_example("ur5")
    T = katana.fk(katana.random_q(8, seed=1))
    T[:, :3, :3] = ur5.fk(ur5.random_q(8, seed=1))[:, :3, :3]  # orientations it cannot take
    with pytest.warns(toolkit.UnreachableTargetsWarning, match="8 of 8 targets not reached"):
        result = katana.ik_batch(T)
    assert not result.success.any()
    reachable = katana.fk(katana.random_q(8, seed=2))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # reached targets, or a fitting mask: no warning
        assert katana.ik_batch(reachable).success.all()
        katana.ik_batch(T, mask=[1, 1, 1, 1, 1, 0])  # 5 fixed: the solver's honest miss


def test_the_report_says_what_its_first_run_costs_before_paying_it(monkeypatch, capsys, tmp_path):
    from toolkit import report
    from toolkit.cli import main

    ran = []
    monkeypatch.setattr(report, "run_report", lambda out, quiet: ran.append(quiet) or 0)
    assert main(["report", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "compiling the toolkit's kernels (about 1-1.5 minutes on 2 cores" in out
    assert "done in" in out and ran == [False]
    assert main(["report", "-o", str(tmp_path), "--quiet"]) == 0
    assert capsys.readouterr().out == "" and ran == [False, True]
