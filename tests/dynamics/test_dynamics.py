"""Rigid-body dynamics (toolkit.dynamics), each checked by another route: RNEA against the
Euler-Lagrange equations built from the mass matrix and the potential energy by finite
differences; its gravity part against the compiled back end's gravity; the mass matrix
against the kinetic energy; ABA against RNEA (a round trip); a payload against the frame
Jacobian transpose of the load's weight and inertial force."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import dynamics
from toolkit.errors import ConfigurationError, InvalidParameterError
from toolkit.kinematics import CompiledBackend, PinocchioBackend

ROBOTS = ["katana_6m180", "ur5", "anthropomorphic"]


def _robot(name):
    if name in toolkit.available_models():
        return toolkit.load(name)
    return toolkit.load_example(name)


def _state(robot, seed):
    rng = np.random.default_rng(seed)
    q = robot.random_q(seed=seed)
    return q, rng.normal(size=robot.joints.nv), rng.normal(size=robot.joints.nv)


def _potential(robot, q):
    data = robot.model.createData()
    return float(pin.computePotentialEnergy(robot.model, data, q))


@pytest.mark.parametrize("name", ROBOTS)
def test_inverse_dynamics_is_the_euler_lagrange_equation(name):
    """tau = M qdd + (dM/dt) qd - 1/2 d(qd^T M qd)/dq + dV/dq, every derivative by central
    differences of CRBA's M and the potential energy (no RNEA in this route)."""
    robot = _robot(name)
    h = 1e-6
    for seed in range(5):
        q, qd, qdd = _state(robot, seed)
        M = dynamics.mass_matrix(robot, q)
        dM = np.zeros((robot.joints.nv, robot.joints.nv, robot.joints.nv))  # dM / dq_k
        dV = np.zeros(robot.joints.nv)
        for k in range(robot.joints.nv):
            e = np.zeros(robot.joints.nv)
            e[k] = h
            qp, qm = pin.integrate(robot.model, q, e), pin.integrate(robot.model, q, -e)
            dM[k] = (dynamics.mass_matrix(robot, qp) - dynamics.mass_matrix(robot, qm)) / (2 * h)
            dV[k] = (_potential(robot, qp) - _potential(robot, qm)) / (2 * h)
        Mdot = np.einsum("kij,k->ij", dM, qd)
        quad = np.einsum("kij,i,j->k", dM, qd, qd)
        expected = M @ qdd + Mdot @ qd - 0.5 * quad + dV
        tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
        np.testing.assert_allclose(tau, expected, atol=1e-5 * max(1.0, np.abs(tau).max()))


@pytest.mark.parametrize("name", ROBOTS)
def test_at_rest_it_is_the_back_ends_gravity(name):
    robot = _robot(name)
    Q = robot.random_q(20, seed=1)
    zero = np.zeros((20, robot.joints.nv))
    np.testing.assert_allclose(dynamics.inverse_dynamics(robot, Q, zero, zero),
                               robot.gravity(Q), atol=1e-9)  # fmt: skip


@pytest.mark.parametrize("name", ROBOTS)
def test_gravity_with_a_payload_is_its_weight_through_the_jacobian(name):
    """``dynamics.gravity`` (``Robot.gravity``): the back end's g(q) without a payload, one
    row or N; with a point mass m at the tip, g(q) plus J_tip^T (-m g) (the Jacobian of the
    tip's origin, Pinocchio's, in the world frame)."""
    robot = _robot(name)
    Q = robot.random_q(6, seed=2)
    np.testing.assert_array_equal(dynamics.gravity(robot, Q), robot.gravity(Q))
    np.testing.assert_array_equal(dynamics.gravity(robot, Q[0]), robot.gravity(Q)[0])
    m = 2.3
    g = robot.model.gravity.linear
    for q in Q:
        J = robot.jacobian(q)[:3]
        np.testing.assert_allclose(robot.gravity(q, payload=m) - robot.gravity(q),
                                   J.T @ (-m * g), atol=1e-9)  # fmt: skip
    with pytest.raises(toolkit.ConfigurationError, match="NaN"):
        dynamics.gravity(robot, np.full(robot.nq, np.nan))


