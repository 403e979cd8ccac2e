# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Head time in the choice (``search.head_speed_deg_s``, ``search.head_tour``; docs/design.md 6.14).

The seconds of a view against the head-time model the evaluation scores with, the tour detour
against nearest-neighbour tours walked by hand, and the session's choice against the policy's
scores divided by those seconds, worked out here.
"""
from __future__ import annotations

from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_time import (head_time_s, SACCADE_TIME_S, SETTLE_TIME_S,
                                         tour_detour_deg, view_seconds)
from ipomdp_gaze.policies.baselines import elm_policy
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
import numpy as np
import pytest

MODEL = load_observation('faces-pan-tilt-profile')
GRID = MODEL.grid


def test_view_seconds_are_the_head_time_models_step():
    grid = Grid(7, 9, 2.5)
    detector_s = 0.07
    for a, b in ((0, 62), (30, 31), (10, 10), (grid.center_index, 5)):
        step = head_time_s(grid, [a, b], [detector_s] * 2) - head_time_s(grid, [a], [detector_s])
        seconds = view_seconds(grid, a, detector_s + SETTLE_TIME_S + SACCADE_TIME_S, 120.0)[b]
        if a == b:                               # no saccade: the model counts none
            seconds -= SACCADE_TIME_S
        assert seconds == pytest.approx(step)


def _nearest_tour_deg(grid, start, first, cells):
    """Walk the tour start -> first -> nearest left ... with plain Python."""
    def step(a, b):
        (ra, ca), (rb, cb) = divmod(a, grid.cols), divmod(b, grid.cols)
        return max(abs(ra - rb), abs(ca - cb)) * grid.spacing_deg
    left = [c for c in cells if c != first]
    length, at = step(start, first), first
    while left:
        nxt = min(left, key=lambda c: (step(at, c), cells.index(c)))
        length += step(at, nxt)
        left.remove(nxt)
        at = nxt
    return length


@pytest.mark.parametrize('seed', range(6))
def test_tour_detour_against_tours_walked_by_hand(seed):
    rng = np.random.default_rng(seed)
    grid = Grid(9, 11, 5.0)
    cells = [int(c) for c in rng.choice(grid.n_cells, size=int(rng.integers(1, 9)),
                                        replace=False)]
    start = int(rng.integers(grid.n_cells))
    tours = np.array([_nearest_tour_deg(grid, start, c, cells) for c in cells])
    detour = tour_detour_deg(grid, start, cells)
    np.testing.assert_allclose(detour, tours - tours.min())
    assert detour.min() == 0.0 and tour_detour_deg(grid, start, []).size == 0


def test_a_near_cell_that_leaves_the_rest_behind_costs_its_detour():
    grid = Grid(1, 9, 5.0)
    # From cell 2 to cells 3, 0 and 8: starting with the nearest, 3, walks 5 + 15 + 40 = 60
    # deg; starting with 0 walks 10 + 15 + 25 = 50; with 8, 30 + 25 + 15 = 70.
    detour = tour_detour_deg(grid, 2, [3, 0, 8])
    np.testing.assert_allclose(detour, [10.0, 0.0, 20.0])


def _first_best(score):
    """Return the lowest cell within the project's tie tolerance (1e-9) of the best score."""
    best = score.max()
    return int(np.flatnonzero(score >= best - 1e-9 * abs(best))[0])


def _session(policy_name='coverage', **settings):
    policy = build_policy(policy_name, GRID, MODEL)
    return SearchSession(GRID, MODEL, policy, SearchSettings(**settings)), policy


def _advance(session, views):
    """Start and apply ``views`` frames of zero counts; return the belief before the choice."""
    session.reset()
    session.start()
    for _ in range(views - 1):
        session.update(Frame(np.zeros(GRID.n_cells, dtype=np.int64)))
    return session


@pytest.mark.parametrize('policy_name, tour', [('elm', False), ('coverage', False),
                                               ('coverage', True)])
@pytest.mark.parametrize('views', [1, 3, 6])
def test_the_choice_is_the_best_score_per_second(policy_name, tour, views):
    speed, view_s = 120.0, 0.15
    session, policy = _session(policy_name, inhibit_return=True, head_speed_deg_s=speed,
                               view_time_s=view_s, head_tour=tour)
    _advance(session, views)
    here, visited = session.fixation, session.visited.copy()
    visited[here] = True                        # the frame below is taken there
    result = session.update(Frame(np.zeros(GRID.n_cells, dtype=np.int64)))
    belief = session.belief[None, :GRID.n_cells]
    rows, cols = GRID.rows_cols()
    r, c = divmod(here, GRID.cols)
    seconds = view_s + np.maximum(abs(rows - r), abs(cols - c)) * GRID.spacing_deg / speed
    elm = elm_policy(GRID, MODEL)
    given = belief / belief.sum()
    info = np.asarray(elm.scores(given if policy_name == 'coverage' else belief)).reshape(-1)
    if policy_name == 'elm':
        expected = info / seconds
    else:
        tiles = np.flatnonzero(policy.tile)
        tile_seconds = seconds.copy()
        if tour:
            left = tiles[~visited[tiles]]
            tile_seconds[left] += tour_detour_deg(GRID, here, left) / speed
        per = info / (tile_seconds if given.max() < policy.peak else seconds)
        bonus = np.abs(per).max() + 1.0
        expected = per + (given.max() < policy.peak) * bonus * policy.tile
    expected[visited] = -np.inf
    assert result.fixation == _first_best(expected)


