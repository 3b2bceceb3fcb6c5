"""Analytic IK by subproblem decomposition: structures found from the axes, every branch
verified, the families against the numeric IK on random robots built from random axes,
calibrated arms polished, and bad input refused."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import chain_urdf as _urdf
from helpers import random_position_chain
from helpers import random_spherical_shoulder as _spherical_shoulder
from helpers import same_up_to_turns as _same_up_to_turns
from helpers import unit as _unit

import toolkit
from toolkit import calibration as cal

rng = np.random.default_rng(7)


def random_spherical_wrist():
    h = [_unit(rng.normal(size=3)) for _ in range(6)]
    h[2] = h[1] if rng.random() < 0.5 else -h[1]  # axes 2, 3 parallel
    o = [rng.normal(size=3) * 0.3 for _ in range(3)]
    w = rng.normal(size=3) * 0.3
    o += [w + 0.0 * h[3], w + 0.2 * h[4], w - 0.1 * h[5]]  # axes 4-6 through w
    return _urdf(h, o, w + rng.normal(size=3) * 0.1)


def random_three_parallel():
    h = [_unit(rng.normal(size=3)) for _ in range(6)]
    h[2], h[3] = h[1], -h[1]  # axes 2, 3, 4 parallel
    o = [rng.normal(size=3) * 0.3 for _ in range(5)]
    o.append(o[4] - 0.12 * h[4])  # axes 5, 6 meet: o6 on axis 5
    return _urdf(h, o, o[5] + rng.normal(size=3) * 0.1)


def random_meeting_shoulder():
    h = [_unit(rng.normal(size=3)) for _ in range(6)]
    S = rng.normal(size=3) * 0.2
    w = rng.normal(size=3) * 0.3
    o = [S, S + 0.0 * h[1], rng.normal(size=3) * 0.3, w - 0.1 * h[3], w, w + 0.15 * h[5]]
    return _urdf(h, o, w + rng.normal(size=3) * 0.1)


def random_spherical_shoulder():
    """Axes 1-3 through one point, axes 4, 5 parallel (helpers.random_spherical_shoulder)."""
    return _spherical_shoulder(rng)


@pytest.mark.parametrize(
    ("name", "family"),
    [("ur5", "three parallel"), ("ur10", "three parallel"), ("z1", "three parallel"),
     ("katana_6m90a", "three parallel"), ("kinova", "spherical wrist")],
)  # fmt: skip
def test_the_structure_is_read_from_the_axes(name, family):
    robot = toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)
    assert robot.structure.family == family and robot.structure.exact
    assert robot.structure.deviation < 1e-9


def test_arms_without_a_structure_say_why():
    assert "7 revolute joints" in toolkit.load_example("panda").structure.reason
    assert toolkit.load_example("panda").structure.family is None
    assert "neither a revolute nor a prismatic" in toolkit.load("bending").structure.reason
    with pytest.raises(toolkit.UnsupportedModelError, match="7 revolute joints"):
        toolkit.load_example("panda").ik_all(np.eye(4))
    broken = toolkit.load_urdf(random_spherical_wrist().replace('name="j5"', 'name="j5"'))
    assert broken.structure.family == "spherical wrist"


@pytest.mark.parametrize(
    "make",
    [random_spherical_wrist, random_three_parallel, random_meeting_shoulder,
     random_spherical_shoulder],
)  # fmt: skip
def test_every_branch_of_random_robots_of_a_family_is_verified_and_complete(make):
    for _ in range(3):
        robot = toolkit.load_urdf(make())
        assert robot.structure.exact, robot.structure.reason
        for seed in range(10):
            q = robot.random_q(seed=seed)
            result = robot.ik_all(robot.fk(q))
            assert result.solved >= 1
            assert (result.position_error <= 1e-10).all()
            assert (result.orientation_error <= 1e-10).all()
            for row in result.q[result.success]:  # an independent check of each claim
                np.testing.assert_allclose(robot.fk(row), robot.fk(q), atol=1e-9)
            assert any(
                _same_up_to_turns(robot.joints.angles(r), robot.joints.angles(q)) for r in result.q
            )
            # every distinct solution the numeric IK finds lies among the branches
            for start in robot.random_q(4, seed=100 + seed):
                found = robot.ik(robot.fk(q), q0=start, tol=1e-9, restarts=0, method="numeric")
                if found.success:
                    # a pose within 1e-9 fixes the angles to 1e-9 / (the Jacobian's smallest
                    # singular value): near a singularity, more loosely than 1e-6
                    sigma = np.linalg.svd(robot.jacobian(found.q), compute_uv=False)[-1]
                    close = max(1e-6, 10 * 1e-9 / sigma)
                    assert any(
                        _same_up_to_turns(
                            robot.joints.angles(r), robot.joints.angles(found.q), close
                        )
                        for r in result.q
                    )


def test_the_ur5_gets_its_eight_branches_and_every_turn_within_its_limits():
    ur5 = toolkit.load_example("ur5")
    q = ur5.random_q(seed=3)
    result = ur5.ik_all(ur5.fk(q), turns=True)
    assert len(set(result.labels)) == 8
    assert result.within_limits.all() and result.success.all()
    # every angle equivalent by a whole turn and inside the limits is listed, once
    rows = {tuple(np.round(r, 9)) for r in result.q}
    assert len(rows) == len(result.q) > 8
    for r in result.q:
        for j in range(6):
            for turn in (-2 * np.pi, 2 * np.pi):
                other = r.copy()
                other[j] += turn
                inside = ur5.joints.lower[j] <= other[j] <= ur5.joints.upper[j]
                assert inside == (tuple(np.round(other, 9)) in rows)
    assert {"shoulder +, elbow +, wrist +", "shoulder -, elbow -, wrist -"} <= set(result.labels)


def test_a_calibrated_ur5_gets_all_its_branches_polished_to_1e_10():
    ur5 = toolkit.load_example("ur5")
    truth = cal.perturb(ur5, seed=1)
    Q = ur5.random_q(60, seed=2)
    arm = cal.identify(ur5, Q, cal.simulate(truth, Q)).robot
    assert arm.structure.family == "three parallel" and not arm.structure.exact
    assert 1e-9 < arm.structure.deviation < 0.01
    for seed in range(10, 14):
        q = ur5.random_q(seed=seed)
        result = arm.ik_all(arm.fk(q))
        exact = ur5.ik_all(ur5.fk(q))
        assert result.polished and len(set(result.labels)) == len(set(exact.labels))
        assert (result.position_error <= 1e-10).all() and (result.orientation_error <= 1e-10).all()


def test_ik_analytic_takes_the_branch_nearest_q0():
    ur5 = toolkit.load_example("ur5")
    T = ur5.fk(ur5.random_q(seed=5))
    branches = ur5.ik_all(T, turns=True)
    for row in branches.q[:: len(branches.q) // 5]:
        answer = ur5.ik(T, q0=row, method="analytic")
        assert answer.success and np.abs(answer.q - row).max() < 1e-9
    for q0 in ur5.random_q(6, seed=6):  # any start: the verified row nearest it, by sum |dq|
        rows = branches.q[branches.success]
        best = rows[np.argmin(np.abs(rows - q0).sum(axis=1))]
        np.testing.assert_allclose(ur5.ik(T, q0=q0, method="analytic").q, best, atol=1e-12)
    assert ur5.ik(T, method="auto").success
    panda = toolkit.load_example("panda")
    assert panda.ik(panda.fk(panda.random_q(seed=1)), method="auto").success  # numeric


def test_bad_input_to_the_analytic_ik_is_refused():
    ur5 = toolkit.load_example("ur5")
    T = ur5.fk(ur5.random_q(seed=5))
    bad = T.copy()
    bad[0, 0] = np.nan
    with pytest.raises(toolkit.ToolkitError):
        ur5.ik_all(bad)
    skew = T.copy()
    skew[:3, :3] *= 2.0
    with pytest.raises(toolkit.InvalidParameterError, match="rotation"):
        ur5.ik_all(skew)
    with pytest.raises(toolkit.InvalidParameterError, match=r"target pose \(4, 4\)"):
        ur5.ik_all(T[:3, 3])
    with pytest.raises(toolkit.InvalidParameterError, match="method"):
        ur5.ik(T, method="closed")
    with pytest.raises(toolkit.InvalidParameterError, match="full pose"):
        ur5.ik(T, method="analytic", mask=[1, 1, 1, 1, 1, 0])
    with pytest.raises(toolkit.UnsupportedModelError, match="no analytic IK"):
        toolkit.load_example("panda").ik(np.eye(4), method="analytic")
    far = np.eye(4)
    far[:3, 3] = [5.0, 0.0, 0.0]
    out = ur5.ik_all(far)
    assert out.solved == 0  # out of reach: no branch, said by the result


def _chain_arrays(robot):
    from toolkit.ik.analytic.door import packed_family

    chain, found = robot._analytic._chain_structure(robot.frames.id(None))
    return chain, found, packed_family(chain, found)


@pytest.mark.parametrize(
    "family", ["three parallel", "spherical wrist", "spherical wrist, meeting shoulder"]
)
def test_the_compiled_family_equals_the_python_form(family):
    """Exact arms and arms only near the family (perturbed: the least-squares roots split
    and kept), every branch's angles and label."""
    from toolkit.ik import families, registry
    from toolkit.ik.analytic.door import branch_label

    if family == "three parallel":
        robots = [toolkit.load_example("ur5"), toolkit.load("katana_6m90a")]
        robots += [toolkit.load_urdf(random_three_parallel()) for _ in range(3)]
    elif family == "spherical wrist":
        robots = [toolkit.load_example("kinova")]
        robots += [toolkit.load_urdf(random_spherical_wrist()) for _ in range(3)]
    else:
        robots = [toolkit.load_urdf(random_meeting_shoulder()) for _ in range(4)]
    robots.append(toolkit.load_urdf(cal.perturb(robots[0], seed=3).urdf_text, mimic=False,
                                    tip=robots[0].tip))  # fmt: skip
    solve = registry.REGISTRY[family].kernel
    out, roots = np.zeros((8, 6)), np.full((8, 3), -1, np.int64)
    total = 0
    for robot in robots:
        chain, found, packed = _chain_arrays(robot)
        assert found.family == family and found.compiled
        ok = families.EXACT_ONLY if found.exact else families.NEAR_OK
        for seed in range(20):
            T = robot.fk(robot.random_q(seed=seed))
            n = solve(*packed, T, not found.exact, np.zeros(6), out, roots, np.zeros(8, np.int64))
            python = registry.REGISTRY[family].python(chain, found.points, T, ok)
            assert n == len(python)
            total += n
            for k, (angles, label) in enumerate(python):
                np.testing.assert_allclose(out[k], angles, atol=1e-9)
                # the Python form names its own roots
                assert label == branch_label(tuple(roots[k].tolist()))
    assert total >= 20 * len(robots) * 2  # most targets have several branches


