"""One kinematics contract: both back ends give the same answer on every joint type.

The compiled back end is compared with Pinocchio (the reference, called directly on the
model) to 1e-10, single configurations and batches on both sides of the parallel
threshold, on crafted descriptions (mimic multipliers from -10 to 10 and tiny ones,
continuous joints on skew axes, free-flyer roots) and on real robots; the same seed gives
the same IK answer on both back ends; configurations are valid by construction.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import toolkit
import toolkit.kinematics
from toolkit.kinematics import PARALLEL_MIN
from toolkit.robot import Robot

_LINK = (
    '<link name="{n}"><inertial><mass value="{m}"/><origin xyz="0.03 -0.02 0.05"/>'
    '<inertia ixx="1e-3" iyy="2e-3" izz="3e-3" ixy="0" ixz="0" iyz="0"/></inertial></link>'
)
_LIMIT = '<limit lower="-2.5" upper="2.5" effort="10" velocity="1"/>'


def chain_urdf(joints: list[tuple[str, str, str]]) -> str:
    """A chain l0 - l1 - ... joined by (type, axis, extra XML) joints, skewed placements."""
    links = "".join(_LINK.format(n=f"l{i}", m=1.0 + 0.3 * i) for i in range(len(joints) + 1))
    body = "".join(
        f'<joint name="j{i}" type="{kind}"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="0.12 {0.01 * i} 0.07" rpy="{0.1 * i} -0.2 0.3"/><axis xyz="{axis}"/>'
        f"{extra}</joint>"
        for i, (kind, axis, extra) in enumerate(joints)
    )
    return f'<robot name="crafted">{links}{body}</robot>'


def _mimic(of: int, multiplier: float, offset: float = 0.0) -> str:
    return f'{_LIMIT}<mimic joint="j{of}" multiplier="{multiplier!r}" offset="{offset!r}"/>'


MULTIPLIERS = [-10.0, -7.0, -2.5, -1.0, -1e-9, 1e-12, 0.5, 1.0, 3.0, 7.0, 10.0]
CRAFTED = {
    **{
        f"mimic x{m:g}": [
            ("revolute", "0 0.6 0.8", _LIMIT),
            ("revolute", "0.3 0 -0.95", _mimic(0, m, 0.3)),
            ("prismatic", "0.6 0 0.8", _mimic(0, m, -0.05)),
            ("revolute", "1 0 0", _LIMIT),
        ]
        for m in MULTIPLIERS
    },
    "continuous skew": [
        ("continuous", "0 0 -1", ""),
        ("continuous", "0.48 0.6 0.64", ""),
        ("revolute", "0 1 0", _LIMIT),
        ("continuous", "-1 0 0", ""),
    ],
    "everything": [
        ("revolute", "0 0 1", _LIMIT),
        ("continuous", "0.6 -0.8 0", ""),
        ("prismatic", "0 0 -1", _LIMIT),
        ("revolute", "0.3 0 -0.95", _mimic(0, 7.0, 0.2)),
        ("revolute", "0 1 0", _LIMIT),
    ],
}


def _crafted(name: str, floating: bool) -> Robot:
    text = chain_urdf(CRAFTED[name])
    if floating:
        model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer(), mimic=True)
    else:
        model = pin.buildModelFromXML(text, mimic=True)
    return Robot(model, tip=f"l{len(CRAFTED[name])}")


def _reference(model: pin.Model, Q: np.ndarray, fid: int):
    """Pinocchio's own FK, Jacobian and gravity, one configuration at a time."""
    data = model.createData()
    T, J, G = [], [], []
    for q in Q:
        pin.forwardKinematics(model, data, q)
        T.append(pin.updateFramePlacement(model, data, fid).homogeneous.copy())
        J.append(pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED))
        G.append(pin.computeGeneralizedGravity(model, data, q).copy())
    return np.array(T), np.array(J).reshape(len(Q), 6, model.nv), np.array(G)


