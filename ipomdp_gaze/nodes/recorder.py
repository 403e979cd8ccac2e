# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ``recorder`` node: write a search to a rosbag2 bag (MCAP), as ``ros2 bag record -s mcap``.

No ``ros2 bag`` is installable here, so the node writes the bag itself with ``rosbags`` (pure
Python): a directory ``path`` with ``metadata.yaml`` and one ``.mcap`` file in rosbag2's layout
(read here with the ``mcap`` and ``rosbags`` readers). ``max_bag_size_mb`` and
``max_bag_duration_s`` (0: no split, the default) split it as ``ros2 bag record
--max-bag-size/--max-bag-duration`` does, for a long session with a camera: files
``<name>_0.mcap``, ``<name>_1.mcap``, ..., a new one once the file being written holds that many
MB (1e6 bytes on disk; MCAP is written in chunks of about 1 MiB, so a file ends at the first
chunk that reaches it) or a message comes more than that many seconds after the file's first.
``metadata.yaml`` lists every file in ``relative_file_paths`` and ``files`` (path, start,
duration, message count), and each file's messages come before the next one's
(:class:`ipomdp_gaze.files.bag.SplitWriter`), so ``ros2 bag play``, ``rosbags`` and
``ipomdp-gaze replay`` read the files in order as one bag. Messages are recorded serialized (CDR)
as they arrive, timestamped with the time the middleware received them. ``topics`` lists the
relative topic names to record (:data:`TOPICS` gives each one's type and QoS; the default
is every one of them: camera images, ``camera_info``, ``joint_states``, ``fixation``,
``pan_tilt``, ``evidence``, ``evidence_image``, ``belief``, the controller's events ``found``,
``absent``, ``gave_up``, ``lost``, ``reacquired`` and ``room_done``, its people
``gaze_controller/targets`` and ``gaze_controller/target_cells`` (its ``~/targets`` and
``~/target_cells``, many targets), ``/diagnostics``, ``/parameter_events`` (the parameters set
while recording), ``ground_truth``, the scene camera's ``walk_truth`` and the detector's
``annotated_image`` and raw ``detections``). A topic no node publishes in the mode running is
subscribed to and stays empty. The ``pan_tilt`` and ``fixation`` subscriptions (transient local)
take ROS's start-up QoS overrides, as the cameras' and the detector's do: ``-p
qos_overrides./pan_tilt.subscription.durability:=volatile`` records a volatile teleop publisher.
The chunk begun is written and synced every :data:`FLUSH_PERIOD_S` (of the system's clock, also
under ``use_sim_time``), so a recording cut off loses about a second at most: ``ipomdp-gaze
reindex`` recovers the rest. Only the hand-off of the bytes to the system holds the bag's lock;
the ``fsync`` runs on a thread of its own, so on slow storage the executor and the
subscriptions' writes do not wait for it.

