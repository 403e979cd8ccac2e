# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A belief over many targets: one independent occupancy per cell (docs/design.md section 11).

``x_j = 1`` when a target's centre lies in cell j. A priori the ``x_j`` are independent with
``P(x_j = 1) = q``. Given the occupancy, every cell's observation depends on its own ``x_j``
only, through the same per-offset pair of distributions the single-target belief uses
(``p_T`` when occupied, ``p_N`` when empty; the Gaussian model ``N(d, 1)`` / ``N(0, 1)``, a count
model's tables, the scan's ``s_T`` / ``s_N``). The posterior then factorises over cells, and each
cell is a binary Bayes filter in log odds (occupancy grid mapping, Elfes 1989; *Probabilistic
Robotics* 4.2):

    L_j = log(q / (1 - q)) + sum_frames [log p_T(o_j | offset_jk) - log p_N(o_j | offset_jk)]

which is exactly the single-target belief's per-cell term ``l_j`` (NaN: not observed, 0).
``P(x_j = 1) = sigmoid(L_j)``; "nobody here" is ``prod_j (1 - P(x_j = 1))``. Conditioned on
exactly one occupied cell the posterior is ``softmax(L)``, the single-target belief with a
uniform prior; conditioned on at most one it is ``softmax([L, 0])``, the single-target belief
with the absent hypothesis of prior ``a`` when ``q / (1 - q) = (1 - a) / (N a)``.

**Infomax.** A fixation k sees cell j through the channel ``(p_T, p_N)`` at offset ``jk``; its
expected reduction of the summed cell entropies is ``sum_j I(P(x_j); offset_jk)``, the binary
channel's mutual information (:func:`channel_information`), because the cells are independent
given the occupancy and a priori. :class:`InformationTable` tabulates ``I`` over log odds per
offset once per model so that the gains of every candidate fixation are one gather and a sum.

**Counted once** (:func:`count_faces`). Tables calibrated with one face per image count a face's
detections that land in a neighbour cell as that neighbour's "no target" evidence only in part,
so with several faces a neighbour of a face can look occupied too. A face is therefore reported
once per cluster of occupied cells (cells within ``link`` cells, Chebyshev, of each other), split
only where the detector's own boxes in the cluster are distinct faces.

