# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Honest evaluation: percent correct vs fixations, fixations to 90% correct, bootstrap intervals.

Fixations to 90% correct is the first t where percent correct reaches 0.90, interpolated linearly
between t-1 and t (percent correct at t = 0 is the uniform guess, 1/N, or with a prior over the
cells its largest probability, ``chance``); ``None`` if never reached.
Intervals are percentile bootstraps over episodes.

For moving and absent targets and the stopping rules (docs/design.md section 7.4): the rates of
right, wrong ``found``, wrong ``absent`` and ``gave_up`` decisions with Wilson intervals
(:func:`decision_summary`), and the first lock and tracking accuracy of a moving target with
bootstrap intervals, alone or paired (:func:`tracking_summary`,
:func:`paired_tracking_difference`).
"""
from __future__ import annotations

import numpy as np

LEVEL = 0.90


def prior_chance(prior) -> float | None:
    """Percent correct at t = 0 under ``prior`` (N,): its MAP cell's, ``max P`` (None: 1/N)."""
    return None if prior is None else float(np.max(prior))


def fixations_to_level(percent_correct: np.ndarray, n_cells: int, level: float = LEVEL,
                       chance: float | None = None):
    """
    First t (interpolated) at which ``percent_correct[t-1] >= level``; ``None`` if never.

    Works on a curve (T,) or a stack of curves (B, T), returning a float array with NaN for never.
    ``chance`` is percent correct at t = 0, before any fixation (default ``1/n_cells``; with a
    prior P over the cells, ``max P``: the MAP guess of the prior, 0 fixations when it reaches
    ``level``).
    """
    pc = np.atleast_2d(np.asarray(percent_correct, dtype=float))
    start = 1.0 / n_cells if chance is None else float(chance)
    curve = np.concatenate([np.full((pc.shape[0], 1), start), pc], axis=1)
    reached = curve >= level
    hit = reached.any(axis=1)
    t = np.argmax(reached, axis=1)                    # first index in curve (0 = prior)
    prev = curve[np.arange(len(t)), np.maximum(t - 1, 0)]
    cur = curve[np.arange(len(t)), t]
    with np.errstate(divide='ignore', invalid='ignore'):
        frac = np.where(cur > prev, (level - prev) / (cur - prev), 1.0)
    value = np.where(t == 0, 0.0, t - 1 + frac)
    value = np.where(hit, value, np.nan)
    if np.ndim(percent_correct) == 1:
        return None if np.isnan(value[0]) else float(value[0])
    return value


def bootstrap_counts(episodes: int, resamples: int, rng: np.random.Generator) -> np.ndarray:
    """Multinomial resampling weights (resamples, episodes) of a bootstrap over episodes."""
    return rng.multinomial(episodes, np.full(episodes, 1.0 / episodes), size=resamples)


def fixations_to_90_ci(correct: np.ndarray, n_cells: int, rng: np.random.Generator,
                       resamples: int = 1000, counts: np.ndarray | None = None,
                       chance: float | None = None):
    """
    Point estimate and 95% percentile-bootstrap interval of fixations to 90% correct.

    Parameters
    ----------
    correct : bool array (episodes, T)
        Whether each episode's MAP guess is right after t = 1..T fixations.
    n_cells : int
        N, for the chance level 1/N at t = 0.
    rng : numpy.random.Generator
        Source of the bootstrap resampling.
    resamples : int
        Number of bootstrap resamples.
    counts : array (resamples, episodes), optional
        Shared resampling weights, so paired comparisons resample the same episodes.
    chance : float, optional
        Percent correct at t = 0 in place of 1/N (a prior's largest probability).

    Returns
    -------
    (estimate, (low, high)) with ``None`` where 90% is not reached, and no interval (None) from
    fewer than :data:`MIN_EPISODES` episodes.

    """
    episodes = correct.shape[0]
    point = fixations_to_level(correct.mean(axis=0), n_cells, chance=chance)
    if point is None:
        return None, None
    if episodes < MIN_EPISODES:
        return point, None
    if counts is None:
        counts = bootstrap_counts(episodes, resamples, rng)
    # Whole counts, exact in float32 (below 2^24); divided in float64 as the point estimate's
    # mean is, so a resample at exactly 90% reaches it as the sample does (not 0.89999998).
    curves = (counts.astype(np.float32) @ correct.astype(np.float32)).astype(np.float64) \
        / episodes
    values = fixations_to_level(curves, n_cells, chance=chance)
    beyond = np.where(np.isnan(values), np.inf, values)     # not reached within the horizon
    return point, _interval(beyond, beyond)


