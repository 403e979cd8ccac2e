# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze search``: one offline search, printed fixation by fixation."""
from __future__ import annotations

import sys

from ipomdp_gaze.files.writable import write_figure
from ipomdp_gaze.model.belief import draw_cells
from ipomdp_gaze.model.observation import as_observation
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.policies.registry import build_policy, NAMED_POLICIES
from ipomdp_gaze.search import answer
from ipomdp_gaze.search.sensors import ModelSensor
from ipomdp_gaze.search.sensors import run_search as run_offline
from ipomdp_gaze.search.session import SearchSession, SearchSettings
import numpy as np

from .common import (add_prior_arg, add_task_args, cell_arg, cell_index, check_output_file,
                     nonneg_int, output_file, read_prior, task_from_args)
from .search_args import add_search_args, settings_from_args

# The paper's convention: the policy picks every fixation, the first included (design 4.1).
SEARCH_SETTINGS = SearchSettings(confidence=0.95, start_cell='policy')
# With no budget (--max-fixations 0) an offline search still ends: after this many frames per cell.
NO_BUDGET_FRAMES_PER_CELL = 100


def add_parser(sub):
    p = sub.add_parser('search', help='run one simulated search offline and print each fixation',
                       description='Simulate one search for a hidden target and print where '
                                   'the policy looked, the belief at the most likely cell and '
                                   'whether that guess is right.')
    add_task_args(p)
    p.add_argument('--policy', default='elm', choices=NAMED_POLICIES,
                   help='the policy by name (default elm)')
    p.add_argument('--policy-file', default=None, metavar='PATH',
                   help='a policy YAML file or a shipped kernel name (overrides --policy)')
    p.add_argument('--target', type=cell_arg, default=None, metavar='ROW,COL',
                   help='target cell as ROW,COL or a flat index (default random)')
    p.add_argument('--empty', action='store_true',
                   help='a target-absent trial: the scene holds no target (the frames are '
                        'noise); with --absent-prior the search can answer absent')
    add_search_args(p, SEARCH_SETTINGS, ('confidence', 'absent_prior'))
    p.add_argument('--max-fixations', type=nonneg_int, default=None, metavar='N',
                   help='fixation budget: gave up when it runs out undecided (default 4 N; 0 = '
                        f'no budget, but an offline search still gives up after '
                        f'{NO_BUDGET_FRAMES_PER_CELL} N)')
    add_prior_arg(p, 'the hidden target is drawn from it (unless --target) and the belief starts '
                     'at it')
    p.add_argument('--seed', type=nonneg_int, default=0)
    p.add_argument('--plot', type=output_file, default=None, metavar='PNG',
                   help='save the final belief with the scan path as a picture')
    p.set_defaults(run=run)


