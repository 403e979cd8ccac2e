# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
No callback can end a node: faults injected into the real nodes' callbacks, in this process.

Each node runs in a context of its own (on this run's domain, in a namespace of its own) and is
spun here by a ``SingleThreadedExecutor`` until what the test waits for has happened. A
callback made to raise is counted (``callback_errors`` with its reason in ``/diagnostics``),
its service still answers (``success: false``), and the node serves the next message.
"""
from __future__ import annotations

import time

import numpy as np
import pytest

pytestmark = pytest.mark.ros


class Rig:
    """A context with the node under test and a ``driver`` node, spun on demand."""

    def __init__(self, ros_env, make_node, namespace):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=int(ros_env['ROS_DOMAIN_ID']), args=[])
        self.node = make_node(context=self.context, namespace=namespace)
        self.driver = Node('driver', context=self.context, namespace=namespace)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.driver)

    def spin_until(self, condition, timeout_s: float = 20.0) -> None:
        deadline = time.monotonic() + timeout_s
        while not condition():
            assert time.monotonic() < deadline, 'timed out'
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        import rclpy
        self.executor.shutdown(timeout_sec=1)
        self.node.destroy_node()
        self.driver.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def detector(ros_env):
    from ipomdp_gaze.nodes.detector import FovealDetectorNode
    rig = Rig(ros_env, FovealDetectorNode, '/guard_fovea')
    yield rig
    rig.close()


def test_an_injected_failing_callback_is_counted_and_the_node_carries_on(detector):
    from diagnostic_msgs.msg import DiagnosticArray
    from ipomdp_gaze.harness.watch import LATCHED
    from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays, images
    from ipomdp_gaze.vision.scenes import PAPER_TASK, SceneSet
    from sensor_msgs.msg import Image
    from std_msgs.msg import Int32MultiArray
    node, driver = detector.node, detector.driver
    grid = node.loop.setup.grid
    statuses, frames = [], []
    driver.create_subscription(DiagnosticArray, '/diagnostics', lambda m: statuses.extend(
        diagnostics.values_of(s) for s in m.status
        if s.name == '/guard_fovea/foveal_detector: detector'), 50)
    from ipomdp_gaze.nodes.detector import FRAME_QOS
    driver.create_subscription(Image, 'evidence_image', frames.append, FRAME_QOS)
    fixation = driver.create_publisher(Int32MultiArray, 'fixation', LATCHED)
    image = driver.create_publisher(Image, 'image', 10)
    fixate = node.loop.fixate

    def broken(cell, now_s, search_id=None):
        raise RuntimeError(f'injected fault at cell {cell}')

    node.loop.fixate = broken
    detector.spin_until(lambda: image.get_subscription_count() > 0)
    fixation.publish(grid_arrays.row_col(grid, 0))
    detector.spin_until(lambda: node.guard.errors == 1)
    assert 'RuntimeError: injected fault at cell 0' in node.guard.last_error
    n = len(statuses)
    detector.spin_until(lambda: len(statuses) > n)
    assert statuses[-1]['callback_errors'] == '1'
    assert statuses[-1]['callback_errors.on_fixation'] == '1'
    assert 'injected fault' in statuses[-1]['last_callback_error']
    # Repaired, the same node serves the next fixation with an image.
    node.loop.fixate = fixate
    fixation.publish(grid_arrays.row_col(grid, grid.index(10, 10)))
    detector.spin_until(lambda: node.loop.pending is not None)
    scene = SceneSet('test', **PAPER_TASK, color='rgb', seed=0).scene(0)
    image.publish(images.camera_image(scene.image, driver.get_clock().now().to_msg()))
    detector.spin_until(lambda: len(frames) == 1)
    counts = images.evidence_from_image(frames[0], grid)      # faces-420: the fovea's windows
    assert np.isfinite(counts[grid.index(10, 10)]) and (counts[~np.isnan(counts)] >= 0).all()
    assert node.guard.errors == 1


def test_a_failing_service_answers_false_and_a_failing_timer_keeps_ticking(ros_env):
    from ipomdp_gaze.nodes.camera import SimulatedCameraNode
    from std_srvs.srv import Trigger
    rig = Rig(ros_env, SimulatedCameraNode, '/guard_camera')
    try:
        node = rig.node

        def broken():
            raise KeyError('no such target')

        node._new_target = broken
        client = rig.driver.create_client(Trigger, 'simulated_camera/reset')
        rig.spin_until(client.service_is_ready)
        future = client.call_async(Trigger.Request())
        rig.spin_until(future.done)
        reply = future.result()
        assert not reply.success and reply.message == "internal error: KeyError: 'no such target'"
        assert node.guard.by_callback['on_reset'] == 1
        # A timer whose callback always fails still fires, each failure counted.
        ticks = []

        def failing_tick():
            ticks.append(1)
            raise ZeroDivisionError('tick')

        node.create_timer(0.01, node.guard.wrap(failing_tick))
        rig.spin_until(lambda: len(ticks) >= 5)
        assert node.guard.by_callback['failing_tick'] == len(ticks)
    finally:
        rig.close()


def test_a_callback_failing_after_shutdown_is_neither_counted_nor_warned():
    """Ctrl-C while a callback publishes: its 'publisher's context is invalid' is no fault."""
    from types import SimpleNamespace
    from ipomdp_gaze.nodes.guard import CallbackGuard
    warnings = []
    context = SimpleNamespace(up=True)
    context.ok = lambda: context.up
    node = SimpleNamespace(context=context, get_logger=lambda: SimpleNamespace(
        warning=lambda text, **_: warnings.append(text)))
    guard = CallbackGuard(node)

    def publish(_msg):
        raise RuntimeError("Failed to publish: publisher's context is invalid")
    guarded = guard.wrap(publish, 'on_evidence_image')
    guarded(None)
    assert guard.errors == 1 and len(warnings) == 1             # running: a fault
    context.up = False
    guarded(None)
    assert guard.errors == 1 and len(warnings) == 1             # shut down: quiet


def test_a_failing_callback_of_two_arguments_that_is_no_service_returns_none():
    """
    QA: a parameter set's ``apply(old, new)`` failing returned ``new``, taken for a service.

    The controller then logged ``parameters set: ...; ControllerConfig(values={...`` (the whole
    configuration, as if it were what the set did). A service still answers its response.
    """
    from types import SimpleNamespace
    from ipomdp_gaze.nodes.guard import CallbackGuard
    from std_srvs.srv import Trigger
    node = SimpleNamespace(context=SimpleNamespace(ok=lambda: True), get_logger=lambda: (
        SimpleNamespace(warning=lambda text, **_: None)))
    guard = CallbackGuard(node)

    def apply(old, new):
        raise OverflowError(34, 'Numerical result out of range')
    assert guard.wrap(apply)(object(), {'confidence': 0.9}) is None
    assert guard.by_callback['apply'] == 1
    reply = guard.wrap(apply, 'on_reset')(Trigger.Request(), Trigger.Response(success=True))
    assert isinstance(reply, Trigger.Response) and not reply.success
    assert reply.message == "internal error: OverflowError: (34, 'Numerical result out of range')"
