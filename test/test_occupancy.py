# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The many-target occupancy belief against brute-force Bayes over every occupancy pattern."""
from dataclasses import replace
import itertools
import math
import threading
import time

from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import Motion
from ipomdp_gaze.model.observation import CountObservation, GaussianObservation
from ipomdp_gaze.model.occupancy import (_TABLES, binary_entropy, cell_prior, channel_information,
                                         clusters, count_faces, decided, information_table,
                                         InformationTable, log_nobody, MAX_LOG_ODDS, occupancy,
                                         one_target_belief, predict_occupancy, prior_log_odds,
                                         TABLE_CACHE_SIZE, TABLE_LOG_ODDS, update_log_odds)
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
import numpy as np
import pytest


def _tables(grid, k, rng, informative_radius=None):
    """Random count tables (rows, cols, K); offsets beyond the radius equal (say nothing)."""
    pt = rng.dirichlet(np.ones(k), size=grid.shape)
    pn = rng.dirichlet(np.ones(k), size=grid.shape)
    if informative_radius is not None:
        dr, dc = np.meshgrid(np.arange(grid.rows), np.arange(grid.cols), indexing='ij')
        far = np.maximum(dr, dc) > informative_radius
        pt[far] = pn[far]
    return pt, pn


def _model(grid, k=3, seed=0, radius=None):
    rng = np.random.default_rng(seed)
    pt, pn = _tables(grid, k, rng, radius)
    return CountObservation(grid, pt, pn, scan_target=rng.dirichlet(np.ones(k)),
                            scan_null=rng.dirichlet(np.ones(k)))


def _patterns(n):
    return np.array(list(itertools.product((0, 1), repeat=n)), dtype=bool)       # (2^N, N)


def _cell_log_lik(model, frame, fixation, occupied):
    """Return log p(o_j | x_j) per cell (N,) for the pattern's x; NaN cells 0."""
    offsets = model.offsets(fixation)
    counts = np.nan_to_num(frame).astype(int)
    table = np.where(occupied[:, None], model.p_target.reshape(-1, model.max_count + 1)[offsets],
                     model.p_null.reshape(-1, model.max_count + 1)[offsets])
    out = np.log(table[np.arange(frame.size), counts])
    return np.where(np.isnan(frame), 0.0, out)


def _brute_posterior(model, q, frames, fixations, scan=None):
    """P(pattern | frames) over all 2^N patterns, exactly by enumeration."""
    n = model.grid.n_cells
    patterns = _patterns(n)
    log_p = patterns.sum(1) * math.log(q) + (n - patterns.sum(1)) * math.log1p(-q)
    for x, pattern in enumerate(patterns):
        if scan is not None:
            counts = scan.astype(int)
            log_p[x] += np.log(np.where(pattern, model.scan_target[counts],
                                        model.scan_null[counts])).sum()
        for frame, k in zip(frames, fixations):
            log_p[x] += _cell_log_lik(model, frame, k, pattern).sum()
    post = np.exp(log_p - log_p.max())
    return patterns, post / post.sum()


def _frames(model, rng, fixations, truth, nan_share=0.3, spill=0):
    """Frames from a world with targets at ``truth``; neighbours of a target get +spill counts."""
    grid, k = model.grid, model.max_count + 1
    frames = []
    for fixation in fixations:
        frame = np.zeros(grid.n_cells)
        offsets = model.offsets(fixation)
        for j in range(grid.n_cells):
            table = model.p_target if truth[j] else model.p_null
            frame[j] = rng.choice(k, p=table.reshape(-1, k)[offsets[j]])
        if spill:
            r, c = np.divmod(np.flatnonzero(truth), grid.cols)
            rr, cc = np.divmod(np.arange(grid.n_cells), grid.cols)
            near = np.any((np.maximum(np.abs(rr[:, None] - r), np.abs(cc[:, None] - c)) == 1),
                          axis=1)
            frame = np.where(near, np.minimum(frame + spill, k - 1), frame)
        frame[rng.random(grid.n_cells) < nan_share] = np.nan
        frames.append(frame)
    return frames


@pytest.mark.parametrize('spill', [0, 2])
def test_occupancy_equals_brute_force_enumeration(spill):
    grid = Grid(2, 3)
    model = _model(grid, k=4, seed=3)
    rng = np.random.default_rng(7)
    truth = np.zeros(grid.n_cells, dtype=bool)
    truth[[1, 5]] = True
    fixations = [0, 4, 2, 2]
    frames = _frames(model, rng, fixations, truth, spill=spill)
    scan = rng.integers(0, 4, grid.n_cells).astype(float)
    q = 0.2
    log_odds = prior_log_odds(grid.n_cells, q) + model.scan_log_likelihood_ratio(scan)
    for frame, k in zip(frames, fixations):
        log_odds = update_log_odds(log_odds, model.log_likelihood_ratio(frame, k))
    patterns, post = _brute_posterior(model, q, frames, fixations, scan)
    assert np.any(np.isnan(np.array(frames)))                    # unobserved cells are tested
    np.testing.assert_allclose(occupancy(log_odds), post @ patterns, rtol=1e-10)
    np.testing.assert_allclose(np.exp(log_nobody(log_odds)), post[0], rtol=1e-10)
    # Conditioned on exactly one occupied cell: the single-target belief's softmax.
    one = patterns.sum(1) == 1
    np.testing.assert_allclose(one_target_belief(log_odds),
                               post[one][np.argsort(np.argmax(patterns[one], 1))]
                               / post[one].sum(), rtol=1e-10)


def test_session_matches_brute_force_and_in_place_update():
    grid = Grid(2, 2)
    model = _model(grid, seed=11)
    rng = np.random.default_rng(2)
    truth = np.array([True, False, False, True])
    fixations = [3, 0, 1]
    frames = _frames(model, rng, fixations, truth)
    settings = SearchSettings(targets='many', confidence=0.999, absent_prior=0.3)
    session = OccupancySession(grid, model, settings)
    session.reset()
    session.start()
    for frame, k in zip(frames, fixations):
        session.fixate(k)
        assert session.update(Frame(frame)).applied
    q = cell_prior(grid.n_cells, 0.3)
    assert (1 - q) ** grid.n_cells == pytest.approx(0.3)
    patterns, post = _brute_posterior(model, q, frames, fixations)
    np.testing.assert_allclose(session.belief, post @ patterns, rtol=1e-10)
    assert session.absent_probability == pytest.approx(post[0], rel=1e-10)
    out = np.zeros(grid.n_cells)
    update_log_odds(np.ones(grid.n_cells), np.arange(4.0), out=out)
    np.testing.assert_array_equal(out, [1, 2, 3, 4])


