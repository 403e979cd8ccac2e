# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The detector's ``annotated_image`` (the search drawn on the camera image) and ``detections``.

:class:`Annotator` is attached to the ``foveal_detector`` node when ``publish_annotated`` is
true (off by default: drawing costs about 3-7 ms a frame, ``bench/faces/annotate.py``). It follows
the
controller's ``belief`` and ``found`` and keeps the fixations of the current search (a uniform
belief, sent at every reset, starts a new one); for every frame the detector publishes, and again
for every belief and ``found`` that follows it, it publishes ``annotated_image`` (``rgb8``, at the
camera's resolution, stamped like the camera image): the drawing of
:func:`ipomdp_gaze.vision.annotate.annotate`, for ``rqt_image_view`` and Foxglove. With every
frame it also publishes the raw detections on ``detections`` (``geometry_msgs/PoseArray``,
stamped like the camera image: one pose per raw detection, ``position.x, position.y`` its box
centre in image pixels, OpenCV / ROS pixel coordinates). Nothing is drawn or sent to a topic
nobody subscribes to.
"""
from __future__ import annotations

from collections import deque

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Point, Pose, PoseArray
from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays, images
from ipomdp_gaze.vision.annotate import annotate, fovea_cell_map, view_cell_map
import numpy as np
from sensor_msgs.msg import Image
from std_msgs.msg import Float32MultiArray, Header

TOPIC = 'annotated_image'
# Fixations drawn: the newest of the search (a tracking search never ends, and each frame
# draws every fixation kept).
MAX_DRAWN = 100


class Annotator:
    """Draw each served frame with the belief, fixations, detections and answer; publish it."""

    def __init__(self, node):
        self.node = node
        self.publisher = node.create_publisher(Image, TOPIC, 2)
        self.detections = node.create_publisher(PoseArray, 'detections', 10)
        # under the node's guard, as its other callbacks: counted if they fail, one at a time
        node.create_subscription(Float32MultiArray, 'belief', node.guard.wrap(self._on_belief),
                                 10)
        node.create_subscription(DiagnosticStatus, 'found', node.guard.wrap(self._on_found), 10)
        self.fixations: deque = deque(maxlen=MAX_DRAWN)
        self.count = 0                  # fixations of this search, MAX_DRAWN of them kept
        self.search_id = None
        self.belief = None
        self.found = None
        self.found_label = 'found'
        self.found_radius = 0
        self.frame = None
        self.published = 0

    @property
    def _loop(self):
        return self.node.loop

    def on_frame(self, frame) -> None:
        """Take a frame the detector just published and draw it."""
        self.frame = frame
        if frame.search_id is not None and frame.search_id != self.search_id:
            # a new search: a reset at a prior that is not uniform sends no uniform belief
            self.search_id = frame.search_id
            self._new_search()
        if frame.fixation is not None and (not self.fixations
                                           or self.fixations[-1] != frame.fixation):
            self.fixations.append(int(frame.fixation))
            self.count += 1
        if frame.detections_px is not None and self.detections.get_subscription_count() > 0:
            msg = PoseArray(header=Header(stamp=frame.token))
            msg.poses = [Pose(position=Point(x=float(x), y=float(y)))
                         for x, y in np.asarray(frame.detections_px, dtype=float).reshape(-1, 2)]
            self.detections.publish(msg)
        self._publish()

    def _on_belief(self, msg: Float32MultiArray) -> None:
        grid = self._loop.setup.grid
        try:
            belief = grid_arrays.from_multiarray(msg, grid)
        except ValueError:
            return
        if np.ptp(belief) == 0:                    # a reset: a new search
            self._new_search()
            self.frame = None
        self.belief = np.asarray(belief, dtype=np.float64)
        self._publish()

    def _new_search(self) -> None:
        self.fixations.clear()
        self.count, self.found = 0, None

    def _on_found(self, msg: DiagnosticStatus) -> None:
        try:
            found = diagnostics.parse_found(msg)
        except (KeyError, ValueError):
            return
        self.found = (int(found['cell']), float(found['probability']))
        self.found_label = 'found, forced' if found['ended'].startswith('forced:') else 'found'
        self.found_radius = found['radius']
        self._publish()

    def _publish(self) -> None:
        """Draw the last frame with what is known now, if there is a frame and a listener."""
        frame = self.frame
        if frame is None or frame.image is None or self.publisher.get_subscription_count() == 0:
            return
        grid = self._loop.setup.grid
        height, width = frame.image.shape[:2]
        if frame.head_rc is not None and self._loop.camera is not None:
            cell_map = view_cell_map(grid, self._loop.camera, frame.head_rc)
        else:
            cell_map = fovea_cell_map(grid, width, height)
        windows = [(*w.rect_px, w.whole_image) for w in frame.windows]
        picture = annotate(frame.image, cell_map, self.belief, self.fixations, windows,
                           frame.detections_px, self.found,
                           label=f'fixation {self.count}',
                           found_label=self.found_label, found_radius=self.found_radius)
        self.publisher.publish(images.camera_image(picture, frame.token))
        self.published += 1
