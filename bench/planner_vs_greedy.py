# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
7x7 human FPOC: the planner and tempered ELM against ELM and the ideal searcher, on both cores.

Run: ``.venv/bin/python bench/planner_vs_greedy.py [--episodes 4000] [--seed 1] [--jobs 2]``
(about 10 CPU-minutes at 4,000 episodes; docs/reproduction_notes.md quotes a run).

Every policy runs the same episodes (common random numbers) for 16 fixations, split into pieces
of 500 episodes over a process pool (``simulate(..., rows=)``, so ELM, tempered ELM and the
ideal searcher give exactly their serial numbers). Printed: fixations to 90% correct by the
indicator (MAP guess right) and by the expected percent correct (mean of ``max_i B_i``, the same
curve with less variance), each with a 95% bootstrap interval, then the paired differences.
"""
import argparse
from concurrent.futures import ProcessPoolExecutor
import time

from ipomdp_gaze.evaluation import fixations_to_90_ci, paired_difference_ci
from ipomdp_gaze.fpoc import make_fpoc
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.planner import make_planner, TemperedELM
from ipomdp_gaze.simulate import simulate
import numpy as np

GRID, FPOC = Grid(7, 7, 0.42), make_fpoc('human')
HORIZON, CHUNK = 16, 500
NAMES = ('elm', 'tempered', 'greedy', 'planner')


def build(name):
    """Return the policy called ``name``."""
    if name == 'tempered':
        return TemperedELM(GRID, FPOC)
    if name == 'planner':
        return make_planner(GRID, FPOC)
    return make_baseline(name, GRID, FPOC)


def piece(name, episodes, seed, rows):
    """Simulate rows ``start:stop`` of the run: correct, max_i B_i and CPU seconds."""
    start = time.process_time()
    result = simulate(GRID, FPOC, build(name), episodes, HORIZON, seed, rows=rows)
    return result.correct, result.map_prob, time.process_time() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--episodes', type=int, default=4000)
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--jobs', type=int, default=2)
    args = parser.parse_args()
    n = args.episodes
    results = {}
    with ProcessPoolExecutor(args.jobs) as pool:
        jobs = {name: [pool.submit(piece, name, n, args.seed, (a, min(a + CHUNK, n)))
                       for a in range(0, n, CHUNK)] for name in NAMES[::-1]}
        for name in NAMES:
            parts = [job.result() for job in jobs[name]]
            results[name] = [np.concatenate([p[i] for p in parts]) for i in (0, 1)]
            cpu = sum(p[2] for p in parts)
            print(f'{name}: {cpu:.0f} s CPU, {1000 * cpu / (n * HORIZON):.2f} ms per decision')
    measures = ('indicator', 'expected')
    for name in NAMES:
        for i, label in enumerate(measures):
            point, ci = fixations_to_90_ci(results[name][i], GRID.n_cells,
                                           np.random.default_rng([args.seed, 7]), 1000)
            print(f'{name:9s} {label:9s} {point:.3f} [{ci[0]:.3f}, {ci[1]:.3f}]')
    for a, b in (('planner', 'elm'), ('planner', 'greedy'), ('planner', 'tempered'),
                 ('tempered', 'elm'), ('tempered', 'greedy'), ('greedy', 'elm')):
        for i, label in enumerate(measures):
            diff, ci = paired_difference_ci(results[a][i], results[b][i], GRID.n_cells,
                                            np.random.default_rng([args.seed, 8]), 1000)
            print(f'{a} - {b} ({label}, {n} paired): {diff:+.3f} [{ci[0]:+.3f}, {ci[1]:+.3f}]')


if __name__ == '__main__':
    main()
