# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Observation models: what a frame of evidence says about where the target is.

An observation model is the seam between the detector and the belief (docs/design.md section 1).
It answers two questions for a fixation k, on one frame (N,) or a batch (E, N):

- ``log_likelihood_ratio(observation, fixation)``: the per-cell term
  ``log p(o | target at i) - log p(o | no target anywhere)`` that the one Bayes step
  (:func:`ipomdp_gaze.model.belief.bayes_update`) adds to the log belief (cells whose observation
  is NaN
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

from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.fpoc import dprime_table, FPOC
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.wording import counted
import numpy as np

OVERFLOW_REASON = 'evidence too large: d * (o - d/2) overflows float64'
# Largest grid whose (fixation, cell) d' matrix is kept for batched look-ups (8 * N^2 bytes).
MATRIX_MAX_CELLS = 4096
# Largest grid whose single-fixation look-ups read that matrix's rows too (contiguous, no copy;
# 512 KiB at most), built on the first frame: a frame's d' was a strided window copied each time.
ROW_MAX_CELLS = 256
# Log-likelihood ratio of a count one hypothesis forbids: decisive, but finite.
MAX_LOG_RATIO = 50.0
# Largest d' the simulator draws frames for: a frame's term d (o - d/2) overflows from about
# d' = 1.9e154, and from about 1e153 a few frames push the log belief to -inf, where the reward
# sum B log B is NaN (0 * -inf); at 1e150 that takes ~1e8 frames.
SAMPLE_MAX_DPRIME = 1e150


def _numbers(observation) -> np.ndarray:
    """Return evidence as a float64 array; strings or objects are an :class:`EvidenceError`."""
    try:
        return np.asarray(observation, dtype=float)
    except (TypeError, ValueError):
        raise EvidenceError('evidence must be numbers') from None


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
    obs = _numbers(observation)
    if obs.ndim != 1 or obs.size != n_cells:
        raise EvidenceError(f'evidence has {counted(obs.size, "value")} in shape {obs.shape}, '
                            f'expected {n_cells}: shape ({n_cells},), one per cell, row-major')
    if np.any(np.isinf(obs)):
        raise EvidenceError('evidence contains +/-inf')
    return obs


def check_frames_shape(observation, n_cells: int) -> np.ndarray:
    """
    Return frames as float64 of shape ``(N,)`` or ``(E, N)``: one value per cell, row-major.

    Raises
    ------
    EvidenceError
        For any other shape (a frame of another grid would otherwise broadcast against this
        one's cells).

    """
    if type(observation) is np.ndarray and observation.dtype == np.float64 \
            and observation.shape == (n_cells,):
        return observation                      # a checked frame (the sessions'): as it is
    obs = _numbers(observation)
    if obs.ndim not in (1, 2) or obs.shape[-1] != n_cells:
        raise EvidenceError(f'evidence has shape {obs.shape}, expected ({n_cells},) or '
                            f'(episodes, {n_cells}): one value per cell, row-major')
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


def _fixation_index(grid: Grid, fixation) -> int:
    """Check a single fixation: an integer cell index inside ``grid`` (a bool is none)."""
    try:
        if isinstance(fixation, bool):
            raise TypeError(fixation)
        k = operator.index(fixation)
    except TypeError:
        raise ValueError(f'fixation must be an integer cell index, got {fixation!r}') from None
    if not 0 <= k < grid.n_cells:
        raise ValueError(f'fixation {fixation!r} is outside a {grid.rows}x{grid.cols} grid')
    return k


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
    (:func:`ipomdp_gaze.model.fpoc.dprime_table`): the cells seen from k are the ``rows x cols``
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
        r, c = divmod(_fixation_index(self.grid, fixation), self.grid.cols)
        return self.grid.fixation_window(self.table, r, c)

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
            self._by_fixation.flags.writeable = False      # its rows are handed out
        return self._by_fixation

    def dprime(self, fixation) -> np.ndarray:
        """``d_jk`` of every cell j: shape (N,) for one fixation, (E, N) for E fixations."""
        if np.ndim(fixation) == 0:
            if self.grid.n_cells <= ROW_MAX_CELLS:
                return self.dprime_by_fixation()[_fixation_index(self.grid, fixation)]
            return self.dprime_window(fixation).reshape(-1)
        return self.dprime_by_fixation()[np.asarray(fixation, dtype=np.intp)]

    def check_sampling(self) -> None:
        """
        Refuse (ValueError) a d' so large that a frame drawn by :meth:`sample` overflows.

        The simulator and training apply drawn frames unchecked (``validate=False``): far above
        :data:`SAMPLE_MAX_DPRIME` the term ``d (o - d/2)`` of such a frame is +/-inf, the log
        belief turns to NaN (inf - inf) and every guess is scored wrong without a word.
        """
        d_max = float(self.table.max())
        if d_max > SAMPLE_MAX_DPRIME:
            raise ValueError(f"d' up to {SAMPLE_MAX_DPRIME:g} can be simulated, the FPOC gives "
                             f"{d_max:.6g}: the drawn frames' terms d (o - d/2) would overflow "
                             'float64 (or push the log belief to -inf)')

    def observed(self, fixation: int) -> np.ndarray:
        """Cells a frame from ``fixation`` says anything about (``d' > 0``), shape (N,)."""
        return self.dprime(fixation) > 0

    def elm_kernel(self) -> np.ndarray:
        """
        Return ELM's kernel on the offset table: ``2 KL(N(d, 1) || N(0, 1)) = d^2``.

        A d' above about 1.3e154 squares to inf, which the policy refuses (``kernel must be
        finite``), without a numpy warning.
        """
        with np.errstate(over='ignore'):
            return self.table ** 2

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
        if validate:
            observation = check_frames_shape(observation, self.grid.n_cells)
        return gaussian_log_likelihood_ratio(observation, self.dprime(fixation), validate)

    def sample(self, targets, fixations, rng: np.random.Generator,
               present=None) -> np.ndarray:
        """
        Draw frames: ``N(0, 1)`` everywhere plus ``d_target,k`` at each target.

        ``targets`` and ``fixations`` are scalars (one frame (N,)) or arrays (E,) (frames (E, N)).
        The draws are ``rng.standard_normal`` of the frames' shape, so a seeded stream gives the
        same noise to every policy (common random numbers). ``present`` (bool, or (E,) bools)
        marks scenes that hold their target; an empty scene's frame is pure null noise, drawn
        the same way (its ``targets`` entry is ignored). Default: every scene has its target.
        """
        n = self.grid.n_cells
        if np.ndim(targets) == 0:
            obs = rng.standard_normal(n)
            target = int(targets)
            if present is None or present:
                obs[target] += self.dprime_window(fixations).flat[target]
            return obs
        targets = np.asarray(targets)
        obs = rng.standard_normal((targets.size, n))
        signal = self.dprime_by_fixation()[np.asarray(fixations, dtype=np.intp), targets]
        if present is not None:
            signal = np.where(present, signal, 0.0)
        obs[np.arange(targets.size), targets] += signal
        return obs


def _distributions(name: str, table, shape_problem, atol: float) -> np.ndarray:
    """
    Check a table of count distributions (counts on the last axis); return it normalised.

    ``shape_problem(shape)`` returns what is wrong with the shape, or ''. Entries must be
    finite and non-negative, and each distribution must sum to 1 within ``atol``.
    """
    try:
        a = np.array(table, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f'{name} table must be numbers') from None
    problem = shape_problem(a.shape)
    if problem:
        raise ValueError(f'{name} table must {problem}, got shape {a.shape}')
    bad = np.argwhere(~np.isfinite(a) | (a < 0))
    if bad.size:
        *offset, c = (int(x) for x in bad[0])
        where = f'offset ({offset[0]}, {offset[1]}) ' if offset else ''
        raise ValueError(f'{name} table must be finite and >= 0: {where}count {c} is '
                         f'{a[tuple(bad[0])]}')
    with np.errstate(over='ignore'):            # entries near the float limit: inf, refused
        total = a.sum(axis=-1)
    off = np.argwhere(np.abs(np.atleast_1d(total) - 1.0) > atol)
    if off.size:
        if a.ndim == 1:
            raise ValueError(f'{name} table must sum to 1 over counts, got {float(total):.9g}')
        dr, dc = (int(x) for x in off[0])
        raise ValueError(f'{name} table must sum to 1 over counts at every offset: offset '
                         f'({dr}, {dc}) sums to {total[dr, dc]:.9g}')
    return a / total[..., None]


def check_count_tables(p_target, p_null, grid: Grid, atol: float = 1e-6):
    """
    Validate the two count tables of a :class:`CountObservation`; return them as float64.

    Both have shape ``(rows, cols, K)``: entry ``[|dr|, |dc|, c]`` is the probability of count c
    in a cell ``|dr|`` rows and ``|dc|`` columns from the fixation, with the target in that cell
    (``p_target``) or not (``p_null``). Every entry must be finite and non-negative, every
    offset's K entries must sum to 1 (within ``atol``), and K >= 2.

    Raises
    ------
    ValueError
        Naming the table, the offset and the problem.

    """
    def shape_problem(shape):
        if len(shape) != 3 or shape[:2] != grid.shape or shape[2] < 2:
            return (f'have shape ({grid.rows}, {grid.cols}, K) with K >= 2 (offsets |dr|, '
                    f'|dc| of a {grid.rows}x{grid.cols} grid, then counts)')
        return ''

    target, null = (_distributions(name, table, shape_problem, atol)
                    for name, table in (('target', p_target), ('null', p_null)))
    if target.shape != null.shape:
        raise ValueError(f'target and null tables must have the same shape, got '
                         f'{target.shape} and {null.shape}')
    return target, null


def check_scan_tables(scan_target, scan_null, max_count: int, atol: float = 1e-6):
    """
    Validate the scan tables of a :class:`CountObservation`; return them as float64 (K,) each.

    ``scan_target[c]`` and ``scan_null[c]`` are the probabilities of count c in a cell of the
    one-time whole-image scan with and without the target in it (no offset: the scan does not
    depend on the fixation). Same rules as :func:`check_count_tables`; K must be the tables'.

    Raises
    ------
    ValueError
        Naming the table and the problem.

    """
    def shape_problem(shape):
        return ('' if shape == (max_count + 1,) else
                f'have K = {max_count + 1} entries (one per count, as the fixation tables)')

    return tuple(_distributions(name, table, shape_problem, atol)
                 for name, table in (('scan target', scan_target), ('scan null', scan_null)))


class CountObservation:
    """
    A count model learned from a real detector (docs/design.md section 6).

    The frame of fixation k holds one detection count per cell (NaN = not observed). A cell
    ``(|dr|, |dc|)`` from the fixation shows count c with probability ``p_target[|dr|, |dc|, c]``
    if the target is in it and ``p_null[|dr|, |dc|, c]`` otherwise, independently across cells
    (naive Bayes); counts above ``K - 1`` are clipped to ``K - 1``. The log-likelihood ratio of a
    cell is ``log p_target(c | offset) - log p_null(c | offset)``, and ELM's kernel is
    ``2 KL(p_target || p_null)`` per offset. The Gaussian model is the special case of
    continuous ``o``; both plug into the same Bayes step.

    Parameters
    ----------
    grid : Grid
        The visual array the tables were measured on.
    p_target, p_null : array (rows, cols, K)
        The count tables (see :func:`check_count_tables`). A zero probability is allowed: a
        count impossible under both hypotheses is refused as evidence, one impossible under one
        hypothesis rules it out (log ratio -inf or +inf, clipped to +/- :data:`MAX_LOG_RATIO`).
    meta : dict, optional
        Where the model came from (image size, fovea, detector, calibration): kept as given.
    scan_target, scan_null : array (K,), optional
        The tables of the one-time whole-image scan (:meth:`scan_log_likelihood_ratio`, a fovea
        with ``scan_once``); both or neither (see :func:`check_scan_tables`).

    """

    name = 'counts'

    def __init__(self, grid: Grid, p_target, p_null, meta: dict | None = None,
                 scan_target=None, scan_null=None):
        self.grid = grid
        self.p_target, self.p_null = check_count_tables(p_target, p_null, grid)
        self.max_count = self.p_target.shape[2] - 1
        if (scan_target is None) != (scan_null is None):
            raise ValueError('scan tables come in pairs: give both scan_target and scan_null '
                             'or neither')
        self.scan_target = self.scan_null = self._scan_ratio = None
        if scan_target is not None:
            self.scan_target, self.scan_null = check_scan_tables(scan_target, scan_null,
                                                                 self.max_count)
            with np.errstate(divide='ignore', invalid='ignore'):
                ratio = np.log(self.scan_target) - np.log(self.scan_null)
            self._scan_ratio = np.where((self.scan_target == 0) & (self.scan_null == 0), np.nan,
                                        np.clip(ratio, -MAX_LOG_RATIO, MAX_LOG_RATIO))
        self.meta = dict(meta or {})
        rows, cols, k = self.p_target.shape
        with np.errstate(divide='ignore', invalid='ignore'):
            ratio = np.log(self.p_target) - np.log(self.p_null)
        both_zero = (self.p_target == 0) & (self.p_null == 0)
        ratio = np.where(both_zero, np.nan, np.clip(ratio, -MAX_LOG_RATIO, MAX_LOG_RATIO))
        # Offsets as a (2R-1, 2C-1) table: entry [dr + R-1, dc + C-1] = offset (|dr|, |dc|).
        dr = np.abs(np.arange(-(rows - 1), rows))
        dc = np.abs(np.arange(-(cols - 1), cols))
        self._offset_id = dr[:, None] * cols + dc[None, :]
        self._ratio = ratio.reshape(rows * cols, k)             # [offset id, count]
        self._cdf = {'target': np.cumsum(self.p_target.reshape(rows * cols, k), axis=1),
                     'null': np.cumsum(self.p_null.reshape(rows * cols, k), axis=1)}
        self._pair_offsets = None
        self._informative = np.any(self.p_target != self.p_null, axis=2).reshape(-1)

    def __repr__(self):
        scan = ', with scan' if self.has_scan else ''
        return (f'CountObservation({self.grid.rows}x{self.grid.cols} grid, '
                f'K={self.max_count + 1}{scan})')

    def __eq__(self, other):
        if not isinstance(other, CountObservation) or self.grid.shape != other.grid.shape \
                or self.has_scan != other.has_scan:
            return False
        same = np.array_equal(self.p_target, other.p_target) \
            and np.array_equal(self.p_null, other.p_null)
        if self.has_scan:
            same = same and np.array_equal(self.scan_target, other.scan_target) \
                and np.array_equal(self.scan_null, other.scan_null)
        return same

    def __hash__(self):
        scan = (self.scan_target.tobytes(), self.scan_null.tobytes()) if self.has_scan else ()
        return hash((self.grid.shape, self.p_target.tobytes(), self.p_null.tobytes()) + scan)

    @property
    def has_scan(self) -> bool:
        """Whether the model has the tables of a one-time whole-image scan."""
        return self.scan_target is not None

    def to_dict(self) -> dict:
        """``{'model': 'counts', 'max_count': K-1, ...meta}``: what a policy file records."""
        return {'model': self.name, 'max_count': self.max_count, **self.meta}

    # -- offsets ---------------------------------------------------------------------------
    def offsets(self, fixation) -> np.ndarray:
        """Offset id ``|dr| * cols + |dc|`` of every cell: (N,) for one fixation, (E, N) for E."""
        rows, cols = self.grid.shape
        if np.ndim(fixation) == 0:
            r, c = divmod(_fixation_index(self.grid, fixation), cols)
            return self.grid.fixation_window(self._offset_id, r, c).reshape(-1)
        if self._pair_offsets is None:
            if self.grid.n_cells > MATRIX_MAX_CELLS:
                raise ValueError(f'a batch of fixations needs an N x N offset table; a '
                                 f'{rows}x{cols} grid has more than {MATRIX_MAX_CELLS} cells')
            ri, ci = self.grid.pair_offset_index()            # [k, j]
            self._pair_offsets = np.ascontiguousarray(self._offset_id[ri, ci])
        return self._pair_offsets[np.asarray(fixation, dtype=np.intp)]

    def observed(self, fixation: int) -> np.ndarray:
        """Cells whose count says anything at this fixation (tables differ there), shape (N,)."""
        return self._informative[self.offsets(fixation)]

    def elm_kernel(self) -> np.ndarray:
        """Return ELM's kernel on the ``(2R-1, 2C-1)`` offset table: ``2 KL(p_t || p_n)``."""
        with np.errstate(divide='ignore', invalid='ignore'):
            terms = np.where(self.p_target > 0, self.p_target
                             * (np.log(self.p_target) - np.log(self.p_null)), 0.0)
        kl = np.minimum(terms.sum(axis=2), MAX_LOG_RATIO)      # p_null = 0 where p_target > 0
        return 2.0 * kl.reshape(-1)[self._offset_id]

    # -- the model -------------------------------------------------------------------------
    def counts(self, observation, validate: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """
        Integer counts clipped to ``0..K-1`` and the mask of unobserved (NaN) cells.

        Raises
        ------
        EvidenceError
            For a negative, non-integer or non-finite (other than NaN) count.

        """
        obs = check_frames_shape(observation, self.grid.n_cells) if validate else \
            np.asarray(observation, dtype=float)
        missing = np.isnan(obs)
        if validate:
            bad = ~missing & (~np.isfinite(obs) | (obs < 0) | (obs != np.floor(obs)))
            if np.any(bad):
                i = int(np.flatnonzero(bad)[0])
                raise EvidenceError(f'counts must be integers >= 0 (NaN = not observed): cell '
                                    f'{i % obs.shape[-1]} is {obs.flat[i]!r}')
        counts = np.where(missing, 0.0, np.minimum(obs, self.max_count)).astype(np.intp)
        return counts, missing

    def log_likelihood_ratio(self, observation, fixation, validate: bool = True) -> np.ndarray:
        """
        Per-cell term ``log p_target(c_i | offset_ik) - log p_null(c_i | offset_ik)``.

        Parameters
        ----------
        observation : array (N,) or (E, N)
            Counts per cell (clipped to ``K - 1``); NaN = not observed (term 0).
        fixation : int or array (E,)
            Where each frame was taken.
        validate : bool
            Check the counts (only frames from :meth:`sample` skip it).

        Raises
        ------
        EvidenceError
            For invalid counts, or a count that neither hypothesis allows at its offset.

        """
        counts, missing = self.counts(observation, validate)
        return self._terms(self._ratio[self.offsets(fixation), counts], counts, missing,
                           validate, 'count')

    def scan_log_likelihood_ratio(self, counts, validate: bool = True) -> np.ndarray:
        """
        Per-cell term of the whole-image scan: ``log scan_target(c_i) - log scan_null(c_i)``.

        The scan is one observation per image, taken before the first fixation; its counts
        are clipped to ``K - 1`` like a frame's, NaN = not observed (term 0).

        Raises
        ------
        ValueError
            If the model has no scan tables.
        EvidenceError
            For invalid counts, or a count neither hypothesis allows.

        """
        if not self.has_scan:
            raise ValueError('this count model has no scan tables: it was measured without a '
                             'whole-image scan (fovea scan_once false)')
        counts, missing = self.counts(counts, validate)
        return self._terms(self._scan_ratio[counts], counts, missing, validate, 'scan count')

    @staticmethod
    def _terms(term: np.ndarray, counts: np.ndarray, missing: np.ndarray, validate: bool,
               what: str) -> np.ndarray:
        """Zero the unobserved cells' terms; refuse a count neither hypothesis allows (NaN)."""
        term[missing] = 0.0
        if validate and np.any(np.isnan(term)):
            i = int(np.flatnonzero(np.isnan(term))[0])
            raise EvidenceError(f'{what} {counts.flat[i]} at cell {i % counts.shape[-1]} has '
                                f'probability 0 with and without the target; the frame is '
                                f'refused')
        return term

    def sample(self, targets, fixations, rng: np.random.Generator,
               present=None) -> np.ndarray:
        """
        Draw count frames: each cell from ``p_null`` at its offset, the target from ``p_target``.

        One uniform draw per cell (``rng.random`` of the frames' shape) is turned into a count
        by the inverse CDF, so a seeded stream gives every policy the same draws (common random
        numbers). Scalars give one frame (N,), arrays (E,) give (E, N); counts are float64.
        ``present`` (bool, or (E,) bools) marks scenes that hold their target; an empty scene
        draws every cell from ``p_null`` with the same uniforms. Default: every scene does.
        """
        single = np.ndim(targets) == 0
        targets = np.atleast_1d(np.asarray(targets, dtype=np.intp))
        fixations = np.atleast_1d(np.asarray(fixations, dtype=np.intp))
        if single:
            offsets = self.offsets(int(fixations[0]))[None, :]
        else:
            offsets = self.offsets(fixations)
        u = rng.random(offsets.shape)
        frames = np.zeros(offsets.shape)
        cdf_null = self._cdf['null']
        for c in range(self.max_count):
            frames += u > cdf_null[offsets, c]
        rows = np.arange(targets.size)
        if present is not None:
            rows = rows[np.broadcast_to(np.asarray(present, dtype=bool), rows.shape)]
            targets = targets[rows]
        u_t, off_t = u[rows, targets], offsets[rows, targets]
        frames[rows, targets] = np.sum(u_t[:, None] > self._cdf['target'][off_t, :-1], axis=1)
        return frames[0] if single else frames

    def sample_scan(self, targets, rng: np.random.Generator, present=None) -> np.ndarray:
        """
        Draw one-time scan frames: each cell from ``scan_null``, the target from ``scan_target``.

        As :meth:`sample` (one uniform per cell, inverse CDF, ``present`` for empty scenes), with
        the position-independent scan tables; scalars give (N,), arrays (E,) give (E, N).

        Raises
        ------
        ValueError
            If the model has no scan tables.

        """
        if not self.has_scan:
            raise ValueError('this count model has no scan tables: it was measured without a '
                             'whole-image scan (fovea scan_once false)')
        single = np.ndim(targets) == 0
        targets = np.atleast_1d(np.asarray(targets, dtype=np.intp))
        u = rng.random((targets.size, self.grid.n_cells))
        frames = np.searchsorted(np.cumsum(self.scan_null)[:-1], u, side='left').astype(float)
        rows = np.arange(targets.size)
        if present is not None:
            rows = rows[np.broadcast_to(np.asarray(present, dtype=bool), rows.shape)]
            targets = targets[rows]
        frames[rows, targets] = np.searchsorted(np.cumsum(self.scan_target)[:-1],
                                                u[rows, targets], side='left')
        return frames[0] if single else frames


def as_observation(grid: Grid, model):
    """
    Return the observation model of a search on ``grid``: ``model``, or an FPOC's Gaussian model.

    A model of another grid's shape is refused (ValueError): its tables would not fit the belief.
    """
    if isinstance(model, FPOC):
        return GaussianObservation(grid, model)
    if not hasattr(model, 'log_likelihood_ratio'):
        raise TypeError(f'expected an observation model or an FPOC, got {type(model).__name__}')
    own = getattr(model, 'grid', None)
    if own is not None and tuple(own.shape) != tuple(grid.shape):
        raise ValueError(f'the observation model is for a {own.rows}x{own.cols} grid, the '
                         f'search is on a {grid.rows}x{grid.cols} grid')
    return model