def _assert_equal_to_pinocchio(robot: Robot, seed: int) -> None:
    assert robot.kinematics.engine.name == "compiled", robot.kinematics.engine
    for n in (3, PARALLEL_MIN + 5):  # one core, and spread over the cores
        Q = robot.random_q(n, seed=seed)
        for frame in {robot.tip, list(robot.frames)[1]}:
            fid = robot.frames.id(frame)
            T, J, G = _reference(robot.model, Q, fid)
            np.testing.assert_allclose(robot.fk(Q, frame), T, rtol=0, atol=1e-10)
            np.testing.assert_allclose(robot.jacobian(Q, frame), J, rtol=0, atol=1e-10)
            np.testing.assert_allclose(robot.fk(Q[1], frame), T[1], rtol=0, atol=1e-10)
            np.testing.assert_allclose(robot.jacobian(Q[2], frame), J[2], rtol=0, atol=1e-10)
        scale = max(1.0, float(np.abs(G).max()))
        np.testing.assert_allclose(robot.gravity(Q), G, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(robot.gravity(Q[0]), G[0], rtol=0, atol=1e-10 * scale)


@pytest.mark.parametrize("floating", [False, True], ids=["fixed", "floating"])
@pytest.mark.parametrize("name", sorted(CRAFTED))
def test_crafted_joints_equal_pinocchio(name, floating):
    _assert_equal_to_pinocchio(_crafted(name, floating), seed=len(name))


REAL = ["kinova", "tiago_no_hand", "pr2", "ur5", "panda", "solo12", "talos_left_arm", "baxter"]


@pytest.mark.parametrize("name", REAL)
def test_real_robots_with_every_joint_kind_are_compiled(name):
    robot = toolkit.load_example(name)
    _assert_equal_to_pinocchio(robot, seed=3)


def test_floating_base_robots_are_compiled_and_sample_valid_configurations():
    robot = toolkit.load_example("ur5", floating=True)
    assert (
        robot.kinematics.engine.name == "compiled"
        and "free-flyer" in robot.kinematics.engine.reason
    )
    Q = robot.random_q(500, seed=4)
    assert np.all(np.abs(Q[:, :3]) <= toolkit.kinematics.FREE_FLYER_BOX)
    np.testing.assert_allclose(np.linalg.norm(Q[:, 3:7], axis=1), 1.0, atol=1e-12)
    assert robot.joints.within_limits(Q)
    _assert_equal_to_pinocchio(robot, seed=5)


def test_a_quaternion_off_the_unit_sphere_is_refused():
    robot = toolkit.load_example("ur5", floating=True)
    q = robot.joints.neutral()
    q[3:7] = [1.0, 1.0, 0.0, 0.0]  # norm sqrt 2: Pinocchio would return a scaled "rotation"
    with pytest.raises(toolkit.ConfigurationError, match="quaternion"):
        robot.fk(q)
    with pytest.raises(toolkit.ConfigurationError, match="root_joint"):
        robot.joints.within_limits(q)
    with pytest.raises(toolkit.ConfigurationError):
        robot.ik(robot.fk(robot.joints.neutral()), q0=q)


def _same_seed_same_answer(robot: Robot, n: int, seed: int) -> None:
    """The numeric solver's seeded stream (``method="auto"`` answers by branches on the
    compiled back end only: its door verifies by the compiled kinematics)."""
    reference = Robot(robot.model, tip=robot.tip, backend="pinocchio")
    targets = robot.fk(robot.random_q(n, seed=seed))
    solved = 0
    for i, T in enumerate(targets):
        compiled = robot.ik(T, seed=i, method="numeric")
        pinocchio = reference.ik(T, seed=i, method="numeric")
        assert compiled.success == pinocchio.success
        np.testing.assert_allclose(compiled.q, pinocchio.q, rtol=0, atol=1e-8)
        if compiled.success:
            robot.fk(compiled.q)  # a successful q is one fk accepts
            solved += 1
    assert solved >= 0.8 * n


@pytest.mark.parametrize("name", ["ur5", "panda", "kinova", "tiago_no_hand"])
def test_the_same_seed_gives_the_same_q_on_both_back_ends(name):
    _same_seed_same_answer(toolkit.load_example(name), 25, seed=7)


@pytest.mark.parametrize("name", ["mimic x7", "continuous skew", "everything"])
def test_the_same_seed_gives_the_same_q_on_crafted_joints(name):
    _same_seed_same_answer(_crafted(name, floating=False), 20, seed=8)
    _same_seed_same_answer(_crafted(name, floating=True), 10, seed=9)


def test_ik_batch_and_path_use_the_same_back_end_and_stream():
    robot = toolkit.load_example("kinova")
    reference = Robot(robot.model, tip=robot.tip, backend="pinocchio")
    targets = robot.fk(robot.random_q(12, seed=10))
    a = robot.ik_batch(targets, seed=3, method="numeric")
    b = reference.ik_batch(targets, seed=3, method="numeric")
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-8)
    assert a.success.all() and (a.success == b.success).all()
    # a path built from joint angles (straight lines of (cos, sin) pairs leave the circle)
    angles = robot.joints.angles(robot.random_q(seed=11))
    Q = robot.joints.q_from_angles(np.linspace(angles, angles + 0.3, 8))
    path = robot.fk(Q)
    p1 = robot.ik_path(path, q0=Q[0], method="numeric")
    p2 = reference.ik_path(path, q0=Q[0], method="numeric")
    assert p1.all_succeeded
    np.testing.assert_allclose(p1.q, p2.q, rtol=0, atol=1e-8)


