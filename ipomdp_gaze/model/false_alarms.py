# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A scene's own false-alarm rate, learned during the search (docs/design.md section 6.7).

A count model's null tables are an average over the calibration backgrounds, but a scene of
grass or printed text fires the detector far more often than that average, in view after view:
each of its detections then looks like a face. Here the scene's rate of detections without a
face is the model's times an unknown factor ``s`` from a few ``scales`` (equally likely a
priori), and the belief is over (scale, cell or absent):

    P(frames | s, target at i) / P(frames | model's null) = G_s * R_s(i)
    G_s  = prod over observed cells j of p_null_s(c_j) / p_null(c_j)
    R_s(i) = p_target(c_i) / p_null_s(c_i)

``G_s`` is the evidence every cell gives about the scene's rate (most cells hold no face), and
``R_s`` the usual per-cell ratio with the scaled null table. The cells' belief is the marginal
over ``s``. With the still-scene evidence (``repeat_weight`` < 1) both terms are kept per cell
from the most informative view plus the weighted rest, as for the plain model. The scaled null
table multiplies every nonzero count's probability by ``s`` (the total capped at
:data:`MAX_DETECTION_PROBABILITY`) at the offsets where the model's tables differ; where they
are equal the offset says nothing, for every scale. The one-time scan keeps the model's tables.

**Hotspots.** A texture may also fire at one place, view after view (a tuft of grass, a printed
letter): a scale for the whole scene does not explain it, and to the plain model a spot that
gives two or three detections from every pose looks like a face, more so with every view. With
``hotspot_prior`` > 0 each cell without the face is, independently and with that prior, a
hotspot whose counts follow the model's null tables scaled by ``hotspot_scale`` (the same
:func:`scaled_null`), persistent across the search. A cell's background evidence is then the
mixture ``B_s(i) = (1 - rho) + rho * prod p_hot / p_null_s`` over its own views, and

    P(frames | s, target at i) / P(frames | model's null) = G_s * prod_j B_s(j) * R_s(i) / B_s(i)

so weak counts repeated at one spot are worth at most about ``1 / rho`` for a face there, while
the counts a face gives near the view's centre (far more than a hotspot's) still are.
"""
from __future__ import annotations

import math

from ipomdp_gaze.model.belief import normalize_log
from ipomdp_gaze.model.checks import check_factor_above_one, check_in_range, is_number
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.model.still_evidence import StillEvidence
import numpy as np

MAX_SCALES = 8
# A hotspot fires this many times as often as the model's null tables by default.
DEFAULT_HOTSPOT_SCALE = 20.0
# The largest prior that a cell is a hotspot (check_hotspot_prior).
MAX_HOTSPOT_PRIOR = 0.5
# A scaled null table never gives a cell a detection with more than this probability.
MAX_DETECTION_PROBABILITY = 0.95


def check_false_alarm_scales(value, name: str = 'false_alarm_scales') -> tuple:
    """Return the scales as a sorted tuple of floats, or raise ValueError naming ``name``."""
    try:                                    # numbers: no text ('2' was the factor 2), no bools
        scales = tuple(float(v) for v in value) if all(is_number(v) for v in value) else ()
    except TypeError:
        scales = ()
    if not 1 <= len(scales) <= MAX_SCALES or len(set(scales)) != len(scales) \
            or not all(math.isfinite(s) and s > 0 for s in scales):
        raise ValueError(f'{name} must be 1 to {MAX_SCALES} distinct positive factors of the '
                         f"model's false-alarm rates ([1.0]: the rates as calibrated), got "
                         f'{value!r}')
    return tuple(sorted(scales))


def check_hotspot_prior(value, name: str = 'hotspot_prior') -> float:
    """Return the prior that a cell is a hotspot as a float in [0, 0.5], or raise ValueError."""
    return check_in_range(value, name, 0.0, MAX_HOTSPOT_PRIOR, ' (0: no hotspots)')


def check_hotspot_scale(value, name: str = 'hotspot_scale') -> float:
    """Return the factor of a hotspot's detection rate as a float > 1, or raise ValueError."""
    return check_factor_above_one(value, name, "the model's false-alarm rates")


def scaled_null(p_target: np.ndarray, p_null: np.ndarray, scale: float) -> np.ndarray:
    """Return ``p_null`` with each nonzero count ``scale`` times as likely (where informative)."""
    p_null = np.asarray(p_null, dtype=float)
    detections = p_null[..., 1:] * scale
    total = detections.sum(axis=-1, keepdims=True)
    detections *= np.minimum(1.0, MAX_DETECTION_PROBABILITY / np.maximum(total, 1e-300))
    out = np.concatenate([1.0 - detections.sum(axis=-1, keepdims=True), detections], axis=-1)
    same = np.all(np.asarray(p_target) == p_null, axis=-1)
    out[same] = p_null[same]
    return out


