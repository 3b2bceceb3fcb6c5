"""Collisions against an independent route: coal called pair by pair on a freshly built
Pinocchio model and GeometryModel, with the pairs worked out here from the SRDF's XML;
the scene as plain data; collision-free IK judged by that independent check."""

from __future__ import annotations

import json
import pickle
import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest

import toolkit
import toolkit.robot
from toolkit import Scene
from toolkit.descriptions import PackageResolver, read_description


class Independent:
    """Self-collision of a robot's file, computed without the toolkit's checker."""

    def __init__(self, robot: toolkit.Robot) -> None:
        text = PackageResolver(None, robot.urdf_path).absolute_uris(
            read_description(robot.urdf_path)
        )
        self.model = pin.buildModelFromXML(text)
        self.geom = pin.buildGeomFromUrdfString(self.model, text, pin.GeometryType.COLLISION)
        self.data, self.gdata = self.model.createData(), self.geom.createData()
        disabled = set()
        if robot.srdf_path is not None:
            for item in ET.parse(robot.srdf_path).getroot().iter("disable_collisions"):
                disabled.add(frozenset((item.get("link1"), item.get("link2"))))
        objs = self.geom.geometryObjects
        link = [self.model.frames[g.parentFrame].name for g in objs]
        shaped = {g.parentJoint for g in objs}

        def body_above(joint: int) -> int:  # the nearest joint above with a shape (0: base)
            up = self.model.parents[joint]
            return up if up == 0 or up in shaped else body_above(up)

        self.pairs = []
        for i in range(len(objs)):
            for j in range(i + 1, len(objs)):
                a, b = objs[i].parentJoint, objs[j].parentJoint
                if a == b or (a and body_above(a) == b) or (b and body_above(b) == a):
                    continue
                if frozenset((link[i], link[j])) in disabled:
                    continue
                self.pairs.append((i, j))
        self.link = link
        self.disabled = disabled

    def check(self, q: np.ndarray) -> tuple[bool, float]:
        """(in collision, smallest distance over the pairs) at q."""
        pin.updateGeometryPlacements(self.model, self.data, self.geom, self.gdata, q)
        hit, closest = False, np.inf
        for i, j in self.pairs:
            gi, gj = self.geom.geometryObjects[i], self.geom.geometryObjects[j]
            Mi, Mj = self.gdata.oMg[i], self.gdata.oMg[j]
            ti = coal.Transform3s(Mi.rotation, Mi.translation)
            tj = coal.Transform3s(Mj.rotation, Mj.translation)
            result = coal.DistanceResult()
            d = coal.distance(gi.geometry, ti, gj.geometry, tj, coal.DistanceRequest(), result)
            closest = min(closest, d)
            collide = coal.CollisionResult()
            coal.collide(gi.geometry, ti, gj.geometry, tj, coal.CollisionRequest(), collide)
            hit = hit or collide.isCollision()
        return hit, closest


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "n"), [("panda", 1200), ("ur5", 800), ("katana_6m180", 1000), ("arm5dof", 400)]
)
def test_self_collision_equals_an_independent_check(name, n):
    """The catalogue's models too: their templates give primitives as collision shapes
    (and the Katana its floor)."""
    robot = toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)
    judge = Independent(robot)
    Q = robot.random_q(n, seed=11)
    ours = robot.in_collision(Q)
    compared = hits = 0
    for q, flag in zip(Q, ours, strict=True):
        theirs, closest = judge.check(q)
        if abs(closest) < 1e-3 and not theirs:
            continue  # within a millimetre of contact: either answer is fair
        compared += 1
        hits += theirs
        assert flag == theirs, (name, q.tolist(), closest)
    assert compared >= 0.95 * n and hits > 0, (compared, hits)


def test_srdf_disabled_pairs_are_never_reported():
    robot = toolkit.load_example("panda")
    judge = Independent(robot)
    assert judge.disabled, "the Panda's SRDF disables pairs"
    names = {frozenset(p) for p in judge.disabled}
    seen = 0
    for q in robot.random_q(600, seed=12):
        for a, b in robot.collision_checker().collisions(q):
            assert frozenset((a, b)) not in names
            seen += 1
    assert seen > 0


