# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze reproduce``: regenerate ``docs/reproduction.md`` and its figures.

Everything comes from the shipped kernels and fixed seeds, so a rerun gives the same numbers;
``--retrain`` retrains every shipped kernel first (long). Each figure and table is measured in
the run that writes the report, with common random numbers across policies.
"""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
import csv
import functools
import hashlib
import json
import os
from pathlib import Path
import resource
import time

from ipomdp_gaze.evaluation import bootstrap_counts, fixations_to_90_ci, paired_difference_ci
from ipomdp_gaze.fpoc import dprime_matrix, dprime_table
from ipomdp_gaze.observation import GaussianObservation
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.conv import radial_bins
from ipomdp_gaze.policies.greedy import expected_percent_correct_at
from ipomdp_gaze.policies.planner import make_planner, TemperedELM
from ipomdp_gaze.simulate import draw_targets, simulate
import numpy as np

from .common import nonneg_int, positive_int

ROOT = Path(__file__).resolve().parents[2]
KERNELS = ('human-7x7-infomax', 'human-11x11-infomax', 'human-11x11-fixate_target',
           'exponential-11x11-infomax', 'camera-11x11-infomax')
PAPER_7X7 = {'learned infomax': 7.86, 'greedy': 8.96, 'map': 9.25, 'random': 11.33}
# The ideal searcher, the switching searcher and the planner run this many fixations (90% is
# reached by about 9).
COSTLY_HORIZON = 16
# The other runs stop here instead of at N: Fig. 4a plots 25 fixations, and every 11x11 policy
# reaches 90% by 30. A run must be REACHED correct at its last fixation (checked).
HORIZON_7X7, HORIZON_11X11, REACHED = 25, 60, 0.95
# The slow searchers (policies whose class sets ``costly = True``) are split into pieces of this
# many episodes, the planner into PLANNER_CHUNK (fixed, so the planner's own draws, one stream
# per piece, do not depend on the number of processes).
COSTLY_CHUNK, PLANNER_CHUNK = 250, 500
PAPER_11X11 = {'infomax-trained': 18.0, 'fixate-target-trained': 20.0}


def add_parser(sub):
    p = sub.add_parser('reproduce', help="regenerate docs/reproduction.md and the paper's figures",
                       description='Reproduce Table I and Figs. 3-6 of Butko & Movellan (2008) '
                                   'from the shipped kernels with fixed seeds.')
    p.add_argument('--out', type=Path, default=ROOT / 'docs', help='output folder (default docs/)')
    p.add_argument('--episodes', type=positive_int, default=20000)
    p.add_argument('--episodes-greedy', type=positive_int, default=2000)
    p.add_argument('--episodes-planner', type=positive_int, default=2000)
    p.add_argument('--seed', type=nonneg_int, default=0)
    p.add_argument('--bootstrap', type=positive_int, default=1000)
    p.add_argument('--retrain', action='store_true', help='retrain every shipped kernel first')
    p.add_argument('--cache', type=Path, default=ROOT / '.cache' / 'reproduce', metavar='DIR',
                   help='keep every simulated piece here and reuse it while its inputs and the '
                        'package source are unchanged (default .cache/reproduce)')
    p.add_argument('--no-cache', dest='cache', action='store_const', const=None,
                   help='simulate everything, keep nothing')
    p.add_argument('--jobs', type=positive_int, default=os.cpu_count() or 1,
                   help='worker processes (default: one per core; the numbers do not depend on '
                        'it)')
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


def _retrain(log):
    from ipomdp_gaze.cli import main as cli_main
    from ipomdp_gaze.policies.policy_file import resolve_source
    for name in KERNELS:
        argv = retrain_argv(_load(name), resolve_source(name))
        log(f'retraining {name}: ipomdp-gaze {" ".join(argv)}')
        if cli_main(argv) != 0:
            raise RuntimeError(f'retraining {name} failed')


def source_digest() -> str:
    """SHA-256 of every Python source of the package (a cached result is stale when it moves)."""
    digest = hashlib.sha256()
    package = Path(__file__).resolve().parents[1]
    for folder in (package, package / 'policies'):
        for path in sorted(folder.resolve().rglob('*.py')):
            digest.update(path.read_bytes())
    return digest.hexdigest()


class PieceCache:
    """
    Results of simulated pieces on disk, keyed by everything that decides them.

    The key is the SHA-256 of a piece's recipe (how its policy is built: a baseline's name, or
    a policy file's name and kernel), its task (grid, FPOC), its own targets, horizon, seed and
    rows, and of :func:`source_digest` (the code that builds and runs the policy), so a changed
    kernel, setting or line of code misses the cache. The run's length is not in the key: a run
    of n episodes is the first n episodes of a longer one (targets, noise and each piece's
    policy stream are prefix-stable), so a longer run reuses every piece of a shorter one whose
    rows it shares. ``folder=None`` caches nothing.
    """

    # What a piece file holds after its JSON line, in this order (the line records it).
    LAYOUT = {'correct': 'packbits', 'map_prob': '<f8'}

    def __init__(self, folder: Path | None):
        self.folder = None if folder is None else Path(folder)
        self.source = source_digest() if folder is not None else ''
        self.hits = 0

    def key(self, recipe, grid, fpoc, targets, horizon, seed, rows) -> str | None:
        """
        Return the hex key of rows ``start:stop`` of a run on ``targets`` (None: never cached).

        Only the piece's own targets, ``targets[start:stop]``, enter the key, so runs of any
        length share it (see the class docstring). None without a recipe or a folder.
        """
        if self.folder is None or recipe is None:
            return None
        start, stop = rows
        digest = hashlib.sha256(self.source.encode())
        text = repr((recipe, (grid.rows, grid.cols, grid.spacing_deg), fpoc.model,
                     sorted(fpoc.params().items()), horizon, seed, (start, stop)))
        digest.update(text.encode())
        digest.update(np.ascontiguousarray(targets[start:stop], dtype=np.int64).tobytes())
        return digest.hexdigest()

    def load(self, key):
        """Return a cached piece, ``(correct, map_prob, cpu_seconds, decisions)``, or None."""
        if key is None:
            return None
        try:
            raw = (self.folder / f'{key}.bin').read_bytes()
            head, _, body = raw.partition(b'\n')
            meta = json.loads(head)
            if meta['layout'] != self.LAYOUT:
                return None                     # another layout: simulate again
            shape = tuple(int(v) for v in meta['shape'])
            size = int(np.prod(shape))
            packed = -(-size // 8)
            if len(body) != packed + 8 * size:
                return None                     # a truncated or foreign file: simulate again
            bits = np.unpackbits(np.frombuffer(body, dtype=np.uint8, count=packed), count=size)
            map_prob = np.frombuffer(body, dtype='<f8', offset=packed).astype(np.float64)
            found = (bits.reshape(shape).astype(bool), map_prob.reshape(shape),
                     float(meta['seconds']), int(meta['decisions']))
        except (OSError, KeyError, ValueError, TypeError):
            return None
        self.hits += 1
        return found

    def store(self, key, result):
        """
        Write one piece: a JSON line, the packed bits of ``correct``, then ``map_prob``.

        The JSON line holds the shape, ``LAYOUT``, CPU seconds and decisions; ``map_prob``
        is little-endian float64. Written to a temporary file and renamed into place, so a
        reader never sees half a piece.
        """
        if key is None:
            return
        correct, map_prob, seconds, decisions = result
        self.folder.mkdir(parents=True, exist_ok=True)
        head = json.dumps({'shape': list(correct.shape), 'layout': self.LAYOUT,
                           'seconds': float(seconds), 'decisions': int(decisions)}).encode()
        bits = np.packbits(correct.astype(bool)).tobytes()
        values = np.ascontiguousarray(map_prob, dtype='<f8').tobytes()
        tmp = self.folder / f'{key}.{os.getpid()}.tmp'
        tmp.write_bytes(head + b'\n' + bits + values)
        os.replace(tmp, self.folder / f'{key}.bin')


class _RaoBlackwell:
    """
    A policy that also records, after each decision, ``E[max_i B'_i | belief, fixation]``.

    That is :func:`ipomdp_gaze.policies.greedy.expected_percent_correct_at`: the probability that
    the MAP guess is right after the observation, with that observation's noise integrated out.
    Its mean over episodes is the percent-correct curve (the simulated belief is the exact
    posterior), with less variance than ``max_i B_i``. ``seconds`` is the CPU time spent on it,
    kept out of the policy's decision time.
    """

    def __init__(self, policy, dprime):
        self.policy, self.dprime = policy, dprime
        self.scores, self.seconds = [], 0.0

    def select(self, belief, t, rng):
        fixations = np.asarray(self.policy.select(belief, t, rng), dtype=np.int64)
        t0 = time.process_time()
        self.scores.append(expected_percent_correct_at(belief, self.dprime, fixations))
        self.seconds += time.process_time() - t0
        return fixations


def _simulate_rows(grid, model, policy, targets, horizon, seed, rows, rao_blackwell=False):
    """
    Run one piece of work in a worker: correct, max_i B_i, CPU seconds, decisions.

    With ``rao_blackwell`` the second matrix is the Rao-Blackwellised ``max_i B_i`` of
    :class:`_RaoBlackwell` instead (the same mean).
    """
    t0 = time.process_time()
    scored = _RaoBlackwell(policy, dprime_matrix(grid, model.fpoc)) if rao_blackwell else None
    result = simulate(grid, model, scored or policy, targets.size, horizon, seed,
                      targets=targets, rows=rows)
    seconds = time.process_time() - t0
    if scored is None:
        return result.correct, result.map_prob, seconds, result.fixations.size
    return (result.correct, np.stack(scored.scores, axis=1), seconds - scored.seconds,
            result.fixations.size)


class Runner:
    """
    Simulate policies on shared targets and noise; keep each one's per-episode matrices.

    Every run is submitted to ``pool`` (a process pool, or None to run in this process) in
    pieces of ``chunk`` episodes: each piece is the rows ``start:stop`` of the whole run
    (:func:`ipomdp_gaze.simulate.simulate` with ``rows``), so a deterministic policy's matrix is
    the one a single serial run gives, whatever the number of processes. A stochastic policy's
    own draws come from one stream per piece (fixed ``chunk``, so still deterministic).
    :meth:`collect` waits for every submitted run and keeps, per name, ``correct`` (MAP guess
    right), ``map_prob`` (``max_i B_i``), CPU ``seconds`` and ``decisions``. Pieces found in
    ``cache`` (a :class:`PieceCache`) are not run again; new ones are stored there. Used by
    ``reproduce`` and ``bench/planner_vs_greedy.py``. With ``rao_blackwell`` (Gaussian FPOC
    model), ``map_prob`` holds ``E[max_i B'_i]`` given the belief and fixation before each
    observation (:class:`_RaoBlackwell`): the same curve, less variance.
    """

    def __init__(self, grid, fpoc, episodes, seed, bootstrap, pool=None, cache=None,
                 rao_blackwell=False):
        self.rao_blackwell = bool(rao_blackwell)
        self.grid, self.fpoc, self.seed = grid, fpoc, seed
        self.episodes, self.bootstrap, self.pool = episodes, bootstrap, pool
        self.cache = PieceCache(None) if cache is None else cache
        self.model = GaussianObservation(grid, fpoc)
        self.targets = draw_targets(grid.n_cells, episodes, seed)
        self.correct, self.map_prob, self.seconds, self.decisions = {}, {}, {}, {}
        self._pending = {}

    def submit(self, name, policy, episodes=None, horizon=None, chunk=None, *, recipe=None):
        """
        Queue ``episodes`` (default all) of ``policy`` for ``horizon`` fixations.

        ``recipe`` says how ``policy`` was built (see :class:`PieceCache`); without one the run
        is never cached. Returns the number of pieces.
        """
        n = self.episodes if episodes is None else min(episodes, self.episodes)
        chunk = n if chunk is None else int(chunk)
        jobs = []
        for start in range(0, n, chunk):
            args = (self.grid, self.model, policy, self.targets[:n], horizon, self.seed,
                    (start, min(start + chunk, n)), self.rao_blackwell)
            key = self.cache.key(recipe if not self.rao_blackwell or recipe is None
                                 else (recipe, 'rao-blackwell'),
                                 self.grid, self.fpoc, *args[3:7])
            found = self.cache.load(key)
            if found is not None:
                jobs.append((None, found))
            elif self.pool is not None:
                jobs.append((key, self.pool.submit(_simulate_rows, *args)))
            else:
                jobs.append((key, _simulate_rows(*args)))
        self._pending[name] = jobs
        return len(jobs)

    def collect(self):
        """Wait for every queued run; keep its matrices, summed CPU seconds and decisions."""
        for name, jobs in self._pending.items():
            parts = []
            for key, job in jobs:                     # key None: the piece came from the cache
                job = job.result() if hasattr(job, 'result') else job
                if key is not None:
                    self.cache.store(key, job)
                parts.append(job)
            self.correct[name] = np.concatenate([p[0] for p in parts])
            self.map_prob[name] = np.concatenate([p[1] for p in parts])
            self.seconds[name] = sum(p[2] for p in parts)
            self.decisions[name] = sum(p[3] for p in parts)
        self._pending = {}

    def summary(self, name):
        """Return episodes, fixations to 90% correct and its bootstrap interval of a run."""
        correct = self.correct[name]
        _check_reached(name, correct)
        counts = _bootstrap_counts(correct.shape[0], self.bootstrap, (self.seed, 7))
        point, ci = fixations_to_90_ci(correct, self.grid.n_cells, None, self.bootstrap,
                                       counts=counts)
        return correct.shape[0], point, ci

    def paired(self, a, b):
        """Return the paired difference ``a - b`` of fixations to 90% and its interval."""
        horizon = min(self.correct[a].shape[1], self.correct[b].shape[1])
        n = min(self.correct[a].shape[0], self.correct[b].shape[0])
        for name in (a, b):
            _check_reached(name, self.correct[name][:n, :horizon])
        counts = _bootstrap_counts(n, self.bootstrap, (self.seed, 8))
        return paired_difference_ci(self.correct[a][:, :horizon], self.correct[b][:, :horizon],
                                    self.grid.n_cells, None, self.bootstrap, counts=counts)


@functools.lru_cache(maxsize=8)
def _bootstrap_counts(episodes, resamples, key):
    """
    Return the resampling weights ``default_rng(key)`` draws for ``episodes`` (computed once).

    Every summary (and every paired difference) of a run drew the same weights from the same
    seed; drawing them once gives the same numbers at a fraction of the cost.
    """
    counts = bootstrap_counts(episodes, resamples, np.random.default_rng(list(key)))
    counts.flags.writeable = False
    return counts


def _check_reached(name, correct):
    """
    Refuse a run cut too short: every bootstrap resample must reach 90% within its horizon.

    Runs stop at :data:`HORIZON_7X7` / :data:`HORIZON_11X11` fixations, not N (fixations to 90%
    only needs the curve up to its first crossing, and fixation t's numbers do not depend on
    later ones). Requiring 95% correct at the last fixation leaves no resample short of 90%.
    """
    final = float(correct[:, -1].mean())
    if final < REACHED:
        raise RuntimeError(f'{name}: only {final:.1%} correct after {correct.shape[1]} fixations; '
                           f'raise the horizon of this run')


def _fmt(point, ci):
    if point is None:
        return 'not reached'
    return f'{point:.2f}' + (f' [{ci[0]:.2f}, {ci[1]:.2f}]' if ci else '')


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


def _simulate_all(args, specs, pool, cache, log):
    """
    Queue every simulation of the report (the slowest first), then wait for all of them.

    The slow searchers of Table I, the planner and every policy whose class sets ``costly``,
    run on the first ``--episodes-planner`` / ``--episodes-greedy`` episodes for
    :data:`COSTLY_HORIZON` fixations. Returns the runners of Table I (7x7), of the 11x11
    comparison and of the other FPOCs.
    """
    h7 = specs['human-7x7-infomax']
    grid7, fpoc7 = h7.grid, h7.fpoc
    r7 = Runner(grid7, fpoc7, args.episodes, args.seed, args.bootstrap, pool, cache)
    table = {name: _policy(source, h7) for name, source in (
        ('learned infomax', h7), ('elm', 'elm'), ('tempered elm', 'tempered'), ('map', 'map'),
        ('center', 'center'), ('random', 'random'), ('greedy', 'greedy'),
        ('switching', 'switching'))}
    slow = [name for name, (policy, _) in table.items() if getattr(policy, 'costly', False)]
    log(f"7x7 slow searchers: planner, {', '.join(slow)} ({args.jobs} processes)")
    r7.submit('planner', make_planner(grid7, fpoc7), args.episodes_planner, COSTLY_HORIZON,
              PLANNER_CHUNK, recipe=('planner', 'defaults'))
    for name in slow:
        policy, recipe = table[name]
        r7.submit(name, policy, args.episodes_greedy, COSTLY_HORIZON, COSTLY_CHUNK,
                  recipe=recipe)

    # 11x11: infomax-trained vs fixate-target-trained.
    h11 = specs['human-11x11-infomax']
    r11 = Runner(h11.grid, h11.fpoc, args.episodes, args.seed, args.bootstrap, pool, cache)
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
                        cache)
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
    out, figures = args.out, args.out / 'figures'
    figures.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    load_start = os.getloadavg()[0]

    def log(message):
        print(f'[{time.perf_counter() - started:6.0f} s] {message}', flush=True)

    if args.retrain:
        _retrain(log)
    specs = {name: _load(name) for name in KERNELS}
    plt = _pyplot()
    lines = []
    pool = ProcessPoolExecutor(args.jobs) if args.jobs > 1 else None
    cache = PieceCache(args.cache)
    try:
        r7, r11, others = _simulate_all(args, specs, pool, cache, log)
    except BaseException:
        if pool is not None:                    # do not wait for the pieces still running
            for process in list((pool._processes or {}).values()):
                process.terminate()
            pool.shutdown(wait=False, cancel_futures=True)
        raise
    if pool is not None:
        pool.shutdown()
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
    data = ROOT / 'docs' / 'data'
    curves = {'weight sharing (conv, 27 weights)': data / 'human-7x7-infomax.csv',
              'no weight sharing (logistic, 2401 weights)': data / 'human-7x7-logistic.csv'}
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for label, path in curves.items():
        if not path.exists():
            raise FileNotFoundError(f'learning curve {path} is missing (train with --family)')
        c = _read_curve(path)
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
    fig.savefig(figures / 'fig3_learning_curves.png', dpi=110)
    plt.close(fig)

    lines += _report(args, r7, r11, others, specs, planner_ms, curves)
    cpu = sum(getattr(resource.getrusage(who), field) for field in ('ru_utime', 'ru_stime')
              for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    wall = time.perf_counter() - started
    load_end = os.getloadavg()[0]
    lines += [f'This report: {wall / 60:.1f} min wall, {cpu / 60:.1f} min CPU in {args.jobs} '
              f'processes ({cache.hits} of the pieces from the cache), load average '
              f'{load_start:.1f} at the start and {load_end:.1f} at the end (this machine: '
              f'{os.cpu_count()} cores).', '']
    (out / 'reproduction.md').write_text('\n'.join(lines) + '\n')
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
              f'{PLANNER_CHUNK} episodes) divided by its decisions (this machine).',
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
    speed = []
    for label, path in curves.items():
        c = _read_curve(path)
        ok = np.where(c['fixations_to_90'] <= PAPER_7X7['learned infomax'])[0]
        if ok.size:
            speed.append((label, c['epoch'][ok[0]], c['wall_seconds'][ok[0]]))
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
    notes = ROOT / 'docs' / 'reproduction_notes.md'
    if notes.exists():
        lines += [notes.read_text().rstrip(), '']
    return lines
