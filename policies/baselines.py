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

from ipomdp_gaze.model.belief import argmax_ties_low
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import as_observation
from ipomdp_gaze.model.view_reach import axis_covered, axis_reach, view_cells, WHOLE_CELL_TOL
import numpy as np

from .conv import ConvPolicy

STRATEGIES = ('map', 'random', 'center', 'elm', 'spiral', 'sweep', 'coverage', 'greedy',
              'tempered', 'switching')
# coverage: the sweep's tile poses come first while no cell's belief reaches this.
COVERAGE_PEAK = 0.3
# A model without a camera's field of view (the Gaussian FPOCs, the fovea): the sweep's raster
# looks at every SWEEP_STEP-th cell in each direction.
SWEEP_STEP = 3

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


def sweep_tile_cells(grid: Grid, model) -> tuple[int, int]:
    """
    Return ``(rows, cols)`` of cells one view covers: the camera's field of view over the spacing.

    The camera is the one a pan/tilt count model was calibrated with (its ``meta``); a model
    without one (Gaussian FPOCs, the fovea) gets the raster's :data:`SWEEP_STEP`.
    """
    view = view_cells(grid, model)
    if view is None:
        return SWEEP_STEP, SWEEP_STEP
    # Whole cells as axis_reach counts them: a 25-degree view over 5-degree cells is 5 cells,
    # though numpy 1.x's arctan gave 24.999999999999996 degrees, which int() alone cut to 4.
    return (max(1, min(grid.rows, int(view[0] + WHOLE_CELL_TOL))),
            max(1, min(grid.cols, int(view[1] + WHOLE_CELL_TOL))))


