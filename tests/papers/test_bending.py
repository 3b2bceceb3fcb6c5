"""Paper 4: the cable-driven bending manipulator (rolling, cables, inverse, mimic model)."""

from __future__ import annotations

import numpy as np
import pytest
import yourdfpy
from helpers import fd_jacobian
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import bending
from toolkit import bending as B
from toolkit.descriptions import committed_urdf_path
from toolkit.errors import GeometryError, InvalidParameterError

R, D, H0 = 0.02, 0.016, 0.008
GEO = B.Geometry(R, D, H0)
A_M = GEO.alpha_m


def test_geometry_constants():
    assert A_M == pytest.approx(np.arcsin(0.4))
    assert GEO.L0 == pytest.approx(2 * R * (1 - np.cos(A_M)))
    assert GEO.r == pytest.approx(np.sqrt(R**2 - (D / 2) ** 2))
    assert GEO.r == pytest.approx(R * np.cos(A_M))  # the exit points sit at alpha_m


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"R": 0.02, "d": 0.04, "h0": 0.01}, "d < 2R"),
        ({"R": 0.02, "d": 0.05, "h0": 0.01}, "d < 2R"),
        ({"R": 0.02, "d": 0.01, "h0": 0.0}, "h0"),
        ({"R": -1, "d": 0.01, "h0": 0.01}, "> 0"),
    ],
)
def test_invalid_geometry(kwargs, match):
    with pytest.raises(GeometryError, match=match):
        B.Geometry(**kwargs)


def test_invalid_alpha_and_n():
    with pytest.raises(GeometryError, match="alpha"):
        B.link_pose(A_M + 0.01, 0.0, 3, R, H0, d=D)
    with pytest.raises(GeometryError, match="alpha"):
        B.cables_from_angles(-0.1, 0.0, 3, R, D)
    with pytest.raises(GeometryError, match="n must"):
        B.link_pose(0.1, 0.0, 0, R, H0)
    with pytest.raises(GeometryError, match="n must"):
        B.inverse([0, 0, -0.05], 2.5, R, D, H0)
    with pytest.raises(InvalidParameterError):
        B.inverse([0, np.nan, -0.05], 3, R, D, H0)


# ---------------------------------------------------------------- rolling geometry
def _contact(alpha: float, psi: float) -> np.ndarray:
    u = np.array([np.sin(alpha) * np.cos(psi), np.sin(alpha) * np.sin(psi), -np.cos(alpha)])
    return np.array([0, 0, R - H0]) + R * u  # on the upper sphere, towards the lower one


@pytest.mark.parametrize(("alpha", "psi"), [(0.1, 0.0), (0.3, 1.2), (A_M, 4.0)])
def test_rolling_without_slipping(alpha, psi):
    """Equal arcs: the contact point moved by R alpha on both spheres."""
    T = B.element_transform(alpha, psi, R, H0)
    A = _contact(alpha, psi)
    # the lower sphere's centre is 2R from the upper one, through the contact point
    centre = T[:3, :3] @ np.array([0, 0, -(R - H0)]) + T[:3, 3]
    np.testing.assert_allclose(np.linalg.norm(centre - np.array([0, 0, R - H0])), 2 * R)
    np.testing.assert_allclose((centre + np.array([0, 0, R - H0])) / 2, A, atol=1e-15)
    # material point of the lower element that touched at alpha = 0: its top pole
    pole = T[:3, :3] @ np.array([0, 0, -(R - H0) + R]) + T[:3, 3]
    arc_lower = R * np.arccos(np.clip(np.dot(pole - centre, A - centre) / R**2, -1, 1))
    arc_upper = R * alpha  # from the bottom pole of the upper sphere to A
    assert arc_lower == pytest.approx(arc_upper, abs=1e-12)


def test_bends_towards_psi_and_eq5_sign_erratum():
    for psi in (0.0, 1.0, 2.5, 4.0):
        T = B.element_transform(0.2, psi, R, H0)
        direction = np.array([np.cos(psi), np.sin(psi)])
        assert T[:2, 3] @ direction > 0  # the centre moves towards psi
        assert T[:2, :3] @ np.array([0, 0, -1]) @ direction > 0  # so does the element axis
        printed = B.paper_eq5_centre(0.2, psi, R, H0)
        np.testing.assert_allclose(printed[:2], -T[:2, 3], atol=1e-15)  # x, y: sign erratum
        assert printed[2] == pytest.approx(T[2, 3], abs=1e-15)  # z is right
    np.testing.assert_allclose(B.element_transform(0, 0, R, H0)[:3, 3], [0, 0, -2 * H0])


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, A_M), st.floats(0, 2 * np.pi), st.integers(1, 12))
def test_chord_angle_is_n_alpha(alpha, psi, n):
    """The paper's claim G = n alpha: the chord O0 -> On lies along the direction at n alpha
    from -Z0 in the bending plane (pointing along it while n alpha < pi)."""
    p = B.link_pose(alpha, psi, n, R, H0)[:3, 3]
    g = n * alpha
    direction = np.array([np.sin(g) * np.cos(psi), np.sin(g) * np.sin(psi), -np.cos(g)])
    np.testing.assert_allclose(np.cross(p, direction), 0, atol=1e-15)
    if g < np.pi - 1e-6:
        assert p @ direction > 0
        G = np.arctan2(np.hypot(p[0], p[1]), -p[2])
        assert G == pytest.approx(g, abs=1e-9)


