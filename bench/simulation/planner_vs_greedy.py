# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
7x7 human FPOC: the searchers beyond the paper against ELM and the ideal searcher, on both cores.

Run: ``.venv/bin/python bench/simulation/planner_vs_greedy.py [--episodes 4000] [--seed 1] [--jobs
2]
[--horizon 16] [--policies elm,tempered,greedy,planner] [--planner-options K=V,...]
[--cache DIR] [--chunk 2000] [--rao-blackwell] [--json OUT] [--scheduler ADDRESS] [--quiet]``.
docs/reproduction.md quotes two runs: ``--episodes 4000 --seed 1`` (about 10 CPU-minutes) and
``--episodes 200000 --seed 1 --horizon 9 --policies elm,tempered,greedy,switching --json
docs/data/searchers-7x7.json`` (about 2.5 CPU-hours, two thirds of it the ideal searcher).

Every policy runs the same episodes (common random numbers), split into pieces over an
executor (``ipomdp_gaze.drivers.pieces.Runner`` on ``--jobs`` processes or the Dask cluster of
``--scheduler``: ``simulate(..., rows=)``, so every deterministic policy gives exactly its
serial numbers; the planner draws its rollouts from one stream per piece of 500 episodes).
Printed: fixations to 90% correct by the indicator (MAP guess right) and by the expected percent
correct (mean of ``max_i B_i``, the same curve with less variance), each with a 95% bootstrap
interval, then the paired differences. ``--cache DIR`` keeps finished pieces in
``pieces.PieceCache``, so an interrupted run resumes and a longer run reuses a shorter one: a
run of n episodes is the first n episodes of a longer one (test_simulate.py), so a piece's key
is its policy and options, task, own targets, seed, horizon and rows and the package source, not
the run's length. The pieces of the other policies are ``--chunk`` episodes (default 2000; their
numbers do not depend on it).

