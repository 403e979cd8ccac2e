# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Batched simulation of the visual-search task: thousands of episodes at once.

Any policy plugs in through one method, ``select(belief, t, rng) -> fixations``: ``belief`` is an
(episodes, N) array of probabilities, ``t`` the 0-based fixation number and ``rng`` a
``numpy.random.Generator`` for stochastic policies. Targets and observation noise come from their
own seeded streams, so every policy run with the same seed sees the same targets and the same
noise draws (common random numbers).

Beyond the paper (docs/design.md section 7): the target may move between fixations (the true
target follows a :class:`ipomdp_gaze.model.motion.Motion` and the belief is predicted with it, or
not,
``predict=False``), and scenes may be empty at a rate ``absent_rate`` that is set separately from
the model's ``absent_prior`` (the belief's absent hypothesis). Target paths and empty scenes have
their own streams, so they too are shared by every policy.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from ipomdp_gaze.model.belief import check_prior, draw_cells, map_cell
from ipomdp_gaze.model.checks import positive_int
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import check_probability, Motion
from ipomdp_gaze.model.observation import as_observation
from ipomdp_gaze.model.stopping import BatchBelief, check_absent_prior
import numpy as np

# Stream tags of the seed sequence: targets, noise per fixation, the policy's own draws, the
# target's steps between fixations, and which scenes are empty.
_TARGET, _NOISE, _POLICY, _MOTION, _ABSENT, _SCAN = 0, 1, 2, 3, 4, 5


class Policy(Protocol):
    """Anything that picks the next fixation for a batch of beliefs."""

    def select(self, belief: np.ndarray, t: int, rng: np.random.Generator) -> np.ndarray:
        """Return one fixation (cell index) per episode, shape (episodes,)."""


@dataclass
class SearchResult:
    """
    What a batch of simulated searches produced.

    ``correct[e, t-1]`` is whether episode e's most likely hypothesis after t observations is
    the truth (its target's cell then; "absent" for an empty scene, which only a belief with the
    absent hypothesis can guess); ``fixations[e, t-1]`` is the t-th fixation; ``map_prob[e, t-1]``
    the probability of the most likely cell then and ``guess[e, t-1]`` that cell;
    ``target_path[e, t-1]`` the target's cell at fixation t (-1 in an empty scene); ``present``
    whether each scene holds a target; ``absent_prob[e, t-1]`` is ``P(absent)`` (None without
    the absent hypothesis).
    """

    targets: np.ndarray
    fixations: np.ndarray
    correct: np.ndarray
    map_prob: np.ndarray
    infomax: np.ndarray
    guess: np.ndarray | None = None
    target_path: np.ndarray | None = None
    present: np.ndarray | None = None
    absent_prob: np.ndarray | None = None

    @property
    def percent_correct(self) -> np.ndarray:
        """Fraction correct after t = 1..horizon fixations."""
        return self.correct.mean(axis=0)


def draw_targets(n_cells: int, episodes: int, seed: int, prior=None) -> np.ndarray:
    """
    Random target cells from the seed's target stream: uniform, or drawn from ``prior``.

    ``prior`` (N,) sums to 1 (:func:`check_prior`); both draws are prefix-stable.
    """
    rng = np.random.default_rng([seed, _TARGET])
    return draw_cells(rng, n_cells, None if prior is None else check_prior(prior, n_cells),
                      episodes)


def draw_present(episodes: int, absent_rate: float, seed: int) -> np.ndarray:
    """
    Return which scenes hold a target: each is empty with probability ``absent_rate``.

    Drawn from the seed's own stream (``random(episodes) >= absent_rate``), so it is
    prefix-stable and shared by every policy; ``absent_rate = 0`` draws nothing.
    """
    rate = check_probability(absent_rate, 'absent_rate')
    if rate == 0:
        return np.ones(episodes, dtype=bool)
    return np.random.default_rng([seed, _ABSENT]).random(episodes) >= rate


def noise_stream(seed: int, t: int) -> np.random.Generator:
    """Return the generator of the observation noise for fixation ``t`` (0-based)."""
    return np.random.default_rng([seed, _NOISE, t])


def motion_stream(seed: int, t: int) -> np.random.Generator:
    """Return the generator of the target's step after fixation ``t`` (0-based)."""
    return np.random.default_rng([seed, _MOTION, t])


def policy_rng(seed: int) -> np.random.Generator:
    """Return the generator handed to the policy's ``select``."""
    return np.random.default_rng([seed, _POLICY])


