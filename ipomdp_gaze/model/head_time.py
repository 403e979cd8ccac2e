# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The head-time model of a pan/tilt search: what a path of views costs in seconds and degrees.

Per view the detector's time plus the controller's ``settle_time_s``; per saccade the scene
camera's ``saccade_time_s`` plus the largest joint angle over the joints' speed. The offline
evaluation (``evaluate --scenes pan-tilt``) and the benches score head time with it; the nodes
take their defaults from the same constants.
"""
from __future__ import annotations

from ipomdp_gaze.model.grid import Grid
import numpy as np

# The controller's default settle_time_s and the scene camera's default saccade_time_s (s).
SETTLE_TIME_S = 0.1
SACCADE_TIME_S = 0.15
# The joints' speed of the head model (deg/s).
HEAD_SPEED_DEG_S = 120.0


def head_time_s(grid: Grid, path, detector_s) -> float:
    """
    Return the head-time model's seconds for a path: views, and saccades from the centre.

    Per view the detector's time plus :data:`SETTLE_TIME_S`; per saccade
    :data:`SACCADE_TIME_S` plus the largest joint angle over :data:`HEAD_SPEED_DEG_S`.
    """
    if not len(path):
        return 0.0
    rows, cols = grid.cell(np.concatenate([[grid.center_index], np.asarray(path)]))
    step = np.maximum(np.abs(np.diff(rows)), np.abs(np.diff(cols))) * grid.spacing_deg
    moves = step > 0
    return float(np.sum(detector_s) + SETTLE_TIME_S * len(path)
                 + np.sum(SACCADE_TIME_S + step[moves] / HEAD_SPEED_DEG_S))


def head_travel_deg(grid: Grid, path) -> float:
    """Sum over saccades of the angle the head turns, ``spacing * hypot(d_row, d_col)``."""
    if len(path) < 2:
        return 0.0
    rows, cols = grid.cell(np.asarray(path))
    return float(grid.spacing_deg * np.hypot(np.diff(rows), np.diff(cols)).sum())


def view_seconds(grid: Grid, from_cell: int, view_time_s: float,
                 head_speed_deg_s: float) -> np.ndarray:
    """
    Return the seconds of the next view at each cell, from the head at ``from_cell``: (N,).

    ``view_time_s`` (the view's detector and settling time and the saccade's start) plus the
    largest joint angle over ``head_speed_deg_s``, as :func:`head_time_s` counts a saccade. The
    view at ``from_cell`` itself costs ``view_time_s``.
    """
    return view_time_s + _step_deg(grid, from_cell) / head_speed_deg_s


def _step_deg(grid: Grid, from_cell: int) -> np.ndarray:
    """Return the largest joint angle from ``from_cell`` to each cell (degrees), (N,)."""
    rows, cols = grid.rows_cols()
    r, c = divmod(int(from_cell), grid.cols)
    return np.maximum(np.abs(rows - r), np.abs(cols - c)) * grid.spacing_deg


def tour_detour_deg(grid: Grid, from_cell: int, cells) -> np.ndarray:
    """
    Return, for each of ``cells``, how much longer a tour of them all is when it starts there.

    The tour from ``from_cell`` first to cell ``k`` and then on through the others, each time to
    the nearest one left (largest joint angle, as a saccade is timed), against the shortest such
    tour over the first choices: 0 for the best first cell, more for a near cell that leaves the
    others scattered. Vectorised over the first choices; ``cells`` are flat indices, (K,).
    """
    cells = np.asarray(cells, dtype=np.int64).reshape(-1)
    k = cells.size
    if k == 0:
        return np.zeros(0)
    rows, cols = grid.cell(cells)
    step = np.maximum(np.abs(rows[:, None] - rows[None, :]),
                      np.abs(cols[:, None] - cols[None, :])) * grid.spacing_deg
    length = _step_deg(grid, from_cell)[cells]
    left = ~np.eye(k, dtype=bool)               # tour t (first cell t): cells not yet visited
    at = np.arange(k)
    for _ in range(k - 1):
        reach = np.where(left, step[at], np.inf)
        nxt = np.argmin(reach, axis=1)
        length = length + reach[np.arange(k), nxt]
        left[np.arange(k), nxt] = False
        at = nxt
    return length - length.min()


def covering_poses(grid: Grid, shown: np.ndarray) -> np.ndarray:
    """
    Return the fewest poses whose views together show every cell: an exact set cover.

    ``shown[p, j]`` says whether the view from pose ``p`` (a cell of ``grid``) shows cell ``j``
    (N, N). Solved as a 0-1 program (scipy's MILP, HiGHS); among the fewest, the poses nearest
    the centre in all (a tie-break worth less than one pose). What a perfect detector would
    need to call a room done: every cell seen once (the moonshot of issue 37).

    Raises
    ------
    ValueError
        When some cell is shown by no pose.

    """
    from scipy.optimize import Bounds, LinearConstraint, milp
    shown = np.asarray(shown, dtype=bool)
    if not shown.any(axis=0).all():
        raise ValueError('no pose shows every cell: no cover')
    p = shown.shape[0]
    near = _step_deg(grid, grid.center_index)[:p]
    cost = 1.0 + near / (2.0 * p * (near.max() + 1.0))
    result = milp(cost, integrality=np.ones(p), bounds=Bounds(0, 1),
                  constraints=LinearConstraint(shown.T.astype(float), lb=1, ub=np.inf))
    return np.flatnonzero(np.round(result.x) > 0)


def shortest_tour(grid: Grid, cells) -> np.ndarray:
    """
    Return ``cells`` in the order of least saccade time from the head at the grid's centre.

    Exact (every order) for up to 7 cells, else nearest neighbour improved by 2-opt; the
    saccade time is the head-time model's (:func:`head_time_s`: a move costs
    :data:`SACCADE_TIME_S` plus the largest joint angle over :data:`HEAD_SPEED_DEG_S`; the
    views cost the same in every order).
    """
    from itertools import permutations
    cells = np.asarray(cells, dtype=np.int64).reshape(-1)
    if cells.size < 2:
        return cells

    def seconds(order):
        return head_time_s(grid, np.asarray(order), 0.0)

    if cells.size <= 7:
        return np.asarray(min(permutations(cells.tolist()), key=seconds), dtype=np.int64)
    order, left = [], set(cells.tolist())
    at = grid.center_index
    while left:
        step = _step_deg(grid, at)
        at = min(left, key=lambda c: (step[c], c))
        order.append(at)
        left.remove(at)
    order = np.asarray(order, dtype=np.int64)
    improved = True
    while improved:
        improved = False
        for i in range(len(order) - 1):
            for j in range(i + 2, len(order) + 1):
                trial = np.concatenate([order[:i], order[i:j][::-1], order[j:]])
                if seconds(trial) < seconds(order) - 1e-12:
                    order, improved = trial, True
    return order
