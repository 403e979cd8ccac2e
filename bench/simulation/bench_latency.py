# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Decision latency of the controller path (belief update + policy choice) from 7x7 to 512x512.

Each call is exactly what the gaze controller node does per frame: ``GazeController.offer(frame,
stamp)`` (check the frame, the observation model's log-likelihood ratio, the one Bayes step, the
found check and the policy's choice), with the ELM kernel (``K = d'^2``, human FPOC) and frames
drawn from the observation model (float32, like a ``Float32MultiArray`` buffer); the belief is
reset every :data:`EPISODE` calls and when a search ends at its found event, so flat and
peaked beliefs both occur. The direct and FFT
paths run interleaved in rounds on the same frames (their fixation sequences must agree), beside
naive references run in the same process: the probability-domain (exp) update with
``scipy.signal.correlate2d`` or ``scipy.signal.correlate(method='fft')`` scores, the allocating
library path (N x N matrices, as before issue 5) and a per-cell Python loop. Also: the measured
direct/FFT break-even, peak memory (tracemalloc) and the effect of kernel truncation.

Run through ``bench/run.py`` (``make bench``), or alone: ``python bench/simulation/bench_latency.py
[--quick] [--figures DIR]`` prints the markdown section (and draws its figures in ``DIR``).
"""
import argparse
import math
from pathlib import Path
import sys
import time
import tracemalloc

from ipomdp_gaze.model.belief import argmax_ties_low, bayes_update, TIE_RTOL, uniform_log_belief
from ipomdp_gaze.model.fpoc import dprime_table, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio, GaussianObservation
from ipomdp_gaze.policies import conv
from ipomdp_gaze.policies.baselines import elm_policy
from ipomdp_gaze.policies.conv import ConvPolicy, kernel_matrix
from ipomdp_gaze.search.gaze import GazeController
import numpy as np
import scipy.signal

TITLE = 'Decision latency (belief update + policy choice), FFT break-even, memory'
ORDER = 10
SIZES = (7, 11, 21, 64, 128, 256, 512)
CALLS = {7: 4000, 11: 4000, 21: 2000, 64: 600, 128: 200, 256: 80, 512: 30}
ROUNDS = 5
EPISODE = 25
DIRECT_MAX_SIDE = 64            # N x N matrix of 134 MB; 128x128 would need 2.1 GB
REFERENCE_CALLS = {'exp + correlate2d': {7: 400, 11: 400, 21: 100, 64: 6, 128: 2},
                   'exp + correlate (fft)': dict.fromkeys(SIZES, 40) | {256: 10, 512: 4},
                   'allocating library path': {7: 1000, 11: 1000, 21: 400, 64: 40},
                   'per-cell Python loop': {7: 20, 11: 6}}
BREAK_EVEN_SIDES = (8, 12, 16, 20, 22, 24, 26, 28, 30, 32, 36, 40, 44, 48)
TRUNCATIONS = (0.0, 1e-16, 1e-12, 1e-9, 1e-6)
TARGETS_US = {11: 50.0, 256: 5000.0}
INTRO = (
    'Each call is exactly what the gaze controller node does per frame: '
    '`GazeController.offer(frame, stamp)` (frame check, log-likelihood ratio of the Gaussian '
    'observation model, the one Bayes step, found check, policy choice), with the ELM kernel '
    "(`K = d'^2`, human FPOC, "
    'exactly 0 beyond 46 cells) and frames drawn from the observation model (float32, as read '
    f'from a `Float32MultiArray` buffer); the belief is reset every {EPISODE} frames, so flat and '
    'peaked beliefs both occur. Direct and FFT run interleaved in rounds on the same frames, and '
    'their fixation sequences are compared. Beside them, naive references in the same process: '
    'the probability-domain (exp) update with `scipy.signal.correlate2d` or '
    '`scipy.signal.correlate(method="fft")` scores, the allocating library path of before issue '
    "5 (the Bayes step with an N x N d' matrix, scores by an N x N product) and a per-cell "
    'Python loop.')


class TimedPolicy:
    """Forwards ``select`` to a policy and records its wall time: the decision inside ``offer``."""

    def __init__(self, policy):
        self.policy = policy
        self.ns = []

    def select(self, belief, t, rng):
        t0 = time.perf_counter_ns()
        choice = self.policy.select(belief, t, rng)
        self.ns.append(time.perf_counter_ns() - t0)
        return choice


class ControllerLoop:
    """The controller's per-frame work, driven by frames from the observation model."""

    def __init__(self, grid, fpoc, method, seed=0, frames=16, truncate=conv.DEFAULT_TRUNCATE):
        self.grid = grid
        self.model = GaussianObservation(grid, fpoc)
        self.table = self.model.table
        self.policy = ConvPolicy(grid, self.model.elm_kernel(), method=method, truncate=truncate)
        self.timed = TimedPolicy(self.policy)
        self.core = GazeController(grid, self.model, self.timed)
        rng = np.random.default_rng(seed)
        self.noise = rng.standard_normal((frames, grid.n_cells)).astype(np.float32)
        self.targets = rng.integers(0, grid.n_cells, size=10_000)
        self.frame = np.empty(grid.n_cells, dtype=np.float32)
        self.calls = 0
        self.fixations = []
        self.update_ns, self.decide_ns, self.cpu_ns = [], [], []
        self.target = 0

    def _prepare(self):
        """Start an episode when due and fill the next frame (not timed)."""
        g = self.grid
        if self.calls % EPISODE == 0 or self.core.stopped:    # found ends a search
            self.core.reset(0.0)
            self.target = int(self.targets[(self.calls // EPISODE) % self.targets.size])
        self.frame[:] = self.noise[self.calls % self.noise.shape[0]]
        rt, ct = divmod(self.target, g.cols)
        rk, ck = divmod(self.core.fixation, g.cols)
        self.frame[self.target] += self.table[rt - rk + g.rows - 1, ct - ck + g.cols - 1]

    def run(self, calls, keep=None):
        """Time ``calls`` frames; ``keep`` (list) collects a copy of every belief."""
        clock, cpu = time.perf_counter_ns, time.thread_time_ns
        core, frame, decided = self.core, self.frame, self.timed.ns
        for _ in range(calls):
            self._prepare()
            c0 = cpu()
            t0 = clock()
            result = core.offer(frame, 1.0)
            t1 = clock()
            c1 = cpu()
            self.calls += 1
            self.fixations.append(result.fixation)
            if keep is not None:
                keep.append(core.belief)
            if not decided:                 # the frame ended the search: no choice to time
                continue
            decide = decided.pop()
            self.update_ns.append(t1 - t0 - decide)
            self.decide_ns.append(decide)
            self.cpu_ns.append(c1 - c0)


class ReferenceLoop:
    """Naive implementations of the same per-frame work, for the ratios of item 4."""

    def __init__(self, grid, fpoc, kind, seed=0):
        self.grid, self.kind = grid, kind
        self.model = GaussianObservation(grid, fpoc)
        self.table = self.model.table
        self.kernel = self.table ** 2
        rng = np.random.default_rng(seed)
        self.noise = rng.standard_normal((16, grid.n_cells))
        self.calls, self.ns, self.cpu_ns = 0, [], []
        self.k = grid.center_index
        if kind == 'allocating library path':
            self.d_matrix = kernel_matrix(grid, self.table).T.copy()        # d[j, k]
            self.weights_t = kernel_matrix(grid, self.kernel).T.copy()
        self.reset()

    def reset(self):
        """Uniform prior in the reference's own representation."""
        n = self.grid.n_cells
        self.log_b = uniform_log_belief(n)
        self.b = np.full(n, 1.0 / n)
        self.b_list = [1.0 / n] * n

    def step(self, obs):
        """One frame: update and choose, the reference way."""
        g, k = self.grid, self.k
        if self.kind == 'allocating library path':
            self.log_b = bayes_update(self.log_b, gaussian_log_likelihood_ratio(
                obs, self.d_matrix[:, k]))
            return int(argmax_ties_low(np.exp(self.log_b) @ self.weights_t))
        if self.kind == 'per-cell Python loop':
            return self._loop_step(obs)
        d = self.model.dprime(k)
        lik = np.exp(d * (obs - 0.5 * d))
        b = self.b * np.where(np.isnan(lik), 1.0, lik)
        self.b = b / b.sum()
        grid_b = self.b.reshape(g.shape)
        if self.kind == 'exp + correlate2d':
            scores = scipy.signal.correlate2d(self.kernel, grid_b, mode='valid')
        else:
            scores = scipy.signal.correlate(self.kernel, grid_b, mode='valid', method='fft')
        return int(argmax_ties_low(scores[::-1, ::-1].ravel()))

    def _loop_step(self, obs):
        g, k, b = self.grid, self.k, self.b_list
        rows, cols = g.rows, g.cols
        rk, ck = divmod(k, cols)
        for j in range(rows * cols):
            rj, cj = divmod(j, cols)
            d = self.table[rj - rk + rows - 1, cj - ck + cols - 1]
            if not math.isnan(obs[j]):
                b[j] *= math.exp(d * (obs[j] - 0.5 * d))
        total = sum(b)
        for j in range(rows * cols):
            b[j] /= total
        scores = []
        for kk in range(rows * cols):
            rk, ck = divmod(kk, cols)
            s = 0.0
            for j in range(rows * cols):
                rj, cj = divmod(j, cols)
                s += b[j] * self.kernel[rj - rk + rows - 1, cj - ck + cols - 1]
            scores.append(s)
        return int(argmax_ties_low(np.array(scores)))

    def run(self, calls):
        """Time ``calls`` frames."""
        clock, cpu = time.perf_counter_ns, time.thread_time_ns
        for _ in range(calls):
            if self.calls % EPISODE == 0:
                self.reset()
                self.k = self.grid.center_index
            obs = self.noise[self.calls % 16]
            c0 = cpu()
            t0 = clock()
            self.k = self.step(obs)
            self.ns.append(clock() - t0)
            self.cpu_ns.append(cpu() - c0)
            self.calls += 1


def _median_p99(ns):
    a = np.asarray(ns, dtype=float) / 1e3
    return float(np.median(a)), float(np.percentile(a, 99))


def _fmt_us(us):
    if us is None or not np.isfinite(us):
        return '-'
    if us >= 1e6:
        return f'{us / 1e6:.2f} s'
    if us >= 1e3:
        return f'{us / 1e3:.2f} ms'
    return f'{us:.1f} µs'


def _fmt_ratio(ratio):
    """Return a reference / ours ratio: 2 significant digits below 10 (0.18x, 1.0x), else whole."""
    return f'{ratio:#.2g}x' if ratio < 9.95 else f'{ratio:,.0f}x'


def _fmt_bytes(b):
    if b is None:
        return '-'
    if b >= 2 ** 30:
        return f'{b / 2 ** 30:.2f} GiB'
    return f'{b / 2 ** 20:.1f} MiB' if b >= 2 ** 20 else f'{b / 2 ** 10:.0f} KiB'


def peak_memory(grid, fpoc, method):
    """Peak traced bytes while building the observation model, controller and policy + 3 calls."""
    tracemalloc.start()
    try:
        loop = ControllerLoop(grid, fpoc, method, frames=1)
        loop.run(3)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def frame_allocation(loop, frames=20):
    """Peak bytes traced by tracemalloc while the loop's controller handles frames."""
    core, frame = loop.core, loop.frame.copy()
    tracemalloc.start()
    try:
        for _ in range(frames):
            core.offer(frame, 1.0)
            loop.timed.ns.clear()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def latency(ctx, fpoc):
    """Item 1: per-size medians and p99 of ours and of the references."""
    rows = []
    for side in SIZES:
        grid = Grid(side, side)
        calls = max(5, CALLS[side] // (10 if ctx.quick else 1))
        methods = ['direct', 'fft'] if side <= DIRECT_MAX_SIDE else ['fft']
        loops = {m: ControllerLoop(grid, fpoc, m) for m in methods}
        refs = {}
        for kind, by_size in REFERENCE_CALLS.items():
            if side in by_size:
                refs[kind] = (ReferenceLoop(grid, fpoc, kind),
                              max(1, by_size[side] // (10 if ctx.quick else 1)))
        ctx.log(f'latency {side}x{side}: {calls} calls x {methods}, references {list(refs)}')
        for loop in loops.values():
            loop.run(min(5, calls))                     # warm-up (FFT plans, caches)
            loop.update_ns.clear(), loop.decide_ns.clear(), loop.cpu_ns.clear()
            loop.fixations.clear()
            loop.calls = 0
            loop.policy.rescored = 0
        for r in range(ROUNDS):
            share = calls // ROUNDS + (r < calls % ROUNDS)
            for loop in loops.values():
                loop.run(share)
            for ref, ref_calls in refs.values():
                ref.run(ref_calls // ROUNDS + (r < ref_calls % ROUNDS))
        auto = 'direct' if side * side <= conv.DIRECT_MAX_CELLS else 'fft'
        row = {'side': side, 'n': side * side, 'auto': auto, 'calls': calls}
        for m, loop in loops.items():
            total = np.add(loop.update_ns, loop.decide_ns)
            row[m] = _median_p99(total)
            row[m + ' update'] = _median_p99(loop.update_ns)
            row[m + ' decide'] = _median_p99(loop.decide_ns)
            row[m + ' cpu'] = _median_p99(loop.cpu_ns)
            row[m + ' allocation'] = frame_allocation(loop)
            row[m + ' shape'] = getattr(loop.policy, 'fft_shape', None)
            row[m + ' rescored'] = loop.policy.rescored
        if len(loops) == 2:
            row['same decisions'] = loops['direct'].fixations == loops['fft'].fixations
        for kind, (ref, _) in refs.items():
            row[kind] = _median_p99(ref.ns) if ref.ns else None
            row[kind + ' cpu'] = _median_p99(ref.cpu_ns) if ref.ns else None
        for m in methods:
            row[m + ' memory'] = peak_memory(grid, fpoc, m)
        rows.append(row)
    return rows


def break_even(ctx, fpoc):
    """Direct vs FFT decision CPU time over grid sides, single belief and a batch of 256."""
    out = []
    rng = np.random.default_rng(5)
    for side in BREAK_EVEN_SIDES:
        grid = Grid(side, side)
        kernel = dprime_table(grid, fpoc) ** 2
        policies = {m: ConvPolicy(grid, kernel, method=m) for m in ('direct', 'fft')}
        beliefs = rng.dirichlet(np.full(grid.n_cells, 0.3), size=256)
        reps = 40 if ctx.quick else 300
        single = {m: [] for m in policies}
        batch = {m: [] for m in policies}
        for p in policies.values():
            p.decide(beliefs[0]), p.select(beliefs[:8], 0, None)
        clock = time.thread_time_ns
        for r in range(reps):
            b = beliefs[r % 256]
            for m, p in policies.items():
                t0 = clock()
                p.decide(b)
                single[m].append(clock() - t0)
            if r % 20 == 0:
                for m, p in policies.items():
                    t0 = clock()
                    p.select(beliefs, 0, None)
                    batch[m].append(clock() - t0)
        out.append({'side': side, 'n': side * side,
                    'fft shape': policies['fft'].fft_shape,
                    'direct': float(np.median(single['direct'])) / 1e3,
                    'fft': float(np.median(single['fft'])) / 1e3,
                    'batch direct': float(np.median(batch['direct'])) / 1e3,
                    'batch fft': float(np.median(batch['fft'])) / 1e3})
        ctx.log(f"break-even {side}x{side}: direct {out[-1]['direct']:.1f} µs, "
                f"fft {out[-1]['fft']:.1f} µs")
    return out


def _crossing(rows, a, b):
    """First side from which ``b`` stays faster than ``a``; None if never."""
    for i, row in enumerate(rows):
        if all(r[b] < r[a] for r in rows[i:]):
            return row['side']
    return None


def truncation(ctx):
    """Decisions and cost of the FFT path with truncated kernel support, on benchmark beliefs."""
    out = []
    for model in ('human', 'exponential'):
        fpoc = make_fpoc(model)
        for side in ((128,) if ctx.quick else (128, 256)):
            grid = Grid(side, side)
            beliefs = []
            ControllerLoop(grid, fpoc, 'fft', seed=11).run(2 * EPISODE, keep=beliefs)
            beliefs = np.array(beliefs)
            kernel = dprime_table(grid, fpoc) ** 2
            exact = ConvPolicy(grid, kernel, method='fft', truncate=0.0)
            reference = [exact.decide(b) for b in beliefs]
            exact_scores = exact.scores(beliefs)
            for tol in TRUNCATIONS:
                policy = ConvPolicy(grid, kernel, method='fft', truncate=tol)
                t0 = time.thread_time_ns()
                decisions = [policy.decide(b) for b in beliefs]
                per_call = (time.thread_time_ns() - t0) / len(beliefs) / 1e3
                raw = policy.scores(beliefs)
                raw_decisions = argmax_ties_low(raw)
                peak = np.abs(exact_scores.max(axis=1))
                error = np.abs(raw - exact_scores).max(axis=1) / (TIE_RTOL * peak)
                out.append({'model': model, 'side': side, 'truncate': tol,
                            'shape': policy.fft_shape, 'beliefs': len(beliefs),
                            'same': int(np.sum(np.array(decisions) == reference)),
                            'raw same': int(np.sum(raw_decisions == reference)),
                            'error/tie': float(error.max()),
                            'rescored': policy.rescored, 'us': per_call})
            ctx.log(f'truncation {model} {side}x{side} done')
    return out


def greedy_cost(ctx):
    """Ideal searcher decision time at 7x7 and 11x11, when policies.greedy exists."""
    try:
        from ipomdp_gaze.policies.greedy import PercentCorrectGreedy
    except ImportError:
        return None
    fpoc, out = make_fpoc('human'), []
    for side in (7, 11):
        grid = Grid(side, side)
        beliefs = []
        ControllerLoop(grid, fpoc, 'direct', seed=3).run(EPISODE, keep=beliefs)
        greedy = PercentCorrectGreedy(grid, fpoc)
        elm = elm_policy(grid, fpoc)
        rng = np.random.default_rng(0)
        g_ns, e_ns = [], []
        for rep in range(2 if ctx.quick else 4):
            for t, b in enumerate(beliefs):
                t0 = time.perf_counter_ns()
                greedy.select(b[None, :], t, rng)
                t1 = time.perf_counter_ns()
                elm.decide(b)
                g_ns.append(t1 - t0)
                e_ns.append(time.perf_counter_ns() - t1)
        out.append((side, _median_p99(g_ns), _median_p99(e_ns)))
    return out


def plot(ctx, rows, scan):
    """Log-log latency and memory vs cells; the break-even scan."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, (ax, axm) = plt.subplots(1, 2, figsize=(12, 4.8))
    styles = {'direct': ('C0', 'o-'), 'fft': ('C1', 's-'),
              'exp + correlate2d': ('C3', 'v--'), 'exp + correlate (fft)': ('C4', '^--'),
              'allocating library path': ('C2', 'd--'), 'per-cell Python loop': ('C7', 'x--')}
    for key, (color, style) in styles.items():
        pts = [(r['n'], r[key]) for r in rows if r.get(key)]
        if not pts:
            continue
        n = np.array([p[0] for p in pts])
        med = np.array([p[1][0] for p in pts])
        p99 = np.array([p[1][1] for p in pts])
        label = key if key in ('direct', 'fft') else f'reference: {key}'
        ax.errorbar(n, med, yerr=[np.zeros_like(med), p99 - med], fmt=style, color=color,
                    capsize=3, label=label)
    auto = [(r['n'], r[r['auto'] + ' cpu'][0]) for r in rows]
    ax.plot([a[0] for a in auto], [a[1] for a in auto], 'k.:', label='ours (auto), CPU time')
    for side, target in TARGETS_US.items():
        ax.plot(side * side, target, marker='*', color='k', markersize=14, linestyle='none')
    ax.plot([], [], marker='*', color='k', linestyle='none', label='target (issue 5)')
    ax.set(xscale='log', yscale='log', xlabel='cells N',
           ylabel='µs per frame (wall median; bar: p99)',
           title='Belief update + decision (ELM kernel, human FPOC)')
    ax.grid(True, which='both', alpha=0.3)
    ax.legend(fontsize=8)
    for m, color in (('direct', 'C0'), ('fft', 'C1')):
        pts = [(r['n'], r[m + ' memory']) for r in rows if r.get(m + ' memory')]
        axm.plot([p[0] for p in pts], [p[1] / 2 ** 20 for p in pts], 'o-', color=color,
                 label=f'{m}: peak traced memory')
    n = np.array([r['n'] for r in rows], dtype=float)
    axm.plot(n, 8 * n * n / 2 ** 20, 'k:', label='one N x N float64 matrix')
    axm.set(xscale='log', yscale='log', xlabel='cells N', ylabel='MiB',
            title='Peak memory (tracemalloc: model, controller, policy, 3 calls)')
    axm.grid(True, which='both', alpha=0.3)
    axm.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(ctx.figure('bench_latency.png'), dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    n = [r['n'] for r in scan]
    ax.plot(n, [r['direct'] for r in scan], 'o-', label='direct, one belief')
    ax.plot(n, [r['fft'] for r in scan], 's-', label='FFT, one belief')
    ax.plot(n, [r['batch direct'] / 256 for r in scan], 'o--', label='direct, per belief of 256')
    ax.plot(n, [r['batch fft'] / 256 for r in scan], 's--', label='FFT, per belief of 256')
    ax.axvline(conv.DIRECT_MAX_CELLS, color='k', linestyle=':',
               label=f'DIRECT_MAX_CELLS = {conv.DIRECT_MAX_CELLS}')
    ax.axvline(conv.DIRECT_MAX_CELLS_BATCH, color='k', linestyle='--',
               label=f'DIRECT_MAX_CELLS_BATCH = {conv.DIRECT_MAX_CELLS_BATCH}')
    ax.set(xscale='log', yscale='log', xlabel='cells N', ylabel='µs CPU per decision (median)',
           title='Direct vs FFT scores + tie-rule argmax')
    ax.grid(True, which='both', alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(ctx.figure('bench_breakeven.png'), dpi=110)
    plt.close(fig)


def _targets_text(rows) -> str:
    """Each target with this run's wall median of the automatic method: met or missed."""
    parts = []
    for side, target_us in TARGETS_US.items():
        row = next((r for r in rows if r['side'] == side), None)
        if row is None:
            parts.append(f'{side}x{side} under {_fmt_us(target_us)} (not run)')
            continue
        got = row[row['auto']][0]
        verdict = 'met' if got < target_us else '**missed**'
        parts.append(f'{side}x{side} under {_fmt_us(target_us)} ({verdict}: '
                     f'{_fmt_us(got)})')
    return ', '.join(parts)


def report(rows, scan, trunc, greedy) -> str:
    """Markdown of the section."""
    text = [INTRO, '',
            '![latency and memory](figures/bench_latency.png)', '',
            '### Our path per frame: wall-clock median / p99 (CPU-time median)', '',
            '| grid | cells | auto picks | direct | FFT | FFT size | update / decide (auto, '
            'wall median) | same decisions | peak memory direct | peak memory FFT | '
            'allocated per frame (auto) |',
            '|---|---|---|---|---|---|---|---|---|---|---|']
    for r in rows:
        cell = {m: (f'{_fmt_us(r[m][0])} / {_fmt_us(r[m][1])} ({_fmt_us(r[m + " cpu"][0])})'
                    if m in r else
                    'refused (N x N matrix of ' + _fmt_bytes(8 * r['n'] ** 2) + ')')
                for m in ('direct', 'fft')}
        a = r['auto']
        cell[a] = f'**{cell[a]}**'
        same = {True: 'yes', False: '**no**'}.get(r.get('same decisions'), '-')
        shape = r.get('fft shape') or '-'
        text.append(f"| {r['side']}x{r['side']} | {r['n']} | {a} | {cell['direct']} | "
                    f"{cell['fft']} | {shape[0]}x{shape[1]} | {_fmt_us(r[a + ' update'][0])} / "
                    f"{_fmt_us(r[a + ' decide'][0])} | {same} | "
                    f"{_fmt_bytes(r.get('direct memory'))} | {_fmt_bytes(r['fft memory'])} | "
                    f"{_fmt_bytes(r[a + ' allocation'])} |")
    text += ['', f"Calls per size: {', '.join(str(r['calls']) for r in rows)} "
             f'(in {ROUNDS} interleaved rounds, after 5 warm-up calls); the belief is reset every '
             f'{EPISODE} frames. Targets (median): {_targets_text(rows)}. '
             'Wall-clock time includes waiting for a core on the shared machine; CPU time '
             '(`time.thread_time_ns`) is what the code itself costs. Peak memory: tracemalloc '
             'while building the observation model, controller and policy and handling 3 frames. '
             'Allocated per frame: tracemalloc peak over 20 frames of a built controller '
             '(`GazeController.offer`): the frame check, the log-likelihood ratio and the Bayes '
             'step allocate a few temporaries of N floats each; the direct decision writes to '
             'preallocated buffers, the FFT path allocates its transforms (`scipy.fft` has no '
             '`out=`). "update" is `offer` minus the policy\'s choice inside it.', '',
             '### References measured in the same run (CPU-time median per frame; ratio = '
             'reference / ours with the automatic method)', '',
             '| grid | ' + ' | '.join(REFERENCE_CALLS) + ' |',
             '|---|' + '---|' * len(REFERENCE_CALLS)]
    for r in rows:
        ours = r[r['auto'] + ' cpu'][0]
        cells = []
        for kind in REFERENCE_CALLS:
            v = r.get(kind + ' cpu')
            cells.append(f'{_fmt_us(v[0])} ({_fmt_ratio(v[0] / ours)})' if v else 'not run')
        text.append(f"| {r['side']}x{r['side']} | " + ' | '.join(cells) + ' |')
    text += ['', 'correlate2d is O(N^2) per frame (about 5 s at 256x256), so it is run up to '
             '128x128 only; the per-cell loop only at 7x7 and 11x11.', '',
             '### Break-even of direct and FFT scoring', '',
             '![break-even](figures/bench_breakeven.png)', '',
             'CPU-time medians per decision (scores + tie-rule argmax), random beliefs '
             '(Dirichlet 0.3), ELM kernel of the human FPOC.', '',
             '| grid | cells | FFT size | direct, one belief | FFT, one belief | '
             'direct, batch of 256 | FFT, batch of 256 |', '|---|---|---|---|---|---|---|']
    for r in scan:
        text.append(f"| {r['side']}x{r['side']} | {r['n']} | {r['fft shape'][0]}x"
                    f"{r['fft shape'][1]} | {_fmt_us(r['direct'])} | {_fmt_us(r['fft'])} | "
                    f"{_fmt_us(r['batch direct'])} | {_fmt_us(r['batch fft'])} |")
    single = _crossing(scan, 'direct', 'fft')
    batch = _crossing(scan, 'batch direct', 'batch fft')
    text += ['', f'Measured break-even in this run: FFT is faster from {single}x{single} on '
             f'for one belief and from {batch}x{batch} on for a batch of 256. The automatic '
             f'switch in `policies/conv.py`: direct up to `DIRECT_MAX_CELLS` = '
             f'{conv.DIRECT_MAX_CELLS} cells ({math.isqrt(conv.DIRECT_MAX_CELLS)}x'
             f'{math.isqrt(conv.DIRECT_MAX_CELLS)}) for one belief and `DIRECT_MAX_CELLS_BATCH` '
             f'= {conv.DIRECT_MAX_CELLS_BATCH} ({math.isqrt(conv.DIRECT_MAX_CELLS_BATCH)}x'
             f'{math.isqrt(conv.DIRECT_MAX_CELLS_BATCH)}) for a batch; near the break-even the '
             'two cost the same within the noise, and direct is preferred there (no '
             'transform buffers, no re-scoring).', '',
             "### Kernel truncation on the benchmark's belief maps", '',
             'Beliefs: every belief (after each update) of two 25-fixation searches of the FFT '
             'controller loop with that FPOC. '
             '`truncate` drops kernel entries below that fraction of the largest from the FFT '
             '(0: only exact zeros, lossless; the default is `DEFAULT_TRUNCATE` = '
             f'{conv.DEFAULT_TRUNCATE:g}, used in the tables above). "raw" = tie-rule argmax of '
             'the truncated FFT '
             'scores alone; "decisions" = the policy (near-maximal cells re-scored exactly). '
             'Score error in units of the tie tolerance `1e-9 |peak|`.', '',
             '| FPOC | grid | truncate | FFT size | raw same | decisions same | '
             'max score error / tie tol. | re-scored | CPU per decision |',
             '|---|---|---|---|---|---|---|---|---|']
    for r in trunc:
        text.append(f"| {r['model']} | {r['side']}x{r['side']} | {r['truncate']:g} | "
                    f"{r['shape'][0]}x{r['shape'][1]} | {r['raw same']}/{r['beliefs']} | "
                    f"{r['same']}/{r['beliefs']} | {r['error/tie']:.2g} | {r['rescored']} | "
                    f"{_fmt_us(r['us'])} |")
    if greedy:
        text += ['', '### Ideal searcher (percent-correct greedy) decision cost', '',
                 '| grid | greedy median / p99 | ELM median / p99 (reference) |',
                 '|---|---|---|']
        for side, g, e in greedy:
            text.append(f'| {side}x{side} | {_fmt_us(g[0])} / {_fmt_us(g[1])} | '
                        f'{_fmt_us(e[0])} / {_fmt_us(e[1])} |')
    else:
        text += ['', '*Ideal searcher: `policies.greedy` is not in this tree; not timed.*']
    return '\n'.join(text) + '\n'


def bench(ctx) -> str:
    """Run the section (see the module docstring)."""
    fpoc = make_fpoc('human')
    rows = latency(ctx, fpoc)
    scan = break_even(ctx, fpoc)
    trunc = truncation(ctx)
    greedy = greedy_cost(ctx)
    if ctx.figures is not None:
        plot(ctx, rows, scan)
    return report(rows, scan, trunc, greedy)


def main(argv=None) -> None:
    """Run alone: print the section; draw its figures only where ``--figures`` says."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--quick', action='store_true', help='few calls: a smoke run')
    parser.add_argument('--figures', type=Path, default=None, metavar='DIR',
                        help="write the section's figures into DIR (default: not drawn; "
                             'make bench writes those of docs/benchmarks.md)')
    args = parser.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from run import Context
    print(bench(Context(args.quick, args.figures)))


if __name__ == '__main__':
    main()
