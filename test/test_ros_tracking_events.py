# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Issue 38 over DDS: a target that leaves and comes back gives ``found``, ``lost``, ``reacquired``.

The controller and the simulated camera run as processes. The controller tracks (motion on, an
absent hypothesis, ``motion.leave_prob`` and ``motion.keep_probability``, section 12.5 of
docs/design.md); the camera holds its target at one cell, then empties its scene (the person
walked out), then puts the target back at another cell. The events arrive in that order on
their own topics, each once, with the cells and times they report.
"""
from __future__ import annotations

import time

from conftest import config_path, wait_for
import pytest

pytestmark = pytest.mark.ros

CONTROLLER, CAMERA = 'gaze_controller', 'simulated_camera'
FIRST, SECOND = (2, 8), (8, 3)
EVENT_TIMEOUT_S = 90.0


@pytest.fixture(scope='module')
def events(launch, probe):
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.harness.watch import SearchRecord

    search = SearchRecord(probe, depth=400)
    rec = {'search': search, 'targets': search.targets, 'truth': search.truth,
           'found': search.found, 'lost': probe.record(DiagnosticStatus, 'lost', 10),
           'reacquired': probe.record(DiagnosticStatus, 'reacquired', 10),
           'absent': probe.record(DiagnosticStatus, 'absent', 10),
           'status': probe.search_status(CONTROLLER)}
    controller = launch('controller', [
        '--params-file', config_path('controller.yaml'), '-p', 'absent.prior:=0.3',
        '-p', 'motion.sigma_cells:=0.3', '-p', 'motion.leave_prob:=0.05',
        '-p', 'motion.track_view:=peak', '-p', 'motion.keep_probability:=0.5',
        '-p', 'diagnostics_period_s:=0.2'])
    # Events are volatile: the camera starts (and with its first frame the search) only once
    # every event subscription has matched, so the first search's found is the one recorded.
    # (A reset instead races a found the search already sent before the reset was served.)
    assert wait_for(lambda: all(probe.matched(t) for t in ('found', 'lost', 'reacquired')),
                    30), controller.output()
    rec['started_at'] = time.monotonic()
    camera = launch('camera', ['--params-file', config_path('camera.yaml'),
                               '-p', f'target_row:={FIRST[0]}', '-p', f'target_col:={FIRST[1]}',
                               '-p', 'seed:=3'])
    output = lambda: controller.output() + camera.output()            # noqa: E731
    assert wait_for(lambda: _after(rec['found'], rec['started_at']), EVENT_TIMEOUT_S), \
        'no found event\n' + output()

    def move(params):
        results = probe.set_parameters(CAMERA, params)
        assert all(r.successful for r in results), [r.reason for r in results]
        assert probe.reset(CAMERA).success
        return time.monotonic()

    rec['left_at'] = move({'empty_scene': True})
    assert wait_for(lambda: _after(rec['lost'], rec['left_at']), EVENT_TIMEOUT_S), \
        'no lost event\n' + output()
    rec['back_at'] = move({'empty_scene': False, 'target_row': SECOND[0],
                           'target_col': SECOND[1]})
    assert wait_for(lambda: _at_second(rec['reacquired'], rec['back_at']), EVENT_TIMEOUT_S), \
        'no reacquired event at the second place\n' + output()
    return rec


def _after(events, t0):
    """Return the events that arrived after ``t0`` (``time.monotonic``)."""
    return [(t, msg) for t, msg in events if t > t0]


def _at_second(events, t0):
    """
    Return the reacquired events after ``t0`` at :data:`SECOND`.

    A frame the camera rendered before its scene change took effect can still show the face at
    :data:`FIRST` after ``t0`` (a race of the test's two parameter calls, not of the tracker).
    """
    from ipomdp_gaze.msg_adapters import diagnostics
    at = [(t, msg, diagnostics.parse_reacquired(msg)) for t, msg in _after(events, t0)]
    return [(t, msg) for t, msg, event in at if (event['row'], event['col']) == SECOND]


def test_a_target_that_leaves_and_returns_is_lost_then_reacquired(events):
    from ipomdp_gaze.msg_adapters import diagnostics
    found = diagnostics.parse_found(_after(events['found'], events['started_at'])[0][1])
    t_lost, msg = _after(events['lost'], events['left_at'])[0]
    lost = diagnostics.parse_lost(msg)
    t_back, msg = _at_second(events['reacquired'], events['back_at'])[0]
    again = diagnostics.parse_reacquired(msg)
    assert (found['row'], found['col']) == FIRST
    assert (lost['row'], lost['col']) == FIRST                   # where it was last found
    assert lost['probability'] < 0.5 or lost['absent_probability'] > lost['probability']
    assert (again['row'], again['col']) == SECOND and again['probability'] >= 0.95
    assert found['fixations'] < lost['fixations'] < again['fixations']
    assert events['left_at'] < t_lost < events['back_at'] < t_back
    # The lost event says how long the target had been tracked, reacquired how long it was gone.
    assert lost['seconds_tracked'] > 0
    assert 0 < again['seconds_lost'] < t_back - t_lost + 1.0


def test_a_reacquisition_is_not_a_second_found(events):
    """One search: the first find is found, every later one reacquired; the counts agree."""
    assert len(_after(events['found'], events['started_at'])) == 1
    again = _after(events['reacquired'], events['started_at'])
    assert wait_for(lambda: events['status'].values.get('reacquired') == str(len(again)), 10)
    status = events['status'].values
    assert int(status['lost']) == len(_after(events['lost'], events['started_at'])) >= 1
    assert status['search_ended'] == 'false'
