# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Property tests of the model core under any input (hypothesis; derandomized under ``CI``).

For any frame (finite, NaN, +/-inf, 1e300, the largest doubles), any d' >= 0 (up to 1e300) and
any sequence of fixations, the Bayes update either refuses the frame with an
:class:`~ipomdp_gaze.model.belief.EvidenceError` naming the reason, leaving the belief as it was,
or
returns a finite, non-negative belief that sums to 1. NaN entries are unobserved cells: they
change nothing. Every policy's choice is a valid cell for any belief, including one-hot beliefs,
beliefs with zeros and denormal probabilities.
"""
from __future__ import annotations

import os

from hypothesis import assume, given, HealthCheck, settings
from hypothesis import strategies as st
from ipomdp_gaze.model.belief import bayes_update, EvidenceError, uniform_log_belief
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.inhibition import unvisited_choice
from ipomdp_gaze.model.observation import check_evidence
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
from ipomdp_gaze.policies.baselines import make_baseline, STRATEGIES
from ipomdp_gaze.policies.conv import ConvPolicy, MAX_KERNEL_ABS_SUM
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.gaze import GazeController
import numpy as np
import pytest

# More examples with PROPERTY_EXAMPLES (make soak uses 1000); CI derandomizes (conftest.py).
PROPERTY = settings(deadline=None, max_examples=int(os.environ.get('PROPERTY_EXAMPLES', '40')),
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
BIG = 1.7976931348623157e308
SPECIAL = [0.0, -0.0, 1.0, -1.0, 1e300, -1e300, BIG, -BIG, 5e-324, 1e-300, 3.4e38, -3.4e38,
           np.nan, np.inf, -np.inf]
observation_value = st.one_of(st.sampled_from(SPECIAL), st.floats(allow_nan=True,
                                                                  allow_infinity=True))
finite_observation = st.one_of(st.sampled_from([v for v in SPECIAL if not np.isinf(v)]),
                               st.floats(allow_nan=True, allow_infinity=False))
dprime_value = st.one_of(st.sampled_from([0.0, 5e-324, 1e-12, 1.0, 4.0, 1e10, 1e154, 1e155,
                                          1e300]),
                         st.floats(0.0, 1e300, allow_nan=False, allow_infinity=False))


def assert_belief(log_belief) -> None:
    """Check a log belief describes a finite, non-negative belief that sums to 1."""
    log_belief = np.asarray(log_belief)
    assert not np.any(np.isnan(log_belief)) and not np.any(log_belief == np.inf)
    belief = np.exp(log_belief)
    assert np.all(np.isfinite(belief)) and np.all(belief >= 0)
    np.testing.assert_allclose(belief.sum(axis=-1), 1.0, rtol=0, atol=1e-12)


@st.composite
def log_beliefs(draw, n):
    """Return a normalised log belief over n cells: any finite logits, some cells at 0."""
    logits = np.array(draw(st.lists(st.floats(-1e300, 0.0), min_size=n, max_size=n)))
    zeros = np.array(draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    zeros[draw(st.integers(0, n - 1))] = False                 # at least one possible cell
    logits[zeros] = -np.inf
    log_b = bayes_update(logits, llr(np.full(n, np.nan), np.zeros(n)))
    assert_belief(log_b)
    return log_b


@st.composite
def frames(draw, values=observation_value):
    """Return a log belief, an observation and d' (all for the same n cells)."""
    n = draw(st.integers(1, 40))
    log_b = draw(log_beliefs(n))
    obs = np.array(draw(st.lists(values, min_size=n, max_size=n)), dtype=float)
    d = np.array(draw(st.lists(dprime_value, min_size=n, max_size=n)), dtype=float)
    return log_b, obs, d


@PROPERTY
@given(frames())
def test_update_refuses_with_a_reason_or_gives_a_normalised_belief(case):
    log_b, obs, d = case
    before = log_b.copy()
    try:
        after = bayes_update(log_b, llr(check_evidence(obs, obs.size), d))
    except EvidenceError as exc:
        reason = str(exc)
        assert 'inf' in reason or 'overflows' in reason, reason
        np.testing.assert_array_equal(log_b, before)
        # Only a frame that would poison the belief is refused.
        with np.errstate(over='ignore', invalid='ignore'):
            term = d * (obs - d / 2)
        assert np.any(np.isinf(obs)) or not np.all(np.isfinite(term[~np.isnan(obs)]))
        return
    assert_belief(after)
    np.testing.assert_array_equal(log_b, before)                 # not updated in place
    assert np.all(after[np.isneginf(before)] == -np.inf)         # impossible stays impossible


