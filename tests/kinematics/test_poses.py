"""The tip's pose alone (:mod:`toolkit.kinematics.poses`) equals the frames' kernels to the
last bit, one configuration at a time and vectorized, on every robot here."""

from __future__ import annotations

import numba
import numpy as np
import pytest

import toolkit
from toolkit.descriptions import EXAMPLE_ROBOTS
from toolkit.kinematics import kernels, poses
from toolkit.kinematics.joints import FREE_FLYER

CATALOGUE = [*toolkit.available_models()]
ROBOTS = [*CATALOGUE, *sorted(EXAMPLE_ROBOTS)]


@numba.njit(cache=False)
def _three_ways(Q, ints, flts, tip_pl):
    """(frames + tip, chain_pose, chain_poses (or NaN where the chain is not serial)) of
    each row of Q, as (B, 4, 4) each."""
    B = Q.shape[0]
    W = np.empty((ints.shape[0] + 1, 15))
    H = np.zeros((4, 4))
    ref, one, many = np.zeros((B, 4, 4)), np.zeros((B, 4, 4)), np.full((B, 4, 4), np.nan)
    for b in range(B):
        kernels.frames(Q[b], ints, flts, W)
        kernels.tip(W, tip_pl, ref[b, :3, :3], ref[b, :3, 3])
        ref[b, 3, 3] = 1.0
        poses.chain_pose(Q[b], ints, flts, tip_pl, W, H)
        one[b] = H
    if poses.serial(ints):
        X, S = np.empty((12, B)), np.empty((2, B))
        poses.chain_poses(Q, B, ints, flts, tip_pl, X, S)
        for b in range(B):
            for a in range(3):
                many[b, a, :3] = X[3 * a : 3 * a + 3, b]
                many[b, a, 3] = X[9 + a, b]
            many[b, 3] = (0.0, 0.0, 0.0, 1.0)
    return ref, one, many


def _robot(name: str) -> toolkit.Robot:
    return toolkit.load(name) if name in CATALOGUE else toolkit.load_example(name)


@pytest.mark.parametrize("name", ROBOTS)
def test_the_tip_pose_is_the_frames_to_the_last_bit(name):
    robot = _robot(name)
    Q = robot.random_q(33, seed=7)
    for frame in {robot.tip, list(robot.frames)[-1]}:
        ints, flts, tip_pl = robot.kinematics.chain(robot.frames.id(frame))
        ref, one, many = _three_ways(Q, ints, flts, tip_pl)
        np.testing.assert_array_equal(one, ref)
        serial = bool(poses.serial(ints))
        assert serial == (not (ints[:, 1] == FREE_FLYER).any())  # a path is a serial chain
        if serial:
            np.testing.assert_array_equal(many, ref)
        np.testing.assert_allclose(one, robot.fk(Q, frame), rtol=0, atol=1e-12)


_TILTED = """<robot name="tilted">
  <link name="base"/><link name="a"/><link name="b"/><link name="c"/><link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0.1 0 0.2" rpy="0.3 -0.2 0.5"/><axis xyz="0.3 0.5 0.81"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="prismatic"><parent link="a"/><child link="b"/>
    <origin xyz="0 0.2 0" rpy="0 0.4 0"/><axis xyz="0.6 0 0.8"/>
    <limit lower="-0.5" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j4" type="fixed"><parent link="c"/><child link="tool"/>
    <origin xyz="0 0 0.1" rpy="0.1 0.2 0.3"/></joint>
</robot>"""


def test_tilted_axes_a_slide_and_few_rows():
    """Turns about a tilted axis (Rodrigues' formula), a slide along one, a turn about -y;
    batches of none, one and a few."""
    arm = toolkit.load_urdf(_TILTED, tip="tool")
    ints, flts, tip_pl = arm.kinematics.chain(arm.frames.id(None))
    assert ints[0, 4] < 0 and poses.serial(ints)
    for n in (0, 1, 5, 40):
        Q = arm.random_q(max(n, 1), seed=2).reshape(-1, arm.joints.nq)[:n]
        ref, one, many = _three_ways(Q, ints, flts, tip_pl)
        np.testing.assert_array_equal(one, ref)
        np.testing.assert_array_equal(many, ref)
        np.testing.assert_allclose(one, arm.fk(Q), rtol=0, atol=1e-12)


def test_a_tree_is_not_serial():
    """The whole tree of an arm with two fingers: not serial (chain_pose then goes through
    the frames)."""
    panda = toolkit.load_example("panda")
    ints = panda.kinematics.tree[0]
    assert not poses.serial(ints)
    ints, _, _ = panda.kinematics.chain(panda.frames.id(None))
    assert poses.serial(ints)
