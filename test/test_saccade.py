# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The simulated head's saccades: a re-sent command neither restarts a saccade nor waits."""
from __future__ import annotations

import pytest

pytestmark = pytest.mark.ros


class _Timer:

    def __init__(self):
        self.resets = 0

    def reset(self):
        self.resets += 1

    def cancel(self):
        pass


def _head():
    from ipomdp_gaze.nodes.saccade import SaccadeMixin

    class Head(SaccadeMixin):

        def __init__(self):
            self.pose, self.goal, self.moving = 0, 0, False
            self._saccade_timer, self.frames = _Timer(), []

        def _arrived(self):
            self.frames.append(self.pose)
    return Head()


def test_a_resent_goal_neither_restarts_the_saccade_nor_waits_again():
    head = _head()
    head._saccade_to(5, (1, 0))
    assert (head.moving, head._saccade_timer.resets, head.frames) == (True, 1, [])
    head._saccade_to(5, (1, 0))                          # re-sent under way: goes on
    assert head._saccade_timer.resets == 1
    head._on_arrival()
    assert (head.pose, head.moving, head.frames) == (5, False, [5])
    head._saccade_to(5, (1, 0))                          # re-sent at the goal: a frame now
    assert (head.pose, head.moving, head._saccade_timer.resets, head.frames) == \
        (5, False, 1, [5, 5])
    head._saccade_to(5, (2, 0))                          # a new command to where it stands:
    assert (head.moving, head._saccade_timer.resets, head.frames) == (True, 2, [5, 5])
    head._on_arrival()                                   # it settles again first
    assert head.frames == [5, 5, 5]
    head._saccade_to(7, (3, 0))                          # a new goal: a saccade
    assert (head.moving, head._saccade_timer.resets, head.frames) == (True, 3, [5, 5, 5])


class _Logger:

    def __init__(self):
        self.warnings = []

    def warning(self, text, **_):
        self.warnings.append(text)


def test_a_command_beyond_the_grid_is_clipped_to_its_edge_and_warned():
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import joints
    from builtin_interfaces.msg import Time
    from sensor_msgs.msg import JointState
    head_map = PanTiltMap(Grid(5, 7, spacing_deg=5.0))
    head, logger = _head(), _Logger()
    head.get_logger = lambda: logger
    inside = joints.joint_state(head_map, head_map.grid.index(4, 6), Time())
    assert head._commanded_cell(inside, head_map) == head_map.grid.index(4, 6)
    assert logger.warnings == []
    far = JointState(name=['pan_joint', 'tilt_joint'], position=[-3.0, 0.0])
    assert head._commanded_cell(far, head_map) == head_map.grid.index(2, 6)    # pan's edge
    assert len(logger.warnings) == 1 and 'beyond the 5x7 grid' in logger.warnings[0]
    nan = JointState(name=['pan_joint', 'tilt_joint'], position=[float('nan'), 0.0])
    assert head._commanded_cell(nan, head_map) is None
    assert 'ignored a pan_tilt command' in logger.warnings[1]


@pytest.mark.parametrize('pan_rad', [1e300, -7.0])
def test_a_command_beyond_a_turn_is_ignored_in_one_readable_line(pan_rad):
    """
    QA: a pan of 1e300 rad was clipped and logged with its 300 digits (``:.4f``).

    The detector refuses joint angles beyond one turn as absurd; the camera ignores such a
    command as malformed, with a short warning, and the head stays where it was.
    """
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from sensor_msgs.msg import JointState
    head_map = PanTiltMap(Grid(5, 7, spacing_deg=5.0))
    head, logger = _head(), _Logger()
    head.get_logger = lambda: logger
    absurd = JointState(name=['pan_joint', 'tilt_joint'], position=[pan_rad, 0.0])
    assert head._commanded_cell(absurd, head_map) is None
    assert len(logger.warnings) == 1 and len(logger.warnings[0]) < 120
    assert logger.warnings[0].startswith('ignored a pan_tilt command: pan/tilt ')
    assert 'beyond +/-6.2832 rad (one turn)' in logger.warnings[0]
