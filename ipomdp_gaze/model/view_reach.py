# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Which cells a pan/tilt view sees, and which it sees well (docs/design.md section 6.16).

A view ``view_cells`` wide (the camera's field of view over the grid's spacing) sees the cells
at offsets up to ``seen = floor(view_cells / 2 - 1/2)`` from its centre, and sees them *well*
up to ``well``, the offsets whose cell's outer edge lies :data:`TILE_MARGIN_CELLS` or more inside
the image: a face near the outer edge of a cell at the border is cut by the image, and a
detector misses a cut face. Along an axis a view sees a cell whole when it sees it well, and
otherwise only the cell's half nearer the view's centre. A cell is *covered* by a set of views
when each of its four quarters is seen whole by one of them (views on both sides of a cell each
see the half the other cuts). The sweep's tiles (``policies.baselines.sweep_tiles``) are the
fewest views that cover every cell; ``search.absent_needs_coverage`` holds ``absent`` back until
the views of a search have.
"""
from __future__ import annotations

import math
from typing import NamedTuple

from ipomdp_gaze.model.grid import Grid
import numpy as np

# A cell is seen well from a view when its outer edge lies this far (in cells) inside the image.
TILE_MARGIN_CELLS = 0.25
# A view's width in cells is rounded down to whole cells after adding this: arctan's last bits
# (numpy 1.x gave a 25-degree view as 24.999999999999996 degrees) must not cost a cell.
WHOLE_CELL_TOL = 1e-9


def view_cells(grid: Grid, model) -> tuple[float, float] | None:
    """Return the camera's field of view in cells ``(rows, cols)`` (None without one)."""
    image = (getattr(model, 'meta', None) or {}).get('image') or {}
    camera = image.get('camera') if image.get('view') == 'pan_tilt' else None
    if not camera:
        return None
    from ipomdp_gaze.model.head_camera import PinholeCamera
    hfov, vfov = PinholeCamera.from_dict(camera).fov_deg
    return vfov / grid.spacing_deg, hfov / grid.spacing_deg


def axis_reach(cells: float) -> tuple[int, int]:
    """Return ``(seen, well)``: the offsets a view ``cells`` wide sees, and sees well."""
    seen = max(0, math.floor(cells / 2 - 0.5 + WHOLE_CELL_TOL))
    well = min(seen, max(0, math.floor(cells / 2 - 0.5 - TILE_MARGIN_CELLS + WHOLE_CELL_TOL)))
    return seen, well


def axis_covered(offset: np.ndarray, seen: int, well: int) -> np.ndarray:
    """
    Return, per row of ``offset`` (cell minus view centre, one column per view), coverage.

    Covered: a view sees it well, or views on both of its sides see it.
    """
    offset = np.asarray(offset)
    near = np.abs(offset)
    sees = near <= seen
    return ((near <= well).any(axis=-1)
            | ((sees & (offset >= 0)).any(axis=-1) & (sees & (offset <= 0)).any(axis=-1)))


class ViewReach(NamedTuple):
    """A camera's reach on a grid: ``seen`` and ``well`` offsets, ``(rows, cols)`` each."""

    seen: tuple[int, int]
    well: tuple[int, int]

    @classmethod
    def of(cls, grid: Grid, model) -> 'ViewReach | None':
        """Return the reach of ``model``'s pan/tilt camera on ``grid`` (None without one)."""
        view = view_cells(grid, model)
        if view is None:
            return None
        (seen_r, well_r), (seen_c, well_c) = axis_reach(view[0]), axis_reach(view[1])
        return cls((seen_r, seen_c), (well_r, well_c))

    def covered(self, grid: Grid, views) -> np.ndarray:
        """Return which cells the views at cells ``views`` cover, (N,) bool."""
        views = np.unique(np.asarray(views, dtype=np.int64).reshape(-1))
        if not views.size:
            return np.zeros(grid.n_cells, dtype=bool)
        rows, cols = grid.rows_cols()
        vr, vc = np.divmod(views, grid.cols)
        halves = []                       # per axis: (low half seen, high half seen), (N, V)
        for axis, (here, there) in enumerate(((rows, vr), (cols, vc))):
            offset = here.reshape(-1, 1) - there.reshape(1, -1)
            whole = np.abs(offset) <= self.well[axis]
            halves.append((whole | (offset > 0), whole | (offset < 0)))
        sees = ((np.abs(rows.reshape(-1, 1) - vr) <= self.seen[0])
                & (np.abs(cols.reshape(-1, 1) - vc) <= self.seen[1]))
        covered = np.ones(grid.n_cells, dtype=bool)
        for row_half in halves[0]:        # each quarter: a row half and a column half
            for col_half in halves[1]:
                covered &= (sees & row_half & col_half).any(axis=1)
        return covered

    def sees_well(self, grid: Grid, cells) -> np.ndarray:
        """Return which views (every cell as a view centre) see one of ``cells`` well, (N,)."""
        cells = np.asarray(cells, dtype=np.int64).reshape(-1)
        rows, cols = grid.rows_cols()
        cr, cc = np.divmod(cells, grid.cols)
        return ((np.abs(rows.reshape(-1, 1) - cr) <= self.well[0])
                & (np.abs(cols.reshape(-1, 1) - cc) <= self.well[1])).any(axis=1)
