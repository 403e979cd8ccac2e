# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Many moving targets (docs/design.md section 12.10).

The predicted occupancy, the people's tracks, the head's time in turns, and the moving
many-target session end to end.
"""
from __future__ import annotations

from dataclasses import replace
import itertools
import math
import os

from hypothesis import given, settings
from hypothesis import strategies as st
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import Motion, VelocityMotion
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.model.occupancy import occupancy, predict_occupancy
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.session import Frame, SearchSettings
from ipomdp_gaze.search.tracks import GLANCE, Tracks, Turns
import numpy as np
import pytest

# More examples with PROPERTY_EXAMPLES (make soak uses 1000); CI derandomizes (conftest.py).
PROPERTY = settings(deadline=None, max_examples=int(os.environ.get('PROPERTY_EXAMPLES', '40')))


def _logit(p):
    p = np.asarray(p, dtype=float)
    return np.log(p) - np.log1p(-p)


# -- the prediction ---------------------------------------------------------------------------
@pytest.mark.parametrize('sigma, jump', [(0.7, 0.0), (1.3, 0.1)])
def test_one_possible_target_is_predicted_exactly_as_the_chain_moves_it(sigma, jump):
    """A single cell that may hold someone: ``P'_j = P_i T_ij``, the exact Bernoulli step."""
    grid = Grid(4, 5)
    motion = Motion(grid, sigma, jump)
    p = np.full(grid.n_cells, 1e-300)
    p[7] = 0.8
    predicted, outside = predict_occupancy(_logit(p), 0.0, motion, 1.0)
    exact = 0.8 * motion.transition_matrix()[7]
    assert outside == 0.0
    np.testing.assert_allclose(occupancy(predicted), exact, rtol=1e-9, atol=1e-12)


def test_several_targets_are_within_the_bonferroni_bound_of_the_exact_occupancy():
    """
    Bound the prediction by the exact occupancy of independent cells.

    Each cell moves its target by the chain: the exact occupancy after the step is
    ``1 - prod_i (1 - P_i T_ij)``, checked by enumerating every pattern of occupied cells; the
    prediction is at least it and exceeds it by at most ``sum_{a<b} P_a T_aj P_b T_bj``.
    """
    grid = Grid(2, 3)
    motion = Motion(grid, 0.9, 0.05)
    t = motion.transition_matrix()
    p = np.random.default_rng(4).uniform(0.05, 0.9, grid.n_cells)
    exact = np.zeros(grid.n_cells)
    for pattern in itertools.product((0, 1), repeat=grid.n_cells):        # brute force
        x = np.array(pattern, dtype=bool)
        weight = np.prod(np.where(x, p, 1 - p))
        empty = np.prod(1 - t[x], axis=0) if x.any() else np.ones(grid.n_cells)
        exact += weight * (1 - empty)
    np.testing.assert_allclose(exact, 1 - np.prod(1 - p[:, None] * t, axis=0), atol=1e-12)
    predicted = occupancy(predict_occupancy(_logit(p), 0.0, motion, 1.0)[0])
    pair = p[:, None] * t                                                   # [a, j]
    bound = 0.5 * (pair.sum(0) ** 2 - (pair ** 2).sum(0))
    assert np.all(predicted >= exact - 1e-12)
    assert np.all(predicted - exact <= bound + 1e-12)
    assert np.any(predicted - exact > 1e-3)                                 # not trivially equal


def test_walking_out_and_coming_back_keeps_the_expected_number_of_people():
    """People walking out of reach are kept in ``outside`` and come back: the sum is kept."""
    grid = Grid(5, 5)
    motion = VelocityMotion(grid, 0.2, 0.0, 0.2, 2.0, 0.1, 1.0)
    p = np.full(grid.n_cells, 0.01)
    p[[0, 12]] = [0.99, 0.9]
    log_odds, outside = _logit(p), 0.5
    total = p.sum() + outside
    for _ in range(6):
        log_odds, outside = predict_occupancy(log_odds, outside, motion, 0.7)
        assert occupancy(log_odds).sum() + outside == pytest.approx(total, rel=1e-9)
    assert outside != 0.5


