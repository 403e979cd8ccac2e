# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The Gaussian observation model: its likelihood ratio, its samples and its ELM kernel."""
from ipomdp_gaze.model.belief import bayes_update, EvidenceError, uniform_log_belief
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import as_observation, GaussianObservation
import numpy as np
import pytest
from scipy.stats import norm

GRID = Grid(5, 6, 0.42)
FPOC = make_fpoc('human')
MODEL = GaussianObservation(GRID, FPOC)


def brute_force_log_ratio(frame, fixation):
    """``log p(o | target at i) - log p(o | no target)`` from Gaussian densities, per cell i."""
    d = dprime_matrix(GRID, FPOC)[:, fixation]
    null = norm.logpdf(frame)
    seen = ~np.isnan(frame)
    out = np.empty(GRID.n_cells)
    for i in range(GRID.n_cells):
        mean = np.where(np.arange(GRID.n_cells) == i, d, 0.0)
        out[i] = np.sum(norm.logpdf(frame[seen], loc=mean[seen]) - null[seen])
    return out


@pytest.mark.parametrize('seed', range(5))
def test_log_likelihood_ratio_matches_gaussian_densities(seed):
    rng = np.random.default_rng(seed)
    fixation = int(rng.integers(GRID.n_cells))
    frame = rng.normal(0, 1.5, GRID.n_cells)
    frame[rng.random(GRID.n_cells) < 0.2] = np.nan
    np.testing.assert_allclose(MODEL.log_likelihood_ratio(frame, fixation),
                               brute_force_log_ratio(frame, fixation), rtol=1e-9, atol=1e-9)


def test_batched_ratio_equals_one_frame_at_a_time():
    rng = np.random.default_rng(3)
    fixations = rng.integers(0, GRID.n_cells, 7)
    frames = rng.normal(size=(7, GRID.n_cells))
    batch = MODEL.log_likelihood_ratio(frames, fixations)
    for e in range(7):
        one = MODEL.log_likelihood_ratio(frames[e], fixations[e])
        np.testing.assert_array_equal(batch[e], one)
    np.testing.assert_array_equal(
        MODEL.log_likelihood_ratio(frames, fixations, validate=False), batch)


@pytest.mark.parametrize('side', [3, 15, 16])
def test_one_fixation_reads_the_same_dprime_on_small_and_large_grids(side):
    """A small grid's rows of the (fixation, cell) matrix equal the offset table's window."""
    grid = Grid(side, side + 1)                 # 240 cells read rows, 272 the window
    model = GaussianObservation(grid, make_fpoc('human'))
    for k in (0, grid.n_cells // 2, grid.n_cells - 1):
        one = model.dprime(k)
        window = model.dprime_window(k).reshape(-1)
        np.testing.assert_array_equal(one, window)
        if one.flags.writeable:                 # a copy: writing it changes nothing
            one[:] = -1.0
        else:
            with pytest.raises(ValueError):
                one[0] = 1.0                    # a shared row: read-only
        np.testing.assert_array_equal(model.dprime(k), window)
    with pytest.raises(ValueError, match='outside'):
        model.dprime(grid.n_cells)


def test_a_frame_that_overflows_is_refused():
    frame = np.zeros(GRID.n_cells)
    frame[3] = 1e308
    with pytest.raises(EvidenceError, match='overflows'):
        MODEL.log_likelihood_ratio(frame, 3)


def test_samples_follow_the_model():
    """Mean d' at the target, 0 elsewhere, unit variance: within 5 standard errors."""
    episodes = 40000
    rng = np.random.default_rng(1)
    targets = rng.integers(0, GRID.n_cells, episodes)
    fixations = rng.integers(0, GRID.n_cells, episodes)
    frames = MODEL.sample(targets, fixations, np.random.default_rng(2))
    rows = np.arange(episodes)
    d = dprime_matrix(GRID, FPOC)[targets, fixations]
    residual = frames[rows, targets] - d
    se = 1 / np.sqrt(episodes)
    assert abs(residual.mean()) < 5 * se and abs(residual.std() - 1) < 5 * se / np.sqrt(2)
    others = frames.copy()
    others[rows, targets] = np.nan
    assert abs(np.nanmean(others)) < 5 * se / np.sqrt(GRID.n_cells - 1)


def test_samples_are_common_random_numbers():
    """The same stream gives the same noise whatever the fixations: only the target moves."""
    targets = np.array([0, 5, 29])
    a = MODEL.sample(targets, np.array([0, 0, 0]), np.random.default_rng(4))
    b = MODEL.sample(targets, np.array([7, 12, 29]), np.random.default_rng(4))
    noise = np.random.default_rng(4).standard_normal((3, GRID.n_cells))
    diff = b - a
    diff[np.arange(3), targets] = 0.0
    assert np.all(diff == 0.0)
    np.testing.assert_array_equal(
        MODEL.sample(5, 12, np.random.default_rng(4)),
        noise[0] + np.where(np.arange(GRID.n_cells) == 5, MODEL.dprime(12)[5], 0.0))


def test_bayes_step_with_the_model_concentrates_on_the_target():
    rng = np.random.default_rng(5)
    log_b = uniform_log_belief(GRID.n_cells)
    for _ in range(60):
        frame = MODEL.sample(17, 17, rng)
        log_b = bayes_update(log_b, MODEL.log_likelihood_ratio(frame, 17))
    assert np.argmax(log_b) == 17 and np.exp(log_b[17]) > 0.999


def test_observed_cells_and_elm_kernel():
    camera = GaussianObservation(Grid(11, 11, 5.0), make_fpoc('camera', half_width_deg=10.0,
                                                              half_height_deg=10.0))
    seen = camera.observed(60).reshape(11, 11)
    assert seen[3:8, 3:8].all() and seen.sum() == 25
    np.testing.assert_array_equal(MODEL.elm_kernel(), MODEL.table ** 2)


def test_as_observation_takes_a_model_or_an_fpoc():
    assert as_observation(GRID, MODEL) is MODEL
    assert as_observation(GRID, FPOC) == MODEL
    assert MODEL.to_dict() == {'model': 'gaussian', 'fpoc': FPOC.to_dict()}
    with pytest.raises(TypeError, match='observation model or an FPOC'):
        as_observation(GRID, 'human')
