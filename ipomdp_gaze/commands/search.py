# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze search``: one offline search, printed fixation by fixation."""
from __future__ import annotations

from ipomdp_gaze.belief import entropy, map_cell, normalize_log, uniform_log_belief
from ipomdp_gaze.fpoc import dprime_matrix
from ipomdp_gaze.simulate import sample_observation
import numpy as np
from policies.baselines import make_baseline, STRATEGIES

from .common import add_task_args, nonneg_int, positive_int, task_from_args


def add_parser(sub):
    p = sub.add_parser('search', help='run one simulated search offline and print each fixation',
                       description='Simulate one search for a hidden target and print where '
                                   'the policy looked, the belief at the most likely cell and '
                                   'whether that guess is right.')
    add_task_args(p)
    p.add_argument('--policy', default='elm', choices=STRATEGIES)
    p.add_argument('--policy-file', default=None, metavar='PATH',
                   help='a policy YAML file or a shipped kernel name (overrides --policy)')
    p.add_argument('--target', type=nonneg_int, default=None, help='target cell (default random)')
    p.add_argument('--confidence', type=float, default=0.95,
                   help='stop when the most likely cell reaches this probability')
    p.add_argument('--max-fixations', type=positive_int, default=None)
    p.add_argument('--seed', type=nonneg_int, default=0)
    p.set_defaults(run=run)


def run_search(grid, fpoc, policy, target, confidence, max_fixations, seed, out=print):
    """Search until the MAP probability reaches ``confidence``; return (guess, fixations)."""
    rng = np.random.default_rng(seed)
    d = dprime_matrix(grid, fpoc)
    log_b = uniform_log_belief(grid.n_cells, 1)
    belief = np.exp(log_b)
    targets = np.array([target])
    tr, tc = grid.cell(target)
    out(f'target hidden at cell {target} (row {tr}, col {tc}) of a {grid.rows}x{grid.cols} grid')
    guess = 0
    for t in range(max_fixations):
        k = int(policy.select(belief, t, rng)[0])
        obs = sample_observation(d[target, k], targets, grid.n_cells, rng)
        log_b += d[:, k] * (obs - 0.5 * d[:, k])
        normalize_log(log_b)
        np.exp(log_b, out=belief)
        guess = int(map_cell(belief)[0])
        kr, kc = grid.cell(k)
        gr, gc = grid.cell(guess)
        p = belief[0, guess]
        out(f'fixation {t + 1:3d}: looked at ({kr},{kc})  most likely ({gr},{gc}) '
            f'p={p:.3f}  entropy={entropy(belief)[0]:.2f} nats  '
            f"{'right' if guess == target else 'wrong'}")
        if p >= confidence:
            break
    verdict = 'right' if guess == target else 'wrong'
    out(f'found: the target is most likely at ({grid.cell(guess)[0]},{grid.cell(guess)[1]}) '
        f'after {t + 1} fixations, which is {verdict}')
    return guess, t + 1


def run(args) -> int:
    grid, fpoc = task_from_args(args)
    if args.policy_file:
        from policies.policy_file import load_policy
        policy = load_policy(args.policy_file, grid=grid, fpoc=fpoc)
    else:
        policy = make_baseline(args.policy, grid, fpoc)
    if not 0 < args.confidence < 1:
        raise ValueError(f'--confidence must be between 0 and 1, got {args.confidence}')
    rng = np.random.default_rng([args.seed, 1])
    target = int(rng.integers(grid.n_cells)) if args.target is None else args.target
    if target >= grid.n_cells:
        raise ValueError(f'--target {target} is outside the {grid.n_cells}-cell grid')
    max_fix = args.max_fixations or 4 * grid.n_cells
    run_search(grid, fpoc, policy, target, args.confidence, max_fix, args.seed)
    return 0
