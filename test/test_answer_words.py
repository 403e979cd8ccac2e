# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""How a search ended, in words: the confidence clause never says "below" of a sure answer."""
from __future__ import annotations

import math
from types import SimpleNamespace

from ipomdp_gaze.commands.find import plot_title
from ipomdp_gaze.commands.search import run_search as search_and_print
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search import answer
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.sensors import run_search
from ipomdp_gaze.search.session import Frame, SearchSettings
import numpy as np
import pytest


@pytest.mark.parametrize('decision, reason, p, want', [
    ('found', '', 0.995, ' (reached the confidence 0.99)'),
    ('found', 'budget', 0.62, ' (below the confidence 0.99)'),
    ('absent', 'pixels', 0.493, ' (below the confidence 0.99)'),
    # a room's pass ends forced while the face it names is sure
    ('found', 'pass', 0.9995, ' (at the confidence 0.99, forced before the search was done)'),
    # absent held back until every cell was seen well (absent_needs_coverage), then forced
    ('absent', 'budget', 0.995, ' (at the confidence 0.99, forced before the search was done)'),
    ('found', 'group', 0.68, ' (below the confidence 0.99)'),
    ('gave_up', 'budget', 0.4, ' (below the confidence 0.99)'),
    ('', '', 0.5, ''),
])
def test_the_confidence_clause(decision, reason, p, want):
    assert answer.confidence_clause(decision, reason, p, 0.99) == want


def test_a_title_says_how_the_calls_from_coarse_to_fine_and_a_forced_count_ended():
    ladder = SimpleNamespace(answer_probability=math.nan, fixations=0, stop='found',
                             decision='found', cell=(5, 9), method='scales')
    title = plot_title('a.png', ladder, 0.99)
    assert 'found by full-frame detector calls, coarse to fine' in title
    assert 'one full-frame detector scan' not in title
    faces = tuple(SimpleNamespace(probability=p) for p in (0.9, 0.995, 0.999))
    forced = SimpleNamespace(answer_probability=0.9, fixations=0, stop='pixels',
                             decision='found', cell=(5, 9), method='fovea', faces=faces)
    assert plot_title('a.png', forced, 0.99, occupancy=True, faces=3).startswith(
        'a.png: 3 faces (search forced by the pixel budget (one full scan): cells still '
        'undecided on their likelier side; 2 of the faces at the confidence 0.99, the others '
        'forced), 0 fixations')


def test_a_forced_many_target_search_does_not_call_its_sure_faces_forced():
    # fr_two_people.jpg (a QA photograph): the full-resolution pass read the whole pixel
    # budget, two weak boxes' cells stayed at even odds, and both faces reached 0.991
    faces = tuple(SimpleNamespace(probability=0.9913) for _ in range(2))
    result = SimpleNamespace(answer_probability=0.9913, fixations=0, stop='pixels',
                             decision='found', cell=(3, 5), method='fovea', faces=faces)
    title = plot_title('two.jpg', result, 0.99, occupancy=True, faces=2)
    assert title == ('two.jpg: 2 faces (search forced by the pixel budget (one full scan): '
                     'cells still undecided on their likelier side; every face at the '
                     'confidence 0.99), 0 fixations (pixels)')


def _weak(grid):
    """Count tables that barely tell a target from nothing: no search decides on them soon."""
    p_null = np.tile([0.8, 0.15, 0.05], grid.shape + (1,))
    return CountObservation(grid, 0.95 * p_null + 0.05 / 3, p_null)


@pytest.mark.parametrize('settings, cause', [
    ({'stop_on_repeat': True}, 'the next fixation would repeat a cell'),
    ({'stop_on_repeat': True, 'inhibit_return': True}, 'every cell fixated once')])
def test_search_says_what_ended_a_search_at_its_repeat_stop(settings, cause):
    """QA: search said 'every cell fixated once' also when the next fixation would repeat one."""
    grid = Grid(3, 3)
    model = _weak(grid)
    lines = []
    *_, result = search_and_print(grid, model, build_policy('elm', grid, model), 4,
                                  SearchSettings(confidence=0.999, **settings), 0,
                                  out=lines.append)
    assert (result.decision, result.reason) == ('gave_up', 'repeat'), lines
    assert lines[-1].startswith('gave up: no cell reached the confidence 0.999 at the repeat '
                                f'stop ({cause}); the target is most likely at '), lines[-1]
    assert (result.fixations == grid.n_cells) == ('inhibit_return' in settings)


class _Nothing:
    """A detector that sees nothing: every cell 0 (a still, empty room)."""

    scans = False

    def __init__(self, grid):
        self.grid = grid

    def start(self, scene):
        pass

    def observe(self, cell):
        return Frame(np.zeros(self.grid.n_cells))


@pytest.mark.parametrize('settings, blind, cause', [
    ({'inhibit_return': True}, False, 'every cell fixated once'),
    ({'stop_on_repeat': True}, False, 'the next fixation would repeat a cell'),
    ({}, True, 'no view left would tell anything new')],
    ids=['inhibited', 'repeat', 'nothing-new'])
def test_find_says_what_ended_a_many_target_search_at_its_repeat_stop(settings, blind, cause):
    """
    QA: a room's repeat stop was 'every cell fixated once' however it came.

    With many targets the repeat stop also comes without search.stop_on_repeat: with
    inhibition of return once every cell was fixated, or when no view left would tell anything
    new; find's words (a title, forced by the limit) say which.
    """
    grid = Grid(3, 3)
    model = _weak(grid)
    if blind:
        model = CountObservation(grid, model.p_null, model.p_null)
    session = OccupancySession(grid, model, SearchSettings(
        targets='many', confidence=0.999, scan=False, decide_at_budget=True, absent_prior=0.5,
        **settings))
    outcome = run_search(session, _Nothing(grid), None, limit=100)
    assert (outcome.decision, outcome.reason) == ('absent', 'repeat')
    assert (outcome.fixations == grid.n_cells) == ('inhibit_return' in settings)
    words = f'the repeat stop ({cause})'
    assert answer.limit_text(outcome.reason, outcome.limit_cause) == words
    result = SimpleNamespace(answer_probability=outcome.absent_probability,
                             fixations=outcome.fixations, stop=outcome.reason,
                             decision=outcome.decision, cell=(0, 0), method='fovea', faces=(),
                             limit_cause=outcome.limit_cause)
    assert plot_title('a.png', result, 0.999, occupancy=True, faces=0).startswith(
        f'a.png: 0 faces (absent, forced by {words}: every cell likelier empty than occupied, '
        'P(nobody here) ')
    assert answer.limit_text('repeat') == 'the repeat stop'
