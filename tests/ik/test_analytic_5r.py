"""Analytic IK of 5-joint arms (axes 2, 3, 4 parallel: the Katana 6M180, [P2]'s arm) and
the analytic method along paths and on 3-joint arms: every branch verified, none missing
against the numeric IK, [P2]'s geometric IK equal to the general solver, orientations the
arm cannot take reported with their residual, and calibrated arms polished."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from helpers import chain_urdf, same_up_to_turns, unit

import toolkit
from toolkit import arm5dof
from toolkit import calibration as cal

rng = np.random.default_rng(11)
FAMILY = "5R, axes 2, 3, 4 parallel"


def random_5r():
    h = [unit(rng.normal(size=3)) for _ in range(5)]
    h[2] = h[1] if rng.random() < 0.5 else -h[1]
    h[3] = h[1] if rng.random() < 0.5 else -h[1]
    o = [rng.normal(size=3) * 0.3 for _ in range(5)]
    return chain_urdf(h, o, o[4] + rng.normal(size=3) * 0.1, "r5")


def _numeric_solutions_among(robot, T, branches, starts, seed):
    """How many distinct solutions the numeric IK finds from ``starts`` random starts, all
    asserted to lie among ``branches`` (to 1e-6, or looser by 1e-9 over the Jacobian's
    smallest singular value near a singularity)."""
    found = []
    for start in robot.random_q(starts, seed=seed):
        res = robot.ik(T, q0=start, tol=1e-10, restarts=0, method="numeric")
        if not res.success:
            continue
        sigma = np.linalg.svd(robot.jacobian(res.q), compute_uv=False)[-1]
        close = max(1e-6, 10 * 1e-10 / sigma)
        a = robot.joints.angles(res.q)
        assert any(same_up_to_turns(robot.joints.angles(b), a, close) for b in branches), a
        if not any(same_up_to_turns(f, a, 1e-6) for f in found):
            found.append(a)
    return len(found)


@pytest.mark.parametrize("name", ["katana_6m180", "arm5dof"])
def test_the_5_joint_arms_of_the_catalogue_have_the_5r_family(name):
    structure = toolkit.load(name).structure
    assert structure.family == FAMILY and structure.exact
    assert structure.joints == tuple(f"joint{i}" for i in range(1, 6))


def test_every_branch_of_random_5r_arms_is_verified_and_none_is_missing():
    for _ in range(3):
        robot = toolkit.load_urdf(random_5r())
        assert robot.structure.family == FAMILY and robot.structure.exact
        for seed in range(10):
            q = robot.random_q(seed=seed)
            T = robot.fk(q)
            result = robot.ik_all(T)
            # without the Katana's symmetry the other shoulder root generally misses the
            # orientation (6 equations, 5 joints): listed, with success False
            ok = result.success
            assert ok.sum() >= 2 and (ok == (result.orientation_error <= 1e-10)).all()
            assert (result.position_error[ok] <= 1e-10).all()
            for row in result.q[ok]:  # an independent check of each claim
                np.testing.assert_allclose(robot.fk(row), T, atol=1e-9)
            assert any(
                same_up_to_turns(robot.joints.angles(r), robot.joints.angles(q))
                for r in result.q[ok]
            )
            _numeric_solutions_among(robot, T, result.q[ok], 4, 100 + seed)


def test_the_compiled_5r_family_equals_the_python_form_exact_and_near():
    from toolkit.ik import families, family_kernels
    from toolkit.ik.analytic.door import branch_label, packed_family

    katana = toolkit.load("katana_6m180")
    near = toolkit.load_urdf(cal.perturb(katana, seed=2).urdf_text, mimic=False, tip=katana.tip)
    robots = [katana, toolkit.load("arm5dof"), near]
    robots += [toolkit.load_urdf(random_5r()) for _ in range(3)]
    out, roots = np.zeros((8, 5)), np.full((8, 3), -1, np.int64)
    for robot in robots:
        chain, found = robot._analytic._chain_structure(robot.frames.id(None))
        assert found.family == FAMILY and found.compiled
        total = 0
        ok = families.EXACT_ONLY if found.exact else families.NEAR_OK
        for seed in range(30):
            q = robot.random_q(seed=seed)
            T = robot.fk(q)
            if seed % 3 == 0:  # an orientation the arm cannot take: the nearest one
                T[:3, :3] = T[:3, :3] @ pin.exp3(np.array([0.2, -0.1, 0.3]))
            n = family_kernels.five_r_parallel(*packed_family(chain, found), T,
                                                 not found.exact, np.zeros(5), out, roots,
                                                 np.zeros(8, np.int64))  # fmt: skip
            python = families.five_r_parallel(chain, found.points, T, ok)
            assert n == len(python)
            total += n
            for k, (angles, label) in enumerate(python):
                np.testing.assert_allclose(out[k], angles, atol=1e-9)
                assert label == branch_label(tuple(roots[k].tolist()), wrist=False)
        assert total >= 30  # most targets have branches (the generating one among them)


def test_the_katana_6m180_branches_hold_every_numeric_solution():
    katana = toolkit.load("katana_6m180")
    distinct = 0
    for seed, q in enumerate(katana.random_q(15, seed=5)):
        T = katana.fk(q)
        result = katana.ik_all(T)
        assert result.solved >= 1
        distinct += _numeric_solutions_among(katana, T, result.q[result.success], 12, seed)
    assert distinct >= 15  # the numeric IK found something to compare on every target


def test_p2s_geometric_ik_equals_the_general_5r_solver():
    robot = toolkit.load("arm5dof")
    compared = 0
    for q in robot.random_q(40, seed=9):
        T = robot.fk(q)
        general = robot.ik_all(T)
        p, x = T[:3, 3], T[:3, 0]  # the gripper point and its axis (the roll's)
        pitch = np.arctan2(x[2], x[:2] @ (p[:2] / np.hypot(*p[:2])))
        closed = arm5dof.geometric_ik(p, pitch, arm5dof.MODEL_LENGTHS)
        assert len(closed) == len(general.q) == 4
        for s in closed:  # [P2] leaves the roll at 0: the other four joints agree
            assert any(same_up_to_turns(s[:4], row[:4], 1e-9) for row in general.q)
        compared += len(closed)
    assert compared == 160


def test_an_orientation_the_arm_cannot_take_gets_branches_with_their_residual():
    katana = toolkit.load("katana_6m180")
    turned = 0
    for seed in range(40):
        T = katana.fk(katana.random_q(seed=seed))
        w = unit(rng.normal(size=3)) * rng.uniform(0.02, 0.3)
        T[:3, :3] = T[:3, :3] @ pin.exp3(w)
        result = katana.ik_all(T)
        assert not result.success.any()
        if len(result.q):  # the point placed, the orientation as near as roll and pitch get
            turned += 1
            assert (result.position_error <= 1e-10).all()
            assert 1e-6 < result.orientation_error.min() <= np.linalg.norm(w) + 1e-9
            for row in result.q:
                F = katana.fk(row)
                assert np.linalg.norm(F[:3, 3] - T[:3, 3]) <= 1e-9
                miss = np.linalg.norm(pin.log3(F[:3, :3].T @ T[:3, :3]))
                assert miss <= np.linalg.norm(w) + 1e-9
        answer = katana.ik(T, method="analytic", restarts=3)
        assert not answer.success  # the numeric fallback misses too, and says by how much
        assert max(answer.position_error, answer.orientation_error) > 1e-6
    assert turned >= 30


def test_a_calibrated_katana_6m180_keeps_the_branch_that_reaches_and_counts_the_rest():
    katana = toolkit.load("katana_6m180")
    arm = toolkit.load_urdf(cal.perturb(katana, seed=2).urdf_text, tip=katana.tip)
    assert arm.structure.family == FAMILY and not arm.structure.exact
    found = 0
    for q in katana.random_q(20, seed=4):
        T = arm.fk(q)
        result = arm.ik_all(T)
        exact = katana.ik_all(katana.fk(q))
        assert result.polished
        assert (result.position_error <= 1e-10).all() and (result.orientation_error <= 1e-10).all()
        # a pose of a perturbed 5-joint arm is generally reached by one branch only: the
        # symmetry that gave the others is broken; they are counted, not returned
        assert len(result.q) + result.lost >= len(exact.q)
        sigma = np.linalg.svd(arm.jacobian(q), compute_uv=False)[-1]
        close = max(1e-6, 10 * 1e-10 / sigma)
        found += any(
            same_up_to_turns(arm.joints.angles(r), arm.joints.angles(q), close) for r in result.q
        )
    assert found == 20


def test_ik_path_with_the_analytic_method_keeps_its_branch():
    ur5 = toolkit.load_example("ur5")
    q0 = np.array([0.4, -1.2, 1.5, -1.8, -1.4, 0.3])
    start = ur5.fk(q0)
    path = []
    for t in np.linspace(0.0, 0.15, 25):
        T = start.copy()
        T[:3, 3] += [0.0, t, -0.5 * t]
        path.append(T)
    result = ur5.ik_path(path, q0=q0, method="analytic")
    assert result.all_succeeded and result.jumps == [] and result.max_step < 0.2
    labels = set()
    for T, q in zip(path, result.q, strict=True):
        np.testing.assert_allclose(ur5.fk(q), T, atol=1e-9)
        branches = ur5.ik_all(T)
        at = [i for i, row in enumerate(branches.q) if np.abs(row - q).max() < 1e-9]
        assert at, "each step is one of the target's branches"
        labels.add(branches.labels[at[0]])
    assert len(labels) == 1  # the same shoulder, elbow and wrist all along
    with pytest.raises(toolkit.InvalidParameterError, match="method"):
        ur5.ik_path(path, method="closed")


def test_a_3_joint_arm_takes_method_analytic_with_a_position():
    arm = toolkit.load("anthropomorphic")
    q = arm.random_q(seed=6)
    p = arm.fk(q, "point_m")[:3, 3]
    branches = arm.ik_all(p, frame="point_m")
    for row in branches.q[branches.success]:
        answer = arm.ik(p, q0=row, frame="point_m", method="analytic")
        assert answer.success and answer.iterations == 0
        assert np.abs(answer.q - row).max() < 1e-9
    with pytest.raises(toolkit.InvalidParameterError, match="needs a position"):
        arm.ik(np.eye(4), frame="point_m", method="analytic")


@pytest.mark.parametrize(
    ("name", "frame", "positions"),
    [("katana_6m180", None, False), ("kinova", None, False), ("scara", "point_m", True)],
)
def test_ik_all_batch_gives_ik_alls_branches_compiled_or_not(name, frame, positions):
    robot = toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)
    Q = robot.random_q(6, seed=3)
    T = robot.fk(Q, frame)
    targets = T[:, :3, 3] if positions else T
    batch = robot.ik_all_batch(targets, frame=frame)
    assert batch.q.shape[:2] == batch.success.shape and batch.q.shape[2] == robot.nq
    for n, target in enumerate(targets):
        single = robot.ik_all(target, frame=frame)
        assert batch.found[n] == len(set(single.labels))
        rows = batch.q[n, : batch.found[n]]
        assert np.isnan(batch.q[n, batch.found[n] :]).all()
        for row, ok in zip(rows, batch.success[n, : batch.found[n]], strict=True):
            F = robot.fk(row, frame)  # each row checked again, independently
            miss = np.abs(F[:3, 3] - target) if positions else np.abs(F - target)
            assert ok == (miss.max() < 1e-9 and robot.joints.within_limits(row))
            assert any(
                same_up_to_turns(robot.joints.angles(row), robot.joints.angles(s)) for s in single.q
            )
        assert (batch.roots[n, : batch.found[n]] >= -1).all()