class RowsOf:
    """
    The rows ``start:stop`` of every batch a generator would draw for a whole run.

    ``standard_normal(shape)`` and ``random(shape)`` with ``shape[0] == stop - start`` draw the
    whole run's ``(episodes,) + shape[1:]`` from the wrapped generator and return rows
    ``start:stop``, so a slice of episodes gets exactly the numbers it gets in the whole run.
    Any other shape is drawn directly. The cost is the whole run's draws, for every slice.
    """

    def __init__(self, rng: np.random.Generator, start: int, stop: int, episodes: int):
        self.rng, self.start, self.stop, self.episodes = rng, start, stop, episodes

    def _draw(self, method, size, **kwargs):
        shape = tuple(np.atleast_1d(size)) if size is not None else ()
        if not shape or shape[0] != self.stop - self.start:
            return method(size, **kwargs)
        return method((self.episodes,) + shape[1:], **kwargs)[self.start:self.stop]

    def standard_normal(self, size=None, **kwargs):
        """Rows ``start:stop`` of the whole run's standard normal draws."""
        return self._draw(self.rng.standard_normal, size, **kwargs)

    def random(self, size=None, **kwargs):
        """Rows ``start:stop`` of the whole run's uniform draws."""
        return self._draw(self.rng.random, size, **kwargs)


def check_rows(rows, episodes: int) -> tuple[int, int]:
    """Validate ``rows = (start, stop)`` within a run of ``episodes``; return it as ints."""
    try:
        start, stop = (int(v) for v in rows)
    except (TypeError, ValueError):
        raise ValueError(f'rows must be (start, stop), got {rows!r}') from None
    if not 0 <= start < stop <= episodes:
        raise ValueError(f'rows must satisfy 0 <= start < stop <= episodes ({episodes}), '
                         f'got ({start}, {stop})')
    return start, stop


def rollout(model, beliefs: BatchBelief, where: np.ndarray, present, horizon: int, choose,
            noise, record, motion: Motion | None = None, steps=None, predict: bool = True,
            move_after_last: bool = True) -> None:
    """
    Run the batched episode loop of :func:`simulate` and policy-gradient training.

    Each fixation ``t``: ``k = choose(t)``; a frame drawn at the targets ``where`` (``present``:
    which scenes hold one, None for all) with ``noise(t)``; the Bayes step on ``beliefs``
    (:class:`~ipomdp_gaze.model.stopping.BatchBelief`), whose information gain
    ``record(t, k, gain, where)`` gets with the belief after the update; then, with a
    ``motion``, the targets step (``steps(t)``) and the belief is predicted (``predict``). After
    the last fixation the targets step only with ``move_after_last`` (training's draw order).
    A Gaussian model whose drawn frames would overflow is refused first (ValueError): the
    frames are applied unchecked.
    """
    check = getattr(model, 'check_sampling', None)
    if check is not None:
        check()
    for t in range(horizon):
        k = choose(t)
        frames = model.sample(where, k, noise(t), present=present)
        gain = beliefs.update(model.log_likelihood_ratio(frames, k, validate=False))
        record(t, k, gain, where)
        if motion is not None and (move_after_last or t + 1 < horizon):
            where = motion.move(where, steps(t))
            if predict:
                beliefs.predict(motion)


def check_targets(targets, n_cells: int, episodes: int) -> np.ndarray:
    """
    Return given target cells as an int64 array of shape ``(episodes,)``.

    A ValueError names what is wrong: a cell outside ``0..N-1`` (a negative one would wrap
    round to the last cells when the frames are drawn, while the scoring compares the guess with
    the negative number, so the search could never be right), a fraction or a wrong length.
    """
    values = np.asarray(targets)
    if values.shape != (episodes,):
        raise ValueError(f'targets must hold one cell per episode, shape ({episodes},), got '
                         f'shape {values.shape}')
    if values.dtype.kind not in 'iu':
        if values.dtype.kind != 'f' or not np.all(np.isfinite(values)) or \
                np.any(values != np.round(values)):
            raise ValueError(f'targets must be whole cell indices, got dtype {values.dtype}')
    values = values.astype(np.int64)
    bad = (values < 0) | (values >= n_cells)
    if bad.any():
        raise ValueError(f'targets must be cells in 0..{n_cells - 1}, got {int(values[bad][0])} '
                         f'(episode {int(np.flatnonzero(bad)[0])})')
    return values