def test_a_single_target_walks_as_the_single_target_belief_predicts():
    """With one possible target the occupancy moves as one target's belief (walking out too)."""
    grid = Grid(6, 7)
    many, one = (VelocityMotion(grid, 0.3, 0.01, 0.0, 2.0, 0.2, 1.0) for _ in range(2))
    p = np.full(grid.n_cells, 1e-300)
    p[17] = 0.7
    log_odds, outside = _logit(p), 0.0
    belief = np.log(np.append(p / p.sum(), 1e-300))
    for dt in (0.4, 0.3, 0.5):
        log_odds, outside = predict_occupancy(log_odds, outside, many, dt)
        one.predict_over(belief, dt)
    single = np.exp(belief[:grid.n_cells])
    np.testing.assert_allclose(occupancy(log_odds), 0.7 * single, rtol=1e-7,
                               atol=1e-12)


def test_no_motion_predicts_nothing():
    grid = Grid(3, 3)
    log_odds = _logit(np.linspace(0.1, 0.9, 9))
    predicted, outside = predict_occupancy(log_odds, 0.3, Motion(grid), 5.0)
    assert np.array_equal(predicted, log_odds) and outside == 0.3


# -- the tracks and the turns -----------------------------------------------------------------
def _field(grid, cells, p=0.999, rest=1e-4):
    probability = np.full(grid.n_cells, rest)
    probability[list(cells)] = p
    return probability


def test_people_are_found_followed_lost_and_reacquired_by_number():
    grid = Grid(8, 8)
    tracks = Tracks(grid)
    a, b = grid.index(1, 1), grid.index(6, 5)

    def step(cells, t, keep=0.5):
        probability = _field(grid, cells)
        return [(e['event'], e['person'], grid.cell(e['cell']))
                for e in tracks.step(probability, probability >= 0.99, keep, t)]

    assert step([a, b], 0.0) == [('found', 1, (1, 1)), ('found', 2, (6, 5))]
    assert step([a + 1, b - 1], 1.0) == []                 # each moved a cell: same people
    assert [(t.person, grid.cell(t.cell)) for t in tracks.found] == [(1, (1, 2)), (2, (6, 4))]
    assert step([a + 1], 2.0) == [('lost', 2, (6, 4))]
    assert step([a + 1, grid.index(7, 2)], 3.0) == [('reacquired', 2, (7, 2))]
    events = tracks.step(_field(grid, [a + 1, grid.index(7, 2)]), _field(grid, []) > 1, 0.5, 4.0)
    assert events == []
    lost = tracks.step(_field(grid, [grid.index(7, 2)]), _field(grid, []) > 1, 0.5, 6.5)
    assert [(e['event'], e['person'], e['seconds']) for e in lost] == [('lost', 1, 6.5)]


def test_a_face_split_between_two_cells_is_not_lost_and_its_spill_over_is_no_new_person():
    grid = Grid(6, 6)
    tracks = Tracks(grid)
    first = _field(grid, [grid.index(2, 2)])
    assert len(tracks.step(first, first >= 0.99, 0.9, 0.0)) == 1
    split = _field(grid, [grid.index(2, 2), grid.index(2, 3)], p=0.7)      # 1 - 0.3^2 = 0.91
    assert tracks.step(split, split >= 0.99, 0.9, 0.5) == []
    assert tracks.found[0].probability == pytest.approx(0.91, abs=1e-3)
    spill = _field(grid, [grid.index(2, 3), grid.index(3, 3)])
    assert tracks.step(spill, spill >= 0.99, 0.9, 1.0) == []               # one face, two cells
    assert len(tracks.tracks) == 1


def test_two_people_close_together_keep_their_own_numbers():
    # Person 2 steps into person 1's gate, its face the likelier: person 1 does not take it (the
    # old rule, the likeliest cell of the gate, in the order of the numbers: person 1 jumped to
    # person 2's face and person 2 was lost); each keeps the peak nearest to where it was.
    grid = Grid(8, 8)
    tracks = Tracks(grid)
    a, b = grid.index(2, 1), grid.index(5, 4)
    first = _field(grid, [a, b])
    assert len(tracks.step(first, first >= 0.99, 0.5, 0.0)) == 2
    a1, b1 = grid.index(2, 2), grid.index(4, 3)
    probability = _field(grid, [a1, b1], p=0.995)
    probability[b1] = 0.9999
    assert tracks.step(probability, probability >= 0.99, 0.5, 0.5) == []
    assert [(t.person, t.cell) for t in tracks.found] == [(1, a1), (2, b1)]