Pure numpy (and scipy's connected components); no ROS, no policies.
"""
from __future__ import annotations

import math
import threading

from ipomdp_gaze.model.checks import check_number
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

# Log odds the information table covers; beyond it the gain of a cell is ~0 (decided).
TABLE_LOG_ODDS = 30.0
TABLE_STEP = 0.1
# Gaussian channel discretised into this many observation bins (for information only).
GAUSSIAN_BINS = 801


def check_occupancy_prior(value, name: str = 'occupancy prior') -> float:
    """Return a per-cell prior ``q`` in (0, 1) (ValueError with the reason otherwise)."""
    if not 0.0 < check_number(value, name) < 1.0:
        raise ValueError(f'{name} must be between 0 and 1 (exclusive), got {value!r}')
    return float(value)


def cell_prior(n_cells: int, absent_prior: float = 0.0) -> float:
    """
    Return the per-cell prior ``q``: ``P(nobody) = (1 - q)^N = absent_prior``, or ``1 / N`` for 0.

    So ``absent.prior`` means "nobody here" in both beliefs.
    """
    if absent_prior <= 0:
        return 1.0 / n_cells
    return -math.expm1(math.log(absent_prior) / n_cells)


def prior_log_odds(n_cells: int, q: float) -> np.ndarray:
    """``log(q / (1 - q))`` in every cell, shape (N,)."""
    q = check_occupancy_prior(q, 'q')
    return np.full(n_cells, math.log(q) - math.log1p(-q))


def update_log_odds(log_odds: np.ndarray, term: np.ndarray,
                    out: np.ndarray | None = None) -> np.ndarray:
    """
    One frame: ``L_j += l_j``, with ``l_j`` an observation model's per-cell log-likelihood ratio.

    ``term`` (..., N) is what the single-target step adds (0 for unobserved cells); no
    renormalisation: each cell is its own binary filter.
    """
    if out is None:
        return np.asarray(log_odds, dtype=float) + term
    np.add(log_odds, term, out=out)
    return out


def occupancy(log_odds: np.ndarray) -> np.ndarray:
    """``P(x_j = 1) = 1 / (1 + exp(-L_j))`` (..., N), without overflow."""
    return np.exp(-np.logaddexp(0.0, -np.asarray(log_odds, dtype=float)))


def log_nobody(log_odds: np.ndarray) -> np.ndarray:
    """``log P(every cell empty) = -sum_j log(1 + exp(L_j))`` (...)."""
    return -np.sum(np.logaddexp(0.0, log_odds), axis=-1)


def one_target_belief(log_odds: np.ndarray, absent: bool = False) -> np.ndarray:
    """
    Return the posterior conditioned on exactly one occupied cell: ``softmax(L)`` (..., N).

    ``absent=True`` conditions on at most one: ``softmax([L, 0])`` (..., N + 1), "nobody" last.
    A batch (E, N) gives each row's own.
    """
    log_odds = np.asarray(log_odds, dtype=float)
    if absent:
        log_odds = np.concatenate([log_odds, np.zeros(log_odds.shape[:-1] + (1,))], axis=-1)
    z = log_odds - log_odds.max(axis=-1, keepdims=True)
    e = np.exp(z)
    return e / e.sum(axis=-1, keepdims=True)


def binary_entropy(p: np.ndarray) -> np.ndarray:
    """``-p log p - (1 - p) log(1 - p)`` in nats (0 log 0 = 0)."""
    p = np.asarray(p, dtype=float)
    with np.errstate(divide='ignore', invalid='ignore'):
        h = -(np.where(p > 0, p * np.log(p), 0.0) + np.where(p < 1, (1 - p) * np.log1p(-p), 0.0))
    return h


def channel_information(p, p_target, p_null) -> np.ndarray:
    """
    Mutual information (nats) between a binary cell and one observation of it.

    ``I = sum_c [p p_T(c) log(p_T(c) / m(c)) + (1 - p) p_N(c) log(p_N(c) / m(c))]`` with
    ``m = p p_T + (1 - p) p_N``: the expected entropy reduction ``H(p) - E_c H(p | c)``.

    Parameters
    ----------
    p : array (...)
        ``P(x = 1)`` of each cell.
    p_target, p_null : array (..., K)
        The channel of each cell (broadcast against ``p``), observations on the last axis.

    """
    p = np.asarray(p, dtype=float)[..., None]
    pt, pn = np.asarray(p_target, dtype=float), np.asarray(p_null, dtype=float)
    m = p * pt + (1 - p) * pn
    with np.errstate(divide='ignore', invalid='ignore'):
        a = np.where(pt > 0, p * pt * np.log(pt / m), 0.0)
        b = np.where(pn > 0, (1 - p) * pn * np.log(pn / m), 0.0)
    return np.maximum(np.sum(a + b, axis=-1), 0.0)


def channels(model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Return the per-offset channels of a model: ``(p_T (M, K), p_N (M, K), offset_id)``.

    ``offset_id`` is the ``(2R-1, 2C-1)`` offset table (docs/design.md 1.1) of row indices into
    the M channels. A count model gives its tables; the Gaussian model's ``N(d, 1)`` and
    ``N(0, 1)`` are binned on a fine grid of observations (:data:`GAUSSIAN_BINS`), which only
    the information needs (the belief uses the exact ratio).
    """
    if hasattr(model, 'p_target'):
        rows, cols, k = model.p_target.shape
        dr = np.abs(np.arange(-(rows - 1), rows))
        dc = np.abs(np.arange(-(cols - 1), cols))
        return (model.p_target.reshape(rows * cols, k), model.p_null.reshape(rows * cols, k),
                dr[:, None] * cols + dc[None, :])
    from scipy.stats import norm
    d, inverse = np.unique(np.asarray(model.table, dtype=float), return_inverse=True)
    edges = np.linspace(-9.0, d.max() + 9.0, GAUSSIAN_BINS + 1)
    edges[0], edges[-1] = -np.inf, np.inf
    cdf_t = norm.cdf(edges[None, :] - d[:, None])
    cdf_n = norm.cdf(edges)
    return (np.diff(cdf_t, axis=1), np.broadcast_to(np.diff(cdf_n), (d.size, GAUSSIAN_BINS)),
            inverse.reshape(model.table.shape))


class InformationTable:
    """
    ``I(sigmoid(L); offset)`` on a grid of log odds per offset, for many candidates at once.

    Built once per model: ``M x B`` channel informations (B log-odds points from
    ``-TABLE_LOG_ODDS`` to ``+TABLE_LOG_ODDS`` in steps of ``TABLE_STEP``), read by linear
    interpolation in L (clamped at the ends, where I is ~0).
    """

    def __init__(self, model):
        pt, pn, offset_id = channels(model)
        # Offsets with the same pair of distributions (far offsets, symmetric ones) share a row.
        distinct, first, inverse = np.unique(np.concatenate([pt, pn], axis=1), axis=0,
                                             return_index=True, return_inverse=True)
        self.offset_id = inverse.reshape(-1)[offset_id]
        self.grid = model.grid
        self.log_odds = np.arange(-TABLE_LOG_ODDS, TABLE_LOG_ODDS + TABLE_STEP / 2, TABLE_STEP)
        p = occupancy(self.log_odds)
        self.table = channel_information(p[None, :], pt[first][:, None, :],
                                         pn[first][:, None, :])             # (M, B)
        ri, ci = self.grid.pair_offset_index()
        # [k, j] -> the flat index of (channel of offset k - j, cell j) in by_channel's (M, N):
        # one 1-D take per call (a gather with two broadcast index arrays costs 4x more).
        flat = np.array(self.offset_id[ri, ci], dtype=np.intp, order='C')
        flat *= flat.shape[1]
        flat += np.arange(flat.shape[1])
        self.flat_pair = flat
        kernel = np.asarray(model.elm_kernel(), dtype=float)
        self.view_information = np.ascontiguousarray(kernel[ri, ci])     # [k, j] ELM kernel

    def by_channel(self, log_odds: np.ndarray) -> np.ndarray:
        """``I`` of every cell (N,) through every distinct channel: (M, N), interpolated."""
        x = (np.clip(log_odds, -TABLE_LOG_ODDS, TABLE_LOG_ODDS) + TABLE_LOG_ODDS) / TABLE_STEP
        i0 = np.minimum(np.floor(x).astype(np.intp), self.log_odds.size - 2)
        f = x - i0
        return self.table[:, i0] * (1 - f) + self.table[:, i0 + 1] * f

    def __call__(self, log_odds: np.ndarray, candidates=None) -> np.ndarray:
        """``I[k, j]`` of cell j seen from candidate k: (K, N), K = all cells by default."""
        flat = self.flat_pair if candidates is None else \
            self.flat_pair[np.asarray(candidates)]
        return np.take(self.by_channel(log_odds).ravel(), flat)


# id(model) -> (model, table) of the last TABLE_CACHE_SIZE models, oldest first; read and
# written under _TABLES_LOCK only (composed nodes on a MultiThreadedExecutor share it).
TABLE_CACHE_SIZE = 8
_TABLES = {}
_TABLES_LOCK = threading.Lock()


def information_table(model) -> InformationTable:
    """
    Return the :class:`InformationTable` of a model, built once per model (a small cache).

    Safe from many threads: a table is built outside the lock (another model's caller does not
    wait for it) and published under it; of two threads that built one model's table at once,
    both return the one published first.
    """
    key = id(model)
    with _TABLES_LOCK:
        cached = _TABLES.get(key)
    if cached is not None and cached[0] is model:
        return cached[1]
    table = InformationTable(model)
    with _TABLES_LOCK:
        cached = _TABLES.get(key)
        if cached is None or cached[0] is not model:      # not published meanwhile
            _TABLES.pop(key, None)                         # a freed model's reused id
            while len(_TABLES) >= TABLE_CACHE_SIZE:
                _TABLES.pop(next(iter(_TABLES)))
            cached = _TABLES[key] = (model, table)
    return cached[1]


def decided(log_odds: np.ndarray, confidence: float) -> tuple[np.ndarray, np.ndarray]:
    """Masks (N,) of cells decided occupied (``P >= c``) and empty (``P <= 1 - c``)."""
    threshold = math.log(confidence) - math.log1p(-confidence)
    return log_odds >= threshold, log_odds <= -threshold


def clusters(cells: np.ndarray, grid, link: int = 1) -> np.ndarray:
    """
    Label (M,) of cells (M,) grouped into clusters: linked when within ``link`` cells (Chebyshev).

    Labels are 0.. in order of each cluster's first cell.
    """
    cells = np.asarray(cells, dtype=np.intp)
    if cells.size == 0:
        return np.zeros(0, dtype=np.intp)
    r, c = np.divmod(cells, grid.cols)
    near = np.maximum(np.abs(r[:, None] - r[None, :]), np.abs(c[:, None] - c[None, :])) <= link
    i, j = np.nonzero(near)
    graph = coo_matrix((np.ones(i.size), (i, j)), shape=(cells.size, cells.size))
    _, labels = connected_components(graph, directed=False)
    _, first = np.unique(labels, return_index=True)
    order = np.argsort(np.argsort(first))
    return order[labels]


def box_iou(a: np.ndarray, b: np.ndarray, over: str = 'union') -> np.ndarray:
    """
    Intersection over union (A, B) of boxes ``x, y, w, h`` (A, 4) and (B, 4).

    ``over='smaller'``: over the smaller box's area (1 when one box lies inside the other).
    """
    a, b = np.asarray(a, dtype=float).reshape(-1, 4), np.asarray(b, dtype=float).reshape(-1, 4)
    x0 = np.maximum(a[:, None, 0], b[None, :, 0])
    y0 = np.maximum(a[:, None, 1], b[None, :, 1])
    x1 = np.minimum(a[:, None, 0] + a[:, None, 2], b[None, :, 0] + b[None, :, 2])
    y1 = np.minimum(a[:, None, 1] + a[:, None, 3], b[None, :, 1] + b[None, :, 3])
    inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)
    area_a, area_b = (a[:, 2] * a[:, 3])[:, None], (b[:, 2] * b[:, 3])[None, :]
    union = np.minimum(area_a, area_b) if over == 'smaller' else area_a + area_b - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)


