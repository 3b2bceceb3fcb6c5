"""Robot descriptions users have: xacro with ROS packages, URDF text, mimic grippers."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import yourdfpy

import toolkit
from toolkit.cli import main
from toolkit.descriptions import default_tip, example_robot_data_dir

ARM = """<?xml version="1.0"?>
<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="prefix" default=""/>
  <xacro:arg name="length" default="0.3"/>
  <xacro:include filename="$(find my_parts)/urdf/parts.xacro"/>
  <link name="$(arg prefix)base"/>
  <xacro:moving_link name="$(arg prefix)upper"/>
  <joint name="$(arg prefix)j1" type="revolute">
    <parent link="$(arg prefix)base"/><child link="$(arg prefix)upper"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/>
  </joint>
  <link name="$(arg prefix)tip">
    <visual><geometry><mesh filename="package://my_arm/meshes/tip.stl"/></geometry></visual>
  </link>
  <joint name="$(arg prefix)fix" type="fixed">
    <parent link="$(arg prefix)upper"/><child link="$(arg prefix)tip"/>
    <origin xyz="$(arg length) 0 0"/>
  </joint>
  <link name="$(arg prefix)imu"/>
  <joint name="$(arg prefix)imu_mount" type="fixed">
    <parent link="$(arg prefix)base"/><child link="$(arg prefix)imu"/>
  </joint>
</robot>
"""

PARTS = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="moving_link" params="name">
    <link name="${name}"><inertial><mass value="1.0"/><origin xyz="0.1 0 0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  </xacro:macro>
</robot>
"""


def _package(folder: Path, name: str) -> Path:
    folder.mkdir(parents=True)
    (folder / "package.xml").write_text(f"<package><name>{name}</name></package>")
    return folder


@pytest.fixture
def workspace(tmp_path) -> dict[str, Path]:
    arm = _package(tmp_path / "ws" / "src" / "my_arm", "my_arm")
    (arm / "urdf").mkdir()
    (arm / "meshes").mkdir()
    (arm / "urdf" / "arm.urdf.xacro").write_text(ARM)
    parts = _package(tmp_path / "elsewhere" / "my_parts", "my_parts")
    (parts / "urdf").mkdir()
    (parts / "urdf" / "parts.xacro").write_text(PARTS)
    return {"xacro": arm / "urdf" / "arm.urdf.xacro", "arm": arm, "parts": parts}


def _tip_x(robot: toolkit.Robot) -> float:
    return float(robot.fk(np.zeros(robot.nq))[0, 3])


def test_xacro_with_package_dirs_as_folders_and_args(workspace):
    robot = toolkit.load_urdf(workspace["xacro"], package_dirs=[workspace["parts"].parent])
    assert robot.nq == 1 and robot.tip == "tip"  # not the imu bolted to the base
    assert _tip_x(robot) == pytest.approx(0.3)
    text = robot.urdf_path.read_text()
    assert f"{workspace['arm']}/meshes/tip.stl" in text  # package:// made absolute
    left = toolkit.load_urdf(
        workspace["xacro"],
        package_dirs=[workspace["parts"].parent],
        args={"prefix": "left_", "length": 0.5},
    )
    assert left.tip == "left_tip" and left.joints.names == ["left_j1"]
    assert _tip_x(left) == pytest.approx(0.5)


def test_package_dirs_as_a_map_and_ros_package_path(workspace, monkeypatch):
    by_map = toolkit.load_urdf(workspace["xacro"], package_dirs={"my_parts": workspace["parts"]})
    assert by_map.nq == 1
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(workspace["parts"].parent))
    by_env = toolkit.load_urdf(workspace["xacro"])
    assert _tip_x(by_env) == pytest.approx(0.3)


def test_upward_search_finds_a_sibling_package(workspace, tmp_path):
    sibling = workspace["arm"].parent / "my_parts"
    sibling.parent.mkdir(exist_ok=True)
    workspace["parts"].rename(sibling)
    robot = toolkit.load_urdf(workspace["xacro"])  # ws/src/my_parts, found walking up
    assert robot.nq == 1