def test_the_peaks_are_held_cells_one_per_neighbourhood_likeliest_first():
    grid = Grid(6, 6)
    tracks = Tracks(grid)
    probability = _field(grid, [grid.index(1, 1), grid.index(1, 2), grid.index(4, 4)], p=0.6)
    probability[grid.index(4, 4)] = 0.8
    # (1, 1) and (1, 2) hold 1 - 0.4^2 = 0.84 together; (4, 4) holds 0.8 alone
    assert tracks.peaks(probability, 0.82).tolist() == [grid.index(1, 1)]
    assert tracks.peaks(probability, 0.5).tolist() == [grid.index(4, 4), grid.index(1, 1)]
    assert tracks.peaks(probability, 0.9).tolist() == []


def test_turns_share_the_head_between_people_with_a_glance_after_each_round():
    turns = Turns(dwell_s=1.0)
    seen = [turns.advance([1, 2], 0.4) for _ in range(9)]
    assert seen == [1, 1, 1, 2, 2, 2, GLANCE, 1, 1]
    assert turns.advance([1], 0.4) == 1 and turns.advance([2], 0.4) == 2   # 1 lost: next
    assert turns.advance([], 0.4) is GLANCE
    with pytest.raises(ValueError, match='dwell_s must be finite and > 0'):
        Turns(0.0)


# -- the session ------------------------------------------------------------------------------
def _sensor(grid, radius=2):
    """Return counts 0..3: a face at offset <= 1 fires 2-3 times, clutter rarely; blind beyond."""
    rows, cols = np.meshgrid(np.arange(grid.rows), np.arange(grid.cols), indexing='ij')
    d = np.maximum(rows, cols)[..., None]
    pt = np.where(d <= 1, [0.02, 0.08, 0.3, 0.6], [0.3, 0.3, 0.2, 0.2])
    pn = np.broadcast_to([0.9, 0.08, 0.015, 0.005], pt.shape)
    far = d[..., 0] > radius
    pt = np.where(far[..., None], pn, pt)
    return CountObservation(grid, pt / pt.sum(-1, keepdims=True), pn.copy())


def _frame(model, rng, fixation, people, radius=2):
    grid = model.grid
    fr, fc = grid.cell(fixation)
    values = np.full(grid.n_cells, np.nan)
    occupied = {int(c) for c in people}
    for j in range(grid.n_cells):
        r, c = grid.cell(j)
        if max(abs(r - fr), abs(c - fc)) <= radius:
            table = model.p_target if j in occupied else model.p_null
            values[j] = rng.choice(4, p=table[abs(r - fr), abs(c - fc)])
    return values


MOVING = SearchSettings(targets='many', confidence=0.99, motion_sigma_cells=0.3,
                        motion_jump_prob=0.001, motion_track_view='peak', motion_dwell_s=1.0,
                        motion_keep_probability=0.5, absent_prior=0.5, motion_leave_prob=0.02)


def test_two_walking_people_are_both_found_and_looked_at_in_turn():
    grid = Grid(9, 9)
    model = _sensor(grid)
    session = OccupancySession(grid, model, MOVING, link=1)
    session.reset(seed=0)
    rng = np.random.default_rng(2)
    fixation = session.start()
    positions = np.array([[1.0, 1.0], [7.0, 6.0]])
    velocity = np.array([[0.0, 0.4], [0.0, -0.4]])
    looked, events = [], []
    for _ in range(120):
        positions = np.clip(positions + velocity * 0.3, 0, 8)
        cells = [grid.index(*np.rint(p).astype(int)) for p in positions]
        result = session.update(Frame(_frame(model, rng, fixation, cells)), dt_s=0.3)
        events += list(session.people_events)
        near = [max(np.abs(np.subtract(grid.cell(fixation), grid.cell(c)))) <= 1 for c in cells]
        looked.append(near)
        fixation = result.fixation
        assert not result.ended
    assert {e['person'] for e in events if e['event'] == 'found'} == {1, 2}
    assert session.decision == 'found' and len(session.tracks.found) == 2
    late = np.array(looked[60:])
    assert late[:, 0].mean() > 0.25 and late[:, 1].mean() > 0.25, late.mean(0)   # both, in turn
    assert [f['person'] for f in session.faces()] == [1, 2]