# Stands for "beyond the horizon" in a bootstrap interval (_interval): finite, so interpolating
# towards it stays a number, and far above any number of fixations.
BEYOND = 1e300
# Every resample of one episode is that episode: its bootstrap "interval" has no width, which is
# no 95% interval. Fewer episodes (searches) than this give none (None), as mean_ci does.
MIN_EPISODES = 2


def format_interval(ci, spec: str = '.3f', episodes: int | None = None) -> str:
    """
    Format a 95% interval as ``[low, high]`` (each with ``spec``), or ``-`` when there is none.

    A bootstrap interval is None from fewer than :data:`MIN_EPISODES` searches; given
    ``episodes`` (the searches it was drawn from), a missing interval of more says its other
    reason, a bound beyond the horizon (:func:`_interval`).
    """
    if ci is not None:
        return f'[{ci[0]:{spec}}, {ci[1]:{spec}}]'
    if episodes is not None and episodes >= MIN_EPISODES:
        return '[beyond the horizon]'
    return '-'


def _interval(low_values: np.ndarray, high_values: np.ndarray):
    """
    Return the 95% percentile interval, or None when a bound lies beyond the horizon.

    A resample that never reaches 90% within the horizon is "more than T" (+inf), not dropped:
    dropping it would narrow the interval exactly where the horizon cuts it. Infinities become
    +/-:data:`BEYOND` for the interpolation (``inf * 0`` would be NaN where a percentile falls
    on a finite resample), and a bound that lands beyond the horizon is no bound.
    """
    low_values = np.clip(np.asarray(low_values, dtype=float), -BEYOND, BEYOND)
    high_values = np.clip(np.asarray(high_values, dtype=float), -BEYOND, BEYOND)
    low = float(np.percentile(low_values, 2.5))
    high = float(np.percentile(high_values, 97.5))
    # a bound interpolated part of the way towards BEYOND is beyond the finite resamples too
    finite = np.concatenate([low_values, high_values])
    finite = finite[np.abs(finite) < BEYOND]
    if not finite.size or not finite.min() <= low <= high <= finite.max():
        return None
    return low, high


def paired_difference_ci(correct_a: np.ndarray, correct_b: np.ndarray, n_cells: int,
                         rng: np.random.Generator, resamples: int = 1000,
                         counts: np.ndarray | None = None, chance: float | None = None):
    """
    Difference ``a - b`` of fixations to 90% on the same episodes, with a paired 95% CI.

    Both are measured on the first ``n = min`` episodes; each bootstrap resample weights the same
    episodes of a and b (``counts``, shape (resamples, n), drawn from ``rng`` when omitted).
    ``chance``: percent correct at t = 0 (:func:`fixations_to_level`). No interval (None) from
    fewer than :data:`MIN_EPISODES` episodes.
    """
    n = min(correct_a.shape[0], correct_b.shape[0])
    a, b = correct_a[:n], correct_b[:n]
    pa = fixations_to_level(a.mean(axis=0), n_cells, chance=chance)
    pb = fixations_to_level(b.mean(axis=0), n_cells, chance=chance)
    if pa is None or pb is None:
        return None, None
    if n < MIN_EPISODES:
        return pa - pb, None
    if counts is None:
        counts = bootstrap_counts(n, resamples, rng)
    counts = counts.astype(np.float32)
    va = fixations_to_level((counts @ a.astype(np.float32)).astype(np.float64) / n, n_cells,
                            chance=chance)
    vb = fixations_to_level((counts @ b.astype(np.float32)).astype(np.float64) / n, n_cells,
                            chance=chance)
    # beyond the horizon: +inf on that side; both beyond, the difference could be anything
    with np.errstate(invalid='ignore'):
        diff = np.where(np.isnan(va), np.inf, va) - np.where(np.isnan(vb), np.inf, vb)
    unknown = np.isnan(diff)
    return pa - pb, _interval(np.where(unknown, -np.inf, diff),
                              np.where(unknown, np.inf, diff))