@pytest.mark.parametrize('absent_prior', [0.0, 0.25])
@pytest.mark.parametrize('kind', ['gaussian', 'counts'])
def test_single_target_is_occupancy_conditioned_on_one(kind, absent_prior):
    """The paper's belief (session, one target) = the occupancy given exactly / at most one."""
    grid = Grid(3, 3)
    model = (GaussianObservation(grid, make_fpoc('human')) if kind == 'gaussian'
             else _model(grid, k=5, seed=4))
    rng = np.random.default_rng(5)
    settings = SearchSettings(absent_prior=absent_prior, confidence=1 - 1e-15)
    one = SearchSession(grid, model, None, settings)
    one.reset()
    one.start()
    n = grid.n_cells
    # q / (1 - q) = (1 - a) / (N a): the at-most-one conditional has the absent prior a.
    q = 1.0 / n if absent_prior == 0 else 1.0 / (1.0 + n * absent_prior / (1 - absent_prior))
    log_odds = prior_log_odds(n, q)
    for t in range(6):
        k = int(rng.integers(n))
        frame = model.sample(4, k, rng)
        frame[rng.random(n) < 0.2] = np.nan
        one.fixate(k)
        one.update(Frame(frame))
        log_odds = update_log_odds(log_odds, model.log_likelihood_ratio(frame, k))
    expected = one_target_belief(log_odds, absent=absent_prior > 0)
    np.testing.assert_allclose(np.exp(one.log_belief), expected, rtol=1e-9, atol=1e-15)


def _brute_expected_entropy_drop(model, log_odds, fixation):
    """H(before) - E[H(after)] of the summed cell entropies, over every possible frame."""
    k = model.max_count + 1
    n = model.grid.n_cells
    p = occupancy(log_odds)
    offsets = model.offsets(fixation)
    pt = model.p_target.reshape(-1, k)[offsets]
    pn = model.p_null.reshape(-1, k)[offsets]
    before = binary_entropy(p).sum()
    expected = 0.0
    for frame in itertools.product(range(k), repeat=n):
        c = np.array(frame)
        m = p * pt[np.arange(n), c] + (1 - p) * pn[np.arange(n), c]
        prob = np.prod(m)
        after = update_log_odds(log_odds, model.log_likelihood_ratio(c.astype(float), fixation))
        expected += prob * binary_entropy(occupancy(after)).sum()
    return before - expected


def test_infomax_gain_equals_brute_force_expected_entropy():
    grid = Grid(2, 2)
    model = _model(grid, k=3, seed=21, radius=0)     # a view tells only about its own cell
    log_odds = np.array([-2.0, 0.3, 1.5, -0.2])
    table = InformationTable(model)
    gains = table(log_odds).sum(axis=1)
    brute = np.array([_brute_expected_entropy_drop(model, log_odds, k) for k in range(4)])
    offsets = model.offsets(np.arange(4))
    k = model.max_count + 1
    exact = channel_information(occupancy(log_odds)[None, :],
                                model.p_target.reshape(-1, k)[offsets],
                                model.p_null.reshape(-1, k)[offsets]).sum(axis=1)
    np.testing.assert_allclose(exact, brute, rtol=1e-10)
    np.testing.assert_allclose(gains, brute, rtol=2e-3)
    session = OccupancySession(grid, model, SearchSettings(targets='many'),
                               costs=[1.0, 1.0, 3.0, 1.0])
    session.reset()
    np.testing.assert_allclose(session.gains(log_odds), brute, rtol=2e-3)
    assert session.gains(log_odds).argmax() == brute.argmax()


def _brute_fresh_entropy_drop(model, log_odds, fixation, cells):
    """H(before) - E[H(after)] when the frame observes only ``cells`` (others NaN)."""
    k = model.max_count + 1
    p = occupancy(log_odds)
    at = np.flatnonzero(cells)
    offsets = model.offsets(fixation)[at]
    pt = model.p_target.reshape(-1, k)[offsets]
    pn = model.p_null.reshape(-1, k)[offsets]
    expected = 0.0
    for counts in itertools.product(range(k), repeat=at.size):
        c = np.array(counts, dtype=np.int64)
        prob = np.prod(p[at] * pt[np.arange(at.size), c]
                       + (1 - p[at]) * pn[np.arange(at.size), c])
        frame = np.full(log_odds.size, np.nan)
        frame[at] = c
        after = update_log_odds(log_odds, model.log_likelihood_ratio(frame, fixation))
        expected += prob * binary_entropy(occupancy(after)).sum()
    return binary_entropy(p).sum() - expected


def test_a_partly_cached_view_gains_only_what_the_cells_it_reads_afresh_tell():
    """gains(cover=): the expected entropy drop of the frame fresh_counts leaves (others NaN)."""
    grid = Grid(2, 3)
    model = _model(grid, k=3, seed=4)
    log_odds = np.array([-2.0, 0.3, 1.5, -0.2, 0.8, -1.1])
    cover = np.ones((6, 6), dtype=bool)
    cover[1] = [True, True, False, False, False, True]    # its other windows cached
    cover[4] = [False, False, False, True, True, False]
    cover[5] = False                                     # every window cached: nothing read
    session = OccupancySession(grid, model, SearchSettings(targets='many'))
    session.reset()
    whole, fresh = session.gains(log_odds), session.gains(log_odds, cover=cover)
    for view in range(6):
        brute = _brute_fresh_entropy_drop(model, log_odds, view, cover[view])
        assert fresh[view] == pytest.approx(brute, rel=2e-3, abs=1e-12)
    assert whole[1] > fresh[1] > 0 and whole[4] > fresh[4] > 0 and fresh[5] == 0
    np.testing.assert_array_equal(fresh[[0, 2, 3]], whole[[0, 2, 3]])    # read whole


def _fresh_choice(session, costs, cover):
    session.set_fresh(lambda: (costs, cover))
    session.reset()
    return session.start()


def test_a_view_served_whole_from_the_cache_is_never_chosen_while_another_gains():
    grid = Grid(3, 3)
    model = _model(grid, k=3, seed=8, radius=1)
    settings = SearchSettings(targets='many', scan=False, start_cell='policy',
                              max_fixations=20)
    session = OccupancySession(grid, model, settings)
    session.reset()
    best = session.start()                      # the choice without a cache
    costs, cover = np.ones(9), np.ones((9, 9), dtype=bool)
    assert _fresh_choice(session, costs, cover) == best
    costs[best], cover[best] = 0.0, False        # served whole from the cache
    choice = _fresh_choice(session, costs, cover)
    assert choice != best
    gains = session.gains(cover=cover)
    assert gains[choice] == gains[costs > 0].max() > 0
    # a partly cached view is scored per the pixels it reads afresh
    costs, cover = np.ones(9), np.ones((9, 9), dtype=bool)
    other = (best + 1) % 9
    cover[other] = np.arange(9) == other
    costs[other] = 1e-6
    assert _fresh_choice(session, costs, cover) == other
    # every view cached: nothing is worth a fixation, the search gives up as it does today
    session.set_fresh(lambda: (np.zeros(9), np.zeros((9, 9), dtype=bool)))
    session.reset()
    session.start()
    result = session.update(Frame(np.zeros(9)))
    assert result.ended and result.reason == 'repeat' and session.fixations == 1


