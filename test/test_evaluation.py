# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Fixations to 90% correct and its bootstrap interval."""
from ipomdp_gaze.simulation.evaluation import (fixations_to_90_ci, fixations_to_level,
                                               paired_difference_ci)
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


def test_evaluate_paired_compares_each_policy_with_the_first_on_the_same_episodes(capsys):
    from ipomdp_gaze.cli import main
    from ipomdp_gaze.commands.evaluate import evaluate
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.policies.registry import build_policy
    grid, fpoc = Grid(5, 5, 0.42), make_fpoc('human')
    policies = {name: build_policy(name, grid, fpoc) for name in ('map', 'elm')}
    policies['map again'] = build_policy('map', grid, fpoc)
    result = evaluate(grid, fpoc, policies, 3000, None, 0, paired=True)
    same = result['paired']['map again - map']
    assert same['difference'] == 0 and same['ci95'] == [0.0, 0.0]
    better = result['paired']['elm - map']            # ELM beats MAP (docs/baselines.md)
    assert better['ci95'][1] < 0 and better['episodes'] == 3000
    assert 'paired' not in evaluate(grid, fpoc, policies, 300, None, 0)
    assert main(['evaluate', '--grid', '3x3', '--policy', 'map', '--policy', 'random',
                 '--episodes', '500', '--paired']) == 0
    assert 'random - map: ' in capsys.readouterr().out


def test_slow_searchers_say_so_and_evaluate_runs_them_on_fewer_episodes():
    """The policy class, not its name, marks a slow searcher (``costly``)."""
    from ipomdp_gaze.commands.evaluate import evaluate
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.policies.baselines import make_baseline, STRATEGIES
    from ipomdp_gaze.policies.planner import make_planner
    from ipomdp_gaze.simulation.simulate import simulate
    grid, fpoc = Grid(3, 3, 0.42), make_fpoc('human')
    slow = {name for name in STRATEGIES
            if getattr(make_baseline(name, grid, fpoc), 'costly', False)}
    assert slow == {'greedy', 'switching'} and make_planner(grid, fpoc).costly
    named = make_baseline('elm', grid, fpoc)
    named.name = 'greedy'                   # a policy file called greedy.yaml is not slow
    policies = {'map': make_baseline('map', grid, fpoc),
                'greedy': make_baseline('greedy', grid, fpoc), 'named': named}
    result = evaluate(grid, fpoc, policies, 200, 5, 0, episodes_greedy=40, bootstrap=20)
    assert {name: r['episodes'] for name, r in result['policies'].items()} == {
        'map': 200, 'greedy': 40, 'named': 200}
    first = simulate(grid, fpoc, make_baseline('greedy', grid, fpoc), 40, 5, 0)
    np.testing.assert_allclose(result['policies']['greedy']['percent_correct'],
                               first.percent_correct, atol=1e-6)


def test_a_horizon_that_cuts_resamples_widens_the_interval_or_leaves_it_undefined():
    """A resample not at 90% within the horizon is "more than T", never dropped (QA: narrower)."""
    from ipomdp_gaze.simulation.evaluation import fixations_to_90_ci, paired_difference_ci
    rng = np.random.default_rng(4)
    # each episode becomes right for good at a geometric time: 90% is crossed near t = 8
    turns = rng.geometric(0.25, size=(2, 400))
    full = [np.arange(1, 31)[None, :] >= t[:, None] for t in turns]
    counts = np.random.default_rng(5).multinomial(400, np.full(400, 1 / 400), size=1000)
    for horizon in (8, 9, 10, 30):
        cut = [c[:, :horizon] for c in full]
        point, ci = fixations_to_90_ci(cut[0], 49, None, counts=counts)
        point_full, ci_full = fixations_to_90_ci(full[0], 49, None, counts=counts)
        if point is not None:
            assert point == point_full
            assert ci is None or ci == ci_full, (horizon, ci, ci_full)
        diff, paired = paired_difference_ci(cut[0], cut[1], 49, None, counts=counts)
        _, paired_full = paired_difference_ci(full[0], full[1], 49, None, counts=counts)
        assert paired is None or paired == paired_full, (horizon, paired, paired_full)
    assert ci == ci_full and paired == paired_full          # horizon 30: nothing cut


def test_a_percentile_on_a_finite_resample_next_to_those_beyond_is_that_resample():
    """QA review: with inf, numpy's interpolation gave inf * 0 = NaN at an exact position."""
    from ipomdp_gaze.simulation.evaluation import _interval
    values = np.r_[np.arange(976.0), np.full(25, np.inf)]       # 1001 resamples, 25 beyond
    assert _interval(values, values) == (25.0, 975.0)
    values = np.r_[np.arange(970.0), np.full(31, np.inf)]       # the 97.5% one is beyond
    assert _interval(values, values) is None
    # part of the way towards one beyond (1000 resamples, 25 beyond) is beyond too (review)
    values = np.r_[np.arange(975.0), np.full(25, np.inf)]
    assert _interval(values, values) is None
    assert _interval(-values, -values) is None


