# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The search session (ipomdp_gaze.search.session) and its sensors, against brute force, by driver.

The belief after a scan and frames is the brute-force posterior (every hypothesis's likelihood
multiplied out, the absent hypothesis included); a repeat weight below 1 counts each cell's
views beyond its most informative one at that weight, recomputed here with plain loops; the
stop rules, the call order and every refused setting are checked; and the same frames give the
same fixations and decisions through find's driver and through the controller's.
"""
from __future__ import annotations

from dataclasses import replace
import itertools
import math

from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.model.still_evidence import cell_information
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.sensors import ModelSensor, run_search
from ipomdp_gaze.search.session import (Frame, OrderError, SearchSession, SearchSettings,
                                        start_index)
import numpy as np
import pytest

GRID = Grid(3, 4, 1.0)          # not square, an even side
K = 4


def count_model(seed=0, scan=True) -> CountObservation:
    """Random count tables on GRID (target tables favour higher counts near the fixation)."""
    rng = np.random.default_rng(seed)
    shape = GRID.shape + (K,)
    p_null = rng.dirichlet([6.0, 2.0, 1.0, 1.0], size=GRID.shape)
    p_target = rng.dirichlet([1.0, 1.0, 2.0, 3.0], size=GRID.shape)
    scan_tables = {}
    if scan:
        scan_tables = {'scan_target': rng.dirichlet([1.0, 1.0, 2.0, 3.0]),
                       'scan_null': rng.dirichlet([6.0, 2.0, 1.0, 1.0])}
    return CountObservation(GRID, p_target.reshape(shape), p_null.reshape(shape),
                            **scan_tables)


def brute_force_log_posterior(model, scan, frames, absent_prior, cell_prior=None):
    """Return log P(h | scan, frames) for each cell h, then absent: likelihoods multiplied out."""
    n = GRID.n_cells
    hypotheses = list(range(n)) + ([None] if absent_prior > 0 else [])
    cell_prior = np.full(n, 1 / n) if cell_prior is None else cell_prior
    out = []
    for h in hypotheses:
        prior = absent_prior if h is None else (1 - absent_prior) * cell_prior[h]
        if prior == 0:
            out.append(-math.inf)
            continue
        log_p = math.log(prior)
        for i in range(n):
            if scan is not None:
                table = model.scan_target if i == h else model.scan_null
                log_p += math.log(table[int(scan[i])])
            for fixation, frame in frames:
                fr, fc = GRID.cell(fixation)
                r, c = GRID.cell(i)
                table = model.p_target if i == h else model.p_null
                log_p += math.log(table[abs(r - fr), abs(c - fc), int(frame[i])])
        out.append(log_p)
    out = np.array(out)
    return out - np.logaddexp.reduce(out)


def weighted_log_posterior(model, scan, frames, absent_prior, weight):
    """Return the repeat-weighted posterior, by loops: per cell, best view + weight * the rest."""
    n = GRID.n_cells
    kernel = model.elm_kernel()
    log_b = np.full(n, math.log((1 - absent_prior) / n))
    if absent_prior > 0:
        log_b = np.append(log_b, math.log(absent_prior))
    if scan is not None:
        for i in range(n):
            log_b[i] += math.log(model.scan_target[int(scan[i])]) - \
                math.log(model.scan_null[int(scan[i])])
    for i in range(n):
        terms, infos = [], []
        for fixation, frame in frames:
            fr, fc = GRID.cell(fixation)
            r, c = GRID.cell(i)
            dr, dc = abs(r - fr), abs(c - fc)
            count = int(frame[i])
            terms.append(math.log(model.p_target[dr, dc, count])
                         - math.log(model.p_null[dr, dc, count]))
            infos.append(cell_information(kernel, GRID, fixation)[i])
        if not terms:
            continue
        best = int(np.argmax(infos)) if max(infos) > 0 else None
        kept = terms[best] if best is not None else 0.0
        log_b[i] += kept + weight * (sum(terms) - kept)
    return log_b - np.logaddexp.reduce(log_b)


@pytest.mark.parametrize('absent_prior', [0.0, 0.3])
@pytest.mark.parametrize('with_scan', [False, True])
def test_the_belief_is_the_brute_force_posterior(absent_prior, with_scan):
    model = count_model(1, scan=with_scan)
    settings = SearchSettings(confidence=1 - 1e-12, absent_prior=absent_prior,
                              max_fixations=8)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    sensor = ModelSensor(GRID, model, np.random.default_rng(4))
    sensor.start(5)
    session.reset(seed=0)
    scan = None
    if with_scan:
        frame = sensor.scan()
        scan = frame.values
        session.scan(frame)
        np.testing.assert_allclose(session.log_belief,
                                   brute_force_log_posterior(model, scan, [], absent_prior),
                                   atol=1e-12)
    cell, frames = session.start(), []
    for _ in range(8):
        frame = sensor.observe(cell)
        frames.append((cell, frame.values))
        result = session.update(frame)
        expected = brute_force_log_posterior(model, scan, frames, absent_prior)
        np.testing.assert_allclose(session.log_belief, expected, atol=1e-10)
        if result.ended:
            break
        cell = result.fixation
    assert result.ended and result.decision == 'gave_up' and result.truncated


@pytest.mark.parametrize('absent_prior', [0.0, 0.3])
def test_a_session_prior_is_where_the_belief_starts_and_bayes_goes_on_from(absent_prior):
    """The brute-force posterior under a prior over the cells, one of them ruled out."""
    model = count_model(2)
    prior = np.arange(GRID.n_cells, dtype=float)         # cell 0 at 0: never the target
    prior /= prior.sum()
    settings = SearchSettings(confidence=1 - 1e-12, absent_prior=absent_prior,
                              max_fixations=6)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings,
                            prior=prior.reshape(GRID.shape))
    sensor = ModelSensor(GRID, model, np.random.default_rng(5))
    sensor.start(7)
    session.reset(seed=0)
    np.testing.assert_allclose(session.belief, (1 - absent_prior) * prior, atol=1e-15)
    frame = sensor.scan()
    scan = frame.values
    session.scan(frame)
    cell, frames = session.start(), []
    for _ in range(6):
        frame = sensor.observe(cell)
        frames.append((cell, frame.values))
        result = session.update(frame)
        np.testing.assert_allclose(
            session.log_belief, brute_force_log_posterior(model, scan, frames, absent_prior,
                                                          prior), atol=1e-10)
        assert session.belief[0] == 0 and np.isfinite(session.entropy_nats)
        if result.ended:
            break
        cell = result.fixation
    session.reset()                                     # every search starts at it again
    np.testing.assert_allclose(session.belief, (1 - absent_prior) * prior, atol=1e-15)
    for bad, message in (([1.0], r'prior must hold one probability per cell, 12 values'),
                         (np.full(GRID.n_cells, 0.5), 'prior must sum to 1, got 6'),
                         (np.full((4, 3), 1 / 12), r'prior must be \(rows, cols\) = \(3, 4\)')):
        with pytest.raises(ValueError, match=message):
            SearchSession(GRID, model, None, settings, prior=bad)


def test_a_prior_with_empty_cells_keeps_a_moving_belief_finite():
    """A walking target from a prior with zeros: the motion step fills them, nothing is NaN."""
    model = count_model(3, scan=False)
    prior = np.zeros(GRID.n_cells)
    prior[[5, 6]] = 0.5
    settings = SearchSettings(confidence=0.999, motion_sigma_cells=0.7, max_fixations=0)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings,
                            prior=prior)
    sensor = ModelSensor(GRID, model, np.random.default_rng(6))
    sensor.start(5)
    session.reset(seed=1)
    cell = session.start()
    for _ in range(5):
        result = session.update(sensor.observe(cell), dt_s=1.0)
        cell = result.fixation if result.fixation is not None else cell
        belief = session.belief
        assert np.all(np.isfinite(belief)) and belief.sum() == pytest.approx(1.0)
        assert np.all(belief > 0)                       # the walk reaches every cell of 3x4
        assert np.isfinite(session.entropy_nats)


@pytest.mark.parametrize('weight', [0.0, 0.25])
@pytest.mark.parametrize('absent_prior', [0.0, 0.2])
def test_repeat_weight_counts_a_cells_repeated_views_at_that_weight(weight, absent_prior):
    model = count_model(2)
    settings = SearchSettings(confidence=1 - 1e-12, absent_prior=absent_prior,
                              repeat_weight=weight, inhibit_return=True)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    sensor = ModelSensor(GRID, model, np.random.default_rng(8))
    sensor.start(None)                                  # an empty scene
    session.reset()
    scan = sensor.scan()
    session.scan(scan)
    cell, frames = session.start(), []
    for _ in range(2 * GRID.n_cells):                   # every cell, then every cell again
        frame = sensor.observe(cell)
        frames.append((cell, frame.values))
        cell = session.update(frame).fixation
    np.testing.assert_allclose(
        session.log_belief,
        weighted_log_posterior(model, scan.values, frames, absent_prior, weight), atol=1e-10)


def test_calls_out_of_order_fail_loudly():
    model = count_model(3)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), SearchSettings())
    frame = Frame(np.zeros(GRID.n_cells))
    with pytest.raises(OrderError, match='reset'):
        session.update(frame)
    session.reset()
    with pytest.raises(OrderError, match='start the search'):
        session.update(frame)
    session.start()
    with pytest.raises(OrderError, match='before the first fixation'):
        session.scan(Frame(np.zeros(GRID.n_cells), kind='scan'))
    with pytest.raises(OrderError, match='has started'):
        session.start()


def test_stop_rules_found_absent_budget_and_repeat():
    model = count_model(4, scan=False)
    elm = build_policy('elm', GRID, model)
    strong = np.zeros(GRID.n_cells)
    # found: a frame only the target explains (count 3 at the fixation, impossible without it)
    p_null, p_target = model.p_null.copy(), model.p_target.copy()
    p_null[0, 0], p_target[0, 0] = [0.7, 0.2, 0.1, 0.0], [0.1, 0.1, 0.1, 0.7]
    sure = CountObservation(GRID, p_target, p_null)
    session = SearchSession(GRID, sure, elm, SearchSettings(confidence=0.6))
    session.reset()
    k = session.start()
    strong[k] = 3
    result = session.update(Frame(strong))
    assert (result.decision, result.map_cell, result.fixations) == ('found', k, 1)
    assert result.terminated and not result.truncated and result.fixation is None
    # absent: zero counts everywhere with an absent prior decide absent sooner or later
    session = SearchSession(GRID, model, elm, SearchSettings(confidence=0.9, absent_prior=0.5,
                                                             inhibit_return=True))
    session.reset()
    session.start()
    for _ in range(50):
        result = session.update(Frame(np.zeros(GRID.n_cells)))
        if result.ended:
            break
    assert result.decision == 'absent' and result.terminated
    assert result.absent_probability >= 0.9
    with pytest.raises(OrderError, match='ended'):
        session.update(Frame(np.zeros(GRID.n_cells)))
    # gave_up (budget) and gave_up (repeat: every cell fixated once), with a weak detector
    weak = CountObservation(GRID, 0.9 * model.p_null + 0.1 / K, model.p_null)
    elm = build_policy('elm', GRID, weak)
    for settings, fixations, reason in (
            (SearchSettings(confidence=1 - 1e-12, max_fixations=3), 3, 'budget'),
            (SearchSettings(confidence=1 - 1e-12, inhibit_return=True, stop_on_repeat=True),
             GRID.n_cells, 'repeat')):
        session = SearchSession(GRID, weak, elm, settings)
        outcome = run_search(session, ModelSensor(GRID, weak, np.random.default_rng(0)), 2)
        assert (outcome.decision, outcome.reason, outcome.fixations) == \
            ('gave_up', reason, fixations)
        if reason == 'repeat':
            assert sorted(outcome.path) == list(range(GRID.n_cells))


def test_start_rules_centre_policy_and_cell():
    model = count_model(5)
    elm = build_policy('elm', GRID, model)
    for start, expected in ((None, GRID.center_index), ((2, 3), GRID.index(2, 3))):
        session = SearchSession(GRID, model, elm, SearchSettings(start_cell=start))
        session.reset()
        assert session.start() == expected
    # 'policy': the policy's choice on the prior; after a scan the default is the same rule.
    session = SearchSession(GRID, model, elm, SearchSettings(start_cell='policy'))
    session.reset()
    prior = np.full((1, GRID.n_cells), 1 / GRID.n_cells)
    assert session.start() == int(elm.select(prior, 0, None)[0])
    session = SearchSession(GRID, model, elm, SearchSettings())
    session.reset()
    scan = np.zeros(GRID.n_cells)
    scan[7] = 3
    session.scan(Frame(scan, kind='scan'))
    assert session.start() == int(elm.select(session.belief[None, :], 0, None)[0])
    assert start_index(GRID, SearchSettings(start_cell=(1, 1))) == 5
    with pytest.raises(ValueError, match='outside a 3x4 grid'):
        SearchSession(GRID, model, elm, SearchSettings(start_cell=(3, 0)))


@pytest.mark.parametrize('changes, message', [
    ({'confidence': 1.0}, r'^confidence must be between 0 and 1 \(exclusive\), got 1.0$'),
    ({'confidence': 0}, r'^confidence must be between 0 and 1 \(exclusive\), got 0$'),
    ({'confidence': 'high'}, r"^confidence must be a number, got 'high'$"),   # as in YAML
    ({'max_fixations': -1}, r'^search.max_fixations must be an integer >= 0 \(0: no budget\)'),
    ({'max_fixations': 2.5}, r'^search.max_fixations must be an integer >= 0'),
    ({'inhibit_return': 'yes'}, r'^search.inhibit_return must be true or false'),
    ({'repeat_weight': 1.5}, r'^search.repeat_weight must be in \[0, 1\]'),
    ({'absent_prior': 1.0}, r'^absent.prior must be a probability in \[0, 1\)'),
    ({'motion_sigma_cells': -1.0}, r'^motion.sigma_cells must be finite and >= 0'),
    ({'motion_jump_prob': 2.0}, r'^motion.jump_prob must be a probability in \[0, 1\)'),
    ({'start_cell': (1,)}, r'^start_cell must be \(row, col\) integers'),
    ({'start_cell': (-1, 0)}, r'^start_cell must be \(row, col\) with row, col >= 0'),
    ({'scan': 1}, r'^search.scan must be true or false'),
])
def test_every_bad_setting_is_refused_with_one_message(changes, message):
    with pytest.raises(ValueError, match=message):
        SearchSettings(**changes)
    with pytest.raises(ValueError, match=message):
        replace(SearchSettings(), **changes)


def test_settings_from_parameters_as_the_node_and_yaml_name_them():
    values = {'confidence': 0.99, 'search.max_fixations': 0, 'search.inhibit_return': True,
              'search.repeat_weight': 0.1, 'absent.prior': 0.2, 'start_row': 0,
              'start_col': -1, 'fpoc.dprime': 4.0}
    settings = SearchSettings.from_parameters(values, grid=GRID)
    assert settings == SearchSettings(confidence=0.99, inhibit_return=True, repeat_weight=0.1,
                                      absent_prior=0.2, start_cell=(0, 1))
    assert SearchSettings.from_parameters(settings.to_parameters()) == settings
    assert SearchSettings.from_parameters({'start_row': -1, 'start_col': -1}).start_cell is None
    with pytest.raises(ValueError, match='outside a 3x4 grid'):
        SearchSettings.from_parameters({'start_row': 3, 'start_col': 0}, grid=GRID)


def test_a_session_without_a_policy_takes_the_drivers_fixations():
    model = count_model(6)
    session = SearchSession(GRID, model, None, SearchSettings(confidence=1 - 1e-9))
    session.reset()
    session.start()
    for cell in (0, 11, 4):
        session.fixate(cell)
        assert session.update(Frame(np.zeros(GRID.n_cells))).fixation == cell
    assert session.path == (0, 11, 4)
    with pytest.raises(ValueError):
        session.fixate(GRID.n_cells)


def test_a_rejected_frame_changes_nothing_and_says_why():
    model = count_model(7)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), SearchSettings())
    session.reset()
    session.start()
    before = session.log_belief
    for values, reason in ((np.full(GRID.n_cells, 0.5), 'integers'),
                           (np.zeros(GRID.n_cells + 1), 'expected 12'),
                           (np.full(GRID.n_cells, np.inf), 'inf')):
        result = session.update(Frame(values))
        assert result.status == 'rejected' and reason in result.reason
        np.testing.assert_array_equal(session.log_belief, before)
        assert session.fixations == 0


@pytest.mark.parametrize('scene, message', [
    (2.7, 'a cell index must be a whole number, got 2.7'),
    ('3', "a cell index must be a whole number, got '3'"),
    ([1, 2], r'a cell index must be one whole number, got \[1, 2\]'),
    (12, 'cell index 12 is outside a 3x4 grid'),
])
def test_a_model_sensors_target_is_one_cell_of_the_grid(scene, message):
    """QA: start(2.7) hid the target in cell 2 and start('3') in cell 3, without a word."""
    sensor = ModelSensor(GRID, count_model(1), np.random.default_rng(0))
    with pytest.raises(ValueError, match=message):
        sensor.start(scene)
    sensor.start(np.int64(7))
    assert sensor.target == 7 and type(sensor.target) is int


@pytest.mark.parametrize('cell', [True, False, np.True_, np.bool_(False)])
def test_a_bool_is_no_cell(cell):
    """QA: fixate(True) fixated cell 1: Python counts a bool as an integer, a cell it is not."""
    from ipomdp_gaze.search.many import OccupancySession
    message = f'a cell index must be a whole number, got {cell!r}'
    model = count_model(1)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), SearchSettings())
    session.reset()
    session.start()
    many = OccupancySession(GRID, model, SearchSettings(targets='many'))
    many.reset()
    many.start()
    sensor = ModelSensor(GRID, model, np.random.default_rng(0))
    for call in (session.fixate, many.fixate, sensor.start, sensor.observe, GRID.cell):
        with pytest.raises(ValueError, match=f'^{message}$'):
            call(cell)
    with pytest.raises(ValueError, match=f'^a row must be a whole number, got {cell!r}$'):
        GRID.index(cell, 0)
    with pytest.raises(ValueError, match='^fixation must be an integer cell index'):
        model.offsets(cell)
    with pytest.raises(ValueError, match=r'^start_cell must be \(row, col\) integers'):
        SearchSettings(start_cell=(cell, 0))
    with pytest.raises(ValueError, match='must be a whole number'):
        sensor.observe(2.7)                     # was int(): cell 2
    session.fixate(np.int64(1))
    assert session.fixation == 1 and type(session.fixation) is int
    assert SearchSettings(start_cell=(np.int64(1), 0)).start_cell == (1, 0)


def test_the_event_log_records_each_step():
    model = count_model(8)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model),
                            SearchSettings(max_fixations=2, confidence=1 - 1e-12))
    outcome = run_search(session, ModelSensor(GRID, model, np.random.default_rng(1)), 3)
    kinds = [event['event'] for event in outcome.log]
    assert kinds == ['reset', 'scan', 'start', 'frame', 'frame']
    last = outcome.log[-1]
    assert last['decision'] == 'gave_up' and last['reason'] == 'budget'
    assert last['fixation'] == list(GRID.cell(outcome.path[-1]))
    assert last['belief']['map_cell'] == list(GRID.cell(outcome.cell))
    assert outcome.log[0]['settings']['search.max_fixations'] == 2


def test_sample_scan_draws_from_the_scan_tables():
    model = count_model(9)
    rng = np.random.default_rng(3)
    targets = np.full(40_000, 5)
    frames = model.sample_scan(targets, rng)
    for column, table in ((frames[:, 5], model.scan_target), (frames[:, 0], model.scan_null)):
        observed = np.bincount(column.astype(int), minlength=K)
        expected = table * column.size
        chi2 = float(((observed - expected) ** 2 / expected).sum())
        assert chi2 < 16.3                          # chi-square, 3 dof, p = 0.001
    empty = model.sample_scan(targets[:10], np.random.default_rng(3), present=False)
    nulls = model.sample_scan(np.zeros(10, dtype=int), np.random.default_rng(3),
                              present=np.zeros(10, dtype=bool))
    np.testing.assert_array_equal(empty, nulls)
    assert model.sample_scan(5, np.random.default_rng(3)).shape == (GRID.n_cells,)


def test_the_controller_and_finds_driver_agree_on_the_same_frames():
    """Frames recorded from find's driver, replayed into the controller: same fixations."""
    model = count_model(10, scan=False)
    settings = SearchSettings(confidence=0.99, inhibit_return=True, repeat_weight=0.3,
                              absent_prior=0.1, max_fixations=9)
    policy = build_policy('elm', GRID, model)

    class Recording(ModelSensor):

        def observe(self, cell):
            frame = super().observe(cell)
            self.recorded.append((cell, frame.values))
            return frame

    for target in itertools.islice(range(GRID.n_cells), 0, None, 3):
        sensor = Recording(GRID, model, np.random.default_rng(target))
        sensor.recorded = []
        outcome = run_search(SearchSession(GRID, model, policy, settings), sensor, target)
        controller = GazeController(GRID, model, policy, settings)
        for t, (cell, values) in enumerate(sensor.recorded):
            assert controller.fixation == cell
            controller.offer(values, float(t + 1))
        assert controller.stopped and controller.decision == outcome.decision
        assert controller.map_cell == outcome.cell
        np.testing.assert_array_equal(controller.belief, outcome.belief)


