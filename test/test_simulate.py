# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Batched simulator: common random numbers, agreement with step-by-step updates, calibration."""
from ipomdp_gaze.model.belief import bayes_update, map_cell, uniform_log_belief
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import Motion
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.simulation.evaluation import fixations_to_90_ci
from ipomdp_gaze.simulation.simulate import draw_targets, noise_stream, simulate
import numpy as np
import pytest

GRID = Grid(7, 7, 0.42)
HUMAN = make_fpoc('human')


def test_simulator_matches_sequential_updates():
    grid, fpoc = Grid(3, 4, 0.42), make_fpoc('human')
    policy = make_baseline('elm', grid, fpoc)
    res = simulate(grid, fpoc, policy, episodes=5, horizon=6, seed=11)
    d = dprime_matrix(grid, fpoc)
    for e in range(5):
        log_b = uniform_log_belief(grid.n_cells)
        for t in range(6):
            k = int(policy.select(np.exp(log_b)[None], t, None)[0])
            assert k == res.fixations[e, t]
            obs = noise_stream(11, t).standard_normal((5, grid.n_cells))[e]
            obs[res.targets[e]] += d[res.targets[e], k]
            log_b = bayes_update(log_b, llr(obs, d[:, k]))
            assert (map_cell(np.exp(log_b)) == res.targets[e]) == res.correct[e, t]


def test_common_random_numbers_across_policies():
    a = simulate(GRID, HUMAN, make_baseline('center', GRID, HUMAN), 50, 5, seed=3)
    b = simulate(GRID, HUMAN, make_baseline('center', GRID, HUMAN), 50, 5, seed=3)
    c = simulate(GRID, HUMAN, make_baseline('map', GRID, HUMAN), 50, 5, seed=3)
    np.testing.assert_array_equal(a.correct, b.correct)
    np.testing.assert_array_equal(a.targets, c.targets)
    np.testing.assert_array_equal(a.targets, draw_targets(49, 50, 3))


def test_targets_are_uniform():
    counts = np.bincount(draw_targets(49, 49_000, 0), minlength=49)
    # Chi-square with 48 dof: 99.9% quantile is about 84.0.
    assert np.sum((counts - 1000) ** 2 / 1000) < 84.0


@pytest.mark.parametrize('name, reference', [('random', 11.33), ('map', 9.1)])
def test_calibrated_baselines_reach_design_values(name, reference):
    """
    docs/design.md: random about 11.3 and MAP about 9.1 fixations to 90% on 7x7 (human default).

    The tolerance is four bootstrap standard errors of this run plus 0.05 for the rounding of the
    reference, so a correct model fails this with probability well below 1e-3.
    """
    episodes = 6000
    res = simulate(GRID, HUMAN, make_baseline(name, GRID, HUMAN), episodes, 20, seed=2024)
    point, (low, high) = fixations_to_90_ci(res.correct, 49, np.random.default_rng(0), 400)
    se = (high - low) / (2 * 1.96)
    assert abs(point - reference) < 4 * se + 0.05, (point, se)


def test_learned_order_of_baselines():
    """ELM beats MAP, MAP beats random, on paired episodes (differences far beyond noise)."""
    f90 = {}
    for name in ('elm', 'map', 'random'):
        res = simulate(GRID, HUMAN, make_baseline(name, GRID, HUMAN), 3000, 20, seed=5)
        f90[name] = fixations_to_90_ci(res.correct, 49, np.random.default_rng(0), 1)[0]
    assert f90['elm'] < f90['map'] - 0.6 and f90['map'] < f90['random'] - 1.0, f90


def test_fewer_episodes_see_a_prefix_of_the_same_draws():
    """Common random numbers hold across batch sizes: 300 episodes are the first 300 of 1000."""
    policy = make_baseline('elm', GRID, HUMAN)
    small = simulate(GRID, HUMAN, policy, 300, 8, seed=9)
    large = simulate(GRID, HUMAN, policy, 1000, 8, seed=9)
    np.testing.assert_array_equal(small.correct, large.correct[:300])
    np.testing.assert_array_equal(small.fixations, large.fixations[:300])