def test_someone_who_leaves_is_lost_and_reacquired_when_back():
    grid = Grid(7, 7)
    model = _sensor(grid)
    session = OccupancySession(grid, model, MOVING, link=1)
    session.reset(seed=0)
    rng = np.random.default_rng(5)
    fixation = session.start()
    kinds = []
    for step in range(90):
        people = [] if 30 <= step < 50 else [grid.index(3, 3 if step < 30 else 4)]
        result = session.update(Frame(_frame(model, rng, fixation, people)), dt_s=0.3)
        kinds += [(step, e['event'], e['person']) for e in session.people_events]
        fixation = result.fixation
    names = [k for _, k, _ in kinds]
    assert names[:3] == ['found', 'lost', 'reacquired'], kinds
    assert all(person == 1 for _, _, person in kinds)
    assert kinds[1][0] >= 30 and kinds[2][0] >= 50


def test_a_still_room_is_unchanged_and_the_controller_reports_each_persons_events():
    still = OccupancySession(Grid(5, 5), _sensor(Grid(5, 5)), SearchSettings(targets='many'))
    still.reset()
    assert not still.motion.active and still.outside == 0.0
    grid = Grid(7, 7)
    core = GazeController(grid, _sensor(grid), None, MOVING)
    assert core.follows_people
    rng = np.random.default_rng(1)
    kinds, t = [], 0.0
    for step in range(60):
        t += 0.3
        result = core.offer(_frame(core.observation, rng, core.fixation, [grid.index(2, 4)]), t)
        assert result.applied
        kinds += [(e.kind, e.person, e.fixations) for e in result.people]
    assert kinds[0][:2] == ('found', 1) and kinds[0][2] >= 1
    assert not core.stopped


def test_bad_dwell_is_refused_with_its_parameter_name():
    with pytest.raises(ValueError, match='motion.dwell_s'):
        SearchSettings(targets='many', motion_dwell_s=-1.0)
    assert math.isclose(SearchSettings().motion_dwell_s, 2.0)


def test_the_clutter_map_of_the_occupancy_belief_is_its_exact_hotspot_posterior():
    """
    Check the occupancy clutter map against enumeration.

    One cell, face ``x`` and hotspot ``h`` independent a priori: the hotspot's posterior odds
    after a frame, enumerated over ``(x, h)``, equal the map's; the face's term is the exact
    ``P(o | x = 1) / P(o | x = 0)`` with the hotspot marginalised.
    """
    from ipomdp_gaze.model.clutter_map import ClutterMap
    grid = Grid(3, 3)
    model = _sensor(grid)
    clutter = ClutterMap(model, 0.05, 20.0)
    rng = np.random.default_rng(3)
    b = rng.uniform(0.05, 0.9, grid.n_cells)
    pi = occupancy(clutter.log_odds.copy())
    obs = rng.integers(0, 4, grid.n_cells).astype(float)
    fixation = 4
    ratio = model.log_likelihood_ratio(obs, fixation)
    face = clutter.occupancy_step(_logit(b), obs, fixation, ratio)
    offsets = model.offsets(fixation)
    c = obs.astype(int)
    t = model.p_target.reshape(-1, 4)[offsets, c]
    n = model.p_null.reshape(-1, 4)[offsets, c]
    h = clutter._hot.p_target.reshape(-1, 4)[offsets, c]
    joint = {(x, y): (b if x else 1 - b) * (pi if y else 1 - pi) * (t if x else (h if y else n))
             for x in (0, 1) for y in (0, 1)}                                # brute force
    hot_odds = (joint[0, 1] + joint[1, 1]) / (joint[0, 0] + joint[1, 0])
    np.testing.assert_allclose(occupancy(clutter.log_odds), hot_odds / (1 + hot_odds),
                               rtol=1e-10)
    np.testing.assert_allclose(face, np.log(t) - np.log((1 - pi) * n + pi * h), rtol=1e-10)