def test_a_scene_round_trips_and_pickles(tmp_path):
    scene = (
        Scene()
        .add_floor(0.0)
        .add_box("table", [0.8, 1.2, 0.04], [0.5, 0.0, 0.3])
        .add_sphere("ball", 0.05, [0.4, 0.3, 0.5])
        .add_cylinder("post", 0.03, 0.6, [0.3, -0.4, 0.3])
        .attach("tool", "panda_hand", "cylinder", [0.02, 0.15], [0, 0, 0.1])
    )
    path = tmp_path / "scene.json"
    scene.save(path)
    again = Scene.load(path)
    assert again == scene and pickle.loads(pickle.dumps(scene)) == scene
    assert again.digest() == scene.digest() and len(again) == 5
    assert "table" in repr(scene)


def test_a_mesh_is_loaded_once_and_pickles_without_it(tmp_path, monkeypatch):
    """``add_mesh`` loads the file (a bad one is refused there); the checker then uses that
    mesh (a 2-million-triangle file took 7 s to load, again at the build); a pickled
    scene carries the fields, not the mesh, and loads it where it is unpickled."""
    path = tmp_path / "cube.stl"
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)]) * 0.1
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]  # fmt: skip
    lines = ["solid cube"]
    for f in faces:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += [f"vertex {' '.join(map(str, corners[i]))}" for i in f]
        lines += ["endloop", "endfacet"]
    path.write_text("\n".join([*lines, "endsolid cube"]) + "\n")
    loads: list[str] = []
    real = coal.MeshLoader

    class Counting:
        def load(self, *args):
            loads.append(str(args[0]))
            return real().load(*args)

    monkeypatch.setattr(coal, "MeshLoader", Counting)
    scene = Scene().add_mesh("cube", path, [0.45, 0.0, 0.3])
    robot = toolkit.load_example("ur5")
    checker = robot.collision_checker(scene)
    assert loads == [str(path)] and "cube" in checker.names
    again = pickle.loads(pickle.dumps(scene))
    assert again == scene and "_mesh" not in again.objects[0].__dict__
    assert type(again.objects[0].shape()).__name__.startswith("BVHModel") and len(loads) == 2


def test_a_scene_digest_follows_its_objects_and_so_does_the_robots_checker():
    """The digest is kept between calls, and made again whenever the list of objects
    changes: added, removed, or one replaced by an object with the same name elsewhere
    (also by writing the list directly); equal scenes have equal digests."""
    scene = Scene().add_box("box", [0.1, 0.1, 0.1], [0.5, 0.0, 0.3])
    first = scene.digest()
    assert scene.digest() == first == Scene.from_dict(scene.to_dict()).digest()
    scene.add_sphere("ball", 0.05, [0.0, 0.5, 0.3])
    second = scene.digest()
    assert second != first
    moved = Scene().add_box("box", [0.1, 0.1, 0.1], [0.5, 0.0, 0.9]).objects[0]
    scene.objects[0] = moved  # the same name, elsewhere: written into the list directly
    assert scene.digest() not in (first, second)
    scene.objects[:] = scene.objects[1:]
    assert scene.digest() == Scene().add_sphere("ball", 0.05, [0.0, 0.5, 0.3]).digest()
    ur5 = toolkit.load_example("ur5")
    q = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0])
    wall = Scene().add_box("wall", [2.0, 2.0, 0.02], [0.0, 0.0, 2.0])
    assert not ur5.in_collision(q, wall)
    wall.objects[0] = Scene().add_box("wall", [2.0, 2.0, 0.02], [0.0, 0.0, 0.3]).objects[0]
    assert ur5.in_collision(q, wall)  # the checker of the scene as it is now


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda s: s.add_box("b", [0.1, -0.1, 0.1]), "box size"),
        (lambda s: s.add_box("b", [0.1, 0.1]), "box size"),
        (lambda s: s.add_sphere("s", float("nan")), "sphere radius"),
        (lambda s: s.add_box("b", [0.1] * 3, np.ones((4, 4))), "rotation"),
        (lambda s: s.add_box("", [0.1] * 3), "name"),
        (lambda s: s.add_floor().add_floor(), "already has"),
        (lambda s: s.attach("t", "hand", "cone", [0.1]), "box, sphere or cylinder"),
        (lambda s: s.add_mesh("m", "/no/such.stl"), "not found"),
    ],
)
def test_bad_scene_input_is_refused(build, message):
    with pytest.raises(toolkit.InvalidParameterError, match=message):
        build(Scene())


