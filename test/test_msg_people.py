# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""msg_adapters.people and the room_done event: the many-target messages (no DDS, no node)."""
from __future__ import annotations

import math

from conftest import HAVE_ROS_MSGS
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
import numpy as np
import pytest

if HAVE_ROS_MSGS:
    from builtin_interfaces.msg import Time
    from ipomdp_gaze.msg_adapters import diagnostics, people
    from std_msgs.msg import Float32MultiArray, MultiArrayDimension, MultiArrayLayout

pytestmark = pytest.mark.ros

GRID = Grid(11, 11, 5.0)


def test_target_cells_layout_and_round_trip():
    found = [(GRID.index(5, 9), 0.966), (GRID.index(7, 0), 0.934)]
    msg = people.people_array(GRID, found)
    dims = [(d.label, d.size, d.stride) for d in msg.layout.dim]
    assert dims == [('people', 2, 8), ('row_col_cell_probability', 4, 4)]
    assert msg.layout.data_offset == 0
    np.testing.assert_allclose(list(msg.data), [5, 9, 64, 0.966, 7, 0, 77, 0.934], rtol=1e-6)
    back = people.read_people_array(msg, GRID)
    assert [c for c, _ in back] == [c for c, _ in found]
    np.testing.assert_allclose([p for _, p in back], [p for _, p in found], rtol=1e-6)


def test_nobody_is_an_empty_array():
    msg = people.people_array(GRID, [])
    assert [(d.label, d.size, d.stride) for d in msg.layout.dim] == [
        ('people', 0, 0), ('row_col_cell_probability', 4, 4)]
    assert len(msg.data) == 0 and people.read_people_array(msg, GRID) == []


def _array(data, k, label='row_col_cell_probability', offset=0):
    msg = Float32MultiArray(layout=MultiArrayLayout(dim=[
        MultiArrayDimension(label='people', size=k, stride=4 * k),
        MultiArrayDimension(label=label, size=4, stride=4)], data_offset=offset))
    msg.data = [float(v) for v in data]
    return msg


@pytest.mark.parametrize('msg, words', [
    (lambda: _array([5, 9, 64, 0.9], 1, label='xyz'), 'must have 2 dimensions'),
    (lambda: _array([5, 9, 64, 0.9], 1, offset=1), 'data_offset 0'),
    (lambda: _array([5, 9, 64], 1), 'says 1 person (4 values), has 3 values'),
    (lambda: _array([5, 9, 63, 0.9], 1), 'is not a cell of the 11x11 grid'),
    (lambda: _array([11, 0, 121, 0.9], 1), 'is not a cell of the 11x11 grid'),
    (lambda: _array([5, 9, 64, 1.5], 1), 'probability 1.5 is not in [0, 1]'),
    (lambda: Float32MultiArray(), 'must have 2 dimensions'),
])
def test_a_malformed_target_cells_message_is_refused_with_the_reason(msg, words):
    with pytest.raises(people.PeopleLayoutError) as info:
        people.read_people_array(msg(), GRID)
    assert words in str(info.value)


@pytest.mark.parametrize('signs', [(1, 1), (-1, 1), (1, -1)])
def test_targets_poses_are_the_head_directions_of_the_cells(signs):
    head = PanTiltMap(GRID, 'pan', 'tilt', *signs, 0.1, -0.05)
    cells = [0, GRID.index(5, 9), GRID.index(7, 0), GRID.n_cells - 1]
    msg = people.people_poses(head, cells, Time(sec=3, nanosec=4), 'base')
    assert msg.header.frame_id == 'base' and msg.header.stamp.sec == 3
    assert len(msg.poses) == 4
    for pose, cell, (pan, tilt) in zip(msg.poses, cells, people.poses_angles(msg), strict=True):
        assert (pan, tilt) == pytest.approx(head.angles(cell), abs=1e-12)
        assert (pose.position.x, pose.position.y, pose.position.z) == (0.0, 0.0, 0.0)
        q = pose.orientation
        assert q.x ** 2 + q.y ** 2 + q.z ** 2 + q.w ** 2 == pytest.approx(1.0)


