# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Percent-correct greedy searcher: the ideal searcher of Najemnik & Geisler (2005).

It fixates ``argmax_k sum_i B_i P(C | i, k)``, the cell that maximises the probability that the
MAP guess after one more observation is right (docs/design.md section 3), where

    P(C | i, k) = int phi(w) prod_{j != i} Phi([ln(B_i/B_j) + (d_ik^2 + d_jk^2)/2 + d_ik w]
                                                / d_jk) dw

and a factor with ``d_jk = 0`` is the step ``1[ln(B_i/B_j) + d_ik^2/2 + d_ik w > 0]``.

How the score is computed (exactly the same quantity, O(N^2 Q) instead of O(N^3 Q))
-------------------------------------------------------------------------------------
Write ``Y_j = ln B_j + d_jk (o_j - d_jk/2)`` for the unnormalised log posterior of cell j after
the observation o from fixation k. When no cell holds the target ("null"), the Y_j are
independent ``N(mu_j, d_jk^2)`` with ``mu_j = ln B_j - d_jk^2/2``, and ``exp(Y_i)`` is ``B_i``
times the likelihood ratio of "target at i" against the null. Changing measure,
``B_i P(C | i, k) = E_null[exp(Y_i) 1(i = argmax_j Y_j)]``, so the sum over i is

    score(k) = E_null[exp(max_j Y_j)] = int exp(y) (1 - G_k(y)) dy,  G_k(y) = prod_j F_j(y),

with ``F_j(y) = Phi((y - mu_j)/d_jk)`` the null CDF of ``Y_j`` (the step ``1[y > ln B_j]`` when
``d_jk = 0``). Ties do not change the value of the maximum, so the score does not depend on the
tie rule (it only decides which tied cell is named). The steps of the ``d_jk = 0`` cells combine
into a lower limit ``L_k = max_j ln B_j``: below it ``G_k = 0`` and the integral is ``exp(L_k)``.

