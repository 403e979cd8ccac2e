# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The search session for many targets (``search.targets: many``; docs/design.md section 11).

The same steps and results as :class:`ipomdp_gaze.search.session.SearchSession` (``reset``,
``scan``, ``start``, ``update``, ``stop``; :class:`~ipomdp_gaze.search.session.StepResult`), so
:func:`ipomdp_gaze.search.sensors.run_search` drives either, on the occupancy belief of
:mod:`ipomdp_gaze.model.occupancy`:

1. ``reset``: every cell's log odds ``log(q / (1 - q))`` with ``(1 - q)^N = absent_prior``
   (:func:`~ipomdp_gaze.model.occupancy.cell_prior`; ``q = 1/N`` without one);
2. ``scan``: ``L_j += log s_T(c_j) - log s_N(c_j)`` (or a sensor's own per-cell term, a frame
   of kind ``evidence``);
3. ``update``: ``L_j += l_j`` of the frame (the single-target belief's own term), with a still
   scene's repeated views weighted by ``repeat_weight`` (:mod:`ipomdp_gaze.model.still_evidence`:
   1 is naive Bayes);
4. stop when every cell is decided at ``confidence`` either way (``P(x_j) >= c`` occupied;
   empty by default when its evidence alone says so, ``L_j - L_prior <= -log(c / (1 - c))``,
   or with ``empty_by_evidence=False`` when ``P(x_j) <= 1 - c``; with ``link`` r > 0 a cell
   within r cells of an occupied one is settled too: it would join that face's cluster, so it
   cannot be another face): ``found``
   if a cell is occupied, else ``absent``; at the fixation budget or a driver's cost cap
   (:meth:`stop`), ``gave_up`` or, with ``decide_at_budget``, every cell by its likelier side;
   ``gave_up`` (reason ``repeat``) when no view left would tell anything new, or, with
   ``stop_on_repeat``, when the best view is one already taken;
