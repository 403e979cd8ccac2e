# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Inhibition of return: never fixate a cell twice in one search of a still scene.

With a deterministic detector on a still scene (an image, or a head looking at a room that does
not change), a second look at a cell repeats the same counts and the Bayes step would count the
same evidence twice (docs/design.md section 6.4). ``find`` and, with ``search.inhibit_return``,
the gaze controller then take the policy's best cell among those not yet fixated.
"""
from __future__ import annotations

from ipomdp_gaze.model.belief import argmax_ties_low
from ipomdp_gaze.model.grid import Grid
import numpy as np


def policy_choice(selected, n_cells: int) -> int:
    """Check and return the cell a policy's ``select`` returned for a one-belief batch."""
    flat = np.asarray(selected).reshape(-1)
    if flat.size != 1 or not np.issubdtype(flat.dtype, np.integer):
        raise ValueError(f'the policy must return one integer cell for a (1, N) belief, got '
                         f'{selected!r}')
    index = int(flat[0])
    if not 0 <= index < n_cells:
        raise ValueError(f'the policy chose cell {index}, outside the {n_cells}-cell grid')
    return index


def unvisited_choice(policy, belief: np.ndarray, visited: np.ndarray, t: int, rng,
                     grid: Grid) -> int:
    """
    Return the policy's best cell among the unvisited ones (inhibition of return).

    A policy with ``scores`` (ELM, learned kernels) gets its scores masked; ``map`` the belief
    masked; any other policy's choice, when already visited, is replaced by the nearest
    unvisited cell (Chebyshev distance, then the lowest index). ``belief`` is ``(1, N)``,
    ``visited`` a boolean ``(N,)`` with at least one False.
    """
    n = visited.size
    scorer = getattr(policy, 'scores', None)
    if callable(scorer) or getattr(policy, 'name', '') == 'map':
        scores = np.array(scorer(belief) if callable(scorer) else belief,
                          dtype=float).reshape(-1)
        if scores.size != n:
            raise ValueError(f'the policy scored {scores.size} cells of the {n}-cell grid')
        if np.isnan(scores).any():
            raise ValueError('the policy scored a cell NaN')
        if np.all(scores[~visited] == -np.inf):  # every unvisited score -inf: the first of them
            return int(np.argmin(visited))
        infinite = np.flatnonzero((scores == np.inf) & ~visited)
        if infinite.size:                       # the tie rule's tolerance is NaN at +inf
            return int(infinite[0])
        scores[visited] = -np.inf
        return int(argmax_ties_low(scores))
    choice = policy_choice(policy.select(belief, t, rng), n)
    if not visited[choice]:
        return choice
    rows, cols = grid.rows_cols()
    r, c = divmod(choice, grid.cols)
    distance = np.maximum(np.abs(rows - r), np.abs(cols - c))
    return int(np.argmin(np.where(visited, n + grid.rows + grid.cols, distance)))
