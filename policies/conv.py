# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Convolutional (shift-invariant) logistic policy: ``p(k | B) ∝ exp(score_k)``.

``score_k = sum_j B_j K[r_j - r_k + R-1, c_j - c_k + C-1]``: a cross-correlation of the belief with
the kernel K of shape ``(2R-1, 2C-1)`` (docs/design.md section 3). The radially weight-shared
family ties all entries with the same squared displacement ``dr^2 + dc^2``.

Two ways to compute the scores, chosen automatically by grid size:

- ``direct``: one product with the N x N matrix ``W[j, k]`` (built lazily, small grids only);
- ``fft``: a cross-correlation by real FFTs (``scipy.fft``) of the belief zero-padded to
  ``P x Q``, with the kernel's spectrum precomputed once. No N x N array is ever built, so a
  512 x 512 grid costs a few tens of MB. The kernel is cropped to the box of its non-zero entries
  (exact, since the dropped entries are 0; ``truncate`` may also drop entries below a relative
  size) and ``P >= R + W`` with ``W`` the box's reach from the centre, so a kernel whose weights
  vanish far out (the human FPOC's d'^2 is exactly 0 beyond 46 cells) needs far less than
  ``2R-1``.

The switch is at :data:`DIRECT_MAX_CELLS` (one belief) and :data:`DIRECT_MAX_CELLS_BATCH` (a
batch), the measured break-evens (``docs/benchmarks.md``). Both paths make the same argmax
decisions: FFT scores carry round-off (and any truncation) within a bound ``eps`` computed per
belief, and every cell whose FFT score is within ``rtol |peak| + (2 + rtol) eps`` of the peak is
re-scored exactly by the direct sum before the project's tie rule (docs/design.md section 4) is
applied. When truncation leaves too many such cells, the scores are recomputed without it.
"""
from __future__ import annotations

import math

from ipomdp_gaze.model.belief import argmax_ties_low, TIE_RTOL
from ipomdp_gaze.model.grid import Grid
import numpy as np
import scipy.fft

ACTIONS = ('argmax', 'sample')
METHODS = ('auto', 'direct', 'fft')

# Break-even between the N x N product and the FFT path, measured with
# bench/simulation/bench_latency.py
# (docs/benchmarks.md): for one belief (the controller) the two cost the same at 24x24-28x28 (the
# crossing moved within that range over three runs); for a batch of 256 beliefs (simulation)
# direct stays faster up to 40x40-44x44 and FFT wins from 48x48.
DIRECT_MAX_CELLS = 676
DIRECT_MAX_CELLS_BATCH = 1600
# The direct path refuses an N x N matrix larger than this (a 128x128 grid would need 2.1 GB).
DIRECT_MAX_BYTES = 1 << 30
# Safety factor of the FFT round-off bound (Higham's eta ~ 7u per radix stage, then x2).
FFT_ERROR_FACTOR = 16.0
# Default truncation: kernel entries below this fraction of the largest are left out of the FFT
# (below float64 resolution next to the largest term; decisions never depend on it).
DEFAULT_TRUNCATE = 1e-16
# A kernel whose absolute values sum past this is refused: a score is a belief-weighted sum of
# its entries and the FFT path adds up its spectrum over up to P x Q terms (1.7e7 for a 1024 x
# 1024 grid), so every score and every sum on the way stays finite (huge kernels made NaN
# scores, and the controller fixated cell 0 forever).
MAX_KERNEL_ABS_SUM = 1e300
# Near-maximal candidates re-scored exactly at most; more means a flat belief (a massive tie).
RESCORE_MAX = 16
# Cells re-scored per vectorised chunk (memory bound for the gathered windows).
_RESCORE_CHUNK_VALUES = 1 << 21


def check_action(action: str) -> str:
    """Validate an action rule name."""
    if action not in ACTIONS:
        raise ValueError(f"unknown action {action!r}; valid actions: {', '.join(ACTIONS)}")
    return action


def check_kernel(values, grid: Grid, what: str = 'kernel') -> np.ndarray:
    """
    Validate a kernel for ``grid`` and return it as a float64 ``(2R-1, 2C-1)`` array.

    ``values`` is the 2-D kernel or its ``(2R-1) * (2C-1)`` entries row-major (a ROS parameter).
    This is the only place a kernel is checked; ``what`` names it in the message.

    Raises
    ------
    ValueError
        Naming the expected size or the first non-finite entry.

    """
    shape = grid.kernel_shape
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f'{what} must be numbers') from None
    if a.size != shape[0] * shape[1] or (a.ndim > 1 and a.shape != shape):
        raise ValueError(f'{what} must have {shape[0] * shape[1]} values ({shape[0]}x{shape[1]} '
                         f'row-major for a {grid.rows}x{grid.cols} grid), got {a.size} in shape '
                         f'{a.shape}')
    a = a.reshape(shape)
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise ValueError(f'{what} must be finite, entry {int(bad[0])} is {a.flat[bad[0]]}')
    check_score_scale(a, what)
    return a


def check_score_scale(weights: np.ndarray, what: str, axis: int | None = None) -> None:
    """
    Refuse weights whose absolute values sum past :data:`MAX_KERNEL_ABS_SUM` (ValueError).

    ``axis`` sums per row (a logistic policy's theta: one score per row); None sums them all.
    """
    with np.errstate(over='ignore'):
        total = float(np.max(np.abs(weights).sum(axis=axis)))
    if not total <= MAX_KERNEL_ABS_SUM:
        per = ' in a row' if axis is not None else ''
        raise ValueError(f'{what}: the sum of its absolute values{per} must be at most '
                         f'{MAX_KERNEL_ABS_SUM:g} (a score is a sum of belief times weights and '
                         f'must not overflow), got {total:g}')


def squared_distance_table(grid: Grid) -> np.ndarray:
    """``dr^2 + dc^2`` on the (2R-1, 2C-1) kernel grid."""
    dr = np.arange(-(grid.rows - 1), grid.rows)
    dc = np.arange(-(grid.cols - 1), grid.cols)
    return dr[:, None] ** 2 + dc[None, :] ** 2


def radial_bins(grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """
    Distinct squared distances (sorted) and the bin of each kernel entry.

    Returns ``(squared_distance, bin_index)`` with ``bin_index`` of the kernel's shape, so
    ``kernel = weight[bin_index]`` (27 weights at 7x7, 61 at 11x11).
    """
    table = squared_distance_table(grid)
    values, inverse = np.unique(table, return_inverse=True)
    return values, inverse.reshape(table.shape)


def kernel_from_radial(grid: Grid, weight: np.ndarray) -> np.ndarray:
    """Expand one weight per distinct squared distance into the full kernel."""
    values, bins = radial_bins(grid)
    weight = np.asarray(weight, dtype=float)
    if weight.shape != values.shape:
        raise ValueError(f'radial weights must have {values.size} values for a '
                         f'{grid.rows}x{grid.cols} grid, got {weight.size}')
    return weight[bins]


def kernel_matrix(grid: Grid, kernel: np.ndarray) -> np.ndarray:
    """Return ``W[k, j] = K[r_j - r_k + R-1, c_j - c_k + C-1]``, N x N (small grids only)."""
    # Row k of W is the R x C window of K starting at (R-1-r_k, C-1-c_k): one copy, no indices.
    windows = np.lib.stride_tricks.sliding_window_view(np.asarray(kernel), grid.shape)
    return np.ascontiguousarray(windows[::-1, ::-1]).reshape(grid.n_cells, grid.n_cells)


def _transposed_kernel_matrix(grid: Grid, kernel: np.ndarray) -> np.ndarray:
    """Return ``W.T[j, k]`` of :func:`kernel_matrix` in one allocation."""
    # W.T[(r_j, c_j), (r_k, c_k)] = K[r_j - r_k + R-1, ...] = flipped K's window at (R-1-r_j, ...).
    windows = np.lib.stride_tricks.sliding_window_view(kernel[::-1, ::-1], grid.shape)
    return np.ascontiguousarray(windows[::-1, ::-1]).reshape(grid.n_cells, grid.n_cells)


def support_box(kernel: np.ndarray, truncate: float = 0.0) -> tuple[slice, slice]:
    """
    Return the smallest box of ``kernel`` holding every entry with ``|K| > truncate * max|K|``.

    With ``truncate = 0`` the box holds every non-zero entry, so cropping to it is exact. An
    all-zero kernel gives its central entry.
    """
    magnitude = np.abs(kernel)
    keep = magnitude > truncate * magnitude.max() if truncate > 0 else magnitude > 0
    rows, cols = np.flatnonzero(keep.any(axis=1)), np.flatnonzero(keep.any(axis=0))
    if rows.size == 0:
        r, c = kernel.shape[0] // 2, kernel.shape[1] // 2
        return slice(r, r + 1), slice(c, c + 1)
    return slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1)


def fft_size(n: int, box: slice, real: bool) -> int:
    """
    Smallest fast FFT length for ``n`` cells along an axis with kernel rows/cols in ``box``.

    The circular correlation equals the linear one on the ``n`` outputs when the length is at
    least ``n + max(reach below the centre, reach above it)``; the centre of the axis is ``n-1``.
    """
    reach = max(n - 1 - box.start, box.stop - 1 - (n - 1), 0)
    return scipy.fft.next_fast_len(n + reach, real=real)


class _Spectrum:
    """Precomputed FFT of a kernel cropped to its support box; its error bound per ``||B||``."""

    def __init__(self, grid: Grid, kernel: np.ndarray, truncate: float):
        rows, cols = grid.shape
        box_r, box_c = self.box = support_box(kernel, truncate)
        self.shape = (fft_size(rows, box_r, real=False), fft_size(cols, box_c, real=True))
        p, q = self.shape
        crop = kernel[box_r, box_c]
        # Entry of offset (dr, dc) at circular position (dr mod P, dc mod Q).
        padded = np.zeros((p, q), dtype=np.longdouble)
        ri = (np.arange(box_r.start, box_r.stop) - (rows - 1)) % p
        ci = (np.arange(box_c.start, box_c.stop) - (cols - 1)) % q
        padded[np.ix_(ri, ci)] = crop
        # The spectrum in extended precision, rounded once: its error is u |K^| per entry.
        self.spectrum = np.conj(scipy.fft.rfft2(padded)).astype(np.complex128)
        dropped = kernel.copy()
        dropped[box_r, box_c] = 0.0
        unit = np.finfo(float).eps / 2
        self.eps_per_norm = (FFT_ERROR_FACTOR * unit * (math.log2(p * q) + 1.0)
                             * float(np.abs(crop).sum()) + float(np.sqrt(np.sum(dropped ** 2))))


class ConvPolicy:
    """
    Shift-invariant logistic policy defined by a 2-D kernel (any kernel, symmetric or not).

    Parameters
    ----------
    grid : Grid
        The visual array.
    kernel : array (2R-1, 2C-1), or its entries row-major
        ``K[dr + R-1, dc + C-1]`` is the weight of belief ``dr`` rows below and ``dc`` columns
        right of the candidate fixation; checked by :func:`check_kernel`.
    action : {'argmax', 'sample'}
        How :meth:`select` turns scores into a fixation.
    method : {'auto', 'direct', 'fft'}
        How scores are computed; ``auto`` uses ``direct`` up to :data:`DIRECT_MAX_CELLS` cells for
        one belief and up to :data:`DIRECT_MAX_CELLS_BATCH` for a batch, ``fft`` above.
    truncate : float
        Entries with ``|K| <= truncate * max|K|`` are left out of the FFT (0 keeps every non-zero
        entry; the default is :data:`DEFAULT_TRUNCATE`, 1e-16). Argmax decisions do not depend
        on it: the error it adds is part of the bound that selects the cells re-scored exactly,
        and a belief with more than :data:`RESCORE_MAX` such cells is scored again without
        truncation; only the cost moves.

    Notes
    -----
    The object keeps preallocated buffers for :meth:`decide`; use one instance per thread.

    """

    name = 'learned'

    def __init__(self, grid: Grid, kernel, action: str = 'argmax', method: str = 'auto',
                 truncate: float = DEFAULT_TRUNCATE, what: str = 'kernel'):
        kernel = check_kernel(kernel, grid, what)
        if method not in METHODS:
            raise ValueError(f"unknown method {method!r}; valid methods: {', '.join(METHODS)}")
        truncate = float(truncate)
        if not 0.0 <= truncate < 1.0:
            raise ValueError(f'truncate must be in [0, 1), got {truncate!r}')
        self.grid = grid
        self.kernel = kernel
        self.action = check_action(action)
        self.truncate = truncate
        n = grid.n_cells
        if method == 'direct' and 8 * n * n > DIRECT_MAX_BYTES:
            raise ValueError(f'method direct needs an N x N matrix of {8 * n * n / 2**30:.1f} GiB '
                             f'for a {grid.rows}x{grid.cols} grid; use method fft')
        self.method = method
        self._weights_t = None                  # [j, k], built on first direct use
        self._spectra = {}                      # FFT set-ups by truncation, built on first use
        self._score = np.empty(n)
        self._near = np.empty(n, dtype=bool)
        # Exact re-scoring uses the box of non-zero entries (lossless).
        self._exact_box = support_box(kernel)
        self.rescored = 0                       # FFT decisions that needed exact re-scoring

    def uses_direct(self, batch: bool = False) -> bool:
        """Whether scores of one belief (or of a batch) are computed by the direct product."""
        if self.method != 'auto':
            return self.method == 'direct'
        return self.grid.n_cells <= (DIRECT_MAX_CELLS_BATCH if batch else DIRECT_MAX_CELLS)

    @property
    def fft_shape(self) -> tuple[int, int]:
        """Return the padded size ``(P, Q)`` of the FFT path (with ``truncate``)."""
        return self._fft().shape

    # -- FFT path ----------------------------------------------------------------------------
    def _fft(self, lossless: bool = False) -> _Spectrum:
        """Return the FFT set-up for ``truncate`` (or for 0: lossless), built on first use."""
        tol = 0.0 if lossless else self.truncate
        if tol not in self._spectra:
            # A truncation that drops no entry has the lossless set-up: the same one serves both.
            box = support_box(self.kernel, tol)
            same = [s for s in self._spectra.values() if s.box == box]
            self._spectra[tol] = same[0] if same else _Spectrum(self.grid, self.kernel, tol)
        return self._spectra[tol]

    def _fft_scores(self, belief: np.ndarray, lossless: bool = False) -> np.ndarray:
        fft = self._fft(lossless)
        rows, cols = self.grid.shape
        p, q = fft.shape
        b = np.asarray(belief, dtype=float)
        grid_b = b.reshape(b.shape[:-1] + (rows, cols))
        spec = scipy.fft.rfft2(grid_b, s=(p, q))    # one call: half the padding copies
        spec *= fft.spectrum
        spec = scipy.fft.ifft(spec, axis=-2, overwrite_x=True)
        out = scipy.fft.irfft(spec[..., :rows, :], n=q, axis=-1)[..., :cols]
        return out.reshape(b.shape)

    def fft_error_bound(self, belief: np.ndarray, lossless: bool = False) -> np.ndarray:
        """
        Bound on ``|FFT score - exact score|`` for each belief (last axis).

        ``(16 u (log2(PQ) + 1) ||K_crop||_1 + ||K_dropped||_2) ||B||_2``: FFT round-off
        (Higham, Accuracy and Stability of Numerical Algorithms, sec. 24.1, with the kernel's
        spectrum exact to rounding) plus the truncated entries (Cauchy-Schwarz).
        """
        b = np.asarray(belief, dtype=float)
        return self._fft(lossless).eps_per_norm * np.sqrt(np.einsum('...i,...i->...', b, b))

    # -- exact scores ------------------------------------------------------------------------
    def exact_scores(self, belief: np.ndarray, cells) -> np.ndarray:
        """
        Direct sums ``score_k`` for the given cells of one belief (N,), without an N x N array.

        Only the kernel's non-zero box enters the sum, so a cell costs at most the box's size.
        """
        rows, cols = self.grid.shape
        grid_b = np.asarray(belief, dtype=float).reshape(rows, cols)
        cells = np.asarray(cells, dtype=np.int64).ravel()
        box_r, box_c = self._exact_box
        out = np.empty(cells.size)
        for i, k in enumerate(cells):
            rk, ck = divmod(int(k), cols)
            # Cells j with kernel row rj - rk + R-1 inside the box.
            r0, r1 = max(0, box_r.start + rk - rows + 1), min(rows, box_r.stop + rk - rows + 1)
            c0, c1 = max(0, box_c.start + ck - cols + 1), min(cols, box_c.stop + ck - cols + 1)
            if r0 >= r1 or c0 >= c1:
                out[i] = 0.0
                continue
            window = self.kernel[r0 - rk + rows - 1:r1 - rk + rows - 1,
                                 c0 - ck + cols - 1:c1 - ck + cols - 1]
            out[i] = np.einsum('ij,ij->', grid_b[r0:r1, c0:c1], window)
        return out

    def _decide_fft(self, belief: np.ndarray, score: np.ndarray, lossless: bool = False) -> int:
        """Tie-rule argmax of one belief from its FFT scores, exact near the maximum."""
        peak = float(score.max())
        eps = float(self.fft_error_bound(belief, lossless))
        rtol = TIE_RTOL
        # Every cell the direct path could call tied with its maximum is above this line.
        low = peak - rtol * abs(peak) - (2.0 + rtol) * eps
        cand = np.flatnonzero(score >= low)
        if cand.size == 1:
            return int(cand[0])
        self.rescored += 1
        if cand.size <= RESCORE_MAX:
            return int(cand[argmax_ties_low(self.exact_scores(belief, cand))])
        if self.truncate > 0 and not lossless:  # too blurred by truncation: use every entry
            if self._fft(True) is not self._fft():
                return self._decide_fft(belief, self._fft_scores(belief, True), lossless=True)
            # Truncation dropped nothing: the lossless pass would have these scores, bound and
            # candidates; it counts as a second re-scoring, as it did.
            self.rescored += 1
        return self._decide_flat(belief, score, cand, eps)

    def _decide_flat(self, belief, score, cand, eps) -> int:
        """
        Resolve a massive near-tie (a flat belief on a large grid) with few exact sums.

        The FFT's best cell is re-scored exactly, which brackets the maximum within
        ``[best, peak + eps]`` (exact when few cells come that close); a candidate is tied for
        certain when its FFT score clears the threshold of the upper end by ``eps``, out for
        certain when it misses that of the lower end by ``eps``, and re-scored exactly otherwise.
        Without truncation ``eps`` is ~1e-15 of the scores, and the decision can differ from the
        direct path's only if an exact score lies within ``2 eps`` of the tie threshold itself,
        as close as the direct path's own round-off.
        """
        rtol = TIE_RTOL
        cand_score = score[cand]
        top = int(np.argmax(cand_score))
        best = float(self.exact_scores(belief, cand[top:top + 1])[0])
        # Only cells with an FFT score above (best - eps) can beat it; few: re-score them all.
        rivals = np.flatnonzero(cand_score + eps > best)
        if rivals.size <= RESCORE_MAX:
            best = max(best, float(self.exact_scores(belief, cand[rivals]).max()))
            high = best
        else:
            high = max(best, float(cand_score[top]) + eps)
        threshold = best - rtol * abs(best)
        threshold_high = high - rtol * abs(high)
        sure = cand_score - eps >= threshold_high
        first_sure = int(np.argmax(sure)) if sure.any() else cand.size
        unsure = np.flatnonzero(cand_score[:first_sure] + eps >= threshold)
        for start in range(0, unsure.size, RESCORE_MAX):
            part = cand[unsure[start:start + RESCORE_MAX]]
            tied = np.flatnonzero(self.exact_scores(belief, part) >= threshold)
            if tied.size:
                return int(part[tied[0]])
        return int(cand[first_sure])

    # -- direct path -------------------------------------------------------------------------
    def _direct_weights(self) -> np.ndarray:
        if self._weights_t is None:
            n = self.grid.n_cells
            if 8 * n * n > DIRECT_MAX_BYTES:
                raise ValueError(f'the direct path needs an N x N matrix of '
                                 f'{8 * n * n / 2**30:.1f} GiB; this grid uses method fft')
            self._weights_t = _transposed_kernel_matrix(self.grid, self.kernel)
        return self._weights_t

    # -- public API --------------------------------------------------------------------------
    def scores(self, belief: np.ndarray) -> np.ndarray:
        """``score_k`` for each cell, shape like ``belief`` (FFT path: within the error bound)."""
        belief = np.asarray(belief)
        if self.uses_direct(batch=belief.ndim > 1 and belief.shape[0] > 1):
            return belief @ self._direct_weights()
        return self._fft_scores(belief)

    def probabilities(self, belief: np.ndarray) -> np.ndarray:
        """Softmax ``p(k | B)``."""
        s = self.scores(belief)
        s = s - s.max(axis=-1, keepdims=True)
        p = np.exp(s)
        return p / p.sum(axis=-1, keepdims=True)

    def decide(self, belief: np.ndarray) -> int:
        """
        Argmax fixation of one belief (N,) with the project tie rule: the controller's fast path.

        On the direct path it allocates nothing: the scores and the tie mask go to preallocated
        buffers (``belief`` should be a contiguous float64 array, as the controller keeps it).
        """
        if self.uses_direct():
            weights = self._weights_t if self._weights_t is not None else self._direct_weights()
            if not (isinstance(belief, np.ndarray) and belief.dtype == np.float64
                    and belief.flags.c_contiguous and belief.shape == self._score.shape):
                belief = np.ascontiguousarray(belief, dtype=float).reshape(self._score.shape)
            score = np.dot(belief, weights, out=self._score)
            peak = score.max()
            np.greater_equal(score, peak - TIE_RTOL * abs(peak), out=self._near)
            return int(self._near.argmax())
        belief = np.asarray(belief, dtype=float).reshape(-1)
        return self._decide_fft(belief, self._fft_scores(belief))

    def _argmax(self, belief: np.ndarray) -> np.ndarray:
        if self.uses_direct(batch=True):
            return argmax_ties_low(belief @ self._direct_weights())
        score = self._fft_scores(belief)
        peak = score.max(axis=-1, keepdims=True)
        eps = self.fft_error_bound(belief)[:, None]
        low = peak - TIE_RTOL * np.abs(peak) - (2.0 + TIE_RTOL) * eps
        count = np.count_nonzero(score >= low, axis=-1)
        choice = np.argmax(score, axis=-1)
        for e in np.flatnonzero(count > 1):     # rows with a near-tie only
            choice[e] = self._decide_fft(belief[e], score[e])
        return choice

    def select(self, belief, t, rng):
        """Fixation(s) for a belief (N,) or a batch (E, N), by the policy's action rule."""
        if self.action == 'argmax':
            belief = np.asarray(belief, dtype=float)
            if belief.ndim == 1:
                return self.decide(belief)
            if belief.shape[0] == 1:
                return np.array([self.decide(belief[0])])
            return self._argmax(belief)
        p = self.probabilities(np.atleast_2d(belief))
        u = rng.random((p.shape[0], 1))
        k = np.minimum((np.cumsum(p, axis=1) < u).sum(axis=1), p.shape[1] - 1)
        return k if np.ndim(belief) > 1 else k[0]