@pytest.mark.parametrize('absent_prior', [0.0, 0.4])
def test_excluded_cells_get_the_brute_force_posterior_of_a_prior_without_them(absent_prior):
    model = count_model(2)
    settings = SearchSettings(confidence=1 - 1e-12, absent_prior=absent_prior, max_fixations=6)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    sensor = ModelSensor(GRID, model, np.random.default_rng(7))
    sensor.start(3)
    session.reset(seed=0)
    frame = sensor.scan()
    session.scan(frame)
    excluded = [0, 1, 3, 3]
    session.exclude(excluded)
    cell, frames = session.start(), []
    for _ in range(6):
        obs = sensor.observe(cell)
        frames.append((cell, obs.values))
        result = session.update(obs)
        # the Bayes posterior under the prior restricted to the other hypotheses
        expected = brute_force_log_posterior(model, frame.values, frames, absent_prior)
        expected[[0, 1, 3]] = -np.inf
        expected -= np.logaddexp.reduce(expected)
        np.testing.assert_allclose(session.log_belief, expected, atol=1e-10)
        assert session.map_cell not in (0, 1, 3)
        if result.ended:
            break
        cell = result.fixation
    with pytest.raises(ValueError, match='outside|in 0'):
        session.exclude([GRID.n_cells])
    with pytest.raises(ValueError, match='no cell to search'):
        session.exclude(np.arange(GRID.n_cells))