def test_a_reversed_structure_is_solved_compiled_as_the_python_form_solves_it():
    """The kernel on the chain seen from its frame at T^-1, turned back: the branches and
    labels of registry.solve (random spherical shoulders; the Panda with joint 7 locked),
    exact and perturbed, one target at a time and in a batch."""
    from toolkit.ik import families, registry

    panda = toolkit.load_example("panda")
    cases = [(toolkit.load_urdf(random_spherical_shoulder()), None) for _ in range(2)]
    cases.append((panda, {"panda_joint7": 0.4}))
    near = toolkit.load_urdf(cal.perturb(cases[0][0], seed=5).urdf_text, mimic=False,
                             tip=cases[0][0].tip)  # fmt: skip
    cases.append((near, None))
    for robot, lock in cases:
        chain, found = robot._analytic._chain_structure(
            robot.frames.id(None), robot._analytic._locked(lock)
        )
        assert found.reversed and found.compiled
        ok = families.EXACT_ONLY if found.exact else families.NEAR_OK
        Q = robot.random_q(12, seed=8)
        if lock:
            Q[:, 6] = 0.4
        for T in robot.fk(Q):
            door = robot._analytic._door(robot.frames.id(None), robot._analytic._locked(lock))
            rest = np.zeros(robot.model.nv)
            A, labels, free = robot._analytic._raw_branches(
                (chain, found, door), T, rest, found.exact
            )
            python = registry.solve(chain, found, T, ok)
            assert labels == [label for _, label in python]
            assert all(label.startswith("reversed: ") for label in labels)
            assert not free.any()  # random targets: no singular pose
            for a, (b, _) in zip(A, python, strict=True):  # up to whole turns
                np.testing.assert_allclose(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi, 0,
                                           atol=1e-9)  # fmt: skip
            if found.exact:
                result = robot.ik_all(T, lock=lock)
                assert result.success.any()
                for q in result.q[result.success]:
                    np.testing.assert_allclose(robot.fk(q), T, atol=1e-9)
    arm = cases[0][0]
    Ts = arm.fk(arm.random_q(20, seed=9))
    batch = arm.ik_all_batch(Ts)
    for i, T in enumerate(Ts):
        assert batch.found[i] == len(set(arm.ik_all(T).labels))
        for q in batch.q[i, : batch.found[i]]:
            np.testing.assert_allclose(arm.fk(q), T, atol=1e-9)