def test_tiago_ik_success_means_a_valid_q():
    """The audit's case: the wheels' (cos, sin) pairs were left at (0, 0)."""
    robot = toolkit.load_example("tiago_no_hand")
    res = robot.ik([0.3522, 0.1784, 0.2684])
    assert res.success
    robot.fk(res.q)  # accepted: every pair on the circle
    pairs = res.q[robot.joints.cos_index] ** 2 + res.q[robot.joints.sin_index] ** 2
    np.testing.assert_allclose(pairs, 1.0, atol=1e-12)


def test_success_is_refused_for_a_q_off_the_circle():
    from toolkit.ik import PoseTask, verify

    robot = toolkit.load_example("kinova")
    q = robot.random_q(seed=2)
    task = PoseTask.from_target(robot.frames.id(None), robot.fk(q))
    assert verify(robot._numeric.ik_state, task, q, 1e-9).success
    bad = q.copy()
    bad[robot.joints.cos_index[0]] *= 1.5  # the same pose for Pinocchio, but not a valid q
    assert not verify(robot._numeric.ik_state, task, bad, 1e-9).success


def test_a_continuous_joint_on_a_negative_axis_loads(tmp_path):
    """pybullet's laikago and racecar: ``<axis xyz="0 0 -1"/>`` on a continuous joint."""
    path = tmp_path / "wheel.urdf"
    path.write_text(chain_urdf([("continuous", "0 0 -1", ""), ("continuous", "0 -1 0", "")]))
    robot = toolkit.load_urdf(path, tip="l2")
    assert robot.kinematics.engine.name == "compiled"
    _assert_equal_to_pinocchio(robot, seed=1)


def test_the_back_end_can_be_chosen_and_is_refused_when_it_cannot_be_had():
    robot = toolkit.load_example("ur5")
    assert Robot(robot.model, backend="pinocchio").kinematics.engine.name == "pinocchio"
    with pytest.raises(toolkit.InvalidParameterError, match="backend"):
        Robot(robot.model, backend="gpu")
    spherical = pin.Model()
    joint = spherical.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    spherical.appendBodyToJoint(joint, pin.Inertia.Random(), pin.SE3.Identity())
    spherical.addBodyFrame("ball_link", joint, pin.SE3.Identity(), 0)
    assert Robot(spherical).kinematics.engine.name == "pinocchio"
    with pytest.raises(toolkit.UnsupportedModelError, match="ball"):
        Robot(spherical, backend="compiled")
    # the fallback answers as Pinocchio does, and samples unit quaternions
    q = Robot(spherical).random_q(5, seed=1)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    res = Robot(spherical).ik(Robot(spherical).fk(q[0]), seed=1)
    assert res.success and np.isclose(np.linalg.norm(res.q), 1.0)


def test_robots_pickle_with_their_back_end_choice():
    import pickle

    robot = Robot(toolkit.load_example("ur5").model, backend="pinocchio")
    again = pickle.loads(pickle.dumps(robot))
    assert again == robot and again.kinematics.engine.name == "pinocchio"


def _pybullet_robots() -> list:
    data = pytest.importorskip("pybullet_data", reason="pybullet is in the test extra")
    from pathlib import Path

    return sorted(Path(data.getDataPath()).rglob("*.urdf"))


def test_every_pybullet_data_robot_pinocchio_parses_is_compiled_and_agrees():
    """pybullet_data's 1,095 descriptions (laikago, mini_cheetah, racecar: continuous
    joints on negative axes): each one that moves is compiled and equals Pinocchio."""
    moving = failed = 0
    for path in _pybullet_robots():
        try:
            robot = toolkit.load_urdf(path)
        except toolkit.ModelLoadError:
            failed += 1  # the cause is named; tests/descriptions/test_corpus.py holds that
            continue
        if robot.joints.nv == 0:
            continue
        moving += 1
        Q = robot.random_q(4, seed=1)
        T, J, G = _reference(robot.model, Q, robot.frames.id(None))
        assert robot.kinematics.engine.name == "compiled", (path, robot.kinematics.engine)
        np.testing.assert_allclose(robot.fk(Q), T, rtol=0, atol=1e-10, err_msg=str(path))
        np.testing.assert_allclose(robot.jacobian(Q), J, rtol=0, atol=1e-10, err_msg=str(path))
        scale = max(1.0, float(np.abs(G).max()))
        np.testing.assert_allclose(robot.gravity(Q), G, rtol=0, atol=1e-10 * scale)
    assert moving >= 35 and failed <= 10, (moving, failed)