@pytest.mark.parametrize("name", ROBOTS)
def test_the_mass_matrix_gives_the_kinetic_energy(name):
    robot = _robot(name)
    data = robot.model.createData()
    for seed in range(10):
        q, qd, _ = _state(robot, seed)
        M = dynamics.mass_matrix(robot, q)
        np.testing.assert_allclose(M, M.T, atol=0)
        assert np.linalg.eigvalsh(M).min() > 0
        energy = pin.computeKineticEnergy(robot.model, data, q, qd)
        assert 0.5 * qd @ M @ qd == pytest.approx(energy, rel=1e-10, abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), name=st.sampled_from(ROBOTS),
       mass=st.floats(0.0, 3.0))  # fmt: skip
def test_forward_dynamics_inverts_inverse_dynamics(seed, name, mass):
    robot = _robot(name)
    q, qd, qdd = _state(robot, seed)
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd, payload=mass)
    back = dynamics.forward_dynamics(robot, q, qd, tau, payload=mass)
    np.testing.assert_allclose(back, qdd, atol=1e-8 * max(1.0, np.abs(qdd).max()))


@pytest.mark.parametrize("name", ["katana_6m180", "ur5"])
def test_a_payload_is_its_weight_and_inertial_force_through_the_jacobian(name):
    """A point mass m at an offset c of the tip: tau_with - tau_without = J_c^T m (a_c - g),
    J_c the Jacobian and a_c the classical acceleration of that point, in the world frame."""
    robot = _robot(name)
    model, data = robot.model, robot.model.createData()
    m, c = 1.7, np.array([0.01, -0.02, 0.05])
    load = dynamics.Payload(m, tuple(c))
    fid = robot.frames.id(None)
    for seed in range(5):
        q, qd, qdd = _state(robot, seed)
        extra = (dynamics.inverse_dynamics(robot, q, qd, qdd, payload=load)
                 - dynamics.inverse_dynamics(robot, q, qd, qdd))  # fmt: skip
        pin.forwardKinematics(model, data, q, qd, qdd)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        frame = model.frames[fid]
        point = pin.Frame("c", frame.parentJoint, frame.placement * pin.SE3(np.eye(3), c),
                          pin.FrameType.OP_FRAME)  # fmt: skip
        work = pin.Model(model)
        pid = work.addFrame(point)
        wdata = work.createData()
        pin.forwardKinematics(work, wdata, q, qd, qdd)
        pin.computeJointJacobians(work, wdata, q)
        pin.updateFramePlacements(work, wdata)
        J = pin.getFrameJacobian(work, wdata, pid, pin.LOCAL_WORLD_ALIGNED)[:3]
        a = pin.getFrameClassicalAcceleration(work, wdata, pid, pin.LOCAL_WORLD_ALIGNED).linear
        np.testing.assert_allclose(extra, J.T @ (m * (a - work.gravity.linear)), atol=1e-9)


def test_a_batch_equals_its_rows_and_the_model_is_untouched():
    robot = toolkit.load("katana_6m180")
    before = robot.model.inertias[robot.model.nq].mass
    Q = robot.random_q(6, seed=2)
    V, A = np.ones((6, robot.joints.nv)), np.linspace(-1, 1, 6 * robot.joints.nv).reshape(6, -1)
    batch = dynamics.inverse_dynamics(robot, Q, V, A, payload=0.5)
    rows = [dynamics.inverse_dynamics(robot, q, v, a, payload=0.5)
            for q, v, a in zip(Q, V, A, strict=True)]  # fmt: skip
    np.testing.assert_allclose(batch, rows, atol=0)
    assert dynamics.mass_matrix(robot, Q).shape == (6, robot.joints.nv, robot.joints.nv)
    assert robot.model.inertias[robot.model.nq].mass == before


