# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Grid-shaped arrays <-> ``std_msgs`` multi-arrays (docs/design.md section 5).

The layout of a ``rows x cols`` grid is
``dim[0] = {label: 'rows', size: rows, stride: rows*cols}``,
``dim[1] = {label: 'cols', size: cols, stride: cols}``, ``data_offset = 0``, data row-major.
Incoming arrays with an empty layout are read as row-major of the node's grid when their length
fits; a layout that disagrees with the grid makes the frame invalid (:class:`LayoutError`).

A walking face's truth per frame (``walk_truth``, a ``Float64MultiArray``, docs/design.md
section 12.6) is ``[stamp_sec, stamp_nanosec, t_s, row, col, cell_row, cell_col]``: the frame's
stamp, the walk's time, the face centre's grid position (not rounded) and its cell, ``-1, -1``
out of the grid's reach.
"""
from __future__ import annotations

import array
from dataclasses import dataclass
import math

from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.grid import Grid
import numpy as np
from std_msgs.msg import (Float32MultiArray, Float64MultiArray, Int32MultiArray,
                          MultiArrayDimension, MultiArrayLayout)


class LayoutError(EvidenceError):
    """A message layout that does not describe the node's grid."""


def grid_layout(grid: Grid) -> MultiArrayLayout:
    """Build the two-dimension row-major layout of ``grid``."""
    return MultiArrayLayout(
        dim=[MultiArrayDimension(label='rows', size=grid.rows, stride=grid.n_cells),
             MultiArrayDimension(label='cols', size=grid.cols, stride=grid.cols)],
        data_offset=0)


def to_multiarray(values, grid: Grid) -> Float32MultiArray:
    """
    Pack ``values`` (N,) or (rows, cols) in a ``Float32MultiArray`` with the grid layout.

    Raises
    ------
    ValueError
        If ``values`` does not have one entry per cell.

    """
    a = np.ascontiguousarray(values, dtype=np.float32)
    if a.size != grid.n_cells or a.shape not in ((grid.n_cells,), grid.shape):
        raise ValueError(f'expected {grid.n_cells} values (shape ({grid.n_cells},) or '
                         f'{grid.shape}), got shape {a.shape}')
    msg = Float32MultiArray(layout=grid_layout(grid))
    msg.data = array.array('f', a.tobytes())
    return msg


def check_layout(layout: MultiArrayLayout, grid: Grid) -> None:
    """
    Raise :class:`LayoutError` unless ``layout`` is empty or describes ``grid`` row-major.

    Accepted: no dimensions; one dimension of size N; or two of sizes (rows, cols). A stride of 0
    counts as unset; any other stride must be the row-major one. ``data_offset`` must be 0.
    """
    if layout.data_offset != 0:
        raise LayoutError(f'layout.data_offset is {layout.data_offset}, expected 0')
    dims = list(layout.dim)
    if not dims:
        return
    if len(dims) == 1:
        expected = [(grid.n_cells, grid.n_cells)]
    elif len(dims) == 2:
        expected = [(grid.rows, grid.n_cells), (grid.cols, grid.cols)]
    else:
        raise LayoutError(f'layout has {len(dims)} dimensions, expected 2 '
                          f'({grid.rows} rows x {grid.cols} cols)')
    for dim, (size, stride) in zip(dims, expected):
        if dim.size != size:
            sizes = 'x'.join(str(d.size) for d in dims)
            want = 'x'.join(str(size) for size, _ in expected)
            raise LayoutError(f'layout is {sizes}, the grid is {want} '
                              f'({grid.rows} rows x {grid.cols} cols)')
        if dim.stride not in (0, stride):
            raise LayoutError(f"layout dimension '{dim.label}' has stride {dim.stride}, "
                              f'expected {stride} (row-major {grid.rows}x{grid.cols})')


def from_multiarray(msg, grid: Grid) -> np.ndarray:
    """
    Read a grid-shaped ``Float32MultiArray`` as float64 values, shape (N,).

    The layout is checked (:func:`check_layout`) and the length must be N; the values themselves
    (NaN, inf) are left for :func:`ipomdp_gaze.model.belief.check_evidence`.

    Raises
    ------
    LayoutError
        If the layout disagrees with the grid.
    EvidenceError
        If the data does not have one value per cell.

    """
    check_layout(msg.layout, grid)
    values = np.asarray(msg.data, dtype=np.float32)
    if values.size != grid.n_cells:
        raise EvidenceError(f'evidence has {values.size} values, expected {grid.n_cells} '
                            f'({grid.rows}x{grid.cols} grid)')
    return values.astype(np.float64)


def row_col(grid: Grid, cell: int | None) -> Int32MultiArray:
    """Build an ``Int32MultiArray`` ``[row, col]`` of a cell (``fixation``, ``ground_truth``)."""
    row, col = (-1, -1) if cell is None else grid.cell(cell)
    msg = Int32MultiArray(layout=MultiArrayLayout(
        dim=[MultiArrayDimension(label='row_col', size=2, stride=2)], data_offset=0))
    msg.data = [int(row), int(col)]
    return msg


