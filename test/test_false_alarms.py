# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""A scene's own false-alarm rate and hotspots (``model.false_alarms``) against Bayes."""
from ipomdp_gaze.drivers.scene_tasks import compare_settings
from ipomdp_gaze.model.false_alarms import check_false_alarm_scales, FalseAlarmMixture, scaled_null
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
import numpy as np
import pytest


def _model(rng, rows=3, cols=3, k=3):
    """Return a count model whose target and null tables differ at every offset."""
    grid = Grid(rows, cols)
    target = rng.dirichlet([1.0, 2.0, 3.0][:k], size=(rows, cols))
    null = rng.dirichlet([20.0, 1.0, 0.5][:k], size=(rows, cols))
    return grid, CountObservation(grid, target, null)


def _scaled(table, s):
    out = table.copy()
    out[..., 1:] *= s                                   # small scales: no cap is reached
    out[..., 0] = 1.0 - out[..., 1:].sum(axis=-1)
    return out


def _brute_posterior(model, frames, scales, absent_prior, hotspot_prior=0.0, hotspot_scale=2.0):
    """
    P(cell or absent | frames) by enumerating (scale, hypothesis, which cells are hotspots).

    Full likelihoods: every frame's probability under each joint hypothesis, no factoring.
    """
    import itertools
    grid = model.grid
    n = grid.n_cells
    cells = [grid.cell(i) for i in range(n)]
    hot_table = _scaled(model.p_null, hotspot_scale)
    patterns = itertools.product((False, True), repeat=n) if hotspot_prior > 0 else [(False,) * n]
    patterns = list(patterns)
    post = np.zeros(n + 1)
    for s in scales:
        null = _scaled(model.p_null, s)
        for h in range(n + 1):
            prior = absent_prior if h == n else (1 - absent_prior) / n
            for hot in patterns:
                if h < n and hot[h]:
                    continue                            # the face's cell is no hotspot
                p_hot = np.prod([hotspot_prior if hot[j] else 1 - hotspot_prior
                                 for j in range(n) if j != h])
                like = 1.0
                for fixation, counts in frames:
                    fr, fc = cells[fixation]
                    for j in range(n):
                        if np.isnan(counts[j]):
                            continue
                        r, c = cells[j]
                        off = (abs(r - fr), abs(c - fc))
                        table = model.p_target if j == h else hot_table if hot[j] else null
                        like *= table[off][int(counts[j])]
                post[h] += prior * p_hot * like / len(scales)
    return post / post.sum()


def _searched(model, settings, rng, n_frames: int, first_at_random: bool = False):
    """Search on random count frames (a fifth of the cells unobserved); the session, the frames."""
    grid = model.grid
    session = SearchSession(grid, model, None, settings)
    session.reset(seed=0)
    session.start()
    if first_at_random:
        session.fixate(int(rng.integers(grid.n_cells)))
    frames = []
    for _ in range(n_frames):
        counts = rng.integers(0, 3, size=grid.n_cells).astype(float)
        counts[rng.random(grid.n_cells) < 0.2] = np.nan          # some cells not observed
        frames.append((session.fixation, counts))
        assert session.update(Frame(counts)).applied
        session.fixate(int(rng.integers(grid.n_cells)))
    return session, frames


@pytest.mark.parametrize('seed', range(4))
def test_the_belief_is_the_brute_force_posterior_marginal_over_the_scales(seed):
    rng = np.random.default_rng(seed)
    grid, model = _model(rng)
    scales = (0.5, 1.0, 2.5)
    settings = SearchSettings(confidence=0.999999, absent_prior=0.3, false_alarm_scales=scales)
    session, frames = _searched(model, settings, rng, 5, first_at_random=True)
    expected = _brute_posterior(model, frames, scales, 0.3)
    assert session.belief == pytest.approx(expected[:-1], rel=1e-9, abs=1e-12)
    assert session.absent_probability == pytest.approx(expected[-1], rel=1e-9)


@pytest.mark.parametrize('seed', range(3))
def test_with_hotspots_the_belief_is_the_brute_force_posterior(seed):
    rng = np.random.default_rng(10 + seed)
    grid, model = _model(rng, 2, 3)
    scales, rho, hot = (1.0, 1.5), 0.2, 2.5
    settings = SearchSettings(confidence=0.999999, absent_prior=0.3, false_alarm_scales=scales,
                              hotspot_prior=rho, hotspot_scale=hot)
    session, frames = _searched(model, settings, rng, 4)
    expected = _brute_posterior(model, frames, scales, 0.3, rho, hot)
    assert session.belief == pytest.approx(expected[:-1], rel=1e-9, abs=1e-12)
    assert session.absent_probability == pytest.approx(expected[-1], rel=1e-9)


