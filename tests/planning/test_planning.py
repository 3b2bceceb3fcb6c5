"""Collision-free planning (toolkit.planning, Robot.plan): paths checked again here,
configuration by configuration at a finer step, by the checker's single-configuration
route (coal on every pair, without the batch's pre-filter)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit.planning import RESOLUTION, PlannerSettings
from toolkit.planning.edges import EdgeChecker

UR5 = toolkit.load_example("ur5")
WALL = toolkit.Scene().add_box("wall", [0.1, 1.2, 0.8], [0.45, 0.0, 0.4]).add_floor(-0.01)
A = np.array([-1.4, -1.0, 1.5, -1.9, -1.57, 0.0])
B = np.array([1.4, -1.0, 1.5, -1.9, -1.57, 0.0])


def dense(path: np.ndarray, step: float) -> np.ndarray:
    """Every configuration of a path's straight segments, joints at most ``step`` apart."""
    out = [path[0]]
    for p, q in itertools.pairwise(path):
        k = max(1, math.ceil(float(np.abs(q - p).max()) / step))
        out += [p + (q - p) * t for t in np.arange(1, k + 1) / k]
    return np.array(out)


def free_everywhere(robot: toolkit.Robot, path: np.ndarray, scene: toolkit.Scene) -> bool:
    return all(
        not robot.collision_checker(scene).collisions(q) for q in dense(path, math.radians(0.25))
    )


def test_a_path_around_a_wall_is_free_at_a_quarter_degree_and_ends_where_asked():
    assert UR5.in_collision(np.linspace(A, B, 60), WALL).any()  # the straight line hits it
    result = UR5.plan(A, B, scene=WALL, seed=1)
    assert result.success and result.verified and result.goal == 0, result.reason
    np.testing.assert_array_equal(result.path[0], A)
    np.testing.assert_array_equal(result.path[-1], B)
    assert len(result.path) >= 3 and result.checks > 0 and result.nodes >= 2
    assert free_everywhere(UR5, result.path, WALL)
    assert result.length >= np.linalg.norm(B - A)
    np.testing.assert_allclose(UR5.joints.q_from_angles(result.values), result.path, atol=1e-15)


def test_the_same_seed_gives_the_same_plan_and_another_seed_another():
    one, again = UR5.plan(A, B, scene=WALL, seed=4), UR5.plan(A, B, scene=WALL, seed=4)
    np.testing.assert_array_equal(one.path, again.path)
    other = UR5.plan(A, B, scene=WALL, seed=5)
    assert other.success and not np.array_equal(one.path, other.path)


def test_a_free_straight_line_is_the_plan():
    result = UR5.plan(A, A + 0.3, seed=0)
    assert result.success and len(result.path) == 2 and result.nodes == 2


def test_several_goals_reach_one_of_them():
    blocked = np.array([0.0, -1.0, 1.5, -1.9, -1.57, 0.0])  # inside the wall
    result = UR5.plan(A, np.array([blocked, B]), scene=WALL, seed=2)
    assert result.success and len(result.goals) == 1  # the blocked goal left out
    np.testing.assert_array_equal(result.path[-1], result.goals[result.goal])


def test_a_tool_pose_goal_is_every_free_branch_and_the_path_ends_on_the_pose():
    T = UR5.fk(B)
    result = UR5.plan(A, pose=T, scene=WALL, seed=3)
    assert result.success, result.reason
    np.testing.assert_allclose(UR5.fk(result.path[-1]), T, atol=1e-9)
    branches = UR5.ik_all(T)
    assert 1 <= len(result.goals) <= int(branches.success.sum())
    assert not UR5.in_collision(result.goals, WALL).any()
    assert free_everywhere(UR5, result.path, WALL)


def test_an_arm_without_structure_plans_to_a_pose_by_numeric_goals():
    panda = toolkit.load_example("panda")
    Q = panda.random_q(40, seed=11)
    q0, q1 = Q[~np.asarray(panda.in_collision(Q), dtype=bool)][:2]
    result = panda.plan(q0, pose=panda.fk(q1), seed=0, time_limit=20)
    assert result.success, result.reason
    np.testing.assert_allclose(panda.fk(result.path[-1]), panda.fk(q1), atol=1e-5)
    assert free_everywhere(panda, result.path, toolkit.Scene())


