# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze search``: one offline search, printed fixation by fixation."""
from __future__ import annotations

from pathlib import Path

from ipomdp_gaze.belief import bayes_update, entropy, map_cell, uniform_log_belief
from ipomdp_gaze.observation import as_observation
from ipomdp_gaze.policies.registry import build_policy, NAMED_POLICIES
import numpy as np

from .common import add_task_args, cell_arg, cell_index, nonneg_int, positive_int, task_from_args


def add_parser(sub):
    p = sub.add_parser('search', help='run one simulated search offline and print each fixation',
                       description='Simulate one search for a hidden target and print where '
                                   'the policy looked, the belief at the most likely cell and '
                                   'whether that guess is right.')
    add_task_args(p)
    p.add_argument('--policy', default='elm', choices=NAMED_POLICIES)
    p.add_argument('--policy-file', default=None, metavar='PATH',
                   help='a policy YAML file or a shipped kernel name (overrides --policy)')
    p.add_argument('--target', type=cell_arg, default=None, metavar='ROW,COL',
                   help='target cell as ROW,COL or a flat index (default random)')
    p.add_argument('--confidence', type=float, default=0.95,
                   help='stop when the most likely cell reaches this probability')
    p.add_argument('--max-fixations', type=positive_int, default=None)
    p.add_argument('--seed', type=nonneg_int, default=0)
    p.add_argument('--plot', type=Path, default=None, metavar='PNG',
                   help='save the final belief with the scan path as a picture')
    p.set_defaults(run=run)


def run_search(grid, model, policy, target, confidence, max_fixations, seed, out=print):
    """Search until the MAP probability reaches ``confidence``; return (guess, path, belief)."""
    rng = np.random.default_rng(seed)
    log_b = uniform_log_belief(grid.n_cells, 1)
    belief = np.exp(log_b)
    targets = np.array([target])
    tr, tc = grid.cell(target)
    out(f'target hidden at cell {target} (row {tr}, col {tc}) of a {grid.rows}x{grid.cols} grid')
    guess = 0
    path = []
    for t in range(max_fixations):
        k = int(policy.select(belief, t, rng)[0])
        path.append(k)
        fixations = np.array([k])
        frames = model.sample(targets, fixations, rng)
        bayes_update(log_b, model.log_likelihood_ratio(frames, fixations), out=log_b)
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
    return guess, path, belief[0]


def plot_search(grid, belief, path, target, title, out_path):
    """Save the belief as a heatmap with the numbered scan path and the target (a star)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.2, 4.6))
    log_belief = np.log10(np.maximum(belief, 1e-12)).reshape(grid.shape)
    image = ax.imshow(log_belief, cmap='inferno', vmin=max(log_belief.min(), -8), vmax=0)
    fig.colorbar(image, ax=ax, label='log10 belief')
    rows, cols = grid.cell(np.asarray(path))
    ax.plot(cols, rows, '-', color='cyan', lw=1.5, alpha=0.8)
    for i, (r, c) in enumerate(zip(rows, cols)):
        ax.text(c, r, str(i + 1), color='black', ha='center', va='center', fontsize=8,
                bbox={'boxstyle': 'circle,pad=0.2', 'fc': 'cyan', 'ec': 'none'})
    tr, tc = grid.cell(target)
    ax.plot(tc, tr, marker='*', ms=16, mfc='none', mec='lime', mew=2)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel('column')
    ax.set_ylabel('row')
    fig.tight_layout()
    out_path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_path, dpi=110)
    plt.close(fig)


def run(args) -> int:
    grid, fpoc = task_from_args(args)
    if args.policy_file:
        policy = build_policy('learned', grid, fpoc, file=args.policy_file)
    else:
        policy = build_policy(args.policy, grid, fpoc)
    if not 0 < args.confidence < 1:
        raise ValueError(f'--confidence must be between 0 and 1, got {args.confidence}')
    rng = np.random.default_rng([args.seed, 1])
    target = int(rng.integers(grid.n_cells)) if args.target is None else \
        cell_index(args.target, grid, '--target')
    max_fix = args.max_fixations or 4 * grid.n_cells
    guess, path, belief = run_search(grid, as_observation(grid, fpoc), policy, target,
                                     args.confidence, max_fix, args.seed)
    if args.plot:
        name = args.policy_file or args.policy
        task = f'{fpoc.model} FPOC' if args.observation is None else args.observation
        title = (f'{grid.rows}x{grid.cols}, {task}, {name}: '
                 f'{len(path)} fixations (star = target)')
        plot_search(grid, belief, path, target, title, args.plot)
        print(f'wrote {args.plot}')
    return 0
