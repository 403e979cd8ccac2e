# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Look-ahead planner vs the baselines on paired episodes (7x7, human FPOC, calibrated default).

Run: ``.venv/bin/python bench/simulation/bench_planner.py [--episodes 2000] [--episodes-fast
20000] [--quick]`` (``--quick``: 200 and 2,000 episodes, 200 bootstrap resamples, unless given).

Every policy sees the same targets and observation noise (common random numbers; a run of n
episodes is the first n episodes of a longer one). Printed for each policy: fixations to 90%
correct with a 95% bootstrap interval, computed two ways on the same episodes:

- ``indicator``: the project's measure, percent correct = fraction of episodes whose MAP guess is
  the target (``SearchResult.correct``);
- ``expected``: percent correct estimated by the mean of ``max_i B_i`` (``SearchResult.map_prob``).
  In simulation the belief is the exact posterior, so ``max_i B_i`` is the probability that the
  MAP guess is right given the history: the same curve, unbiased, with less variance
  (conditional Monte Carlo). It resolves differences the indicator cannot at these sizes.

Then the paired differences planner - other (and tempered ELM - ELM) with 95% intervals
(``paired_difference_ci``), the planner's decision time on single beliefs (median ms) and its
batched throughput, and every run's wall time.
"""
import argparse
import json
from pathlib import Path
import time

from ipomdp_gaze.commands.common import (bootstrap_count, nonneg_int, parse_with_outputs,
                                         positive_int)
from ipomdp_gaze.model.belief import bayes_update
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import GaussianObservation
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.planner import make_planner, TemperedELM
from ipomdp_gaze.simulation.evaluation import (fixations_to_90_ci, format_interval,
                                               paired_difference_ci)
from ipomdp_gaze.simulation.simulate import draw_targets, simulate
import numpy as np


def measure(result, n_cells, seed, resamples):
    """Fixations to 90% with 95% intervals, by the indicator and the expected percent correct."""
    out = {}
    for key, data in (('indicator', result.correct), ('expected', result.map_prob)):
        point, ci = fixations_to_90_ci(data, n_cells, np.random.default_rng([seed, 99]),
                                       resamples)
        out[key] = {'fixations_to_90': point, 'ci95': list(ci) if ci else None}
    return out


def paired(result_a, result_b, n_cells, seed, resamples):
    """Paired differences a - b of fixations to 90% (both measures) on their common episodes."""
    out = {}
    for key in ('correct', 'map_prob'):
        diff, ci = paired_difference_ci(getattr(result_a, key), getattr(result_b, key), n_cells,
                                        np.random.default_rng([seed, 98]), resamples)
        out['indicator' if key == 'correct' else 'expected'] = {
            'difference': diff, 'ci95': list(ci) if ci else None}
    return out


def decision_times(planner, grid, model, episodes=20, fixations=10, seed=0):
    """Wall and CPU ms of single-belief decisions on beliefs along the base policy's searches."""
    rng = np.random.default_rng([seed, 7])
    n = grid.n_cells
    targets = rng.integers(0, n, episodes)
    log_b = np.full((episodes, n), -np.log(n))
    times, cpu = [], []
    for t in range(fixations):
        belief = np.exp(log_b)
        for e in range(episodes):
            start, start_cpu = time.perf_counter(), time.process_time()
            planner.select(belief[e], t, rng)
            times.append(time.perf_counter() - start)
            cpu.append(time.process_time() - start_cpu)
        k = planner.base.select(belief, t, rng)
        frames = model.sample(targets, k, rng)
        bayes_update(log_b, model.log_likelihood_ratio(frames, k, validate=False), out=log_b)
    return 1000 * np.asarray(times), 1000 * np.asarray(cpu)


