# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
What a camera on a pan/tilt head sees: pixels to grid cells (docs/design.md section 6.5).

Pure geometry, numpy only. The grid is the controller's pan/tilt grid: cell ``(r, c)`` is the
head pose of :class:`ipomdp_gaze.model.head.PanTiltMap`, and directions are measured in grid units
from the grid's centre, columns to the right and rows down (as image x and y).

A view taken with the head at grid position ``(r_h, c_h)`` (the cell it was sent to, or the
unrounded position its joint angles give, :meth:`ipomdp_gaze.model.head.PanTiltMap.position`) by a
pinhole camera with intrinsics ``K = [fx 0 cx; 0 fy cy; 0 0 1]`` shows pixel ``(u, v)`` at the
cell::

    col = round(c_h + atan((u - cx) / fx) / spacing)
    row = round(r_h + atan((v - cy) / fy) / spacing)

with the angles in the unit of ``spacing`` and halves rounded up. ``(u, v)`` are OpenCV / ROS
pixel coordinates, in which the centre of the top-left pixel is ``(0, 0)``. The mapping is
separable and monotone, so a view shows a rectangle of cells: those that the centres of its
first and last pixel columns and rows fall in (:func:`view_extent`). Every other cell is **not
observed** (NaN in a count frame), and a point whose cell lies outside the grid is not counted.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from ipomdp_gaze.model.checks import finite as _finite, is_number, short_repr
from ipomdp_gaze.model.grid import Grid
import numpy as np

# What a camera's K is (camera_info.k, an observation file's image.camera.K).
K_WORDS = '9 finite numbers (the 3x3 camera matrix, row-major)'


@dataclass(frozen=True)
class PinholeCamera:
    """
    Image size and intrinsics of a pinhole camera (``camera_info``: width, height and K).

    ``cx`` and ``cy`` are in OpenCV / ROS pixel coordinates (the top-left pixel's centre is
    ``(0, 0)``); lens distortion is not modelled.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    def __post_init__(self):
        for name in ('width', 'height'):
            value = getattr(self, name)
            if isinstance(value, bool) or int(value) != value or value < 1:
                raise ValueError(f'camera {name} must be a positive integer, got {value!r}')
            object.__setattr__(self, name, int(value))
        for name in ('fx', 'fy', 'cx', 'cy'):
            object.__setattr__(self, name, _finite(f'camera {name}', getattr(self, name)))
        if self.fx <= 0 or self.fy <= 0:
            raise ValueError(f'camera fx and fy must be > 0, got {self.fx!r}, {self.fy!r}')

    @classmethod
    def from_fov(cls, width: int, height: int, hfov_deg: float) -> PinholeCamera:
        """Square pixels, the principal point at the image centre, ``hfov_deg`` edge to edge."""
        hfov = _finite('hfov_deg', hfov_deg)
        if not 0 < hfov < 180:
            raise ValueError(f'hfov_deg must be in (0, 180), got {hfov_deg!r}')
        fx = (width / 2.0) / math.tan(math.radians(hfov) / 2.0)
        return cls(width, height, fx, fx, (width - 1) / 2.0, (height - 1) / 2.0)

    @classmethod
    def from_k(cls, width: int, height: int, k) -> PinholeCamera:
        """
        Build a camera from ``camera_info``'s size and K (9 numbers, row-major).

        Raises
        ------
        ValueError
            If K is not :data:`K_WORDS` with ``fx, fy > 0``, a zero skew and a last row ``0 0 1``,
            or the size is not positive.

        """
        try:                                # a nested [[...], ...] or text is no K either
            values = [float(x) if is_number(x) else math.nan for x in k]
        except TypeError:
            values = []
        if len(values) != 9 or not all(math.isfinite(x) for x in values):
            raise ValueError(f'K must be {K_WORDS}, got '
                             f'{short_repr(k.tolist() if isinstance(k, np.ndarray) else k, 60)}')
        if values[1] != 0 or values[3] != 0 or values[6:] != [0.0, 0.0, 1.0]:
            raise ValueError(f'K must be [fx, 0, cx, 0, fy, cy, 0, 0, 1], got {values}')
        return cls(width, height, values[0], values[4], values[2], values[5])

    @property
    def k(self) -> list[float]:
        """Return K row-major, as ``camera_info.k``."""
        return [self.fx, 0.0, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0]

    @property
    def fov_deg(self) -> tuple[float, float]:
        """Horizontal and vertical field of view in degrees, between the image's outer edges."""
        left, top = self.angles_deg(-0.5, -0.5)
        right, bottom = self.angles_deg(self.width - 0.5, self.height - 0.5)
        return float(right - left), float(bottom - top)

    def angles_deg(self, u, v):
        """Directions ``(atan((u - cx) / fx), atan((v - cy) / fy))`` in degrees of pixels."""
        return (np.degrees(np.arctan((np.asarray(u, dtype=float) - self.cx) / self.fx)),
                np.degrees(np.arctan((np.asarray(v, dtype=float) - self.cy) / self.fy)))

    def to_dict(self) -> dict:
        """``{width, height, K}``: what an observation file records."""
        return {'width': self.width, 'height': self.height, 'K': [float(x) for x in self.k]}

    @classmethod
    def from_dict(cls, data: dict) -> PinholeCamera:
        """Inverse of :meth:`to_dict`."""
        try:
            return cls.from_k(data['width'], data['height'], data['K'])
        except (KeyError, TypeError):
            raise ValueError(f'a camera record must be {{width, height, K}}, got '
                             f'{data!r}') from None

    def matches(self, other: PinholeCamera, rel_tol: float = 1e-3) -> bool:
        """Whether both have the same size and, within ``rel_tol`` of fx, the same K."""
        return (self.width, self.height) == (other.width, other.height) and all(
            abs(a - b) <= rel_tol * self.fx for a, b in zip(self.k, other.k))