# ---------------------------------------------------------------- Pinocchio mimic model
@pytest.mark.parametrize(("links", "n"), [(1, 5), (2, 3), (3, 4), (4, 2)])
def test_mimic_model_equals_closed_form(links, n, rng):
    robot = toolkit.load("bending", links=links, n=n)
    assert robot.nq == 2 * links
    assert robot.joints.names[:2] == ["link1_psi", "link1_alpha"]
    for q in robot.random_q(100, rng):
        alphas, psis = B.q_to_angles(q)
        assert np.all(alphas >= 0) and np.all((psis >= 0) & (psis < 2 * np.pi))
        np.testing.assert_allclose(robot.fk(q), B.chain_pose(alphas, psis, n, R, H0), atol=1e-12)
        # (alpha, psi) -> q -> (alpha, psi): the same angles, the same pose
        q2 = B.angles_to_q(alphas, psis)
        np.testing.assert_allclose(
            np.concatenate(B.q_to_angles(q2)), np.concatenate((alphas, psis)), atol=1e-12
        )
        np.testing.assert_allclose(robot.fk(q2), robot.fk(q), atol=1e-12)


def test_committed_urdf_and_yourdfpy(rng):
    """yourdfpy applies the <mimic> multipliers itself: a third route."""
    path = committed_urdf_path("bending")
    robot = toolkit.load("bending")
    urdf = yourdfpy.URDF.load(str(path), load_meshes=False, build_scene_graph=True)
    assert list(urdf.actuated_joint_names) == robot.joints.names
    for q in robot.random_q(30, rng):
        urdf.update_cfg(q)
        np.testing.assert_allclose(robot.fk(q), urdf.get_transform("tool", "element_0"), atol=1e-12)


def test_working_point_and_jacobian(rng):
    robot = toolkit.load("bending", links=2, n=3, L_t=0.03)
    for q in robot.random_q(5, rng):
        alphas, psis = B.q_to_angles(q)
        np.testing.assert_allclose(
            robot.fk(q), B.chain_pose(alphas, psis, 3, R, H0, L_t=0.03), atol=1e-12
        )
        np.testing.assert_allclose(robot.jacobian(q), fd_jacobian(robot.fk, q), atol=1e-7)


def test_numeric_ik_through_robot_ik_including_near_straight():
    robot = toolkit.load("bending", links=3, n=4)
    for q in [np.zeros(6), np.array([0.3, 1e-4, -1.0, 0.02, 2.0, -1e-3]), robot.random_q(seed=5)]:
        target = robot.fk(q)[:3, 3]
        res = robot.ik(target, seed=1)
        assert res.success, res
        assert np.linalg.norm(robot.fk(res.q)[:3, 3] - target) < 1e-6


def test_bad_model_arguments():
    with pytest.raises(GeometryError, match="d < 2R"):
        toolkit.load("bending", d=0.05)
    with pytest.raises(InvalidParameterError):
        toolkit.load("bending", n=0)


# ---------------------------------------------------------------- cables
def test_paper_cable_formulas_match_the_exact_geometry_in_plane():
    """Eqs. 1, 3 and 4 are exact for bending in a cable's plane."""
    for alpha in (0.05, 0.2, A_M):
        exact = B.cable_lengths_exact(alpha, 0.0, R, D)
        assert exact["XP"] == pytest.approx(2 * R * (1 - np.cos(A_M - alpha)), abs=1e-15)
        assert exact["XN"] == pytest.approx(2 * R * (1 - np.cos(A_M + alpha)), abs=1e-15)
        assert exact["YP"] == pytest.approx(2 * (R - GEO.r * np.cos(alpha)), abs=1e-15)
        paper = B.cables_from_angles(alpha, 0.0, 3, R, D)
        assert paper["XP"] == pytest.approx(3 * (GEO.L0 - exact["XP"]), abs=1e-15)
        assert paper["XN"] == pytest.approx(3 * (GEO.L0 - exact["XN"]), abs=1e-15)
        assert paper["side"] == pytest.approx(3 * (GEO.L0 - exact["YP"]), abs=1e-15)
    assert B.cable_lengths_exact(A_M, 0.0, R, D)["XP"] == pytest.approx(0, abs=1e-15)


def test_one_leading_cable_in_each_direction():
    for name, psi in (("XP", 0.0), ("YP", np.pi / 2), ("XN", np.pi), ("YN", 1.5 * np.pi)):
        change = B.cables_from_angles(0.2, psi, 4, R, D)[name]
        alpha, psi_back = B.angles_from_cables({name: change}, 4, R, D)
        assert alpha == pytest.approx(0.2, abs=1e-12)
        assert psi_back == pytest.approx(psi, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, A_M), st.floats(0, 2 * np.pi - 1e-9), st.integers(1, 10))