def test_a_direction_points_the_camera_axis_where_rep_103_says():
    """Pan left (+) turns x towards +y; tilt down (+) turns x towards -z."""
    def axis(pan, tilt):
        q = people.direction(pan, tilt)
        x, y, z, w = q.x, q.y, q.z, q.w              # the rotated x axis: first column of R
        return (1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y))
    np.testing.assert_allclose(axis(math.pi / 2, 0.0), (0, 1, 0), atol=1e-12)
    np.testing.assert_allclose(axis(0.0, math.pi / 2), (0, 0, -1), atol=1e-12)
    pan, tilt = 0.3, 0.2
    np.testing.assert_allclose(axis(pan, tilt), (math.cos(tilt) * math.cos(pan),
                                                 math.cos(tilt) * math.sin(pan),
                                                 -math.sin(tilt)), atol=1e-12)


def test_room_done_event_round_trip():
    msg = diagnostics.room_done_status('/gaze_controller: room_done', 2, 1, 20, 4, True,
                                       'budget', 0.99)
    assert msg.message == ('room done: 2 people found (1 new) by re-check 4 after 20 '
                           'fixations, forced by the fixation budget below the confidence 0.99')
    assert diagnostics.parse_room_done(msg) == {
        'people': 2, 'new_people': 1, 'fixations': 20, 'search_id': 4, 'recheck': True,
        'ended': 'forced:budget', 'confidence': 0.99}
    msg = diagnostics.room_done_status('x', 0, 0, 7, 2, False, '', 0.95)
    assert diagnostics.parse_room_done(msg)['ended'] == 'confidence'
    assert 'room done: 0 people found (0 new) by search 2' in msg.message
    msg = diagnostics.room_done_status('x', 1, 1, 12, 2, False, 'pass', 0.99)
    assert msg.message.startswith('room done: 1 person found (1 new) by search 2'), msg.message


@pytest.mark.parametrize('cause, words', [
    ('every_cell', 'the repeat stop (every cell fixated once)'),
    ('next_repeats', 'the repeat stop (the next fixation would repeat a cell)'),
    ('nothing_new', 'the repeat stop (no view left would tell anything new)')])
def test_a_room_done_at_its_repeat_stop_says_what_ended_it(cause, words):
    """QA: a room forced at its repeat stop was 'forced by every cell fixated once' always."""
    msg = diagnostics.room_done_status('x', 0, 0, 9, 3, False, 'repeat', 0.99, cause)
    assert msg.message == ('room done: 0 people found (0 new) by search 3 after 9 fixations, '
                           f'forced by {words} below the confidence 0.99')
    assert diagnostics.parse_room_done(msg)['ended'] == 'forced:repeat'


def test_a_forced_answer_at_the_confidence_is_not_said_to_be_below_it():
    """A room's pass forced found of a sure cell: the event said 1.0000 'below' 0.95."""
    msg = diagnostics.found_status('x', 9, 7, 106, -0.17, 0.35, 1.0, 16, 'pass', 0.95)
    assert msg.message.endswith('after 16 fixations, forced by the end of its pass (at the '
                                'confidence 0.95, before the search was done)')
    assert diagnostics.values_of(msg)['ended'] == 'forced:pass'
    msg = diagnostics.absent_status('x', 0.995, 20, 'budget', 0.99)
    assert 'below' not in msg.message and '(at the confidence 0.99' in msg.message
    msg = diagnostics.found_status('x', 5, 9, 64, -0.35, 0.0, 0.7539, 12, 'pass', 0.99)
    assert msg.message.endswith('forced by the end of its pass below the confidence 0.99')


def test_a_persons_lost_event_says_its_own_probability_not_the_most_likely_cells():
    """
    QA: a person's lost said "most likely cell now 0.0317" while another was followed at 1.0.

    A person's probability is that someone is at its cells (its last one or one next to it);
    the event of one target still names the most likely cell's.
    """
    msg = diagnostics.lost_status('/gaze_controller: lost', 1, 2, 13, 0.0317, 0.0, 92, 0.81,
                                  person=2)
    assert msg.message == ('person 2 lost: last found at row 1, col 2, tracked 0.81 s; someone '
                           'at its cells now 0.0317, nobody here 0.0000 after 92 fixations')
    assert diagnostics.person_of(msg) == 2
    assert diagnostics.parse_lost(msg)['probability'] == pytest.approx(0.0317)
    one = diagnostics.lost_status('/gaze_controller: lost', 1, 2, 13, 0.0317, 0.0, 92, 0.81)
    assert 'tracked 0.81 s; most likely cell now 0.0317, nobody here' in one.message