Quadrature and its error
------------------------
The integral runs over ``[lo, hi]`` with ``lo = max(L_k, max_j (mu_j - Z d_jk))`` and
``hi = max_j (ln B_j + d_jk^2/2 + Z d_jk)``; with ``Z = 7.1`` the two cut-offs change the score by
at most ``2 Phi(-Z) = 1.2e-12`` (below lo, ``G_k <= Phi(-Z)`` and ``exp(lo) <= 1``; above hi, cell
j's tail contributes at most ``B_j Phi(-Z)``). Every cell j's features lie within
``Z d_jk + d_jk^2`` above ``lo``, so narrow (small-d) features sit near the lower end:
Gauss-Legendre nodes in ``t`` mapped by ``y = lo + (hi - lo) t^power`` concentrate there (see
:func:`default_nodes` for the node counts and their measured errors). ``G_k`` is summed as
``log1p(-q_j)`` of the upper tails ``q_j = 1 - F_j`` and ``1 - G_k`` taken as ``-expm1``, so the
upper tail (weighted by ``exp(y)``) keeps full relative precision.

Pruning and its bound
---------------------
Cells are sorted by belief and only the smallest top set S is kept, with the tail ``j not in S``
dropped from both the hypotheses and the competitors. Then, for every fixation k,
``0 <= score(k) - score_S(k) <= sum_{j not in S} B_j Phi(ln(B_j/B_m)/s + s/2)``, m the most likely
cell and ``s = sqrt(2) max d``. Proof: ``exp(max_all Y) - exp(max_S Y)`` is 0 unless some dropped
j beats every kept cell, and then it is at most ``sum_{j not in S} exp(Y_j) 1(Y_j > Y_m)``; its
null expectation is ``sum_j B_j P(Y_j > Y_m | target j)``, and under target j,
``Y_j - Y_m ~ N(ln(B_j/B_m) + s_jm^2/2, s_jm^2)`` with ``s_jm^2 = d_jk^2 + d_mk^2 <= s^2``; the
probability increases with ``s_jm`` because ``B_j <= B_m``. S is the smallest set whose bound is at
most ``tol`` (default 1e-10, below the 1e-9 relative tie tolerance of docs/design.md section 4),
so the choice is ``tol``-optimal. When S is a single cell every fixation scores ``B_m`` exactly and
the tie rule names cell 0: more information cannot change the MAP guess by more than ``tol``.
"""
from __future__ import annotations

import functools

from ipomdp_gaze.model.belief import argmax_ties_low, TIE_RTOL
from ipomdp_gaze.model.fpoc import dprime_matrix, FPOC
from ipomdp_gaze.model.grid import Grid
import numpy as np
from scipy.special import ndtr

Z_TAIL = 7.1
DEFAULT_TOL = 1e-10
# Quadrature (nodes, power): the first when every positive d' is at least SHARP_DPRIME, else the
# second (the far periphery of 9x9 and larger human-FPOC grids has d' down to 0.002).
NODES_SMOOTH = (112, 2)
NODES_SHARP = (192, 3)
SHARP_DPRIME = 0.05
MAX_ELEMENTS = 1 << 21
D_MAX = 25.0
W_LIMIT = 8.3


def default_nodes(dprime: np.ndarray) -> tuple[int, int]:
    """
    Quadrature ``(nodes, power)`` for a d' matrix.

    Measured against 1024 nodes on beliefs from simulated searches
    (``bench/simulation/bench_greedy.py``):
    112 nodes with power 2 stay within 2e-11 (7x7 human) and 3e-10 (7x7 exponential); 192 with
    power 3 below 2e-9 at 11x11 human, where d' reaches 0.002.
    """
    d = np.asarray(dprime, dtype=float)
    positive = d[d > 0]
    if positive.size and positive.min() < SHARP_DPRIME:
        return NODES_SHARP
    return NODES_SMOOTH


@functools.lru_cache(maxsize=16)
def mapped_nodes(nodes: int, power: int):
    """
    Gauss-Legendre nodes on [0, 1] mapped by ``t -> t^power``: ``(positions, weights)``.

    ``sum(weights * f(positions))`` approximates ``int_0^1 f(u) du`` with nodes crowded near 0.
    """
    if int(nodes) != nodes or nodes < 2:
        raise ValueError(f'nodes must be an integer >= 2, got {nodes!r}')
    if int(power) != power or power < 1:
        raise ValueError(f'power must be an integer >= 1, got {power!r}')
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    t = (x + 1.0) / 2.0
    t_nodes, w_nodes = t ** power, w / 2.0 * power * t ** (power - 1)
    t_nodes.flags.writeable = False
    w_nodes.flags.writeable = False
    return t_nodes, w_nodes


def check_belief(belief, n_cells: int) -> np.ndarray:
    """
    Validate a belief (N,) or batch (E, N) and return it as a normalised (E, N) float array.

    Raises
    ------
    ValueError
        When the shape does not end in ``n_cells``, or an entry is negative or not finite, or a
        row sums to zero.

    """
    b = np.asarray(belief, dtype=float)
    if b.ndim not in (1, 2) or b.shape[-1] != n_cells:
        raise ValueError(f'belief must have shape (N,) or (episodes, N) with N = {n_cells}, '
                         f'got {b.shape}')
    b = np.atleast_2d(b)
    if not np.all(np.isfinite(b)):
        raise ValueError('belief contains NaN or inf')
    if np.any(b < 0):
        raise ValueError('belief contains negative probabilities')
    total = b.sum(axis=1, keepdims=True)
    if np.any(total <= 0):
        raise ValueError('belief has a row that sums to zero')
    return b / total


def check_dprime(dprime) -> np.ndarray:
    """
    Validate the ``d[j, k]`` matrix and return it as a float array.

    Raises
    ------
    ValueError
        When it is not a finite, non-negative square matrix or has d' above :data:`D_MAX`.

    """
    d = np.asarray(dprime, dtype=float)
    if d.ndim != 2 or d.shape[0] != d.shape[1] or not np.all(np.isfinite(d)) or np.any(d < 0):
        raise ValueError(f'dprime must be a finite, non-negative square matrix, got {d.shape}')
    if d.max(initial=0.0) > D_MAX:
        raise ValueError(f"d' up to {D_MAX:g} is supported (the tail probabilities underflow "
                         f'beyond), got {d.max():g}')
    return d


def prune(belief: np.ndarray, s_max: float, tol: float):
    """
    Choose the kept cells of each belief row.

    Parameters
    ----------
    belief : array (E, N)
        Normalised beliefs.
    s_max : float
        ``sqrt(2) * max d``: the largest spread of ``Y_j - Y_m`` over fixations.
    tol : float
        Largest allowed bound on the score error.

    Returns
    -------
    order : int array (E, N)
        Cells by decreasing belief (stable, so ties keep index order).
    sizes : int array (E,)
        Number of kept cells: the first ``sizes[e]`` of ``order[e]``.
    bound : array (E,)
        The proven bound on ``score(k) - score_S(k)`` (the same for every fixation k).

    """
    order = np.argsort(-belief, axis=1, kind='stable')
    srt = np.take_along_axis(belief, order, axis=1)
    with np.errstate(divide='ignore'):
        log_ratio = np.log(srt) - np.log(srt[:, :1])
    if s_max > 0:
        beat = ndtr(log_ratio / s_max + s_max / 2.0)
    else:
        beat = (log_ratio >= 0).astype(float)
    term = srt * beat
    # tail[:, n] = bound when the first n+1 cells are kept.
    tail = np.cumsum(term[:, ::-1], axis=1)[:, ::-1]
    tail = np.concatenate([tail[:, 1:], np.zeros((belief.shape[0], 1))], axis=1)
    sizes = np.argmax(tail <= tol, axis=1) + 1
    bound = tail[np.arange(belief.shape[0]), sizes - 1]
    return order, sizes, bound


def _group_scores(log_b: np.ndarray, dk: np.ndarray, t_nodes: np.ndarray,
                  w_nodes: np.ndarray) -> np.ndarray:
    """
    ``int exp(y) (1 - G_k(y)) dy`` for a group of episodes with the same number of kept cells.

    Parameters
    ----------
    log_b : array (G, S)
        Log belief of the kept cells.
    dk : array (G, S, N)
        ``d_jk`` of kept cell j for every fixation k.
    t_nodes, w_nodes : arrays (Q,)
        Mapped quadrature nodes and weights on [0, 1].

    Returns
    -------
    array (G, N)

    """
    smooth = dk > 0
    lb = log_b[:, :, None]
    mu = lb - 0.5 * dk * dk
    lo = np.max(np.where(smooth, mu - Z_TAIL * dk, lb), axis=1)
    hi = np.max(np.where(smooth, lb + dk * (0.5 * dk + Z_TAIL), -np.inf), axis=1)
    span = np.maximum(hi - lo, 0.0)
    y = lo[..., None] + span[..., None] * t_nodes                 # (G, N, Q)
    # A d = 0 cell is a step below lo: its factor is 1, i.e. its upper tail q = 0.
    mu = np.where(smooth, mu, -np.inf)[..., None]
    inv_d = (1.0 / np.where(smooth, dk, 1.0))[..., None]
    # q_j = 1 - F_j(y) = Phi((mu_j - y) / d_jk);  log G = sum_j log1p(-q_j).
    q = np.subtract(mu, y[:, None, :, :])
    q *= inv_d
    ndtr(q, out=q)
    np.negative(q, out=q)
    np.log1p(q, out=q)
    log_g = np.sum(q, axis=1)                                       # (G, N, Q)
    with np.errstate(divide='ignore'):
        integrand = np.exp(y + np.log(-np.expm1(log_g)))
    return np.exp(lo) + span * (integrand @ w_nodes)


def expected_percent_correct(belief, dprime: np.ndarray, tol: float = DEFAULT_TOL,
                             nodes: int | None = None, power: int | None = None,
                             return_bound: bool = False, max_elements: int = MAX_ELEMENTS):
    """
    Score ``sum_i B_i P(C | i, k)`` of every fixation k: the probability of a correct MAP guess.

    Parameters
    ----------
    belief : array (N,) or (E, N)
        Probabilities (normalised here).
    dprime : array (N, N)
        ``d[j, k]``, from :func:`ipomdp_gaze.model.fpoc.dprime_matrix`.
    tol : float
        Bound on the pruning error of every score (0 keeps every cell with non-zero belief).
    nodes, power : int, optional
        Gauss-Legendre nodes and the power of the node map; :func:`default_nodes` when omitted.
    return_bound : bool
        Also return the per-row pruning bound and kept-set size.
    max_elements : int
        Work-array size per vectorised chunk (memory limit).

    Returns
    -------
    scores : array shaped like ``belief``
        And, with ``return_bound``, ``(scores, bound (E,), kept (E,))``.

    """
    single = np.ndim(belief) == 1
    scores, bound, sizes = _scores(belief, dprime, None, tol, nodes, power, max_elements)
    if single:
        scores, bound, sizes = scores[0], bound[0], sizes[0]
    return (scores, bound, sizes) if return_bound else scores


def expected_percent_correct_at(belief, dprime: np.ndarray, fixations, tol: float = DEFAULT_TOL,
                                nodes: int | None = None, power: int | None = None,
                                max_elements: int = MAX_ELEMENTS) -> np.ndarray:
    """
    Score of one fixation per belief row: ``sum_i B_ei P(C | i, k_e)``.

    The same quantity, quadrature and pruning as :func:`expected_percent_correct`, for the
    fixation ``k_e`` of each row only (N times less work). It is ``E[max_i B'_i]``, the expected
    probability that the MAP guess is right after the observation from ``k_e``: averaged over
    the episodes of a search it is the percent-correct curve with the last observation's noise
    integrated out (a Rao-Blackwellised estimate, lower variance, same mean).

    Parameters
    ----------
    belief : array (E, N)
        Probabilities (normalised here).
    dprime : array (N, N)
        ``d[j, k]``.
    fixations : int array (E,)
        The fixation of each row.
    tol, nodes, power, max_elements
        As in :func:`expected_percent_correct`.

    Returns
    -------
    array (E,)

    """
    return _scores(belief, dprime, fixations, tol, nodes, power, max_elements)[0]


def _scores(belief, dprime, fixations, tol, nodes, power, max_elements):
    """
    Validate, prune and integrate: ``(scores, bound, kept)`` of every fixation, or of one per row.

    ``fixations`` None scores every fixation k (scores (E, N)); an int array (E,) scores only
    ``k_e`` of row e (scores (E,)). The shared work of :func:`expected_percent_correct` and
    :func:`expected_percent_correct_at`.
    """
    d = check_dprime(dprime)
    n = d.shape[0]
    if not np.isfinite(tol) or tol < 0:
        raise ValueError(f'tol must be finite and >= 0, got {tol!r}')
    b = check_belief(belief, n)
    if fixations is not None:
        k = np.asarray(fixations)
        if k.shape != (b.shape[0],) or not np.issubdtype(k.dtype, np.integer) \
                or np.any((k < 0) | (k >= n)):
            raise ValueError(f'fixations must be {b.shape[0]} cell indices in [0, {n}), got '
                             f'{k!r}')
    auto_nodes, auto_power = default_nodes(d)
    t_nodes, w_nodes = mapped_nodes(auto_nodes if nodes is None else nodes,
                                    auto_power if power is None else power)
    order, sizes, bound = prune(b, np.sqrt(2.0) * float(d.max(initial=0.0)), tol)
    columns = n if fixations is None else 1
    scores = np.empty((b.shape[0], columns))
    for size in np.unique(sizes):
        rows = np.flatnonzero(sizes == size)
        if size == 1:
            scores[rows] = b[rows, order[rows, 0]][:, None]
            continue
        chunk = max(1, int(max_elements // (size * columns * t_nodes.size)))
        for start in range(0, rows.size, chunk):
            part = rows[start:start + chunk]
            cells = order[part, :size]
            log_b = np.log(np.take_along_axis(b[part], cells, axis=1))
            dk = d[cells] if fixations is None else d[cells, k[part, None]][:, :, None]
            scores[part] = _group_scores(log_b, dk, t_nodes, w_nodes)
    return (scores if fixations is None else scores[:, 0]), bound, sizes


def _pairwise_tie_win(b_i, b_j, i_lower):
    """
    Whether cell i is named over cell j when both posteriors keep their prior ratio.

    The project tie rule (``argmax_ties_low``) applied to the pair: the lower index wins when it
    is within a relative ``TIE_RTOL`` of the larger value.
    """
    return np.where(i_lower, b_i >= (1.0 - TIE_RTOL) * b_j, (1.0 - TIE_RTOL) * b_i > b_j)


def percent_correct_given_target(belief, dprime: np.ndarray, nodes: int = 512,
                                 max_elements: int = MAX_ELEMENTS) -> np.ndarray:
    """
    Najemnik & Geisler's ``P(C | i, k)`` for one belief, straight from the formula.

    This is the reference the fast score is checked against (``sum_i B_i P[i, k]`` equals
    :func:`expected_percent_correct`); it costs O(N^3 Q). Steps from ``d_jk = 0`` cells become a
    lower limit on w; with ``d_ik = 0`` too the factor is the project tie rule applied to the
    pair (ties go to the lower index), so ``P`` is what :func:`ipomdp_gaze.model.belief.map_cell`
    scores. The integral over ``w in [lower, 8.3]`` uses ``nodes`` Gauss-Legendre nodes.

    Parameters
    ----------
    belief : array (N,)
        Probabilities (normalised here).
    dprime : array (N, N)
        ``d[j, k]``.
    nodes : int
        Gauss-Legendre nodes of the integral over w.
    max_elements : int
        Work-array size per vectorised chunk (memory limit).

    Returns
    -------
    array (N, N)
        ``P[i, k]``: probability that the MAP cell after one observation from fixation k is i,
        given that the target is at i.

    """
    d = check_dprime(dprime)
    n = d.shape[0]
    if np.ndim(belief) != 1:
        raise ValueError('percent_correct_given_target takes a single belief of shape (N,)')
    b = check_belief(belief, n)[0]
    x, wq = np.polynomial.legendre.leggauss(int(nodes))
    with np.errstate(divide='ignore'):
        log_b = np.log(b)
    idx = np.arange(n)
    out = np.empty((n, n))
    chunk = max(1, int(max_elements // (n * n * (x.size + 1))))
    for start in range(0, n, chunk):
        hyp = idx[start:start + chunk]                                  # (H,)
        with np.errstate(invalid='ignore'):
            lr = log_b[hyp, None] - log_b[None, :]                      # (H, J)
        lr = np.where(np.isnan(lr), -np.inf, lr)                        # 0/0: B_i = B_j = 0
        di = d[hyp][:, None, :]                                         # (H, 1, K) d_ik
        dj = d[None, :, :]                                              # (1, J, K) d_jk
        other = (idx[None, :] != hyp[:, None])[:, :, None]              # (H, J, 1)
        lr3 = lr[:, :, None]
        base = lr3 + 0.5 * (di * di + dj * dj)                          # (H, J, K)
        smooth_j = dj > 0
        seen_i = di > 0
        # Constant factors (d_ik = 0): Phi(base / d_jk) or the tie rule.
        tie = _pairwise_tie_win(b[hyp][:, None, None], b[None, :, None],
                                (hyp[:, None] < idx[None, :])[:, :, None])
        with np.errstate(divide='ignore', invalid='ignore'):
            const = np.where(smooth_j, ndtr(base / np.where(smooth_j, dj, 1.0)), tie)
        const = np.where(other, const, 1.0)
        p_const = np.prod(const, axis=1)                                # (H, K)
        # Integrated factors (d_ik > 0): lower limit from the steps of d_jk = 0 competitors.
        with np.errstate(divide='ignore', invalid='ignore'):
            step_w = -(lr3 + 0.5 * di * di) / np.where(seen_i, di, 1.0)
        step_w = np.where(other & ~smooth_j, step_w, -np.inf)
        lower = np.clip(np.max(step_w, axis=1), -W_LIMIT, W_LIMIT)      # (H, K)
        half = (W_LIMIT - lower) / 2.0
        w = lower[..., None] + half[..., None] * (x + 1.0)              # (H, K, Q)
        with np.errstate(divide='ignore', invalid='ignore'):
            arg = (base[..., None] + di[..., None] * w[:, None, :, :]) / \
                np.where(smooth_j, dj, 1.0)[..., None]
        arg = np.where((other & smooth_j)[..., None], arg, np.inf)
        arg = np.where(np.isnan(arg), np.inf, arg)
        prod = np.prod(ndtr(arg), axis=1)                               # (H, K, Q)
        density = np.exp(-0.5 * w * w) / np.sqrt(2.0 * np.pi)
        p_int = half * np.sum(prod * density * wq, axis=-1)
        out[hyp] = np.where(d[hyp] > 0, p_int, p_const)
    return out


class PercentCorrectGreedy:
    """
    Ideal searcher: fixate ``argmax_k sum_i B_i P(C | i, k)`` (ties to the lowest index).

    Batched over episodes and pruned (see the module docstring for the proven error bound).
    """

    name = 'greedy'
    # A slow searcher: evaluate and reproduce run it on fewer episodes.
    costly = True

    def __init__(self, grid: Grid, fpoc: FPOC, tol: float = DEFAULT_TOL,
                 nodes: int | None = None, power: int | None = None,
                 max_elements: int = MAX_ELEMENTS):
        self.grid = grid
        self.fpoc = fpoc
        self.dprime = check_dprime(dprime_matrix(grid, fpoc))
        if not np.isfinite(tol) or tol < 0:
            raise ValueError(f'tol must be finite and >= 0, got {tol!r}')
        auto_nodes, auto_power = default_nodes(self.dprime)
        self.nodes = auto_nodes if nodes is None else nodes
        self.power = auto_power if power is None else power
        mapped_nodes(self.nodes, self.power)
        self.tol = float(tol)
        self.max_elements = int(max_elements)

    def expected_percent_correct(self, belief, return_bound: bool = False):
        """Score of every fixation: probability that the next MAP guess is right."""
        return expected_percent_correct(belief, self.dprime, self.tol, self.nodes, self.power,
                                        return_bound, self.max_elements)

    def select(self, belief, t, rng):
        """Fixation with the highest score for each belief row, ties to the lowest index."""
        return argmax_ties_low(np.atleast_2d(self.expected_percent_correct(belief)))
