# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
NMPT's fixed fixation policy: a softmax of the Gaussian-smoothed belief (docs/design.md 6).

Butko's NMPT toolbox (the code of the CVPR 2009 follow-up) chooses fixations with a fixed
heuristic, ``ConvolutionalLogisticPolicy`` in its default ``GAUSSIAN`` mode: smooth the belief
map with a Gaussian, multiply by a gain of 300, take the softmax over cells and sample a cell
from it. :class:`NMPTPolicy` does the same:

    p(k | B) ∝ exp(gain * (G * B)_k)

where ``G * B`` is the belief on the grid smoothed by a separable kernel, the image border
replicated (each tap that falls off the grid takes the edge cell's belief, so the smoothing is
a weighted average of belief values and keeps the belief's scale).

**Which kernel.** The design reference (docs/design.md section 6) describes it as a Gaussian of
standard deviation 5 cells, which is what NMPT's documentation says ("a Gaussian with
standard-deviation boxSize grid-cells", ``boxSize = 5``); that is the default here, truncated at
``ceil(3 sigma)`` cells. NMPT's source, however, calls ``cvSmooth(belief, CV_GAUSSIAN, 5, 5)``,
whose arguments are the *aperture* (5x5 cells) with the standard deviation left at 0, for which
OpenCV uses the fixed binomial taps ``[1, 4, 6, 4, 1] / 16`` (a standard deviation of one cell).
Pass ``taps=NMPT_SOURCE_TAPS`` for that kernel. The difference matters: on a 21x21 grid a belief
of 0.1 in one cell raises its smoothed value by about ``0.1 / (2 pi 25) * 300 = 0.19`` with
sigma 5 (the softmax is then close to uniform), but by about ``0.1 * 0.14 * 300 = 4.2`` with the
binomial taps (the cell is about 65 times likelier than a cell far away).

Randomness comes from the ``rng`` passed to :meth:`NMPTPolicy.select` (inverse CDF over cells in
row-major order, as NMPT does); ``action='argmax'`` picks the mode instead (tie rule of
docs/design.md section 4.1).
"""
from __future__ import annotations

import math

from ipomdp_gaze.model.belief import argmax_ties_low
from ipomdp_gaze.model.grid import Grid
import numpy as np

from .conv import check_action

NMPT_SIGMA_CELLS = 5.0
NMPT_GAIN = 300.0
# cvSmooth(CV_GAUSSIAN, 5, 5) with sigma 0: OpenCV's fixed 5-tap Gaussian, per axis.
NMPT_SOURCE_TAPS = (1 / 16, 4 / 16, 6 / 16, 4 / 16, 1 / 16)


def gaussian_taps(sigma_cells: float, radius: int | None = None) -> np.ndarray:
    """
    Normalised 1-D Gaussian ``exp(-d^2 / (2 sigma^2))`` for ``d = -radius..radius``.

    ``radius`` defaults to ``ceil(3 sigma)``.
    """
    sigma = float(sigma_cells)
    if not math.isfinite(sigma) or sigma <= 0:
        raise ValueError(f'sigma_cells must be a positive number, got {sigma_cells!r}')
    radius = math.ceil(3.0 * sigma) if radius is None else int(radius)
    d = np.arange(-radius, radius + 1, dtype=float)
    taps = np.exp(-0.5 * (d / sigma) ** 2)
    return taps / taps.sum()


def check_taps(taps) -> np.ndarray:
    """Return 1-D smoothing taps as float64: odd length, finite, >= 0, summing to 1 (1e-9)."""
    values = np.asarray(taps, dtype=float)
    if values.ndim != 1 or values.size % 2 != 1:
        raise ValueError(f'taps must be a 1-D sequence of odd length, got shape {values.shape}')
    if not np.all(np.isfinite(values)) or np.any(values < 0):
        raise ValueError('taps must be finite and >= 0')
    if abs(values.sum() - 1.0) > 1e-9:
        raise ValueError(f'taps must sum to 1, got {values.sum():.12g}')
    return values


def smoothing_matrix(n: int, taps) -> np.ndarray:
    """
    Return the ``(n, n)`` matrix of 1-D smoothing with ``taps``, the border replicated.

    Row i holds the weight of every cell j in the smoothed value of cell i: tap ``d`` (offset
    ``d - len(taps) // 2``) adds to cell ``clip(i + offset, 0, n - 1)``, as OpenCV's
    ``BORDER_REPLICATE`` does.
    """
    taps = check_taps(taps)
    half = taps.size // 2
    rows = np.repeat(np.arange(n), taps.size)
    cols = np.clip(np.arange(n)[:, None] + np.arange(-half, half + 1)[None, :], 0, n - 1)
    matrix = np.zeros((n, n))
    np.add.at(matrix, (rows, cols.ravel()), np.tile(taps, n))
    return matrix


class NMPTPolicy:
    """
    NMPT's fixed policy: sample from ``softmax(gain * smoothed belief)`` (module docstring).

    Parameters
    ----------
    grid : Grid
        The visual array.
    sigma_cells : float
        Standard deviation of the Gaussian, in cells (default 5, docs/design.md section 6).
    gain : float
        Multiplies the smoothed belief before the softmax (NMPT's ``softmaxGain``, 300).
    taps : sequence of float, optional
        Explicit 1-D kernel applied along rows and columns (odd length, summing to 1), instead
        of the Gaussian; :data:`NMPT_SOURCE_TAPS` is what NMPT's source computes.
    action : {'sample', 'argmax'}
        Sample from the softmax (NMPT) or take its mode.

    """

    name = 'nmpt'

    def __init__(self, grid: Grid, sigma_cells: float = NMPT_SIGMA_CELLS,
                 gain: float = NMPT_GAIN, taps=None, action: str = 'sample'):
        gain = float(gain)
        if not math.isfinite(gain) or gain <= 0:
            raise ValueError(f'gain must be a positive number, got {gain!r}')
        self.grid = grid
        self.gain = gain
        self.action = check_action(action)
        self.taps = gaussian_taps(sigma_cells) if taps is None else check_taps(taps)
        self.sigma_cells = None if taps is not None else float(sigma_cells)
        self._rows = smoothing_matrix(grid.rows, self.taps)
        self._cols_t = smoothing_matrix(grid.cols, self.taps).T

    def __repr__(self):
        kernel = (f'sigma_cells={self.sigma_cells}' if self.sigma_cells is not None
                  else f'taps={self.taps.tolist()}')
        return (f'NMPTPolicy({self.grid.rows}x{self.grid.cols}, {kernel}, gain={self.gain}, '
                f'action={self.action!r})')

    def smoothed(self, belief) -> np.ndarray:
        """Return the smoothed belief ``G * B``, shaped like ``belief`` ((N,) or (E, N))."""
        belief = np.asarray(belief, dtype=float)
        rows, cols = self.grid.shape
        maps = belief.reshape(belief.shape[:-1] + (rows, cols))
        return (self._rows @ maps @ self._cols_t).reshape(belief.shape)

    def probabilities(self, belief) -> np.ndarray:
        """Softmax ``p(k | B)`` of ``gain * smoothed belief``, shape like ``belief``."""
        score = self.gain * self.smoothed(belief)
        score -= score.max(axis=-1, keepdims=True)
        p = np.exp(score)
        return p / p.sum(axis=-1, keepdims=True)

    def select(self, belief, t, rng):
        """Fixation(s) for a belief (N,) or a batch (E, N): sampled, or the mode (argmax)."""
        if self.action == 'argmax':
            return argmax_ties_low(self.smoothed(belief))
        p = self.probabilities(np.atleast_2d(belief))
        u = rng.random((p.shape[0], 1))
        k = np.minimum((np.cumsum(p, axis=1) < u).sum(axis=1), p.shape[1] - 1)
        return k if np.ndim(belief) > 1 else k[0]
