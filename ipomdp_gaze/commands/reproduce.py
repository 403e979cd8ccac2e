# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze reproduce``: regenerate ``docs/reproduction.md`` and its figures.

Everything comes from the shipped kernels and fixed seeds, so a rerun gives the same numbers;
``--retrain`` retrains every shipped kernel first (long). Each figure and table is measured in
the run that writes the report, with common random numbers across policies.
"""
from __future__ import annotations

import csv
import hashlib
import os
from pathlib import Path
import resource
import sys
import time

from ipomdp_gaze.drivers.pieces import COSTLY_CHUNK, PieceCache, PLANNER_CHUNK, Runner
from ipomdp_gaze.files.writable import write_text
from ipomdp_gaze.model.fpoc import dprime_table
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.conv import radial_bins
from ipomdp_gaze.policies.planner import make_planner, TemperedELM
import numpy as np

from .common import bootstrap_count, check_output_folder, nonneg_int, positive_int
from .running import add_run_args, executor_from_args, progress_from_args

ROOT = Path(__file__).resolve().parents[2]
# A source checkout has docs/ (the report, the learning curves of Fig. 3); an installed package
# does not, and writes beside the working directory instead.
CHECKOUT = (ROOT / 'docs' / 'data').is_dir()
CURVES = {'weight sharing (conv, 27 weights)': 'human-7x7-infomax.csv',
          'no weight sharing (logistic, 2401 weights)': 'human-7x7-logistic.csv'}
# The shipped run's options (docs/reproduction.md); the notes quote numbers of this run.
DEFAULTS = {'episodes': 20000, 'episodes_greedy': 2000, 'episodes_planner': 2000, 'seed': 0,
            'bootstrap': 1000, 'retrain': False}
SHIPPED_RUN = ('episodes', 'episodes_greedy', 'episodes_planner', 'seed', 'retrain')
KERNELS = ('human-7x7-infomax', 'human-11x11-infomax', 'human-11x11-fixate_target',
           'exponential-11x11-infomax', 'camera-11x11-infomax')
PAPER_7X7 = {'learned infomax': 7.86, 'greedy': 8.96, 'map': 9.25, 'random': 11.33}
# The ideal searcher, the switching searcher and the planner run this many fixations (90% is
# reached by about 9).
COSTLY_HORIZON = 16
# The other runs stop here instead of at N: Fig. 4a plots 25 fixations, and every 11x11 policy
# reaches 90% by 30. A run must be pieces.REACHED correct at its last fixation (checked). The
# slow searchers run in pieces of pieces.COSTLY_CHUNK episodes, the planner of PLANNER_CHUNK.
HORIZON_7X7, HORIZON_11X11 = 25, 60
PAPER_11X11 = {'infomax-trained': 18.0, 'fixate-target-trained': 20.0}


def add_parser(sub):
    p = sub.add_parser('reproduce', help="regenerate docs/reproduction.md and the paper's figures",
                       description='Reproduce Table I and Figs. 3-6 of Butko & Movellan (2008) '
                                   'from the shipped kernels with fixed seeds.')
    p.add_argument('--out', type=Path, default=ROOT / 'docs' if CHECKOUT else Path('reproduction'),
                   help='output folder (default docs/ of a source checkout, else ./reproduction)')
    p.add_argument('--episodes', type=positive_int, default=DEFAULTS['episodes'])
    p.add_argument('--episodes-greedy', type=positive_int, default=DEFAULTS['episodes_greedy'])
    p.add_argument('--episodes-planner', type=positive_int, default=DEFAULTS['episodes_planner'])
    p.add_argument('--seed', type=nonneg_int, default=DEFAULTS['seed'])
    p.add_argument('--bootstrap', type=bootstrap_count, default=DEFAULTS['bootstrap'])
    p.add_argument('--retrain', action='store_true',
                   help='retrain every shipped kernel first, into OUT/kernels (with its learning '
                        'curve), and report on those')
    p.add_argument('--cache', type=Path, default=(ROOT if CHECKOUT else Path('.')) / '.cache' /
                   'reproduce', metavar='DIR',
                   help='keep every simulated piece here and reuse it while its inputs and the '
                        'package source are unchanged (default .cache/reproduce)')
    p.add_argument('--no-cache', dest='cache', action='store_const', const=None,
                   help='simulate everything, keep nothing')
    add_run_args(p)
    p.set_defaults(run=run)


def _load(name):
    from ipomdp_gaze.policies.policy_file import load_policy_spec
    return load_policy_spec(name)


def retrain_argv(spec, out) -> list[str]:
    """
    Return the ``ipomdp-gaze train`` arguments that retrain a shipped kernel as its file records.

    Task, reward, family, epochs, seed and learning rate come from the file; a kernel that was
    started at a multiple of ELM's (``init: elm x SCALE``) is started there again.
    """
    training = spec.training or {}
    fpoc_args = []
    for key, value in spec.fpoc.params().items():
        fpoc_args += ['--fpoc-param', f'{key}={value}']
    argv = ['train', '--grid', f'{spec.grid.rows}x{spec.grid.cols}',
            '--spacing-deg', str(spec.grid.spacing_deg), '--fpoc', spec.fpoc.model,
            *fpoc_args, '--reward', spec.reward, '--family', spec.family,
            '--epochs', str(int(training.get('epochs', 300))),
            '--seed', str(int(training.get('seed', 0))), '--out', str(out)]
    if 'learning_rate' in training:
        argv += ['--learning-rate', str(training['learning_rate'])]
    init = str(training.get('init', 'zeros'))
    if init.startswith('elm x '):
        argv += ['--init-elm', init[len('elm x '):]]
    return argv


def _retrain(log, folder: Path) -> dict:
    """Retrain every shipped kernel into ``folder`` (never the installed package); their paths."""
    from ipomdp_gaze.cli import main as cli_main
    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for name in KERNELS:
        paths[name] = folder / f'{name}.yaml'
        argv = retrain_argv(_load(name), paths[name])
        log(f'retraining {name}: ipomdp-gaze {" ".join(argv)}')
        if cli_main(argv) != 0:
            raise RuntimeError(f'retraining {name} failed')
    return paths


def _curves(retrained: dict) -> dict | None:
    """
    Return Fig. 3's learning curves by label, or None where they are not at hand.

    The conv curve is the retrained kernel's when ``--retrain`` made one, else the shipped
    record's in docs/data; the logistic curve is always the shipped record's (made by ``train
    --family logistic``, docs/reproduction_notes.md). Only a source checkout has docs/data.
    """
    data = ROOT / 'docs' / 'data'
    curves = {label: data / name for label, name in CURVES.items()}
    if 'human-7x7-infomax' in retrained:
        curves['weight sharing (conv, 27 weights)'] = \
            retrained['human-7x7-infomax'].with_suffix('.csv')
    return curves if all(path.is_file() for path in curves.values()) else None


def _where(executor) -> str:
    """Where the pieces ran, for the log and the report: ``2 processes``, ``3 Dask workers``."""
    if hasattr(executor, 'client'):
        return counted(executor.workers, 'Dask worker')
    return counted(executor.workers, 'process', 'processes')


def _fmt(point, ci):
    if point is None:
        return 'not reached'
    return f'{point:.2f}' + (f' [{ci[0]:.2f}, {ci[1]:.2f}]' if ci else '')


def _plot_curves(plt, curves: dict, path: Path) -> None:
    """Draw Fig. 3: mean return and fixations to 90% per epoch, each curve of ``curves``."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for label, path_csv in curves.items():
        c = _read_curve(path_csv)
        axes[0].plot(c['epoch'], c['mean_return'], label=label)
        ok = ~np.isnan(c['fixations_to_90'])
        axes[1].plot(c['epoch'][ok], c['fixations_to_90'][ok], 'o-', ms=3, label=label)
    axes[0].set_xlabel('epoch (150 episodes each)')
    axes[0].set_ylabel('mean return (infomax)')
    axes[1].set_xlabel('epoch (150 episodes each)')
    axes[1].set_ylabel('fixations to 90% correct')
    axes[1].axhline(PAPER_7X7['learned infomax'], color='0.5', ls='--', lw=0.8)
    for ax in axes:
        ax.set_xscale('log')
        ax.legend()
    fig.suptitle('7x7, human FPOC: learning with and without weight sharing')
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _curve_lines(curves: dict) -> list[str]:
    """Fig. 3's section: when each curve first reaches the paper's level, and the speed-up."""
    lines = []
    for label, path in curves.items():
        c = _read_curve(path)
        ok = np.where(c['fixations_to_90'] <= PAPER_7X7['learned infomax'])[0]
        if ok.size:
            lines.append(f'- {label}: first reaches {PAPER_7X7["learned infomax"]} fixations to '
                         f'90% at epoch {c["epoch"][ok[0]]:.0f} '
                         f'({c["wall_seconds"][ok[0]]:.0f} s wall).')
        else:
            best = np.nanmin(c['fixations_to_90'])
            lines.append(f'- {label}: does not reach {PAPER_7X7["learned infomax"]} within '
                         f'{c["epoch"][-1]:.0f} epochs (best {best:.2f}, '
                         f'{c["wall_seconds"][-1]:.0f} s wall).')
    loaded = {label: _read_curve(path) for label, path in curves.items()}
    level = max(np.nanmin(c['fixations_to_90']) for c in loaded.values())
    reach = {}
    for label, c in loaded.items():
        hit = np.where(c['fixations_to_90'] <= level)[0]
        reach[label] = (c['epoch'][hit[0]], c['wall_seconds'][hit[0]])
    (la, (ea, wa)), (lb, (eb, wb)) = reach.items()
    lines += ['', f"Common level (the worse curve's best): {level:.2f} fixations to 90% on the "
              f'training-time evaluation set. {la} first reaches it at epoch {ea:.0f} '
              f'({wa:.0f} s), {lb} at epoch {eb:.0f} ({wb:.0f} s): weight sharing is '
              f'{eb / ea:.0f}x faster in epochs and {wb / max(wa, 1e-9):.0f}x in wall time '
              '(the paper: about 20x).', '',
              '![Fig. 3](figures/fig3_learning_curves.png)', '']
    return lines


