# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The one search engine: a search session that every driver runs (docs/design.md section 10).

A search is a short sequence of pure steps on one belief over the N cells (plus, with
``absent_prior > 0``, the hypothesis "no target in the grid"):

1. :meth:`SearchSession.reset` -- the prior: ``(1 - absent_prior) / N`` per cell (or
   ``(1 - absent_prior) P_i`` with a session ``prior`` P) and ``absent_prior`` on the absent
   hypothesis (:func:`ipomdp_gaze.model.stopping.initial_log_belief`);
2. :meth:`SearchSession.scan` -- optional, once, before the first fixation: the one-time scan of
   a model with scan tables, ``log B_i += log s_T(c_i) - log s_N(c_i)``;
3. :meth:`SearchSession.start` -- the first fixation: ``settings.start_cell``, or by default
   the policy's choice on the scanned belief after a scan and the grid's centre without one
   (docs/design.md section 4.2);
4. :meth:`SearchSession.update` with each frame taken at the current fixation: predict the belief
   over ``dt_s`` seconds (a moving target, :mod:`ipomdp_gaze.model.motion`), the Bayes step
   ``log B_i += log p_T(o_i | offset_ik) - log p_N(o_i | offset_ik)`` (or, for a still scene with
   ``repeat_weight < 1``, the still-scene evidence of :mod:`ipomdp_gaze.model.still_evidence`),
   then
   the stop rules (:func:`ipomdp_gaze.model.stopping.decide`): ``found``, ``absent`` (terminated:
   the
   evidence decided), ``gave_up`` (truncated: the budget, or every cell seen with
   ``stop_on_repeat``); if the search goes on, the policy chooses the next fixation.

The session holds the model it *assumes*; a sensor (:mod:`ipomdp_gaze.search.sensors`) produces the
frames from the world, which may follow another model. The session imports no ROS, reads no
clock (times arrive as ``dt_s``), prints nothing and writes nothing: drivers (the
``gaze_controller`` node through :class:`ipomdp_gaze.search.gaze.GazeController`, ``ipomdp-gaze
find``,
``search``, the offline evaluation and the Gymnasium environment) build settings, a sensor and a
session, then loop. Its per-search event log (:attr:`SearchSession.log`) is what drivers save.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
import math

from ipomdp_gaze.model.belief import (argmax_ties_low, bayes_update, check_prior, entropy_of_log,
                                      EvidenceError, map_cell, normalize_log, TIE_RTOL)
from ipomdp_gaze.model.clutter_map import ClutterMap
from ipomdp_gaze.model.false_alarms import FalseAlarmMixture
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_time import tour_detour_deg, view_seconds
from ipomdp_gaze.model.inhibition import policy_choice, unvisited_choice
from ipomdp_gaze.model.motion import Motion, VelocityMotion
from ipomdp_gaze.model.observation import as_observation, check_evidence, CountObservation
from ipomdp_gaze.model.position_filter import (GATE_CELLS, measured_position, PositionFilter,
                                               walk_filter)
from ipomdp_gaze.model.still_evidence import cell_information, StillEvidence
from ipomdp_gaze.model.stopping import ABSENT, decide_one, FOUND, initial_log_belief, with_absent
from ipomdp_gaze.model.view_reach import ViewReach
from ipomdp_gaze.search.settings import parameter_names, settings_class
import numpy as np

# Decisions a search can end with; '' while undecided.
DECISIONS = ('found', 'absent', 'gave_up')
# Why a search gave up: the fixation budget, or (stop_on_repeat) the next fixation would repeat
# a cell (NMPT's rule; with inhibition of return: every cell has been fixated).
GAVE_UP_REASONS = ('budget', 'repeat')
# Fixations kept in a search's :attr:`SearchSession.path` (the newest): a tracking search, or a
# still one without a budget that never decides, never ends, and its path would grow by one
# entry per frame for as long as the node runs.
PATH_SIZE = 10_000
# The parameter (node, YAML) name of each setting: the name every refusal message uses.
PARAMETER_NAMES = parameter_names()
# The settings object, generated from the schema (ipomdp_gaze.search.settings.SCHEMA): one checked
# field per setting; SearchSettings(confidence=0.99, max_fixations=60), replace() to change.
SearchSettings = settings_class(module=__name__)


def session_view(name: str, doc: str) -> property:
    """
    Return a read-only property that reads ``self.session.<name>``.

    For wrappers of a search session (the controller's logic, the Gymnasium environment): each
    view they pass through is declared in one line with its own docstring, the session's value
    unchanged.
    """
    return property(lambda self: getattr(self.session, name), doc=doc)


# A stop rule's decision code as the search reports it.
_DECISIONS = {FOUND: 'found', ABSENT: 'absent'}


def pooled_belief(belief: np.ndarray, grid: Grid, radius: int) -> np.ndarray:
    """Return, per cell, the belief within ``radius`` cells (Chebyshev) of it, ``(N,)``."""
    if radius <= 0:
        return belief
    side = 2 * radius + 1
    padded = np.pad(np.asarray(belief, dtype=float).reshape(grid.rows, grid.cols), radius)
    window = np.lib.stride_tricks.sliding_window_view(padded, (side, side))
    return window.sum(axis=(2, 3)).reshape(-1)


def _mixture_settings(settings: SearchSettings) -> tuple:
    """Return the settings the false-alarm mixture is built from."""
    return settings.false_alarm_scales, settings.hotspot_prior, settings.hotspot_scale


def target_motion(grid: Grid, settings: SearchSettings) -> Motion:
    """Return the target's motion of ``settings`` (per second in the nodes)."""
    if settings.motion_max_speed_cells > 0:
        return VelocityMotion(grid, settings.motion_sigma_cells, settings.motion_jump_prob,
                              settings.motion_leave_prob, settings.motion_max_speed_cells,
                              settings.motion_turn_prob, settings.motion_speed_cells)
    return Motion(grid, settings.motion_sigma_cells, settings.motion_jump_prob,
                  settings.motion_leave_prob)


