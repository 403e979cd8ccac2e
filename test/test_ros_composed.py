# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Nodes composed in one process and spun by a ``MultiThreadedExecutor`` (QA, composition).

A team (or a component container) runs our nodes with other nodes in one process, on several
threads: another node's callback then runs beside ours, a done-callback of a service answer runs
in no callback group, and a node may be unloaded (``remove_node``, ``destroy_node``) while one of
its callbacks is under way. Each test holds a callback where the race happens (an event, never a
sleep), so that the outcome does not depend on the machine's speed.
"""
import threading

import pytest

pytestmark = pytest.mark.ros

WAIT_S = 30.0


class _Spinner:
    """Spin a ``MultiThreadedExecutor`` in a thread; keep what its spin raised."""

    def __init__(self, context, nodes, threads: int = 4):
        from rclpy.executors import MultiThreadedExecutor
        self.executor = MultiThreadedExecutor(num_threads=threads, context=context)
        for node in nodes:
            self.executor.add_node(node)
        self.errors = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        while not self._stop.is_set():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception as exc:  # noqa: B902 (what a team's spin would have raised)
                self.errors.append(exc)

    def close(self):
        self._stop.set()
        self._thread.join(WAIT_S)
        self.executor.shutdown(timeout_sec=WAIT_S)


def test_a_recorder_unloaded_during_a_write_closes_its_bag_after_the_write(context, tmp_path):
    """
    QA: destroy_node closed the bag under a write on another thread; the write then raised.

    (``WriterError: Bag was not opened``, or ``AttributeError`` on the writer set to None,
    raised out of the team's ``spin``; a write during the close could corrupt the bag.)
    """
    from ipomdp_gaze.files.bag import read_bag
    from ipomdp_gaze.nodes.recorder import RecorderNode, TOPICS
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from sensor_msgs.msg import JointState
    recorder = RecorderNode(context=context, namespace='/unload', parameter_overrides=[
        Parameter('path', value=str(tmp_path / 'bag')), Parameter('topics', value=['pan_tilt']),
        Parameter('nodes', value=['nobody'])])
    source = Node('unload_source', namespace='/unload', context=context)
    target = source.create_publisher(JointState, 'pan_tilt', TOPICS['pan_tilt'][2])
    entered, release, failures = threading.Event(), threading.Event(), []
    write = recorder.writer.write

    def held_write(*args):
        entered.set()
        release.wait(WAIT_S)
        try:
            write(*args)
        except Exception as exc:  # noqa: B902
            failures.append(exc)
            raise
    recorder.writer.write = held_write
    spinner = _Spinner(context, [recorder, source])
    unloading = threading.Thread(target=recorder.destroy_node)
    try:
        target.publish(JointState(name=['pan', 'tilt'], position=[0.1, 0.2]))
        assert entered.wait(WAIT_S), 'the recorder never received the message'
        spinner.executor.remove_node(recorder)
        unloading.start()
        unloading.join(1.0)     # the unfixed destroy_node has closed the bag by now
        release.set()
        unloading.join(WAIT_S)
        assert not unloading.is_alive()
    finally:
        release.set()
        spinner.close()
        source.destroy_node()
    assert failures == [] and spinner.errors == []
    assert len(read_bag(tmp_path / 'bag').topic('/unload/pan_tilt')) == 1


class _HeldOffer:
    """Hold the controller's next ``core.offer`` until released; note the confidence after."""

    def __init__(self, node):
        self.node, self.offer = node, node.core.offer
        self.entered, self.release, self.returned = (threading.Event(), threading.Event(),
                                                     threading.Event())
        self.confidence = None
        node.core.offer = self

    def __call__(self, *args, **kwargs):
        self.entered.set()
        self.release.wait(WAIT_S)
        try:
            return self.offer(*args, **kwargs)
        finally:
            self.confidence = self.node._config.values['confidence']
            self.node.core.offer = self.offer
            self.returned.set()


def _held_controller(context, namespace):
    """Return a controller, a source node, its held ``core.offer`` and a frame publisher."""
    import numpy as np
    from ipomdp_gaze.msg_adapters import grid_arrays
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from std_msgs.msg import Float32MultiArray
    node = GazeControllerNode(context=context, namespace=namespace, parameter_overrides=[
        Parameter('settle_time_s', value=0.0), Parameter('retry_period_s', value=0.0)])
    source = Node('evidence_source', namespace=namespace, context=context)
    held = _HeldOffer(node)
    frame = grid_arrays.to_multiarray(np.zeros(node._config.grid.n_cells, np.float32),
                                      node._config.grid)
    evidence = source.create_publisher(Float32MultiArray, 'evidence', 10)
    return node, source, held, lambda: evidence.publish(frame)


def test_set_parameters_from_another_thread_waits_for_the_callback_under_way(context):
    """
    QA: a node's ``set_parameters`` called beside its evidence callback rebuilt it mid-frame.

    (Another node's callback on a ``MultiThreadedExecutor``; with ``search.targets`` switched
    under a frame, ``AttributeError: 'SearchSession' object has no attribute 'faces'``.)
    """
    from rclpy.parameter import Parameter
    node, source, held, publish = _held_controller(context, '/set_beside')
    spinner = _Spinner(context, [node, source])
    setter = threading.Thread(target=node.set_parameters,
                              args=([Parameter('confidence', value=0.9)],))
    try:
        while not held.entered.wait(0.1):       # best effort: resent until the node hears it
            publish()
        setter.start()
        setter.join(1.0)    # the unfixed set has rebuilt the configuration by now
        held.release.set()
        setter.join(WAIT_S)
        assert held.returned.wait(WAIT_S) and not setter.is_alive()
    finally:
        held.release.set()
        spinner.close()
        node.destroy_node()
        source.destroy_node()
    assert held.confidence == 0.95                      # the frame ran on one configuration
    assert node._config.values['confidence'] == 0.9     # and the set came after it
    assert node.guard.errors == 0 and spinner.errors == []


def test_a_controller_destroyed_during_a_callback_destroys_after_it(context):
    """QA: destroy_node under an evidence callback made it publish on destroyed publishers."""
    node, source, held, publish = _held_controller(context, '/destroy_beside')
    spinner = _Spinner(context, [node, source])
    unloading = threading.Thread(target=node.destroy_node)
    try:
        while not held.entered.wait(0.1):
            publish()
        spinner.executor.remove_node(node)
        unloading.start()
        unloading.join(1.0)     # the unfixed destroy_node has destroyed the publishers by now
        held.release.set()
        unloading.join(WAIT_S)
        assert held.returned.wait(WAIT_S) and not unloading.is_alive()
    finally:
        held.release.set()
        spinner.close()
        source.destroy_node()
    assert node.core.fixations == 1      # the frame was applied, its fixation published
    assert node.guard.errors == 0, node.guard.last_error
    assert spinner.errors == []


def test_a_parameter_answer_after_the_recorder_is_unloaded_does_nothing(context, tmp_path):
    """
    An answer or a timer taken before ``destroy_node`` that runs after it does nothing.

    (``_listed`` sent its GetParameters on the destroyed client, the timers' ``_ask_parameters``
    and ``_publish_diagnostics`` used the destroyed clients, subscriptions and publisher:
    ``InvalidHandle`` out of the team's spin.)
    """
    from ipomdp_gaze.nodes.recorder import RecorderNode
    from rcl_interfaces.srv import ListParameters
    from rclpy.parameter import Parameter
    from rclpy.task import Future
    recorder = RecorderNode(context=context, namespace='/late_answer', parameter_overrides=[
        Parameter('path', value=str(tmp_path / 'bag')), Parameter('topics', value=['pan_tilt']),
        Parameter('nodes', value=['nobody'])])
    recorder._ask_parameters()              # its clients made: the services are not there
    answer = Future()
    answer.set_result(ListParameters.Response())
    recorder.destroy_node()
    recorder._listed('nobody', answer, 0)   # a done-callback already queued
    recorder._ask_parameters()              # a timer callback already taken
    recorder._publish_diagnostics()         # and the other timer's
    assert recorder.parameters == {}
