# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The gaze controller core without ROS: frames, belief, policy choice, found, counters."""
from __future__ import annotations

from dataclasses import replace

from hypothesis import given, settings
from hypothesis import strategies as st
from ipomdp_gaze.model.belief import argmax_ties_low, bayes_update, uniform_log_belief
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
from ipomdp_gaze.policies.baselines import spiral_order
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.session import SearchSettings
import numpy as np
import pytest

GRID = Grid(11, 11, 5.0)
CAMERA = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)


def controller(policy='elm', settle_time_s=0.5, **kwargs):
    policy = build_policy(policy, GRID, CAMERA) if isinstance(policy, str) else policy
    core = GazeController(GRID, CAMERA, policy, SearchSettings(**kwargs), settle_time_s)
    core.reset(0.0)
    return core


def expected_update(belief, frame, fixation, fpoc=CAMERA):
    d = dprime_matrix(GRID, fpoc)[:, fixation]
    return np.exp(bayes_update(np.log(belief), llr(np.asarray(frame, dtype=float), d)))


def test_starts_uniform_at_the_centre_with_zero_counters():
    core = controller()
    assert core.fixation == GRID.center_index == 60
    np.testing.assert_allclose(core.belief, 1 / 121)
    assert core.counters() == {'received': 0, 'applied': 0, 'rejected': 0, 'skipped': 0}
    assert core.entropy_nats == pytest.approx(np.log(121))


def test_frame_before_settling_is_skipped_and_changes_nothing():
    core = controller(settle_time_s=0.5)
    before = core.belief
    result = core.offer(np.random.default_rng(0).standard_normal(121), stamp_s=0.49)
    assert (result.status, result.fixation) == ('skipped', None)
    np.testing.assert_array_equal(core.belief, before)
    assert core.fixation == 60
    assert core.counters() == {'received': 1, 'applied': 0, 'rejected': 0, 'skipped': 1}


def test_settled_frame_updates_the_belief_and_the_policy_picks_the_next_fixation():
    core = controller(settle_time_s=0.5)
    frame = np.random.default_rng(1).standard_normal(121)
    result = core.offer(frame, stamp_s=0.5, now_s=0.7)
    want = expected_update(np.full(121, 1 / 121), frame, 60)
    np.testing.assert_allclose(core.belief, want, rtol=1e-12)
    elm = build_policy('elm', GRID, CAMERA)
    assert result.applied and result.fixation == core.fixation
    assert core.fixation == int(elm.select(want[None], 1, None)[0])
    assert core.target_time_s == 0.7 and core.fixations == 1


def test_the_event_log_is_kept_only_when_asked_and_changes_no_search():
    """No log by default (the node's topics are its record); ``log_size`` keeps one."""
    frames = np.random.default_rng(5).standard_normal((6, 121))
    runs = []
    for log_size in (0, 100):
        policy = build_policy('elm', GRID, CAMERA)
        core = GazeController(GRID, CAMERA, policy, SearchSettings(), 0.0, log_size=log_size)
        core.reset(0.0)
        runs.append([(core.offer(f, stamp_s=1.0 + i).fixation, core.belief.tobytes())
                     for i, f in enumerate(frames)])
        kinds = [event['event'] for event in core.session.log]
        assert kinds.count('frame') == (6 if log_size else 0)
        assert ('reset' in kinds) == bool(log_size)
        core.configure(SearchSettings(targets='many'))      # a new session keeps the size
        assert bool(core.session.log) == bool(log_size)
    assert runs[0] == runs[1]


def test_one_frame_per_fixation():
    core = controller(settle_time_s=0.5)
    rng = np.random.default_rng(2)
    assert core.offer(rng.standard_normal(121), 1.0).applied
    # A second frame of the same moment belongs to the new fixation, which has not settled.
    result = core.offer(rng.standard_normal(121), 1.0)
    assert result.status == 'skipped'
    assert core.offer(rng.standard_normal(121), 1.5).applied
    assert core.counters() == {'received': 3, 'applied': 2, 'rejected': 0, 'skipped': 1}


def test_nan_cells_are_unobserved():
    core = controller(settle_time_s=0.0)
    frame = np.random.default_rng(3).standard_normal(121)
    frame[[0, 60, 61, 120]] = np.nan
    core.offer(frame, 1.0)
    zeroed = np.where(np.isnan(frame), 0.0, frame)
    d = dprime_matrix(GRID, CAMERA)[:, 60]
    log_b = uniform_log_belief(121) + np.where(np.isnan(frame), 0.0, d * (zeroed - d / 2))
    want = np.exp(log_b - np.logaddexp.reduce(log_b))
    np.testing.assert_allclose(core.belief, want, rtol=1e-12)