def test_a_missing_package_is_named_with_the_places_searched(workspace):
    with pytest.raises(toolkit.ModelLoadError, match="package 'my_parts' not found") as err:
        toolkit.load_urdf(workspace["xacro"], package_dirs=[workspace["arm"]])
    assert "upward search" in str(err.value) and "package_dirs" in str(err.value)


def test_urdf_text_and_unknown_tips(workspace):
    text = toolkit.load_urdf(
        workspace["xacro"], package_dirs=[workspace["parts"].parent]
    ).urdf_path.read_text()
    robot = toolkit.load_urdf(text)
    assert robot.urdf_path is not None and robot.urdf_path.is_file()
    assert _tip_x(robot) == pytest.approx(0.3)
    with pytest.raises(toolkit.FrameNotFoundError, match="valid frames: tip, upper"):
        toolkit.load_urdf(text, tip="nope")
    floating = toolkit.load_urdf(text, floating=True)
    assert (
        floating.nq == 8
        and floating.joints.nv == 7
        and floating.kinematics.engine.name == "compiled"
    )


GRIPPER = """<?xml version="1.0"?>
<robot name="gripper">
  <link name="palm"/>
  <link name="left"><inertial><mass value="0.1"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <link name="right"><inertial><mass value="0.1"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <link name="right_tip"/>
  <joint name="left_finger" type="prismatic">
    <parent link="palm"/><child link="left"/><origin xyz="0 0.02 0.1"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/>
  </joint>
  <joint name="right_finger" type="prismatic">
    <parent link="palm"/><child link="right"/><origin xyz="0 -0.02 0.1"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/>
    <mimic joint="left_finger" multiplier="1.0" offset="0.0"/>
  </joint>
  <joint name="right_tip_joint" type="fixed">
    <parent link="right"/><child link="right_tip"/><origin xyz="0 0 0.05"/>
  </joint>
</robot>
"""


def test_mimic_joints_follow_the_file_and_agree_with_yourdfpy(tmp_path):
    path = tmp_path / "gripper.urdf"
    path.write_text(GRIPPER)
    robot = toolkit.load_urdf(path, tip="right_tip")
    assert robot.nq == 1 and robot.joints.names == ["left_finger"]
    other = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)
    for opening in (0.0, 0.013, 0.04):
        other.update_cfg({"left_finger": opening})
        theirs = other.get_transform("right_tip", "palm")
        np.testing.assert_allclose(robot.fk([opening]), theirs, atol=1e-12)
    assert toolkit.load_urdf(path, tip="right_tip", mimic=False).nq == 2


def test_urdfdoms_complaint_is_in_the_error(tmp_path):
    broken = tmp_path / "broken.urdf"
    broken.write_text(
        '<robot name="b"><link name="a"/><joint name="j" type="revolute">'
        '<parent link="a"/><child link="missing"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    with pytest.raises(toolkit.ModelLoadError, match="missing") as err:
        toolkit.load_urdf(broken)
    assert "broken.urdf" in str(err.value)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"args": {"bad name": 1}}, "identifiers"),
        ({"args": {"prefix": object()}}, "number or text"),
        ({"args": "prefix=left_"}, "args must map"),
        ({"package_dirs": 5}, "package_dirs"),
        ({"mimic": "yes"}, "mimic"),
        ({"floating": 1}, "floating"),
    ],
)
def test_bad_loader_options(workspace, kwargs, message):
    with pytest.raises(toolkit.InvalidParameterError, match=message):
        toolkit.load_urdf(workspace["xacro"], **kwargs)


def test_the_cli_takes_a_xacro_file_its_args_and_package_dirs(workspace, capsys):

    parts = str(workspace["parts"].parent)
    argv = ["fk", str(workspace["xacro"]), "0", "--arg", "length=0.4", "--package-dir", parts]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "'tip'" in out and "0.4" in out
    assert main(["fk", str(workspace["xacro"]), "0"]) == 2  # my_parts cannot be found
    assert "package 'my_parts' not found" in capsys.readouterr().err
    # `toolkit urdf FILE` prints the rendered URDF: the argument applied, no xacro left
    assert (
        main(["urdf", str(workspace["xacro"]), "--arg", "prefix=left_", "--package-dir", parts])
        == 0
    )
    rendered = capsys.readouterr().out
    assert '<joint name="left_j1"' in rendered and "xacro:" not in rendered


