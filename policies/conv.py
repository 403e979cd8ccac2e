# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Convolutional (shift-invariant) logistic policy: ``p(k | B) ∝ exp(score_k)``.

``score_k = sum_j B_j K[r_j - r_k + R-1, c_j - c_k + C-1]``: a cross-correlation of the belief with
the kernel K of shape ``(2R-1, 2C-1)`` (DESIGN.md section 3). The radially weight-shared family
ties all entries with the same squared displacement ``dr^2 + dc^2``.
"""
from __future__ import annotations

from ipomdp_gaze.belief import argmax_ties_low
from ipomdp_gaze.grid import Grid
import numpy as np

ACTIONS = ('argmax', 'sample')


def check_action(action: str) -> str:
    """Validate an action rule name."""
    if action not in ACTIONS:
        raise ValueError(f"unknown action {action!r}; valid actions: {', '.join(ACTIONS)}")
    return action


def squared_distance_table(grid: Grid) -> np.ndarray:
    """``dr^2 + dc^2`` on the (2R-1, 2C-1) kernel grid."""
    dr = np.arange(-(grid.rows - 1), grid.rows)
    dc = np.arange(-(grid.cols - 1), grid.cols)
    return dr[:, None] ** 2 + dc[None, :] ** 2


def radial_bins(grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """
    Distinct squared distances (sorted) and the bin of each kernel entry.

    Returns ``(squared_distance, bin_index)`` with ``bin_index`` of the kernel's shape, so
    ``kernel = weight[bin_index]`` (27 weights at 7x7, 61 at 11x11).
    """
    table = squared_distance_table(grid)
    values, inverse = np.unique(table, return_inverse=True)
    return values, inverse.reshape(table.shape)


def kernel_from_radial(grid: Grid, weight: np.ndarray) -> np.ndarray:
    """Expand one weight per distinct squared distance into the full kernel."""
    values, bins = radial_bins(grid)
    weight = np.asarray(weight, dtype=float)
    if weight.shape != values.shape:
        raise ValueError(f'radial weights must have {values.size} values for a '
                         f'{grid.rows}x{grid.cols} grid, got {weight.size}')
    return weight[bins]


def kernel_matrix(grid: Grid, kernel: np.ndarray) -> np.ndarray:
    """Return ``W[k, j] = K[r_j - r_k + R-1, c_j - c_k + C-1]``, N x N (small grids only)."""
    ri, ci = grid.pair_offset_index()
    return np.ascontiguousarray(kernel[ri, ci])


class ConvPolicy:
    """Shift-invariant logistic policy defined by a 2-D kernel (any kernel, symmetric or not)."""

    name = 'learned'

    def __init__(self, grid: Grid, kernel, action: str = 'argmax'):
        kernel = np.asarray(kernel, dtype=float)
        if kernel.shape != grid.kernel_shape:
            raise ValueError(f'kernel must have shape {grid.kernel_shape} for a '
                             f'{grid.rows}x{grid.cols} grid, got {kernel.shape}')
        if not np.all(np.isfinite(kernel)):
            raise ValueError('kernel contains NaN or inf')
        self.grid = grid
        self.kernel = kernel
        self.action = check_action(action)
        self._weights_t = kernel_matrix(grid, kernel).T.copy()   # [j, k]

    def scores(self, belief: np.ndarray) -> np.ndarray:
        """``score_k`` for each cell, shape like ``belief``."""
        return np.asarray(belief) @ self._weights_t

    def probabilities(self, belief: np.ndarray) -> np.ndarray:
        """Softmax ``p(k | B)``."""
        s = self.scores(belief)
        s = s - s.max(axis=-1, keepdims=True)
        p = np.exp(s)
        return p / p.sum(axis=-1, keepdims=True)

    def select(self, belief, t, rng):
        if self.action == 'argmax':
            return argmax_ties_low(self.scores(belief))
        p = self.probabilities(np.atleast_2d(belief))
        u = rng.random((p.shape[0], 1))
        k = np.minimum((np.cumsum(p, axis=1) < u).sum(axis=1), p.shape[1] - 1)
        return k if np.ndim(belief) > 1 else k[0]