def test_a_spot_firing_weakly_from_every_view_is_not_taken_for_a_face_with_hotspots():
    grid = Grid(5, 5)
    # a face mostly gives 2, the background 0; one detection is rare for both, 2.5x likelier
    # for a face, and a hotspot's tables (the null's x 5) give it 0.2
    target = np.broadcast_to([0.3, 0.1, 0.6], (5, 5, 3))
    model = CountObservation(grid, target, np.broadcast_to([0.95, 0.04, 0.01], (5, 5, 3)))
    peak = {}
    for rho in (0.0, 0.05):
        session = SearchSession(grid, model, None,
                                SearchSettings(confidence=0.999999, absent_prior=0.5,
                                               hotspot_prior=rho, hotspot_scale=5.0))
        session.reset(seed=0)
        session.start()
        for fixation in (12, 6, 8, 16, 18):
            session.fixate(fixation)
            counts = np.zeros(grid.n_cells)
            counts[12] = 1.0                               # the same weak count every view
            session.update(Frame(counts))
        peak[rho] = session.belief[12]
    # without hotspots every view adds to the face there; with them the spot is as likely
    assert peak[0.0] > 0.5 and peak[0.05] < 0.1


def test_a_busy_scene_makes_each_detection_weigh_less_and_learns_its_rate():
    rng = np.random.default_rng(7)
    grid, model = _model(rng, 5, 5)
    busy = (rng.random(grid.n_cells) < 0.6).astype(float)   # a texture firing in most cells
    busy[6] = 2.0                                            # and one cell firing twice
    peak = {}
    for scales in ((1.0,), (1.0, 4.0)):
        session = SearchSession(grid, model, None,
                                SearchSettings(confidence=0.999999, false_alarm_scales=scales))
        session.reset(seed=0)
        session.start()
        session.fixate(12)
        session.update(Frame(busy))
        peak[scales] = session.belief[6]
        if len(scales) > 1:
            scale_posterior = np.exp(session._active_mixture().log_scale_posterior)
            assert scale_posterior[1] > 0.99                 # the scene fires about 4x as often
    # its double detection is as likely from the texture: the cell gets less of the belief
    assert peak[(1.0, 4.0)] < peak[(1.0,)]


@pytest.mark.parametrize('plain, same', [
    ({}, {'false_alarm_scales': [1.0]}),                               # one scale of one
    ({'false_alarm_scales': [1.0, 2.0]},                                # hotspot prior 0
     {'false_alarm_scales': [1.0, 2.0], 'hotspot_prior': 0.0, 'hotspot_scale': 50.0}),
])
def test_the_plain_settings_give_the_plain_model_bit_for_bit(plain, same):
    rng = np.random.default_rng(3)
    grid, model = _model(rng)
    frames = rng.integers(0, 3, size=(3, grid.n_cells)).astype(float)
    beliefs = []
    for settings in (SearchSettings(repeat_weight=0.3, **plain),
                     SearchSettings(repeat_weight=0.3, **same)):
        session = SearchSession(grid, model, None, settings)
        session.reset(seed=0)
        session.start()
        session.fixate(4)
        for counts in frames:
            session.update(Frame(counts))
        beliefs.append(session.log_belief)
    assert np.array_equal(beliefs[0], beliefs[1])


def test_the_scaled_null_table_keeps_uninformative_offsets_and_caps_detections():
    target = np.array([[[0.5, 0.5], [0.9, 0.1]]])
    null = np.array([[[0.5, 0.5], [0.8, 0.2]]])
    out = scaled_null(target, null, 10.0)
    assert np.array_equal(out[0, 0], null[0, 0])                   # target = null: says nothing
    assert out[0, 1] == pytest.approx([0.05, 0.95])                 # 10 x 0.2, capped at 0.95
    assert out.sum(axis=-1) == pytest.approx(np.ones((1, 2)))


@pytest.mark.parametrize('value', [[], [0.0], [1.0, 1.0], [float('nan')], [-2.0],
                                   list(range(1, 10)), None])
def test_bad_scales_are_refused_with_the_parameter_name(value):
    with pytest.raises(ValueError, match='search.false_alarm_scales must be 1 to 8 distinct'):
        SearchSettings(false_alarm_scales=value)


@pytest.mark.parametrize('value', ['abc', '12', [True]])
def test_scales_that_are_no_list_of_numbers_are_refused_with_the_parameter_name(value):
    """Text was read as its characters ('12': the factors 1 and 2), a bool as the factor 1."""
    with pytest.raises(ValueError, match='search.false_alarm_scales must be a list of numbers'):
        SearchSettings(false_alarm_scales=value)


