# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The controller's health report and the settings it checks, without ROS.

:func:`ipomdp_gaze.search.health.classify` decides what ``/diagnostics`` says; every branch is
checked
here with its level, message and detail, and :class:`ipomdp_gaze.search.health.HealthMonitor` with
a
real :class:`ipomdp_gaze.search.gaze.GazeController` (per-period counts, rate, values in their
order).
"""
from __future__ import annotations

from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.stopping import check_confidence
from ipomdp_gaze.search.gaze import check_settle_time, GazeController
from ipomdp_gaze.search.health import classify, Health, HealthMonitor, policy_label
from ipomdp_gaze.search.session import SearchSettings, start_index
import numpy as np
import pytest

GRID = Grid(5, 5, 5.0)
FPOC = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)
VALUE_KEYS = ['policy', 'enabled', 'evidence_rate_hz', 'frames_received', 'frames_applied',
              'frames_rejected', 'frames_skipped', 'frames_dropped', 'seconds_without_evidence',
              'fixations', 'fixation_row', 'fixation_col', 'entropy_nats', 'most_likely_row',
              'most_likely_col', 'most_likely_probability', 'found', 'pan_tilt_resends',
              'last_rejection', 'absent_probability', 'decision', 'search_ended', 'lost',
              'reacquired', 'prior']


def health(enabled=True, stall_timeout_s=5.0, without_s=0.5, arrived=3, rejected=0,
           last_rejection='', found=False) -> Health:
    return classify(enabled, stall_timeout_s, without_s, arrived, rejected, last_rejection,
                    found)


# -- classify: one test per branch ------------------------------------------------------------
def test_frames_arrive_and_are_used_ok_searching():
    h = health()
    assert (h.level, h.message, h.detail, h.stalled) == ('ok', 'searching', '', False)
    assert h.values == {}


def test_disabled_is_ok_even_without_frames_or_for_long():
    for arrived, without_s in ((0, 0.5), (3, 60.0), (0, 60.0)):
        h = health(enabled=False, arrived=arrived, without_s=without_s)
        assert (h.level, h.message, h.detail, h.stalled) == ('ok', 'disabled', '', False)


def test_stalled_because_no_frames_arrive():
    h = health(stall_timeout_s=1.0, without_s=6.25, arrived=0)
    assert (h.level, h.message) == ('warn', 'no usable evidence for 6.2 s')
    assert h.detail == 'no frames arrive' and h.stalled


def test_stalled_with_frames_that_are_rejected_names_the_last_rejection():
    h = health(stall_timeout_s=1.0, without_s=2.0, arrived=7, rejected=2,
               last_rejection='evidence contains +/-inf')
    assert (h.level, h.message) == ('warn', 'no usable evidence for 2.0 s')
    assert h.detail == '7 frames arrived, none usable; last rejection: evidence contains +/-inf'
    assert h.stalled


def test_stalled_with_frames_that_are_skipped_has_no_rejection():
    # An old rejection (not in this period) is not repeated.
    h = health(stall_timeout_s=1.0, without_s=2.0, arrived=4, rejected=0,
               last_rejection='evidence contains +/-inf')
    assert (h.level, h.message, h.detail) == ('warn', 'no usable evidence for 2.0 s',
                                              '4 frames arrived, none usable')


def test_stall_timeout_is_strict_and_zero_never_stalls():
    assert not health(stall_timeout_s=2.0, without_s=2.0).stalled
    assert health(stall_timeout_s=2.0, without_s=2.001).stalled
    h = health(stall_timeout_s=0.0, without_s=1e6, arrived=0)
    assert (h.level, h.message, h.stalled) == ('ok', 'waiting for evidence', False)


def test_target_found_is_ok_even_without_frames():
    for arrived in (0, 3):
        h = health(found=True, arrived=arrived)
        assert (h.level, h.message, h.detail) == ('ok', 'target found', '')


def test_a_stall_is_reported_before_the_found_target():
    h = health(found=True, stall_timeout_s=1.0, without_s=3.0, arrived=0)
    assert (h.level, h.message, h.detail) == ('warn', 'no usable evidence for 3.0 s',
                                              'no frames arrive')


def test_a_period_without_frames_is_ok_until_the_stall_timeout():
    h = health(arrived=0, stall_timeout_s=5.0, without_s=1.5)
    assert (h.level, h.message, h.detail, h.stalled) == ('ok', 'waiting for evidence', '',
                                                         False)
    h = health(arrived=0, stall_timeout_s=5.0, without_s=5.5)
    assert (h.level, h.stalled) == ('warn', True)


@pytest.mark.parametrize('state', [{}, {'enabled': False}, {'found': True}])
def test_a_rejection_in_the_period_turns_an_ok_report_into_a_warning(state):
    h = health(rejected=1, last_rejection='evidence has 120 values', **state)
    assert (h.level, h.message, h.detail) == ('warn', 'evidence rejected: evidence has 120 '
                                                      'values', '')


def test_a_rejection_does_not_replace_another_warning_or_lack_a_reason():
    h = health(arrived=0, rejected=1, last_rejection='bad layout', stall_timeout_s=1.0,
               without_s=2.0)
    assert (h.level, h.message) == ('warn', 'no usable evidence for 2.0 s')
    assert health(rejected=1, last_rejection='').message == 'searching'


# -- the policy label ------------------------------------------------------------------------
def test_policy_label():
    assert policy_label('elm', [], 'camera-11x11-infomax', 'argmax') == 'elm'
    assert policy_label('learned', [0.5] * 9, 'x.yaml', 'sample') == \
        'learned (policy.kernel, sample)'
    assert policy_label('learned', [], 'camera-11x11-infomax', 'argmax') == \
        'learned (camera-11x11-infomax, argmax)'
    assert policy_label('learned', None, 'p.yaml') == 'learned (p.yaml, argmax)'


# -- HealthMonitor with a real controller ----------------------------------------------------
class Centre:
    """A policy that always looks at the centre."""

    def select(self, belief, t, rng):
        return np.full(belief.shape[0], GRID.center_index)


def controller(**kwargs) -> GazeController:
    settle_time_s = kwargs.pop('settle_time_s', 0.0)
    core = GazeController(GRID, FPOC, Centre(), SearchSettings(**kwargs), settle_time_s)
    core.reset(0.0)
    return core


def frame(seed=0) -> np.ndarray:
    return np.random.default_rng(seed).standard_normal(GRID.n_cells)


def test_monitor_reports_each_period_with_values_in_order():
    core = controller()
    monitor = HealthMonitor(0.0)
    for i in range(4):
        assert core.offer(frame(i), 0.1 * (i + 1)).applied
    h = monitor.report(core, 2.0, 5.0, policy='map', dropped=3, resends=2)
    assert (h.level, h.message) == ('ok', 'searching')
    assert list(h.values) == VALUE_KEYS
    v = h.values
    assert v['evidence_rate_hz'] == pytest.approx(4 / 2.0)
    assert (v['frames_received'], v['frames_applied'], v['frames_rejected'],
            v['frames_skipped'], v['frames_dropped']) == (4, 4, 0, 0, 3)
    assert (v['policy'], v['enabled'], v['found'], v['pan_tilt_resends']) == ('map', True,
                                                                              False, 2)
    assert v['seconds_without_evidence'] == pytest.approx(2.0 - 0.4)
    assert (v['fixations'], v['fixation_row'], v['fixation_col']) == (4, 2, 2)
    assert (v['most_likely_row'], v['most_likely_col']) == GRID.cell(core.map_cell)
    assert v['most_likely_probability'] == core.map_probability
    assert v['entropy_nats'] == core.entropy_nats and v['last_rejection'] == ''
    # The next period saw no frame.
    h = monitor.report(core, 3.0, 5.0)
    assert (h.level, h.message) == ('ok', 'waiting for evidence')
    assert h.values['evidence_rate_hz'] == 0.0


def test_monitor_counts_rejections_per_period():
    core = controller()
    monitor = HealthMonitor(0.0)
    core.reject('bad layout')
    assert core.offer(frame(), 0.5).applied
    h = monitor.report(core, 1.0, 5.0)
    assert (h.level, h.message) == ('warn', 'evidence rejected: bad layout')
    assert h.values['last_rejection'] == 'bad layout' and h.values['frames_rejected'] == 1
    assert core.offer(frame(1), 1.5).applied
    h = monitor.report(core, 2.0, 5.0)              # the rejection is old news
    assert (h.level, h.message) == ('ok', 'searching')


def test_monitor_stall_with_skipped_and_rejected_frames():
    core = controller(settle_time_s=100.0)         # every frame is taken before it settles
    monitor = HealthMonitor(0.0)
    assert core.offer(frame(), 1.0).status == 'skipped'
    assert core.offer(np.full(GRID.n_cells, np.inf), 1.5).status == 'rejected'
    h = monitor.report(core, 7.0, 5.0)
    assert (h.level, h.message) == ('warn', 'no usable evidence for 7.0 s')
    assert h.detail == '2 frames arrived, none usable; last rejection: evidence contains +/-inf'
    h = monitor.report(core, 8.0, 5.0)
    assert (h.message, h.detail) == ('no usable evidence for 8.0 s', 'no frames arrive')
    core.set_enabled(False, 8.5)
    assert monitor.report(core, 20.0, 5.0).message == 'disabled'
    core.set_enabled(True, 21.0)
    assert not monitor.report(core, 22.0, 5.0).stalled   # enabling starts the clock again


def test_monitor_reports_the_found_target():
    core = controller(confidence=0.5)
    monitor = HealthMonitor(0.0)
    target = GRID.center_index
    t = 0.0
    while core.found is None:
        t += 1.0
        obs = np.random.default_rng(int(t)).standard_normal(GRID.n_cells)
        obs[target] += 4.0
        core.offer(obs, t)
    h = monitor.report(core, t + 0.5, 60.0)
    assert (h.level, h.message) == ('ok', 'target found') and h.values['found'] is True
    assert monitor.report(core, t + 1.5, 60.0).message == 'target found'


def test_found_in_diagnostics_is_the_decision_now():
    """QA: 'found' stayed true after a moving target was lost (decision absent, not found)."""
    core = controller(confidence=0.6, absent_prior=0.3, motion_sigma_cells=0.3,
                      motion_leave_prob=0.1)
    monitor = HealthMonitor(0.0)
    target, t = GRID.center_index, 0.0
    while core.decision != 'found':
        t += 1.0
        obs = np.random.default_rng(int(t)).standard_normal(GRID.n_cells)
        obs[target] += 4.0
        core.offer(obs, t)
    assert monitor.report(core, t + 0.5, 60.0).values['found'] is True
    while core.decision == 'found':                # the target has left: only noise now
        t += 1.0
        core.offer(np.random.default_rng(int(t)).standard_normal(GRID.n_cells), t)
    assert core.found is not None                   # the event fired in this search ...
    values = monitor.report(core, t + 0.5, 60.0).values
    assert values['found'] is False and values['decision'] == core.decision   # ... not now


def test_monitor_starts_from_the_counters_it_is_given():
    core = controller()
    for i in range(3):
        core.offer(frame(i), float(i + 1))
    core.reject('bad layout')
    h = HealthMonitor(3.0, received=core.received, rejected=core.rejected).report(core, 4.0, 5.0)
    assert (h.level, h.message) == ('ok', 'waiting for evidence')
    assert h.values['evidence_rate_hz'] == 0.0


# -- settings the node checks through the core -----------------------------------------------
def test_confidence_settle_time_and_start_cell_are_checked_once():
    assert check_confidence(0.95) == 0.95 and check_settle_time(0) == 0.0
    for bad in (0.0, 1.0, -0.1, float('nan')):
        with pytest.raises(ValueError, match='confidence must be between 0 and 1'):
            check_confidence(bad)
        with pytest.raises(ValueError, match='confidence must be between 0 and 1'):
            controller(confidence=bad)
    for bad in (-1.0, float('nan'), float('inf')):
        with pytest.raises(ValueError, match='settle_time_s must be finite and >= 0'):
            check_settle_time(bad)

    def start(row, col, grid=GRID):
        values = {'start_row': row, 'start_col': col}
        return start_index(grid, SearchSettings.from_parameters(values, grid=grid))
    assert start(-1, -1) is None and controller().fixation == GRID.center_index
    assert start(0, -1) == GRID.index(0, 2)
    assert start(-1, 4) == GRID.index(2, 4)
    assert start(3, 5, Grid(4, 6, 1.0)) == 23
    for row, col in ((5, 0), (0, 5)):
        with pytest.raises(ValueError, match='outside a 5x5 grid'):
            start(row, col)
    with pytest.raises(ValueError, match='start_cell must be'):
        start(-2, 0)
