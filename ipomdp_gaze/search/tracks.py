# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The people a moving many-target search follows: one track each, and the head's time in turns.

With ``search.targets: many`` and motion on (docs/design.md section 12.10) the occupancy belief
(:mod:`ipomdp_gaze.model.occupancy`) is predicted between frames and updated cell by cell; it says
where people are, not who is who. :class:`Tracks` keeps who: after each frame every person found
is looked for within :data:`GATE_CELLS` of where it was (of where its position filter puts it),
all of them at once: the frame's peaks (cells holding someone, at least the keep probability
over a cell and its neighbours, the likeliest of its :data:`SPILL_CELLS` neighbourhood) go
to the people by global nearest-neighbour assignment (the fewest squared cells between each
person's predicted position and its peak, among assignments that keep the most people; Bar-Shalom
and Li's GNN), so that where two people meet each keeps the peak its motion leads to, not
whichever is likelier:

- it stays found at the likeliest cell there while that cell and its neighbours (within
  :data:`SPILL_CELLS`) hold someone with at least the keep probability
  (``motion.keep_probability``, the confidence when 0): ``1 - prod (1 - P_j)`` over them, so
  a face stepping from one cell to the next, its probability split between both, is not lost.
  Those cells are its own (a face's detections spill into its neighbours);
- otherwise it is ``lost`` if the frame looked there (saw that likeliest cell): the head looked
  and nobody was there. A person the frame did not look at stays found at the likeliest cell of
  its predicted occupancy, however spread (its position filter dropped): while the head follows
  someone else the others walk on unseen, and are looked for when their turn comes; unconfirmed
  for longer than a round of turns (``unseen_s``), it is lost;
- an occupied cell (``P >= confidence``) that no found person owns is somebody: each cluster of
  such cells (within ``link`` cells) is one person, at its likeliest cell. Faces are not told
  apart, so while someone is lost the person found is taken to be the lost one nearest to it
  (``reacquired``); with nobody lost it is new (``found``, the next person number).

Each person found has its own ``motion.track_view: position`` filter
(:class:`ipomdp_gaze.model.position_filter.PositionFilter`), fed with the detections around its
cell. :class:`Turns` shares the head between them: each person is looked at for
``motion.dwell_s`` seconds in the order found, and after each round one view (a glance) goes to
the search for people not yet found.

The occupancy probabilities each method takes are checked where they enter (:meth:`Tracks.step`,
:meth:`~Tracks.peaks`, :meth:`~Tracks.held`): a ValueError names what is wrong (the shape, or
the first cell that is NaN, infinite or outside [0, 1]) before any track changes;
:meth:`~Tracks.view` refuses an ``ahead`` (occupancy or log odds) of another shape or with a
NaN. NaN would have passed every comparison as false: a person lost and reacquired in one
frame at probability nan, or its gate's likeliest cell taken anywhere.

Pure: no ROS, no clock (times arrive as seconds).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from ipomdp_gaze.model.observation import check_evidence
from ipomdp_gaze.model.occupancy import clusters
from ipomdp_gaze.model.position_filter import GATE_CELLS as FILTER_GATE_CELLS
from ipomdp_gaze.model.position_filter import measured_position, PositionFilter
import numpy as np
from scipy.ndimage import maximum_filter
from scipy.optimize import linear_sum_assignment

# A person found is looked for again within this many cells (Chebyshev) of where it was: a face
# walking 20 deg/s crosses 2 cells of 10 degrees in the second between two looks at it.
GATE_CELLS = 2
# Cells within this many cells of a person's cell are its spill-over, not another person.
SPILL_CELLS = 1
# The view of a turn of Turns that looks for people not found yet.
GLANCE = None
# The search's turn lasts at most this share of a person's (``motion.dwell_s``): chosen on
# training walks of two people (docs/design.md section 12.10).
SEARCH_SHARE = 0.5


@dataclass
class Track:
    """One person: its number, cell, probability, whether found, and since when (seconds)."""

    person: int
    cell: int
    probability: float
    found: bool = True
    since_s: float = 0.0
    confirmed_s: float = 0.0
    position: PositionFilter | None = None

    def to_dict(self, grid) -> dict:
        """Plain types: person, cell, row, col, probability, found."""
        row, col = grid.cell(self.cell)
        return {'person': self.person, 'cell': int(self.cell), 'row': int(row),
                'col': int(col), 'probability': float(self.probability), 'found': self.found}


def check_probability(probability, grid) -> np.ndarray:
    """
    Return occupancy probabilities ``P(x_j = 1)`` as float64 (N,), or raise ValueError.

    One per cell, (N,) or (rows, cols), each finite and in [0, 1]; the error names the first
    cell that is not, as ``cell (row, col)``.
    """
    try:
        values = np.asarray(probability, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f'probability must be numbers, one per cell, got '
                         f'{type(probability).__name__}') from None
    if values.shape not in ((grid.n_cells,), (grid.rows, grid.cols)):
        raise ValueError(f'probability must have shape ({grid.n_cells},) or ({grid.rows}, '
                         f'{grid.cols}), got {values.shape}')
    values = values.reshape(-1)
    for bad, rule in ((~np.isfinite(values), 'finite'),
                      ((values < 0) | (values > 1), 'in [0, 1]')):
        if np.any(bad):         # a NaN first: it is neither below 0 nor above 1
            i = int(np.argmax(bad))
            raise ValueError(f'probability must be {rule} in every cell: cell {_rc(grid, i)} is '
                             f'{values[i]:g}')
    return values


def _rc(grid, cell: int) -> tuple[int, int]:
    """Return a cell's ``(row, col)`` as plain ints (for messages)."""
    row, col = grid.cell(int(cell))
    return int(row), int(col)


def _check_keep(keep) -> float:
    """Return the keep probability as a float in [0, 1], or raise ValueError."""
    try:
        value = float(keep)
    except (TypeError, ValueError):
        value = math.nan
    if not 0.0 <= value <= 1.0:
        raise ValueError(f'keep must be a probability in [0, 1], got {keep!r}')
    return value


def near(grid, cell: int, radius: int) -> np.ndarray:
    """Cells (N,) within ``radius`` cells (Chebyshev) of ``cell``."""
    rows, cols = np.divmod(np.arange(grid.n_cells), grid.cols)
    r, c = divmod(int(cell), grid.cols)
    return (np.abs(rows - r) <= radius) & (np.abs(cols - c) <= radius)


class Tracks:
    """
    The people of a moving many-target search (module docstring).

    Parameters
    ----------
    grid : Grid
        The visual array.
    make_filter : callable
        Returns a new position filter for a person found, or None (no ``motion.track_view:
        position``).
    link : int
        Occupied cells within this many cells of each other are one person.

    """

    def __init__(self, grid, make_filter=lambda: None, link: int = 2):
        self.grid = grid
        self.make_filter = make_filter
        self.link = int(link)
        self.reset()

    def reset(self) -> None:
        """Forget everyone: the next person found is person 1."""
        self.tracks: list[Track] = []
        self.next_person = 1

    @property
    def found(self) -> list:
        """Return the people found now, in the order of their numbers."""
        return [t for t in self.tracks if t.found]

    def followed(self, radius: int = GATE_CELLS) -> np.ndarray:
        """Cells (N,) within ``radius`` cells of a person found."""
        mask = np.zeros(self.grid.n_cells, dtype=bool)
        for t in self.found:
            mask |= near(self.grid, t.cell, radius)
        return mask

    def step(self, probability: np.ndarray, occupied: np.ndarray, keep: float, t_s: float,
             dt_s: float = 0.0, values=None, offsets=None,
             unseen_s: float = math.inf) -> list[dict]:
        """
        Follow everyone through one frame; return its events (module docstring).

        Parameters
        ----------
        probability : array (N,)
            ``P(x_j = 1)`` after the frame.
        occupied : bool array (N,)
            Cells decided occupied (``P >= confidence``).
        keep : float
            A person found stays found while its cell holds at least this probability.
        t_s, dt_s : float
            The search's clock at the frame, and the time since the frame before.
        values, offsets : arrays (N,), (N, 2), optional
            The frame (NaN where it did not look; None: it saw every cell) and its detections'
            offsets, for the position filters.
        unseen_s : float
            A person found not confirmed (held at the keep probability) for longer than this is
            lost even where the head did not look: its turn came and went.

        Returns
        -------
        list of dict
            ``{'event': 'found' | 'lost' | 'reacquired', 'person', 'cell', 'probability',
            'seconds'}`` (``seconds``: tracked before ``lost``, lost before ``reacquired``).

        Raises
        ------
        ValueError
            For inputs the tracks cannot follow (:func:`check_probability`, the shapes, a
            keep outside [0, 1], times not finite, a frame with +/-inf), before any track
            changes.

        """
        grid, events = self.grid, []
        probability = check_probability(probability, grid)
        occupied = np.asarray(occupied)
        if occupied.dtype != bool or occupied.size != grid.n_cells:
            raise ValueError(f'occupied must be {grid.n_cells} bools, one per cell, got '
                             f'{occupied.dtype} of shape {occupied.shape}')
        occupied = occupied.reshape(-1)
        keep = _check_keep(keep)
        if not (math.isfinite(t_s) and math.isfinite(dt_s) and dt_s >= 0):
            raise ValueError(f't_s must be finite and dt_s finite and >= 0, got {t_s!r}, '
                             f'{dt_s!r}')
        if values is not None:
            values = check_evidence(values, grid.n_cells)
        if offsets is not None:
            offsets = np.asarray(offsets, dtype=np.float64)
            if offsets.shape != (grid.n_cells, 2):
                raise ValueError(f'offsets must have shape ({grid.n_cells}, 2), got '
                                 f'{offsets.shape}')
        taken = np.zeros(grid.n_cells, dtype=bool)
        seen = np.ones(grid.n_cells, dtype=bool) if values is None else \
            ~np.isnan(np.asarray(values, dtype=float))
        found = self.found
        centres = [self._centre(track, dt_s) for track in found]
        assigned = self._assign(found, centres, probability, keep)
        order = sorted(range(len(found)), key=lambda i: (i not in assigned, i))
        for i in order:
            track, centre = found[i], centres[i]
            window = near(grid, centre, GATE_CELLS) & ~taken
            best = assigned[i] if i in assigned else \
                int(np.argmax(np.where(window, probability, -1.0)))
            held = self._held(probability, best, taken)
            confirmed = window.any() and held >= keep
            if confirmed or (window.any() and not seen[best]
                             and t_s - track.confirmed_s <= unseen_s):
                track.cell, track.probability = best, held
                taken |= near(grid, best, SPILL_CELLS)
                if confirmed:
                    track.confirmed_s = float(t_s)
                    self._measure(track, values, offsets)
                elif track.position is not None:
                    track.position.reset()          # unseen: the occupancy says where
                continue
            track.found = False
            track.probability = self._held(probability, track.cell, taken)
            events.append(self._event('lost', track, t_s - track.since_s))
            track.since_s = float(t_s)
            if track.position is not None:
                track.position.reset()
        cells = np.flatnonzero(occupied & ~taken)
        labels = clusters(cells, grid, self.link)
        for label in range(labels.max() + 1 if labels.size else 0):
            members = cells[labels == label]
            best = int(members[np.argmax(probability[members])])
            track, kind = self._who(best)
            seconds = t_s - track.since_s if kind == 'reacquired' else 0.0
            track.cell, track.probability = best, self._held(probability, best, taken)
            track.found, track.since_s, track.confirmed_s = True, float(t_s), float(t_s)
            if track.position is not None:
                track.position.reset()
            self._measure(track, values, offsets)
            taken |= near(grid, best, SPILL_CELLS)
            events.append(self._event(kind, track, seconds))
        return events

    def peaks(self, probability: np.ndarray, keep: float) -> np.ndarray:
        """
        Return the cells where someone is held (:meth:`held`), likeliest first.

        Cells are taken in order of probability, each one that holds at least ``keep``, is the
        likeliest of its :data:`SPILL_CELLS` neighbourhood (a tie is broken by that order) and is
        not within it of a peak taken before (its spill-over). ValueError: as :meth:`step`.
        """
        return self._peaks(check_probability(probability, self.grid), _check_keep(keep))

    def _peaks(self, probability: np.ndarray, keep: float) -> np.ndarray:
        """Return :meth:`peaks` of probabilities and a keep checked already."""
        with np.errstate(divide='ignore'):
            empty = np.log1p(-np.minimum(probability, 1.0))
        empty = empty.reshape(self.grid.rows, self.grid.cols)
        padded = np.pad(empty, SPILL_CELLS)
        size = 2 * SPILL_CELLS + 1
        total = sum(padded[r:r + self.grid.rows, c:c + self.grid.cols]
                    for r in range(size) for c in range(size))
        top = maximum_filter(probability.reshape(self.grid.rows, self.grid.cols), size=size,
                             mode='nearest').reshape(-1)
        holds = np.flatnonzero((-np.expm1(total.reshape(-1)) >= keep) & (probability >= top))
        out, blocked = [], np.zeros(self.grid.n_cells, dtype=bool)
        for cell in holds[np.argsort(-probability[holds], kind='stable')]:
            if not blocked[cell]:
                out.append(int(cell))
                blocked |= near(self.grid, cell, SPILL_CELLS)
        return np.array(out, dtype=np.int64)

    def _assign(self, found: list, centres: list, probability, keep: float) -> dict:
        """Return ``{index in found: cell}``: each person's peak, by global nearest neighbour."""
        peaks = self._peaks(probability, keep) if found else np.empty(0, dtype=np.int64)
        if not len(peaks):
            return {}
        grid = self.grid
        peak_rc = np.array([grid.cell(int(c)) for c in peaks], dtype=np.float64)
        centre_rc = np.array([grid.cell(int(c)) for c in centres], dtype=np.float64)
        at = np.array([t.position.x if t.position is not None and t.position.started
                       else grid.cell(t.cell) for t in found], dtype=np.float64)
        gated = np.max(np.abs(centre_rc[:, None, :] - peak_rc[None, :, :]), axis=2) <= GATE_CELLS
        cost = np.sum((at[:, None, :] - peak_rc[None, :, :]) ** 2, axis=2)
        # a pair outside the gate costs more than every gated assignment together: the most
        # people are kept first, then the fewest squared cells
        outside = 1.0 + cost[gated].sum()
        rows, cols = linear_sum_assignment(np.where(gated, cost, outside))
        return {int(r): int(peaks[c]) for r, c in zip(rows, cols) if gated[r, c]}

    def held(self, probability: np.ndarray, cell: int, taken: np.ndarray | None = None) -> float:
        """
        Return whether someone is within SPILL_CELLS of ``cell``: ``1 - prod (1 - P_j)``.

        ValueError: as :meth:`step`.
        """
        return self._held(check_probability(probability, self.grid), cell, taken)

    def _held(self, probability: np.ndarray, cell: int, taken: np.ndarray | None = None) -> float:
        """Return :meth:`held` of probabilities checked already."""
        cells = near(self.grid, cell, SPILL_CELLS)
        if taken is not None:
            cells &= ~taken
        with np.errstate(divide='ignore'):         # a cell at 1: log1p(-1) = -inf, held 1
            return float(-np.expm1(np.sum(np.log1p(-np.minimum(probability[cells], 1.0)))))

    def _centre(self, track: Track, dt_s: float) -> int:
        """Return the cell to look for a person around: its filter's prediction, else its cell."""
        position = track.position
        if position is None or not position.started:
            return track.cell
        position.predict(dt_s)
        rc = np.clip(np.round(position.x), 0, [self.grid.rows - 1, self.grid.cols - 1])
        return int(self.grid.index(int(rc[0]), int(rc[1])))

    def _measure(self, track: Track, values, offsets) -> None:
        """Feed a person's filter the detections' mean position around its cell (gated)."""
        position = track.position
        if position is None or values is None or offsets is None:
            return
        cell_rc = np.asarray(self.grid.cell(track.cell), dtype=np.float64)
        if position.started and np.max(np.abs(position.x - cell_rc)) > FILTER_GATE_CELLS:
            position.reset()
        z = measured_position(values, offsets, self.grid, track.cell)
        if z is None or np.max(np.abs(z - cell_rc)) > FILTER_GATE_CELLS:
            return
        if position.started:
            position.update(z)
        else:
            position.start(z)

    def _who(self, cell: int) -> tuple[Track, str]:
        """Return the lost person nearest ``cell`` (reacquired), else a new person (found)."""
        lost = [t for t in self.tracks if not t.found]
        if lost:
            r, c = self.grid.cell(cell)
            distance = [max(abs(r - tr), abs(c - tc))
                        for tr, tc in (self.grid.cell(t.cell) for t in lost)]
            return lost[int(np.argmin(distance))], 'reacquired'
        track = Track(self.next_person, cell, 0.0, position=self.make_filter())
        self.next_person += 1
        self.tracks.append(track)
        return track, 'found'

    def view(self, track: Track, lead_s: float, ahead: np.ndarray | None = None) -> int:
        """
        Return the cell to look at for ``track``.

        The cell of its filter's position ``lead_s`` ahead when it has one; else the likeliest
        cell of ``ahead`` (the occupancy predicted ``lead_s`` ahead) within :data:`GATE_CELLS`
        of it; else its cell. ``ahead`` may be the log odds instead (the same order); one
        with a NaN is refused (ValueError): it would be the likeliest cell.
        """
        grid = self.grid
        if ahead is not None:
            ahead = np.asarray(ahead, dtype=np.float64)
            if ahead.size != grid.n_cells:
                raise ValueError(f'ahead must be {grid.n_cells} numbers, one per cell, got '
                                 f'shape {ahead.shape}')
            ahead = ahead.reshape(-1)
            if np.isnan(ahead).any():
                i = int(np.argmax(np.isnan(ahead)))
                raise ValueError(f'ahead must not be NaN: cell {_rc(grid, i)} is nan')
        if track.position is not None and track.position.started:
            rc = np.clip(np.round(track.position.ahead(lead_s)), 0,
                         [grid.rows - 1, grid.cols - 1]).astype(np.int64)
            return int(grid.index(int(rc[0]), int(rc[1])))
        if ahead is not None:
            window = near(grid, track.cell, GATE_CELLS)
            return int(np.argmax(np.where(window, ahead, -np.inf)))
        return int(track.cell)

    def _event(self, kind: str, track: Track, seconds: float) -> dict:
        return {'event': kind, 'person': track.person, 'cell': int(track.cell),
                'probability': float(track.probability), 'seconds': max(0.0, float(seconds))}


class Turns:
    """
    The head's time shared between the people found (module docstring).

    :meth:`advance` names whom the next view is for: each person ``dwell_s`` seconds in the
    order of their numbers, then the search's turn (:data:`GLANCE`), round and round. The
    search's turn is one view when the search has nothing to do; while it has (cells
    undecided, or someone likely who is not followed yet) it goes on, up to
    :data:`SEARCH_SHARE` of ``dwell_s``: one
    view of a new face is not enough to find it, and by the next round its evidence would have
    spread with the motion.
    """

    def __init__(self, dwell_s: float):
        dwell_s = float(dwell_s)
        if not math.isfinite(dwell_s) or dwell_s <= 0:
            raise ValueError(f'dwell_s must be finite and > 0, got {dwell_s!r}')
        self.dwell_s = dwell_s
        self.reset()

    def reset(self) -> None:
        """No turn under way."""
        self.current = GLANCE
        self.searching = False
        self.last_person = 0
        self.spent_s = 0.0

    def advance(self, people, dt_s: float, search: bool = False) -> int | None:
        """
        Return the person the next view is for, or :data:`GLANCE` (the search).

        ``people`` are the numbers of the people found now (ascending), ``dt_s`` the time since
        the last view, ``search`` whether the search has something to do (class docstring).
        With nobody found every view is the search's.
        """
        people = sorted(int(p) for p in people)
        if not people:
            self.reset()
            return GLANCE
        self.spent_s += max(0.0, float(dt_s))
        if self.current is not GLANCE and self.current in people \
                and self.spent_s < self.dwell_s:
            return self.current
        if self.current is GLANCE and self.searching and search \
                and self.spent_s < SEARCH_SHARE * self.dwell_s:
            return GLANCE
        after = self.last_person if self.current is GLANCE else self.current
        later = [p for p in people if p > after]
        self.searching = False
        if self.current is not GLANCE and not later:
            self.current = GLANCE                  # a round is over: the search's turn
            self.searching = True
        else:
            self.current = later[0] if later else people[0]
            self.last_person = self.current
        self.spent_s = 0.0
        return self.current
