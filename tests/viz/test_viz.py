"""The meshcat viewer, checked in a real headless Chromium (the screenshot is kept)."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import warnings
from pathlib import Path
from urllib.parse import urlparse

import numpy as np
import pytest

import toolkit
from toolkit import backlash, maps
from toolkit.cli import main
from toolkit.errors import ToolkitError
from toolkit.viz import viewer as viz_module

ARTIFACTS = Path(
    os.environ.get("TOOLKIT_ARTIFACT_DIR", Path(__file__).resolve().parents[1] / "artifacts")
)
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
# CI sets TOOLKIT_REQUIRE_BROWSER=1 so that a missing browser fails instead of skipping
REQUIRE = os.environ.get("TOOLKIT_REQUIRE_BROWSER") == "1"

needs_meshcat = pytest.mark.skipif(
    not viz_module.meshcat_available() and not REQUIRE, reason="meshcat not installed"
)


def _screenshot(
    url: str, out: Path, size: tuple[int, int] = (800, 600), budget_ms: int = 8000
) -> np.ndarray:
    import matplotlib.image

    if CHROMIUM is None:
        if REQUIRE:
            pytest.fail("chromium is required (TOOLKIT_REQUIRE_BROWSER=1) but not installed")
        pytest.skip("chromium not installed")
    out.parent.mkdir(parents=True, exist_ok=True)
    profile = out.parent / f"chromium-profile-{out.stem}"
    cmd = [
        CHROMIUM,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={profile}",
        f"--window-size={size[0]},{size[1]}",
        f"--virtual-time-budget={budget_ms}",
        f"--screenshot={out}",
        url,
    ]
    subprocess.run(cmd, capture_output=True, timeout=120, check=False)
    shutil.rmtree(profile, ignore_errors=True)
    assert out.is_file(), "chromium wrote no screenshot"
    return matplotlib.image.imread(str(out))[..., :3]


def _robot_pixels(image: np.ndarray) -> int:
    """Pixels of the robot's orange (toolkit_orange, 1.0 0.55 0.0) under any shading."""
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return int(np.sum((r > 0.45) & (b < 0.35) & (g > 0.35 * r) & (g < 0.75 * r)))


def _listening_addresses(port: int) -> set[str]:
    """Local addresses of LISTEN sockets on ``port`` (from /proc/net/tcp)."""
    found = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            fields = line.split()
            addr, hexport = fields[1].split(":")
            if int(hexport, 16) == port and fields[3] == "0A":
                found.add(addr)
    return found


@pytest.mark.slow
@needs_meshcat
def test_viewer_draws_the_robot_in_headless_chromium():
    robot = toolkit.load("katana_6m180")
    with viz_module.Viewer(robot) as viewer:
        url = urlparse(viewer.url)
        assert url.hostname == "127.0.0.1"
        # the web server listens on the loopback interface only
        assert _listening_addresses(url.port) == {"0100007F"}
        viewer.show([0.3, 0.5, 0.4, -1.0, 0.2])
        viewer.marker([0.3, 0.1, 0.4])
        viewer.path(np.array([[0, 0, 0.5], [0.2, 0.1, 0.5], [0.3, 0.2, 0.3]]))
        shown = _screenshot(viewer.url, ARTIFACTS / "viewer_katana_6m180.png")
        assert _robot_pixels(shown) > 1000, "no robot-coloured pixels in the canvas"
        # the backlash view adds a translucent ghost of the commanded pose
        layer = backlash.Backlash(robot, payload=0.5)
        viewer.show_backlash(layer, [0.0, 1.2, 0.0, -1.2, 0.0])
        ghosted = _screenshot(viewer.url, ARTIFACTS / "viewer_backlash_ghost.png")
        assert np.abs(ghosted - shown).max() > 0.2
        # the same check on a scene without the robot finds none: it can fail
        viewer.meshcat["robot"].set_property("visible", False)
        viewer.meshcat["commanded"].set_property("visible", False)
        hidden = _screenshot(viewer.url, ARTIFACTS / "viewer_hidden.png")
        assert _robot_pixels(hidden) < _robot_pixels(shown) / 10  # the orange end of the x axis


