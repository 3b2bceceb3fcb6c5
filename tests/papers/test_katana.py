"""Katana 6M (paper 1): Pinocchio vs an independent modified-DH product vs the closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import katana

# Paper 1, Table 2, written out here independently of the toolkit (degrees, as printed),
# with the Katana 450 lengths of data/katana.md.
A2, A3, A4 = 0.190, 0.139, 0.1473
A5 = {"6m180": 0.1555, "6m90a": 0.1505, "6m90b": 0.1505}
BASE_HEIGHT = 0.2015
LIMITS_DEG = [
    (-169.5, 169.5),
    (-30, 102),
    (-122.5, 122.5),
    (-112, 112),
    (-168, 168),
    (-29.5, 299.5),
]


def paper_table(variant: str) -> list[tuple[float, float, float]]:
    """(d, a, alpha[deg]) rows of Table 2."""
    a5 = A5[variant]
    rows = [(0, 0, 0), (0, 0, 90), (0, A2, 0), (0, A3, 0)]
    if variant == "6m180":
        return [*rows, (A4 + a5, 0, -90)]
    return [*rows, (A4, 0, -90), (a5, 0, -90 if variant == "6m90a" else 90)]


def eq2(alpha_deg: float, a: float, theta: float, d: float) -> np.ndarray:
    """Paper 1, eq. 2, typed in from the paper's matrix."""
    al = math.radians(alpha_deg)
    ct, st_, ca, sa = math.cos(theta), math.sin(theta), math.cos(al), math.sin(al)
    return np.array(
        [
            [ct, -st_, 0, a],
            [ca * st_, ca * ct, -sa, -d * sa],
            [sa * st_, sa * ct, ca, d * ca],
            [0, 0, 0, 1],
        ]
    )


def reference_fk(variant: str, q: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    for (d, a, alpha), theta in zip(paper_table(variant), q, strict=True):
        T = T @ eq2(alpha, a, theta, d)
    return T


BASE = np.eye(4)
BASE[2, 3] = BASE_HEIGHT


@pytest.mark.parametrize("variant", ["6m180", "6m90a", "6m90b"])
def test_pinocchio_matches_modified_dh_product(variant, rng):
    robot = toolkit.load(f"katana_{variant}")
    qs = robot.random_q(1000, rng)
    worst = 0.0
    for q in qs:
        worst = max(worst, np.abs(robot.fk(q) - BASE @ reference_fk(variant, q)).max())
    assert worst < 1e-12


@pytest.mark.parametrize("variant", ["6m180", "6m90a", "6m90b"])
def test_joint_limits_are_the_papers(variant):
    robot = toolkit.load(f"katana_{variant}")
    expected = np.radians(LIMITS_DEG[: robot.nq])
    np.testing.assert_allclose(robot.joints.lower, expected[:, 0], atol=1e-15)
    np.testing.assert_allclose(robot.joints.upper, expected[:, 1], atol=1e-15)


def test_dh_tables_are_papers_table_2():
    for variant in katana.VARIANTS:
        rows = katana.DH_TABLES[variant]
        expected = paper_table(variant)
        assert len(rows) == len(expected)
        for row, (d, a, alpha) in zip(rows, expected, strict=True):
            assert row.d == pytest.approx(d, abs=1e-15)
            assert row.a == pytest.approx(a, abs=1e-15)
            assert row.alpha == pytest.approx(math.radians(alpha), abs=1e-15)


def test_closed_form_matches_pinocchio(rng):
    robot = toolkit.load("katana_6m180")
    qs = robot.random_q(2000, rng)
    closed = katana.closed_form_fk(qs)
    pino = np.linalg.inv(BASE) @ robot.fk(qs)
    assert np.abs(closed - pino).max() < 1e-12
    # the single-configuration call agrees with the batch
    np.testing.assert_array_equal(katana.closed_form_fk(qs[7]), closed[7])


def test_closed_form_with_other_lengths_matches_render(rng):
    lengths = (0.21, 0.15, 0.12, 0.08)
    robot = toolkit.load("katana_6m180", a2=0.21, a3=0.15, a4=0.12, a5=0.08)
    qs = robot.random_q(200, rng)
    assert (
        np.abs(katana.closed_form_fk(qs, lengths) - np.linalg.inv(BASE) @ robot.fk(qs)).max()
        < 1e-12
    )


def test_dh_fk_matches_reference(rng):
    for variant in katana.VARIANTS:
        n = len(paper_table(variant))
        for q in rng.uniform(-3, 3, size=(50, n)):
            np.testing.assert_allclose(
                katana.dh_fk(q, variant), reference_fk(variant, q), atol=1e-14
            )


REACH = A2 + A3 + A4 + A5["6m180"]


@pytest.mark.parametrize(
    ("q", "p"),
    [
        ([0, 0, 0, 0, 0], [A2 + A3, 0, A4 + A5["6m180"]]),  # (18)
        ([0, 0, 0, -math.pi / 2, 0], [REACH, 0, 0]),  # (19)
        ([0, math.pi / 2, 0, -math.pi / 2, 0], [0, 0, REACH]),  # (20)
    ],
    ids=["case18", "case19", "case20"],
)
def test_paper_sanity_cases(q, p):
    robot = toolkit.load("katana_6m180")
    np.testing.assert_allclose(katana.closed_form_fk(q)[:3, 3], p, atol=1e-15)
    np.testing.assert_allclose(robot.fk(q)[:3, 3], np.add(p, [0, 0, BASE_HEIGHT]), atol=1e-15)


def test_approach_column_of_paper():
    # a_x = -cos t1 sin t234, a_y = -sin t1 sin t234, a_z = cos t234 (eqs. 12-15)
    q = np.array([0.3, 0.4, -0.2, 0.9, 1.1])
    t234 = q[1] + q[2] + q[3]
    a = katana.closed_form_fk(q)[:3, 2]
    expected = [-math.cos(q[0]) * math.sin(t234), -math.sin(q[0]) * math.sin(t234), math.cos(t234)]
    np.testing.assert_allclose(a, expected, atol=1e-15)
    n_z, s_z = katana.closed_form_fk(q)[2, :2]
    assert n_z == pytest.approx(math.sin(t234) * math.cos(q[4]), abs=1e-15)
    assert s_z == pytest.approx(-math.sin(t234) * math.sin(q[4]), abs=1e-15)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-10, 10, allow_nan=False), min_size=5, max_size=5))