def test_a_drivers_limit_ends_the_search_as_the_budget_does():
    model = count_model(11)
    weak = CountObservation(GRID, 0.9 * model.p_null + 0.1 / K, model.p_null)
    elm = build_policy('elm', GRID, weak)
    for decide, expected in ((False, 'gave_up'), (True, None)):
        session = SearchSession(GRID, weak, elm, SearchSettings(absent_prior=0.5,
                                                                decide_at_budget=decide))
        session.reset()
        with pytest.raises(OrderError, match='started'):
            session.stop('pixels')
        session.start()
        session.update(Frame(np.zeros(GRID.n_cells)))
        absent, peak = session.absent_probability, session.map_probability
        result = session.stop('pixels')
        want = expected or ('absent' if absent >= peak else 'found')
        assert (result.decision, result.reason, result.ended) == (want, 'pixels', True)
        assert session.log[-1]['event'] == 'stop'
        with pytest.raises(OrderError):
            session.stop('pixels')


def test_with_the_stop_rule_off_decisions_are_reported_and_every_fixation_is_taken():
    model = count_model(scan=False)
    policy = build_policy('elm', GRID, model)
    on = SearchSettings(confidence=0.9, absent_prior=0.3, max_fixations=40)
    off = replace(on, stop_on_decision=False)
    stopped = SearchSession(GRID, model, policy, on)
    first = run_search(stopped, ModelSensor(GRID, model, np.random.default_rng(5)), 7, seed=1,
                       fixations=range(GRID.n_cells))
    assert first.decision in ('found', 'absent') and first.fixations < GRID.n_cells
    session = SearchSession(GRID, model, policy, off)
    fired, beliefs = [], []

    def record(frame, result):
        fired.append(result.fired)
        beliefs.append(session.log_belief.copy())
        assert not result.ended

    outcome = run_search(session, ModelSensor(GRID, model, np.random.default_rng(5)), 7, seed=1,
                         fixations=range(GRID.n_cells), on_frame=record)
    assert outcome.fixations == GRID.n_cells and outcome.path == tuple(range(GRID.n_cells))
    # The same frames: the belief when the stopped search ended is the one at that frame here,
    # and the decision it ended with is the one reported (fired) then.
    np.testing.assert_allclose(beliefs[first.fixations - 1], stopped.log_belief)
    assert fired[first.fixations - 1] == first.decision
    assert sum(bool(f) for f in fired[:first.fixations - 1]) == 0


