# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Which reason a prior wrong in several ways is refused with: the most fundamental one, and right.

``belief.prior`` (the controller's settings check, ``prior_from``): any prior with
``search.targets`` many, then values that are not numbers, then the count of values, then the
first weight not finite, below 0, or all 0. One message said ``weights must be finite, >= 0
and not all 0`` of a NaN, a negative weight and all zeros alike, and the count was checked
before the refusal of any prior with many targets. ``--prior`` files and ``check_prior`` (a
prior given to the simulation, a policy file's ``training.prior``) say the same reasons.
"""
from ipomdp_gaze.model.belief import check_prior, prior_from_weights
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.search.controller_config import prior_from
import numpy as np
import pytest

GRID = Grid(2, 3)
NAN, INF = float('nan'), float('inf')
MANY = "a prior over one target's cell (belief.prior) does not go with search.targets many"
COUNT = ('belief.prior must hold one weight per cell, 6 values for a 2x3 grid (row-major; none: '
         'uniform), got {}')


@pytest.mark.parametrize('weights, targets, message', [
    # many targets: no prior at all, whatever is wrong with it besides
    ([1, 2, 3], 'many', MANY),
    ([-1, NAN, 0, 0, 0, 0, 0], 'many', MANY),
    ([1, 1, 1, 1, 1, 1], 'many', MANY),
    # not numbers, before the count
    (['a', 'b'], 'one', "belief.prior must be numbers, one weight per cell, got ['a', 'b']"),
    # the count before the values
    ([-1, 1, 1], 'one', COUNT.format(3)),
    ([NAN] * 7, 'one', COUNT.format(7)),
    ([0, 0, 0], 'one', COUNT.format(3)),
    # a NaN or an infinity before a negative weight (a NaN is not below 0, nor above)
    ([-1, 1, NAN, 1, 1, 1], 'one', 'belief.prior weights must be finite: cell (0, 2) is nan'),
    ([1, 1, 1, -INF, 1, 1], 'one', 'belief.prior weights must be finite: cell (1, 0) is -inf'),
    # a negative weight before the sum: these sum to 0, the reason is the negative one
    ([-1, 1, 0, 0, 0, 0], 'one', 'belief.prior weights must be >= 0: cell (0, 0) is -1'),
    ([0, 0, 0, 0, 0, -2.5], 'one', 'belief.prior weights must be >= 0: cell (1, 2) is -2.5'),
    ([0, 0, 0, 0, 0, 0], 'one', 'belief.prior weights must not all be 0 (the target would be '
                                'in no cell)'),
])
def test_belief_prior_is_refused_for_its_most_fundamental_fault(weights, targets, message):
    with pytest.raises(ValueError) as raised:
        prior_from({'belief.prior': weights, 'search.targets': targets}, GRID)
    assert str(raised.value) == message


def test_a_good_belief_prior_is_scaled_and_none_is_uniform():
    np.testing.assert_allclose(prior_from({'belief.prior': [0, 1, 1, 0, 2, 0]}, GRID),
                               [0, 0.25, 0.25, 0, 0.5, 0])
    assert prior_from({'belief.prior': []}, GRID) is None
    assert prior_from({'belief.prior': [], 'search.targets': 'many'}, GRID) is None


def test_weights_without_a_grid_name_their_position():
    with pytest.raises(ValueError) as raised:
        prior_from_weights([1, 2, -3])
    assert str(raised.value) == 'weights must be >= 0: weight 3 is -3'


@pytest.mark.parametrize('prior, message', [
    ([0.5, NAN, -0.5, 1.0, 0, 0], 'prior must be finite in every cell, got nan'),
    ([0.5, 0.5, -0.5, 0.5, 0, 0], 'prior must be >= 0 in every cell, got -0.5'),
    ([0.5, -0.5, 0, 0, 0, 0], 'prior must be >= 0 in every cell, got -0.5'),
    ([-1, NAN, 1], 'prior must hold one probability per cell, 6 values (rows x cols, '
                   'row-major), got shape (3,)'),
    ([0.0] * 6, 'prior must sum to 1, got 0'),
])
def test_check_prior_gives_the_first_fault_in_the_same_order(prior, message):
    with pytest.raises(ValueError) as raised:
        check_prior(prior, GRID.n_cells, GRID.shape)
    assert str(raised.value) == message


@pytest.mark.parametrize('text, message', [
    ('1 1 1\n1 nan -1\n', 'weights must be finite: cell (1, 1) is nan'),
    ('1 1 -1\n0 0 0\n', 'weights must be >= 0: cell (0, 2) is -1'),
    ('0 0 0\n0 0 0\n', 'weights must not all be 0 (the target would be in no cell)'),
])
def test_a_prior_file_names_the_cell_of_its_fault(tmp_path, cli_here, text, message):
    path = tmp_path / 'prior.txt'
    path.write_text(text)
    run = cli_here('evaluate', '--grid', '2x3', '--episodes', '10', '--prior', path)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        f'ipomdp-gaze evaluate: error: --prior {path}: {message}']
