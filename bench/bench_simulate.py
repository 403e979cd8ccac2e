# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Simulation throughput: 20,000 episodes x 49 fixations of the 7x7 task per baseline.

Run: ``.venv/bin/python bench/bench_simulate.py``. Prints wall seconds and episode-fixations per
second, beside a naive per-episode Python loop on a subsample (the reference ratio).
"""
import time

from ipomdp_gaze.belief import map_cell, uniform_log_belief, update_log_belief
from ipomdp_gaze.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.simulate import simulate
import numpy as np
from policies.baselines import make_baseline


def naive(grid, fpoc, episodes, seed=0):
    """Per-episode, per-fixation loop (the reference the batched simulator is compared with)."""
    rng = np.random.default_rng(seed)
    d = dprime_matrix(grid, fpoc)
    for _ in range(episodes):
        target = rng.integers(grid.n_cells)
        log_b = uniform_log_belief(grid.n_cells)
        for _ in range(grid.n_cells):
            k = int(map_cell(np.exp(log_b)))
            obs = rng.standard_normal(grid.n_cells)
            obs[target] += d[target, k]
            log_b = update_log_belief(log_b, obs, d[:, k])


def main():
    grid, fpoc = Grid(7, 7, 0.42), make_fpoc('human')
    episodes = 20000
    for name in ('map', 'random', 'elm'):
        policy = make_baseline(name, grid, fpoc)
        t0 = time.perf_counter()
        simulate(grid, fpoc, policy, episodes, seed=0)
        wall = time.perf_counter() - t0
        print(f'{name:8s} 20,000 x 49: {wall:6.2f} s  '
              f'{episodes * 49 / wall / 1e6:6.2f} M episode-fixations/s')
    t0 = time.perf_counter()
    naive(grid, fpoc, 200)
    wall_naive = (time.perf_counter() - t0) * episodes / 200
    t0 = time.perf_counter()
    simulate(grid, fpoc, make_baseline('map', grid, fpoc), episodes, seed=0)
    wall = time.perf_counter() - t0
    print(f'naive per-episode loop (extrapolated from 200 episodes): {wall_naive:.1f} s; '
          f'batched is {wall_naive / wall:.0f}x faster')


if __name__ == '__main__':
    main()