def test_with_the_stop_rule_off_the_budget_still_ends_the_search():
    model = count_model(scan=False)
    settings = SearchSettings(confidence=0.6, max_fixations=5, stop_on_decision=False)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    outcome = run_search(session, ModelSensor(GRID, model, np.random.default_rng(2)), 3, seed=0)
    assert outcome.fixations == 5 and outcome.decision == 'gave_up' and outcome.reason == 'budget'


def test_run_search_calls_the_frame_hook_once_per_applied_frame_with_the_frame():
    model = count_model()
    session = SearchSession(GRID, model, build_policy('elm', GRID, model),
                            SearchSettings(confidence=0.99, max_fixations=6))
    seen = []
    sensor = ModelSensor(GRID, model, np.random.default_rng(3))
    outcome = run_search(session, sensor, 2, seed=0,
                         on_frame=lambda frame, step: seen.append((frame.kind, step.fixations)))
    assert seen == [('fixation', k) for k in range(1, outcome.fixations + 1)]


@pytest.mark.parametrize('cell, truth, decision, right', [
    ((3, 4), (3, 4), 'found', True), ((2, 5), (3, 4), 'found', True),
    ((1, 4), (3, 4), 'found', False), ((3, 4), (3, 4), 'absent', False),
    ((3, 4), None, 'absent', True), ((3, 4), None, 'found', False),
    ((2, 3), (3, 4), 'gave_up', True), (None, (3, 4), 'gave_up', False)])