@pytest.mark.parametrize('name', ['elm', 'greedy'])
def test_pieces_of_a_run_are_the_rows_of_the_whole_run(name):
    """``rows``: pieces of a run (moving, sometimes absent target) stack into the serial run."""
    grid = Grid(4, 4, 0.42)
    policy = make_baseline(name, grid, HUMAN)
    scene = {'motion': Motion(grid, 0.5, 0.1), 'absent_prior': 0.1, 'absent_rate': 0.2}
    whole = simulate(grid, HUMAN, policy, 23, 7, seed=3, **scene)
    pieces = [simulate(grid, HUMAN, policy, 23, 7, seed=3, rows=(a, min(a + 5, 23)), **scene)
              for a in range(0, 23, 5)]
    for key in ('fixations', 'correct', 'map_prob', 'target_path', 'present', 'absent_prob'):
        np.testing.assert_array_equal(getattr(whole, key),
                                      np.concatenate([getattr(p, key) for p in pieces]), key)


def test_pieces_of_a_count_model_run_are_its_rows():
    grid, rng = Grid(3, 4, 1.0), np.random.default_rng(0)
    p_target = rng.dirichlet(np.ones(4), size=grid.shape)
    p_null = rng.dirichlet(np.ones(4), size=grid.shape)
    model = CountObservation(grid, p_target, p_null)
    policy = make_baseline('elm', model.grid, model)
    whole = simulate(model.grid, model, policy, 9, 5, seed=1)
    pieces = [simulate(model.grid, model, policy, 9, 5, seed=1, rows=r) for r in ((0, 4), (4, 9))]
    np.testing.assert_array_equal(whole.correct, np.concatenate([p.correct for p in pieces]))
    np.testing.assert_array_equal(whole.fixations, np.concatenate([p.fixations for p in pieces]))


@pytest.mark.parametrize('rows', [(0, 0), (-1, 3), (2, 11), (5, 2), 'ab', (1,)])
def test_bad_rows_are_refused(rows):
    with pytest.raises(ValueError, match='rows must'):
        simulate(GRID, HUMAN, make_baseline('elm', GRID, HUMAN), 10, 3, seed=0, rows=rows)


@pytest.mark.parametrize('targets, message', [
    ([0, 4, -1], 'cells in 0..8, got -1'),
    ([0, 4, 9], 'cells in 0..8, got 9'),
    ([0, 4], r'shape \(3,\)'),
    ([0.5, 4, 1], 'whole cell indices'),
])
def test_given_targets_outside_the_grid_are_refused(targets, message):
    # A target of -1 used to be accepted: the frames put the signal on the last cell (numpy's
    # wrap-round) while the score compared the guess with -1, so that episode was never right.
    grid = Grid(3, 3, 1.0)
    with pytest.raises(ValueError, match=message):
        simulate(grid, HUMAN, make_baseline('elm', grid, HUMAN), 3, 4, seed=0, targets=targets)


def test_given_targets_are_the_searched_cells():
    # With a d' so large that one look decides, every episode is right after one fixation at
    # exactly the targets it was given, whole floats included.
    grid = Grid(3, 3, 1.0)
    sure = make_fpoc('table', ecc_deg=[0.0, 5.0], dprime=[40.0, 40.0])
    targets = np.array([8.0, 0.0, 4.0, 8.0])
    res = simulate(grid, sure, make_baseline('elm', grid, sure), 4, 1, seed=1, targets=targets)
    np.testing.assert_array_equal(res.guess[:, 0], [8, 0, 4, 8])
    assert res.correct.all()


class Fixed:
    """A policy of one's own that returns the same choices every time."""

    name = 'fixed'

    def __init__(self, choice):
        self.choice = choice

    def select(self, belief, t, rng):
        return self.choice


