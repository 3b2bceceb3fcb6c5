"""Planning groups and named states from an SRDF (``Robot.group``, ``Robot.states``), and a
MoveIt request's ``group_name``: checked against the whole robot at the same joint values."""

from __future__ import annotations

import pickle
import re

import numpy as np
import pytest

import toolkit
from toolkit.errors import InvalidParameterError, ModelLoadError

PANDA = toolkit.load_example("panda")
ARM = [f"panda_joint{k}" for k in range(1, 8)]


def whole(robot: toolkit.Robot, arm_q: np.ndarray, fingers: float = 0.0) -> np.ndarray:
    """The whole Panda's q for the arm's values and both fingers at ``fingers``."""
    q = PANDA.joints.neutral().copy()
    for name, value in zip(ARM, arm_q, strict=True):
        q[PANDA.model.joints[PANDA.model.getJointId(name)].idx_q] = value
    for name in ("panda_finger_joint1", "panda_finger_joint2"):
        q[PANDA.model.joints[PANDA.model.getJointId(name)].idx_q] = fingers
    return q


def test_the_pandas_arm_group_moves_the_arm_alone_and_answers_as_the_whole_robot():
    arm = PANDA.group("arm")
    assert arm.joints.names == ARM and arm.nq == 7 and arm.tip == PANDA.tip
    Q = arm.random_q(20, seed=4)
    for q in Q:
        np.testing.assert_allclose(arm.fk(q), PANDA.fk(whole(PANDA, q)), atol=1e-12)
        assert arm.in_collision(q) == PANDA.in_collision(whole(PANDA, q))
    opened = PANDA.group("arm", at=whole(PANDA, Q[0], fingers=0.03))
    tip = opened.frames.id("panda_leftfinger")
    np.testing.assert_allclose(
        opened.fk(Q[1], frame="panda_leftfinger"),
        PANDA.fk(whole(PANDA, Q[1], fingers=0.03), frame="panda_leftfinger"),
        atol=1e-12,
    )
    assert tip >= 0
    target = PANDA.fk(whole(PANDA, Q[2]))
    solved = arm.ik(target, seed=1)
    assert solved.success and solved.q.shape == (7,)
    np.testing.assert_allclose(PANDA.fk(whole(PANDA, solved.q)), target, atol=1e-6)


def test_a_group_pickles_and_groups_by_joint_names():
    arm = PANDA.group("arm")
    again = pickle.loads(pickle.dumps(arm))
    q = arm.random_q(seed=2)
    np.testing.assert_array_equal(again.fk(q), arm.fk(q))
    hand = PANDA.group(["panda_finger_joint1"])
    assert hand.joints.names == ["panda_finger_joint1"]
    assert PANDA.group(PANDA.joints.names) is PANDA  # nothing to lock


@pytest.mark.parametrize(
    ("group", "message"),
    [
        ("panda_arm", "no group 'panda_arm' (groups: arm, hand, arm_and_hand)"),
        ("ar", "did you mean arm"),
        (["panda_joint9"], "unknown joints ['panda_joint9']"),
        ([], "unknown joints []"),
    ],
)
def test_an_unknown_group_is_refused_naming_what_there_is(group, message):
    with pytest.raises(InvalidParameterError, match=re.escape(message)):
        PANDA.group(group)


def test_named_states_are_configurations_of_the_robot_asking():
    states = PANDA.states
    assert set(states) == {"default"}
    q = states["default"]
    assert q.shape == (PANDA.nq,) and PANDA.joints.within_limits(q)
    values = PANDA.joints.angles(q)
    names = PANDA.joints.names
    assert values[names.index("panda_joint4")] == pytest.approx(-2.35619)
    assert values[names.index("panda_finger_joint1")] == pytest.approx(0.001)
    arm_state = PANDA.group("arm").states["default"]
    np.testing.assert_allclose(arm_state, values[:7])
    assert toolkit.load("katana_6m180").states == {}


_URDF = """<robot name="toy">
  <link name="base"/><link name="a"/><link name="b"/><link name="c"/><link name="hand"/>
  <link name="finger"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="hand" type="fixed"><parent link="c"/><child link="hand"/>
    <origin xyz="0.1 0 0"/></joint>
  <joint name="slide" type="prismatic"><parent link="hand"/><child link="finger"/>
    <axis xyz="0 1 0"/><limit lower="0.01" upper="0.04" effort="1" velocity="1"/></joint>
</robot>"""

_SRDF = """<robot name="toy">
  <group name="chain"><chain base_link="a" tip_link="c"/></group>
  <group name="links"><link name="hand"/><link name="finger"/></group>
  <group name="both"><group name="chain"/><joint name="j1"/></group>
  <group name="loop"><group name="loop"/></group>
  <group name="missing"><group name="nowhere"/></group>
  <group_state name="up" group="chain"><joint name="j2" value="0.5"/></group_state>
</robot>"""


