# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The log-domain belief update against a brute-force Bayes posterior, and its edge cases."""
from ipomdp_gaze.model.belief import (argmax_ties_low, bayes_update, entropy, entropy_of_log,
                                      EvidenceError,
                                      fixate_target_reward, infomax_reward, map_cell,
                                      normalize_log, uniform_log_belief)
from ipomdp_gaze.model.observation import check_evidence
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
import numpy as np
import pytest
from scipy.stats import norm


def brute_force_posterior(prior, observations, dprimes):
    """Posterior over the target cell from products of Gaussian densities over all cells."""
    n = prior.size
    post = prior.astype(float).copy()
    for obs, d in zip(observations, dprimes):
        for i in range(n):                          # hypothesis: target at i
            mean = np.where(np.arange(n) == i, d, 0.0)
            observed = ~np.isnan(obs)
            post[i] *= np.prod(norm.pdf(obs[observed], loc=mean[observed]))
    return post / post.sum()


@pytest.mark.parametrize('seed', range(8))
def test_update_matches_brute_force_bayes(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 10))
    prior = rng.dirichlet(np.ones(n))
    log_b = np.log(prior)
    observations, dprimes = [], []
    for _ in range(int(rng.integers(1, 6))):
        d = rng.uniform(0, 3, n) * (rng.random(n) > 0.2)    # some cells with d = 0
        obs = rng.normal(0, 1.5, n)
        obs[rng.random(n) < 0.15] = np.nan                   # some unobserved cells
        observations.append(obs)
        dprimes.append(d)
        log_b = bayes_update(log_b, llr(obs, d))
    expected = brute_force_posterior(prior, observations, dprimes)
    np.testing.assert_allclose(np.exp(log_b), expected, rtol=1e-9, atol=1e-12)


def test_batched_update_equals_single_updates():
    rng = np.random.default_rng(3)
    log_b = np.log(rng.dirichlet(np.ones(6), size=4))
    obs, d = rng.normal(size=(4, 6)), rng.uniform(0, 2, (4, 6))
    batched = bayes_update(log_b, llr(obs, d))
    for e in range(4):
        np.testing.assert_allclose(batched[e], bayes_update(log_b[e], llr(obs[e], d[e])))


def test_in_place_update_returns_same_array():
    log_b = uniform_log_belief(4)
    out = bayes_update(log_b, llr(np.zeros(4), np.ones(4)), out=log_b)
    assert out is log_b
    np.testing.assert_allclose(np.exp(log_b).sum(), 1.0)


@pytest.mark.parametrize('value', [1e6, -1e6])
def test_extreme_observations_stay_finite_and_normalised(value):
    log_b = uniform_log_belief(9)
    obs = np.zeros(9)
    obs[4] = value
    for _ in range(50):
        log_b = bayes_update(log_b, llr(obs, np.full(9, 2.0)))
    b = np.exp(log_b)
    assert np.all(np.isfinite(log_b))
    assert b.sum() == pytest.approx(1.0, abs=1e-12)
    if value > 0:
        assert b[4] == pytest.approx(1.0)
    else:
        assert b[4] == 0.0 and np.all(b[np.arange(9) != 4] == pytest.approx(1 / 8))


def test_zero_dprime_learns_nothing():
    rng = np.random.default_rng(0)
    log_b = np.log(rng.dirichlet(np.ones(7)))
    after = bayes_update(log_b, llr(rng.normal(0, 100, 7), np.zeros(7)))
    np.testing.assert_allclose(after, log_b, atol=1e-12)


def test_nan_cells_are_unobserved():
    log_b = uniform_log_belief(5)
    obs = np.array([np.nan, 3.0, np.nan, np.nan, np.nan])
    after = bayes_update(log_b, llr(obs, np.full(5, 2.0)))
    b = np.exp(after)
    assert np.all(np.isfinite(after)) and b.sum() == pytest.approx(1.0)
    # Only cell 1 was observed: the other four keep equal belief.
    assert np.ptp(b[[0, 2, 3, 4]]) < 1e-15 and b[1] > b[0]
    all_nan = bayes_update(log_b, llr(np.full(5, np.nan), np.full(5, 2.0)))
    np.testing.assert_allclose(all_nan, log_b)


@pytest.mark.parametrize('frame, reason', [
    (np.zeros(4), 'expected 5'),
    (np.zeros((5, 1)), 'expected 5'),
    (np.array([0, 0, np.inf, 0, 0]), 'inf'),
    (np.array([0, 0, -np.inf, 0, 0]), 'inf'),
])
def test_invalid_frames_are_rejected_with_reason(frame, reason):
    with pytest.raises(EvidenceError, match=reason):
        check_evidence(frame, 5)


def test_check_evidence_accepts_nan():
    assert np.isnan(check_evidence([0.0, np.nan, 1.0], 3)[1])


def test_rewards_and_entropy():
    b = np.array([0.5, 0.25, 0.25, 0.0])
    assert entropy(b) == pytest.approx(1.5 * np.log(2))
    assert infomax_reward(b) == pytest.approx(-1.5 * np.log(2))
    assert fixate_target_reward(b, 1) == 0.25
    np.testing.assert_allclose(fixate_target_reward(np.stack([b, b[::-1]]), np.array([0, 0])),
                               [0.5, 0.0])


