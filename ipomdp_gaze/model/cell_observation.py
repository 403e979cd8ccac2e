# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
What one cell's observation is: an integer ``0..K-1`` made from the detections centred in it.

A count model (docs/design.md section 6) tabulates ``P(o | target, offset)`` and
``P(o | no target, offset)`` for ``o`` in ``0..K-1``; it does not care how ``o`` was made. A
cascade returns many raw boxes and no scores, so counting them is the natural observation; a
DNN returns few boxes, each with a score, so the best score says more. :class:`CellObservation`
names the rule, and an observation file records it (key ``cells``; absent: ``counts``):

- ``counts``: the number of detections centred in the cell, clipped to ``K - 1`` (NMPT);
- ``score_bins``: 0 when no detection is centred in the cell, else
  ``1 + searchsorted(edges, best score, 'right')``: the cell's best score in one of ``K - 1``
  bins cut at the ``K - 2`` increasing ``edges``. ``calibrate`` chooses the edges on training
  data (:func:`quantile_edges`: equal shares of the training cells' best scores per bin) and
  records them;
- ``threshold``: the number of detections scoring at least ``threshold``, clipped to ``K - 1``;
- ``grouped``: what OpenCV's grouping of the view's raw boxes says (``groupRectangles`` with
  ``min_neighbors``, as ``detectMultiScale`` groups; the vision layer groups and passes each
  group's cell and support, the number of raw boxes it merged). A cell holding the centre of a
  group reads ``raw_levels + 1 + searchsorted(edges, support, 'right')``, the support of its
  largest-support group in one of ``K - 1 - raw_levels`` bins cut at ``K - 2 - raw_levels``
  increasing ``edges``; a cell without a group reads its raw count clipped to ``raw_levels``
  (``raw_levels`` 0: grouping alone, 0 without a group). Isolated raw boxes, which grouping
  drops and texture gives, then stay below every group (docs/design.md section 6.13).

Scores are compared with the recorded edges, never with the bits of a score, so a DNN whose
scores differ in the last digits on another machine moves a cell by at most one bin near an
edge.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

KINDS = ('counts', 'score_bins', 'threshold', 'grouped')
# The kinds whose observation is binned at recorded edges.
EDGE_KINDS = ('score_bins', 'grouped')


@dataclass(frozen=True)
class CellObservation:
    """
    The rule turning a cell's detections into its observation (module docstring).

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`.
    max_count : int
        K: observations are ``0..K-1`` (at least 2).
    edges : tuple of float
        ``score_bins``: the ``K - 2`` strictly increasing bin edges; ``grouped``: the
        ``K - 2 - raw_levels`` edges on a group's support.
    threshold : float
        ``threshold``: the lowest score counted.
    min_neighbors : int
        ``grouped``: groups of at most this many raw boxes are dropped (OpenCV's
        ``minNeighbors``, at least 1); 0 for the other kinds.
    raw_levels : int
        ``grouped``: a cell without a group reads its raw count clipped to this (0: reads 0).

    """

    kind: str = 'counts'
    max_count: int = 10
    edges: tuple = ()
    threshold: float = 0.0
    min_neighbors: int = 0
    raw_levels: int = 0

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"cell observation kind must be one of {', '.join(KINDS)}, got "
                             f'{self.kind!r}')
        k = self.max_count
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 2:
            raise ValueError(f'max_count must be an int >= 2, got {k!r}')
        edges = tuple(float(e) for e in self.edges)
        self._check_grouping(k)
        if self.kind in EDGE_KINDS:
            need = k - 2 - self.raw_levels
            if len(edges) != need:
                raise ValueError(f'{self.kind} with K = {k}'
                                 + (f' and raw_levels {self.raw_levels}'
                                    if self.kind == 'grouped' else '')
                                 + f' needs {need} edges, got {len(edges)}')
            if not all(math.isfinite(e) for e in edges) or \
                    any(a >= b for a, b in zip(edges, edges[1:])):
                raise ValueError(f'edges must be finite and strictly increasing, got {edges}')
        elif edges:
            raise ValueError(f'edges are for score_bins and grouped, not {self.kind}')
        threshold = float(self.threshold)
        if not math.isfinite(threshold):
            raise ValueError(f'threshold must be a finite number, got {self.threshold!r}')
        object.__setattr__(self, 'max_count', int(k))
        object.__setattr__(self, 'edges', edges)
        object.__setattr__(self, 'threshold', threshold)

    def _check_grouping(self, k: int) -> None:
        """Refuse grouping settings that do not fit the kind (min_neighbors, raw_levels)."""
        for name in ('min_neighbors', 'raw_levels'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
                raise ValueError(f'{name} must be an int >= 0, got {value!r}')
            object.__setattr__(self, name, int(value))
        if self.kind != 'grouped':
            if self.min_neighbors or self.raw_levels:
                raise ValueError(f'min_neighbors and raw_levels are for grouped, not '
                                 f'{self.kind}')
            return
        if self.min_neighbors < 1:
            raise ValueError('grouped needs min_neighbors >= 1: with 0 OpenCV does not group '
                             'and every raw box would be its own group')
        if self.raw_levels > k - 2:
            raise ValueError(f'grouped with K = {k} leaves no bin for a group with raw_levels '
                             f'{self.raw_levels} (at most {k - 2})')

    def values(self, cells, scores, n_cells: int, groups=None) -> np.ndarray:
        """
        Observation ``0..K-1`` of each of ``n_cells`` cells, ``(n_cells,)`` ``int64``.

        ``cells`` ``(M,)`` is the cell of each detection (all in ``0..n_cells-1``) and
        ``scores`` ``(M,)`` its score. ``grouped`` also needs ``groups``, ``(group_cells,
        support)``: the cell of each grouped box's centre and the raw boxes it merged.
        """
        cells = np.asarray(cells, dtype=np.int64)
        scores = np.asarray(scores, dtype=np.float64)
        top = self.max_count - 1
        if self.kind == 'counts':
            return np.minimum(np.bincount(cells, minlength=n_cells), top)
        if self.kind == 'grouped':
            if groups is None:
                raise ValueError('grouped cells need the grouped boxes (groups=(cells, '
                                 'support))')
            group_cells = np.asarray(groups[0], dtype=np.int64)
            support = np.asarray(groups[1], dtype=np.float64)
            best = np.zeros(n_cells)
            np.maximum.at(best, group_cells, support)
            raw = np.minimum(np.bincount(cells, minlength=n_cells), self.raw_levels)
            bins = self.raw_levels + 1 + np.searchsorted(np.asarray(self.edges), best,
                                                         side='right')
            return np.where(best > 0, bins, raw).astype(np.int64)
        if self.kind == 'threshold':
            kept = cells[scores >= self.threshold]
            return np.minimum(np.bincount(kept, minlength=n_cells), top)
        best = np.full(n_cells, -np.inf)
        np.maximum.at(best, cells, scores)
        bins = 1 + np.searchsorted(np.asarray(self.edges), best, side='right')
        return np.where(np.isfinite(best), bins, 0).astype(np.int64)

    def to_dict(self) -> dict:
        """Plain types for an observation file (only the keys the kind uses)."""
        out = {'kind': self.kind, 'max_count': self.max_count}
        if self.kind in EDGE_KINDS:
            out['edges'] = list(self.edges)
        if self.kind == 'grouped':
            out['min_neighbors'] = self.min_neighbors
            out['raw_levels'] = self.raw_levels
        if self.kind == 'threshold':
            out['threshold'] = self.threshold
        return out

    @classmethod
    def from_dict(cls, data) -> CellObservation:
        """Inverse of :meth:`to_dict`; unknown keys are errors."""
        if not isinstance(data, dict):
            raise ValueError(f'a cell observation must be a mapping, got {type(data).__name__}')
        unknown = sorted(set(data) - {'kind', 'max_count', 'edges', 'threshold',
                                      'min_neighbors', 'raw_levels'})
        if unknown:
            raise ValueError(f'unknown cell observation setting {unknown[0]!r}')
        values = dict(data)
        values['edges'] = tuple(values.get('edges') or ())
        return cls(**values)


def quantile_edges(best_scores, n_bins: int) -> tuple:
    """
    Edges giving ``n_bins`` bins of about equal shares of ``best_scores`` (training data).

    The ``n_bins - 1`` edges are the quantiles at ``1/n_bins .. (n_bins-1)/n_bins``, rounded to
    6 decimals; equal quantiles (a detector with few distinct scores) are merged and an edge at
    the lowest score (which would leave the first bin empty) is dropped, so fewer bins may come
    back.

    Raises
    ------
    ValueError
        If there is no score to choose from.

    """
    scores = np.asarray(best_scores, dtype=np.float64).ravel()
    scores = scores[np.isfinite(scores)]
    if scores.size == 0:
        raise ValueError('no detection on the training data: no score to choose bin edges from')
    q = np.arange(1, n_bins) / n_bins
    edges = np.unique(np.round(np.quantile(scores, q), 6))
    return tuple(float(e) for e in edges if e > scores.min())


def cell_observation_of(meta: dict, max_count: int) -> CellObservation:
    """Return the cell observation an observation file records (``meta['cells']``), else counts."""
    block = (meta or {}).get('cells')
    if block is None:
        return CellObservation('counts', int(max_count))
    rule = CellObservation.from_dict(dict(block))
    if rule.max_count != max_count:
        raise ValueError(f'the observation file records cells with K = {rule.max_count} but its '
                         f'tables have K = {max_count}')
    return rule
