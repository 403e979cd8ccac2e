# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The digital fovea of Butko & Movellan's CVPR 2009 follow-up: count observations from a detector.

A ``rows x cols`` grid tiles the whole image (docs/design.md section 6). Fixating a cell places
nested square windows of :attr:`FoveaConfig.windows_cells` cells (reference ``(21, 15, 9, 3)``)
centred on it. Each window is resized by its own scale factor and searched by the detector; the
centre of every raw detection is mapped back to full-image pixels and binned to its cell. A
cell's observation is the number of detections centred in it, summed over windows and clipped
to ``0..max_count-1``; cells outside every window are NaN, "not observed" (section 1.4).

**Geometry.** Per axis, a window of ``s`` cells on a grid of ``G`` cells covers
``n = min(s, G)`` cells starting at ``clip(p - s // 2, 0, G - n)`` for a fixation at ``p``: it is
centred on the fixated cell (odd sizes) and *shifted, not cropped*, to stay inside the grid, so
it always covers ``n`` cells; a window as large as the grid covers the whole image. Cell ``r`` of
an image ``H`` pixels high spans rows ``floor(r * H / rows)`` to ``floor((r + 1) * H / rows) - 1``
(as in NMPT), so windows tile exactly when ``H`` is not a multiple of ``rows``. A point
``(x, y)`` (a detection's box centre, ``(x + w/2, y + h/2)``) lies in cell
``(floor(y * rows / H), floor(x * cols / W))``, the convention of the labelled scenes; the rare
centre in the sub-pixel sliver where the integer window edge and this continuous cell edge
disagree is counted in the window's own edge cell, so only covered cells ever get counts.

**Resolution.** A window of ``w x h`` pixels is resized to ``round(w * scale) x round(h * scale)``
(at least 1x1). NMPT's reference resizes every window to the pixel size of the smallest one
(``scale = min(windows_cells) / cells``: the 3-cell window at full resolution, the 21-cell one 7x
down); that is the default. Faces must still be about the cascade's 20 px where the detector
sees them, so small faces vanish from the coarse windows: hence a scale per window. A window
larger than the grid is resized by its own factor after being cut down to the grid.

**Interpolation.** NMPT uses nearest neighbour. The default here is ``'area'``
(``cv2.INTER_AREA``): at 7x down nearest neighbour keeps one pixel in 49 and aliases the Haar
features, whereas area averaging is the anti-aliased decimation (a box filter, exact and fast for
integer factors). The choice is recorded in :meth:`FoveaConfig.to_dict`, as a model measured with
one interpolation is only valid with it.

**Cost and caching.** The whole-image window does not depend on the fixation: its detections are
computed on the first fixation after :meth:`Fovea.start` and reused for the rest of the image, so
its pixels count once per image (as in NMPT).

**The scan** (``scan_once=True``). NMPT adds the whole-image window's counts to every fixation's
frame, so the same detections enter the Bayes step again at each fixation: a single false alarm
in that window, counted ten times, can make the belief confident. With ``scan_once`` the
whole-image windows form a separate observation, :meth:`Fovea.scan`, taken once per image before
the first fixation and modelled by its own offset-free table (docs/design.md section 6.8); the
fixation frames then hold the other windows only. Without a whole-image window there is nothing to
scan and the option is refused.

With ``reuse_windows=True`` every window's detections are kept per image, keyed by the cells it
covers and its resized size (the detector is deterministic, so a repeated window gives the same
boxes); this changes the cost, never the counts.
"""
from __future__ import annotations

from dataclasses import dataclass
import time
from typing import NamedTuple

import cv2
from ipomdp_gaze.files.yaml_files import check_record
from ipomdp_gaze.model.cell_observation import CellObservation
from ipomdp_gaze.model.checks import positive_int as _positive_int
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.vision.detector import (box_centres_px, detect, detector_color,
                                         detector_settings, detector_window_px, to_detector_image)
import numpy as np

REFERENCE_WINDOWS_CELLS = (21, 15, 9, 3)
REFERENCE_MAX_COUNT = 10
INTERPOLATIONS = {
    'area': cv2.INTER_AREA,
    'nearest': cv2.INTER_NEAREST,
    'nearest_exact': cv2.INTER_NEAREST_EXACT,
    'linear': cv2.INTER_LINEAR,
    'cubic': cv2.INTER_CUBIC,
}
# The YAML types of the settings of a fovea record (ipomdp_gaze.files.yaml_files.check_record).
RECORD_TYPES = {'windows_cells': 'integers', 'scales': 'numbers?', 'max_count': 'integer',
                'interpolation': 'text', 'scan_once': 'flag'}


@dataclass(frozen=True)
class FoveaConfig:
    """
    Windows, resolutions, count range and interpolation of a digital fovea (validated).

    Parameters
    ----------
    windows_cells : tuple of int
        Side of each square window in cells, strictly decreasing (largest first).
    scales : tuple of float, optional
        Resize factor in ``(0, 1]`` of each window. ``None`` means NMPT's
        ``min(windows_cells) / cells`` and is replaced by those numbers, so two configurations
        that resize alike compare equal and :meth:`to_dict` records the actual factors.
    max_count : int
        K: observations are clipped to ``0..K-1`` (at least 2).
    interpolation : str
        Resampling used to resize windows, a key of :data:`INTERPOLATIONS`.
    scan_once : bool
        Observe the whole-image windows once per image (:meth:`Fovea.scan`) instead of adding
        their counts to every fixation's frame (NMPT).

    """

    windows_cells: tuple = REFERENCE_WINDOWS_CELLS
    scales: tuple | None = None
    max_count: int = REFERENCE_MAX_COUNT
    interpolation: str = 'area'
    scan_once: bool = False

    def __post_init__(self):
        windows = self.windows_cells
        if np.ndim(windows) != 1 or len(windows) == 0:
            raise ValueError(f'windows_cells must be a non-empty sequence, got {windows!r}')
        windows = tuple(_positive_int('every window size (cells)', w) for w in windows)
        if any(a <= b for a, b in zip(windows, windows[1:])):
            raise ValueError(f'windows_cells must be strictly decreasing, got {windows}')
        if self.scales is None:
            scales = tuple(windows[-1] / w for w in windows)
        else:
            if np.ndim(self.scales) != 1 or len(self.scales) != len(windows):
                raise ValueError(f'scales needs one factor per window ({len(windows)}), '
                                 f'got {self.scales!r}')
            scales = tuple(float(s) for s in self.scales)
            if not all(np.isfinite(s) and 0.0 < s <= 1.0 for s in scales):
                raise ValueError(f'every scale must be in (0, 1], got {scales}')
        max_count = self.max_count
        if isinstance(max_count, bool) or not isinstance(max_count, (int, np.integer)) \
                or max_count < 2:
            raise ValueError(f'max_count must be an int >= 2, got {max_count!r}')
        if self.interpolation not in INTERPOLATIONS:
            raise ValueError(f'interpolation must be one of {sorted(INTERPOLATIONS)}, '
                             f'got {self.interpolation!r}')
        if not isinstance(self.scan_once, (bool, np.bool_)):
            raise ValueError(f'scan_once must be true or false, got {self.scan_once!r}')
        object.__setattr__(self, 'windows_cells', windows)
        object.__setattr__(self, 'scan_once', bool(self.scan_once))
        object.__setattr__(self, 'scales', scales)
        object.__setattr__(self, 'max_count', int(max_count))

    @property
    def cv2_interpolation(self) -> int:
        """Return the ``cv2.INTER_*`` flag of :attr:`interpolation`."""
        return INTERPOLATIONS[self.interpolation]

    def to_dict(self) -> dict:
        """Plain types for YAML/JSON: lists for the tuples, the scales resolved."""
        return {'windows_cells': list(self.windows_cells), 'scales': list(self.scales),
                'max_count': self.max_count, 'interpolation': self.interpolation,
                'scan_once': self.scan_once}

    @classmethod
    def from_dict(cls, data: dict) -> FoveaConfig:
        """Inverse of :meth:`to_dict`; missing keys take the defaults, unknown keys are errors."""
        if not isinstance(data, dict):
            raise ValueError(f'a fovea configuration must be a mapping, got {type(data).__name__}')
        check_record(data, RECORD_TYPES, 'fovea')
        unknown = set(data) - set(RECORD_TYPES)
        if unknown:
            raise ValueError(f'unknown fovea settings: {sorted(unknown)}')
        values = dict(data)
        for key in ('windows_cells', 'scales'):
            if values.get(key) is not None:
                values[key] = tuple(values[key])
        return cls(**values)


class Window(NamedTuple):
    """One window of a fixation: where it is (cells and pixels) and the size it is resized to."""

    cells: tuple
    """``(row, col, n_rows, n_cols)``: first cell and extent in cells."""
    rect_px: tuple
    """``(x, y, width, height)`` in full-image pixels (OpenCV's rectangle order)."""
    resized_px: tuple
    """``(width, height)`` of the image the detector is given."""
    scale: float
    """The configured resize factor."""
    whole_image: bool
    """True if the window covers the whole grid, so it does not depend on the fixation."""


@dataclass(frozen=True, eq=False)
class Observation:
    """
    The count observation of one fixation, and what it cost.

    Attributes
    ----------
    counts : numpy.ndarray
        ``(N,)`` ``float64``: detections centred in each cell, summed over windows, clipped to
        ``0..max_count-1``; NaN for cells outside every window.
    raw_counts : numpy.ndarray
        ``(N,)`` ``int64``: the same counts before clipping (0 where not observed).
    fixation : int
        Row-major index of the fixated cell.
    windows : tuple of Window
        The windows, largest first.
    centres_px : numpy.ndarray
        ``(M, 2)`` ``float64``: ``x, y`` of every raw detection's centre in full-image pixels.
    window_index : numpy.ndarray
        ``(M,)`` ``int64``: the window each detection came from.
    scores : numpy.ndarray
        ``(M,)`` ``float64``: each detection's score (1 for a detector without scores).
    cells : numpy.ndarray
        ``(M,)`` ``int64``: the cell each detection was binned to.
    detector_pixels : int
        Pixels of the images given to the detector for this fixation (the resized windows);
        a window whose detections were reused from the cache counts 0.
    seconds : float
        Wall time of this fixation: resizing, detector and binning.
    from_cache : tuple of bool
        For each window, whether its detections were reused rather than computed.
    boxes_px : numpy.ndarray
        ``(M, 4)`` ``float64``: every raw detection's box ``x, y, w, h`` in full-image pixels.

    """

    counts: np.ndarray
    raw_counts: np.ndarray
    fixation: int
    windows: tuple
    centres_px: np.ndarray
    window_index: np.ndarray
    detector_pixels: int
    seconds: float
    from_cache: tuple
    scores: np.ndarray = None
    cells: np.ndarray = None
    boxes_px: np.ndarray = None


@dataclass(frozen=True, eq=False)
class Scan:
    """
    The one-time observation of the whole-image windows (``scan_once``), and what it cost.

    Attributes
    ----------
    counts : numpy.ndarray
        ``(N,)`` ``float64``: detections of the whole-image windows centred in each cell,
        clipped to ``0..max_count-1``; every cell is observed.
    raw_counts : numpy.ndarray
        ``(N,)`` ``int64``: the same counts before clipping.
    windows : tuple of Window
        The whole-image windows.
    centres_px : numpy.ndarray
        ``(M, 2)`` ``float64``: every raw detection's centre in full-image pixels.
    detector_pixels : int
        Pixels given to the detector (0 when the scan was already taken on this image).
    seconds : float
        Wall time of the scan.
    boxes_px : numpy.ndarray
        ``(M, 4)`` ``float64``: every raw detection's box ``x, y, w, h`` in full-image pixels.

    """

    counts: np.ndarray
    raw_counts: np.ndarray
    windows: tuple
    centres_px: np.ndarray
    detector_pixels: int
    seconds: float
    scores: np.ndarray = None
    cells: np.ndarray = None
    boxes_px: np.ndarray = None


def cell_edges_px(size_px: int, n_cells: int) -> np.ndarray:
    """First pixel of every cell and the end, ``floor(i * size_px / n_cells)``, shape (n+1,)."""
    return (np.arange(n_cells + 1, dtype=np.int64) * int(size_px)) // int(n_cells)


def window_cells(grid_shape: tuple[int, int], windows_cells, fixation_rc) -> np.ndarray:
    """
    Place the windows of one fixation: ``(K, 4)`` ``int64`` rows ``row, col, n_rows, n_cols``.

    Per axis a window of ``s`` cells covers ``n = min(s, G)`` cells starting at
    ``clip(p - s // 2, 0, G - n)``: centred on the fixated cell ``p`` and shifted (not cropped)
    to stay inside the grid of ``G`` cells.
    """
    sizes = np.asarray(windows_cells, dtype=np.int64)
    placed = []
    for axis_cells, p in zip(grid_shape, fixation_rc):
        n = np.minimum(sizes, axis_cells)
        placed.append((np.clip(p - sizes // 2, 0, axis_cells - n), n))
    (row, n_rows), (col, n_cols) = placed
    return np.stack([row, col, n_rows, n_cols], axis=1)


def _cover(fresh: np.ndarray, in_rows: np.ndarray, in_cols: np.ndarray) -> np.ndarray:
    """Return the cells (M, rows * cols) of each fixation's windows marked in ``fresh`` (M, K)."""
    cover = np.zeros((fresh.shape[0], in_rows.shape[2], in_cols.shape[2]), dtype=bool)
    for i in range(fresh.shape[1]):
        cover |= fresh[:, i, None, None] & in_rows[:, i, :, None] & in_cols[:, i, None, :]
    return cover.reshape(fresh.shape[0], cover.shape[1] * cover.shape[2])


def _resized(size_px: int, scale: float) -> int:
    """``round(size_px * scale)`` (halves up), at least 1."""
    return max(1, int(np.floor(size_px * scale + 0.5)))


class Fovea:
    """
    A digital fovea over one image at a time: ``start(image)``, then ``observe(fixation)``.

    Parameters
    ----------
    detector : callable
        ``detector(gray) -> (M, 4)`` raw boxes ``x, y, w, h`` (see
        :mod:`ipomdp_gaze.vision.detector`).
    grid : Grid or (int, int)
        The grid tiling every image, ``rows x cols`` (the paper: 21x21).
    config : FoveaConfig, optional
        Windows, scales, K and interpolation; the reference configuration by default.
    reuse_windows : bool
        Keep every window's detections for the current image, not only the whole-image window's.
    cells : CellObservation, optional
        What a cell's observation is (:mod:`ipomdp_gaze.model.cell_observation`); default the
        count of detections centred in it, clipped to ``config.max_count - 1``. Its K must be
        ``config.max_count``.

    Attributes
    ----------
    image_detector_pixels : int
        Detector pixels spent on the current image so far (all fixations).
    image_seconds : float
        Wall time spent on the current image so far: :meth:`start` (grey conversion) and every
        :meth:`observe`.
    n_fixations : int
        Fixations observed on the current image.

    """

    def __init__(self, detector, grid=(21, 21), config: FoveaConfig | None = None,
                 reuse_windows: bool = False, cells: CellObservation | None = None):
        if not callable(detector):
            raise ValueError(f'detector must be callable, got {type(detector).__name__}')
        self.detector = detector
        self.grid = grid if isinstance(grid, Grid) else Grid(*grid)
        self.config = FoveaConfig() if config is None else config
        if not isinstance(self.config, FoveaConfig):
            raise ValueError(f'config must be a FoveaConfig, got {type(self.config).__name__}')
        if self.config.scan_once and self.config.windows_cells[0] < max(self.grid.shape):
            raise ValueError(f'scan_once needs a whole-image window: the largest window '
                             f'({self.config.windows_cells[0]} cells) does not cover the '
                             f'{self.grid.rows}x{self.grid.cols} grid')
        self.reuse_windows = bool(reuse_windows)
        self.cells = CellObservation('counts', self.config.max_count) if cells is None else cells
        if not isinstance(self.cells, CellObservation) or \
                self.cells.max_count != self.config.max_count:
            raise ValueError(f'cells must be a CellObservation with K = max_count '
                             f'({self.config.max_count}), got {self.cells!r}')
        if self.cells.kind == 'grouped':
            raise ValueError('grouped cells are for one whole view (the pan/tilt head): the '
                             "fovea's windows see one face at several scales and would group "
                             'them apart')
        self._color = detector_color(detector)
        self._scales = np.asarray(self.config.scales)
        self._gray = None
        self._row_edges_px = self._col_edges_px = None
        self._cache = {}
        self._fresh = None              # fresh_views' windows of every fixation on this image
        self.image_detector_pixels = 0
        self.image_seconds = 0.0
        self.n_fixations = 0

    def settings(self) -> dict:
        """Grid, fovea and detector settings, as recorded in an observation file."""
        return {'grid': [self.grid.rows, self.grid.cols], 'fovea': self.config.to_dict(),
                'detector': detector_settings(self.detector)}

    @property
    def image_shape(self) -> tuple[int, int] | None:
        """``(H, W)`` of the current image, or ``None`` before :meth:`start`."""
        return None if self._gray is None else self._gray.shape[:2]

    def start(self, image: np.ndarray) -> None:
        """
        Take a new image (grey or RGB ``uint8``, see :func:`to_gray`) and forget the last one.

        The image is kept in the detector's colour space (:func:`to_detector_image`).

        Raises
        ------
        ValueError
            If the image is not a valid grey/RGB ``uint8`` image, is smaller than the detector's
            window, or has fewer pixels than the grid has cells along a side (a cell would be
            empty).

        """
        t0 = time.perf_counter()
        gray = to_detector_image(image, self._color, detector_window_px(self.detector))
        height, width = gray.shape[:2]
        if height < self.grid.rows or width < self.grid.cols:
            raise ValueError(f'image of {width}x{height} pixels (WxH) is smaller than the '
                             f'{self.grid.cols}x{self.grid.rows} grid: some cells would be empty')
        self._gray = gray
        self._row_edges_px = cell_edges_px(height, self.grid.rows)
        self._col_edges_px = cell_edges_px(width, self.grid.cols)
        self._cache = {}
        self._fresh = None
        self.image_detector_pixels = 0
        self.n_fixations = 0
        self.image_seconds = time.perf_counter() - t0

    def window_rects(self, fixation: int, image_shape=None) -> tuple[Window, ...]:
        """
        Place the windows of a fixation, in cells and pixels, largest first (also for plots).

        ``image_shape`` ``(H, W)`` defaults to the current image's.
        """
        row, col = self.grid.cell(fixation)
        if image_shape is None:
            if self._gray is None:
                raise RuntimeError('no image: call start(image) first or pass image_shape')
            row_edges, col_edges = self._row_edges_px, self._col_edges_px
        else:
            height, width = (int(v) for v in image_shape[:2])
            row_edges = cell_edges_px(height, self.grid.rows)
            col_edges = cell_edges_px(width, self.grid.cols)
        placed = window_cells(self.grid.shape, self.config.windows_cells, (row, col))
        whole = (placed[:, 2] == self.grid.rows) & (placed[:, 3] == self.grid.cols)
        y0, y1 = row_edges[placed[:, 0]], row_edges[placed[:, 0] + placed[:, 2]]
        x0, x1 = col_edges[placed[:, 1]], col_edges[placed[:, 1] + placed[:, 3]]
        windows = []
        for i, scale in enumerate(self.config.scales):
            width_px, height_px = int(x1[i] - x0[i]), int(y1[i] - y0[i])
            windows.append(Window(
                cells=tuple(int(v) for v in placed[i]),
                rect_px=(int(x0[i]), int(y0[i]), width_px, height_px),
                resized_px=(_resized(width_px, scale), _resized(height_px, scale)),
                scale=float(scale), whole_image=bool(whole[i])))
        return tuple(windows)

    def fixation_cost(self, fixation: int) -> int:
        """
        Detector pixels :meth:`observe` would spend on ``fixation`` now (windows not yet cached).

        With ``scan_once`` the whole-image windows are left out, as :meth:`observe` leaves them;
        a window that repeats an earlier one of the fixation, which :meth:`observe` serves from
        the cache once it has read it, is counted once.
        """
        read, pixels = set(), 0
        for w in self.window_rects(fixation):
            key = (w.cells, w.resized_px)
            if (self.config.scan_once and w.whole_image) or key in self._cache or key in read:
                continue
            pixels += w.resized_px[0] * w.resized_px[1]
            if w.whole_image or self.reuse_windows:
                read.add(key)
        return pixels

    def fresh_views(self) -> tuple[np.ndarray, np.ndarray]:
        """
        Return what a fixation at each cell would read afresh now: pixels (N,), cells (N, N).

        ``costs[k]`` is :meth:`fixation_cost` ``(k)``: the detector pixels of fixation k's
        windows not in the image's cache (nor a copy of an earlier window of the same
        fixation, which :meth:`observe` serves from the cache); ``cover[k, j]`` says cell j
        lies in one of those windows: the cells
        :func:`ipomdp_gaze.vision.search.fresh_counts` keeps of that fixation. A fixation
        whose every window is cached reads nothing (0, no cell). With ``scan_once`` the
        whole-image windows are left out, as :meth:`observe` leaves them. The windows of every
        fixation are placed once per image; the cover is recomputed when the cache grows.

        Raises
        ------
        RuntimeError
            Before :meth:`start`.

        """
        if self._gray is None:
            raise RuntimeError('no image: call start(image) first')
        f = self._fresh
        if f is None:
            f = self._fresh = self._fixation_windows()
        if f['seen'] != len(self._cache):
            for cells, resized in list(self._cache)[f['seen']:]:
                f['cached'] |= np.all(f['keys'] == (*cells, *resized), axis=-1)
            f['seen'] = len(self._cache)
            fresh = f['read'] & ~f['cached']
            changed = np.flatnonzero(np.any(fresh != f['fresh'], axis=1))   # their cover
            f['fresh'] = fresh
            f['costs'] = np.sum(np.where(fresh, f['pixels'], 0), axis=1).astype(float)
            f['cover'][changed] = _cover(fresh[changed], f['in_rows'][changed],
                                         f['in_cols'][changed])
        return f['costs'].copy(), f['cover'].copy()

    def _fixation_windows(self) -> dict:
        """
        Place the windows of every fixation on the current image (vectorised :meth:`window_rects`).

        ``keys`` (N, K, 6): each window's cache key ``row, col, n_rows, n_cols, width, height``;
        ``pixels`` (N, K); ``read`` (N, K): the windows :meth:`observe` reads, less a copy of an
        earlier window of its fixation that it would serve from the cache; ``in_rows`` (N, K,
        rows) and ``in_cols`` (N, K, cols): the cells each covers; and :meth:`fresh_views`'
        state with nothing cached: ``cached``, ``seen`` (cache entries taken into account),
        ``fresh``, ``cover`` and ``costs``.
        """
        grid, config = self.grid, self.config
        sizes = np.asarray(config.windows_cells, dtype=np.int64)
        rows_of, cols_of = grid.rows_cols()
        placed = []
        for axis_cells, p, edges in ((grid.rows, rows_of, self._row_edges_px),
                                     (grid.cols, cols_of, self._col_edges_px)):
            n = np.minimum(sizes, axis_cells)
            first = np.clip(p[:, None] - sizes // 2, 0, axis_cells - n)          # (N, K)
            placed.append((first, np.broadcast_to(n, first.shape),
                           edges[first + n] - edges[first]))
        (row, n_rows, height_px), (col, n_cols, width_px) = placed
        scales = np.asarray(config.scales)
        width = np.maximum(1, np.floor(width_px * scales + 0.5).astype(np.int64))
        height = np.maximum(1, np.floor(height_px * scales + 0.5).astype(np.int64))
        keys = np.stack([row, col, n_rows, n_cols, width, height], axis=-1)
        whole = (n_rows == grid.rows) & (n_cols == grid.cols)
        read = ~whole if config.scan_once else np.ones(whole.shape, dtype=bool)
        kept = whole | self.reuse_windows
        for i in range(1, keys.shape[1]):
            for j in range(i):
                read[:, i] &= ~(kept[:, j] & read[:, j]
                                & np.all(keys[:, i] == keys[:, j], axis=-1))
        in_rows = (np.arange(grid.rows) >= row[..., None]) \
            & (np.arange(grid.rows) < (row + n_rows)[..., None])
        in_cols = (np.arange(grid.cols) >= col[..., None]) \
            & (np.arange(grid.cols) < (col + n_cols)[..., None])
        pixels = width * height
        return {'keys': keys, 'pixels': pixels, 'read': read, 'in_rows': in_rows,
                'in_cols': in_cols, 'cached': np.zeros(read.shape, dtype=bool), 'seen': 0,
                'fresh': read, 'cover': _cover(read, in_rows, in_cols),
                'costs': np.sum(np.where(read, pixels, 0), axis=1).astype(float)}

    def scan_cost(self) -> int:
        """Detector pixels :meth:`scan` would spend now (0 without a scan or once done)."""
        if not self.config.scan_once:
            return 0
        return int(sum(w.resized_px[0] * w.resized_px[1] for w in self.window_rects(0)
                       if w.whole_image and (w.cells, w.resized_px) not in self._cache))

    def scan(self) -> Scan | None:
        """
        Observe the whole-image windows once (``scan_once``); None when the fovea has no scan.

        The first call after :meth:`start` runs the detector; later calls on the same image
        return the same counts at no detector cost.

        Raises
        ------
        RuntimeError
            Before :meth:`start`.

        """
        if not self.config.scan_once:
            return None
        t0 = time.perf_counter()
        windows = tuple(w for w in self.window_rects(0) if w.whole_image)
        centres, cells, scores, boxes, pixels = [], [], [], [], 0
        for window in windows:
            found, cost = self._detect(window)
            pixels += cost
            centres.append(found[0])
            cells.append(found[1])
            scores.append(found[2])
            boxes.append(found[3])
        cells, scores = np.concatenate(cells), np.concatenate(scores)
        raw = np.bincount(cells, minlength=self.grid.n_cells).astype(np.int64)
        counts = self.cells.values(cells, scores, self.grid.n_cells).astype(np.float64)
        seconds = time.perf_counter() - t0
        self.image_detector_pixels += pixels
        self.image_seconds += seconds
        return Scan(counts=counts, raw_counts=raw, windows=windows,
                    centres_px=np.concatenate(centres), detector_pixels=pixels, seconds=seconds,
                    scores=scores, cells=cells, boxes_px=np.concatenate(boxes))

    def observe(self, fixation: int) -> Observation:
        """
        Fixate a cell of the current image and return its count :class:`Observation`.

        With ``scan_once`` the whole-image windows are left out (they are :meth:`scan`'s).

        Raises
        ------
        RuntimeError
            Before :meth:`start`.
        ValueError
            If the fixation is not a cell of the grid, or the detector returns malformed boxes.

        """
        t0 = time.perf_counter()
        windows = self.window_rects(fixation)
        if self.config.scan_once:
            windows = tuple(w for w in windows if not w.whole_image)
        rows, cols = self.grid.shape
        observed = np.zeros((rows, cols), dtype=bool)
        cells, centres, scores, window_index, from_cache, boxes = [], [], [], [], [], []
        pixels = 0
        for i, window in enumerate(windows):
            row, col, n_rows, n_cols = window.cells
            observed[row:row + n_rows, col:col + n_cols] = True
            found, cost = self._detect(window)
            from_cache.append(cost == 0)
            pixels += cost
            centres.append(found[0])
            cells.append(found[1])
            scores.append(found[2])
            boxes.append(found[3])
            window_index.append(np.full(len(found[1]), i, dtype=np.int64))
        cells, scores = np.concatenate(cells), np.concatenate(scores)
        raw = np.bincount(cells, minlength=rows * cols).astype(np.int64)
        counts = np.where(observed.ravel(), self.cells.values(cells, scores, rows * cols),
                          np.nan)
        seconds = time.perf_counter() - t0
        self.image_detector_pixels += pixels
        self.image_seconds += seconds
        self.n_fixations += 1
        return Observation(counts=counts.astype(np.float64), raw_counts=raw,
                           fixation=self.grid.index(*self.grid.cell(fixation)),
                           windows=windows, centres_px=np.concatenate(centres),
                           window_index=np.concatenate(window_index), detector_pixels=pixels,
                           seconds=seconds, from_cache=tuple(from_cache), scores=scores,
                           cells=cells, boxes_px=np.concatenate(boxes))

    def _detect(self, window: Window) -> tuple[tuple, int]:
        """
        Return a window's detections (from the image's cache when it holds them) and their cost.

        The cost is the pixels given to the detector (0 from the cache). Whole-image windows are
        always kept for the image, the others with ``reuse_windows``.
        """
        key = (window.cells, window.resized_px)
        found = self._cache.get(key)
        if found is not None:
            return found, 0
        found = self._search(window)
        if window.whole_image or self.reuse_windows:
            self._cache[key] = found
        return found, window.resized_px[0] * window.resized_px[1]

    def _search(self, window: Window) -> tuple:
        """Detect in one window: centres ``(M, 2)``, cells, scores, boxes ``(M, 4)`` (image px)."""
        x, y, width_px, height_px = window.rect_px
        out_width, out_height = window.resized_px
        crop = self._gray[y:y + height_px, x:x + width_px]
        if (out_width, out_height) == (width_px, height_px):
            view = np.ascontiguousarray(crop)
        else:
            view = cv2.resize(crop, (out_width, out_height),
                              interpolation=self.config.cv2_interpolation)
        boxes, scores = detect(self.detector, view)
        back = np.array([width_px / out_width, height_px / out_height])
        centres = box_centres_px(boxes) * back + (x, y)
        boxes_px = np.concatenate([boxes[:, :2] * back + (x, y), boxes[:, 2:4] * back], axis=1)
        height, width = self._gray.shape[:2]
        row, col, n_rows, n_cols = window.cells
        cell_row = np.clip(np.floor(centres[:, 1] * self.grid.rows / height).astype(np.int64),
                           row, row + n_rows - 1)
        cell_col = np.clip(np.floor(centres[:, 0] * self.grid.cols / width).astype(np.int64),
                           col, col + n_cols - 1)
        return centres, cell_row * self.grid.cols + cell_col, scores, boxes_px
