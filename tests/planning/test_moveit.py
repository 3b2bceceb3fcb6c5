"""MoveIt's formats: planning scenes (every primitive, meshes, planes, attached objects,
both pose spellings), motion plan requests (joint and pose goals) and joint trajectories,
read from hand-written files in tests/data/moveit; plans from them checked on the exact
shapes; bad files refused naming the field; ``toolkit plan`` end to end."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

import toolkit
from toolkit import planning
from toolkit.cli import main
from toolkit.collision import Scene

DATA = Path(__file__).resolve().parents[1] / "data" / "moveit"


@pytest.fixture(scope="module")
def ur5():
    return toolkit.load_example("ur5")


@pytest.fixture(scope="module")
def panda():
    return toolkit.load_example("panda")


def _pose(o):
    return np.array(o.pose).reshape(4, 4)


def test_every_shape_of_the_scene_file_lands_where_the_file_puts_it(ur5):
    """Each object against the file's numbers worked by hand: the shelf's box and cylinder
    turned 90 degrees about z with the object's pose, MoveIt's (height, radius) as the
    toolkit's (radius, length), a cone as its enclosing cylinder, the mesh's triangles in
    its STL, a plane 2z + 0.1 = 0 as a floor at z = -0.05, the held part on its link."""
    scene = planning.read_scene(DATA / "scene.yaml", frames=planning.fixed_frames(ur5))
    by = {o.name: o for o in scene.objects}
    assert list(by) == ["shelf_0", "shelf_1", "ball", "cone", "wedge", "ground", "held_part"]
    Rz = pin.exp3(np.array([0.0, 0.0, math.pi / 2]))
    np.testing.assert_allclose(_pose(by["shelf_0"])[:3, :3], Rz, atol=1e-12)
    np.testing.assert_allclose(_pose(by["shelf_0"])[:3, 3], [0.6, 0.0, 0.3], atol=1e-12)
    np.testing.assert_allclose(_pose(by["shelf_1"])[:3, 3], [0.6, 0.1, 0.15], atol=1e-12)
    assert by["shelf_0"].size == (0.4, 0.2, 0.02) and by["shelf_1"].size == (0.05, 0.3)
    assert by["ball"].kind == "sphere" and by["ball"].size == (0.05,)
    assert by["cone"].kind == "cylinder" and by["cone"].size == (0.04, 0.2)
    assert by["ground"].kind == "floor" and _pose(by["ground"])[2, 3] == pytest.approx(-0.05)
    assert by["held_part"].link == "wrist_3_link"
    np.testing.assert_allclose(_pose(by["held_part"])[:3, 3], [0.0, 0.0, 0.05])
    stl = Path(by["wedge"].path).read_text()
    vertices = {tuple(float(v) for v in m.split()) for m in re.findall(r"vertex (.+)", stl)}
    assert vertices == {(0.0, 0.0, 0.0), (0.1, 0.0, 0.0), (0.0, 0.1, 0.0), (0.0, 0.0, 0.1)}
    assert stl.count("facet normal") == 4
    np.testing.assert_allclose(_pose(by["wedge"])[:3, 3], [0.0, -0.5, 0.3])


def test_the_scene_collides_where_its_shapes_are(ur5):
    """The read scene in use: the UR5's tool pushed into the ball collides with it; the
    same configuration in an empty scene does not; the wedge mesh is seen too."""
    scene = planning.read_scene(DATA / "scene.yaml", frames=planning.fixed_frames(ur5))
    hits = 0
    for target in ([-0.4, 0.3, 0.5], [0.02, -0.48, 0.32]):
        T = np.eye(4)
        T[:3, :3] = pin.exp3(np.array([math.pi, 0.0, 0.0]))
        T[:3, 3] = target
        answer = ur5.ik_all(T)
        for q in answer.q[answer.success]:
            if ur5.in_collision(q):
                continue
            hits += 1
            assert ur5.in_collision(q, scene)
            assert not ur5.in_collision(q, Scene().add_floor(-0.05))
            break
    assert hits == 2


def test_both_pose_spellings_read_the_same():
    data = yaml.safe_load((DATA / "scene.yaml").read_text())
    for obj in data["world"]["collision_objects"]:
        for p in obj.get("primitive_poses", []) + obj.get("mesh_poses", []):
            if isinstance(p.get("position"), dict):
                p["position"] = [p["position"][k] for k in "xyz"]
            if isinstance(p.get("orientation"), dict):
                p["orientation"] = [p["orientation"][k] for k in "xyzw"]
    a, b = planning.read_scene(DATA / "scene.yaml"), planning.read_scene(data)
    assert [(o.name, o.kind, o.size) for o in a] == [(o.name, o.kind, o.size) for o in b]
    for x, y in zip(a, b, strict=True):
        np.testing.assert_allclose(x.pose, y.pose, atol=1e-15)


def test_an_object_in_a_frame_fixed_to_the_base_is_placed_by_that_frame(ur5):
    """The UR5's ``base`` frame is its ``base_link`` turned by pi about z: a box given in
    ``base`` at x = 0.5 lies at x = -0.5 in the planning frame."""
    doc = {"world": {"collision_objects": [{
        "id": "b", "header": {"frame_id": "base"},
        "primitives": [{"type": "box", "dimensions": [0.1, 0.1, 0.1]}],
        "primitive_poses": [{"position": [0.5, 0.0, 0.2]}]}]}}  # fmt: skip
    scene = planning.read_scene(doc, frames=planning.fixed_frames(ur5))
    expected = ur5.model.frames[ur5.model.getFrameId("base")].placement.homogeneous
    np.testing.assert_allclose(_pose(scene.objects[0])[:3, 3], (expected @ [0.5, 0, 0.2, 1])[:3])
    assert _pose(scene.objects[0])[0, 3] == pytest.approx(-0.5)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda o: o["primitives"][0].update(type="torus"), r"primitives\[0\]\.type"),
        (lambda o: o["primitives"][0].update(dimensions=[1, 2]), r"primitives\[0\]\.dimensions"),
        (lambda o: o.update(operation="REMOVE"), "only ADD is read"),
        (lambda o: o.update(header={"frame_id": "tool0"}), "frame 'tool0', not one fixed"),
        (lambda o: o["primitive_poses"][0].update(orientation=[0, 0, 0, 0]), "zero quaternion"),
        (lambda o: o["primitive_poses"].pop(), "one pose per primitive"),
        (lambda o: o.update(planes=[{"coef": [1, 0, 0, 0]}]), "horizontal plane"),
    ],
)  # fmt: skip
def test_a_bad_scene_names_the_object_and_the_field(ur5, tmp_path, edit, message):
    data = yaml.safe_load((DATA / "scene.yaml").read_text())
    edit(data["world"]["collision_objects"][0])
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(toolkit.InvalidParameterError, match=message) as info:
        planning.read_scene(path, frames=planning.fixed_frames(ur5))
    assert str(info.value).startswith(f"{path}: world.collision_objects[0] ('shelf')")


def test_files_that_are_not_scenes_are_refused(tmp_path):
    for text, message in (("- a\n- b\n", "is a YAML mapping"), ("a: [1,\n", "cannot read"),
                          ("!!python/object:os.system {}\n", "cannot read")):  # fmt: skip
        path = tmp_path / "x.yaml"
        path.write_text(text)
        with pytest.raises(toolkit.InvalidParameterError, match=message):
            planning.read_scene(path)
    with pytest.raises(toolkit.InvalidParameterError, match="no such file"):
        planning.read_scene(tmp_path / "missing.yaml")
    data = yaml.safe_load((DATA / "scene.yaml").read_text())
    data["robot_state"]["attached_collision_objects"][0]["object"]["header"]["frame_id"] = "x"
    with pytest.raises(toolkit.InvalidParameterError, match="attached to 'wrist_3_link' but"):
        planning.read_scene(data)


def test_a_joint_request_plans_with_the_fingers_held(panda):
    """The Panda request: the start as written (the fingers brought to their 0.04 m limit),
    the goal's arm joints, the fingers held; the plan reaches the goal and every segment is
    free on the exact shapes at 0.5 degree steps, checked here configuration by
    configuration."""
    request = planning.read_request(DATA / "request_joints.yaml")
    assert request.group == "panda_arm" and request.time_limit == 7.5
    assert request.held(panda) == ["panda_finger_joint1", "panda_finger_joint2"]
    start, goal = request.start_q(panda), request.goal_q(panda)
    values = panda.joints.angles(start)
    np.testing.assert_allclose(values[:7], [0, -0.785, 0, -2.356, 0, 1.571, 0.785])
    assert values[7] == values[8] == pytest.approx(0.04)
    np.testing.assert_allclose(
        panda.joints.angles(goal)[0, :7], [0.8, -0.3, 0.1, -1.9, 0.2, 1.9, 0.5]
    )
    box = np.eye(4)
    box[:3, 3] = [0.45, 0.35, 0.45]
    scene = Scene().add_box("crate", [0.15, 0.15, 0.15], box)
    result = request.plan(panda, scene, seed=3)
    assert result.success and result.verified, result.reason
    np.testing.assert_allclose(result.path[-1], goal[0], atol=1e-12)
    assert (result.path[:, 7:] == start[7:]).all()
    for a, b in zip(result.path[:-1], result.path[1:], strict=True):
        steps = max(2, math.ceil(np.abs(b - a).max() / math.radians(0.5)) + 1)
        for s in np.linspace(0.0, 1.0, steps):
            assert not panda.in_collision(a + s * (b - a), scene)


def test_a_pose_request_plans_to_the_tool_pose(ur5):
    request = planning.read_request(DATA / "request_pose.yaml")
    link, T = request.pose_goals[0]
    assert link == "tool0" and request.held(ur5) == []
    np.testing.assert_allclose(T[:3, :3], np.diag([1.0, -1.0, -1.0]), atol=1e-12)
    np.testing.assert_allclose(T[:3, 3], [0.35, 0.25, 0.4])
    result = request.plan(ur5, seed=1, time_limit=5.0)
    assert result.success, result.reason
    np.testing.assert_allclose(ur5.fk(result.path[-1], "tool0"), T, atol=1e-9)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["goal_constraints"].clear(), "no goal"),
        (lambda d: d["goal_constraints"][0]["joint_constraints"][0].update(joint_name="elbow"),
         "no moving joint 'elbow'"),
        (lambda d: d["start_state"]["joint_state"]["position"].pop(), "start_state"),
        (lambda d: d["goal_constraints"].append({"position_constraints": [], "orientation_"
                                                 "constraints": []}), r"goal_constraints\[1\]"),
    ],
)  # fmt: skip
def test_a_bad_request_names_the_field(panda, tmp_path, edit, message):
    data = yaml.safe_load((DATA / "request_joints.yaml").read_text())
    edit(data)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(toolkit.InvalidParameterError, match=message):
        planning.read_request(path).goal_q(panda)


def test_a_joint_trajectory_round_trips_exactly(tmp_path):
    rng = np.random.default_rng(4)
    t = np.cumsum(rng.uniform(0.001, 0.5, 40)) - 0.001
    Q, V = rng.normal(size=(40, 3)), rng.normal(size=(40, 3))
    path = planning.write_joint_trajectory(tmp_path / "t.yaml", ["a", "b", "c"], t, Q, V)
    back = planning.read_joint_trajectory(path)
    assert back.names == ("a", "b", "c") and back.accelerations is None
    np.testing.assert_array_equal(back.positions, Q)
    np.testing.assert_array_equal(back.velocities, V)
    np.testing.assert_allclose(back.times, t, rtol=0, atol=1e-9)  # nanosecond stamps
    with pytest.raises(toolkit.InvalidParameterError, match="increasing"):
        planning.write_joint_trajectory(tmp_path / "u.yaml", ["a"], [0.0, 0.0], [[1.0], [2.0]])
    with pytest.raises(toolkit.InvalidParameterError, match="positions must be finite"):
        planning.write_joint_trajectory(tmp_path / "u.yaml", ["a", "b"], [0.0], [[1.0]])


def test_toolkit_plan_writes_a_timed_trajectory_along_the_plan(ur5, tmp_path, capsys):
    """``toolkit plan`` from start and goal values around a wall given as a MoveIt scene
    (the straight joint motion turns the arm through it):
    the trajectory file starts and ends at them, at rest, with increasing times, within
    the joint limits, and each sample free of the box."""
    scene = {"world": {"collision_objects": [{
        "id": "wall", "header": {"frame_id": "base_link"},
        "primitives": [{"type": 1, "dimensions": [0.05, 0.6, 0.8]}],
        "primitive_poses": [{"position": [0.5, 0.0, 0.4]}]}]}}  # fmt: skip
    (tmp_path / "wall.yaml").write_text(yaml.safe_dump(scene))
    start, goal = (
        ["-2.0", "-1.2", "1.2", "-1.5", "-1.5", "0"],
        ["2.0", "-1.2", "1.2", "-1.5", "-1.5", "0"],
    )
    out = tmp_path / "plan.yaml"
    argv = ["plan", "ur5", "--scene", str(tmp_path / "wall.yaml"), "--start", *start,
            "--goal", *goal, "-o", str(out), "--rate", "50"]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "solved in" in text and "verified free" in text and f"wrote {out}" in text
    assert "searched on the sphere covers" in text and "over its whole motion (certified" in text
    traj = planning.read_joint_trajectory(out)
    assert traj.names == tuple(ur5.joints.names)
    np.testing.assert_allclose(traj.positions[0], [float(v) for v in start], atol=1e-12)
    np.testing.assert_allclose(traj.positions[-1], [float(v) for v in goal], atol=1e-12)
    assert (np.diff(traj.times) > 0).all() and np.abs(traj.velocities[[0, -1]]).max() < 1e-12
    walls = planning.read_scene(tmp_path / "wall.yaml", frames=planning.fixed_frames(ur5))
    assert ur5.in_collision(ur5.joints.q_from_angles([0.0, -1.2, 1.2, -1.5, -1.5, 0.0]), walls)
    Q = ur5.joints.q_from_angles(
        traj.positions
    )  # the straight joint motion's middle hits it, not these
    assert ur5.joints.within_limits(Q) and not np.asarray(ur5.in_collision(Q, walls)).any()


def test_toolkit_plan_reads_a_request_and_refuses_bad_input(tmp_path, capsys):
    assert main(["plan", "panda", "--request", str(DATA / "request_joints.yaml"),
                 "--time-limit", "5"]) == 0  # fmt: skip
    assert "solved in" in capsys.readouterr().out
    assert main(["plan", "ur5", "--start", "0", "0", "0", "0", "0", "0"]) == 2
    assert "--goal" in capsys.readouterr().err
    assert main(["plan", "ur5", "--start", "0", "0", "--goal", "1", "1"]) == 2
    assert "6 joint values" in capsys.readouterr().err
    bad = tmp_path / "bad.yaml"
    bad.write_text("world: {collision_objects: [{id: x, primitives: [{type: 9}], "
                   "primitive_poses: [{}]}]}\n")  # fmt: skip
    assert (
        main(["plan", "ur5", "--scene", str(bad), "--start", *"000000", "--goal", *"100000"]) == 2
    )
    assert "primitives[0].type" in capsys.readouterr().err


def test_a_frames_mapping_is_checked_as_every_pose_is():
    """``frames={name: pose}`` gets the scene's own pose check (one check for both): a
    rotation that is not one, or a last row that is not (0, 0, 0, 1), is refused."""
    skew, tilted = np.eye(4), np.eye(4)
    skew[0, 1] = 0.5
    tilted[3, 2] = 1.0
    for bad, message in ((skew, "not a rotation"), (tilted, "last row"), ("x", "numeric")):
        with pytest.raises(toolkit.InvalidParameterError, match=message):
            planning.read_scene(DATA / "scene.yaml", frames={"base_link": bad})


def test_held_joints_are_brought_within_their_own_limits_on_an_arm_with_continuous_joints():
    """The Kinova (continuous joints 1, 4 and 6 stored as (cos, sin)): a held joint is
    clamped by its own limits, read where its coordinate lies in q (joint 2 at 3.0 rad is
    within [0.82, 5.46] and stays; joint 3 at 6.0 is brought to its upper limit 5.95)."""
    kinova = toolkit.load_example("kinova")
    names = kinova.joints.names
    request = planning.MotionRequest(start={names[1]: 3.0, names[2]: 6.0, names[0]: 2.5},
                                     joint_goals=({names[0]: 0.5},))  # fmt: skip
    values = kinova.joints.angles(request.start_q(kinova))
    j2, j3 = (kinova.model.joints[kinova.model.getJointId(n)] for n in names[1:3])
    assert values[1] == 3.0 and kinova.joints.lower[j2.idx_q] < 3.0 < kinova.joints.upper[j2.idx_q]
    assert values[2] == kinova.joints.upper[j3.idx_q] and values[0] == pytest.approx(2.5)
