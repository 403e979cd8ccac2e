# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Fixations to 90% correct and its bootstrap interval."""
from ipomdp_gaze.evaluation import fixations_to_90_ci, fixations_to_level, paired_difference_ci
import numpy as np
import pytest


def test_linear_interpolation_between_fixations():
    assert fixations_to_level(np.array([0.5, 0.8, 0.95, 1.0]), 10) == pytest.approx(2 + 1 / 1.5)
    assert fixations_to_level(np.array([0.9, 1.0]), 10) == pytest.approx((0.9 - 0.1) / 0.8)


def test_never_reached_is_none():
    assert fixations_to_level(np.array([0.2, 0.5, 0.89]), 4) is None
    assert np.isnan(fixations_to_level(np.array([[0.2, 0.3], [0.5, 0.95]]), 4)[0])


def test_bootstrap_interval_covers_the_truth():
    """Episodes correct from fixation T_e on, T_e uniform on 1..10: the curve is t/10."""
    rng = np.random.default_rng(0)
    first = rng.integers(1, 11, size=4000)
    correct = np.arange(1, 13)[None, :] >= first[:, None]
    point, (low, high) = fixations_to_90_ci(correct, 100, rng, 500)
    assert low <= point <= high
    assert low - 0.05 < 9.0 < high + 0.05
    assert high - low < 0.5


def test_paired_difference_of_identical_runs_is_zero():
    rng = np.random.default_rng(1)
    correct = np.arange(1, 13)[None, :] >= rng.integers(1, 11, size=500)[:, None]
    diff, (low, high) = paired_difference_ci(correct, correct, 100, rng, 200)
    assert diff == 0 and low == 0 and high == 0