The bag's ``custom_data`` (in ``metadata.yaml``) holds ``ipomdp_gaze/version`` (the package),
``ipomdp_gaze/parameters/<node>`` (every parameter of each node in ``nodes``, as YAML, fetched
once they answer; ``ipomdp_gaze/parameters_node/<node>`` the fully qualified name of the node
that answered, ``<namespace>/<node>``, so a replay takes that node's ``/parameter_events``, a
global topic, and not a namesake's in another namespace;
``ipomdp_gaze/parameters_time/<node>`` when the recorder asked for them, in ns of the clock the
messages are stamped with, so a replay applies the ``/parameter_events`` after it),
``ipomdp_gaze/namespace`` (the recorder's: its relative topics and nodes are resolved in it,
``/head1/pan_tilt`` under ``-r __ns:=/head1``) and
``ipomdp_gaze/files`` (the sha256 of each policy and observation file those parameters
name): what ``ipomdp-gaze replay`` needs to re-run the search. Each is also written into the
MCAP file being written as soon as it is known (a metadata record, synced to the disk), so a
recording cut off (power lost, SIGKILL) keeps it: ``ipomdp-gaze reindex`` rebuilds such a bag's
``metadata.yaml`` from its MCAP files. ``compression`` ``zstd``
compresses the MCAP chunks (as rosbag2's ``zstd`` storage presets do; every MCAP
reader decompresses them). ``/diagnostics`` carries ``<node>: recording`` with the messages
written and the publishers matched per topic.
"""
from __future__ import annotations

import hashlib
from pathlib import Path
import sys
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseArray
from ipomdp_gaze.files.bag import MAX_BAG_DURATION_S, MAX_BAG_SIZE_MB
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.msg_adapters import diagnostics
from rcl_interfaces.msg import ParameterEvent
from rcl_interfaces.srv import GetParameters, ListParameters
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import NameValidationException
from rclpy.expand_topic_name import expand_topic_name
from rclpy.node import Node
from rclpy.parameter import parameter_value_to_python
from rclpy.qos import DurabilityPolicy, qos_profile_parameter_events, QoSProfile, \
    ReliabilityPolicy
from rclpy.validate_full_topic_name import validate_full_topic_name
from rclpy.validate_topic_name import validate_topic_name
from sensor_msgs.msg import CameraInfo, Image, JointState
from std_msgs.msg import Float32MultiArray, Float64MultiArray, Int32MultiArray
import yaml

from . import NODE_NAMES
from .guard import CallbackGuard
from .outputs import QuietPublishers
from .params import Param, ParameterTransaction, T
from .qos import command_subscription
from .spin import run_node

NODE_NAME = NODE_NAMES['recorder']
LATCHED = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
BEST_EFFORT = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
EVENT = (DiagnosticStatus, 'diagnostic_msgs/msg/DiagnosticStatus', RELIABLE)
# The controller's private ~/targets and ~/target_cells, relative to the recorder's namespace.
CONTROLLER_TOPIC = NODE_NAMES['controller'] + '/'
# Relative topic -> (message type, ROS type name, QoS of the subscription).
TOPICS = {
    # Images reliable: over best effort a large image is lost whole when one fragment is.
    'image': (Image, 'sensor_msgs/msg/Image', RELIABLE),
    'camera_info': (CameraInfo, 'sensor_msgs/msg/CameraInfo', BEST_EFFORT),
    'joint_states': (JointState, 'sensor_msgs/msg/JointState', BEST_EFFORT),
    'fixation': (Int32MultiArray, 'std_msgs/msg/Int32MultiArray', LATCHED),
    'pan_tilt': (JointState, 'sensor_msgs/msg/JointState', LATCHED),
    'evidence': (Float32MultiArray, 'std_msgs/msg/Float32MultiArray', BEST_EFFORT),
    'evidence_image': (Image, 'sensor_msgs/msg/Image', BEST_EFFORT),
    'belief': (Float32MultiArray, 'std_msgs/msg/Float32MultiArray', RELIABLE),
    'found': EVENT,
    'absent': EVENT,
    'gave_up': EVENT,
    'lost': EVENT,
    'reacquired': EVENT,
    'room_done': EVENT,
    CONTROLLER_TOPIC + 'targets': (PoseArray, 'geometry_msgs/msg/PoseArray', LATCHED),
    CONTROLLER_TOPIC + 'target_cells': (Float32MultiArray, 'std_msgs/msg/Float32MultiArray',
                                        LATCHED),
    '/diagnostics': (DiagnosticArray, 'diagnostic_msgs/msg/DiagnosticArray', RELIABLE),
    '/parameter_events': (ParameterEvent, 'rcl_interfaces/msg/ParameterEvent',
                          qos_profile_parameter_events),
    'ground_truth': (Int32MultiArray, 'std_msgs/msg/Int32MultiArray', LATCHED),
    'walk_truth': (Float64MultiArray, 'std_msgs/msg/Float64MultiArray', RELIABLE),
    'annotated_image': (Image, 'sensor_msgs/msg/Image', RELIABLE),
    'detections': (PoseArray, 'geometry_msgs/msg/PoseArray', RELIABLE),
}
# The commands, which a volatile publisher (a teleop tool) may send: their subscriptions take
# ROS's start-up QoS overrides, as the cameras' and the detector's do (nodes/qos.py).
COMMAND_TOPICS = ('pan_tilt', 'fixation')
FILE_PARAMETERS = ('policy.file', 'observation.file')
PARAMETER_RETRY_S = 0.5
# The bag's chunk begun is written to the disk (synced) this often (s): a recording cut off
# (power lost, SIGKILL) loses at most about this much, not a chunk of up to 1 MiB (minutes of
# evidence without images, and the topics themselves until the first chunk).
FLUSH_PERIOD_S = 1.0
# A parameter request unanswered this long is sent again (s).
PARAMETER_ANSWER_S = 3.0


def recorder_params() -> list[Param]:
    """Every parameter of the recorder, in declaration order."""
    return [
        Param('path', '', T.STRING, 'the bag directory to create (it must not exist; read-only)',
              read_only=True),
        Param('topics', list(TOPICS), T.STRING_ARRAY,
              f"relative topics to record, of: {', '.join(TOPICS)} (read-only)",
              read_only=True),
        Param('nodes', [NODE_NAMES['controller'], NODE_NAMES['detector']], T.STRING_ARRAY,
              "nodes whose parameters go into the bag's metadata (read-only)", read_only=True),
        Param('compression', '', T.STRING,
              "'' (none) or 'zstd' (the MCAP chunks; read-only)", read_only=True,
              choices=('', 'zstd')),
        Param('max_bag_size_mb', 0.0, T.DOUBLE,
              'split the bag: a new MCAP file once the one being written holds this many MB '
              '(1e6 bytes on disk; 0: no split; read-only)', read_only=True,
              float_range=(0.0, MAX_BAG_SIZE_MB)),
        Param('max_bag_duration_s', 0.0, T.DOUBLE,
              'split the bag: a new MCAP file for a message more than this many seconds after '
              "the file's first (0: no split; read-only)", read_only=True,
              float_range=(0.0, MAX_BAG_DURATION_S)),
        Param('diagnostics_period_s', 1.0, T.DOUBLE,
              'period of the recorder: recording status on /diagnostics (messages and '
              'matched publishers per topic; read-only)', read_only=True,
              float_range=(0.01, 3600.0)),
    ]


def split_overrides(max_bag_size_mb: float = 0.0, max_bag_duration_s: float = 0.0) -> list:
    """Return the recorder's ``-p`` arguments of these split limits (none for 0: no split)."""
    out = []
    for name, value in (('max_bag_size_mb', max_bag_size_mb),
                        ('max_bag_duration_s', max_bag_duration_s)):
        if value:
            out += ['-p', f'{name}:={float(value)!r}']
    return out


