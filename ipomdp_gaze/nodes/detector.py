# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ``foveal_detector`` node: camera images in, one frame of detection counts per fixation out.

A thin wrapper: :class:`ipomdp_gaze.vision.detection.DetectorLoop` decides which image serves which
fixation and counts its detections, and :mod:`msg_adapters` reads and fills every message
(docs/design.md section 6.6). Two modes (``mode``, read-only):

- ``fovea``: a fixed camera; the grid tiles the image and the digital fovea is placed on the
  fixated cell (the shipped ``faces-420`` model by default);
- ``camera``: a camera on the pan/tilt head; the detector runs on the whole view, its
  detections are binned to pan/tilt cells with ``camera_info``'s K and the head pose of the
  ``joint_states`` message stamped like the image, and cells outside the view are NaN (the
  shipped ``faces-pan-tilt-profile`` model by default).

Relative topic names:

- subscribes ``image`` (``sensor_msgs/Image``: ``mono8``, ``rgb8`` or ``bgr8``; reliable, or
  best effort with ``image_best_effort``; depth 1: the newest wins), ``camera_info``
  (``sensor_msgs/CameraInfo``, ``camera`` mode), ``joint_states`` (``sensor_msgs/JointState``,
  ``camera`` mode) and ``fixation`` (``std_msgs/Int32MultiArray`` ``[row, col, search_id]``,
  ``[-1, -1, search_id]`` for the one-time scan, or an older controller's ``[row, col]``;
  transient local: the controller's);
- publishes ``evidence_image`` (``32FC1``, stamped with the image's capture stamp; NaN = not
  observed; with ``publish_offsets`` in ``camera`` mode ``32FC3``: per cell the count and the
  mean offset ``(row, col)`` of its detections from the cell's centre, in cells, which a
  tracking controller with ``motion.track_view: position`` reads, docs/design.md section 12.9;
  with ``publish_groups`` N > 0 ``32FC4``: those, then how many detections grouped with
  ``min_neighbors`` N are centred in each cell, which a many-target pass names, section 11.7)
  or, with ``publish_image: false``, ``evidence``; and ``/diagnostics``.

A malformed image (another encoding, a step or data length that disagrees with the size, an
empty or oversized image, a stamp that breaks the time sanity rule) is rejected with a throttled
warning naming the reason and counted; so are absurd joint states, ``camera_info`` and
fixations (:mod:`ipomdp_gaze.vision.detection`). Every callback runs under a
:class:`ipomdp_gaze.nodes.guard.CallbackGuard`: an unexpected error is counted
(``callback_errors``) and the node carries on. Run with ``ros2 run ipomdp_gaze detector`` (or
``ipomdp-gaze detector``).
"""
from __future__ import annotations

from dataclasses import dataclass
import sys

from diagnostic_msgs.msg import DiagnosticArray
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays, images, joints, stamps
from ipomdp_gaze.search.controller_config import head_from
from ipomdp_gaze.vision.detection import (build_setup, DetectorLoop, DetectorSetup, MAX_AGE_S,
                                          MODES, STAMP_TOLERANCE_S)
from ipomdp_gaze.vision.detector import describe_detector
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import CameraInfo, Image, JointState
from std_msgs.msg import Float32MultiArray, Int32MultiArray

from . import NODE_NAMES
from .annotation import Annotator
from .guard import CallbackGuard, GuardedNode
from .outputs import QuietPublishers
from .params import joint_params, MAX_CELLS_PER_SIDE, Param, ParameterTransaction, T
from .qos import command_subscription, FRAME_QOS
from .spin import run_node

NODE_NAME = NODE_NAMES['detector']
SENSOR_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
# camera_info comes with every frame: its lens distortion is warned about this seldom.
DISTORTION_WARN_S = 3600.0
# Images are large: over best effort, Fast DDS drops a whole image when one fragment is lost,
# so the subscription is reliable unless the driver only publishes best effort.
IMAGE_QOS = {False: QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE),
             True: SENSOR_QOS}
WARN_THROTTLE_S = 5.0
# A fixation that waits longer than this for a usable image is stuck, not starting up: the log
# says why (camera_info, joint states), and /diagnostics warns.
STUCK_S = 2.0
SETUP_KEYS = ('observation.file', 'grid.rows', 'grid.cols', 'grid.spacing_deg',
              'detector.kind', 'detector.options', 'detector.cascade', 'detector.scale_factor',
              'detector.min_neighbors', 'detector.cascade_dir')


def detector_params() -> list[Param]:
    """Every parameter of the foveal detector, in declaration order."""
    return [
        Param('mode', 'fovea', T.STRING,
              'fovea: a fixed camera, the grid tiles the image; camera: a camera on the pan/tilt '
              'head (read-only)', read_only=True, choices=MODES),
        Param('observation.file', '', T.STRING,
              'count model: an ipomdp_gaze/observation-v1 path or shipped name ("": '
              'faces-420 in fovea mode, faces-pan-tilt-profile in camera mode); its grid, '
              'fovea and detector win'),
        Param('grid.rows', 0, T.INTEGER, "rows (0: the observation file's; read-only)",
              read_only=True, int_range=(0, MAX_CELLS_PER_SIDE)),
        Param('grid.cols', 0, T.INTEGER, "columns (0: the observation file's; read-only)",
              read_only=True, int_range=(0, MAX_CELLS_PER_SIDE)),
        Param('grid.spacing_deg', 0.0, T.DOUBLE,
              "camera mode: pan/tilt degrees per cell (0.0: the observation file's; read-only)",
              read_only=True, float_range=(0.0, 90.0)),
        Param('detector.kind', '', T.STRING,
              'detector kind: haar, yunet, an ipomdp_gaze.detectors entry point or '
              'package.module:Factory, whose code runs ("": the observation file\'s; another '
              'is refused)'),
        Param('detector.options', None, T.STRING_ARRAY,
              'settings of the detector itself as NAME=VALUE (YAML values); each must repeat '
              'the value in the observation file'),
        Param('detector.cascade', '', T.STRING,
              "Haar cascade file name (\"\": the observation file's; another is refused)"),
        Param('detector.scale_factor', 0.0, T.DOUBLE,
              "detectMultiScale scale factor (0.0: the observation file's)",
              float_range=(0.0, 10.0)),
        Param('detector.min_neighbors', -1, T.INTEGER,
              "detectMultiScale minNeighbors (-1: the observation file's)",
              int_range=(-1, 1000)),
        Param('detector.cascade_dir', '', T.STRING,
              'folder holding the Haar cascades ("": cv2.data, then /usr/share/opencv4); one '
              'that does not exist or lacks a cascade is refused, any with a detector that uses '
              'no cascade (YuNet)'),
    ] + joint_params(limits=False) + [
        Param('joint_state_tolerance_s', 0.0, T.DOUBLE,
              'camera mode: pair an image with a joint state stamped at most this far from it '
              '(0: the same stamp)', float_range=(0.0, 1.0)),
        Param('image_best_effort', False, T.BOOL,
              'subscribe image best effort, for a driver that publishes it so (default '
              'reliable: large images lose fragments over best effort; read-only)',
              read_only=True),
        Param('stamp_tolerance_s', STAMP_TOLERANCE_S, T.DOUBLE,
              "images and joint states stamped more than this ahead of the node's clock are "
              'rejected (a camera clock running ahead)', float_range=(0.0, 3600.0)),
        Param('max_image_age_s', MAX_AGE_S, T.DOUBLE,
              'images and joint states stamped more than this before they arrive are rejected '
              'as stale (0: no limit)', float_range=(0.0, 1e6)),
        Param('publish_image', True, T.BOOL,
              'publish stamped 32FC1 evidence_image frames (false: evidence)'),
        Param('publish_offsets', False, T.BOOL,
              "camera mode: evidence_image is 32FC3, each cell's count followed by the mean "
              'offset (row, col) of its detections from the cell centre in cells, NaN where none '
              '(for motion.track_view: position; read-only)', read_only=True),
        Param('publish_groups', 0, T.INTEGER,
              'camera mode, > 0: evidence_image is 32FC4, the 32FC3 channels then how many '
              'detections grouped as detectMultiScale groups with this min_neighbors are centred '
              'in each cell (what a many-target pass names, docs/design.md section 11.7; 0: '
              'none; read-only)', int_range=(0, 1000), read_only=True),
        Param('publish_annotated', False, T.BOOL,
              'publish annotated_image (the camera image with the belief, fixations, fovea '
              'windows, detections and the found cell drawn on it, rgb8) and the raw '
              'detections (geometry_msgs/PoseArray of box centres in pixels; read-only)',
              read_only=True),
        Param('max_image_side_px', images.MAX_IMAGE_SIDE_PX, T.INTEGER,
              'images larger than this on a side are rejected (read-only)', read_only=True,
              int_range=(32, 65536)),
        Param('diagnostics_period_s', 1.0, T.DOUBLE, 'period of /diagnostics',
              float_range=(0.01, 3600.0)),
    ]


@dataclass
class DetectorConfig:
    """What the node derives from its parameters."""

    values: dict
    setup: DetectorSetup
    head: PanTiltMap | None


def _detector_settings(values: dict) -> dict:
    """Return the detector settings given as parameters (unset ones left out)."""
    from ipomdp_gaze.vision.detectors import parse_options
    given = parse_options(values['detector.options'])
    if values['detector.kind']:
        given['kind'] = values['detector.kind']
    if values['detector.cascade']:
        given['cascade'] = values['detector.cascade']
    if values['detector.scale_factor'] > 0:
        given['scale_factor'] = values['detector.scale_factor']
    if values['detector.min_neighbors'] >= 0:
        given['min_neighbors'] = values['detector.min_neighbors']
    return given


class FovealDetectorNode(GuardedNode, QuietPublishers, Node):
    """ROS 2 wrapper of :class:`ipomdp_gaze.vision.detection.DetectorLoop`."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        self.guard = guard = CallbackGuard(self)
        self._transaction = ParameterTransaction(self, detector_params(),
                                                 guard.refusing(self._build),
                                                 guard.wrap(self._apply_config))
        self._transaction.declare()
        self._transaction.start(self._build(self._transaction.values()))
        cfg = self._config
        v = cfg.values
        self.loop = DetectorLoop(cfg.setup, cfg.head, v['joint_state_tolerance_s'],
                                 stamp_tolerance_s=v['stamp_tolerance_s'],
                                 max_age_s=v['max_image_age_s'])
        self._reported = (0, 0, 0)
        self._evidence_pub = self.create_publisher(Float32MultiArray, 'evidence', FRAME_QOS)
        self._image_pub = self.create_publisher(Image, 'evidence_image', FRAME_QOS)
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self.create_subscription(Image, 'image', guard.wrap(self._on_image),
                                 IMAGE_QOS[v['image_best_effort']])
        command_subscription(self, Int32MultiArray, 'fixation', guard.wrap(self._on_fixation))
        if cfg.setup.mode == 'camera':
            self.create_subscription(CameraInfo, 'camera_info', guard.wrap(self._on_camera_info),
                                     SENSOR_QOS)
            self.create_subscription(JointState, 'joint_states',
                                     guard.wrap(self._on_joint_states),
                                     QoSProfile(depth=50,
                                                reliability=ReliabilityPolicy.BEST_EFFORT))
        self._diag_timer = self.create_timer(v['diagnostics_period_s'],
                                             guard.wrap(self._publish_diagnostics))
        self._annotator = Annotator(self) if v['publish_annotated'] else None
        g = cfg.setup.grid
        self.get_logger().info(
            f'{cfg.setup.mode} mode, count model {cfg.setup.name!r} ({g.rows}x{g.cols} grid, '
            f'K = {cfg.setup.model.max_count + 1}), detector '
            f'{describe_detector(cfg.setup.detector)}; waiting for fixation and image')
        for note in cfg.setup.notes:
            self.get_logger().warning(note)

    @property
    def _config(self) -> DetectorConfig:
        """Return the configuration in force."""
        return self._transaction.config

    # -- parameters ----------------------------------------------------------------------
    def _build(self, values: dict, changed=None,
               previous: DetectorConfig | None = None) -> DetectorConfig:
        """Derive a :class:`DetectorConfig` (ValueError names the problem)."""
        if previous is not None and not any(k in changed for k in SETUP_KEYS):
            setup = previous.setup
        else:
            setup = build_setup(
                values['mode'], values['observation.file'],
                (values['grid.rows'], values['grid.cols'], values['grid.spacing_deg']),
                _detector_settings(values), values['detector.cascade_dir'])
        head = head_from(values, setup.grid) if setup.mode == 'camera' else None
        if values['publish_groups'] > 0:
            if setup.mode != 'camera' or not values['publish_image']:
                raise ValueError('publish_groups is for camera mode with publish_image: true '
                                 '(the groups travel in the 32FC4 evidence_image)')
            setup.observer.group_min_neighbors = int(values['publish_groups'])
        return DetectorConfig(dict(values), setup, head)

    def _apply_config(self, old: DetectorConfig, cfg: DetectorConfig) -> None:
        """Follow a new configuration: model, head mapping, tolerance and period."""
        self.loop.set_setup(cfg.setup)
        self.loop.head = cfg.head
        self.loop.tolerance_s = cfg.values['joint_state_tolerance_s']
        self.loop.stamp_tolerance_s = cfg.values['stamp_tolerance_s']
        self.loop.set_max_age(cfg.values['max_image_age_s'])
        if cfg.values['diagnostics_period_s'] != old.values['diagnostics_period_s']:
            self.destroy_timer(self._diag_timer)
            self._diag_timer = self.create_timer(cfg.values['diagnostics_period_s'],
                                                 self.guard.wrap(self._publish_diagnostics))

    # -- inputs --------------------------------------------------------------------------
    def _now_s(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def _stamp_s(self, stamp) -> float:
        """Seconds of a header stamp; its arrival time when the stamp was left at zero."""
        return self._now_s() if stamps.is_zero(stamp) else stamps.to_seconds(stamp)

    def _on_image(self, msg: Image) -> None:
        try:
            pixels = images.image_array(msg, self._config.values['max_image_side_px'])
        except images.ImageError as exc:
            self._handle(self.loop.reject(str(exc)))
            return
        now = self.get_clock().now()
        stamp = msg.header.stamp
        if stamps.is_zero(stamp):
            stamp = now.to_msg()
        self._handle(self.loop.add_image(stamps.to_seconds(stamp), pixels, stamp,
                                         now.nanoseconds * 1e-9))

    def _on_camera_info(self, msg: CameraInfo) -> None:
        try:
            camera = images.camera_from_info(msg)
        except images.ImageError as exc:
            self._handle(self.loop.refuse('camera_info', str(exc)))
            return
        outcome = self.loop.set_camera(camera, self._config.values['max_image_side_px'])
        if self.loop.mismatch:
            self.get_logger().warning(self.loop.mismatch)
            self.loop.mismatch = ''
        if any(float(d) != 0.0 for d in msg.d):
            self.get_logger().warning(
                f'camera_info has lens distortion ({msg.distortion_model or "unnamed model"}): '
                'the detector maps pixels to cells with K alone, so detections near the edge '
                'may land a cell off; give it rectified images (image_proc) and their '
                'camera_info', throttle_duration_sec=DISTORTION_WARN_S)
        self._handle(outcome)

    def _on_joint_states(self, msg: JointState) -> None:
        head = self._config.head
        named = [j for j in (head.pan_joint, head.tilt_joint) if j in msg.name] if head else []
        if not named:
            return              # a joint state of other joints: not the head's
        if len(named) == 1:     # a driver that publishes each joint alone: refused, and said
            other = head.tilt_joint if named[0] == head.pan_joint else head.pan_joint
            self._handle(self.loop.refuse(
                'joint_states', f'it names {named[0]!r} but not {other!r}: both head joints '
                                'must be in one JointState (the pose of one instant)'))
            return
        try:
            pan, tilt = joints.angles_from_joint_state(msg, head)
        except ValueError as exc:
            self._handle(self.loop.refuse('joint_states', str(exc)))
            return
        self._handle(self.loop.add_pose(self._stamp_s(msg.header.stamp), pan, tilt,
                                        self._now_s()))

    def _on_fixation(self, msg: Int32MultiArray) -> None:
        try:
            cell, search_id = grid_arrays.read_fixation(msg, self._config.setup.grid)
        except ValueError as exc:
            self._handle(self.loop.refuse('fixation', str(exc)))
            return
        if cell is None:
            if not self._config.values['publish_image']:
                self._handle(self.loop.refuse(
                    'fixation', 'a scan request needs publish_image: true (a scan frame is '
                                'tagged in evidence_image)'))
                return
            self._handle(self.loop.request_scan(search_id, self._now_s()))
            return
        self._handle(self.loop.fixate(cell, self._now_s(), search_id))

    # -- outputs -------------------------------------------------------------------------
    def _handle(self, outcome) -> None:
        if outcome.status == 'published':
            frame, grid = outcome.frame, self._config.setup.grid
            values = self._config.values
            if values['publish_image']:
                grouped = values['publish_groups'] > 0
                offsets = frame.offsets if values['publish_offsets'] or grouped else None
                self._image_pub.publish(images.evidence_image(
                    frame.counts, grid, frame.token,
                    images.frame_tag(frame.kind, frame.search_id), offsets,
                    frame.groups if grouped else None))
            else:
                self._evidence_pub.publish(grid_arrays.to_multiarray(frame.counts, grid))
            if self._annotator is not None:
                self._annotator.on_frame(frame)
        elif outcome.status == 'rejected':
            self.get_logger().warning(
                f'rejected an image ({self.loop.rejected} so far): {outcome.reason}',
                throttle_duration_sec=WARN_THROTTLE_S)
        elif outcome.status == 'refused':
            refused = sum(counts[1] for counts in self.loop.inputs.values())
            self.get_logger().warning(
                f'ignored a message ({refused} so far): {outcome.reason}',
                throttle_duration_sec=WARN_THROTTLE_S)

    def _warn_if_stuck(self) -> None:
        """
        Say why a fixation waits, once it has waited past the start-up's (:data:`STUCK_S`).

        camera_info or a joint state to pair with the image: the first fixation may come before
        either, so only a wait that lasts is warned about.
        """
        reason = self.loop.waiting
        if not self._stuck():
            return
        if reason.startswith('no camera_info'):
            hint = (f"; is the camera driver's camera_info remapped to "
                    f"{self.resolve_topic_name('camera_info')}?")
        elif reason.startswith('no joint state'):
            hint = (f'; are {self.resolve_topic_name("joint_states")} stamped like the images '
                    '(raise joint_state_tolerance_s to how far apart they are)?')
        elif reason.startswith('no image captured'):
            hint = (f' ({counted(self.loop.received, "image")} received in all); is the camera '
                    f'publishing on {self.resolve_topic_name("image")}'
                    + ('' if self.get_parameter('image_best_effort').value else
                       ' (a best-effort camera needs image_best_effort: true)') + '?')
        else:
            return
        self.get_logger().warning(f'a fixation waits: {reason}{hint}',
                                  throttle_duration_sec=WARN_THROTTLE_S)

    def _stuck(self) -> bool:
        """Whether the waiting fixation has waited longer than :data:`STUCK_S`."""
        return self.loop.waited_s(self._now_s()) > STUCK_S

    def _publish_diagnostics(self) -> None:
        self._warn_if_stuck()
        values = {**self.loop.values(), **self.guard.values()}
        level, message = 'ok', 'serving fixations'
        now = (self.loop.rejected, sum(c[1] for c in self.loop.inputs.values()),
               self.guard.errors)
        new = [b - a for a, b in zip(self._reported, now)]
        if values['waiting_for_image'] and self.loop.waiting.startswith('no camera_info'):
            level, message = 'warn', 'no camera_info received'
        elif values['waiting_for_image'] and self.loop.waiting.startswith('no joint state') \
                and self._stuck():
            level, message = 'warn', 'no joint state pairs with the images'
        elif values['waiting_for_image'] and self.loop.waiting.startswith('no image captured') \
                and self._stuck():
            level, message = 'warn', 'no image arrives'
        elif any(new):
            level = 'warn'
            message = ', '.join(f'{n} {what}' for n, what in zip(
                new, ('images rejected', 'other messages ignored', 'callback errors')) if n)
        self._reported = now
        self._diag_pub.publish(diagnostics.diagnostic_array(
            [diagnostics.status(f'{self.get_fully_qualified_name()}: detector', level, message,
                                values)], self.get_clock().now().to_msg()))


def main(args=None) -> int:
    """Run the ``foveal_detector`` node until shutdown (Ctrl-C or SIGTERM)."""
    return run_node(FovealDetectorNode, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
