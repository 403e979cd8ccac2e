# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The absent hypothesis against brute-force N+1-state posteriors, and the stopping rules."""
from ipomdp_gaze.model.belief import bayes_update, uniform_log_belief
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import Motion
from ipomdp_gaze.model.observation import CountObservation, GaussianObservation
from ipomdp_gaze.model.stopping import (ABSENT, BatchBelief, check_absent_prior,
                                        check_confidence, check_max_fixations, decide,
                                        decide_one, first_decisions, FOUND, GAVE_UP,
                                        initial_log_belief, UNDECIDED)
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.simulation.evaluation import (decision_summary, mean_ci,
                                               paired_tracking_difference, search_outcomes,
                                               tracking_arrays, tracking_summary, wilson_interval)
from ipomdp_gaze.simulation.simulate import (draw_present, motion_stream, noise_stream,
                                             SearchResult, simulate)
import numpy as np
import pytest
from scipy.stats import norm

GRID = Grid(3, 4, 0.42)
HUMAN = make_fpoc('human')


def with_absent(llr):
    """Append the absent hypothesis's 0 to the frame's terms."""
    return np.concatenate([llr, np.zeros(llr.shape[:-1] + (1,))], axis=-1)


def gaussian_likelihoods(frame, d):
    """``p(frame | target at i)`` for i = 0..N-1 and ``p(frame | no target)`` last (N + 1)."""
    n = frame.size
    seen = ~np.isnan(frame)
    out = np.empty(n + 1)
    for i in range(n + 1):
        mean = np.where(np.arange(n) == i, d, 0.0)
        out[i] = np.prod(norm.pdf(frame[seen], loc=mean[seen]))
    return out


@pytest.mark.parametrize('seed', range(6))
def test_absent_hypothesis_matches_brute_force_gaussian(seed):
    rng = np.random.default_rng(seed)
    prior_absent = rng.uniform(0.05, 0.9)
    n = GRID.n_cells
    d = dprime_matrix(GRID, HUMAN)
    model = GaussianObservation(GRID, HUMAN)
    post = np.append(np.full(n, (1 - prior_absent) / n), prior_absent)
    log_b = initial_log_belief(n, prior_absent)
    for _ in range(4):
        k = int(rng.integers(n))
        frame = rng.normal(0, 1.2, n)
        frame[rng.random(n) < 0.2] = np.nan
        post = post * gaussian_likelihoods(frame, d[:, k])
        post /= post.sum()
        log_b = bayes_update(log_b, with_absent(model.log_likelihood_ratio(frame, k)))
        np.testing.assert_allclose(np.exp(log_b), post, rtol=1e-9, atol=1e-13)


@pytest.mark.parametrize('seed', range(4))
def test_absent_hypothesis_matches_brute_force_counts(seed):
    rng = np.random.default_rng(seed)
    grid = Grid(3, 3, 1.0)
    target = rng.dirichlet(np.full(3, 2.0), size=grid.shape)
    null = rng.dirichlet(np.full(3, 2.0), size=grid.shape)
    model = CountObservation(grid, target, null)
    n = grid.n_cells
    post = np.append(np.full(n, 0.6 / n), 0.4)
    log_b = initial_log_belief(n, 0.4)
    for _ in range(3):
        k = int(rng.integers(n))
        frame = rng.integers(0, 3, n).astype(float)
        rk, ck = grid.cell(k)
        like = np.ones(n + 1)
        for i in range(n + 1):                          # i = n: every cell from the null table
            for j in range(n):
                rj, cj = grid.cell(j)
                table = target if i == j else null
                like[i] *= table[abs(rj - rk), abs(cj - ck), int(frame[j])]
        post = post * like / np.sum(post * like)
        log_b = bayes_update(log_b, with_absent(model.log_likelihood_ratio(frame, k)))
        np.testing.assert_allclose(np.exp(log_b), post, rtol=1e-9, atol=1e-13)


class Recorder:
    """A policy that records the beliefs it is shown and fixates like ELM."""

    def __init__(self, grid, fpoc):
        self.elm = make_baseline('elm', grid, fpoc)
        self.seen = []

    def select(self, belief, t, rng):
        self.seen.append(belief.copy())
        return self.elm.select(belief, t, rng)