def test_closed_form_equals_dh_product_anywhere(q):
    np.testing.assert_allclose(
        katana.closed_form_fk(q), reference_fk("6m180", np.array(q)), atol=1e-12
    )


def test_nominal_torques_eq1():
    drive = [  # P [W], n [rpm], eta_M, i_R, eta_R from the paper's drive table
        (44.5, 6400, 0.84, 100, 0.80),
        (47.9, 6400, 0.85, 371, 0.80),
        (23.2, 6400, 0.79, 371, 0.80),
        (44.5, 6400, 0.84, 100, 0.80),
        (3.88, 7800, 0.81, 100, 0.80),
        (3.88, 7800, 0.81, 100, 0.80),
    ]
    expected = [P / (2 * math.pi * n / 60) * em * ir * er for P, n, em, ir, er in drive]
    torques = katana.nominal_torques()
    assert torques.shape == (6,)
    np.testing.assert_allclose(torques, expected, rtol=1e-14)
    # the joint effort limits of the URDF are the same nominal torques
    robot = toolkit.load("katana_6m90a")
    np.testing.assert_allclose(robot.model.effortLimit, expected, rtol=1e-12)


def test_closed_form_rejects_bad_input():
    with pytest.raises(toolkit.ConfigurationError, match="shape"):
        katana.closed_form_fk([0, 0, 0])
    with pytest.raises(toolkit.ConfigurationError, match="NaN"):
        katana.closed_form_fk([0, 0, float("nan"), 0, 0])
    with pytest.raises(toolkit.InvalidParameterError, match="a3"):
        katana.closed_form_fk(np.zeros(5), (0.19, -0.1, 0.1, 0.1))
    with pytest.raises(toolkit.InvalidParameterError, match="variant"):
        katana.dh_table("6m42")
