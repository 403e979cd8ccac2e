# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The moonshot's bounds (issue 37): the fewest covering views and the quickest tour, by brute force.

``covering_poses`` returns a cover of the fewest poses (checked against every subset on small
grids), ``shortest_tour`` the order of least saccade time (against every order up to 7 cells;
beyond, an order no reversal of a stretch improves).
"""
from __future__ import annotations

from itertools import combinations, permutations

from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import observed_cells, PinholeCamera
from ipomdp_gaze.model.head_time import covering_poses, head_time_s, shortest_tour
import numpy as np
import pytest


def _shown(grid: Grid, reach: int) -> np.ndarray:
    """Each pose shows the cells within ``reach`` (Chebyshev) of it."""
    rows, cols = grid.rows_cols()
    return np.array([(np.abs(rows - r) <= reach) & (np.abs(cols - c) <= reach)
                     for r, c in zip(rows, cols)])


@pytest.mark.parametrize('shape, reach', [((3, 3), 1), ((4, 5), 1), ((5, 5), 1), ((3, 7), 2)])
def test_the_cover_has_the_fewest_poses_every_subset_allows(shape, reach):
    grid = Grid(*shape, 5.0)
    shown = _shown(grid, reach)
    cover = covering_poses(grid, shown)
    assert shown[cover].any(axis=0).all()
    fewest = next(k for k in range(1, grid.n_cells + 1)
                  if any(shown[list(c)].any(axis=0).all()
                         for c in combinations(range(grid.n_cells), k)))
    assert cover.size == fewest


def test_a_cell_no_pose_shows_is_refused():
    shown = np.ones((4, 4), dtype=bool)
    shown[:, 2] = False
    with pytest.raises(ValueError, match='no cover'):
        covering_poses(Grid(2, 2, 5.0), shown)


def test_a_camera_covers_the_head_grid():
    grid = Grid(11, 11, 5.0)
    camera = PinholeCamera(320, 240, 320 / 2 / np.tan(np.radians(12.5)),
                           320 / 2 / np.tan(np.radians(12.5)), 159.5, 119.5)
    shown = np.array([observed_cells(camera, grid, grid.cell(p)) for p in range(grid.n_cells)])
    cover = covering_poses(grid, shown)
    assert shown[cover].any(axis=0).all() and 4 <= cover.size <= 16


def test_the_tour_is_the_quickest_order_from_the_centre():
    grid = Grid(11, 11, 5.0)
    rng = np.random.default_rng(3)
    for k in (1, 2, 4, 6):
        cells = rng.choice(grid.n_cells, size=k, replace=False)
        tour = shortest_tour(grid, cells)
        assert sorted(tour.tolist()) == sorted(cells.tolist())
        views = np.zeros(k)
        best = min(head_time_s(grid, list(p), views) for p in permutations(cells.tolist()))
        assert head_time_s(grid, tour, views) == pytest.approx(best)


def test_a_long_tour_no_reversal_of_a_stretch_makes_quicker():
    """Beyond 7 cells the tour is 2-opt optimal: reversing any stretch takes no less time."""
    grid = Grid(11, 11, 5.0)
    for seed in (5, 6):
        cells = np.random.default_rng(seed).choice(grid.n_cells, size=12, replace=False)
        tour = shortest_tour(grid, cells)
        assert sorted(tour.tolist()) == sorted(cells.tolist())
        views = np.zeros(len(cells))
        seconds = head_time_s(grid, tour, views)
        for i in range(len(tour) - 1):
            for j in range(i + 2, len(tour) + 1):
                trial = np.concatenate([tour[:i], tour[i:j][::-1], tour[j:]])
                assert head_time_s(grid, trial, views) >= seconds - 1e-9