def test_no_path_within_the_time_says_so():
    result = UR5.plan(A, B, scene=WALL, time_limit=1e-6)
    assert not result.success and not result.verified and result.goal == -1
    assert result.path.shape == (0, 6) and "no path found within" in result.reason


def test_the_time_limit_covers_the_whole_call_but_compiling(monkeypatch):
    """The search gets what is left of ``time_limit`` after the checker and the ends were
    built; the compiler's seconds are not counted; nothing left: no search, and the reason
    names the set-up's share."""
    from toolkit.robot import plans

    asked: list[float] = []
    real = plans.plan_values

    def spy(*args, **kwargs):
        asked.append(kwargs["time_limit"])
        return real(*args, **kwargs)

    monkeypatch.setattr(plans, "plan_values", spy)
    monkeypatch.setattr(plans, "_spent", lambda clock: 0.25)
    result = UR5.plan(A, B, scene=WALL, time_limit=2.0, seed=0)
    assert asked == [1.75] and result.success and result.time_s == 0.25

    UR5.collision_checker(WALL)  # built: the clock is not asked while building it
    monkeypatch.setattr(plans, "_spent", lambda clock: 3.0)
    asked.clear()
    late = UR5.plan(A, B, scene=WALL, time_limit=2.0, seed=0)
    assert asked == [] and not late.success and late.path.shape == (0, 6)
    assert "the scene, start and goals took 3 s of it" in late.reason

    monkeypatch.undo()
    began = plans.time.perf_counter() - 5.0  # 5 s ago, 2 s of them compiling
    monkeypatch.setattr(plans, "compile_seconds", lambda: 9.0)
    assert plans._spent((began, 7.0)) == pytest.approx(3.0, abs=0.5)


def test_the_compilers_seconds_are_counted_and_its_first_use_said_once(caplog):
    """Every numba compile adds to ``compile_seconds`` (loading from the cache is not
    compiling); the first toolkit kernel's compile is said once on ``toolkit.compile``."""
    import logging

    import numba

    from toolkit.kinematics import compile_seconds, compiler

    before = compile_seconds()
    numba.njit(lambda x: x + 1.5)(1.0)  # compiled, never cached
    assert compile_seconds() > before
    clock = compiler._CompileClock()

    class Event:
        def __init__(self, module):
            func = type("F", (), {"__module__": module})
            self.data = {"dispatcher": type("D", (), {"py_func": func})}

    with caplog.at_level(logging.WARNING, logger="toolkit.compile"):
        for module in ("mine", "toolkit.planning.kernels", "toolkit.ik.checks"):
            clock.on_start(Event(module))
            clock.on_end(Event(module))
    said = [r.getMessage() for r in caplog.records if r.name == "toolkit.compile"]
    assert len(said) == 1 and "waits for the compiler" in said[0] and "warmup" in said[0]
    assert clock.depth == 0 and clock.total >= 0.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"start": B * 0 + [0.0, -1.0, 1.5, -1.9, -1.57, 0.0], "goal": B}, "start collides"),
        ({"start": A, "goal": [0.0, -1.0, 1.5, -1.9, -1.57, 0.0]}, "goal 0 collides"),
        (
            {"start": A, "goal": [9.0, 0, 0, 0, 0, 0]},
            r"goal \(configuration 0\): joint 'shoulder_pan_joint' is 9 rad, outside its limits "
            r"\[-6.28319, 6.28319\] rad",
        ),
        ({"start": [0, -1, 1, 0, 0, 7.0], "goal": B}, r"start: joint 'wrist_3_joint' is 7 rad"),
        ({"start": A}, "one of them"),
        ({"start": A, "goal": B, "pose": np.eye(4)}, "one of them"),
        ({"start": A, "goal": B, "time_limit": 0}, "time_limit"),
        ({"start": A, "goal": B, "resolution": 0.0}, "resolution"),
        ({"start": A, "goal": B, "resolution": 1.0}, "resolution"),
        ({"start": A, "goal": B, "seed": -1}, "seed"),
        ({"start": A, "goal": B, "simplify": "yes"}, "simplify"),
        ({"start": A, "pose": np.zeros((2, 3))}, "pose"),
        ({"start": A, "pose": np.diag([1.0, 1, 1, 1]) + np.eye(4, k=3) * 5}, "reaches the pose"),
        ({"start": [np.nan] * 6, "goal": B}, "NaN"),
        ({"start": A, "goal": np.zeros((0, 6))}, "no configuration"),
    ],
)
def test_bad_plans_are_refused_naming_the_problem(kwargs, message):
    with pytest.raises(toolkit.ToolkitError, match=message):
        UR5.plan(scene=WALL, **kwargs)


