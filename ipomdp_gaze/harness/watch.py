# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Watch running nodes from a process of their own: record topics, call services, wait for things.

:class:`Watch` is a node in a context of its own on the nodes' domain, spun by a
``SingleThreadedExecutor`` in a thread with a stop flag and joined when it is closed (the pattern
measured to work with these rclpy wheels: ROS_NOTES.md section 7). The demo, the tests and the
benches all watch the nodes through it; :class:`SearchRecord` records what a search publishes
and :class:`SearchStatus` follows the controller's ``/diagnostics`` status.
"""
from __future__ import annotations

from collections import deque
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from ipomdp_gaze.harness.processes import wait_for
from ipomdp_gaze.model.belief import is_reset_belief
from ipomdp_gaze.msg_adapters import diagnostics
from ipomdp_gaze.nodes import NODE_NAMES
import numpy as np
from rcl_interfaces.srv import GetParameters, SetParameters, SetParametersAtomically
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float32MultiArray, Int32MultiArray
from std_srvs.srv import SetBool, Trigger

CONTROLLER, CAMERA = NODE_NAMES['controller'], NODE_NAMES['camera']
# What the nodes publish once and keep for late joiners (pan_tilt, ground_truth).
LATCHED = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
SPIN_TIMEOUT_S = 0.02
CALL_POLL_S = 0.001


class Latest:
    """The latest message of a topic and how many arrived (no unbounded list)."""

    def __init__(self):
        self.msg = None
        self.count = 0

    def __call__(self, msg) -> None:
        """Take a message."""
        self.msg = msg
        self.count += 1


class SearchStatus:
    """The latest ``<node>: search`` status of a controller on ``/diagnostics`` (level: int)."""

    def __init__(self, node: str = CONTROLLER):
        self.node = node
        self.suffix = f'{node}: search'
        self.values: dict = {}
        self.level = self.message = None
        self.count = 0
        self.history = deque(maxlen=200)

    def __call__(self, msg: DiagnosticArray) -> None:
        """Take a ``/diagnostics`` message."""
        for status in msg.status:
            if status.name.endswith(self.suffix):
                self.values = diagnostics.values_of(status)
                level = status.level
                self.level = int.from_bytes(level, 'little') if isinstance(level, bytes) \
                    else int(level)
                self.message = status.message
                self.history.append((self.level, self.message))
                self.count += 1

    def counter(self, name: str) -> int:
        """Return the counter ``frames_<name>`` (-1 before the first status)."""
        return int(self.values.get(f'frames_{name}', -1))

    def counters(self) -> dict:
        """Return the frame counters received, applied, rejected, skipped and dropped."""
        return {k: self.counter(k) for k in ('received', 'applied', 'rejected', 'skipped',
                                             'dropped')}

    def wait_fresh(self, timeout_s: float = 20.0) -> dict:
        """
        Wait for a status published after this call; return the counters.

        Raises
        ------
        TimeoutError
            If none came within ``timeout_s``.

        """
        n = self.count
        if not wait_for(lambda: self.count > n + 1, timeout_s):
            raise TimeoutError(f'no /diagnostics from {self.node}')
        return self.counters()


class Watch:
    """
    A node of its own that records what other nodes publish and calls their services.

    Parameters
    ----------
    domain_id : int
        The nodes' ROS domain.
    name : str
        Name of this node.
    nodes : NodeGroup, optional
        Node processes to keep an eye on: :meth:`wait_until` raises
        :class:`ipomdp_gaze.harness.processes.NodeExited` when one of them exits.

    """

    def __init__(self, domain_id: int, name: str = 'watch', nodes=None):
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=int(domain_id), args=[])
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.nodes = nodes
        self._clients = {}
        self._subscriptions: dict = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)

    def __enter__(self) -> 'Watch':
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """
        Stop the spin thread, then destroy the node and the context.

        Raises
        ------
        RuntimeError
            If the spin thread did not stop (the node is left as it is).

        """
        self._stop.set()
        self._thread.join(timeout=10)
        if self._thread.is_alive():
            raise RuntimeError('the watch spin thread did not stop')
        self.executor.shutdown(timeout_sec=1)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    # -- topics ----------------------------------------------------------------------------
    def record(self, msg_type, topic: str, qos=10, distinct_stamps: bool = False,
               keep=None) -> list:
        """
        Subscribe and return the list the messages are appended to (as ``(t, msg)``).

        ``t`` is ``time.monotonic()`` at arrival. With ``distinct_stamps``, a message with the
        header stamp of one already recorded (the controller's re-sent ``pan_tilt``) is dropped;
        with ``keep``, a message for which ``keep(msg)`` is false.
        """
        received, stamps = [], set()

        def on_message(msg):
            if keep is not None and not keep(msg):
                return
            if distinct_stamps:
                key = (msg.header.stamp.sec, msg.header.stamp.nanosec)
                if key in stamps:
                    return
                stamps.add(key)
            received.append((time.monotonic(), msg))

        self._subscribe(msg_type, topic, on_message, qos)
        return received

    def latest(self, msg_type, topic: str, qos=10) -> Latest:
        """Subscribe and keep only the latest message and the count."""
        latest = Latest()
        self._subscribe(msg_type, topic, latest, qos)
        return latest

    def _subscribe(self, msg_type, topic: str, callback, qos) -> None:
        subscription = self.node.create_subscription(msg_type, topic, callback, qos)
        self._subscriptions.setdefault(topic, []).append(subscription)

    def matched(self, topic: str) -> int:
        """
        Return how many publishers every subscription of this watch on ``topic`` has matched.

        The least count over them (0 without a subscription): a publisher known from the graph
        may not be matched yet, and what it sends before it is lost (volatile topics).
        """
        subscriptions = self._subscriptions.get(topic, [])
        return min((s.get_publisher_count() for s in subscriptions), default=0)

    def search_status(self, node: str = CONTROLLER) -> SearchStatus:
        """Follow the ``search`` status of a controller on ``/diagnostics``."""
        status = SearchStatus(node)
        self.node.create_subscription(DiagnosticArray, '/diagnostics', status, 50)
        return status

    def status_values(self, suffix: str) -> list:
        """Collect the values of every ``/diagnostics`` status whose name ends with ``suffix``."""
        values = []

        def on_diagnostics(msg: DiagnosticArray) -> None:
            values.extend(diagnostics.values_of(item) for item in msg.status
                          if item.name.endswith(suffix))
        self.node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics, 50)
        return values

    def publisher(self, msg_type, topic: str, qos=10):
        """Create a publisher on ``topic``."""
        return self.node.create_publisher(msg_type, topic, qos)

    # -- services --------------------------------------------------------------------------
    def call(self, srv_type, name: str, request, timeout_s: float = 30.0):
        """
        Call a service and return its response (one client per service, kept).

        Raises
        ------
        TimeoutError
            If the service is not there or does not answer within ``timeout_s``.

        """
        client = self._clients.get((srv_type, name))
        if client is None:
            client = self._clients[srv_type, name] = self.node.create_client(srv_type, name)
        if not client.service_is_ready() and not client.wait_for_service(timeout_sec=timeout_s):
            raise TimeoutError(f'no service {name}')
        future = client.call_async(request)
        if not wait_for(future.done, timeout_s, CALL_POLL_S):
            raise TimeoutError(f'{name} did not answer')
        return future.result()

    def reset(self, node: str = CONTROLLER):
        """Call ``~/reset`` of a node (``std_srvs/Trigger``); return the response."""
        return self.call(Trigger, f'/{node}/reset', Trigger.Request())

    def enable(self, flag: bool, node: str = CONTROLLER):
        """Call ``~/enable`` of a controller (``std_srvs/SetBool``); return the response."""
        return self.call(SetBool, f'/{node}/enable', SetBool.Request(data=bool(flag)))

    def set_parameters(self, node: str, params, timeout_s: float = 30.0) -> list:
        """
        Set parameters of another node one by one (what ``ros2 param set`` does); the results.

        ``params`` is a list of ``rclpy.parameter.Parameter`` or a dict ``{name: value}`` (a
        value may be a ``Parameter`` too).
        """
        request = SetParameters.Request(parameters=_parameter_msgs(params))
        return list(self.call(SetParameters, f'/{node}/set_parameters', request,
                              timeout_s).results)

    def set_parameters_atomically(self, node: str, params, timeout_s: float = 30.0):
        """Set parameters of another node all or none; return the result."""
        request = SetParametersAtomically.Request(parameters=_parameter_msgs(params))
        return self.call(SetParametersAtomically, f'/{node}/set_parameters_atomically', request,
                         timeout_s).result

    def get_parameters(self, node: str, names, timeout_s: float = 30.0) -> dict:
        """Get parameters of another node: ``{name: python value}``."""
        names = list(names)
        response = self.call(GetParameters, f'/{node}/get_parameters',
                             GetParameters.Request(names=names), timeout_s)
        return {n: parameter_value_to_python(v) for n, v in zip(names, response.values)}

    # -- waiting -----------------------------------------------------------------------------
    def wait_until(self, condition, timeout_s: float = 20.0, interval_s: float = 0.02) -> bool:
        """
        Poll ``condition()`` every ``interval_s`` until it is true (True) or ``timeout_s`` passes.

        Raises
        ------
        NodeExited
            When a node process of :attr:`nodes` exits meanwhile.

        """
        deadline = time.monotonic() + timeout_s
        while not condition():
            if time.monotonic() > deadline:
                return False
            if self.nodes is not None:
                self.nodes.check()
            time.sleep(interval_s)
        return True


def quiet_condition(lists, quiet_s: float):
    """
    Return a condition for :meth:`Watch.wait_until`: none of ``lists`` grew for ``quiet_s``.

    For a node that was told to stop sending (a disabled controller): once its topics are quiet,
    nothing it sent before is still in flight.
    """
    state = {'lengths': [len(x) for x in lists], 'since': time.monotonic()}

    def quiet() -> bool:
        lengths = [len(x) for x in lists]
        if lengths != state['lengths']:
            state['lengths'], state['since'] = lengths, time.monotonic()
        return time.monotonic() - state['since'] >= quiet_s
    return quiet


def _parameter_msgs(params) -> list:
    if isinstance(params, dict):
        params = [v if isinstance(v, Parameter) else Parameter(k, value=v)
                  for k, v in params.items()]
    return [p.to_parameter_msg() for p in params]


def is_update(msg: Float32MultiArray, priors=()) -> bool:
    """
    Whether a ``belief`` is the result of a fixation, not a reset.

    A reset's belief is uniform, or at the prior in force: ``priors`` are the controller's
    ``belief.prior`` values as probabilities (N,), as replay takes the recorded ones.
    """
    return not is_reset_belief(msg.data, priors)


class SearchRecord:
    """
    What the controller and the camera publish during searches, as ``(t, msg)`` lists.

    ``beliefs`` (``belief``, keep-last ``depth``; with ``updates_only`` not the belief of a
    reset, uniform or at one of ``priors``: :func:`is_update`; with ``n_cells`` only beliefs of
    that many cells, not a previous run's grid), ``targets`` (``pan_tilt``, latched, each sent
    target once), ``found``, ``absent`` and ``truth`` (the camera's ``ground_truth``, latched).
    """

    def __init__(self, watch: Watch, depth: int = 200, updates_only: bool = False,
                 n_cells: int | None = None, priors=()):
        priors = tuple(priors)

        def keep(msg) -> bool:
            fits = n_cells is None or len(msg.data) == n_cells    # not another run's grid
            return fits and (not updates_only or is_update(msg, priors))
        self.beliefs = watch.record(Float32MultiArray, 'belief', depth, keep=keep)
        self.targets = watch.record(JointState, 'pan_tilt', LATCHED, distinct_stamps=True)
        self.found = watch.record(DiagnosticStatus, 'found', 10)
        self.absent = watch.record(DiagnosticStatus, 'absent', 10)
        self.truth = watch.record(Int32MultiArray, 'ground_truth', LATCHED)

    def belief(self, i: int = -1) -> np.ndarray:
        """Return belief ``i`` as float64 probabilities."""
        return np.asarray(self.beliefs[i][1].data, dtype=np.float64)

    def reached(self, probability: float, since: int = 0) -> int | None:
        """Index of the first belief from ``since`` on whose most likely cell reaches it."""
        return next((i for i in range(since, len(self.beliefs))
                     if np.max(np.asarray(self.beliefs[i][1].data)) >= probability), None)
