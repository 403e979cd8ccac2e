# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Non-myopic planner: look-ahead rollouts from the current belief with a base policy.

At every decision the planner takes a shortlist of candidate fixations (the base policy's own
choice first, then the next best cells by the base policy's score) and simulates ``rollouts``
futures from the current belief for each of them: a target drawn from the belief, the observation
at the candidate, then the base policy for the rest of the look-ahead. All candidates of an
episode see the same targets and the same noise draws (common random numbers), so their
*difference* is estimated far more precisely than any one value. The planner moves away from the
base policy's choice only when a candidate's paired advantage is positive by more than
``switch_z`` standard errors, so rollout noise alone does not make it worse than its base
(rollout policy improvement, Bertsekas: with exact values the planner is never worse than its
base on the look-ahead objective).

Scores (``objective``) of one simulated future:

``correct``
    ``max_i B_i`` after the last look-ahead fixation: the probability that the MAP guess is
    right given the simulated history, an unbiased and lower-variance stand-in for the 0/1
    outcome (conditional Monte Carlo), so the mean is the expected percent correct.
``correct_sum``
    The same summed over every look-ahead step.
``infomax``
    The paper's return: the infomax reward ``sum_i B_i log B_i`` summed over the look-ahead.
``entropy``
    The infomax reward of the final belief only.

The default base policy is :class:`TemperedELM`, ELM (Najemnik & Geisler 2009, kernel ``d^2``)
applied to a flattened belief ``B^a``; the tempering was tuned on held-out seeds for fixations to
90% correct (bench/simulation/bench_planner.py has the numbers). Any policy with ``select(belief,
t, rng)``
can be the base, for example a learned convolutional kernel.
"""
from __future__ import annotations

from ipomdp_gaze.model.belief import argmax_ties_low
from ipomdp_gaze.model.checks import finite as _finite
from ipomdp_gaze.model.checks import positive_int as _positive_int
from ipomdp_gaze.model.fpoc import dprime_matrix, FPOC
from ipomdp_gaze.model.grid import Grid
import numpy as np

from .conv import kernel_matrix

OBJECTIVES = ('correct', 'correct_sum', 'infomax', 'entropy')
DTYPES = ('float32', 'float64')
LOG_FLOOR = -700.0
# Tempered ELM's defaults, tuned on held-out seeds (bench/simulation/bench_planner.py).
BELIEF_POWER, DPRIME_POWER = 0.7, 1.75


class TemperedELM:
    """
    ELM on a tempered belief: ``argmax_k sum_i B_i^a d_ik^p`` (ties to the lowest index).

    ``belief_power`` a = 1 and ``dprime_power`` p = 2 is exactly ELM. ``a < 1`` flattens the
    belief, so cells that are unlikely but not yet ruled out keep drawing fixations: a cheap
    non-myopic correction, since the search is scored several fixations later, not at the next.
    """

    name = 'tempered_elm'
    action = 'argmax'

    def __init__(self, grid: Grid, fpoc: FPOC, belief_power: float = BELIEF_POWER,
                 dprime_power: float = DPRIME_POWER, dprime=None):
        self.belief_power = _finite('belief_power', belief_power, positive=True)
        self.dprime_power = _finite('dprime_power', dprime_power, positive=True)
        d = dprime_matrix(grid, fpoc) if dprime is None else np.asarray(dprime, dtype=float)
        n = grid.n_cells
        if d.shape != (n, n):
            raise ValueError(f'dprime must have shape ({n}, {n}), got {d.shape}')
        weights = d ** self.dprime_power                                  # [i, k]
        self._weights = {np.dtype(np.float64): weights,
                         np.dtype(np.float32): weights.astype(np.float32)}

    def scores(self, belief: np.ndarray) -> np.ndarray:
        """``score_k = sum_i B_i^a d_ik^p``, shape like ``belief`` (float32 stays float32)."""
        b = np.asarray(belief)
        if b.dtype not in self._weights:
            b = b.astype(float)
        tempered = b if self.belief_power == 1.0 else np.power(b, self.belief_power)
        return tempered @ self._weights[b.dtype]

    def select(self, belief, t, rng):
        """Highest score per belief, ties to the lowest cell index."""
        return argmax_ties_low(self.scores(belief))


class TemperedPolicy:
    """
    Any belief policy fed the tempered belief ``B^a / sum B^a`` (a learned kernel, say).

    For a policy linear in the belief (a convolutional kernel) this is the same tempering as
    :class:`TemperedELM`; whether it helps a given kernel is an empirical question.
    """

    def __init__(self, base, belief_power: float):
        if not callable(getattr(base, 'select', None)):
            raise ValueError('base policy must have a select(belief, t, rng) method')
        self.base = base
        self.belief_power = _finite('belief_power', belief_power, positive=True)
        self.name = 'tempered_' + str(getattr(base, 'name', 'policy'))

    def tempered(self, belief: np.ndarray) -> np.ndarray:
        """``B^a`` renormalised over the last axis."""
        b = np.power(np.asarray(belief), self.belief_power)
        return b / b.sum(axis=-1, keepdims=True)

    @property
    def scores(self):
        """Return the base policy's ``scores`` on the tempered belief, or None if it has none."""
        scorer = getattr(self.base, 'scores', None)
        if not callable(scorer):
            return None
        return lambda belief: scorer(self.tempered(belief))

    def select(self, belief, t, rng):
        """Return the base policy's choice for the tempered belief."""
        return self.base.select(self.tempered(belief), t, rng)


class RolloutPlanner:
    """
    Pick each fixation by simulated look-ahead with a base policy (batched over episodes).

    Parameters
    ----------
    grid, fpoc
        The task.
    base : policy, optional
        The rollout policy, anything with ``select(belief, t, rng)``; :class:`TemperedELM` when
        omitted. If it has ``scores(belief)`` the shortlist is its best cells, otherwise the most
        likely cells.
    belief_power : float, optional
        Feed the base policy the tempered belief ``B^a`` (:class:`TemperedPolicy`); for a given
        base only (the default base is already tempered).
    candidates : int
        Shortlist size, the base policy's choice included.
    rollouts : int
        Simulated futures per candidate (the same ones for every candidate), at least.
    rollout_budget : int, optional
        Simulated fixations per candidate and decision: a short look-ahead then gets
        ``rollout_budget // look-ahead`` futures (if more than ``rollouts``), so every decision
        costs about the same and the late, short look-aheads are estimated more precisely.
    horizon : int
        Look-ahead length in fixations, the candidate included (at least this many).
    until : int, optional
        Look ahead at least up to this many fixations in total: the objective is then the same
        absolute fixation at every decision before it (for example the one where 90% correct is
        expected).
    objective : str
        One of :data:`OBJECTIVES`.
    switch_z : float
        A candidate replaces the base policy's choice only if its mean paired advantage exceeds
        ``switch_z`` standard errors (a one-sided test against rollout noise).
    dtype : str
        ``'float32'`` (fast) or ``'float64'`` for the rollout arithmetic.
    chunk_rows : int
        Simulated rows (episodes x candidates x rollouts) held at once; bounds memory only.
    dprime : array (N, N), optional
        ``d[j, k]``; computed from ``fpoc`` when omitted.

    """

    name = 'planner'
    # A slow searcher: evaluate and reproduce run it on fewer episodes.
    costly = True

    def __init__(self, grid: Grid, fpoc: FPOC, base=None, candidates: int = 4,
                 rollouts: int = 64, rollout_budget: int | None = 2048, horizon: int = 2,
                 until: int | None = 8, objective: str = 'correct', switch_z: float = 2.0,
                 dtype: str = 'float32', belief_power: float | None = None,
                 chunk_rows: int = 1 << 17, dprime=None):
        n = grid.n_cells
        d = dprime_matrix(grid, fpoc) if dprime is None else np.asarray(dprime, dtype=float)
        if d.shape != (n, n):
            raise ValueError(f'dprime must have shape ({n}, {n}), got {d.shape}')
        if base is None:
            if belief_power is not None:
                raise ValueError('belief_power needs a base policy; the default base is '
                                 'already TemperedELM')
            base = TemperedELM(grid, fpoc, dprime=d)
        if not callable(getattr(base, 'select', None)):
            raise ValueError('base policy must have a select(belief, t, rng) method')
        inner = base
        if belief_power is not None:
            base = TemperedPolicy(base, belief_power)
        if objective not in OBJECTIVES:
            valid = ', '.join(OBJECTIVES)
            raise ValueError(f'unknown objective {objective!r}; valid objectives: {valid}')
        if str(dtype) not in DTYPES:
            raise ValueError(f'dtype must be one of {DTYPES}, got {dtype!r}')
        self.grid = grid
        self.fpoc = fpoc
        self.base = base
        self.candidates = min(_positive_int('candidates', candidates), n)
        self.rollouts = _positive_int('rollouts', rollouts)
        self.rollout_budget = (None if rollout_budget is None
                               else _positive_int('rollout_budget', rollout_budget))
        self.horizon = _positive_int('horizon', horizon)
        self.until = None if until is None else _positive_int('until', until)
        self.objective = objective
        self.switch_z = _finite('switch_z', switch_z)
        self.dtype = np.dtype(str(dtype))
        self.chunk_rows = _positive_int('chunk_rows', chunk_rows)
        d_fix = np.ascontiguousarray(d.T)                                 # [k, j] = d_jk
        self._d_fix = d_fix.astype(self.dtype)
        self._half_d2_fix = (-0.5 * d_fix ** 2).astype(self.dtype)
        self._d2_fix = (d_fix ** 2).astype(self.dtype)
        self._base_weights = None
        self._base_power = None if belief_power is None else base.belief_power
        kernel = getattr(inner, 'kernel', None)
        if kernel is not None and getattr(inner, 'action', None) == 'argmax':
            self._base_weights = kernel_matrix(grid, np.asarray(kernel)).T.astype(self.dtype)

    def lookahead(self, t: int) -> int:
        """Fixations simulated at decision ``t`` (0-based): ``horizon``, or up to ``until``."""
        return self.horizon if self.until is None else max(self.horizon, self.until - t)

    def rollouts_at(self, t: int) -> int:
        """Return the number of simulated futures per candidate at decision ``t``."""
        if self.rollout_budget is None:
            return self.rollouts
        return max(self.rollouts, self.rollout_budget // self.lookahead(t))

    def shortlist(self, belief: np.ndarray, t: int, rng: np.random.Generator) -> np.ndarray:
        """Candidates (E, m): the base policy's choice first, then its next best cells."""
        base_choice = np.asarray(self.base.select(belief, t, rng), dtype=np.int64)
        scorer = getattr(self.base, 'scores', None)
        scores = np.array(scorer(belief) if callable(scorer) else belief, dtype=float)
        episodes, n = scores.shape
        scores[np.arange(episodes), base_choice] = np.inf
        m = self.candidates
        if m < n:
            top = np.argpartition(-scores, m - 1, axis=1)[:, :m]
        else:
            top = np.tile(np.arange(n), (episodes, 1))
        order = np.argsort(-np.take_along_axis(scores, top, axis=1), axis=1, kind='stable')
        return np.take_along_axis(top, order, axis=1)

    @staticmethod
    def sample_targets(belief: np.ndarray, r: int, rng: np.random.Generator) -> np.ndarray:
        """Stratified (systematic) draws of ``r`` targets per episode from the belief (E, r)."""
        cdf = np.cumsum(belief, axis=1)
        cdf /= cdf[:, -1:]
        u = (np.arange(r)[None, :] + rng.random((belief.shape[0], 1))) / r
        idx = (cdf[:, None, :] < u[:, :, None]).sum(axis=2)
        return np.minimum(idx, belief.shape[1] - 1)

    def values(self, belief, t: int, rng: np.random.Generator):
        """
        Shortlist (E, m), mean rollout score (E, m) and paired advantage z-scores (E, m).

        The z-score of candidate c is the mean over rollouts of ``score_c - score_0`` (same
        target and noise for both) divided by its standard error; 0 for candidate 0.
        """
        belief = np.atleast_2d(np.asarray(belief, dtype=float))
        cand = self.shortlist(belief, t, rng)
        episodes, m = cand.shape
        r, n = self.rollouts_at(t), self.grid.n_cells
        step = max(1, self.chunk_rows // (m * r))
        value = np.empty((episodes, m))
        z = np.zeros((episodes, m))
        h = self.lookahead(t)
        for start in range(0, episodes, step):
            part = slice(start, min(start + step, episodes))
            targets = self.sample_targets(belief[part], r, rng)
            noise = rng.standard_normal((h, targets.shape[0], r, n), dtype=self.dtype)
            score = self.rollout_scores(belief[part], cand[part], t, targets, noise, rng)
            value[part] = score.mean(axis=2)
            if r > 1:
                diff = score - score[:, :1]
                mean = diff.mean(axis=2)
                se = diff.std(axis=2, ddof=1) / np.sqrt(r)
                with np.errstate(divide='ignore', invalid='ignore'):
                    z[part] = np.where(se > 0, mean / se, np.sign(mean) * np.inf)
        return cand, value, z

    def _base_choice(self, belief: np.ndarray, t: int, rng: np.random.Generator) -> np.ndarray:
        if self._base_weights is not None:
            if self._base_power is not None:
                belief = np.power(belief, self._base_power)
            return np.argmax(belief @ self._base_weights, axis=1)
        if isinstance(self.base, TemperedELM):
            return np.argmax(self.base.scores(belief), axis=1)
        return np.asarray(self.base.select(belief.astype(float), t, rng), dtype=np.int64)

    def rollout_scores(self, belief, cand, t, targets, noise, rng) -> np.ndarray:
        """
        Score of every simulated future, shape (E, m, R).

        Parameters
        ----------
        belief : array (E, N)
            Current beliefs (probabilities).
        cand : int array (E, m)
            First fixation of each candidate future.
        t : int
            Fixations made so far (the base policy is asked with ``t + s``).
        targets : int array (E, R)
            Target cell of each future, shared by the candidates.
        noise : array (H, E, R, N)
            Standard normal noise of each look-ahead fixation, shared by the candidates; H is
            the look-ahead length.
        rng : numpy.random.Generator
            Passed to a stochastic base policy.

        """
        episodes, m = cand.shape
        h, _, r, n = noise.shape
        rows = episodes * m * r
        log_b = np.log(np.maximum(belief, np.exp(LOG_FLOOR))).astype(self.dtype)
        flat = np.repeat(log_b, m * r, axis=0)
        row = np.arange(rows)
        tgt = np.broadcast_to(targets[:, None, :], (episodes, m, r)).reshape(rows)
        fix = np.broadcast_to(cand[:, :, None], (episodes, m, r)).reshape(rows)
        score = np.zeros(rows)
        for s in range(h):
            d = self._d_fix[fix].reshape(episodes, m, r, n)
            flat += np.multiply(d, noise[s][:, None].astype(self.dtype)).reshape(rows, n)
            flat += self._half_d2_fix[fix]
            flat[row, tgt] += self._d2_fix[fix, tgt]            # the target's mean d_jk
            flat -= flat.max(axis=1, keepdims=True)
            b = np.exp(flat)
            total = b.sum(axis=1, keepdims=True)
            flat -= np.log(total)
            b /= total
            last = s == h - 1
            if self.objective == 'correct_sum' or (self.objective == 'correct' and last):
                score += b.max(axis=1)
            elif self.objective == 'infomax' or (self.objective == 'entropy' and last):
                score += np.einsum('ij,ij->i', b, flat)
            if not last:
                fix = self._base_choice(b, t + s + 1, rng)
        return score.reshape(episodes, m, r)

    def select(self, belief, t, rng):
        """Fixation per episode (E,), or one cell index for a single belief (N,)."""
        single = np.ndim(belief) == 1
        cand, value, z = self.values(belief, t, rng)
        allowed = z > self.switch_z
        allowed[:, 0] = True
        pick = argmax_ties_low(np.where(allowed, value, -np.inf))
        k = cand[np.arange(cand.shape[0]), pick]
        return int(k[0]) if single else k


def make_planner(grid: Grid, fpoc: FPOC, base=None, **options) -> RolloutPlanner:
    """Build the look-ahead planner; ``options`` are :class:`RolloutPlanner` arguments."""
    return RolloutPlanner(grid, fpoc, base=base, **options)
