"""Inverse kinematics: the numeric solver on every model, and the closed-form solvers."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import arm5dof, katana

CATALOGUE = ["katana_6m180", "katana_6m90a", "katana_6m90b", "arm5dof"]


def get(name: str) -> toolkit.Robot:
    return toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)


def rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


@pytest.mark.parametrize("method", ["auto", "numeric"])
@pytest.mark.parametrize("name", [*CATALOGUE, "ur5", "panda"])
def test_round_trip_fk_ik_fk(name, method):
    """The default (by branches where a compiled family answers) and the numeric solver."""
    robot = get(name)
    qs = robot.random_q(25, seed=7)
    solved = 0
    for q in qs:
        target = robot.fk(q)
        res = robot.ik(target, tol=1e-8, method=method)
        assert robot.joints.within_limits(res.q)  # limits hold on every answer, solved or not
        if res.success:
            solved += 1
            T = robot.fk(res.q)  # independent check of the claim
            assert np.linalg.norm(T[:3, 3] - target[:3, 3]) <= 1e-8
            assert np.abs(T[:3, :3] - target[:3, :3]).max() <= 1e-7
            assert res.position_error <= 1e-8 and res.orientation_error <= 1e-8
    # measured: 25/25 on most models; the Katana 6M90A/B have targets near joint limits
    # whose basins are tiny (docs/ik.md), hence the margin
    assert solved >= 23, f"{name}: only {solved} of 25 reachable targets solved"


@pytest.mark.parametrize("name", ["katana_6m180", "ur5"])
def test_position_only_targets(name):
    robot = get(name)
    for q in robot.random_q(10, seed=3):
        p = robot.fk(q)[:3, 3]
        res = robot.ik(p)
        assert res.success and res.orientation_error == 0.0
        assert np.linalg.norm(robot.fk(res.q)[:3, 3] - p) <= 1e-6


def test_mask_frees_axes_and_full_pose_is_honest():
    robot = toolkit.load("katana_6m180")  # 5 DOF: a random orientation is out of reach
    rng = np.random.default_rng(11)
    q = robot.random_q(seed=rng)
    target = robot.fk(q) @ rot_x(0.7)  # tilt the approach axis out of the arm's plane
    full = robot.ik(target, restarts=5)
    assert not full.success and full.orientation_error > 1e-3
    masked = robot.ik(target, mask=[1, 1, 1, 0, 0, 0])
    assert masked.success and masked.position_error <= 1e-6
    # rz about the tool axis is the roll joint: freeing it keeps a reachable pose solvable
    reachable = robot.fk(q)
    res = robot.ik(reachable, mask=[1, 1, 1, 1, 1, 0])
    assert res.success
    np.testing.assert_allclose(robot.fk(res.q)[:3, 2], reachable[:3, 2], atol=1e-6)


def test_unreachable_target_is_not_success():
    robot = toolkit.load("katana_6m180")
    far = np.array([2.0, 0.0, 0.2015])
    res = robot.ik(far, restarts=3)
    assert not res.success
    reach = 0.190 + 0.139 + 0.1473 + 0.1555
    # the residual is the true one of the returned q, and no q can beat the reach bound
    assert res.position_error == pytest.approx(np.linalg.norm(robot.fk(res.q)[:3, 3] - far))
    assert 2.0 - reach - 1e-9 <= res.position_error < 2.0
    assert robot.joints.within_limits(res.q)
    assert res.restarts == 3


def test_the_time_limit_stops_restarts():
    robot = toolkit.load("katana_6m180")
    # a million restarts take seconds even compiled: the 20 ms budget must cut them short
    res = robot.ik(np.array([2.0, 0.0, 0.2]), restarts=1_000_000, time_limit=0.02)
    assert not res.success and res.restarts < 1_000_000


def test_same_seed_same_answer():
    robot = toolkit.load_example("panda")
    target = robot.fk(robot.random_q(seed=5))
    a = robot.ik(target, q0=robot.random_q(seed=9), seed=42)
    b = robot.ik(target, q0=robot.random_q(seed=9), seed=42)
    np.testing.assert_array_equal(a.q, b.q)
    assert (a.iterations, a.restarts, a.success) == (b.iterations, b.restarts, b.success)


@pytest.mark.parametrize(
    ("target", "kwargs", "message"),
    [
        (np.zeros((3, 3)), {}, "4x4 pose or a 3-vector"),
        ([0.1, float("nan"), 0.2], {}, "NaN"),
        (np.diag([1.0, 1, 2, 1]), {}, "not a rotation"),
        (np.eye(4), {"mask": [1, 1, 1]}, "six non-negative"),
        (np.eye(4), {"mask": [0] * 6}, "no axis"),
        ([0.1, 0.2, 0.3], {"mask": [1, 1, 1, 1, 0, 0]}, "no orientation"),
        (np.eye(4), {"tol": 0.0}, "tol"),
        (np.eye(4), {"frame": "nope"}, "unknown frame"),
    ],
)
def test_bad_ik_input(target, kwargs, message):
    robot = toolkit.load("katana_6m90a")
    with pytest.raises(toolkit.ToolkitError, match=message):
        robot.ik(target, **kwargs)


@pytest.mark.parametrize("method", ["auto", "numeric"])
def test_ik_path_keeps_branch(method):
    robot = toolkit.load_example("ur5")
    q_a, q_b = robot.random_q(seed=1) * 0.3, robot.random_q(seed=2) * 0.3
    path = [q_a + s * (q_b - q_a) for s in np.linspace(0, 1, 40)]
    targets = [robot.fk(q) for q in path]
    result = robot.ik_path(targets, q0=q_a, method=method)
    assert result.all_succeeded
    assert result.jumps == [] and result.max_step < 0.1
    for q, T in zip(result.q, targets, strict=True):
        assert np.abs(robot.fk(q) - T).max() < 1e-6


@pytest.mark.parametrize("method", ["auto", "numeric"])
def test_ik_path_reports_jumps(method):
    robot = toolkit.load_example("ur5")
    q_a = robot.random_q(seed=1) * 0.3
    q_far = q_a + np.array([2.0, 0, 0, 0, 0, 0])
    result = robot.ik_path([robot.fk(q_a), robot.fk(q_far)], q0=q_a, max_jump=0.5, method=method)
    assert result.all_succeeded and result.jumps == [1]


# ----------------------------------------------------------------- closed form: paper 2


def front_pitch(T: np.ndarray, axis: int) -> float:
    """Elevation of a tool axis above the horizontal, seen from the front (toward the target)."""
    p, d = T[:3, 3], T[:3, axis]
    h = p[:2] / np.hypot(*p[:2])
    return float(np.arctan2(d[2], d[:2] @ h))


def test_geometric_ik_reproduces_targets_on_the_model():
    robot = toolkit.load("arm5dof")
    for q in robot.random_q(300, seed=4):
        T = robot.fk(q)
        sols = arm5dof.geometric_ik(T[:3, 3], front_pitch(T, 0), arm5dof.MODEL_LENGTHS)
        assert len(sols) == 4  # elbow up/down, front and over the back
        for s in sols:
            assert s[4] == 0.0
            Ts = robot.fk(s)
            assert np.abs(Ts[:3, 3] - T[:3, 3]).max() < 1e-9
            assert np.abs(Ts[:3, 0] - T[:3, 0]).max() < 1e-9  # same approach direction
        assert min(np.abs(np.r_[q[:4], 0] - s).max() for s in sols) < 1e-8


def test_geometric_matches_numeric_ik():
    robot = toolkit.load("arm5dof")
    for q in robot.random_q(10, seed=8):
        T = robot.fk(q)
        res = robot.ik(T, mask=[1, 1, 1, 0, 1, 1])  # roll about the gripper axis x is free
        assert res.success
        sols = arm5dof.geometric_ik(T[:3, 3], front_pitch(T, 0), arm5dof.MODEL_LENGTHS)
        wrapped = [np.abs(np.angle(np.exp(1j * (res.q[:4] - s[:4])))).max() for s in sols]
        assert min(wrapped) < 1e-5


def test_stretched_arm_branches_merge():
    b, l2, l3, l4 = arm5dof.PAPER_LENGTHS
    result = arm5dof.solve([l2 + l3 + l4, 0, b], 0.0)
    assert len(result.solutions) == 2  # elbow up and down coincide on each side
    np.testing.assert_allclose(result.solutions[0], np.zeros(5), atol=1e-7)
    assert result.out_of_reach == 0.0


def test_unreachable_reports_distance():
    b, l2, l3, l4 = arm5dof.PAPER_LENGTHS
    result = arm5dof.solve([l2 + l3 + l4 + 7.0, 0, b], 0.0)
    assert len(result.solutions) == 0 and arm5dof.geometric_ik([87.0, 0, b], 0.0) == []
    assert result.out_of_reach == pytest.approx(7.0)
    inner = arm5dof.solve([l4 + 10.0, 0, b], 0.0)  # wrist 10 from the shoulder: < l2 - l3
    assert inner.out_of_reach == pytest.approx(l2 - l3 - 10.0)


def test_target_on_base_axis():
    result = arm5dof.solve([0, 0, 40.0], np.pi / 2)
    assert result.base_axis and len(result.solutions) >= 2
    for s in result.solutions:
        np.testing.assert_allclose(arm5dof.forward(s), [0, 0, 40.0], atol=1e-9)
    yawed = arm5dof.solve([0, 0, 40.0], np.pi / 2, base_yaw=1.0)
    assert yawed.solutions[0][0] == pytest.approx(1.0)


def test_limits_filter_solutions():
    all_sols = arm5dof.geometric_ik([40, 10, 30], 0.2)
    lower = np.array([-np.pi / 2, -np.pi, -np.pi, -np.pi, -np.pi])
    upper = np.array([np.pi / 2, np.pi, 0.0, np.pi, np.pi])
    kept = arm5dof.geometric_ik([40, 10, 30], 0.2, lower=lower, upper=upper)
    assert len(all_sols) == 4 and len(kept) == 1
    assert np.all(kept[0] >= lower) and np.all(kept[0] <= upper)


def test_batch_equals_single():
    rng = np.random.default_rng(2)
    q = rng.uniform(-np.pi, np.pi, size=(200, 5))
    P = arm5dof.forward(q)
    phi = q[:, 1] + q[:, 2] + q[:, 3]
    d = np.stack([np.cos(phi) * np.cos(q[:, 0]), np.cos(phi) * np.sin(q[:, 0]), np.sin(phi)], 1)
    h = P[:, :2] / np.hypot(P[:, 0], P[:, 1])[:, None]
    front = np.arctan2(d[:, 2], np.sum(d[:, :2] * h, axis=1))  # pitch seen toward the target
    sols, valid = arm5dof.geometric_ik_batch(P, front)
    assert sols.shape == (200, 4, 5) and valid.all()
    back = arm5dof.forward(sols.reshape(-1, 5)).reshape(200, 4, 3)
    assert np.abs(back - P[:, None, :]).max() < 1e-9
    for i in range(0, 200, 37):
        single = arm5dof.geometric_ik(P[i], front[i])
        assert min(np.abs(single[0] - s).max() for s in sols[i]) < 1e-12


def test_bad_geometric_input():
    with pytest.raises(toolkit.InvalidParameterError, match="upper_arm must be > 0"):
        arm5dof.geometric_ik([1, 2, 3], 0.0, lengths=(3, -50, 25, 5))
    with pytest.raises(toolkit.InvalidParameterError, match="four finite numbers"):
        arm5dof.geometric_ik([1, 2, 3], 0.0, lengths=(3, 50, 25))
    with pytest.raises(toolkit.InvalidParameterError, match="position"):
        arm5dof.geometric_ik([1, 2], 0.0)
    with pytest.raises(toolkit.InvalidParameterError, match="finite"):
        arm5dof.geometric_ik([1, 2, 3], float("nan"))


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.floats(-3.1, 3.1), min_size=4, max_size=4),
    st.tuples(st.floats(0.5, 100), st.floats(1, 100), st.floats(1, 100), st.floats(0, 20)),
)
def test_geometric_round_trip_property(angles, lengths):
    q = np.r_[angles, 0.0]
    p = arm5dof.forward(q, lengths)
    if np.hypot(p[0], p[1]) < 1e-6:
        return  # on the base axis theta1 is arbitrary (tested separately)
    phi = angles[1] + angles[2] + angles[3]
    h = p[:2] / np.hypot(p[0], p[1])
    d = np.array([np.cos(phi) * np.cos(q[0]), np.cos(phi) * np.sin(q[0]), np.sin(phi)])
    front_phi = np.arctan2(d[2], d[:2] @ h)
    sols = arm5dof.geometric_ik(p, front_phi, lengths)
    assert sols, "a configuration's own target must be reachable"
    scale = max(lengths)
    for s in sols:
        assert np.abs(arm5dof.forward(s, lengths) - p).max() < 1e-9 * scale


# ----------------------------------------------------------------- closed form: Katana 6M180


def test_katana_closed_form_ik_against_pinocchio():
    robot = toolkit.load("katana_6m180")
    base = np.array([0, 0, 0.2015])
    counts = []
    for q in robot.random_q(300, seed=6):
        T = robot.fk(q)
        p0 = T[:3, 3] - base  # frame 0 is at the shoulder
        sols = katana.closed_form_ik(p0, front_pitch(T, 2), roll=q[4])
        counts.append(len(sols))
        assert min(np.abs(s - q).max() for s in sols) < 1e-8  # the original is among them
        for s in sols:
            assert robot.joints.within_limits(s)
            Ts = robot.fk(s)
            assert np.abs(Ts[:3, 3] - T[:3, 3]).max() < 1e-12
            assert np.abs(Ts[:3, 2] - T[:3, 2]).max() < 1e-12
    assert max(counts) >= 2  # several branches survive the limits somewhere


def test_katana_closed_form_ik_limits_switch():
    # case (19): stretched horizontally; without limits the back branch appears too
    reach = 0.190 + 0.139 + 0.1473 + 0.1555
    within = katana.closed_form_ik([reach, 0, 0], 0.0)
    free = katana.closed_form_ik([reach, 0, 0], 0.0, respect_limits=False)
    assert len(within) == 1 and len(free) == 2
    np.testing.assert_allclose(within[0], [0, 0, 0, -np.pi / 2, 0], atol=1e-7)


def test_joint_points_end_on_the_gripper_point():
    from toolkit import arm5dof

    for q in arm5dof.geometric_ik((40.0, 10.0, 30.0), 0.2):
        pts = arm5dof.joint_points(q)
        np.testing.assert_allclose(pts[-1], [40.0, 10.0, 30.0], atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(np.diff(pts, axis=0), axis=1), [3, 50, 25, 5])


def test_fused_solver_matches_the_task_definition():
    """The solver loop and the independent check share one PoseTask residual; the loop's
    answer must meet it, and its Jacobian must be the residual's derivative."""
    from toolkit.ik import PoseTask

    robot = toolkit.load_example("panda")
    target = robot.fk(robot.random_q(seed=8))
    fid = robot.frames.id(None)
    res = robot.ik(target, mask=[1, 1, 1, 1, 1, 0], tol=1e-9)
    task = PoseTask.from_target(fid, target, [1, 1, 1, 1, 1, 0])
    data = robot.model.createData()

    def residual(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pin.computeJointJacobians(robot.model, data, q)
        M = pin.updateFramePlacement(robot.model, data, fid)
        e = np.empty(6)
        task.residual_into(e, M)
        J = pin.getFrameJacobian(robot.model, data, fid, pin.LOCAL_WORLD_ALIGNED)
        return e, task.tool_jacobian(J, M)

    e, _ = residual(res.q)
    assert np.linalg.norm(e[:3]) == pytest.approx(res.position_error, abs=1e-12)
    assert np.linalg.norm(e[3:5]) == pytest.approx(res.orientation_error, abs=1e-12)
    # at a full-pose solution (zero error) de/dq = -J exactly: finite differences
    res = robot.ik(target, tol=1e-10)
    task = PoseTask.from_target(fid, target)
    e, J = residual(res.q)
    assert np.abs(e).max() < 1e-9
    h = 1e-6
    for i in range(robot.joints.nv):
        dq = np.zeros(robot.joints.nv)
        dq[i] = h
        fd = (residual(res.q + dq)[0] - residual(res.q - dq)[0]) / (2 * h)
        np.testing.assert_allclose(fd, -J[:, i], atol=1e-6)


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


def test_joints_that_do_not_move_the_frame_stay_at_the_start():
    """The Panda's fingers do not move its tool frame: every answer (restarts drawn at
    random included, one target or a batch) keeps them at the start's values."""
    panda = toolkit.load_example("panda")
    start = panda.joints.neutral().copy()
    start[7:] = [0.03, 0.01]
    targets = panda.fk(panda.random_q(6, seed=11))
    for k, T in enumerate(targets):
        answer = panda.ik(T, start, seed=k, max_iter=4, restarts=30, method="numeric")
        np.testing.assert_array_equal(answer.q[7:], [0.03, 0.01])
        assert answer.success == (answer.position_error <= 1e-6 >= answer.orientation_error)
    batch = panda.ik_batch(targets, start, max_iter=4, restarts=30)
    np.testing.assert_array_equal(batch.q[:, 7:], np.tile([0.03, 0.01], (6, 1)))
    outside = start.copy()
    outside[7] = 0.5  # beyond the finger's 0.04 m: brought to its limit
    assert panda.ik(targets[0], outside, method="numeric").q[7] == pytest.approx(0.04)
