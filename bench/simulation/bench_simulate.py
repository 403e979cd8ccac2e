# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Simulation throughput: 20,000 episodes x 49 fixations of the 7x7 task per baseline.

Run: ``.venv/bin/python bench/simulation/bench_simulate.py``. Prints wall seconds and
episode-fixations per
second, beside a naive per-episode Python loop on a subsample (the reference ratio).
``bench/run.py`` calls :func:`bench` instead, which also times 11x11 and writes a markdown table.
"""
import argparse
import time

from ipomdp_gaze.model.belief import bayes_update, map_cell, uniform_log_belief
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.simulation.simulate import simulate
import numpy as np


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
            log_b = bayes_update(log_b, llr(obs, d[:, k]))


TITLE = 'Simulation throughput (batched simulator)'
ORDER = 30


def bench(ctx) -> str:
    """Markdown section for ``bench/run.py``: throughput per grid and policy, naive ratio."""
    fpoc = make_fpoc('human')
    scale = 10 if ctx.quick else 1
    runs = [(Grid(7, 7), name, 20000 // scale) for name in ('map', 'random', 'elm')]
    runs += [(Grid(11, 11), name, 5000 // scale) for name in ('map', 'elm')]
    rows, batched = [], {}
    for grid, name, episodes in runs:
        policy = make_baseline(name, grid, fpoc)
        t0 = time.perf_counter()
        simulate(grid, fpoc, policy, episodes, seed=0)
        wall = time.perf_counter() - t0
        rate = episodes * grid.n_cells / wall
        batched[(grid.rows, name)] = rate
        rows.append(f'| {grid.rows}x{grid.cols} | {name} | {episodes:,} x {grid.n_cells} | '
                    f'{wall:.2f} s | {rate / 1e6:.3f} M |')
        ctx.log(f'simulate {grid.rows}x{grid.cols} {name}: {wall:.1f} s')
    sample = 200 // scale
    grid = Grid(7, 7)
    t0 = time.perf_counter()
    naive(grid, fpoc, sample)
    naive_rate = sample * grid.n_cells / (time.perf_counter() - t0)
    return '\n'.join([
        'Common random numbers (seed 0), horizon N, from the uniform prior; one process, one '
        'BLAS thread. Reference: a naive per-episode, per-fixation Python loop (MAP policy, '
        f'7x7, {sample} episodes) run in the same process.', '',
        '| grid | policy | episodes x fixations | wall | episode-fixations/s |',
        '|---|---|---|---|---|', *rows, '',
        f'Naive loop: {naive_rate / 1e3:.1f} k episode-fixations/s; the batched simulator '
        f'(MAP, 7x7) is {batched[(7, "map")] / naive_rate:.0f}x faster in this run.'])


def main(argv=None):
    """Run alone: the 7x7 throughput of each baseline and the naive loop's ratio."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.parse_args(argv)
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
