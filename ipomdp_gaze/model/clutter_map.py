# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Spots of texture that fire view after view while the target moves: a clutter map (§12.8).

The still scene's hotspots (:mod:`ipomdp_gaze.model.false_alarms`) weigh a face at cell i against
all the counts cell i ever gave; with a moving target the face's cell changes from frame to
frame and that bookkeeping no longer holds, so the session switched hotspots off with motion on,
and a spot that fires under the head in every view then holds a false ``found`` for as long as
the head looks at it. A clutter map (the radar tracker's per-cell estimate of its false-alarm
density, learned over time) keeps instead, per cell, the probability ``pi_i`` that it is a
hotspot: static while the face moves, updated frame by frame with the cells' hotspot states
taken independent of each other and of where the face is (an assumed-density filter):

- the face's term of a frame at cell i is ``log T_i - log M_i``, where ``M_i = (1 - pi_i) N_i +
  pi_i H_i`` is cell i's count without the face (background or hotspot) and ``T``, ``N``, ``H``
  are the count's probabilities under the face, the model's null and the hotspot's scaled null
  (:func:`ipomdp_gaze.model.false_alarms.scaled_null`) at the cell's offset; under "absent"
  every cell draws from its ``M``, so that hypothesis keeps the ratio 1;
- the hotspot's update is the frame's exact marginal under that factorised prior, with ``b`` the
  belief predicted to the frame:

      P(frame | hot_i) / P(frame | not hot_i) = (b_i T_i + H_i S_i) / (b_i T_i + N_i S_i)
      S_i = sum over j != i of b_j T_j / M_j, plus b_absent

  (the face elsewhere, or nobody, explains the rest of the frame). Counts a face is believed to
  give leave ``pi_i`` alone; counts nothing else explains raise it; a view of an empty spot
  lowers it.

With many targets (the occupancy belief, one face or none per cell, :mod:`ipomdp_gaze.model.
occupancy`) the cells are independent, so cell i's own occupancy ``b_i`` explains the rest:
``S_i = 1 - b_i`` above (:meth:`ClutterMap.occupancy_step`), and the face's term is the same.

Weak counts repeated at one spot then stop counting for a face after a view or two, while the
counts a face gives near the view's centre (far more than a hotspot's) still do. With a prior of
0 the face's term is the model's ratio exactly.
"""
from __future__ import annotations

import math

from ipomdp_gaze.model.false_alarms import check_hotspot_prior, check_hotspot_scale, scaled_null
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.model.occupancy import occupancy
import numpy as np


def _log_sigmoid(x: np.ndarray) -> np.ndarray:
    """Return ``log(1 / (1 + exp(-x)))`` without overflow."""
    return -np.logaddexp(0.0, -x)


class ClutterMap:
    """
    Per-cell hotspot probabilities of a moving target's search, and the face's terms they give.

    Parameters
    ----------
    model : CountObservation
        The count model the searcher assumes.
    hotspot_prior : float
        The prior that a cell is a hotspot (> 0).
    hotspot_scale : float
        A hotspot's detections are this many times as likely as the model's null tables say.

    """

    def __init__(self, model: CountObservation, hotspot_prior: float, hotspot_scale: float):
        prior = check_hotspot_prior(hotspot_prior)
        if prior <= 0:
            raise ValueError('a clutter map needs hotspot_prior > 0')
        self.hotspot_prior = prior
        self.hotspot_scale = check_hotspot_scale(hotspot_scale)
        self._hot = CountObservation(
            model.grid, scaled_null(model.p_target, model.p_null, self.hotspot_scale),
            model.p_null)
        self.log_prior_odds = math.log(prior) - math.log1p(-prior)
        self.log_odds = np.full(model.grid.n_cells, self.log_prior_odds)

    def reset(self) -> None:
        """Forget every frame: each cell back to the prior."""
        self.log_odds[:] = self.log_prior_odds

    @property
    def probability(self) -> np.ndarray:
        """Each cell's probability of being a hotspot now, shape (N,)."""
        return occupancy(self.log_odds)

    def step(self, log_belief: np.ndarray, observation: np.ndarray, fixation: int,
             ratio: np.ndarray) -> np.ndarray:
        """
        Take one frame: return the face's term ``log T - log M`` and learn from the frame.

        ``log_belief`` is the normalised belief predicted to the frame (N cells, or N + 1 with
        the absent hypothesis last), ``observation`` the validated frame taken at ``fixation``
        and ``ratio`` the model's ``log T - log N`` of it. The term uses the map as it was
        before the frame, as the Bayes step of the belief must.
        """
        hot = self.hot_ratio(observation, fixation)
        face = self.face_term(ratio, hot)
        self.update(log_belief, ratio, hot, face)
        return face

    def occupancy_step(self, log_odds: np.ndarray, observation: np.ndarray, fixation: int,
                       ratio: np.ndarray) -> np.ndarray:
        """
        Take one frame of the occupancy belief: return the face's term and learn from the frame.

        ``log_odds`` is each cell's occupancy predicted to the frame (N,); otherwise as
        :meth:`step`, with ``S_i = 1 - b_i`` (module docstring).
        """
        hot = self.hot_ratio(observation, fixation)
        face = self.face_term(ratio, hot)
        with np.errstate(invalid='ignore'):
            log_x = np.asarray(log_odds, dtype=float) + ratio   # log b_i T_i / ((1 - b_i) N_i)
        log_x = np.where(np.isnan(log_x), -np.inf, log_x)
        self.log_odds += np.logaddexp(log_x, hot) - np.logaddexp(log_x, 0.0)
        return face

    def hot_ratio(self, observation: np.ndarray, fixation: int) -> np.ndarray:
        """Return ``log H_i - log N_i`` per cell for a validated frame (0 where unobserved)."""
        hot = self._hot.log_likelihood_ratio(observation, fixation, validate=False)
        return np.nan_to_num(hot, nan=0.0)

    def face_term(self, ratio: np.ndarray, hot: np.ndarray) -> np.ndarray:
        """Return the face's per-cell term ``log T - log M`` from the model's ``log T - log N``."""
        log_m = np.logaddexp(_log_sigmoid(-self.log_odds), _log_sigmoid(self.log_odds) + hot)
        return ratio - log_m

    def update(self, log_belief: np.ndarray, ratio: np.ndarray, hot: np.ndarray,
               face: np.ndarray) -> None:
        """
        Learn from one frame (module docstring).

        ``log_belief`` is the normalised belief predicted to the frame (N cells, or N + 1 with
        the absent hypothesis last), ``ratio`` the model's ``log T - log N``, ``hot`` the
        :meth:`hot_ratio` and ``face`` the :meth:`face_term` of the frame, all before this call.
        """
        n = self.log_odds.size
        log_b = log_belief[:n]
        with np.errstate(invalid='ignore'):
            weights = log_b + face                    # log b_j T_j / M_j, -inf where excluded
        parts = weights if log_belief.size == n else np.append(weights, log_belief[n])
        total = np.logaddexp.reduce(parts)
        if not np.isfinite(total):
            return
        share = np.minimum(np.exp(weights - total), 1.0 - 1e-15)
        log_rest = total + np.log1p(-share)           # log S_i
        with np.errstate(invalid='ignore'):
            log_x = log_b + ratio - log_rest          # log b_i T_i / (N_i S_i)
        log_x = np.where(np.isnan(log_x), -np.inf, log_x)
        self.log_odds += np.logaddexp(log_x, hot) - np.logaddexp(log_x, 0.0)