@pytest.mark.parametrize('model_kind', ['gaussian', 'counts'])
def test_simulated_filter_matches_brute_force_with_motion_and_absence(model_kind):
    """Every belief a policy sees and every P(absent): a dense N+1-state forward filter."""
    grid = Grid(3, 4, 0.42)
    n, episodes, horizon, seed = grid.n_cells, 6, 5, 21
    if model_kind == 'gaussian':
        model = GaussianObservation(grid, HUMAN)
    else:
        rng = np.random.default_rng(3)
        model = CountObservation(grid, rng.dirichlet(np.full(3, 1.0), size=grid.shape),
                                 rng.dirichlet(np.full(3, 2.0), size=grid.shape))
    motion = Motion(grid, 0.6, 0.05)
    big = np.zeros((n + 1, n + 1))
    big[:n, :n] = motion.transition_matrix()
    big[n, n] = 1.0                                     # the absent mass is not moved
    policy = Recorder(grid, HUMAN)
    res = simulate(grid, model, policy, episodes, horizon, seed, motion=motion,
                   absent_prior=0.3, absent_rate=0.5)
    assert 0 < res.present.sum() < episodes
    for e in range(episodes):
        post = np.append(np.full(n, 0.7 / n), 0.3)
        for t in range(horizon):
            np.testing.assert_allclose(policy.seen[t][e], post[:n], rtol=1e-9, atol=1e-14)
            k = res.fixations[e, t]
            frames = model.sample(res.target_path[:, t].clip(0), res.fixations[:, t],
                                  noise_stream(seed, t), present=res.present)
            like = np.exp(with_absent(model.log_likelihood_ratio(frames[e], k)))
            post = post * like / np.sum(post * like)
            assert res.absent_prob[e, t] == pytest.approx(post[n], rel=1e-9, abs=1e-14)
            assert res.map_prob[e, t] == pytest.approx(post[:n].max(), rel=1e-9)
            post = post @ big
        if res.present[e]:
            path = res.target_path[e]
            for t in range(horizon - 1):        # the true target took the walk's steps
                step = motion.move(res.target_path[:, t], motion_stream(seed, t))
                assert step[e] == path[t + 1]
        else:
            assert np.all(res.target_path[e] == -1)


def test_defaults_leave_the_paper_task_unchanged():
    grid, n = Grid(4, 4, 0.42), 16
    np.testing.assert_array_equal(initial_log_belief(n, 0.0), uniform_log_belief(n))
    policy = make_baseline('elm', grid, HUMAN)
    plain = simulate(grid, HUMAN, policy, 300, 10, seed=4)
    same = simulate(grid, HUMAN, policy, 300, 10, seed=4, motion=Motion(grid), absent_prior=0.0,
                    absent_rate=0.0)
    for name in ('targets', 'fixations', 'correct', 'map_prob', 'infomax', 'guess'):
        np.testing.assert_array_equal(getattr(plain, name), getattr(same, name))
    assert plain.absent_prob is None and plain.present.all()
    np.testing.assert_array_equal(plain.target_path, np.repeat(plain.targets[:, None], 10, 1))


def test_initial_belief_with_absent_prior():
    log_b = initial_log_belief(8, 0.25, episodes=3)
    assert log_b.shape == (3, 9)
    np.testing.assert_allclose(np.exp(log_b[:, 8]), 0.25)
    np.testing.assert_allclose(np.exp(log_b[:, :8]), 0.75 / 8)


def test_empty_scenes_are_drawn_at_their_rate_and_prefix_stable():
    present = draw_present(40_000, 0.3, seed=7)
    assert abs((~present).mean() - 0.3) < 4 * np.sqrt(0.21 / 40_000)
    np.testing.assert_array_equal(draw_present(100, 0.3, seed=7), present[:100])
    assert draw_present(5, 0.0, seed=7).all()


# -- stop rules on hand-made sequences ---------------------------------------------------------
def test_decide_found_absent_and_undecided():
    assert decide(0.96, 0.01, 0.95) == FOUND
    assert decide(0.95, 0.0, 0.95) == FOUND                 # reaching the level counts
    assert decide(0.02, 0.97, 0.95) == ABSENT
    assert decide(0.5, 0.45, 0.95) == UNDECIDED
    # Below 0.5 two hypotheses can reach the level: the more probable wins, a tie to the cell.
    assert decide(0.45, 0.5, 0.4) == ABSENT
    assert decide(0.45, 0.45, 0.4) == FOUND
    np.testing.assert_array_equal(decide([0.99, 0.1, 0.3], [0.0, 0.9, 0.3], 0.9),
                                  [FOUND, ABSENT, UNDECIDED])


def test_decide_one_is_decide_for_every_pair():
    """The session's scalar rule gives the array rule's code, at ties, the level and NaN."""
    values = [0.0, 0.2, 0.45, 0.5, 0.9, 0.95, 0.99, 1.0, float('nan')]
    for confidence in (0.4, 0.5, 0.95, 0.99):
        for cell in values:
            for absent in values:
                assert decide_one(cell, absent, confidence) == decide(cell, absent, confidence)