# -- moving and absent targets, stopping (docs/design.md section 7) -----------------------------
Z95 = 1.959963984540054
OUTCOMES = ('right', 'wrong_found', 'wrong_absent', 'gave_up')
# An answer within this many cells (Chebyshev) of the target's cell is right on pixels: a face
# straddles cells and splits its evidence (docs/design.md section 10.4).
RIGHT_RADIUS_CELLS = 1


def cells_apart(a, b) -> int:
    """Return the Chebyshev distance in cells between two ``(row, col)`` cells."""
    return int(max(abs(int(a[0]) - int(b[0])), abs(int(a[1]) - int(b[1]))))


def answer_is_right(cell, truth, decision: str = 'found',
                    radius: int = RIGHT_RADIUS_CELLS) -> bool:
    """
    Return whether a search's answer is right: the one rule of every image evaluation.

    ``truth`` is the target's ``(row, col)`` or None (nobody there): then only ``absent`` is
    right. With a target, any answer but ``absent`` (``found``, or a budget's forced answer) is
    right when ``cell`` is within ``radius`` cells (Chebyshev) of it.
    """
    if truth is None:
        return decision == 'absent'
    return decision != 'absent' and cell is not None and cells_apart(cell, truth) <= radius


def match_faces(answers, truths, radius: int = RIGHT_RADIUS_CELLS) -> int:
    """
    Return how many true faces a room's answers found: the most pairs matched at once.

    ``answers`` and ``truths`` are ``(row, col)`` cells. An answer finds a true face when it is
    within ``radius`` cells (Chebyshev) of it; each true face and each answer is matched at most
    once, and the count is the largest such matching (``scipy.optimize.linear_sum_assignment``
    on the ``(A, T)`` table of pairs within reach). The room's false faces are
    ``len(answers) - match_faces(...)``, its recall ``match_faces(...) / len(truths)``.
    """
    answers = [tuple(int(v) for v in a) for a in answers]
    truths = [tuple(int(v) for v in t) for t in truths]
    if not answers or not truths:
        return 0
    near = np.array([[cells_apart(a, t) <= radius for t in truths] for a in answers])
    # scipy.optimize takes ~0.17 s to import; every command imports this module, few match rooms.
    from scipy.optimize import linear_sum_assignment
    rows, cols = linear_sum_assignment(near.astype(float), maximize=True)
    return int(near[rows, cols].sum())


CHUNK = 100


def wilson_interval(successes: int, trials: int, z: float = Z95):
    """
    Return the Wilson score interval ``(low, high)`` of a proportion; None for 0 trials.

    ``centre = (k + z^2/2) / (n + z^2)``, ``half = z sqrt(k (n - k) / n + z^2 / 4) / (n + z^2)``.
    """
    k, n = float(successes), float(trials)
    if n <= 0:
        return None
    centre = (k + z * z / 2) / (n + z * z)
    half = z * np.sqrt(k * (n - k) / n + z * z / 4) / (n + z * z)
    return float(max(0.0, centre - half)), float(min(1.0, centre + half))


def rate(mask: np.ndarray) -> dict:
    """Return ``{count, rate, ci95}`` of a boolean array (Wilson 95% interval)."""
    mask = np.asarray(mask, dtype=bool)
    k, n = int(mask.sum()), int(mask.size)
    ci = wilson_interval(k, n)
    return {'count': k, 'rate': k / n if n else None, 'ci95': list(ci) if ci else None}


