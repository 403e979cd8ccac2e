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

import math
import operator

import numpy as np

TIE_RTOL = 1e-9
OVERFLOW_REASON = 'evidence too large: d * (o - d/2) overflows float64'


OVERFLOW_REASON = 'evidence too large: d * (o - d/2) overflows float64'


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
        raise EvidenceError(f'{OVERFLOW_REASON} at cell {i % term.shape[-1]} (o = {o:.6g}, '
                            f"d' = {d:.6g}, term {term.flat[i]}); the frame is refused")
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


def dprime_window(grid, table: np.ndarray, fixation: int) -> np.ndarray:
    """
    Return ``d_jk`` of every cell j for fixation k as a ``(rows, cols)`` view of the offset table.

    ``table`` is the ``(2R-1, 2C-1)`` d' table of :func:`ipomdp_gaze.fpoc.dprime_table`; entry
    ``[r_j - r_k + R-1, c_j - c_k + C-1]`` is cell j seen from k, so the cells of one fixation
    form the window starting at ``(R-1-r_k, C-1-c_k)``. No copy and no N x N matrix.
    """
    rows, cols = grid.rows, grid.cols
    r, c = grid.cell(fixation)
    return table[rows - 1 - r:2 * rows - 1 - r, cols - 1 - c:2 * cols - 1 - c]


def dprime_column(grid, table: np.ndarray, fixation: int, out: np.ndarray | None = None):
    """
    Column ``d[:, k]`` of :func:`ipomdp_gaze.fpoc.dprime_matrix`, shape (N,), from the table.

    Writes into ``out`` (shape (N,)) when given, so a caller can reuse one buffer.
    """
    window = dprime_window(grid, table, fixation)
    if out is None:
        return window.reshape(-1)
    out.reshape(grid.rows, grid.cols)[...] = window
    return out


class BeliefTracker:
    """
    One belief with preallocated buffers: the controller's allocation-free Bayes update.

    ``update(observation, fixation)`` applies paper eq. 6 in the log domain, reading ``d_.k``
    straight from the ``(2R-1, 2C-1)`` offset table (no N x N matrix) and writing only to
    buffers made here, so a message costs no array allocation. :attr:`belief` (probabilities)
    and :attr:`log_belief` are kept in step and are overwritten in place by every update and
    reset: copy them to keep a value. A controller does
    ``tracker.update(frame, fixation)`` then ``fixation = policy.decide(tracker.belief)``.

    Parameters
    ----------
    grid : Grid
        The visual array.
    dprime_table : array (2R-1, 2C-1)
        d' on the offset table (:func:`ipomdp_gaze.fpoc.dprime_table`).

    """

    def __init__(self, grid, dprime_table: np.ndarray):
        table = np.ascontiguousarray(dprime_table, dtype=float)
        if table.shape != grid.kernel_shape:
            raise ValueError(f'dprime_table must have shape {grid.kernel_shape} for a '
                             f'{grid.rows}x{grid.cols} grid, got {table.shape}')
        if not np.all(np.isfinite(table)) or np.any(table < 0):
            raise ValueError('dprime_table must be finite and >= 0')
        self.grid = grid
        self.table = table
        n = grid.n_cells
        self.log_belief = np.empty(n)
        self.belief = np.empty(n)
        self._term = np.empty(grid.shape)
        self._obs = np.empty(grid.shape)
        self._dprime = np.empty(grid.shape)
        self._nan = np.empty(grid.shape, dtype=bool)
        self._log_grid = self.log_belief.reshape(grid.shape)
        self.reset()

    def reset(self, log_belief=None) -> None:
        """Start again from the uniform prior, or from ``log_belief`` (N,), renormalised."""
        if log_belief is None:
            self.log_belief.fill(-np.log(self.grid.n_cells))
        else:
            value = np.asarray(log_belief, dtype=float)
            if value.shape != self.log_belief.shape or np.any(np.isnan(value)) \
                    or not np.any(np.isfinite(value)) or np.any(value == np.inf):
                raise ValueError(f'log_belief must be {self.grid.n_cells} values below +inf '
                                 'with at least one finite, no NaN')
            self.log_belief[...] = value
        self._normalize()

    def _normalize(self) -> None:
        log_b, b = self.log_belief, self.belief
        np.subtract(log_b, np.maximum.reduce(log_b), out=log_b)
        np.exp(log_b, out=b)
        total = np.add.reduce(b)
        np.subtract(log_b, math.log(total), out=log_b)
        np.multiply(b, 1.0 / total, out=b)

    def update(self, observation: np.ndarray, fixation: int) -> None:
        """
        Apply one frame taken at ``fixation``: ``log B_i += d_ik (o_i - d_ik / 2)``, renormalise.

        Parameters
        ----------
        observation : array (N,) or (rows, cols)
            One value per cell (float32 or float64, e.g. a zero-copy view of a message's data);
            NaN means "not observed" and leaves the cell's term out.
        fixation : int
            The cell the frame was taken at.

        Raises
        ------
        EvidenceError
            For a wrong size or any +/-inf; the belief is unchanged.
        ValueError
            For a fixation outside the grid.

        """
        grid = self.grid
        rows, cols = grid.rows, grid.cols
        obs = observation if isinstance(observation, np.ndarray) else np.asarray(observation,
                                                                                 dtype=float)
        if obs.size != rows * cols or obs.ndim not in (1, 2) or \
                (obs.ndim == 2 and obs.shape != (rows, cols)):
            raise EvidenceError(f'evidence has {obs.size} values in shape {obs.shape}, '
                                f'expected {rows * cols}')
        try:
            k = operator.index(fixation)
        except TypeError:
            raise ValueError(f'fixation must be an integer cell index, got {fixation!r}') from None
        if not 0 <= k < rows * cols:
            raise ValueError(f'fixation {fixation!r} is outside a {rows}x{cols} grid')
        if obs.dtype == np.float64 and obs.flags.c_contiguous:
            obs = obs.reshape(rows, cols)
        else:                                   # float32 messages: cast once into a buffer
            self._obs[...] = obs.reshape(rows, cols)
            obs = self._obs
        missing = not math.isfinite(np.add.reduce(obs, axis=None))   # NaN, +/-inf or overflow
        if missing:
            np.isinf(obs, out=self._nan)
            if self._nan.any():
                raise EvidenceError('evidence contains +/-inf')
        r, c = divmod(k, cols)
        r0, c0 = rows - 1 - r, cols - 1 - c
        # Copy d_.k out of the table first: a ufunc reading a strided 2-D window would allocate.
        d, term = self._dprime, self._term
        d[...] = self.table[r0:r0 + rows, c0:c0 + cols]
        np.multiply(d, -0.5, out=term)
        np.add(term, obs, out=term)
        np.multiply(term, d, out=term)
        if missing:
            np.isnan(term, out=self._nan)
            np.copyto(term, 0.0, where=self._nan)
        if not math.isfinite(np.add.reduce(term, axis=None)):
            np.isinf(term, out=self._nan)
            if self._nan.any():
                raise EvidenceError(OVERFLOW_REASON)
        np.add(self._log_grid, term, out=self._log_grid)
        self._normalize()

    def map_cell(self) -> int:
        """Return the most likely cell (tie rule of :func:`argmax_ties_low`)."""
        return int(argmax_ties_low(self.belief))
