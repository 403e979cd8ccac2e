# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A target that may be absent, and when a search stops (docs/design.md section 7).

**The absent hypothesis.** Besides "the target is in cell i" (i = 0..N-1) the belief may hold
hypothesis N, "there is no target in the grid", with prior ``absent_prior``; the cells share the
rest, ``(1 - absent_prior) / N`` each. Under it every cell draws from the null model, so its
log-likelihood ratio against "no target anywhere" is exactly 0 and a frame's Bayes step is the
usual one (:func:`ipomdp_gaze.model.belief.bayes_update`) on the N + 1 log probabilities with a 0
appended to the frame's terms. The N cell probabilities then sum to ``1 - P(absent)``. The motion
step (:mod:`ipomdp_gaze.model.motion`) leaves the absent mass alone. With ``absent_prior = 0`` the
belief has N entries, exactly as without this module.

**Stopping.** After each frame, with the confidence level ``c``:

- ``found`` when the most likely cell's probability (on the N + 1 scale) reaches ``c``;
- ``absent`` when ``P(absent)`` reaches ``c``;
- ``gave_up`` when the fixation budget runs out first: undecided, not an error.

The decision is the most probable hypothesis that reaches ``c`` (ties to the cell, the lower
index); for ``c > 0.5`` at most one can. If the model is right (targets absent at the prior's
rate, moving as modelled), Bayes' rule bounds the wrong decisions: among searches that decide,
at most ``1 - c`` are wrong (in expectation), because at the moment of a decision the decided
hypothesis has posterior probability at least ``c``.
"""
from __future__ import annotations

import math

from ipomdp_gaze.model.belief import bayes_update, uniform_log_belief
from ipomdp_gaze.model.checks import (check_budget, check_confidence,  # noqa: F401
                                      check_probability)
import numpy as np

# Decision codes of :func:`decide` and :func:`first_decisions`.
UNDECIDED, FOUND, ABSENT = 0, 1, 2
GAVE_UP = UNDECIDED
DECISIONS = {FOUND: 'found', ABSENT: 'absent'}


def check_max_fixations(value, name: str = 'max_fixations') -> int | None:
    """:func:`check_budget` as None for no budget (``None`` or 0 in)."""
    return None if value is None else (check_budget(value, name) or None)


def check_absent_prior(value, name: str = 'absent_prior') -> float:
    """Return ``absent_prior`` in ``[0, 1)`` (ValueError with the reason otherwise)."""
    return check_probability(value, name)


def initial_log_belief(n_cells: int, absent_prior: float = 0.0,
                       episodes: int | None = None, prior: np.ndarray | None = None) -> np.ndarray:
    """
    Return the prior's log probabilities: N cells, plus the absent hypothesis when it is used.

    With ``absent_prior = 0`` this is :func:`ipomdp_gaze.model.belief.uniform_log_belief` (N
    columns).
    Otherwise the last of N + 1 columns is ``log(absent_prior)`` and each cell has
    ``log((1 - absent_prior) / N)``. With ``prior`` P over the cells ((N,), summing to 1,
    checked by the caller) each cell has ``log((1 - absent_prior) P_i)``: -inf where P_i = 0.
    """
    absent = check_absent_prior(absent_prior)
    if absent == 0:
        log_b = uniform_log_belief(n_cells, episodes)
    else:
        shape = (n_cells + 1,) if episodes is None else (episodes, n_cells + 1)
        log_b = np.full(shape, math.log1p(-absent) - math.log(n_cells))
        log_b[..., n_cells] = math.log(absent)
    if prior is not None:
        with np.errstate(divide='ignore'):
            log_b[..., :n_cells] += np.log(prior * n_cells)
    return log_b


def decide(map_probability, absent_probability, confidence: float) -> np.ndarray:
    """
    Return the decision code(s) after a frame: :data:`FOUND`, :data:`ABSENT` or :data:`UNDECIDED`.

    Parameters
    ----------
    map_probability : float or array
        Probability of the most likely cell (on the N + 1 scale).
    absent_probability : float or array
        ``P(absent)`` (0 without the absent hypothesis).
    confidence : float
        The level ``c``.

    """
    cell = np.asarray(map_probability, dtype=float)
    absent = np.asarray(absent_probability, dtype=float)
    found = (cell >= confidence) & (cell >= absent)
    gone = (absent >= confidence) & (absent > cell)
    return np.where(found, FOUND, np.where(gone, ABSENT, UNDECIDED))


def decide_one(map_probability: float, absent_probability: float, confidence: float) -> int:
    """
    Return :func:`decide`'s code for one search, in Python floats.

    The same rule and the same code for every value, NaN included (a search session decides
    once per frame, where numpy's scalar overhead was most of the rule's cost).
    """
    if map_probability >= confidence and map_probability >= absent_probability:
        return FOUND
    if absent_probability >= confidence and absent_probability > map_probability:
        return ABSENT
    return UNDECIDED


def first_decisions(map_probability: np.ndarray, absent_probability, confidence: float,
                    max_fixations: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the first decision of each search and the fixations it took.

    Parameters
    ----------
    map_probability : array (E, T)
        Probability of the most likely cell after fixation t = 1..T of each search.
    absent_probability : array (E, T) or None
        ``P(absent)`` after each fixation (None: no absent hypothesis).
    confidence : float
        The level ``c``.
    max_fixations : int, optional
        The budget (default T; 0 is no budget, as everywhere): decisions after it do not count.

    Returns
    -------
    kind : int array (E,)
        :data:`FOUND`, :data:`ABSENT` or :data:`GAVE_UP` (no decision within the budget).
    fixations : int array (E,)
        Fixations up to and including the deciding one; the budget for ``gave_up``.

    """
    p = np.asarray(map_probability, dtype=float)
    max_fixations = check_max_fixations(max_fixations)
    budget = p.shape[1] if max_fixations is None else min(max_fixations, p.shape[1])
    if budget == 0:                             # no fixation recorded: nothing decided
        return np.full(p.shape[0], GAVE_UP), np.zeros(p.shape[0], dtype=int)
    absent = np.zeros_like(p) if absent_probability is None else np.asarray(absent_probability)
    codes = decide(p[:, :budget], absent[:, :budget], check_confidence(confidence))
    decided = codes != UNDECIDED
    first = np.argmax(decided, axis=1)
    any_decided = decided[np.arange(p.shape[0]), first]
    kind = np.where(any_decided, codes[np.arange(p.shape[0]), first], GAVE_UP)
    return kind, np.where(any_decided, first + 1, budget)


