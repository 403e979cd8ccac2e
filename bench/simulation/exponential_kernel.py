# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Why a zero-start kernel on the exponential FPOC looks next to a likely target, not at it.

Run: ``.venv/bin/python bench/simulation/exponential_kernel.py [--old OLD.yaml] [--episodes 4000]``
(a few minutes; the numbers are quoted in docs/reproduction_notes.md).

Three measurements on the 11x11 exponential task (0.42 deg/cell, d' = 2 exp(-e / 1.5 deg)):

1. The training objective of the argmax policies: the infomax return ``sum_t sum_i B_i log B_i``
   over 121 fixations (mean over ``--episodes``), for ELM, MAP, the shipped kernel and ``--old``.
2. The policy gradient of the softmax policy per tie class of the conv kernel (squared distance
   d^2 from the fixation), ``g_c = sum over the class's members of dJ/dtheta``, averaged over
   ``--gradient-epochs`` epochs of 150 episodes, at three kernels: zero, 15 x ELM, ``--old``.
   A class moves by ``lr g_c``: the sum over its members, so a ring of 4 or 8 cells moves 4 or 8
   times as fast as a single centre cell with the same per-member gradient.
3. Where each policy looks during search: the distance in cells of fixation t+1 from the MAP
   cell after fixation t, by the MAP probability then.
"""
import argparse

from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.conv import radial_bins
from ipomdp_gaze.policies.policy_file import load_policy_spec
from ipomdp_gaze.policies.training import (elm_init, sample_episodes, theta_gradient, TrainConfig,
                                           Trainer)
from ipomdp_gaze.simulation.simulate import simulate
import numpy as np

KERNEL = 'exponential-11x11-infomax'


def gradient_by_class(grid, fpoc, params, epochs, seed=5):
    """Mean and standard error over epochs of the per-class gradient at ``params``."""
    trainer = Trainer(grid, fpoc, TrainConfig(learning_rate=5.0, baseline=True), params=params)
    theta = trainer.family.theta(trainer.params)
    grads = []
    for i in range(epochs):
        batch = sample_episodes(theta, trainer.model, 'infomax', 150, grid.n_cells,
                                np.random.default_rng([seed, i]))
        grads.append(trainer.family.project(theta_gradient(batch, 0.75, 1.0, True)))
    grads = np.array(grads)
    return grads.mean(axis=0), grads.std(axis=0, ddof=1) / np.sqrt(epochs)


def where_it_looks(grid, result):
    """Distance of fixation t+1 from the MAP cell after t, and the MAP probability then."""
    rows, cols = np.divmod(result.fixations[:, 1:], grid.cols)
    map_rows, map_cols = np.divmod(result.guess[:, :-1], grid.cols)
    return np.hypot(rows - map_rows, cols - map_cols), result.map_prob[:, :-1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--old', default=None, help='an earlier kernel file to compare')
    parser.add_argument('--episodes', type=int, default=4000)
    parser.add_argument('--gradient-epochs', type=int, default=40)
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args()
    spec = load_policy_spec(KERNEL)
    grid, fpoc = spec.grid, spec.fpoc
    kernels = {'shipped': spec}
    if args.old:
        kernels['old'] = load_policy_spec(args.old)
    policies = {'elm': make_baseline('elm', grid, fpoc), 'map': make_baseline('map', grid, fpoc)}
    policies.update({name: s.make_policy('argmax') for name, s in kernels.items()})

    print(f'1. Infomax return of the argmax policies ({args.episodes} episodes, seed '
          f'{args.seed}, {grid.n_cells} fixations)')
    results = {}
    for name, policy in policies.items():
        results[name] = simulate(grid, fpoc, policy, args.episodes, grid.n_cells, args.seed)
        ret = results[name].infomax.sum(axis=1)
        print(f'   {name:8s} {ret.mean():8.2f} +- {ret.std(ddof=1) / np.sqrt(ret.size):.2f}')

    values, bins = radial_bins(grid)
    members = np.bincount(bins.ravel(), minlength=values.size)
    starts = {'zero': None, '15 x ELM': elm_init(grid, fpoc, 15.0)}
    for name, s in kernels.items():
        starts[name] = np.asarray(s.radial()['weight'], dtype=float)
    print(f'\n2. Policy gradient per tie class ({args.gradient_epochs} epochs x 150 episodes; '
          'mean +- standard error)')
    for name, params in starts.items():
        mean, se = gradient_by_class(grid, fpoc, params, args.gradient_epochs)
        print(f'   at {name}:')
        for c in range(6):
            print(f'     d^2 = {values[c]:2d} ({members[c]} cells): class {mean[c]:+.4f} +- '
                  f'{se[c]:.4f}, per cell {mean[c] / members[c]:+.5f}')

    print('\n3. Where the policies look: distance (cells) of the next fixation from the MAP cell')
    for name, result in results.items():
        dist, conf = where_it_looks(grid, result)
        parts = []
        for low, high in ((0.0, 0.2), (0.2, 0.5), (0.5, 0.9), (0.9, 1.01)):
            pick = (conf >= low) & (conf < high)
            parts.append(f'P(MAP) {low:.1f}-{min(high, 1):.1f}: {dist[pick].mean():.2f} cells, '
                         f'at the MAP cell {np.mean(dist[pick] == 0):.0%}')
        print(f'   {name:8s} ' + '; '.join(parts))


if __name__ == '__main__':
    main()