def _pyplot():
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    return plt


def _radial_profile(spec):
    values, bins = radial_bins(spec.grid)
    kernel = spec.kernel
    weight = np.array([kernel[bins == b].mean() for b in range(values.size)])
    return np.sqrt(values), weight


def preferred_offset_cells(kernel: np.ndarray) -> float:
    """
    Distance in cells from a single likely target to where the policy then looks.

    With the belief on one cell j, ``score_k = K[r_j - r_k + R-1, c_j - c_k + C-1]``: the policy
    looks at the offset of the kernel's largest entry (ties to the first, as argmax does).
    """
    rows, cols = kernel.shape
    r, c = np.unravel_index(int(np.argmax(kernel)), kernel.shape)
    return float(np.hypot(r - (rows - 1) // 2, c - (cols - 1) // 2))


def _plot_kernels(plt, specs, titles, path, fpoc_panel=False):
    n = len(specs)
    rows = 3 if fpoc_panel else 2
    fig, axes = plt.subplots(rows, n, figsize=(3.6 * n, 3.1 * rows), squeeze=False)
    for i, (spec, title) in enumerate(zip(specs, titles)):
        row = 0
        if fpoc_panel:
            ax = axes[0, i]
            ecc_cells = np.linspace(0, spec.grid.rows - 1, 200)
            ax.plot(ecc_cells, spec.fpoc(ecc_cells * spec.grid.spacing_deg, 0.0), color='k')
            ax.set_title(f'FPOC: {spec.fpoc.model}')
            ax.set_xlabel('eccentricity (cells)')
            ax.set_ylabel("d'")
            row = 1
        dist, weight = _radial_profile(spec)
        ax = axes[row, i]
        ax.plot(dist, weight, 'o-', ms=3)
        ax.axhline(0, color='0.6', lw=0.8)
        ax.set_title(title)
        ax.set_xlabel('distance from fixation (cells)')
        ax.set_ylabel('kernel weight')
        ax = axes[row + 1, i]
        lim = np.max(np.abs(spec.kernel))
        im = ax.imshow(spec.kernel, cmap='RdBu_r', vmin=-lim, vmax=lim,
                       extent=[-(spec.grid.cols - 0.5), spec.grid.cols - 0.5,
                               spec.grid.rows - 0.5, -(spec.grid.rows - 0.5)])
        ax.set_xlabel('column offset (cells)')
        ax.set_ylabel('row offset (cells)')
        fig.colorbar(im, ax=ax, shrink=0.8)
        if spec.fpoc.model == 'camera':
            inside = dprime_table(spec.grid, spec.fpoc) > 0
            ax.contour(np.arange(-(spec.grid.cols - 1), spec.grid.cols),
                       np.arange(-(spec.grid.rows - 1), spec.grid.rows), inside.astype(float),
                       levels=[0.5], colors='k', linewidths=1)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _read_curve(path):
    with open(path, newline='') as fh:
        rows = list(csv.DictReader(fh))
    out = {}
    for key in ('epoch', 'mean_return', 'fixations_to_90', 'wall_seconds'):
        out[key] = np.array([float(r[key]) if r.get(key) not in (None, '') else np.nan
                             for r in rows])
    return out


def _policy(source, spec):
    """
    Return ``(policy, recipe)``: the kernel of a policy file, or a baseline on its task.

    ``source`` is a policy spec, ``'tempered'`` (tempered ELM at its defaults) or a baseline's
    name; the recipe names it for the cache (a kernel by its bytes).
    """
    if not isinstance(source, str):
        kernel = hashlib.sha256(np.ascontiguousarray(source.kernel).tobytes()).hexdigest()
        return source.make_policy('argmax'), ('kernel', source.family, kernel)
    if source == 'tempered':
        return TemperedELM(spec.grid, spec.fpoc), ('tempered elm', 'defaults')
    return make_baseline(source, spec.grid, spec.fpoc), ('baseline', source)


def _simulate_all(args, specs, pool, cache, log, progress=None):
    """
    Queue every simulation of the report (the slowest first), then wait for all of them.

    The slow searchers of Table I, the planner and every policy whose class sets ``costly``,
    run on the first ``--episodes-planner`` / ``--episodes-greedy`` episodes for
    :data:`COSTLY_HORIZON` fixations. Returns the runners of Table I (7x7), of the 11x11
    comparison and of the other FPOCs.
    """
    h7 = specs['human-7x7-infomax']
    grid7, fpoc7 = h7.grid, h7.fpoc
    r7 = Runner(grid7, fpoc7, args.episodes, args.seed, args.bootstrap, pool, cache,
                progress=progress)
    table = {name: _policy(source, h7) for name, source in (
        ('learned infomax', h7), ('elm', 'elm'), ('tempered elm', 'tempered'), ('map', 'map'),
        ('center', 'center'), ('random', 'random'), ('greedy', 'greedy'),
        ('switching', 'switching'))}
    slow = [name for name, (policy, _) in table.items() if getattr(policy, 'costly', False)]
    log(f"7x7 slow searchers: planner, {', '.join(slow)} ({_where(pool)})")
    r7.submit('planner', make_planner(grid7, fpoc7), args.episodes_planner, COSTLY_HORIZON,
              PLANNER_CHUNK, recipe=('planner', 'defaults'))
    for name in slow:
        policy, recipe = table[name]
        r7.submit(name, policy, args.episodes_greedy, COSTLY_HORIZON, COSTLY_CHUNK,
                  recipe=recipe)

    # 11x11: infomax-trained vs fixate-target-trained.
    h11 = specs['human-11x11-infomax']
    r11 = Runner(h11.grid, h11.fpoc, args.episodes, args.seed, args.bootstrap, pool, cache,
                 progress=progress)
    ft11 = specs['human-11x11-fixate_target']
    log('11x11 human and the other FPOCs')
    for name, source in (('infomax-trained', h11), ('fixate-target-trained', ft11), ('elm', 'elm'),
                         ('map', 'map')):
        policy, recipe = _policy(source, h11)
        r11.submit(name, policy, horizon=HORIZON_11X11, recipe=recipe)

    # Other FPOCs at 11x11 (the kernels of Fig. 6), each against ELM and MAP on its own task.
    others = {}
    for name in ('exponential-11x11-infomax', 'camera-11x11-infomax'):
        spec = specs[name]
        runner = Runner(spec.grid, spec.fpoc, args.episodes, args.seed, args.bootstrap, pool,
                        cache, progress=progress)
        for label, source in (('learned', spec), ('elm', 'elm'), ('map', 'map')):
            policy, recipe = _policy(source, spec)
            runner.submit(label, policy, horizon=HORIZON_11X11, recipe=recipe)
        others[name] = runner

    # Table I: 7x7, human FPOC.
    log('7x7 fast policies')
    for name, (policy, recipe) in table.items():
        if name not in slow:
            r7.submit(name, policy, horizon=HORIZON_7X7, recipe=recipe)
    for label, runner in (('11x11', r11), *others.items(), ('7x7', r7)):
        runner.collect()
        log(f'{label} done')
    if args.cache is not None:
        log(f'{cache.hits} pieces from the cache {args.cache}')
    return r7, r11, others


def run(args) -> int:
    check_output_folder('--out', args.out)
    if args.cache is not None:
        check_output_folder('--cache', args.cache)
    out, figures = args.out, args.out / 'figures'
    figures.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    load_start = os.getloadavg()[0]

    def log(message):
        print(f'[{time.perf_counter() - started:6.0f} s] {message}', file=sys.stderr,
              flush=True)

    retrained = _retrain(log, out / 'kernels') if args.retrain else {}
    specs = {name: _load(str(retrained.get(name, name))) for name in KERNELS}
    curves = _curves(retrained)
    if curves is None:
        log('Fig. 3 is not drawn: its learning curves (docs/data/human-7x7-*.csv) are in a '
            'source checkout of ipomdp_gaze, not in an installed package')
    plt = _pyplot()
    lines = []
    cache = PieceCache(args.cache)
    # An error or Ctrl-C cancels the pieces still running; the finished ones are in the cache.
    with executor_from_args(args) as pool, \
            progress_from_args(args, 0, 'reproduce', 'episode') as progress:
        r7, r11, others = _simulate_all(args, specs, pool, cache, log, progress)
    where = _where(pool)
    h7, h11 = specs['human-7x7-infomax'], specs['human-11x11-infomax']
    planner_ms = 1000 * r7.seconds['planner'] / r7.decisions['planner']

    # Figure 4a.
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for name in ('switching', 'planner', 'learned infomax', 'tempered elm', 'elm', 'greedy', 'map',
                 'center', 'random'):
        pc = r7.correct[name].mean(axis=0)[:25]
        ax.plot(np.arange(1, pc.size + 1), pc, marker='o', ms=3, label=name)
    ax.axhline(0.9, color='0.5', ls='--', lw=0.8)
    ax.set_xlabel('fixations')
    ax.set_ylabel('percent correct (49-AFC)')
    ax.set_title('7x7, human FPOC: percent correct vs fixations')
    ax.legend()
    fig.tight_layout()
    fig.savefig(figures / 'fig4a_percent_correct.png', dpi=110)
    plt.close(fig)

    # Kernel figures.
    _plot_kernels(plt, [h7], ['learned infomax kernel, 7x7 human'],
                  figures / 'fig4b_kernel_human_7x7.png')
    _plot_kernels(plt, [h11, specs['human-11x11-fixate_target']],
                  ['infomax, 11x11 human', 'fixate target, 11x11 human'],
                  figures / 'fig5a_kernels_11x11.png')
    fig6 = [h11, specs['exponential-11x11-infomax'], specs['camera-11x11-infomax']]
    _plot_kernels(plt, fig6, ['human', 'exponential', 'camera'],
                  figures / 'fig6_kernels_by_fpoc.png', fpoc_panel=True)

    # Figure 3: learning curves with and without weight sharing.
    if curves is not None:
        _plot_curves(plt, curves, figures / 'fig3_learning_curves.png')

    lines += _report(args, r7, r11, others, specs, planner_ms, curves)
    cpu = sum(getattr(resource.getrusage(who), field) for field in ('ru_utime', 'ru_stime')
              for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    if hasattr(pool, 'client'):                 # the pieces' CPU time on the cluster's workers
        cpu += sum(sum(r.seconds.values()) for r in (r7, r11, *others.values()))
    wall = time.perf_counter() - started
    load_end = os.getloadavg()[0]
    lines += [f'This report: {wall / 60:.1f} min wall, {cpu / 60:.1f} min CPU in {where} '
              f'({cache.hits} of the pieces from the cache), load average '
              f'{load_start:.1f} at the start and {load_end:.1f} at the end (this machine: '
              f'{os.cpu_count()} cores).', '']
    write_text(out / 'reproduction.md', '\n'.join(lines) + '\n')
    log(f'wrote {out / "reproduction.md"} and {figures}/ ({wall:.0f} s wall, {cpu:.0f} s CPU)')
    return 0


def _report(args, r7, r11, others, specs, planner_ms, curves):
    seed = args.seed
    lines = ['# Reproducing Butko & Movellan (2008), "I-POMDP: An Infomax Model of Eye Movement"',
             '',
             f'Regenerated by `make reproduce` (`ipomdp-gaze reproduce --seed {seed}`) from the '
             'shipped kernels in `policies/kernels/`; `--retrain` retrains them first. Every '
             'policy in a table sees the same targets and observation noise (common random '
             'numbers); intervals are 95% percentile bootstraps over episodes '
             f'({args.bootstrap} resamples). Fixations to 90% correct are interpolated linearly '
             'between fixations; the first fixation is chosen by the policy from the uniform '
             'prior (ties to the lowest cell index).',
             '',
             '## Table I: fixations to 90% correct, 7x7 (49-AFC), human FPOC',
             '',
             f'Human FPOC at the calibrated default (noise_contrast 0.20, foveal_dprime 2.0, '
             f'0.42 deg/cell); argmax actions; {args.episodes} episodes (the ideal searcher and '
             f'the switching searcher {min(args.episodes_greedy, args.episodes)}, the planner '
             f'{min(args.episodes_planner, args.episodes)}, each on the first episodes of the '
             f'same set and for {COSTLY_HORIZON} fixations, enough to pass 90%).',
             '',
             '| policy | paper | ours [95% CI] | episodes |',
             '|---|---|---|---|']
    labels = {'learned infomax': 'learned infomax (conv kernel)', 'greedy':
              'percent-correct greedy (ideal searcher)', 'map': 'fixate target (MAP)',
              'random': 'fixate random', 'elm': 'ELM (N&G 2009)', 'center': 'fixate centre',
              'tempered elm': 'tempered ELM (ours: B^0.7, d^1.75)',
              'planner': 'rollout planner on tempered ELM (ours)',
              'switching': 'switching: tempered ELM, the ideal searcher from fixation 6 (ours)'}
    for name in ('learned infomax', 'greedy', 'map', 'random', 'elm', 'center', 'tempered elm',
                 'planner', 'switching'):
        n, point, ci = r7.summary(name)
        paper = PAPER_7X7.get(name)
        lines.append(f"| {labels[name]} | {'' if paper is None else paper} | "
                     f'{_fmt(point, ci)} | {n} |')
    lines += ['', 'Paired differences (same episodes; negative = fewer fixations):', '']
    for a, b in (('learned infomax', 'elm'), ('learned infomax', 'map'),
                 ('tempered elm', 'elm'), ('tempered elm', 'greedy'), ('planner', 'elm'),
                 ('planner', 'tempered elm'), ('planner', 'greedy'), ('greedy', 'elm'),
                 ('learned infomax', 'greedy'), ('switching', 'elm'), ('switching', 'greedy'),
                 ('switching', 'tempered elm')):
        diff, ci = r7.paired(a, b)
        n = min(r7.correct[a].shape[0], r7.correct[b].shape[0])
        lines.append(f'- {a} - {b}: {_fmt(diff, ci)} fixations ({n} paired episodes)')
    lines += ['', f'Planner decision time: {planner_ms:.2f} ms of CPU per decision, measured as '
              'the CPU time of the batched evaluation (pieces of '
              f'{PLANNER_CHUNK} episodes) divided by its decisions (this machine). Its '
              "rollouts run in float32, whose last bits depend on the CPU's vector "
              "instructions and on BLAS's thread count (`ipomdp-gaze` runs BLAS on one thread "
              'unless OPENBLAS_NUM_THREADS or OMP_NUM_THREADS is set; on two, this row read '
              '7.64), so on another machine a few of its choices, and the last digit of its '
              'rows, may differ (every other row is computed in float64).',
              '', '![Fig. 4a](figures/fig4a_percent_correct.png)', '']

    lines += ['## 11x11 (121-AFC), human FPOC: infomax-trained vs fixate-target-trained', '',
              '| policy | paper | ours [95% CI] | episodes |', '|---|---|---|---|']
    for name in ('infomax-trained', 'fixate-target-trained', 'elm', 'map'):
        n, point, ci = r11.summary(name)
        paper = PAPER_11X11.get(name)
        lines.append(f"| {name} | {'' if paper is None else paper:} | {_fmt(point, ci)} | {n} |")
    diff, ci = r11.paired('infomax-trained', 'fixate-target-trained')
    lines += ['', f'Paired difference infomax-trained - fixate-target-trained: {_fmt(diff, ci)}.',
              '']

    lines += ['## Kernels of the other FPOCs (11x11)', '',
              '| kernel | learned [95% CI] | ELM | MAP |', '|---|---|---|---|']
    for name, runner in others.items():
        cells = [_fmt(*runner.summary(label)[1:]) for label in ('learned', 'elm', 'map')]
        spec = specs[name]
        lines.append(f'| {name} ({spec.grid.spacing_deg} deg/cell, {spec.fpoc.to_dict()}) | '
                     + ' | '.join(cells) + ' |')
    lines += ['']

    lines += ['## Where the learned kernels look (Figs. 4b, 5a, 6)', '',
              'With the belief on a single cell, a convolutional policy looks at the offset of '
              "its kernel's largest entry; the table gives that distance, the paper's claim, and "
              'whether ours shows it.', '',
              '| kernel | looks this far from a likely target | paper | holds? |',
              '|---|---|---|---|']
    claims = {'human-7x7-infomax': ('next to, not at', lambda d: 0 < d <= 2.5),
              'human-11x11-infomax': ('next to, not at', lambda d: 0 < d <= 2.5),
              'human-11x11-fixate_target': ('at it (when sure)', lambda d: d == 0),
              'exponential-11x11-infomax': ('straight at it', lambda d: d == 0),
              'camera-11x11-infomax': ('near the edge of the field of view', None)}
    for name, (claim, check) in claims.items():
        spec = specs[name]
        dist = preferred_offset_cells(spec.kernel)
        if check is None:
            half = (dprime_table(spec.grid, spec.fpoc) > 0).sum(axis=1).max() // 2
            holds = half - 0.5 <= dist <= half + 0.5
            claim = f'{claim} (edge at {half} cells)'
        else:
            holds = check(dist)
        lines.append(f"| {name} | {dist:.2f} cells | {claim} | {'yes' if holds else 'no'} |")
    lines += ['', '![Fig. 4b](figures/fig4b_kernel_human_7x7.png)', '',
              '![Fig. 5a](figures/fig5a_kernels_11x11.png)', '',
              '![Fig. 6](figures/fig6_kernels_by_fpoc.png)', '']

    lines += ['## Fig. 3: learning with and without weight sharing', '']
    lines += _curve_lines(curves) if curves is not None else [
        'Not drawn: its learning curves (docs/data/human-7x7-*.csv) are in a source checkout of '
        'ipomdp_gaze, not in an installed package.', '']
    notes = ROOT / 'docs' / 'reproduction_notes.md'
    if notes.exists():
        shipped = {name: DEFAULTS[name] for name in SHIPPED_RUN}
        given = {name: getattr(args, name) for name in SHIPPED_RUN}
        if given != shipped:
            def flags(values):
                return ', '.join(f'`--{name.replace("_", "-")}`' if value is True else
                                 f'`--{name.replace("_", "-")} {value}`'
                                 for name, value in values.items() if value is not False)
            lines += [f'*The notes below quote the shipped run ({flags(shipped)}); this run '
                      f'used {flags({k: v for k, v in given.items() if v != shipped[k]})}, and '
                      'its own numbers are the tables and figures above.*', '']
        lines += [notes.read_text().rstrip(), '']
    return lines