``--rao-blackwell`` replaces the expected measure by ``expected_rb``: the mean of
``E[max_i B'_i]`` given the belief and the fixation before each observation (the percent correct
after it with that observation's noise integrated out, ``greedy.expected_percent_correct_at``).
Same curve, about half the variance of paired differences at 7x7. docs/reproduction.md quotes
``--episodes 200000 --seed 2 --horizon 9 --policies elm,tempered,greedy,switching
--rao-blackwell --json docs/data/searchers-7x7-rb.json``.
"""
import argparse
import itertools
import json
from pathlib import Path

from ipomdp_gaze.commands.common import positive_int
from ipomdp_gaze.drivers.pieces import PieceCache, PLANNER_CHUNK, Runner
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.planner import make_planner
from ipomdp_gaze.simulation.evaluation import (fixations_to_90_ci, format_interval,
                                               paired_difference_ci)
from ipomdp_gaze.simulation.executor import make_executor
from ipomdp_gaze.simulation.progress import Progress
import numpy as np

GRID, FPOC = Grid(7, 7, 0.42), make_fpoc('human')
NAMES = ('elm', 'tempered', 'greedy', 'switching', 'planner')
DEFAULT_CHUNK = 2000
RESAMPLES = 1000                        # bootstrap resamples of every interval


def build(name, planner_options):
    """Return the policy called ``name`` and its recipe (how the piece cache names it)."""
    if name == 'planner':
        return (make_planner(GRID, FPOC, **planner_options),
                ('planner', tuple(sorted(planner_options.items()))))
    return make_baseline(name, GRID, FPOC), ('baseline', name)


def policy_list(text):
    """Comma-separated names from :data:`NAMES`."""
    names = [name for name in text.split(',') if name]
    unknown = sorted(set(names) - set(NAMES))
    if unknown or not names:
        raise argparse.ArgumentTypeError(f"policies must be some of {', '.join(NAMES)}, "
                                         f'got {text!r}')
    return names


def planner_options(text):
    """``key=value,...`` options of :class:`RolloutPlanner` (numbers or words)."""
    options = {}
    for item in filter(None, text.split(',')):
        key, sep, value = item.partition('=')
        if not sep or not key:
            raise argparse.ArgumentTypeError(f'planner options are key=value, got {item!r}')
        for kind in (int, float, str):
            try:
                options[key] = kind(value)
                break
            except ValueError:
                continue
    return options


def _value(value, ci, sign: str, episodes: int) -> str:
    """
    Format a value and its 95% interval from ``episodes`` episodes.

    No interval is ``-`` from fewer than MIN_EPISODES episodes, else a bound lies beyond the
    horizon; no value: 90% is never reached (by one of the pair).
    """
    if value is None:
        return 'never' if sign == '' else 'not defined (a policy never reaches 90%)'
    return f'{value:{sign}.3f} {format_interval(ci, sign + ".3f", episodes)}'


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--episodes', type=int, default=4000)
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--horizon', type=int, default=16)
    parser.add_argument('--policies', type=policy_list,
                        default=['elm', 'tempered', 'greedy', 'planner'])
    parser.add_argument('--planner-options', type=planner_options, default={},
                        help='RolloutPlanner options, e.g. candidates=8,rollout_budget=8192')
    parser.add_argument('--cache', type=Path, default=None)
    parser.add_argument('--chunk', type=positive_int, default=DEFAULT_CHUNK,
                        help='episodes per piece of every policy but the planner (its pieces '
                             'are 500)')
    parser.add_argument('--rao-blackwell', action='store_true',
                        help="the expected measure from E[max_i B'_i] given the belief and "
                             'fixation before each observation (less variance)')
    parser.add_argument('--json', type=Path, default=None)
    parser.add_argument('--scheduler', default=None, metavar='ADDRESS',
                        help='a Dask scheduler to run the pieces on (docs/cluster.md)')
    parser.add_argument('--quiet', action='store_true', help='no progress on stderr')
    args = parser.parse_args(argv)
    n, names = args.episodes, args.policies
    policies = {name: build(name, args.planner_options) for name in names}
    cache = PieceCache(args.cache)
    out = {'episodes': n, 'seed': args.seed, 'horizon': args.horizon,
           'rao_blackwell': args.rao_blackwell, 'policies': {}, 'paired': {}}
    pieces = 0
    with make_executor(args.jobs, args.scheduler) as pool, \
            Progress(0, 'planner_vs_greedy', 'episode', quiet=args.quiet) as progress:
        runner = Runner(GRID, FPOC, n, args.seed, RESAMPLES, pool, cache, args.rao_blackwell,
                        progress)
        for name in sorted(names, key=lambda x: not getattr(policies[x][0], 'costly', False)):
            policy, recipe = policies[name]
            pieces += runner.submit(name, policy, horizon=args.horizon,
                                    chunk=PLANNER_CHUNK if name == 'planner' else args.chunk,
                                    recipe=recipe)
        runner.collect()
    if args.cache is not None:
        print(f'{cache.hits} of {pieces} pieces from the cache {args.cache}')
    results = {name: (runner.correct[name], runner.map_prob[name]) for name in names}
    for name in names:
        cpu = runner.seconds[name]
        ms = 1000 * cpu / (n * args.horizon)
        out['policies'][name] = {'cpu_s': cpu, 'ms_per_decision': ms}
        print(f'{name}: {cpu:.0f} s CPU, {ms:.2f} ms per decision')
    measures = ('indicator', 'expected_rb' if args.rao_blackwell else 'expected')
    for name in names:
        for i, label in enumerate(measures):
            point, ci = fixations_to_90_ci(results[name][i], GRID.n_cells,
                                           np.random.default_rng([args.seed, 7]), RESAMPLES)
            out['policies'][name][label] = {'fixations_to_90': point, 'ci95': ci}
            print(f'{name:9s} {label:9s} {_value(point, ci, "", n)}')
    for a, b in itertools.combinations(names[::-1], 2):
        for i, label in enumerate(measures):
            diff, ci = paired_difference_ci(results[a][i], results[b][i], GRID.n_cells,
                                            np.random.default_rng([args.seed, 8]), RESAMPLES)
            out['paired'].setdefault(f'{a} - {b}', {})[label] = {'difference': diff, 'ci95': ci}
            print(f'{a} - {b} ({label}, {n} paired): {_value(diff, ci, "+", n)}')
    if args.json is not None:
        args.json.write_text(json.dumps(out, indent=1) + '\n')


if __name__ == '__main__':
    main()
