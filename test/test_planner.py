# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Look-ahead planner (policies/planner.py): validity, determinism, rollouts, quality."""
from ipomdp_gaze.model.fpoc import dprime_matrix, dprime_table, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies.baselines import elm_policy, MapPolicy
from ipomdp_gaze.policies.conv import ConvPolicy
from ipomdp_gaze.policies.planner import make_planner, RolloutPlanner, TemperedELM, TemperedPolicy
from ipomdp_gaze.simulation.simulate import noise_stream, simulate
import numpy as np
import pytest

GRID = Grid(7, 7)
FPOC = make_fpoc('human')
D = dprime_matrix(GRID, FPOC)
N = GRID.n_cells


def random_beliefs(episodes, seed, sharpness=3.0):
    """Beliefs from a softmax of Gaussian scores: from fairly flat to peaked."""
    logits = sharpness * np.random.default_rng(seed).standard_normal((episodes, N))
    b = np.exp(logits - logits.max(axis=1, keepdims=True))
    return b / b.sum(axis=1, keepdims=True)


def small_planner(**options):
    opts = {'candidates': 3, 'rollouts': 16, 'rollout_budget': None, 'dprime': D}
    opts.update(options)
    return make_planner(GRID, FPOC, **opts)


def test_select_returns_valid_cells_for_batches_and_single_beliefs():
    planner = small_planner()
    beliefs = random_beliefs(12, seed=1)
    k = planner.select(beliefs, 3, np.random.default_rng(0))
    assert k.shape == (12,)
    assert np.issubdtype(k.dtype, np.integer)
    assert np.all((k >= 0) & (k < N))
    one = planner.select(beliefs[0], 3, np.random.default_rng(0))
    assert isinstance(one, int) and 0 <= one < N


def test_shortlist_starts_with_the_base_choice_and_has_distinct_cells():
    planner = small_planner(candidates=5)
    beliefs = random_beliefs(20, seed=2)
    cand = planner.shortlist(beliefs, 0, np.random.default_rng(0))
    assert cand.shape == (20, 5)
    np.testing.assert_array_equal(cand[:, 0], planner.base.select(beliefs, 0, None))
    assert all(len(set(row)) == 5 for row in cand.tolist())
    # The rest are the base policy's next best cells, in order.
    scores = planner.base.scores(beliefs)
    picked = np.take_along_axis(scores, cand[:, 1:], axis=1)
    assert np.all(np.diff(picked, axis=1) <= 0)


def test_deterministic_given_the_rng_and_the_simulation_seed():
    planner = small_planner()
    beliefs = random_beliefs(8, seed=3)
    a = planner.select(beliefs, 2, np.random.default_rng(5))
    b = planner.select(beliefs, 2, np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)
    r1 = simulate(GRID, FPOC, planner, 6, 4, seed=9)
    r2 = simulate(GRID, FPOC, planner, 6, 4, seed=9)
    np.testing.assert_array_equal(r1.fixations, r2.fixations)


def conv_kernel_policy(power=1.75):
    """Build a convolutional policy with kernel ``d^power`` (stands in for a learned kernel)."""
    return ConvPolicy(GRID, dprime_table(GRID, FPOC) ** power)


@pytest.mark.parametrize('base_name', ['elm', 'tempered', 'map', 'tempered conv'])
def test_rollouts_reproduce_simulate_on_the_same_targets_and_noise(base_name):
    """A rollout fed simulate's targets and noise ends in simulate's belief, step for step."""
    base = {'elm': elm_policy(GRID, FPOC), 'tempered': TemperedELM(GRID, FPOC),
            'map': MapPolicy(), 'tempered conv': conv_kernel_policy()}[base_name]
    power = 0.7 if base_name == 'tempered conv' else None
    episodes, steps, seed = 10, 5, 4
    reference = base if power is None else TemperedPolicy(base, power)
    result = simulate(GRID, FPOC, reference, episodes, steps, seed=seed)
    noise = np.stack([noise_stream(seed, s).standard_normal((episodes, N))
                      for s in range(steps)])[:, :, None, :]          # (H, E, R=1, N)
    uniform = np.full((episodes, N), 1.0 / N)
    first = result.fixations[:, :1]
    targets = result.targets[:, None]
    for objective, expected in (('correct', result.map_prob[:, -1]),
                                ('infomax', result.infomax.sum(axis=1))):
        planner = RolloutPlanner(GRID, FPOC, base=base, rollouts=1, horizon=steps, until=None,
                                 objective=objective, dtype='float64', belief_power=power,
                                 dprime=D)
        score = planner.rollout_scores(uniform, first, 0, targets, noise, None)
        np.testing.assert_allclose(score[:, 0, 0], expected, rtol=1e-9, atol=1e-9)