def run_search(grid, model, policy, target, settings: SearchSettings, seed, out=print,
               prior=None):
    """
    Run one simulated search on the search session, printing each fixation.

    ``prior`` (N,), optional: where the belief starts (the session's prior). The model's own
    sampler is the world (:class:`ipomdp_gaze.search.sensors.ModelSensor`); one
    generator, ``default_rng(seed)``, serves the policy and the noise; the loop is
    :func:`ipomdp_gaze.search.sensors.run_search`. Returns ``(guess, path, belief, result)``
    (``result``: the last :class:`ipomdp_gaze.search.session.StepResult`).
    """
    rng = np.random.default_rng(seed)
    session = SearchSession(grid, model, policy, settings, prior=prior)
    sensor = ModelSensor(grid, model, rng)
    with_absent = settings.absent_prior > 0
    if target is None:
        out(f'no target: an empty {grid.rows}x{grid.cols} grid (a target-absent trial)')
    else:
        tr, tc = grid.cell(target)
        out(f'target hidden at cell {target} ({tr}, {tc}) of a {grid.rows}x{grid.cols} grid')
    steps = []

    def says_absent(result) -> bool:
        # The simulator's and the stop rule's answer: absent while strictly the likelier.
        return with_absent and result.absent_probability > result.map_probability

    def right(result, answer_absent: bool) -> str:
        if target is None:
            return 'right' if answer_absent else 'wrong'
        return 'right' if result.map_cell == target and not answer_absent else 'wrong'

    def show(frame, result):
        steps.append(result)
        kr, kc = grid.cell(session.path[-1])
        gr, gc = grid.cell(result.map_cell)
        entropy = max(session.entropy_nats, 0.0) + 0.0    # never -0.00 of a decided belief
        # With the absent hypothesis the answer so far is absent while it is the likeliest.
        absent = f'  P(absent)={result.absent_probability:.3f}' if with_absent else ''
        likelier = says_absent(result)
        out(f'fixation {result.fixations:3d}: looked at ({kr}, {kc})  ->  most likely ({gr}, '
            f'{gc}) p={result.map_probability:.3f}{absent}  entropy {entropy:.2f} nats  '
            f'{right(result, likelier)}')

    limit = None if settings.max_fixations else NO_BUDGET_FRAMES_PER_CELL * grid.n_cells
    run_offline(session, sensor, target, seed=rng, limit=limit, on_frame=show)
    result = steps[-1]
    guess = result.map_cell
    gr, gc = grid.cell(guess)
    if result.decision == 'absent':
        clause = answer.confidence_clause(result.decision, result.reason,
                                          result.absent_probability, settings.confidence)
        out(f'{answer.heading(result.decision, result.reason)}: no target, P(absent) '
            f'{result.absent_probability:.3f}, after {counted(result.fixations, "fixation")}'
            f'{clause}, which is {right(result, True)}')
        return None, session.path, session.belief, result
    verdict = right(result, False)
    likeliest = f'the target is most likely at ({gr}, {gc}), probability ' \
                f'{result.map_probability:.3f}'
    if says_absent(result):             # undecided, but the answer so far is absent
        verdict = right(result, True)
        likeliest = f'most likely no target, P(absent) {result.absent_probability:.3f}'
    clause = answer.confidence_clause(result.decision, result.reason, result.map_probability,
                                      settings.confidence)
    if not result.decision:
        out(f'gave up: no cell reached the confidence {settings.confidence:.12g} after '
            f'{counted(result.fixations, "fixation")}, the cap of an offline search without a '
            f'budget ({NO_BUDGET_FRAMES_PER_CELL} per cell); {likeliest}, which is {verdict}')
    elif result.decision == 'gave_up':
        out(f'gave up: no cell reached the confidence {settings.confidence:.12g} at '
            f'{answer.limit_text(result.reason, session.limit_cause)}; {likeliest}, after '
            f'{counted(result.fixations, "fixation")}, which is {verdict}')
    else:
        out(f'{answer.heading(result.decision, result.reason)}: the target is most likely at '
            f'({gr}, {gc}), probability {result.map_probability:.3f}, after '
            f'{counted(result.fixations, "fixation")}{clause}, which is {verdict}')
    return guess, session.path, session.belief, result


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
    if target is not None:
        tr, tc = grid.cell(target)
        ax.plot(tc, tr, marker='*', ms=16, mfc='none', mec='lime', mew=2)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel('column')
    ax.set_ylabel('row')
    fig.tight_layout()
    write_figure(fig, out_path, dpi=110)
    plt.close(fig)


def run(args) -> int:
    if args.plot:
        check_output_file('--plot', args.plot, plot=True)
    grid, fpoc = task_from_args(args)
    if args.policy_file:
        policy = build_policy('learned', grid, fpoc, file=args.policy_file)
    else:
        policy = build_policy(args.policy, grid, fpoc)
    if args.max_fixations is None:
        args.max_fixations = 4 * grid.n_cells
    settings = settings_from_args(args, SEARCH_SETTINGS, grid)
    prior = None if args.prior is None else read_prior(args.prior, grid)
    rng = np.random.default_rng([args.seed, 1])
    if args.empty and args.target is not None:
        raise ValueError('--empty is a scene without a target: leave out --target')
    if args.target is not None:
        target = cell_index(args.target, grid, '--target')
        if prior is not None and prior[target] == 0:
            raise ValueError(f'--target {grid.cell(target)} is a cell --prior {args.prior} rules '
                             'out (weight 0): the search could never find it there')
    else:
        target = int(draw_cells(rng, grid.n_cells, prior))
    if args.empty:
        target = None
    guess, path, belief, result = run_search(grid, as_observation(grid, fpoc), policy, target,
                                             settings, args.seed, prior=prior)
    if args.plot:
        name = args.policy_file or args.policy
        task = f'{fpoc.model} FPOC' if args.observation is None else args.observation
        ending = answer.heading(result.decision, result.reason)
        if not result.decision:
            ending = (f'gave up at the cap of an offline search ({NO_BUDGET_FRAMES_PER_CELL} per '
                      'cell)')
        elif result.decision == 'gave_up':
            ending += f' at {answer.limit_text(result.reason)}'
        # Two lines: one would run past the figure's edges and under the colour bar.
        p = (f'P(absent)={result.absent_probability:.3f}' if result.decision == 'absent'
             else f'p={result.map_probability:.3f}')
        title = (f'{grid.rows}x{grid.cols}, {task}, {name}\n{ending}, '
                 f'{p}, {counted(len(path), "fixation")} '
                 f"{'(no target)' if target is None else '(star = target)'}")
        plot_search(grid, belief, path, target, title, args.plot)
        print(f'ipomdp-gaze search: wrote {args.plot}', file=sys.stderr)
    return 0