def tempered_vs_elm(grid, fpoc, d, seeds, episodes, horizon, resamples):
    """Tempered ELM - ELM on several fresh seeds: per seed and pooled (normal approximation)."""
    rows = []
    for seed in seeds:
        a = simulate(grid, fpoc, TemperedELM(grid, fpoc, dprime=d), episodes, horizon, seed=seed)
        b = simulate(grid, fpoc, make_baseline('elm', grid, fpoc), episodes, horizon, seed=seed)
        entry = paired(a, b, grid.n_cells, seed, resamples)
        rows.append(entry)
        print(f"  seed {seed:>4}: indicator {fmt(entry['indicator'], episodes)}   "
              f"expected {fmt(entry['expected'], episodes)}", flush=True)
    pooled = {}
    for key in ('indicator', 'expected'):
        if any(r[key]['difference'] is None for r in rows):     # a policy never reaches 90%
            pooled[key] = {'difference': None, 'ci95': None}
            continue
        diffs = np.array([r[key]['difference'] for r in rows])
        if any(r[key]['ci95'] is None for r in rows):   # too few episodes, or beyond the horizon
            pooled[key] = {'difference': float(diffs.mean()), 'ci95': None}
            continue
        ses = np.array([(r[key]['ci95'][1] - r[key]['ci95'][0]) / 3.92 for r in rows])
        mean, se = diffs.mean(), np.sqrt(np.sum(ses ** 2)) / len(rows)
        pooled[key] = {'difference': float(mean), 'ci95': [mean - 1.96 * se, mean + 1.96 * se]}
    print(f'  pooled ({len(seeds)} x {episodes}): indicator '
          f"{fmt(pooled['indicator'], episodes)}   expected {fmt(pooled['expected'], episodes)}")
    return {'seeds': list(seeds), 'episodes_per_seed': episodes, 'per_seed': rows,
            'pooled': pooled}