@PROPERTY
@given(frames(finite_observation))
def test_in_place_update_is_all_or_nothing(case):
    log_b, obs, d = case
    before = log_b.copy()
    try:
        bayes_update(log_b, llr(obs, d), out=log_b)
    except EvidenceError:
        np.testing.assert_array_equal(log_b, before)
    else:
        assert_belief(log_b)


@PROPERTY
@given(frames(finite_observation), st.data())
def test_nan_cells_are_unobserved(case, data):
    log_b, obs, d = case
    hidden = np.array(data.draw(st.lists(st.booleans(), min_size=obs.size, max_size=obs.size)))
    masked = np.where(hidden, np.nan, obs)
    other_d = np.where(hidden, data.draw(dprime_value), d)      # d' of unobserved cells is moot
    try:
        want = bayes_update(log_b, llr(masked, d))
    except EvidenceError:
        with pytest.raises(EvidenceError):
            bayes_update(log_b, llr(masked, other_d))
        return
    np.testing.assert_array_equal(bayes_update(log_b, llr(masked, other_d)), want)
    np.testing.assert_allclose(llr(masked, d)[hidden], 0.0)
    np.testing.assert_allclose(bayes_update(log_b, llr(np.full(obs.size, np.nan), d)), log_b,
                               rtol=1e-12, atol=1e-12)


def test_overflowing_frames_are_refused_not_turned_into_nan():
    log_b = uniform_log_belief(3)
    for obs, d in (([1e308, 0.0, 0.0], [4.0, 4.0, 4.0]),            # 4e308 > max double
                   ([-1e308] * 3, [4.0] * 3),                      # every cell -inf
                   ([0.0, 0.0, 0.0], [1e200, 1e200, 1e200])):      # d'^2 / 2 overflows
        with pytest.raises(EvidenceError, match='overflows'):
            bayes_update(log_b, llr(np.array(obs), np.array(d)))
    # Just below overflow it is evidence like any other: all mass on the one cell.
    after = bayes_update(log_b, llr(np.array([4e307, 0.0, 0.0]), np.full(3, 4.0)))
    np.testing.assert_array_equal(np.exp(after), [1.0, 0.0, 0.0])


def grids():
    return st.tuples(st.integers(1, 4), st.integers(1, 4)).map(lambda rc: Grid(*rc, 5.0))


@pytest.mark.filterwarnings('ignore:overflow encountered in square:RuntimeWarning')
@PROPERTY
@given(grids(), st.floats(1e-6, 1e300), st.floats(0.0, 30.0), st.sampled_from(['map', 'elm']),
       st.lists(st.tuples(st.sampled_from(['frame', 'short', 'nan', 'off', 'on', 'reset']),
                          st.lists(observation_value, min_size=16, max_size=16)),
                max_size=25))
def test_controller_core_survives_any_sequence(grid, dprime, half_width_deg, policy, events):
    fpoc = make_fpoc('camera', dprime=dprime, half_width_deg=half_width_deg,
                     half_height_deg=half_width_deg)
    try:
        built = build_policy(policy, grid, fpoc)
    except ValueError as exc:                   # ELM of a d' whose square overflows
        assert 'kernel must be finite' in str(exc)
        return
    core = GazeController(grid, fpoc, built)
    core.reset(0.0)
    now = 0.0
    for kind, values in events:
        now += 1.0
        frame = np.array(values[:grid.n_cells], dtype=float)
        if kind == 'short':
            frame = frame[:-1]
        elif kind == 'nan':
            frame[::2] = np.nan
        if kind == 'off':
            core.set_enabled(False, now)
        elif kind == 'on':
            core.set_enabled(True, now)
        elif kind == 'reset':
            core.reset(now)
        else:
            before, fixation = core.belief, core.fixation
            result = core.offer(frame, now)
            assert result.status in ('applied', 'rejected', 'skipped')
            if result.status != 'applied':
                np.testing.assert_array_equal(core.belief, before)
                assert core.fixation == fixation and result.reason
            if result.status == 'rejected':
                assert core.last_rejection == result.reason
        assert 0 <= core.fixation < grid.n_cells
        b = core.belief
        assert np.all(np.isfinite(b)) and np.all(b >= 0)
        assert b.sum() == pytest.approx(1.0, abs=1e-12)
        assert np.isfinite(core.entropy_nats) and 0 <= core.map_cell < grid.n_cells
        c = core.counters()
        assert c['received'] == c['applied'] + c['rejected'] + c['skipped']


