# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Batched simulation of the visual-search task: thousands of episodes at once.

Any policy plugs in through one method, ``select(belief, t, rng) -> fixations``: ``belief`` is an
(episodes, N) array of probabilities, ``t`` the 0-based fixation number and ``rng`` a
``numpy.random.Generator`` for stochastic policies. Targets and observation noise come from their
own seeded streams, so every policy run with the same seed sees the same targets and the same
noise draws (common random numbers).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from .belief import bayes_update, map_cell, uniform_log_belief
from .grid import Grid
from .observation import as_observation

# Stream tags of the seed sequence: targets, noise per fixation, and the policy's own draws.
_TARGET, _NOISE, _POLICY = 0, 1, 2


class Policy(Protocol):
    """Anything that picks the next fixation for a batch of beliefs."""

    def select(self, belief: np.ndarray, t: int, rng: np.random.Generator) -> np.ndarray:
        """Return one fixation (cell index) per episode, shape (episodes,)."""


@dataclass
class SearchResult:
    """
    What a batch of simulated searches produced.

    ``correct[e, t-1]`` is whether episode e's MAP guess after t observations is its target;
    ``fixations[e, t-1]`` is the t-th fixation; ``map_prob[e, t-1]`` the MAP probability then.
    """

    targets: np.ndarray
    fixations: np.ndarray
    correct: np.ndarray
    map_prob: np.ndarray
    infomax: np.ndarray

    @property
    def percent_correct(self) -> np.ndarray:
        """Fraction correct after t = 1..horizon fixations."""
        return self.correct.mean(axis=0)


def draw_targets(n_cells: int, episodes: int, seed: int) -> np.ndarray:
    """Uniformly random target cells from the seed's target stream."""
    rng = np.random.default_rng([seed, _TARGET])
    return rng.integers(0, n_cells, size=episodes)


def noise_stream(seed: int, t: int) -> np.random.Generator:
    """Return the generator of the observation noise for fixation ``t`` (0-based)."""
    return np.random.default_rng([seed, _NOISE, t])


def policy_rng(seed: int) -> np.random.Generator:
    """Return the generator handed to the policy's ``select``."""
    return np.random.default_rng([seed, _POLICY])


def simulate(grid: Grid, model, policy: Policy, episodes: int, horizon: int | None = None,
             seed: int = 0, targets: np.ndarray | None = None, progress=None) -> SearchResult:
    """
    Run ``episodes`` searches of ``horizon`` fixations (default N) from a uniform belief.

    Parameters
    ----------
    grid
        The visual array.
    model
        The observation model (:mod:`ipomdp_gaze.observation`), or an FPOC for the Gaussian one.
    policy
        Anything with ``select(belief, t, rng)``.
    episodes, horizon, seed
        Batch size, fixations per episode and the seed of all random streams.
    targets : array (episodes,), optional
        Target cells; drawn from the seed's target stream when omitted.
    progress : callable, optional
        Called with the fixation number after each step.

    """
    n = grid.n_cells
    horizon = n if horizon is None else int(horizon)
    if horizon < 1 or episodes < 1:
        raise ValueError('episodes and horizon must be >= 1')
    model = as_observation(grid, model)
    targets = draw_targets(n, episodes, seed) if targets is None else np.asarray(targets)
    rows = np.arange(episodes)
    rng = policy_rng(seed)
    log_b = uniform_log_belief(n, episodes)
    belief = np.exp(log_b)
    fixations = np.empty((episodes, horizon), dtype=np.int64)
    correct = np.empty((episodes, horizon), dtype=bool)
    map_prob = np.empty((episodes, horizon))
    infomax = np.empty((episodes, horizon))
    for t in range(horizon):
        k = np.asarray(policy.select(belief, t, rng), dtype=np.int64)
        fixations[:, t] = k
        frames = model.sample(targets, k, noise_stream(seed, t))
        bayes_update(log_b, model.log_likelihood_ratio(frames, k, validate=False), out=log_b)
        np.exp(log_b, out=belief)
        guess = map_cell(belief)
        correct[:, t] = guess == targets
        map_prob[:, t] = belief[rows, guess]
        infomax[:, t] = np.sum(belief * log_b, axis=1)
        if progress is not None:
            progress(t + 1)
    return SearchResult(targets, fixations, correct, map_prob, infomax)