def pixel_cells(u, v, camera: PinholeCamera, head_rc, spacing_deg: float):
    """
    Nearest grid ``(row, col)`` (int arrays, possibly outside the grid) of pixels ``(u, v)``.

    ``head_rc`` is the head's grid position ``(r_h, c_h)``, an integer cell or a real position.
    """
    row, col = pixel_positions(u, v, camera, head_rc, spacing_deg)
    return np.floor(row + 0.5).astype(np.int64), np.floor(col + 0.5).astype(np.int64)


def pixel_positions(u, v, camera: PinholeCamera, head_rc, spacing_deg: float):
    """Grid positions ``(row, col)`` (float arrays, cells) of pixels ``(u, v)``."""
    du, dv = camera.angles_deg(u, v)
    return head_rc[0] + dv / spacing_deg, head_rc[1] + du / spacing_deg


def view_extent(camera: PinholeCamera, grid: Grid, head_rc) -> tuple[int, int, int, int]:
    """
    Cells a view shows: ``(row0, row1, col0, col1)``, inclusive, clipped to the grid.

    The range is empty (``row0 > row1`` or ``col0 > col1``) when the view misses the grid.
    """
    rows, cols = pixel_cells([0, camera.width - 1], [0, camera.height - 1], camera, head_rc,
                             grid.spacing_deg)
    return (max(int(rows[0]), 0), min(int(rows[1]), grid.rows - 1),
            max(int(cols[0]), 0), min(int(cols[1]), grid.cols - 1))


def observed_cells(camera: PinholeCamera, grid: Grid, head_rc) -> np.ndarray:
    """Row-major mask ``(N,)`` of the cells a view from ``head_rc`` shows."""
    row0, row1, col0, col1 = view_extent(camera, grid, head_rc)
    mask = np.zeros(grid.shape, dtype=bool)
    if row0 <= row1 and col0 <= col1:
        mask[row0:row1 + 1, col0:col1 + 1] = True
    return mask.reshape(-1)


def bin_points(centres_uv: np.ndarray, camera: PinholeCamera, grid: Grid, head_rc,
               max_count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Count points of a view per cell: ``(counts, raw_counts, cells)``.

    ``counts`` is ``(N,)`` float64, clipped to ``0..max_count-1``, NaN outside the view;
    ``raw_counts`` the unclipped ``int64`` counts; ``cells`` the cell index of each point, -1
    for a point whose cell lies outside the grid (it is not counted).
    """
    centres = np.asarray(centres_uv, dtype=float).reshape(-1, 2)
    row, col = pixel_cells(centres[:, 0], centres[:, 1], camera, head_rc, grid.spacing_deg)
    inside = (row >= 0) & (row < grid.rows) & (col >= 0) & (col < grid.cols)
    cells = np.where(inside, row * grid.cols + col, -1)
    raw = np.bincount(cells[inside], minlength=grid.n_cells).astype(np.int64)
    observed = observed_cells(camera, grid, head_rc)
    counts = np.where(observed, np.minimum(raw, max_count - 1), np.nan).astype(np.float64)
    return counts, raw, cells


def point_offsets(centres_uv: np.ndarray, camera: PinholeCamera, grid: Grid,
                  head_rc) -> np.ndarray:
    """
    Mean offset of a view's points from the centre of the cell they are binned to, per cell.

    Returns ``(N, 2)`` float64 ``(row, col)`` offsets in cells, each within half a cell, NaN
    for a cell without a point: where in its cell a detected face is (docs/design.md 12.9).
    """
    centres = np.asarray(centres_uv, dtype=float).reshape(-1, 2)
    pos = np.stack(pixel_positions(centres[:, 0], centres[:, 1], camera, head_rc,
                                   grid.spacing_deg), axis=1)
    cell_rc = np.floor(pos + 0.5)
    inside = (cell_rc[:, 0] >= 0) & (cell_rc[:, 0] < grid.rows) & (cell_rc[:, 1] >= 0) \
        & (cell_rc[:, 1] < grid.cols)
    cells = (cell_rc[inside, 0] * grid.cols + cell_rc[inside, 1]).astype(np.int64)
    n = np.bincount(cells, minlength=grid.n_cells).astype(np.float64)
    out = np.full((grid.n_cells, 2), np.nan)
    has = n > 0
    for axis in (0, 1):
        total = np.bincount(cells, weights=pos[inside, axis] - cell_rc[inside, axis],
                            minlength=grid.n_cells)
        out[has, axis] = total[has] / n[has]
    return out
