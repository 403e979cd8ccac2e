# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The nodes under ``use_sim_time``, whose clock is a ``/clock`` topic.

That clock can start late, pause and jump back (a simulator's reset, ``ros2 bag play --loop``):
the search must go on, and a signal must end a node while the clock is paused.
"""
from __future__ import annotations

import time

import numpy as np
import pytest

pytestmark = pytest.mark.ros


def _spin_until(executor, condition, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while not condition() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    return condition()


def test_a_clock_set_back_keeps_the_search_going_and_a_late_clock_is_no_stall(context):
    """QA: after /clock jumped back every frame was skipped as taken before the head settled."""
    from builtin_interfaces.msg import Time as TimeMsg
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from rosgraph_msgs.msg import Clock
    from std_msgs.msg import Float32MultiArray
    namespace = '/sim_time_jump'
    node = GazeControllerNode(context=context, namespace=namespace, parameter_overrides=[
        Parameter('use_sim_time', value=True), Parameter('settle_time_s', value=0.2),
        Parameter('policy.name', value='elm'), Parameter('evidence_queue_depth', value=10),
        Parameter('retry_period_s', value=0.0)])
    source = Node('sim_time_source', namespace=namespace, context=context)
    from ipomdp_gaze.nodes.controller import STATE_QOS
    from sensor_msgs.msg import JointState
    targets = []
    source.create_subscription(JointState, 'pan_tilt', targets.append, STATE_QOS)
    clock = source.create_publisher(Clock, '/clock', 10)
    evidence = source.create_publisher(Float32MultiArray, 'evidence', 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(source)
    n = node._config.grid.n_cells

    def tick(seconds: float) -> bool:
        clock.publish(Clock(clock=TimeMsg(sec=int(seconds), nanosec=int(seconds % 1 * 1e9))))
        return _spin_until(executor, lambda: abs(node._now_s() - seconds) < 1e-6, 10.0)

    def frame_applied() -> bool:
        before = node.core.counters()
        evidence.publish(Float32MultiArray(data=np.zeros(n, np.float32).tolist()))
        assert _spin_until(executor, lambda: node.core.counters()['received']
                           > before['received'], 10.0)
        return node.core.counters()['applied'] > before['applied']

    try:
        assert _spin_until(executor, lambda: clock.get_subscription_count() > 0
                           and evidence.get_subscription_count() > 0, 30.0)
        assert node._now_s() == 0.0                   # no /clock yet: sim time 0
        assert tick(2000.0)
        # The first tick is a jump of 2000 s: not 2000 s without evidence.
        assert node.core.seconds_without_evidence(node._now_s()) < 1.0
        assert tick(2001.0) and frame_applied()
        assert tick(2002.0) and frame_applied()
        assert tick(100.0) and tick(101.0)            # set back, as a looped bag does
        # The target goes out again on the new clock (retries are off: the detector would
        # otherwise wait from the old one for good).
        assert _spin_until(executor, lambda: targets and targets[-1].header.stamp.sec in
                           (100, 101), 10.0), [t.header.stamp.sec for t in targets]
        assert frame_applied(), node.core.counters()
        assert tick(102.0) and frame_applied()
        assert node.core.seconds_without_evidence(node._now_s()) < 1.0
        # A clock that runs ahead fast (a simulation faster than real time): time that passed.
        assert tick(112.0)
        assert node.core.seconds_without_evidence(node._now_s()) == pytest.approx(10.0)
        assert frame_applied()
    finally:
        executor.shutdown()
        source.destroy_node()
        node.destroy_node()


def test_use_sim_time_turned_on_at_run_time_moves_the_search_to_the_new_clock(context):
    """Review: rcl reports the switch as a jump of 0, so the target stayed at system time."""
    from builtin_interfaces.msg import Time as TimeMsg
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from rosgraph_msgs.msg import Clock
    from std_msgs.msg import Float32MultiArray
    namespace = '/sim_time_switch'
    node = GazeControllerNode(context=context, namespace=namespace, parameter_overrides=[
        Parameter('settle_time_s', value=0.2), Parameter('policy.name', value='elm'),
        Parameter('evidence_queue_depth', value=10)])
    source = Node('sim_time_switch_source', namespace=namespace, context=context)
    clock = source.create_publisher(Clock, '/clock', 10)
    evidence = source.create_publisher(Float32MultiArray, 'evidence', 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(source)
    n = node._config.grid.n_cells
    try:
        assert node._now_s() > 1e9                     # system time
        assert node.set_parameters([Parameter('use_sim_time', value=True)])[0].successful
        assert _spin_until(executor, lambda: clock.get_subscription_count() > 0
                           and evidence.get_subscription_count() > 0, 30.0)
        for seconds in (50.0, 51.0):
            clock.publish(Clock(clock=TimeMsg(sec=int(seconds))))
            assert _spin_until(executor, lambda: node._now_s() == seconds, 10.0)
        assert node.core.target_time_s <= 51.0
        before = node.core.counters()['applied']
        evidence.publish(Float32MultiArray(data=np.zeros(n, np.float32).tolist()))
        assert _spin_until(executor, lambda: node.core.counters()['applied'] > before, 10.0), \
            node.core.counters()
    finally:
        executor.shutdown()
        source.destroy_node()
        node.destroy_node()


@pytest.mark.parametrize('which', ['controller', 'camera'])
def test_a_table_fpoc_takes_its_d_prime_list_as_a_parameter_service_delivers_it(context, which):
    """QA: a list set at run time arrives as array.array('d') and was always refused."""
    from ipomdp_gaze.nodes.camera import SimulatedCameraNode
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    from rcl_interfaces.msg import Parameter as ParameterMsg, ParameterType, ParameterValue
    from rclpy.parameter import Parameter
    make = GazeControllerNode if which == 'controller' else SimulatedCameraNode
    node = make(context=context, namespace=f'/table_fpoc_{which}', parameter_overrides=[
        Parameter('fpoc.model', value='table'), Parameter('fpoc.ecc_deg', value=[0.0, 10.0, 20.0]),
        Parameter('fpoc.dprime', value=[4.0, 2.0, 1.0])])
    try:
        # What the set_parameters service hands the node (ros2 param set does this).
        sent = Parameter.from_parameter_msg(ParameterMsg(name='fpoc.dprime', value=ParameterValue(
            type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=[3.0, 1.5, 0.5])))
        assert type(sent.value).__name__ == 'array'
        result, = node.set_parameters([sent])
        assert result.successful, result.reason
        assert list(node.get_parameter('fpoc.dprime').value) == [3.0, 1.5, 0.5]
        refused, = node.set_parameters([Parameter.from_parameter_msg(ParameterMsg(
            name='fpoc.dprime', value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY,
                                                     double_array_value=[3.0, 1.5])))])
        assert not refused.successful and refused.reason
        assert list(node.get_parameter('fpoc.dprime').value) == [3.0, 1.5, 0.5]
    finally:
        node.destroy_node()


def test_the_wake_up_that_lets_a_signal_end_spin_runs_on_the_steady_clock(context, monkeypatch):
    """QA: on the node's clock (sim time) a paused /clock stopped it, and SIGINT could wait."""
    import rclpy
    from ipomdp_gaze.nodes import spin as spin_module
    from rclpy.clock import ClockType
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    node = Node('wake_on_sim_time', context=context,
                parameter_overrides=[Parameter('use_sim_time', value=True)])
    seen = []
    monkeypatch.setattr(rclpy, 'spin', lambda n: seen.extend(
        (t.clock.clock_type, t.timer_period_ns) for t in n.timers))
    try:
        spin_module.spin(node)
    finally:
        node.destroy_node()
    assert seen == [(ClockType.STEADY_TIME, int(spin_module.WAKE_PERIOD_S * 1e9))]