def test_unknown_link_and_bad_scene_files(tmp_path):
    robot = toolkit.load_example("ur5")
    with pytest.raises(toolkit.InvalidParameterError, match="attached object 't'"):
        robot.in_collision(robot.joints.neutral(), Scene().attach("t", "nope", "sphere", [0.1]))
    bad = tmp_path / "bad.json"
    bad.write_text('{"objects": [{"name": "x", "kind": "cone"}]}')
    with pytest.raises(toolkit.InvalidParameterError, match="kind must be one of"):
        Scene.load(bad)
    with pytest.raises(toolkit.InvalidParameterError, match="scene must be"):
        robot.in_collision(robot.joints.neutral(), scene="table")


@pytest.mark.parametrize(
    ("objects", "message"),
    [
        ([{"name": "a", "shape": "box", "size": [1, 1, 1]}],
         r"objects\[0\] \('a'\): unknown field\(s\) 'shape'"),
        ([{"name": "a", "kind": "box", "size": [1, 1, 1]}, {"name": "p", "kind": "cylinder",
          "size": [0.04]}], r"objects\[1\] \('p'\): size: a cylinder takes \[radius, length\]"),
        ([{"name": "b", "kind": "sphere", "size": [0.1], "pose": [1, 2]}],
         r"objects\[0\] \('b'\): pose"),
        ([{"name": "f", "kind": "floor", "pose": "x"}], r"objects\[0\] \('f'\): pose"),
    ],
)  # fmt: skip
def test_a_bad_scene_file_names_the_object_and_the_field(tmp_path, objects, message):
    bad = tmp_path / "cell.json"
    bad.write_text(json.dumps({"objects": objects}))
    with pytest.raises(toolkit.InvalidParameterError, match=message) as info:
        Scene.load(bad)
    assert str(info.value).startswith(f"{bad}: scene objects[")
    with pytest.raises(toolkit.InvalidParameterError, match=r"unknown field\(s\) \['units'\]"):
        Scene.from_dict({"objects": [], "units": "mm"})


def test_the_documented_scene_file_loads_and_a_floor_takes_a_position(tmp_path):
    """The example of docs/collision.md's 'Scene files' reads as written; a floor's pose
    may be a position (its z is the height), as every other object's may."""
    text = Path(__file__).resolve().parents[2].joinpath("docs", "collision.md").read_text()
    example = text.split("### Scene files", 1)[1].split("```json", 1)[1].split("```", 1)[0]
    scene = Scene.from_dict(json.loads(example))
    assert [o.kind for o in scene.objects] == ["box", "sphere", "cylinder", "box"]
    assert scene.objects[0].support and scene.objects[3].link == "tool0"
    floor = Scene.from_dict({"objects": [{"name": "f", "kind": "floor", "pose": [0, 0, 0.1]}]})
    assert floor.objects[0].pose[11] == 0.1
    assert Scene.from_dict(Scene().add_floor(0.3).to_dict()).objects[0].pose[11] == 0.3


def test_the_floor_and_a_box_are_seen():
    robot = toolkit.load_example("ur5")
    q = robot.joints.neutral()
    assert not robot.in_collision(q, Scene().add_floor(-0.05))  # the base sits on it
    tip = robot.fk(q)[:3, 3]
    box = Scene().add_box("crate", [0.1, 0.1, 0.1], tip)
    assert robot.in_collision(q, box)
    pairs = robot.collision_checker(box).collisions(q)
    assert any("crate" in p for p in pairs)
    alone, _ = robot.collision_checker().min_distance(q)
    far, _ = robot.collision_checker(
        Scene().add_sphere("s", 0.05, tip + np.array([0, 0, 2.0]))
    ).min_distance(q)
    assert far == pytest.approx(alone)  # a far ball changes nothing
    near, pair = robot.collision_checker(
        Scene().add_sphere("s", 0.05, tip + np.array([0, 0, 0.07]))
    ).min_distance(q)
    assert near < alone and "s" in pair and near < 0.07


def _panda_cell() -> Scene:
    # the table starts 0.15 m in front of the base (at 0.05 m it cut 6 mm into panda_link0,
    # which the checker now tests: every configuration would collide)
    return (
        Scene()
        .add_floor(0.0)
        .add_box("table", [1.0, 1.2, 0.04], [0.65, 0.0, 0.10])
        .add_box("obstacle", [0.15, 0.15, 0.3], [0.45, 0.25, 0.27])
    )