def test_unlimited_and_continuous_joints_are_sampled_within_one_turn():
    from toolkit.planning import value_bounds

    kinova = toolkit.load_example("kinova")
    lo, hi = value_bounds(kinova)
    continuous = [j.nq == 2 for j in kinova.model.joints[1:]]
    assert any(continuous)
    for c, low, up in zip(continuous, lo, hi, strict=True):
        assert (low, up) == ((-math.pi, math.pi) if c else (low, up)) and low < up


@settings(max_examples=60, deadline=None)
@given(
    a=st.lists(st.floats(-3, 3), min_size=3, max_size=3),
    b=st.lists(st.floats(-3, 3), min_size=3, max_size=3),
    resolution=st.floats(1e-3, 0.5),
)
def test_an_edge_is_checked_at_steps_no_longer_than_the_resolution(a, b, resolution):
    seen: list[np.ndarray] = []

    def collides(P: np.ndarray) -> np.ndarray:
        seen.extend(P)
        return np.zeros(len(P), dtype=bool)

    edges = EdgeChecker(collides, resolution)
    A3, B3 = np.array(a), np.array(b)
    assert edges.free(A3, B3)
    P = np.array([A3, *sorted(seen, key=lambda p: float(np.abs(p - A3).max()))])
    assert np.abs(np.diff(P, axis=0)).max() <= resolution * (1 + 1e-12) + 1e-15
    np.testing.assert_array_equal(seen[0], B3)  # the end first
    assert edges.checks == len(seen) == max(1, math.ceil(np.abs(B3 - A3).max() / resolution))


def test_a_blocked_end_stops_the_edge_after_one_check():
    calls: list[int] = []

    def collides(P: np.ndarray) -> np.ndarray:
        calls.append(len(P))
        return np.ones(len(P), dtype=bool)

    edges = EdgeChecker(collides, RESOLUTION)
    assert not edges.free(np.zeros(2), np.ones(2))
    assert calls == [1] and edges.checks == 1


def test_held_fingers_stay_at_their_start_all_along():
    panda = toolkit.load_example("panda")
    Q = panda.random_q(40, seed=21)
    q0, q1 = Q[~np.asarray(panda.in_collision(Q), dtype=bool)][:2]
    fingers = ["panda_finger_joint1", "panda_finger_joint2"]
    cols = [panda.model.joints[panda.model.getJointId(n)].idx_q for n in fingers]
    q1[cols] = q0[cols]
    result = panda.plan(q0, q1, hold=fingers, seed=1)
    assert result.success, result.reason
    np.testing.assert_array_equal(result.path[:, cols], np.tile(q0[cols], (len(result.path), 1)))
    to_pose = panda.plan(q0, pose=panda.fk(q1), hold=fingers, seed=1, time_limit=20)
    assert to_pose.success and (to_pose.path[:, cols] == q0[cols]).all()
    moved = q1.copy()
    moved[cols[0]] = q0[cols[0]] / 2 + 0.001
    with pytest.raises(toolkit.InvalidParameterError, match="moves a held joint"):
        panda.plan(q0, moved, hold=fingers)
    with pytest.raises(toolkit.InvalidParameterError, match="no joint 'thumb'"):
        panda.plan(q0, q1, hold=["thumb"])