class FalseAlarmMixture:
    """
    The evidence of a search under each false-alarm scale, and the belief it gives.

    Parameters
    ----------
    model : CountObservation
        The count model the searcher assumes.
    scales : sequence of float
        The factors (checked by :func:`check_false_alarm_scales`), equally likely a priori.
    hotspot_prior : float
        The prior that a cell without the face is a hotspot (module docstring); 0: none.
    hotspot_scale : float
        A hotspot's detections are this many times as likely as the model's null tables say.

    """

    def __init__(self, model: CountObservation, scales, hotspot_prior: float = 0.0,
                 hotspot_scale: float = DEFAULT_HOTSPOT_SCALE):
        self.scales = check_false_alarm_scales(scales)
        self.hotspot_prior = check_hotspot_prior(hotspot_prior)
        self.hotspot_scale = check_hotspot_scale(hotspot_scale)
        grid = model.grid
        nulls = [scaled_null(model.p_target, model.p_null, s) for s in self.scales]
        # R_s: target against the scaled null; G_s per cell: the scaled null against the model's.
        self._cell = [CountObservation(grid, model.p_target, n) for n in nulls]
        self._null = [CountObservation(grid, n, model.p_null) for n in nulls]
        self._cell_evidence = [StillEvidence(grid.n_cells) for _ in self.scales]
        self._null_evidence = [StillEvidence(grid.n_cells) for _ in self.scales]
        # A hotspot against the model's null (the scale's null is divided out in log_belief).
        self._hot = CountObservation(
            grid, scaled_null(model.p_target, model.p_null, self.hotspot_scale), model.p_null) \
            if self.hotspot_prior > 0 else None
        self._hot_evidence = StillEvidence(grid.n_cells)
        self.log_scale_prior = np.full(len(self.scales), -math.log(len(self.scales)))
        self.log_scale_posterior = self.log_scale_prior.copy()

    def reset(self) -> None:
        """Forget every frame (a new search, or the evidence counted afresh)."""
        for evidence in (*self._cell_evidence, *self._null_evidence, self._hot_evidence):
            evidence.reset()
        self.log_scale_posterior = self.log_scale_prior.copy()

    def add(self, observation: np.ndarray, fixation: int, information: np.ndarray) -> None:
        """
        Record one validated frame under every scale (``information`` as StillEvidence takes).

        A count that two tables both rule out says nothing here (term 0): the frame was
        checked against the model itself already.
        """
        for s in range(len(self.scales)):
            cell = self._cell[s].log_likelihood_ratio(observation, fixation, validate=False)
            null = self._null[s].log_likelihood_ratio(observation, fixation, validate=False)
            self._cell_evidence[s].add(np.nan_to_num(cell), information)
            self._null_evidence[s].add(np.nan_to_num(null), information)
        if self._hot is not None:
            hot = self._hot.log_likelihood_ratio(observation, fixation, validate=False)
            self._hot_evidence.add(np.nan_to_num(hot), information)

    def log_belief(self, base: np.ndarray, repeat_weight: float) -> np.ndarray:
        """
        Return the log belief of the cells (and absent) after the frames, marginal over scales.

        ``base`` is the log belief before the first recorded frame (N or N + 1 entries, the
        absent hypothesis last); :attr:`log_scale_posterior` is updated too.
        """
        n = self._cell_evidence[0].kept.size
        joint = np.empty((len(self.scales), base.size))
        rho = self.hotspot_prior
        hot = self._hot_evidence.log_likelihood_ratio(repeat_weight) if rho > 0 else None
        for s in range(len(self.scales)):
            cell = self._cell_evidence[s].log_likelihood_ratio(repeat_weight)
            null = self._null_evidence[s].log_likelihood_ratio(repeat_weight)
            if hot is not None:
                # log B_s per cell: background or hotspot, each against the scale's null.
                background = np.logaddexp(math.log1p(-rho), math.log(rho) + hot - null)
                cell = cell - background
                null = null + background
            joint[s] = base
            with np.errstate(invalid='ignore'):     # an excluded cell stays at -inf
                joint[s, :n] += cell
            joint[s] += null.sum() + self.log_scale_prior[s]
        peak = joint.max()
        with np.errstate(divide='ignore'):
            marginal = peak + np.log(np.exp(joint - peak).sum(axis=0))
            per_scale = peak + np.log(np.exp(joint - peak).sum(axis=1))
        self.log_scale_posterior = normalize_log(per_scale)
        return normalize_log(marginal)
