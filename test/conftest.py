# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Shared fixtures; the ROS ones run real nodes over real DDS, isolated per test run.

Every run gets its own ``ROS_DOMAIN_ID`` (derived from the pytest process id, 0..101), discovery
limited to this host and node log files in a temporary directory. Nodes under test run as
separate processes (as a user runs them); the test's own node (:class:`Probe`) spins a
``SingleThreadedExecutor`` in a thread with a stop flag and is joined at teardown (ROS_NOTES.md
section 7).
"""
from __future__ import annotations

import importlib.util
import os
from pathlib import Path
import threading
import time

from hypothesis import settings
import pytest

# Property tests: the same examples on every CI run (CI=1), fresh ones on a developer's machine.
settings.register_profile('ci', derandomize=True, deadline=None, print_blob=True)
if os.environ.get('CI'):
    settings.load_profile('ci')

HAVE_RCLPY = importlib.util.find_spec('rclpy') is not None
HAVE_ROS_MSGS = importlib.util.find_spec('std_msgs') is not None
# The message adapters need the ROS message packages (the `ros` extra); skip them without it.
collect_ignore = [] if HAVE_ROS_MSGS else ['test_msg_adapters.py']
REPO = Path(__file__).resolve().parents[1]


def wait_for(condition, timeout_s: float = 20.0, interval_s: float = 0.02) -> bool:
    """Poll ``condition()`` until it is true or ``timeout_s`` passes; return its last value."""
    deadline = time.monotonic() + timeout_s
    while True:
        if condition():
            return True
        if time.monotonic() > deadline:
            return bool(condition())
        time.sleep(interval_s)


@pytest.fixture(scope='session')
def ros_env(tmp_path_factory):
    """Environment of an isolated ROS run; this process uses it too (set before rclpy.init)."""
    if not HAVE_RCLPY:
        pytest.skip('rclpy is not installed (pip install -e ".[ros]")')
    from ipomdp_gaze.nodes.processes import domain_id_for, ros_environment
    env = ros_environment(domain_id_for(), tmp_path_factory.mktemp('ros_log'))
    keys = ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOG_DIR', 'ROS_LOCALHOST_ONLY')
    saved = {k: os.environ.get(k) for k in keys}
    for k in keys:
        if k in env:
            os.environ[k] = env[k]
        else:
            os.environ.pop(k, None)
    yield env
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


class Probe:
    """The test's own node: subscriptions that record, publishers, service and parameter calls."""

    def __init__(self, domain_id: int, name: str = 'test_probe'):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id, args=[])
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)

    def close(self):
        """Stop the spin thread, then destroy the node and the context."""
        self._stop.set()
        self._thread.join(timeout=10)
        assert not self._thread.is_alive(), 'the probe spin thread did not stop'
        self.executor.shutdown(timeout_sec=1)
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.context)

    def record(self, msg_type, topic: str, qos=10, distinct_stamps: bool = False) -> list:
        """
        Subscribe and return the list the messages are appended to (as ``(t, msg)``).

        With ``distinct_stamps``, a message with the header stamp of one already recorded (the
        controller's re-sent ``pan_tilt``) is dropped.
        """
        received, stamps = [], set()

        def on_message(msg):
            if distinct_stamps:
                key = (msg.header.stamp.sec, msg.header.stamp.nanosec)
                if key in stamps:
                    return
                stamps.add(key)
            received.append((time.monotonic(), msg))

        self.node.create_subscription(msg_type, topic, on_message, qos)
        return received

    def publisher(self, msg_type, topic: str, qos=10):
        """Create a publisher on ``topic``."""
        return self.node.create_publisher(msg_type, topic, qos)

    def call(self, srv_type, name: str, request, timeout_s: float = 20.0):
        """Call a service and return its response."""
        client = self.node.create_client(srv_type, name)
        try:
            assert client.wait_for_service(timeout_sec=timeout_s), f'no service {name}'
            future = client.call_async(request)
            assert wait_for(future.done, timeout_s), f'{name} did not answer'
            return future.result()
        finally:
            self.node.destroy_client(client)

    def set_parameters(self, node_name: str, values: dict, timeout_s: float = 20.0) -> list:
        """Call SetParameters on another node (what ``ros2 param set`` does); the results."""
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter
        params = []
        for name, value in values.items():
            if isinstance(value, Parameter):
                params.append(value.to_parameter_msg())
            else:
                params.append(Parameter(name, value=value).to_parameter_msg())
        response = self.call(SetParameters, f'/{node_name}/set_parameters',
                             SetParameters.Request(parameters=params), timeout_s)
        return list(response.results)

    def get_parameters(self, node_name: str, names, timeout_s: float = 20.0) -> dict:
        """Call GetParameters on another node: ``{name: python value}``."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python
        response = self.call(GetParameters, f'/{node_name}/get_parameters',
                             GetParameters.Request(names=list(names)), timeout_s)
        return {n: parameter_value_to_python(v) for n, v in zip(names, response.values)}


@pytest.fixture(scope='module')
def probe(ros_env):
    """Provide a :class:`Probe` on this run's domain, shared by the tests of one module."""
    p = Probe(int(ros_env['ROS_DOMAIN_ID']))
    yield p
    p.close()


@pytest.fixture(scope='module')
def launch(ros_env, tmp_path_factory):
    """
    Start nodes as separate processes (each call returns its ``NodeProcess``).

    At teardown every process gets SIGTERM and must exit with status 0 (a clean shutdown).
    """
    from ipomdp_gaze.nodes.processes import NodeProcess
    logs = tmp_path_factory.mktemp('node_output')
    started = []

    def start(node: str, ros_args=()):
        proc = NodeProcess(node, ros_args, ros_env, logs / f'{node}-{len(started)}.log')
        started.append(proc.start())
        return proc

    yield start
    codes = [(p, p.stop()) for p in started]
    bad = [f'{p.node}: exit status {code}\n{p.output()[-3000:]}' for p, code in codes if code]
    assert not bad, 'nodes did not shut down cleanly:\n' + '\n'.join(bad)


def config_path(name: str) -> str:
    """Find a shipped config file as the nodes do."""
    from ipomdp_gaze.nodes.config import config_file
    return str(config_file(name))