def test_bad_input_is_refused_with_its_name():
    robot = toolkit.load("katana_6m180")
    q, z = robot.joints.neutral(), np.zeros(robot.joints.nv)
    with pytest.raises(ConfigurationError, match="qd"):
        dynamics.inverse_dynamics(robot, q, np.zeros(3), z)
    with pytest.raises(ConfigurationError, match="tau"):
        dynamics.forward_dynamics(robot, q, z, [np.nan] * robot.joints.nv)
    with pytest.raises(InvalidParameterError, match="rows"):
        dynamics.inverse_dynamics(robot, robot.random_q(3, seed=1), np.zeros((2, robot.joints.nv)),
                                  np.zeros((3, robot.joints.nv)))  # fmt: skip
    with pytest.raises(InvalidParameterError, match="payload"):
        dynamics.inverse_dynamics(robot, q, z, z, payload=-1.0)
    with pytest.raises(InvalidParameterError, match="semidefinite"):
        dynamics.mass_matrix(robot, q, payload=dynamics.Payload(1.0, inertia=(-1.0,) + (0.0,) * 8))
    with pytest.raises(toolkit.FrameNotFoundError):
        dynamics.mass_matrix(robot, q, payload=dynamics.Payload(1.0, frame="nowhere"))


@pytest.mark.parametrize(
    "name", ["ur5", "panda", "kinova", "katana_6m180", "scara", "cartesian", "anthropomorphic"]
)
def test_the_compiled_rnea_is_pinocchios_row_by_row(name):
    """A batch (compiled, over the cores) against Pinocchio's ``rnea`` on each row, with a
    payload that has an offset centre of mass and its own inertia: revolute, prismatic and
    continuous joints, trees with fingers."""
    robot = _robot(name)
    assert dynamics.rigid.compiled_tree(robot.kinematics) is not None
    rng = np.random.default_rng(7)
    N = 300
    Q = robot.random_q(N, seed=rng)
    V, A = rng.uniform(-2, 2, (N, robot.joints.nv)), rng.uniform(-5, 5, (N, robot.joints.nv))
    load = dynamics.Payload(1.3, (0.02, -0.01, 0.04), (0.01, 0.001, 0.0, 0.001, 0.02, 0.0,
                                                       0.0, 0.0, 0.015))  # fmt: skip
    tau = dynamics.inverse_dynamics(robot, Q, V, A, payload=load)
    model = dynamics.payload.model_with(robot, load)
    data = model.createData()
    ref = np.array([pin.rnea(model, data, *row) for row in zip(Q, V, A, strict=True)])
    np.testing.assert_allclose(tau, ref, rtol=0, atol=1e-10 * max(1.0, np.abs(ref).max()))


def test_the_compiled_rnea_adds_the_armature_and_refuses_what_it_cannot_take():
    """A rotor's armature adds armature * qdd, as in Pinocchio; a free-flying base is left
    to Pinocchio (no compiled tree), and the answer is still Pinocchio's."""
    robot = toolkit.load_example("ur5")
    before = np.array(robot.model.armature)
    try:
        robot.model.armature = np.linspace(0.1, 0.6, robot.joints.nv)
        Q = robot.random_q(16, seed=3)
        V, A = np.ones((16, robot.joints.nv)), np.full((16, robot.joints.nv), 2.0)
        data = robot.model.createData()
        ref = np.array([pin.rnea(robot.model, data, *r) for r in zip(Q, V, A, strict=True)])
        np.testing.assert_allclose(dynamics.inverse_dynamics(robot, Q, V, A), ref, atol=1e-10)
    finally:
        robot.model.armature = before
    floating = pin.buildModelFromUrdf(str(robot.urdf_path), pin.JointModelFreeFlyer())
    assert dynamics.rigid.compiled_tree(CompiledBackend(floating)) is None
    assert dynamics.rigid.compiled_tree(PinocchioBackend(robot.model)) is None


def test_batches_either_side_of_the_compiled_threshold_agree():
    robot = toolkit.load_example("panda")
    k = dynamics.rigid.COMPILED_MIN
    Q = robot.random_q(k, seed=5)
    rng = np.random.default_rng(5)
    V, A = rng.normal(size=(k, robot.joints.nv)), rng.normal(size=(k, robot.joints.nv))
    whole = dynamics.inverse_dynamics(robot, Q, V, A)  # compiled
    parts = dynamics.inverse_dynamics(robot, Q[:-1], V[:-1], A[:-1])  # Pinocchio, row by row
    np.testing.assert_allclose(whole[:-1], parts, rtol=0, atol=1e-10)


