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


def test_a_dwell_at_the_moment_of_the_recheck_sends_no_person(context):
    """QA: at 2 s / 2 s the head was sent to a person, then to the pass's first pose at once."""
    from builtin_interfaces.msg import Time as TimeMsg
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import joints
    from ipomdp_gaze.harness.watch import LATCHED
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import JointState
    node = GazeControllerNode(context=context, namespace='/room_turns', cli_args=[
        '--ros-args', '--params-file', config_path('faces_camera_controller.yaml'),
        '--params-file', config_path('faces_camera_room_controller.yaml'),
        '-p', 'use_sim_time:=true', '-p', 'retry_period_s:=0.0',
        '-p', 'room.dwell_s:=2.0', '-p', 'room.recheck_period_s:=2.0'])
    source = Node('room_turns_source', namespace='/room_turns', context=context)
    sent = []
    source.create_subscription(JointState, 'pan_tilt', sent.append, LATCHED)  # keeps 10
    clock = source.create_publisher(Clock, '/clock', 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(source)

    def tick(seconds: int) -> None:
        clock.publish(Clock(clock=TimeMsg(sec=seconds)))
        assert _spin_until(executor, lambda: node._now_s() == seconds)

    grid = node._config.grid
    head = PanTiltMap(grid, 'pan_joint', 'tilt_joint')
    people = [grid.index(3, 7), grid.index(9, 9)]
    try:
        assert _spin_until(executor, lambda: clock.get_subscription_count() > 0, 30.0)
        tick(100)
        # A search of the room ends at 100 s with two people (as the node's own end does).
        node._room.done([{'cell': c, 'probability': 0.9} for c in people])
        node._make_room_timers(node._config.values)
        tick(101)
        before = len(sent)
        tick(102)                                       # the dwell's tick and the re-check's

        def at_102() -> list:
            return [head.nearest_cell(*joints.angles_from_joint_state(m, head))
                    for m in sent[before:] if m.header.stamp.sec == 102]

        # the re-check's command, the last one sent then (one publisher: in order)
        assert _spin_until(executor, lambda: node._room.rechecking
                           and node.core.fixation in at_102())
        assert at_102() == [node.core.fixation], [grid.cell(c) for c in at_102()]
    finally:
        executor.shutdown()
        source.destroy_node()
        node.destroy_node()


def test_a_clock_set_back_restarts_the_turns_and_the_recheck_in_step(context):
    """
    QA: /clock set back from 101 s to 50 s: at 53 s a person and the re-check's pose, at once.

    rcl restarted both timers at 50 s, but the room counted the turns from 100 s: every tick
    was a turn, also the re-check's.
    """
    from builtin_interfaces.msg import Time as TimeMsg
    from ipomdp_gaze.harness.watch import LATCHED
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import joints
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import JointState
    node = GazeControllerNode(context=context, namespace='/room_jump', cli_args=[
        '--ros-args', '--params-file', config_path('faces_camera_controller.yaml'),
        '--params-file', config_path('faces_camera_room_controller.yaml'),
        '-p', 'use_sim_time:=true', '-p', 'retry_period_s:=0.0',
        '-p', 'room.dwell_s:=1.0', '-p', 'room.recheck_period_s:=3.0'])
    source = Node('room_jump_source', namespace='/room_jump', context=context)
    sent = []
    source.create_subscription(JointState, 'pan_tilt', sent.append, LATCHED)  # keeps 10
    clock = source.create_publisher(Clock, '/clock', 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(source)

    def tick(seconds: int) -> None:
        clock.publish(Clock(clock=TimeMsg(sec=seconds)))
        assert _spin_until(executor, lambda: node._now_s() == seconds)

    def sent_at(seconds: int) -> int:
        return sum(m.header.stamp.sec == seconds for m in sent)

    grid = node._config.grid
    head = PanTiltMap(grid, 'pan_joint', 'tilt_joint')
    try:
        assert _spin_until(executor, lambda: clock.get_subscription_count() > 0, 30.0)
        tick(100)
        node._room.done([{'cell': c, 'probability': 0.9}
                         for c in (grid.index(3, 7), grid.index(9, 9))])
        node._make_room_timers(node._config.values)
        tick(101)
        assert _spin_until(executor, lambda: sent_at(101) == 1)
        tick(50)                                        # a simulator's reset
        for seconds in (51, 52):                        # a turn each: no stall
            tick(seconds)
            assert _spin_until(executor, lambda: sent_at(seconds) == 1)
        tick(53)                                        # the dwell's tick and the re-check's

        def at_53() -> list:
            return [head.nearest_cell(*joints.angles_from_joint_state(m, head))
                    for m in sent if m.header.stamp.sec == 53]

        # the re-check's command, the last one sent then (one publisher: in order)
        assert _spin_until(executor, lambda: node._room.rechecking
                           and node.core.fixation in at_53())
        assert at_53() == [node.core.fixation], [grid.cell(c) for c in at_53()]
    finally:
        executor.shutdown()
        source.destroy_node()
        node.destroy_node()
