# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Baselines by strategy string and the convolutional policy's scores."""
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies.baselines import make_baseline, spiral_order, STRATEGIES
from ipomdp_gaze.policies.conv import ConvPolicy, kernel_from_radial, radial_bins
import numpy as np
import pytest

GRID = Grid(5, 6, 0.42)
HUMAN = make_fpoc('human')


def test_unknown_strategy_lists_valid_ones():
    with pytest.raises(ValueError, match='valid policies: map, random, center, elm, spiral'):
        make_baseline('saliency', GRID, HUMAN)


@pytest.mark.parametrize('name', [s for s in STRATEGIES if s != 'greedy'])
def test_every_baseline_returns_valid_cells(name):
    rng = np.random.default_rng(0)
    belief = rng.dirichlet(np.ones(GRID.n_cells), size=17)
    for t in range(3):
        k = make_baseline(name, GRID, HUMAN).select(belief, t, rng)
        assert k.shape == (17,) and np.all((0 <= k) & (k < GRID.n_cells))


def test_elm_is_argmax_of_belief_weighted_dprime_squared():
    rng = np.random.default_rng(1)
    belief = rng.dirichlet(np.ones(GRID.n_cells) * 0.3, size=20)
    d = dprime_matrix(GRID, HUMAN)
    expected = np.argmax(belief @ d ** 2, axis=1)
    np.testing.assert_array_equal(make_baseline('elm', GRID, HUMAN).select(belief, 0, rng),
                                  expected)


def test_conv_scores_are_a_cross_correlation_with_an_asymmetric_kernel():
    rng = np.random.default_rng(2)
    kernel = rng.normal(size=GRID.kernel_shape)
    belief = rng.dirichlet(np.ones(GRID.n_cells), size=3)
    scores = ConvPolicy(GRID, kernel).scores(belief)
    for e in range(3):
        for k in range(GRID.n_cells):
            rk, ck = GRID.cell(k)
            s = sum(belief[e, j] * kernel[GRID.cell(j)[0] - rk + 4, GRID.cell(j)[1] - ck + 5]
                    for j in range(GRID.n_cells))
            assert scores[e, k] == pytest.approx(s)


def test_radial_bins_counts_match_the_paper():
    assert radial_bins(Grid(7, 7))[0].size == 27
    assert radial_bins(Grid(11, 11))[0].size == 61
    g = Grid(7, 7)
    kernel = kernel_from_radial(g, np.arange(27.0))
    np.testing.assert_array_equal(kernel, kernel.T)
    np.testing.assert_array_equal(kernel, kernel[::-1, ::-1])


def test_sampled_action_follows_the_softmax():
    g = Grid(1, 3)
    policy = ConvPolicy(g, np.array([[0.0, 0.0, 0.0, np.log(2), np.log(4)]]), action='sample')
    # With the belief on cell 2, score_k = K[2 - c_k + 2]: log 4, log 2 and 0 for k = 0, 1, 2.
    belief = np.tile([[0.0, 0.0, 1.0]], (30000, 1))
    k = policy.select(belief, 0, np.random.default_rng(0))
    freq = np.bincount(k, minlength=3) / k.size
    expected = np.array([4, 2, 1]) / 7
    assert np.all(np.abs(freq - expected) < 4 * np.sqrt(expected * (1 - expected) / k.size))


def test_spiral_visits_every_cell_once():
    for g in (Grid(7, 7), Grid(4, 6), Grid(1, 5)):
        order = spiral_order(g)
        assert sorted(order.tolist()) == list(range(g.n_cells))
        assert order[0] == g.center_index


def test_center_policy_from_uniform():
    k = make_baseline('center', Grid(7, 7), HUMAN).select(np.full((2, 49), 1 / 49), 0, None)
    assert list(k) == [24, 24]


@pytest.mark.parametrize('peak, diffuse',
                         [(0.25, True), (0.29, True), (0.31, False), (0.4, False)])
def test_coverage_raises_the_tiles_only_while_no_cell_given_a_target_reaches_its_peak(
        peak, diffuse):
    """Below 0.3 only, on the cells given a target (they sum to 1 - P(absent))."""
    coverage, elm = make_baseline('coverage', GRID, HUMAN), make_baseline('elm', GRID, HUMAN)
    belief = np.full(GRID.n_cells, (1 - peak) / (GRID.n_cells - 1))
    belief[7] = peak
    elm_scores = np.asarray(elm.scores(belief[None, :]), dtype=float).reshape(-1)
    for scale in (1.0, 0.5):                  # the same belief with P(absent) = 0.5
        scores = coverage.scores(scale * belief[None, :]).reshape(-1)
        raised = scores - elm_scores
        np.testing.assert_allclose(raised[coverage.tile == 0], 0.0, atol=1e-12)
        assert np.all(raised[coverage.tile == 1] > elm_scores.max()) == diffuse
        assert np.all(np.abs(raised[coverage.tile == 1]) < 1e-12) == (not diffuse)