def test_the_cli_ik_takes_a_mask_and_says_when_orientation_is_free(capsys):

    assert main(["ik", "katana_6m180", "0.3", "0.1", "0.4"]) == 0
    assert "orientation free" in capsys.readouterr().out
    import pinocchio as pin

    T = toolkit.load("katana_6m180").fk([0.2, 0.6, 0.4, -1.0, 0.3])
    rpy = np.degrees(pin.rpy.matrixToRpy(T[:3, :3]))
    argv = ["ik", "katana_6m180", *(f"{v:.9f}" for v in T[:3, 3]), "--rpy"]
    argv += [*(f"{v:.9f}" for v in rpy), "--deg"]
    assert main([*argv, "--mask", "1", "1", "1", "1", "1", "0"]) == 0
    out = capsys.readouterr().out
    assert "orientation error" in out and "NOT solved" not in out


def test_every_example_robot_by_name():
    """Every description example-robot-data ships loads by name (or says why it cannot),
    with a tip that moves when the joints do."""
    from toolkit.descriptions import example_robots

    names = example_robots()
    assert len(names) >= 60 and {"ur5", "panda", "talos_full_v2", "solo12", "go2"} <= set(names)
    loaded = 0
    for name in names:
        try:
            robot = toolkit.load_example(name)
        except toolkit.ToolkitError as exc:
            assert str(exc), name  # a refusal with a message, never a raw exception
            continue
        loaded += 1
        if robot.joints.nv == 0:
            continue
        poses = robot.fk(robot.random_q(3, seed=1))
        assert np.isfinite(poses).all(), name
        frame = robot.model.frames[robot.frames.id(None)]
        assert frame.parentJoint > 0, f"{name}: the tip {robot.tip!r} is fixed to the base"
    assert loaded >= 60
    legged = toolkit.load_example("solo12", floating=True)
    assert legged.nq == 7 + 12 and legged.kinematics.engine.name == "compiled"
    with pytest.raises(toolkit.UnknownModelError, match="valid names"):
        toolkit.load_example("r2d2")


def test_the_cli_lets_joints_that_do_not_move_the_frame_be_left_out(capsys):
    """Panda's fingers do not move the hand frame: seven values are enough."""

    arm = [0.1, -0.4, 0.2, -1.9, 0.3, 1.6, 0.5]
    assert main(["fk", "panda", *map(str, arm)]) == 0
    seven = capsys.readouterr().out
    assert main(["fk", "panda", *map(str, arm), "0.02", "0.03"]) == 0
    nine = capsys.readouterr().out
    assert seven == nine
    robot = toolkit.load_example("panda")
    expected = robot.fk(robot.joints.q_from_angles([*arm, 0.0, 0.0]))
    printed = np.array(
        [[float(x) for x in row.strip(" []").split()] for row in seven.splitlines()[1:]]
    )
    np.testing.assert_allclose(printed, expected, atol=1e-6)
    assert main(["fk", "panda", "0", "0"]) == 2
    assert "the 7 that move frame 'panda_hand_tcp'" in capsys.readouterr().err


def _shared_folder(tmp_path: Path) -> Path:
    """A folder like /tmp: anyone may create entries in it (mode 1777)."""
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o1777)
    return shared


