# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The percent-correct greedy searcher (Najemnik & Geisler ideal searcher)."""
from ipomdp_gaze.model.belief import bayes_update, map_cell
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.greedy import (expected_percent_correct, expected_percent_correct_at,
                                         percent_correct_given_target, PercentCorrectGreedy)
import numpy as np
import pytest

GRID5 = Grid(5, 5, 0.42)
HUMAN = make_fpoc('human')
# A 3x3-cell field of view on a 5x5 grid: most cells have d = 0 from any fixation.
CAMERA = make_fpoc('camera', dprime=1.5, half_width_deg=0.42, half_height_deg=0.42)
SIGMAS = 4.5


def skewed_belief(n_cells, seed):
    """Return a non-uniform belief with a spread of magnitudes."""
    rng = np.random.default_rng(seed)
    belief = rng.dirichlet(np.full(n_cells, 0.7))
    return belief / belief.sum()


def tied_belief():
    """Return a 5x5 belief whose largest values (cells 10 and 20, unseen from 0) tie exactly."""
    belief = np.linspace(1.0, 2.0, GRID5.n_cells)
    belief[[10, 20]] = 6.0
    belief[[3, 17]] = belief[8]
    return belief / belief.sum()


def monte_carlo_map_correct(belief, d, fixation, targets, samples, rng):
    """Estimate, per target, how often ``map_cell`` names it after one observation."""
    n = belief.size
    hits = np.empty(len(targets))
    for row, target in enumerate(targets):
        obs = rng.standard_normal((samples, n))
        obs[:, target] += d[target, fixation]
        log_b = np.broadcast_to(np.log(belief), (samples, n))
        posterior = bayes_update(log_b, llr(obs, np.broadcast_to(d[:, fixation], (samples, n))))
        hits[row] = np.mean(map_cell(np.exp(posterior)) == target)
    return hits


def assert_binomial(estimate, p, samples):
    se = np.sqrt(p * (1.0 - p) / samples)
    bad = np.abs(estimate - p) > SIGMAS * se + 1e-12
    assert not np.any(bad), (f'Monte Carlo {estimate[bad]} vs formula {p[bad]} '
                             f'(+/- {SIGMAS} x {se[bad]})')


@pytest.mark.parametrize('fpoc, belief, fixations', [
    (HUMAN, skewed_belief(25, 0), (0, 12, 7)),
    (CAMERA, tied_belief(), (0, 12, 9)),
], ids=['human', 'camera-with-d0-and-ties'])
def test_hypothesis_formula_matches_monte_carlo(fpoc, belief, fixations):
    d = dprime_matrix(GRID5, fpoc)
    p = percent_correct_given_target(belief, d)
    rng = np.random.default_rng(5)
    samples = 3000
    for k in fixations:
        mc = monte_carlo_map_correct(belief, d, k, range(GRID5.n_cells), samples, rng)
        assert_binomial(mc, p[:, k], samples)


def test_camera_ties_go_to_the_lower_index():
    d = dprime_matrix(GRID5, CAMERA)
    assert d[10, 0] == 0 and d[20, 0] == 0
    p = percent_correct_given_target(tied_belief(), d)
    assert p[20, 0] == 0.0 and p[10, 0] > 0.1
    assert p[17, 0] == 0.0          # cell 17 ties with cell 8 and cell 3, lower indices


@pytest.mark.parametrize('fpoc, belief', [
    (HUMAN, skewed_belief(25, 1)), (CAMERA, tied_belief()), (CAMERA, skewed_belief(25, 2)),
    (make_fpoc('exponential'), skewed_belief(25, 3)),
], ids=['human', 'camera-ties', 'camera', 'exponential'])
def test_fast_score_equals_the_najemnik_geisler_sum(fpoc, belief):
    d = dprime_matrix(GRID5, fpoc)
    reference = belief @ percent_correct_given_target(belief, d)
    fast = expected_percent_correct(belief, d, tol=0.0)
    np.testing.assert_allclose(fast, reference, rtol=0, atol=1e-9)


@pytest.mark.parametrize('fpoc', [HUMAN, CAMERA], ids=['human', 'camera'])
def test_score_matches_monte_carlo_probability_correct(fpoc):
    d = dprime_matrix(GRID5, fpoc)
    belief = skewed_belief(25, 4)
    score = expected_percent_correct(belief, d)
    rng = np.random.default_rng(6)
    samples = 40000
    fixations = (0, 6, 12)
    estimate = np.empty(len(fixations))
    for row, k in enumerate(fixations):
        targets = rng.choice(GRID5.n_cells, size=samples, p=belief)
        obs = rng.standard_normal((samples, GRID5.n_cells))
        obs[np.arange(samples), targets] += d[targets, k]
        log_b = np.broadcast_to(np.log(belief), obs.shape)
        posterior = bayes_update(log_b, llr(obs, np.broadcast_to(d[:, k], obs.shape)))
        estimate[row] = np.mean(map_cell(np.exp(posterior)) == targets)
    assert_binomial(estimate, score[list(fixations)], samples)


def peaked_beliefs(n_cells, rows, seed):
    """Return beliefs whose logs fall off linearly over 10 to 40 nats, cells shuffled."""
    rng = np.random.default_rng(seed)
    out = np.empty((rows, n_cells))
    for r, depth in enumerate(np.linspace(10, 40, rows)):
        out[r] = np.exp(-rng.permutation(np.linspace(0.0, depth, n_cells)))
    return out / out.sum(axis=1, keepdims=True)