def test_collision_free_ik_avoids_the_table_and_the_obstacle():
    robot = toolkit.load_example("panda")
    scene = _panda_cell()
    judge = Independent(robot)
    Q = robot.random_q(400, seed=13)
    free = Q[~robot.in_collision(Q, scene)][:40]
    targets = robot.fk(free)
    solved = 0
    for i, T in enumerate(targets):
        res = robot.ik(T, scene=scene, seed=i)
        if not res.success:
            continue
        solved += 1
        assert res.collision is None
        assert not judge.check(res.q)[0]  # no self-collision, by the independent route
        assert not robot.in_collision(res.q, scene)
    assert solved >= 0.9 * len(targets)


def test_a_failure_says_which_pair_collides():
    robot = toolkit.load_example("panda")
    q = robot.random_q(seed=3)
    T = robot.fk(q)
    wall = Scene().add_box("wall", [2.0, 2.0, 2.0], np.r_[T[:3, 3] + [0, 0, 1.1]])
    res = robot.ik(T[:3, 3], scene=wall, restarts=3)
    if not res.success:  # reached, but something hits the wall (or itself)
        assert res.collision is not None and res.position_error < 1e-6
    blocked = Scene().add_sphere("ball", 0.08, T[:3, 3])
    res = robot.ik(T, scene=blocked, restarts=20, tol=1e-5)
    assert not res.success and res.collision is not None and "ball" in res.collision
    with pytest.raises(toolkit.InvalidParameterError, match="collision_free=True"):
        robot.ik(T, scene=blocked, collision_free=False)


def test_a_description_without_collision_shapes_uses_its_visuals(tmp_path):
    text = toolkit.load("katana_6m180").urdf_path.read_text()
    bare = re.sub(r"<collision>.*?</collision>", "", text, flags=re.S)
    path = tmp_path / "bare.urdf"
    path.write_text(bare)
    robot = toolkit.load_urdf(path, tip="tool")
    with pytest.warns(toolkit.collision.CollisionGeometryWarning, match="visual"):
        flag = robot.in_collision(robot.joints.neutral())
    assert flag is False  # the pairs that touch at neutral are left out


def test_the_catalogue_gives_collision_shapes_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error", toolkit.collision.CollisionGeometryWarning)
        for name in ("katana_6m180", "katana_6m90a", "anthropomorphic", "scara", "bending"):
            robot = toolkit.load(name)
            q = np.clip(robot.joints.neutral(), robot.joints.lower, robot.joints.upper)
            assert not robot.in_collision(q), (name, robot.collision_checker().collisions(q))


def test_the_cli_takes_a_scene_and_says_what_collides(tmp_path, capsys):
    from toolkit.cli import main

    robot = toolkit.load_example("panda")
    T = robot.fk(robot.random_q(seed=3))
    path = tmp_path / "cell.json"
    Scene().add_sphere("ball", 0.08, T[:3, 3]).save(path)
    x, y, z = (f"{v:.6f}" for v in T[:3, 3])
    assert main(["ik", "panda", x, y, z, "--scene", str(path)]) == 1
    out = capsys.readouterr().out  # the ball at the target: the hand would be inside it
    assert "NOT solved" in out and "reached, but" in out and "hits ball" in out
    assert main(["ik", "panda", x, y, z, "--collision-free"]) == 0


