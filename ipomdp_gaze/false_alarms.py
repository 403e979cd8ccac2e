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
"""
from __future__ import annotations

import math

import numpy as np

from .belief import normalize_log
from .observation import CountObservation
from .still_evidence import StillEvidence

MAX_SCALES = 8
# A scaled null table never gives a cell a detection with more than this probability.
MAX_DETECTION_PROBABILITY = 0.95


def check_false_alarm_scales(value, name: str = 'false_alarm_scales') -> tuple:
    """Return the scales as a sorted tuple of floats, or raise ValueError naming ``name``."""
    try:
        scales = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        scales = ()
    if not 1 <= len(scales) <= MAX_SCALES or len(set(scales)) != len(scales) \
            or not all(math.isfinite(s) and s > 0 for s in scales):
        raise ValueError(f'{name} must be 1 to {MAX_SCALES} distinct positive factors of the '
                         f"model's false-alarm rates ([1.0]: the rates as calibrated), got "
                         f'{value!r}')
    return tuple(sorted(scales))


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

    """

    def __init__(self, model: CountObservation, scales):
        self.scales = check_false_alarm_scales(scales)
        grid = model.grid
        nulls = [scaled_null(model.p_target, model.p_null, s) for s in self.scales]
        # R_s: target against the scaled null; G_s per cell: the scaled null against the model's.
        self._cell = [CountObservation(grid, model.p_target, n) for n in nulls]
        self._null = [CountObservation(grid, n, model.p_null) for n in nulls]
        self._cell_evidence = [StillEvidence(grid.n_cells) for _ in self.scales]
        self._null_evidence = [StillEvidence(grid.n_cells) for _ in self.scales]
        self.log_scale_prior = np.full(len(self.scales), -math.log(len(self.scales)))
        self.log_scale_posterior = self.log_scale_prior.copy()

    def reset(self) -> None:
        """Forget every frame (a new search, or the evidence counted afresh)."""
        for evidence in (*self._cell_evidence, *self._null_evidence):
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

    def log_belief(self, base: np.ndarray, repeat_weight: float) -> np.ndarray:
        """
        Return the log belief of the cells (and absent) after the frames, marginal over scales.

        ``base`` is the log belief before the first recorded frame (N or N + 1 entries, the
        absent hypothesis last); :attr:`log_scale_posterior` is updated too.
        """
        n = self._cell_evidence[0].kept.size
        joint = np.empty((len(self.scales), base.size))
        for s in range(len(self.scales)):
            joint[s] = base
            with np.errstate(invalid='ignore'):     # an excluded cell stays at -inf
                joint[s, :n] += self._cell_evidence[s].log_likelihood_ratio(repeat_weight)
            joint[s] += self._null_evidence[s].log_likelihood_ratio(repeat_weight).sum() \
                + self.log_scale_prior[s]
        peak = joint.max()
        with np.errstate(divide='ignore'):
            marginal = peak + np.log(np.exp(joint - peak).sum(axis=0))
            per_scale = peak + np.log(np.exp(joint - peak).sum(axis=1))
        self.log_scale_posterior = normalize_log(per_scale)
        return normalize_log(marginal)