def test_a_package_planted_in_a_shared_folder_is_never_used(tmp_path):
    """The audit's attack: a victim's xacro under /tmp needs package my_parts; another
    user created /tmp/my_parts. xacro would run its ${...} expressions as the victim."""
    shared = _shared_folder(tmp_path)
    victim = shared / "victim"
    victim.mkdir(mode=0o755)
    (victim / "arm.urdf.xacro").write_text(ARM)
    planted = _package(shared / "my_parts", "my_parts")
    (planted / "urdf").mkdir()
    marker = '<visual><geometry><box size="9 9 9"/></geometry></visual><inertial>'
    (planted / "urdf" / "parts.xacro").write_text(PARTS.replace("<inertial>", marker))
    with pytest.raises(toolkit.ModelLoadError, match="package 'my_parts' not found") as err:
        toolkit.load_urdf(victim / "arm.urdf.xacro")
    message = str(err.value)
    assert f"stopped at {shared}: writable by others" in message
    assert "package_dirs={'my_parts': '/path/to/my_parts'}" in message
    # the user can still name it on purpose
    robot = toolkit.load_urdf(victim / "arm.urdf.xacro", package_dirs={"my_parts": planted})
    assert 'size="9 9 9"' in robot.urdf_path.read_text()


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="needs chown")
def test_a_package_folder_of_another_user_is_skipped_and_said(workspace):
    sibling = workspace["arm"].parent / "my_parts"
    workspace["parts"].rename(sibling)
    os.chown(sibling, 65534, 65534)  # "nobody" owns it now
    with pytest.raises(toolkit.ModelLoadError, match="owned by another user") as err:
        toolkit.load_urdf(workspace["xacro"])
    assert "Skipped as another user could have planted them" in str(err.value)
    os.chown(sibling, os.getuid(), os.getgid())
    assert toolkit.load_urdf(workspace["xacro"]).nq == 1


def test_a_sibling_folder_named_like_the_package_needs_no_package_xml(workspace):
    """docs/descriptions.md: a folder named like the package is found walking up."""
    sibling = workspace["arm"].parent / "my_parts"
    workspace["parts"].rename(sibling)
    (sibling / "package.xml").unlink()
    assert toolkit.load_urdf(workspace["xacro"]).nq == 1


def test_the_upward_search_never_climbs_past_the_home_folder(workspace, monkeypatch):
    home = workspace["arm"].parent  # ws/src is "home": ws/ and above are not searched
    monkeypatch.setenv("HOME", str(home))
    above = _package(home.parent / "my_parts", "my_parts")  # ws/my_parts: above home
    (above / "urdf").mkdir()
    (above / "urdf" / "parts.xacro").write_text(PARTS)
    with pytest.raises(toolkit.ModelLoadError, match="your home folder"):
        toolkit.load_urdf(workspace["xacro"])
    monkeypatch.setenv("HOME", str(home.parent))
    assert toolkit.load_urdf(workspace["xacro"]).nq == 1


STL_CUBE = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
            (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]  # fmt: skip


def _cube_stl(path, edge=0.1):
    """An ASCII STL of a cube of ``edge`` [m] centred on the origin."""
    v = (np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)]) - 0.5) * edge
    lines = ["solid cube"]
    for a, b, c in STL_CUBE:
        n = np.cross(v[b] - v[a], v[c] - v[a])
        lines += [f"facet normal {n[0]} {n[1]} {n[2]}", " outer loop"]
        lines += [f"  vertex {v[i][0]} {v[i][1]} {v[i][2]}" for i in (a, b, c)]
        lines += [" endloop", "endfacet"]
    path.write_text("\n".join([*lines, "endsolid cube"]) + "\n")


def test_mesh_paths_relative_to_the_description_resolve_from_its_folder(tmp_path, monkeypatch):
    """``<mesh filename="meshes/part.stl"/>`` is read from the URDF's own folder (as ROS
    tools, yourdfpy and Pinocchio given the folder do), whatever the working folder: the
    collision shapes load and collide where the cube is."""
    from toolkit.collision import Scene

    folder = tmp_path / "arm"
    (folder / "meshes").mkdir(parents=True)
    _cube_stl(folder / "meshes" / "part.stl")
    inertial = ('<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
                'ixy="0" ixz="0" iyz="0"/></inertial>')  # fmt: skip
    (folder / "arm.urdf").write_text(
        f'<robot name="relarm"><link name="base">{inertial}</link><link name="l1">'
        '<collision><origin xyz="0 0 0.3"/><geometry><mesh filename="meshes/part.stl"/>'
        f"</geometry></collision>{inertial}</link>"
        '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
        '<axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        "</robot>"
    )
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    robot = toolkit.load_urdf(folder / "arm.urdf")
    box = np.eye(4)
    box[:3, 3] = [0.04, 0.0, 0.3]  # overlaps the cube at q = 0, not once turned by 1.5 rad
    scene = Scene().add_box("box", [0.1, 0.1, 0.1], box)
    assert robot.in_collision([0.0], scene)
    assert not robot.in_collision([1.5], scene)