def fmt(block, episodes):
    """
    Format a value and its 95% interval (``-``: none from fewer than MIN_EPISODES episodes).

    ``episodes`` is how many the interval was drawn from.
    """
    value, ci = block.get('fixations_to_90', block.get('difference')), block['ci95']
    if value is None:
        return f"{'never':>23}"
    sign = '+' if 'difference' in block else ''
    return f'{value:{sign}7.3f} {format_interval(ci, sign + ".2f", episodes):>16}'


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--quick', action='store_true',
                        help='a smoke run: the defaults 200, 2000 and 200 resamples')
    parser.add_argument('--episodes', type=positive_int, default=None,
                        help='planner (and greedy) episodes (default 2000)')
    parser.add_argument('--episodes-elm-planner', type=nonneg_int, default=0,
                        help='episodes of the planner with plain ELM as base (0: skip)')
    parser.add_argument('--episodes-fast', type=positive_int, default=None,
                        help='episodes of MAP, ELM and tempered ELM (default 20000)')
    parser.add_argument('--horizon', type=positive_int, default=12, help='fixations per episode')
    parser.add_argument('--seed', type=nonneg_int, default=0)
    parser.add_argument('--bootstrap', type=bootstrap_count, default=None,
                        help='bootstrap resamples (default 1000)')
    parser.add_argument('--tempered-seeds', type=nonneg_int, default=0,
                        help='also compare tempered ELM with ELM on this many fresh seeds '
                             '(100, 101, ...) of --episodes-fast episodes each')
    parser.add_argument('--skip-planner', action='store_true',
                        help='only the fast policies (and --tempered-seeds)')
    parser.add_argument('--json', type=Path, default=None)
    args = parse_with_outputs(parser, argv, json='--json')
    for name, full, quick in (('episodes', 2000, 200), ('episodes_fast', 20000, 2000),
                              ('bootstrap', 1000, 200)):
        if getattr(args, name) is None:
            setattr(args, name, quick if args.quick else full)

    grid, fpoc = Grid(7, 7, 0.42), make_fpoc('human')
    n = grid.n_cells
    d = dprime_matrix(grid, fpoc)
    total = max(args.episodes_fast, args.episodes, args.episodes_elm_planner)
    targets = draw_targets(n, total, args.seed)
    policies = {
        'map': (make_baseline('map', grid, fpoc), args.episodes_fast),
        'elm': (make_baseline('elm', grid, fpoc), args.episodes_fast),
        'tempered_elm': (TemperedELM(grid, fpoc, dprime=d), args.episodes_fast),
    }
    try:
        policies['greedy'] = (make_baseline('greedy', grid, fpoc), args.episodes)
    except ImportError:
        print('percent-correct greedy (policies/greedy.py) not available: skipped')
    if args.skip_planner:
        policies.pop('greedy', None)
    if args.episodes_elm_planner and not args.skip_planner:
        policies['planner_elm_base'] = (
            make_planner(grid, fpoc, base=make_baseline('elm', grid, fpoc), dprime=d),
            args.episodes_elm_planner)
    planner = make_planner(grid, fpoc, dprime=d)
    if not args.skip_planner:
        policies['planner'] = (planner, args.episodes)

    results, report = {}, {'task': {'grid': grid.to_dict(), 'fpoc': fpoc.to_dict(),
                                    'horizon': args.horizon, 'seed': args.seed},
                           'policies': {}, 'paired': {}}
    print(f"{'policy':<18} {'episodes':>8} {'indicator fix->90 [95% CI]':>27} "
          f"{'expected fix->90 [95% CI]':>27} {'wall s':>8}")
    for name, (policy, episodes) in policies.items():
        start = time.perf_counter()
        result = simulate(grid, fpoc, policy, episodes, args.horizon, seed=args.seed,
                          targets=targets[:episodes])
        wall = time.perf_counter() - start
        results[name] = result
        entry = measure(result, n, args.seed, args.bootstrap)
        entry.update(episodes=episodes, wall_seconds=wall,
                     decisions_per_second=episodes * args.horizon / wall)
        report['policies'][name] = entry
        print(f"{name:<18} {episodes:>8} {fmt(entry['indicator'], episodes):>27} "
              f"{fmt(entry['expected'], episodes):>27} {wall:8.1f}", flush=True)

    pairs = [('planner', other) for other in results if 'planner' in results and
             other != 'planner']
    pairs.append(('tempered_elm', 'elm'))
    if 'planner_elm_base' in results:
        pairs.append(('planner_elm_base', 'elm'))
    print(f"\n{'paired difference':<34} {'episodes':>8} {'indicator [95% CI]':>25} "
          f"{'expected [95% CI]':>25}")
    for a, b in pairs:
        common = min(results[a].correct.shape[0], results[b].correct.shape[0])
        entry = paired(results[a], results[b], n, args.seed, args.bootstrap)
        entry['episodes'] = common
        report['paired'][f'{a} - {b}'] = entry
        print(f"{a + ' - ' + b:<34} {common:>8} {fmt(entry['indicator'], common):>25} "
              f"{fmt(entry['expected'], common):>25}", flush=True)

    if args.tempered_seeds:
        print(f'\ntempered_elm - elm on {args.tempered_seeds} fresh seeds:')
        report['tempered_seeds'] = tempered_vs_elm(
            grid, fpoc, d, range(100, 100 + args.tempered_seeds), args.episodes_fast,
            args.horizon, args.bootstrap)
    if args.skip_planner:
        if args.json:
            args.json.write_text(json.dumps(report, indent=1))
        return
    ms, cpu_ms = decision_times(planner, grid, GaussianObservation(grid, fpoc), seed=args.seed)
    rate = report['policies']['planner']['decisions_per_second']
    report['planner'] = {'options': {k: getattr(planner, k) for k in (
        'candidates', 'rollouts', 'rollout_budget', 'horizon', 'until', 'objective',
        'switch_z')}, 'single_decision_ms': {'median': float(np.median(ms)),
                                             'p90': float(np.percentile(ms, 90)),
                                             'max': float(np.max(ms)),
                                             'median_cpu': float(np.median(cpu_ms))},
        'batched_decisions_per_second': rate}
    print(f"\nplanner options: {report['planner']['options']}")
    print(f'planner decision time, single belief (200 decisions, fixations 1-10): median '
          f'{np.median(ms):.1f} ms, 90th percentile {np.percentile(ms, 90):.1f} ms, '
          f'max {np.max(ms):.1f} ms; median CPU time {np.median(cpu_ms):.1f} ms '
          f'(wall exceeds CPU when the machine is shared)')
    print(f'planner batched throughput: {rate:.0f} decisions/s '
          f'({args.episodes} episodes x {args.horizon} fixations)')
    if args.json:
        args.json.write_text(json.dumps(report, indent=1))
        print(f'wrote {args.json}')


if __name__ == '__main__':
    main()
