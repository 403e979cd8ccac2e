# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The head-time model of a pan/tilt search: what a path of views costs in seconds and degrees.

Per view the detector's time plus the controller's ``settle_time_s``; per saccade the scene
camera's ``saccade_time_s`` plus the largest joint angle over the joints' speed. The offline
evaluation (``evaluate --scenes pan-tilt``) and the benches score head time with it; the nodes
take their defaults from the same constants.
"""
from __future__ import annotations

from ipomdp_gaze.model.grid import Grid
import numpy as np

# The controller's default settle_time_s and the scene camera's default saccade_time_s (s).
SETTLE_TIME_S = 0.1
SACCADE_TIME_S = 0.15
# The joints' speed of the head model (deg/s).
HEAD_SPEED_DEG_S = 120.0


def head_time_s(grid: Grid, path, detector_s) -> float:
    """
    Return the head-time model's seconds for a path: views, and saccades from the centre.

    Per view the detector's time plus :data:`SETTLE_TIME_S`; per saccade
    :data:`SACCADE_TIME_S` plus the largest joint angle over :data:`HEAD_SPEED_DEG_S`.
    """
    if not len(path):
        return 0.0
    rows, cols = grid.cell(np.concatenate([[grid.center_index], np.asarray(path)]))
    step = np.maximum(np.abs(np.diff(rows)), np.abs(np.diff(cols))) * grid.spacing_deg
    moves = step > 0
    return float(np.sum(detector_s) + SETTLE_TIME_S * len(path)
                 + np.sum(SACCADE_TIME_S + step[moves] / HEAD_SPEED_DEG_S))


def head_travel_deg(grid: Grid, path) -> float:
    """Sum over saccades of the angle the head turns, ``spacing * hypot(d_row, d_col)``."""
    if len(path) < 2:
        return 0.0
    rows, cols = grid.cell(np.asarray(path))
    return float(grid.spacing_deg * np.hypot(np.diff(rows), np.diff(cols)).sum())