@pytest.mark.parametrize('frame, words', [
    (np.zeros(120), '120 values'),
    (np.r_[np.zeros(120), np.inf], 'inf'),
    (np.r_[-np.inf, np.zeros(120)], 'inf'),
    (np.zeros((11, 11)), 'shape'),
])
def test_invalid_frames_are_rejected_and_change_nothing(frame, words):
    core = controller(settle_time_s=0.0)
    before, fixation = core.belief, core.fixation
    result = core.offer(frame, 5.0)
    assert result.status == 'rejected' and words in result.reason
    np.testing.assert_array_equal(core.belief, before)
    assert core.fixation == fixation and core.last_rejection == result.reason
    assert core.counters() == {'received': 1, 'applied': 0, 'rejected': 1, 'skipped': 0}


def test_a_frame_that_observed_nothing_or_comes_from_the_future_is_rejected():
    core = controller(settle_time_s=0.0)
    before, fixation = core.belief, core.fixation
    nothing = core.offer(np.full(121, np.nan), 5.0, now_s=5.0)
    assert nothing.status == 'rejected' and 'observed nothing' in nothing.reason
    ahead = core.offer(np.zeros(121), 5.6, now_s=5.0)          # its clock runs 0.6 s ahead
    assert ahead.status == 'rejected' and '0.600 s ahead' in ahead.reason
    np.testing.assert_array_equal(core.belief, before)
    assert (core.fixation, core.fixations) == (fixation, 0)    # no fixation spent
    assert core.offer(np.zeros(121), 5.4, now_s=5.0).status == 'applied'   # within 0.5 s
    assert core.counters() == {'received': 3, 'applied': 1, 'rejected': 2, 'skipped': 0}


def test_each_frame_is_checked_once_whatever_becomes_of_it(monkeypatch):
    core = controller(settle_time_s=0.5)
    checks = []
    original = core.session.check_frame
    monkeypatch.setattr(core.session, 'check_frame', lambda v: checks.append(1) or original(v))
    statuses = [core.offer(np.zeros(121), 0.1).status,            # before settling
                core.offer(np.zeros(120), 0.6).status,            # wrong length
                core.offer(np.zeros(121), 0.6).status]            # applied
    assert statuses == ['skipped', 'rejected', 'applied'] and len(checks) == 3


def test_reject_counts_frames_the_node_could_not_read():
    core = controller()
    result = core.reject('layout is 7x7, the grid is 11x11')
    assert result.status == 'rejected' and core.rejected == core.received == 1


def test_disabled_skips_frames_and_enabling_resends_the_target():
    core = controller(settle_time_s=0.5)
    assert core.set_enabled(False, 1.0)
    assert not core.set_enabled(False, 1.1)
    result = core.offer(np.zeros(121), 10.0)
    assert (result.status, result.reason) == ('skipped', 'disabled')
    np.testing.assert_allclose(core.belief, 1 / 121)
    assert core.set_enabled(True, 20.0)
    assert core.target_time_s == 20.0
    assert core.offer(np.zeros(121), 20.4).status == 'skipped'
    assert core.offer(np.zeros(121), 20.5).applied


def test_found_fires_once_per_search_and_reset_starts_over():
    core = controller(settle_time_s=0.0, confidence=0.95)
    target = 17
    frame = np.zeros(121)
    frame[target] = 40.0            # an unmistakable detection inside the field of view
    core.fixation = target
    result = core.offer(frame, 1.0)
    assert result.found is not None
    assert (result.found.cell, result.found.fixations) == (target, 1)
    assert result.found.probability >= 0.95
    core.fixation = target
    assert core.offer(frame, 2.0).found is None
    assert core.reset(3.0) == GRID.center_index
    np.testing.assert_allclose(core.belief, 1 / 121)
    assert core.found is None and core.fixations == 0
    core.fixation = target
    assert core.offer(frame, 4.0).found is not None


def test_policy_time_index_counts_fixations_since_reset():
    core = controller('spiral', settle_time_s=0.0)
    order = spiral_order(GRID)
    seen = [core.fixation]
    for t in range(1, 6):
        seen.append(core.offer(np.zeros(121), float(t)).fixation)
    assert seen == list(order[:6])
    core.reset(10.0)
    assert core.offer(np.zeros(121), 11.0).fixation == order[1]