def test_the_search_keeps_its_turn_while_it_has_something_to_do():
    turns = Turns(dwell_s=1.0)
    seen = [turns.advance([1], 0.4, search=True) for _ in range(8)]
    assert seen == [1, 1, 1, GLANCE, GLANCE, 1, 1, 1]         # the search: half a dwell
    turns.reset()
    assert [turns.advance([1], 0.4, search=False) for _ in range(5)] == [1, 1, 1, GLANCE, 1]


def test_a_person_not_looked_at_stays_found_and_is_lost_only_where_the_head_looked():
    grid = Grid(8, 8)
    tracks = Tracks(grid)
    a = grid.index(4, 4)
    first = _field(grid, [a])
    tracks.step(first, first >= 0.99, 0.5, 0.0)
    spread = _field(grid, [], rest=0.01)               # the person's occupancy spread out
    blind = np.full(grid.n_cells, np.nan)
    blind[grid.index(0, 0)] = 0.0                      # the frame looked elsewhere
    assert tracks.step(spread, spread > 1, 0.5, 1.0, values=blind) == []
    assert tracks.found[0].found
    looked = np.full(grid.n_cells, 0.0)                # the frame saw every cell: nobody
    events = tracks.step(spread, spread > 1, 0.5, 2.0, values=looked)
    assert [(e['event'], e['person']) for e in events] == [('lost', 1)]


def _track_state(tracks) -> list:
    """Return what the people's tracks hold, their position filters' state too (plain values)."""
    def filt(f):
        return None if f is None else (f.started, None if f.x is None else f.x.tolist(),
                                       f.v.tolist(), f.p.tolist())
    return [(t.person, t.cell, t.probability, t.found, t.since_s, t.confirmed_s,
             filt(t.position)) for t in tracks.tracks] + [tracks.next_person]


@PROPERTY
@given(st.integers(0, 35), st.sampled_from([math.nan, math.inf, -math.inf, -1e-9, -0.5,
                                            1.0 + 1e-9, 2.0, 1e300]),
       st.floats(0.0, 1.0), st.booleans())
def test_a_probability_not_in_0_1_is_refused_naming_its_cell_and_no_track_changes(
        cell, bad, keep, grid_shaped):
    """
    A NaN passed every comparison as false: a person lost and reacquired in one frame at nan.

    The probability is checked before anything moves: the tracks, their numbers and their
    position filters (predicted at the start of a step) are as they were.
    """
    from ipomdp_gaze.model.position_filter import walk_filter
    grid = Grid(6, 6)
    tracks = Tracks(grid, lambda: walk_filter(0.3, 0.1, 0.3, 0.5))
    values = np.ones(grid.n_cells)                     # a detection at each cell's centre
    offsets = np.zeros((grid.n_cells, 2))
    for t_s, cells in ((0.0, [7, 28]), (0.5, [8, 28])):
        field = _field(grid, cells)
        tracks.step(field, field >= 0.99, 0.5, t_s, 0.5, values, offsets)
    assert [t.position.started for t in tracks.found] == [True, True]
    before = _track_state(tracks)
    probability = _field(grid, [9, 27])
    probability[cell] = bad
    if grid_shaped:
        probability = probability.reshape(grid.shape)
    where = f'cell {tuple(int(v) for v in grid.cell(cell))} is {bad:g}'
    rule = 'finite' if not math.isfinite(bad) else 'in [0, 1]'
    for call in (lambda: tracks.step(probability, _field(grid, []) > 1, keep, 1.0, 0.5, values,
                                     offsets),
                 lambda: tracks.peaks(probability, keep),
                 lambda: tracks.held(probability, cell)):
        with pytest.raises(ValueError) as raised:
            call()
        assert str(raised.value) == f'probability must be {rule} in every cell: {where}'
        assert _track_state(tracks) == before
    # the same frame without the bad cell goes on as before: nobody lost
    probability = _field(grid, [9, 27])
    assert tracks.step(probability, probability >= 0.99, 0.5, 1.0, 0.5) == []