def test_ik_all_batch_gives_the_branches_of_ik_all():
    ur5 = toolkit.load_example("ur5")
    Ts = ur5.fk(ur5.random_q(40, seed=9))
    batch = ur5.ik_all_batch(Ts)
    assert batch.q.shape == (40, 8, ur5.nq) and batch.success.shape == (40, 8)
    for i, T in enumerate(Ts):
        single = ur5.ik_all(T)
        assert batch.found[i] == len(set(single.labels))
        assert (
            batch.success[i, : batch.found[i]].all()
            and not batch.success[i, batch.found[i] :].any()
        )
        assert np.isnan(batch.q[i, batch.found[i] :]).all()
        for q in batch.q[i, : batch.found[i]]:
            np.testing.assert_allclose(ur5.fk(q), T, atol=1e-9)  # an independent check
            assert any(
                _same_up_to_turns(ur5.joints.angles(q), ur5.joints.angles(r)) for r in single.q
            )
    assert np.nanmax(batch.position_error) <= 1e-10 and np.nanmax(batch.orientation_error) <= 1e-10


def test_ik_all_batch_on_a_calibrated_arm_polishes_and_lists_each_branch_once():
    ur5 = toolkit.load_example("ur5")
    arm = toolkit.load_urdf(cal.perturb(ur5, seed=1).urdf_text, mimic=False, tip=ur5.tip)
    Ts = arm.fk(ur5.random_q(30, seed=4))
    batch = arm.ik_all_batch(Ts)
    assert batch.polished
    for i, T in enumerate(Ts):
        rows = batch.q[i, : batch.found[i]]
        assert batch.success[i, : batch.found[i]].all()
        angles = [arm.joints.angles(q) for q in rows]
        for a in range(len(angles)):  # no branch twice
            for b in range(a):
                assert not _same_up_to_turns(angles[a], angles[b])
        assert batch.found[i] == len(set(arm.ik_all(T).labels))