def motion_settings(settings: SearchSettings) -> tuple:
    """Return what the motion object is built from (a change rebuilds it)."""
    return (settings.motion_sigma_cells, settings.motion_jump_prob, settings.motion_leave_prob,
            settings.motion_max_speed_cells, settings.motion_turn_prob,
            settings.motion_speed_cells)


def _wants_mixture(settings: SearchSettings) -> bool:
    return scales_false_alarms(settings) or settings.hotspot_prior > 0


def scales_false_alarms(settings: SearchSettings) -> bool:
    """Say whether the settings scale the model's false-alarm rates (any factors but [1.0])."""
    return settings.false_alarm_scales != (1.0,)


def _check_mixture_model(settings: SearchSettings, observation) -> None:
    """Refuse many targets, and false-alarm scales or hotspots without count tables to scale."""
    if settings.targets != 'one':
        raise ValueError(f"{PARAMETER_NAMES['targets']} {settings.targets} is searched by "
                         f'ipomdp_gaze.search.many.OccupancySession; this session holds one '
                         f'target')
    if not _wants_mixture(settings) or isinstance(observation, CountObservation):
        return
    name = 'false_alarm_scales' if scales_false_alarms(settings) else 'hotspot_prior'
    raise ValueError(f'{PARAMETER_NAMES[name]} needs a count model '
                     f'(observation.model: counts); this search uses '
                     f'{getattr(observation, "name", type(observation).__name__)}')


def check_model_settings(settings: SearchSettings, grid: Grid,
                         observation) -> ViewReach | None:
    """
    Refuse one-target settings that ``observation`` cannot serve (``ValueError``, one line).

    What :class:`SearchSession` checks when it is built, configured or given a model: the
    false-alarm scales and hotspots need count tables, ``search.absent_needs_coverage`` a
    pan/tilt camera (whose reach it returns; None without the setting). The node's parameter
    check calls it, so a change is refused before any of it applies.
    """
    observation = as_observation(grid, observation)
    _check_mixture_model(settings, observation)
    if not settings.absent_needs_coverage:
        return None
    reach = ViewReach.of(grid, observation)        # a camera record it cannot read: refused
    if reach is None:
        raise ValueError('search.absent_needs_coverage needs a pan/tilt count model (its '
                         'camera says which cells a view sees well); this model has no camera')
    return reach


def check_scan_model(observation) -> None:
    """Refuse a one-time scan of a model without scan tables (ValueError, as a count model's)."""
    if not getattr(observation, 'has_scan', False):
        name = getattr(observation, 'name', type(observation).__name__)
        raise ValueError(f'this {name} model has no scan tables: a one-time scan needs a count '
                         f'model measured with one (scan_target, scan_null)')


def check_groups(groups, n_cells: int) -> np.ndarray | None:
    """
    Return a frame's grouped detections per cell as ``(N,)`` float64 (None stays None).

    Raises
    ------
    EvidenceError
        If the shape is not ``(N,)`` or a value is not a whole number >= 0.

    """
    if groups is None:
        return None
    values = np.asarray(groups, dtype=np.float64)
    if values.shape != (n_cells,):
        raise EvidenceError(f'groups must have shape ({n_cells},), got {values.shape}')
    if not (np.isfinite(values).all() and (values >= 0).all()
            and (values == np.round(values)).all()):
        raise EvidenceError('groups must be whole numbers >= 0 (grouped detections per cell)')
    return values


def check_offsets(offsets, n_cells: int) -> np.ndarray | None:
    """
    Return a frame's per-cell detection offsets as ``(N, 2)`` float64 (None stays None).

    Raises
    ------
    EvidenceError
        If the shape is not ``(N, 2)`` or an offset is not NaN and not within half a cell.

    """
    if offsets is None:
        return None
    values = np.asarray(offsets, dtype=np.float64)
    if values.shape != (n_cells, 2):
        raise EvidenceError(f'offsets must have shape ({n_cells}, 2), got {values.shape}')
    seen = values[~np.isnan(values)]
    if seen.size and not (np.isfinite(seen).all() and np.abs(seen).max() <= 0.5 + 1e-6):
        raise EvidenceError('offsets must be NaN or within half a cell of the centre')
    return values


def position_settings(settings: SearchSettings) -> tuple:
    """Return what a position filter is built from (a change rebuilds it)."""
    return (settings.motion_track_view, settings.motion_position_sigma_cells,
            settings.motion_turn_prob, settings.motion_speed_cells, settings.motion_sigma_cells)


def track_filter(settings: SearchSettings) -> PositionFilter | None:
    """
    ``motion.track_view: position``'s filter (docs/design.md section 12.9), else None.

    The velocity changes at ``motion.turn_prob`` per second to a new draw of the prior (per
    axis standard deviation ``motion.speed_cells``), a change of variance ``2 speed^2`` on
    average: the filter's velocity random walk is ``q = 2 turn_prob speed^2``.
    """
    if settings.motion_track_view != 'position':
        return None
    return walk_filter(settings.motion_position_sigma_cells, settings.motion_turn_prob,
                       settings.motion_sigma_cells, settings.motion_speed_cells)


def fixation_index(grid: Grid, cell) -> int:
    """
    Return the cell a driver fixates (``fixate``) as a row-major index (ValueError otherwise).

    One whole number in the grid: a fraction is refused, not truncated, and so is a bool
    (``True`` is no cell 1), a sequence or an array, which :meth:`Grid.cell` would take as many
    cells.
    """
    if np.ndim(cell):
        raise ValueError(f'a cell index must be one whole number, got {cell!r}')
    row, col = grid.cell(cell)
    return row * grid.cols + col


def start_index(grid: Grid, settings: SearchSettings) -> int | None:
    """Return the cell index of ``settings.start_cell`` on ``grid``, or None (the default rule)."""
    settings.check_grid(grid)
    if not isinstance(settings.start_cell, tuple):
        return None
    return grid.index(*settings.start_cell)