def test_the_tracks_refuse_what_they_cannot_follow_before_any_track_changes():
    grid = Grid(5, 5)
    tracks = Tracks(grid)
    field = _field(grid, [12])
    tracks.step(field, field >= 0.99, 0.5, 0.0)
    before = _track_state(tracks)
    occupied = field >= 0.99
    for args, kwargs, message in (
            ((field[:-1], occupied[:-1], 0.5, 1.0), {},
             r'probability must have shape \(25,\) or \(5, 5\), got \(24,\)'),
            ((['a'] * 25, occupied, 0.5, 1.0), {}, 'probability must be numbers'),
            ((field, field, 0.5, 1.0), {}, 'occupied must be 25 bools'),
            ((field, occupied, math.nan, 1.0), {}, r'keep must be a probability in \[0, 1\]'),
            ((field, occupied, 1.5, 1.0), {}, r'keep must be a probability in \[0, 1\]'),
            ((field, occupied, 0.5, math.nan), {}, 't_s must be finite'),
            ((field, occupied, 0.5, 1.0, -0.5), {}, 'dt_s finite and >= 0'),
            ((field, occupied, 0.5, 1.0), {'values': np.full(25, np.inf)}, r'\+/-inf'),
            ((field, occupied, 0.5, 1.0), {'offsets': np.zeros((25, 3))},
             r'offsets must have shape \(25, 2\)')):
        with pytest.raises(ValueError, match=message):
            tracks.step(*args, **kwargs)
        assert _track_state(tracks) == before
    ahead = np.zeros(grid.n_cells)
    ahead[3] = np.nan
    with pytest.raises(ValueError, match=r'ahead must not be NaN: cell \(0, 3\) is nan'):
        tracks.view(tracks.found[0], 0.0, ahead)
    assert tracks.view(tracks.found[0], 0.0, np.log(field)) == 12    # log odds: the same order


@st.composite
def _frames_of_any_number(draw):
    """Frames of a 5x5 grid: counts and NaN (not looked), some with one number anywhere."""
    frames = []
    for _ in range(draw(st.integers(1, 12))):
        values = draw(st.lists(st.sampled_from([0.0, 1.0, 2.0, 3.0, math.nan, math.nan]),
                               min_size=25, max_size=25))
        if draw(st.booleans()):
            values[draw(st.integers(0, 24))] = draw(st.floats())
        frames.append(values)
    return frames


@PROPERTY
@given(_frames_of_any_number(), st.floats(0.0, 2.0))
def test_a_moving_search_rejects_a_bad_frame_and_keeps_its_people(frames, dt_s):
    """
    Only the session gives the tracks their probabilities: from a belief no frame makes NaN.

    A frame a node passes on (any numbers) is applied, and the people's probabilities are
    finite in [0, 1], or rejected with its reason and the belief and the people as they were:
    nothing raises, so a node drops the frame with a warning and keeps its state.
    """
    grid = Grid(5, 5)
    session = OccupancySession(grid, _sensor(grid), replace(MOVING, motion_track_view='position'),
                               link=1)
    session.reset(seed=0)
    session.start()
    for values in frames:
        log_odds, people = session.log_odds.copy(), _track_state(session.tracks)
        result = session.update(Frame(np.array(values)), dt_s=dt_s)
        if not result.applied:
            assert result.reason
            np.testing.assert_array_equal(session.log_odds, log_odds)
            assert _track_state(session.tracks) == people
            continue
        assert all(np.isfinite(e['probability']) and 0.0 <= e['probability'] <= 1.0
                   for e in session.people_events)
        assert all(0.0 <= t.probability <= 1.0 for t in session.tracks.tracks)


def _tracked_session(settings, frames=15, cell=12, seed=0):
    grid = Grid(5, 5)
    model = _sensor(grid)
    session = OccupancySession(grid, model, settings, link=1)
    session.reset(seed=0)
    rng = np.random.default_rng(seed)
    fixation = session.start()
    for _ in range(frames):
        values = _frame(model, rng, fixation, [cell])
        none = np.isnan(values) | (values == 0)                 # detections at cell centres
        offsets = np.where(none[:, None], np.nan, np.zeros((grid.n_cells, 2)))
        result = session.update(Frame(values, offsets=offsets), dt_s=0.3)
        assert result.applied, result.reason
        fixation = result.fixation
    return session


