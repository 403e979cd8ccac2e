# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Many moving targets over DDS (docs/design.md section 12.10): a person found, lost, reacquired.

The controller (``search.targets many`` with motion on) and the simulated camera run as
processes, as in ``test_ros_tracking_events`` for one target. The camera holds its target at one
cell, empties its scene (the person walked out), then puts it back at another cell. The
person's events arrive on the usual event topics, each with the person's number (1); the
controller publishes the person on ``~/targets`` and ``~/target_cells`` while it follows it and
nobody once it is lost; its status says the search goes on.
"""
from __future__ import annotations

import time

from conftest import config_path, people_controller_args, wait_for
import pytest

pytestmark = pytest.mark.ros

CONTROLLER, CAMERA = 'gaze_controller', 'simulated_camera'
FIRST, SECOND = (2, 8), (8, 3)
EVENT_TIMEOUT_S = 90.0


@pytest.fixture(scope='module')
def events(launch, probe):
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.harness.watch import LATCHED
    from std_msgs.msg import Float32MultiArray

    rec = {'found': probe.record(DiagnosticStatus, 'found', 10),
           'lost': probe.record(DiagnosticStatus, 'lost', 10),
           'reacquired': probe.record(DiagnosticStatus, 'reacquired', 10),
           'cells': probe.record(Float32MultiArray, f'/{CONTROLLER}/target_cells', LATCHED),
           'status': probe.search_status(CONTROLLER)}
    controller = launch('controller', people_controller_args(0.5))
    assert wait_for(lambda: all(probe.matched(t) for t in ('found', 'lost', 'reacquired')),
                    30), controller.output()
    rec['started_at'] = time.monotonic()
    camera = launch('camera', ['--params-file', config_path('camera.yaml'),
                               '-p', f'target_row:={FIRST[0]}', '-p', f'target_col:={FIRST[1]}',
                               '-p', 'seed:=3'])
    rec['output'] = lambda: controller.output() + camera.output()           # noqa: E731
    assert wait_for(lambda: _after(rec['found'], rec['started_at']), EVENT_TIMEOUT_S), \
        'no found event\n' + rec['output']()
    # ~/target_cells goes out just after the found event of the same frame.
    assert wait_for(lambda: _people(rec), 10), rec['output']()
    rec['people_found'] = _people(rec)

    def move(params):
        results = probe.set_parameters(CAMERA, params)
        assert all(r.successful for r in results), [r.reason for r in results]
        assert probe.reset(CAMERA).success
        return time.monotonic()

    rec['left_at'] = move({'empty_scene': True})
    assert wait_for(lambda: _after(rec['lost'], rec['left_at']), EVENT_TIMEOUT_S), \
        'no lost event\n' + rec['output']()
    assert wait_for(lambda: _people(rec) == [], 10)
    rec['back_at'] = move({'empty_scene': False, 'target_row': SECOND[0],
                           'target_col': SECOND[1]})
    assert wait_for(lambda: _at_second(rec['reacquired'], rec['back_at']), EVENT_TIMEOUT_S), \
        'no reacquired event at the second place\n' + rec['output']()
    return rec


def _after(events, t0):
    return [(t, msg) for t, msg in events if t > t0]


def _at_second(events, t0):
    from ipomdp_gaze.msg_adapters import diagnostics
    at = [(t, msg, diagnostics.parse_reacquired(msg)) for t, msg in _after(events, t0)]
    return [(t, msg) for t, msg, event in at if (event['row'], event['col']) == SECOND]


def _people(rec) -> list:
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import people
    if not rec['cells']:
        return None
    return [cell for cell, _ in people.read_people_array(rec['cells'][-1][1], Grid(11, 11, 5.0))]


def test_a_person_who_leaves_and_returns_is_lost_then_reacquired_by_number(events):
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import diagnostics
    grid = Grid(11, 11, 5.0)
    msg_found = _after(events['found'], events['started_at'])[0][1]
    found = diagnostics.parse_found(msg_found)
    t_lost, msg_lost = _after(events['lost'], events['left_at'])[0]
    lost = diagnostics.parse_lost(msg_lost)
    t_back, msg_back = _at_second(events['reacquired'], events['back_at'])[0]
    again = diagnostics.parse_reacquired(msg_back)
    assert [diagnostics.person_of(m) for m in (msg_found, msg_lost, msg_back)] == [1, 1, 1]
    assert msg_found.message.startswith('person 1 found at row')
    assert max(abs(found['row'] - FIRST[0]), abs(found['col'] - FIRST[1])) <= 1, found
    assert found['probability'] >= 0.95
    assert max(abs(lost['row'] - FIRST[0]), abs(lost['col'] - FIRST[1])) <= 1, lost
    assert lost['probability'] < 0.5 and lost['seconds_tracked'] > 0
    assert found['fixations'] < lost['fixations'] < again['fixations']
    assert events['left_at'] < t_lost < events['back_at'] < t_back
    assert 0 < again['seconds_lost'] < t_back - t_lost + 1.0
    # ~/target_cells held the person near FIRST while it was followed.
    assert len(events['people_found']) == 1
    row, col = grid.cell(events['people_found'][0])
    assert max(abs(row - FIRST[0]), abs(col - FIRST[1])) <= 1


def test_the_search_goes_on_and_counts_each_persons_events(events):
    assert len(_after(events['found'], events['started_at'])) == 1     # no second person
    again = _after(events['reacquired'], events['started_at'])
    assert wait_for(lambda: events['status'].values.get('reacquired') == str(len(again)), 10)
    status = events['status'].values
    assert int(status['lost']) == len(_after(events['lost'], events['started_at'])) >= 1
    assert status['search_ended'] == 'false'
    assert wait_for(lambda: _people(events) not in (None, []), 20), events['output']()


def test_motion_turned_off_mid_search_forgets_the_people_on_targets(events, probe):
    # Runs last: the module's controller stops following people. A new, still search starts:
    # ~/targets says at once that nobody is known (the pass may name them again when it ends).
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import people
    assert wait_for(lambda: _people(events) not in (None, []), 30), events['output']()
    before = len(events['cells'])
    assert int(events['status'].values['lost']) >= 1        # the moving search's own count
    result = probe.set_parameters_atomically(CONTROLLER, {'motion.sigma_cells': 0.0,
                                                          'motion.leave_prob': 0.0})
    assert result.successful, result.reason

    def emptied():
        grid = Grid(11, 11, 5.0)
        return any(people.read_people_array(msg, grid) == []
                   for _, msg in events['cells'][before:])
    assert wait_for(emptied, 10), events['output']()
    # Still and moving people are two searches: the switch starts a new one (and no dwell on
    # the people the moving search followed goes on).
    assert wait_for(lambda: events['status'].values.get('lost') == '0', 10), events['output']()