def test_solve_poses_is_solve_batch_without_the_task_objects_on_both_loops():
    from toolkit.ik import IKOptions, PoseTask, loops

    ur5 = toolkit.load_example("ur5")
    Ts = ur5.fk(ur5.random_q(6, seed=4))
    Q0 = ur5.random_q(6, seed=5)
    fid, w = ur5.frames.id(None), np.ones(6)
    opts = IKOptions(tol=1e-10, max_iter=100, restarts=2)
    for loop in (ur5._numeric.ik_loop, loops.PinocchioLoop()):
        qs, iters = loop.solve_poses(fid, Ts, w, Q0, ur5._numeric.ik_state, opts, 7)
        again, its = loop.solve_batch(PoseTask.many(fid, Ts, w), Q0, ur5._numeric.ik_state, opts, 7)
        assert np.array_equal(qs, again) and np.array_equal(iters, its)
        reached = np.abs(ur5.fk(qs) - Ts).max(axis=(1, 2)) < 1e-9
        assert reached.sum() >= 4, (loop.name, reached)


def test_starts_sharing_targets_solve_and_are_judged_as_with_a_pose_each():
    """``owner`` (the branches of one target share its pose, not a copy each): the solve on
    both loops equals the solve of the poses gathered per start, and the compiled errors
    (``checks.owned_errors``, serial and over the cores) equal the forward kinematics'
    against the gathered poses, to rounding."""
    from toolkit.ik import IKOptions, checks, loops

    ur5 = toolkit.load_example("ur5")
    Ts = ur5.fk(ur5.random_q(5, seed=8))
    owner = np.array([0, 0, 3, 1, 4, 4, 4, 2, 0], np.int64)
    Q0 = ur5.random_q(len(owner), seed=9)
    fid, w = ur5.frames.id(None), np.ones(6)
    opts = IKOptions(tol=1e-10, max_iter=100, restarts=1)
    gathered = np.ascontiguousarray(Ts[owner])
    for loop in (ur5._numeric.ik_loop, loops.PinocchioLoop()):
        qs, iters = loop.solve_poses(fid, Ts, w, Q0, ur5._numeric.ik_state, opts, 3, owner=owner)
        again, its = loop.solve_poses(fid, gathered, w, Q0, ur5._numeric.ik_state, opts, 3)
        assert np.array_equal(qs, again) and np.array_equal(iters, its)
    F = ur5.fk(qs)
    pos = np.linalg.norm(F[:, :3, 3] - gathered[:, :3, 3], axis=1)
    chord = np.linalg.norm(F[:, :3, :3] - gathered[:, :3, :3], axis=(1, 2))
    rot = 2 * np.arcsin(np.minimum(1.0, chord / (2 * np.sqrt(2))))
    chain = ur5.kinematics.chain(fid)
    for spread in (False, True):
        p, r = checks.owned_errors(spread, np.ascontiguousarray(qs), *chain, Ts, owner)
        np.testing.assert_allclose(p, pos, atol=1e-13)
        np.testing.assert_allclose(r, rot, atol=1e-12)
    assert (pos < 1e-9).sum() >= 5


