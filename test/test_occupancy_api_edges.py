# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The many-target session's Python API at its edges (a researcher's QA run)."""
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.model.occupancy import one_target_belief
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.sensors import run_search
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
import numpy as np
import pytest


def _model(grid):
    pt = np.tile([0.1, 0.2, 0.7], grid.shape + (1,))
    pn = np.tile([0.8, 0.15, 0.05], grid.shape + (1,))
    return CountObservation(grid, pt, pn)


class _Blind:
    """A camera whose detector returns nothing: every cell NaN, so nothing is ever learnt."""

    scans = False

    def __init__(self, grid):
        self.grid, self.frames = grid, 0

    def start(self, scene):
        pass

    def observe(self, cell):
        self.frames += 1
        if self.frames > 50:
            raise RuntimeError('the search did not end')
        return Frame(np.full(self.grid.n_cells, np.nan))


def test_stop_on_repeat_gives_up_before_a_second_look_at_a_cell():
    """run_search ends a search by stop_on_repeat alone; the many-target session ignored it."""
    grid = Grid(3, 3)
    session = OccupancySession(grid, _model(grid),
                               SearchSettings(targets='many', stop_on_repeat=True))
    out = run_search(session, _Blind(grid), None)
    # every view is alike (the same tables at every offset): the centre, then cell 0, whose
    # view is again the best
    assert (out.decision, out.reason, out.path) == ('gave_up', 'repeat', (4, 0))


@pytest.mark.parametrize('many', [False, True])
@pytest.mark.parametrize('cell', [1.5, '3', -1, 9, None, (1, 2), [4], np.array([4])])
def test_fixate_refuses_a_cell_that_is_not_a_whole_index_in_the_grid(many, cell):
    """
    fixate(1.5) looked at cell 1 (int() truncated), though the API refuses fractional cells.

    A sequence or an array is no cell either: Grid.cell takes it as many cells, and the
    fixation became an array.
    """
    grid = Grid(3, 3)
    model = _model(grid)
    if many:
        session = OccupancySession(grid, model, SearchSettings(targets='many'))
    else:
        session = SearchSession(grid, model, None, SearchSettings())
    session.reset()
    session.start()
    with pytest.raises(ValueError):
        session.fixate(cell)
    assert session.fixation == 4
    session.fixate(np.int64(2))
    assert session.fixation == 2 and type(session.fixation) is int


@pytest.mark.parametrize('kwargs, match', [
    ({'costs': [1.0, 2.0, 3.0]}, r'costs must be one number or 9 \(one per cell'),
    ({'costs': np.ones((3, 3))}, r'costs must be one number or 9 \(one per cell'),
    ({'costs': ['a'] * 9}, 'costs must be numbers'),
    ({'link': -1}, 'link must be a whole number of cells >= 0'),
    ({'link': 1.5}, 'link must be a whole number of cells >= 0'),
    ({'link': 'a'}, 'link must be a whole number of cells >= 0'),
    ({'link': float('inf')}, 'link must be a whole number of cells >= 0'),
])
def test_bad_costs_and_link_are_one_clear_value_error(kwargs, match):
    """A wrong-length costs array raised numpy's broadcast error; link -1 or 1.5 was taken."""
    grid = Grid(3, 3)
    with pytest.raises(ValueError, match=match):
        OccupancySession(grid, _model(grid), SearchSettings(targets='many'), **kwargs)


def test_gains_of_a_belief_of_another_length_is_a_value_error():
    grid = Grid(3, 3)
    session = OccupancySession(grid, _model(grid), SearchSettings(targets='many'))
    session.reset()
    with pytest.raises(ValueError, match=r'log odds must have shape \(9,\)'):
        session.gains(np.zeros(4))
    np.testing.assert_array_equal(session.gains(np.zeros(9)), session.gains(np.zeros((3, 3))))


@pytest.mark.parametrize('many', [False, True])
def test_a_scan_with_a_model_without_scan_tables_is_a_value_error(many):
    """A model without scan tables: an AttributeError where SearchSession.scan says ValueError."""
    grid = Grid(3, 3)
    fpoc = make_fpoc('human')
    if many:
        session = OccupancySession(grid, fpoc, SearchSettings(targets='many'))
    else:
        session = SearchSession(grid, fpoc, None, SearchSettings())
    session.reset()
    with pytest.raises(ValueError, match='no scan tables'):
        session.scan(Frame(np.zeros(9), kind='scan'))
    if many:                        # a sensor's own log-likelihood ratios need no tables
        assert session.scan(Frame(np.full(9, -1.0), kind='evidence')).applied


@pytest.mark.parametrize('absent', [False, True])
def test_one_target_belief_of_a_batch_is_each_rows_own(absent):
    """(E, N) log odds were normalised over the whole batch (and flattened with absent=True)."""
    log_odds = np.random.default_rng(0).normal(size=(4, 6)) * 3
    batch = one_target_belief(log_odds, absent)
    assert batch.shape == (4, 7 if absent else 6)
    np.testing.assert_allclose(batch, [one_target_belief(row, absent) for row in log_odds],
                               rtol=1e-12)
    np.testing.assert_allclose(batch.sum(axis=-1), 1.0)


def test_room_done_once_a_still_search_decided_every_cell():
    """room_done says every cell is decided; for a still search it stayed False."""
    grid = Grid(1, 3)
    session = OccupancySession(grid, _model(grid), SearchSettings(
        targets='many', absent_prior=0.5, confidence=0.9))
    session.reset()
    session.start()
    assert not session.room_done
    result = session.update(Frame(np.array([2.0, 0.0, 0.0])))
    while not result.ended:
        assert not session.room_done
        result = session.update(Frame(np.array([2.0, 0.0, 0.0])))
    assert result.decision == 'found' and session.room_done
    budget = OccupancySession(grid, _model(grid), SearchSettings(
        targets='many', absent_prior=0.5, confidence=0.999, max_fixations=1))
    budget.reset()
    budget.start()
    assert budget.update(Frame(np.array([2.0, 0.0, 0.0]))).truncated
    assert not budget.room_done                       # the budget decides nothing