def merge_boxes(boxes, scores=None, iou: float = 0.3, inside: float = 0.6,
                best: bool = False) -> tuple:
    """
    Greedy non-maximum suppression: the distinct boxes ``(F, 4)`` and their support ``(F,)``.

    Boxes in decreasing score order; a box overlapping a kept one by more than ``iou`` (of the
    union), or lying in it by more than ``inside`` (of the smaller box), joins it. One face
    seen by several windows and scales is one box; its support is the sum of the scores of the
    raw boxes it took (1 each for a detector without scores). Ties (every box of a detector
    without scores) go to the box that most others overlap by ``iou``, the middle of a cluster
    of raw detections (then the larger): a stray large box round a face and its neighbour
    does not become the face's box. ``best``: also return each box's best raw score ``(F,)``.
    """
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    if boxes.shape[0] == 0:
        return (boxes, np.zeros(0, dtype=np.intp)) + ((np.zeros(0),) if best else ())
    scores = np.ones(len(boxes)) if scores is None else np.asarray(scores, dtype=float)
    similar = box_iou(boxes, boxes) > iou
    order = np.lexsort((-boxes[:, 2] * boxes[:, 3], -similar.sum(axis=1), -scores))
    overlap = similar | (box_iou(boxes, boxes, 'smaller') > inside)
    owner = np.full(len(boxes), -1)
    kept = []
    for i in order:                       # over detections (a handful per face), not cells
        if owner[i] >= 0:
            continue
        owner[i] = len(kept)
        owner[(owner < 0) & overlap[i]] = len(kept)
        kept.append(i)
    support = np.bincount(owner, weights=scores, minlength=len(kept))
    if not best:
        return boxes[kept], support
    top = np.full(len(kept), -np.inf)
    np.maximum.at(top, owner, scores)
    return boxes[kept], support, top


