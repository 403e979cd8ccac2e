# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Honest evaluation: percent correct vs fixations, fixations to 90% correct, bootstrap intervals.

Fixations to 90% correct is the first t where percent correct reaches 0.90, interpolated linearly
between t-1 and t (percent correct at t = 0 is the uniform guess, 1/N); ``None`` if never reached.
Intervals are percentile bootstraps over episodes.
"""
from __future__ import annotations

import numpy as np

LEVEL = 0.90


def fixations_to_level(percent_correct: np.ndarray, n_cells: int, level: float = LEVEL):
    """
    First t (interpolated) at which ``percent_correct[t-1] >= level``; ``None`` if never.

    Works on a curve (T,) or a stack of curves (B, T), returning a float array with NaN for never.
    """
    pc = np.atleast_2d(np.asarray(percent_correct, dtype=float))
    curve = np.concatenate([np.full((pc.shape[0], 1), 1.0 / n_cells), pc], axis=1)
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
                       resamples: int = 1000, counts: np.ndarray | None = None):
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

    Returns
    -------
    (estimate, (low, high)) with ``None`` where 90% is not reached.

    """
    episodes = correct.shape[0]
    point = fixations_to_level(correct.mean(axis=0), n_cells)
    if point is None:
        return None, None
    if counts is None:
        counts = bootstrap_counts(episodes, resamples, rng)
    curves = (counts.astype(np.float32) @ correct.astype(np.float32)) / episodes
    values = fixations_to_level(curves, n_cells)
    if np.mean(np.isnan(values)) > 0.025:
        return point, None
    low, high = np.nanpercentile(values, [2.5, 97.5])
    return point, (float(low), float(high))


def paired_difference_ci(correct_a: np.ndarray, correct_b: np.ndarray, n_cells: int,
                         rng: np.random.Generator, resamples: int = 1000):
    """Difference ``a - b`` of fixations to 90% on the same episodes, with a paired 95% CI."""
    n = min(correct_a.shape[0], correct_b.shape[0])
    a, b = correct_a[:n], correct_b[:n]
    pa = fixations_to_level(a.mean(axis=0), n_cells)
    pb = fixations_to_level(b.mean(axis=0), n_cells)
    if pa is None or pb is None:
        return None, None
    counts = bootstrap_counts(n, resamples, rng).astype(np.float32)
    va = fixations_to_level(counts @ a.astype(np.float32) / n, n_cells)
    vb = fixations_to_level(counts @ b.astype(np.float32) / n, n_cells)
    diff = va - vb
    low, high = np.nanpercentile(diff, [2.5, 97.5])
    return pa - pb, (float(low), float(high))