def test_motion_turned_on_mid_search_keeps_the_evidence_and_off_forgets_the_people():
    from dataclasses import replace
    still = replace(MOVING, motion_sigma_cells=0.0, motion_jump_prob=0.0, motion_leave_prob=0.0)
    session = _tracked_session(still, frames=3)
    before = session.log_odds
    session.configure(MOVING)
    np.testing.assert_allclose(session.log_odds, before)           # nothing forgotten
    assert session.log_odds.max() > 0
    moving = _tracked_session(MOVING)
    assert moving.tracks.found
    moving.configure(still)
    assert not moving.tracks.tracks and not moving.people_events
    assert all('person' not in f for f in moving.faces(link=1))    # the still room's faces


def test_a_scan_does_not_end_a_moving_search():
    grid = Grid(5, 5)
    rng = np.random.default_rng(0)
    model = CountObservation(grid, _sensor(grid).p_target, _sensor(grid).p_null,
                             scan_target=rng.dirichlet(np.ones(4)),
                             scan_null=rng.dirichlet(np.ones(4)))
    session = OccupancySession(grid, model, MOVING, link=1)
    session.reset(seed=0)
    assert session.scan(Frame(np.full(25, -50.0), 'evidence')).applied
    session.start()
    assert not session.ended and session.decision == ''


def test_new_filter_settings_reach_the_people_already_followed():
    from dataclasses import replace
    session = _tracked_session(replace(MOVING, motion_track_view='position'))
    assert session.tracks.found and session.tracks.found[0].position is not None
    session.configure(MOVING)                                       # track_view peak
    assert all(t.position is None for t in session.tracks.tracks)


def test_a_moving_room_without_an_entry_model_or_a_dwell_view_is_warned_about():
    """Moving people: nobody enters without leave/jump, nobody is kept in view under 'policy'."""
    from ipomdp_gaze.search.controller_config import moving_room_warnings
    moving = SearchSettings(targets='many', motion_sigma_cells=0.5)
    no_entry, no_dwell = moving_room_warnings(moving)
    assert 'a person who comes in after the start is never found' in no_entry
    assert 'motion.dwell_s is not used' in no_dwell
    entering = replace(moving, motion_leave_prob=0.1, motion_track_view='peak')
    assert moving_room_warnings(entering) == []
    assert moving_room_warnings(replace(moving, motion_sigma_cells=0.0)) == []      # still
    assert moving_room_warnings(replace(moving, targets='one')) == []


def test_a_time_step_that_takes_the_clock_past_the_largest_float_is_refused_before_any_change():
    """
    The clock at inf reached the tracks, which refuse an infinite time: after the belief moved.

    Every later frame was refused the same way (the clock stays at inf); now the step is refused
    before anything changes and the search goes on.
    """
    grid = Grid(5, 5)
    session = OccupancySession(grid, _sensor(grid), replace(MOVING, motion_track_view='position'),
                               link=1)
    session.reset(seed=0)
    session.start()
    values = np.full(grid.n_cells, np.nan)
    values[12] = 3.0
    assert session.update(Frame(values), dt_s=1e308).applied
    log_odds, people = session.log_odds.copy(), _track_state(session.tracks)
    with pytest.raises(ValueError, match=r"dt_s 1e\+308 takes the search's clock past the "
                                         r'largest float \(it is at 1e\+308 s\)'):
        session.update(Frame(values), dt_s=1e308)
    np.testing.assert_array_equal(session.log_odds, log_odds)
    assert _track_state(session.tracks) == people
    assert session.update(Frame(values), dt_s=1.0).applied


def test_a_walking_room_is_warned_about_and_a_speed_prior_without_a_walk_is_not():
    """
    QA: the warnings took motion.speed_cells for motion, not motion.max_speed_cells.

    A walk alone (max_speed_cells, the other motion at 0) is followed as moving people, and
    was not warned about; a speed prior without max_speed_cells moves nothing (a still room),
    and was warned about as moving people.
    """
    from ipomdp_gaze.search.controller_config import moving_room_warnings
    walking = SearchSettings(targets='many', motion_max_speed_cells=4.0)
    assert walking.moving and len(moving_room_warnings(walking)) == 2
    still = SearchSettings(targets='many', motion_speed_cells=1.5)
    assert not still.moving and moving_room_warnings(still) == []