5. otherwise the next fixation maximises the expected reduction of the summed cell entropies per
   unit cost: ``argmax_k sum_j w_kj I(P(x_j); offset_jk) / cost_k`` over every cell, the
   unvisited ones with ``inhibit_return`` (the
   cost times the view's seconds of head time with ``search.head_speed_deg_s``), with
   ``w_kj = 1`` where view k sees cell j at a more informative offset (ELM kernel) than any view
   so far, ``repeat_weight`` otherwise, and 0 for a cell settled by ``link``. With a sensor's
   fresh views (:meth:`OccupancySession.set_fresh`: the fovea's windows cached on the image)
   only the cells view k would read afresh count, ``cost_k`` is what it reads afresh, and a
   view with nothing to read is never taken.

**Moving targets** (motion on: ``motion.*`` as for one target; docs/design.md section 12.10):
before each frame the belief is predicted over ``dt_s``
(:func:`ipomdp_gaze.model.occupancy.predict_occupancy`, people out of reach kept as an expected
number ``outside``), the frame is added as it is (no still-scene weighting, no inhibition of
return: a view of a moving scene repeats nothing), and :class:`ipomdp_gaze.search.tracks.Tracks`
follows each person found (``found``, ``lost``, ``reacquired`` in :attr:`people_events`). The
search does not end on a decision: ``found`` while anyone is followed, ``absent`` while every
cell is decided empty; :attr:`room_done` says every cell is decided. The views: each person
found ``motion.dwell_s`` in turn (``motion.track_view``: the cell of its position filter
``motion.lead_s`` ahead, or of the occupancy predicted that far ahead), then the search's turn
(:class:`~ipomdp_gaze.search.tracks.Turns`): the infomax choice above with the cells around the
people followed left out; with nobody found, or
``motion.track_view: policy``, every view is that choice.

**One pass** (still targets, a policy with ``poses``, the sweep's: :meth:`set_policy`;
docs/design.md section 11.7): the views are the pass's poses in order, once each; the search
ends after the last (reason ``pass``; earlier if every cell was decided) with every cell on its
likelier side, and its faces also name every grouped detection the frames carried
(``Frame.groups``) that is not a face already named: more than one cell from it, or, for two
groups whose frames gave offsets, more than :data:`GROUP_SAME_FACE_CELLS` from where it lies.
With ``search.decide_after_pass`` the room is not done at the last pose: every cell has been
seen well, so a cell is decided empty by its posterior from then on, and the search goes on by
the infomax choice (per second of head time) until every cell is decided (reason '') or the
budget; its faces still name the groups, of the pass's views and of the later ones.

The answer for drivers: :meth:`OccupancySession.faces` (one face per cluster of occupied cells,
:func:`ipomdp_gaze.model.occupancy.count_faces`). The session imports no ROS, prints and writes
nothing.
"""
from __future__ import annotations

from collections import deque
import math

from ipomdp_gaze.model.belief import argmax_ties_low, EvidenceError
from ipomdp_gaze.model.clutter_map import ClutterMap
from ipomdp_gaze.model.head_time import view_seconds
from ipomdp_gaze.model.motion import Motion
from ipomdp_gaze.model.observation import as_observation, check_evidence, CountObservation
from ipomdp_gaze.model.occupancy import (binary_entropy, cell_prior, count_faces, decided,
                                         information_table, log_nobody, occupancy,
                                         predict_occupancy, prior_log_odds)
from ipomdp_gaze.model.still_evidence import StillEvidence
from ipomdp_gaze.search.session import (check_groups, check_offsets, check_scan_model,
                                        check_seconds_elapsed, fixation_index, Frame,
                                        motion_settings, OrderError, PATH_SIZE, position_settings,
                                        scales_false_alarms, SearchSettings, start_index,
                                        StepResult, target_motion, track_filter)
from ipomdp_gaze.search.tracks import GLANCE, Tracks, Turns
import numpy as np
from scipy.ndimage import maximum_filter

# A person unconfirmed for a round of turns and this many more is lost (section 12.10).
UNSEEN_SLACK_TURNS = 2
# A best score at most this over the cheapest cost (nats of a view at that cost) is nothing
# left to learn.
MIN_GAIN = 1e-9


def check_many_settings(settings: SearchSettings, grid=None) -> None:
    """
    Refuse settings the many-target belief does not model (ValueError naming them).

    With ``grid``, also a cell prior of certainty: one cell and no ``absent.prior`` (or one so
    small that the prior of each cell rounds to 1), where nothing could be learnt.
    """
    if grid is not None and cell_prior(grid.n_cells, settings.absent_prior) >= 1.0:
        raise ValueError(f'search.targets many on {grid.n_cells} cell'
                         f"{'s' * (grid.n_cells > 1)} needs a larger absent.prior (got "
                         f'{settings.absent_prior:g}): with it the prior of each cell rounds to '
                         f'1, occupied for certain')
    if settings.confidence <= 0.5:
        raise ValueError(f'search.targets many decides each cell at the confidence either way, '
                         f'so it must be above 0.5 (got {settings.confidence:g})')
    still_hotspots = settings.hotspot_prior > 0 and not settings.moving
    if scales_false_alarms(settings) or still_hotspots:
        raise ValueError('search.targets many does not model false-alarm scales, nor hotspots '
                         'of a still scene: leave search.false_alarm_scales [1.0], and '
                         'search.hotspot_prior 0 unless the targets move')


def check_link(link) -> int:
    """Return ``link`` as an int: a whole number of cells >= 0 (ValueError otherwise)."""
    try:
        ok = not isinstance(link, bool) and int(link) == link and link >= 0
    except (TypeError, ValueError, OverflowError):     # OverflowError: int(inf)
        ok = False
    if not ok:
        raise ValueError(f'link must be a whole number of cells >= 0, got {link!r}')
    return int(link)


def check_costs(costs, n_cells: int) -> np.ndarray:
    """
    Return fixation costs as (N,) floats: one number for all, or one per cell, finite and > 0.

    ValueError otherwise; None is 1 for every cell.
    """
    if costs is None:
        return np.ones(n_cells)
    try:
        values = np.asarray(costs, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f'fixation costs must be numbers, got {costs!r}') from None
    if values.ndim > 1 or values.size not in (1, n_cells):
        raise ValueError(f'fixation costs must be one number or {n_cells} (one per cell, '
                         f'row-major), got shape {values.shape}')
    if np.any(~np.isfinite(values) | (values <= 0)):
        raise ValueError('fixation costs must be finite and > 0')
    return np.broadcast_to(values.reshape(-1), (n_cells,)).copy()


# A pass's two grouped detections lying within this many cells of each other (Chebyshev, at
# their cells plus the detections' mean offset, Frame.offsets) are one face; farther apart, two
# people. The cells alone (within one cell: one face) merged neighbours. Training rooms, without
# boxes: 184 of 201 faces against 179 (25 deg, seed 5000), 279 of 318 against 267 (seed 6000),
# 283 of 318 against 278 (40 deg, seed 6000), false faces the same (docs/design.md 11.7).
GROUP_SAME_FACE_CELLS = 0.75


class OccupancySession:
    """
    One many-target search at a time on one grid (module docstring).

    Parameters
    ----------
    grid : Grid
        The visual array.
    observation
        The assumed observation model (count or Gaussian) or an FPOC.
    settings : SearchSettings
        ``confidence``, ``max_fixations``, ``inhibit_return``, ``stop_on_repeat``,
        ``repeat_weight``, ``absent_prior``, ``start_cell``, ``scan``, ``decide_at_budget``.
    costs : array (N,) or float, optional
        Cost of a fixation at each cell, row-major (detector pixels for the fovea), finite and
        > 0; one number for every cell; 1 each by default.
    link : int
        Cells within this many cells (Chebyshev) of a cell decided occupied are settled
        (module docstring); 0: every cell is decided on its own.
    empty_by_evidence : bool
        Decide a cell empty only when its evidence alone says so: ``L_j - L_prior <=
        -log(c / (1 - c))`` (a likelihood-ratio test, so a sparse prior cannot decide a cell
        nobody looked at well; Wald: a face's cell is decided empty with probability at most
        ``(1 - c) / c``). Off: the posterior ``P <= 1 - c`` decides, and a sparse prior
        decides every cell nobody looked at (``find`` chooses that, for its cost).
    log_size : int
        Events kept in :attr:`log`; 0 keeps none, and the per-frame events are not built.

    """

    def __init__(self, grid, observation, settings: SearchSettings | None = None,
                 costs=None, link: int = 0, empty_by_evidence: bool = True,
                 log_size: int = 10_000):
        self.grid = grid
        self.observation = as_observation(grid, observation)
        self.settings = settings or SearchSettings(targets='many')
        self.settings.check_grid(grid)
        check_many_settings(self.settings, grid)
        self.policy = None
        self._pass = None
        self.link = check_link(link)
        self.empty_by_evidence = bool(empty_by_evidence)
        self.table = information_table(self.observation)
        self._view_info = self.table.view_information                     # [k, j]
        self.costs = check_costs(costs, grid.n_cells)
        self._counts = isinstance(self.observation, CountObservation)
        self._still = StillEvidence(grid.n_cells)
        self._motion = target_motion(grid, self.settings)
        self._clutter = None
        self.tracks = Tracks(grid, lambda: track_filter(self.settings))
        self.turns = Turns(self.settings.motion_dwell_s)
        self.people_events: tuple = ()
        self._log = deque(maxlen=int(log_size))
        self.rng = np.random.default_rng(0)
        self._state = None
        self._gain_cache = None         # the still gains' (N, N) terms (:meth:`_still_terms`)
        self._fresh = None              # what each view would read afresh (:meth:`set_fresh`)

    # -- configuration -------------------------------------------------------------------
    @property
    def motion(self) -> Motion:
        """Return how the targets move (``motion.*``; inactive for still targets)."""
        return self._motion

    def configure(self, settings: SearchSettings) -> None:
        """
        Use new settings from the next frame on, keeping the belief of the search under way.

        A new ``absent_prior`` applies from the next :meth:`reset`. Motion turned on, or a new
        ``repeat_weight``, keeps the evidence so far (the still-scene weighting folded in, as
        it was) and counts the still scene's evidence afresh from the next frame (as
        :meth:`SearchSession.configure`); motion turned off, the people followed
        are forgotten (a still room is searched, then decided). New position-filter settings
        give the people followed new filters.

        Raises
        ------
        ValueError
            For settings the occupancy belief does not model (:func:`check_many_settings`).

        """
        settings.check_grid(self.grid)
        check_many_settings(settings, self.grid)
        old, s = self.settings, self._state
        moves = motion_settings(settings) != motion_settings(old)
        if s is not None and not self._motion.active and (
                moves or settings.repeat_weight != old.repeat_weight):
            s['base'] = self.log_odds              # the still evidence, weighted as it was
            self._still.reset()
            self._best = np.zeros(self.grid.n_cells)
        if moves:
            was_moving = self._motion.active
            self._motion = target_motion(self.grid, settings)
            if was_moving and not self._motion.active:
                self.tracks.reset()                # still targets: the room's search decides
                self.turns.reset()
                self.people_events = ()
        if settings.motion_dwell_s != old.motion_dwell_s:
            self.turns = Turns(settings.motion_dwell_s)
        self.settings = settings
        if position_settings(settings) != position_settings(old):
            for track in self.tracks.tracks:       # the people followed take the new filter
                track.position = track_filter(settings)

    def set_observation(self, observation, settings: SearchSettings | None = None) -> None:
        """Assume another observation model (or FPOC) from the next frame; ``settings`` unused."""
        self.observation = as_observation(self.grid, observation)
        self.table = information_table(self.observation)
        self._view_info = self.table.view_information
        self._counts = isinstance(self.observation, CountObservation)

    def set_policy(self, policy) -> None:
        """
        Keep ``policy``: a sweep (a policy with ``poses``) makes a still search one pass of them.

        Any other policy is kept for the record: the occupancy search chooses by its own
        infomax. Takes effect at the next :meth:`reset`: a search is a pass or not throughout,
        of the poses it started with.
        """
        self.policy = policy
        poses = getattr(policy, 'poses', None) if getattr(policy, 'name', '') == 'sweep' \
            else None
        self._pass = None if poses is None else np.asarray(poses, dtype=np.int64).copy()

    def set_fresh(self, fresh) -> None:
        """
        Choose still views by what each would read afresh: ``fresh() -> (costs, cover)``, or None.

        A sensor that serves part of a view from a cache of what it read already (the fovea's
        windows on one image: no new evidence, so its frame leaves the cells only those parts
        saw unobserved) gives, before each choice, each view's cost of what it would read
        afresh, ``costs`` (N,) >= 0 in the unit of the fixation costs, and the cells it would
        observe, ``cover`` (N, N) bool ``[k, j]``. The still infomax choice then counts only
        those cells' information (:meth:`gains` ``cover``) per that cost, and never takes a
        view of cost 0 (nothing new to read); with no view left that tells anything, the search
        gives up (``repeat``). None (the default): every view is read whole, at the fixation
        costs. Moving targets and a pass choose as before.
        """
        if fresh is not None and not callable(fresh):
            raise ValueError(f'fresh must be callable or None, got {type(fresh).__name__}')
        self._fresh = fresh

    def _fresh_views(self) -> tuple[np.ndarray, np.ndarray]:
        """Return :meth:`set_fresh`'s costs (N,) and cover (N, N), checked (ValueError)."""
        n = self.grid.n_cells
        costs, cover = self._fresh()
        costs, cover = np.asarray(costs, dtype=float), np.asarray(cover, dtype=bool)
        if costs.shape != (n,) or cover.shape != (n, n):
            raise ValueError(f'fresh views must be costs ({n},) and cover ({n}, {n}), got '
                             f'{costs.shape} and {cover.shape}')
        if np.any(~np.isfinite(costs) | (costs < 0)):
            raise ValueError('fresh view costs must be finite and >= 0')
        return costs, cover

    @property
    def passing(self) -> bool:
        """
        Whether this search is one pass of the sweep's poses (still targets only).

        Fixed when the search starts (:meth:`reset`: the policy then); motion turned on during
        it ends the pass (a moving search names no groups).
        """
        poses = self._pass if self._state is None else self._state['pass']
        return poses is not None and not self._motion.active

    # -- read-only views -----------------------------------------------------------------
    def _s(self) -> dict:
        if self._state is None:
            raise OrderError('reset the session before using it')
        return self._state

    @property
    def log_odds(self) -> np.ndarray:
        """``L_j`` (N,), a copy."""
        s = self._s()
        if self._motion.active:
            return s['base'].copy()
        return s['base'] + self._still.log_likelihood_ratio(self.settings.repeat_weight)

    @property
    def belief(self) -> np.ndarray:
        """``P(x_j = 1)`` (N,): each cell's probability of holding a target."""
        return occupancy(self.log_odds)

    @property
    def absent_probability(self) -> float:
        """``P(nobody here) = prod_j (1 - P(x_j = 1))``."""
        return float(np.exp(log_nobody(self.log_odds)))

    @property
    def map_cell(self) -> int:
        """Return the most probable cell (ties to the lowest index)."""
        return int(argmax_ties_low(self.log_odds))

    @property
    def map_probability(self) -> float:
        """``P(x_j = 1)`` of :attr:`map_cell`."""
        return float(occupancy(self.log_odds[self.map_cell]))

    @property
    def entropy_nats(self) -> float:
        """Return the summed cell entropies ``sum_j H(P(x_j))`` in nats."""
        return float(binary_entropy(self.belief).sum())

    def occupied(self) -> np.ndarray:
        """
        Return the occupied cells (N,): ``P >= confidence``; after a deadline ``P > 1/2``.

        After a pass (reason ``pass``) too: it ends with every cell on its likelier side.
        """
        s, log_odds = self._s(), self.log_odds
        if s['reason'] == 'pass' or (s['reason'] and self.settings.decide_at_budget):
            return log_odds > 0
        return self._decided(log_odds)[0]

    fixation = property(lambda self: self._s()['fixation'])
    fixations = property(lambda self: self._s()['fixations'])
    path = property(lambda self: tuple(self._s()['path']))
    visited = property(lambda self: self._s()['visited'].copy())
    decision = property(lambda self: self._s()['decision'])
    gave_up_reason = property(lambda self: self._s()['reason'])
    ended = property(lambda self: self._s()['ended'])

    @property
    def limit_setting(self) -> str:
        """
        Return the setting whose rule ended the search at its limit, else ''.

        ``max_fixations`` (reason ``budget``); for ``repeat``, ``inhibit_return`` (every cell
        was fixated) or ``stop_on_repeat`` (the best view was one already taken), and '' when
        no view left would tell anything new; '' for a driver's limit (:meth:`stop`).
        """
        s = self._s()
        return {'budget': 'max_fixations', 'repeat': s['repeat_rule']}.get(s['reason'], '')

    @property
    def limit_cause(self) -> str:
        """
        Return what ended the search at a ``repeat`` stop, else '' (:data:`answer.REPEATS`).

        ``every_cell`` (``search.inhibit_return``: every cell was fixated), ``next_repeats``
        (``search.stop_on_repeat``: the best view was one already taken) or ``nothing_new``
        (no view left would tell anything new).
        """
        s = self._s()
        if s['reason'] != 'repeat':
            return ''
        return {'inhibit_return': 'every_cell', 'stop_on_repeat': 'next_repeats'}.get(
            s['repeat_rule'], 'nothing_new')
    log = property(lambda self: tuple(self._log))

    @property
    def room_done(self) -> bool:
        """Whether every cell is decided (occupied, near a person found, or empty)."""
        return self._s()['room_done']

    def faces(self, boxes=None, scores=None, image_px=None, link: int = 2,
              strong: float | None = None) -> list[dict]:
        """
        Return the faces, each counted once (``occupancy.count_faces``; ``strong``: its).

        Moving targets: the people followed now (:attr:`tracks`), in the order of their
        numbers, each ``{'cell', 'cells', 'probability', 'box': None, 'person'}``.
        """
        if self._motion.active:
            return [{'cell': t.cell, 'cells': np.array([t.cell]), 'probability': t.probability,
                     'box': None, 'person': t.person} for t in self.tracks.found]
        faces = count_faces(self.log_odds, self.grid, self.occupied(), boxes, scores, image_px,
                            link, strong=strong)
        if self.passing:
            faces = self._with_groups(faces, boxes is not None)
        return faces

    def _with_groups(self, faces: list, boxes: bool) -> list[dict]:
        """
        Return a pass's faces: the belief's ``faces`` and its grouped detections, each once.

        The better placed come first, and a later one within one cell of an earlier is that
        face: with the views' boxes, the belief's faces (each at its box), then the groups;
        without them, the groups (each at its group's centre), then the belief's faces (a
        cluster's likeliest cell, which may sit between two faces). Two groups whose frames
        said where their detections lie (``Frame.offsets``) are one face when within
        :data:`GROUP_SAME_FACE_CELLS` of each other (each at its cell plus the mean offset of
        the detections there), so two people in neighbouring cells stay two; without offsets,
        within one cell. Chosen on training rooms (docs/design.md section 11.7). A grouped face
        is ``{'cell', 'cells', 'probability'`` (the belief's, which may doubt it), ``'box':
        None, 'grouped': True, 'at': (row, col)`` in fractional cells or None``}``, in the
        order the views saw them (row-major within a view). With ``search.decide_after_pass``
        a room the belief decided (:attr:`room_done`) names no group whose cell it decided
        empty (``P <= 1 - confidence``): on 260 training rooms only texture was (docs/design.md
        section 11.7).
        """
        rows, cols = self.grid.rows_cols()
        belief, s = self.belief, self._s()
        vetoes = s['room_done'] and self.settings.decide_after_pass
        empty = 1.0 - self.settings.confidence if vetoes else -1.0
        grouped = [{'cell': cell, 'cells': np.array([cell]), 'probability': float(belief[cell]),
                    'box': None, 'grouped': True, 'at': None if math.isnan(r) else (r, c)}
                   for cell, r, c in s['groups'] if belief[cell] > empty]
        out = []

        def apart(face, others):
            for f in others:
                if face.get('at') and f.get('at'):      # two groups: where they lie
                    if max(abs(face['at'][0] - f['at'][0]),
                           abs(face['at'][1] - f['at'][1])) <= GROUP_SAME_FACE_CELLS:
                        return False
                elif max(abs(rows[int(face['cell'])] - rows[int(f['cell'])]),
                         abs(cols[int(face['cell'])] - cols[int(f['cell'])])) <= 1:
                    return False
            return True
        first, then = (faces, grouped) if boxes else (grouped, faces)
        for face in first:                       # the belief's faces stay as counted (§11.3)
            if not face.get('grouped') or apart(face, out):
                out.append(face)
        kept = list(out)
        for face in then:
            if apart(face, kept if not face.get('grouped') else out):
                out.append(face)
        return out

    # -- the steps -----------------------------------------------------------------------
    def reset(self, *, seed=None) -> None:
        """Start a new search: every cell at the prior ``q`` (module docstring)."""
        if isinstance(seed, np.random.Generator):
            self.rng = seed
        elif seed is not None:
            self.rng = np.random.default_rng(seed)
        n, absent = self.grid.n_cells, self.settings.absent_prior
        q = cell_prior(n, absent)
        self._still.reset()
        self._motion.reset()
        self._clutter = None
        self.tracks.reset()
        self.turns.reset()
        self.people_events = ()
        self._best = np.zeros(n)
        prior = prior_log_odds(n, q)
        # People out of reach: as many, against those in reach, as the absent hypothesis of one
        # target holds against its cells (a / (1 - a)); an expected number, the grid's -N log(1-q).
        outside = -n * math.log1p(-q) * absent / (1.0 - absent)
        self._state = {'base': prior, 'prior': prior, 'fixation': None, 'fixations': 0,
                       'path': deque(maxlen=PATH_SIZE), 'scanned': False, 'decision': '',
                       'reason': '', 'ended': False, 'outside': outside, 'clock_s': 0.0,
                       'room_done': False, 'decided_once': False, 'repeat_rule': '',
                       'visited': np.zeros(n, dtype=bool), 'groups': [],
                       'pass': self._pass}
        self._event('reset', settings=self.settings.to_parameters(), cell_prior=q)

    def exclude(self, cells) -> None:
        """Not used by the many-target belief: every cell stays a hypothesis of its own."""
        if len(np.atleast_1d(cells)):
            raise ValueError('a many-target search excludes no cells: each cell is its own '
                             'occupancy')

    def check_frame(self, values) -> np.ndarray:
        """Return a frame's values as floats (N,), or raise :class:`EvidenceError`."""
        obs = check_evidence(values, self.grid.n_cells)
        if self._counts:
            self.observation.counts(obs)
        return obs

    def checked_frame(self, values, kind: str = 'fixation', offsets=None,
                      groups=None) -> Frame:
        """
        Return ``Frame(values, kind, offsets=offsets, groups=groups)`` checked once.

        The values as :meth:`check_frame`, the detections' offsets and grouped detections as
        :func:`~ipomdp_gaze.search.session.check_offsets` and
        :func:`~ipomdp_gaze.search.session.check_groups` (EvidenceError); the belief reads
        neither, a pass answers the groups.
        """
        return Frame(self.check_frame(values), kind=kind,
                     offsets=check_offsets(offsets, self.grid.n_cells),
                     groups=check_groups(groups, self.grid.n_cells))

    def scan(self, frame: Frame) -> StepResult:
        """
        Apply the one-time scan: ``L_j += log s_T(c_j) - log s_N(c_j)`` (once, first).

        A frame of kind ``'evidence'`` carries the log-likelihood ratios themselves (a sensor
        with its own calibration: ``find --all``'s coarse pass, :mod:`ipomdp_gaze.vision.
        scales`); they are added as they are.
        """
        s = self._s()
        if s['fixation'] is not None or s['scanned']:
            raise OrderError('the one-time scan comes once, before the first fixation')
        if not self.settings.scan:
            return self._result('applied', reason='scan off')
        if frame.kind != 'evidence':
            check_scan_model(self.observation)
        try:
            values = check_evidence(frame.values, self.grid.n_cells)
            term = (np.nan_to_num(values) if frame.kind == 'evidence' else
                    self.observation.scan_log_likelihood_ratio(values))
        except EvidenceError as exc:
            return self._result('rejected', reason=str(exc))
        s['scanned'] = True
        s['base'] = s['base'] + term
        self._event('scan', frame=frame.summary(), belief=self._summary())
        return self._result('applied')

    def start(self) -> int:
        """
        Choose the first fixation: the start cell, the choice after a scan, or the centre.

        After a scan that decided every cell the search ends here (:attr:`ended`): no fixation.
        """
        s = self._s()
        if s['fixation'] is not None:
            raise OrderError('the search has started already; reset starts a new one')
        fixed = start_index(self.grid, self.settings)
        if self.passing:
            s['fixation'] = int(s['pass'][0])
        elif fixed is not None:
            s['fixation'] = fixed
        elif s['scanned'] or self.settings.start_cell == 'policy':
            s['fixation'] = self._choose()
            if s['fixation'] is None:
                s['fixation'] = self.grid.center_index
        else:
            s['fixation'] = self.grid.center_index
        # A moving search never ends on a decision: its first frame decides (_decide_moving).
        fired = self._decide() if s['scanned'] and not self._motion.active else ''
        self._event('start', fixation=self._rc(s['fixation']), decision=fired)
        return s['fixation']

    def fixate(self, cell: int) -> None:
        """Take the next frame at ``cell`` instead of the chosen one."""
        s = self._s()
        if s['fixation'] is None:
            raise OrderError('start the search before fixating')
        s['fixation'] = fixation_index(self.grid, cell)

    def predict(self, dt_s: float) -> None:
        """Spread the belief over ``dt_s`` of the targets' motion (nothing for still targets)."""
        s = self._s()
        dt_s = check_seconds_elapsed(dt_s)
        if self._motion.active and dt_s > 0:
            s['base'], s['outside'] = predict_occupancy(s['base'], s['outside'], self._motion,
                                                        dt_s)

    @property
    def outside(self) -> float:
        """Return the expected number of people out of the grid's reach (moving targets)."""
        return float(self._s()['outside'])

    def update(self, frame: Frame, dt_s: float = 0.0) -> StepResult:
        """
        Apply a frame taken at the current fixation; decide; choose the next fixation.

        ValueError, before anything changes: ``dt_s`` not a finite number >= 0, or one that
        takes a moving search's clock past the largest float.
        """
        s = self._s()
        if s['fixation'] is None:
            raise OrderError('start the search (the first fixation) before updating it')
        if s['ended']:
            raise OrderError(f'the search has ended ({s["decision"]}); reset starts a new one')
        k = s['fixation']
        dt_s = check_seconds_elapsed(dt_s)
        if self._motion.active and not math.isfinite(s['clock_s'] + dt_s):
            # the people's tracks time their turns on it (Tracks.step refuses an infinite time)
            raise ValueError(f"dt_s {dt_s!r} takes the search's clock past the largest float "
                             f"(it is at {s['clock_s']!r} s)")
        try:
            obs = self.check_frame(frame.values)
            offsets = check_offsets(frame.offsets, self.grid.n_cells)
            groups = check_groups(frame.groups, self.grid.n_cells)
            term = self.observation.log_likelihood_ratio(obs, k)
        except EvidenceError as exc:
            return self._result('rejected', reason=str(exc))
        if self._motion.active:
            self.predict(dt_s)
            clutter = self._active_clutter()
            if clutter is not None:
                term = clutter.occupancy_step(s['base'], obs, k, term)
            s['base'] = s['base'] + np.nan_to_num(term)
            s['clock_s'] += dt_s
        else:
            information = np.where(np.isnan(obs), 0.0, self._view_info[k])
            self._still.add(term, information)
            np.maximum(self._best, information, out=self._best)
        s['fixations'] += 1
        s['path'].append(k)
        s['visited'][k] = True
        if groups is not None and self.passing:     # only a pass names them, where they lie
            at = np.flatnonzero(groups > 0)
            rows, cols = self.grid.rows_cols()
            shift = np.full((at.size, 2), np.nan) if offsets is None else offsets[at]
            s['groups'].extend((int(c), float(rows[c] + dr), float(cols[c] + dc))
                               for c, (dr, dc) in zip(at, shift))
        if self._motion.active:
            fired = self._decide_moving(obs, offsets, dt_s)
        else:
            fired = self._decide()
        if not s['ended']:
            following = self._choose_moving(dt_s) if self._motion.active else self._choose()
            if following is None:
                fired = self._end_pass() if self.passing else self._limit('repeat')
            else:
                s['fixation'] = following
        if self._log.maxlen:
            self._event('frame', fixation=self._rc(k), frame=frame.summary(),
                        belief=self._summary(), decision=s['decision'], fired=fired,
                        reason=s['reason'], people=list(self.people_events))
        return self._result('applied', fired=fired)

    def stop(self, reason: str) -> StepResult:
        """End the search at a limit outside the session (a cost cap), as the budget does."""
        s = self._s()
        if s['fixation'] is None or s['ended']:
            raise OrderError('stop a search that has started and not ended')
        fired = self._limit(str(reason))
        self._event('stop', reason=s['reason'], decision=fired, belief=self._summary())
        return self._result('applied', fired=fired)

    # -- inside ------------------------------------------------------------------------------
    def settled(self, occupied: np.ndarray) -> np.ndarray:
        """Cells (N,) within ``link`` cells of an occupied one, the occupied ones included."""
        if self.link <= 0:
            return occupied
        side = 2 * self.link + 1
        grid = occupied.reshape(self.grid.shape)
        return maximum_filter(grid, size=side, mode='constant', cval=False).reshape(-1)

    def gains(self, log_odds: np.ndarray | None = None, cover=None) -> np.ndarray:
        """
        Return the expected drop of the summed cell entropies per fixation cell (N,), nats.

        ``sum_j w_kj I(P(x_j); offset_jk)``, ``w_kj`` 1 for a view more informative than any
        so far (ELM kernel), else ``repeat_weight`` (module docstring). With ``cover`` (N, N)
        bool ``[k, j]`` (still targets), only the cells view k would observe count
        (:meth:`set_fresh`); a view covering every cell gains as without.
        """
        if log_odds is None:
            log_odds = self.log_odds
        else:
            log_odds = np.asarray(log_odds, dtype=float)
            if log_odds.size != self.grid.n_cells:
                raise ValueError(f'log odds must have shape ({self.grid.n_cells},) or '
                                 f'{self.grid.shape}, got {log_odds.shape}')
            log_odds = log_odds.reshape(-1)
        if self._motion.active:
            info = self.table(log_odds)                                    # (N, N) [k, j]
            followed = self.tracks.followed()
            return info @ (~followed).astype(float)
        settled = self.settled(self._decided(log_odds)[0]) if self.link > 0 else None
        info, weight = self._still_terms(np.asarray(log_odds, dtype=float), settled)
        if cover is None:
            return np.einsum('kj,kj->k', info, weight)
        return np.einsum('kj,kj->k', info, np.where(np.asarray(cover, dtype=bool), weight, 0.0))

    def _still_terms(self, log_odds: np.ndarray, settled) -> tuple[np.ndarray, np.ndarray]:
        """
        ``I[k, j]`` and ``w[k, j]`` (N, N) of the still gains, kept from the last call.

        Column j depends only on cell j (its log odds, best view so far, settled or not), and a
        still frame changes the cells it saw: only the columns whose inputs changed are
        recomputed, with the same operations, so the arrays (and the sum) are the ones a full
        computation gives. They stay allocated with the session: 16 N^2 bytes (2 MB on 21x21,
        45 MB on 41x41, 270 MB on 64x64), which a full computation allocated anew each call.
        """
        table, rw, best = self.table, self.settings.repeat_weight, self._best

        def columns(cols):
            """Return the terms of the columns ``cols`` (a slice or indices), as :attr:`table`."""
            weight = np.where(self._view_info[:, cols] > best[None, cols], 1.0, rw)
            if settled is not None:
                weight = weight * ~settled[None, cols]
            info = np.take(table.by_channel(log_odds).ravel(), table.flat_pair[:, cols])
            return info, weight

        c = self._gain_cache
        if c is not None and c['table'] is table and c['rw'] == rw \
                and (c['settled'] is None) == (settled is None):
            changed = (c['log_odds'] != log_odds) | (c['best'] != best)
            if settled is not None:
                changed |= c['settled'] != settled
            cols = np.flatnonzero(changed)
            # NaN never equals itself: such a column is recomputed on every call, as before.
            if cols.size <= log_odds.size // 4:
                if cols.size:
                    c['info'][:, cols], c['weight'][:, cols] = columns(cols)
                    c['log_odds'][cols], c['best'][cols] = log_odds[cols], best[cols]
                    c['settled'] = None if settled is None else settled.copy()
                return c['info'], c['weight']
        info, weight = columns(slice(None))
        self._gain_cache = {'table': table, 'rw': rw, 'info': info, 'weight': weight,
                            'log_odds': log_odds.copy(), 'best': best.copy(),
                            'settled': None if settled is None else settled.copy()}
        return info, weight

    def costs_from(self, cell: int | None, costs=None) -> np.ndarray:
        """
        Return the cost of the next view at each cell (N,), with the head at ``cell``.

        The fixation costs (or ``costs`` (N,): :meth:`set_fresh`'s), times the view's seconds
        under the head model when ``search.head_speed_deg_s`` > 0
        (:func:`ipomdp_gaze.model.head_time.view_seconds`; before the first fixation the head
        is taken to be at the grid's centre, as the head-time model counts): information per
        second of head time, as the single-target session's per-second choice (docs/design.md
        section 6.14).
        """
        settings = self.settings
        costs = self.costs if costs is None else costs
        if settings.head_speed_deg_s <= 0:
            return costs
        at = self.grid.center_index if cell is None else int(cell)
        return costs * view_seconds(self.grid, at, settings.view_time_s,
                                    settings.head_speed_deg_s)

    def _choose(self) -> int | None:
        s = self._s()
        s['repeat_rule'] = ''           # the rule behind a None (limit_setting)
        if self.passing:
            left = s['pass'][~s['visited'][s['pass']]]
            if left.size or not self.settings.decide_after_pass:
                return int(left[0]) if left.size else None
        if self._fresh is None:
            costs = self.costs_from(s['fixation'])
            score = self.gains() / costs
        else:
            fresh, cover = self._fresh_views()
            costs = self.costs_from(s['fixation'], fresh)
            reads = costs > 0
            if not reads.any():
                return None             # every view served from the cache: nothing new
            score = np.full(costs.shape, -np.inf)
            score[reads] = self.gains(cover=cover)[reads] / costs[reads]
            costs = costs[reads]
        if self.settings.inhibit_return:
            score = np.where(s['visited'], -np.inf, score)
        if not np.isfinite(score).any() or score.max() <= MIN_GAIN / costs.min():
            if self.settings.inhibit_return and s['visited'].all():
                s['repeat_rule'] = 'inhibit_return'
            return None
        choice = int(argmax_ties_low(score))
        if self.settings.stop_on_repeat and s['visited'][choice]:
            s['repeat_rule'] = 'stop_on_repeat'
            return None                 # give up (repeat) rather than look at a cell again
        return choice

    def _active_clutter(self) -> ClutterMap | None:
        """Return the clutter map of moving targets with search.hotspot_prior > 0 (counts only)."""
        settings = self.settings
        if settings.hotspot_prior <= 0 or not self._counts:
            return None
        key = (settings.hotspot_prior, settings.hotspot_scale)
        if self._clutter is None or self._clutter[0] != key:
            self._clutter = (key, ClutterMap(self.observation, *key))
        return self._clutter[1]

    @property
    def hotspot_probability(self) -> np.ndarray | None:
        """Each cell's probability of being a hotspot (moving targets' clutter map), or None."""
        return None if self._clutter is None else self._clutter[1].probability

    def _choose_moving(self, dt_s: float) -> int:
        """
        Return the next view with moving targets: a person's turn, else the infomax choice.

        Never None: a moving scene always has something to look at (the current view at worst).
        """
        s, settings = self._s(), self.settings
        found = self.tracks.found
        if settings.motion_track_view != 'policy' and found:
            person = self.turns.advance([t.person for t in found], dt_s, self._search_wanted())
            if person is not GLANCE:
                track = next(t for t in found if t.person == person)
                ahead = None
                if settings.motion_track_view == 'peak' and settings.motion_lead_s > 0:
                    ahead, _ = predict_occupancy(s['base'], s['outside'], self._motion,
                                                 settings.motion_lead_s, update=False)
                elif settings.motion_track_view == 'peak':
                    ahead = s['base']
                return self.tracks.view(track, settings.motion_lead_s, ahead)
        else:
            self.turns.reset()
        costs = self.costs_from(s['fixation'])
        score = self.gains() / costs
        if not np.isfinite(score).any() or score.max() <= MIN_GAIN / costs.min():
            return s['fixation']
        return int(argmax_ties_low(score))

    def _search_wanted(self) -> bool:
        """
        Whether the search has something to do: cells undecided, or someone likely unfollowed.

        Likely: a cell not within 2 cells of anyone followed with ``P >= 1/2``.
        """
        s = self._s()
        if not s['room_done']:
            return True
        unfollowed = ~self.tracks.followed()
        return bool(np.any(s['base'][unfollowed] >= 0.0))

    def _decide_moving(self, values: np.ndarray, offsets, dt_s: float) -> str:
        """
        Follow the people through a frame; return the decision it fired (module docstring).

        Cells are decided as still ones are (:meth:`_decided`); the evidence of a cell, its log
        odds above the prior, flows with the motion like the rest, so a room decided empty
        becomes undecided again as people could have walked in. The fixation budget ends a search
        that has decided nothing yet, as for one moving target.
        """
        s, settings = self._s(), self.settings
        log_odds = s['base']
        occupied, empty = self._decided(log_odds)
        # A person at an occupied cell (P >= confidence) is held, as one target's found holds
        # at the confidence whatever motion.keep_probability says: a keep above the confidence
        # would lose and reacquire the person in the same frame.
        keep = min(settings.motion_keep_probability or settings.confidence, settings.confidence)
        # A round of turns: each person and the search dwell_s at most; one more for slack.
        unseen_s = settings.motion_dwell_s * (len(self.tracks.found) + UNSEEN_SLACK_TURNS)
        self.people_events = tuple(self.tracks.step(
            occupancy(log_odds), occupied, keep, s['clock_s'], dt_s, values, offsets, unseen_s))
        followed = self.tracks.followed(self.link) if self.link > 0 else \
            np.zeros(self.grid.n_cells, dtype=bool)
        s['room_done'] = bool(np.all(self.settled(occupied) | followed | empty))
        decision = 'found' if self.tracks.found else ('absent' if s['room_done'] else '')
        fired = decision if decision and decision != s['decision'] else ''
        s['decision'] = decision
        s['decided_once'] = s['decided_once'] or bool(decision)
        if not s['decided_once'] and settings.max_fixations \
                and s['fixations'] >= settings.max_fixations:
            fired = self._limit('budget')
        return fired

    def _decided(self, log_odds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """
        Cells decided occupied and empty (N,) (``empty_by_evidence``: the evidence alone).

        After a pass's last pose with ``search.decide_after_pass``, empty by the posterior:
        every cell was seen well by one of the pass's views.
        """
        occupied, empty = decided(log_odds, self.settings.confidence)
        if self.empty_by_evidence and not self._pass_seen():
            empty = empty & decided(log_odds - self._s()['prior'], self.settings.confidence)[1]
        return occupied, empty

    def _pass_seen(self) -> bool:
        """Whether a pass that goes on to decide (``decide_after_pass``) has taken every pose."""
        s = self._s()
        return bool(self.passing and self.settings.decide_after_pass
                    and s['visited'][s['pass']].all())

    def _decide(self) -> str:
        s, settings = self._state, self.settings
        occupied, empty = self._decided(self.log_odds)
        if np.all(self.settled(occupied) | empty):
            s['ended'] = s['room_done'] = True
            found = bool(self.faces()) if self.passing else occupied.any()   # and its groups
            s['decision'] = 'found' if found else 'absent'
            return s['decision']
        if self.passing and not settings.decide_after_pass and s['visited'][s['pass']].all():
            return self._end_pass()
        if settings.max_fixations and s['fixations'] >= settings.max_fixations:
            return self._limit('budget')
        return ''

    def _end_pass(self) -> str:
        """End a pass after its last pose: every cell on its likelier side, groups named."""
        s = self._state
        s['reason'], s['ended'] = 'pass', True
        s['decision'] = 'found' if self.faces() else 'absent'
        return s['decision']

    def _limit(self, reason: str) -> str:
        s = self._state
        s['reason'], s['ended'] = reason, True
        decision = 'gave_up'
        if self.settings.decide_at_budget and not self._motion.active:
            found = bool(self.faces()) if self.passing else np.any(self.log_odds > 0)
            decision = 'found' if found else 'absent'    # a pass: its groups too
        s['decision'] = decision
        return decision

    def _rc(self, cell: int) -> list:
        return [int(v) for v in self.grid.cell(int(cell))]

    def _summary(self) -> dict:
        occupied, empty = self._decided(self.log_odds)
        return {'map_cell': self._rc(self.map_cell), 'map_probability': self.map_probability,
                'absent_probability': self.absent_probability,
                'entropy_nats': self.entropy_nats, 'occupied': int(occupied.sum()),
                'undecided': int((~occupied & ~empty).sum())}

    def _event(self, kind: str, **data) -> None:
        self._log.append({'event': kind, **data})

    def _result(self, status: str, reason: str = '', fired: str = '') -> StepResult:
        s = self._state
        return StepResult(status, s['fixations'], self.map_cell, self.map_probability,
                          self.absent_probability, reason or s['reason'], s['decision'], fired,
                          None if s['ended'] else s['fixation'], s['ended'])
