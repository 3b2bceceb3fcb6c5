"""The 6R family solved by a search along q6 (axes 1, 2 meeting, axes 4, 5 meeting): random
robots of the family built from random axes against the numeric IK, the Panda with joint 3
locked (every branch, its own q among them, along a sweep of the locked angle), and a
calibrated Panda polished to 1e-10."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import chain_urdf, numeric_among_branches, same_up_to_turns, unit

import toolkit
from toolkit import calibration as cal

rng = np.random.default_rng(31)
FAMILY = "meeting pairs, search"


def random_meeting_pairs():
    h = [unit(rng.normal(size=3)) for _ in range(6)]
    S, W = rng.normal(size=3) * 0.2, rng.normal(size=3) * 0.3 + [0.0, 0.0, 0.6]
    o = [S, S, rng.normal(size=3) * 0.3, W, W, W + rng.normal(size=3) * 0.15]
    return chain_urdf(h, o, o[5] + rng.normal(size=3) * 0.1, "pairs")


def test_every_branch_of_random_robots_of_the_search_family_is_verified_and_complete():
    compared = 0
    for _ in range(3):
        robot = toolkit.load_urdf(random_meeting_pairs())
        assert robot.structure.family == FAMILY and robot.structure.exact
        for seed in range(8):
            q = robot.random_q(seed=seed)
            T = robot.fk(q)
            result = robot.ik_all(T)
            ok = result.success
            assert ok.any() and (result.position_error[ok] <= 1e-10).all()
            assert (result.orientation_error[ok] <= 1e-10).all()
            for row in result.q[ok]:  # an independent check of each claim
                np.testing.assert_allclose(robot.fk(row), T, atol=1e-9)
            assert any(same_up_to_turns(r, q, 1e-7) for r in result.q)
            starts = robot.random_q(12, seed=100 + seed)
            compared += numeric_among_branches(robot, T, result.q, starts)
    assert compared >= 30


def test_the_panda_with_joint_3_locked_gets_its_own_q_among_every_branch():
    panda = toolkit.load_example("panda")
    for seed in range(25):
        q = panda.random_q(seed=seed)
        lock = {"panda_joint3": float(q[2])}
        result = panda.ik_all(panda.fk(q), lock=lock)
        assert result.structure.family == FAMILY
        assert (result.position_error <= 1e-10).all() and (result.orientation_error <= 1e-10).all()
        assert np.allclose(result.q[:, 2], q[2])  # the locked joint stays where it was put
        assert any(same_up_to_turns(panda.joints.angles(r)[:7], panda.joints.angles(q)[:7], 1e-7)
                   for r in result.q)  # fmt: skip


def test_a_sweep_of_the_locked_angle_gives_branches_along_the_self_motion():
    panda = toolkit.load_example("panda")
    q = panda.random_q(seed=4)
    T = panda.fk(q)
    reached = 0
    for angle in np.linspace(q[2] - 0.3, q[2] + 0.3, 7):
        result = panda.ik_all(T, lock={"panda_joint3": float(angle)})
        for row in result.q[result.success]:
            np.testing.assert_allclose(panda.fk(row), T, atol=1e-9)
            assert abs(row[2] - angle) < 1e-12
        reached += bool(result.success.any())
    assert reached >= 5
    cache = panda._analytic.caches.structures
    for angle in np.linspace(-1.0, 1.0, 100):  # a long sweep keeps a bounded cache
        panda.structure_of(lock={"panda_joint3": float(angle)})
    assert sum(isinstance(k, tuple) for k in cache) <= 64


def test_a_calibrated_panda_with_joint_3_locked_is_polished_to_1e_10():
    panda = toolkit.load_example("panda")
    truth = toolkit.load_urdf(cal.perturb(panda, seed=3).urdf_text, mimic=False, tip=panda.tip)
    found = 0
    for seed in range(10):
        q = panda.random_q(seed=seed)
        lock = {"panda_joint3": float(q[2])}
        result = truth.ik_all(truth.fk(q), lock=lock)
        assert result.polished and not result.structure.exact
        assert (result.position_error <= 1e-10).all() and (result.orientation_error <= 1e-10).all()
        assert np.allclose(result.q[:, 2], q[2])
        found += any(same_up_to_turns(truth.joints.angles(r)[:7], truth.joints.angles(q)[:7], 1e-7)
                     for r in result.q)  # fmt: skip
    assert found >= 9


def test_the_xarm6_of_pybullet_data_is_solved_by_the_search_with_every_branch():
    import warnings
    from pathlib import Path

    data = pytest.importorskip("pybullet_data", reason="pybullet is in the test extra")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its meshes are not needed for the kinematics
        xarm = toolkit.load_urdf(Path(data.getDataPath()) / "xarm" / "xarm6_robot.urdf")
    assert xarm.structure.family == FAMILY  # no closed form: EAIK refuses the file
    compared = 0
    for seed in range(12):
        q = xarm.random_q(seed=seed)
        T = xarm.fk(q)
        result = xarm.ik_all(T)
        assert (result.position_error <= 1e-10).all() and (result.orientation_error <= 1e-10).all()
        assert any(
            same_up_to_turns(xarm.joints.angles(r), xarm.joints.angles(q), 1e-7) for r in result.q
        )
        for start in xarm.random_q(4, seed=50 + seed):
            found = xarm.ik(T, q0=start, tol=1e-10, restarts=0, method="numeric")
            if found.success:
                sigma = np.linalg.svd(xarm.jacobian(found.q), compute_uv=False)[-1]
                close = max(1e-6, 10 * 1e-10 / sigma)
                seen = xarm.joints.angles(found.q)
                assert any(same_up_to_turns(xarm.joints.angles(r), seen, close)
                           for r in result.q)  # fmt: skip
                compared += 1
    assert compared >= 10


def test_the_compiled_root_search_finds_the_numpy_searchs_roots_bit_for_bit(monkeypatch):
    """The compiled search (``search.roots``) against the numpy search it replaced
    (tests/oracles/search_roots.py): the same roots, in the same order, on the same curves,
    to the last bit, for random robots of the family and the Panda with joint 3 locked."""
    from oracles.search_roots import roots as numpy_roots

    from toolkit.ik.analytic import search

    compiled, seen = search.roots, []

    def both(chain, o, T, grid):
        ours, theirs = compiled(chain, o, T, grid), numpy_roots(chain, o, T, grid)
        seen.append(len(ours[0]))
        np.testing.assert_array_equal(ours[0], theirs[0])
        np.testing.assert_array_equal(ours[1], theirs[1])
        return ours

    monkeypatch.setattr(search, "roots", both)

    def python_form(robot, T, lock=()):  # the family's Python form, which calls roots
        chain, found = robot._analytic._chain_structure(robot.frames.id(None), lock)
        search.meeting_pairs(chain, found.points, T)

    robots = [toolkit.load_urdf(random_meeting_pairs()) for _ in range(2)]
    for robot in robots:
        for T in robot.fk(robot.random_q(6, seed=3)):
            python_form(robot, T)
    panda = toolkit.load_example("panda")
    Q = panda.random_q(6, seed=4)
    Q[:, 2] = 0.3
    for T in panda.fk(Q):
        python_form(panda, T, panda._analytic._locked({"panda_joint3": 0.3}))
    assert len(seen) == 18 and sum(seen) >= 36  # several roots a target


def _search_arms():
    """(robot, lock): two random robots of the family and the Panda with joint 3 locked."""
    panda = toolkit.load_example("panda")
    arms = [(toolkit.load_urdf(random_meeting_pairs()), None) for _ in range(2)]
    return [*arms, (panda, {"panda_joint3": 0.3})]


def test_the_compiled_search_family_equals_its_python_form_with_up_to_16_branches():
    """The kernel (16 rows) against the Python form: the same branches in the same order,
    the same labels named from its roots; with 8 rows, a target of more branches is handed
    back (-1) rather than cut."""
    from toolkit.ik import Family, families, registry
    from toolkit.ik.analytic.door import packed_family

    record = registry.REGISTRY[Family.MEETING_PAIRS]
    most = 0
    for robot, lock in _search_arms():
        chain, found = robot._analytic._chain_structure(
            robot.frames.id(None), robot._analytic._locked(lock)
        )
        packed = packed_family(chain, found)
        Q = robot.random_q(15, seed=8)
        if lock:
            Q[:, 2] = 0.3
        for T in robot.fk(Q):
            out, roots = np.zeros((16, 6)), np.full((16, 3), -1, np.int64)
            n = record.kernel(*packed, T, False, np.zeros(6), out, roots, np.zeros(16, np.int64))
            python = record.python(chain, found.points, T, families.EXACT_ONLY)
            assert n == len(python) >= 1
            for k, (angles, label) in enumerate(python):
                np.testing.assert_allclose(out[k], angles, atol=1e-12)
                assert Family.MEETING_PAIRS.label(tuple(roots[k].tolist())) == label
            few = record.kernel(*packed, T, False, np.zeros(6), out[:8], roots[:8],
                                np.zeros(8, np.int64))  # fmt: skip
            assert few == (n if n <= 8 else -1)
            most = max(most, n)
    assert most > 8  # a target with more branches than the closed forms' 8 rows


def test_ik_all_of_the_search_family_is_its_batch_of_one_and_auto_ik_stays_numeric():
    for robot, lock in _search_arms():
        Q = robot.random_q(8, seed=2)
        if lock:
            Q[:, 2] = 0.3
        Ts = robot.fk(Q)
        batch = robot.ik_all_batch(Ts, lock=lock)
        for n, T in enumerate(Ts):
            one = robot.ik_all(T, lock=lock)
            k = int(batch.found[n])
            assert len(one.q) == k and one.solved >= 1
            np.testing.assert_array_equal(one.q, batch.q[n, :k])
            np.testing.assert_array_equal(one.success, batch.success[n, :k])
            for q in one.q[one.success]:  # Pinocchio's forward kinematics, not the door's
                np.testing.assert_allclose(robot.fk(q), T, atol=1e-9)
        if lock is None:  # a search is slower than the numeric ik of one target
            assert robot.ik(Ts[0]).method == "numeric"
            answer = robot.ik(Ts[0], method="analytic")
            assert answer.method == "analytic" and answer.success