def test_first_decision_of_each_sequence():
    cell = np.array([[0.2, 0.6, 0.96, 0.99, 0.99],       # found at fixation 3
                     [0.1, 0.05, 0.01, 0.0, 0.0],         # absent at fixation 4
                     [0.3, 0.4, 0.5, 0.6, 0.7],           # never: gave up at the end
                     [0.3, 0.4, 0.5, 0.6, 0.97],          # found at 5, beyond a budget of 4
                     [0.97, 0.1, 0.1, 0.1, 0.1]])         # found at once; what follows is moot
    absent = np.array([[0.1, 0.1, 0.0, 0.0, 0.0],
                       [0.5, 0.8, 0.9, 0.96, 0.99],
                       [0.1, 0.1, 0.1, 0.1, 0.1],
                       [0.0, 0.0, 0.0, 0.0, 0.0],
                       [0.0, 0.9, 0.99, 0.99, 0.99]])
    kind, fix = first_decisions(cell, absent, 0.95)
    np.testing.assert_array_equal(kind, [FOUND, ABSENT, GAVE_UP, FOUND, FOUND])
    np.testing.assert_array_equal(fix, [3, 4, 5, 5, 1])
    kind, fix = first_decisions(cell, absent, 0.95, max_fixations=4)
    np.testing.assert_array_equal(kind, [FOUND, ABSENT, GAVE_UP, GAVE_UP, FOUND])
    np.testing.assert_array_equal(fix, [3, 4, 4, 4, 1])
    kind, _ = first_decisions(cell, None, 0.95)             # no absent hypothesis
    np.testing.assert_array_equal(kind, [FOUND, GAVE_UP, GAVE_UP, FOUND, FOUND])


def hand_made_result():
    """Five searches of 4 fixations on a 3x3 grid, two of them in empty scenes."""
    guess = np.array([[4, 4, 4, 4], [0, 1, 2, 2], [8, 8, 8, 8], [3, 3, 3, 3], [0, 0, 0, 0]])
    path = np.array([[4, 4, 4, 4], [0, 1, 5, 5], [7, 7, 7, 7], [-1] * 4, [-1] * 4])
    map_prob = np.array([[0.5, 0.96, 0.99, 0.99], [0.3, 0.4, 0.5, 0.6], [0.96, 0.9, 0.9, 0.9],
                         [0.97, 0.1, 0.1, 0.1], [0.1, 0.05, 0.01, 0.01]])
    absent_prob = np.array([[0.1, 0.0, 0.0, 0.0], [0.2, 0.3, 0.3, 0.3], [0.0, 0.0, 0.0, 0.0],
                            [0.0, 0.5, 0.5, 0.5], [0.8, 0.9, 0.96, 0.99]])
    present = np.array([True, True, True, False, False])
    zeros = np.zeros((5, 4))
    return SearchResult(path[:, 0], guess, zeros.astype(bool), map_prob, zeros, guess, path,
                        present, absent_prob)


def test_outcomes_and_rates_of_hand_made_searches():
    res = hand_made_result()
    outcome, fixations = search_outcomes(res, 0.95)
    # right (found at 4), gave up, wrong found (8, target at 7), wrong found (empty), right.
    np.testing.assert_array_equal(outcome, [0, 3, 1, 1, 0])
    np.testing.assert_array_equal(fixations, [2, 4, 1, 1, 3])
    s = decision_summary(res, 0.95)
    assert s['all']['searches'] == 5 and s['decided']['searches'] == 4
    assert s['decided']['wrong']['count'] == 2 and s['decided']['wrong']['rate'] == 0.5
    assert s['all']['gave_up']['rate'] == pytest.approx(0.2)
    assert s['present']['right']['count'] == 1 and s['present']['searches'] == 3
    assert s['absent']['right']['count'] == 1 and s['absent']['wrong_found']['count'] == 1
    assert s['present']['fixations_to_decision']['mean'] == pytest.approx(1.5)
    assert s['all']['fixations_to_decision']['mean'] == pytest.approx(7 / 4)
    assert s['decided']['wrong']['ci95'] == pytest.approx(list(wilson_interval(2, 4)))