def mean_ci(values: np.ndarray) -> dict:
    """Return ``{mean, ci95}``: the mean and its normal 95% interval (None when empty)."""
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return {'mean': None, 'ci95': None}
    mean = float(v.mean())
    if v.size < 2:
        return {'mean': mean, 'ci95': None}
    half = Z95 * float(v.std(ddof=1)) / np.sqrt(v.size)
    return {'mean': mean, 'ci95': [mean - half, mean + half]}


def search_outcomes(result, confidence: float, max_fixations: int | None = None):
    """
    Classify every search by its first decision (:func:`ipomdp_gaze.model.stopping`).

    Returns ``(outcome, fixations)``: ``outcome[e]`` indexes :data:`OUTCOMES`: ``right`` (found
    at the target's cell at that moment, or absent in an empty scene), ``wrong_found`` (found
    anywhere else, or in an empty scene), ``wrong_absent`` (absent while the target is there) or
    ``gave_up``; ``fixations[e]`` up to the decision (the budget when it gave up).
    """
    from ipomdp_gaze.model.stopping import ABSENT, first_decisions, FOUND
    kind, fixations = first_decisions(result.map_prob, result.absent_prob, confidence,
                                      max_fixations)
    rows = np.arange(kind.size)
    step = fixations - 1
    present = np.ones(kind.size, bool) if result.present is None else result.present
    target = result.target_path[rows, step]
    cell = result.guess[rows, step]
    outcome = np.full(kind.size, OUTCOMES.index('gave_up'))
    right = ((kind == FOUND) & present & (cell == target)) | ((kind == ABSENT) & ~present)
    outcome[kind == FOUND] = OUTCOMES.index('wrong_found')
    outcome[kind == ABSENT] = OUTCOMES.index('wrong_absent')
    outcome[right] = OUTCOMES.index('right')
    return outcome, fixations


def decision_summary(result, confidence: float, max_fixations: int | None = None) -> dict:
    """
    Rates of right, wrong ``found``, wrong ``absent`` and ``gave_up`` with Wilson intervals.

    Over all searches, over the decided ones (plus ``wrong``, both wrong kinds together: Bayes'
    guarantee bounds it by ``1 - confidence`` when the model is right), and over the searches
    with and without a target; with the fixations to a decision (mean, normal 95% interval) of
    the decided searches in each group.
    """
    outcome, fixations = search_outcomes(result, confidence, max_fixations)
    present = np.ones(outcome.size, bool) if result.present is None else result.present
    gave_up = outcome == OUTCOMES.index('gave_up')

    def group(mask):
        o = outcome[mask]
        out = {'searches': int(mask.sum())}
        out.update({name: rate(o == i) for i, name in enumerate(OUTCOMES)})
        out['fixations_to_decision'] = mean_ci(fixations[mask & ~gave_up])
        return out

    decided = {'searches': int((~gave_up).sum())}
    o = outcome[~gave_up]
    decided.update({name: rate(o == i) for i, name in enumerate(OUTCOMES[:3])})
    decided['wrong'] = rate((o == 1) | (o == 2))
    everyone = np.ones(outcome.size, bool)
    return {'confidence': float(confidence), 'max_fixations': int(
        result.map_prob.shape[1] if max_fixations is None else max_fixations),
        'all': group(everyone), 'decided': decided, 'present': group(present),
        'absent': group(~present)}


def _near(guess: np.ndarray, path: np.ndarray, cols: int) -> np.ndarray:
    gr, gc = np.divmod(guess, cols)
    pr, pc = np.divmod(path, cols)
    return (np.abs(gr - pr) <= 1) & (np.abs(gc - pc) <= 1)