@pytest.mark.parametrize('choice, message', [
    (np.array([0, -1, 4]), 'policy fixed chose -1 for episode 1 at fixation 1: a fixation is '
                           r'a cell index in 0..8'),
    (np.array([0, 4, 9]), 'chose 9 for episode 2'),
    (np.array([2.7, 0, 0]), 'chose 2.7 for episode 0'),
    (np.array([0, 4]), r'must choose one cell per episode, shape \(3,\), got shape \(2,\)'),
    (np.array(['a'] * 3), 'must choose cell indices, got dtype <U1'),
])
def test_a_policys_choice_outside_the_grid_is_refused(choice, message):
    # QA: a policy of one's own returning -1 had its frames drawn at cell 8 (numpy's wrap-round)
    # while -1 was recorded as the fixation, and 2.7 fixated cell 2, without a word.
    grid = Grid(3, 3, 1.0)
    with pytest.raises(ValueError, match=message):
        simulate(grid, HUMAN, Fixed(choice), 3, 2, seed=0)


def test_a_policys_whole_choices_and_one_for_all_are_taken():
    grid = Grid(3, 3, 1.0)
    res = simulate(grid, HUMAN, Fixed(np.array([8.0, 0.0, 4.0])), 3, 2, seed=0)
    np.testing.assert_array_equal(res.fixations, [[8, 8], [0, 0], [4, 4]])
    assert res.fixations.dtype == np.int64
    np.testing.assert_array_equal(simulate(grid, HUMAN, Fixed(4), 3, 1, seed=0).fixations, 4)


def test_given_targets_in_cells_the_prior_rules_out_are_refused():
    # QA: they were taken, and every such search was scored wrong (its belief held 0 there);
    # the Gymnasium environment and search --target refuse such a target.
    grid = Grid(3, 3, 1.0)
    prior = np.full(9, 1 / 8)
    prior[5] = 0.0
    policy = make_baseline('elm', grid, HUMAN)
    with pytest.raises(ValueError, match='targets must be cells the prior allows: episode 1 '
                                         'has its target in cell 5, which the prior rules out'):
        simulate(grid, HUMAN, policy, 3, 2, seed=0, targets=[0, 5, 5], prior=prior)
    res = simulate(grid, HUMAN, policy, 3, 2, seed=0, targets=[0, 4, 8], prior=prior)
    np.testing.assert_array_equal(res.targets, [0, 4, 8])


@pytest.mark.parametrize('kwargs, message', [
    ({'horizon': 2.5}, 'horizon must be a positive integer, got 2.5'),
    ({'horizon': '3'}, "horizon must be a positive integer, got '3'"),
    ({'horizon': 0}, 'horizon must be a positive integer, got 0'),
    ({'episodes': 2.5}, 'episodes must be a positive integer, got 2.5'),
    ({'seed': None}, 'seed must be a non-negative integer, got None'),
    ({'seed': -1}, 'seed must be a non-negative integer, got -1'),
])
def test_counts_and_the_seed_must_be_whole(kwargs, message):
    # QA: a horizon of 2.5 ran 2 fixations and '3' ran 3; episodes=2.5 and seed=None were
    # numpy's TypeErrors, seed=-1 its 'expected non-negative integer'.
    grid = Grid(3, 3, 1.0)
    args = {'episodes': 3, 'horizon': 2, 'seed': 0, **kwargs}
    with pytest.raises(ValueError, match=message):
        simulate(grid, HUMAN, make_baseline('elm', grid, HUMAN), **args)
    res = simulate(grid, HUMAN, make_baseline('elm', grid, HUMAN), np.int64(3), np.int64(2),
                   seed=np.uint32(4))
    assert res.correct.shape == (3, 2)