def _spread(n_cells: int, n_poses: int, margin: float) -> np.ndarray:
    """Centres of ``n_poses`` views spread evenly, the outer ones ``margin`` cells in."""
    if n_poses == 1:
        return np.array([(n_cells - 1) // 2], dtype=np.int64)
    return np.round(np.linspace(margin, n_cells - 1 - margin, n_poses)).astype(np.int64)


def _tile_centres(n_cells: int, side: int) -> np.ndarray:
    """Centres of the fewest tiles of ``side`` cells covering ``n_cells``, spread evenly."""
    return _spread(n_cells, -(-n_cells // side), (side - 1) / 2.0)


def _covers(poses: np.ndarray, n_cells: int, seen: int, well: int) -> bool:
    """Whether every cell is well seen from a pose, or seen from poses on both of its sides."""
    offset = np.arange(n_cells).reshape(-1, 1) - poses.reshape(1, -1)
    return bool(np.all(axis_covered(offset, seen, well)))


def axis_poses(n_cells: int, view_cells: float) -> np.ndarray:
    """
    Return the fewest view centres along an axis of ``n_cells`` that see every cell.

    A view ``view_cells`` wide (its field of view over the spacing) sees the cells at offsets up
    to ``seen`` from its centre and sees them *well* up to ``well``
    (:func:`ipomdp_gaze.model.view_reach.axis_reach`). Every cell must be well seen from some
    view, or seen from views on both of its sides (each sees the half the other cuts). Of the
    evenly spread layouts with the fewest views (no uneven layout needs fewer: test_sweep checks
    every one), the one whose outer views sit furthest in from the edges (at most ``well``).
    """
    seen, well = axis_reach(view_cells)
    for n_poses in range(1, n_cells + 1):
        for margin in range(min(well, (n_cells - 1) // 2), -1, -1):
            poses = _spread(n_cells, n_poses, margin)
            if _covers(poses, n_cells, seen, well):
                return poses
    return np.arange(n_cells, dtype=np.int64)


def sweep_tiles(grid: Grid, model) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the sweep's poses (cells, boustrophedon order) and each cell's own pose.

    With a camera (a pan/tilt count model) the poses along each axis are :func:`axis_poses`:
    the fewest views that see every cell well (not only at the image's border); without one,
    the fewest tiles of :data:`SWEEP_STEP` cells, evenly spread. Rows of poses top to bottom,
    left to right then right to left. ``owner[k]`` is the index in ``poses`` of the pose cell
    ``k`` belongs to (the nearest pose in units of :func:`sweep_tile_cells`).
    """
    tile_rows, tile_cols = sweep_tile_cells(grid, model)
    view = view_cells(grid, model)
    if view is None:
        rows, cols = _tile_centres(grid.rows, tile_rows), _tile_centres(grid.cols, tile_cols)
    else:
        rows, cols = axis_poses(grid.rows, view[0]), axis_poses(grid.cols, view[1])
    poses = []
    for i, r in enumerate(rows):
        for c in (cols if i % 2 == 0 else cols[::-1]):
            poses.append(grid.index(int(r), int(c)))
    poses = np.asarray(poses, dtype=np.int64)
    pr, pc = np.divmod(poses, grid.cols)
    cr, cc = grid.rows_cols()
    distance = np.maximum(np.abs(cr.reshape(-1, 1) - pr) / tile_rows,
                          np.abs(cc.reshape(-1, 1) - pc) / tile_cols)
    return poses, np.argmin(distance, axis=1)


class SweepPolicy:
    """
    The blind sweep a robot team starts with: tile the grid by the camera's view, boustrophedon.

    Fixation ``t`` is pose ``t mod P`` of :func:`sweep_tiles` (the next pass repeats the order;
    with inhibition of return the session moves a repeat to the nearest unvisited cell). It
    ignores the belief. Start it with ``start_cell='policy'`` so its first pose is its own.
    """

    name = 'sweep'

    def __init__(self, grid: Grid, model):
        self.poses, self.owner = sweep_tiles(grid, model)

    def select(self, belief, t, rng):
        return np.full(np.shape(belief)[0], self.poses[t % self.poses.size], dtype=np.int64)


class ELMPolicy(ConvPolicy):
    """
    ELM (Najemnik & Geisler 2009): ``argmax_k sum_i B_i 2 KL_ik``, a conv policy.

    ``2 KL`` per offset is the observation model's :meth:`elm_kernel` (``d^2`` for the Gaussian
    model, so ``argmax_k sum_i B_i d_ik^2``). Its scores are an expected information (>= 0), so
    a score per second of head time means something (:meth:`scores_per_second`).
    """

    name = 'elm'

    def __init__(self, grid: Grid, model):
        super().__init__(grid, as_observation(grid, model).elm_kernel(), action='argmax')

    def scores_per_second(self, belief, seconds: np.ndarray, detour_s=None) -> np.ndarray:
        """Return ELM's scores over each view's seconds (``search.head_speed_deg_s``; no tour)."""
        belief = np.atleast_2d(np.asarray(belief, dtype=float))
        return np.array(self.scores(belief), dtype=float).reshape(belief.shape) / seconds


def elm_policy(grid: Grid, model) -> ELMPolicy:
    """Build ELM for ``model`` (:class:`ELMPolicy`)."""
    return ELMPolicy(grid, model)


class CoveragePolicy:
    """
    ELM that covers the grid with the sweep's tiles while the belief is diffuse.

    While no cell's belief given a target is present reaches ``peak``
    (:data:`COVERAGE_PEAK`), the best of the sweep's
    tile poses by ELM's score (with inhibition of return: the unvisited ones; then every other
    cell by ELM); after that, ELM. ELM alone starts from the centre and takes the rows two
    cells from it (5-degree cells, a 3-row view): the grid's edge rows are then left at the
    view's nearly blind offset and are covered last. ``scores`` lets inhibition of return mask
    visited cells.
    """

    name = 'coverage'

    def __init__(self, grid: Grid, model, peak: float = COVERAGE_PEAK):
        self.elm = elm_policy(grid, model)
        poses, _ = sweep_tiles(grid, model)
        self.tile = np.zeros(grid.n_cells)
        self.tile[poses] = 1.0
        self.peak = float(peak)

    def scores(self, belief, seconds: np.ndarray | None = None,
               tile_seconds: np.ndarray | None = None) -> np.ndarray:
        """
        Return ELM's scores, those of the tile poses raised above the rest while diffuse.

        With ``seconds`` (each view's head time) ELM's scores are divided by them first, and
        while diffuse by ``tile_seconds`` when given (the tour a tile commits to): the tiles
        still come first, the best informative one per second first.
        """
        belief = np.atleast_2d(np.asarray(belief, dtype=float))
        # Given a target is present: with the absent hypothesis the cells sum to 1 - P(absent).
        belief = belief / np.maximum(belief.sum(axis=1, keepdims=True), 1e-300)
        scores = np.array(self.elm.scores(belief), dtype=float).reshape(belief.shape)
        diffuse = belief.max(axis=1, keepdims=True) < self.peak
        if seconds is not None:
            spent = seconds if tile_seconds is None else np.where(diffuse, tile_seconds, seconds)
            scores = scores / spent
        bonus = np.abs(scores).max(axis=1, keepdims=True) + 1.0
        return scores + diffuse * bonus * self.tile

    def scores_per_second(self, belief, seconds: np.ndarray, detour_s=None) -> np.ndarray:
        """
        Return :meth:`scores` per second of each view (``search.head_speed_deg_s``).

        ``detour_s(cells)``: the seconds a tour of the tiles left grows by when it starts at
        each of ``cells`` (``search.head_tour``), added to the tiles' seconds while diffuse.
        """
        tile_seconds = None
        if detour_s is not None:
            tiles = np.flatnonzero(self.tile)
            tile_seconds = np.array(seconds, dtype=float)
            tile_seconds[tiles] += detour_s(tiles)
        return self.scores(belief, seconds, tile_seconds)

    def select(self, belief, t, rng):
        return argmax_ties_low(self.scores(belief))


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
    if strategy == 'sweep':
        return SweepPolicy(grid, model)
    if strategy == 'coverage':
        return CoveragePolicy(grid, model)
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
