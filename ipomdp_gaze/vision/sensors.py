# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Sensors over pixels (:class:`ipomdp_gaze.search.sensors.Sensor`).

The fovea over a still image, and the pan/tilt head's camera looking around a scene.

Both run a real detector and count its raw detections per cell, exactly as the ROS detector node
does (:mod:`ipomdp_gaze.vision.detection`), so an offline search through them is the node's search
without the transport.
"""
from __future__ import annotations

from ipomdp_gaze.model.head_camera import PinholeCamera
from ipomdp_gaze.search.session import Frame
from ipomdp_gaze.vision.fovea import Fovea
from ipomdp_gaze.vision.pan_tilt import SceneGeometry, ViewObserver


class FoveaSensor:
    """The digital fovea over one still image (docs/design.md section 6.2); scene = the image."""

    def __init__(self, fovea: Fovea):
        self.fovea = fovea
        self.grid = fovea.grid
        self.scans = bool(fovea.config.scan_once)

    def start(self, scene) -> None:
        self.fovea.start(scene)

    def scan_cost(self) -> int:
        """Detector pixels the scan would spend now (:meth:`Fovea.scan_cost`)."""
        return self.fovea.scan_cost()

    def fixation_cost(self, cell: int) -> int:
        """Detector pixels a fixation at ``cell`` would spend now."""
        return self.fovea.fixation_cost(int(cell))

    def scan(self) -> Frame | None:
        scan = self.fovea.scan()
        if scan is None:
            return None
        return Frame(scan.counts, kind='scan', detector_pixels=scan.detector_pixels,
                     seconds=scan.seconds, detections=tuple(map(tuple, scan.centres_px)))

    def observe(self, cell: int) -> Frame:
        obs = self.fovea.observe(int(cell))
        return Frame(obs.counts, detector_pixels=obs.detector_pixels, seconds=obs.seconds,
                     detections=tuple(map(tuple, obs.centres_px)))


class PanTiltSensor:
    """
    A camera on the pan/tilt head looking around a panorama (docs/design.md section 6.5).

    The scene is the panorama image (:class:`SceneGeometry`'s size); a fixation renders the view
    with the head at the cell and bins the detector's raw detections to cells with the camera's
    geometry (:class:`ViewObserver`), NaN outside the view. No scan: a head sees one view at a
    time.
    """

    scans = False

    def __init__(self, observer: ViewObserver, geometry: SceneGeometry,
                 camera: PinholeCamera | None = None):
        if observer.grid.shape != geometry.grid.shape:
            raise ValueError('the view observer and the scene geometry have different grids')
        self.observer = observer
        self.geometry = geometry
        self.camera = geometry.camera if camera is None else camera
        self.grid = geometry.grid
        self.image = None

    def start(self, scene) -> None:
        self.image = scene

    def scan(self) -> None:
        return None

    def view(self, cell: int):
        """Render the camera image with the head at ``cell``."""
        return self.geometry.render(self.image, self.grid.cell(int(cell)))

    def observe(self, cell: int) -> Frame:
        head = self.grid.cell(int(cell))
        obs = self.observer.observe(self.view(cell), self.camera, head)
        return Frame(obs.counts, detector_pixels=obs.detector_pixels, seconds=obs.seconds,
                     detections=tuple(map(tuple, obs.centres_uv)), groups=obs.groups,
                     offsets=None if obs.groups is None else obs.offsets)