@pytest.mark.parametrize('name, value', [('hotspot_prior', -0.1), ('hotspot_prior', 0.6),
                                         ('hotspot_prior', True), ('hotspot_prior', 'x'),
                                         ('hotspot_scale', 1.0), ('hotspot_scale', float('inf')),
                                         ('hotspot_scale', None)])
def test_bad_hotspot_settings_are_refused_with_the_parameter_name(name, value):
    with pytest.raises(ValueError, match=f'search.{name} must be'):
        SearchSettings(**{name: value})


def test_settings_round_trip_and_a_searcher_label_takes_a_list():
    settings = SearchSettings(false_alarm_scales=(8, 1, 2), hotspot_prior=0.02, hotspot_scale=10)
    assert settings.false_alarm_scales == (1.0, 2.0, 8.0)
    params = settings.to_parameters()
    assert params['search.false_alarm_scales'] == [1.0, 2.0, 8.0]
    assert params['search.hotspot_prior'] == 0.02 and params['search.hotspot_scale'] == 10.0
    assert SearchSettings.from_parameters(params) == settings
    changed = compare_settings(SearchSettings(), 'coverage:search.false_alarm_scales=[1, 4],'
                                                 'search.repeat_weight=0.3')
    assert changed.false_alarm_scales == (1.0, 4.0) and changed.repeat_weight == 0.3


def test_a_gaussian_model_refuses_scales_it_cannot_apply():
    from ipomdp_gaze.model.fpoc import make_fpoc
    grid = Grid(5, 5, 1.0)
    with pytest.raises(ValueError, match='search.false_alarm_scales needs a count model'):
        SearchSession(grid, make_fpoc('human'), None,
                      SearchSettings(false_alarm_scales=[1.0, 2.0]))
    session = SearchSession(grid, make_fpoc('human'), None, SearchSettings())
    with pytest.raises(ValueError, match='needs a count model'):
        session.configure(SearchSettings(false_alarm_scales=[1.0, 2.0]))
    with pytest.raises(ValueError, match='search.hotspot_prior needs a count model'):
        session.configure(SearchSettings(hotspot_prior=0.1))


def test_check_accepts_any_order_and_mixture_needs_valid_scales():
    assert check_false_alarm_scales([4, 0.5]) == (0.5, 4.0)
    _, model = _model(np.random.default_rng(0))
    with pytest.raises(ValueError):
        FalseAlarmMixture(model, [])
    assert FalseAlarmMixture(model, [2, 1]).scales == (1.0, 2.0)


def test_a_count_the_null_rules_out_is_still_a_frame_with_scales():
    rng = np.random.default_rng(5)
    grid, model = _model(rng)
    null = model.p_null.copy()
    null[..., 2] = 0.0                                      # the background never gives 2
    null /= null.sum(axis=-1, keepdims=True)
    model = CountObservation(grid, model.p_target, null)
    session = SearchSession(grid, model, None, SearchSettings(false_alarm_scales=[1.0, 3.0]))
    session.reset(seed=0)
    session.start()
    counts = np.zeros(grid.n_cells)
    counts[4] = 2.0
    assert session.update(Frame(counts)).applied
    assert np.all(np.isfinite(session.belief)) and session.map_cell == 4


@pytest.mark.parametrize('seed', range(2))
def test_one_factor_scales_the_false_alarm_rates_as_the_brute_force_posterior(seed):
    rng = np.random.default_rng(20 + seed)
    grid, model = _model(rng)
    settings = SearchSettings(confidence=0.999999, absent_prior=0.3, false_alarm_scales=[1.5])
    session, frames = _searched(model, settings, rng, 4)
    expected = _brute_posterior(model, frames, (1.5,), 0.3)
    assert session.belief == pytest.approx(expected[:-1], rel=1e-9, abs=1e-12)
    assert not np.allclose(expected, _brute_posterior(model, frames, (1.0,), 0.3))


def test_one_factor_other_than_one_is_refused_where_scales_are():
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.search.many import check_many_settings
    with pytest.raises(ValueError, match='does not model false-alarm scales'):
        check_many_settings(SearchSettings(targets='many', false_alarm_scales=[2.0]))
    with pytest.raises(ValueError, match='search.false_alarm_scales needs a count model'):
        SearchSession(Grid(5, 5, 1.0), make_fpoc('human'), None,
                      SearchSettings(false_alarm_scales=[2.0]))