@pytest.mark.parametrize("pool", ["fork", "threads"])
def test_many_problems_on_workers_plan_as_they_do_one_by_one(pool):
    """``plan_many``: pairs, mappings and requests in one list; on 3 forked workers or
    threads the same plans (bit for bit) as one by one with seed + i; each path free at a
    quarter degree; a refused problem named by its index."""
    from toolkit import planning

    rng = np.random.default_rng(3)
    pairs = []
    while len(pairs) < 6:
        a, b = A.copy(), B.copy()
        a[0], b[0] = rng.uniform(-2.2, -1.0), rng.uniform(1.0, 2.2)
        if not UR5.in_collision(a, WALL) and not UR5.in_collision(b, WALL):
            pairs.append((a, b))
    problems = [*pairs[:4], {"start": pairs[4][0], "goal": pairs[4][1], "seed": 99},
                planning.MotionRequest(start=dict(zip(UR5.joints.names, pairs[5][0], strict=True)),
                                       joint_goals=(dict(zip(UR5.joints.names, pairs[5][1],
                                                             strict=True)),))]  # fmt: skip
    threaded = planning.plan_many(UR5, problems, scene=WALL, workers=3, seed=7, time_limit=5.0,
                                  pool=pool)  # fmt: skip
    for i, result in enumerate(threaded):
        seed = 99 if i == 4 else 7 + i
        alone = UR5.plan(*pairs[i], scene=WALL, seed=seed, time_limit=5.0)
        assert result.success and free_everywhere(UR5, result.path, WALL)
        np.testing.assert_array_equal(result.path, alone.path)
    with pytest.raises(toolkit.InvalidParameterError, match="problem 1: start collides"):
        planning.plan_many(UR5, [pairs[0], (np.zeros(6), B)], scene=WALL, workers=2,
                           pool=pool)  # fmt: skip
    with pytest.raises(toolkit.InvalidParameterError, match="a problem is a MotionRequest"):
        planning.plan_many(UR5, ["not a problem"])
    with pytest.raises(toolkit.InvalidParameterError, match="pool"):
        planning.plan_many(UR5, pairs[:2], pool="processes")


