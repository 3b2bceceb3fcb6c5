"""Paper 3: the five 3-DOF positioning structures (FK, point motion, IK, workspaces)."""

from __future__ import annotations

import numpy as np
import pytest
import yourdfpy
from helpers import fd_jacobian
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import structures as S
from toolkit.descriptions import committed_urdf_path
from toolkit.errors import ConfigurationError, InvalidParameterError, UnknownModelError

NAMES = list(S.STRUCTURES)


@pytest.fixture(scope="module")
def robots():
    return {name: toolkit.load(name) for name in NAMES}


def _rot(axis: str, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


@pytest.mark.parametrize("name", NAMES)
def test_fk_equals_paper_matrix_product(name, robots, rng):
    robot = robots[name]
    a, b, c = (robot.params[k] for k in "abc")
    for q in robot.random_q(500, rng):
        t12, t23, t34 = S.paper_transforms(name, q, a, b, c)
        for T in (t12, t23, t34):
            assert np.linalg.det(T[:3, :3]) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(robot.fk(q), t12 @ t23 @ t34, atol=1e-12)
        assert np.linalg.det(robot.fk(q)[:3, :3]) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_fk_with_other_dimensions(name):
    robot = toolkit.load(name, a=0.7, b=0.2, c=0.15)
    q = robot.random_q(seed=3)
    np.testing.assert_allclose(robot.fk(q), S.paper_T14(name, q, 0.7, 0.2, 0.15), atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_committed_urdf_agrees_with_yourdfpy(name, robots, rng):
    path = committed_urdf_path(name)
    urdf = yourdfpy.URDF.load(str(path), load_meshes=False, build_scene_graph=True)
    robot = robots[name]
    assert list(urdf.actuated_joint_names) == ["joint1", "joint2", "joint3"]
    for q in robot.random_q(100, rng):
        urdf.update_cfg(q)
        np.testing.assert_allclose(robot.fk(q), urdf.get_transform("link4", "link1"), atol=1e-12)
        np.testing.assert_allclose(
            robot.fk(q, "point_m"), urdf.get_transform("point_m", "link1"), atol=1e-12
        )


def test_prismatic_axes_follow_the_reading_notes(robots):
    """Cartesian: f1 moves along base x, f2 along y, f3 along z."""
    robot = robots["cartesian"]
    q0 = np.array([0.2, 0.2, -0.2])
    for i, axis in enumerate(np.eye(3)):
        dq = np.zeros(3)
        dq[i] = 0.01
        moved = robot.fk(q0 + dq)[:3, 3] - robot.fk(q0)[:3, 3]
        np.testing.assert_allclose(moved, 0.01 * axis, atol=1e-15)


# ---------------------------------------------------------------- z-x-z helper
@settings(max_examples=50, deadline=None)
@given(
    st.floats(-3.1, 3.1),
    st.floats(0.01, 3.13),
    st.floats(-3.1, 3.1),
    st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)),
)
def test_euler_zxz_and_origin_round_trip(psi, theta, phi, abc):
    T = S.euler_zxz(psi, theta, phi, *abc)
    R = _rot("z", psi) @ _rot("x", theta) @ _rot("z", phi)
    np.testing.assert_allclose(T[:3, :3], R, atol=1e-12)
    np.testing.assert_allclose(T[:3, 3], abc, atol=0)
    xyz, rpy = S.zxz_to_origin(psi, theta, phi, *abc)
    r, p, y = rpy
    urdf_R = (
        _rot("z", y)
        @ np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
        @ _rot("x", r)
    )
    np.testing.assert_allclose(urdf_R, R, atol=1e-9)
    back = S.origin_to_zxz(xyz, rpy)
    np.testing.assert_allclose(S.euler_zxz(*back), T, atol=1e-9)