def with_absent(term: np.ndarray, log_belief: np.ndarray) -> np.ndarray:
    """
    Return per-cell terms ``(..., N)`` ready for a belief of N or N + 1 hypotheses.

    With the absent hypothesis (``log_belief`` has one more entry than ``term``) its term is 0:
    under it every cell draws from the null model, so its likelihood ratio is 1.
    """
    if log_belief.shape[-1] == term.shape[-1]:
        return term
    pad = [(0, 0)] * (term.ndim - 1) + [(0, 1)]
    return np.pad(term, pad)


class BatchBelief:
    """
    The beliefs of a batch of searches, ``(E, N)`` or ``(E, N + 1)``, and their one Bayes step.

    The batched counterpart of a search session's belief, shared by the simulator
    (:func:`ipomdp_gaze.simulation.simulate.simulate`) and policy-gradient training
    (:func:`ipomdp_gaze.policies.training.sample_episodes`): the prior, the step
    ``log B += llr`` with the absent hypothesis's 0 (:func:`with_absent`) and renormalisation,
    the infomax reward ``sum_h B_h log B_h`` over every hypothesis (0 log 0 = 0 where a motion
    step left a cell at 0), and the motion prediction. ``prior`` (N,), summing to 1: where the
    target is a priori (default uniform), the cells' share of the mass that is not absent.

    Attributes
    ----------
    log_belief : array (E, N) or (E, N + 1)
        Log probabilities, the absent hypothesis last.
    belief : array (E, N)
        The cell probabilities (what a policy sees), kept in step with ``log_belief``.

    """

    def __init__(self, n_cells: int, absent_prior: float, episodes: int, moving: bool = False,
                 prior: np.ndarray | None = None):
        self.n = n_cells
        self.log_belief = initial_log_belief(n_cells, absent_prior, episodes, prior)
        self.has_absent = self.log_belief.shape[1] > n_cells
        # A prior with empty cells holds zeros from the start, as a motion step may leave them:
        # the reward then takes the 0 log 0 = 0 path of ``moving``.
        self.moving = bool(moving) or (prior is not None and not np.all(prior))
        self._terms = np.zeros((episodes, n_cells + 1)) if self.has_absent else None
        self.belief = np.exp(self.log_belief[:, :n_cells])
        self.absent_probability = None

    def update(self, llr: np.ndarray) -> np.ndarray:
        """Apply one frame per search (``llr`` (E, N)); return the infomax reward (E,)."""
        log_b, n = self.log_belief, self.n
        if self.has_absent:
            self._terms[:, :n] = llr                # the absent hypothesis's term stays 0
            llr = self._terms
        bayes_update(log_b, llr, out=log_b)
        if self.has_absent or self.moving:
            full = np.exp(log_b)
            self.belief[...] = full[:, :n]
            if self.has_absent:
                self.absent_probability = full[:, n]
            with np.errstate(invalid='ignore'):     # 0 * -inf where a cell is 0: not summed
                return np.sum(full * log_b, axis=1, where=full > 0)
        np.exp(log_b, out=self.belief)
        return np.sum(self.belief * log_b, axis=1)

    def predict(self, motion) -> None:
        """Spread every belief by one step of ``motion`` (the absent mass stays)."""
        motion.predict_log(self.log_belief)
        self.belief[...] = np.exp(self.log_belief[:, :self.n])
