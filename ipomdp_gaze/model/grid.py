# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Grid geometry of the visual array: cell index <-> (row, col) <-> offsets in degrees.

Cells are row-major, ``i = r * cols + c``; row 0 is the top and column 0 the left, as in an
image. Offsets of cell ``j`` seen from fixation ``k`` are ``dy = spacing_deg * (r_j - r_k)`` and
``dx = spacing_deg * (c_j - c_k)``.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import re

from ipomdp_gaze.model.checks import is_number
import numpy as np

_GRID_RE = re.compile(r'^\s*(\d+)\s*[xX]\s*(\d+)\s*$')


def parse_grid(text: str) -> tuple[int, int]:
    """
    Parse ``'ROWSxCOLS'`` (for example ``'7x7'``) into ``(rows, cols)``.

    Raises
    ------
    ValueError
        If the text is not two positive integers joined by ``x``.

    """
    match = _GRID_RE.match(str(text))
    if not match:
        raise ValueError(f'grid must look like ROWSxCOLS, e.g. 7x7, got {text!r}')
    rows, cols = int(match.group(1)), int(match.group(2))
    if rows < 1 or cols < 1:
        raise ValueError(f'grid must have at least one row and one column, got {text!r}')
    return rows, cols


@dataclass(frozen=True)
class Grid:
    """A ``rows x cols`` visual array with ``spacing_deg`` degrees between neighbouring cells."""

    rows: int
    cols: int
    spacing_deg: float = 0.42

    def __post_init__(self):
        for name in ('rows', 'cols'):
            value = getattr(self, name)
            try:                        # None, 'x', inf, nan, [3]: refused by name, as 2.5 is
                whole = not isinstance(value, bool) and int(value) == value and value >= 1
            except (TypeError, ValueError, OverflowError):
                whole = False
            if not whole:
                raise ValueError(f'{name} must be a positive integer, got {value!r}')
            object.__setattr__(self, name, int(value))
        spacing = float(self.spacing_deg) if is_number(self.spacing_deg) else math.nan
        if not np.isfinite(spacing) or spacing <= 0:
            raise ValueError(
                f'spacing_deg must be a positive finite number, got {self.spacing_deg!r}')
        object.__setattr__(self, 'spacing_deg', spacing)

    @property
    def n_cells(self) -> int:
        """Return the number of cells N = rows * cols."""
        return self.rows * self.cols

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)``."""
        return (self.rows, self.cols)

    @property
    def kernel_shape(self) -> tuple[int, int]:
        """Shape ``(2*rows-1, 2*cols-1)`` of an offset table or a convolutional kernel."""
        return (2 * self.rows - 1, 2 * self.cols - 1)

    @property
    def center_index(self) -> int:
        """Index of the centre cell (the upper-left of the central four on even sizes)."""
        return self.index((self.rows - 1) // 2, (self.cols - 1) // 2)

    def index(self, row, col):
        """Row-major cell index ``row * cols + col`` (scalars checked in the grid, or arrays)."""
        if np.ndim(row) or np.ndim(col):
            return np.asarray(row) * self.cols + np.asarray(col)
        row, col = _whole(row, 'row'), _whole(col, 'column')
        if not (0 <= row < self.rows and 0 <= col < self.cols):
            raise ValueError(f'cell ({row}, {col}) is outside a {self.rows}x{self.cols} grid')
        return row * self.cols + col

    def cell(self, index):
        """``(row, col)`` of a cell index (scalars or arrays)."""
        if np.ndim(index):
            index = np.asarray(index)
            return index // self.cols, index % self.cols
        index = _whole(index, 'cell index')
        if not 0 <= index < self.n_cells:
            raise ValueError(f'cell index {index} is outside a {self.rows}x{self.cols} grid')
        return divmod(index, self.cols)

    def rows_cols(self) -> tuple[np.ndarray, np.ndarray]:
        """Row and column of every cell, each of shape (N,)."""
        idx = np.arange(self.n_cells)
        return idx // self.cols, idx % self.cols

    def offsets_deg(self, fixation: int) -> tuple[np.ndarray, np.ndarray]:
        """Offsets ``(dx, dy)`` in degrees of every cell seen from ``fixation``, shape (N,)."""
        rf, cf = self.cell(fixation)
        r, c = self.rows_cols()
        with np.errstate(over='ignore'):        # past the largest double: infinitely far, d' 0
            return self.spacing_deg * (c - cf), self.spacing_deg * (r - rf)

    def fixation_window(self, table: np.ndarray, row: int, col: int) -> np.ndarray:
        """
        Return the ``(rows, cols)`` view of an offset table centred on fixation ``(row, col)``.

        ``table`` has shape ``(2*rows-1, 2*cols-1, ...)`` with entry ``[dr + rows-1, dc + cols-1]``
        for a cell ``dr`` rows and ``dc`` columns from the fixation (:meth:`offset_table_deg`,
        a d' table, ELM's kernel); the view's entry ``[i, j]`` is cell ``(i, j)``'s. No copy.
        """
        return table[self.rows - 1 - row:2 * self.rows - 1 - row,
                     self.cols - 1 - col:2 * self.cols - 1 - col]

    def offset_table_deg(self) -> tuple[np.ndarray, np.ndarray]:
        """
        Offsets ``(dx, dy)`` of shape ``(2*rows-1, 2*cols-1)``.

        Entry ``[r_j - r_k + rows-1, c_j - c_k + cols-1]`` is the offset of cell j seen from k, so
        large grids never need an N x N array.
        """
        dr = np.arange(-(self.rows - 1), self.rows)
        dc = np.arange(-(self.cols - 1), self.cols)
        with np.errstate(over='ignore'):        # past the largest double: infinitely far, d' 0
            dy, dx = np.meshgrid(self.spacing_deg * dr, self.spacing_deg * dc, indexing='ij')
        return dx, dy

    def pair_offset_index(self) -> tuple[np.ndarray, np.ndarray]:
        """
        Return indices into an offset table for every (fixation k, cell j) pair, each (N, N).

        ``table[ri[k, j], ci[k, j]]`` is the entry for cell j seen from fixation k.
        """
        r, c = self.rows_cols()
        ri = r[None, :] - r[:, None] + self.rows - 1
        ci = c[None, :] - c[:, None] + self.cols - 1
        return ri, ci

    def to_dict(self) -> dict:
        """``{'rows', 'cols', 'spacing_deg'}`` as written to JSON and policy files."""
        return {'rows': self.rows, 'cols': self.cols, 'spacing_deg': self.spacing_deg}


def _whole(value, what: str) -> int:
    """
    Return a scalar cell coordinate as an int; a fraction (1.5) is refused, not truncated.

    A bool (numpy's too) is refused: ``True`` is no cell, though Python counts it as 1.
    """
    if type(value) is int:                      # the controller's every frame: no more work
        return value
    try:
        whole = int(value)
        exact = whole == value and not isinstance(value, (bool, np.bool_))
    except (TypeError, ValueError, OverflowError):
        exact = False
    if not exact:
        raise ValueError(f'a {what} must be a whole number, got {value!r}')
    return whole