def test_origin_to_zxz_of_the_permutation():
    # the joint origins of the templates: P = rpy (pi/2, 0, pi/2)
    psi, theta, phi, a, b, c = S.origin_to_zxz((0, 0, 0.5), (np.pi / 2, 0, np.pi / 2))
    want = np.array([[0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 0.5], [0, 0, 0, 1]])
    np.testing.assert_allclose(S.euler_zxz(psi, theta, phi, a, b, c), want, atol=1e-12)
    # theta = 0: only psi + phi is defined
    np.testing.assert_allclose(
        S.euler_zxz(*S.origin_to_zxz((0, 0, 0), (0, 0, 0.3))), S.euler_zxz(0.1, 0, 0.2), atol=1e-12
    )


# ---------------------------------------------------------------- point motion
def _smooth_f(t: float) -> np.ndarray:
    return np.array([0.3 * np.sin(1.3 * t), 0.4 + 0.1 * np.cos(0.7 * t), -0.15 + 0.1 * np.sin(t)])


@pytest.mark.parametrize("name", NAMES)
def test_point_velocity_and_acceleration_equal_finite_differences(name, robots):
    robot = robots[name]
    a, b, c = (robot.params[k] for k in "abc")
    rho = np.array([0.03, -0.02, 0.05])
    lo, hi = robot.joints.lower, robot.joints.upper
    mid, half = (lo + hi) / 2, (hi - lo) / 4

    def f(t: float) -> np.ndarray:
        return mid + half * np.array([np.sin(1.3 * t), np.cos(0.7 * t), np.sin(t + 0.4)])

    def r_paper(t: float) -> np.ndarray:  # r_M = T14 rho, the paper's matrices
        return (S.paper_T14(name, f(t), a, b, c) @ np.append(rho, 1.0))[:3]

    h = 1e-4
    for t in (0.0, 0.7, 2.1):
        qd = (f(t + h) - f(t - h)) / (2 * h)
        qdd = (f(t + h) - 2 * f(t) + f(t - h)) / h**2
        r, v, acc = robot.point_kinematics(f(t), qd, qdd, rho)
        np.testing.assert_allclose(r, r_paper(t), atol=1e-12)
        np.testing.assert_allclose(v, (r_paper(t + h) - r_paper(t - h)) / (2 * h), atol=1e-6)
        fd_acc = (r_paper(t + h) - 2 * r_paper(t) + r_paper(t - h)) / h**2
        np.testing.assert_allclose(acc, fd_acc, atol=1e-4)


def test_point_kinematics_on_any_robot():
    robot = toolkit.load("katana_6m180")
    rng = np.random.default_rng(0)
    q, qd = robot.random_q(seed=rng), rng.normal(size=5)
    rho = np.array([0.01, 0.02, 0.03])
    r, v, _ = robot.point_kinematics(q, qd, np.zeros(5), rho)

    def point(x):
        T = robot.fk(x)
        out = np.eye(4)
        out[:3, 3] = T[:3, :3] @ rho + T[:3, 3]
        return out

    np.testing.assert_allclose(v, fd_jacobian(point, q)[:3] @ qd, atol=1e-7)
    np.testing.assert_allclose(r, point(q)[:3, 3], atol=1e-15)
    with pytest.raises(ConfigurationError, match="rho"):
        robot.point_kinematics(q, qd, qd, [1, 2])


def test_point_history_callables_and_samples_agree(robots):
    robot = robots["anthropomorphic"]
    t = np.linspace(0, 2, 401)
    by_function = S.point_history(robot, _smooth_f, t)
    by_list = S.point_history(robot, [lambda s, i=i: _smooth_f(s)[i] for i in range(3)], t)
    samples = np.array([_smooth_f(s) for s in t])
    by_samples = S.point_history(robot, samples, t)
    np.testing.assert_allclose(by_function.r, by_list.r, atol=0)
    np.testing.assert_allclose(by_function.v, by_samples.v, atol=1e-4)
    np.testing.assert_allclose(by_function.a[5:-5], by_samples.a[5:-5], atol=1e-2)
    # velocity is the time derivative of position
    np.testing.assert_allclose(
        np.gradient(by_function.r, t, axis=0)[1:-1], by_function.v[1:-1], atol=2e-4
    )
    with pytest.raises(ConfigurationError, match="shape"):
        S.point_history(robot, samples[:, :2], t)


