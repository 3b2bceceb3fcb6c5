"""A joint locked after every joint of the chain (the Panda's seventh) at a new angle: its
structure comes from the first angle's by moving the frame (``chain.retipped``), and every
answer equals a fresh detection's; a lock in the middle of the chain at a new angle tries
the family found at its earlier angles first, and finds what a fresh detection finds."""

from __future__ import annotations

import numpy as np
import pytest

import toolkit
from toolkit import calibration as cal

PANDA = toolkit.load_example("panda")


def _fresh(robot: toolkit.Robot) -> toolkit.Robot:
    """The same model with empty caches (no template)."""
    return toolkit.Robot(robot.model, tip=robot.tip)


@pytest.mark.parametrize("near", [False, True])
def test_a_tail_lock_at_new_angles_answers_as_a_fresh_detection(near):
    robot = PANDA
    if near:  # a calibrated Panda: its family only near, every branch polished
        robot = toolkit.load_urdf(cal.perturb(PANDA, seed=3).urdf_text, tip=PANDA.tip)
    Q = robot.random_q(12, seed=41)
    Ts = robot.fk(Q)
    for q, T in zip(Q, Ts, strict=True):
        lock = {"panda_joint7": float(q[6])}
        a, b = robot.structure_of(lock=lock), _fresh(robot).structure_of(lock=lock)
        assert (a.family, a.reversed, a.exact) == (b.family, b.reversed, b.exact)
        assert a.deviation == pytest.approx(b.deviation, abs=1e-12)
        np.testing.assert_allclose(a.points, b.points, rtol=0, atol=1e-12)
        here, fresh = robot.ik_all(T, lock=lock), _fresh(robot).ik_all(T, lock=lock)
        assert here.polished == fresh.polished == near and here.success.any()
        if near:  # the same solutions; which exact branch a polish came from (its label)
            # may differ where the exact geometry's roots are within rounding of double
            A, B = here.q[here.success], fresh.q[fresh.success]
            assert len(A) == len(B)
            assert all(np.abs(B - a).max(axis=1).min() < 1e-8 for a in A)
            continue
        assert here.labels == fresh.labels
        np.testing.assert_allclose(here.q, fresh.q, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(here.success, fresh.success)
    kept = robot._analytic.caches.structures
    templates = [k for k in kept if isinstance(k, tuple) and k[0] == "tail"]
    assert len(templates) == 1  # kept once, used for the other angles


def test_a_lock_in_the_middle_of_the_chain_keeps_no_template():
    robot = _fresh(PANDA)
    q = robot.random_q(seed=42)
    robot.ik_all(robot.fk(q), lock={"panda_joint3": float(q[2])})
    kept = robot._analytic.caches.structures
    assert not [k for k in kept if isinstance(k, tuple) and k[0] == "tail"]


def test_retipped_moves_a_reversed_familys_points_with_the_frame():
    """The reversed chain's points at a new frame are the fresh reversed chain's."""
    from toolkit.ik.analytic.chain import chain_of, retipped, reverse

    j7 = int(PANDA.model.getJointId("panda_joint7"))
    fid = PANDA.frames.id(None)
    base = chain_of(PANDA.model, fid, {j7: 0.3})
    found = PANDA.structure_of(lock={"panda_joint7": 0.3})
    assert found.reversed
    other = chain_of(PANDA.model, fid, {j7: -1.1})
    moved, structure = retipped(base, found, other.tip)
    np.testing.assert_allclose(moved.tip, other.tip, atol=1e-15)
    np.testing.assert_allclose(reverse(moved).points, reverse(other).points, atol=1e-12)
    assert structure.points is not None and found.points is not None
    G = np.linalg.inv(other.tip) @ base.tip
    np.testing.assert_allclose(structure.points, found.points @ G[:3, :3].T + G[:3, 3])


@pytest.mark.parametrize("near", [False, True])
def test_a_mid_chain_lock_at_new_angles_keeps_its_family_as_a_fresh_detection_finds_it(near):
    robot = PANDA
    if near:
        robot = toolkit.load_urdf(cal.perturb(PANDA, seed=4).urdf_text, tip=PANDA.tip)
    robot = _fresh(robot)
    for angle in np.random.default_rng(5).uniform(-2.8, 2.8, 12).tolist():
        lock = {"panda_joint3": angle}
        a, b = robot.structure_of(lock=lock), _fresh(robot).structure_of(lock=lock)
        assert (a.family, a.reversed, a.exact, a.joints) == (
            b.family,
            b.reversed,
            b.exact,
            b.joints,
        )
        np.testing.assert_allclose(a.points, b.points, rtol=0, atol=1e-12)
        assert a.deviation == pytest.approx(b.deviation, abs=1e-15)
    hints = robot._analytic.caches.families
    assert list(hints.values()) == [(a.family, a.reversed)]  # one entry: joint 3 on the tip


def test_a_hint_whose_family_does_not_hold_is_passed_over():
    from toolkit.ik.analytic import structure as arm

    chain = arm.chain_of(PANDA.model, PANDA.frames.id(None), {3: 0.7})  # panda_joint3 locked
    plain = arm.find_structure(chain)
    assert plain.family == arm.Family.MEETING_PAIRS
    for hint in [(arm.Family.THREE_PARALLEL, False), (arm.Family.SPHERICAL_WRIST, True)]:
        hinted = arm.find_structure(chain, hint)
        assert (hinted.family, hinted.reversed, hinted.reason) == (
            plain.family, plain.reversed, plain.reason,
        )  # fmt: skip