def test_a_fingers_gravity_torque_is_its_weight_along_its_axis():
    """The Panda's two fingers (axes +y and -y of the hand, 15 g each): at rest each joint
    holds its finger's weight along its own axis, -m g . axis, the world axis taken from the
    forward kinematics of the finger's frame, so the two torques are opposite (the Robotics
    Toolbox 1.5's ``rne`` gives them the same sign: benchmarks/dynamics.py traces it)."""
    panda = toolkit.load_example("panda")
    model = panda.model
    Q = panda.random_q(12, seed=4)
    tau = dynamics.inverse_dynamics(
        panda, Q, np.zeros((12, panda.joints.nv)), np.zeros((12, panda.joints.nv))
    )
    g = np.array([0.0, 0.0, -9.81])
    for name in ("panda_finger_joint1", "panda_finger_joint2"):
        j = model.getJointId(name)
        mass = model.inertias[j].mass
        axis = {"panda_finger_joint1": [0, 1, 0], "panda_finger_joint2": [0, -1, 0]}[name]
        link = "panda_leftfinger" if name.endswith("1") else "panda_rightfinger"
        for q, row in zip(Q, tau, strict=True):
            R = panda.fk(q, link)[:3, :3]
            expected = -mass * g @ (R @ np.array(axis, dtype=float))
            assert row[model.joints[j].idx_v] == pytest.approx(expected, abs=1e-12)
    left, right = (model.joints[model.getJointId(n)].idx_v
                   for n in ("panda_finger_joint1", "panda_finger_joint2"))  # fmt: skip
    np.testing.assert_allclose(tau[:, left], -tau[:, right], atol=1e-12)
    assert np.abs(tau[:, left]).max() > 1e-3  # the hand tilted: a torque that could be wrong


def _bodies_by_yourdfpy(robot, angles: np.ndarray) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """(mass, world centre of mass, world rotation of the inertia's axes) and the inertia in
    those axes of every link with mass, from yourdfpy's reading of the URDF file (fixed
    links, fingers and mimic joints as yourdfpy places them), one angle per joint: no
    Pinocchio in this route."""
    urdf = _yourdfpy(robot)
    model = robot.model
    cfg = {}
    for name in urdf.actuated_joint_names:
        if model.existJointName(name):
            cfg[name] = float(angles[model.joints[model.getJointId(name)].idx_v])
    urdf.update_cfg(cfg)
    out = []
    for name, link in urdf.link_map.items():
        body = link.inertial
        if body is None or not body.mass:
            continue
        frame = np.asarray(urdf.get_transform(name, urdf.base_link))
        at = frame @ (np.eye(4) if body.origin is None else np.asarray(body.origin))
        out.append((float(body.mass), at[:3, 3].copy(), at[:3, :3].copy(),
                    np.asarray(body.inertia, dtype=float)))  # fmt: skip
    return out


_YOURDFPY: dict[str, object] = {}


def _yourdfpy(robot):
    import yourdfpy

    key = str(robot.urdf_path)
    if key not in _YOURDFPY:
        _YOURDFPY[key] = yourdfpy.URDF.load(key, load_meshes=False, build_scene_graph=True)
    return _YOURDFPY[key]


