# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Full logistic policy: ``p(k | B) ∝ exp(score_k)`` with ``score_k = sum_j theta[k, j] B_j``.

One free weight per (fixation, cell) pair: N x N weights (2,401 at 7x7, 14,641 at 11x11), paper
Sec. III. The convolutional family of :mod:`policies.conv` is the special case
``theta[k, j] = K[r_j - r_k + R-1, c_j - c_k + C-1]``.
"""
from __future__ import annotations

from ipomdp_gaze.model.belief import argmax_ties_low
from ipomdp_gaze.model.grid import Grid
import numpy as np

from .conv import check_action, check_score_scale


def softmax(scores: np.ndarray) -> np.ndarray:
    """Row-wise softmax, shifted by the row maximum so it never overflows."""
    s = np.asarray(scores, dtype=float)
    s = s - s.max(axis=-1, keepdims=True)
    p = np.exp(s)
    return p / p.sum(axis=-1, keepdims=True)


def sample_rows(p: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Draw one index per row of the probability array ``p`` (E, N) by inverse CDF."""
    u = rng.random((p.shape[0], 1))
    return np.minimum((np.cumsum(p, axis=1) < u).sum(axis=1), p.shape[1] - 1)


class LogisticPolicy:
    """Logistic policy with a full N x N weight matrix ``theta[k, j]`` (fixation k, cell j)."""

    name = 'logistic'

    def __init__(self, grid: Grid, theta, action: str = 'argmax'):
        theta = np.asarray(theta, dtype=float)
        n = grid.n_cells
        if theta.shape != (n, n):
            raise ValueError(f'theta must have shape {(n, n)} for a {grid.rows}x{grid.cols} '
                             f'grid, got {theta.shape}')
        if not np.all(np.isfinite(theta)):
            raise ValueError('theta contains NaN or inf')
        check_score_scale(theta, 'theta', axis=1)
        self.grid = grid
        self.theta = theta
        self.action = check_action(action)
        self._theta_t = np.ascontiguousarray(theta.T)   # [j, k]

    def scores(self, belief: np.ndarray) -> np.ndarray:
        """``score_k = sum_j theta[k, j] B_j`` for each cell, shape like ``belief``."""
        return np.asarray(belief) @ self._theta_t

    def probabilities(self, belief: np.ndarray) -> np.ndarray:
        """Softmax ``p(k | B)``."""
        return softmax(self.scores(belief))

    def select(self, belief, t, rng):
        """Next fixation per episode: argmax of the scores (ties low) or a softmax sample."""
        if self.action == 'argmax':
            return argmax_ties_low(self.scores(belief))
        k = sample_rows(self.probabilities(np.atleast_2d(belief)), rng)
        return k if np.ndim(belief) > 1 else k[0]