@pytest.mark.parametrize('tour', [False, True])
def test_a_first_view_chosen_by_the_policy_is_timed_from_the_centre(tour):
    """``start_cell: policy``: before any view the head is where the head model starts it."""
    speed, view_s = 120.0, 0.15
    session, policy = _session(inhibit_return=True, head_speed_deg_s=speed, view_time_s=view_s,
                               head_tour=tour, start_cell='policy')
    session.reset()
    first = session.start()
    centre = GRID.center_index
    belief = session.belief[None, :GRID.n_cells]
    seconds = view_seconds(GRID, centre, view_s, speed)
    detour = (lambda cells: tour_detour_deg(GRID, centre, cells) / speed) if tour else None
    expected = np.asarray(policy.scores_per_second(belief, seconds, detour)).reshape(-1)
    assert first == _first_best(expected)
    assert policy.tile[first] == 1.0           # a diffuse belief: a tile, not the centre


def test_without_head_speed_the_choice_is_unchanged():
    a, _ = _session(inhibit_return=True)
    b, _ = _session(inhibit_return=True, view_time_s=0.05, head_tour=True)
    for session in (a, b):
        _advance(session, 8)
    assert a.path == b.path


def test_the_tour_keeps_an_empty_room_short():
    """Zero counts everywhere: the tour's path turns the head less than the nearest tile's."""
    travel = {}
    for tour in (False, True):
        session, _ = _session(inhibit_return=True, head_speed_deg_s=120.0, view_time_s=0.15,
                              head_tour=tour, confidence=0.999, absent_prior=0.8)
        _advance(session, 13)
        rows, cols = GRID.cell(np.asarray(session.path))
        travel[tour] = np.maximum(abs(np.diff(rows)), abs(np.diff(cols))).sum()
    assert travel[True] < travel[False]


def test_other_policies_choose_as_before_and_bad_values_are_refused():
    kernel = np.zeros(GRID.kernel_shape)
    for name, args in (('learned', (kernel,)), ('map', ()), ('sweep', ())):
        paths = []
        for speed in (0.0, 60.0):
            session = SearchSession(GRID, MODEL, build_policy(name, GRID, MODEL, *args),
                                    SearchSettings(inhibit_return=True, head_speed_deg_s=speed))
            paths.append(_advance(session, 6).path)
        assert paths[0] == paths[1], name
    with pytest.raises(ValueError, match='search.view_time_s must be finite and > 0'):
        SearchSettings(view_time_s=0.0)
    with pytest.raises(ValueError, match='search.head_speed_deg_s'):
        SearchSettings(head_speed_deg_s=-1.0)


def test_a_moving_target_is_followed_as_before():
    paths = []
    for speed in (0.0, 60.0):
        session, _ = _session(head_speed_deg_s=speed, motion_sigma_cells=0.5)
        paths.append(_advance(session, 6).path)
    assert paths[0] == paths[1]


def _room(**settings):
    from ipomdp_gaze.search.many import OccupancySession
    session = OccupancySession(GRID, MODEL, SearchSettings(
        targets='many', repeat_weight=0.1, absent_prior=0.8, inhibit_return=True, **settings),
        link=1)
    session.reset(seed=0)
    session.start()
    return session


def _room_frames(session, frames, rng):
    """Apply frames of null counts; yield (view, the next choice, the gains it chose by)."""
    for _ in range(frames):
        counts = MODEL.sample(0, session.fixation, rng, present=False)
        here = session.fixation
        result = session.update(Frame(counts))
        if session.ended:
            break
        yield here, result.fixation, session.gains()


@pytest.mark.parametrize('seed', range(3))
def test_many_targets_choose_the_most_information_per_second(seed):
    speed, view_s = 120.0, 0.15
    session = _room(head_speed_deg_s=speed, view_time_s=view_s)
    rows, cols = GRID.rows_cols()
    steps = 0
    for here, choice, gains in _room_frames(session, 8, np.random.default_rng(seed)):
        r, c = divmod(here, GRID.cols)
        seconds = view_s + np.maximum(abs(rows - r), abs(cols - c)) * GRID.spacing_deg / speed
        score = np.where(session.visited, -np.inf, gains / seconds)
        assert choice == _first_best(score)
        steps += 1
    assert steps >= 4


def test_many_targets_without_head_speed_choose_by_information_alone():
    rng = np.random.default_rng(5)
    session = _room()
    for here, choice, gains in _room_frames(session, 6, rng):
        score = np.where(session.visited, -np.inf, gains)
        assert choice == _first_best(score)
    paths = []
    for speed in (0.0, 120.0):
        room = _room(head_speed_deg_s=speed, view_time_s=0.15)
        list(_room_frames(room, 8, np.random.default_rng(6)))
        paths.append(room.path)
    assert paths[0] != paths[1]                 # the head time moved the views


def test_many_targets_ignore_the_tour():
    """The tour is coverage's: the occupancy belief chooses per second without it (§6.15)."""
    from ipomdp_gaze.search.many import OccupancySession
    from ipomdp_gaze.search.session import Frame
    paths = []
    for tour in (False, True):
        session = OccupancySession(GRID, MODEL, SearchSettings(
            targets='many', head_speed_deg_s=120.0, head_tour=tour, absent_prior=0.5,
            max_fixations=6))
        session.reset(seed=0)
        session.start()
        for _ in range(6):
            if session.update(Frame(np.zeros(GRID.n_cells))).ended:
                break
        paths.append(session.path)
    assert paths[0] == paths[1] and len(paths[0]) > 1
