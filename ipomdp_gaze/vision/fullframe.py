# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The full-frame baseline of the CVPR 2009 comparison: the detector on the whole image, no fovea.

:func:`scan` runs the detector once on the whole image, at full resolution or downscaled (the
cheap baselines, e.g. 3/4, 1/2, 1/3), and answers in both ways the paper's comparison needs
(docs/design.md section 6):

- **NMPT's rule**: the cell holding the most raw detection centres (ties: the lowest cell
  index, the project's tie rule; no detection: ``None``);
- **OpenCV's answer**: the raw detections grouped as ``detectMultiScale(..., minNeighbors=3)``
  does, and the cell of the largest grouped box's centre (ties: the first in OpenCV's order).

Cells follow the fovea's convention: a point ``(x, y)`` of an ``H x W`` image lies in cell
``(floor(y * rows / H), floor(x * cols / W))``. Boxes are mapped back to full-image pixels.
"""
from __future__ import annotations

from dataclasses import dataclass
import time

import cv2
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.vision.detector import (as_detections, box_centres_px, DEFAULT_MIN_NEIGHBORS,
                                         detect, detector_color, detector_window_px,
                                         group_boxes, to_detector_image)
import numpy as np

# The largest factor a scan enlarges an image by (find's ladder for faces smaller than the
# detector sees at full resolution, vision.scales.finest_scale).
MAX_SCALE = 4.0
# The most pixels an enlarged call reads (OpenCV's detectors need about 75 bytes a pixel: 24 Mpx
# is about 1.8 GB); an image enlarged for small faces stops there, never below its own size.
MAX_ENLARGED_PX = 24_000_000


@dataclass(frozen=True, eq=False)
class ScanResult:
    """
    What a full-frame scan found and what it cost.

    Attributes
    ----------
    counts : numpy.ndarray
        ``(N,)`` ``int64``: raw detections centred in each cell (not clipped).
    cell : int or None
        NMPT's answer: the cell with the most raw detections (lowest index on ties), or ``None``
        if there is none.
    boxes_px : numpy.ndarray
        ``(M, 4)`` ``float64``: the raw boxes ``x, y, w, h`` in full-image pixels.
    grouped_px : numpy.ndarray
        ``(G, 4)`` ``float64``: OpenCV's grouped detections in full-image pixels.
    grouped_cell : int or None
        The cell of the largest grouped box's centre, or ``None`` if nothing survives grouping.
    scale : float
        The resize factor the image was scanned at.
    detector_pixels : int
        Pixels of the image the detector was given.
    seconds : float
        Wall time from the decoded array to the answer: grey conversion, resizing, detector,
        grouping and binning.
    scores : numpy.ndarray
        ``(M,)`` score of each raw box (1 for a detector without scores).

    """

    counts: np.ndarray
    cell: int | None
    boxes_px: np.ndarray
    grouped_px: np.ndarray
    grouped_cell: int | None
    scale: float
    detector_pixels: int
    seconds: float
    scores: np.ndarray = None


def cells_of_points(points_px: np.ndarray, image_shape: tuple[int, int], grid: Grid) -> np.ndarray:
    """
    Row-major cells ``(M,)`` of points ``(M, 2)`` ``x, y`` in an image of ``(H, W)`` pixels.

    ``(floor(y * rows / H), floor(x * cols / W))``, clipped into the grid (a point on the far
    border belongs to the last cell).
    """
    height, width = image_shape[:2]
    points_px = np.asarray(points_px, dtype=np.float64).reshape(-1, 2)
    row = np.clip(np.floor(points_px[:, 1] * grid.rows / height), 0, grid.rows - 1)
    col = np.clip(np.floor(points_px[:, 0] * grid.cols / width), 0, grid.cols - 1)
    return row.astype(np.int64) * grid.cols + col.astype(np.int64)


def scaled_size(width: int, height: int, scale: float) -> tuple[int, int]:
    """Return the ``(width, height)`` a full-frame call at ``scale`` gives the detector."""
    return (max(1, int(np.floor(width * scale + 0.5))),
            max(1, int(np.floor(height * scale + 0.5))))


def scan(image: np.ndarray, detector, grid=(21, 21), scale: float = 1.0,
         interpolation: int = cv2.INTER_AREA,
         min_neighbors: int = DEFAULT_MIN_NEIGHBORS) -> ScanResult:
    """
    Run the detector on the whole image, optionally downscaled by ``scale``.

    Parameters
    ----------
    image : numpy.ndarray
        ``uint8`` grey ``(H, W)`` or RGB ``(H, W, 3)`` (:func:`to_gray`).
    detector : callable
        ``detector(image) -> (M, 5)`` or ``(M, 4)`` raw boxes, in its colour space; its
        ``group`` method, if any, merges them (else :func:`group_boxes` on the rounded boxes).
    grid : Grid or (int, int)
        The grid tiling the image.
    scale : float
        Resize factor in ``(0, MAX_SCALE]``; the image is resized to ``round(W * scale) x
        round(H * scale)`` with ``interpolation`` (default area averaging, the anti-aliased
        decimation the fovea uses too) or, above 1, enlarged bilinearly.
    interpolation : int
        ``cv2.INTER_*`` flag for a reduction.
    min_neighbors : int
        Grouping threshold for OpenCV's answer (3, detectMultiScale's default).

    Raises
    ------
    ValueError
        For a bad image (:func:`to_gray`) or a scale outside ``(0, MAX_SCALE]``.

    """
    t0 = time.perf_counter()
    grid = grid if isinstance(grid, Grid) else Grid(*grid)
    scale = float(scale)
    if not (np.isfinite(scale) and 0.0 < scale <= MAX_SCALE):
        raise ValueError(f'scale must be in (0, {MAX_SCALE:g}], got {scale!r}')
    gray = to_detector_image(image, detector_color(detector), detector_window_px(detector))
    height, width = gray.shape[:2]
    out_width, out_height = scaled_size(width, height, scale)
    if (out_width, out_height) != (width, height):
        gray = cv2.resize(gray, (out_width, out_height),
                          interpolation=interpolation if scale <= 1.0 else cv2.INTER_LINEAR)
    raw, scores = detect(detector, gray)
    group = getattr(detector, 'group', None)
    grouped = as_detections(group(raw, min_neighbors) if callable(group)
                            else group_boxes(np.round(raw), min_neighbors))[0]
    back = np.array([width / out_width, height / out_height] * 2)
    boxes_px, grouped_px = raw * back, grouped * back
    counts = np.bincount(cells_of_points(box_centres_px(boxes_px), (height, width), grid),
                         minlength=grid.n_cells).astype(np.int64)
    cell = int(np.argmax(counts)) if counts.any() else None
    grouped_cell = None
    if len(grouped_px):
        largest = int(np.argmax(grouped_px[:, 2] * grouped_px[:, 3]))
        grouped_cell = int(cells_of_points(box_centres_px(grouped_px[largest]),
                                           (height, width), grid)[0])
    return ScanResult(counts=counts, cell=cell, boxes_px=boxes_px, grouped_px=grouped_px,
                      grouped_cell=grouped_cell, scale=scale,
                      detector_pixels=out_width * out_height,
                      seconds=time.perf_counter() - t0, scores=scores)
