# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""search.repeat_weight: a cell's repeated views of a still scene weighted, vs brute force."""
from dataclasses import replace

from ipomdp_gaze.model.belief import bayes_update, uniform_log_belief
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation, GaussianObservation
from ipomdp_gaze.model.still_evidence import cell_information, check_repeat_weight, StillEvidence
from ipomdp_gaze.model.stopping import initial_log_belief
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.session import SearchSettings
import numpy as np
import pytest

GRID = Grid(4, 5, 1.0)
K = 4


def count_model(seed=0):
    """Random tables, informative within one cell of the fixation and silent beyond."""
    rng = np.random.default_rng(seed)
    null = rng.dirichlet(np.full(K, 2.0), size=GRID.shape)
    target = rng.dirichlet(np.full(K, 2.0), size=GRID.shape)
    target[2:, :] = null[2:, :]
    target[:, 2:] = null[:, 2:]
    return CountObservation(GRID, target, null)


def brute_force(model, frames, weight, absent_prior=0.0):
    """
    Compute the belief from first principles.

    Per cell, the frames that observed it at an informative offset: the first of the most
    informative counts fully, every other one by ``weight``.
    """
    kernel = model.elm_kernel()
    n = GRID.n_cells
    total = np.zeros(n)
    for i in range(n):
        r, c = divmod(i, GRID.cols)
        seen = []
        for fixation, frame in frames:
            fr, fc = divmod(fixation, GRID.cols)
            info = kernel[r - fr + GRID.rows - 1, c - fc + GRID.cols - 1]
            term = model.log_likelihood_ratio(frame, fixation)[i]
            if info > 0 and not np.isnan(frame[i]):
                seen.append((info, term))
        if seen:
            best = max(range(len(seen)), key=lambda j: (seen[j][0], -j))
            total[i] = seen[best][1] + weight * sum(t for j, (_, t) in enumerate(seen)
                                                    if j != best)
    log_b = initial_log_belief(n, absent_prior)
    if absent_prior:
        total = np.append(total, 0.0)
    log_b = log_b + total
    b = np.exp(log_b - log_b.max())
    return b / b.sum()


def core(model, weight, **kwargs):
    return GazeController(GRID, model, build_policy('elm', GRID, model),
                          SearchSettings(confidence=1 - 1e-12, repeat_weight=weight, **kwargs))


@pytest.mark.parametrize('weight', [0.0, 0.3, 1.0])
@pytest.mark.parametrize('absent_prior', [0.0, 0.2])
def test_the_belief_is_the_brute_force_posterior(weight, absent_prior):
    model = count_model(1)
    rng = np.random.default_rng(5)
    controller = core(model, weight, absent_prior=absent_prior, inhibit_return=False)
    frames = []
    for t in range(1, 16):
        frame = rng.integers(0, K + 2, GRID.n_cells).astype(float)   # some above K - 1: clipped
        frame[rng.random(GRID.n_cells) < 0.2] = np.nan
        frames.append((controller.fixation, frame))
        assert controller.offer(frame, float(t)).applied
        expected = brute_force(model, frames, weight, absent_prior)
        np.testing.assert_allclose(controller.belief, expected[:GRID.n_cells], rtol=1e-9,
                                   atol=1e-15)
        assert controller.absent_probability == pytest.approx(
            expected[-1] if absent_prior else 0.0, rel=1e-9, abs=1e-15)


def test_weight_one_is_the_naive_bayes_product_of_every_frame():
    model = count_model(2)
    rng = np.random.default_rng(3)
    controller = core(model, 1.0)
    log_b = uniform_log_belief(GRID.n_cells)
    for t in range(1, 12):
        frame = rng.integers(0, K, GRID.n_cells).astype(float)
        fixation = controller.fixation
        controller.offer(frame, float(t))
        log_b = bayes_update(log_b, model.log_likelihood_ratio(frame, fixation))
        np.testing.assert_array_equal(controller.belief, np.exp(log_b))