def test_the_one_right_answer_rule(cell, truth, decision, right):
    from ipomdp_gaze.simulation.evaluation import answer_is_right
    assert answer_is_right(cell, truth, decision) is right


def _views_from_scratch(session, radius):
    """Return the read-only views recomputed from the log belief alone, as first written."""
    log_b = session.log_belief
    cells = np.exp(log_b[:GRID.n_cells])
    if radius:
        padded = np.pad(cells.reshape(GRID.shape), radius)
        square = np.lib.stride_tricks.sliding_window_view(padded, (2 * radius + 1,) * 2)
        pooled = square.sum(axis=(2, 3)).reshape(-1)
    else:
        pooled = cells
    peak = pooled.max()
    answer = int(np.argmax(pooled >= peak - 1e-9 * abs(peak)))
    full = np.exp(log_b)
    entropy = float(-np.sum(np.where(full > 0, full * np.log(np.where(full > 0, full, 1.0)),
                                     0.0)))
    return cells, answer, float(pooled[answer]), entropy


def _assert_views_follow(session, radius):
    cells, answer, probability, entropy = _views_from_scratch(session, radius)
    assert session.belief.tobytes() == cells.tobytes()
    assert (session.map_cell, session.map_probability) == (answer, probability)
    assert session.entropy_nats == pytest.approx(entropy, rel=1e-12)   # from the logs