@st.composite
def beliefs(draw, n):
    """Return a batch of probability vectors: dirichlet-like, one-hot, with zeros or denormals."""
    episodes = draw(st.integers(1, 3))
    kind = draw(st.sampled_from(['any', 'one-hot', 'uniform', 'denormal']))
    if kind == 'one-hot':
        b = np.zeros((episodes, n))
        b[np.arange(episodes), draw(st.integers(0, n - 1))] = 1.0
        return b
    if kind == 'uniform':
        return np.full((episodes, n), 1.0 / n)
    raw = np.array(draw(st.lists(st.floats(0.0, 1.0), min_size=episodes * n,
                                 max_size=episodes * n))).reshape(episodes, n)
    raw[:, 0] += 1e-300                                     # never all zero
    if kind == 'denormal':
        raw *= 5e-324 / raw.max(axis=1, keepdims=True)
    return raw / raw.sum(axis=1, keepdims=True)


def assert_cells(choice, belief, grid) -> None:
    k = np.asarray(choice)
    assert k.shape == (belief.shape[0],), k.shape
    assert np.issubdtype(k.dtype, np.integer)
    assert np.all((0 <= k) & (k < grid.n_cells))


@pytest.mark.parametrize('name', STRATEGIES)
def test_every_baseline_chooses_a_valid_cell(name):
    make_baseline(name, Grid(1, 1), make_fpoc('human'))     # a broken import fails here
    check_baseline(name)


@PROPERTY
@given(grids(), st.sampled_from(['human', 'camera']), st.data())
def check_baseline(name, grid, model, data):
    policy = make_baseline(name, grid, make_fpoc(model))
    belief = data.draw(beliefs(grid.n_cells))
    for t in (0, 1, data.draw(st.integers(2, 10 ** 6))):
        assert_cells(policy.select(belief, t, np.random.default_rng(t)), belief, grid)


@PROPERTY
@given(grids(), st.sampled_from(['argmax', 'sample']), st.floats(-1e300, 1e300),
       st.data())
def test_conv_policy_with_any_finite_kernel_chooses_a_valid_cell(grid, action, scale, data):
    shape = grid.kernel_shape
    kernel = scale * np.array(data.draw(st.lists(
        st.floats(-1.0, 1.0), min_size=shape[0] * shape[1],
        max_size=shape[0] * shape[1]))).reshape(shape)
    assume(np.all(np.isfinite(kernel)))
    with np.errstate(over='ignore'):
        total = np.abs(kernel).sum()
    if not total <= MAX_KERNEL_ABS_SUM:                     # its scores could overflow: refused
        with pytest.raises(ValueError, match='the sum of its absolute values'):
            ConvPolicy(grid, kernel, action=action)
        return
    policy = ConvPolicy(grid, kernel, action=action)
    belief = data.draw(beliefs(grid.n_cells))
    rng = np.random.default_rng(data.draw(st.integers(0, 2 ** 32)))
    assert_cells(policy.select(belief, 0, rng), belief, grid)
    visited = np.zeros(grid.n_cells, dtype=bool)
    assert 0 <= unvisited_choice(policy, belief[:1], visited, 0, rng, grid) < grid.n_cells


@st.composite
def crowds(draw):
    """Draw occupied cells on a 4x6 grid of 20 px cells and raw boxes with scores."""
    log_odds = np.array(draw(st.lists(st.sampled_from([-5.0, 5.0]), min_size=24, max_size=24)))
    n = draw(st.integers(0, 12))
    boxes = np.array([[draw(st.integers(-5, 115)), draw(st.integers(-5, 75)),
                       draw(st.integers(4, 40)), draw(st.integers(4, 40))] for _ in range(n)],
                     dtype=float).reshape(-1, 4)
    scores = np.array([draw(st.floats(0.3, 1.0)) for _ in range(n)])
    return Grid(4, 6), log_odds, boxes, scores


@PROPERTY
@given(crowds(), st.floats(0.3, 1.0))
def test_a_strong_score_only_ever_splits_a_cluster_into_more_faces(crowd, strong):
    from ipomdp_gaze.model.occupancy import count_faces
    grid, log_odds, boxes, scores = crowd
    occupied = log_odds > 0
    plain = count_faces(log_odds, grid, occupied, boxes, scores, (120, 80))
    more = count_faces(log_odds, grid, occupied, boxes, scores, (120, 80), strong=strong)
    assert len(more) >= len(plain)

    def cells(faces):
        return set(np.concatenate([f['cells'] for f in faces]).tolist()) if faces else set()
    assert cells(more) == cells(plain) == set(np.flatnonzero(occupied).tolist())
    # a strong score above every raw score changes nothing
    above = count_faces(log_odds, grid, occupied, boxes, scores, (120, 80), strong=1.5)
    assert [(f['cell'], f['probability']) for f in above] == \
        [(f['cell'], f['probability']) for f in plain]
