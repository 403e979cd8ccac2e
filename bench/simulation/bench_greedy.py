# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Cost and accuracy of the percent-correct greedy searcher (the Najemnik & Geisler ideal searcher).

Run: ``.venv/bin/python bench/simulation/bench_greedy.py [--quick] [--json OUT]``.

Beliefs come from simulated searches (7x7: the greedy searcher's own; 11x11: ELM searches, as
simulating the greedy searcher there is slow), one decision per call (a batch of one), timed
with ``time.perf_counter``: median, p90, p99 over many decisions, by fixation number, and the
uniform prior (the costliest, nothing can be pruned); wall and process-CPU time (the steadier
figure on a shared machine). Beside it, in the same run, the naive
reference: Najemnik & Geisler's formula summed directly (``percent_correct_given_target``,
O(N^3 Q)). Accuracy: the scores against 1024 quadrature nodes without pruning, and the pruning
gap against its proven bound.
"""
import argparse
import json
from pathlib import Path
import time

from ipomdp_gaze.commands.common import parse_with_outputs
from ipomdp_gaze.model.belief import argmax_ties_low
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.greedy import (expected_percent_correct, percent_correct_given_target,
                                         PercentCorrectGreedy)
from ipomdp_gaze.simulation.simulate import simulate
import numpy as np


class Recorder:
    """Wrap a policy and keep every belief batch it is asked about."""

    def __init__(self, policy):
        self.policy = policy
        self.beliefs = []

    def select(self, belief, t, rng):
        """Record the beliefs, then defer to the wrapped policy."""
        self.beliefs.append(np.array(belief, copy=True))
        return self.policy.select(belief, t, rng)


def search_beliefs(grid, fpoc, policy_name, episodes, horizon, seed):
    """Beliefs ``(horizon, episodes, N)`` seen by a policy during simulated searches."""
    recorder = Recorder(make_baseline(policy_name, grid, fpoc))
    t0 = time.perf_counter()
    result = simulate(grid, fpoc, recorder, episodes, horizon, seed)
    wall = time.perf_counter() - t0
    return np.stack(recorder.beliefs), result, wall


def time_calls(function, arguments):
    """
    Wall and process-CPU seconds of ``function(a)`` for each argument, as two arrays.

    The CPU time is the steadier figure on a machine shared with other jobs.
    """
    wall, cpu = np.empty(len(arguments)), np.empty(len(arguments))
    for i, arg in enumerate(arguments):
        w0, c0 = time.perf_counter(), time.process_time()
        function(arg)
        wall[i], cpu[i] = time.perf_counter() - w0, time.process_time() - c0
    return wall, cpu


def summary_ms(seconds):
    """Median, p90, p99 and max wall milliseconds, and the median CPU milliseconds."""
    wall, cpu = 1e3 * np.asarray(seconds[0]), 1e3 * np.asarray(seconds[1])
    return {'median_ms': float(np.median(wall)), 'p90_ms': float(np.percentile(wall, 90)),
            'p99_ms': float(np.percentile(wall, 99)), 'max_ms': float(wall.max()),
            'cpu_median_ms': float(np.median(cpu)), 'calls': int(wall.size)}


def decision_costs(policy, beliefs, samples, rng):
    """Time single decisions on beliefs sampled uniformly over (fixation number, episode)."""
    horizon, episodes, _ = beliefs.shape
    t_idx = rng.integers(0, horizon, samples)
    e_idx = rng.integers(0, episodes, samples)
    seconds, cpu = time_calls(lambda b: policy.select(b[None], 0, None), beliefs[t_idx, e_idx])
    kept = np.array([policy.expected_percent_correct(b, return_bound=True)[2]
                     for b in beliefs[t_idx, e_idx]])
    by_t = {}
    for lo, hi in ((0, 1), (1, 5), (5, 10), (10, 20), (20, horizon)):
        sel = (t_idx >= lo) & (t_idx < hi)
        if sel.any():
            by_t[f'{lo}-{hi - 1}'] = {'median_ms': float(1e3 * np.median(seconds[sel])),
                                      'cpu_median_ms': float(1e3 * np.median(cpu[sel])),
                                      'mean_kept_cells': float(kept[sel].mean()),
                                      'calls': int(sel.sum())}
    uniform = np.full((1, beliefs.shape[2]), 1.0 / beliefs.shape[2])
    return {'all': summary_ms((seconds, cpu)), 'by_fixation_number': by_t,
            'uniform_prior': summary_ms(time_calls(lambda b: policy.select(b, 0, None),
                                                   [uniform] * 15))}


def accuracy(policy, beliefs, samples, rng):
    """Quadrature error against 1024 nodes (unpruned) and the pruning gap against its bound."""
    flat = beliefs.reshape(-1, beliefs.shape[-1])
    pick = flat[rng.choice(len(flat), size=min(samples, len(flat)), replace=False)]
    d = policy.dprime
    reference = expected_percent_correct(pick, d, tol=0.0, nodes=1024, power=2)
    unpruned = expected_percent_correct(pick, d, tol=0.0, nodes=policy.nodes, power=policy.power)
    pruned, bound, kept = policy.expected_percent_correct(pick, return_bound=True)
    gap = unpruned - pruned
    return {'beliefs': int(len(pick)), 'nodes': policy.nodes, 'power': policy.power,
            'max_quadrature_error': float(np.abs(unpruned - reference).max()),
            'max_pruned_vs_reference': float(np.abs(pruned - reference).max()),
            'decisions_equal_to_reference': float(np.mean(argmax_ties_low(pruned)
                                                          == argmax_ties_low(reference))),
            'pruning_gap_min': float(gap.min()), 'pruning_gap_max': float(gap.max()),
            'max_bound': float(bound.max()), 'mean_kept_cells': float(kept.mean())}


def naive_reference(policy, belief, node_counts):
    """Cost of the direct O(N^3 Q) formula on one belief, beside the fast path on the same one."""
    d = policy.dprime
    out = {}
    for nodes in node_counts:
        _, cpu = time_calls(lambda b: np.argmax(b @ percent_correct_given_target(b, d, nodes)),
                            [belief])
        out[f'direct_formula_{nodes}_nodes_ms'] = float(1e3 * cpu[0])
    _, cpu = time_calls(lambda b: policy.select(b[None], 0, None), [belief] * 5)
    out['fast_ms'] = float(1e3 * np.median(cpu))
    out['ratio'] = out[f'direct_formula_{policy.nodes}_nodes_ms'] / out['fast_ms']
    return out


def bench_grid(shape, policy_name, episodes, horizon, samples, naive_nodes=(), seed=0):
    """Everything for one grid with the default human FPOC."""
    grid, fpoc = Grid(*shape, 0.42), make_fpoc('human')
    policy = PercentCorrectGreedy(grid, fpoc)
    beliefs, result, wall = search_beliefs(grid, fpoc, policy_name, episodes, horizon, seed)
    rng = np.random.default_rng(seed)
    out = {'grid': f'{shape[0]}x{shape[1]}', 'beliefs_from': f'{policy_name} searches',
           'episodes': episodes, 'horizon': horizon,
           'simulate_wall_s': wall, 'decision': decision_costs(policy, beliefs, samples, rng),
           'accuracy': accuracy(policy, beliefs, min(samples, 300), rng)}
    out['naive_reference'] = naive_reference(policy, beliefs[0, 0],
                                             tuple(naive_nodes) + (policy.nodes,))
    return out


def print_grid(result):
    """Plain-text report of one grid."""
    dec, acc = result['decision'], result['accuracy']
    print(f"== {result['grid']} human FPOC; beliefs from {result['beliefs_from']} "
          f"({result['episodes']} episodes x {result['horizon']}, simulated in "
          f"{result['simulate_wall_s']:.1f} s)")
    a = dec['all']
    print(f"one decision (wall): median {a['median_ms']:.2f} ms, p90 {a['p90_ms']:.2f}, "
          f"p99 {a['p99_ms']:.2f}, max {a['max_ms']:.2f}; CPU median {a['cpu_median_ms']:.2f} ms "
          f"({a['calls']} calls)")
    for span, row in dec['by_fixation_number'].items():
        print(f"  fixations {span:>6}: median {row['median_ms']:8.2f} ms wall, "
              f"{row['cpu_median_ms']:8.2f} ms CPU, mean kept cells "
              f"{row['mean_kept_cells']:5.1f} ({row['calls']} calls)")
    u = dec['uniform_prior']
    print(f"uniform prior (nothing pruned): median {u['median_ms']:.2f} ms wall, "
          f"{u['cpu_median_ms']:.2f} ms CPU")
    n = result['naive_reference']
    print('naive reference on the uniform prior (CPU): ' + ', '.join(
        f'{k} {v:.1f}' for k, v in n.items() if k.endswith('_ms')) +
        f"; the fast path is {n['ratio']:.0f}x faster at equal node count")
    print(f"accuracy on {acc['beliefs']} beliefs ({acc['nodes']} nodes, power {acc['power']}): "
          f"max quadrature error {acc['max_quadrature_error']:.1e}, pruned vs 1024-node "
          f"reference {acc['max_pruned_vs_reference']:.1e}; pruning gap in "
          f"[{acc['pruning_gap_min']:.1e}, {acc['pruning_gap_max']:.1e}] <= bound "
          f"{acc['max_bound']:.1e}; decisions equal to the reference: "
          f"{100 * acc['decisions_equal_to_reference']:.1f}%")


def main(argv=None):
    """Run the benchmark and print (and optionally write) the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--quick', action='store_true', help='fewer episodes and calls')
    parser.add_argument('--json', type=Path, default=None, metavar='OUT')
    args = parse_with_outputs(parser, argv, json='--json')
    scale = 0.25 if args.quick else 1.0
    results = [
        bench_grid((7, 7), 'greedy', int(120 * scale), 49, int(600 * scale), (512,)),
        bench_grid((11, 11), 'elm', int(40 * scale), 60, int(120 * scale)),
    ]
    for result in results:
        print_grid(result)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(results, indent=1) + '\n')
        print(f'wrote {args.json}')
    return results


if __name__ == '__main__':
    main()