def test_the_prior_is_the_chance_level_when_90_percent_is_crossed_at_the_first_fixation():
    """Percent correct at t = 0 is 1/N: the first segment runs from (0, 1/N) to (1, pc[0])."""
    assert fixations_to_level(np.array([0.95, 1.0]), 4) == pytest.approx(0.65 / 0.7)
    assert fixations_to_level(np.array([[0.95], [0.2]]), 4)[0] == pytest.approx(0.65 / 0.7)


def test_a_curve_that_reaches_90_percent_exactly_has_reached_it():
    assert fixations_to_level(np.array([0.5, 0.9]), 10) == pytest.approx(2.0)
    assert fixations_to_level(np.array([0.5, 0.9, 0.9, 1.0]), 10) == pytest.approx(2.0)


def _never_right_in_one_resample():
    """Return 9 episodes right from fixation 1 and one never; resamples: the sample, 1 beyond."""
    correct = np.zeros((10, 3), dtype=bool)
    correct[:9] = True
    counts = np.ones((1000, 10), dtype=np.int64)
    counts[-1] = 0
    counts[-1, 9] = 10
    return correct, counts


def test_a_resample_that_never_reaches_90_percent_is_beyond_the_horizon_not_undefined():
    correct, counts = _never_right_in_one_resample()
    point, ci = fixations_to_90_ci(correct, 10, None, counts=counts)
    assert point == pytest.approx((0.9 - 0.1) / (0.9 - 0.1))
    assert ci == (pytest.approx(point), pytest.approx(point))     # 1 of 1000: inside 97.5%


def test_a_paired_resample_beyond_the_horizon_on_both_sides_widens_nothing_it_cannot_know():
    correct, counts = _never_right_in_one_resample()
    diff, ci = paired_difference_ci(correct, correct, 10, None, counts=counts)
    assert diff == 0 and ci == (0.0, 0.0)


def test_a_resample_identical_to_the_sample_reaches_90_percent_where_the_sample_does():
    """Bug: the bootstrap divided its curves in float32, 9/10 = 0.89999998 < 0.9: never."""
    correct = np.zeros((10, 3), dtype=bool)
    correct[:9] = True                                     # exactly 90% right from fixation 1
    same = np.ones((1000, 10), dtype=np.int64)             # every resample is the sample
    point, ci = fixations_to_90_ci(correct, 10, None, counts=same)
    assert point == 1.0 and ci == (1.0, 1.0)
    other = np.zeros((10, 3), dtype=bool)
    other[:9, 1:] = True                                   # the same, one fixation later
    diff, paired = paired_difference_ci(correct, other, 10, None, counts=same)
    assert diff == pytest.approx(-1.0) and paired == (pytest.approx(-1.0), pytest.approx(-1.0))


def test_chance_is_percent_correct_before_the_first_fixation():
    """A prior's MAP cell is right with its probability at t = 0: the curve starts there."""
    assert fixations_to_level(np.array([0.95, 1.0]), 10, chance=0.92) == 0.0
    assert fixations_to_level(np.array([0.95, 1.0]), 10, chance=0.5) == pytest.approx(0.4 / 0.45)
    assert fixations_to_level(np.array([0.95, 1.0]), 10) == pytest.approx(0.8 / 0.85)
    correct = np.ones((20, 3), dtype=bool)
    assert fixations_to_90_ci(correct, 10, np.random.default_rng(0), 50,
                              chance=1.0) == (0.0, (0.0, 0.0))


def test_one_episode_gives_no_interval_rather_than_one_of_no_width():
    """Every resample of one episode is that episode: [x, x] would be no 95% interval."""
    correct = np.arange(1, 13)[None, :] >= np.array([[4]])
    point, ci = fixations_to_90_ci(correct, 100, np.random.default_rng(0), 200)
    assert point == pytest.approx(3.9) and ci is None       # between fixations 3 (0) and 4 (1)
    other = np.arange(1, 13)[None, :] >= np.array([[6]])
    diff, ci = paired_difference_ci(other, correct, 100, np.random.default_rng(0), 200)
    assert diff == pytest.approx(2.0) and ci is None
    two = np.concatenate([correct, other])
    assert fixations_to_90_ci(two, 100, np.random.default_rng(0), 200)[1] is not None


def test_one_search_gives_no_tracking_interval():
    from types import SimpleNamespace
    from ipomdp_gaze.simulation.evaluation import paired_tracking_difference, tracking_summary
    one = SimpleNamespace(target_path=np.array([[0] * 4]), guess=np.array([[0, 0, 20, 0]]),
                          present=None)
    other = SimpleNamespace(target_path=one.target_path, guess=np.array([[0] * 4]), present=None)
    summary = tracking_summary(one, 5, np.random.default_rng(0))['tracking_accuracy']
    assert summary['value'] == pytest.approx(2 / 3) and summary['ci95'] is None
    paired = paired_tracking_difference(one, other, 5, np.random.default_rng(0))
    assert paired['difference'] == pytest.approx(-1 / 3) and paired['ci95'] is None
