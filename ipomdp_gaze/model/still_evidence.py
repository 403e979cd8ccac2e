# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Evidence of a still scene, each cell's counted once: ``search.repeat_weight`` (design §5.5, §6.6).

The naive-Bayes step treats every frame as independent evidence. On a still scene seen by a
deterministic detector that is not so: the views of a pan/tilt head overlap (a 5x5-cell view on
the 11x11 grid), so a cell is seen from up to nine poses, and what the detector says about it
each time is a function of the same pixels. A persistent false alarm is then counted up to nine
times, and so is the face.

:class:`StillEvidence` keeps, per cell, the term of the view that saw it at its most informative
offset so far (the largest ELM kernel value, :func:`cell_information`; on a tie the earlier
view) and the sum of all its terms. The belief is the prior times
``exp(kept + repeat_weight * (sum - kept))``: weight 1 is the naive-Bayes product of every frame
(the default), weight 0 the posterior when every view of a cell repeats the information of its
best view, between them a partial discount of the repeats.
"""
from __future__ import annotations

from ipomdp_gaze.model.checks import check_in_range
import numpy as np


def check_repeat_weight(weight: float, name: str = 'repeat_weight') -> float:
    """
    Return the weight of a cell's repeated views as a float.

    Raises
    ------
    ValueError
        Unless it is in [0, 1].

    """
    return check_in_range(weight, name, 0.0, 1.0)


def cell_information(kernel: np.ndarray, grid, fixation: int) -> np.ndarray:
    """
    How much a frame from ``fixation`` says about each cell: ELM's kernel at the cell's offset.

    ``kernel`` is an observation model's ``elm_kernel()`` on ``grid`` (an offset table,
    :meth:`ipomdp_gaze.model.grid.Grid.fixation_window`: ``2 KL(p_target || p_null)`` for a count
    model, ``d'^2`` for the Gaussian one). Returns ``(N,)``, 0 where the frame says nothing.
    """
    return grid.fixation_window(kernel, *grid.cell(int(fixation))).reshape(-1)


class StillEvidence:
    """
    A search's evidence per cell: the most informative view's term and the sum of all terms.

    Parameters
    ----------
    n_cells : int
        Cells of the grid.

    """

    def __init__(self, n_cells: int):
        self.kept = np.zeros(n_cells)
        self.kept_information = np.zeros(n_cells)
        self.total = np.zeros(n_cells)

    def reset(self) -> None:
        """Forget every frame (a new search)."""
        self.kept[:] = 0.0
        self.kept_information[:] = 0.0
        self.total[:] = 0.0

    def add(self, term: np.ndarray, information: np.ndarray) -> None:
        """
        Record one frame: its per-cell log-likelihood ratios and their information.

        A cell's kept term is replaced when this frame saw it at a strictly more informative
        offset (``information`` 0, for a cell outside the view or not observed, never replaces).
        """
        better = information > self.kept_information
        self.kept[better] = term[better]
        self.kept_information[better] = information[better]
        self.total += term

    def log_likelihood_ratio(self, repeat_weight: float) -> np.ndarray:
        """Per-cell term of the whole search: ``kept + repeat_weight * (sum - kept)``."""
        return self.kept + repeat_weight * (self.total - self.kept)
