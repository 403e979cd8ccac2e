# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Where in its cell a tracked target is: a constant-velocity Kalman filter on its grid position.

The cell belief (:mod:`ipomdp_gaze.model.motion`) says which cell holds the target; after each
Bayes step a face seen in cell k sits on k as a whole, so a view chosen on it moves on only when
the counts show the next cell, and the head lags a walking face (docs/design.md section 12.7).
The detections say more: the raw boxes of a face are centred around it, so their mean says where
in its cell it is, to a tenth of a cell. This filter keeps that position and a velocity, per axis
(rows down, columns right, in cells), the textbook constant-velocity model (*Probabilistic
Robotics* ch. 3.2; Bar-Shalom et al., *Estimation with Applications to Tracking and Navigation*
ch. 6.3): the velocity is a random walk of spectral density ``q`` cells^2/s^3 and the position
a random walk of ``sigma_cells^2`` cells^2/s beside it; a measurement is the position with
Gaussian noise of ``measurement_sigma_cells``. The session runs it only while the target is
found (``motion.track_view: position``) and looks at the cell of the position predicted
``motion.lead_s`` ahead (docs/design.md section 12.9).
"""
from __future__ import annotations

import math
import sys

from ipomdp_gaze.model.checks import check_number
import numpy as np

# The filter's lengths (cells) are scaled down together so the largest is at most this: its
# squares, and their products with any frame's dt, stay far from overflowing (a length of 1e308
# was an OverflowError in sigma ** 2). A Kalman filter's estimates are the same when every noise
# variance is multiplied by one factor (the gains are ratios of them), so nothing else changes.
MAX_LENGTH_CELLS = 1e100

# A measurement or a filtered position farther than this from the cell belief's peak (cells, on
# either axis) is another target or the filter gone astray: the cell belief decides.
GATE_CELLS = 1.5


def measured_position(values, offsets, grid, peak: int) -> np.ndarray | None:
    """
    Return the detections' mean grid position ``(row, col)`` around ``peak``, or None.

    ``values`` ``(N,)`` is the frame (counts; NaN not observed), ``offsets`` ``(N, 2)`` the mean
    offset ``(row, col)`` of the detections centred in each cell from its centre (NaN where
    none). The position is the mean over the cells within one cell of ``peak`` (Chebyshev)
    holding detections, each weighted by its value: for a count model the mean of the boxes'
    centres, each count clipped as the model clips it.
    """
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    offsets = np.asarray(offsets, dtype=np.float64).reshape(-1, 2)
    pr, pc = grid.cell(int(peak))
    rows, cols = grid.cell(np.arange(grid.n_cells))
    near = (np.abs(rows - pr) <= 1) & (np.abs(cols - pc) <= 1) & (values > 0) \
        & np.isfinite(offsets).all(axis=1)
    if not near.any():
        return None
    w = values[near]
    rc = np.stack([rows[near] + offsets[near, 0], cols[near] + offsets[near, 1]], axis=1)
    return (w[:, None] * rc).sum(axis=0) / w.sum()


def walk_filter(measurement_sigma_cells: float, turn_prob: float, sigma_cells: float = 0.0,
                speed_cells: float = 0.0) -> PositionFilter:
    """
    Return the filter of a walking target's settings, its lengths scaled (MAX_LENGTH_CELLS).

    The velocity's random walk is ``q = 2 turn_prob speed_cells^2`` (docs/design.md section
    12.9); ``q`` and every variance are of the scaled lengths, so any finite lengths work.
    """
    lengths = [check_number(measurement_sigma_cells, 'measurement_sigma_cells'),
               check_number(sigma_cells, 'sigma_cells'), check_number(speed_cells, 'speed_cells')]
    turn_prob = check_number(turn_prob, 'turn_prob')
    largest = max(lengths)
    if math.isfinite(largest) and largest > MAX_LENGTH_CELLS:
        lengths = [length / largest * MAX_LENGTH_CELLS for length in lengths]
    measurement, sigma, speed = lengths
    measurement = max(measurement, sys.float_info.min)          # > 0 after scaling too
    return PositionFilter(measurement, 2.0 * float(turn_prob) * speed * speed, sigma, speed)


class PositionFilter:
    """
    A constant-velocity Kalman filter on a target's grid position (module docstring).

    Both axes share the model and so one covariance ``(2, 2)`` over ``(position, velocity)``.

    Parameters
    ----------
    measurement_sigma_cells : float
        Standard deviation of a measured position (cells), > 0.
    accel_density : float
        ``q``: the velocity's random walk, cells^2 per s^3 (>= 0).
    sigma_cells : float
        The position's own random walk, cells per sqrt(s) (>= 0).
    speed_cells : float
        Standard deviation of the velocity when the filter starts (cells/s, >= 0).

    A variance that is not finite is refused (:func:`walk_filter` scales large lengths).

    """

    def __init__(self, measurement_sigma_cells: float, accel_density: float,
                 sigma_cells: float = 0.0, speed_cells: float = 0.0):
        measurement_sigma_cells, accel_density, sigma_cells, speed_cells = (
            check_number(value, name) for value, name in (
                (measurement_sigma_cells, 'measurement_sigma_cells'),
                (accel_density, 'accel_density'), (sigma_cells, 'sigma_cells'),
                (speed_cells, 'speed_cells')))
        if not measurement_sigma_cells > 0:
            raise ValueError(f'measurement_sigma_cells must be > 0, got '
                             f'{measurement_sigma_cells!r}')
        if not (accel_density >= 0 and sigma_cells >= 0 and speed_cells >= 0):
            raise ValueError('accel_density, sigma_cells and speed_cells must be >= 0')
        # a product, not ** (which raises OverflowError); a measurement variance that underflows
        # is the smallest normal number (the update divides by it when nothing else is left)
        self.r = max(float(measurement_sigma_cells) * float(measurement_sigma_cells),
                     sys.float_info.min)
        self.q = float(accel_density)
        self.s2 = float(sigma_cells) * float(sigma_cells)
        self.v2 = float(speed_cells) * float(speed_cells)
        if not all(math.isfinite(v) for v in (self.r, self.q, self.s2, self.v2)):
            raise ValueError("the filter's variances must be finite (walk_filter scales lengths "
                             f'over {MAX_LENGTH_CELLS:g} cells)')
        self.reset()

    def reset(self) -> None:
        """Forget the target: no position until the next :meth:`start`."""
        self.x = None
        self.v = np.zeros(2)
        self.p = np.zeros((2, 2))

    @property
    def started(self) -> bool:
        return self.x is not None

    def start(self, z) -> None:
        """Start at measured position ``z`` with the velocity's prior."""
        self.x = np.asarray(z, dtype=np.float64).copy()
        self.v = np.zeros(2)
        self.p = np.diag([self.r, self.v2])

    def predict(self, dt_s: float) -> None:
        """Move the state ``dt_s`` seconds ahead."""
        if self.x is None or dt_s <= 0:
            return
        dt = float(dt_s)
        f = np.array([[1.0, dt], [0.0, 1.0]])
        qm = self.q * np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]])
        qm[0, 0] += self.s2 * dt
        self.x = self.x + self.v * dt
        self.p = f @ self.p @ f.T + qm

    def update(self, z) -> None:
        """Apply a measured position ``z`` ``(row, col)``."""
        z = np.asarray(z, dtype=np.float64)
        s = self.p[0, 0] + self.r
        gain = self.p[:, 0] / s
        residual = z - self.x
        self.x = self.x + gain[0] * residual
        self.v = self.v + gain[1] * residual
        self.p = self.p - np.outer(gain, self.p[0, :])

    def ahead(self, lead_s: float) -> np.ndarray:
        """Return the position predicted ``lead_s`` seconds ahead."""
        return self.x + self.v * float(lead_s)
