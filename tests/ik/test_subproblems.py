"""The subproblems of analytic IK against their definitions (hypothesis), degenerate
cases included: each answer is put back into the equation it solves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from toolkit.ik.analytic import subproblem_kernels as sk
from toolkit.ik.analytic.subproblems import (
    EXACT,
    INFINITE,
    LEAST_SQUARES,
    circle_pair,
    rot,
    sp1,
    sp2,
    sp3,
    sp4,
    sp5,
    sp6,
)  # fmt: skip

VEC = st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3).map(np.array)
ANGLE = st.floats(-math.pi, math.pi)
# SP5, SP6: vectors on a grid of eighths, so that a degenerate instance is exactly so (a
# matrix within round-off of rank 1 loses digits and may be answered in least squares)
GRID = st.lists(st.integers(-8, 8), min_size=3, max_size=3).map(lambda v: np.array(v) / 8.0)


def _unit(v):
    n = np.linalg.norm(v)
    return v / n if n > 1e-3 else np.array([0.0, 0.0, 1.0])


def test_rot_is_a_right_handed_turn():
    np.testing.assert_allclose(rot(np.array([0.0, 0, 1]), math.pi / 2) @ [1, 0, 0], [0, 1, 0],
                               atol=1e-15)  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(VEC, VEC, ANGLE)
def test_sp1_recovers_the_angle_that_made_p2(p, k, theta):
    k = _unit(k)
    if np.linalg.norm(p - k * (k @ p)) < 1e-3:
        return
    got, kind = sp1(p, rot(k, theta) @ p, k)
    assert kind == EXACT
    np.testing.assert_allclose(rot(k, got) @ p, rot(k, theta) @ p, atol=1e-12)


@settings(max_examples=300, deadline=None)
@given(VEC, VEC, VEC)
def test_sp1_least_squares_is_no_worse_than_any_angle(p1, p2, k):
    k = _unit(k)
    got, _ = sp1(p1, p2, k)
    best = np.linalg.norm(rot(k, got) @ p1 - p2)
    for t in np.linspace(-math.pi, math.pi, 73):
        assert best <= np.linalg.norm(rot(k, t) @ p1 - p2) + 1e-9  # a point on the axis: ties


def test_sp1_on_the_axis_says_every_angle():
    k = np.array([0.0, 0.0, 1.0])
    assert sp1(2 * k, 2 * k, k) == (0.0, INFINITE)
    assert sp1(2 * k, np.array([1.0, 0, 0]), k)[1] == LEAST_SQUARES


@settings(max_examples=300, deadline=None)
@given(VEC, VEC, VEC, ANGLE)
def test_sp4_finds_the_angle_that_made_d_and_its_twin(h, p, k, theta):
    k = _unit(k)
    d = float(h @ rot(k, theta) @ p)
    got, kind = sp4(h, p, k, d)
    if kind == INFINITE:
        return
    assert kind == EXACT
    for t in got:
        assert abs(h @ rot(k, t) @ p - d) < 1e-9
    # the angle used is among them (up to 2 pi), unless the equation does not depend on it
    dist = min(abs(math.remainder(t - theta, 2 * math.pi)) for t in got)
    slope = abs(h @ np.cross(k, rot(k, theta) @ p))
    assert dist < 1e-6 or slope < 1e-4


def test_sp4_out_of_reach_gives_the_closest_and_says_so():
    h, p, k = np.array([1.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 0, 1])
    (t,), kind = sp4(h, p, k, 2.0)
    assert kind == LEAST_SQUARES and abs(t) < 1e-12  # h^T R p = cos t: largest at 0
    assert sp4(k, k, k, 1.0)[1] == INFINITE  # does not depend on theta, and holds
    assert sp4(k, k, k, 0.5)[1] == LEAST_SQUARES


@settings(max_examples=300, deadline=None)
@given(VEC, VEC, VEC, ANGLE)
def test_sp3_reaches_the_distance(p1, p2, k, theta):
    k = _unit(k)
    d = float(np.linalg.norm(rot(k, theta) @ p1 - p2))
    got, kind = sp3(p1, p2, k, d)
    if kind == INFINITE:
        return
    # within TANGENT of a tangent SP3 gives one root: the two it merges lie up to
    # sqrt(2 TANGENT) ~ 1.4e-7 rad apart, which moves the point on its circle (radius r)
    r = float(np.linalg.norm(p1 - k * (k @ p1)))
    for t in got:
        assert abs(np.linalg.norm(rot(k, t) @ p1 - p2) - d) < 1e-7 + 1.5e-7 * r


@settings(max_examples=300, deadline=None)
@given(VEC, VEC, VEC, ANGLE, ANGLE)
# both points within ZERO of their axes: SP1's thresholds and SP2's used to disagree
@example(np.array([0.0, 1e-12, 0.0]), np.zeros(3), np.array([0.0, 1.0, 0.0]), 1.0, 1.0)
def test_sp2_recovers_both_angles(p, k1, k2, t1, t2):
    k1, k2 = _unit(k1), _unit(k2)
    if np.linalg.norm(np.cross(k1, k2)) < 0.1:  # nearly parallel: the meeting point is
        return  # ill-conditioned (1 / |k1 x k2|^2), parallel axes are tested below
    p1 = p
    p2 = rot(k2, t2).T @ rot(k1, t1) @ p1  # so that R(k1, t1) p1 = R(k2, t2) p2
    got, kind = sp2(p1, p2, k1, k2)
    assert kind in (EXACT, INFINITE)
    for a, b in got:
        np.testing.assert_allclose(rot(k1, a) @ p1, rot(k2, b) @ p2, atol=1e-7)
    if kind == EXACT:
        assert min(np.linalg.norm(rot(k1, a) @ p1 - rot(k1, t1) @ p1) for a, _ in got) < 1e-6


def test_sp2_parallel_axes_are_a_family_and_disjoint_circles_least_squares():
    z = np.array([0.0, 0, 1])
    assert sp2(np.array([1.0, 0, 0]), np.array([0.0, 1, 0]), z, z)[1] == INFINITE
    x = np.array([1.0, 0, 0])
    _, kind = sp2(np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, 1.0]) * 0.5, x, z)
    assert kind == LEAST_SQUARES


@pytest.mark.parametrize("fn", [sp1, sp3, sp4])
def test_no_division_by_zero_on_zero_vectors(fn):
    z = np.zeros(3)
    k = np.array([0.0, 0.0, 1.0])
    with np.errstate(all="raise"):
        if fn is sp1:
            fn(z, z, k)
        else:
            fn(z, z, k, 0.0)


ROW = st.lists(st.floats(-12.0, 12.0), min_size=1, max_size=6)


@settings(max_examples=300, deadline=None)
@given(ROW, st.data())
def test_turns_list_every_whole_turn_within_the_limits_and_nothing_else(row, data):
    from toolkit.ik.analytic.branches import turns, turns_many

    n = len(row)
    lo = np.array(data.draw(st.lists(st.floats(-9.0, 0.0), min_size=n, max_size=n)))
    hi = lo + np.array(data.draw(st.lists(st.floats(0.0, 14.0), min_size=n, max_size=n)))
    sliding = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    a = np.array(row)
    got = turns(a, lo, hi)
    # brute force: each joint's turns a + 2 pi k inside [lo, hi], every combination
    w = np.remainder(a + np.pi, 2 * np.pi) - np.pi
    per = []
    for j in range(n):
        inside = [w[j] + 2 * np.pi * k for k in range(-6, 7)
                  if lo[j] - 1e-12 <= w[j] + 2 * np.pi * k <= hi[j] + 1e-12]  # fmt: skip
        per.append(inside or [w[j]])
    want = np.array(np.meshgrid(*per, indexing="ij")).reshape(n, -1).T
    assert got.shape == want.shape and np.allclose(got, want)
    # many rows at once: each row's turns in order; a prismatic joint keeps its value
    rows, owner = turns_many(np.stack([a, a + 1.0]), lo, hi, sliding)
    for i, base in enumerate([a, a + 1.0]):
        mine = rows[owner == i]
        assert np.allclose(mine[:, sliding], base[sliding])
        alone = turns(base[~sliding], lo[~sliding], hi[~sliding])
        assert np.allclose(mine[:, ~sliding], alone)


@settings(max_examples=300, deadline=None)
@given(st.integers(1, 9), st.integers(1, 6), st.data())
def test_distinct_keeps_each_row_unequal_up_to_turns_to_every_earlier_one(rows, n, data):
    from toolkit.ik.analytic.branches import distinct

    pick = st.floats(-9.0, 9.0)
    sliding = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    A = np.array(data.draw(st.lists(st.lists(pick, min_size=n, max_size=n), min_size=rows,
                                    max_size=rows)))  # fmt: skip
    for i in range(1, rows):  # some rows repeat an earlier one, turned by whole turns
        if data.draw(st.booleans()):
            k = np.array(data.draw(st.lists(st.integers(-2, 2), min_size=n, max_size=n)))
            A[i] = A[data.draw(st.integers(0, i - 1))] + 2 * np.pi * k * ~sliding
    keep = distinct(A, sliding)
    for i in range(rows):  # the definition, row by row against every earlier row
        gaps = [max(abs(d) if s else abs(math.remainder(d, 2 * math.pi))
                    for d, s in zip(A[i] - A[k], sliding, strict=True))
                for k in range(i)]  # fmt: skip
        assert keep[i] == all(g >= 1e-9 for g in gaps)


def test_turns_refuse_limits_that_give_too_many_rows_with_the_joints_named():
    from toolkit.errors import InvalidParameterError
    from toolkit.ik.analytic.branches import MAX_TURN_ROWS, turns_many

    wide = np.full(6, 200.0)  # 0 + 2 pi k for k in -31..31: 63 turns per joint
    with pytest.raises(InvalidParameterError, match=r"joints \[0, 1, 2, 3, 4, 5\].*narrow"):
        turns_many(np.zeros((2, 6)), -wide, wide, np.zeros(6, dtype=bool))
    rows, _ = turns_many(np.zeros((1, 3)), -wide[:3], wide[:3], np.zeros(3, dtype=bool))
    assert len(rows) == 63**3 <= MAX_TURN_ROWS


def _same(a, b, close=1e-6):
    return abs(math.remainder(a - b, 2 * math.pi)) < close


@settings(max_examples=300, deadline=None)
@given(GRID, GRID, GRID, GRID, GRID, GRID, ANGLE, ANGLE, ANGLE)
def test_sp5_recovers_the_angles_that_made_p0_and_each_answer_solves_it(
    p1, p2, p3, k1, k2, k3, t1, t2, t3
):
    k1, k2, k3 = _unit(k1), _unit(k2), _unit(k3)
    p0 = rot(k2, t2) @ (p2 + rot(k3, t3) @ p3) - rot(k1, t1) @ p1
    sols, kind = sp5(p0, p1, p2, p3, k1, k2, k3)
    if kind == EXACT:
        for a, b, c in sols:
            miss = p0 + rot(k1, a) @ p1 - rot(k2, b) @ (p2 + rot(k3, c) @ p3)
            assert np.linalg.norm(miss) < 1e-7
    # where the generating angles are well determined (the residual's Jacobian in (t1, t2,
    # t3) far from singular: no family of answers, no multiple root), they are found
    x3 = rot(k3, t3) @ p3
    J = np.stack([np.cross(k1, rot(k1, t1) @ p1), -np.cross(k2, rot(k2, t2) @ (p2 + x3)),
                  -rot(k2, t2) @ np.cross(k3, x3)], axis=1)  # fmt: skip
    if np.linalg.svd(J, compute_uv=False)[-1] > 0.05:
        assert kind == EXACT
        assert any(_same(a, t1, 1e-6) and _same(c, t3, 1e-6) for a, _, c in sols)


@settings(max_examples=300, deadline=None)
@given(st.lists(GRID, min_size=12, max_size=12), ANGLE, ANGLE)
def test_sp6_recovers_both_angles_and_each_answer_solves_it(vecs, t1, t2):
    h, k, p = vecs[:4], [_unit(v) for v in vecs[4:8]], vecs[8:]
    d = (float(h[0] @ rot(k[0], t1) @ p[0] + h[1] @ rot(k[1], t2) @ p[1]),
         float(h[2] @ rot(k[2], t1) @ p[2] + h[3] @ rot(k[3], t2) @ p[3]))  # fmt: skip
    sols, kind = sp6(tuple(h), tuple(k), tuple(p), d)
    if kind == EXACT:  # each answer solves it (to round-off; at a double root, its square root)
        for a, b in sols:
            assert abs(h[0] @ rot(k[0], a) @ p[0] + h[1] @ rot(k[1], b) @ p[1] - d[0]) < 1e-6
            assert abs(h[2] @ rot(k[2], a) @ p[2] + h[3] @ rot(k[3], b) @ p[3] - d[1]) < 1e-6

    def turn(i, t):  # d/dt of h_i^T R(k_i, t) p_i
        return float(h[i] @ np.cross(k[i], rot(k[i], t) @ p[i]))

    J = np.array([[turn(0, t1), turn(1, t2)], [turn(2, t1), turn(3, t2)]])
    if np.linalg.svd(J, compute_uv=False)[-1] > 0.05:  # well determined: found, exactly
        assert kind == EXACT
        assert any(_same(a, t1, 1e-6) and _same(b, t2, 1e-6) for a, b in sols)


def test_sp5_and_sp6_say_when_no_angle_or_every_angle_solves():
    x, y, z = np.eye(3)
    far = sp5(np.array([10.0, 0, 0]), x, x, x, z, x, y)  # 10 m apart, arms of 1 m
    assert far[1] == LEAST_SQUARES and len(far[0]) >= 1
    assert sp5(np.array([10.0, 0, 0]), x, x, x, z, z, z)[1] == LEAST_SQUARES  # flat, too far
    assert sp5(np.zeros(3), x, x, y, z, z, z)[1] == INFINITE  # flat and within reach
    zero = np.zeros(3)
    assert sp6((zero,) * 4, (z,) * 4, (x,) * 4, (0.0, 0.0))[1] == INFINITE
    assert sp5(zero, zero, zero, zero, z, z, z)[1] == INFINITE


ENTRY = st.integers(-4, 4).map(lambda v: v / 4.0)  # small integers: rank-1 matrices, often
FLAG = {sk.EXACT: EXACT, sk.LEAST_SQUARES: LEAST_SQUARES, sk.INFINITE: INFINITE}
"""The compiled subproblems' integer flags as the Python forms' words."""


@settings(max_examples=400, deadline=None)
@given(st.lists(ENTRY, min_size=8, max_size=8), ANGLE, ANGLE, st.booleans())
def test_the_compiled_circle_pair_flags_as_the_python_one_and_its_pairs_solve(
    entries, t1, t2, reachable
):
    """Random 2x2 matrices on a coarse grid (many of rank 1 or 0), with a right-hand side
    reached by (t1, t2) or not: the same flag as the Python form; exact pairs solve both
    equations, and include (t1, t2) where it is well determined."""
    from toolkit.ik.analytic import sp5_kernels

    A1 = np.array(entries[:4]).reshape(2, 2)
    A2 = np.array(entries[4:]).reshape(2, 2)
    d = A1 @ [math.cos(t1), math.sin(t1)] + A2 @ [math.cos(t2), math.sin(t2)]
    if not reachable:
        d = d * 3.0 + 1.0
    _, kind = circle_pair(A1, A2, d)
    pairs = np.zeros((4, 2))
    count, code = sp5_kernels.circle_pair(A1, A2, d, pairs)
    assert FLAG[code] == kind and 1 <= count <= 4
    if kind != EXACT:
        return
    size = max(1.0, np.abs(A1).sum() + np.abs(A2).sum() + np.abs(d).sum())
    for a, b in pairs[:count]:
        miss = A1 @ [math.cos(a), math.sin(a)] + A2 @ [math.cos(b), math.sin(b)] - d
        assert np.abs(miss).max() <= 1e-8 * size
    J = np.stack([A1 @ [-math.sin(t1), math.cos(t1)], A2 @ [-math.sin(t2), math.cos(t2)]], 1)
    if reachable and np.linalg.svd(J, compute_uv=False)[-1] > 0.05:
        assert any(_same(a, t1) and _same(b, t2) for a, b in pairs[:count])


@settings(max_examples=200, deadline=None)
@given(GRID, GRID, GRID, GRID, GRID, GRID, ANGLE, ANGLE, ANGLE)
def test_the_compiled_sp5_solves_and_finds_what_the_python_one_does(
    p1, p2, p3, k1, k2, k3, t1, t2, t3
):
    """Where both say exact, every compiled answer closes the loop; where the generating
    angles are well determined, both find them (the compiled form may find a double root
    the Python form's Newton stops short of)."""
    from toolkit.ik.analytic import sp5_kernels

    k1, k2, k3 = _unit(k1), _unit(k2), _unit(k3)
    p0 = rot(k2, t2) @ (p2 + rot(k3, t3) @ p3) - rot(k1, t1) @ p1
    _, kind = sp5(p0, p1, p2, p3, k1, k2, k3)
    out = np.zeros((4, 3))
    count, code = sp5_kernels.sp5(p0, p1, p2, p3, k1, k2, k3, out)
    if FLAG[code] == EXACT:
        for a, b, c in out[:count]:
            miss = p0 + rot(k1, a) @ p1 - rot(k2, b) @ (p2 + rot(k3, c) @ p3)
            assert np.linalg.norm(miss) < 1e-7
    x3 = rot(k3, t3) @ p3
    J = np.stack([np.cross(k1, rot(k1, t1) @ p1), -np.cross(k2, rot(k2, t2) @ (p2 + x3)),
                  -rot(k2, t2) @ np.cross(k3, x3)], axis=1)  # fmt: skip
    if np.linalg.svd(J, compute_uv=False)[-1] > 0.05:
        assert kind == EXACT and FLAG[code] == EXACT
        assert any(_same(a, t1) and _same(c, t3) for a, _, c in out[:count])
