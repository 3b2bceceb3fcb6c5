"""The Robot object: Jacobians, cross-checks with yourdfpy, example robots, bad input."""

from __future__ import annotations

import numpy as np
import pytest
import yourdfpy
from helpers import fd_jacobian

import toolkit
from toolkit.descriptions import committed_urdf_path

KATANAS = ["katana_6m180", "katana_6m90a", "katana_6m90b"]
EXAMPLES = ["ur5", "panda", "so101", "z1"]


@pytest.mark.parametrize("name", KATANAS)
def test_committed_urdf_pinocchio_agrees_with_yourdfpy(name, rng):
    path = committed_urdf_path(name)
    robot = toolkit.load_urdf(path, tip="tool")
    urdf = yourdfpy.URDF.load(str(path), load_meshes=False, build_scene_graph=True)
    assert list(urdf.actuated_joint_names) == robot.joints.names
    for q in robot.random_q(300, rng):
        urdf.update_cfg(q)
        for frame in ("tool", "link3"):
            np.testing.assert_allclose(
                robot.fk(q, frame), urdf.get_transform(frame, "base_link"), atol=1e-12
            )


@pytest.mark.parametrize("name", KATANAS)
def test_catalogue_load_equals_committed_urdf(name, rng):
    robot, committed = toolkit.load(name), toolkit.load_urdf(committed_urdf_path(name), tip="tool")
    qs = robot.random_q(50, rng)
    np.testing.assert_array_equal(robot.fk(qs), committed.fk(qs))


@pytest.mark.parametrize("name", KATANAS + EXAMPLES)
def test_jacobian_equals_finite_differences(name, rng):
    robot = toolkit.load(name) if name in KATANAS else toolkit.load_example(name)
    for q in robot.random_q(20, rng):
        J = robot.jacobian(q)
        assert J.shape == (6, robot.joints.nv)
        np.testing.assert_allclose(J, fd_jacobian(robot.fk, q), atol=1e-7)


def test_jacobian_of_other_frame(rng):
    robot = toolkit.load("katana_6m90b")
    q = robot.random_q(seed=rng)
    np.testing.assert_allclose(
        robot.jacobian(q, "link4"), fd_jacobian(lambda x: robot.fk(x, "link4"), q), atol=1e-7
    )
    # joints after link 4 do not move it
    assert np.abs(robot.jacobian(q, "link4")[:, 4:]).max() == 0.0


@pytest.mark.parametrize("name", EXAMPLES)
def test_example_robots_load_from_disk_and_match_yourdfpy(name, rng):
    robot = toolkit.load_example(name)
    assert robot.urdf_path is not None and robot.urdf_path.is_file()
    urdf = yourdfpy.URDF.load(
        str(robot.urdf_path),
        load_meshes=False,
        build_scene_graph=True,
        build_collision_scene_graph=False,
        load_collision_meshes=False,
    )
    root = urdf.base_link
    for q in robot.random_q(20, rng):
        urdf.update_cfg(dict(zip(robot.joints.names, q, strict=True)))
        np.testing.assert_allclose(robot.fk(q), urdf.get_transform(robot.tip, root), atol=1e-10)


def test_unknown_example_lists_valid_names():
    with pytest.raises(toolkit.UnknownModelError, match="ur5") as err:
        toolkit.load_example("ur55")
    assert "panda" in str(err.value) and "so101" in str(err.value)


@pytest.mark.parametrize(("name", "example"), [("panda", "panda"), ("ur5e", "ur5")])
def test_an_example_robots_name_given_to_load_names_the_other_door(name, example):
    """``load`` is the catalogue's; a name at or near an example robot's says
    ``load_example`` loads that one; a name near neither lists the catalogue."""
    with pytest.raises(toolkit.UnknownModelError) as err:
        toolkit.load(name)
    assert f"toolkit.load_example({example!r})" in str(err.value)
    with pytest.raises(toolkit.UnknownModelError, match="did you mean 'katana_6m90b'"):
        toolkit.load("katana")