@pytest.mark.slow  # a fresh interpreter that plans, then forks: ~25 s
def test_forked_workers_do_not_wait_for_a_lock_their_parent_held(tmp_path):
    """A robot's locks and the planner's module lock held (by another thread, say) while
    ``plan_many`` forks: each child makes them anew, so its cached queries do not wait for
    ever (run in a subprocess with a time limit: a hang fails the test)."""
    import subprocess
    import sys

    code = (
        "import numpy as np, toolkit\n"
        "from toolkit import planning\n"
        "ur5 = toolkit.load_example('ur5')\n"
        "wall = toolkit.Scene().add_box('wall', [0.1, 1.2, 0.8], [0.45, 0.0, 0.4])\n"
        "a = np.array([-1.4, -1.0, 1.5, -1.9, -1.57, 0.0])\n"
        "b = np.array([1.4, -1.0, 1.5, -1.9, -1.57, 0.0])\n"
        "ur5.plan(a, b, scene=wall)\n"
        "ur5._caches.lock.acquire()\n"
        "ur5._analytic.caches.lock.acquire()\n"
        "from toolkit.robot import plans\n"
        "plans._TESTS_LOCK.acquire()  # the module's lock of kept tests too\n"
        "res = planning.plan_many(ur5, [(a, b), (b, a)], scene=wall, workers=2)\n"
        "print(all(r.success for r in res))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().endswith("True")


def test_a_problem_refused_by_an_error_of_its_own_kind_is_named_with_its_kind():
    """An error whose constructor takes more than a message (an unknown frame) keeps its
    kind and gains the problem's index in ``plan_many``."""
    from toolkit import planning

    problems = [{"start": A, "pose": UR5.fk(B), "frame": "no such frame"}]
    with pytest.raises(toolkit.FrameNotFoundError, match="problem 0: unknown frame"):
        planning.plan_many(UR5, problems, scene=WALL, workers=1)


def test_an_error_in_a_forked_worker_reaches_the_caller_intact():
    """An unknown frame in a problem planned by a forked worker: the caller gets the same
    error (its kind, message with the index, and attributes), not a broken pool; every
    toolkit error pickles whatever its constructor takes."""
    import pickle

    from toolkit import planning

    for error in (toolkit.FrameNotFoundError("f", ["a", "b"], "arm"),
                  toolkit.UnknownModelError("m", ["x"]),
                  toolkit.ConvergenceError("did not converge", 0.5)):  # fmt: skip
        back = pickle.loads(pickle.dumps(error))
        assert type(back) is type(error) and str(back) == str(error)
        assert back.__dict__ == error.__dict__
    problems = [(A, B), {"start": A, "pose": UR5.fk(B), "frame": "no such frame"}]
    with pytest.raises(toolkit.FrameNotFoundError, match="problem 1: unknown frame") as info:
        planning.plan_many(UR5, problems, scene=WALL, workers=2)
    assert info.value.name == "no such frame"


def test_the_exact_search_follows_the_compiled_ones_balance_and_domains(monkeypatch):
    """The Python RRT-Connect (the search on the exact shapes) on a plane with a wall and a
    gap: a tree is extended twice in a row only while it is at most half the other; a
    blocked extension gives its node the domain's radius, and a sample beyond a node's
    radius is not tried (no configuration checked)."""
    from toolkit.planning import trees

    def collides(P: np.ndarray) -> np.ndarray:  # x in (1.4, 1.6) blocked but for y > 2.5
        return (np.abs(P[:, 0] - 1.5) < 0.1) & (P[:, 1] < 2.5)

    edges = EdgeChecker(collides, 0.01)
    extended: list[tuple[int, int, int]] = []  # (the tree extended, the two trees' sizes)
    real = trees._extend

    def spy(tree, target, edges, step, domain):
        extended.append((0 if tree is seen[0] else 1, seen[0].size, seen[1].size))
        return real(tree, target, edges, step, domain)

    seen: list[trees.Tree] = []
    made = trees.Tree

    def tree(roots):
        seen.append(made(roots))
        return seen[-1]

    monkeypatch.setattr(trees, "Tree", tree)
    monkeypatch.setattr(trees, "_extend", spy)
    goals = np.array([[3.0, 0.0], [3.0, 0.2], [3.0, 0.4], [3.0, 0.6], [3.0, 0.8]])
    path, _, _ = trees.rrt_connect(np.zeros(2), goals, (np.zeros(2), np.full(2, 3.0)), edges,
                                   np.random.default_rng(3), math.inf,
                                   PlannerSettings(max_edge=0.3))  # fmt: skip
    assert path is not None and not collides(dense(path, 0.005)).any()
    again = [i for i in range(1, len(extended)) if extended[i][0] == extended[i - 1][0]]
    assert again, "no tree was extended twice in a row"
    for (last, *_), (now, *size) in itertools.pairwise(extended):  # the same tree again
        assert (now == last) == (2 * size[last] <= size[1 - last])  # iff at most half the other
    node = made(np.array([[1.3, 1.0]]))
    domain = PlannerSettings().domain
    assert real(node, np.array([1.7, 1.0]), edges, 0.3, domain) is None
    assert node.radius[0] == domain[0]
    before = edges.checks
    assert real(node, np.array([1.3, 1.0 + 4.5]), edges, 0.3, domain) is None  # beyond 4 rad
    assert edges.checks == before and node.size == 1
    assert real(node, np.array([1.0, 1.0]), edges, 0.3, domain) is not None  # within: tried
    assert edges.checks > before
    assert node.radius[0] == pytest.approx(domain[0] * (1 + domain[2]))


@pytest.mark.parametrize(("robot", "joints"), [("panda", 7), ("ur5", 6)])
def test_the_example_moveit_files_plan_from_the_command_line(robot, joints, tmp_path, capsys):
    """docs/examples' scene and request of each robot, as docs/planning.md runs them: the
    straight line between the request's start and goal collides, the command plans around
    it and writes a trajectory of the group's joints (the Panda's arm: 7, no fingers)."""
    from pathlib import Path

    from toolkit import planning
    from toolkit.cli import main

    folder = Path(__file__).resolve().parents[2] / "docs" / "examples"
    scene_file, request_file = folder / f"{robot}_scene.yaml", folder / f"{robot}_request.yaml"
    model = toolkit.load_example(robot)
    request = planning.read_request(request_file)
    group = request.robot_for(model)
    scene = planning.read_scene(scene_file, frames=planning.fixed_frames(model))
    ends = group.joints.angles(np.array([request.start_q(group), request.goal_q(group)[0]]))
    line = group.joints.q_from_angles(np.linspace(ends[0], ends[1], 200))
    assert group.in_collision(line, scene).any()  # the straight line does not do
    out = tmp_path / "plan.yaml"
    code = main(["plan", robot, "--request", str(request_file), "--scene", str(scene_file),
                 "-o", str(out)])  # fmt: skip
    assert code == 0, capsys.readouterr().out
    written = planning.read_joint_trajectory(out)
    assert len(written.names) == joints == group.joints.nv
    assert not group.in_collision(group.joints.q_from_angles(written.positions), scene).any()