def test_resolved_rate_tracks_a_circle(robots):
    robot = robots["scara"]
    t = np.linspace(0, 2, 201)
    q0 = np.array([0.3, 1.8, -0.1])
    start = S.default_rho(robot)
    T0 = robot.fk(q0)
    p0 = T0[:3, :3] @ start + T0[:3, 3]
    path = p0 + 0.05 * np.stack(
        [np.cos(np.pi * t) - 1, np.sin(np.pi * t), -0.5 * np.sin(np.pi * t)], axis=1
    )
    res = S.resolved_rate(robot, path, t, q0)
    assert res.success, res.error.max()
    assert res.error.max() < 1e-4
    for q, p in zip(res.q[::20], path[::20], strict=True):
        T = robot.fk(q)
        assert np.linalg.norm(T[:3, :3] @ start + T[:3, 3] - p) < 1e-4


# ---------------------------------------------------------------- closed-form IK
@pytest.mark.parametrize("name", NAMES)
def test_closed_form_ik_round_trip(name, robots, rng):
    robot = robots[name]
    rho = S.default_rho(robot)
    counts = []
    for q in robot.random_q(200, rng):
        T = robot.fk(q)
        target = T[:3, :3] @ rho + T[:3, 3]
        sols = S.closed_form_ik(robot, target)
        assert any(np.allclose(s, q, atol=1e-8) for s in sols)
        for s in sols:
            assert robot.joints.within_limits(s)
            Ts = robot.fk(s)
            np.testing.assert_allclose(Ts[:3, :3] @ rho + Ts[:3, 3], target, atol=1e-10)
        counts.append(len(sols))
    most = {"cartesian": 1, "cylindrical": 1, "spherical": 1, "scara": 2, "anthropomorphic": 2}
    assert max(counts) == most[name]


def test_all_branches_without_limits(robots):
    """Anthropomorphic: shoulder front/back x elbow up/down; SCARA: left/right arm."""
    robot = toolkit.load(
        "anthropomorphic", j2_lower=-np.pi, j2_upper=np.pi, j3_lower=-np.pi, j3_upper=np.pi
    )
    target = (
        robot.fk([0.4, 0.3, 0.9])[:3, :3] @ S.default_rho(robot) + robot.fk([0.4, 0.3, 0.9])[:3, 3]
    )
    assert len(S.closed_form_ik(robot, target)) == 4
    scara = robots["scara"]
    p = np.array([0.3, 0.35, 0.2])
    sols = S.closed_form_ik(scara, p)
    assert len(sols) == 2 and abs(sols[0][1] - sols[1][1]) > 0.1


@pytest.mark.parametrize("name", NAMES)
def test_closed_form_agrees_with_numeric_ik(name, robots):
    robot = robots[name]
    for q in robot.random_q(5, seed=11):
        target = robot.fk(q, "point_m")[:3, 3]
        numeric = robot.ik(target, frame="point_m", tol=1e-9, method="numeric")
        assert numeric.success
        sols = S.closed_form_ik(robot, target)
        # near a singular (stretched) pose a 1e-9 m residual still allows ~1e-4 rad
        assert min(np.abs(s - numeric.q).max() for s in sols) < 1e-3


@pytest.mark.parametrize("name", NAMES)
def test_unreachable_point_has_no_solution(name, robots):
    assert S.closed_form_ik(robots[name], [5.0, 5.0, 5.0]) == []


def test_structure_errors(robots):
    with pytest.raises(UnknownModelError, match="structure"):
        S.paper_T14("delta", [0, 0, 0], 1, 1, 1)
    with pytest.raises(UnknownModelError):
        S.closed_form_ik(toolkit.load("arm5dof"), [0.1, 0.1, 0.1])
    with pytest.raises(InvalidParameterError, match="target"):
        S.closed_form_ik(robots["scara"], [np.nan, 0, 0])
    with pytest.raises(ConfigurationError, match="rho"):
        S.closed_form_ik(robots["scara"], [0.1, 0, 0], rho=[1, 2, 3, 4])


