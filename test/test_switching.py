# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The switching searcher: tempered ELM before ``switch_at``, the ideal searcher from then on."""
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.greedy import expected_percent_correct
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.policies.switching import SWITCH_AT, SwitchingSearcher
from ipomdp_gaze.simulation.simulate import simulate
import numpy as np
import pytest

GRID = Grid(5, 5, 0.42)
HUMAN = make_fpoc('human')


def beliefs(seed, size=40):
    """Peaked random beliefs, so the two rules often disagree."""
    return np.random.default_rng(seed).dirichlet(np.full(GRID.n_cells, 0.2), size=size)


def test_before_the_switch_it_is_tempered_elm_and_after_it_the_ideal_searcher():
    b = beliefs(0)
    d = dprime_matrix(GRID, HUMAN)
    tempered = np.argmax(b ** 0.7 @ d ** 1.75, axis=1)
    ideal = np.argmax(expected_percent_correct(b, d), axis=1)
    assert np.any(tempered != ideal)            # the test would not tell them apart otherwise
    policy = SwitchingSearcher(GRID, HUMAN, switch_at=3)
    rng = np.random.default_rng(1)
    for t in range(3):
        np.testing.assert_array_equal(policy.select(b, t, rng), tempered)
    for t in (3, 4, 20):
        np.testing.assert_array_equal(policy.select(b, t, rng), ideal)


def test_switch_at_zero_is_the_ideal_searcher_in_simulation():
    greedy = simulate(GRID, HUMAN, make_baseline('greedy', GRID, HUMAN), 30, 6, 3)
    switching = simulate(GRID, HUMAN, SwitchingSearcher(GRID, HUMAN, switch_at=0), 30, 6, 3)
    np.testing.assert_array_equal(switching.fixations, greedy.fixations)


def test_it_changes_searches_only_from_the_switch_on():
    tempered = simulate(GRID, HUMAN, make_baseline('tempered', GRID, HUMAN), 200, 8, 4)
    switching = simulate(GRID, HUMAN, make_baseline('switching', GRID, HUMAN), 200, 8, 4)
    np.testing.assert_array_equal(switching.fixations[:, :SWITCH_AT],
                                  tempered.fixations[:, :SWITCH_AT])
    assert np.any(switching.fixations[:, SWITCH_AT:] != tempered.fixations[:, SWITCH_AT:])


@pytest.mark.parametrize('switch_at', [-1, 2.5, True, '3'])
def test_bad_switch_is_rejected(switch_at):
    with pytest.raises(ValueError, match='switch_at must be an integer >= 0'):
        SwitchingSearcher(GRID, HUMAN, switch_at=switch_at)


@pytest.mark.parametrize('name, what', [('tempered', 'tempered ELM'),
                                        ('switching', 'tempered ELM, then the ideal searcher')])
def test_a_count_model_is_refused_with_a_reason(name, what):
    target = np.broadcast_to([0.5, 0.5], GRID.shape + (2,))
    counts = CountObservation(GRID, target, np.broadcast_to([0.9, 0.1], GRID.shape + (2,)))
    with pytest.raises(ValueError, match=f'{name} \\({what}\\) needs the Gaussian model'):
        build_policy(name, GRID, counts)
