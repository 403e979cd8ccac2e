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


class SimClockRig:
    """An in-process controller and a node of this test that drives /clock and the evidence."""

    def __init__(self, context, namespace: str, **parameters):
        from ipomdp_gaze.nodes.controller import GazeControllerNode, STATE_QOS
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from rclpy.parameter import Parameter
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float32MultiArray
        parameters = {'settle_time_s': 0.2, 'policy.name': 'elm', 'evidence_queue_depth': 10,
                      **parameters}
        self.node = GazeControllerNode(context=context, namespace=namespace, parameter_overrides=[
            Parameter(name, value=value) for name, value in parameters.items()])
        self.source = Node(f'{namespace.strip("/")}_source', namespace=namespace,
                           context=context)
        self.targets = []
        self.source.create_subscription(JointState, 'pan_tilt', self.targets.append, STATE_QOS)
        self.clock = self.source.create_publisher(Clock, '/clock', 10)
        self.evidence = self.source.create_publisher(Float32MultiArray, 'evidence', 10)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.source)

    def spin_until(self, condition, timeout_s: float = 10.0) -> bool:
        return _spin_until(self.executor, condition, timeout_s)

    def connected(self) -> bool:
        return self.spin_until(lambda: self.clock.get_subscription_count() > 0
                               and self.evidence.get_subscription_count() > 0, 30.0)

    def tick(self, seconds: float) -> bool:
        """Publish /clock at ``seconds``; whether the controller's clock reads it."""
        from builtin_interfaces.msg import Time as TimeMsg
        from rosgraph_msgs.msg import Clock
        self.clock.publish(Clock(clock=TimeMsg(sec=int(seconds),
                                               nanosec=int(seconds % 1 * 1e9))))
        return self.spin_until(lambda: abs(self.node._now_s() - seconds) < 1e-6)

    def frame_applied(self) -> bool:
        """Send a frame of zeros; whether the controller applied it (not skipped)."""
        from std_msgs.msg import Float32MultiArray
        core = self.node.core
        before = core.counters()
        n = self.node._config.grid.n_cells
        self.evidence.publish(Float32MultiArray(data=np.zeros(n, np.float32).tolist()))
        assert self.spin_until(lambda: core.counters()['received'] > before['received'])
        return core.counters()['applied'] > before['applied']

    def close(self) -> None:
        self.executor.shutdown()
        self.source.destroy_node()
        self.node.destroy_node()


def test_a_clock_set_back_keeps_the_search_going_and_a_late_clock_is_no_stall(context):
    """QA: after /clock jumped back every frame was skipped as taken before the head settled."""
    rig = SimClockRig(context, '/sim_time_jump', use_sim_time=True, retry_period_s=0.0)
    node = rig.node
    try:
        assert rig.connected()
        assert node._now_s() == 0.0                   # no /clock yet: sim time 0
        assert rig.tick(2000.0)
        # The first tick is a jump of 2000 s: not 2000 s without evidence.
        assert node.core.seconds_without_evidence(node._now_s()) < 1.0
        assert rig.tick(2001.0) and rig.frame_applied()
        assert rig.tick(2002.0) and rig.frame_applied()
        assert rig.tick(100.0) and rig.tick(101.0)    # set back, as a looped bag does
        # The target goes out again on the new clock (retries are off: the detector would
        # otherwise wait from the old one for good).
        assert rig.spin_until(lambda: rig.targets and rig.targets[-1].header.stamp.sec in
                              (100, 101)), [t.header.stamp.sec for t in rig.targets]
        assert rig.frame_applied(), node.core.counters()
        assert rig.tick(102.0) and rig.frame_applied()
        assert node.core.seconds_without_evidence(node._now_s()) < 1.0
        # A clock that runs ahead fast (a simulation faster than real time): time that passed.
        assert rig.tick(112.0)
        assert node.core.seconds_without_evidence(node._now_s()) == pytest.approx(10.0)
        assert rig.frame_applied()
    finally:
        rig.close()


def test_use_sim_time_turned_on_at_run_time_moves_the_search_to_the_new_clock(context):
    """Review: rcl reports the switch as a jump of 0, so the target stayed at system time."""
    from rclpy.parameter import Parameter
    rig = SimClockRig(context, '/sim_time_switch')
    node = rig.node
    try:
        assert node._now_s() > 1e9                     # system time
        assert node.set_parameters([Parameter('use_sim_time', value=True)])[0].successful
        assert rig.connected()
        assert rig.tick(50.0) and rig.tick(51.0)
        assert node.core.target_time_s <= 51.0
        assert rig.frame_applied(), node.core.counters()
    finally:
        rig.close()


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
