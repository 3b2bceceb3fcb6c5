"""Every path a plan returns is certified over its whole motion, whichever search found it:
the exact shapes' certificate (toolkit.planning.sweep.ExactSweep, conservative advancement
on coal's distances) against samples that miss an obstacle between them, and MoveIt inputs
as MotionBenchMaker writes them (start states naming joints the description fixes or lacks,
values a hair outside a limit, scene files that are not scenes)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

import toolkit
from toolkit import planning
from toolkit.planning import certain
from toolkit.planning.edges import EdgeChecker
from toolkit.planning.sweep import ExactSweep
from toolkit.robot import checker_for
from toolkit.robot.plans import certain_test

from .test_planning import UR5, WALL, dense
from .test_planning import A as WALL_A
from .test_planning import B as WALL_B

# the shoulder turns 0.5 rad: the tool sweeps an arc through a 6 cm cube half way, which
# checks 0.5 rad apart (the coarsest resolution a plan takes) never see
A = np.array([-0.25, -1.2, 1.6, -1.9, -1.57, 0.0])
B = np.array([0.25, -1.2, 1.6, -1.9, -1.57, 0.0])


def _cube_on_the_arc() -> toolkit.Scene:
    middle = UR5.fk((A + B) / 2, "tool0")[:3, 3]
    return toolkit.Scene().add_box("cube", [0.06, 0.06, 0.06], middle)


CUBE = _cube_on_the_arc()


def _sweep(scene: toolkit.Scene) -> ExactSweep:
    checker = checker_for(UR5, scene)
    test = certain_test(UR5, checker)
    assert test is not None and test.sweeps
    return ExactSweep(checker, test, UR5.joints.q_from_angles)


def _collides_densely(a: np.ndarray, b: np.ndarray, scene: toolkit.Scene) -> bool:
    checker = UR5.collision_checker(scene)
    return any(checker.collisions(q) for q in dense(np.stack([a, b]), math.radians(0.05)))


def test_the_samples_miss_the_cube_and_the_certificate_does_not():
    checker = checker_for(UR5, CUBE)
    collides = lambda Q: np.asarray(checker.in_collision_many(Q), dtype=bool)  # noqa: E731
    assert EdgeChecker(collides, 0.5).free(A, B)  # the premise: both samples are free
    assert _collides_densely(A, B, CUBE)
    sweep = _sweep(CUBE)
    assert not sweep(A, B)
    assert sweep.checks > 0


def test_the_certificate_passes_free_motions_and_never_a_colliding_one():
    sweep = _sweep(CUBE)
    rng = np.random.default_rng(5)
    passed = refused = 0
    for _ in range(12):
        a = A + rng.normal(0.0, 0.3, 6)
        b = a + rng.normal(0.0, 0.2, 6)
        if UR5.in_collision(a, CUBE) or UR5.in_collision(b, CUBE):
            continue
        if sweep(a, b):
            passed += 1
            assert not _collides_densely(a, b, CUBE)
        else:
            refused += 1
    assert passed >= 3  # it certifies motions, not only refuses them
    far = toolkit.Scene().add_box("far", [0.1, 0.1, 0.1], [2.0, 2.0, 2.0])
    assert _sweep(far)(A, B)  # nothing near: the whole arc in a few steps
    del refused


def test_a_path_from_the_exact_search_is_certified_whole(monkeypatch):
    """The covers' search finds nothing (forced): the exact search checks its edges 0.5 rad
    apart, so its first straight line runs through the cube between two checks; that line
    must not come back (round five returned it, ``swept`` False)."""
    monkeypatch.setattr(planning, "search", lambda *a, **k: (None, -1, 0, 0))
    result = UR5.plan(A, B, scene=CUBE, seed=1, resolution=0.5, time_limit=20.0)
    assert result.success, result.reason
    assert result.search == "exact" and result.certificate == "exact" and result.swept
    for a, b in zip(result.path[:-1], result.path[1:], strict=True):
        assert not _collides_densely(a, b, CUBE)


def test_an_escape_segment_the_certificate_refuses_is_not_returned(monkeypatch):
    """An end the covers do not clear is left by a short straight segment: round five
    checked it at samples only and called the path certified. Here every escape is made to
    run through the cube (checked at its two ends), and the plan must not return it."""
    real_free = certain.CertainTest.free

    def goal_not_cleared(self, V):  # the covers never pass B
        out = real_free(self, V)
        out[np.all(np.isclose(V, UR5.joints.angles(B)), axis=1)] = False
        return out

    def through_the_cube(test, edges, end, bounds, rng, deadline, settings):
        return UR5.joints.angles(A) if np.allclose(end, UR5.joints.angles(B)) else None

    monkeypatch.setattr(certain.CertainTest, "free", goal_not_cleared)
    monkeypatch.setattr(planning, "escape", through_the_cube)
    result = UR5.plan(A, B, scene=CUBE, seed=2, resolution=0.5, time_limit=20.0)
    if result.success:  # found another way, on the exact shapes
        assert result.certificate in ("exact", "covers+exact")
        for a, b in zip(result.path[:-1], result.path[1:], strict=True):
            assert not _collides_densely(a, b, CUBE)


def test_every_path_says_how_it_was_certified():
    for seed in range(3):
        result = UR5.plan(WALL_A, WALL_B, scene=WALL, seed=seed)
        assert result.success, result.reason
        assert result.swept and result.certificate in ("covers", "covers+exact", "exact")


# ---------------------------------------------------------------- MoveIt inputs
def _request(tmp_path, start_names, start_values, goal):
    data = {
        "start_state": {"joint_state": {"name": start_names, "position": start_values}},
        "goal_constraints": [{"joint_constraints": [
            {"joint_name": n, "position": float(v)} for n, v in zip(UR5.joints.names, goal,
                                                                    strict=True)]}],
        "group_name": "manipulator",
    }  # fmt: skip
    path = tmp_path / "request.yaml"
    path.write_text(yaml.safe_dump(data))
    return planning.read_request(path)


def test_a_start_state_may_name_joints_the_description_fixes_or_lacks(tmp_path):
    names = [*UR5.joints.names, "ee_fixed_joint", "l_wheel_joint"]  # fixed in UR5; absent
    request = _request(tmp_path, names, [*A.tolist(), 0.3, 1.0], B)
    assert request.ignored(UR5) == ["ee_fixed_joint", "l_wheel_joint"]
    np.testing.assert_array_equal(request.start_q(UR5), A)
    result = request.plan(UR5, CUBE, seed=1)
    assert result.success and result.ignored == ("ee_fixed_joint", "l_wheel_joint")


def test_a_goal_still_may_not_name_a_joint_that_does_not_move(tmp_path):
    request = _request(tmp_path, UR5.joints.names, A.tolist(), B)
    bad = planning.MotionRequest(request.start, ({"ee_fixed_joint": 0.0},))
    with pytest.raises(toolkit.InvalidParameterError, match="ee_fixed_joint"):
        bad.goal_q(UR5)


def test_values_a_hair_outside_a_limit_are_put_on_it_and_farther_ones_named():
    edge = B.copy()
    edge[0] = 2 * math.pi + 2.7e-6  # the limit is 2 pi: a file's rounding past it
    result = UR5.plan(A, edge, seed=1)
    assert result.success, result.reason
    assert result.path[-1][0] == UR5.joints.upper[0]  # on the limit the description gives
    far = B.copy()
    far[0] = 2 * math.pi + 1e-3
    with pytest.raises(
        toolkit.ConfigurationError, match=r"joint 'shoulder_pan_joint' is 6.28419 rad, outside"
    ):
        UR5.plan(A, far)


@pytest.mark.parametrize(
    "text", ["::: not yaml [[[", "name: a scene without objects\nrobot_model_name: ur5\n"]
)
def test_a_file_that_is_not_a_planning_scene_is_refused(tmp_path, text):
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    with pytest.raises(toolkit.InvalidParameterError, match="no MoveIt planning scene"):
        planning.read_scene(path)


def test_planning_scene_world_is_read_as_world(tmp_path):
    pose = {"position": [0.5, 0.0, 0.2], "orientation": [0, 0, 0, 1]}
    box = {"id": "crate", "operation": 0, "primitive_poses": [pose],
           "primitives": [{"type": "box", "dimensions": [0.1, 0.2, 0.3]}]}  # fmt: skip
    for key in ("world", "planning_scene_world"):
        path = tmp_path / f"{key}.yaml"
        path.write_text(yaml.safe_dump({key: {"collision_objects": [box]}}))
        scene = planning.read_scene(path)
        assert len(scene) == 1
    empty = tmp_path / "empty.yaml"
    empty.write_text(yaml.safe_dump({"world": {"collision_objects": []}}))
    assert len(planning.read_scene(empty)) == 0  # a scene with nothing in it is a scene


# ---------------------------------------------------------------- deferred pairs
def _all_own_pairs(robot, checker):
    bounds = checker.bounds
    count = checker.robot_count
    return np.flatnonzero((bounds.first < count) & (bounds.second < count))


def test_pairs_left_out_of_the_search_are_certified_after_it(monkeypatch):
    """Every pair of the robot's own shapes left out of the compiled search (as the covers
    of MotionBenchMaker's Panda, 2 cm apart between link 5 and link 7, cannot prove them
    apart): the plan still never returns a self-collision, and a start that collides on
    one is refused by coal."""
    from toolkit.robot import plans

    monkeypatch.setattr(plans, "deferred_pairs", _all_own_pairs)
    ur5 = toolkit.load_example("ur5")  # a robot of its own: nothing kept from other tests
    test = certain_test(ur5, checker_for(ur5, WALL))
    assert test is not None and test.deferred.size > 0
    assert len(test.packed.first) + test.deferred.size == len(checker_for(ur5, WALL).bounds.first)
    result = ur5.plan(WALL_A, WALL_B, scene=WALL, seed=1)
    assert result.success and result.certificate == "covers+exact", result.reason
    for a, b in zip(result.path[:-1], result.path[1:], strict=True):
        assert not _collides_densely(a, b, WALL)
    folded = np.array([0.0, -1.0, math.pi, -1.9, -1.57, 0.0])  # the wrist in the base
    assert ur5.collision_checker(WALL).first_collision(folded) is not None
    with pytest.raises(toolkit.InvalidParameterError, match="start collides"):
        ur5.plan(folded, WALL_B, scene=WALL)


def test_an_end_only_own_pairs_keep_from_the_covers_is_planned_on_the_covers():
    """A start the bounds leave undecided by the robot's own pairs alone (free on coal): those
    pairs are left out of the covers' search and certified after it, so the plan does not
    go to the exact search (Baxter's goals with the elbows 2 cm from the torso)."""
    from toolkit.robot.deferral import end_pairs

    ur5 = toolkit.load_example("ur5")
    checker = checker_for(ur5, WALL)
    bounds, count = checker.bounds, checker.robot_count
    test = certain_test(ur5, checker)
    Q = ur5.random_q(4000, seed=11)
    state, listed = bounds.decide_pairs(Q)
    picked = None
    for q, st, row in zip(Q, state, listed, strict=True):
        pairs = row[1 : 1 + row[0]]
        own = (bounds.first[pairs] < count) & (bounds.second[pairs] < count)
        new = not set(pairs.tolist()) <= set(test.deferred.tolist())
        if st == 0 and 0 < row[0] < listed.shape[1] and own.all() and new:
            if checker.first_collision(q) is None:
                picked = q
                break
    assert picked is not None  # such configurations exist on the UR5
    extra = end_pairs(checker, test.deferred, picked[None])
    assert extra.size and not test.free(ur5.joints.angles(picked[None]))[0]
    goal = picked + np.array([0.5, 0.0, 0.0, 0.0, 0.0, 0.0])  # the arm turned as a whole
    assert checker.first_collision(goal) is None
    result = ur5.plan(picked, goal, scene=WALL, seed=1)
    assert result.success and result.search == "covers", result.reason
    assert result.certificate == "covers+exact" and result.escapes == 0  # no escape needed
    for a, b in zip(result.path[:-1], result.path[1:], strict=True):
        assert not _collides_densely(a, b, WALL)