@needs_meshcat
def test_viewer_bad_input():
    robot = toolkit.load("scara")
    with viz_module.Viewer(robot) as viewer:
        with pytest.raises(ToolkitError, match="path points"):
            viewer.path([[0, 0, 0]])
        with pytest.raises(ToolkitError, match="color"):
            viewer.marker([0, 0, 0], color=(2, 0, 0))
        with pytest.raises(toolkit.ConfigurationError):
            viewer.show([0.0, 0.0])
        viewer.animate(np.zeros((3, 3)), dt=0.0)
        viewer.ghost([0.1, 0.2, -0.1])
        viewer.clear()


def test_viewer_without_meshcat_says_how_to_install(monkeypatch):
    monkeypatch.setattr(viz_module, "meshcat_available", lambda: False)
    with pytest.raises(viz_module.ViewerUnavailable, match="pip install"):
        viz_module.Viewer(toolkit.load("scara"))


@pytest.mark.slow
@needs_meshcat
def test_cli_view_prints_a_loopback_url():
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "toolkit.cli",
            "view",
            "cartesian",
            "--q",
            "0.1",
            "0.2",
            "-0.1",
            "--seconds",
            "0.5",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    line = next(x for x in proc.stdout.splitlines() if x.startswith("viewer: "))
    assert urlparse(line.split()[1]).hostname == "127.0.0.1"
    with socket.socket() as s:  # the server is gone after the command ends
        port = urlparse(line.split()[1]).port
        assert s.connect_ex(("127.0.0.1", port)) != 0


_HOLDER = """
import time, toolkit
from toolkit.viz import Viewer
viewer = Viewer(toolkit.load("scara"))
print("HOLDER", viewer.url, viewer._proc.pid, flush=True)
time.sleep(120)
"""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie waiting for its (dead) parent's reaper counts as gone
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


