# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Belief over the target's cell: log-domain Bayes update, rewards and the MAP guess.

The observation model (paper eqs. 3-4): at fixation k, cell j gives ``o_j ~ N(d_jk, 1)`` if the
target is at j and ``N(0, 1)`` otherwise. The posterior (paper eq. 6, Najemnik & Geisler 2005
eq. 1) is ``log B_i += d_ik * (o_i - d_ik / 2)`` followed by renormalisation; a NaN observation
means "not observed" and contributes nothing. All functions work on a single belief (N,) or a
batch (episodes, N).
"""
from __future__ import annotations

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
    peak = np.max(log_belief, axis=-1, keepdims=True)
    log_belief -= peak
    log_belief -= np.log(np.sum(np.exp(log_belief), axis=-1, keepdims=True))
    return log_belief


def check_evidence(observation, n_cells: int) -> np.ndarray:
    """
    Validate one frame of evidence and return it as a float64 array of shape (N,).

    NaN entries are allowed (unobserved cells). A wrong length or any +/-inf makes the whole
    frame invalid.

    Raises
    ------
    EvidenceError
        With the reason, when the frame cannot be used.

    """
    obs = np.asarray(observation, dtype=float)
    if obs.ndim != 1 or obs.size != n_cells:
        raise EvidenceError(f'evidence has {obs.size} values in shape {obs.shape}, '
                            f'expected {n_cells}')
    if np.any(np.isinf(obs)):
        raise EvidenceError('evidence contains +/-inf')
    return obs


def log_likelihood(observation: np.ndarray, dprime: np.ndarray) -> np.ndarray:
    """
    Log-likelihood ratio term ``d_i * (o_i - d_i / 2)`` with NaN observations counted as 0.

    Parameters
    ----------
    observation : array (..., N)
        One observation per cell; NaN = not observed.
    dprime : array (..., N)
        ``d_ik`` of each cell i for the current fixation k.

    Raises
    ------
    EvidenceError
        If an observed cell's term is not a finite number: an observation of +/-inf, or one so
        large (about 1e308 / d') that the term overflows. Such a frame would turn the log belief
        into inf - inf = NaN, so it is refused whole.

    """
    with np.errstate(over='ignore', invalid='ignore'):
        term = dprime * (observation - 0.5 * dprime)
    term = np.where(np.isnan(observation), 0.0, term)
    bad = ~np.isfinite(term)
    if np.any(bad):
        i = np.flatnonzero(bad)[0]
        o, d = np.broadcast_to(observation, term.shape).flat[i], \
            np.broadcast_to(dprime, term.shape).flat[i]
        raise EvidenceError(f"evidence {o:.6g} at cell {i % term.shape[-1]} with d' = {d:.6g} "
                            f'gives a log-likelihood of {term.flat[i]}; the frame is refused')
    return term


def update_log_belief(log_belief: np.ndarray, observation: np.ndarray,
                      dprime: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """
    Posterior ``log B_i + d_i (o_i - d_i/2)``, renormalised (paper eq. 6).

    Parameters
    ----------
    log_belief : array (..., N)
        Current log belief (normalised).
    observation : array (..., N)
        The frame; NaN entries are unobserved cells and leave their term unchanged.
    dprime : array (..., N)
        ``d_ik`` for the fixation k the frame was taken at.
    out : array, optional
        Where to write the result (may be ``log_belief`` itself for an in-place update).

    Raises
    ------
    EvidenceError
        From :func:`log_likelihood`, before anything is written.

    """
    term = log_likelihood(observation, dprime)
    if out is None:
        out = np.array(log_belief, dtype=float, copy=True)
    elif out is not log_belief:
        out[...] = log_belief
    with np.errstate(over='ignore'):          # a sum below -1.8e308 is -inf: probability 0
        out += term
        return normalize_log(out)


def belief_from_log(log_belief: np.ndarray) -> np.ndarray:
    """Probabilities ``exp(log B)``; exact sums to 1 up to rounding."""
    return np.exp(log_belief)


def entropy(belief: np.ndarray) -> np.ndarray:
    """Shannon entropy ``-sum_i B_i log B_i`` in nats (0 log 0 = 0)."""
    b = np.asarray(belief, dtype=float)
    with np.errstate(divide='ignore', invalid='ignore'):
        terms = np.where(b > 0, b * np.log(np.where(b > 0, b, 1.0)), 0.0)
    return -np.sum(terms, axis=-1)


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

    This is the project-wide tie rule (DESIGN.md section 4), so runs are reproducible.
    """
    s = np.asarray(scores, dtype=float)
    peak = np.max(s, axis=-1, keepdims=True)
    near = s >= peak - rtol * np.abs(peak)
    return np.argmax(near, axis=-1)


def map_cell(belief: np.ndarray) -> np.ndarray:
    """Return the most likely cell (MAP guess) with the tie rule of :func:`argmax_ties_low`."""
    return argmax_ties_low(belief)


def percent_correct(belief: np.ndarray, target: np.ndarray) -> float:
    """Fraction of episodes whose MAP cell is the target (N-alternative forced choice)."""
    return float(np.mean(map_cell(belief) == np.asarray(target)))