def fixation(grid: Grid, cell: int | None, search_id: int) -> Int32MultiArray:
    """
    Build the controller's ``fixation``: ``[row, col, search_id]``, or ``[-1, -1, search_id]``.

    ``[-1, -1, id]`` asks the detector for the one-time scan of search ``id`` (``cell`` None);
    the id tells the detector which search a request belongs to, so that a reset is seen and a
    frame is never paired with the wrong search.
    """
    row, col = (-1, -1) if cell is None else grid.cell(cell)
    msg = Int32MultiArray(layout=MultiArrayLayout(
        dim=[MultiArrayDimension(label='row_col_search', size=3, stride=3)], data_offset=0))
    msg.data = [int(row), int(col), int(search_id)]
    return msg


def read_fixation(msg, grid: Grid) -> tuple[int | None, int | None]:
    """
    Return ``(cell, search_id)`` of a ``fixation``: cell None for a scan request.

    ``[row, col]`` (no id, an older controller) gives ``(cell, None)``.

    Raises
    ------
    ValueError
        If the message is not ``[row, col]``, ``[row, col, id]`` or ``[-1, -1, id]`` with a
        cell inside the grid and an id >= 0.

    """
    data = list(msg.data)
    if len(data) not in (2, 3):
        raise ValueError(f'fixation must be [row, col] or [row, col, search_id], got {data}')
    if len(data) == 2:
        return cell_from_row_col(msg, grid, 'fixation'), None
    row, col, search_id = data
    if search_id < 0:
        raise ValueError(f'fixation search_id must be >= 0, got {search_id}')
    if (row, col) == (-1, -1):
        return None, int(search_id)
    if not (0 <= row < grid.rows and 0 <= col < grid.cols):
        raise ValueError(f'fixation ({row}, {col}) is outside the {grid.rows}x{grid.cols} grid')
    return grid.index(row, col), int(search_id)


def ground_truth(grid: Grid, cell: int | None) -> Int32MultiArray:
    """Build a camera's ground truth: ``data = [row, col]``, ``[-1, -1]`` for an empty scene."""
    return row_col(grid, cell)


def cell_from_row_col(msg, grid: Grid, what: str = 'a cell',
                      allow_empty: bool = False) -> int | None:
    """
    Return the cell index of an ``Int32MultiArray`` ``[row, col]`` (``what`` names it).

    With ``allow_empty``, ``[-1, -1]`` (no target) gives None.

    Raises
    ------
    ValueError
        If the message is not two integers inside the grid (or ``[-1, -1]`` when allowed).

    """
    data = list(msg.data)
    if len(data) != 2:
        raise ValueError(f'{what} must be [row, col], got {data}')
    row, col = data
    if allow_empty and (row, col) == (-1, -1):
        return None
    if not (0 <= row < grid.rows and 0 <= col < grid.cols):
        raise ValueError(f'{what} ({row}, {col}) is outside the '
                         f'{grid.rows}x{grid.cols} grid')
    return grid.index(row, col)


def cell_from_ground_truth(msg, grid: Grid) -> int | None:
    """Return the cell of a ground-truth ``[row, col]`` message, None for ``[-1, -1]`` (empty)."""
    return cell_from_row_col(msg, grid, 'ground truth', allow_empty=True)


WALK_TRUTH_FIELDS = ('stamp_sec', 'stamp_nanosec', 't_s', 'row', 'col', 'cell_row', 'cell_col')


@dataclass(frozen=True)
class WalkTruth:
    """One frame's walk truth: its stamp, the walk's time, the face's position and cell."""

    stamp: tuple
    t_s: float
    position: tuple
    cell: tuple | None


def walk_truth(stamp, t_s: float, position, cell) -> Float64MultiArray:
    """Build ``walk_truth`` of a frame (module docstring); ``cell`` None out of reach."""
    row, col = (-1, -1) if cell is None else cell
    msg = Float64MultiArray(layout=MultiArrayLayout(
        dim=[MultiArrayDimension(label=','.join(WALK_TRUTH_FIELDS), size=7, stride=7)],
        data_offset=0))
    msg.data = [float(stamp.sec), float(stamp.nanosec), float(t_s), float(position[0]),
                float(position[1]), float(row), float(col)]
    return msg


def read_walk_truth(msg, grid: Grid) -> WalkTruth:
    """
    Return the :class:`WalkTruth` of a ``walk_truth`` message.

    Raises
    ------
    ValueError
        If it is not 7 finite values whose stamp is whole and whose cell is in the grid or
        ``-1, -1``.

    """
    data = [float(v) for v in msg.data]
    if len(data) != len(WALK_TRUTH_FIELDS) or not all(math.isfinite(v) for v in data):
        raise ValueError(f'walk_truth must be 7 finite values ({", ".join(WALK_TRUTH_FIELDS)}), '
                         f'got {data}')
    sec, nanosec, t_s, row, col, cell_row, cell_col = data
    if sec != int(sec) or nanosec != int(nanosec) or not 0 <= nanosec < 1e9:
        raise ValueError(f'walk_truth stamp must be whole seconds and nanoseconds, got '
                         f'{sec}, {nanosec}')
    cell = (int(cell_row), int(cell_col))
    if cell == (-1, -1) and (cell_row, cell_col) == (-1.0, -1.0):
        cell = None
    elif cell != (cell_row, cell_col) or not (0 <= cell[0] < grid.rows
                                              and 0 <= cell[1] < grid.cols):
        raise ValueError(f'walk_truth cell ({cell_row:g}, {cell_col:g}) is outside the '
                         f'{grid.rows}x{grid.cols} grid')
    return WalkTruth((int(sec), int(nanosec)), t_s, (row, col), cell)