@pytest.mark.parametrize("name", ["kinova", "panda", "arm5dof"])
def test_weights_and_kinetic_energy_from_an_independent_reading_of_the_file(name):
    """On the arms where the Robotics Toolbox 1.5 differs from Pinocchio
    (benchmarks/dynamics.py: the two whose fingers hang from rotated joints, and one with
    joints on negative axes): the gravity torques are the
    derivatives of the links' potential energy, sum m g z, and 1/2 qd^T M qd their kinetic
    energy, sum 1/2 m |v|^2 + 1/2 w^T R I R^T w, every link's pose from yourdfpy,
    velocities by central differences in time."""
    from helpers import rot_log

    robot = _robot(name)
    rng = np.random.default_rng(8)
    fingers = [robot.model.joints[j].idx_v for j in range(1, robot.model.njoints)
               if "finger" in robot.model.names[j]]  # fmt: skip
    arm = [i for i in range(robot.joints.nv) if i not in fingers]
    h = 1e-6

    def potential(a):
        return sum(m * 9.81 * c[2] for m, c, _, _ in _bodies_by_yourdfpy(robot, a))

    for _ in range(3):
        angles = robot.joints.angles(robot.random_q(seed=rng))
        angles[fingers] = angles[fingers[0]] if fingers else 0.0  # as the mimic joint has it
        q = robot.joints.q_from_angles(angles)
        for k in arm:
            e = np.zeros(robot.joints.nv)
            e[k] = h
            expected = (potential(angles + e) - potential(angles - e)) / (2 * h)
            assert robot.gravity(q)[k] == pytest.approx(expected, abs=1e-6)
        qd = rng.normal(size=robot.joints.nv)
        qd[fingers] = 0.0
        now = _bodies_by_yourdfpy(robot, angles)
        ahead, behind = (_bodies_by_yourdfpy(robot, angles + s * h * qd) for s in (1, -1))
        energy = 0.0
        for (m, _, R, inertia), (_, c1, R1, _), (_, c0, R0, _) in zip(now, ahead, behind,
                                                                     strict=True):  # fmt: skip
            v, w = (c1 - c0) / (2 * h), rot_log(R1 @ R0.T) / (2 * h)
            energy += 0.5 * m * v @ v + 0.5 * w @ (R @ inertia @ R.T) @ w
        M = dynamics.mass_matrix(robot, q)
        assert 0.5 * qd @ M @ qd == pytest.approx(energy, rel=1e-6)


@pytest.mark.parametrize("name", ["ur5", "katana_6m180", "kinova"])
def test_the_power_the_torques_deliver_is_the_rate_of_the_arms_energy(name):
    """Along a frictionless motion (a quintic through three random configurations), the
    torques' power tau . qd equals d/dt of the kinetic plus potential energy (Pinocchio's
    energies of the states, differentiated in time by central differences): the batch
    RNEA (compiled) and the single call both."""
    from toolkit import motion

    robot = _robot(name)
    path = motion.quintic(robot, robot.random_q(3, seed=5), [0.0, 1.0, 2.0])
    t = np.linspace(0.05, 1.95, 40)
    h = 1e-5
    data = robot.model.createData()

    def energy(times):
        q, qd, _ = path.evaluate(times)
        Q = robot.joints.q_from_angles(q)
        return np.array([pin.computeKineticEnergy(robot.model, data, a, v)
                         + pin.computePotentialEnergy(robot.model, data, a)
                         for a, v in zip(Q, qd, strict=True)])  # fmt: skip

    rate = (energy(t + h) - energy(t - h)) / (2 * h)
    q, qd, qdd = path.evaluate(t)
    Q = robot.joints.q_from_angles(q)
    tau = dynamics.inverse_dynamics(robot, Q, qd, qdd)
    power = np.einsum("ij,ij->i", tau, qd)
    scale = max(1.0, np.abs(power).max())
    np.testing.assert_allclose(power, rate, atol=1e-6 * scale)
    single = dynamics.inverse_dynamics(robot, Q[7], qd[7], qdd[7])
    assert single @ qd[7] == pytest.approx(rate[7], abs=1e-6 * scale)
    assert np.abs(power).max() > 0.1  # a motion that does work


