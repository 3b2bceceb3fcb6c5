"""The kernels' sine and cosine (:mod:`toolkit.kinematics.trig`) against the C library's."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from toolkit.kinematics import trig


@numba.njit(cache=False)
def _ours(X):
    out = np.empty((X.shape[0], 2))
    for i in range(X.shape[0]):
        out[i, 0], out[i, 1] = trig.sincos(X[i])
    return out


@numba.njit(cache=False)
def _reduced(X):  # the plain loop that vectorizes
    out = np.empty((2, X.shape[0]))
    for i in range(X.shape[0]):
        out[0, i], out[1, i] = trig.sincos_reduced(X[i])
    return out


def _ulps(X, got):
    want = np.stack([np.sin(X), np.cos(X)], axis=1)
    return np.abs(got - want) / np.spacing(np.abs(want))


@pytest.mark.parametrize(("width", "ulps"), [(50.0, 1.0), (trig.REDUCED, 2.0)])
def test_within_units_in_the_last_place(width, ulps):
    X = np.random.default_rng(3).uniform(-width, width, 1_000_000)
    assert _ulps(X, _ours(X)).max() <= ulps


def test_exact_near_the_quarter_turns():
    """Where sin or cos is near 0 (x near k pi / 2) the reduction keeps every digit."""
    rng = np.random.default_rng(4)
    k = rng.integers(-60_000, 60_000, 100_000)
    X = k * (math.pi / 2) + rng.normal(0.0, 1e-9, len(k))
    X = np.concatenate([X, k[:1000] * (math.pi / 2), [0.0, math.pi, -math.pi, 1e-300]])
    assert _ulps(X, _ours(X)).max() <= 1.0


def test_beyond_the_reduction_and_not_finite():
    X = np.array([trig.REDUCED, -trig.REDUCED, 3.7e7, -1e300])
    got = _ours(X)
    np.testing.assert_array_equal(got, np.stack([np.sin(X), np.cos(X)], axis=1))
    assert np.isnan(_ours(np.array([np.nan, np.inf, -np.inf]))).all()


def test_the_vectorized_loop_gives_the_same_bits():
    X = np.random.default_rng(5).uniform(-trig.REDUCED, trig.REDUCED, 10_001)
    np.testing.assert_array_equal(_reduced(X), _ours(X).T)