def test_tempered_elm_with_unit_powers_is_elm():
    beliefs = random_beliefs(200, seed=6)
    elm = elm_policy(GRID, FPOC)
    same = TemperedELM(GRID, FPOC, belief_power=1.0, dprime_power=2.0)
    np.testing.assert_array_equal(same.select(beliefs, 0, None), elm.select(beliefs, 0, None))
    np.testing.assert_allclose(same.scores(beliefs), elm.scores(beliefs), rtol=1e-12)


def test_tempering_a_conv_kernel_equals_tempered_elm():
    beliefs = random_beliefs(300, seed=7)
    wrapped = TemperedPolicy(conv_kernel_policy(1.75), 0.7)
    direct = TemperedELM(GRID, FPOC, belief_power=0.7, dprime_power=1.75)
    np.testing.assert_array_equal(wrapped.select(beliefs, 0, None),
                                  direct.select(beliefs, 0, None))
    assert TemperedPolicy(MapPolicy(), 0.5).scores is None
    planner = make_planner(GRID, FPOC, base=conv_kernel_policy(1.75), belief_power=0.7,
                           dprime=D)
    np.testing.assert_array_equal(planner._base_choice(beliefs, 0, None),
                                  direct.select(beliefs, 0, None))


def test_make_planner_takes_a_base_policy_and_options():
    elm = elm_policy(GRID, FPOC)
    planner = make_planner(GRID, FPOC, base=elm, candidates=4, objective='infomax', until=None)
    assert planner.base is elm and planner.candidates == 4 and planner.lookahead(7) == 2
    assert isinstance(make_planner(GRID, FPOC).base, TemperedELM)
    assert make_planner(GRID, FPOC, until=8, horizon=2).lookahead(3) == 5
    assert make_planner(GRID, FPOC, rollouts=8, rollout_budget=64, until=None,
                        horizon=4).rollouts_at(0) == 16


@pytest.mark.parametrize('options, message', [
    ({'objective': 'speed'}, 'objective'),
    ({'candidates': 0}, 'candidates'),
    ({'rollouts': 2.5}, 'rollouts'),
    ({'horizon': -1}, 'horizon'),
    ({'switch_z': float('nan')}, 'switch_z'),
    ({'dtype': 'float16'}, 'dtype'),
    ({'base': object()}, 'base'),
    ({'dprime': np.ones((3, 3))}, 'dprime'),
    ({'belief_power': 0.7}, 'belief_power'),
    ({'base': MapPolicy(), 'belief_power': -1}, 'belief_power'),
])
def test_bad_options_raise_errors_naming_the_problem(options, message):
    with pytest.raises(ValueError, match=message):
        make_planner(GRID, FPOC, **options)


def test_bad_tempering_is_rejected():
    with pytest.raises(ValueError, match='belief_power'):
        TemperedELM(GRID, FPOC, belief_power=0)


def paired_gap(policy_a, policy_b, episodes, seed, fixation=8):
    """
    Mean and standard error of the per-episode paired difference of ``max B`` at a fixation.

    ``max_i B_i`` after t fixations is the probability that the MAP guess is right given the
    history, so its mean is the percent correct at t; pairing (same targets and noise) removes
    most of the between-episode variance.
    """
    a = simulate(GRID, FPOC, policy_a, episodes, fixation, seed=seed)
    b = simulate(GRID, FPOC, policy_b, episodes, fixation, seed=seed)
    diff = a.map_prob[:, -1] - b.map_prob[:, -1]
    return diff.mean(), diff.std(ddof=1) / np.sqrt(episodes)


# One-sided 99.9% normal quantile: a correct planner fails this check with probability ~0.001.
Z_TOL = 3.09


def test_planner_is_not_worse_than_its_base_policy_beyond_sampling_error():
    """
    Percent correct at fixation 8 (the 90% region): planner vs ELM, its base, paired.

    The tolerance is Z_TOL standard errors of the paired mean difference, estimated from the
    same run; ``switch_z=1`` makes the planner leave its base often enough to matter.
    """
    base = elm_policy(GRID, FPOC)
    planner = make_planner(GRID, FPOC, base=base, candidates=3, rollouts=48,
                           rollout_budget=None, switch_z=1.0)
    episodes = 150
    gap, se = paired_gap(planner, base, episodes, seed=21)
    switched = simulate(GRID, FPOC, planner, episodes, 8, seed=21).fixations
    unchanged = simulate(GRID, FPOC, base, episodes, 8, seed=21).fixations
    assert np.mean(np.any(switched != unchanged, axis=1)) > 0.2    # the check is not vacuous
    assert gap > -Z_TOL * se, (gap, se)


def test_the_paired_check_detects_a_worse_policy():
    """The same statistic on the same number of episodes does flag MAP as worse than ELM."""
    gap, se = paired_gap(MapPolicy(), elm_policy(GRID, FPOC), 150, seed=21)
    assert gap < -Z_TOL * se, (gap, se)