def test_batch_checks_equal_single_checks_and_ik_batch_avoids_collisions():
    robot = toolkit.load_example("panda")
    scene = _panda_cell()
    Q = robot.random_q(300, seed=14)
    flags = robot.in_collision(Q, scene)  # over the cores (300 >= PARALLEL_MIN)
    assert flags.any() and not flags.all()
    assert flags.tolist() == [robot.in_collision(q, scene) for q in Q]
    free = Q[~flags][:60]
    targets = robot.fk(free)
    plain = robot.ik_batch(targets, seed=4)
    safe = robot.ik_batch(targets, seed=4, scene=scene)
    assert robot.in_collision(plain.q[plain.success], scene).any(), "the plain IK collides"
    assert not robot.in_collision(safe.q[safe.success], scene).any()
    assert safe.success.mean() >= 0.9
    judge = Independent(robot)
    assert not any(judge.check(q)[0] for q in safe.q[safe.success])
    # the batch's rounds of re-solves give each row the single solver's answer
    redone = np.flatnonzero(robot.in_collision(plain.q, scene) & plain.success)
    assert len(redone) >= 1
    redone = np.union1d(redone, np.arange(10))  # and rows that needed no re-solve
    for i in redone.tolist():
        one = robot.ik(targets[i], seed=4 + i, scene=scene)
        assert one.success == safe.success[i]
        assert np.allclose(one.q, safe.q[i], atol=1e-9)
    # rows that cannot be solved collision-free (a ball at the target) keep the single
    # solver's answer too: its first reached, colliding solution, success False
    blocked = scene.add_sphere("ball", 0.06, targets[0][:3, 3])
    stuck = robot.ik_batch(targets[:4], seed=4, scene=blocked, restarts=3)
    assert not stuck.success[0]
    for i in range(4):
        one = robot.ik(targets[i], seed=4 + i, scene=blocked, restarts=3)
        assert one.success == stuck.success[i]
        assert np.allclose(one.q, stuck.q[i], atol=1e-9)
        assert one.position_error == pytest.approx(stuck.position_error[i], abs=1e-12)


def test_the_katana_stands_on_its_floor():
    """The template's floor: every configuration with its tool below the floor is in
    collision without any scene, and the neutral configuration is free."""
    robot = toolkit.load("katana_6m180")
    assert not robot.in_collision(robot.joints.neutral())
    Q = robot.random_q(1500, seed=15)
    below = robot.fk(Q)[:, 2, 3] < 0.0
    assert below.sum() > 50
    assert robot.in_collision(Q[below]).all()
    hit = {
        name
        for q in Q[below][:20]
        for pair in robot.collision_checker().collisions(q)
        for name in pair
    }
    assert "floor" in hit


def test_ik_path_keeps_every_step_collision_free_or_names_the_first_that_is_not():
    robot = toolkit.load_example("panda")
    scene = _panda_cell()
    Q = robot.random_q(200, seed=16)
    free = Q[~robot.in_collision(Q, scene)]
    a, b = free[0], free[1]
    path = robot.fk(np.linspace(a, a + 0.2 * (b - a), 6))
    res = robot.ik_path(path, q0=a, scene=scene)
    assert res.all_succeeded and res.collision_step is None
    assert not robot.in_collision(res.q, scene).any()
    blocked = Scene().add_sphere("ball", 0.06, path[3][:3, 3])  # step 3's tool point
    stuck = robot.ik_path(path, q0=a, scene=blocked, restarts=2)
    k = stuck.collision_step
    assert k is not None and k <= 3 and not stuck.success[k]  # the hand would be in the ball
    assert stuck.success[:k].all() and not robot.in_collision(stuck.q[:k], blocked).any()
    assert robot.ik_path(path, q0=a).collision_step is None  # plain IK: no check


def test_disabled_pairs_are_computed_written_and_honoured(tmp_path):
    """The setup assistant's method on the Panda (its own SRDF set aside): the pairs that
    never collide in the samples are written as an SRDF, which a reload honours."""
    from toolkit.collision import disabled_pairs

    robot = toolkit.load_example("panda")
    path = tmp_path / "panda.srdf"
    found = disabled_pairs(robot, 400, seed=1, srdf=path)
    never = {frozenset((a, b)) for a, b, why in found if why == "Never"}
    assert len(never) >= 10
    bare = toolkit.load_urdf(robot.urdf_path, tip=robot.tip, mimic=False)  # no SRDF: all pairs
    Q = bare.random_q(400, seed=1)
    hit = {frozenset(p) for q in Q for p in bare.collision_checker().collisions(q)}
    assert hit and not (hit & never), "a pair called Never collided in the same samples"
    reloaded = toolkit.load_urdf(robot.urdf_path, tip=robot.tip, mimic=False, srdf=path)
    for q in bare.random_q(300, seed=2):
        assert not {frozenset(p) for p in reloaded.collision_checker().collisions(q)} & never
    with pytest.raises(toolkit.InvalidParameterError, match="srdf"):
        toolkit.load_urdf(robot.urdf_path, srdf=tmp_path / "missing.srdf")