def test_the_views_follow_every_change_of_the_belief_and_of_the_settings():
    """Views computed once per belief: reset, scan, exclude, update, predict, configure."""
    model = count_model(12)
    settings = SearchSettings(confidence=1 - 1e-12, absent_prior=0.3, found_radius=1)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    sensor = ModelSensor(GRID, model, np.random.default_rng(4))
    sensor.start(5)
    session.reset(seed=0)
    _assert_views_follow(session, 1)
    session.scan(sensor.scan())
    _assert_views_follow(session, 1)
    session.exclude([5, 6])
    _assert_views_follow(session, 1)
    cell = session.start()
    for _ in range(3):
        before = session.belief
        result = session.update(sensor.observe(cell))
        assert not np.array_equal(session.belief, before)
        _assert_views_follow(session, 1)
        cell = result.fixation
    session.configure(replace(settings, found_radius=0))
    _assert_views_follow(session, 0)
    session.configure(replace(settings, found_radius=2))
    _assert_views_follow(session, 2)
    session.configure(replace(settings, motion_sigma_cells=0.8))  # moving: the square too
    _assert_views_follow(session, 1)
    before = session.belief
    session.predict(1.5)
    assert not np.array_equal(session.belief, before)
    _assert_views_follow(session, 1)
    session.reset()
    _assert_views_follow(session, 1)
    np.testing.assert_allclose(session.belief, 0.7 / GRID.n_cells)


def test_the_belief_a_caller_gets_is_its_own_copy():
    model = count_model(13)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), SearchSettings())
    session.reset()
    session.start()
    mine = session.belief
    mine[:] = 0.0
    assert session.belief.sum() == pytest.approx(1.0)
    assert session.map_probability == pytest.approx(1.0 / GRID.n_cells)


def test_a_frame_checked_by_the_session_is_not_checked_again_by_it(monkeypatch):
    model = count_model(14)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), SearchSettings())
    session.reset()
    session.start()
    checks = []
    original = session.check_frame
    monkeypatch.setattr(session, 'check_frame', lambda v: checks.append(1) or original(v))
    frame = session.checked_frame(np.zeros(GRID.n_cells))
    assert session.update(frame).applied and len(checks) == 1
    assert session.update(Frame(np.zeros(GRID.n_cells))).applied and len(checks) == 2
    with pytest.raises(EvidenceError, match='integers'):
        session.checked_frame(np.full(GRID.n_cells, 0.5))


def test_a_checked_frame_is_checked_again_by_another_session_or_model():
    model = count_model(15)
    gaussian = SearchSession(GRID, make_fpoc('camera', half_width_deg=1.0,
                                             half_height_deg=1.0), None, SearchSettings())
    fractional = gaussian.checked_frame(np.full(GRID.n_cells, 0.5))   # fine for a Gaussian
    counts = SearchSession(GRID, model, None, SearchSettings())
    counts.reset()
    counts.start()
    result = counts.update(fractional)
    assert result.status == 'rejected' and 'integers' in result.reason
    gaussian.reset()
    gaussian.start()
    frame = gaussian.checked_frame(np.full(GRID.n_cells, 0.5))
    gaussian.set_observation(model)                 # the model changed since the check
    result = gaussian.update(frame)
    assert result.status == 'rejected' and 'integers' in result.reason
    assert gaussian.fixations == 0
    fresh = SearchSession(GRID, model, None, SearchSettings())
    fresh.reset()
    scan = fresh.checked_frame(np.zeros(GRID.n_cells), kind='scan')
    assert scan.kind == 'scan' and fresh.scan(scan).applied


def test_the_fixation_as_row_and_col():
    """Issue 35: start() stays a row-major index; fixation_cell is the same cell as (row, col)."""
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.policies.registry import build_policy
    from ipomdp_gaze.search.session import SearchSession
    grid = Grid(5, 7)
    fpoc = make_fpoc('human')
    session = SearchSession(grid, fpoc, build_policy('elm', grid, fpoc))
    session.reset(seed=0)
    assert session.fixation_cell is None
    cell = session.start()
    assert isinstance(cell, int) and cell == grid.center_index
    assert session.fixation_cell == (2, 3) == tuple(int(v) for v in grid.cell(cell))