def _supported(boxes: np.ndarray, counts: np.ndarray, support: float, top=None,
               strong: float | None = None) -> np.ndarray:
    """
    Return which of a cluster's merged boxes ``(K, 4)`` are faces of their own (bool, (K,)).

    A box is one when its support is at least ``support`` times the cluster's best. With
    ``strong``, a box whose best raw score ``top`` reaches it needs that only of the boxes
    beside it (centres closer than the larger of the two on both axes): a stray box beside a
    face is still not a second face.
    """
    if strong is None:
        return counts >= support * counts.max()
    centres = boxes[:, :2] + boxes[:, 2:] / 2
    near = ((np.abs(centres[:, None, 0] - centres[None, :, 0])
             < np.maximum(boxes[:, None, 2], boxes[None, :, 2]))
            & (np.abs(centres[:, None, 1] - centres[None, :, 1])
               < np.maximum(boxes[:, None, 3], boxes[None, :, 3])))
    local = counts >= support * np.where(near, counts[None, :], 0.0).max(axis=1)
    return local & ((counts >= support * counts.max()) | (top >= strong))


def cell_boxes_px(grid, cells, image_px) -> np.ndarray:
    """Pixel rectangles ``x, y, w, h`` (M, 4) of cells in an image of ``(width, height)``."""
    width, height = image_px
    r, c = np.divmod(np.asarray(cells, dtype=np.int64), grid.cols)
    x0, x1 = (c * width) // grid.cols, ((c + 1) * width) // grid.cols
    y0, y1 = (r * height) // grid.rows, ((r + 1) * height) // grid.rows
    return np.stack([x0, y0, x1 - x0, y1 - y0], axis=1).astype(float)