def node_name(node: str, namespace: str = '/') -> str:
    """
    Return the fully qualified name of a node of ``nodes``, resolved as a topic is.

    A relative name is in the recorder's ``namespace`` (``--ros-args -r __ns:=/head1`` records
    ``/head1/pan_tilt`` and asks ``/head1/gaze_controller``); ``/name`` is absolute.
    """
    if node.startswith('/'):
        return '/' + node.strip('/')
    return namespace.rstrip('/') + '/' + node.strip('/')


def file_hashes(parameters: dict) -> dict:
    """``{name or path: sha256}`` of the policy and observation files named by parameters."""
    from ipomdp_gaze.files.observation_file import resolve_source as observation_source
    from ipomdp_gaze.policies.policy_file import resolve_source as policy_source
    out = {}
    for values in parameters.values():
        for key, resolve in (('policy.file', policy_source),
                             ('observation.file', observation_source)):
            name = values.get(key)
            if not name:
                continue
            try:
                path = Path(resolve(name))
                out[str(name)] = hashlib.sha256(path.read_bytes()).hexdigest()
            except (OSError, ValueError):
                out[str(name)] = 'not found'
    return out


class _Syncer:
    """
    ``fsync`` the bag's handed-off chunks on a thread of its own, off the executor.

    The flush timer's callback runs, as every write does, under the node's callback guard and
    in a single-threaded executor: an ``fsync`` there held every write back for as long as the
    disk took. At most one sync waits besides the one under way; a newer one meanwhile is
    dropped (its duplicates closed), as the next flush hands the file off again.
    """

    def __init__(self, logger):
        self._logger = logger
        self._ready = threading.Condition()
        self._waiting, self._stop = None, False
        self.dropped = 0
        self._thread = threading.Thread(target=self._run, name='recorder-fsync', daemon=True)
        self._thread.start()

    def submit(self, pending) -> bool:
        """Queue ``pending`` (a :class:`~ipomdp_gaze.files.bag.PendingSync`); False: dropped."""
        with self._ready:
            if self._stop or self._waiting is not None:
                self.dropped += 1
                pending.close()
                return False
            self._waiting = pending
            self._ready.notify()
            return True

    def _run(self) -> None:
        while True:
            with self._ready:
                while self._waiting is None and not self._stop:
                    self._ready.wait()
                pending, self._waiting = self._waiting, None
            if pending is None:
                return
            try:
                pending.sync()
            except OSError as exc:          # the disk failed: said, the recording goes on
                self._logger.error(f'could not sync the bag to the disk: {exc}',
                                   throttle_duration_sec=5.0)

    def stop(self, timeout_s: float = 30.0) -> None:
        """Sync what waits, then end the thread (at most ``timeout_s`` for a stuck disk)."""
        with self._ready:
            self._stop = True
            self._ready.notify()
        self._thread.join(timeout_s)