def _port_open(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(0.5)
        return s.connect_ex(("127.0.0.1", port)) == 0


@pytest.mark.slow
@needs_meshcat
@pytest.mark.parametrize("signal_name", ["SIGTERM", "SIGKILL"])
def test_the_server_dies_with_its_parent(signal_name):
    import signal
    import time

    holder = subprocess.Popen([sys.executable, "-c", _HOLDER], stdout=subprocess.PIPE, text=True)
    try:
        line = ""
        while not line.startswith("HOLDER"):
            line = holder.stdout.readline()
            assert line, "the holder process ended early"
        _, url, server = line.split()
        port, server_pid = urlparse(url).port, int(server)
        assert _alive(server_pid) and _port_open(port)
        holder.send_signal(getattr(signal, signal_name))
        holder.wait(timeout=10)
        deadline = time.monotonic() + 10  # about 0.5 s unloaded; margin for a busy machine
        while time.monotonic() < deadline and (_alive(server_pid) or _port_open(port)):
            time.sleep(0.1)
        assert not _alive(server_pid), "the meshcat server outlived its parent"
        assert not _port_open(port), "the viewer's port is still taken"
    finally:
        holder.kill()


@needs_meshcat
def test_an_unanswered_server_url_fails_fast():
    import time

    start = time.monotonic()
    with pytest.raises(viz_module.ViewerUnavailable, match="no meshcat server answers"):
        viz_module.Viewer(toolkit.load("scara"), zmq_url="tcp://127.0.0.1:1", timeout=1.0)
    assert time.monotonic() - start < 10
    with pytest.raises(toolkit.InvalidParameterError, match="tcp://HOST:PORT"):
        viz_module.Viewer(toolkit.load("scara"), zmq_url="http://x")


def _box_stl(path: Path, size: tuple[float, float, float]) -> None:
    """An ASCII STL of a box centred on the origin (12 triangles)."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) / 2
    corners = corners * np.array(size)
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]  # fmt: skip
    lines = ["solid box"]
    for a, b, c in faces:
        n = np.cross(corners[b] - corners[a], corners[c] - corners[a])
        n = n / np.linalg.norm(n)
        lines += [f"facet normal {n[0]} {n[1]} {n[2]}", "outer loop"]
        lines += [f"vertex {p[0]} {p[1]} {p[2]}" for p in (corners[a], corners[b], corners[c])]
        lines += ["endloop", "endfacet"]
    path.write_text("\n".join([*lines, "endsolid box"]))


MESH_ARM = """<?xml version="1.0"?>
<robot name="mesh_arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="height" default="1.6"/>
  <material name="magenta"><color rgba="0.9 0.0 0.9 1"/></material>
  <link name="base">
    <visual><origin xyz="0 0 1.6"/>
      <geometry><mesh filename="package://mesh_arm/meshes/column.stl"/></geometry>
      <material name="magenta"/></visual>
  </link>
  <link name="arm">
    <visual><origin xyz="0 0 0.3"/>
      <geometry><mesh filename="package://mesh_arm/meshes/arm.stl"/>
      </geometry><material name="magenta"/></visual>
  </link>
  <joint name="lift" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 $(arg height)"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="hand">
    <visual><geometry><mesh filename="package://mesh_arm/meshes/hand.stl"/></geometry></visual>
  </link>
  <joint name="wrist" type="fixed">
    <parent link="arm"/><child link="hand"/><origin xyz="0 0 0.6"/>
  </joint>
</robot>
"""


def _magenta_pixels(image: np.ndarray) -> int:
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return int(np.sum((r > 0.3) & (b > 0.3) & (g < 0.35 * np.minimum(r, b))))


@pytest.mark.slow
@needs_meshcat
def test_the_viewer_draws_meshes_of_a_package_and_falls_back_for_a_missing_one(tmp_path):
    """A ROS-style description (xacro + STL meshes under package://) is drawn with its
    meshes, framed whole although it is tall; the missing hand mesh becomes a primitive
    shape with a warning naming the file."""
    pkg = tmp_path / "src" / "mesh_arm"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "urdf").mkdir()
    (pkg / "package.xml").write_text("<package><name>mesh_arm</name></package>")
    _box_stl(pkg / "meshes" / "column.stl", (0.3, 0.3, 3.2))
    _box_stl(pkg / "meshes" / "arm.stl", (0.2, 0.2, 0.6))
    (pkg / "urdf" / "mesh_arm.urdf.xacro").write_text(MESH_ARM)
    robot = toolkit.load_urdf(pkg / "urdf" / "mesh_arm.urdf.xacro", tip="hand")
    with pytest.warns(viz_module.MissingMeshWarning, match="hand.stl"):
        viewer = viz_module.Viewer(robot)
    with viewer:
        (missing,) = viewer.missing_meshes
        assert missing.endswith("mesh_arm/meshes/hand.stl")
        meshes = [g.meshPath for g in viewer._visuals.geometry.geometryObjects]
        assert sum(p.endswith(("column.stl", "arm.stl")) for p in meshes) == 2
        image = _screenshot(viewer.url, ARTIFACTS / "viewer_mesh_arm.png")
        magenta = np.argwhere((image[..., 0] > 0.3) & (image[..., 2] > 0.3) & (image[..., 1] < 0.2))
        assert len(magenta) > 2000, "no mesh-coloured pixels in the canvas"
        # the whole 3.2 m column fits: its top and bottom are inside the picture
        rows = magenta[:, 0]
        assert rows.min() > 5 and rows.max() < image.shape[0] - 5
        assert rows.max() - rows.min() > image.shape[0] / 4, "the robot is drawn tiny"
        viewer.meshcat["robot"].set_property("visible", False)
        hidden = _screenshot(viewer.url, ARTIFACTS / "viewer_mesh_arm_hidden.png")
        assert _magenta_pixels(hidden) < 50


@pytest.mark.slow
@needs_meshcat
def test_a_large_arm_fills_the_view():
    """The UR5 is framed by its bounding box (meshes included): it spans a good part of the
    picture, not a few pixels (COLLADA cameras must not take the view over)."""
    robot = toolkit.load_example("ur5")
    with viz_module.Viewer(robot, q=[0, -1.2, 1.0, -1.4, -1.57, 0]) as viewer:
        viewer.meshcat["robot"].set_property("visible", False)
        hidden = _screenshot(viewer.url, ARTIFACTS / "viewer_ur5_hidden.png")
        viewer.meshcat["robot"].set_property("visible", True)
        # the seven COLLADA meshes (1-3 MB of text each) are parsed in the page after it
        # loads; on a busy machine that can outlast the first screenshot's time budget
        for budget in (8000, 20000, 40000):
            shown = _screenshot(viewer.url, ARTIFACTS / "viewer_ur5.png", budget_ms=budget)
            drawn = np.argwhere(np.abs(shown - hidden).sum(axis=-1) > 0.1)
            if len(drawn) > 2000 and np.ptp(drawn[:, 0]) > shown.shape[0] / 5:
                break
    assert len(drawn) > 2000, "the arm is not drawn"
    height = np.ptp(drawn[:, 0])
    # meshcat orbits the base origin, so the arm fills the upper half; before the box
    # framing (and with the COLLADA cameras) it was about 40 pixels tall
    assert height > shown.shape[0] / 5, f"the arm is drawn {height} pixels tall"


@pytest.mark.slow
def test_the_report_page_in_headless_chromium(tmp_path):
    """The report as a reader sees it: sections in paper order, one per paper, figures
    drawn, no empty table cells; the screenshot is kept for a look."""
    import re

    out = tmp_path / "report"
    assert main(["report", "-o", str(out), "--quiet"]) == 0
    page = (out / "index.html").read_text()
    titles = re.findall(r"<h2>([^<]*)</h2>", page)
    papers = [int(t.split()[1]) for t in titles if t.startswith("Paper ")]
    assert papers == [1, 2, 3, 4], titles  # one heading per paper, in order, before the rest
    assert titles[:4] == [t for t in titles if t.startswith("Paper ")]
    assert len(re.findall(r"<h3>", page)) >= 2  # the Katana's two parts under one heading
    assert "<td></td>" not in page and "<tbody></tbody>" not in page
    assert "recomputed" in page and "measured" in page
    image = _screenshot((out / "index.html").as_uri(), ARTIFACTS / "report_page.png", (1200, 2400))
    text = (image.sum(axis=-1) < 0.6).sum()  # dark pixels: text and table rules
    colour = (np.ptp(image, axis=-1) > 0.3).sum()  # saturated pixels: PASS cells, figures
    assert text > 5_000 and colour > 5_000


@pytest.mark.slow
@needs_meshcat
def test_a_map_is_drawn_as_coloured_voxels_beside_the_robot():

    robot = toolkit.load("scara")
    result = maps.reachability(robot, voxel=0.06, position_only=True, workers=1)
    with viz_module.Viewer(robot) as viewer:
        drawn = maps.show_voxels(result, viewer)
        image = _screenshot(viewer.url, ARTIFACTS / "viewer_map_voxels.png")
        viewer.meshcat["map"].delete()
        without = _screenshot(viewer.url, ARTIFACTS / "viewer_map_voxels_none.png")
    assert drawn == int((result.index > 0).sum()) > 100
    yellow = (image[..., 0] > 0.75) & (image[..., 1] > 0.75) & (image[..., 2] < 0.35)
    assert yellow.sum() > 500  # viridis' top colour: index 1
    assert np.abs(image - without).sum(axis=-1).__gt__(0.2).sum() > 1000


def _red_pixels(image: np.ndarray) -> int:
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    # red (green and blue alike and well below red), seen through a grey object too; the
    # orange links have no blue
    return int(np.sum((r > g + 0.15) & (r > b + 0.1) & (b > 0.6 * g)))


@pytest.mark.slow
@needs_meshcat
def test_colliding_links_turn_red_beside_the_scene_and_the_collision_shapes_show():
    robot = toolkit.load("katana_6m180")
    pose = np.eye(4)
    pose[:3, 3] = (0.35, 0.0, 0.15)
    cell = toolkit.Scene().add_box("block", (0.1, 0.1, 0.3), pose)
    Q = robot.random_q(3000, seed=2)
    q = Q[np.flatnonzero(robot.in_collision(Q, cell) & ~robot.in_collision(Q))[0]]
    free = Q[np.flatnonzero(~robot.in_collision(Q, cell))[0]]
    with viz_module.Viewer(robot) as viewer:
        assert viewer.show_collisions(free, cell) == []
        calm = _screenshot(viewer.url, ARTIFACTS / "viewer_collision_free.png")
        pairs = viewer.show_collisions(q, cell)
        hit = _screenshot(viewer.url, ARTIFACTS / "viewer_collision_red.png")
        assert pairs and all("block" in pair for pair in pairs)
        assert _red_pixels(hit) > 200 > _red_pixels(calm)
        viewer.show_collision_geometry()
        shapes = _screenshot(viewer.url, ARTIFACTS / "viewer_collision_shapes.png")
        green = (shapes[..., 1] > 0.5) & (shapes[..., 0] < 0.5 * shapes[..., 1])
        assert green.sum() > 5000 and _robot_pixels(shapes) < _robot_pixels(calm) / 5
        viewer.show_collision_geometry(False)
        back = _screenshot(viewer.url, ARTIFACTS / "viewer_collision_back.png")
        assert _robot_pixels(back) > _robot_pixels(shapes) * 5
        with pytest.raises(toolkit.InvalidParameterError, match="Scene"):
            viewer.show_scene("cell.json")


@pytest.mark.slow
@needs_meshcat
def test_a_placement_shows_the_robot_reaching_its_tasks_beside_the_scene():

    robot = toolkit.load("katana_6m180")
    points = robot.fk(robot.random_q(5, seed=np.random.default_rng(0)))[:, :3, 3] + [0.4, 0, 0]
    wall = toolkit.Scene().add_box("wall", (0.05, 1.0, 0.6), pose=(0.4, 0.6, 0.3))
    result = maps.placement(robot, points, [[0.2, -0.2], [0.6, 0.2]], step=0.1, yaws=4,
                            verify=2, scene=wall)  # fmt: skip
    with viz_module.Viewer(robot) as viewer:
        shown = viewer.show_placement(result, scene=wall, dt=0.0)
        image = _screenshot(viewer.url, ARTIFACTS / "viewer_placement.png")
        q = result.q[0][result.reached[0]][-1]
        np.testing.assert_allclose(viewer._q, q)  # the robot reaches the last task shown
        viewer.clear()  # the task markers gone
        bare = _screenshot(viewer.url, ARTIFACTS / "viewer_placement_no_tasks.png")
        with pytest.raises(toolkit.InvalidParameterError, match="Placement"):
            viewer.show_placement("best")
        with pytest.raises(toolkit.InvalidParameterError, match="rank"):
            viewer.show_placement(result, rank=5)
    assert shown == int(result.reached[0].sum()) >= 1
    assert _robot_pixels(image) > 1000

    def green(im):
        return int(((im[..., 1] > 0.55) & (im[..., 0] < 0.35) & (im[..., 2] < 0.4)).sum())

    assert green(image) > green(bare) + 100  # the reached tasks' markers (beside the y axis)


@pytest.mark.slow
@needs_meshcat
def test_every_branch_of_an_ik_all_answer_is_drawn_as_a_ghost_of_its_own_colour():
    robot = toolkit.load("katana_6m90a")  # light meshes: the browser draws them at once
    q = robot.random_q(seed=8)
    every = robot.ik_all(robot.fk(q))
    with viz_module.Viewer(robot) as viewer:
        labels = viewer.show_branches(every)
        many = _screenshot(viewer.url, ARTIFACTS / "viewer_branches.png")
        np.testing.assert_allclose(viewer._q, every.q[every.success][0])
        one = every._replace(success=np.arange(len(every.q)) == 0)  # one branch left
        assert viewer.show_branches(one) == [every.labels[0]]
        single = _screenshot(viewer.url, ARTIFACTS / "viewer_branches_one.png")
        assert viewer.show_branches(every, within_limits=False) == list(dict.fromkeys(every.labels))
        with pytest.raises(toolkit.InvalidParameterError, match="ik_all"):
            viewer.show_branches(q)
    assert labels == list(dict.fromkeys(np.array(every.labels)[every.success])) and len(labels) == 4
    assert _robot_pixels(many) > 1000 and _robot_pixels(single) > 1000
    changed = np.abs(many - single).max(axis=2) > 0.15  # the other branches' stick figures
    assert changed.sum() > 300


def _colour_pixels(image: np.ndarray, rgb: tuple[float, ...], close: float = 0.12) -> int:
    """Pixels within ``close`` of a colour in every channel (a translucent ghost's shading
    over the sky moves it; the colours of BRANCH_COLOURS are far apart)."""
    return int((np.abs(image - np.array(rgb[:3])).max(axis=2) < close).sum())


@pytest.mark.slow
@needs_meshcat
def test_the_ur5s_eight_branches_show_in_a_saved_page_without_the_server(tmp_path):
    """The UR5's meshes load slowly over the live socket in headless Chromium; the saved
    page carries them inline and opens without the server (closed before the shot)."""
    from toolkit.viz.answers import BRANCH_COLOURS

    ur5 = toolkit.load_example("ur5")
    every = ur5.ik_all(ur5.fk(ur5.random_q(seed=3)))
    with viz_module.Viewer(ur5) as viewer:
        viewer.show(every.q[0])
        alone = viewer.save_html(tmp_path / "alone.html")
        assert len(viewer.show_branches(every)) == 8
        page = viewer.save_html(tmp_path / "branches.html")
        with pytest.raises(toolkit.InvalidParameterError, match="folder"):
            viewer.save_html(tmp_path)
        with pytest.raises(toolkit.InvalidParameterError, match="no folder"):
            viewer.save_html(tmp_path / "missing" / "page.html")
    assert page.stat().st_size > 100_000  # the meshes inline
    shots = [_screenshot(p.as_uri(), ARTIFACTS / f"viewer_ur5_{p.stem}.png", size=(1000, 750),
                         budget_ms=20000) for p in (alone, page)]  # fmt: skip
    # each ghost's colour, against the same view without the ghosts (the sky and the arm's
    # own greys match some colours a little)
    gained = [_colour_pixels(shots[1], c) - _colour_pixels(shots[0], c) for c in BRANCH_COLOURS]
    assert sum(n > 60 for n in gained[:7]) >= 6, gained  # the 7 ghosts
    assert abs(gained[8]) < 60, gained  # a colour no ghost has


@pytest.mark.slow
@needs_meshcat
def test_a_base_inside_an_obstacle_turns_red(tmp_path):
    """The Katana 6M180 whose base column stands 2 cm inside a crate (not a support): the
    base link is in collision at every configuration and the viewer draws it red; with the
    crate clear of it, nothing is red."""
    robot = toolkit.load("katana_6m180")
    q = np.clip(np.radians([60, 60, -60, -60, 0]), robot.joints.lower, robot.joints.upper)
    pages = []
    for name, x in (("clear", 0.25), ("inside", 0.10)):
        crate = toolkit.Scene().add_box("crate", (0.1, 0.1, 0.1), pose=(x, 0.0, 0.05))
        with viz_module.Viewer(robot) as viewer:
            pairs = viewer.show_collisions(q, crate)
            assert (("base_link", "crate") in pairs) == (name == "inside"), pairs
            pages.append(viewer.save_html(tmp_path / f"{name}.html"))
    shots = [_screenshot(p.as_uri(), ARTIFACTS / f"viewer_base_{p.stem}.png", size=(1000, 750),
                         budget_ms=20000) for p in pages]  # fmt: skip
    red = [_colour_pixels(s, (0.9, 0.1, 0.1), close=0.3) for s in shots]
    assert red[1] > red[0] + 200, red


@pytest.mark.slow
@needs_meshcat
def test_a_trajectory_plays_as_an_animation_whose_frames_are_the_arms_poses(monkeypatch):
    """Viewer.play sends one meshcat animation: a clip per visual shape, one key per frame,
    each key the shape's pose at the sampled configuration (checked by the link's own
    forward kinematics); with a backlash layer the robot shows the outputs, a ghost the
    commands; and it plays in the browser (a screenshot mid-motion differs from the start)."""
    import pinocchio as pin

    robot = toolkit.load("katana_6m180")
    motion = backlash.pick_and_place(2.0)
    layer = backlash.Backlash(robot, payload=0.5)
    with viz_module.Viewer(robot) as viewer:
        import meshcat.visualizer

        sent = []
        real = meshcat.visualizer.Visualizer.set_animation
        monkeypatch.setattr(meshcat.visualizer.Visualizer, "set_animation",
                            lambda self, a, **k: (sent.append(a), real(self, a, **k)))  # fmt: skip
        frames = viewer.play(motion, rate=10, layer=layer)
        assert frames == len(motion.at_rate(robot, 10).t) == 21 and len(sent) == 1
        shapes = viewer._main.visual_model.geometryObjects
        clips = sent[0].clips
        assert len(clips) == 2 * len(shapes)  # the robot and the commanded ghost
        outputs = backlash.along(layer, motion, 10).theta_dynamic
        data = robot.model.createData()
        shape = shapes[len(shapes) - 1]
        name = viewer._main.getViewerNodeName(shape, pin.GeometryType.VISUAL)
        clip = next(c for p, c in clips.items() if p.lower().endswith(name))
        for k in (0, 7, 20):
            pin.forwardKinematics(robot.model, data, outputs[k])
            placement = data.oMi[shape.parentJoint] * shape.placement
            key = clip.tracks["position"].values[k]
            np.testing.assert_allclose(key, placement.translation, atol=1e-9)
        with pytest.raises(ToolkitError, match="Trajectory"):
            viewer.play(np.zeros((3, 5)))
        with pytest.raises(ToolkitError, match="rate"):
            viewer.play(motion, rate=0)
        start = _screenshot(viewer.url, ARTIFACTS / "viewer_play_start.png", budget_ms=200)
        later = _screenshot(viewer.url, ARTIFACTS / "viewer_play_later.png", budget_ms=1500)
        assert _robot_pixels(later) > 1000 and np.abs(later - start).max() > 0.2


def test_a_plan_plays_with_its_scene_and_a_colliding_motion_is_shown_red(monkeypatch):
    """A solved plan plays (timed trapezoidally: frames at the rate over its duration) with
    its scene drawn, without a warning; a timed motion straight through the wall warns
    with the time and the pair and leaves a red ghost at the first colliding frame; an
    unsolved plan is refused with its reason."""
    from toolkit import motion

    robot = toolkit.load_example("ur5")
    wall = toolkit.Scene().add_box("wall", [0.05, 0.6, 0.8], [0.5, 0.0, 0.4])
    a = robot.joints.q_from_angles([-2.0, -1.2, 1.2, -1.5, -1.5, 0.0])
    b = robot.joints.q_from_angles([2.0, -1.2, 1.2, -1.5, -1.5, 0.0])
    plan = robot.plan(a, b, scene=wall, seed=1)
    assert plan.success
    with viz_module.Viewer(robot) as viewer:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            frames = viewer.play(plan, rate=20, scene=wall)
        timed = motion.trapezoidal(robot, plan.path, acceleration=2.0)
        assert frames == len(timed.at_rate(robot, 20).t)
        assert "scene" in viewer._extra and "collision" not in viewer._ghosts
        straight = motion.trapezoidal(robot, np.array([a, b]), acceleration=2.0)
        with pytest.warns(toolkit.CollisionWarning, match=r"t = [\d.]+ s: .* with wall"):
            viewer.play(straight, rate=20, scene=wall)
        assert "collision" in viewer._ghosts
        unsolved = toolkit.planning.PlanResult(
            success=False, path=np.zeros((0, 6)), goal=-1, goals=np.zeros((0, 6)), time_s=0.1,
            checks=0, nodes=0, reason="no path within the time limit",
        )  # fmt: skip
        with pytest.raises(ToolkitError, match="no path within the time limit"):
            viewer.play(unsolved)


def test_a_node_drawn_again_after_a_delete_goes_to_a_fresh_path():
    """meshcat's server does not replay a path deleted and drawn again to a browser that
    connects later: a scene drawn twice, markers after clear(), each land on a new path
    (and the old one is deleted), so a page opened later shows them."""
    robot = toolkit.load_example("ur5")
    wall = toolkit.Scene().add_box("wall", [0.05, 0.6, 0.8], [0.5, 0.0, 0.4])
    with viz_module.Viewer(robot) as viewer:
        viewer.show_scene(wall)
        first = viewer._node("scene").path.lower()
        viewer.show_scene(wall)
        second = viewer._node("scene").path.lower()
        assert first != second and second.startswith(first)
        viewer.marker([0.3, 0.0, 0.3])
        markers = viewer._node("markers").path.lower()
        viewer.clear()
        viewer.marker([0.3, 0.0, 0.3])
        assert viewer._node("markers").path.lower() != markers


def test_the_viewer_says_its_url_once(capsys):
    pytest.importorskip("meshcat")
    from toolkit.viz import Viewer

    with Viewer(toolkit.load("scara")) as viewer:
        printed = capsys.readouterr().out
        assert viewer.url not in printed and "You can open the visualizer" not in printed


def test_a_trajectory_file_is_read_for_the_robot_or_the_group_it_moves(tmp_path):
    """``toolkit view --trajectory``'s reading: a MoveIt trajectory of the Panda's seven arm
    joints moves the arm's group (the fingers locked), its samples reproduced; with its
    velocities and accelerations the quintic through them; a joint the robot lacks is
    refused by name."""
    from toolkit.cli.inputs import trajectory_of

    panda = toolkit.load_example("panda")
    arm = [f"panda_joint{k}" for k in range(1, 8)]
    t = np.array([0.0, 0.5, 1.2])
    q = np.array([[0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.7],
                  [0.2, -0.4, 0.1, -1.9, 0.1, 1.6, 0.6],
                  [0.4, -0.3, 0.2, -1.8, 0.2, 1.7, 0.5]])  # fmt: skip
    plain = toolkit.planning.write_joint_trajectory(tmp_path / "a.yaml", arm, t, q)
    robot, motion = trajectory_of(panda, str(plain))
    assert robot.joints.names == arm and motion.duration == pytest.approx(1.2)
    samples = motion.sample(robot, t)
    np.testing.assert_allclose(samples.angles, q, atol=1e-12)
    qd, qdd = np.gradient(q, t, axis=0), np.zeros_like(q)
    full = toolkit.planning.write_joint_trajectory(tmp_path / "b.yaml", arm, t + 3.0, q, qd, qdd)
    robot, motion = trajectory_of(panda, str(full))
    np.testing.assert_allclose(motion.sample(robot, t).angles, q, atol=1e-12)
    np.testing.assert_allclose(motion.sample(robot, t).qd, qd, atol=1e-9)
    wrong = toolkit.planning.write_joint_trajectory(tmp_path / "c.yaml", ["elbow"], t, q[:, :1])
    with pytest.raises(toolkit.InvalidParameterError, match=r"joints \['elbow'\] are not"):
        trajectory_of(panda, str(wrong))


@needs_meshcat
def test_the_cli_view_plays_a_trajectory_in_a_scene(tmp_path, capsys):
    """``toolkit view ROBOT --trajectory FILE --scene FILE`` plays it (meshcat's server
    only: no browser needed) and says how long and how many frames."""
    ur5 = toolkit.load_example("ur5")
    t = np.array([0.0, 1.0])
    q = np.array([[-1.4, -1.0, 1.5, -1.9, -1.57, 0.0], [-1.2, -1.0, 1.5, -1.9, -1.57, 0.0]])
    path = toolkit.planning.write_joint_trajectory(tmp_path / "t.yaml", ur5.joints.names, t, q)
    scene = tmp_path / "s.json"
    toolkit.Scene().add_box("wall", [0.1, 1.2, 0.8], [0.45, 0.0, 0.4]).save(scene)
    code = main(["view", "ur5", "--trajectory", str(path), "--scene", str(scene),
                 "--seconds", "0", "--rate", "10"])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0 and "playing" in out and "1.00 s, 11 frames at 10 frames/s" in out