def test_start_cell_and_validation():
    core = controller(start_cell=(0, 10))
    assert core.reset(0.0) == 10
    with pytest.raises(ValueError, match='outside'):
        core.configure(replace(core.settings, start_cell=(11, 0)))
    with pytest.raises(ValueError, match='settle_time_s'):
        core.configure(core.settings, settle_time_s=-1.0)
    with pytest.raises(ValueError, match='confidence'):
        replace(core.settings, confidence=1.0)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(['good', 'nan', 'short', 'inf', 'reject', 'off', 'on']),
                          st.floats(0.0, 1.0)), max_size=30))
def test_counters_add_up(events):
    core = controller(settle_time_s=0.3)
    rng = np.random.default_rng(0)
    now = 0.0
    for kind, dt in events:
        now += dt
        frame = rng.standard_normal(121)
        if kind == 'nan':
            frame[rng.random(121) < 0.5] = np.nan
        elif kind == 'short':
            frame = frame[:100]
        elif kind == 'inf':
            frame[3] = np.inf
        if kind == 'reject':
            core.reject('bad layout')
        elif kind in ('off', 'on'):
            core.set_enabled(kind == 'on', now)
        else:
            core.offer(frame, now)
        c = core.counters()
        assert c['received'] == c['applied'] + c['rejected'] + c['skipped']
        assert c['applied'] == core.fixations
        np.testing.assert_allclose(core.belief.sum(), 1.0, rtol=1e-12)


@pytest.mark.parametrize('seed', range(6))
def test_search_with_the_camera_observation_model_finds_the_target(seed):
    """The core alone finds the target: the MAP cell at 0.999 is the target."""
    rng = np.random.default_rng([seed, 42])
    target = int(rng.integers(121))
    d = dprime_matrix(GRID, CAMERA)
    core = controller(settle_time_s=0.0, confidence=0.999)     # the search ends at found
    for t in range(200):
        frame = rng.standard_normal(121)
        frame[target] += d[target, core.fixation]
        frame[d[:, core.fixation] == 0] = np.nan
        core.offer(frame, float(t))
        if core.map_probability >= 0.999:
            break
    assert core.map_probability >= 0.999
    assert core.map_cell == target
    assert core.found is not None and core.found.fixations <= core.fixations


def test_inhibition_of_return_never_fixates_a_cell_twice_then_opens_them_again():
    """A still scene: the same frame again and again. MAP would stare; with IOR it moves on."""
    frame = np.zeros(121)
    frame[5] = 1.0                                 # weak evidence near the top edge, every look
    kwargs = {'settle_time_s': 0.0, 'confidence': 1 - 1e-9}
    stare = controller('map', **kwargs)
    ior = controller('map', inhibit_return=True, **kwargs)
    fixations = {'stare': [], 'ior': []}
    for t in range(1, 41):
        for name, core in (('stare', stare), ('ior', ior)):
            fixations[name].append(core.fixation)
            assert core.offer(frame, float(t)).applied
    assert len(set(fixations['stare'])) < 30              # MAP goes back to cells it saw
    assert len(set(fixations['ior'])) == 40                # never the same cell twice
    ior.reset(100.0)
    assert ior.fixation == GRID.center_index and not ior.session.visited.any()
    # Once every cell of a small grid has been fixated, all are open again.
    grid = Grid(2, 2)
    small = GazeController(grid, CAMERA, build_policy('map', grid, CAMERA),
                           SearchSettings(confidence=1 - 1e-9, inhibit_return=True))
    seen = []
    for t in range(1, 6):
        seen.append(small.fixation)
        assert small.offer(np.zeros(4), float(t)).applied
    assert sorted(seen[:4]) == [0, 1, 2, 3] and small.session.visited.sum() == 1


def test_inhibition_of_return_gives_the_best_unvisited_cell_of_elm_and_is_off_for_motion():
    rng = np.random.default_rng(4)
    elm = build_policy('elm', GRID, CAMERA)
    core = controller('elm', settle_time_s=0.0, inhibit_return=True)
    seen = [core.fixation]
    for t in range(1, 30):
        core.offer(rng.standard_normal(121), float(t))
        scores = elm.scores(core.belief[None]).reshape(-1)
        scores[seen] = -np.inf
        assert core.fixation == int(argmax_ties_low(scores)) and core.fixation not in seen
        seen.append(core.fixation)
    moving = controller('map', settle_time_s=0.0, inhibit_return=True, motion_sigma_cells=0.1,
                        confidence=1 - 1e-9)
    frame = np.zeros(121)
    frame[5] = 1.0
    picks = []
    for t in range(1, 41):
        picks.append(moving.fixation)
        moving.offer(frame, float(t))
    assert len(set(picks)) < 30                            # a moving target: cells looked at again
