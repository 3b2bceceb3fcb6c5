"""The compiled engine against Pinocchio (the reference), and the IK on both back ends."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit.descriptions import EXAMPLE_ROBOTS, example_robot_data_dir

CATALOGUE = [*toolkit.available_models()]
ROBOTS = [*CATALOGUE, *sorted(EXAMPLE_ROBOTS)]


def _load(name: str) -> toolkit.Robot:
    return toolkit.load(name) if name in CATALOGUE else toolkit.load_example(name)


def _reference(robot: toolkit.Robot, Q: np.ndarray, fid: int):
    data = robot.model.createData()
    T, J, G = [], [], []
    for q in Q:
        pin.forwardKinematics(robot.model, data, q)
        T.append(pin.updateFramePlacement(robot.model, data, fid).homogeneous.copy())
        J.append(pin.computeFrameJacobian(robot.model, data, q, fid, pin.LOCAL_WORLD_ALIGNED))
        G.append(pin.computeGeneralizedGravity(robot.model, data, q).copy())
    return np.array(T), np.array(J).reshape(len(Q), 6, robot.joints.nv), np.array(G)


@pytest.mark.parametrize("name", ROBOTS)
def test_compiled_kinematics_equal_pinocchio(name):
    robot = _load(name)
    assert robot.kinematics.engine.name == "compiled", robot.kinematics.engine
    Q = robot.random_q(64, seed=11)
    for frame in {robot.tip, list(robot.frames)[-1], list(robot.frames)[1]}:
        fid = robot.frames.id(frame)
        T, J, G = _reference(robot, Q, fid)
        np.testing.assert_allclose(robot.fk(Q, frame), T, rtol=0, atol=1e-12)
        np.testing.assert_allclose(robot.jacobian(Q, frame), J, rtol=0, atol=1e-12)
    scale = max(1.0, float(np.abs(G).max()))
    np.testing.assert_allclose(robot.gravity(Q), G, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize(("links", "n"), [(1, 3), (2, 5), (4, 2)])
def test_compiled_mimic_chains_equal_pinocchio(links, n):
    robot = toolkit.load("bending", links=links, n=n)
    Q = robot.random_q(40, seed=links)
    T, J, G = _reference(robot, Q, robot.frames.id(None))
    np.testing.assert_allclose(robot.fk(Q), T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(robot.jacobian(Q), J, rtol=0, atol=1e-12)
    np.testing.assert_allclose(robot.gravity(Q), G, rtol=0, atol=1e-12)


_PANDA = toolkit.load_example("panda")


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=9, max_size=9))
def test_compiled_panda_at_any_configuration(fractions):
    lo, hi = _PANDA.joints.lower, _PANDA.joints.upper
    q = lo + (np.array(fractions) + 1) / 2 * (hi - lo)
    Q = np.repeat(q[None], 8, axis=0)
    T, J, G = _reference(_PANDA, Q[:1], _PANDA.frames.id(None))
    np.testing.assert_allclose(_PANDA.fk(Q)[0], T[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(_PANDA.jacobian(Q)[0], J[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(_PANDA.gravity(Q)[0], G[0], rtol=0, atol=1e-11)


def test_continuous_joints_are_compiled_too():
    kinova = toolkit.load_urdf(
        example_robot_data_dir() / "kinova_description/robots/kinova.urdf",
        tip="j2s6s200_end_effector",
    )
    assert (
        kinova.kinematics.engine.name == "compiled"
        and "continuous" in kinova.kinematics.engine.reason
    )
    Q = kinova.random_q(16, seed=1)
    T, J, G = _reference(kinova, Q, kinova.frames.id(None))
    np.testing.assert_allclose(kinova.fk(Q), T, atol=1e-12)
    np.testing.assert_allclose(kinova.jacobian(Q), J, atol=1e-12)
    np.testing.assert_allclose(kinova.gravity(Q), G, atol=1e-12)
    targets = kinova.fk(kinova.random_q(6, seed=2))
    batch = kinova.ik_batch(targets, tol=1e-7)
    assert batch.success.all() and batch.position_error.max() <= 1e-7


@pytest.mark.parametrize("method", ["auto", "numeric"])
@pytest.mark.parametrize("name", ["ur5", "panda", "katana_6m90a", "scara"])
def test_ik_batch_equals_single_solves(name, method):
    robot = _load(name)
    targets = robot.fk(robot.random_q(24, seed=5))
    batch = robot.ik_batch(targets, tol=1e-7, seed=100, method=method)
    for i, T in enumerate(targets):
        single = robot.ik(T, tol=1e-7, seed=100 + i, method=method)
        assert single.success == batch.success[i]
        np.testing.assert_allclose(batch.q[i], single.q, rtol=0, atol=1e-12)
        assert batch.position_error[i] == pytest.approx(single.position_error, abs=1e-15)
    assert batch.success_rate > 0.95


def test_ik_batch_positions_and_bad_input():
    robot = _load("ur5")
    points = robot.fk(robot.random_q(10, seed=6))[:, :3, 3]
    batch = robot.ik_batch(points)
    assert batch.success.all() and (batch.orientation_error == 0).all()
    with pytest.raises(toolkit.InvalidParameterError, match=r"\(N, 4, 4\)"):
        robot.ik_batch(np.zeros((3, 5)))
    with pytest.raises(toolkit.InvalidParameterError, match="time_limit"):
        robot.ik_batch(points, time_limit=1.0)


_READ_ONLY = """
import numpy as np, toolkit
robot = toolkit.load_example("ur5")
T = robot.fk(robot.random_q(seed=1))
ok = bool(np.isfinite(robot.fk(robot.random_q(9))).all())
print(robot.kinematics.engine.name, robot.ik(T).success, ok)
"""


@pytest.mark.slow
def test_works_when_the_jit_cache_folder_cannot_be_written(tmp_path):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where numba wants its cache folder")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(blocker / "cache")}
    out = subprocess.run(
        [sys.executable, "-c", _READ_ONLY], env=env, capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["compiled", "True", "True"]