def test_ik_all_batch_refuses_what_it_cannot_do():
    ur5 = toolkit.load_example("ur5")
    with pytest.raises(toolkit.InvalidParameterError, match="target poses"):
        ur5.ik_all_batch(np.zeros((3, 3)))
    with pytest.raises(toolkit.InvalidParameterError, match=r"\(N, 3\) target positions"):
        scara = toolkit.load("scara")
        scara.ik_all_batch(scara.fk(scara.random_q(2, seed=1), "point_m"), frame="point_m")
    with pytest.raises(toolkit.UnsupportedModelError, match="7 revolute joints"):
        toolkit.load_example("panda").ik_all_batch(np.tile(np.eye(4), (2, 1, 1)))


def test_maps_decide_orientations_from_every_branch_exactly():
    from toolkit import maps

    ur5 = toolkit.load_example("ur5")
    kwargs = {"voxel": 0.2, "orientations": 6, "bounds": [[0.1, -0.3, 0.0], [0.6, 0.2, 0.4]],
              "collision_free": False, "workers": 1}  # fmt: skip
    exact = maps.reachability(ur5, **kwargs)  # method="auto": analytic for the UR5
    lower = maps.reachability(ur5, method="numeric", **kwargs)
    assert (exact.index >= lower.index - 1e-12).all()  # the numeric budget is a lower bound
    # ground truth per voxel and orientation: is any branch of ik_all within the limits?
    centres = exact.centers.reshape(-1, 3)
    index = exact.index.reshape(-1)
    for v in range(0, len(centres), 3):
        count = 0
        for R in exact.orientations:
            T = np.eye(4)
            T[:3, :3], T[:3, 3] = R, centres[v]
            count += bool(ur5.ik_all(T).success.any())
        assert index[v] == pytest.approx(count / len(exact.orientations))
    with pytest.raises(toolkit.InvalidParameterError, match="compiled analytic structure"):
        maps.reachability(toolkit.load_example("panda"), method="analytic", **kwargs)
    with pytest.raises(toolkit.InvalidParameterError, match="unknown method"):
        maps.reachability(ur5, method="closed", **kwargs)


