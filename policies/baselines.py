# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Baseline searchers chosen by a strategy string, after scikit-learn's ``DummyClassifier``.

Every policy has ``select(belief, t, rng) -> fixations`` for a batch of beliefs (episodes, N).
``make_baseline('elm', grid, model)`` builds one for an observation model (or an FPOC, for the
Gaussian model); an unknown name raises a ``ValueError`` listing the valid ones. Randomness comes
from the ``rng`` passed at each call.
"""
from __future__ import annotations

from ipomdp_gaze.belief import argmax_ties_low
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.observation import as_observation
import numpy as np

from .conv import ConvPolicy

STRATEGIES = ('map', 'random', 'center', 'elm', 'spiral', 'greedy', 'tempered', 'switching')

_NEEDS_FPOC = {'greedy': 'the ideal searcher', 'tempered': 'tempered ELM',
               'switching': 'tempered ELM, then the ideal searcher'}


class MapPolicy:
    """Fixate target: look at the most likely cell, ``argmax_k B_k``."""

    name = 'map'

    def select(self, belief, t, rng):
        return argmax_ties_low(belief)


class RandomPolicy:
    """Look at a uniformly random cell."""

    name = 'random'

    def __init__(self, grid: Grid):
        self.n_cells = grid.n_cells

    def select(self, belief, t, rng):
        return rng.integers(0, self.n_cells, size=np.shape(belief)[0])


class CenterPolicy:
    """Always look at the centre cell."""

    name = 'center'

    def __init__(self, grid: Grid):
        self.cell = grid.center_index

    def select(self, belief, t, rng):
        return np.full(np.shape(belief)[0], self.cell, dtype=np.int64)


def spiral_order(grid: Grid) -> np.ndarray:
    """Cells in a square spiral from the centre outwards (right, down, left, up; growing arms)."""
    r, c = (grid.rows - 1) // 2, (grid.cols - 1) // 2
    order, seen = [], set()
    moves = ((0, 1), (1, 0), (0, -1), (-1, 0))
    arm, m = 1, 0
    limit = 4 * max(grid.rows, grid.cols) ** 2
    steps = 0
    if 0 <= r < grid.rows and 0 <= c < grid.cols:
        order.append(grid.index(r, c))
        seen.add((r, c))
    while len(order) < grid.n_cells and steps < limit:
        for _ in range(2):
            dr, dc = moves[m % 4]
            for _ in range(arm):
                r, c = r + dr, c + dc
                steps += 1
                if 0 <= r < grid.rows and 0 <= c < grid.cols and (r, c) not in seen:
                    seen.add((r, c))
                    order.append(grid.index(r, c))
            m += 1
        arm += 1
    return np.asarray(order, dtype=np.int64)


class SpiralPolicy:
    """Open-loop scan: a spiral from the centre outwards, repeated; ignores the belief."""

    name = 'spiral'

    def __init__(self, grid: Grid):
        self.order = spiral_order(grid)

    def select(self, belief, t, rng):
        return np.full(np.shape(belief)[0], self.order[t % self.order.size], dtype=np.int64)


def elm_policy(grid: Grid, model) -> ConvPolicy:
    """
    ELM (Najemnik & Geisler 2009): ``argmax_k sum_i B_i 2 KL_ik``, a conv policy.

    ``2 KL`` per offset is the observation model's :meth:`elm_kernel` (``d^2`` for the Gaussian
    model, so ``argmax_k sum_i B_i d_ik^2``).
    """
    policy = ConvPolicy(grid, as_observation(grid, model).elm_kernel(), action='argmax')
    policy.name = 'elm'
    return policy


def make_baseline(strategy: str, grid: Grid, model):
    """Build the baseline called ``strategy`` (one of :data:`STRATEGIES`) for ``model``."""
    if strategy == 'map':
        return MapPolicy()
    if strategy == 'random':
        return RandomPolicy(grid)
    if strategy == 'center':
        return CenterPolicy(grid)
    if strategy == 'spiral':
        return SpiralPolicy(grid)
    if strategy == 'elm':
        return elm_policy(grid, model)
    if strategy in ('greedy', 'tempered', 'switching'):
        fpoc = getattr(as_observation(grid, model), 'fpoc', None)
        if fpoc is None:
            raise ValueError(f'policy {strategy} ({_NEEDS_FPOC[strategy]}) needs the Gaussian '
                             'model of an FPOC, not a count model')
        if strategy == 'greedy':
            from .greedy import PercentCorrectGreedy
            return PercentCorrectGreedy(grid, fpoc)
        if strategy == 'tempered':
            from .planner import TemperedELM
            return TemperedELM(grid, fpoc)
        from .switching import SwitchingSearcher
        return SwitchingSearcher(grid, fpoc)
    raise ValueError(f"unknown policy {strategy!r}; valid policies: {', '.join(STRATEGIES)}")