@dataclass(frozen=True)
class Frame:
    """
    One observation of the whole grid.

    ``values`` holds one number per cell, row-major (N,): a standardised response for the
    Gaussian model, a detection count for a count model; NaN means not observed. ``kind`` is
    ``'fixation'`` (taken at the session's current fixation) or ``'scan'`` (the one-time scan).
    ``detector_pixels`` and ``seconds`` are what producing it cost; ``detections`` any boxes
    the sensor wants drivers to draw or record. ``offsets`` ``(N, 2)``, optional: the mean
    offset ``(row, col)`` in cells of the detections centred in each cell from its centre (NaN
    where none), which ``motion.track_view: position`` reads (docs/design.md section 12.9).
    ``groups`` ``(N,)``, optional: how many of the detector's grouped detections (as
    ``detectMultiScale`` groups its raw boxes) are centred in each cell, which a many-target
    pass answers (docs/design.md section 11.7) and ``search.group_stop`` stops at (section
    6.15). A frame built by
    :meth:`SearchSession.checked_frame` carries the session and model that checked it, so that
    session does not check it again.
    """

    values: np.ndarray
    kind: str = 'fixation'
    detector_pixels: int = 0
    seconds: float = 0.0
    detections: tuple = ()
    offsets: np.ndarray | None = None
    groups: np.ndarray | None = None
    _checked_by: tuple = field(default=(), init=False, repr=False, compare=False)

    def summary(self) -> dict:
        """Return what the event log keeps of a frame: cells observed, sum and peak, cost."""
        values = np.asarray(self.values, dtype=float)
        seen = values[~np.isnan(values)]
        with np.errstate(over='ignore'):        # legal evidence near the float limit sums to inf
            total = float(seen.sum()) if seen.size else 0.0
        return {'kind': self.kind, 'observed_cells': int(seen.size), 'sum': total,
                'peak': float(seen.max()) if seen.size else None,
                'detector_pixels': int(self.detector_pixels)}


@dataclass(frozen=True)
class StepResult:
    """
    What one frame did (as Gymnasium's ``step``: terminated and truncated kept apart).

    ``status`` is ``'applied'`` or ``'rejected'`` (``reason`` says why; the belief is then
    unchanged). ``decision`` is ``found`` / ``absent`` (``terminated``: the evidence decided,
    or for ``found`` with reason ``group`` a grouped detection, ``search.group_stop``),
    ``gave_up`` (``truncated``: a limit, ``reason`` ``budget`` or ``repeat``) or ``''``;
    ``fired`` names the decision first reached by this frame ('' if none: with motion on a
    decision can be reported, lost and reached again). ``fixation`` is the next fixation, None
    once the search has ended.
    """

    status: str
    fixations: int
    map_cell: int
    map_probability: float
    absent_probability: float
    reason: str = ''
    decision: str = ''
    fired: str = ''
    fixation: int | None = None
    ended: bool = False

    @property
    def applied(self) -> bool:
        """Whether the frame updated the belief."""
        return self.status == 'applied'

    @property
    def terminated(self) -> bool:
        """Whether the evidence decided (``found`` or ``absent``) and the search ended."""
        return self.ended and self.decision in ('found', 'absent')

    @property
    def truncated(self) -> bool:
        """Whether a limit ended the search undecided (``gave_up``)."""
        return self.ended and self.decision == 'gave_up'


class OrderError(RuntimeError):
    """A session step called out of order (update before start, a scan after a fixation)."""


@dataclass
class _Search:
    """Per-search state of a session (replaced whole by :meth:`SearchSession.reset`)."""

    log_belief: np.ndarray
    still_base: np.ndarray
    visited: np.ndarray
    fixation: int | None = None
    fixations: int = 0
    scanned: bool = False
    decision: str = ''
    reason: str = ''
    # A repeat stop's cause (:attr:`SearchSession.limit_cause`), as the settings were then.
    repeat_cause: str = ''
    ended: bool = False
    decided_once: bool = False
    group_cell: int | None = None
    path: deque = field(default_factory=lambda: deque(maxlen=PATH_SIZE))
    # Every cell fixated in this search (the views :meth:`SearchSession._uncovered` counts; the
    # path keeps only the newest PATH_SIZE, and ``visited`` is cleared by inhibition of return).
    viewed: np.ndarray | None = None
    # What the read-only views derive from log_belief, each computed once: emptied whenever
    # log_belief (or a setting a view depends on) changes.
    views: dict = field(default_factory=dict)


class _PerSecond:
    """
    The session's policy seen per second of head time (``search.head_speed_deg_s``).

    Its scores are the policy's ``scores_per_second`` from the current fixation (before the
    first, the grid's centre, where the head model starts: ``start_cell: policy``), so
    inhibition of return and the choice treat it as any policy with scores.
    """

    def __init__(self, session: 'SearchSession'):
        self.session = session

    def _here(self) -> int:
        """Return the head's cell: the current fixation, else the grid's centre."""
        fixation = self.session._search.fixation
        return self.session.grid.center_index if fixation is None else fixation

    def scores(self, belief: np.ndarray) -> np.ndarray:
        """Return the policy's scores per second of each view from the current fixation."""
        session = self.session
        settings, here = session.settings, self._here()
        seconds = view_seconds(session.grid, here, settings.view_time_s,
                               settings.head_speed_deg_s)
        detour_s = self._detour_s if settings.head_tour else None
        return np.asarray(session.policy.scores_per_second(belief, seconds, detour_s),
                          dtype=float)

    def select(self, belief, t, rng) -> np.ndarray:
        return argmax_ties_low(self.scores(belief))

    def _detour_s(self, cells) -> np.ndarray:
        """Return the seconds the tour of the unvisited ``cells`` grows by starting at each."""
        session = self.session
        search, settings = session._search, session.settings
        cells = np.asarray(cells, dtype=np.int64)
        left = ~search.visited[cells] if settings.inhibit_return \
            else np.ones(cells.size, dtype=bool)
        out = np.zeros(cells.size)
        out[left] = tour_detour_deg(session.grid, self._here(), cells[left]) \
            / settings.head_speed_deg_s
        return out


