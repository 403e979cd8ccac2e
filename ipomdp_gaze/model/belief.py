# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Belief over the target's cell: the one Bayes step, rewards and the MAP guess.

The belief is kept in the log domain. Every consumer (controller, simulator, Gymnasium env,
``search``, training, benches) updates it with :func:`bayes_update`, adding the per-cell
log-likelihood ratio of a frame that an observation model (:mod:`ipomdp_gaze.model.observation`)
computed, then renormalising (paper eq. 6; docs/design.md section 1). All functions work on a
single belief (N,) or a batch (episodes, N).
"""
from __future__ import annotations

import math

from ipomdp_gaze.model.checks import short_repr
import numpy as np

TIE_RTOL = 1e-9


class EvidenceError(ValueError):
    """A frame of evidence that cannot be used (it is rejected, the belief is unchanged)."""


def uniform_log_belief(n_cells: int, episodes: int | None = None) -> np.ndarray:
    """Log of the uniform prior ``B_i = 1/N``, shape (N,) or (episodes, N)."""
    shape = (n_cells,) if episodes is None else (episodes, n_cells)
    return np.full(shape, -np.log(n_cells))


def normalize_log(log_belief: np.ndarray) -> np.ndarray:
    """Renormalise in place so that ``sum exp(log_belief) = 1`` (log-sum-exp); returns it."""
    if log_belief.ndim == 1:                    # one belief (the controller): scalar reductions
        log_belief -= log_belief.max()
        log_belief -= math.log(np.add.reduce(np.exp(log_belief)))
        return log_belief
    peak = np.max(log_belief, axis=-1, keepdims=True)
    log_belief -= peak
    log_belief -= np.log(np.sum(np.exp(log_belief), axis=-1, keepdims=True))
    return log_belief


def bayes_update(log_belief: np.ndarray, log_likelihood_ratio: np.ndarray,
                 out: np.ndarray | None = None) -> np.ndarray:
    """
    Posterior ``log B_i + l_i``, renormalised: the one Bayes step.

    ``l_i = log p(o | target at i) - log p(o | no target)`` is the frame's per-cell
    log-likelihood ratio from an observation model (terms common to every cell cancel in the
    normalisation, so the ratio is all the step needs).

    Parameters
    ----------
    log_belief : array (..., N)
        Current log belief (normalised).
    log_likelihood_ratio : array (..., N)
        The frame's terms; 0 for cells it says nothing about.
    out : array, optional
        Where to write the result (may be ``log_belief`` itself for an in-place update).

    """
    if out is None:
        out = np.array(log_belief, dtype=float, copy=True)
    elif out is not log_belief:
        out[...] = log_belief
    with np.errstate(over='ignore'):          # a sum below -1.8e308 is -inf: probability 0
        out += log_likelihood_ratio
        return normalize_log(out)


def entropy(belief: np.ndarray) -> np.ndarray:
    """Shannon entropy ``-sum_i B_i log B_i`` in nats (0 log 0 = 0)."""
    b = np.asarray(belief, dtype=float)
    positive = b > 0
    terms = np.zeros(b.shape)
    np.log(b, out=terms, where=positive)
    np.multiply(terms, b, out=terms, where=positive)
    return -np.sum(terms, axis=-1)


def entropy_of_log(log_belief: np.ndarray, cells: np.ndarray | None = None) -> float:
    """
    Shannon entropy in nats of one normalised log belief (N,): ``-sum_i B_i log B_i``.

    From the logs themselves, without taking the log of ``exp(log B)`` again (a third of the
    controller's per-frame cost on a 128x128 grid went there); cells at ``-inf`` count 0.
    ``cells``: ``exp`` of the first entries of ``log_belief`` when the caller has them already
    (a search session's cell probabilities), so they are not taken again.
    """
    log_b = np.asarray(log_belief, dtype=float)
    if cells is None:
        b = np.exp(log_b)
    elif cells.size == log_b.size:
        b = cells
    else:
        b = np.concatenate([cells, np.exp(log_b[cells.size:])])
    if not np.isfinite(log_b).all():
        keep = b > 0
        return float(-np.dot(b[keep], log_b[keep]))
    return float(-np.dot(b, log_b))


def infomax_reward(belief: np.ndarray) -> np.ndarray:
    """Infomax reward ``R(B) = sum_i B_i log B_i`` (negative entropy, paper eq. 8)."""
    return -entropy(belief)


def fixate_target_reward(belief: np.ndarray, fixation) -> np.ndarray:
    """Fixate-target reward ``R = B_k``: the belief at the fixated cell k."""
    b = np.asarray(belief)
    if b.ndim == 1:
        return b[int(fixation)]
    return np.take_along_axis(b, np.asarray(fixation)[:, None], axis=1)[:, 0]


def argmax_ties_low(scores: np.ndarray, rtol: float = TIE_RTOL) -> np.ndarray:
    """
    Return the argmax on the last axis; ties within ``rtol`` of the max go to the lowest index.

    This is the project-wide tie rule (docs/design.md section 4), so runs are reproducible.
    """
    s = np.asarray(scores, dtype=float)
    if s.ndim == 1:                             # one belief: scalar arithmetic, same numbers
        peak = s.max()
        return np.argmax(s >= peak - rtol * abs(peak))
    peak = np.max(s, axis=-1, keepdims=True)
    near = s >= peak - rtol * np.abs(peak)
    return np.argmax(near, axis=-1)


def map_cell(belief: np.ndarray) -> np.ndarray:
    """Return the most likely cell (MAP guess) with the tie rule of :func:`argmax_ties_low`."""
    return argmax_ties_low(belief)


def check_prior(prior, n_cells: int, shape: tuple[int, int] | None = None) -> np.ndarray:
    """
    Return a prior over the target's cell as a float array (N,) summing to 1.

    A ValueError names what is wrong: the length, a value that is negative or not finite, or a
    sum other than 1 (within 1e-6; a prior is not renormalised silently). Cells may be 0: the
    target is never there and the belief keeps them at 0.
    """
    try:                                    # a string, a mapping or ragged rows: one line
        values = np.asarray(prior)
    except (TypeError, ValueError):
        values = None
    if values is None or values.dtype.kind not in 'iuf':    # no text ('0.5'), no true/false
        raise ValueError(f'prior must be numbers, one per cell, got {type(prior).__name__} '
                         f'{short_repr(prior)}')
    if values.ndim == 2 and shape is not None and values.shape != tuple(shape):
        raise ValueError(f'prior must be (rows, cols) = {tuple(shape)} or ({n_cells},), got shape '
                         f'{values.shape}')
    values = values.astype(float).reshape(-1) if values.ndim == 2 else values.astype(float)
    if values.shape != (n_cells,):
        raise ValueError(f'prior must hold one probability per cell, {n_cells} values (rows x '
                         f'cols, row-major), got shape {np.shape(prior)}')
    for bad, rule in ((~np.isfinite(values), 'finite'), (values < 0, '>= 0')):
        if np.any(bad):         # a NaN first: it is neither negative nor positive
            raise ValueError(f'prior must be {rule} in every cell, got {values[bad][0]:g}')
    total = float(values.sum())
    if abs(total - 1.0) > 1e-6:
        raise ValueError(f'prior must sum to 1, got {total:.6g}')
    return values / total


def draw_cells(rng: np.random.Generator, n_cells: int, prior: np.ndarray | None = None,
               size=None):
    """
    Draw random cells from ``rng``: uniform, or from ``prior`` (N,), checked, summing to 1.

    The uniform draw is ``integers(0, N)``, the draw before priors existed, so a seed gives
    the targets it gave then; a prior draws with ``choice``.
    """
    if prior is None:
        return rng.integers(0, n_cells, size=size)
    return rng.choice(n_cells, size=size, p=prior)


def prior_from_weights(weights, shape: tuple[int, int] | None = None) -> np.ndarray:
    """
    Scale weights >= 0 (one per cell) to a prior summing to 1: a prior file's, ``belief.prior``.

    A ValueError says the first thing wrong, in this order (a NaN is neither negative nor
    positive: it is named as what it is), the cell named ``(row, col)`` of ``shape`` if given:
    a weight not finite, a weight below 0, then every weight 0. The caller names the setting.
    """
    weights = np.asarray(weights, dtype=float).reshape(-1)

    def cell(i: int) -> str:
        return f'cell {divmod(i, shape[1])}' if shape else f'weight {i + 1}'
    for bad, rule in ((~np.isfinite(weights), 'finite'), (weights < 0, '>= 0')):
        if np.any(bad):
            i = int(np.argmax(bad))
            raise ValueError(f'weights must be {rule}: {cell(i)} is {weights[i]:g}')
    if not weights.max() > 0:
        raise ValueError('weights must not all be 0 (the target would be in no cell)')
    weights = weights / weights.max()           # the sum of weights near 1e308 stays finite
    return weights / weights.sum()


def prior_is_uniform(prior) -> bool:
    """Return whether a prior over the cells is None or uniform (a uniform file is the default)."""
    if prior is None:
        return True
    values = np.asarray(prior, dtype=float).reshape(-1)
    return bool(np.allclose(values, 1.0 / values.size, rtol=1e-9, atol=0.0))


def is_reset_belief(belief, priors=()) -> bool:
    """
    Return whether a published belief is a reset's: uniform, or proportional to one of ``priors``.

    A search starts at the prior in force (``belief.prior``, else uniform) times ``1 - absent
    prior``, so a reset is told from a fixation's update by its shape, not its sum; ``priors``
    are probabilities (N,) (another size never matches; float32 messages: rtol 1e-5).
    """
    data = np.asarray(belief, dtype=float).reshape(-1)
    if data.size == 0:
        return False
    if np.ptp(data) == 0:
        return True
    total = data.sum()
    return bool(total > 0 and any(
        np.size(p) == data.size and np.allclose(data / total, np.reshape(p, -1), rtol=1e-5,
                                                atol=1e-9) for p in priors))