def _box_cells(boxes: np.ndarray, grid, image_px) -> np.ndarray:
    """
    Return the cell of each box centre (M,), a centre outside the image in the nearest edge cell.

    A wide view at the grid's edge sees past it (the 40-degree lens), so a box may lie outside
    the picture the grid tiles.
    """
    centres = boxes[:, :2] + boxes[:, 2:] / 2
    width, height = image_px
    row = np.clip(np.floor(centres[:, 1] * grid.rows / height), 0, grid.rows - 1)
    col = np.clip(np.floor(centres[:, 0] * grid.cols / width), 0, grid.cols - 1)
    return (row * grid.cols + col).astype(np.intp)


def count_faces(log_odds: np.ndarray, grid, occupied: np.ndarray, boxes=None, scores=None,
                image_px=None, link: int = 2, iou: float = 0.3,
                support: float = 0.5, strong: float | None = None) -> list[dict]:
    """
    Return one face per cluster of occupied cells, split where the detector's boxes differ.

    Parameters
    ----------
    log_odds : array (N,)
        The occupancy belief.
    grid : Grid
        Its grid.
    occupied : bool array (N,)
        Cells decided occupied.
    boxes, scores : arrays (M, 4), (M,), optional
        Every raw detection of the search in image pixels ``x, y, w, h`` (and its score).
    image_px : (int, int), optional
        ``(width, height)``; needed for boxes.
    link : int
        Occupied cells within this many cells (Chebyshev) belong to one cluster.
    iou : float
        Raw boxes overlapping more than this are one face (:func:`merge_boxes`).
    support : float
        A cluster is split only by merged boxes with at least this share of the support of its
        best-supported box (a stray raw box beside a face does not make a second face).
    strong : float, optional
        A detector's strong score (``find --all``'s coarse pass): a merged box holding a raw box
        of that score needs the share of ``support`` only of the boxes beside it, so that in a
        crowd a face one call saw stays a face beside faces that several calls saw. Ignored
        without ``scores`` (a detector that keeps none has no strong score).

    Returns
    -------
    list of dict
        ``{'cell': int, 'cells': array, 'probability': float, 'box': array (4,) or None}``,
        most probable first; ``cell`` is the cell of the box centre, else the cell at its cells'
        probability-weighted centroid (spill-over spreads evenly round a face).
        ``probability`` is ``P(at least one of its cells is occupied) = 1 - prod (1 - P(x_j))``.
        A cluster with two or more distinct boxes centred in its cells (or the cells next to
        them) is that many faces; each takes the cells nearest its box centre. Otherwise it is
        one face, with the merged box of its detections, or its cells' pixel rectangle.

    """
    occupied_cells = np.flatnonzero(occupied)
    labels = clusters(occupied_cells, grid, link)
    log_empty = -np.logaddexp(0.0, log_odds)                  # log(1 - P(x_j = 1))
    merged = counts = centre_cells = None
    if boxes is not None and image_px is not None and len(boxes):
        merged, counts, top = merge_boxes(boxes, scores, iou, best=True)
        if scores is None:
            strong = None
        centre_cells = _box_cells(merged, grid, image_px)
    faces = []
    for label in range(labels.max() + 1 if labels.size else 0):
        cells = occupied_cells[labels == label]
        own = np.zeros(0, dtype=np.intp)
        if merged is not None:
            r, c = np.divmod(cells, grid.cols)
            br, bc = np.divmod(centre_cells, grid.cols)
            dist = np.maximum(np.abs(br[:, None] - r[None, :]), np.abs(bc[:, None] - c[None, :]))
            own = np.flatnonzero(dist.min(axis=1) <= 1)
            if own.size:
                own = own[_supported(merged[own], counts[own], support, top[own], strong)]
        if own.size >= 2:
            r, c = np.divmod(cells, grid.cols)
            br, bc = np.divmod(centre_cells[own], grid.cols)
            nearest = np.argmin((br[:, None] - r[None, :]) ** 2 + (bc[:, None] - c[None, :]) ** 2,
                                axis=0)
            parts = [(cells[nearest == i], merged[b]) for i, b in enumerate(own)]
        elif own.size == 1:
            parts = [(cells, merged[own[0]])]
        else:
            box = None
            if image_px is not None:
                rect = cell_boxes_px(grid, cells, image_px)
                x0, y0 = rect[:, 0].min(), rect[:, 1].min()
                box = np.array([x0, y0, (rect[:, 0] + rect[:, 2]).max() - x0,
                                (rect[:, 1] + rect[:, 3]).max() - y0])
            parts = [(cells, box)]
        for part, box in parts:
            if part.size == 0:                # a box whose cells all went to its neighbour
                part = cells[[int(np.argmax(log_odds[cells]))]]
            r, c = np.divmod(part, grid.cols)           # spill-over spreads round the face
            w = occupancy(log_odds[part])
            best = int(np.rint(w @ r / w.sum()) * grid.cols + np.rint(w @ c / w.sum()))
            if box is not None and merged is not None and own.size:
                best = int(_box_cells(box[None, :], grid, image_px)[0])
            faces.append({'cell': best, 'cells': part,
                          'probability': float(-np.expm1(log_empty[part].sum())),
                          'box': None if box is None else np.asarray(box, dtype=float)})
    faces.sort(key=lambda f: -f['probability'])
    return faces