def test_forward_dynamics_with_mimic_joints_equals_the_expanded_model_projected():
    """The bending manipulator's joints follow two (mimic), which Pinocchio's ABA refuses:
    forward dynamics by the projection, checked against the model read without mimic (every
    joint free), its mass matrix and bias taken by Pinocchio there and projected by the
    URDF's own mimic relations (multiplier, offset), read here from the XML."""
    import xml.etree.ElementTree as ET

    robot = toolkit.load("bending")
    text = toolkit.urdf_text("bending")
    full = toolkit.load_urdf(text, mimic=False)
    fm, fd = full.model, full.model.createData()
    follows = {}
    for joint in ET.fromstring(text).iter("joint"):
        mimic = joint.find("mimic")
        if mimic is not None:
            follows[joint.get("name")] = (mimic.get("joint"), float(mimic.get("multiplier", 1.0)),
                                          float(mimic.get("offset", 0.0)))  # fmt: skip
    assert follows  # the model does have mimic joints
    G, offset = np.zeros((fm.nv, robot.joints.nv)), np.zeros(fm.nv)
    for j in range(1, fm.njoints):
        name, col = fm.names[j], fm.joints[j].idx_v
        master, gain, shift = follows.get(name, (name, 1.0, 0.0))
        G[col, robot.joints.names.index(master)] = gain
        offset[col] = shift
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = robot.random_q(seed=rng)
        qd, tau = rng.normal(size=robot.joints.nv), rng.normal(size=robot.joints.nv)
        qf, vf = G @ robot.joints.angles(q) + offset, G @ qd
        M = np.array(pin.crba(fm, fd, qf))
        M = np.triu(M) + np.triu(M, 1).T
        bias = np.array(pin.rnea(fm, fd, qf, vf, np.zeros(fm.nv)))
        expected = np.linalg.solve(G.T @ M @ G, tau - G.T @ bias)
        got = dynamics.forward_dynamics(robot, q, qd, tau)
        np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-10 * np.abs(expected).max())
        # and it undoes the inverse dynamics
        np.testing.assert_allclose(dynamics.inverse_dynamics(robot, q, qd, got), tau, atol=1e-8)


def _ur5_without_inertia():
    import re

    ur5 = toolkit.load_example("ur5")
    text = re.sub(r"<inertial>.*?</inertial>", "", ur5.urdf_path.read_text(), flags=re.S)
    with pytest.warns(toolkit.errors.InertiaWarning, match="shoulder_link, upper_arm_link"):
        return toolkit.load_urdf(text, package_dirs=[ur5.urdf_path.parents[2]])


def test_a_description_without_inertia_warns_at_load_and_every_dynamics_call_refuses():
    bare = _ur5_without_inertia()
    q, zero = bare.random_q(seed=1), np.zeros(6)
    assert bare.fk(q).shape == (4, 4)  # kinematics is fine
    calls = [
        lambda: dynamics.inverse_dynamics(bare, q, zero, zero),
        lambda: dynamics.forward_dynamics(bare, q, zero, zero),
        lambda: dynamics.mass_matrix(bare, q),
        lambda: dynamics.gravity(bare, q),
        lambda: dynamics.inverse_dynamics(bare, q, zero, zero, payload=1.0),
        lambda: toolkit.backlash.Backlash(bare, nominal_torque=np.ones(6)),
        lambda: toolkit.motion.time_optimal(bare, [q, q + 0.1], acceleration=2.0, torque=True),
    ]
    for call in calls:
        with pytest.raises(toolkit.UnsupportedModelError, match=r"needs the links' inertia.*"
                           r"shoulder_link"):  # fmt: skip
            call()


def test_a_tool_link_without_inertia_on_a_wrist_with_its_own_is_no_defect():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", toolkit.errors.InertiaWarning)
        ur5 = toolkit.load_example("ur5")  # ee_link has shapes and no inertia, wrist_3 has
    assert dynamics.mass_matrix(ur5, ur5.random_q(seed=2)).shape == (6, 6)


@pytest.mark.parametrize("name", ["ur10", "panda", "kinova", "z1"])
def test_the_compiled_batch_mass_matrix_equals_pinocchio_row_by_row(name):
    """The batch door (compiled CRBA about the world's origin) against Pinocchio's crba on
    each row: turning, sliding (the Panda's fingers) and continuous joints, with armature."""
    robot = toolkit.load_example(name)
    Q = robot.random_q(64, seed=4)
    M = dynamics.mass_matrix(robot, Q)  # >= COMPILED_MIN rows: the compiled route
    data = robot.model.createData()
    for q, got in zip(Q, M, strict=True):
        ref = np.array(pin.crba(robot.model, data, q))
        ref = np.triu(ref) + np.triu(ref, 1).T
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * max(1.0, np.abs(ref).max()))
    heavy = dynamics.mass_matrix(robot, Q, payload=2.0)
    assert np.all(np.linalg.eigvalsh(heavy - M).min(axis=1) > -1e-12)  # a payload adds inertia
    one = dynamics.mass_matrix(robot, Q[3], payload=2.0)  # one row: Pinocchio's route
    np.testing.assert_allclose(heavy[3], one, atol=1e-12 * max(1.0, np.abs(one).max()))