def check_seconds_elapsed(dt_s) -> float:
    """Return ``dt_s`` as float seconds, or raise ValueError unless it is finite and >= 0."""
    try:
        value = float(dt_s)
    except (TypeError, ValueError):
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f'dt_s must be a finite number of seconds >= 0, got {dt_s!r}')
    return value


def check_policy_grid(policy, grid) -> None:
    """Refuse a policy built for another grid's shape (ValueError): its scores would not fit."""
    own = getattr(policy, 'grid', None)
    if own is not None and tuple(own.shape) != tuple(grid.shape):
        raise ValueError(f'the policy is for a {own.rows}x{own.cols} grid, the search is on a '
                         f'{grid.rows}x{grid.cols} grid')


class SearchSession:
    """
    One search at a time on one grid, with an assumed observation model and a policy.

    Parameters
    ----------
    grid : Grid
        The visual array.
    observation
        The observation model the searcher assumes (:mod:`ipomdp_gaze.model.observation`) or an
        FPOC.
    policy
        Anything with ``select(belief (1, N), t, rng)``; with ``scores(belief)`` inhibition of
        return masks the scores. None: the driver chooses every fixation itself
        (:meth:`fixate`, as a Gymnasium agent does); the session then never chooses.
    settings : SearchSettings
        Checked already; the start cell is checked against ``grid`` here.
    prior : array (N,) or (rows, cols), optional
        Where the target is a priori, summing to 1 (:func:`ipomdp_gaze.model.belief.check_prior`):
        every search starts at it (default uniform, the paper's task); cells at 0 stay at 0.
    log_size : int
        Events kept in :attr:`log` (the newest); a tracking search never ends. 0 keeps none,
        and the per-frame events are not even built (the gaze controller's: its results and
        the node's topics say what happened).

    """

    def __init__(self, grid: Grid, observation, policy, settings: SearchSettings | None = None,
                 log_size: int = 10_000, prior=None):
        self.grid = grid
        self.prior = None
        self.set_prior(prior)
        self.observation = as_observation(grid, observation)
        check_policy_grid(policy, grid)
        self.policy = policy
        self.settings = settings or SearchSettings()
        self.settings.check_grid(grid)
        self.motion = target_motion(grid, self.settings)
        self._kernel = None
        self._still = StillEvidence(grid.n_cells)
        self._log = deque(maxlen=int(log_size))
        self.rng = np.random.default_rng(0)
        self._search = None
        self._counts = isinstance(self.observation, CountObservation)
        self._mixture = None
        self._clutter = None
        self._position = track_filter(self.settings)
        self._reach = check_model_settings(self.settings, grid, self.observation)

    # -- configuration -------------------------------------------------------------------
    def configure(self, settings: SearchSettings) -> None:
        """
        Use new settings from the next frame on, keeping the belief of the search under way.

        A new ``absent_prior`` applies from the next :meth:`reset`; a change of
        ``repeat_weight`` or of motion on/off counts the still scene's evidence afresh from the
        belief now.
        """
        settings.check_grid(self.grid)
        reach = check_model_settings(settings, self.grid, self.observation)
        old = self.settings
        self.settings = settings
        self._reach = reach
        if motion_settings(settings) != motion_settings(old):
            self.motion = target_motion(self.grid, settings)
        if position_settings(settings) != position_settings(old):
            self._position = track_filter(settings)
        self._changed()                 # the answer's square follows found_radius and motion
        mixture_changed = _mixture_settings(settings) != _mixture_settings(old)
        if mixture_changed or settings.moving != old.moving:
            self._mixture = None
            self._clutter = None
        if self._search is not None and (settings.repeat_weight != old.repeat_weight
                                         or settings.moving != old.moving or mixture_changed):
            self._still.reset()
            if self._mixture is not None:
                self._mixture.reset()
            self._search.still_base = self._search.log_belief.copy()

    def set_observation(self, observation, settings: SearchSettings | None = None) -> None:
        """
        Assume another observation model (or FPOC) from the next frame on.

        ``settings``: the ones :meth:`configure` is about to be given (a driver changing both
        at once); the model is checked against them instead of those in force.
        """
        observation = as_observation(self.grid, observation)
        settings = settings or self.settings
        # many targets: this session is replaced (configure), nothing to check against
        reach = check_model_settings(settings, self.grid, observation) \
            if settings.targets == 'one' else None
        self.observation = observation
        self._counts = isinstance(self.observation, CountObservation)
        self._reach = reach
        self._kernel = None
        self._mixture = None
        self._clutter = None

    def set_policy(self, policy) -> None:
        """Choose with another policy from the next choice on (one of this grid's shape)."""
        check_policy_grid(policy, self.grid)
        self.policy = policy

    def set_prior(self, prior) -> None:
        """From the next reset, start every search at ``prior`` (N,) (None: uniform)."""
        if prior is not None:
            prior = check_prior(prior, self.grid.n_cells, self.grid.shape)
            prior.flags.writeable = False
        self.prior = prior

    # -- read-only views -----------------------------------------------------------------
    def _state(self) -> _Search:
        if self._search is None:
            raise OrderError('reset the session before using it')
        return self._search

    @property
    def log_belief(self) -> np.ndarray:
        """Log probabilities, (N,) or (N + 1,) with the absent hypothesis last; a copy."""
        return self._state().log_belief.copy()

    def _view(self, name: str, compute):
        """Return a view of the belief, computed once after each change (:meth:`_changed`)."""
        views = self._state().views
        if name not in views:
            views[name] = compute()
        return views[name]

    def _changed(self) -> None:
        """Forget the views: the log belief, or a setting a view depends on, has changed."""
        if self._search is not None:
            self._search.views.clear()

    def _cells(self) -> np.ndarray:
        """Cell probabilities ``exp(log B_i)`` (N,), shared and read-only."""
        def compute():
            cells = np.exp(self._search.log_belief[:self.grid.n_cells])
            cells.flags.writeable = False
            return cells
        return self._view('cells', compute)

    @property
    def belief(self) -> np.ndarray:
        """Cell probabilities ``B_i`` (N,), a copy; they sum to ``1 - P(absent)``."""
        return self._cells().copy()

    @property
    def absent_probability(self) -> float:
        """``P(absent)``: 0 without the absent hypothesis."""
        log_b = self._state().log_belief
        return float(np.exp(log_b[-1])) if log_b.size > self.grid.n_cells else 0.0

    @property
    def map_cell(self) -> int:
        """
        Return the answer: the most likely cell (ties to the lowest index).

        With ``found_radius`` r > 0: the cell whose (2r + 1)-square holds the most belief.
        After a grouped detection ended the search (``search.group_stop``): its cell.
        """
        group_cell = self._state().group_cell
        if group_cell is not None:
            return group_cell
        return self._view('map_cell', lambda: int(map_cell(self._pooled())))

    def _pooled(self) -> np.ndarray:
        radius = self.settings.found_radius
        return self._view('pooled', lambda: pooled_belief(self._cells(), self.grid, radius))

    @property
    def map_probability(self) -> float:
        """Probability of the answer: its cell, or its square with ``found_radius``."""
        return self._view('map_probability', lambda: float(self._pooled()[self.map_cell]))

    @property
    def entropy_nats(self) -> float:
        """Entropy of the belief over all its hypotheses, in nats."""
        return self._view('entropy_nats',
                          lambda: entropy_of_log(self._search.log_belief, self._cells()))

    @property
    def fixation(self) -> int | None:
        """Return the current fixation, a row-major index; None before :meth:`start`."""
        return self._state().fixation

    @property
    def fixation_cell(self) -> tuple[int, int] | None:
        """
        Return the current fixation as ``(row, col)``; None before :meth:`start`.

        :meth:`start`, :attr:`fixation`, :attr:`map_cell` and ``StepResult.fixation`` stay
        row-major indices ``row * cols + col`` (what :meth:`fixate`, :meth:`exclude` and the
        policies take); this is the same cell for a driver that moves a head by row and column.
        """
        cell = self._state().fixation
        return None if cell is None else tuple(int(v) for v in self.grid.cell(cell))

    @property
    def visited(self) -> np.ndarray:
        """Cells fixated in this search since inhibition of return last reopened them."""
        return self._state().visited.copy()

    @property
    def repeated_evidence(self) -> np.ndarray:
        """Per cell, the still-scene evidence beyond its most informative view (N,)."""
        return self._still.total - self._still.kept

    @property
    def fixations(self) -> int:
        """Frames applied in this search."""
        return self._state().fixations

    @property
    def path(self) -> tuple:
        """Return the fixations whose frames were applied, in order: the newest PATH_SIZE."""
        return tuple(self._state().path)

    @property
    def decision(self) -> str:
        """Return found, absent, gave_up or ''; with motion, the tracker's state."""
        return self._state().decision

    @property
    def gave_up_reason(self) -> str:
        """Return the limit that ended the search (budget, repeat or a driver's), else ''."""
        return self._state().reason

    @property
    def limit_setting(self) -> str:
        """
        Return the setting whose rule ended the search at its limit, else ''.

        ``max_fixations`` (reason ``budget``), ``stop_on_repeat`` (``repeat``: only that rule
        gives up on a repeat); '' for a driver's limit (:meth:`stop`) or none.
        """
        return {'budget': 'max_fixations', 'repeat': 'stop_on_repeat'}.get(
            self._state().reason, '')

    @property
    def limit_cause(self) -> str:
        """
        Return what ended the search at a ``repeat`` stop, else '' (:data:`answer.REPEATS`).

        ``every_cell`` (inhibition of return, still target: every cell was fixated) or
        ``next_repeats`` (the policy's next fixation was a cell fixated already).
        """
        search = self._state()
        return search.repeat_cause if search.reason == 'repeat' else ''

    @property
    def ended(self) -> bool:
        """Return whether the search has ended: no more frames until :meth:`reset`."""
        return self._state().ended

    @property
    def log(self) -> tuple:
        """Return the events, oldest first: dicts, the newest ``log_size`` of them."""
        return tuple(self._log)

    # -- the steps -----------------------------------------------------------------------
    def check_frame(self, values) -> np.ndarray:
        """
        Return a frame's values as floats (N,), or raise :class:`EvidenceError` with the reason.

        Refused: a wrong length, +/-inf, and for a count model a negative or fractional count.
        NaN is allowed (not observed).
        """
        obs = check_evidence(values, self.grid.n_cells)
        if self._counts:
            self.observation.counts(obs)
        return obs

    def checked_frame(self, values, kind: str = 'fixation', offsets=None,
                      groups=None) -> Frame:
        """
        Return ``Frame(values, kind, offsets=offsets, groups=groups)`` checked here, once.

        The values as :meth:`check_frame`; ``groups`` are checked and kept (one target reads
        them only with ``search.group_stop``).

        :meth:`update` and :meth:`scan` take it without checking it again while the session
        assumes the same model. For a driver that must know whether a frame is usable before
        deciding what to do with it (the controller counts a bad frame as rejected even when it
        would skip it). The values are :meth:`check_frame`'s floats; change none of them before
        the frame is applied.

        Raises
        ------
        EvidenceError
            With the reason, as :meth:`check_frame`.

        """
        frame = Frame(self.check_frame(values), kind=kind,
                      offsets=check_offsets(offsets, self.grid.n_cells),
                      groups=check_groups(groups, self.grid.n_cells))
        object.__setattr__(frame, '_checked_by', (self, self.observation))
        return frame

    def _frame_values(self, frame: Frame) -> np.ndarray:
        """Return a frame's checked values: checked here unless this session checked them."""
        checked = frame._checked_by
        if checked and checked[0] is self and checked[1] is self.observation:
            return frame.values
        return self.check_frame(frame.values)

    def _frame_part(self, frame: Frame, name: str, check) -> np.ndarray | None:
        """Return a frame's ``offsets`` or ``groups``: checked here unless this session did."""
        checked = frame._checked_by
        if checked and checked[0] is self:
            return getattr(frame, name)
        return check(getattr(frame, name), self.grid.n_cells)

    def reset(self, *, seed=None) -> None:
        """
        Start a new search from the prior.

        A ``seed`` (an int, or a Generator to use as it is) restarts the policy's random
        stream, which otherwise runs on.

        The prior is ``(1 - absent_prior) / N`` per cell (``(1 - absent_prior) P_i`` with the
        session's ``prior`` P) and ``absent_prior`` on the absent hypothesis (none when it is 0).
        """
        if isinstance(seed, np.random.Generator):
            self.rng = seed
        elif seed is not None:
            self.rng = np.random.default_rng(seed)
        log_b = initial_log_belief(self.grid.n_cells, self.settings.absent_prior,
                                   prior=self.prior)    # a cell at 0: log 0 = -inf, kept so
        self._still.reset()
        self.motion.reset()
        if self._mixture is not None:
            self._mixture.reset()
        if self._clutter is not None:
            self._clutter.reset()
        self._position = track_filter(self.settings)
        self._search = _Search(log_b, log_b.copy(), np.zeros(self.grid.n_cells, dtype=bool),
                               viewed=np.zeros(self.grid.n_cells, dtype=bool))
        self._event('reset', settings=self.settings.to_parameters())

    def exclude(self, cells) -> None:
        """
        Rule cells out of the search under way: their probability becomes 0, the rest renormalised.

        For a search for *another* target once one was found there (``find --all``): the
        posterior is the Bayes posterior under the prior restricted to the other hypotheses
        (the other cells, and the absent one), since a likelihood times a zero prior stays zero.
        Excluded cells may still be fixated (their views see the cells round them). Call it after
        :meth:`reset` and before the frames it should condition; at least one cell must remain.

        Raises
        ------
        ValueError
            For a cell outside the grid, or when no cell would remain.

        """
        search = self._state()
        index = np.unique(np.asarray(cells, dtype=np.int64).reshape(-1))
        if index.size and (index.min() < 0 or index.max() >= self.grid.n_cells):
            raise ValueError(f'cells to exclude must be in 0..{self.grid.n_cells - 1}, got '
                             f'{index.tolist()}')
        open_cells = np.isfinite(search.log_belief[:self.grid.n_cells])
        open_cells[index] = False
        if not open_cells.any():
            raise ValueError('excluding these cells would leave no cell to search')
        for log_b in (search.log_belief, search.still_base):
            log_b[index] = -np.inf
            normalize_log(log_b)
        self._changed()
        self._event('exclude', cells=[self._rc(c) for c in index])

    def scan(self, frame: Frame) -> StepResult:
        """
        Apply the one-time scan, before the first fixation is chosen (at most once a search).

        ``log B_i += log s_T(c_i) - log s_N(c_i)`` with the model's scan tables. Skipped
        (status ``applied``, reason ``scan off``) with ``settings.scan`` false.

        Raises
        ------
        OrderError
            After :meth:`start` or a second time.
        ValueError
            If the model has no scan tables.

        """
        search = self._state()
        if search.fixation is not None or search.scanned:
            raise OrderError('the one-time scan comes once, before the first fixation')
        if not self.settings.scan:
            return self._result('applied', reason='scan off')
        check_scan_model(self.observation)
        try:
            obs = self._frame_values(frame)
            term = self.observation.scan_log_likelihood_ratio(obs)
        except EvidenceError as exc:
            return self._result('rejected', reason=str(exc))
        search.scanned = True
        bayes_update(search.log_belief, with_absent(term, search.log_belief),
                     out=search.log_belief)
        self._changed()
        search.still_base = search.log_belief.copy()
        self._event('scan', frame=frame.summary(), belief=self._belief_summary())
        return self._result('applied')

    def start(self) -> int:
        """
        Choose the first fixation and return it, a row-major index (:attr:`fixation_cell`).

        ``settings.start_cell`` if it is a cell; the policy's choice (its best unvisited cell
        with inhibition of return) on the belief if it is ``'policy'`` or after a scan;
        otherwise, and without a policy (the driver chooses: :meth:`fixate`), the grid's centre.
        """
        search = self._state()
        if search.fixation is not None:
            raise OrderError('the search has started already; reset starts a new one')
        fixed = start_index(self.grid, self.settings)
        if fixed is not None:
            search.fixation = fixed
        elif self.policy is not None and (search.scanned or self.settings.start_cell == 'policy'):
            search.fixation = self._choose()
        else:
            search.fixation = self.grid.center_index
        self._event('start', fixation=self._rc(search.fixation))
        return search.fixation

    def fixate(self, cell: int) -> None:
        """
        Take the next frame at ``cell`` instead of the policy's choice.

        For a driver that follows fixations made elsewhere (a recording, a head that could not
        reach the chosen cell, a test).
        """
        search = self._state()
        if search.fixation is None:
            raise OrderError('start the search before fixating')
        search.fixation = fixation_index(self.grid, cell)

    def predict(self, dt_s: float) -> None:
        """Spread the belief over ``dt_s`` of the target's motion (nothing for a still target)."""
        dt_s = check_seconds_elapsed(dt_s)
        if self.motion.active and dt_s > 0:
            self.motion.predict_over(self._state().log_belief, dt_s)
            self._changed()

    def update(self, frame: Frame, dt_s: float = 0.0) -> StepResult:
        """
        Apply a frame taken at the current fixation; decide; choose the next fixation.

        Validate (a frame of the wrong length, with +/-inf, or, for a count model, a negative or
        fractional count is rejected and the belief unchanged), predict over ``dt_s`` (motion),
        the Bayes step (or the still-scene evidence), the stop rules, the next choice.

        Raises
        ------
        OrderError
            Before :meth:`start`, or after the search has ended.
        ValueError
            For a ``dt_s`` that is negative or not finite.

        """
        search = self._state()
        if search.fixation is None:
            raise OrderError('start the search (the first fixation) before updating it')
        if search.ended:
            raise OrderError(f'the search has ended ({search.decision}); reset starts a new one')
        dt_s = check_seconds_elapsed(dt_s)
        try:
            obs = self._frame_values(frame)
            offsets = self._frame_part(frame, 'offsets', check_offsets)
            groups = self._frame_part(frame, 'groups', check_groups)
            term = self.observation.log_likelihood_ratio(obs, search.fixation)
        except EvidenceError as exc:
            return self._result('rejected', reason=str(exc))
        self.predict(dt_s)
        mixture = self._active_mixture()
        if mixture is not None:
            information = self._still_information(obs)
            self._still.add(term, information)
            mixture.add(obs, search.fixation, information)
            search.log_belief[:] = mixture.log_belief(search.still_base,
                                                      self.settings.repeat_weight)
        elif self.settings.repeat_weight < 1.0 and not self.motion.active:
            bayes_update(search.still_base,
                         with_absent(self._still_term(obs, term), search.log_belief),
                         out=search.log_belief)
        else:
            clutter = self._active_clutter()
            if clutter is not None:
                term = clutter.step(search.log_belief, obs, search.fixation, term)
            bayes_update(search.log_belief, with_absent(term, search.log_belief),
                         out=search.log_belief)
        self._changed()
        search.fixations += 1
        search.path.append(search.fixation)
        search.visited[search.fixation] = True
        search.viewed[search.fixation] = True
        fired = self._decide(groups)
        self._follow(obs, offsets, dt_s)
        if not search.ended:
            following = self._choose()
            if following is None:
                search.decision, search.reason, search.ended = 'gave_up', 'repeat', True
                search.repeat_cause = 'every_cell' if self.settings.inhibit_return \
                    and not self.motion.active else 'next_repeats'
                fired = 'gave_up'
            else:
                search.fixation = following
        if self._log.maxlen:
            self._event('frame', fixation=self._rc(search.path[-1]), frame=frame.summary(),
                        belief=self._belief_summary(), decision=search.decision,
                        fired=fired, reason=search.reason)
        return self._result('applied', fired=fired)

    # -- inside ------------------------------------------------------------------------------
    def _still_information(self, obs: np.ndarray) -> np.ndarray:
        if self._kernel is None:
            self._kernel = np.asarray(self.observation.elm_kernel(), dtype=float)
        information = cell_information(self._kernel, self.grid, self._search.fixation)
        return np.where(np.isnan(obs), 0.0, information)

    def _still_term(self, obs: np.ndarray, term: np.ndarray) -> np.ndarray:
        self._still.add(term, self._still_information(obs))
        return self._still.log_likelihood_ratio(self.settings.repeat_weight)

    def _active_mixture(self) -> FalseAlarmMixture | None:
        """Return the false-alarm mixture when the settings ask for one and the target is still."""
        if not _wants_mixture(self.settings) or self.motion.active:
            return None
        if self._mixture is None:
            self._mixture = FalseAlarmMixture(self.observation, *_mixture_settings(self.settings))
        return self._mixture

    def _active_clutter(self) -> ClutterMap | None:
        """Return the clutter map when hotspots are asked for and the target moves (§12.8)."""
        if self.settings.hotspot_prior <= 0 or not self.motion.active or not self._counts:
            return None
        if self._clutter is None:
            self._clutter = ClutterMap(self.observation, self.settings.hotspot_prior,
                                       self.settings.hotspot_scale)
        return self._clutter

    @property
    def hotspot_probability(self) -> np.ndarray | None:
        """Each cell's probability of being a hotspot (the clutter map, §12.8); None without."""
        return None if self._clutter is None else self._clutter.probability

    def _decide(self, groups: np.ndarray | None = None) -> str:
        """
        Run the stop rules after an applied frame; return the decision it fired ('').

        The confidence first (``absent`` held back while ``search.absent_needs_coverage`` finds
        a cell the views have not covered), then a grouped detection (``search.group_stop``),
        then the budget.
        """
        search, settings = self._search, self.settings
        pooled = self._pooled()
        peak, absent = float(pooled.max()), self.absent_probability
        views = search.views
        if 'map_cell' not in views:         # the answer from this peak: argmax_ties_low's rule
            views['map_cell'] = int(np.argmax(pooled >= peak - TIE_RTOL * abs(peak)))
        code = decide_one(peak, absent, settings.confidence)
        decision = _DECISIONS.get(code, '')
        if decision == 'absent' and self._uncovered().size:
            decision = ''                   # search.absent_needs_coverage: not yet (§6.16)
        keep = settings.motion_keep_probability
        if self.motion.active and not decision and search.decision == 'found' and keep \
                and peak >= keep and peak >= absent:
            decision = 'found'              # tracking: found holds until below keep_probability
        fired = ''
        if self.motion.active or not settings.stop_on_decision:
            fired = decision if decision and decision != search.decision else ''
            search.decision = decision
        elif decision:
            search.decision, search.ended, fired = decision, True, decision
        search.decided_once = search.decided_once or bool(fired)
        if not search.ended and self._group_stops(groups):
            open_cells = np.isfinite(search.log_belief[:self.grid.n_cells])     # not excluded
            cells = np.flatnonzero((groups > 0) & open_cells)
            pooled = self._pooled()
            if cells.size and pooled[cells].max() >= settings.group_probability:
                search.group_cell = int(cells[np.argmax(pooled[cells])])
                search.decision, search.reason, search.ended = 'found', 'group', True
                search.decided_once = True
                return 'found'
        if search.group_cell is None and 'map_probability' not in views:
            views['map_probability'] = float(pooled[views['map_cell']])
        budget_applies = not search.decided_once or not settings.stop_on_decision
        if budget_applies and settings.max_fixations \
                and search.fixations >= settings.max_fixations:
            fired = self._limit('budget')
        return fired

    def _uncovered(self) -> np.ndarray:
        """
        Return the cells the search's views have not covered, with ``absent_needs_coverage``.

        Only the cells that may hold the target: not one the prior rules out (or
        :meth:`exclude` took out), whose belief is 0 for good. Empty without the setting, for
        a moving target or without a pan/tilt camera (:mod:`ipomdp_gaze.model.view_reach`,
        docs/design.md section 6.16).
        """
        if not self.settings.absent_needs_coverage or self.motion.active \
                or self._reach is None:
            return np.zeros(0, dtype=np.int64)
        open_cells = np.isfinite(self._search.log_belief[:self.grid.n_cells])
        views = np.flatnonzero(self._search.viewed)
        return np.flatnonzero(~self._reach.covered(self.grid, views) & open_cells)

    def _group_stops(self, groups: np.ndarray | None) -> bool:
        """Whether a frame's grouped detections end the search (docs/design.md section 6.15)."""
        return bool(self.settings.group_stop and self.settings.stop_on_decision
                    and not self.motion.active and groups is not None and np.any(groups > 0))

    def _limit(self, reason: str) -> str:
        """
        End the search at a limit; return its decision.

        ``gave_up``, or with ``decide_at_budget`` (still target) the likelier of ``absent``
        and ``found``: ``absent`` if ``P(absent)`` is at least the answer's probability.
        """
        search = self._search
        decision = 'gave_up'
        if self.settings.decide_at_budget and not self.motion.active:
            decision = 'absent' if self.absent_probability >= self.map_probability else 'found'
        search.decision, search.reason, search.ended = decision, reason, True
        return decision

    def _follow(self, obs: np.ndarray, offsets, dt_s: float) -> None:
        """
        Move ``motion.track_view: position``'s filter on by a frame (docs/design.md 12.9).

        It runs while the target is found: predicted over ``dt_s``, started or updated with the
        detections' mean position around the belief's peak, and dropped when the target is not
        found or it strays more than :data:`GATE_CELLS` from the peak (the cell belief decides
        which cell; the filter only where in it).
        """
        position = self._position
        if position is None:
            return
        if self._search.decision != 'found' or not self.motion.active:
            position.reset()
            return
        peak = int(np.argmax(self._cells()))
        peak_rc = np.asarray(self.grid.cell(peak), dtype=np.float64)
        z = None if offsets is None else measured_position(obs, offsets, self.grid, peak)
        if z is not None and np.max(np.abs(z - peak_rc)) > GATE_CELLS:
            z = None
        position.predict(dt_s)
        if position.started and np.max(np.abs(position.x - peak_rc)) > GATE_CELLS:
            position.reset()
        if z is not None:
            if position.started:
                position.update(z)
            else:
                position.start(z)

    def _predicted_peak(self) -> int:
        """Return the most likely cell of the belief predicted ``motion.lead_s`` ahead."""
        ahead = self.motion.predict_over(self._search.log_belief.copy(),
                                         self.settings.motion_lead_s, update=False)
        return int(np.argmax(ahead[:self.grid.n_cells]))

    def stop(self, reason: str) -> StepResult:
        """
        End the search now at a limit outside the session (a driver's pixel budget, a deadline).

        Decides as the fixation budget does (:attr:`SearchSettings.decide_at_budget`);
        ``reason`` names the limit (:attr:`gave_up_reason`).

        Raises
        ------
        OrderError
            Before :meth:`start`, or after the search has ended.

        """
        search = self._state()
        if search.fixation is None or search.ended:
            raise OrderError('stop a search that has started and not ended')
        fired = self._limit(str(reason))
        self._event('stop', reason=search.reason, decision=fired, belief=self._belief_summary())
        return self._result('applied', fired=fired)

    def _choose(self) -> int | None:
        """Return the policy's next fixation; None when ``stop_on_repeat`` forbids every choice."""
        search, settings = self._search, self.settings
        if self.policy is None:
            return search.fixation
        if self.motion.active and settings.motion_track_view != 'policy' \
                and search.decision == 'found':
            if self._position is not None and self._position.started:
                rc = np.round(self._position.ahead(settings.motion_lead_s))
                rc = np.clip(rc, 0, [self.grid.rows - 1, self.grid.cols - 1]).astype(np.int64)
                return int(self.grid.index(int(rc[0]), int(rc[1])))
            return self._predicted_peak()
        belief = self._cells()[None, :]
        policy = self.policy
        if settings.head_speed_deg_s > 0 and not self.motion.active \
                and callable(getattr(policy, 'scores_per_second', None)):
            policy = _PerSecond(self)
        if self.absent_probability >= settings.confidence \
                and (uncovered := self._uncovered()).size:
            # absent is held back (search.absent_needs_coverage): a view that covers a cell
            # left (none taken yet: a view that saw one well would have covered it)
            barred = ~self._reach.sees_well(self.grid, uncovered)
            if not barred.all():
                return unvisited_choice(policy, belief, barred, search.fixations, self.rng,
                                        self.grid)
        if settings.inhibit_return and not self.motion.active:
            if search.visited.all():
                if settings.stop_on_repeat:
                    return None
                search.visited[:] = False
            return unvisited_choice(policy, belief, search.visited, search.fixations,
                                    self.rng, self.grid)
        choice = policy_choice(policy.select(belief, search.fixations, self.rng),
                               self.grid.n_cells)
        if settings.stop_on_repeat and search.visited[choice]:
            return None
        return choice

    def _rc(self, cell: int) -> list:
        return [int(v) for v in self.grid.cell(int(cell))]

    def _belief_summary(self) -> dict:
        cell = self.map_cell
        return {'map_cell': self._rc(cell), 'map_probability': self.map_probability,
                'absent_probability': self.absent_probability,
                'entropy_nats': self.entropy_nats}

    def _event(self, kind: str, **data) -> None:
        self._log.append({'event': kind, **data})

    def _result(self, status: str, reason: str = '', fired: str = '') -> StepResult:
        search = self._search
        cell = self.map_cell
        return StepResult(status, search.fixations, cell, self.map_probability,
                          self.absent_probability, reason or search.reason, search.decision,
                          fired, None if search.ended else search.fixation, search.ended)