def test_fresh_views_are_checked():
    grid = Grid(2, 2)
    session = OccupancySession(grid, _model(grid), SearchSettings(targets='many', scan=False,
                                                                  start_cell='policy'))
    with pytest.raises(ValueError, match='callable'):
        session.set_fresh(np.ones(4))
    for costs, cover, match in ((np.ones(3), np.ones((4, 4)), r'costs \(4,\)'),
                                (-np.ones(4), np.ones((4, 4)), '>= 0')):
        session.set_fresh(lambda: (costs, cover))
        session.reset()
        with pytest.raises(ValueError, match=match):
            session.start()


def test_infomax_choice_per_cost_with_spread_views():
    grid = Grid(3, 3)
    model = _model(grid, k=3, seed=8, radius=1)
    costs = np.linspace(1.0, 2.0, 9)
    session = OccupancySession(grid, model, SearchSettings(targets='many', scan=False,
                                                           start_cell='policy'), costs=costs)
    session.reset()
    first = session.start()
    k = model.max_count + 1
    offsets = model.offsets(np.arange(9))
    p = session.belief
    exact = channel_information(p[None, :], model.p_target.reshape(-1, k)[offsets],
                                model.p_null.reshape(-1, k)[offsets]).sum(axis=1)
    assert first == int(np.argmax(exact / costs))
    assert np.all(exact[[0, 2, 6, 8]] < exact[4])       # corners see 4 cells, the centre 9


def test_stop_rules_decided_budget_and_repeat():
    grid = Grid(2, 2)
    pt = np.tile([0.05, 0.95], (2, 2, 1))
    pn = np.tile([0.95, 0.05], (2, 2, 1))
    model = CountObservation(grid, pt, pn)
    settings = SearchSettings(targets='many', confidence=0.99, absent_prior=0.5,
                              inhibit_return=True)
    session = OccupancySession(grid, model, settings)
    session.reset()
    session.start()
    for _ in range(2):                                # two looks at 0.95 / 0.05: not 0.99 yet
        result = session.update(Frame(np.array([1.0, 0.0, 0.0, 0.0])))
        assert not result.ended
    result = session.update(Frame(np.array([1.0, 0.0, 0.0, 0.0])))
    occupied, empty = decided(session.log_odds, 0.99)
    assert result.ended and result.decision == 'found' and result.terminated
    assert occupied.tolist() == [True, False, False, False] and np.all(occupied | empty)
    session.reset()
    session.start()
    result = session.update(Frame(np.zeros(4)))
    while not result.ended:
        result = session.update(Frame(np.zeros(4)))
    assert result.decision == 'absent' and result.fixations == 2      # evidence 2 x log(1/19)
    budget = OccupancySession(grid, model, SearchSettings(targets='many', max_fixations=1,
                                                          absent_prior=0.5))
    budget.reset()
    budget.start()
    result = budget.update(Frame(np.array([1.0, 0.0, np.nan, 0.0])))
    assert result.truncated and result.reason == 'budget'
    deadline = OccupancySession(grid, model, SearchSettings(
        targets='many', max_fixations=1, absent_prior=0.5, decide_at_budget=True))
    deadline.reset()
    deadline.start()
    result = deadline.update(Frame(np.array([1.0, 0.0, np.nan, 0.0])))
    assert result.decision == 'found'
    assert deadline.occupied().tolist() == [True, False, False, False]
    # Nothing left to learn: a model whose views say nothing gives up (repeat) at once.
    blind = OccupancySession(grid, CountObservation(grid, pn, pn),
                             SearchSettings(targets='many'))
    blind.reset()
    blind.start()
    result = blind.update(Frame(np.zeros(4)))
    assert result.truncated and result.reason == 'repeat'


def test_settings_refusals():
    with pytest.raises(ValueError, match=r"search.targets must be one of one, many, got 'all'"):
        SearchSettings(targets='all')
    assert SearchSettings().targets == 'one'
    assert SearchSettings.from_parameters({'search.targets': 'many'}).targets == 'many'
    grid = Grid(2, 2)
    moving = OccupancySession(grid, _model(grid), SearchSettings(targets='many',
                                                                 motion_sigma_cells=0.5))
    assert moving.motion.active                     # section 12.10: people who move
    # coverage's tour and the one-target group stop mean nothing to the occupancy belief: a
    # configuration layered on the pan/tilt face config (which turns both on) searches as
    # without them
    big = Grid(4, 4)
    paths = []
    for extra in ({}, {'head_tour': True, 'group_stop': True}):
        session = OccupancySession(big, _model(big), SearchSettings(
            targets='many', head_speed_deg_s=50.0, absent_prior=0.5, max_fixations=5,
            **extra))
        session.reset(seed=0)
        cell = session.start()
        for _ in range(5):
            groups = np.zeros(big.n_cells)
            groups[cell] = 1
            result = session.update(Frame(np.zeros(big.n_cells), groups=groups))
            if result.ended:
                break
            cell = result.fixation
        paths.append((session.path, session.decision))
    assert paths[0] == paths[1]
    with pytest.raises(ValueError, match='excludes no cells'):
        session = OccupancySession(grid, _model(grid), SearchSettings(targets='many'))
        session.reset()
        session.exclude([1])


def test_one_face_with_spill_over_is_counted_once():
    """A face whose detections spill into its neighbours makes several occupied cells: one face."""
    grid = Grid(1, 5)
    pt = np.tile([0.1, 0.2, 0.7], (1, 5, 1))
    pn = np.tile([0.8, 0.15, 0.05], (1, 5, 1))
    model = CountObservation(grid, pt, pn)
    truth = np.array([False, False, True, False, False])
    rng = np.random.default_rng(0)
    frames = _frames(model, rng, [2, 1, 3, 2], truth, nan_share=0.0, spill=2)
    log_odds = prior_log_odds(5, 0.1)
    for frame, k in zip(frames, [2, 1, 3, 2]):
        log_odds = update_log_odds(log_odds, model.log_likelihood_ratio(frame, k))
    occupied = decided(log_odds, 0.95)[0]
    assert occupied.sum() >= 2                            # the spill-over looks like faces
    faces = count_faces(log_odds, grid, occupied, image_px=(100, 20))
    assert len(faces) == 1 and faces[0]['cell'] == 2
    assert faces[0]['probability'] == pytest.approx(
        1 - np.prod(1 - occupancy(log_odds[faces[0]['cells']])))
    cells = faces[0]['cells']
    np.testing.assert_array_equal(faces[0]['box'], [20 * cells.min(), 0,
                                                    20 * (cells.max() - cells.min() + 1), 20])
    # Raw boxes of one face from several windows merge into one (equal scores: the largest).
    one_box = np.array([[40, 0, 20, 20], [42, 1, 19, 19], [38, 0, 22, 20]], dtype=float)
    faces = count_faces(log_odds, grid, occupied, one_box, image_px=(100, 20))
    assert len(faces) == 1 and faces[0]['cell'] == 2
    assert faces[0]['box'].tolist() == [38, 0, 22, 20]