def _tracking_session(**changes):
    """Return a count session on GRID with a walking target and the tracking settings."""
    model = count_model(3)
    settings = SearchSettings(confidence=0.95, absent_prior=0.2, motion_sigma_cells=0.2,
                              motion_max_speed_cells=1.0, motion_speed_cells=0.5,
                              motion_turn_prob=0.1, motion_leave_prob=0.05, **changes)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    session.reset(seed=0)
    return session, model


def _strong_frame(model, fixation, target):
    """Return counts that put the target at ``target``: each cell's most telling count."""
    values = np.empty(GRID.n_cells)
    fr, fc = GRID.cell(fixation)
    for i in range(GRID.n_cells):
        r, c = GRID.cell(i)
        ratio = np.log(model.p_target[abs(r - fr), abs(c - fc)]) \
            - np.log(model.p_null[abs(r - fr), abs(c - fc)])
        values[i] = np.argmax(ratio) if i == target else np.argmin(ratio)
    return Frame(values)


def test_a_found_walking_target_is_looked_at_where_the_belief_predicts_it():
    """motion.track_view peak: the next fixation is the peak of the belief lead_s ahead."""
    session, model = _tracking_session(motion_track_view='peak', motion_lead_s=0.3)
    cell = session.start()
    target = GRID.index(1, 1)
    for t in range(6):
        result = session.update(_strong_frame(model, cell, target), dt_s=0.1 if t else 0.0)
        cell = result.fixation
    assert session.decision == 'found'
    ahead = session.log_belief
    session.motion.predict_over(ahead, 0.3, update=False)
    assert cell == int(np.argmax(ahead[:GRID.n_cells]))


def test_found_holds_down_to_keep_probability_and_is_lost_below_it():
    session, model = _tracking_session(motion_keep_probability=0.6)
    cell = session.start()
    target = GRID.index(1, 2)
    for t in range(5):
        cell = session.update(_strong_frame(model, cell, target), dt_s=0.1).fixation
    assert session.decision == 'found'
    empty = Frame(np.full(GRID.n_cells, np.nan))          # unobserved: the belief spreads
    decisions = []
    for _ in range(30):
        session.update(empty, dt_s=0.5)
        decisions.append((session.decision, session.map_probability))
    held = [p for d, p in decisions if d == 'found']
    assert held and min(held) >= 0.6 and any(p < 0.95 for p in held)    # held under c
    assert any(d != 'found' for d, _ in decisions)
    first_lost = next(i for i, (d, _) in enumerate(decisions) if d != 'found')
    assert decisions[first_lost][1] < 0.6 or decisions[first_lost][0] == 'absent'


def test_api_misuse_is_refused_with_the_reason_not_a_numpy_error():
    """QA of the Python API: grids, times, generators, cells and policy scores are checked."""
    from ipomdp_gaze.model.inhibition import unvisited_choice
    from ipomdp_gaze.search.many import OccupancySession
    fpoc = make_fpoc('human')
    other = Grid(3, 3, 1.0)
    with pytest.raises(ValueError, match='the observation model is for a 3x3 grid, the search '
                                         'is on a 3x4 grid'):
        SearchSession(GRID, _count_model_of(other), build_policy('elm', GRID, fpoc))
    with pytest.raises(ValueError, match='the policy is for a 3x3 grid, the search is on a 3x4'):
        SearchSession(GRID, fpoc, build_policy('elm', other, fpoc))
    session = SearchSession(GRID, fpoc, build_policy('elm', GRID, fpoc),
                            SearchSettings(max_fixations=5))
    session.reset(seed=0)
    session.start()
    for bad in (-1.0, math.nan, math.inf, 'soon'):
        with pytest.raises(ValueError, match='dt_s must be a finite number of seconds >= 0'):
            session.update(Frame(np.zeros(GRID.n_cells)), dt_s=bad)
        with pytest.raises(ValueError, match='dt_s must be'):
            session.predict(bad)
    assert session.fixations == 0                           # nothing was applied
    many = OccupancySession(GRID, fpoc, SearchSettings(targets='many', max_fixations=5))
    many.reset(seed=0)
    many.start()
    with pytest.raises(ValueError, match='dt_s must be'):
        many.update(Frame(np.zeros(GRID.n_cells)), dt_s=-0.5)
    with pytest.raises(TypeError, match='rng must be a numpy.random.Generator'):
        ModelSensor(GRID, fpoc, np.random)
    with pytest.raises(ValueError, match=r'cell \(3, 0\) is outside a 3x4 grid'):
        GRID.index(3, 0)
    with pytest.raises(ValueError, match=r'cell \(-1, 2\) is outside'):
        GRID.index(-1, 2)

    class NaNPolicy:
        name = 'nan'

        def scores(self, belief):
            return np.full(belief.shape, np.nan)

    belief = np.full((1, GRID.n_cells), 1 / GRID.n_cells)
    visited = np.zeros(GRID.n_cells, bool)
    visited[0] = True
    with pytest.raises(ValueError, match='the policy scored a cell NaN'):
        unvisited_choice(NaNPolicy(), belief, visited, 0, None, GRID)
    NaNPolicy.scores = lambda self, belief: np.full(belief.shape, -np.inf)
    assert unvisited_choice(NaNPolicy(), belief, visited, 0, None, GRID) == 1   # not cell 0
    mixed = np.zeros(GRID.n_cells)
    mixed[[1, 2]] = -np.inf, np.inf
    NaNPolicy.scores = lambda self, belief: mixed.copy()
    assert unvisited_choice(NaNPolicy(), belief, visited, 0, None, GRID) == 2   # the +inf one
    core = GazeController(GRID, fpoc, build_policy('elm', GRID, fpoc), SearchSettings())
    core.reset(0.0)
    result = core.offer(np.zeros(GRID.n_cells), math.nan)
    assert result.status == 'rejected' and 'stamped nan, not a time' in result.reason