def test_a_collision_free_analytic_map_keeps_only_free_branches():
    from toolkit import maps

    ur5 = toolkit.load_example("ur5")
    table = toolkit.Scene().add_box("table", size=(2.0, 2.0, 0.05), pose=(0, 0, -0.03))
    m = maps.reachability(ur5, voxel=0.25, orientations=4, scene=table, workers=1,
                          bounds=[[0.1, -0.3, 0.0], [0.6, 0.2, 0.5]])  # fmt: skip
    q = m.best_q[m.index > 0]
    assert len(q) and not ur5.in_collision(q, table).any()


def test_random_robots_get_the_family_they_were_built_with():
    assert toolkit.load_urdf(random_meeting_shoulder()).structure.family == (
        "spherical wrist, meeting shoulder"
    )
    reversed_arm = toolkit.load_urdf(random_spherical_shoulder()).structure
    assert reversed_arm.family == "spherical wrist" and reversed_arm.reversed
    assert reversed_arm.compiled  # solved on the chain seen from its frame


def test_the_panda_with_joint_7_locked_gets_every_branch_and_its_own_q():
    panda = toolkit.load_example("panda")
    found = panda.structure_of(lock={"panda_joint7": 0.4})
    assert found.family == "spherical wrist, meeting shoulder" and found.reversed and found.exact
    assert panda.structure_of(lock={"panda_joint3": 0.4}).family == "meeting pairs, search"
    col = panda.joints.names.index("panda_joint7")
    hits = 0
    for seed in range(12):
        q = panda.random_q(seed=seed)
        angles = panda.joints.angles(q)
        result = panda.ik_all(panda.fk(q), lock={"panda_joint7": float(angles[col])})
        assert (result.position_error <= 1e-10).all() and (result.orientation_error <= 1e-10).all()
        for row in result.q[result.success]:  # an independent check of each claim
            np.testing.assert_allclose(panda.fk(row), panda.fk(q), atol=1e-9)
            assert panda.joints.angles(row)[col] == pytest.approx(angles[col], abs=1e-12)
        hits += any(_same_up_to_turns(panda.joints.angles(r)[:7], angles[:7]) for r in result.q)
        # the numeric IK from the branches' neighbourhood lands on one of them
        if result.solved:
            start = result.q[result.success][0] + 0.01
            start[col] = result.q[result.success][0][col]
            numeric = panda.ik(panda.fk(q), q0=start, tol=1e-10, restarts=0, method="numeric")
            if numeric.success and abs(panda.joints.angles(numeric.q)[col] - angles[col]) < 1e-9:
                seen = panda.joints.angles(numeric.q)[:7]
                assert any(_same_up_to_turns(panda.joints.angles(r)[:7], seen)
                           for r in result.q)  # fmt: skip
    assert hits == 12  # the configuration that made the target is always among the branches


def test_a_calibrated_panda_with_joint_7_locked_is_polished_to_1e_10():
    panda = toolkit.load_example("panda")
    Q = panda.random_q(80, seed=2)
    truth = cal.identify(panda, Q, cal.simulate(cal.perturb(panda, seed=3), Q)).robot
    lock = {"panda_joint7": 0.2}
    found = truth.structure_of(lock=lock)
    assert found.family is not None and not found.exact and found.reversed
    col = panda.joints.names.index("panda_joint7")
    for seed in range(4):
        q = truth.random_q(seed=seed)
        q[truth.model.joints[truth.model.getJointId("panda_joint7")].idx_q] = 0.2
        result = truth.ik_all(truth.fk(q), lock=lock)
        assert result.polished and result.solved >= 1
        assert (result.position_error <= 1e-10).all() and (result.orientation_error <= 1e-10).all()
        assert any(
            _same_up_to_turns(truth.joints.angles(r)[:7], truth.joints.angles(q)[:7])
            for r in result.q
        )
        assert all(truth.joints.angles(r)[col] == pytest.approx(0.2) for r in result.q)


