# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Seeded pieces of simulation work, their cache on disk, and the runner that spreads them.

A run of ``episodes`` searches is split into pieces of rows ``start:stop``
(:func:`ipomdp_gaze.simulation.simulate.simulate` with ``rows``); each piece is sent to an executor
(:mod:`ipomdp_gaze.simulation.executor`: this process, a local pool or a Dask cluster) and its
result
depends only on its arguments, so the assembled matrices are the same wherever the pieces ran.
:class:`PieceCache` keeps every finished piece on disk (written here, in the client, as each
piece finishes, so an interrupted run keeps what it finished), and :class:`Runner` assembles
runs of many policies on shared targets and noise (``reproduce``, the benches).
:func:`simulate_pieces` and :func:`concat_results` do the same for one run with every option
of :func:`simulate` (``evaluate``).
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
from pathlib import Path
import time

from ipomdp_gaze.model.fpoc import dprime_matrix
from ipomdp_gaze.model.observation import GaussianObservation
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.policies.greedy import expected_percent_correct_at
from ipomdp_gaze.simulation.evaluation import (bootstrap_counts, fixations_to_90_ci,
                                               paired_difference_ci)
from ipomdp_gaze.simulation.executor import InlineExecutor, source_digest
from ipomdp_gaze.simulation.simulate import draw_targets, SearchResult, simulate
import numpy as np

