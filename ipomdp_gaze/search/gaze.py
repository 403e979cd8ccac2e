# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The gaze controller's brain, without ROS: belief, frame acceptance, policy and found event.

:class:`GazeController` is what the ``gaze_controller`` node wraps. It holds the belief over the
target's cell and the current fixation, and decides what to do with every frame of evidence:

- a frame that cannot be used (wrong length, +/-inf; with a count model also a negative or
  fractional count; the node adds layout errors through :meth:`GazeController.reject`) is
  *rejected* and the belief is unchanged; counts above ``K - 1`` are clipped, not refused;
- while disabled, or before ``settle_time_s`` has passed since the current target was sent
  (a frame taken mid-saccade), a valid frame is *skipped*;
- otherwise it is *applied*: one frame per fixation (the model assumes independent noise per
  observation), NaN cells count as unobserved, and the policy chooses the next fixation at once.

Every frame is counted: ``received = applied + rejected + skipped``. The first fixation after a
reset is the start cell (the centre by default, docs/design.md section 4); the policy picks the
rest. Times are plain seconds on whatever clock the caller uses (the node's ROS clock).

Beyond the paper (docs/design.md section 7): with motion on, the belief is predicted over the
time since the last applied frame before each update (``sigma_cells`` and ``jump_prob`` per
second, :meth:`ipomdp_gaze.model.motion.Motion.over`); with ``absent_prior > 0`` the belief has the
absent hypothesis, and :attr:`GazeController.belief` is the N cell probabilities, summing to
``1 - P(absent)``. After each applied frame the stop rules of :mod:`ipomdp_gaze.model.stopping`
run:
``found``, ``absent`` or, at the fixation budget, ``gave_up``. For a still target a decision ends
the search: later frames are skipped and no new target is chosen until :meth:`reset`. With
motion on, ``found`` and ``absent`` only report: the controller keeps tracking, and each event is
re-armed when its probability falls back below the confidence level. ``gave_up`` ends the search
in both cases (a budget never applies once a search has decided).

The belief, the Bayes step, the stop rules and the choice of the next fixation are the search
session's (:mod:`ipomdp_gaze.search.session`), which every driver runs; this class adds only what a
live
camera needs: times, settling, enable, counters and the events of a frame. Its settings are one
:class:`ipomdp_gaze.search.session.SearchSettings`, checked once and replaced whole
(:meth:`GazeController.configure`).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.session import SearchSession, SearchSettings, session_view
import numpy as np

# Many targets: cells within this many cells of an occupied one are settled (the rooms' link).
ROOM_LINK = 1
# A frame stamped further ahead of the controller's clock is refused: that clock and the
# camera's disagree, and the settle rule (a frame taken after the head arrived) cannot hold. The
# detector node refuses images by the same tolerance (its stamp_tolerance_s default).
STAMP_TOLERANCE_S = 0.5


# A frame's skip reason when it was taken before the current target's settle time.
SETTLING = 'taken before the fixation settled'


def check_settle_time(settle_time_s: float) -> float:
    """
    Return the settle time in seconds as a float.

    Raises
    ------
    ValueError
        Unless it is finite and >= 0.

    """
    if not np.isfinite(settle_time_s) or settle_time_s < 0:
        raise ValueError(f'settle_time_s must be finite and >= 0, got {settle_time_s!r}')
    return float(settle_time_s)


@dataclass(frozen=True)
class Found:
    """
    The found event: the most likely cell reached the confidence level.

    ``forced_by`` names the limit (``budget``) that forced it below the confidence
    (``search.decide_at_budget``), or ``group`` when a grouped detection ended the search
    (``search.group_stop``; not a limit, its probability may be below the confidence), '' when
    the evidence reached it.
    """

    cell: int
    probability: float
    fixations: int
    forced_by: str = ''


@dataclass(frozen=True)
class Absent:
    """The absent event: ``P(absent)`` reached the confidence level (or a limit forced it)."""

    probability: float
    fixations: int
    forced_by: str = ''


@dataclass(frozen=True)
class Lost:
    """
    The lost event (motion on): the tracked target's belief fell below ``motion.keep_probability``.

    ``cell`` is where it was last found; ``probability`` what the belief within ``found_radius``
    of the most likely cell holds now, ``absent_probability`` the absent hypothesis's.
    """

    cell: int
    probability: float
    absent_probability: float
    fixations: int
    seconds_tracked: float


@dataclass(frozen=True)
class Reacquired:
    """The reacquired event (motion on): ``found`` again after ``lost``, ``seconds_lost`` later."""

    cell: int
    probability: float
    fixations: int
    seconds_lost: float


@dataclass(frozen=True)
class PersonEvent:
    """
    A person's event of a moving many-target search: ``found``, ``lost`` or ``reacquired``.

    ``person`` is its number (1, 2, ... in the order found; :mod:`ipomdp_gaze.search.tracks`);
    ``seconds`` how long it was tracked before ``lost``, or lost before ``reacquired``.
    """

    kind: str
    person: int
    cell: int
    probability: float
    fixations: int
    seconds: float = 0.0


@dataclass(frozen=True)
class GaveUp:
    """The gave-up event: the fixation budget ran out before any decision."""

    fixations: int


@dataclass(frozen=True)
class FrameResult:
    """
    What happened to one frame of evidence.

    ``status`` is ``'applied'``, ``'skipped'`` or ``'rejected'``; ``reason`` says why a frame was
    not applied; ``fixation`` is the new target after an applied frame (None when the search has
    ended: no new target); ``found``, ``absent``, ``gave_up``, ``lost`` and ``reacquired`` are
    set on the frame that fired that event (with motion on, a find after a loss is
    ``reacquired``, not a second ``found``). A moving many-target search reports its people's
    events in ``people`` instead, and ``room_done`` on the frame after which every cell is
    decided (again).
    """

    status: str
    reason: str = ''
    fixation: int | None = None
    found: Found | None = None
    absent: Absent | None = None
    gave_up: GaveUp | None = None
    lost: Lost | None = None
    reacquired: Reacquired | None = None
    people: tuple = ()
    room_done: bool = False

    @property
    def applied(self) -> bool:
        """Whether the frame updated the belief."""
        return self.status == 'applied'


# The many-target belief is an occupancy per cell, each starting from absent.prior (section 11.6).
NO_PRIOR_WITH_MANY = ("a prior over one target's cell (belief.prior) does not go with "
                      'search.targets many')


def make_session(grid: Grid, observation, policy, settings: SearchSettings, log_size: int = 0,
                 prior=None):
    """
    Return a new search session of the belief ``settings.targets`` names.

    It keeps the newest ``log_size`` events of :attr:`SearchSession.log`; the controller keeps
    none by default (its frame results and the node's topics say what happened, and building
    an event per frame was a fifth of the 11x11 controller's per-frame time).

    ``one``: :class:`ipomdp_gaze.search.session.SearchSession` (the paper's belief); ``many``:
    :class:`ipomdp_gaze.search.many.OccupancySession` with ``link`` :data:`ROOM_LINK`
    (docs/design.md section 11.6), whose ``policy`` is kept but not used, except a sweep: each
    search is then one pass of its poses (section 11.7). ``prior`` (N,): where the one target is
    a priori (:class:`SearchSession`'s); the many-target belief takes none (ValueError).
    """
    if settings.targets == 'many':
        if prior is not None:
            raise ValueError(NO_PRIOR_WITH_MANY)
        session = OccupancySession(grid, observation, settings, link=ROOM_LINK,
                                   log_size=log_size)
        session.set_policy(policy)
    else:
        session = SearchSession(grid, observation, policy, settings, log_size=log_size,
                                prior=prior)
    return session


class FrameSequence:
    """
    Frames lost on the way to the node, from the publisher's sequence numbers (1, 2, 3, ...).

    A subscription that keeps only the newest frame drops the older ones when frames come
    faster than the node takes them; the gaps in the numbers it sees count them. A number that
    does not increase (a restarted publisher) starts counting again. Only meaningful while a
    single publisher sends the frames.
    """

    def __init__(self):
        self.last: int | None = None
        self.lost = 0

    def see(self, number) -> int:
        """Record the sequence number of a frame taken; return how many were lost before it."""
        if number is None or number <= 0:           # not supported by the middleware
            return 0
        number = int(number)
        gap = number - self.last - 1 if self.last is not None and number > self.last else 0
        self.last = number
        self.lost += gap
        return gap

    def restart(self) -> None:
        """Forget the last number (another publisher joined or left)."""
        self.last = None


class GazeController:
    """
    A live search: the search session plus times, settling, enable and counters.

    Parameters
    ----------
    grid
        The visual array.
    observation
        The controller's model of its camera and detector: an observation model
        (:mod:`ipomdp_gaze.model.observation`) or an FPOC (the Gaussian model).
    policy
        Anything with ``select(belief (1, N), t, rng)``.
    settings
        How searches decide and stop (:class:`ipomdp_gaze.search.session.SearchSettings`); motion
        is
        per second here.
    settle_time_s
        Frames stamped earlier than this after the target was sent are skipped.
    seed
        Seed of the generator handed to the policy (``random``, ``sample``).
    log_size
        Events the session keeps in its log (:attr:`SearchSession.log`); 0, the default, keeps
        none.
    prior
        Where the one target is a priori, (N,) or (rows, cols) summing to 1 (None: uniform;
        the node's ``belief.prior``); not with ``search.targets`` many.

    """

    def __init__(self, grid: Grid, observation, policy, settings: SearchSettings | None = None,
                 settle_time_s: float = 0.0, seed: int = 0,
                 stamp_tolerance_s: float = STAMP_TOLERANCE_S, log_size: int = 0, prior=None):
        self.grid = grid
        self.stamp_tolerance_s = float(stamp_tolerance_s)
        self.log_size = int(log_size)
        self.session = make_session(grid, observation, policy, settings or SearchSettings(),
                                    self.log_size, prior)
        self.settle_time_s = check_settle_time(settle_time_s)
        self.session.reset(seed=seed)
        self.search_id = 0
        self.enabled = True
        self.received = self.applied = self.rejected = self.skipped = 0
        self.last_rejection = ''
        self.reset(0.0)

    # -- configuration -------------------------------------------------------------------
    settings = session_view('settings', 'Return the settings in force.')

    observation = session_view('observation', 'Return the observation model the search assumes.')

    policy = session_view('policy', 'Return the policy that chooses the fixations.')

    motion = session_view(
        'motion',
        "Return the target's motion per second (:class:`ipomdp_gaze.model.motion.Motion`).")

    def configure(self, settings: SearchSettings, settle_time_s: float | None = None,
                  prior=None) -> None:
        """
        Use new settings from the next frame on; the search under way keeps its belief.

        A new ``absent_prior`` or start cell applies from the next :meth:`reset`; a new
        ``targets`` changes the belief, so a new search starts at once (:meth:`reset`), at
        ``prior`` with one target (None: the prior in force, :meth:`set_prior`).
        """
        if settle_time_s is not None:
            self.settle_time_s = check_settle_time(settle_time_s)
        if settings.targets != self.settings.targets:
            rng = self.session.rng
            self.session = make_session(self.grid, self.observation, self.policy, settings,
                                        self.log_size, self.prior if prior is None else prior)
            self.session.reset(seed=rng)
            self.reset(self.target_time_s)
            return
        self.session.configure(settings)

    def set_observation(self, observation, settings: SearchSettings | None = None) -> None:
        """
        Use another observation model (or FPOC) for the following updates; keep the belief.

        ``settings``: those :meth:`configure` gets next, which the model is checked against.
        """
        self.session.set_observation(observation, settings)

    def set_policy(self, policy) -> None:
        """Use another policy from the next choice on."""
        self.session.set_policy(policy)

    @property
    def prior(self):
        """Where the one target is a priori, (N,) (None: uniform, or many targets)."""
        return getattr(self.session, 'prior', None)

    def set_prior(self, prior) -> None:
        """Start the searches at ``prior`` (None: uniform) from the next :meth:`reset` on."""
        if prior is not None and self.settings.targets == 'many':
            raise ValueError(NO_PRIOR_WITH_MANY)
        if self.settings.targets == 'one':
            self.session.set_prior(prior)

    def reseed(self, seed: int) -> None:
        """Restart the policy's random stream."""
        self.session.rng = np.random.default_rng(seed)

    # -- state -----------------------------------------------------------------------------
    belief = session_view(
        'belief', 'Cell probabilities ``B_i`` (N,), a copy; they sum to ``1 - P(absent)``.')

    absent_probability = session_view(
        'absent_probability', '``P(absent)``: 0 without the absent hypothesis.')

    decision = session_view(
        'decision',
        "Return what the search has decided: ``'found'``, ``'absent'``, ``'gave_up'`` or ``''``. "
        'With motion on this is the state of the tracker: ``found`` (``absent``) while that event '
        'has fired and its probability has not fallen back below the confidence level.')

    stopped = session_view(
        'ended',
        'Whether the search has ended (frames are skipped, no target is sent until reset).')

    @property
    def fixation(self) -> int:
        """
        Return the current target cell (settable: the next frame is taken there).

        While the one-time scan is awaited (:attr:`scanning`) the head holds the start cell the
        settings name, or the grid's centre.
        """
        if self.session.fixation is None:
            cell = self.settings.start_cell
            return self.grid.index(*cell) if isinstance(cell, tuple) else self.grid.center_index
        return self.session.fixation

    @fixation.setter
    def fixation(self, cell: int) -> None:
        self.session.fixate(cell)

    @property
    def wants_scan(self) -> bool:
        """Whether searches start with the one-time scan (the model has one, settings.scan)."""
        return bool(getattr(self.observation, 'has_scan', False)) and self.settings.scan

    @property
    def scanning(self) -> bool:
        """Whether the search awaits its one-time scan (no fixation has been chosen yet)."""
        return self.session.fixation is None

    fixations = session_view('fixations', 'Frames applied in this search.')

    map_cell = session_view('map_cell', 'Return the most likely cell (ties to the lowest index).')

    map_probability = session_view('map_probability', 'Probability of the most likely cell.')

    entropy_nats = session_view(
        'entropy_nats',
        'Entropy of the belief in nats (over the N + 1 hypotheses with the absent one).')

    def counters(self) -> dict:
        """Frames received, applied, rejected and skipped (received = the other three)."""
        return {'received': self.received, 'applied': self.applied,
                'rejected': self.rejected, 'skipped': self.skipped}

    # -- events ----------------------------------------------------------------------------
    def reset(self, now_s: float, new_search: bool = True) -> int:
        """
        Start a new search from the prior at the start cell; return it (sent at ``now_s``).

        The prior is :attr:`prior` (uniform without one) over the cells, with ``absent_prior``
        on the absent hypothesis.
        ``new_search`` False restarts the search just begun (:meth:`configure`) under its id.
        """
        self.session.reset()
        self.search_id += bool(new_search)
        if not self.wants_scan:
            self.session.start()
        self.found = self.absent = self.gave_up = self.lost = None
        self.losses = self.reacquisitions = 0
        self.tracked_since_s = self.lost_since_s = 0.0
        self.target_time_s = self.usable_time_s = self.update_time_s = float(now_s)
        return self.fixation

    def retarget(self, now_s: float) -> int:
        """Record that the current target is (re)sent at ``now_s``; frames settle from then on."""
        self.target_time_s = float(now_s)
        return self.fixation

    def shift_clock(self, delta_s: float) -> None:
        """
        Move every time kept by ``delta_s``: the node's clock jumped (sim time set back).

        A ``/clock`` that restarts (a simulator's reset, a bag played in a loop) would otherwise
        leave the target's stamp in the future, and every frame would wait for it to settle.
        """
        delta_s = float(delta_s)
        if not math.isfinite(delta_s):
            raise ValueError(f'a clock jump must be finite, got {delta_s!r}')
        self.target_time_s += delta_s
        self.usable_time_s += delta_s
        self.update_time_s += delta_s
        self.tracked_since_s += delta_s
        self.lost_since_s += delta_s

    def set_enabled(self, enabled: bool, now_s: float) -> bool:
        """
        Enable or disable; returns whether that changed anything.

        Disabled, frames are skipped (no belief update, no new target). Enabling again re-sends
        the current target at ``now_s``.
        """
        enabled = bool(enabled)
        if enabled == self.enabled:
            return False
        self.enabled = enabled
        if enabled:
            self.retarget(now_s)
            self.usable_time_s = float(now_s)
        return True

    def seconds_without_evidence(self, now_s: float) -> float:
        """Seconds since the last applied frame (or since the last reset or enable)."""
        return max(0.0, float(now_s) - self.usable_time_s)

    def reject(self, reason: str) -> FrameResult:
        """Count a frame that could not even be read (for example a bad message layout)."""
        self.received += 1
        return self._refuse(reason)

    def _refuse(self, reason: str) -> FrameResult:
        """Count a received frame as rejected for ``reason``."""
        self.rejected += 1
        self.last_rejection = str(reason)
        return FrameResult('rejected', str(reason))

    def offer_scan(self, evidence, search_id: int, now_s: float) -> FrameResult:
        """
        Use, skip or reject the one-time scan of search ``search_id`` (docs/design.md 6.8, 10.3).

        Applied only while this search awaits it; then the first fixation is chosen (the
        policy's choice on the scanned belief, or the settings' start cell) and returned, to be
        sent at ``now_s``. A scan of another search, or one nobody waits for, is skipped.
        """
        try:
            frame = self.session.checked_frame(evidence, kind='scan')
        except EvidenceError as exc:
            return self.reject(str(exc))
        self.received += 1
        reason = ''
        if not self.enabled:
            reason = 'disabled'
        elif int(search_id) != self.search_id:
            reason = f'a scan of search {search_id}, this is search {self.search_id}'
        elif not self.scanning:
            reason = 'not waiting for a scan: the search has started'
        if reason:
            self.skipped += 1
            return FrameResult('skipped', reason)
        step = self.session.scan(frame)
        if not step.applied:
            self.rejected += 1
            self.last_rejection = step.reason
            return FrameResult('rejected', step.reason)
        self.applied += 1
        cell = self.session.start()
        self.target_time_s = self.usable_time_s = float(now_s)
        return FrameResult('applied', fixation=cell)

    def offer(self, evidence, stamp_s: float, now_s: float | None = None,
              search_id: int | None = None, offsets=None, groups=None) -> FrameResult:
        """
        Use, skip or reject one frame of evidence taken at ``stamp_s``.

        Parameters
        ----------
        evidence : array (N,)
            One standardised detector response per cell; NaN = not observed.
        stamp_s : float
            When the frame was taken (its header stamp, or its arrival time).
        now_s : float, optional
            Current time, when the next target is sent (default ``stamp_s``).
        search_id : int, optional
            The search the frame was taken for (a detector that says so); a frame of another
            search is skipped. None: unknown, judged by its time alone.
        offsets : array (N, 2), optional
            The mean offset of each cell's detections from its centre (``Frame.offsets``).
        groups : array (N,), optional
            The grouped detections centred in each cell (``Frame.groups``).

        """
        if not math.isfinite(stamp_s):
            return self.reject(f'the frame is stamped {stamp_s!r}, not a time')
        try:
            frame = self.session.checked_frame(evidence, offsets=offsets,   # checked once
                                               groups=groups)
        except EvidenceError as exc:
            return self.reject(str(exc))
        self.received += 1
        if not self.enabled:
            self.skipped += 1
            return FrameResult('skipped', 'disabled')
        if search_id is not None and int(search_id) != self.search_id:
            self.skipped += 1
            return FrameResult('skipped', f'a frame of search {search_id}, this is search '
                                          f'{self.search_id}')
        if self.scanning:
            self.skipped += 1
            return FrameResult('skipped', 'waiting for the one-time scan')
        if self.stopped:
            self.skipped += 1
            return FrameResult('skipped', f'the search has ended ({self.decision}); ~/reset '
                                          f'starts a new one')
        if now_s is not None and stamp_s - now_s > self.stamp_tolerance_s:
            return self._refuse(f"stamped {stamp_s - now_s:.3f} s ahead of this node's clock "
                                f'(more than stamp_tolerance_s {self.stamp_tolerance_s:g} s): '
                                'its clock runs ahead')
        if np.isnan(frame.values).all():
            return self._refuse('every cell is NaN: the frame observed nothing, and a fixation '
                                'is not spent on it')
        if stamp_s < self.target_time_s + self.settle_time_s:
            self.skipped += 1
            return FrameResult('skipped', SETTLING)
        dt_s = max(0.0, float(stamp_s) - self.update_time_s)     # a stamp before the last
        if self.follows_people:
            return self._offer_people(frame, dt_s, stamp_s, now_s)
        # While tracking, the cell the target was last found in: the answer before this frame.
        tracked = self.map_cell if self.motion.active and self.session.decision == 'found' \
            else None
        step, rejected = self._update(frame, dt_s, stamp_s)
        if rejected is not None:
            return rejected
        events = self._events(step.fired, float(stamp_s))
        if tracked is not None and step.decision != 'found':
            events['lost'] = self._lose(tracked, float(stamp_s))
        self.target_time_s = self.usable_time_s = float(stamp_s if now_s is None else now_s)
        return FrameResult('applied', fixation=step.fixation, **events)

    def _update(self, frame, dt_s: float, stamp_s: float) -> tuple:
        """Update the session; count the frame; return ``(step, the rejection or None)``."""
        step = self.session.update(frame, dt_s=dt_s)
        if not step.applied:
            self.rejected += 1
            self.last_rejection = step.reason
            return step, FrameResult('rejected', step.reason)
        self.update_time_s = max(self.update_time_s, float(stamp_s))
        self.applied += 1
        return step, None

    @property
    def follows_people(self) -> bool:
        """Whether this is a moving many-target search (people followed one by one)."""
        return isinstance(self.session, OccupancySession) and self.motion.active

    def _offer_people(self, frame, dt_s: float, stamp_s: float, now_s) -> FrameResult:
        """Apply a frame of a moving many-target search; its events are its people's."""
        was_done = self.session.room_done
        step, rejected = self._update(frame, dt_s, stamp_s)
        if rejected is not None:
            return rejected
        people = tuple(PersonEvent(e['event'], e['person'], e['cell'], e['probability'],
                                   self.fixations, e['seconds'])
                       for e in self.session.people_events)
        self.losses += sum(e.kind == 'lost' for e in people)
        self.reacquisitions += sum(e.kind == 'reacquired' for e in people)
        gave_up = GaveUp(self.fixations) if step.fired == 'gave_up' else None
        self.gave_up = gave_up or self.gave_up
        self.target_time_s = self.usable_time_s = float(stamp_s if now_s is None else now_s)
        return FrameResult('applied', fixation=step.fixation, gave_up=gave_up, people=people,
                           room_done=self.session.room_done and not was_done)

    def _events(self, fired: str, stamp_s: float) -> dict:
        """Return the events a frame fired: found (or reacquired), absent, gave_up."""
        forced_by = self.session.gave_up_reason if fired in ('found', 'absent') else ''
        if fired == 'found' and self.motion.active:
            self.tracked_since_s = stamp_s
        if fired == 'found' and self.lost is not None:
            self.reacquisitions += 1
            seconds = max(0.0, stamp_s - self.lost_since_s)
            self.lost = None
            return {'reacquired': Reacquired(self.map_cell, self.map_probability, self.fixations,
                                             seconds)}
        if fired == 'found':
            self.found = Found(self.map_cell, self.map_probability, self.fixations, forced_by)
            return {'found': self.found}
        if fired == 'absent':
            self.absent = Absent(self.absent_probability, self.fixations, forced_by)
            return {'absent': self.absent}
        if fired == 'gave_up':
            self.gave_up = GaveUp(self.fixations)
            return {'gave_up': self.gave_up}
        return {}

    def _lose(self, cell: int, stamp_s: float) -> Lost:
        """Record that the target tracked at ``cell`` was lost at ``stamp_s``; return the event."""
        self.lost = Lost(cell, self.map_probability, self.absent_probability, self.fixations,
                         max(0.0, stamp_s - self.tracked_since_s))
        self.losses += 1
        self.lost_since_s = stamp_s
        return self.lost
