"""The 6R family with three parallel axes at either end ("6R, axes 1, 2, 3 parallel", EAIK's
"outer" case; the last three parallel: the same family read from the frame): detection,
the compiled kernel against its Python form, every branch verified and complete against
numeric restarts, single and batch row for row, a calibrated arm polished."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import numeric_among_branches, random_outer_parallel, same_up_to_turns

import toolkit
from toolkit import calibration as cal
from toolkit.ik import Family, families, registry
from toolkit.ik.analytic.door import packed_family
from toolkit.ik.analytic.structure import reverse

FAMILY = Family.OUTER_PARALLEL
rng = np.random.default_rng(2027)
ROBOTS = [toolkit.load_urdf(random_outer_parallel(rng, last=k % 2 == 1)) for k in range(6)]


def test_three_parallel_axes_at_either_end_are_found_and_four_are_refused():
    for k, robot in enumerate(ROBOTS):
        found = robot.structure
        assert found.family is FAMILY and found.exact and found.compiled
        assert found.reversed == (k % 2 == 1)
    h = [np.array([0.0, 0.0, 1.0])] * 4 + [np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])]
    o = [np.array([0.1 * i, 0.05 * i * i, 0.1]) for i in range(6)]
    from helpers import chain_urdf

    four = toolkit.load_urdf(chain_urdf(h, o, o[5] + 0.1))
    assert four.structure.family is None and "four parallel axes" in four.structure.reason


def test_the_compiled_kernel_equals_the_python_form():
    record = registry.REGISTRY[FAMILY]
    out, roots, free = np.zeros((8, 6)), np.full((8, 3), -1, np.int64), np.zeros(8, np.int64)
    total = 0
    for robot in ROBOTS:
        chain, found = robot._analytic._chain_structure(robot.frames.id(None))
        solved = reverse(chain) if found.reversed else chain
        packed = packed_family(solved, found)
        for q in robot.random_q(15, seed=3):
            T = robot.fk(q)
            if found.reversed:
                T = np.linalg.inv(T)
            n = record.kernel(*packed, T, False, np.zeros(6), out, roots, free)
            python = record.python(solved, found.points, T, families.EXACT_ONLY)
            assert n == len(python)
            for k, (angles, label) in enumerate(python):
                np.testing.assert_allclose(out[k], angles, atol=1e-9)
                assert FAMILY.label(tuple(roots[k].tolist())) == label
                assert FAMILY.roots_of(label) == tuple(roots[k].tolist())
            assert not free[:n].any()
            total += n
    assert total >= 6 * 15


def test_every_branch_is_verified_and_none_of_the_numeric_solutions_is_missing():
    compared = 0
    for robot in ROBOTS:
        for seed in range(6):
            q = robot.random_q(seed=seed)
            T = robot.fk(q)
            result = robot.ik_all(T)
            ok = result.success
            assert ok.any() and len(result.q) <= 8
            for row in result.q[ok]:  # an independent check of each claim: Pinocchio's FK
                np.testing.assert_allclose(robot.fk(row), T, atol=1e-9)
            assert any(same_up_to_turns(r, q, 1e-7) for r in result.q)
            starts = robot.random_q(10, seed=100 + seed)
            compared += numeric_among_branches(robot, T, result.q, starts)
    assert compared >= 30


@pytest.mark.parametrize("k", [0, 1])
def test_ik_all_is_its_batch_of_one_row_for_row_and_ik_answers_from_a_branch(k):
    robot = ROBOTS[k]
    Ts = robot.fk(robot.random_q(10, seed=8))
    batch = robot.ik_all_batch(Ts)
    for n, T in enumerate(Ts):
        one, read = robot.ik_all(T), batch.target(n)
        np.testing.assert_array_equal(one.q, read.q)
        np.testing.assert_array_equal(one.success, read.success)
        assert one.labels == read.labels
        answer = robot.ik(T)
        assert answer.success and answer.method == "analytic"
        assert any(np.allclose(answer.q, r) for r in one.q[one.success])


def test_a_calibrated_arm_near_the_family_has_its_branches_polished():
    truth = cal.perturb(ROBOTS[0], seed=4)
    arm = toolkit.load_urdf(truth.urdf_text, mimic=False, tip=ROBOTS[0].tip)
    assert arm.structure.family is FAMILY and not arm.structure.exact
    for q in arm.random_q(5, seed=6):
        T = arm.fk(q)
        result = arm.ik_all(T)
        assert result.polished and result.success.any()
        for row in result.q[result.success]:
            np.testing.assert_allclose(arm.fk(row), T, atol=1e-9)
        assert any(same_up_to_turns(r, q, 1e-6) for r in result.q)


def test_the_home_pose_of_an_arm_whose_axis_6_lies_along_axis_1_gets_its_free_family():
    """Axis 6 parallel to axis 1 at the home pose: q6 drops out of the SP6, every q6 (joints
    1-3 turning back) holds the pose; each branch is a representative with q6 at q0's angle,
    named free, verified, the home configuration among them."""
    from helpers import chain_urdf, unit

    r = np.random.default_rng(3)
    h = [unit(r.normal(size=3)) for _ in range(6)]
    h[1], h[2], h[5] = h[0], -h[0], h[0]
    o = [r.normal(size=3) * 0.3 for _ in range(6)]
    arm = toolkit.load_urdf(chain_urdf(h, o, o[5] + r.normal(size=3) * 0.1))
    assert arm.structure.family is FAMILY
    T = arm.fk(np.zeros(6))
    for q6 in (0.0, 0.7):
        q0 = np.zeros(6)
        q0[5] = q6
        result = arm.ik_all(T, q0=q0)
        assert result.success.all() and len(result.q) >= 1
        assert all(f == ("j6",) for f in result.free)
        np.testing.assert_allclose(result.q[:, 5], q6, atol=1e-12)
        for row in result.q:  # an independent check: Pinocchio's FK
            np.testing.assert_allclose(arm.fk(row), T, atol=1e-9)
    home = arm.ik_all(T)
    assert any(same_up_to_turns(row, np.zeros(6), 1e-7) for row in home.q)
