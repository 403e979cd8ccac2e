# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze evaluate``: fixations to 90% correct for baselines and policy files."""
from __future__ import annotations

import json
from pathlib import Path

from ipomdp_gaze.evaluation import fixations_to_90_ci, paired_difference_ci
from ipomdp_gaze.observation import as_observation, GaussianObservation
from ipomdp_gaze.observation_file import fingerprint
from ipomdp_gaze.policies.registry import build_policy, NAMED_POLICIES
from ipomdp_gaze.simulate import draw_targets, simulate
import numpy as np

from .common import add_task_args, nonneg_int, positive_int, task_from_args


def add_parser(sub):
    p = sub.add_parser('evaluate', help='measure fixations to 90%% correct of policies',
                       description='Simulate searches with common random numbers across '
                                   'policies; print a table and optionally write JSON.')
    add_task_args(p)
    p.add_argument('--policy', action='append', default=[], choices=NAMED_POLICIES,
                   help='a baseline by name (repeatable)')
    p.add_argument('--policy-file', action='append', default=[], type=Path, metavar='PATH',
                   help='a policy YAML file, keyed by its file stem (repeatable)')
    p.add_argument('--episodes', type=positive_int, default=20000)
    p.add_argument('--episodes-greedy', type=positive_int, default=2000,
                   help='episodes for the slow ideal searcher (default 2000)')
    p.add_argument('--horizon', type=positive_int, default=None,
                   help="fixations per episode (default N, the paper's T)")
    p.add_argument('--seed', type=nonneg_int, default=0)
    p.add_argument('--bootstrap', type=positive_int, default=1000,
                   help='bootstrap resamples for the 95%% interval (default 1000)')
    p.add_argument('--paired', action='store_true',
                   help='also give each policy minus the first, on the same episodes, with a '
                        'paired bootstrap 95%% interval')
    p.add_argument('--json', type=Path, default=None, metavar='OUT', help='write results here')
    p.set_defaults(run=run)


def load_policies(args, grid, fpoc) -> dict:
    """Name -> policy for every ``--policy`` and ``--policy-file``."""
    policies = {}
    for name in args.policy or ([] if args.policy_file else ['map']):
        policies[name] = build_policy(name, grid, fpoc)
    for path in args.policy_file:
        policies[path.stem] = build_policy('learned', grid, fpoc, file=str(path))
    return policies


def evaluate(grid, fpoc, policies: dict, episodes: int, horizon, seed: int,
             episodes_greedy: int = 2000, bootstrap: int = 1000, progress=None,
             paired: bool = False) -> dict:
    """
    Run every policy on the same targets and noise; return the JSON-ready result.

    With ``paired``, ``result['paired']`` holds each later policy minus the first: the
    difference of fixations to 90% on their common episodes with a paired bootstrap interval.
    """
    horizon = grid.n_cells if horizon is None else horizon
    model = as_observation(grid, fpoc)
    targets = draw_targets(grid.n_cells, episodes, seed)
    task = ({'fpoc': model.fpoc.to_dict()} if isinstance(model, GaussianObservation)
            else {'observation': {**model.to_dict(), 'sha256': fingerprint(model)}})
    out = {'grid': grid.to_dict(), **task, 'episodes': episodes,
           'horizon': horizon, 'seed': seed, 'policies': {}}
    correct = {}
    for name, policy in policies.items():
        n = min(episodes, episodes_greedy) if getattr(policy, 'name', '') == 'greedy' else episodes
        result = simulate(grid, model, policy, n, horizon, seed, targets=targets[:n])
        if paired:
            correct[name] = result.correct
        point, ci = fixations_to_90_ci(result.correct, grid.n_cells,
                                       np.random.default_rng([seed, 99]), bootstrap)
        out['policies'][name] = {
            'episodes': n, 'fixations_to_90': point, 'ci95': list(ci) if ci else None,
            'percent_correct': [round(float(x), 6) for x in result.percent_correct]}
        if progress:
            progress(name, out['policies'][name])
    if paired and len(correct) > 1:
        names = list(correct)
        out['paired'] = {}
        for name in names[1:]:
            diff, ci = paired_difference_ci(correct[name], correct[names[0]], grid.n_cells,
                                            np.random.default_rng([seed, 98]), bootstrap)
            out['paired'][f'{name} - {names[0]}'] = {
                'episodes': int(min(correct[name].shape[0], correct[names[0]].shape[0])),
                'difference': diff, 'ci95': list(ci) if ci else None}
    return out


def format_table(result: dict) -> str:
    """Format a plain-text table of fixations to 90% correct."""
    lines = [f"{'policy':<24} {'episodes':>8} {'fix->90%':>9} {'95% CI':>17} {'pc@1':>6} "
             f"{'pc@5':>6} {'pc@10':>6}"]
    for name, r in result['policies'].items():
        pc = r['percent_correct']
        f90 = '   never' if r['fixations_to_90'] is None else f"{r['fixations_to_90']:9.2f}"
        ci = '' if r['ci95'] is None else f"[{r['ci95'][0]:.2f}, {r['ci95'][1]:.2f}]"
        at = [f'{pc[t - 1]:6.3f}' if t <= len(pc) else '     -' for t in (1, 5, 10)]
        lines.append(f"{name:<24} {r['episodes']:>8} {f90:>9} {ci:>17} {' '.join(at)}")
    for label, r in result.get('paired', {}).items():
        if r['difference'] is None:
            lines.append(f'{label}: not defined (a policy never reaches 90%)')
            continue
        ci = '' if r['ci95'] is None else f" [{r['ci95'][0]:+.2f}, {r['ci95'][1]:+.2f}]"
        lines.append(f"{label}: {r['difference']:+.2f}{ci} fixations to 90% "
                     f"({r['episodes']} paired episodes)")
    return '\n'.join(lines)


def run(args) -> int:
    grid, fpoc = task_from_args(args)
    policies = load_policies(args, grid, fpoc)
    result = evaluate(grid, fpoc, policies, args.episodes, args.horizon, args.seed,
                      args.episodes_greedy, args.bootstrap, paired=args.paired)
    task = (f'count model {args.observation}' if args.observation else
            f'{grid.spacing_deg} deg/cell, FPOC {fpoc.to_dict()}')
    print(f"{grid.rows}x{grid.cols} grid, {task}, horizon {result['horizon']}, seed {args.seed}")
    print(format_table(result))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=1) + '\n')
        print(f'wrote {args.json}')
    return 0
