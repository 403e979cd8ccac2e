# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Switching searcher: tempered ELM for the first fixations, the ideal searcher for the rest.

Fixations to 90% correct scores the belief after about eight fixations (7x7, human FPOC). The
ideal searcher (:class:`ipomdp_gaze.policies.greedy.PercentCorrectGreedy`) is exactly optimal for
the last fixation before the scored one, since it maximises the probability that the next MAP
guess is right; early in the search it is myopic. Tempered ELM
(:class:`ipomdp_gaze.policies.planner.TemperedELM`) keeps unlikely cells in play and is the
better early policy. The switching searcher fixates with tempered ELM while ``t < switch_at``
and with the ideal searcher from then on:

    k_t = argmax_k sum_i B_i^a d_ik^p          for t < switch_at
    k_t = argmax_k sum_i B_i P(C | i, k)       for t >= switch_at

``switch_at = 5`` was chosen on training seeds for the 7x7 human FPOC (switching at 3 to 6 gave
the same fixations to 90% within 0.02; docs/reproduction.md has the measurement). It costs the
ideal searcher's decision time from ``switch_at`` on (a few ms at 7x7) and needs the Gaussian
model of an FPOC.
"""
from __future__ import annotations

from ipomdp_gaze.model.fpoc import FPOC
from ipomdp_gaze.model.grid import Grid
import numpy as np

from .greedy import PercentCorrectGreedy
from .planner import BELIEF_POWER, DPRIME_POWER, TemperedELM

SWITCH_AT = 5


class SwitchingSearcher:
    """
    Tempered ELM while ``t < switch_at``, then the percent-correct ideal searcher.

    Parameters
    ----------
    grid, fpoc
        The task (the Gaussian model of ``fpoc``).
    switch_at : int
        First fixation index (0-based) chosen by the ideal searcher; 0 is the ideal searcher
        throughout.
    belief_power, dprime_power : float
        Tempered ELM's ``a`` and ``p`` (:class:`TemperedELM`).

    """

    name = 'switching'
    # A slow searcher: evaluate and reproduce run it on fewer episodes.
    costly = True
    action = 'argmax'

    def __init__(self, grid: Grid, fpoc: FPOC, switch_at: int = SWITCH_AT,
                 belief_power: float = BELIEF_POWER, dprime_power: float = DPRIME_POWER):
        if isinstance(switch_at, bool) or not isinstance(switch_at, (int, np.integer)) \
                or switch_at < 0:
            raise ValueError(f'switch_at must be an integer >= 0, got {switch_at!r}')
        self.switch_at = int(switch_at)
        self.late = PercentCorrectGreedy(grid, fpoc)
        self.early = TemperedELM(grid, fpoc, belief_power, dprime_power, dprime=self.late.dprime)

    def select(self, belief, t, rng):
        """Fixation for each belief row at fixation index ``t`` (the same for the whole batch)."""
        policy = self.early if t < self.switch_at else self.late
        return policy.select(belief, t, rng)