class RecorderNode(QuietPublishers, Node):
    """Subscribe to the search's topics (serialized) and write them to a rosbag2 MCAP bag."""

    def __init__(self, **kwargs):
        # The bag is written by the subscriptions and the parameter answers (executor tasks,
        # in no callback group) and closed by destroy_node, which also destroys the parameter
        # clients and the publisher that the timers and the answers use: in a multi-threaded
        # executor these run at once, so each holds this lock (a writer of None: destroyed).
        self._bag_lock = threading.Lock()
        super().__init__(NODE_NAME, **kwargs)
        # A write that fails (the disk is full) is counted, logged and survived, as every
        # node's callbacks are; the count is in the recording status.
        self.guard = guard = CallbackGuard(self)
        self._transaction = ParameterTransaction(self, recorder_params(), self._build,
                                                 lambda old, new: None)
        self._transaction.declare()
        values = self._transaction.values()
        self._transaction.start(self._build(values))
        from ipomdp_gaze.files.bag import open_writer
        from ipomdp_gaze.files.share_files import package_version
        self.writer = open_writer(values['path'], values['compression'],
                                  max_file_bytes=int(values['max_bag_size_mb'] * 1e6),
                                  max_file_duration_ns=int(values['max_bag_duration_s'] * 1e9))
        self._syncer = _Syncer(self.get_logger())
        self.writer.set_custom_data('ipomdp_gaze/version', package_version())
        # The namespace the relative topics and nodes were resolved in: a replay's too.
        self.writer.set_custom_data('ipomdp_gaze/namespace', self.get_namespace())
        self.connections = {}
        self.counts = dict.fromkeys(values['topics'], 0)
        self.subscriptions_ = {}
        for topic in values['topics']:
            msg_type, type_name, qos = TOPICS[topic]
            self.connections[topic] = self.writer.add_connection(
                self.resolve_topic_name(topic), type_name)
            if topic in COMMAND_TOPICS:
                self.subscriptions_[topic] = command_subscription(
                    self, msg_type, topic, guard.wrap(self._writer_for(topic), 'write'), qos,
                    raw=True)
            else:
                self.subscriptions_[topic] = self.create_subscription(
                    msg_type, topic, guard.wrap(self._writer_for(topic), 'write'), qos, raw=True)
        # By the system's clock, as the messages' times: under use_sim_time a paused or slow
        # simulation's clock would hold the chunk back.
        self.create_timer(FLUSH_PERIOD_S, guard.wrap(self._flush, 'flush'),
                          clock=Clock(clock_type=ClockType.STEADY_TIME))
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self.create_timer(values['diagnostics_period_s'], guard.wrap(self._publish_diagnostics))
        self.parameters: dict = {}
        self._pending = list(values['nodes'])
        self._asked = {}
        self._parameter_clients = {}
        self._parameter_timer = self.create_timer(PARAMETER_RETRY_S,
                                                  guard.wrap(self._ask_parameters))
        self.get_logger().info(f"recording {', '.join(values['topics'])} to {values['path']}")

    def _build(self, values: dict, changed=None, previous=None) -> dict:
        if not values['path']:
            raise ValueError('path is required: the bag directory to create')
        if Path(values['path']).exists():
            raise ValueError(f"path {values['path']} exists; a bag needs a new directory")
        unknown = [t for t in values['topics'] if t not in TOPICS]
        if unknown:
            raise ValueError(f"topics: unknown {', '.join(unknown)}; known: "
                             f"{', '.join(TOPICS)}")
        for node in values['nodes']:
            self._check_node_name(node)
        return dict(values)

    def _check_node_name(self, node: str) -> None:
        """
        Refuse a name of ``nodes`` whose parameter services cannot be named (ValueError).

        Checked as ``create_client`` checks it, which the first ask would otherwise do in a
        timer: an exception out of the spin, with a traceback and the bag begun.
        """
        service = f'{node_name(node, self.get_namespace())}/list_parameters'
        try:
            validate_topic_name(service, is_service=True)
            validate_full_topic_name(expand_topic_name(
                service, self.get_name(), self.get_namespace()), is_service=True)
        except (NameValidationException, ValueError) as exc:
            # rclpy adds the name again with a caret under the fault: its first line only
            reason = str(exc).split('\n')[0].rstrip(':')
            raise ValueError(f'nodes: {node!r} is not a node name ({reason})') from None

    def _writer_for(self, topic: str):
        connection = self.connections[topic]

        def write(data: bytes, info=None) -> None:
            # When the middleware received it (as ros2 bag), not when this callback ran: a
            # busy executor takes the topics in its own order, later. That is the system
            # clock's time, never the simulated one (use_sim_time), and so is the fallback.
            received = info.get('received_timestamp') if isinstance(info, dict) else None
            stamp = int(received) if received else time.time_ns()
            with self._bag_lock:
                if self.writer is None:     # taken before destroy_node closed the bag
                    return
                self.writer.write(connection, stamp, data)
                self.counts[topic] += 1
        return write

    def _flush(self) -> None:
        """
        Write the bag's chunk begun to the disk (:data:`FLUSH_PERIOD_S`).

        Under the lock only the hand-off of the bytes to the operating system; ``fsync`` (slow
        storage: long) runs on the syncer's thread (:class:`_Syncer`), so neither the executor
        nor a message written meanwhile waits for it.
        """
        with self._bag_lock:
            if self.writer is None:
                return
            pending = self.writer.hand_off()
        self._syncer.submit(pending)

    # -- the other nodes' parameters ---------------------------------------------------------
    def _ask_parameters(self) -> None:
        """
        Ask each pending node for its parameters, once both its services are matched.

        Both clients are made at first sight and kept: a request sent before its client has
        matched the service is lost, and a service is discovered some time after the client
        (late under load). A request unanswered after ``PARAMETER_ANSWER_S`` is asked again.
        """
        with self._bag_lock:
            if self.writer is not None:     # else taken before destroy_node: no clients left
                self._ask_pending(time.monotonic())

    def _ask_pending(self, now: float) -> None:
        """Ask the pending nodes (:meth:`_ask_parameters`, under the lock)."""
        for node in list(self._pending):
            asked = self._asked.get(node)
            if asked is not None:
                if now - asked < PARAMETER_ANSWER_S:
                    continue
                del self._asked[node]
            clients = self._parameter_clients.get(node)
            if clients is None:
                name = node_name(node, self.get_namespace())
                clients = self._parameter_clients[node] = (
                    self.create_client(ListParameters, f'{name}/list_parameters'),
                    self.create_client(GetParameters, f'{name}/get_parameters'))
            if not all(c.service_is_ready() for c in clients):
                continue
            self._asked[node] = now
            # The messages' clock (the middleware's receipt: system time), not the node's,
            # which is the simulated time under use_sim_time.
            asked_ns = time.time_ns()
            future = clients[0].call_async(ListParameters.Request())
            future.add_done_callback(lambda f, n=node, t=asked_ns: self._listed(n, f, t))
        if not self._pending:
            self.destroy_timer(self._parameter_timer)

    def _listed(self, node: str, future, asked_ns: int) -> None:
        """Ask ``node`` for the values of the parameters it listed (not once destroyed)."""
        names = list(future.result().result.names)
        with self._bag_lock:
            if self.writer is None:         # answered after destroy_node: no client left
                return
            got = self._parameter_clients[node][1].call_async(
                GetParameters.Request(names=names))
        got.add_done_callback(lambda f: self._got(node, names, f, asked_ns))

    def _got(self, node: str, names: list, future, asked_ns: int) -> None:
        """
        Keep the parameters of ``node``, its full name and when they were asked (``asked_ns``).

        A parameter set after that time is on ``/parameter_events``. One set between the
        request and the answer is already in the answer: its event carries the value kept, so
        a replay sees no change there and takes that value from the start of the recording
        (``/parameter_events`` does not carry the value before; nor does anything hold a change
        made before the recorder asked).
        """
        values = {n: parameter_value_to_python(v) for n, v in zip(names, future.result().values)}
        values = {k: (list(v) if isinstance(v, (list, tuple)) or hasattr(v, 'tolist') else v)
                  for k, v in values.items()}
        values = {k: ([float(x) if isinstance(x, float) else x for x in v]
                      if isinstance(v, list) else v) for k, v in values.items()}
        with self._bag_lock:
            if self.writer is None:         # answered after destroy_node closed the bag
                return
            self.parameters[node] = values
            self.writer.set_custom_data(f'ipomdp_gaze/parameters/{node}',
                                        yaml.safe_dump(values, sort_keys=True))
            self.writer.set_custom_data(f'ipomdp_gaze/parameters_node/{node}',
                                        node_name(node, self.get_namespace()))
            self.writer.set_custom_data(f'ipomdp_gaze/parameters_time/{node}', str(asked_ns))
            self.writer.set_custom_data('ipomdp_gaze/files', yaml.safe_dump(
                file_hashes(self.parameters), sort_keys=True))
            if node in self._pending:
                self._pending.remove(node)
        self.get_logger().info(f'recorded the parameters of {node}')

    def _publish_diagnostics(self) -> None:
        """Publish ``<node>: recording``: messages and matched publishers of each topic."""
        with self._bag_lock:
            if self.writer is None:         # taken before destroy_node: nothing to publish on
                return
            values = {}
            for topic, sub in self.subscriptions_.items():
                name = topic.lstrip('/')
                values[f'messages_{name}'] = self.counts[topic]
                values[f'publishers_{name}'] = sub.get_publisher_count()
            values['parameters_of'] = ','.join(sorted(self.parameters))
            values.update(self.guard.values())
            message = counted(sum(self.counts.values()), 'message')
            if self.guard.errors:
                message += f'; {self.guard.errors} callback errors: {self.guard.last_error}'
            self._diag_pub.publish(diagnostics.diagnostic_array(
                [diagnostics.status(f'{self.get_fully_qualified_name()}: recording',
                                    'warn' if self.guard.errors else 'ok', message, values)],
                self.get_clock().now().to_msg()))

    def destroy_node(self):
        """
        Close the bag (writes metadata.yaml), then destroy the node.

        A write under way (another executor thread) ends first; one that starts later is
        dropped: a node unloaded while its executor spins (composed nodes) neither writes to a
        closed bag nor raises out of the executor's spin.
        """
        with self._bag_lock:
            writer, self.writer = getattr(self, 'writer', None), None
            if writer is not None:
                try:
                    writer.close()
                except OSError as exc:      # the disk is full: the node still goes down
                    self.get_logger().error(f'could not close the bag: {exc}')
        syncer = getattr(self, '_syncer', None)
        if syncer is not None:
            syncer.stop()
        return super().destroy_node()


def main(args=None) -> int:
    """Run the ``recorder`` node until shutdown (Ctrl-C or SIGTERM); the bag is closed then."""
    return run_node(RecorderNode, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