def test_two_faces_in_one_cell_when_the_boxes_say_so():
    grid = Grid(2, 2)
    log_odds = np.array([5.0, -5.0, -5.0, -5.0])
    occupied = log_odds > 0
    boxes = np.array([[2, 2, 20, 20], [24, 3, 20, 20], [3, 2, 19, 20]], dtype=float)
    faces = count_faces(log_odds, grid, occupied, boxes, image_px=(100, 100))
    assert len(faces) == 2
    assert sorted(f['box'][0] for f in faces) == [2, 24]
    assert {f['cell'] for f in faces} == {0}


def test_in_a_crowd_a_strong_box_seen_once_is_a_face_beside_one_seen_often():
    """A crowd of find --all: one cluster of occupied cells, faces seen by one call or three."""
    grid = Grid(1, 6)
    log_odds = np.array([5.0, 5.0, 5.0, 5.0, -5.0, -5.0])
    occupied = log_odds > 0
    often = [[0, 0, 20, 20], [1, 0, 20, 20], [0, 1, 19, 20]]      # three calls, 0.9 each
    once = [[42, 0, 18, 18]]                                       # one call, 0.8
    stray = [[18, 2, 14, 14]]                                      # beside the first, 0.6
    boxes = np.array(often + once + stray, dtype=float)
    scores = np.array([0.9, 0.9, 0.9, 0.8, 0.6])
    # without a strong score the cluster's best support (2.7) decides: one face
    faces = count_faces(log_odds, grid, occupied, boxes, scores, image_px=(120, 20))
    assert len(faces) == 1
    faces = count_faces(log_odds, grid, occupied, boxes, scores, image_px=(120, 20),
                        strong=0.7)
    assert sorted(f['box'][0] for f in faces) == [0, 42]        # the stray is no face
    # a detector that keeps no scores has no strong score: its raw counts decide as before
    assert len(count_faces(log_odds, grid, occupied, boxes, image_px=(120, 20),
                           strong=0.7)) == len(count_faces(log_odds, grid, occupied, boxes,
                                                           image_px=(120, 20)))
    # a strong box touching a face seen more often is still that face
    touching = np.array(often + [[12, 0, 20, 20]], dtype=float)
    faces = count_faces(log_odds, grid, occupied, touching, np.array([0.9, 0.9, 0.9, 0.8]),
                        image_px=(120, 20), strong=0.7)
    assert len(faces) == 1
    # below the strong score, a box seen once beside no other still waits for the best's share
    faces = count_faces(log_odds, grid, occupied, boxes, np.array([0.9, 0.9, 0.9, 0.6, 0.6]),
                        image_px=(120, 20), strong=0.7)
    assert len(faces) == 1


def test_a_box_centred_past_the_grids_edge_names_the_edge_cell():
    """A wide view at the edge sees past the grid: its box still names a cell of the grid."""
    grid = Grid(3, 3)
    log_odds = np.full(9, -5.0)
    log_odds[[0, 8]] = 5.0                              # corners (0, 0) and (2, 2)
    occupied = log_odds > 0
    past = np.array([[-80, -75, 20, 20], [150, 160, 20, 20]], dtype=float)  # up-left, down-right
    for boxes in (past, past[:1], past[1:]):
        faces = count_faces(log_odds, grid, occupied, boxes, image_px=(90, 90), link=1)
        assert sorted(f['cell'] for f in faces) == [0, 8]


def test_clusters_link_distance():
    grid = Grid(3, 6)
    cells = np.array([0, 7, 4, 17])                   # (0,0) (1,1) | (0,4) | (2,5)
    assert clusters(cells, grid, 1).tolist() == [0, 0, 1, 2]
    assert clusters(cells, grid, 2).tolist() == [0, 0, 1, 1]


def test_run_search_on_simulated_scenes_ends_after_a_decisive_scan():
    from ipomdp_gaze.search.sensors import ModelSensor, run_search
    grid = Grid(3, 3)
    pt = np.tile([0.1, 0.9], (3, 3, 1))
    pn = np.tile([0.9, 0.1], (3, 3, 1))
    model = CountObservation(grid, pt, pn, scan_target=[0.0001, 0.9999],
                             scan_null=[0.9999, 0.0001])
    settings = SearchSettings(targets='many', confidence=0.99, absent_prior=0.5,
                              max_fixations=20, inhibit_return=True)
    session = OccupancySession(grid, model, settings)
    empty = run_search(session, ModelSensor(grid, model, np.random.default_rng(0)), None)
    assert empty.decision == 'absent' and empty.fixations == 0 and empty.path == ()
    one = run_search(session, ModelSensor(grid, model, np.random.default_rng(0)), 4)
    assert one.decision == 'found' and one.fixations == 0
    assert [f['cell'] for f in session.faces()] == [4]


def test_the_fixations_after_the_scan_keep_to_their_own_budget():
    """A budget of the whole search and one of the fixations after the scan: both are kept."""
    from ipomdp_gaze.search.sensors import ModelSensor, run_search
    grid = Grid(3, 3)
    model = CountObservation(grid, np.tile([0.5, 0.5], (3, 3, 1)),
                             np.tile([0.55, 0.45], (3, 3, 1)), scan_target=[0.5, 0.5],
                             scan_null=[0.55, 0.45])

    class Costed(ModelSensor):

        def scan(self):
            return replace(super().scan(), detector_pixels=1000)

        def scan_cost(self):
            return 1000

        def fixation_cost(self, cell):
            return 100

        def observe(self, cell):
            return replace(super().observe(cell), detector_pixels=100)
    settings = SearchSettings(targets='many', confidence=0.999, absent_prior=0.5,
                              max_fixations=30, inhibit_return=False)
    session = OccupancySession(grid, model, settings)

    def run(**budgets):
        return run_search(session, Costed(grid, model, np.random.default_rng(0)), 4, **budgets)
    assert run(pixel_budget=1650).fixations == 6                     # 1000 + 6 x 100
    assert run(pixel_budget=10 ** 6, fixation_budget=350).fixations == 3
    capped = run(pixel_budget=1650, fixation_budget=10 ** 6)
    assert capped.fixations == 6 and capped.detector_pixels == 1600
    assert capped.reason == 'pixels'
    assert run(fixation_budget=350).fixations == 3                   # no total budget