def test_cable_round_trip_in_all_quadrants(alpha, psi, n):
    cables = B.cables_from_angles(alpha, psi, n, R, D)
    if alpha > 1e-9 and abs(np.cos(psi)) > 1e-9:  # the leading X cable is on psi's side
        assert (cables["XP"] > cables["XN"]) == (np.cos(psi) > 0)
    a, p = B.angles_from_cables(cables, n, R, D)
    assert a == pytest.approx(alpha, abs=1e-9)
    if alpha > 1e-6:
        assert np.cos(p - psi) == pytest.approx(1.0, abs=1e-9)


def test_angles_from_cables_errors():
    with pytest.raises(InvalidParameterError, match="unknown cable"):
        B.angles_from_cables({"ZP": 0.001}, 3, R, D)
    with pytest.raises(GeometryError, match="cannot shorten"):
        B.angles_from_cables({"XP": 1.0}, 3, R, D)


# ---------------------------------------------------------------- inverse problem
@pytest.mark.parametrize("L_t", [0.0, 0.025])
@pytest.mark.parametrize(
    ("alpha", "psi", "n", "regime"),
    [(0.1, 0.4, 5, "hanging"), (0.3, 3.5, 4, "hanging"), (0.2, 1.0, 10, "curled")],
)
def test_inverse_round_trip_both_regimes(alpha, psi, n, regime, L_t):
    target = B.chain_pose([alpha], [psi], n, R, H0, L_t=L_t)[:3, 3]
    res = B.inverse(target, n, R, D, H0, L_t=L_t)
    assert res.success and res.residual < 1e-9
    assert res.regime == regime
    np.testing.assert_allclose([res.alpha, res.psi], [alpha, psi], atol=1e-9)
    np.testing.assert_allclose(
        res.cables["XP"], B.cables_from_angles(alpha, psi, n, R, D)["XP"], atol=1e-12
    )


def test_inverse_exact_is_n_alpha_for_the_centre():
    target = B.link_pose(0.25, 2.0, 6, R, H0)[:3, 3]
    res = B.inverse(target, 6, R, D, H0)
    G = np.arctan2(np.hypot(*target[:2]), -target[2])
    assert res.alpha == pytest.approx(G / 6, abs=1e-12)


def test_paper_equations_7_to_10():
    # exact for the centre (L_t = 0), both cases
    for alpha, n in ((0.1, 5), (0.2, 10)):
        target = B.link_pose(alpha, 0.7, n, R, H0)[:3, 3]
        a, p = B.paper_inverse(target, n)
        assert (a, p) == pytest.approx((alpha, 0.7), abs=1e-12)
    # eq. 9 subtracts L_t from z only; still exact, because the last element's axis
    # (at 2 n alpha) and the chord (at n alpha) make p_t - L_t e_z fall on the chord
    for alpha, n, L_t in ((0.1, 5, 0.05), (0.2, 10, 0.03)):
        target = B.chain_pose([alpha], [0.7], n, R, H0, L_t=L_t)[:3, 3]
        assert B.paper_inverse(target, n, L_t=L_t)[0] == pytest.approx(alpha, abs=1e-12)
    # ... until the tool is long enough to reach back across the base axis
    target = B.chain_pose([0.2], [0.7], 10, R, H0, L_t=0.1)[:3, 3]
    assert abs(B.paper_inverse(target, 10, L_t=0.1)[0] - 0.2) > 0.05
    assert B.inverse(target, 10, R, D, H0, L_t=0.1).alpha == pytest.approx(0.2, abs=1e-10)


def test_off_surface_target_is_not_solved():
    on = B.link_pose(0.2, 1.0, 5, R, H0)[:3, 3]
    res = B.inverse(on * 1.1, 5, R, D, H0)
    assert not res.success
    assert res.residual == pytest.approx(0.1 * np.linalg.norm(on), rel=1e-6)
    far = B.inverse([0.0, 0.0, 1.0], 2, R, D, H0)  # straight up, beyond any curl of 2 elements
    assert not far.success and far.residual > 0.9


# ---------------------------------------------------------------- figures
def test_figures(tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    data5 = B.figure5()
    assert [len(d[1]) for d in data5] == [2, 3, 4]
    for _title, alphas, psis, pts in data5:
        np.testing.assert_allclose(pts[-1], B.chain_pose(alphas, psis, 5, R, H0)[:3, 3], atol=1e-15)
    data4 = B.figure4()
    assert data4[-1][1][-1, 2] > 0  # curls above the base plane
    assert data4[0][1][-1, 2] < 0  # 3 deg x 10 elements still hangs
    B.draw_figure5(data5)[0].figure.savefig(tmp_path / "f5.png")
    B.draw_figure4(data4).figure.savefig(tmp_path / "f4.png")
    assert (tmp_path / "f5.png").stat().st_size > 10_000


def test_a_bending_angle_beyond_pi_is_refused():
    with pytest.raises(toolkit.GeometryError, match="alpha"):
        bending.link_pose(1e300, 0.0, 3, 0.02, 0.008)
    with pytest.raises(toolkit.GeometryError, match="psi"):
        bending.link_pose(0.1, 1e300, 3, 0.02, 0.008)