def tracking_arrays(result, cols: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Per search: the first lock and the tracking tallies after it.

    Returns ``(first_lock, hits, after)``: ``first_lock[e]`` is the first fixation t (1-based)
    whose most likely cell is the target's cell at that moment (0: never, or an empty scene);
    ``after[e]`` counts the fixations after it and ``hits[e]`` those whose most likely cell is
    within one cell (``max(|dr|, |dc|) <= 1``) of the target's cell then. ``cols`` is the grid's.
    """
    path, guess = result.target_path, result.guess
    present = np.ones(path.shape[0], bool) if result.present is None else result.present
    lock = (guess == path) & present[:, None]
    locked = lock.any(axis=1)
    first = np.argmax(lock, axis=1)
    t = np.arange(path.shape[1])
    after = (t[None, :] > first[:, None]) & locked[:, None]
    hits = np.sum(after & _near(guess, path, cols), axis=1)
    return np.where(locked, first + 1, 0), hits, after.sum(axis=1)


def _ratio_bootstrap(numerators, denominators, rng: np.random.Generator, resamples: int):
    """
    Percentile bootstrap over searches of ``sum(num_i) / sum(den_i)`` for each pair given.

    A resample whose denominator is 0 (no search in it has any fixation to count) has no ratio:
    NaN, which the callers leave out of their percentiles, rather than a ratio of 0.
    """
    e = numerators[0].size
    values = []
    for start in range(0, resamples, CHUNK):
        counts = bootstrap_counts(e, min(CHUNK, resamples - start), rng).astype(float)
        ratios = []
        for num, den in zip(numerators, denominators):
            top, bottom = counts @ num, counts @ den
            ratios.append(np.divide(top, bottom, out=np.full(top.shape, np.nan),
                                    where=bottom > 0))
        values.append(np.stack(ratios))
    return np.concatenate(values, axis=1)


def tracking_summary(result, cols: int, rng: np.random.Generator, resamples: int = 1000) -> dict:
    """
    First lock and tracking accuracy of moving-target searches, with 95% intervals.

    ``locked``: the fraction of searches with a target that ever lock on (Wilson interval);
    ``first_lock``: the mean fixation of the first lock of those that do (normal interval);
    ``tracking_accuracy``: over all fixations after a first lock, the fraction whose most likely
    cell is within one cell of the target (pooled over searches; percentile bootstrap over
    searches).
    """
    first, hits, after = tracking_arrays(result, cols)
    present = np.ones(first.size, bool) if result.present is None else result.present
    total = int(after.sum())
    accuracy = float(hits.sum() / total) if total else None
    ci = None
    if total and first.size >= MIN_EPISODES:
        boot = _ratio_bootstrap([hits.astype(float)], [after.astype(float)], rng, resamples)[0]
        ci = [float(x) for x in np.nanpercentile(boot, [2.5, 97.5])]
    return {'locked': rate(first[present] > 0), 'first_lock': mean_ci(first[first > 0]),
            'tracking_accuracy': {'value': accuracy, 'ci95': ci,
                                  'fixations_after_lock': total}}


def paired_tracking_difference(result_a, result_b, cols: int, rng: np.random.Generator,
                               resamples: int = 1000) -> dict:
    """
    Tracking accuracy of ``a`` minus that of ``b`` on the same searches, paired 95% interval.

    Both are pooled ratios (:func:`tracking_summary`); the bootstrap resamples the same searches
    for both, so the interval is of the difference itself.
    """
    _, hits_a, after_a = tracking_arrays(result_a, cols)
    _, hits_b, after_b = tracking_arrays(result_b, cols)
    n = min(hits_a.size, hits_b.size)
    hits_a, after_a, hits_b, after_b = hits_a[:n], after_a[:n], hits_b[:n], after_b[:n]
    if not after_a.sum() or not after_b.sum():
        return {'difference': None, 'ci95': None}
    point = hits_a.sum() / after_a.sum() - hits_b.sum() / after_b.sum()
    if n < MIN_EPISODES:
        return {'difference': float(point), 'ci95': None}
    boot = _ratio_bootstrap([hits_a.astype(float), hits_b.astype(float)],
                            [after_a.astype(float), after_b.astype(float)], rng, resamples)
    low, high = np.nanpercentile(boot[0] - boot[1], [2.5, 97.5])
    return {'difference': float(point), 'ci95': [float(low), float(high)]}