def check_fixations(fixations, n_cells: int, episodes: int, t: int, policy) -> np.ndarray:
    """
    Return a policy's choices for fixation ``t`` (0-based) as int64 ``(episodes,)``.

    One cell index per episode (one for all is broadcast). A ValueError names the policy, the
    fixation and the first episode whose choice is no cell of the grid: a negative index drew
    its frame at a cell counted from the end while -1 was recorded, and 2.7 fixated cell 2.
    """
    values = np.asarray(fixations)
    name = getattr(policy, 'name', type(policy).__name__)
    if values.shape not in ((episodes,), ()):
        raise ValueError(f'policy {name} must choose one cell per episode, shape ({episodes},), '
                         f'got shape {values.shape} at fixation {t + 1}')
    values = np.broadcast_to(values, (episodes,))
    if values.dtype.kind in 'iu':
        bad = (values < 0) | (values >= n_cells)
    elif values.dtype.kind == 'f':
        bad = ~((values >= 0) & (values < n_cells) & (values == np.floor(values)))
    else:
        raise ValueError(f'policy {name} must choose cell indices, got dtype {values.dtype} at '
                         f'fixation {t + 1}')
    if bad.any():
        e = int(np.flatnonzero(bad)[0])
        raise ValueError(f'policy {name} chose {values[e].item()!r} for episode {e} at fixation '
                         f'{t + 1}: a fixation is a cell index in 0..{n_cells - 1}')
    return values.astype(np.int64)


def check_present(present, episodes: int) -> np.ndarray:
    """Return ``present`` as a bool array of shape ``(episodes,)`` (ValueError otherwise)."""
    values = np.asarray(present)
    if values.shape != (episodes,):
        raise ValueError(f'present must hold one flag per episode, shape ({episodes},), got '
                         f'shape {values.shape}')
    if values.dtype.kind != 'b' and not np.all(np.isin(values, (0, 1))):
        raise ValueError('present must hold True/False (or 1/0) per episode')
    return values.astype(bool)


