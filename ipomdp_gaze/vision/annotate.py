# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
See the search on the camera image: belief, fixations, fovea windows, detections, the answer.

:func:`annotate` is a pure function (numpy and OpenCV's drawing calls, no ROS): it returns an
``rgb8`` copy of a camera image, at the image's resolution, with

- the **belief** as a translucent overlay: each cell tinted by its probability on a log scale
  (``inferno``: dark purple at ``1e-3`` of the most likely cell or less, yellow at the most
  likely cell), the tint's opacity rising with the probability, so that the image stays visible
  where the belief is low;
- the **fixations** so far as discs at their cells' centres, joined by a thin line, the colour
  running from blue (first) to white (latest), numbered where a cell is large enough (discs of
  6 px or more), so that a long scan path stays readable;
- the current **fovea windows** (fixed camera) as cyan rectangles, dashed for a whole-image
  window, or, with a camera on the head, the fixated cell outlined in cyan;
- the raw **detections** (box centres) as yellow crosses;
- the **found** cell as a thick green rectangle with its probability.

Where a pixel is on the grid is a :class:`CellMap`: the cell row of every pixel row and the cell
column of every pixel column (-1 off the grid). A fixed camera's grid tiles the image
(:func:`fovea_cell_map`, the fovea's ``floor(i * size / n)`` edges); a camera on the pan/tilt head
shows a rectangle of cells that depends on where the head points (:func:`view_cell_map`, the
mapping of :mod:`ipomdp_gaze.model.head_camera`). Both are separable, which keeps the overlay a
repeat of a ``(rows, cols)`` colour table: about 3 ms for a 320x240 view and 7 ms for a
420x420 image on this project's 2-core machine
(``bench/faces/annotate.py``).
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import PinholeCamera, pixel_cells
import numpy as np

# Log10 range of the belief overlay, relative to the most likely cell.
LOG_RANGE = 4.0
# Colours, RGB.
WINDOW_RGB = (0, 255, 255)
DETECTION_RGB = (255, 230, 0)
FOUND_RGB = (0, 255, 0)


@dataclass(frozen=True)
class CellMap:
    """
    The grid cell of every pixel, by axis: ``rows`` ``(H,)`` and ``cols`` ``(W,)`` int64.

    ``rows[v]`` is the cell row of pixel row ``v`` and ``cols[u]`` the cell column of pixel
    column ``u``; -1 where the pixel is off the grid.
    """

    grid: Grid
    rows: np.ndarray
    cols: np.ndarray

    @property
    def size_px(self) -> tuple[int, int]:
        """Return ``(width, height)`` of the image the map is for."""
        return int(self.cols.size), int(self.rows.size)

    def cell_index(self) -> np.ndarray:
        """Return the ``(H, W)`` row-major cell of every pixel, -1 off the grid."""
        inside = (self.rows[:, None] >= 0) & (self.cols[None, :] >= 0)
        return np.where(inside, self.rows[:, None] * self.grid.cols + self.cols[None, :], -1)

    def _spans(self, labels: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
        """First and last pixel of each of ``n`` cells along one axis (-1, -2 if not shown)."""
        first = np.full(n, -1, dtype=np.int64)
        last = np.full(n, -2, dtype=np.int64)
        shown = labels >= 0
        pixels = np.flatnonzero(shown)
        if pixels.size:
            # Pixels run in order and the mapping is monotone: reversed assignment keeps the
            # first occurrence, forward assignment the last.
            first[labels[pixels[::-1]]] = pixels[::-1]
            last[labels[pixels]] = pixels
        return first, last

    def cell_boxes(self) -> np.ndarray:
        """
        Pixel box ``x0, y0, x1, y1`` (inclusive) of every cell, ``(N, 4)`` int64.

        A cell that is not in the image has ``x1 < x0`` or ``y1 < y0``.
        """
        x0, x1 = self._spans(self.cols, self.grid.cols)
        y0, y1 = self._spans(self.rows, self.grid.rows)
        rows, cols = np.divmod(np.arange(self.grid.n_cells), self.grid.cols)
        return np.stack([x0[cols], y0[rows], x1[cols], y1[rows]], axis=1)


def fovea_cell_map(grid: Grid, width: int, height: int) -> CellMap:
    """Map of a fixed camera whose image the grid tiles (the fovea's cell edges)."""
    def cells(size: int, n: int) -> np.ndarray:
        edges = (np.arange(n + 1, dtype=np.int64) * int(size)) // int(n)
        return np.searchsorted(edges, np.arange(int(size)), side='right').astype(np.int64) - 1
    return CellMap(grid, cells(height, grid.rows), cells(width, grid.cols))


def view_cell_map(grid: Grid, camera: PinholeCamera, head_rc) -> CellMap:
    """Map of a view from a camera on the pan/tilt head at grid position ``head_rc``."""
    rows, _ = pixel_cells(np.zeros(camera.height), np.arange(camera.height), camera, head_rc,
                          grid.spacing_deg)
    _, cols = pixel_cells(np.arange(camera.width), np.zeros(camera.width), camera, head_rc,
                          grid.spacing_deg)
    rows = np.where((rows >= 0) & (rows < grid.rows), rows, -1)
    cols = np.where((cols >= 0) & (cols < grid.cols), cols, -1)
    return CellMap(grid, rows.astype(np.int64), cols.astype(np.int64))


def as_rgb(image: np.ndarray) -> np.ndarray:
    """Return a contiguous ``(H, W, 3)`` uint8 RGB copy of a grey or RGB uint8 image."""
    image = np.asarray(image)
    if image.dtype != np.uint8 or image.ndim not in (2, 3) or \
            (image.ndim == 3 and image.shape[2] != 3):
        raise ValueError(f'expected a grey (H, W) or RGB (H, W, 3) uint8 image, got '
                         f'{image.dtype} {image.shape}')
    if image.ndim == 2:
        return np.repeat(image[:, :, None], 3, axis=2)
    return np.ascontiguousarray(image).copy()


def belief_colours(belief: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Colour ``(N, 3)`` uint8 and opacity ``(N,)`` of each cell for the overlay.

    ``level = clip(1 + log10(B / max B) / LOG_RANGE, 0, 1)``; the colour is ``inferno(level)``
    and the opacity ``alpha * (0.4 + 0.6 * level)``.
    """
    belief = np.asarray(belief, dtype=np.float64).reshape(-1)
    top = float(np.max(belief)) if belief.size else 0.0
    if not np.isfinite(top) or top <= 0:
        level = np.zeros_like(belief)
    else:
        with np.errstate(divide='ignore'):
            level = np.clip(1.0 + np.log10(np.maximum(belief, 0) / top) / LOG_RANGE, 0.0, 1.0)
    level = np.nan_to_num(level)
    lut = cv2.applyColorMap(np.round(level * 255).astype(np.uint8)[:, None],
                            cv2.COLORMAP_INFERNO)[:, 0, ::-1]     # BGR -> RGB
    return np.ascontiguousarray(lut), alpha * (0.4 + 0.6 * level)


def _order_colour(i: int, n: int) -> tuple[int, int, int]:
    """Fixation ``i`` of ``n``: blue (first) to white (latest)."""
    t = 1.0 if n <= 1 else i / (n - 1)
    return (int(40 + 215 * t), int(90 + 165 * t), 255)


def _text(canvas, text: str, org, scale: float, colour, thickness: int = 1) -> None:
    """Draw text with a dark outline so it reads on any background."""
    cv2.putText(canvas, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), thickness + 2,
                cv2.LINE_AA)
    cv2.putText(canvas, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, colour, thickness,
                cv2.LINE_AA)


def annotate(image: np.ndarray, cell_map: CellMap, belief=None, fixations=(), windows=(),
             detections=None, found=None, alpha: float = 0.45, label: str = '',
             found_label: str = 'found', found_radius: int = 0) -> np.ndarray:
    """
    Draw the search on a copy of ``image``; return ``(H, W, 3)`` uint8 RGB.

    Parameters
    ----------
    image : numpy.ndarray
        Grey ``(H, W)`` or RGB ``(H, W, 3)`` uint8, the size of ``cell_map``.
    cell_map : CellMap
        Where each pixel is on the grid (:func:`fovea_cell_map`, :func:`view_cell_map`).
    belief : array (N,), optional
        Probability of each cell (the absent hypothesis left out).
    fixations : sequence of int
        Row-major cells fixated so far, in order; the last is the current one.
    windows : sequence of (x, y, w, h, whole_image)
        The current fovea windows in pixels; empty: outline the current fixation's cell.
    detections : array (M, 2), optional
        ``x, y`` pixel centres of the raw detections.
    found : (cell, probability), optional
        The cell the search found (or its answer at the budget), and its probability.
    alpha : float
        Opacity of the belief overlay at the most likely cell, in [0, 1].
    label : str
        A line of text at the top left (for example the fixation count).
    found_label : str
        What the answer is called (``found``; ``most likely`` at the budget).
    found_radius : int
        With ``search.found_radius`` r > 0 the answer is the centre of the likeliest
        (2r + 1)-square of cells: that square is outlined too (thin), so that a face a cell
        off the centre is inside what is drawn as found.

    """
    canvas = as_rgb(image)
    width, height = cell_map.size_px
    if canvas.shape[:2] != (height, width):
        raise ValueError(f'the image is {canvas.shape[1]}x{canvas.shape[0]} px but the cell '
                         f'map is for {width}x{height}')
    grid = cell_map.grid
    boxes = cell_map.cell_boxes()
    shown = (boxes[:, 2] >= boxes[:, 0]) & (boxes[:, 3] >= boxes[:, 1])
    cell_px = max(4.0, float(np.median((boxes[shown, 2] - boxes[shown, 0] + 1)))
                  if shown.any() else 8.0)
    scale = float(np.clip(cell_px / 40.0, 0.3, 0.6))
    thick = max(1, int(round(cell_px / 20.0)))
    if belief is not None:
        belief = np.asarray(belief, dtype=np.float64).reshape(-1)
        if belief.size != grid.n_cells:
            raise ValueError(f'belief has {belief.size} cells, the grid {grid.n_cells}')
        canvas = _overlay(canvas, cell_map, *belief_colours(belief, float(alpha)))
    centres = np.stack([(boxes[:, 0] + boxes[:, 2]) / 2.0, (boxes[:, 1] + boxes[:, 3]) / 2.0],
                       axis=1)
    fixations = [int(k) for k in fixations]
    if windows:
        for x, y, w, h, whole in windows:
            if whole:
                _dashed_rect(canvas, (int(x), int(y)), (int(x + w - 1), int(y + h - 1)),
                             WINDOW_RGB, thick, 6 * thick)
            else:
                cv2.rectangle(canvas, (int(x), int(y)), (int(x + w - 1), int(y + h - 1)),
                              WINDOW_RGB, thick)
    elif fixations and shown[fixations[-1]]:
        x0, y0, x1, y1 = boxes[fixations[-1]]
        cv2.rectangle(canvas, (int(x0), int(y0)), (int(x1), int(y1)), WINDOW_RGB, thick + 1)
    visible = [(i, k) for i, k in enumerate(fixations) if shown[k]]
    # The path and the discs at 70% opacity, so that what lies under them stays visible.
    layer = canvas.copy()
    if len(visible) > 1:
        points = np.round(centres[[k for _, k in visible]]).astype(np.int32)
        cv2.polylines(layer, [points.reshape(-1, 1, 2)], False, (200, 220, 255), thick,
                      cv2.LINE_AA)
    radius = int(np.clip(round(cell_px * 0.27), 3, 11))
    for i, k in visible:
        x, y = (int(round(v)) for v in centres[k])
        cv2.circle(layer, (x, y), radius, _order_colour(i, len(fixations)), -1, cv2.LINE_AA)
        cv2.circle(layer, (x, y), radius, (0, 0, 0), 1, cv2.LINE_AA)
    if visible:
        canvas = cv2.addWeighted(layer, 0.7, canvas, 0.3, 0.0)
    for i, k in visible:
        x, y = (int(round(v)) for v in centres[k])
        if radius < 6:
            continue                    # too small to read: the colour gives the order
        text = str(i + 1)
        size = min(scale * 0.8, radius / 16.0 * (1.6 if i < 9 else 1.0))
        (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, size, 1)
        cv2.putText(canvas, text, (x - tw // 2, y + th // 2), cv2.FONT_HERSHEY_SIMPLEX,
                    size, (0, 0, 0), 1, cv2.LINE_AA)
    if detections is not None:
        points = np.asarray(detections, dtype=np.float64).reshape(-1, 2)
        size = max(5, int(round(cell_px * 0.15)))
        for x, y in np.round(points).astype(np.int64):
            cv2.drawMarker(canvas, (int(x), int(y)), DETECTION_RGB, cv2.MARKER_CROSS, size, 1)
    if found is not None:
        cell, probability = int(found[0]), float(found[1])
        if shown[cell]:
            x0, y0, x1, y1 = (int(v) for v in boxes[cell])
            cv2.rectangle(canvas, (x0 - 1, y0 - 1), (x1 + 1, y1 + 1), FOUND_RGB, thick + 1)
        row, col = grid.cell(cell)
        if found_radius > 0:
            r = int(found_radius)
            square = [grid.index(i, j)
                      for i in range(max(0, row - r), min(grid.rows, row + r + 1))
                      for j in range(max(0, col - r), min(grid.cols, col + r + 1))]
            square = [k for k in square if shown[k]]
            if square:
                x0, y0 = (int(v) for v in boxes[square, :2].min(axis=0))
                x1, y1 = (int(v) for v in boxes[square, 2:].max(axis=0))
                cv2.rectangle(canvas, (x0, y0), (x1, y1), FOUND_RGB, 1)
        p = 'n/a' if np.isnan(probability) else f'{probability:.3f}'
        _text(canvas, f'{found_label} ({row}, {col}) p={p}',
              (4, height - int(6 + 8 * scale)), scale, FOUND_RGB, thick)
    if label:
        _text(canvas, label, (4, int(14 + 20 * scale)), scale, (255, 255, 255), thick)
    return canvas


def _overlay(canvas: np.ndarray, cell_map: CellMap, colours: np.ndarray,
             opacity: np.ndarray) -> np.ndarray:
    """
    Blend each cell's colour over its pixels: ``out = (1 - a) * image + a * colour``.

    Separable: ``(rows + 1, cols + 1)`` tables of colour and opacity (the extra row and column
    transparent, for pixels off the grid) repeated over each cell's run of pixel rows and
    columns, then OpenCV's ``blendLinear``.
    """
    grid = cell_map.grid
    colour = np.zeros((grid.rows + 1, grid.cols + 1, 3), dtype=np.uint8)
    colour[:-1, :-1] = colours.reshape(grid.rows, grid.cols, 3)
    weight = np.zeros((grid.rows + 1, grid.cols + 1), dtype=np.float32)
    weight[:-1, :-1] = opacity.reshape(grid.shape)
    row_cells, row_runs = _runs(np.where(cell_map.rows >= 0, cell_map.rows, grid.rows))
    col_cells, col_runs = _runs(np.where(cell_map.cols >= 0, cell_map.cols, grid.cols))

    def spread(table):
        return np.ascontiguousarray(np.repeat(np.repeat(table[row_cells][:, col_cells], row_runs,
                                                        axis=0), col_runs, axis=1))
    a = spread(weight)
    return cv2.blendLinear(canvas, spread(colour), 1.0 - a, a)


def _runs(labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the runs of equal values: ``(value of each run, its length)``."""
    starts = np.flatnonzero(np.r_[True, labels[1:] != labels[:-1]])
    return labels[starts], np.diff(np.r_[starts, labels.size])


def _dashed_rect(canvas: np.ndarray, p0, p1, colour, thick: int = 1, dash: int = 6) -> None:
    """Draw a dashed rectangle (a whole-image window)."""
    (x0, y0), (x1, y1) = p0, p1
    for a, b, fixed, horizontal in ((x0, x1, y0, True), (x0, x1, y1, True),
                                    (y0, y1, x0, False), (y0, y1, x1, False)):
        for s in range(a, b + 1, 2 * dash):
            e = min(s + dash - 1, b)
            start, end = ((s, fixed), (e, fixed)) if horizontal else ((fixed, s), (fixed, e))
            cv2.line(canvas, start, end, colour, thick)


def grid_canvas(grid: Grid, cell_px: int = 40, shade: int = 60) -> tuple[np.ndarray, CellMap]:
    """Return a plain grey image of the grid (``cell_px`` px a cell) and its map: no camera."""
    width, height = grid.cols * int(cell_px), grid.rows * int(cell_px)
    canvas = np.full((height, width), int(shade), dtype=np.uint8)
    canvas[::int(cell_px), :] = shade + 25
    canvas[:, ::int(cell_px)] = shade + 25
    return canvas, fovea_cell_map(grid, width, height)
