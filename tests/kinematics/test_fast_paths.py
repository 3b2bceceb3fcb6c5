"""The single-solve fast paths give the answers of the general ones: the seed keyword, the
target parsing, the chord form of the orientation error, the scalar validity check, the
compiled frames' principal-axis shortcuts."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit.errors import InvalidParameterError
from toolkit.ik import IKOptions, PoseTask

UNREACHABLE = np.array([3.0, 0.0, 0.5])  # 3 m from the UR5's base: restarts always run


def test_the_seed_keyword_equals_the_seed_option():
    robot = toolkit.load_example("ur5")
    for seed in (0, 7, 2**40):
        a = robot.ik(UNREACHABLE, restarts=3, seed=seed)
        b = robot.ik(UNREACHABLE, options=IKOptions(restarts=3, seed=seed))
        np.testing.assert_array_equal(a.q, b.q)
        assert (a.iterations, a.restarts) == (b.iterations, b.restarts)
    # the restarts differ from seed to seed (each start stalls after its own count)
    assert len({robot.ik(UNREACHABLE, restarts=3, seed=s).iterations for s in range(6)}) > 1


def test_seed_none_draws_a_fresh_stream_and_the_default_does_not():
    robot = toolkit.load_example("ur5")
    fresh = {robot.ik(UNREACHABLE, restarts=3, seed=None).iterations for _ in range(8)}
    assert len(fresh) > 1
    same = {robot.ik(UNREACHABLE, restarts=3).iterations for _ in range(4)}
    assert len(same) == 1


@pytest.mark.parametrize("seed", [-1, 1.5, True, "3", 2**64])
def test_a_bad_seed_is_refused(seed):
    robot = toolkit.load_example("ur5")
    with pytest.raises(InvalidParameterError, match="seed"):
        robot.ik(UNREACHABLE, seed=seed)


def test_the_seed_keyword_reaches_the_collision_free_solver():
    robot = toolkit.load_example("ur5")
    target = robot.fk(robot.random_q(seed=3))
    a = robot.ik(target, collision_free=True, seed=5)
    b = robot.ik(target, collision_free=True, options=IKOptions(seed=5))
    np.testing.assert_array_equal(a.q, b.q)


@pytest.mark.parametrize("method", ["auto", "numeric"])
def test_every_layout_of_a_target_gives_the_same_answer(method):
    robot = toolkit.load_example("ur5")
    T = robot.fk(robot.random_q(seed=4))
    reference = robot.ik(T, method=method)
    assert reference.success
    frozen = T.copy()
    frozen.flags.writeable = False
    for target in (
        np.asfortranarray(T),
        frozen,
        T.astype(">f8"),
        T.tolist(),
        np.stack([T, T])[1],
        np.array(T.T).T,  # a transposed view: not C-contiguous
    ):
        res = robot.ik(target, method=method)
        np.testing.assert_array_equal(res.q, reference.q)
    T_before = T.copy()
    robot.ik(T, method=method)
    np.testing.assert_array_equal(T, T_before)  # the caller's array is never written


def _turn(axis: np.ndarray, angle: float) -> np.ndarray:
    return pin.exp3(angle * axis / np.linalg.norm(axis))


@settings(max_examples=200, deadline=None)
@given(
    st.floats(-np.pi, np.pi),
    st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda v: np.linalg.norm(v) > 0.1),
    st.floats(0.0, np.pi),
    st.lists(st.floats(-0.5, 0.5), min_size=3, max_size=3),
)
def test_the_chord_error_equals_the_rotation_angle(q1, axis, angle, shift):
    """errors() without a mask measures the angle from ||R - R_t||; it must equal the norm
    of log3(R^T R_t) (to rounding near 0, within 3e-8 rad near pi)."""
    robot = toolkit.load("katana_6m180")
    q = robot.joints.neutral()
    q[0] = q1
    reached = robot.fk(q)
    target = reached.copy()
    target[:3, :3] = reached[:3, :3] @ _turn(np.array(axis), angle)
    target[:3, 3] += shift
    task = PoseTask.from_target(robot.frames.id(None), target)
    pos, rot = task.errors(robot.model, robot.model.createData(), q)
    exact = np.linalg.norm(pin.log3(reached[:3, :3].T @ target[:3, :3]))
    assert abs(rot - exact) <= (3e-8 if angle > np.pi - 1e-3 else 1e-12 + 1e-9 * exact)
    assert pos == pytest.approx(np.linalg.norm(shift), abs=1e-15)
    masked = PoseTask.from_target(robot.frames.id(None), target, mask=[1, 1, 1, 1, 1, 1.0 - 1e-12])
    assert masked.errors(robot.model, robot.model.createData(), q) == pytest.approx(
        (pos, exact), abs=3e-8
    )


@pytest.mark.parametrize("name", ["ur5", "kinova", "tiago_no_hand"])
def test_the_scalar_validity_check_equals_the_array_one(name):
    robot = toolkit.load_example(name)
    state = robot._numeric.ik_state
    rng = np.random.default_rng(1)
    Q = robot.random_q(200, seed=2)
    Q[::4] += rng.normal(0, 4, Q[::4].shape)  # some out of limits, off the circle
    Q[1::8, 0] = np.nan
    for i, q in enumerate(Q):
        if i % 3 == 0 and robot.joints.units:  # off the circle by a hair, or on it
            g = robot.joints.units[0]
            q[g] *= 1 + (1e-8 if i % 2 else 1e-11)
        assert state.valid(q) == bool(state.valid_rows(q)), (i, q)
    assert {state.valid(q) for q in Q} == {True, False}


_AXES = ["0 0 1", "0 0.6 0.8", "0 -1 0", "1 0 0", "0 0 -1"]


def _chain(rpy: list[str]) -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(len(_AXES) + 1))
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="0.1 0.02 0.05" rpy="{rpy[i]}"/><axis xyz="{axis}"/>'
        '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        for i, axis in enumerate(_AXES)
    )
    return f'<robot name="chain">{links}{joints}</robot>'


def test_principal_axes_and_plain_placements_take_shortcuts_with_pinocchio_s_answer():
    model = pin.buildModelFromXML(_chain(["0 0 0", "0.1 -0.2 0.3", "0 0 0", "0.5 0 0", "0 0 0"]))
    robot = toolkit.Robot(model, tip="l5")
    ints = robot.kinematics.chain(robot.frames.id(None))[0]
    assert ints[:, 4].tolist() == [2, -1, 1, 0, 2]  # the axis index, -1 for the tilted one
    assert ints[:, 5].tolist() == [1, 0, 1, 0, 1]  # placements without a rotation
    data = model.createData()
    Q = robot.random_q(64, seed=3)
    fid = robot.frames.id(None)
    for q, T in zip(Q, robot.fk(Q), strict=True):
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(T, data.oMf[fid].homogeneous, rtol=0, atol=1e-12)
    ur5 = toolkit.load_example("ur5")
    assert (ur5.kinematics.chain(ur5.frames.id(None))[0][:, 4] >= 0).all()


@pytest.mark.parametrize("name", ["ur5", "kinova"])
def test_one_value_per_joint_is_q_itself_only_where_every_joint_has_one_coordinate(name):
    """The shortcut (UR5: q is the values) answers what the general conversion does, as a
    new array; the Kinova's continuous joints keep the (cos, sin) conversion."""
    robot = toolkit.load_example(name)
    q = robot.random_q(5, seed=2)
    values = robot.joints.angles(q)
    assert robot.joints._plain_only == (name == "ur5")
    np.testing.assert_allclose(robot.joints.q_from_angles(values), q, atol=1e-15)
    general = np.arctan2(np.sin(values), np.cos(values))  # each angle wrapped, as angles() does
    continuous = [j.idx_v for j in robot.joints.joints if j.kind == "continuous"]
    np.testing.assert_allclose(values[:, continuous], general[:, continuous], atol=1e-15)
    out = robot.joints.angles(q[0])
    out[:] = 99.0  # a new array: q is not touched
    assert np.abs(q[0]).max() < 99.0 and (robot.joints.q_from_angles(values[0]) is not values[0])