def test_tie_rule_goes_to_lowest_index_within_relative_tolerance():
    assert argmax_ties_low(np.array([1.0, 3.0, 3.0 * (1 + 1e-12), 2.0])) == 1
    assert argmax_ties_low(np.array([1.0, 3.0, 3.0 * (1 + 1e-6)])) == 2
    assert argmax_ties_low(np.zeros(5)) == 0
    assert map_cell(np.exp(uniform_log_belief(49))) == 0
    np.testing.assert_array_equal(argmax_ties_low(np.array([[0, 1, 1], [2, 0, 2.0]])), [1, 0])


def test_overflowing_evidence_is_rejected_and_the_belief_kept():
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.policies.baselines import make_baseline
    from ipomdp_gaze.search.gaze import GazeController
    obs = np.zeros(9)
    obs[4] = 1.7e308
    with pytest.raises(EvidenceError, match='refused'):
        bayes_update(uniform_log_belief(9), llr(obs, np.full(9, 2.0)))
    grid, fpoc = Grid(3, 3), make_fpoc('human')
    core = GazeController(grid, fpoc, make_baseline('map', grid, fpoc))
    core.reset(0.0)
    assert core.offer(np.arange(9.0), 1.0).applied
    before = core.belief
    result = core.offer(obs, 2.0)
    assert result.status == 'rejected' and 'overflows' in result.reason
    np.testing.assert_array_equal(core.belief, before)
    assert np.all(np.isfinite(np.log(core.belief[core.belief > 0])))


def test_entropy_and_the_tie_rule_of_one_belief_are_those_of_a_batch_bit_for_bit():
    rng = np.random.default_rng(3)
    beliefs = rng.dirichlet(np.full(50, 0.2), size=6)
    beliefs[1, 7] = beliefs[2, :10] = 0.0                # 0 log 0 = 0
    beliefs[3, 20] = beliefs[3].max()                     # a tie
    with np.errstate(divide='ignore', invalid='ignore'):
        terms = np.where(beliefs > 0, beliefs * np.log(np.where(beliefs > 0, beliefs, 1.0)), 0)
    assert entropy(beliefs).tobytes() == (-np.sum(terms, axis=-1)).tobytes()
    batch = argmax_ties_low(beliefs)
    for row, belief in enumerate(beliefs):
        assert entropy(belief) == entropy(beliefs)[row]
        assert argmax_ties_low(belief) == batch[row]


@pytest.mark.parametrize('n, impossible', [(1, 0), (7, 0), (121, 3), (16384, 100)])
def test_entropy_of_a_log_belief_is_the_entropy_of_its_probabilities(n, impossible):
    """The controller's entropy from the logs: the same value, cells at -inf counted 0."""
    rng = np.random.default_rng(n)
    log_b = rng.normal(size=n) * 4
    log_b[rng.permutation(n)[:impossible]] = -np.inf
    if n > impossible + 2:
        log_b[np.isfinite(log_b).nonzero()[0][:2]] -= 800.0     # exp underflows to 0 there
    log_b = normalize_log(log_b)
    assert entropy_of_log(log_b) == pytest.approx(float(entropy(np.exp(log_b))), rel=1e-12,
                                                  abs=1e-12)


def test_a_batch_renormalises_terms_far_beyond_the_range_of_exp_as_one_belief_does():
    """The batch path shifts each row by its peak before exp, as the one-belief path does."""
    log_b = uniform_log_belief(5, episodes=3)
    term = np.zeros((3, 5))
    term[0, 2] = 1e6                                    # exp(1e6) overflows unless shifted
    term[1, 4] = -1e6
    term[2] = 800.0 + np.arange(5)
    batch = bayes_update(log_b, term)
    assert np.isfinite(batch).all()
    np.testing.assert_allclose(np.exp(batch).sum(axis=1), 1.0)
    for e in range(3):
        np.testing.assert_allclose(batch[e], bayes_update(log_b[e], term[e]), rtol=1e-12)
    assert batch[0, 2] == 0.0 and batch[0, 0] == -1e6


@pytest.mark.parametrize('scores, expected', [
    ([-3.0, -1.0 - 1e-12, -1.0], 1),       # a negative peak: a near tie within rtol |peak|
    ([-3.0, -1.0 - 1e-6, -1.0], 2),        # a negative peak, not within the tolerance
    ([-1.0, 0.0, 0.0], 1),                 # a peak of 0: the first cell at it
    ([0.0, -1.0, -0.0], 0),
])
def test_the_tie_rule_holds_for_negative_and_zero_peaks_in_one_belief_and_a_batch(
        scores, expected):
    """Infomax rewards and log scores are negative: the rule must not depend on the sign."""
    assert argmax_ties_low(np.array(scores)) == expected
    np.testing.assert_array_equal(argmax_ties_low(np.array([scores, scores])),
                                  [expected, expected])