@pytest.mark.parametrize('fpoc, tol', [
    (HUMAN, 1e-3), (HUMAN, 1e-6), (make_fpoc('camera'), 1e-3), (CAMERA, 1e-3),
], ids=['human-1e-3', 'human-1e-6', 'camera-5x5-fov-1e-3', 'camera-3x3-fov-1e-3'])
def test_pruned_scores_are_within_the_stated_bound(fpoc, tol):
    grid = Grid(7, 7, 0.42)
    d = dprime_matrix(grid, fpoc)
    beliefs = peaked_beliefs(grid.n_cells, 8, 7)
    full = expected_percent_correct(beliefs, d, tol=0.0)
    pruned, bound, kept = expected_percent_correct(beliefs, d, tol=tol, return_bound=True)
    assert np.all(bound <= tol) and np.all(kept < grid.n_cells)
    gap = full - pruned
    quadrature = 1e-10
    assert np.all(gap >= -quadrature)
    assert np.all(gap <= bound[:, None] + quadrature)
    assert np.max(gap) > 0


def test_pruning_keeps_every_cell_of_a_flat_belief():
    d = dprime_matrix(GRID5, HUMAN)
    _, bound, kept = expected_percent_correct(np.ones(25), d, return_bound=True)
    assert kept == 25 and bound == 0.0


def test_single_and_batched_scores_agree():
    grid = Grid(7, 7, 0.42)
    policy = PercentCorrectGreedy(grid, HUMAN)
    beliefs = np.vstack([np.full(grid.n_cells, 1.0 / grid.n_cells),
                         peaked_beliefs(grid.n_cells, 6, 9), skewed_belief(grid.n_cells, 10)])
    batch = policy.expected_percent_correct(beliefs)
    rows = np.array([policy.expected_percent_correct(b) for b in beliefs])
    np.testing.assert_allclose(batch, rows, rtol=0, atol=1e-14)
    choice = policy.select(beliefs, 0, None)
    assert choice.shape == (len(beliefs),) and choice.dtype.kind == 'i'
    np.testing.assert_array_equal(choice, [policy.select(b[None], 0, None)[0] for b in beliefs])
    assert np.all((choice >= 0) & (choice < grid.n_cells))


@pytest.mark.parametrize('shape, centre', [((7, 7), 24), ((5, 5), 12), ((4, 4), 5)])
def test_uniform_prior_on_a_human_fpoc_fixates_the_centre(shape, centre):
    grid = Grid(*shape, 0.42)
    policy = make_baseline('greedy', grid, HUMAN)
    assert policy.name == 'greedy'
    uniform = np.full((3, grid.n_cells), 1.0 / grid.n_cells)
    np.testing.assert_array_equal(policy.select(uniform, 0, None), centre)


def test_fixation_goes_to_a_block_of_likely_cells():
    grid = Grid(7, 7, 0.42)
    belief = np.full(grid.n_cells, 1e-4)
    block = [grid.index(r, c) for r in range(3) for c in range(3)]
    belief[block] = 1.0
    choice = PercentCorrectGreedy(grid, HUMAN).select(belief[None] / belief.sum(), 0, None)
    assert choice[0] == grid.index(1, 1)


@pytest.mark.parametrize('belief, message', [
    (np.ones(24), 'shape'), (np.ones((2, 2, 25)), 'shape'),
    (np.r_[np.ones(24), np.nan], 'NaN'), (np.r_[np.ones(24), -1.0], 'negative'),
    (np.zeros(25), 'sums to zero'),
])
def test_bad_belief_is_a_clear_error(belief, message):
    with pytest.raises(ValueError, match=message):
        PercentCorrectGreedy(GRID5, HUMAN).select(belief, 0, None)


def test_too_large_dprime_is_a_clear_error():
    with pytest.raises(ValueError, match="d' up to"):
        PercentCorrectGreedy(GRID5, make_fpoc('camera', dprime=40.0))


@pytest.mark.parametrize('fpoc', [HUMAN, make_fpoc('camera')], ids=['human', 'camera'])
def test_score_at_one_fixation_is_that_column_of_every_score(fpoc):
    grid = Grid(7, 7, 0.42)
    d = dprime_matrix(grid, fpoc)
    beliefs = np.vstack([np.full(grid.n_cells, 1.0 / grid.n_cells),
                         peaked_beliefs(grid.n_cells, 12, 3), skewed_belief(grid.n_cells, 4),
                         np.eye(grid.n_cells)[5]])
    fixations = np.random.default_rng(2).integers(0, grid.n_cells, len(beliefs))
    every = expected_percent_correct(beliefs, d)
    np.testing.assert_allclose(expected_percent_correct_at(beliefs, d, fixations),
                               every[np.arange(len(beliefs)), fixations], rtol=0, atol=1e-14)


@pytest.mark.parametrize('fixations', [[0], [0, 1, 2], [0.0, 1.0], [-1, 0], [0, 49]])
def test_bad_fixations_for_the_score_at_one_fixation_are_a_clear_error(fixations):
    d = dprime_matrix(Grid(7, 7, 0.42), HUMAN)
    with pytest.raises(ValueError, match='fixations must be 2 cell indices'):
        expected_percent_correct_at(np.ones((2, 49)), d, np.array(fixations))