# Predicted log odds are kept at most this far from 0 (P within 1e-13 of 0 or 1).
MAX_LOG_ODDS = 30.0


def predict_occupancy(log_odds: np.ndarray, outside: float, motion, seconds: float,
                      update: bool = True) -> tuple[np.ndarray, float]:
    """
    Predict the occupancy belief over ``seconds`` of the targets' motion: ``(L', outside')``.

    The expected number of targets in each cell, ``m_j = P(x_j = 1)``, and ``outside``, the
    expected number out of the grid's reach, move exactly as one target's belief and its absent
    hypothesis do (:meth:`ipomdp_gaze.model.motion.Motion.predict_over`, per-second parameters:
    walking out of the grid and ``leave_prob`` move mass between the grid and ``outside``): the
    first moment of independently moving targets (the PHD filter's prediction, Mahler 2003).
    The step conserves the total, so it runs on the normalised vector. The occupancy is then
    ``P'_j = m'_j``, clipped below 1. For one target (every other cell empty) that is the exact
    ``P'_j = P_i T_ij``; for several it is ``1 - prod_i (1 - P_i T_ij)`` (the exact occupancy when
    cells hold independent targets) plus at most ``sum_{a < b} P_a T_aj P_b T_bj``, the chance that
    two of them step into one cell (docs/design.md section 12.10). ``update=False``: a look
    ahead that leaves a walking motion's velocities as they were.
    """
    log_odds = np.asarray(log_odds, dtype=float)
    if not motion.active or seconds <= 0:
        return log_odds.copy(), float(outside)
    n = log_odds.shape[-1]
    log_mass = -np.logaddexp(0.0, -log_odds)                   # log P(x_j = 1)
    with np.errstate(divide='ignore'):
        joint = np.append(log_mass, math.log(outside) if outside > 0 else -np.inf)
    total = float(np.logaddexp.reduce(joint))
    joint -= total
    motion.predict_over(joint, seconds, update=update)
    log_mass = np.minimum(joint[:n] + total, 0.0)
    with np.errstate(divide='ignore'):
        predicted = log_mass - np.log(-np.expm1(log_mass))
    return (np.clip(predicted, -np.inf, MAX_LOG_ODDS),
            float(np.exp(joint[n] + total)) if np.isfinite(joint[n]) else 0.0)