def simulate(grid: Grid, model, policy: Policy, episodes: int, horizon: int | None = None,
             seed: int = 0, targets: np.ndarray | None = None, progress=None,
             motion: Motion | None = None, predict: bool = True, absent_prior: float = 0.0,
             absent_rate: float = 0.0, present: np.ndarray | None = None,
             rows: tuple[int, int] | None = None, scan: bool = True,
             prior: np.ndarray | None = None) -> SearchResult:
    """
    Run ``episodes`` searches of ``horizon`` fixations (default N) from the prior.

    Each fixation t: the policy picks a cell from the belief, a frame is drawn with the target
    where it is now, the one Bayes step updates the belief; then the target takes a step of
    ``motion`` and the belief is predicted with it (docs/design.md section 7).

    Parameters
    ----------
    grid
        The visual array.
    model
        The observation model (:mod:`ipomdp_gaze.model.observation`), or an FPOC for the Gaussian
        one.
    policy
        Anything with ``select(belief, t, rng)``; ``belief`` holds the N cell probabilities
        (summing to ``1 - P(absent)`` with the absent hypothesis).
    episodes, horizon, seed
        Batch size, fixations per episode and the seed of all random streams.
    targets : array (episodes,), optional
        Target cells at the first fixation; drawn from the seed's target stream when omitted.
        With a ``prior``, none may be in a cell it rules out (probability 0).
    progress : callable, optional
        Called with the fixation number after each step.
    motion : Motion, optional
        How the true target moves between fixations (default: it stays put).
    predict : bool
        Whether the belief is predicted with ``motion`` (False: the searcher assumes a still
        target, to measure what prediction is worth).
    absent_prior : float
        The belief's prior of "no target in the grid" (0: no such hypothesis, N entries).
    absent_rate : float
        Fraction of simulated scenes that are empty (their own stream, :func:`draw_present`).
    present : bool array (episodes,), optional
        Which scenes hold a target, instead of drawing them (a prefix of a larger run).
    rows : (start, stop), optional
        Simulate only episodes ``start:stop`` of this run of ``episodes``: targets, empty scenes,
        noise and target steps are drawn for the whole run and sliced (:class:`RowsOf`), so the
        rows are exactly those of the whole run for any policy that draws nothing itself (every
        deterministic one); ``targets`` and ``present`` are then the whole run's. A stochastic
        policy's own draws come from ``[seed, 2, start]`` instead. This is how the work of one
        run is split over processes (``ipomdp-gaze reproduce``).
    scan : bool
        With a count model that has scan tables, first apply the one-time scan (drawn from the
        scan tables, its own stream ``[seed, 5]``), as ``find`` and the fovea do; the first
        fixation is then the policy's choice on the scanned belief.
    prior : array (N,) or (rows, cols), optional
        Where the target is a priori (default uniform): every belief starts at it (times
        ``1 - absent_prior``) and, unless ``targets`` is given, the targets are drawn from it
        on the seed's target stream (:func:`check_prior`: one value per cell, >= 0, summing to 1).

    """
    n = grid.n_cells
    # Whole numbers, named: a horizon of 2.5 ran 2 fixations, '3' ran 3, episodes=2.5 and
    # seed=None were numpy's TypeErrors
    episodes = positive_int('episodes', episodes)
    horizon = n if horizon is None else positive_int('horizon', horizon)
    seed = positive_int('seed', seed, allow_zero=True)
    model = as_observation(grid, model)
    if prior is not None:
        prior = check_prior(prior, n, grid.shape)
    if targets is not None:
        targets = check_targets(targets, n, episodes)
        if prior is not None and np.any(prior[targets] == 0):
            e = int(np.flatnonzero(prior[targets] == 0)[0])
            raise ValueError(f'targets must be cells the prior allows: episode {e} has its '
                             f'target in cell {int(targets[e])}, which the prior rules out '
                             '(probability 0: every search starts sure it is not there)')
    else:
        targets = draw_targets(n, episodes, seed, prior)
    absent_prior = check_absent_prior(absent_prior)
    if present is None:
        present = draw_present(episodes, absent_rate, seed)
    present = check_present(present, episodes)
    total = episodes
    if rows is not None:
        start, stop = check_rows(rows, episodes)
        targets, present, episodes = targets[start:stop], present[start:stop], stop - start

        def noise(t):
            return RowsOf(noise_stream(seed, t), start, stop, total)

        def steps(t):
            return RowsOf(motion_stream(seed, t), start, stop, total)
        scan_rng = RowsOf(np.random.default_rng([seed, _SCAN]), start, stop, total)
        rng = np.random.default_rng([seed, _POLICY, start])
    else:
        def noise(t):
            return noise_stream(seed, t)

        def steps(t):
            return motion_stream(seed, t)
        scan_rng = np.random.default_rng([seed, _SCAN])
        rng = policy_rng(seed)
    all_present = bool(present.all())
    moving = motion is not None and motion.active
    index = np.arange(episodes)
    beliefs = BatchBelief(n, absent_prior, episodes, moving, prior)
    with_absent, belief = beliefs.has_absent, beliefs.belief
    fixations = np.empty((episodes, horizon), dtype=np.int64)
    correct = np.empty((episodes, horizon), dtype=bool)
    map_prob = np.empty((episodes, horizon))
    infomax = np.empty((episodes, horizon))
    guesses = np.empty((episodes, horizon), dtype=np.int64)
    path = np.empty((episodes, horizon), dtype=np.int64)
    absent_prob = np.empty((episodes, horizon)) if with_absent else None
    where = targets.copy() if moving else targets
    if scan and getattr(model, 'has_scan', False):
        frames = model.sample_scan(where, scan_rng, present=None if all_present else present)
        beliefs.update(model.scan_log_likelihood_ratio(frames, validate=False))

    def choose(t):
        return check_fixations(policy.select(belief, t, rng), n, episodes, t, policy)

    def record(t, k, gain, where):
        fixations[:, t] = k
        infomax[:, t] = gain
        truth = where if all_present else np.where(present, where, -1)
        path[:, t] = truth
        if with_absent:
            absent_prob[:, t] = beliefs.absent_probability
        guess = map_cell(belief)
        guesses[:, t] = guess
        map_prob[:, t] = belief[index, guess]
        if with_absent:
            says_absent = absent_prob[:, t] > map_prob[:, t]
            correct[:, t] = np.where(present, ~says_absent & (guess == where), says_absent)
        else:
            correct[:, t] = guess == truth
        if progress is not None:
            progress(t + 1)

    rollout(model, beliefs, where, None if all_present else present, horizon, choose, noise,
            record, motion=motion if moving else None, steps=steps, predict=predict,
            move_after_last=False)
    return SearchResult(targets, fixations, correct, map_prob, infomax, guesses, path, present,
                        absent_prob)
