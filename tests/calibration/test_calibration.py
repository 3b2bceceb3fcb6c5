"""Calibration: the identification Jacobian against finite differences, exact recovery
from noise-free data for every parameter set, unidentifiable parameters named, outliers
flagged, the corrected URDF reloaded equal to the calibrated model, pose selection, and
clear errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import backlash
from toolkit import calibration as cal
from toolkit.calibration._jacobian import Problem

TINY = 1e-12  # "noise-free": the measurements' sigma must be > 0


def _ur5() -> toolkit.Robot:
    return toolkit.load_example("ur5")


def _gravity_set(truth: cal.ArmModel, Q: np.ndarray, links, noise=TINY) -> cal.Measurements:
    out = cal.Measurements()
    for k, link in enumerate(links):
        out = out + cal.simulate(truth, Q, "gravity", noise, frame=link, seed=k)
    return out


@pytest.mark.parametrize(
    ("name", "kinds", "measure"),
    [
        ("ur5", ("offsets", "geometry", "base", "tool"), "poses"),
        ("ur5", ("compliance",), "positions"),
        ("katana_6m180", ("offsets", "geometry"), "gravity"),
        ("katana_6m180", ("offsets", "backlash"), "gravity+positions"),
    ],
)
def test_the_identification_jacobian_equals_finite_differences(name, kinds, measure):
    robot = _ur5() if name == "ur5" else toolkit.load(name)
    layer = backlash.Backlash(robot, payload=0.5) if "backlash" in kinds else None
    truth = cal.perturb(robot, seed=3, parameters=kinds, layer=layer, compliance=2e-3)
    pset = truth.pset
    Q = robot.random_q(6, seed=4)
    if measure == "poses":
        meas = cal.simulate(truth, Q, "poses", (1e-4, 1e-3))
    elif measure == "positions":
        meas = cal.simulate(truth, Q, "positions", 1e-5)
    else:
        meas = _gravity_set(truth, Q, ["link3", "link5"], 1e-3)
        if "positions" in measure:
            meas = meas + cal.simulate(truth, Q, "positions", 1e-5)
    problem = Problem(pset, Q, meas)
    errors = truth.errors  # a non-zero estimate: the steps compose on it
    _, J = problem.evaluate(errors)
    assert np.abs(J).max() > 0.1
    for k, par in enumerate(pset.params):
        h = 1e-6
        step = np.zeros(len(pset))
        step[k] = h
        up = problem.residuals(pset.update(errors, step))
        down = problem.residuals(pset.update(errors, -step))
        numeric = -(up - down) / (2 * h)  # residual = measured - predicted
        tol = 1e-6 if par.kind != "backlash" else 1e-4
        assert np.allclose(J[:, k], numeric, atol=tol * max(1.0, np.abs(numeric).max())), par.name


def _exact(robot, kinds, Q, measure, layer=None, links=("link2", "link3", "link4", "link5")):
    nominal_layer = layer
    if layer is not None:
        nominal_layer = layer.with_parameters(np.full(robot.nq, 0.02), np.full(robot.nq, 0.5))
    pset = cal.ParameterSet(robot, kinds, nominal_layer)
    fake = measure(cal.ArmModel(pset, pset.nominal()), Q)
    _, J = Problem(pset, Q, fake).evaluate(pset.nominal())
    sigma = Problem(pset, Q, fake).sigma
    ident = cal._identify.identifiability(pset.names, J, sigma, len(Q), pset.same_as_offsets())
    keep = [pset.names[k] for k in ident.kept]
    truth = cal.perturb(robot, seed=5, parameters=kinds, layer=layer, compliance=2e-3, only=keep)
    if layer is not None:  # the truth's layer has delta 0.035, k_H 0.2; the start does not
        truth = cal.ArmModel(truth.pset, truth.errors)
    c = cal.identify(robot, Q, measure(truth, Q), parameters=kinds, layer=nominal_layer)
    return truth, c, keep


@pytest.mark.parametrize(
    ("name", "kinds", "kind"),
    [
        ("ur5", ("offsets",), "positions"),
        ("ur5", ("geometry",), "positions"),
        ("ur5", ("base",), "positions"),
        ("ur5", ("tool",), "poses"),
        ("ur5", ("offsets", "geometry", "base", "tool"), "poses"),
        ("katana_6m180", ("compliance",), "positions"),
        ("katana_6m180", ("offsets", "geometry", "base", "tool", "compliance"), "positions"),
    ],
)
def test_noise_free_data_recovers_every_identifiable_parameter(name, kinds, kind):
    robot = _ur5() if name == "ur5" else toolkit.load(name)
    Q = robot.random_q(40, seed=6)

    def measure(arm, Q):
        return cal.simulate(arm, Q, kind, TINY if kind == "positions" else (TINY, TINY))

    truth, c, keep = _exact(robot, kinds, Q, measure)
    assert c.converged and keep
    values = truth.values()
    for name_ in keep:
        assert c.parameters[name_] == pytest.approx(values[name_], abs=1e-8), name_
    for name_ in c.identifiability.fixed:
        assert abs(c.parameters[name_]) < 1e-12  # fixed at the nominal value, never fitted
    held = robot.random_q(30, seed=7)
    v = c.validate(held, cal.simulate(truth, held, "positions", TINY))
    assert v.after[2] < 1e-9 < v.before[0]


def test_backlash_and_offsets_come_back_from_accelerometers_alone():
    robot = toolkit.load("katana_6m180")
    layer = backlash.Backlash(robot, delta=0.035, k_h=0.2, payload=0.5)
    Q = robot.random_q(40, seed=8)

    def measure(arm, Q):
        return _gravity_set(arm, Q, ["link2", "link3", "link4", "link5"])

    truth, c, keep = _exact(robot, ("offsets", "backlash"), Q, measure, layer=layer)
    assert "offset.joint1" in c.identifiability.fixed  # joint 1 turns about gravity
    values = truth.values()
    for name_ in keep:
        assert c.parameters[name_] == pytest.approx(values[name_], abs=1e-6), name_
    assert np.allclose(c.layer.delta[1:], 0.035, atol=1e-6)


def test_unidentifiable_parameters_are_named_with_what_they_move_like():
    robot = _ur5()
    Q = robot.random_q(30, seed=9)
    truth = cal.perturb(robot, seed=1)
    c = cal.identify(robot, Q, cal.simulate(truth, Q, "positions", 2e-5))
    fixed = c.identifiability.fixed
    # the base's turn about the vertical moves the tool like the first joint's offset
    assert "offset.shoulder_pan_joint" in fixed["base.rz"]
    # base and first joint: the base's shift is the first joint placement's shift
    assert "geometry.shoulder_pan_joint.x" in fixed["base.x"]
    # a tool turn does not move the tool point at all
    assert fixed["tool.rx"] == () and "moves nothing" in str(c)
    assert all(np.isnan(c.std[n]) for n in fixed)
    assert not any(np.isnan(c.std[c.identifiability.names[k]]) for k in c.identifiability.kept)


def test_outliers_are_down_weighted_and_reported():
    robot = toolkit.load("katana_6m180")
    Q = robot.random_q(50, seed=10)
    truth = cal.perturb(robot, seed=2)
    meas = cal.simulate(truth, Q, "positions", 2e-5, seed=1)
    points = meas.blocks[0].values.copy()
    bad = [4, 17, 33]
    points[bad] += np.array([0.004, -0.003, 0.002])  # three 5 mm blunders
    dirty = cal.Measurements.positions(points, 2e-5)
    robust = cal.identify(robot, Q, dirty)
    plain = cal.identify(robot, Q, dirty, robust=False)
    assert robust.outliers == bad and plain.outliers == []
    held = robot.random_q(100, seed=11)
    truth_held = cal.simulate(truth, held, "positions", 2e-5, seed=2)
    after_robust = robust.validate(held, truth_held).after[0]
    assert after_robust < 0.5 * plain.validate(held, truth_held).after[0]


@settings(max_examples=6, deadline=None)
@given(st.integers(0, 10**8))
def test_the_corrected_urdf_reloaded_equals_the_calibrated_model(seed):
    robot = toolkit.load("katana_6m180")
    arm = cal.perturb(robot, seed=seed, translation=5e-3, rotation=0.02, offset=0.05)
    reloaded = toolkit.load_urdf(arm.urdf_text, tip=robot.tip)
    Q = robot.random_q(20, seed=seed % 1000)
    assert np.allclose(reloaded.fk(Q), arm.fk(Q), atol=1e-10)


@pytest.mark.slow
def test_the_calibrated_robot_of_the_ur5_reloads_from_its_urdf():
    robot = _ur5()
    Q = cal.select_poses(robot, 30, seed=1)
    truth = cal.perturb(robot, seed=3)
    c = cal.identify(robot, Q, cal.simulate(truth, Q, "poses", (2e-5, 1e-4)))
    held = robot.random_q(50, seed=4)
    assert np.allclose(c.robot.fk(held), c.model.fk(held), atol=1e-10)
    assert c.robot.name.endswith("calibrated") and c.robot.nq == robot.nq


def test_selected_poses_are_more_informative_than_random_ones():
    robot = toolkit.load("katana_6m180")
    chosen = cal.select_poses(robot, 20, seed=3)
    assert chosen.shape == (20, robot.nq) and robot.joints.within_limits(chosen)
    assert not robot.in_collision(chosen).any()
    pset = cal.ParameterSet(robot, cal.DEFAULT)

    def o1(Q):
        fake = cal.simulate(robot, Q, "positions", 2e-5)
        problem = Problem(pset, Q, fake)
        _, J = problem.evaluate(pset.nominal())
        return cal._identify.identifiability(pset.names, J, problem.sigma, len(Q)).d_optimality

    random = [o1(robot.random_q(20, seed=s)) for s in range(5)]
    assert o1(chosen) > max(random)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda r, Q, m: cal.identify(r, Q, m, parameters="wheels"), "unknown parameter set"),
        (lambda r, Q, m: cal.identify(r, Q, m, parameters=()), "unknown parameter set"),
        (lambda r, Q, m: cal.identify(r, Q[:5], m), "measurements for 5 configurations"),
        (lambda r, Q, m: cal.identify(r, Q[:2], cal.simulate(r, Q[:2])), "measure more"),
        (lambda r, Q, m: cal.identify(r, Q[:, :3], m), "shape"),
        (lambda r, Q, m: cal.identify(r, Q, "points"), "Measurements"),
        (lambda r, Q, m: cal.identify(r, Q, m, parameters="backlash"), "layer"),
        (lambda r, Q, m: cal.Measurements.positions(np.full((3, 3), np.nan)), "NaN|finite"),
        (lambda r, Q, m: cal.Measurements.positions(np.zeros((3, 2))), "shape"),
        (lambda r, Q, m: cal.Measurements.positions(np.zeros((3, 3)), sigma=0), "sigma"),
        (lambda r, Q, m: cal.Measurements.gravity("link2", np.zeros((3, 3))), "zero"),
        (lambda r, Q, m: cal.Measurements.poses(np.ones((2, 4, 4))), "orthonormal"),
        (lambda r, Q, m: cal.simulate(r, Q, "gravity"), "frame"),
        (lambda r, Q, m: cal.simulate(r, Q, "sonar"), "kind"),
        (lambda r, Q, m: cal.select_poses(r, 10, kind="gravity"), "frame"),
        (lambda r, Q, m: cal.perturb(r, only=["base.q"]), "unknown parameter name"),
        (lambda r, Q, m: cal.Measurements.gravity("nowhere", np.ones((30, 3))).blocks and
            cal.identify(r, Q, cal.Measurements.gravity("nowhere", np.ones((30, 3)))), "nowhere"),
    ],
)  # fmt: skip
def test_bad_input_gets_a_clear_error(call, message):
    robot = toolkit.load("katana_6m180")
    Q = robot.random_q(30, seed=1)
    meas = cal.simulate(robot, Q)
    with pytest.raises(toolkit.ToolkitError, match=message):
        call(robot, Q, meas)


@pytest.mark.slow
def test_a_noisy_calibration_brings_the_error_down_and_says_so():
    robot = _ur5()
    truth = cal.perturb(robot, seed=7)
    Q = cal.select_poses(robot, 50, seed=2)
    c = cal.identify(robot, Q, cal.simulate(truth, Q, "positions", 2e-5, seed=3))
    held = robot.random_q(200, seed=5)
    v = c.validate(held, cal.simulate(truth, held, "positions", 2e-5, seed=6))
    assert v.reduction >= 0.95 and v.after[0] < 1e-4
    text = str(c)
    assert "identifiable" in text and "condition number" in text and "O1" in text


def _write_csv(path, robot, Q, positions=None, gravity=None):
    import csv

    names = robot.joints.names
    header = [*names]
    if positions is not None:
        header += ["x", "y", "z"]
    if gravity is not None:
        header += [f"{gravity[0]}:g{a}" for a in "xyz"]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for i, q in enumerate(robot.joints.angles(Q)):
            row = [repr(float(v)) for v in q]
            if positions is not None:
                row += ["" if i % 7 == 3 else repr(float(v)) for v in positions[i]]
            if gravity is not None:
                row += [repr(float(v)) for v in gravity[1][i]]
            w.writerow(row)


def test_the_cli_calibrates_from_a_csv_and_writes_the_urdf(tmp_path, capsys):
    from toolkit.cli import main

    robot = toolkit.load("katana_6m180")
    truth = cal.perturb(robot, seed=4)
    Q = robot.random_q(60, seed=1)
    _write_csv(tmp_path / "m.csv", robot, Q, truth.positions(Q) + 1e-5,
               ("link3", truth.gravity(Q, "link3")))  # fmt: skip
    held = robot.random_q(40, seed=2)
    _write_csv(tmp_path / "h.csv", robot, held, truth.positions(held))
    out = tmp_path / "cal.urdf"
    code = main([
        "calibrate", "katana_6m180", str(tmp_path / "m.csv"), "-o", str(out),
        "--validate", str(tmp_path / "h.csv"), "--report", str(tmp_path / "r.txt"),
    ])  # fmt: skip
    text = capsys.readouterr().out
    assert code == 0 and "identifiable" in text and "held-out" in text
    reloaded = toolkit.load_urdf(out, tip=robot.tip)
    # the tracker's 1e-5 m offset on each axis is the base's (every 7th row has no position)
    err = np.linalg.norm(reloaded.fk(held)[:, :3, 3] - truth.positions(held) - 1e-5, axis=1)
    assert err.max() < 1e-5  # the fixed parameters' errors merge to first order only (um)
    assert (tmp_path / "r.txt").read_text().startswith("calibration of katana_6m180")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("joint1,joint2\n0,0\n", "missing joint"),
        ("joint1,joint2,joint3,joint4,joint5,x,y,z,w\n0,0,0,0,0,1,1,1,1\n", "unknown column"),
        ("joint1,joint2,joint3,joint4,joint5,x,y\n0,0,0,0,0,1,1\n", "come together"),
        ("joint1,joint2,joint3,joint4,joint5,x,y,z\n0,0,0,0,0,1,oops,1\n", "not a number"),
        ("joint1,joint2,joint3,joint4,joint5,x,y,z\n0,0,0,0,0,1,nan,1\n", "column 'y'"),
        ("joint1,joint2,joint3,joint4,joint5\n0,0,0,0,0\n", "no measurement"),
        ("joint1,joint2,joint3,joint4,joint5,x,y,z\n", "at least one data row"),
    ],
)
def test_the_cli_refuses_bad_csv_files(tmp_path, capsys, content, message):
    from toolkit.cli import main

    path = tmp_path / "bad.csv"
    path.write_text(content)
    assert main(["calibrate", "katana_6m180", str(path)]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert "[]" not in err  # only the problems there are, never an empty list


@pytest.mark.slow
def test_a_catalogue_model_gets_its_corrected_xacro_arguments():
    robot = toolkit.load("katana_6m180")
    truth = cal.perturb(robot, seed=2, only=["geometry.joint3.x", "geometry.joint4.x"])
    Q = robot.random_q(40, seed=3)
    fit = cal.identify(robot, Q, cal.simulate(truth, Q, "positions", 1e-9))
    found = fit.xacro_arguments()
    values = truth.values()  # joint 3's placement x is a2, joint 4's is a3 ([P1] Table 2)
    assert found.arguments["a2"] == pytest.approx(0.19 + values["geometry.joint3.x"], abs=1e-8)
    assert found.arguments["a3"] == pytest.approx(0.139 + values["geometry.joint4.x"], abs=1e-8)
    assert found.rms < 1e-8 and "m_link2" not in found.arguments  # masses do not move it
    reloaded = toolkit.load("katana_6m180", **found.arguments)
    assert np.allclose(reloaded.fk(Q)[:, :3, 3], truth.positions(Q), atol=1e-8)
    other = cal.identify(_ur5(), Q := _ur5().random_q(30, seed=1),
                         cal.simulate(_ur5(), Q, "positions"))  # fmt: skip
    with pytest.raises(toolkit.UnsupportedModelError, match="catalogue"):
        other.xacro_arguments()


def test_measurements_written_as_the_cli_csv_read_back_exactly(tmp_path):
    """``write_measurements`` then ``read_measurements``: the same commands, every value in
    its row (positions at some rows, gravity at others), the sigmas the reader is given;
    the file is the one ``toolkit calibrate`` reads; poses have no columns (refused)."""
    robot = toolkit.load("katana_6m180")
    truth = cal.perturb(robot, seed=1)
    Q = robot.random_q(9, seed=2)
    link = robot.tip
    meas = (cal.simulate(truth, Q, "positions", at=[0, 2, 3, 7], seed=1)
            + cal.simulate(truth, Q, "gravity", frame=link, at=[1, 2, 8], seed=2))  # fmt: skip
    path = cal.write_measurements(tmp_path / "m.csv", robot, Q, meas)
    Q2, back = cal.read_measurements(robot, path, sigma_position=3e-5, sigma_gravity=2e-3)
    np.testing.assert_array_equal(Q2, Q)
    before, after = meas.columns(len(Q)), back.columns(len(Q))
    assert list(before) == list(after)
    for name in before:
        np.testing.assert_array_equal(np.isnan(before[name]), np.isnan(after[name]))
        np.testing.assert_allclose(after[name], before[name], rtol=0, atol=1e-15)
    kinds = {b.kind: b for b in back.blocks}
    assert (kinds["position"].sigma == 3e-5).all() and (kinds["gravity"].sigma == 2e-3).all()
    np.testing.assert_array_equal(kinds["position"].at, [0, 2, 3, 7])
    header = path.read_text().splitlines()[0].split(",")
    assert header == [*robot.joints.names, "x", "y", "z", f"{link}:gx", f"{link}:gy", f"{link}:gz"]
    with pytest.raises(toolkit.InvalidParameterError, match="tool poses have no CSV columns"):
        cal.write_measurements(tmp_path / "p.csv", robot, Q, cal.simulate(truth, Q, "poses"))
    with pytest.raises(toolkit.InvalidParameterError, match="two measurements of 'x'"):
        (meas + meas).columns(len(Q))


def test_a_calibrated_robot_keeps_the_nominal_joints_names_and_order():
    """The Panda's second finger is a mimic joint in its file; example-robot-data robots are
    loaded with mimic joints independent, and the calibrated robot must be too."""
    panda = toolkit.load_example("panda")
    truth = cal.perturb(panda, seed=1)
    Q = panda.random_q(60, seed=2)
    fit = cal.identify(panda, Q, cal.simulate(truth, Q))
    assert fit.robot.joints.names == panda.joints.names and fit.robot.nq == panda.nq
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
