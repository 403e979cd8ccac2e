# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Scale as an action: the coarse full-frame pass of ``find --all`` and its evidence per cell.

A face of 75 px needs no full-resolution look. Each detector has a table, calibrated per scale on
training groups (``bench/faces/scales.py``): at scale ``s`` the full-frame call finds a face
whose side in the detector's input (``side * s``) is at least ``min_side_px`` with probability
``recall``, and makes ``false_per_mpx`` detections near no face per million detector pixels.
:func:`choose_scale` picks the coarsest scale that sees faces of the sizes that matter
(:data:`MIN_FACE_FRACTION` of the image's shorter side); :func:`coarse_evidence` turns that
call's boxes into one log-likelihood ratio per cell for the many-target belief ("a face centre
lies in cell j"):

- a cell holding a strong box's centre: ``log(recall / f)``, ``f`` the chance of a false
  detection in a cell (``false_per_mpx`` times the call's pixels, spread over the cells);
- a cell holding only weak boxes (a score below ``strong_score``, or for a detector that
  groups, raw detections that did not survive its grouping): the belief is set to even odds,
  so the cell stays undecided and finer fovea windows are spent there;
- every other cell: ``log((1 - recall) / (1 - f))``: a face of a size that matters would have
  been seen.

A face smaller than the scan sees leaves no box, or a weak one: only the latter draws finer
windows, so :data:`MIN_FACE_FRACTION` is the size below which ``find --all`` does not promise
to look.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from ipomdp_gaze.vision.fullframe import cells_of_points, MAX_ENLARGED_PX, MAX_SCALE
import numpy as np

# The smallest face that matters, as a fraction of the image's shorter side: the smallest faces
# of the training group pictures (48 px of 480, 90 of 886; ipomdp_gaze.vision.photos.GROUP_SIZES).
MIN_FACE_FRACTION = 0.1
# YuNet's coarse pass keeps boxes from this score (the fine windows' detector keeps 0.5, as
# calibrated), so that a face the coarse scale sees only faintly still draws finer windows.
WEAK_SCORE = 0.3
# A false-detection chance per cell is never taken below this (the tables count few).
MIN_FALSE = 1e-6
# Two scales within this relative tolerance are one: a table's row (ScaleTable.row) and a rung
# of find's ladder (ladder_scales, which also says whether the ladder ends on the enlarged frame,
# for search_scales and for find's --min-face note alike).
SCALE_RTOL = 1e-3


@dataclass(frozen=True)
class ScaleRow:
    """One scale of a detector's table (module docstring)."""

    scale: float
    min_side_px: float
    recall: float
    false_per_mpx: float


@dataclass(frozen=True)
class ScaleTable:
    """
    A detector's calibrated scales (coarse to fine in :meth:`rows`) and its strong score.

    ``max_side_px``: the largest face side (detector input px) the detector still finds
    strongly (YuNet's largest anchors; a sliding-window cascade such as Haar has none: inf).
    ``haar_check_score``: a face of ``find --all`` whose best box scores below it is reported
    only if OpenCV's Haar cascades see it, with ``haar_check_neighbors`` neighbours
    (:func:`ipomdp_gaze.vision.search.haar_checked`); a score of 0 checks no face.
    """

    detector: str
    rows: tuple
    strong_score: float = 0.0
    weak_score: float = 0.0
    weak_neighbors: int = 1
    max_side_px: float = math.inf
    haar_check_score: float = 0.0
    haar_check_neighbors: int = 1

    def row(self, scale: float) -> ScaleRow:
        """Return the row of ``scale`` (ValueError for a scale not in the table)."""
        for row in self.rows:
            if math.isclose(row.scale, scale, rel_tol=SCALE_RTOL):
                return row
        raise ValueError(f'scale {scale} is not in the {self.detector} table')


def _table(detector: str, rows: dict, strong_score: float = 0.0,
           weak_score: float = 0.0, max_side_px: float = math.inf,
           haar_check_score: float = 0.0) -> ScaleTable:
    return ScaleTable(detector, tuple(sorted((ScaleRow(s, *v) for s, v in rows.items()),
                                             key=lambda r: r.scale)), strong_score, weak_score,
                      max_side_px=max_side_px, haar_check_score=haar_check_score)


_COARSE = {}


def coarse_detector(detector, weak_score: float):
    """
    Return the detector of the coarse pass: ``detector`` keeping boxes from ``weak_score``.

    A detector with a ``score_threshold`` setting is rebuilt once with ``weak_score`` (so that
    a face the coarse scale sees only faintly still leaves a weak box); any other, or
    ``weak_score`` 0, is used as it is.
    """
    settings = getattr(detector, 'settings', None)
    options = settings() if callable(settings) else {}
    if not weak_score or 'score_threshold' not in options \
            or options['score_threshold'] <= weak_score:
        return detector
    key = (id(detector), weak_score)
    if key not in _COARSE:
        _COARSE[key] = (detector, type(detector).from_settings(
            {**options, 'score_threshold': weak_score}))
    return _COARSE[key][1]


# bench/faces/scales.py --faces both --scenes 24 --detector yunet|haar (training material only:
# the training photo's face, the astronaut, six copies on the training group backgrounds, and
# groups of six training lfw thumbnails, faces 0-59, on crops of the training backgrounds; 24
# pictures of each per size, 320x240 to 1920x1440, faces 48-90 px at 640 wide): scale: (min
# side px in the detector input, recall from it, strong false detections per Mpx). Rule: the
# smallest 4 px bin from which the detector finds at least 0.95 of the pooled training faces
# (of all from there up, and of every 16 px window above it). The astronaut alone is seen from
# 16-20 px at every scale, the lfw thumbnails only from 28-48 px: the pool, not the one sharp
# face, is the table (the first table, --faces photos --scenes 4, said 12-20 px at every scale
# and chose scales too coarse for other faces). Strong: YuNet's score 0.7 or more, Haar's
# grouped boxes. False detections are counted one more than were seen (YuNet: 1, 0, 0, 1 in
# 252, 63, 28, 16 Mpx at 1, 1/2, 1/3, 1/4; Haar: 85, 22, 4, 1).
# YuNet's largest side, bench/faces/large_faces.py --sides (training faces 0-59 and the
# astronaut's head, one face a picture on three training backgrounds, at scale 1): the largest
# 50 px step at which it finds at least 0.95 of them strongly: 300 px (0.967; 350: 0.918, 500:
# 0.672; a face of 930 px got one box, of 0.59, on its chin).
# YuNet's Haar check (docs/design.md section 11.4, "Haar checks a face below 0.9"): find
# --all on the training groups and crowds of make faces-groups (16 + 16 pictures per group size,
# 4 + 4 per crowd size; 807 faces named) and on the 432 augmented face-free training photos.
# Every one of the 15 false faces named (13 on coffee turned, 2 on coins) scored at most 0.834
# and none got a Haar box of 1 neighbour in the crop round it; 790 of the 792 true faces were
# kept at 1 neighbour whatever the score (2: 786, 3: 785, 5: 771). 0.85 was the lowest score
# that removed all 15; 0.9 removes the same with a margin for textures not seen in training.
SCALE_TABLES = {
    'yunet': _table('yunet', {1.0: (48.0, 0.981, 0.008), 0.5: (36.0, 0.97, 0.016),
                              0.3333: (40.0, 0.967, 0.036), 0.25: (44.0, 0.953, 0.127)},
                    strong_score=0.7, weak_score=WEAK_SCORE, max_side_px=300.0,
                    haar_check_score=0.9),
    'haar': _table('haar', {1.0: (24.0, 0.971, 0.342), 0.5: (36.0, 0.979, 0.366),
                            0.3333: (40.0, 0.972, 0.179), 0.25: (32.0, 0.959, 0.127)}),
}


def min_face_px(image_px: tuple[int, int], fraction: float = MIN_FACE_FRACTION) -> float:
    """Return the side of the smallest face that matters in an image of ``(width, height)``."""
    return fraction * min(image_px)


def choose_scale(table: ScaleTable, image_px: tuple[int, int],
                 min_face: float | None = None) -> float:
    """
    Return the coarsest scale of ``table`` that sees faces of ``min_face`` px (or larger).

    ``min_face`` defaults to :func:`min_face_px`; a scale sees a face of side ``d`` when
    ``d * scale >= min_side_px``. No scale does: the finest (1.0 when it is in the table).
    """
    side = min_face_px(image_px) if min_face is None else float(min_face)
    for row in table.rows:                                  # coarse to fine
        if side * row.scale >= row.min_side_px:
            return row.scale
    return table.rows[-1].scale


def max_enlargement(image_px: tuple[int, int] | None) -> float:
    """
    Return the most an image of ``(width, height)`` px is enlarged for small faces.

    ``fullframe.MAX_SCALE``, less where the enlarged image would read more than
    ``fullframe.MAX_ENLARGED_PX`` (its memory), but never below 1 (the image at its own size).
    """
    if image_px is None:
        return MAX_SCALE
    area = float(image_px[0]) * float(image_px[1])
    return max(1.0, min(MAX_SCALE, math.sqrt(MAX_ENLARGED_PX / area) if area else MAX_SCALE))


def finest_scale(table: ScaleTable, min_face: float | None = None,
                 image_px: tuple[int, int] | None = None) -> float:
    """
    Return the scale ``find``'s ladder ends at: the table's finest unless ``min_face`` is given.

    With ``min_face`` (px), the coarsest scale of the table that sees faces of that side; when
    even the finest does not, the image enlarged so that it does (``min_side_px / min_face``
    times, at most :func:`max_enlargement` of an image of ``image_px``: smaller faces may
    still be missed). A coarse end is also the ladder's last call, whose strong box no finer
    look confirms (:func:`ladder_scales`; docs/design.md section 11.4).
    """
    finest = table.rows[-1]
    if min_face is None:
        return finest.scale
    if float(min_face) * finest.scale >= finest.min_side_px:
        return choose_scale(table, (0, 0), min_face)
    return max(finest.scale,
               min(max_enlargement(image_px), finest.min_side_px / float(min_face)))


def ladder_scales(table: ScaleTable, start: float, finest: float | None = None) -> list:
    """
    Return the scales of ``find``'s ladder (the full-frame calls of ``search_scales``).

    The table's rows from ``start`` to ``finest`` (default the table's finest), coarse to fine,
    each bound within :data:`SCALE_RTOL`; when ``finest`` is not among them (the frame enlarged
    beyond the table's finest row by :func:`finest_scale`, or a scale between rows) one more
    call at ``finest`` ends the ladder. With ``finest`` below ``start`` (a ``--min-face`` the
    table sees at a coarser scale than the ladder's start) ``start`` is not run: the ladder is
    the one call at ``finest``. The ladder ends on the enlarged frame exactly when its last
    scale is above the table's finest row. (``search_scales`` may add one call, coarser, for
    a box too large for its rung: a close-up.)
    """
    finest = table.rows[-1].scale if finest is None else float(finest)
    rungs = [row.scale for row in table.rows
             if start * (1 - SCALE_RTOL) <= row.scale <= finest * (1 + SCALE_RTOL)]
    if not rungs or finest > rungs[-1] * (1 + SCALE_RTOL):
        rungs.append(finest)
    return rungs


def box_sides(boxes) -> np.ndarray:
    """Return the larger side of each box ``(x, y, w, h)`` of ``boxes`` (M,)."""
    return np.max(np.asarray(boxes, dtype=float).reshape(-1, 4)[:, 2:], axis=1)


def box_cells(boxes, image_px: tuple[int, int], grid) -> np.ndarray:
    """Return the cell holding each box's centre (M,), in an image of ``(width, height)``."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    return cells_of_points(boxes[:, :2] + boxes[:, 2:] / 2, image_px[::-1], grid)


def too_large(table: ScaleTable, boxes, scale: float) -> np.ndarray:
    """Return the boxes (image px) beyond the detector's largest side at ``scale``, (K, 4)."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    return boxes[box_sides(boxes) * scale > table.max_side_px]


def larger_face_scale(table: ScaleTable, boxes, scale: float) -> float | None:
    """
    Return the scale at which the largest box too large for ``scale`` is the largest side.

    The whole image is read again there when a call's box is too large for it (a close-up:
    ``find``'s ladder and ``--all``'s pass); None when no box is.
    """
    large = too_large(table, boxes, scale)
    return table.max_side_px / float(np.max(box_sides(large))) if len(large) else None


def confirm_scale(table: ScaleTable, box_side_px: float, scale: float, finer: float) -> float:
    """
    Return the scale at which ``find``'s ladder confirms a box found by a call at ``scale``.

    The next rung ``finer``, unless the box (``box_side_px`` in image px) would be beyond the
    table's ``max_side_px`` there: then the scale at which it is that side, never below
    ``scale`` (a face filling the frame is confirmed in the crop round it at the call's own
    scale).
    """
    if box_side_px * finer <= table.max_side_px:
        return finer
    return max(scale, table.max_side_px / box_side_px)


def coarse_evidence(row: ScaleRow, grid, image_px: tuple[int, int], detector_pixels: int,
                    strong_px: np.ndarray, weak_px: np.ndarray,
                    prior_log_odds: np.ndarray) -> np.ndarray:
    """
    Return the coarse pass's log-likelihood ratio per cell (N,) (module docstring).

    ``strong_px`` and ``weak_px`` are boxes ``(M, 4)`` ``x, y, w, h`` in image pixels; a weak
    box's cell gets ``-prior_log_odds`` (even odds after the prior) unless a strong box is
    centred there too.
    """
    n = grid.n_cells
    false = max(MIN_FALSE, row.false_per_mpx * detector_pixels / 1e6 / n)
    recall = min(max(row.recall, false), 1.0 - 1e-6)
    term = np.full(n, math.log((1.0 - recall) / (1.0 - false)))
    prior = np.broadcast_to(np.asarray(prior_log_odds, dtype=float), (n,))
    weak = box_cells(weak_px, image_px, grid)
    term[weak] = -prior[weak]
    term[box_cells(strong_px, image_px, grid)] = math.log(recall / false)
    return term