def test_batch_fk_equals_single(rng):
    robot = toolkit.load("katana_6m90a")
    qs = robot.random_q(10, rng)
    batch = robot.fk(qs)
    assert batch.shape == (10, 4, 4)
    for q, T in zip(qs, batch, strict=True):  # batches run on the compiled engine
        np.testing.assert_allclose(robot.fk(q), T, rtol=0, atol=1e-12)


def test_random_q_within_limits_and_seeded():
    robot = toolkit.load("katana_6m180")
    qs = robot.random_q(500, seed=3)
    assert robot.joints.within_limits(qs)
    np.testing.assert_array_equal(qs, robot.random_q(500, seed=3))
    assert not robot.joints.within_limits(robot.joints.upper + 0.01)


def test_unchecked_limits_test_answers_as_the_checked_one():
    """``raw_within_limits`` (the plan door's, on a q it has checked) is ``within_limits``
    without the checks: the same answer at the limits, a tolerance inside and outside."""
    joints = toolkit.load("katana_6m180").joints
    for q in (joints.lower, joints.upper, joints.lower - 1e-13, joints.upper + 2e-12,
              joints.lower - 0.01, (joints.lower + joints.upper) / 2):  # fmt: skip
        for tol in (0.0, 1e-12, 0.02):
            assert joints.raw_within_limits(q, tol) == joints.within_limits(q, tol)
    assert not joints.raw_within_limits(joints.upper + 2e-12)
    assert joints.raw_within_limits(joints.upper + 5e-13)


def test_limits_are_read_only():
    robot = toolkit.load("katana_6m180")
    with pytest.raises(ValueError):
        robot.joints.lower[0] = 0.0


@pytest.mark.parametrize(
    ("q", "message"),
    [
        ([0, 0, 0], r"shape \(5,\)"),
        (np.zeros((2, 2, 5)), "shape"),
        ([0, 0, float("nan"), 0, 0], r"NaN or infinite entries at index \[2\]"),
        ([0, float("inf"), 0, 0, 0], "NaN or infinite"),
        (["a", 0, 0, 0, 0], "numeric"),
    ],
)
def test_bad_configurations_raise(q, message):
    robot = toolkit.load("katana_6m180")
    with pytest.raises(toolkit.ConfigurationError, match=message):
        robot.fk(q)
    with pytest.raises(toolkit.ConfigurationError):
        robot.jacobian(q)


def test_wrong_length_message_names_joints():
    robot = toolkit.load("katana_6m180")
    with pytest.raises(toolkit.ConfigurationError, match="joint1"):
        robot.fk(np.zeros(6))


def test_unknown_frame_lists_valid_frames():
    robot = toolkit.load("katana_6m180")
    with pytest.raises(toolkit.FrameNotFoundError, match="unknown frame 'tol'") as err:
        robot.fk(np.zeros(5), "tol")
    assert "tool" in err.value.valid and "link3" in str(err.value)
    with pytest.raises(toolkit.FrameNotFoundError):
        robot.jacobian(np.zeros(5), "nope")


def test_errors_are_also_builtin_kinds():
    robot = toolkit.load("katana_6m180")
    with pytest.raises(ValueError):
        robot.fk([1.0])
    with pytest.raises(LookupError):
        toolkit.load("no_such_model")


def test_load_urdf_missing_file(tmp_path):
    with pytest.raises(toolkit.ToolkitError, match="not found"):
        toolkit.load_urdf(tmp_path / "missing.urdf")


