# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A room's turns on an in-process controller under ``use_sim_time``: one head command a moment.

The test drives ``/clock`` second by second, so the dwell and re-check timers tick at known
simulated times, whatever the load of the machine.
"""
from __future__ import annotations

import time

from conftest import config_path
import pytest

pytestmark = pytest.mark.ros


def _spin_until(executor, condition, timeout_s: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while not condition() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    return condition()


class _Room:
    """
    An in-process controller in a room's turns under ``use_sim_time``, and a /clock source.

    ``tick(seconds)`` publishes /clock and spins until the controller sees it; ``sent`` keeps
    the head commands (``pan_tilt``); ``cells_at(seconds)`` their cells stamped then.
    """

    def __init__(self, context, namespace: str, dwell_s: float, recheck_s: float):
        from ipomdp_gaze.harness.watch import LATCHED
        from ipomdp_gaze.model.head import PanTiltMap
        from ipomdp_gaze.nodes.controller import GazeControllerNode
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import JointState
        self.node = GazeControllerNode(context=context, namespace=namespace, cli_args=[
            '--ros-args', '--params-file', config_path('faces_camera_controller.yaml'),
            '--params-file', config_path('faces_camera_room_controller.yaml'),
            '-p', 'use_sim_time:=true', '-p', 'retry_period_s:=0.0',
            '-p', f'room.dwell_s:={dwell_s}', '-p', f'room.recheck_period_s:={recheck_s}'])
        self.source = Node(f'{namespace.strip("/")}_source', namespace=namespace,
                           context=context)
        self.sent = []
        self.source.create_subscription(JointState, 'pan_tilt', self.sent.append,
                                        LATCHED)  # keeps 10
        self.clock = self.source.create_publisher(Clock, '/clock', 10)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.source)
        self.grid = self.node._config.grid
        self.head = PanTiltMap(self.grid, 'pan_joint', 'tilt_joint')

    def spin_until(self, condition, timeout_s: float = 10.0) -> bool:
        return _spin_until(self.executor, condition, timeout_s)

    def tick(self, seconds: int) -> None:
        from builtin_interfaces.msg import Time as TimeMsg
        from rosgraph_msgs.msg import Clock
        self.clock.publish(Clock(clock=TimeMsg(sec=seconds)))
        assert self.spin_until(lambda: self.node._now_s() == seconds)

    def cells_at(self, seconds: int, since: int = 0) -> list:
        from ipomdp_gaze.msg_adapters import joints
        return [self.head.nearest_cell(*joints.angles_from_joint_state(m, self.head))
                for m in self.sent[since:] if m.header.stamp.sec == seconds]

    def two_people_found_at_100(self) -> None:
        """Start: a search of the room ends at 100 s with two people (as the node's own end)."""
        assert self.spin_until(lambda: self.clock.get_subscription_count() > 0, 30.0)
        self.tick(100)
        self.node._room.done([{'cell': c, 'probability': 0.9}
                              for c in (self.grid.index(3, 7), self.grid.index(9, 9))])
        self.node._make_room_timers(self.node._config.values)

    def close(self) -> None:
        self.executor.shutdown()
        self.source.destroy_node()
        self.node.destroy_node()


def test_a_dwell_at_the_moment_of_the_recheck_sends_no_person(context):
    """QA: at 2 s / 2 s the head was sent to a person, then to the pass's first pose at once."""
    room = _Room(context, '/room_turns', dwell_s=2.0, recheck_s=2.0)
    node = room.node
    try:
        room.two_people_found_at_100()
        room.tick(101)
        before = len(room.sent)
        room.tick(102)                                  # the dwell's tick and the re-check's
        # the re-check's command, the last one sent then (one publisher: in order)
        assert room.spin_until(lambda: node._room.rechecking
                               and node.core.fixation in room.cells_at(102, before))
        assert room.cells_at(102, before) == [node.core.fixation], \
            [room.grid.cell(c) for c in room.cells_at(102, before)]
    finally:
        room.close()


def test_a_clock_set_back_restarts_the_turns_and_the_recheck_in_step(context):
    """
    QA: /clock set back from 101 s to 50 s: at 53 s a person and the re-check's pose, at once.

    rcl restarted both timers at 50 s, but the room counted the turns from 100 s: every tick
    was a turn, also the re-check's.
    """
    room = _Room(context, '/room_jump', dwell_s=1.0, recheck_s=3.0)
    node = room.node

    def sent_at(seconds: int) -> int:
        return sum(m.header.stamp.sec == seconds for m in room.sent)
    try:
        room.two_people_found_at_100()
        room.tick(101)
        assert room.spin_until(lambda: sent_at(101) == 1)
        room.tick(50)                                   # a simulator's reset
        for seconds in (51, 52):                        # a turn each: no stall
            room.tick(seconds)
            assert room.spin_until(lambda: sent_at(seconds) == 1)
        room.tick(53)                                   # the dwell's tick and the re-check's
        # the re-check's command, the last one sent then (one publisher: in order)
        assert room.spin_until(lambda: node._room.rechecking
                               and node.core.fixation in room.cells_at(53))
        assert room.cells_at(53) == [node.core.fixation], \
            [room.grid.cell(c) for c in room.cells_at(53)]
    finally:
        room.close()