@settings(max_examples=40, deadline=None)
@given(st.floats(-2.5, 2.5), st.floats(-1.5, 1.5), st.floats(-2.7, 2.7))
def test_anthropomorphic_ik_property(f1, f2, f3):
    robot = toolkit.load("anthropomorphic")
    q = np.array([f1, f2, f3])
    T = robot.fk(q)
    target = T[:3, :3] @ S.default_rho(robot) + T[:3, 3]
    assert any(np.allclose(s, q, atol=1e-7) for s in S.closed_form_ik(robot, target))


# ---------------------------------------------------------------- workspaces
@pytest.mark.slow
@pytest.mark.parametrize("name", ["cartesian", "cylindrical", "spherical"])
def test_workspace_volume_matches_analytic(name, robots):
    robot = robots[name]
    est = S.workspace_volume(robot, n=300_000, seed=2)
    exact = S.analytic_volume(robot)
    assert est.volume == pytest.approx(exact, rel=0.03)
    assert est.method.startswith("monte-carlo")


def test_workspace_cloud_and_generic_volume(robots):
    cloud = S.workspace(robots["scara"], 1000)
    assert cloud.shape == (1000, 3)
    reach = np.hypot(cloud[:, 0], cloud[:, 1])
    assert reach.max() <= 0.35 + np.hypot(0.25, 0) + 1e-9
    katana = toolkit.load("katana_6m180")
    ws = S.workspace_volume(katana, n=20_000)
    assert ws.method == "voxels"
    reach = 0.19 + 0.139 + 0.1473 + 0.1555
    assert 0 < ws.volume < 4 / 3 * np.pi * reach**3
    assert S.analytic_volume(robots["scara"]) is None


def test_sections_match_the_analytic_reach_space_of_the_cylindrical_structure():
    """M = Rz(f1) (0, f3 + d, a + f2): on the XZ plane through the base axis, M reaches
    |x| in [f3_min + d, f3_max + d] at z in [a + f2_min, a + f2_max]; on an XY plane in
    that height range, the ring of those radii. Points within a grid step of the boundary
    are not judged."""
    robot = toolkit.load("cylindrical")
    p = robot.params
    d = -float(S.default_rho(robot)[2])
    r_lo, r_hi = p["j3_lower"] + d, p["j3_upper"] + d
    z_lo, z_hi = p["a"] + p["j2_lower"], p["a"] + p["j2_upper"]
    xz = S.reach_section(robot, "xz", n=40)
    assert xz.level == 0.0
    step = max(np.diff(xz.u)[0], np.diff(xz.v)[0])
    x, z = np.meshgrid(xz.u, xz.v)
    inside = (np.abs(x) >= r_lo) & (np.abs(x) <= r_hi) & (z >= z_lo) & (z <= z_hi)
    margin = np.minimum.reduce(
        [np.abs(np.abs(x) - r_lo), np.abs(np.abs(x) - r_hi), np.abs(z - z_lo), np.abs(z - z_hi)]
    )
    judged = margin > step
    assert judged.sum() > 800 and inside[judged].any() and (~inside[judged]).any()
    np.testing.assert_array_equal(xz.inside[judged], inside[judged])
    xy = S.reach_section(robot, "xy", level=0.5 * (z_lo + z_hi), n=40)
    x, y = np.meshgrid(xy.u, xy.v)
    r = np.hypot(x, y)
    judged = np.minimum(np.abs(r - r_lo), np.abs(r - r_hi)) > step
    np.testing.assert_array_equal(xy.inside[judged], ((r >= r_lo) & (r <= r_hi))[judged])


def test_sections_refuse_what_they_cannot_draw():
    with pytest.raises(InvalidParameterError, match="'xz' or 'xy'"):
        S.reach_section(toolkit.load("scara"), "yz")
    with pytest.raises(toolkit.UnsupportedModelError, match="structures"):
        S.reach_section(toolkit.load("katana_6m180"), "xz")


def test_draw_sections_fills_two_equal_aspect_axes():
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    axes = S.draw_sections(toolkit.load("spherical"), n=20)
    assert [ax.get_aspect() for ax in axes] == [1.0, 1.0]
    assert [ax.get_xlabel() for ax in axes] == ["x [m]", "x [m]"]
    assert [ax.get_ylabel() for ax in axes] == ["z [m]", "y [m]"]