def test_a_persistent_false_alarm_seen_from_many_poses_is_counted_once():
    """A still scene: one cell fires in every view; with weight 0 one view's worth remains."""
    model = count_model(4)
    false_alarm = GRID.index(1, 2)
    naive, once = core(model, 1.0, inhibit_return=True), core(model, 0.0, inhibit_return=True)
    frame = np.zeros(GRID.n_cells)
    frame[false_alarm] = K - 1
    frames = []
    for t in range(1, 8):
        frames.append((once.fixation, frame))
        for controller in (naive, once):
            controller.offer(frame, float(t))
    assert [f for f, _ in frames] != [frames[0][0]] * len(frames)     # several poses
    np.testing.assert_allclose(once.belief, brute_force(model, frames, 0.0), rtol=1e-9)
    assert naive.belief[false_alarm] > once.belief[false_alarm]
    information = cell_information(model.elm_kernel(), GRID, false_alarm)
    assert information[false_alarm] == model.elm_kernel()[GRID.rows - 1, GRID.cols - 1]


def test_motion_turns_it_off_and_a_change_keeps_the_belief():
    model = count_model(6)
    rng = np.random.default_rng(8)
    moving = core(model, 0.0, motion_sigma_cells=0.5)
    naive = core(model, 1.0, motion_sigma_cells=0.5)
    for t in range(1, 6):
        frame = rng.integers(0, K, GRID.n_cells).astype(float)
        moving.offer(frame, float(t))
        naive.offer(frame, float(t))
    np.testing.assert_array_equal(moving.belief, naive.belief)
    # A still search switched to weight 0 mid-way: earlier frames stay as they were counted.
    controller = core(model, 1.0)
    frames = []
    for t in range(1, 5):
        frame = rng.integers(0, K, GRID.n_cells).astype(float)
        controller.offer(frame, float(t))
    before = controller.belief
    controller.configure(replace(controller.settings, repeat_weight=0.0))
    np.testing.assert_array_equal(controller.belief, before)
    base = np.log(before)
    for t in range(5, 9):
        frame = rng.integers(0, K, GRID.n_cells).astype(float)
        frames.append((controller.fixation, frame))
        controller.offer(frame, float(t))
    expected = brute_force(model, frames, 0.0)
    log_b = base + np.log(expected)
    np.testing.assert_allclose(controller.belief, np.exp(log_b - log_b.max())
                               / np.exp(log_b - log_b.max()).sum(), rtol=1e-9)
    controller.reset(10.0)
    np.testing.assert_allclose(controller.belief, 1 / GRID.n_cells)
    assert not controller.session.repeated_evidence.any()


def test_gaussian_model_uses_dprime_squared_as_information():
    fpoc = make_fpoc('camera', half_width_deg=1.0, half_height_deg=1.0)
    model = GaussianObservation(GRID, fpoc)
    info = cell_information(model.elm_kernel(), GRID, 7)
    np.testing.assert_allclose(info, model.dprime(7) ** 2)
    controller = GazeController(GRID, fpoc, build_policy('map', GRID, fpoc),
                                SearchSettings(confidence=1 - 1e-12, repeat_weight=0.0))
    frame = np.random.default_rng(2).standard_normal(GRID.n_cells)
    fixation = controller.fixation
    controller.offer(frame, 1.0)
    expected = bayes_update(uniform_log_belief(GRID.n_cells),
                            model.log_likelihood_ratio(frame, fixation))
    np.testing.assert_allclose(controller.belief, np.exp(expected), rtol=1e-12)


@pytest.mark.parametrize('bad', [-0.1, 1.5, float('nan'), float('inf'), True, '0.5', None])
def test_bad_weights_are_refused(bad):
    with pytest.raises(ValueError, match='repeat_weight must be in'):
        check_repeat_weight(bad)
    with pytest.raises(ValueError):
        core(count_model(), bad)


def test_still_evidence_keeps_the_first_of_the_most_informative_views():
    still = StillEvidence(3)
    still.add(np.array([1.0, 2.0, 3.0]), np.array([1.0, 0.0, 2.0]))
    still.add(np.array([5.0, 7.0, 11.0]), np.array([1.0, 0.5, 3.0]))
    np.testing.assert_array_equal(still.kept, [1.0, 7.0, 11.0])
    np.testing.assert_array_equal(still.total, [6.0, 9.0, 14.0])
    np.testing.assert_allclose(still.log_likelihood_ratio(0.5), [3.5, 8.0, 12.5])
