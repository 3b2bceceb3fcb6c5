"""Analytic IK of 3-joint chains placing a point: with prismatic joints (PPP, RPP, RRP with
axes 1, 2 meeting or parallel) and the general 3R (SP5): random robots of each family built
from random axes against the numeric IK, [P3]'s closed forms equal to the general solver on
the five positioning structures, and degenerate chains refused with the reason."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import chain_urdf, random_position_chain, same_up_to_turns, unit

import toolkit

rng = np.random.default_rng(23)


def _axes(n):
    return [unit(rng.normal(size=3)) for _ in range(n)]


@pytest.mark.parametrize(
    ("kind", "family"),
    [("PPP", "PPP"), ("RPP", "RPP"), ("RRP meeting", "RRP, axes 1, 2 meeting"),
     ("RRP parallel", "RRP, axes 1, 2 parallel"), ("3R general", "3R, general")],
)  # fmt: skip
def test_every_branch_of_random_prismatic_chains_places_the_point_and_none_is_missing(kind, family):
    for _ in range(3):
        robot = toolkit.load_urdf(random_position_chain(kind, rng))
        assert robot.structure.family == family and robot.structure.exact
        for seed in range(10):
            q = robot.random_q(seed=seed)
            p = robot.fk(q)[:3, 3]
            result = robot.ik_all(p)
            assert result.solved >= 1
            assert (result.position_error[result.success] <= 1e-10).all()
            for row in result.q[result.success]:  # an independent check of each claim
                np.testing.assert_allclose(robot.fk(row)[:3, 3], p, atol=1e-9)
            assert any(same_up_to_turns(r, q, 1e-8) for r in result.q[result.success])
            for start in robot.random_q(4, seed=100 + seed):
                found = robot.ik(p, q0=start, tol=1e-10, restarts=0, method="numeric")
                if found.success:
                    sigma = np.linalg.svd(robot.jacobian(found.q)[:3], compute_uv=False)[-1]
                    close = max(1e-6, 10 * 1e-10 / sigma)
                    assert any(same_up_to_turns(r, found.q, close) for r in result.q)


@pytest.mark.parametrize(
    ("name", "family", "most"),
    [("cartesian", "PPP", 1), ("cylindrical", "RPP", 2), ("spherical", "RRP, axes 1, 2 meeting", 4),
     ("scara", "RRP, axes 1, 2 parallel", 2), ("anthropomorphic", "3R, axes 1, 2 meeting", 4)],
)  # fmt: skip
def test_p3s_closed_forms_equal_the_general_solver_on_the_five_structures(name, family, most):
    from toolkit.papers.structures.inverse import closed_form_ik

    robot = toolkit.load(name)
    assert robot.structure_of("point_m").family == family
    compared = 0
    for seed in range(30):
        p = robot.fk(robot.random_q(seed=seed), "point_m")[:3, 3]
        general = robot.ik_all(p, frame="point_m")
        ours = general.q[general.success]
        closed = closed_form_ik(robot, p)  # within the joint ranges, each checked by FK
        assert 1 <= len(ours) == len(closed) <= most
        for q in closed:
            assert any(np.abs(q - row).max() < 1e-9 for row in ours)
        compared += len(closed)
    assert compared >= 30


def test_a_scara_takes_method_analytic_and_keeps_its_elbow_along_a_path():
    scara = toolkit.load("scara")
    q = scara.random_q(seed=2)
    p = scara.fk(q, "point_m")[:3, 3]
    answer = scara.ik(p, q0=q, frame="point_m", method="analytic")
    assert answer.success and answer.iterations == 0 and np.abs(answer.q - q).max() < 1e-9
    path = [p + np.array([0.0, 0.002, -0.001]) * k for k in range(20)]
    result = scara.ik_path(path, q0=q, frame="point_m", method="analytic")
    assert result.all_succeeded and result.max_step < 0.1
    assert (np.sign(result.q[:, 1]) == np.sign(q[1])).all()  # the same elbow all along


def test_chains_with_slides_that_cannot_place_a_point_say_why():
    h = _axes(3)
    flat = chain_urdf([h[0], h[1], h[0]], [np.zeros(3)] * 3, np.ones(3) * 0.1, "p", "PPP")
    assert "do not span space" in toolkit.load_urdf(flat).structure.reason
    across = unit(np.cross(h[0], h[1]))
    side = unit(np.cross(h[0], across))
    level = chain_urdf([h[0], across, side], [np.zeros(3)] * 3, np.ones(3) * 0.1, "p", "RPP")
    assert "height along it is fixed" in toolkit.load_urdf(level).structure.reason
    prr = chain_urdf(h, [rng.normal(size=3) for _ in range(3)], np.ones(3) * 0.1, "p", "PRR")
    robot = toolkit.load_urdf(prr)
    assert robot.structure.family is None and "PPP, RPP and RRP" in robot.structure.reason
    with pytest.raises(toolkit.UnsupportedModelError, match="PPP, RPP and RRP"):
        robot.ik_all([0.1, 0.2, 0.3])
    six = chain_urdf(_axes(6), [rng.normal(size=3) for _ in range(6)], np.ones(3), "p", "RRRRRP")
    assert "3-joint chains" in toolkit.load_urdf(six).structure.reason


@pytest.mark.parametrize("name", ["scara", "spherical", "anthropomorphic"])
def test_a_calibrated_positioning_structure_gets_every_branch_polished(name):
    from toolkit import calibration as cal

    nominal = toolkit.load(name)
    truth = cal.perturb(nominal, seed=1, parameters=("offsets", "geometry", "base"))
    arm = toolkit.load_urdf(truth.urdf_text, tip=nominal.tip)
    assert not arm.structure_of("point_m").exact
    for q in nominal.random_q(10, seed=3):
        p = arm.fk(q, "point_m")[:3, 3]
        result = arm.ik_all(p, frame="point_m")
        exact = nominal.ik_all(nominal.fk(q, "point_m")[:3, 3], frame="point_m")
        assert result.polished and result.lost == 0 and len(result.q) == len(exact.q)
        assert (result.position_error <= 1e-10).all()  # outside the limits or not
        for row in result.q:
            np.testing.assert_allclose(arm.fk(row, "point_m")[:3, 3], p, atol=1e-9)
        assert any(np.abs(row - q).max() < 1e-7 for row in result.q[result.success])