def test_a_lock_that_cannot_apply_is_refused():
    panda = toolkit.load_example("panda")
    T = panda.fk(panda.joints.neutral())
    with pytest.raises(toolkit.InvalidParameterError, match="no joint named"):
        panda.ik_all(T, lock={"joint_8": 0.0})
    with pytest.raises(toolkit.InvalidParameterError, match="lock must be a dict"):
        panda.ik_all(T, lock=[("panda_joint7", 0.0)])
    with pytest.raises(toolkit.InvalidParameterError, match="panda_joint7"):
        panda.ik_all(T, lock={"panda_joint7": float("nan")})
    with pytest.raises(toolkit.UnsupportedModelError, match="not between the base"):
        panda.ik_all(T, lock={"panda_finger_joint1": 0.01})


@pytest.mark.parametrize("kind", ["3R meeting", "3R parallel"])
def test_every_branch_of_random_3r_arms_places_the_point_and_none_is_missing(kind):
    for _ in range(3):
        robot = toolkit.load_urdf(random_position_chain(kind, rng))
        assert robot.structure.family.startswith("3R") and robot.structure.exact
        for seed in range(10):
            q = robot.random_q(seed=seed)
            p = robot.fk(q)[:3, 3]
            result = robot.ik_all(p)
            assert result.solved >= 1 and (result.position_error <= 1e-10).all()
            for row in result.q[result.success]:
                np.testing.assert_allclose(robot.fk(row)[:3, 3], p, atol=1e-9)
            assert any(
                _same_up_to_turns(robot.joints.angles(r), robot.joints.angles(q)) for r in result.q
            )
            for start in robot.random_q(4, seed=100 + seed):
                found = robot.ik(p, q0=start, tol=1e-10, restarts=0, method="numeric")
                if found.success:
                    sigma = np.linalg.svd(robot.jacobian(found.q)[:3], compute_uv=False)[-1]
                    close = max(1e-6, 10 * 1e-10 / sigma)
                    seen = robot.joints.angles(found.q)
                    assert any(_same_up_to_turns(robot.joints.angles(r), seen, close)
                               for r in result.q)  # fmt: skip


def test_p3s_anthropomorphic_closed_forms_equal_the_general_3r_solver():
    from toolkit.papers.structures.inverse import closed_form_ik

    robot = toolkit.load("anthropomorphic")
    assert robot.structure.family is None and "lies on axis 3" in robot.structure.reason
    assert robot.structure_of("point_m").family == "3R, axes 1, 2 meeting"
    compared = 0
    for seed in range(25):
        p = robot.fk(robot.random_q(seed=seed), "point_m")[:3, 3]
        general = robot.ik_all(p, frame="point_m")
        closed = closed_form_ik(robot, p)
        ours = general.q[general.success]
        assert len(ours) == len(closed)
        for q in closed:
            assert any(np.abs(q - row).max() < 1e-9 for row in ours)
        compared += len(closed)
    assert compared >= 40


def test_ik_all_refuses_a_target_of_the_wrong_kind():
    arm = toolkit.load("anthropomorphic")
    with pytest.raises(toolkit.InvalidParameterError, match="needs a target position"):
        arm.ik_all(np.eye(4), frame="point_m")
    with pytest.raises(toolkit.InvalidParameterError, match=r"needs a target pose \(4, 4\)"):
        toolkit.load_example("ur5").ik_all([0.3, 0.1, 0.4])


def test_limits_of_too_many_turns_are_refused_only_when_every_turn_is_asked(tmp_path):
    ur5 = toolkit.load_example("ur5")
    text = open(ur5.urdf_path).read()
    wide = text.replace('lower="-6.28318530718"', 'lower="-200"')
    wide = wide.replace('upper="6.28318530718"', 'upper="200"')
    arm = toolkit.load_urdf(wide, package_dirs=[str(ur5.urdf_path.parents[2])], tip=ur5.tip)
    T = arm.fk(arm.random_q(seed=4))
    with pytest.raises(toolkit.InvalidParameterError, match="narrow the limits"):
        arm.ik_all(T, turns=True)
    one = arm.ik_all(T)  # one row per branch: the turn nearest the middle of the limits
    assert len(one.q) == 8 and one.success.all()
    assert (np.abs(arm.joints.angles(one.q)) <= np.pi).all()  # the middle is 0: the wrapped angles
    answer = arm.ik(T, method="analytic")
    assert answer.success and np.abs(arm.fk(answer.q) - T).max() < 1e-9
