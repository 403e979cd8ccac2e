# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Grid cells <-> pan/tilt joint angles of a head: pure geometry, no messages.

REP 103 (x forward, y left, z up): positive pan turns left, positive tilt looks down. With row 0
at the top and column 0 at the left (docs/design.md section 5)::

    pan_rad  = pan_sign  * -(col - (cols-1)/2) * spacing_rad + pan_offset_rad
    tilt_rad = tilt_sign *  (row - (rows-1)/2) * spacing_rad + tilt_offset_rad

Signs, offsets and limits are parameters because real heads differ. Every cell of the grid must
lie inside the joint limits: the model needs every cell to be reachable, so a grid that does not
fit the head is refused instead of being clamped silently. The head command messages are built
by :mod:`ipomdp_gaze.msg_adapters.joints`.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from ipomdp_gaze.model.grid import Grid
import numpy as np


@dataclass(frozen=True)
class PanTiltMap:
    """How grid cells map to the pan and tilt joints of a head."""

    grid: Grid
    pan_joint: str = 'pan_joint'
    tilt_joint: str = 'tilt_joint'
    pan_sign: int = 1
    tilt_sign: int = 1
    pan_offset_rad: float = 0.0
    tilt_offset_rad: float = 0.0
    pan_limits_rad: tuple = (-math.pi, math.pi)
    tilt_limits_rad: tuple = (-math.pi / 2, math.pi / 2)

    def __post_init__(self):
        for name in ('pan_joint', 'tilt_joint'):
            if not str(getattr(self, name)).strip():
                raise ValueError(f'{name} must be a non-empty joint name')
        if self.pan_joint == self.tilt_joint:
            raise ValueError(f'pan_joint and tilt_joint must differ, both are {self.pan_joint!r}')
        for name in ('pan_sign', 'tilt_sign'):
            if getattr(self, name) not in (1, -1):
                raise ValueError(f'{name} must be 1 or -1, got {getattr(self, name)!r}')
        for name in ('pan_offset_rad', 'tilt_offset_rad'):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f'{name} must be finite, got {getattr(self, name)!r}')
        pan, tilt = self.angles(np.arange(self.grid.n_cells))
        for joint, angles, (low, high) in (('pan', pan, self.pan_limits_rad),
                                           ('tilt', tilt, self.tilt_limits_rad)):
            if not (math.isfinite(low) and math.isfinite(high) and low < high):
                raise ValueError(f'{joint} limits must be finite with min < max, '
                                 f'got [{low}, {high}]')
            outside = np.flatnonzero((angles < low - 1e-12) | (angles > high + 1e-12))
            if outside.size:
                cell = int(outside[np.argmax(np.abs(angles[outside]))])
                row, col = self.grid.cell(cell)
                raise ValueError(
                    f'cell ({row}, {col}) needs {joint} {angles[cell]:.4f} rad, outside the '
                    f'{joint} limits [{low:.4f}, {high:.4f}] rad: every cell of the '
                    f'{self.grid.rows}x{self.grid.cols} grid at {self.grid.spacing_deg} deg/cell '
                    f'must be reachable')

    @property
    def spacing_rad(self) -> float:
        """Angle between neighbouring cells in radians."""
        return math.radians(self.grid.spacing_deg)

    def angles(self, cell):
        """``(pan_rad, tilt_rad)`` of a cell index (scalar or array)."""
        row, col = self.grid.cell(cell)
        pan = self.pan_sign * -(np.asarray(col) - (self.grid.cols - 1) / 2) * self.spacing_rad
        tilt = self.tilt_sign * (np.asarray(row) - (self.grid.rows - 1) / 2) * self.spacing_rad
        pan, tilt = pan + self.pan_offset_rad, tilt + self.tilt_offset_rad
        if np.ndim(cell):
            return pan, tilt
        return float(pan), float(tilt)

    def position(self, pan_rad: float, tilt_rad: float) -> tuple[float, float]:
        """
        Return the head's ``(row, col)`` on the grid, not rounded: the inverse of :meth:`angles`.

        Raises
        ------
        ValueError
            If an angle is not finite.

        """
        col = (self.grid.cols - 1) / 2 - (pan_rad - self.pan_offset_rad) / (
            self.pan_sign * self.spacing_rad)
        row = (self.grid.rows - 1) / 2 + (tilt_rad - self.tilt_offset_rad) / (
            self.tilt_sign * self.spacing_rad)
        if not (math.isfinite(col) and math.isfinite(row)):
            raise ValueError(f'pan/tilt must be finite, got {pan_rad!r}, {tilt_rad!r}')
        return float(row), float(col)

    def nearest_cell(self, pan_rad: float, tilt_rad: float) -> int:
        """Return the cell whose pan/tilt is nearest (snapped and clipped to the grid)."""
        row, col = self.position(pan_rad, tilt_rad)
        row = int(np.clip(np.floor(row + 0.5), 0, self.grid.rows - 1))
        col = int(np.clip(np.floor(col + 0.5), 0, self.grid.cols - 1))
        return self.grid.index(row, col)