# The slow searchers (policies whose class sets ``costly = True``) are split into pieces of this
# many episodes, the planner into PLANNER_CHUNK (fixed, so the planner's own draws, one stream
# per piece, do not depend on the number of workers).
COSTLY_CHUNK, PLANNER_CHUNK = 250, 500
# A run must be REACHED correct at its last fixation (checked by Runner.summary).
REACHED = 0.95


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

    Every run is submitted to ``executor`` (:mod:`ipomdp_gaze.simulation.executor`; None runs each
    piece
    here) in pieces of ``chunk`` episodes: each piece is the rows ``start:stop`` of the whole run
    (:func:`ipomdp_gaze.simulation.simulate.simulate` with ``rows``), so a deterministic policy's
    matrix is
    the one a single serial run gives, wherever and on however many workers the pieces ran. A
    stochastic policy's own draws come from one stream per piece (fixed ``chunk``, so still
    deterministic). :meth:`collect` waits for every submitted run and keeps, per name,
    ``correct`` (MAP guess right), ``map_prob`` (``max_i B_i``), CPU ``seconds`` and
    ``decisions``. Pieces found in ``cache`` (a :class:`PieceCache`) are not run again; each new
    one is stored there by this process as soon as it finishes (so Ctrl-C keeps the finished
    ones). ``progress`` (``add(n)`` / ``update(n)``,
    :class:`ipomdp_gaze.simulation.progress.Progress`)
    counts episodes as their pieces finish. Used by ``reproduce`` and
    ``bench/simulation/planner_vs_greedy.py``. With ``rao_blackwell`` (Gaussian FPOC model),
    ``map_prob``
    holds ``E[max_i B'_i]`` given the belief and fixation before each observation
    (:class:`_RaoBlackwell`): the same curve, less variance.
    """

    def __init__(self, grid, fpoc, episodes, seed, bootstrap, executor=None, cache=None,
                 rao_blackwell=False, progress=None):
        self.rao_blackwell = bool(rao_blackwell)
        self.grid, self.fpoc, self.seed = grid, fpoc, seed
        self.episodes, self.bootstrap = episodes, bootstrap
        self.executor = InlineExecutor() if executor is None else executor
        self.cache = PieceCache(None) if cache is None else cache
        self.progress = progress
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
        starts = range(0, n, chunk)
        if self.progress is not None:
            self.progress.add(n)
        jobs = []
        for start in starts:
            size = min(start + chunk, n) - start
            args = (self.grid, self.model, policy, self.targets[:n], horizon, self.seed,
                    (start, start + size), self.rao_blackwell)
            key = self.cache.key(recipe if not self.rao_blackwell or recipe is None
                                 else (recipe, 'rao-blackwell'),
                                 self.grid, self.fpoc, *args[3:7])
            found = self.cache.load(key)
            if found is not None:
                jobs.append(found)
                if self.progress is not None:
                    self.progress.update(size)
                continue
            future = self.executor.submit(_simulate_rows, *args)
            future.add_done_callback(functools.partial(self._finished, key, size))
            jobs.append(future)
        self._pending[name] = jobs
        return len(jobs)

    def _finished(self, key, episodes, future):
        """Store a piece the moment it is done (in this process), and count its episodes."""
        if future.cancelled() or future.exception() is not None:
            return
        self.cache.store(key, future.result())
        if self.progress is not None:
            self.progress.update(episodes)

    def pending(self, name) -> list:
        """Return the pieces of a run not yet collected: futures, or results from the cache."""
        return list(self._pending.get(name, []))

    def collect(self):
        """Wait for every queued run; keep its matrices, summed CPU seconds and decisions."""
        for name, jobs in self._pending.items():
            parts = [job.result() if hasattr(job, 'result') else job for job in jobs]
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

    ``reproduce``'s runs stop at ``HORIZON_7X7`` / ``HORIZON_11X11`` fixations, not N
    (fixations to 90% only needs the curve up to its first crossing, and fixation t's numbers
    do not depend on later ones). Requiring 95% correct at the last fixation leaves no resample
    short of 90%.
    """
    final = float(correct[:, -1].mean())
    if final < REACHED:
        raise RuntimeError(f'{name}: only {final:.1%} correct after '
                           f'{counted(correct.shape[1], "fixation")}; raise the horizon of this '
                           'run')


def _simulate_piece(grid, model, policy, episodes, horizon, seed, rows, options):
    """Run one piece of :func:`simulate_pieces` in a worker."""
    return simulate(grid, model, policy, episodes, horizon, seed, rows=rows, **options)


def simulate_pieces(executor, grid, model, policy, episodes: int, horizon, seed: int,
                    chunk: int | None = None, progress=None, **options) -> list:
    """
    Submit ``simulate(grid, model, policy, episodes, horizon, seed, **options)`` in pieces.

    Returns the futures of the pieces, in row order; :func:`concat_results` of their results is
    the whole run. ``chunk`` None (or at least ``episodes``) is one piece, the plain run
    without ``rows`` (so a stochastic policy keeps the unsplit run's own stream); otherwise
    pieces of ``chunk`` rows (:func:`ipomdp_gaze.simulation.simulate.simulate` with ``rows``):
    exactly
    the unsplit rows for a deterministic policy, and for a stochastic one a result that depends
    on ``chunk`` but not on the executor. ``options`` are passed on (``targets``, ``present``,
    ``motion`` ...); ``progress`` (``add`` / ``update``) counts episodes as pieces finish.
    """
    if chunk is None or chunk >= episodes:
        rows = [None]
    else:
        rows = [(start, min(start + chunk, episodes)) for start in range(0, episodes, chunk)]
    if progress is not None:
        progress.add(episodes)
    futures = []
    for piece in rows:
        future = executor.submit(_simulate_piece, grid, model, policy, episodes, horizon, seed,
                                 piece, options)
        if progress is not None:
            size = episodes if piece is None else piece[1] - piece[0]
            future.add_done_callback(
                lambda f, n=size: f.cancelled() or f.exception() is not None or progress.update(n))
        futures.append(future)
    return futures


def concat_results(parts) -> SearchResult:
    """Join the :class:`SearchResult` of consecutive row pieces into the whole run's."""
    parts = list(parts)
    if len(parts) == 1:
        return parts[0]
    fields = {}
    for name in SearchResult.__dataclass_fields__:
        values = [getattr(p, name) for p in parts]
        fields[name] = None if values[0] is None else np.concatenate(values)
    return SearchResult(**fields)


def train_piece(grid, model, config, params, init: str, epochs: int, final_episodes: int,
                final_seed: int):
    """
    Train one policy of a sweep in a worker; return ``(spec, curve rows, evaluation)``.

    ``config`` is a :class:`ipomdp_gaze.policies.training.TrainConfig` (its seed decides every
    epoch's draws), ``params`` the starting parameters (None: zeros). The closing evaluation on
    ``final_episodes`` episodes (0: none) is :func:`evaluation_block`'s, as ``train`` writes.
    """
    from ipomdp_gaze.policies.training import evaluation_block, Trainer
    trainer = Trainer(grid, model, config, params=params, init=init)
    rows = trainer.run(epochs)
    evaluation = {}
    if final_episodes:
        evaluation = evaluation_block(grid, model, trainer.family.policy(trainer.params),
                                      final_episodes, final_seed, trainer.horizon,
                                      scene=config.scene())
    return trainer.spec(evaluation=evaluation), rows, evaluation