@pytest.mark.parametrize(("name", "share"), [("panda", 0.5), ("ur5", 0.5), ("katana_6m180", 0.3)])
def test_the_prefilter_never_changes_an_answer(name, share):
    """The compiled bounding volumes clear only configurations that coal, pair by pair
    on an independently built model, also finds free; the batch answer equals coal's."""
    robot = toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)
    checker = toolkit.robot.checker_for(robot, None)
    Q = robot.random_q(3000, seed=21)
    state = checker.bounds.decide(Q)
    cleared, hits = state == 1, state == 2
    exact = checker._exact_many(Q)
    assert not (cleared & exact).any() and exact[hits].all()
    assert np.array_equal(robot.in_collision(Q), exact)
    assert (cleared | hits).mean() > share, (cleared.mean(), hits.mean())
    judge = Independent(robot)
    for q in Q[cleared][:150]:
        hit, closest = judge.check(q)
        assert not hit and closest > 0
    for q in Q[hits][:50]:
        hit, closest = judge.check(q)
        assert hit and closest < 0


def test_the_sphere_covers_clear_more_and_only_what_coal_finds_free():
    """The pre-filter's second test (each shape's sphere cover against the other's box):
    on the Panda in a cell, the configurations it clears beyond the boxes' are free for
    coal (the checker's exact pass), free of self-collision pair by pair on an
    independently built model too, and there are some."""
    robot = toolkit.load_example("panda")
    scene = _panda_cell()
    checker = toolkit.robot.checker_for(robot, scene)
    Q = robot.random_q(3000, seed=23)
    bounds = checker.bounds
    covered = bounds.decide(Q)
    n = len(bounds.row)
    empty = (np.zeros(n + 1, np.int64), np.zeros((0, 4)), np.zeros((n, 4)),
             np.zeros(1, np.int64), np.zeros((0, 3)))  # fmt: skip
    bounds._covers, kept = empty, bounds._covers
    try:
        boxes = bounds.decide(Q)
    finally:
        bounds._covers = kept
    more = (covered == 1) & (boxes != 1)
    assert more.sum() >= 30, more.sum()
    assert not ((boxes == 1) & (covered != 1)).any()  # the covers only add
    assert not checker._exact_many(Q[more]).any()
    judge = Independent(robot)
    for q in Q[more][:40]:
        hit, closest = judge.check(q)
        assert not hit and closest > 0


def test_the_prefilter_with_a_scene_and_an_attached_tool():
    robot = toolkit.load_example("panda")
    scene = _panda_cell().attach("tool", "panda_hand", "cylinder", [0.02, 0.15], [0, 0, 0.1])
    checker = toolkit.robot.checker_for(robot, scene)
    Q = robot.random_q(3000, seed=22)
    state = checker.bounds.decide(Q)
    exact = checker._exact_many(Q)
    assert exact.any() and (state == 1).any() and (state == 2).any()
    assert not ((state == 1) & exact).any() and exact[state == 2].all()
    assert np.array_equal(robot.in_collision(Q, scene), exact)


def test_checkers_of_one_robot_share_its_shapes_and_never_each_others_scenes(monkeypatch):
    """The robot's shapes are read and its pairs worked out once (a new scene then costs
    its own objects only); each checker adds its scene to a copy, so neither the robot's
    kept shapes nor another scene's checker sees them."""
    from toolkit.collision import checker as module

    calls = []
    real = module.robot_geometry
    monkeypatch.setattr(module, "robot_geometry", lambda r: calls.append(r.name) or real(r))
    panda = toolkit.load_example("panda")
    q = panda.joints.neutral()
    near = panda.fk(q, "panda_hand")[:3, 3]
    hit = Scene().add_box("on the hand", [0.05, 0.05, 0.05], near)
    away = Scene().add_box("far away", [0.05, 0.05, 0.05], [3.0, 0, 0])
    a, b = panda.collision_checker(hit), panda.collision_checker(away)
    assert calls == ["panda"]  # read once for both scenes
    assert a.in_collision(q) and not b.in_collision(q)
    assert "on the hand" in a.names and "on the hand" not in b.names
    again = panda.collision_checker(Scene())
    assert again.geom.ngeoms == again.robot_count == b.robot_count  # the kept shapes clean
    assert not again.in_collision(q) and calls == ["panda"]
    assert len(a.geom.collisionPairs) > len(again.geom.collisionPairs)
