# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Observation models: what a frame of evidence says about where the target is.

An observation model is the seam between the detector and the belief (docs/design.md section 1).
It answers two questions for a fixation k, on one frame (N,) or a batch (E, N):

- ``log_likelihood_ratio(observation, fixation)``: the per-cell term
  ``log p(o | target at i) - log p(o | no target anywhere)`` that the one Bayes step
  (:func:`ipomdp_gaze.belief.bayes_update`) adds to the log belief (cells whose observation is NaN
  were not observed and add 0);
- ``sample(targets, fixations, rng)``: frames drawn from the model, for simulation and training.

It also gives ``elm_kernel()``, the offset table of twice the Kullback-Leibler divergence between
the target and the null observation distributions, which is what ELM maximises in expectation.

:class:`GaussianObservation` is the paper's model (eqs. 3-4): ``o_j ~ N(d_jk, 1)`` at the target
and ``N(0, 1)`` elsewhere, with ``d_jk`` from an FPOC. Its log-likelihood ratio is
``d_jk (o_j - d_jk / 2)`` and ``2 KL = d^2``.
"""
from __future__ import annotations

import math
import operator

import numpy as np

from .belief import EvidenceError
from .fpoc import dprime_table, FPOC
from .grid import Grid

OVERFLOW_REASON = 'evidence too large: d * (o - d/2) overflows float64'
# Largest grid whose (fixation, cell) d' matrix is kept for batched look-ups (8 * N^2 bytes).
MATRIX_MAX_CELLS = 4096


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


def gaussian_log_likelihood_ratio(observation: np.ndarray, dprime: np.ndarray,
                                  validate: bool = True) -> np.ndarray:
    """
    Log-likelihood ratio ``d_i (o_i - d_i / 2)`` of the Gaussian model, NaN observations as 0.

    Parameters
    ----------
    observation : array (..., N)
        One observation per cell; NaN = not observed.
    dprime : array (..., N)
        ``d_ik`` of each cell i for the fixation k the frame was taken at.
    validate : bool
        Check the frame (NaN cells count 0; a term that is not finite refuses the frame). Only
        frames drawn by :meth:`GaussianObservation.sample`, finite by construction, skip it.

    Raises
    ------
    EvidenceError
        If an observed cell's term is not a finite number: an observation of +/-inf, or one so
        large (about 1e308 / d') that the term overflows. Such a frame would turn the log belief
        into inf - inf = NaN, so it is refused whole.

    """
    if not validate:
        return dprime * (observation - 0.5 * dprime)
    with np.errstate(over='ignore', invalid='ignore'):
        term = dprime * (observation - 0.5 * dprime)
        if math.isfinite(np.add.reduce(term, axis=None)):   # every cell observed and finite
            return term
    term = np.where(np.isnan(observation), 0.0, term)
    bad = ~np.isfinite(term)
    if np.any(bad):
        i = np.flatnonzero(bad)[0]
        o, d = np.broadcast_to(observation, term.shape).flat[i], \
            np.broadcast_to(dprime, term.shape).flat[i]
        raise EvidenceError(f'{OVERFLOW_REASON} at cell {i % term.shape[-1]} (o = {o:.6g}, '
                            f"d' = {d:.6g}, term {term.flat[i]}); the frame is refused")
    return term


class GaussianObservation:
    """
    The paper's observation model: unit-variance Gaussian evidence with FPOC means.

    Parameters
    ----------
    grid : Grid
        The visual array.
    fpoc : FPOC
        Detectability ``d'`` as a function of the offset from fixation.

    Notes
    -----
    ``d_jk`` is read from the ``(2R-1, 2C-1)`` offset table
    (:func:`ipomdp_gaze.fpoc.dprime_table`): the cells seen from k are the ``rows x cols``
    window starting at ``(R-1-r_k, C-1-c_k)``, so a single frame never needs an N x N matrix.
    Batches of fixations use the N x N matrix ``d[k, j]``, built on first use for grids of up
    to :data:`MATRIX_MAX_CELLS` cells.

    """

    name = 'gaussian'

    def __init__(self, grid: Grid, fpoc: FPOC):
        if not isinstance(fpoc, FPOC):
            raise TypeError(f'fpoc must be an FPOC, got {type(fpoc).__name__}')
        self.grid = grid
        self.fpoc = fpoc
        self.table = dprime_table(grid, fpoc)
        self._by_fixation = None

    def __repr__(self):
        return f'GaussianObservation({self.grid!r}, {self.fpoc!r})'

    def __eq__(self, other):
        return isinstance(other, GaussianObservation) and self.grid == other.grid \
            and self.fpoc == other.fpoc

    def __hash__(self):
        return hash((self.grid, self.fpoc))

    def to_dict(self) -> dict:
        """``{'model': 'gaussian', 'fpoc': {...}}``."""
        return {'model': self.name, 'fpoc': self.fpoc.to_dict()}

    # -- d' ------------------------------------------------------------------------------
    def dprime_window(self, fixation: int) -> np.ndarray:
        """``d_jk`` of every cell j for one fixation k as a ``(rows, cols)`` view (no copy)."""
        rows, cols = self.grid.shape
        r, c = divmod(self._fixation(fixation), cols)
        return self.table[rows - 1 - r:2 * rows - 1 - r, cols - 1 - c:2 * cols - 1 - c]

    def dprime_by_fixation(self) -> np.ndarray:
        """Return the N x N matrix ``d[k, j]`` (fixation k, cell j), built once (small grids)."""
        if self._by_fixation is None:
            n = self.grid.n_cells
            if n > MATRIX_MAX_CELLS:
                raise ValueError(f'a batch of fixations needs an N x N matrix; a '
                                 f'{self.grid.rows}x{self.grid.cols} grid has more than '
                                 f'{MATRIX_MAX_CELLS} cells')
            ri, ci = self.grid.pair_offset_index()
            self._by_fixation = np.ascontiguousarray(self.table[ri, ci])
        return self._by_fixation

    def dprime(self, fixation) -> np.ndarray:
        """``d_jk`` of every cell j: shape (N,) for one fixation, (E, N) for E fixations."""
        if np.ndim(fixation) == 0:
            return self.dprime_window(fixation).reshape(-1)
        return self.dprime_by_fixation()[np.asarray(fixation, dtype=np.intp)]

    def observed(self, fixation: int) -> np.ndarray:
        """Cells a frame from ``fixation`` says anything about (``d' > 0``), shape (N,)."""
        return self.dprime(fixation) > 0

    def elm_kernel(self) -> np.ndarray:
        """Return ELM's kernel on the offset table: ``2 KL(N(d, 1) || N(0, 1)) = d^2``."""
        return self.table ** 2

    def _fixation(self, fixation) -> int:
        try:
            k = operator.index(fixation)
        except TypeError:
            raise ValueError(f'fixation must be an integer cell index, got {fixation!r}') from None
        if not 0 <= k < self.grid.n_cells:
            raise ValueError(f'fixation {fixation!r} is outside a {self.grid.rows}x'
                             f'{self.grid.cols} grid')
        return k

    # -- the model -----------------------------------------------------------------------
    def log_likelihood_ratio(self, observation, fixation, validate: bool = True) -> np.ndarray:
        """
        Per-cell term ``d_ik (o_i - d_ik / 2)`` of frames taken at ``fixation``.

        Parameters
        ----------
        observation : array (N,) or (E, N)
            One frame, or one frame per episode; NaN = not observed.
        fixation : int or array (E,)
            Where each frame was taken.
        validate : bool
            See :func:`gaussian_log_likelihood_ratio`.

        Raises
        ------
        EvidenceError
            For a frame that cannot be used (nothing is changed anywhere).

        """
        return gaussian_log_likelihood_ratio(observation, self.dprime(fixation), validate)

    def sample(self, targets, fixations, rng: np.random.Generator) -> np.ndarray:
        """
        Draw frames: ``N(0, 1)`` everywhere plus ``d_target,k`` at each target.

        ``targets`` and ``fixations`` are scalars (one frame (N,)) or arrays (E,) (frames (E, N)).
        The draws are ``rng.standard_normal`` of the frames' shape, so a seeded stream gives the
        same noise to every policy (common random numbers).
        """
        n = self.grid.n_cells
        if np.ndim(targets) == 0:
            obs = rng.standard_normal(n)
            target = int(targets)
            obs[target] += self.dprime_window(fixations).flat[target]
            return obs
        targets = np.asarray(targets)
        obs = rng.standard_normal((targets.size, n))
        obs[np.arange(targets.size), targets] += self.dprime_by_fixation()[
            np.asarray(fixations, dtype=np.intp), targets]
        return obs


def as_observation(grid: Grid, model) -> GaussianObservation:
    """Return ``model`` if it is an observation model, or the Gaussian model of an FPOC."""
    if isinstance(model, FPOC):
        return GaussianObservation(grid, model)
    if not hasattr(model, 'log_likelihood_ratio'):
        raise TypeError(f'expected an observation model or an FPOC, got {type(model).__name__}')
    return model