def test_only_relative_mesh_paths_are_rewritten(tmp_path):
    from toolkit.descriptions.files import relative_meshes

    text = ('<mesh filename="a/b.stl"/><mesh scale="1 1 1" filename=\'c.dae\'/>'
            '<mesh filename="package://pkg/m.stl"/><mesh filename="file:///x/y.stl"/>'
            '<mesh filename="/abs/z.stl"/>')  # fmt: skip
    out = relative_meshes(text, tmp_path)
    assert f'filename="{tmp_path / "a" / "b.stl"}"' in out
    assert f"filename='{tmp_path / 'c.dae'}'" in out
    for kept in ("package://pkg/m.stl", "file:///x/y.stl", '"/abs/z.stl"'):
        assert kept in out


ONE_JOINT = """
<?xml version="1.0" encoding="{encoding}"?>
<robot name="{name}">
  <link name="base"/>
  <link name="tip"><inertial><mass value="1"/>
    <inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="tip"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


def test_the_viewer_reads_what_the_kinematic_loader_reads(tmp_path):
    """pybullet's diff_ring.urdf: a blank line before ``<?xml ...?>`` crashed the viewer's
    visual loader with a raw ParseError while fk accepted the file."""
    path = tmp_path / "blank_first_line.urdf"
    path.write_text(ONE_JOINT.format(encoding="UTF-8", name="blank"))
    robot = toolkit.load_urdf(path)
    from toolkit.viz import visual_model

    assert visual_model(robot).geometry.ngeoms >= 1


def test_an_iso_8859_1_description_loads(tmp_path):
    path = tmp_path / "latin.urdf"
    text = ONE_JOINT.format(encoding="ISO-8859-1", name="bras_articulé")
    path.write_bytes(text.encode("latin-1"))
    robot = toolkit.load_urdf(path)
    assert robot.nq == 1
    np.testing.assert_allclose(robot.fk([0.0])[:3, 3], [0.3, 0, 0])


def test_a_robot_from_urdf_text_is_named_by_its_robot_tag():
    robot = toolkit.load_urdf(ONE_JOINT.format(encoding="UTF-8", name="my_arm").strip())
    assert robot.name == "my_arm"


def test_package_dirs_values_must_be_folders():
    with pytest.raises(toolkit.InvalidParameterError, match="package name: folder"):
        toolkit.load_urdf(ONE_JOINT.format(encoding="UTF-8", name="x"), package_dirs={"p": None})


def test_the_default_tip_is_the_end_of_the_arm_not_a_finger():
    """The Panda file (mimic fingers): its hand's tool point; a gripper without a named
    tool frame: the last frame before the fingers branch."""
    panda = toolkit.load_urdf(example_robot_data_dir() / "panda_description/urdf/panda.urdf")
    assert panda.tip == "panda_hand_tcp"
    import pinocchio as pin

    model = pin.buildModelFromUrdf(
        str(example_robot_data_dir() / "panda_description/urdf/panda.urdf")
    )
    for frame in ("panda_hand_tcp",):  # without a named tool point: the hand
        model.frames[model.getFrameId(frame)].name = "renamed_point"
    assert default_tip(model) in ("panda_hand", "renamed_point")
    assert "finger" not in default_tip(model)


def test_the_missing_mesh_warning_points_at_the_callers_line(tmp_path):
    from toolkit.viz import MissingMeshWarning, visual_model

    path = tmp_path / "missing_mesh.urdf"
    path.write_text(
        ONE_JOINT.format(encoding="UTF-8", name="m").replace(
            '<box size="0.1 0.1 0.1"/>', '<mesh filename="nowhere.stl"/>'
        )
    )
    robot = toolkit.load_urdf(path)
    with pytest.warns(MissingMeshWarning) as caught:
        visual_model(robot)
    assert caught[0].filename == __file__  # this test's line, never the toolkit's source
