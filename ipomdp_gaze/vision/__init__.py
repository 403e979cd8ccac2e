# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Real pixels for the model (docs/design.md section 6): detectors, the digital fovea, baselines.

- :mod:`~ipomdp_gaze.vision.detector`: the detector interface (a callable returning raw boxes),
  OpenCV's Viola-Jones cascade (:class:`HaarDetector`), :func:`find_cascade`, :func:`to_gray`;
- :mod:`~ipomdp_gaze.vision.fovea`: the digital fovea (:class:`Fovea`, :class:`FoveaConfig`),
  count observations per fixation;
- :mod:`~ipomdp_gaze.vision.fullframe`: the full-frame scan baseline (:func:`scan`);
- :mod:`~ipomdp_gaze.vision.scenes`: labelled scenes built from scikit-image's photos and faces
  (imported on its own, not re-exported here);
- :mod:`~ipomdp_gaze.vision.pan_tilt`: the pan/tilt face task, a scene a head camera looks
  around in, its rendered views and their counts (imported on its own).

Part of the core: numpy and OpenCV only, nothing from ROS or the policies.
"""
from ipomdp_gaze.vision.detector import (as_boxes, Detector, find_cascade, group_boxes,
                                         HaarDetector, REFERENCE_CASCADE, to_gray)
from ipomdp_gaze.vision.fovea import (cell_edges_px, Fovea, FoveaConfig, Observation,
                                      REFERENCE_WINDOWS_CELLS, Window, window_cells)
from ipomdp_gaze.vision.fullframe import cells_of_points, scan, ScanResult

__all__ = [
    'as_boxes', 'cell_edges_px', 'cells_of_points', 'Detector', 'find_cascade', 'Fovea',
    'FoveaConfig', 'group_boxes', 'HaarDetector', 'Observation', 'REFERENCE_CASCADE',
    'REFERENCE_WINDOWS_CELLS', 'scan', 'ScanResult', 'to_gray', 'Window', 'window_cells',
]
