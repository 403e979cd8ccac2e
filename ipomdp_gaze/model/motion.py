# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A moving target: the forward dynamics applied to the belief between fixations.

Between two fixations the target takes one step of a random walk (Butko's NMPT; docs/design.md
section 7.1). From cell ``s = (r, c)`` it moves to ``d = (r', c')`` with probability

    T[s, d] = (1 - jump_prob) * G[s, d] + jump_prob / N
    G[s, d] = g(r' - r) g(c' - c) / Z(s),   g(x) = exp(-x^2 / (2 sigma_cells^2))  for |x| <= R

with ``R = ceil(3 sigma_cells)`` cells (truncation) and ``Z(s)`` the sum of ``g g`` over the cells
of the grid that ``s`` reaches, so no mass leaves the grid. The truncation box and the grid are
both rectangles, so ``Z(s) = Z_row(r) Z_col(c)`` and ``G = G_row (x) G_col`` (a Kronecker
product): the prediction of a belief ``P`` (rows x cols) is ``G_row^T P G_col`` (a separable
truncated convolution, ``O(N (rows + cols))``) and a target's step draws its row and column move
independently. The prediction of the cell mass ``B`` is therefore

    B'_d = (1 - jump_prob) * sum_s B_s G[s, d] + jump_prob * (sum_s B_s) / N

and an absent hypothesis (:mod:`ipomdp_gaze.model.stopping`) is left alone, unless the target
may leave the grid and come back (``leave_prob`` l > 0, a person walking out of the head's reach;
docs/design.md section 12.2): then, with ``A`` the absent hypothesis's probability,

    A'   = (1 - l) A + l sum_s B_s
    B''_d = (1 - l) B'_d + l A / N

(a target leaves from anywhere, and comes back anywhere). ``sigma_cells = 0``, ``jump_prob = 0``
and ``leave_prob = 0`` is a target that stays put (no prediction at all).