def test_tracking_metrics_of_hand_made_searches():
    res = hand_made_result()
    first, hits, after = tracking_arrays(res, cols=3)
    # Search 1 locks at t=1 and tracks; search 2 locks at 1, then cell 2 vs 5 is 1 row off
    # (near), search 3 never locks (8 vs 7 is near, but never the cell itself); empty scenes
    # never lock.
    np.testing.assert_array_equal(first, [1, 1, 0, 0, 0])
    np.testing.assert_array_equal(after, [3, 3, 0, 0, 0])
    np.testing.assert_array_equal(hits, [3, 3, 0, 0, 0])
    s = tracking_summary(res, 3, np.random.default_rng(0), 200)
    assert s['tracking_accuracy']['value'] == 1.0
    assert s['locked']['count'] == 2 and s['first_lock']['mean'] == 1.0
    worse = hand_made_result()
    worse.guess[1, 2:] = 6                              # 2 rows off: not tracking
    gain = paired_tracking_difference(res, worse, 3, np.random.default_rng(0), 200)
    assert gain['difference'] == pytest.approx(2 / 6)


def test_wilson_interval_values():
    low, high = wilson_interval(0, 100)
    assert low == 0.0 and high == pytest.approx(0.03699, abs=1e-5)
    low, high = wilson_interval(50, 100)
    assert (low, high) == pytest.approx((0.40383, 0.59617), abs=1e-5)
    assert wilson_interval(0, 0) is None


def test_bayes_guarantee_holds_when_the_model_is_right():
    """Wrong decisions are at most 1 - c of the decided searches (seeded, 4,000 searches)."""
    grid = Grid(5, 5, 0.42)
    res = simulate(grid, HUMAN, make_baseline('elm', grid, HUMAN), 4000, 40, seed=3,
                   absent_prior=0.5, absent_rate=0.5)
    s = decision_summary(res, 0.9)
    assert s['decided']['searches'] > 3800
    assert s['decided']['wrong']['ci95'][0] < 0.1
    assert s['decided']['wrong']['rate'] <= 0.1


@pytest.mark.parametrize('check, value, message', [
    (check_confidence, 1.0, 'confidence must be between 0 and 1'),
    (check_confidence, 0.0, 'confidence must be between 0 and 1'),
    (check_confidence, float('nan'), 'confidence must be between 0 and 1'),
    (check_absent_prior, 1.0, r'absent_prior must be a probability in \[0, 1\)'),
    (check_absent_prior, -0.2, r'absent_prior must be a probability in \[0, 1\)'),
    (check_max_fixations, -1, 'max_fixations must be an integer >= 0'),
    (check_max_fixations, 2.5, 'max_fixations must be an integer >= 0'),
])
def test_bad_settings_are_refused_with_a_reason(check, value, message):
    with pytest.raises(ValueError, match=message):
        check(value)


def test_budget_zero_means_none():
    assert check_max_fixations(0) is None and check_max_fixations(None) is None
    assert check_max_fixations(7) == 7


def test_a_batch_reward_counts_a_cell_at_probability_zero_as_0_log_0():
    """Infomax reward over every hypothesis: a cell at -inf (a motion step) adds 0, not NaN."""
    batch = BatchBelief(4, 0.2, episodes=2, moving=True)
    batch.log_belief[0, 1] = -np.inf
    batch.log_belief[:] = bayes_update(batch.log_belief, np.zeros((2, 5)))
    llr = np.array([[0.5, 0.0, -1.0, 2.0], [0.0, 1.0, 0.0, 0.0]])
    reward = batch.update(llr)
    for e in range(2):
        log_b = bayes_update(batch.log_belief[e], np.zeros(5))      # already the posterior
        p = np.exp(log_b)
        expected = sum(x * np.log(x) for x in p if x > 0)
        assert reward[e] == pytest.approx(expected, rel=1e-12)
    assert np.isfinite(reward).all() and batch.belief[0, 1] == 0.0


def test_the_mean_and_its_normal_interval_use_the_sample_standard_deviation():
    values = np.array([1.0, 2.0, 3.0, 7.0])
    half = 1.959963984540054 * np.sqrt(np.sum((values - 3.25) ** 2) / 3) / 2
    out = mean_ci(values)
    assert out['mean'] == 3.25 and out['ci95'] == pytest.approx([3.25 - half, 3.25 + half])
    assert mean_ci(np.array([2.0])) == {'mean': 2.0, 'ci95': None}
    assert mean_ci(np.array([])) == {'mean': None, 'ci95': None}


def test_wrong_decisions_count_a_wrong_absent_as_well_as_a_wrong_found():
    res = hand_made_result()
    res.absent_prob[1] = 0.97                 # search 1 (a target present) now says absent
    outcome, _ = search_outcomes(res, 0.95)
    np.testing.assert_array_equal(outcome, [0, 2, 1, 1, 0])
    s = decision_summary(res, 0.95)
    assert s['decided']['searches'] == 5 and s['decided']['wrong']['count'] == 3
    assert s['decided']['wrong_absent']['count'] == 1