def _count_model_of(grid):
    """Return a count model of ``grid`` (flat tables: the grid is all that matters here)."""
    table = np.full((grid.rows, grid.cols, 3), 1 / 3)
    return CountObservation(grid, table, table.copy())


def test_the_one_time_scan_is_refused_a_second_time_and_the_belief_kept():
    model = count_model(3)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), SearchSettings())
    session.reset()
    scan = Frame(np.array([3.0] + [0.0] * (GRID.n_cells - 1)), kind='scan')
    assert session.scan(scan).applied
    before = session.log_belief
    with pytest.raises(OrderError, match='once'):
        session.scan(scan)
    np.testing.assert_array_equal(session.log_belief, before)


@pytest.mark.parametrize('how', ['budget', 'stop'])
def test_at_a_limit_a_tie_between_absent_and_the_answer_decides_absent(how):
    """decide_at_budget: absent when P(absent) is at least the answer's probability."""
    grid = Grid(1, 1)
    settings = SearchSettings(absent_prior=0.5, decide_at_budget=True,
                              max_fixations=1 if how == 'budget' else 0)
    session = SearchSession(grid, make_fpoc('human'), None, settings)
    session.reset()
    session.start()
    result = session.update(Frame(np.array([np.nan])))     # unobserved: the prior stays
    if how == 'stop':
        assert not result.ended
        result = session.stop('pixels')
    assert session.absent_probability == session.map_probability == 0.5
    reason = 'budget' if how == 'budget' else 'pixels'
    assert (result.decision, result.reason, result.ended) == ('absent', reason, True)


def test_with_motion_the_budget_ends_only_a_search_that_has_not_decided_yet():
    session, model = _tracking_session(max_fixations=6)
    cell = session.start()
    target = GRID.index(1, 2)
    fired = []
    for t in range(12):
        result = session.update(_strong_frame(model, cell, target), dt_s=0.1)
        fired.append(result.fired)
        assert not result.ended, (t, result)
        cell = result.fixation
    assert 'found' in fired[:5] and session.fixations == 12


def test_an_excluded_cell_stays_ruled_out_when_repeated_views_are_weighted():
    model = count_model(2)
    settings = SearchSettings(confidence=1 - 1e-12, repeat_weight=0.5, max_fixations=8)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    sensor = ModelSensor(GRID, model, np.random.default_rng(3))
    sensor.start(5)                                      # the target sits in the excluded cell
    session.reset(seed=0)
    session.exclude([5])
    cell = session.start()
    for _ in range(8):
        result = session.update(sensor.observe(cell))
        assert session.belief[5] == 0.0
        assert session.belief.sum() == pytest.approx(1.0)
        if result.ended:
            break
        cell = result.fixation


@pytest.mark.parametrize('radius', [0, 1])
def test_the_answer_after_a_frame_is_the_tie_rules_cell_of_the_pooled_belief(radius):
    """The stop rule's peak gives the answer (no second max): ties within 1e-9 to the lowest."""
    from ipomdp_gaze.model.belief import argmax_ties_low
    from ipomdp_gaze.search.session import pooled_belief
    model = count_model(4, scan=False)
    settings = SearchSettings(confidence=1 - 1e-12, found_radius=radius, max_fixations=0)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    session.reset(seed=0)
    cell = session.start()
    zeros = np.zeros(GRID.n_cells)                   # a frame of 0 counts: cells stay tied
    for frame in [zeros] + [np.random.default_rng(i).integers(0, K, GRID.n_cells)
                            for i in range(6)]:
        result = session.update(Frame(frame.astype(float)))
        pooled = pooled_belief(session.belief, GRID, radius)
        assert result.map_cell == session.map_cell == int(argmax_ties_low(pooled))
        assert result.map_probability == pytest.approx(pooled[result.map_cell], abs=1e-15)
        cell = result.fixation
    assert cell is not None


def test_a_search_that_never_ends_keeps_only_the_newest_fixations_in_its_path(monkeypatch):
    # A tracking search (motion on) never ends: its path grew by one entry per frame for as
    # long as the controller ran (about 12 bytes a frame, 30 MB a day at 30 Hz on 11x11).
    import ipomdp_gaze.search.many as many
    import ipomdp_gaze.search.session as session_module
    monkeypatch.setattr(session_module, 'PATH_SIZE', 20, raising=False)
    monkeypatch.setattr(many, 'PATH_SIZE', 20, raising=False)
    model = count_model(3)
    settings = SearchSettings(confidence=1 - 1e-9, motion_sigma_cells=0.5)
    sessions = [SearchSession(GRID, model, build_policy('elm', GRID, model), settings,
                              log_size=0),
                many.OccupancySession(GRID, model, replace(settings, targets='many'),
                                      log_size=0)]
    for session in sessions:
        session.reset(seed=0)
        cell, looked = session.start(), []
        for _ in range(200):
            looked.append(cell)
            result = session.update(Frame(np.zeros(GRID.n_cells)), dt_s=0.1)
            assert result.applied and not result.ended
            cell = result.fixation
        assert session.fixations == 200
        assert session.path == tuple(looked[-20:])