def test_present_of_the_wrong_length_is_refused():
    grid = Grid(3, 3, 1.0)
    with pytest.raises(ValueError, match='one flag per episode'):
        simulate(grid, HUMAN, make_baseline('elm', grid, HUMAN), 3, 2, present=[True, False])


def test_a_prior_is_where_the_belief_starts_and_the_targets_are_drawn():
    # The sequential Bayes posterior from the prior (the first test's loop, started at log
    # prior instead of uniform) gives every fixation, guess and MAP probability of the batch.
    grid, fpoc = Grid(3, 4, 0.42), make_fpoc('human')
    prior = np.random.default_rng(4).dirichlet(np.ones(grid.n_cells))
    policy = make_baseline('elm', grid, fpoc)
    res = simulate(grid, fpoc, policy, episodes=6, horizon=5, seed=12, prior=prior)
    d = dprime_matrix(grid, fpoc)
    for e in range(6):
        log_b = np.log(prior)
        for t in range(5):
            k = int(policy.select(np.exp(log_b)[None], t, None)[0])
            assert k == res.fixations[e, t]
            obs = noise_stream(12, t).standard_normal((6, grid.n_cells))[e]
            obs[res.targets[e]] += d[res.targets[e], k]
            log_b = bayes_update(log_b, llr(obs, d[:, k]))
            assert map_cell(np.exp(log_b)) == res.guess[e, t]
            assert np.exp(log_b).max() == pytest.approx(res.map_prob[e, t], rel=1e-12)


def test_with_a_blind_fpoc_the_belief_stays_at_the_prior():
    grid = Grid(3, 5, 1.0)
    blind = make_fpoc('table', ecc_deg=[0.0, 5.0], dprime=[0.0, 0.0])
    prior = np.arange(1.0, 16.0)
    prior[[0, 7]] = 0.0
    prior /= prior.sum()
    res = simulate(grid, blind, make_baseline('elm', grid, blind), 4000, 3, seed=2, prior=prior)
    assert (res.guess == 14).all()
    np.testing.assert_allclose(res.map_prob, prior[14], rtol=1e-12)
    # The infomax reward is the prior's negative entropy (0 log 0 = 0), not NaN.
    kept = prior[prior > 0]
    np.testing.assert_allclose(res.infomax, np.sum(kept * np.log(kept)), rtol=1e-12)
    counts = np.bincount(res.targets, minlength=grid.n_cells)
    assert counts[[0, 7]].sum() == 0
    # Targets follow the prior: a chi-square test at a generous level.
    expected = 4000 * prior[prior > 0]
    chi2 = np.sum((counts[prior > 0] - expected) ** 2 / expected)
    assert chi2 < 40.0                                      # 12 dof: p < 1e-4 beyond


@pytest.mark.parametrize('prior, message', [
    (np.full(8, 1 / 8), 'one probability per cell, 9 values'),
    (np.full(9, 0.1), 'sum to 1, got 0.9'),
    (np.r_[-0.1, np.full(8, 1.1 / 8)], '>= 0 in every cell, got -0.1'),
    (np.r_[np.nan, np.full(8, 1 / 8)], 'finite in every cell, got nan'),
    (np.full((9, 1), 1 / 9), r'\(rows, cols\) = \(3, 3\) or \(9,\), got shape \(9, 1\)'),
    ('centre', "prior must be numbers, one per cell, got str 'centre'"),       # QA: no numpy
    ({'centre': 1.0}, 'prior must be numbers, one per cell, got dict'),      # message, no
    ([[0.5, 0.5], [0.0]], 'prior must be numbers, one per cell, got list'),  # TypeError
    ([0.1j] * 9, 'prior must be numbers, one per cell, got list'),
])
def test_bad_priors_are_refused(prior, message):
    grid = Grid(3, 3, 1.0)
    with pytest.raises(ValueError, match=message):
        simulate(grid, HUMAN, make_baseline('elm', grid, HUMAN), 3, 2, prior=prior)
