# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The sweep answer rules a team would write, scored on the same views as the searches.

One pass of the sweep's poses (the views the ``sweep`` policy takes), answered without a belief:
:data:`SWEEP_RULES` (docs/design.md section 10.4).
"""
from __future__ import annotations

from ipomdp_gaze.drivers.scene_report import scene_result, SceneResult
from ipomdp_gaze.vision.pan_tilt import view_groups
import numpy as np

# The sweep's answer rules, computed from one pass of its poses (the views the sweep policy takes):
# the cell with most raw detections in its own tile; the first view with a raw detection; the
# first view with a detection grouped as OpenCV does with min_neighbors 3 or 5.
SWEEP_RULES = ('sweep-tile', 'sweep-first-raw', 'sweep-first-grouped3', 'sweep-first-grouped5')
# Rooms with several faces (drivers/rooms.py): one pass answering every grouped detection.
ROOM_SWEEPS = ('sweep-all-grouped3', 'sweep-all-grouped5', 'every-view-grouped3',
               'every-view-grouped5')
# OpenCV's detectMultiScale groups its raw windows with groupRectangles(eps=0.2).
_GROUP_EPS = 0.2


def sweep_rule(spec, task, scene, index: int, rule: str) -> SceneResult:
    """
    One pass of the sweep's poses, answered by ``rule`` (:data:`SWEEP_RULES`), without a belief.

    ``sweep-tile``: after the pass, the cell with most detections in its own tile (ties: the
    lowest index); ``sweep-first-*``: stop at the first view with a detection in the grid (raw,
    or grouped with min_neighbors 3 / 5: the largest group) and answer its cell. No detection
    in the whole pass: ``absent``.
    """
    grid = task.model.grid
    poses, owner = task.sweep.poses, task.sweep.owner
    best = np.full(grid.n_cells, -1.0)
    path, pixels, detector_s = [], 0, []
    answer, decision = None, 'absent'
    for p, pose in enumerate(poses):
        frame = task.sensor.observe(int(pose))
        path.append(int(pose))
        pixels += frame.detector_pixels
        detector_s.append(frame.seconds)
        counts = np.nan_to_num(np.asarray(frame.values, dtype=float), nan=-1.0)
        if rule == 'sweep-tile':
            mine = owner == p
            best[mine] = counts[mine]
            continue
        if rule == 'sweep-first-raw':
            if counts.max() > 0:
                answer = int(np.argmax(counts))
                break
            continue
        inside = grouped_cells(task, int(pose), int(rule[-1]))
        if inside.size:
            answer = int(inside[0])
            break
    if rule == 'sweep-tile' and best.max() > 0:
        answer = int(np.argmax(best))
    if answer is not None:
        decision = 'found'
    cell = tuple(int(v) for v in grid.cell(grid.center_index if answer is None else answer))
    face = None if scene.cell is None else tuple(int(v) for v in scene.cell)
    return scene_result(task, scene, index, rule, cell, face, decision, '', tuple(path), pixels,
                        detector_s)


def grouped_cells(task, pose: int, min_neighbors: int) -> np.ndarray:
    """
    Cells of the grouped detections of the view at ``pose``, the largest box first.

    The raw boxes the task's sensor recorded for that view (:func:`group_cells`).
    """
    grid = task.model.grid
    return group_cells(task.sensor.recorder.detector, task.sensor.boxes[int(pose)], task.camera,
                       grid, grid.cell(int(pose)), task.max_count, min_neighbors)


def group_cells(detector, raw, camera, grid, head_rc, max_count: int,
                min_neighbors: int) -> np.ndarray:
    """
    Cells of a view's raw boxes grouped as a team would, the largest box first.

    Grouped by the detector's own rule (YuNet's boxes are already suppressed), else as
    ``detectMultiScale`` does with ``min_neighbors`` (as ``fullframe.scan``); boxes whose centre
    is off the grid are dropped (:func:`ipomdp_gaze.vision.pan_tilt.view_groups`).
    """
    cells, _ = view_groups(raw, min_neighbors, camera, grid, head_rc, max_count,
                           getattr(detector, 'group', None))
    return cells[cells >= 0]