def test_load_urdf_unparsable(tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'/><joint name='j' type='revolute'>")
    with pytest.raises(toolkit.ToolkitError):
        toolkit.load_urdf(bad)


def test_a_robot_keeps_its_caches_itself_and_never_grows_new_attributes():
    """Every cache is made with the robot (per robot, with its own lock): queries add no
    attribute to it, and two robots (or a robot and its unpickled copy) share nothing."""
    import pickle

    a, b = toolkit.load_example("ur5"), toolkit.load_example("ur5")
    before = set(vars(a))
    T = a.fk(a.random_q(seed=1))
    a.ik_all(T)
    a.ik_all_batch(T[None])
    a.in_collision(a.joints.neutral())
    assert set(vars(a)) == before
    assert a._caches is not b._caches and a._caches.lock is not b._caches.lock
    assert a._analytic.caches.doors and not b._analytic.caches.doors
    copy = pickle.loads(pickle.dumps(a))
    assert copy._caches is not a._caches and not copy._analytic.caches.doors


def test_motion_rank_counts_the_directions_the_joints_move_the_tool():
    assert toolkit.load_example("ur5").frames.rank() == 6
    assert toolkit.load_example("panda").frames.rank() == 6  # 7 joints, 6 directions
    assert toolkit.load("katana_6m180").frames.rank() == 5
    assert toolkit.load("scara").frames.rank() == 3
    assert toolkit.load("katana_6m180").frames.rank("base_link") == 0


def test_frames_read_as_a_mapping_of_names_to_indices():
    ur5 = toolkit.load_example("ur5")
    frames = ur5.frames
    names = [f.name for f in ur5.model.frames]
    assert list(frames) == list(dict.fromkeys(names)) and len(frames) == len(set(names))
    for name in ("tool0", "base_link", "wrist_3_joint"):
        assert name in frames and ur5.model.frames[frames[name]].name == name
    assert frames.id(None) == frames[ur5.tip] and frames.tip == ur5.tip
    assert "nope" not in frames and 3 not in frames and frames.get("nope") is None
    with pytest.raises(toolkit.FrameNotFoundError, match=r"'nope'.*valid frames"):
        frames["nope"]
    with pytest.raises(toolkit.FrameNotFoundError):
        frames.id("nope")
    with pytest.raises(toolkit.FrameNotFoundError):
        toolkit.Robot(ur5.model, tip="nope")


def test_the_joint_space_checks_what_it_is_given():
    kinova = toolkit.load_example("kinova")  # continuous joints: nq 9, nv 6 (... per joint)
    joints = kinova.joints
    assert (joints.nq, joints.nv) == (kinova.model.nq, kinova.model.nv)
    assert joints.names == [kinova.model.names[j] for j in range(1, kinova.model.njoints)]
    values = np.linspace(-1.0, 1.0, joints.nv)
    q = joints.q_from_angles(values)
    np.testing.assert_allclose(joints.angles(q), values, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(joints.check(q), q)
    with pytest.raises(toolkit.ConfigurationError, match=r"shape .*take two numbers"):
        joints.check(values)
    with pytest.raises(toolkit.ConfigurationError, match="NaN"):
        joints.angles(np.full(joints.nq, np.nan))
    with pytest.raises(toolkit.ConfigurationError, match="qd must have shape"):
        joints.check_v(np.zeros(joints.nv + 1), "qd")
    inside = kinova.random_q(seed=1)
    assert joints.within_limits(inside)
    limited = np.flatnonzero(joints.scalar_q & np.isfinite(joints.upper))[0]  # not a (cos, sin)
    inside[limited] = joints.upper[limited] + 0.01
    assert not joints.within_limits(inside)
    import pinocchio

    np.testing.assert_array_equal(joints.neutral(), pinocchio.neutral(kinova.model))


def test_an_unknown_name_gets_the_closest_matches():
    with pytest.raises(toolkit.UnknownModelError, match=r"did you mean 'katana_6m180'"):
        toolkit.load("katana6m180")
    with pytest.raises(toolkit.UnknownModelError, match=r"did you mean 'panda'\?"):
        toolkit.load_example("pnada")
    with pytest.raises(toolkit.FrameNotFoundError, match=r"did you mean 'tool'"):
        toolkit.load("katana_6m180").fk([0, 0, 0, 0, 0], "tol")
    with pytest.raises(toolkit.UnknownModelError) as nothing_close:
        toolkit.load("zzzzzz")
    assert "did you mean" not in str(nothing_close.value)
