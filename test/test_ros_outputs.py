# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The nodes' publishers carry no QoS event handlers; incompatible pairs are still reported.

Each event handler is rebuilt into the executor's wait set on every wake (docs/design.md section
5.1), so only the subscriptions keep rclpy's defaults: an incompatible publisher on an input is
logged by our node, an incompatible subscriber on an output by the subscriber's own node.
"""
from __future__ import annotations

import re
import time

import numpy as np
import pytest

pytestmark = pytest.mark.ros


@pytest.mark.parametrize('module, cls', [('controller', 'GazeControllerNode'),
                                         ('camera', 'SimulatedCameraNode')])
def test_only_subscriptions_keep_event_handlers(context, module, cls):
    import importlib

    from rclpy.event_handler import EventHandler, QoSSubscriptionEventType
    node = getattr(importlib.import_module(f'ipomdp_gaze.nodes.{module}'), cls)(context=context)
    try:
        handlers = [w for w in node.waitables if isinstance(w, EventHandler)]
        assert len(list(node.publishers)) >= 4
        assert len(list(node.subscriptions)) >= 1
        kinds = {type(h.event_type) for h in handlers}
        assert kinds == {QoSSubscriptionEventType}, kinds
        assert len(handlers) <= 2 * len(list(node.subscriptions))
    finally:
        node.destroy_node()


def test_an_incompatible_publisher_on_an_input_is_still_reported(launch, probe):
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float32MultiArray
    cam = launch('camera', ['-p', 'rate_hz:=0.0'])
    best_effort = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
    reliable = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
    probe.publisher(JointState, 'pan_tilt', best_effort)      # the camera asks for reliable
    probe.node.create_subscription(Float32MultiArray, 'evidence', lambda msg: None, reliable)
    said = "New publisher discovered on topic 'pan_tilt', offering incompatible QoS"
    assert probe.wait_until(lambda: said in cam.output(), 30, 0.1), cam.output()[-3000:]
    time.sleep(1.0)
    # The camera's evidence is best effort: this reliable subscriber is told in its own log.
    assert 'requesting incompatible QoS' not in cam.output()


def test_the_belief_map_is_built_only_for_subscribers(context, monkeypatch):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import Float32MultiArray

    from ipomdp_gaze.msg_adapters import grid_arrays
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    packed = []                                 # the belief as it was at each publish
    pack = grid_arrays.to_multiarray
    monkeypatch.setattr(grid_arrays, 'to_multiarray',
                        lambda values, grid: packed.append(np.array(values)) or pack(values, grid))
    # A namespace of its own: no other test's node on this domain reaches its inputs.
    node = GazeControllerNode(context=context, namespace='/belief_only')
    listener = rclpy.create_node('belief_listener', context=context, namespace='/belief_only')
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(listener)
    try:
        node._publish_belief()
        assert packed == []                     # nobody subscribed: nothing built, nothing lost
        received = []
        listener.create_subscription(Float32MultiArray, 'belief',
                                     received.append, 10)
        deadline = time.monotonic() + 30
        while not node._belief_pub.get_subscription_count() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        while not received and time.monotonic() < deadline:
            node._publish_belief()
            executor.spin_once(timeout_sec=0.1)
        assert received and packed
        grid = node._config.grid
        values = grid_arrays.from_multiarray(received[-1], grid)
        assert any(np.allclose(values, sent, rtol=1e-6, atol=0) for sent in packed)
        np.testing.assert_allclose(values, node.core.belief, rtol=1e-6)
    finally:
        executor.shutdown()
        listener.destroy_node()
        node.destroy_node()


def test_a_new_room_frame_republishes_the_people_in_it(context):
    """Known gap: ~/targets kept the old frame_id until the next search of the room ended."""
    import rclpy
    from geometry_msgs.msg import PoseArray
    from ipomdp_gaze.nodes.controller import GazeControllerNode, STATE_QOS
    from ipomdp_gaze.search.room import Person
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    node = GazeControllerNode(context=context, namespace='/room_frame', parameter_overrides=[
        Parameter('search.targets', value='many')])
    listener = rclpy.create_node('room_frame_listener', context=context, namespace='/room_frame')
    received = []
    listener.create_subscription(PoseArray, 'gaze_controller/targets', received.append,
                                 STATE_QOS)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(listener)
    grid = node._config.grid

    def spin_until(condition):
        deadline = time.monotonic() + 30
        while not condition() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        return condition()

    try:
        node._publish_people([Person(grid.index(2, 3), 0.99), Person(grid.index(8, 8), 0.97)])
        assert spin_until(lambda: received and len(received[-1].poses) == 2)
        assert received[-1].header.frame_id == 'pan_tilt_base'
        first = [(p.orientation.z, p.orientation.w) for p in received[-1].poses]
        assert node.set_parameters([Parameter('room.frame_id', value='head_base')])[0].successful
        assert spin_until(lambda: received[-1].header.frame_id == 'head_base')
        assert [(p.orientation.z, p.orientation.w) for p in received[-1].poses] == first
        # A new head mapping: the same people, their poses turned the other way.
        count = len(received)
        assert node.set_parameters([Parameter('pan_sign', value=-1)])[0].successful
        assert spin_until(lambda: len(received) > count)
        assert [(p.orientation.z, p.orientation.w) for p in received[-1].poses] != first
        # One target: ~/targets says nothing more, whatever the frame.
        assert node.set_parameters([Parameter('search.targets', value='one')])[0].successful
        executor.spin_once(timeout_sec=0.2)
        count = len(received)
        assert node.set_parameters([Parameter('room.frame_id', value='other')])[0].successful
        deadline = time.monotonic() + 1.0
        while time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        assert all(m.header.frame_id != 'other' for m in received[count:])
    finally:
        executor.shutdown()
        listener.destroy_node()
        node.destroy_node()


@pytest.mark.parametrize('durability, moves', [('volatile', True), (None, False)])
def test_a_volatile_teleop_drives_the_camera_with_its_qos_overridden(context, durability, moves):
    """The command subscription takes ROS's QoS overrides: volatile matches any publisher."""
    import rclpy
    from ipomdp_gaze.msg_adapters import joints
    from ipomdp_gaze.nodes.camera import SimulatedCameraNode
    from ipomdp_gaze.nodes.qos import STATE_QOS
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    from rclpy.qos import DurabilityPolicy
    from sensor_msgs.msg import JointState
    name = 'qos_overrides./teleop/pan_tilt.subscription.durability'
    overrides = [Parameter('rate_hz', value=0.0)]
    if durability:
        overrides.append(Parameter(name, value=durability))
    camera = SimulatedCameraNode(context=context, namespace='/teleop',
                                 parameter_overrides=overrides)
    teleop = rclpy.create_node('teleop', context=context, namespace='/teleop')
    command = teleop.create_publisher(JointState, 'pan_tilt', 10)     # volatile, reliable
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(camera)
    executor.add_node(teleop)
    head = camera._config.head
    corner = camera._config.grid.index(0, 0)
    try:
        assert camera.get_parameter(name).value == (durability or 'transient_local')
        deadline = time.monotonic() + (20.0 if moves else 2.0)
        while camera.goal != corner and time.monotonic() < deadline:
            command.publish(joints.joint_state(head, corner, camera.get_clock().now().to_msg()))
            executor.spin_once(timeout_sec=0.1)
        assert (camera.goal == corner) is moves
        assert STATE_QOS.durability == DurabilityPolicy.TRANSIENT_LOCAL     # the shared one
    finally:
        executor.shutdown()
        teleop.destroy_node()
        camera.destroy_node()