Units: ``sigma_cells`` and ``jump_prob`` are per fixation in simulation and training. In the
nodes they are per second (:meth:`Motion.over`): a step of ``dt`` seconds is a random walk of
variance ``sigma_cells^2 dt`` (``sigma = sigma_cells sqrt(dt)``) and jumps with probability
``1 - (1 - jump_prob)^dt`` (``leave_prob`` likewise).
"""
from __future__ import annotations

import math
import sys

from ipomdp_gaze.model.belief import normalize_log
from ipomdp_gaze.model.checks import (check_number, check_probability,  # noqa: F401
                                      check_sigma_cells)
from ipomdp_gaze.model.grid import Grid
import numpy as np

TRUNCATE_SIGMAS = 3.0
# The prediction adds the step's diagonals one by one (instead of a matrix product) when an
# axis is at least this many times longer than the step's 2R + 1 offsets: a few cells of a
# short step (sigma_cells per second over a millisecond loop) on a long axis.
BAND_RATIO = 32
ALMOST_ONE = math.nextafter(1.0, 0.0)
# exp(x) rounds to exactly 0 from this down (log of half the smallest subnormal, 2**-1075).
LOG_UNDERFLOW = -1075 * math.log(2.0)
# A step this many times an axis's length has g(k) exactly 1.0 at every offset on it
# (k^2 / (2 sigma^2) < 2**-61): a larger sigma gives the same matrix, computed without
# sigma ** 2 overflowing (motion.sigma_cells 1e200 was an OverflowError).
FLAT_STEP_AXES = 2.0 ** 30


def step_sigma(sigma_cells: float, seconds: float) -> float:
    """Return ``sigma_cells * sqrt(seconds)``, at most the largest float (never inf)."""
    return min(sigma_cells * math.sqrt(seconds), sys.float_info.max)


def axis_transition(size: int, sigma_cells: float) -> np.ndarray:
    """
    One axis of the Gaussian step: ``G_axis[x, x'] = g(x' - x) / sum_{x''} g(x'' - x)``.

    ``g(k) = exp(-k^2 / (2 sigma^2))`` for ``|k| <= ceil(3 sigma)`` and 0 beyond; the sum runs
    over the ``size`` positions of the axis, so each row sums to 1 (mass kept inside the grid).
    ``sigma_cells = 0`` gives the identity. ``g`` is evaluated once per offset ``k`` in
    ``-R..R`` and laid out along the diagonals (row x is the table ``g(x' - x)`` seen from x):
    the same entries, row sums and quotients as evaluating it for every pair of positions.
    """
    sigma = min(check_sigma_cells(sigma_cells), size * FLAT_STEP_AXES)
    # g(1) underflows: exactly the identity (a sigma below 1.5e-162, whose square is 0, too)
    if sigma ** 2 == 0 or math.exp(-0.5 / sigma ** 2) == 0.0:
        return np.eye(size)
    reach = min(math.ceil(TRUNCATE_SIGMAS * sigma), size - 1)
    offset = np.arange(-reach, reach + 1)
    table = np.zeros(2 * size - 1)              # entry size - 1 + k: g(k)
    table[size - 1 - reach:size + reach] = np.exp(-0.5 * (offset / sigma) ** 2)
    # Row x is table[size - 1 - x:][:size]: a view stepping back one entry per row, copied.
    weights = np.ndarray((size, size), buffer=table, offset=(size - 1) * table.itemsize,
                         strides=(-table.itemsize, table.itemsize)).copy()
    return weights / weights.sum(axis=1, keepdims=True)


def _diagonals(matrix: np.ndarray, reach: int) -> list:
    """Return ``(k, M[x, x + k])`` for the offsets ``k`` in ``-reach..reach`` not all 0."""
    bands = [(k, np.ascontiguousarray(np.diagonal(matrix, k))) for k in range(-reach, reach + 1)]
    return [(k, diagonal) for k, diagonal in bands if diagonal.any()]


def _axis_bands(row_matrix: np.ndarray, col_matrix: np.ndarray, sigma_cells: float):
    """
    Return the diagonals of both axes' steps when adding them beats a matrix product, else None.

    The step reaches at most ``R = ceil(3 sigma)`` cells (:func:`axis_transition`); every entry
    beyond is exactly 0, and so are the offsets whose ``g`` underflows, so the diagonals kept
    hold the whole matrix. A step that is exactly the identity (``g(1)``, the largest entry off
    the diagonal, underflows: a step of a hundredth of a cell) is ``()``: the product is then
    the values themselves.
    """
    if sigma_cells <= 0:
        return None
    if all(m.shape[0] == 1 or m[0, 1] == 0.0 for m in (row_matrix, col_matrix)):
        return ()
    size = min(row_matrix.shape[0], col_matrix.shape[0])
    reach = min(math.ceil(TRUNCATE_SIGMAS * min(sigma_cells, size)), size - 1)
    if (2 * reach + 1) * BAND_RATIO > size:
        return None
    row = _diagonals(row_matrix, reach)
    return row, row if col_matrix is row_matrix else _diagonals(col_matrix, reach)


def _banded_step(values: np.ndarray, bands: list, axis: int) -> np.ndarray:
    """
    Return ``values`` times a band matrix along ``axis`` (``y[d] = sum_s v[s] M[s, d]``, new).

    ``axis`` is -1 (columns) or -2 (rows); ``bands`` are the matrix's ``(k, M[x, x + k])``
    (:func:`_diagonals`): the same products as ``np.matmul``, summed offset by offset.
    """
    size = values.shape[axis]
    out = np.zeros(values.shape)
    scratch = np.empty(values.shape)
    for k, diagonal in bands:
        lo, hi = max(k, 0), size + min(k, 0)            # destinations d = s + k
        if axis == -1:
            src, dst, tmp = values[..., lo - k:hi - k], out[..., lo:hi], scratch[..., lo:hi]
        else:
            src, dst, tmp = values[..., lo - k:hi - k, :], out[..., lo:hi, :], \
                scratch[..., lo:hi, :]
            diagonal = diagonal[:, None]
        np.multiply(src, diagonal, out=tmp)
        dst += tmp
    return out


class Motion:
    """
    The target's random walk on a grid (see the module docstring for the formulas).

    Parameters
    ----------
    grid : Grid
        The visual array.
    sigma_cells : float
        Standard deviation of a step in cells (>= 0; 0 = no Gaussian step).
    jump_prob : float
        Probability in ``[0, 1)`` that a step is instead a jump to a uniformly random cell.
    leave_prob : float
        Probability in ``[0, 1)`` that a present target leaves the grid in a step, and that an
        absent one comes back (to a uniformly random cell); only with an absent hypothesis.

    """

    def __init__(self, grid: Grid, sigma_cells: float = 0.0, jump_prob: float = 0.0,
                 leave_prob: float = 0.0):
        self.grid = grid
        self.sigma_cells = check_sigma_cells(sigma_cells)
        self.jump_prob = check_probability(jump_prob, 'jump_prob')
        self.leave_prob = check_probability(leave_prob, 'leave_prob')
        self.row_matrix = axis_transition(grid.rows, self.sigma_cells)
        self.col_matrix = self.row_matrix if grid.cols == grid.rows else \
            axis_transition(grid.cols, self.sigma_cells)
        self._row_t = np.ascontiguousarray(self.row_matrix.T)
        self._bands = _axis_bands(self.row_matrix, self.col_matrix, self.sigma_cells)
        self._cdf = None                        # the step's CDFs, built on the first move
        self._over = None                       # the last (seconds, Motion) of over()

    def __repr__(self):
        return (f'Motion({self.grid!r}, sigma_cells={self.sigma_cells}, '
                f'jump_prob={self.jump_prob}, leave_prob={self.leave_prob})')

    @property
    def active(self) -> bool:
        """Whether the target moves at all (otherwise prediction is the identity)."""
        return self.sigma_cells > 0 or self.jump_prob > 0 or self.leave_prob > 0

    def is_identity(self, with_absent: bool = False) -> bool:
        """
        Whether a step leaves every belief exactly as it is.

        True when the Gaussian step is the identity (``g(1)`` underflows: a step of a hundredth of
        a cell, a fast loop with slow motion) and nothing jumps, nor leaves (``with_absent``).
        The prediction then skips its round trip through probabilities, which could only add
        round-off.
        """
        return self._bands == () and not self.jump_prob and not (with_absent and self.leave_prob)

    def to_dict(self) -> dict:
        """``{'sigma_cells': ..., 'jump_prob': ..., 'leave_prob': ...}``."""
        return {'sigma_cells': self.sigma_cells, 'jump_prob': self.jump_prob,
                'leave_prob': self.leave_prob}

    def over(self, seconds: float) -> 'Motion':
        """
        Return the motion over ``seconds`` when ``sigma_cells`` and ``jump_prob`` are per second.

        ``sigma = sigma_cells * sqrt(seconds)`` (variance grows linearly in time) and
        ``jump = 1 - (1 - jump_prob)^seconds`` (``leave`` likewise), kept just below 1 for a very
        long gap (the belief is then uniform); ``seconds <= 0`` is no motion.
        """
        dt = max(0.0, float(seconds))
        if self._over is not None and self._over[0] == dt:
            return self._over[1]
        jump = min(1.0 - (1.0 - self.jump_prob) ** dt, ALMOST_ONE)
        leave = min(1.0 - (1.0 - self.leave_prob) ** dt, ALMOST_ONE)
        motion = Motion(self.grid, step_sigma(self.sigma_cells, dt), jump, leave)
        self._over = (dt, motion)
        return motion

    # -- the belief ----------------------------------------------------------------------
    def transition_matrix(self) -> np.ndarray:
        """Return the dense ``T[s, d]`` (N x N, each row sums to 1); for tests and small grids."""
        n = self.grid.n_cells
        return (1.0 - self.jump_prob) * np.kron(self.row_matrix, self.col_matrix) \
            + self.jump_prob / n

    def predict(self, cells: np.ndarray) -> np.ndarray:
        """
        Predict cell mass one step ahead: ``(1 - j) * B G + j * sum(B) / N`` (new array).

        Parameters
        ----------
        cells : array (N,) or (E, N)
            Probabilities of the cells (their sum may be below 1 when a target may be absent).

        """
        b = np.asarray(cells, dtype=float)
        rows, cols = self.grid.shape
        grid_b = b.reshape(b.shape[:-1] + (rows, cols))
        if self._bands is None:
            moved = np.matmul(self._row_t, np.matmul(grid_b, self.col_matrix)).reshape(b.shape)
        elif not self._bands:                   # the identity: 1 times each value, exactly
            moved = b.copy()
        else:
            row_bands, col_bands = self._bands
            moved = _banded_step(_banded_step(grid_b, col_bands, -1), row_bands, -2)
            moved = moved.reshape(b.shape)
        if self.jump_prob:
            mass = b.sum(axis=-1, keepdims=True)
            moved *= 1.0 - self.jump_prob
            moved += self.jump_prob * mass / self.grid.n_cells
        return moved

    def predict_log(self, log_belief: np.ndarray) -> np.ndarray:
        """
        Predict a normalised log belief in place (an absent column N moves by ``leave_prob``).

        ``log_belief`` has N columns, or N + 1 with the absent hypothesis last (which only
        ``leave_prob`` changes: the module docstring). The step runs on
        probabilities relative to the largest entry, so nothing underflows that is within
        ``exp(-745)`` of it; cells that the step leaves at exactly 0 get ``-inf``. The result is
        renormalised (the step keeps the mass; this removes round-off). Returns ``log_belief``.
        """
        n = self.grid.n_cells
        if not self.active:
            return log_belief
        peak = np.max(log_belief, axis=-1, keepdims=True)
        if self.is_identity(log_belief.shape[-1] > n):
            # The step moves nothing: of the round trip through probabilities only its underflow
            # is kept (a cell below exp's range relative to the peak becomes exactly 0).
            cells = log_belief[..., :n]
            cells[cells - peak <= LOG_UNDERFLOW] = -np.inf
            return log_belief
        cells = np.subtract(log_belief[..., :n], peak)
        moved = self.predict(np.exp(cells, out=cells))
        if self.leave_prob and log_belief.shape[-1] > n:
            leave = self.leave_prob
            absent = np.exp(log_belief[..., n:] - peak)
            present = moved.sum(axis=-1, keepdims=True)
            moved *= 1.0 - leave
            moved += leave * absent / n
            with np.errstate(divide='ignore'):
                log_belief[..., n:] = np.log((1.0 - leave) * absent + leave * present) + peak
        with np.errstate(divide='ignore'):
            np.add(np.log(moved, out=moved), peak, out=log_belief[..., :n])
        return normalize_log(log_belief)

    def predict_over(self, log_belief: np.ndarray, seconds: float,
                     update: bool = True) -> np.ndarray:
        """Predict a log belief over ``seconds`` in place (per-second parameters); return it."""
        if self.active and seconds > 0:
            self.over(seconds).predict_log(log_belief)
        return log_belief

    def reset(self) -> None:
        """Forget what a search learned about the motion (nothing: a random walk has no state)."""

    # -- the target ----------------------------------------------------------------------
    @staticmethod
    def _step_cdf(matrix: np.ndarray) -> np.ndarray:
        cdf = np.cumsum(matrix, axis=1)
        return cdf / cdf[:, -1:]                # the last reachable entry is exactly 1

    def move(self, targets: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """
        Draw each target's next cell from ``T[target, .]`` (new array, shape of ``targets``).

        Four uniform numbers per target, ``rng.random((E, 4))``: the row move, the column move
        (each by its axis's inverse CDF, which is exact because ``G`` is a Kronecker product),
        whether the step is a jump (``u < jump_prob``) and, if so, the cell ``floor(u N)``. The
        draws do not depend on where the targets are, so every policy run on the same stream
        sees the same target paths (common random numbers).
        """
        t = np.asarray(targets, dtype=np.int64)
        u = rng.random(t.shape + (4,))
        cols = self.grid.cols
        r, c = np.divmod(t, cols)
        if self._cdf is None:
            self._cdf = [self._step_cdf(m) for m in (self.row_matrix, self.col_matrix)]
        row_cdf, col_cdf = self._cdf
        new_r = np.sum(u[..., 0, None] > row_cdf[r], axis=-1)
        new_c = np.sum(u[..., 1, None] > col_cdf[c], axis=-1)
        moved = new_r * cols + new_c
        jump_to = np.minimum((u[..., 3] * self.grid.n_cells).astype(np.int64),
                             self.grid.n_cells - 1)
        return np.where(u[..., 2] < self.jump_prob, jump_to, moved)


def axis_drift(size: int, sigma_cells: float, shift_cells: float) -> np.ndarray:
    """
    One axis of a drifting step: move by ``shift_cells``, then the Gaussian step of ``sigma``.

    The shift splits each position's mass between the two positions around ``x + shift``
    (linear interpolation); mass shifted past either end leaves the axis (the row sums to less
    than 1: the target walked out of the grid). :func:`axis_transition` then spreads it.
    """
    # a shift past size + 1 cells takes every position off the axis, as a larger one does (and
    # keeps floor() within int64: max_speed_cells 1e308 made it a NaN belief)
    x = np.arange(size) + min(max(float(shift_cells), -(size + 1.0)), size + 1.0)
    low = np.floor(x).astype(np.int64)
    frac = x - low
    shift = np.zeros((size, size + 2))           # columns 0 and size + 1: past the ends
    rows = np.arange(size)
    np.add.at(shift, (rows, np.clip(low, -1, size) + 1), 1.0 - frac)
    np.add.at(shift, (rows, np.clip(low + 1, -1, size) + 1), frac)
    return shift[:, 1:size + 1] @ axis_transition(size, sigma_cells)


class VelocityMotion(Motion):
    """
    A target that walks: a velocity per target, kept between turns (docs/design.md section 12.2).

    The state is ``(cell, k)`` with ``k`` one of ``classes^2`` velocities ``(v_row, v_col)``,
    each axis ``linspace(-max_speed, max_speed, classes)`` cells per second, drawn from the
    prior ``pi(k)``, a Gaussian of standard deviation ``speed_cells`` per axis (uniform when 0).
    Over ``dt`` seconds a target of velocity ``v`` moves by ``v dt`` and then by the random walk
    of ``sigma_cells sqrt(dt)`` (:func:`axis_drift` per axis); one that walks past the grid's
    edge has left (the absent hypothesis gains its mass). It jumps as :class:`Motion` says, turns
    with probability ``1 - (1 - turn_prob)^dt`` (its velocity drawn anew from ``pi``), and an
    absent target comes back with probability ``1 - (1 - leave_prob)^dt`` where it left: at the
    cell it walked out from (one absent from the start: at a uniformly drawn cell). The belief
    over cells stays the session's; this object keeps ``P(k | cell)`` and ``P(exit | absent)``,
    which the Bayes step leaves alone (the detector sees where a target is, not how fast it goes
    nor where an absent one left), so predicting the joint and summing it is the exact filter.
    Without an absent hypothesis the mass that left is renormalised away.
    """

    def __init__(self, grid: Grid, sigma_cells: float = 0.0, jump_prob: float = 0.0,
                 leave_prob: float = 0.0, max_speed_cells: float = 0.0, turn_prob: float = 0.0,
                 speed_cells: float = 0.0, classes: int = 9):
        super().__init__(grid, sigma_cells, jump_prob, leave_prob)
        speed = check_number(max_speed_cells, 'max_speed_cells')
        if not math.isfinite(speed) or speed <= 0:
            raise ValueError(f'max_speed_cells must be > 0, got {max_speed_cells!r}')
        self.max_speed_cells = speed
        self.turn_prob = check_probability(turn_prob, 'turn_prob')
        self.speed_cells = check_sigma_cells(speed_cells, 'speed_cells')
        if isinstance(classes, bool) or int(classes) != classes or classes < 2:
            raise ValueError(f'classes must be an int >= 2, got {classes!r}')
        self.classes = int(classes)
        # speed times the unit steps: linspace(-speed, speed) overflows its step past 9e307
        self.speeds = speed * np.linspace(-1.0, 1.0, self.classes)
        with np.errstate(over='ignore'):              # a speed far beyond speed_cells: weight 0
            axis = np.ones(self.classes) if self.speed_cells == 0 else \
                np.exp(-0.5 * (self.speeds / self.speed_cells) ** 2)
        prior = np.outer(axis, axis)
        self.prior = prior / prior.sum()
        self.reset()

    def __repr__(self):
        return (f'VelocityMotion({self.grid!r}, sigma_cells={self.sigma_cells}, '
                f'jump_prob={self.jump_prob}, leave_prob={self.leave_prob}, '
                f'max_speed_cells={self.max_speed_cells}, turn_prob={self.turn_prob}, '
                f'speed_cells={self.speed_cells}, classes={self.classes})')

    @property
    def active(self) -> bool:
        """Return True: a target with a velocity moves."""
        return True

    def to_dict(self) -> dict:
        """Return the parameters (:meth:`Motion.to_dict` and the velocity's)."""
        return {**super().to_dict(), 'max_speed_cells': self.max_speed_cells,
                'turn_prob': self.turn_prob, 'speed_cells': self.speed_cells,
                'classes': self.classes}

    def reset(self) -> None:
        """Forget the velocities (``P(k | cell)`` is the prior) and where targets left."""
        self.velocity = np.repeat(self.prior[:, :, None], self.grid.n_cells, axis=2)
        self.entry = np.full(self.grid.n_cells, 1.0 / self.grid.n_cells)

    def velocity_mean(self, cells: np.ndarray) -> np.ndarray:
        """Return the mean velocity ``(v_row, v_col)`` in cells/s, weighted by ``cells``."""
        weights = self.velocity * np.asarray(cells, dtype=float)[None, None, :]
        total = weights.sum()
        if total <= 0:
            return np.zeros(2)
        per_class = weights.sum(axis=2) / total
        return np.array([np.sum(per_class.sum(axis=1) * self.speeds),
                         np.sum(per_class.sum(axis=0) * self.speeds)])

    def predict_over(self, log_belief: np.ndarray, seconds: float,
                     update: bool = True) -> np.ndarray:
        """
        Predict a normalised log belief over ``seconds`` in place (the class docstring).

        ``update=False`` leaves ``P(k | cell)`` as it was (a look ahead, not a step of time).
        Returns ``log_belief``.
        """
        dt = float(seconds)
        if dt <= 0:
            return log_belief
        n, k = self.grid.n_cells, self.classes
        rows, cols = self.grid.shape
        peak = np.max(log_belief)
        cells = np.exp(log_belief[:n] - peak)
        sigma = step_sigma(self.sigma_cells, dt)
        row_t = np.stack([axis_drift(rows, sigma, float(v) * dt).T for v in self.speeds])
        col = np.stack([axis_drift(cols, sigma, float(v) * dt) for v in self.speeds])
        joint = (self.velocity * cells[None, None, :]).reshape(k, k, rows, cols)
        moved = np.matmul(np.matmul(row_t[:, None], joint), col[None, :]).reshape(k, k, n)
        kept = row_t.sum(axis=1)[:, None, :, None] * col.sum(axis=2)[None, :, None, :]
        walked_out = np.maximum((joint * (1.0 - kept)).sum(axis=(0, 1)).reshape(n), 0.0)
        jump = min(1.0 - (1.0 - self.jump_prob) ** dt, ALMOST_ONE)
        if jump:
            moved = (1.0 - jump) * moved + jump * moved.sum(axis=2, keepdims=True) / n
        turn = min(1.0 - (1.0 - self.turn_prob) ** dt, ALMOST_ONE)
        if turn:
            moved = (1.0 - turn) * moved \
                + turn * moved.sum(axis=(0, 1), keepdims=True) * self.prior[:, :, None]
        if log_belief.shape[-1] > n:
            back = min(1.0 - (1.0 - self.leave_prob) ** dt, ALMOST_ONE)
            absent = math.exp(log_belief[n] - peak)
            moved += back * absent * self.prior[:, :, None] * self.entry[None, None, :]
            stays = (1.0 - back) * absent * self.entry + walked_out
            gone = float(stays.sum())
            if update and gone > 0:
                self.entry = stays / gone
            with np.errstate(divide='ignore'):
                log_belief[n] = math.log(gone) + peak if gone > 0 else -np.inf
        new_cells = moved.sum(axis=(0, 1))
        if update:
            with np.errstate(divide='ignore', invalid='ignore'):
                self.velocity = np.where(new_cells > 0, moved / new_cells, self.prior[:, :, None])
        with np.errstate(divide='ignore'):
            log_belief[:n] = np.log(new_cells) + peak
        return normalize_log(log_belief)
