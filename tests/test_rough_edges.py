"""The audit's rough edges, one reproduction each (issue: what a new user still hit)."""

from __future__ import annotations

import numpy as np
import pytest

import toolkit
from toolkit import backlash, bending, maps
from toolkit.cli import main
from toolkit.descriptions import default_tip, example_robot_data_dir

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


def test_the_cli_takes_a_tip(capsys):
    assert main(["fk", "panda", *["0"] * 4, "--tip", "panda_link4"]) == 0
    out = capsys.readouterr().out
    T = toolkit.load_example("panda").fk(np.zeros(9), "panda_link4")
    assert f"{T[0, 3]:.4f}" in out
    assert main(["fk", "panda", *["0"] * 4, "--tip", "nope"]) == 2
    assert "valid frames" in capsys.readouterr().err


def test_toolkit_list_names_commands_that_exist(capsys):
    main(["list"])
    out = capsys.readouterr().out
    assert "toolkit load NAME" not in out and "toolkit.load(NAME)" in out


def test_map_backlash_compensate_prints_the_compensated_figures(capsys):
    argv = ["map", "backlash", "katana_6m180", "--voxel", "0.2", "--position-only"]
    assert main([*argv, "--orientations", "2", "--payload", "0.5", "--compensate", "-q"]) == 0
    assert "after compensation" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--orientations", "0"], "orientations"),
        (["--png", "/no/such/folder/x.png"], "--png"),
        (["--scheduler", "tcp://127.0.0.1:9"], "no Dask scheduler answers"),
    ],
)
def test_bad_map_options_fail_before_any_work(argv, message, capsys):
    assert main(["map", "reach", "ur5", "--voxel", "0.3", "-q", *argv]) == 2
    assert message in capsys.readouterr().err


def test_an_empty_store_path_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(toolkit.MapStoreError, match="empty path"):
        maps.reachability(toolkit.load_example("ur5"), voxel=0.4, orientations=2, store="")
    assert not list(tmp_path.iterdir()), "the working folder was made a store"


def test_eq17_with_torques_and_nominal_torques_of_other_lengths():
    with pytest.raises(toolkit.InvalidParameterError, match="number of joints"):
        backlash.offset(np.ones(5), np.ones(3))


def test_a_bending_angle_beyond_pi_is_refused():
    with pytest.raises(toolkit.GeometryError, match="alpha"):
        bending.link_pose(1e300, 0.0, 3, 0.02, 0.008)
    with pytest.raises(toolkit.GeometryError, match="psi"):
        bending.link_pose(0.1, 1e300, 3, 0.02, 0.008)


def _chain_text(n: int) -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(n + 1))
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(n)
    )
    return f'<robot name="long">{links}{joints}</robot>'


def test_a_description_beyond_the_link_limit_is_refused_before_parsing(tmp_path):
    """4,000 links crashed the process (SIGSEGV) inside Pinocchio's recursive parser."""
    from toolkit.descriptions import MAX_LINKS

    path = tmp_path / "long.urdf"
    path.write_text(_chain_text(4000))
    with pytest.raises(toolkit.ModelLoadError, match=f"more than the {MAX_LINKS:,}"):
        toolkit.load_urdf(path)
    assert toolkit.load_urdf(_chain_text(50)).nq == 50


def test_a_description_beyond_the_size_limit_is_refused(tmp_path, monkeypatch):
    from toolkit.descriptions import files as descriptions

    monkeypatch.setattr(descriptions, "MAX_FILE_BYTES", 2000)
    path = tmp_path / "big.urdf"
    path.write_text(_chain_text(30))
    with pytest.raises(toolkit.ModelLoadError, match="bytes, more than"):
        toolkit.load_urdf(path)


BOMB = """<?xml version="1.0"?>
<robot name="bomb" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="b" params="n">
    <xacro:if value="${n > 0}">
      <xacro:b n="${n - 1}"/><xacro:b n="${n - 1}"/>
    </xacro:if>
  </xacro:macro>
  <link name="base"/>
  <xacro:b n="40"/>
</robot>
"""


def test_a_xacro_macro_bomb_stops_and_frees_the_lock(tmp_path, monkeypatch):
    """2^40 expansions hung while holding the xacro lock; the budget stops it, and the next
    render (another thread's, a catalogue model) goes on."""
    from toolkit.descriptions import render

    monkeypatch.setattr(render, "XACRO_SECONDS", 1.0)
    path = tmp_path / "bomb.urdf.xacro"
    path.write_text(BOMB)
    with pytest.raises(toolkit.RenderError, match=r"expansion of .* stopped"):
        toolkit.load_urdf(path)
    assert toolkit.load("scara").nq == 3
    assert len(toolkit.urdf_text("cartesian", a=0.7)) > 100


def test_the_report_console_shows_whole_first_sentences():
    from toolkit.report.benchmark import benchmark_section
    from toolkit.report.render import SECTIONS, _first_sentence

    assert _first_sentence(benchmark_section.__doc__).endswith("has run.")
    for make in SECTIONS:
        title = _first_sentence(make.__doc__)
        assert title.endswith("."), title


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


def test_the_viewer_says_its_url_once(capsys):
    pytest.importorskip("meshcat")
    from toolkit.viz import Viewer

    with Viewer(toolkit.load("scara")) as viewer:
        printed = capsys.readouterr().out
        assert viewer.url not in printed and "You can open the visualizer" not in printed