@pytest.mark.parametrize('policy, value, message', [
    ('durability', 'bogus', 'Unexpected QoS override for policy `durability`: `bogus`'),
    ('depth', -1, 'qos_overrides./pan_tilt.subscription.depth must be >= 1, got -1'),
])
def test_a_bad_qos_override_is_a_value_error_naming_it(context, policy, value, message):
    """QA: rclpy's bare RuntimeError (or rcl's 'invalid allocator') was a start-up traceback."""
    from ipomdp_gaze.nodes.camera import SimulatedCameraNode
    from rclpy.parameter import Parameter
    name = f'qos_overrides./pan_tilt.subscription.{policy}'
    with pytest.raises(ValueError, match=re.escape(message)):
        SimulatedCameraNode(context=context, parameter_overrides=[Parameter(name, value=value)])


def test_the_qos_override_parameters_rebuild_and_log_nothing(context):
    # QA: each of rclpy's qos_overrides.* declarations rebuilt the node's configuration, then
    # logged 'parameters set: qos_overrides./pan_tilt.subscription.durability=...' at start-up.
    from ipomdp_gaze.nodes.camera import SimulatedCameraNode
    from rclpy.parameter import Parameter

    class Counting(SimulatedCameraNode):
        builds = 0

        def _build(self, *args, **kwargs):
            Counting.builds += 1
            return super()._build(*args, **kwargs)

    node = Counting(context=context, parameter_overrides=[Parameter('rate_hz', value=0.0)])
    try:
        assert Counting.builds == 1                         # the start, nothing more
        assert node.get_parameter('qos_overrides./pan_tilt.subscription.depth').value == 1
        assert node.set_parameters([Parameter('seed', value=3)])[0].successful
        assert Counting.builds == 2                         # its own parameters still build
    finally:
        node.destroy_node()