def test_the_single_target_session_refuses_many_targets():
    grid = Grid(2, 2)
    with pytest.raises(ValueError, match='search.targets many is searched by '
                                         'ipomdp_gaze.search.many.OccupancySession'):
        SearchSession(grid, _model(grid), None, SearchSettings(targets='many'))


def test_gaussian_information_equals_the_integral_of_the_entropy_drop():
    """The Gaussian channel's information (binned for the table) against direct integration."""
    grid = Grid(3, 3)
    model = GaussianObservation(grid, make_fpoc('human'))
    log_odds = np.array([-4.0, -1.0, 0.0, 0.5, 2.0, -6.0, 1.0, -0.3, 3.0])
    p = occupancy(log_odds)
    o = np.linspace(-12.0, 14.0, 26_001)
    phi0 = np.exp(-0.5 * o ** 2) / math.sqrt(2 * math.pi)

    def drop(p_j, d):
        phi1 = np.exp(-0.5 * (o - d) ** 2) / math.sqrt(2 * math.pi)
        m = p_j * phi1 + (1 - p_j) * phi0
        after = binary_entropy(np.divide(p_j * phi1, m, out=np.zeros_like(m), where=m > 0))
        trapezoid = getattr(np, 'trapezoid', None) or np.trapz     # numpy 1.x: trapz only
        return binary_entropy(p_j) - trapezoid(m * after, o)

    d = model.dprime(np.arange(9))                                      # [k, j]
    brute = np.array([[drop(p[j], d[k, j]) for j in range(9)] for k in range(9)])
    np.testing.assert_allclose(InformationTable(model)(log_odds), brute, rtol=2e-3, atol=1e-6)


def test_empty_by_evidence_needs_looks_where_a_sparse_prior_decides_at_once():
    """A sparse prior decides every cell empty before any look; the evidence rule does not."""
    from ipomdp_gaze.search.sensors import ModelSensor, run_search
    grid = Grid(3, 3)
    pt = np.tile([0.1, 0.9], (3, 3, 1))
    pn = np.tile([0.9, 0.1], (3, 3, 1))
    model = CountObservation(grid, pt, pn, scan_target=[0.5, 0.5], scan_null=[0.5, 0.5])
    settings = SearchSettings(targets='many', confidence=0.99, absent_prior=0.95,
                              max_fixations=30, inhibit_return=True)
    assert cell_prior(9, 0.95) < 0.01                     # every cell "empty" a priori
    eager = run_search(OccupancySession(grid, model, settings, empty_by_evidence=False),
                       ModelSensor(grid, model, np.random.default_rng(0)), 4)
    assert eager.decision == 'absent' and eager.fixations == 0      # it never looked
    session = OccupancySession(grid, model, settings)                # the default
    careful = run_search(session, ModelSensor(grid, model, np.random.default_rng(0)), 4)
    assert careful.fixations > 0 and careful.decision == 'found'
    assert [f['cell'] for f in session.faces()] == [4]
    log_odds, prior = session.log_odds, prior_log_odds(9, cell_prior(9, 0.95))
    empty = ~session.occupied()
    assert np.all(log_odds[empty] - prior[empty] <= -math.log(99))


def test_faces_with_spill_over_are_counted_once_across_random_scenes():
    """Scenes of 0-2 faces whose detections spill into both neighbours: no face comes out twice."""
    grid = Grid(1, 9)
    pt = np.tile([0.15, 0.25, 0.6], (1, 9, 1))
    pn = np.tile([0.85, 0.1, 0.05], (1, 9, 1))
    model = CountObservation(grid, pt, pn)
    rng = np.random.default_rng(12)
    exact = 0
    for trial in range(60):
        n_faces = trial % 3
        truth = np.zeros(9, dtype=bool)
        if n_faces:
            truth[rng.choice([1, 4, 7], size=n_faces, replace=False)] = True  # 3 cells apart
        fixations = list(rng.integers(0, 9, size=6))
        frames = _frames(model, rng, fixations, truth, nan_share=0.0, spill=1)
        log_odds = prior_log_odds(9, 0.1)
        for frame, k in zip(frames, fixations):
            log_odds = update_log_odds(log_odds, model.log_likelihood_ratio(frame, k))
        faces = count_faces(log_odds, grid, decided(log_odds, 0.95)[0], link=2)
        cells = [f['cell'] for f in faces]
        assert len(faces) <= n_faces                                 # never twice
        assert all(np.abs(np.flatnonzero(truth) - c).min() <= 1 for c in cells)
        exact += len(faces) == n_faces
        if n_faces == 1:                      # a lone face's spill-over is one cluster
            assert len(faces) == 1
    assert exact >= 45       # two faces 3 cells apart can merge (their spill-over touches)