@pytest.fixture(scope="module")
def toy(tmp_path_factory):
    folder = tmp_path_factory.mktemp("toy")
    (folder / "toy.urdf").write_text(_URDF)
    (folder / "toy.srdf").write_text(_SRDF)
    return toolkit.load_urdf(folder / "toy.urdf", srdf=folder / "toy.srdf", tip="hand")


def test_the_srdfs_elements_are_read_as_moveit_reads_them(toy):
    """A chain: the joints below its base link down to its tip link; a link: the joint
    above it where that joint moves (the fixed ``hand`` joint adds nothing); subgroups
    joined; a group containing itself or a missing group refused; the locked slide at its
    lower limit (its neutral 0 lies outside)."""
    assert toy.group("chain").joints.names == ["j2", "j3"]
    assert toy.group("links").joints.names == ["slide"]
    assert toy.group("both").joints.names == ["j1", "j2", "j3"]
    with pytest.raises(InvalidParameterError, match="contains itself"):
        toy.group("loop")
    with pytest.raises(InvalidParameterError, match="no subgroup 'nowhere'"):
        toy.group("missing")
    arm = toy.group("both")
    q = np.array([0.2, -0.4, 0.9])
    full = np.array([0.2, -0.4, 0.9, 0.01])  # the slide at its lower limit
    np.testing.assert_allclose(arm.fk(q, frame="finger"), toy.fk(full, frame="finger"), atol=1e-12)
    assert toy.group("links").tip == "finger"  # the slide does not move the robot's tip
    assert toy.group("chain").states["up"].tolist() == [0.5, 0.0]


def test_a_link_and_a_joint_of_one_name_are_grouped(toy):
    """Baxter names a fixed joint as a link (``left_hand``), as the toy's ``hand``;
    Pinocchio's reduction refuses a name two frames share: the group is made all the
    same, and the link keeps its name."""
    names = [f.name for f in toy.model.frames]
    assert names.count("hand") == 2  # the fixed joint's frame and the link's
    chain = toy.group("chain")
    q = np.array([0.3, -0.2])
    np.testing.assert_allclose(
        chain.fk(q, frame="hand"), toy.fk(np.array([0.0, 0.3, -0.2, 0.01]), frame="hand"),
        atol=1e-12,
    )  # fmt: skip


def test_a_damaged_srdf_is_refused(tmp_path):
    (tmp_path / "toy.urdf").write_text(_URDF)
    (tmp_path / "toy.srdf").write_text("<robot><group name='x'>")
    robot = toolkit.load_urdf(tmp_path / "toy.urdf", srdf=tmp_path / "toy.srdf")
    with pytest.raises(ModelLoadError, match="not a readable SRDF"):
        robot.group("x")


def test_a_requests_group_plans_the_groups_joints_alone():
    """A MoveIt request naming the SRDF's ``arm``: the path holds the arm's seven joints;
    the fingers stay where the start state puts them (as the whole robot's fk shows)."""
    a = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
    b = np.array([0.8, -0.5, 0.3, -2.0, 0.2, 1.8, 0.4])
    request = toolkit.planning.read_request({
        "group_name": "arm",
        "start_state": {"joint_state": {
            "name": [*ARM, "panda_finger_joint1", "panda_finger_joint2"],
            "position": [*a, 0.02, 0.02]}},
        "goal_constraints": [{"joint_constraints": [
            {"joint_name": n, "position": float(v)} for n, v in zip(ARM, b, strict=True)]}],
    })  # fmt: skip
    robot = request.robot_for(PANDA)
    assert robot.joints.names == ARM
    result = request.plan(PANDA, seed=0)
    assert result.success and result.path.shape[1] == 7
    np.testing.assert_allclose(result.path[0], a)
    np.testing.assert_allclose(
        robot.fk(result.path[-1]), PANDA.fk(whole(PANDA, b, fingers=0.02)), atol=1e-12
    )


def test_an_srdf_is_read_once_while_it_stays_the_same_and_anew_when_it_changes(tmp_path):
    """read_srdf answers a file met again from what it read (the same objects), and reads
    a file that was rewritten afresh: a group added is seen at once."""
    import os

    from toolkit.descriptions.srdf import read_srdf

    path = tmp_path / "arm.srdf"
    path.write_text('<robot name="r"><group name="arm"><joint name="j1"/></group></robot>')
    first = read_srdf(path)
    assert read_srdf(path) is first and list(first[0]) == ["arm"]
    path.write_text('<robot name="r"><group name="arm"><joint name="j1"/></group>'
                    '<group name="hand"><joint name="j2"/></group></robot>')  # fmt: skip
    os.utime(path, ns=(1, 1))  # a change time unlike the first's, even on a coarse clock
    assert list(read_srdf(path)[0]) == ["arm", "hand"]