def test_simulated_searches_of_the_paper_task_find_the_target_or_nobody():
    """7x7, human FPOC, one target or none: each target found within one cell, none invented."""
    from ipomdp_gaze.search.sensors import ModelSensor, run_search
    grid = Grid(7, 7)
    model = GaussianObservation(grid, make_fpoc('human'))
    settings = SearchSettings(targets='many', confidence=0.95, max_fixations=60,
                              absent_prior=0.5)
    session = OccupancySession(grid, model, settings)
    for e in range(12):
        target = None if e % 4 == 0 else int(np.random.default_rng(e).integers(49))
        outcome = run_search(session, ModelSensor(grid, model, np.random.default_rng([7, e])),
                             target)
        cells = [grid.cell(f['cell']) for f in session.faces()]
        assert outcome.decision == ('absent' if target is None else 'found')
        if target is not None:
            [(r, c)] = cells
            assert max(abs(r - target // 7), abs(c - target % 7)) <= 1
        else:
            assert cells == []


class _Sweep:
    """A stand-in for the sweep policy: its name and its poses (what a pass reads)."""

    name = 'sweep'

    def __init__(self, poses):
        self.poses = np.asarray(poses)


def _pass_session(grid, model, poses, **settings):
    session = OccupancySession(grid, model, SearchSettings(
        targets='many', absent_prior=0.5, max_fixations=20, **settings), link=1)
    session.set_policy(_Sweep(poses))
    session.reset()
    return session


def test_a_pass_takes_the_sweeps_poses_in_order_and_ends_on_the_likelier_side():
    grid = Grid(3, 3)
    model = _model(grid, k=3, seed=4)
    poses = [0, 2, 8, 6]
    session = _pass_session(grid, model, poses)
    assert session.passing
    taken = [session.start()]
    rng = np.random.default_rng(1)
    result = None
    while not session.ended:
        result = session.update(Frame(rng.integers(0, 3, grid.n_cells).astype(float)))
        if not session.ended:
            taken.append(result.fixation)
    assert taken == poses and session.path == tuple(poses)
    assert result.reason == 'pass' and session.gave_up_reason == 'pass'
    assert session.occupied().tolist() == (session.log_odds > 0).tolist()
    assert result.decision == ('found' if session.faces() else 'absent')
    # Any other policy: the infomax choice, as before.
    other = OccupancySession(grid, model, SearchSettings(targets='many', absent_prior=0.5))
    other.set_policy(object())
    other.reset()
    assert not other.passing


def test_a_pass_names_grouped_detections_apart_from_the_beliefs_faces():
    grid = Grid(5, 5)
    pt = np.tile([0.5, 0.5], (5, 5, 1))              # counts that say nothing: the belief
    model = CountObservation(grid, pt, pt.copy())     # names no face, the groups decide
    session = _pass_session(grid, model, [6, 8, 18])
    session.start()
    groups = np.zeros((3, grid.n_cells))
    groups[0, [0, 1, 12]] = 1                         # 1 is within one cell of 0: one face
    groups[1, [13, 24]] = 1                           # 13 is next to 12 (seen before)
    groups[2, [24]] = 2                               # the same face again
    for frame_groups in groups:
        session.update(Frame(np.zeros(grid.n_cells), groups=frame_groups))
    assert session.ended and session.decision == 'found'
    faces = session.faces()
    assert [f['cell'] for f in faces] == [0, 12, 24]
    assert all(f['grouped'] and f['box'] is None for f in faces)
    assert [f['probability'] for f in faces] == pytest.approx(session.belief[[0, 12, 24]])


def test_a_pass_tells_neighbouring_groups_apart_by_where_their_detections_lie():
    from ipomdp_gaze.search.many import GROUP_SAME_FACE_CELLS
    grid = Grid(5, 5)
    pt = np.tile([0.5, 0.5], (5, 5, 1))
    model = CountObservation(grid, pt, pt.copy())
    session = _pass_session(grid, model, [6, 8, 18])
    session.start()
    frames = []
    for cells, shifts in (([11, 12], [(0.0, -0.3), (0.0, 0.3)]),    # two people, 1.6 apart
                          ([17], [(-0.45, 0.0)]),     # below the second, 0.55 from it
                          ([2, 3], [(0.0, 0.45), (0.0, -0.45)])):   # one face, 0.1 apart
        groups, offsets = np.zeros(grid.n_cells), np.full((grid.n_cells, 2), np.nan)
        groups[cells] = 1
        offsets[cells] = shifts
        frames.append(Frame(np.zeros(grid.n_cells), groups=groups, offsets=offsets))
    for frame in frames:
        session.update(frame)
    faces = session.faces()
    # 12 is 1.6 from 11 (two faces, where the cells alone made one); 17 lies 0.55 from 12's
    # detections (row 3 - 0.45 against row 2, col 2 against 2.3): within 0.75, the same face;
    # 3 lies 0.1 from 2.
    assert GROUP_SAME_FACE_CELLS == 0.75
    assert [f['cell'] for f in faces] == [11, 12, 2]
    assert faces[0]['at'] == pytest.approx((2.0, 0.7)) and faces[1]['at'] == \
        pytest.approx((2.0, 2.3))


def test_a_pass_names_the_better_placed_first_and_the_rest_only_away_from_them():
    grid = Grid(3, 3)
    pt = np.tile([0.05, 0.95], (3, 3, 1))
    pn = np.tile([0.95, 0.05], (3, 3, 1))
    session = _pass_session(grid, CountObservation(grid, pt, pn), [4])
    session.start()
    values = np.zeros(grid.n_cells)
    values[0] = 1.0                                  # the belief: cell 0 likelier occupied
    groups = np.zeros(grid.n_cells)
    groups[[1, 8]] = 1                               # 1 is within one cell of it, 8 is not
    result = session.update(Frame(values, groups=groups))
    assert result.ended and result.reason == 'pass'
    # With the views' boxes the belief's face (at its box) first, the groups away from it ...
    box = np.array([[1.0, 1.0, 8.0, 8.0]])            # centred in cell 0 of a 30x30 picture
    with_boxes = session.faces(box, None, (30, 30))
    assert [(f['cell'], f.get('grouped', False)) for f in with_boxes] == [(0, False), (8, True)]
    # ... without them the groups (at their centres) first: cell 0 is taken for group 1's face.
    without = [(f['cell'], f.get('grouped', False)) for f in session.faces()]
    assert without == [(1, True), (8, True)]


@pytest.mark.parametrize('groups, match', [
    (np.zeros(3), 'shape'), (np.full(4, -1.0), 'whole numbers'), (np.full(4, 0.5), 'whole'),
    (np.array([0, 1, np.nan, 0]), 'whole'), (np.array([0, np.inf, 0, 0]), 'whole')])
def test_bad_groups_are_refused_and_the_belief_is_unchanged(groups, match):
    from ipomdp_gaze.model.belief import EvidenceError
    grid = Grid(2, 2)
    session = _pass_session(grid, _model(grid, k=2), [0, 3])
    session.start()
    before = session.log_odds.copy()
    with pytest.raises(EvidenceError, match=match):
        session.checked_frame(np.zeros(4), groups=groups)
    result = session.update(Frame(np.zeros(4), groups=groups))
    assert result.status == 'rejected' and match in result.reason
    assert np.array_equal(session.log_odds, before) and session.fixations == 0


def test_a_moving_search_makes_no_pass():
    grid = Grid(3, 3)
    session = OccupancySession(grid, _model(grid), SearchSettings(
        targets='many', motion_sigma_cells=0.5))
    session.set_policy(_Sweep([0, 8]))
    session.reset()
    assert not session.passing


def test_a_pass_cut_by_its_budget_decides_with_its_groups_and_keeps_its_policy():
    grid = Grid(5, 5)
    pt = np.tile([0.5, 0.5], (5, 5, 1))              # the belief names nobody
    model = CountObservation(grid, pt, pt.copy())
    groups = np.zeros(grid.n_cells)
    groups[12] = 1
    session = OccupancySession(grid, model, SearchSettings(
        targets='many', absent_prior=0.5, max_fixations=2, decide_at_budget=True), link=1)
    session.set_policy(_Sweep([6, 8, 18]))
    session.reset()
    session.start()
    session.update(Frame(np.zeros(grid.n_cells), groups=groups))
    session.set_policy(object())                     # mid-search: the pass goes on
    assert session.passing
    result = session.update(Frame(np.zeros(grid.n_cells)))
    assert result.reason == 'budget' and result.decision == 'found'
    assert [f['cell'] for f in session.faces()] == [12]
    session.reset()                                   # the next search: infomax, no groups
    assert not session.passing
    session.start()
    session.update(Frame(np.zeros(grid.n_cells), groups=groups))
    assert session.faces() == []
    session.set_policy(_Sweep([6, 8, 18]))
    assert not session.passing and session.faces() == []


def test_a_pass_that_decides_takes_the_posterior_for_empty_once_every_pose_is_seen():
    """``search.decide_after_pass``: empty by the evidence alone during the pass, then by P."""
    grid = Grid(5, 5)
    pt = np.tile([0.5, 0.5], (5, 5, 1))              # counts that say nothing: only the prior
    model = CountObservation(grid, pt, pt.copy())     # (log odds -5.5 < -4.6) decides a cell
    poses = [6, 8, 18, 16]
    for decide in (False, True):
        session = OccupancySession(grid, model, SearchSettings(
            targets='many', absent_prior=0.9, confidence=0.99, max_fixations=20,
            decide_after_pass=decide), link=1)
        session.set_policy(_Sweep(poses))
        session.reset()
        session.start()
        results = [session.update(Frame(np.zeros(grid.n_cells))) for _ in poses]
        assert [r.ended for r in results] == [False] * 3 + [True]      # the pass first
        assert session.path == tuple(poses) and session.decision == 'absent'
        assert session.room_done == decide
        assert results[-1].reason == ('' if decide else 'pass')


def test_a_decided_room_names_no_group_where_its_belief_decided_nobody():
    """A group in a cell the decided belief holds empty is texture; the pass alone names it."""
    grid = Grid(5, 5)
    pt = np.tile([0.5, 0.5], (5, 5, 1))
    model = CountObservation(grid, pt, pt.copy())
    groups = np.zeros(grid.n_cells)
    groups[12] = 1
    named = {}
    for decide in (False, True):
        session = OccupancySession(grid, model, SearchSettings(
            targets='many', absent_prior=0.9, confidence=0.99, max_fixations=20,
            decide_after_pass=decide), link=1)
        session.set_policy(_Sweep([6, 8, 18, 16]))
        session.reset()
        session.start()
        for k in range(4):
            session.update(Frame(np.zeros(grid.n_cells), groups=groups if k == 1 else None))
        assert session.ended and session.belief[12] < 0.01
        named[decide] = ([f['cell'] for f in session.faces()], session.decision)
    assert named[False] == ([12], 'found')            # the pass names every group
    assert named[True] == ([], 'absent')               # decided: its belief vetoes it


def test_a_pass_that_decides_goes_on_by_infomax_until_the_room_is_done():
    from ipomdp_gaze.search.sensors import ModelSensor, run_search
    grid = Grid(3, 3)
    pt = np.tile([0.1, 0.3, 0.6], (3, 3, 1))         # a face's cell fires more, at every offset
    model = CountObservation(grid, pt, pt[..., ::-1].copy())
    poses = [0, 2, 8, 6]
    ended = {}
    for decide in (False, True):
        session = OccupancySession(grid, model, SearchSettings(
            targets='many', absent_prior=0.5, max_fixations=40, decide_after_pass=decide),
            link=1)
        session.set_policy(_Sweep(poses))
        outcome = run_search(session, ModelSensor(grid, model, np.random.default_rng(0)), 4)
        ended[decide] = (outcome, session.room_done, [f['cell'] for f in session.faces()])
    passed, done, cells = ended[False]
    assert list(passed.path) == poses and passed.reason == 'pass' and not done
    assert passed.decision == 'absent' and cells == []             # the pass alone missed it
    decided, done, cells = ended[True]
    assert list(decided.path[:4]) == poses and len(decided.path) > 4     # views after the pass
    assert decided.reason == '' and done and decided.decision == 'found'
    assert [grid.cell(c) for c in cells] == [(1, 1)]                # the face, counted once


def test_a_stray_large_box_does_not_become_the_box_of_the_faces_it_covers():
    """Haar's raw boxes (no scores): the box most others overlap is kept, not the largest."""
    from ipomdp_gaze.model.occupancy import merge_boxes
    face = [[100, 100, 40, 40], [102, 99, 40, 41], [98, 101, 42, 40]]
    other = [[160, 105, 30, 30], [161, 104, 31, 31]]
    stray = [[60, 60, 160, 160]]                            # round both, a texture's scale
    kept, support = merge_boxes(stray + face + other)
    assert len(kept) == 2 and kept[0].tolist() in face and kept[1].tolist() in other
    assert support.tolist() == [4, 2]                       # the stray joined the face it holds
    kept, _ = merge_boxes(stray + face, scores=[0.9, 0.8, 0.7, 0.6])    # scores still rule
    assert kept.tolist()[0] == stray[0]


@pytest.mark.parametrize('link', [0, 1])
def test_the_still_gains_kept_between_frames_are_those_computed_afresh(link):
    """The gains' (N, N) terms are updated per changed column; every call equals a fresh one."""
    grid = Grid(12, 12)                    # a frame changes at most 25 of 144 cells' terms
    model = _model(grid, k=3, seed=7, radius=2)
    session = OccupancySession(grid, model, SearchSettings(
        targets='many', absent_prior=0.5, repeat_weight=0.5, confidence=0.99), link=link)
    session.reset()
    session.start()
    rng = np.random.default_rng(3)

    def fresh(log_odds=None):
        kept, session._gain_cache = session._gain_cache, None
        try:
            return session.gains(log_odds)
        finally:
            session._gain_cache = kept

    for step in range(40):
        if step == 20:
            session.configure(replace(session.settings, repeat_weight=0.2))
        want = fresh()
        np.testing.assert_array_equal(session.gains(), want)
        other = session.log_odds + rng.normal(0, 0.01, grid.n_cells) * \
            (rng.random(grid.n_cells) < 0.1)
        np.testing.assert_array_equal(session.gains(other), fresh(other))
        if session.ended:
            break
        fixation = grid.index(*rng.integers(3, 8, 2))
        session.fixate(fixation)
        # Each cell's likeliest count for a face at (5, 5), none elsewhere: cells get decided
        # (and with link, their neighbours settled) while the search goes on.
        terms = np.stack([model.log_likelihood_ratio(np.full(grid.n_cells, c), fixation)
                          for c in range(3)])
        face = np.zeros(grid.n_cells, bool)
        face[grid.index(5, 5)] = True
        frame = np.where(face, terms.argmax(axis=0), terms.argmin(axis=0)).astype(float)
        frame[rng.random(grid.n_cells) < 0.3] = np.nan
        session.update(Frame(frame))


def test_the_information_table_interpolates_between_its_points_and_clamps_beyond_them():
    """Off its 0.1 grid the table interpolates; decided cells (|L| >= 30) read its ends, ~0."""
    grid = Grid(3, 4)
    model = _model(grid, k=3, seed=8)
    table = InformationTable(model)
    offsets = model.offsets(np.arange(grid.n_cells))
    k = model.max_count + 1
    rng = np.random.default_rng(8)
    log_odds = rng.uniform(-8.0, 8.0, grid.n_cells)
    log_odds[:4] = [0.05, -2.95, 1.234, 3.3333]              # between the table's points
    exact = channel_information(occupancy(log_odds)[None, :],
                                model.p_target.reshape(-1, k)[offsets],
                                model.p_null.reshape(-1, k)[offsets])
    np.testing.assert_allclose(table(log_odds), exact, atol=5e-4)
    decided_cells = np.array([TABLE_LOG_ODDS, TABLE_LOG_ODDS + 15.0, -TABLE_LOG_ODDS, -1e6,
                              np.inf, -np.inf] + [0.0] * (grid.n_cells - 6))
    info = table(decided_cells)
    assert np.isfinite(info).all()
    assert np.all(info[:, :6] < 1e-9)
    session = OccupancySession(grid, model, SearchSettings(targets='many'))
    session.reset()
    assert np.isfinite(session.gains(decided_cells)).all()


def test_a_cell_is_decided_at_exactly_the_confidence_either_way():
    confidence = 0.9
    threshold = math.log(confidence) - math.log1p(-confidence)
    occupied, empty = decided(np.array([threshold, -threshold, np.nextafter(threshold, 0),
                                        np.nextafter(-threshold, 0)]), confidence)
    np.testing.assert_array_equal(occupied, [True, False, False, False])
    np.testing.assert_array_equal(empty, [False, True, False, False])


def test_a_predicted_expected_count_above_one_is_a_cell_occupied_for_certain_not_nan():
    """People walking in from outside can make m_j exceed 1: P'_j is clipped below 1."""
    grid = Grid(1, 2)
    motion = Motion(grid, 0.0, 0.0, 0.5)                  # half of those out of reach come in
    log_odds, outside = predict_occupancy(np.array([2.0, -1.0]), 5.0, motion, 1.0)
    assert np.all(np.isfinite(log_odds)) and np.all(log_odds <= MAX_LOG_ODDS)
    np.testing.assert_array_equal(log_odds, [MAX_LOG_ODDS, MAX_LOG_ODDS])
    assert 0.0 < outside < 5.0


@pytest.mark.parametrize('seconds', [0.0, -1.0])
def test_no_time_predicts_nothing_even_for_decided_cells(seconds):
    log_odds = np.array([45.0, -60.0, 0.3, 2.0])
    predicted, outside = predict_occupancy(log_odds, 0.7, Motion(Grid(2, 2), 0.8, 0.1, 0.2),
                                           seconds)
    np.testing.assert_array_equal(predicted, log_odds)
    assert outside == 0.7 and predicted is not log_odds


def test_the_information_table_of_a_model_is_never_another_models_by_a_reused_id():
    """The cache is keyed by id(model); an id reused after a model is freed must not match."""
    grid = Grid(2, 3)
    first, second = _model(grid, seed=1), _model(grid, seed=2)
    stale = information_table(first)
    _TABLES[id(second)] = (first, stale)          # as if `second` reused a freed model's id
    try:
        table = information_table(second)
        assert table is not stale
        np.testing.assert_array_equal(table.table, InformationTable(second).table)
    finally:
        _TABLES.pop(id(second), None)


@pytest.mark.parametrize('weight', [0.0, 0.3])
def test_a_view_seen_already_gains_repeat_weight_of_its_information_and_unseen_cells_full(weight):
    """w_kj is repeat_weight where view k repeats an equally good view; NaN cells were unseen."""
    grid = Grid(3, 3)
    model = _model(grid, k=3, seed=8, radius=1)
    session = OccupancySession(grid, model, SearchSettings(
        targets='many', scan=False, repeat_weight=weight, confidence=0.999))
    session.reset()
    k = session.start()
    frame = np.zeros(grid.n_cells)
    frame[0] = np.nan                                        # cell 0 not observed
    session.update(Frame(frame))
    info = InformationTable(model)(session.log_odds)        # [view, cell]
    seen = model.observed(k) & ~np.isnan(frame)
    expected = np.where(seen, weight, 1.0) * info[k]
    assert session.gains()[k] == pytest.approx(expected.sum(), rel=1e-12)


def test_inhibition_of_return_keeps_a_many_target_search_off_the_views_it_took():
    grid = Grid(3, 3)
    model = _model(grid, k=3, seed=8, radius=1)
    weak = CountObservation(grid, 0.95 * model.p_null + 0.05 * model.p_target, model.p_null)
    session = OccupancySession(grid, weak, SearchSettings(
        targets='many', scan=False, inhibit_return=True, max_fixations=9, confidence=0.999))
    session.reset()
    session.start()
    while not session.ended:
        session.update(Frame(np.zeros(grid.n_cells)))
    assert len(session.path) >= 3 and len(set(session.path)) == len(session.path)


def test_the_information_table_cache_is_safe_from_many_threads(monkeypatch):
    """
    Composed nodes on a MultiThreadedExecutor fill the cache at once (QA): no thread fails.

    More models than the cache keeps, so the threads evict and insert together, and every
    look at the cache and every build lets the other threads run (as a large grid's build
    does): no error, every table the one built alone, never more than the cache's size.
    """
    grid = Grid(2, 3)
    models = [_model(grid, seed=seed) for seed in range(3 * TABLE_CACHE_SIZE // 2)]
    alone = [InformationTable(model) for model in models]
    sizes = []

    class Cache(dict):
        """The cache, with a thread switch between reading its oldest key and evicting it."""

        def __iter__(self):
            keys = list(super().__iter__())
            time.sleep(0.0005)
            return iter(keys)

        def __setitem__(self, key, value):
            super().__setitem__(key, value)
            sizes.append(len(self))

    class Build(InformationTable):
        """A build that lets the other threads run first."""

        def __init__(self, model):
            time.sleep(0.001)
            super().__init__(model)

    monkeypatch.setattr('ipomdp_gaze.model.occupancy._TABLES', Cache())
    monkeypatch.setattr('ipomdp_gaze.model.occupancy.InformationTable', Build)
    threads, calls = 8, 100
    start, errors, got = threading.Barrier(threads), [], [[] for _ in range(threads)]

    def hammer(i):
        try:
            start.wait()
            for n in range(calls):
                j = (i * 5 + n) % len(models)
                got[i].append((j, information_table(models[j])))
        except Exception as exc:                      # noqa: B902 (any failure is the finding)
            errors.append(exc)

    workers = [threading.Thread(target=hammer, args=(i,)) for i in range(threads)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()
    assert errors == []
    assert sum(map(len, got)) == threads * calls
    assert max(sizes) <= TABLE_CACHE_SIZE
    for j, table in itertools.chain.from_iterable(got):
        for name in ('table', 'offset_id', 'flat_pair', 'view_information'):
            np.testing.assert_array_equal(getattr(table, name), getattr(alone[j], name))
