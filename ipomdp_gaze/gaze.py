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
second, :meth:`ipomdp_gaze.motion.Motion.over`); with ``absent_prior > 0`` the belief has the
absent hypothesis, and :attr:`GazeController.belief` is the N cell probabilities, summing to
``1 - P(absent)``. After each applied frame the stop rules of :mod:`ipomdp_gaze.stopping` run:
``found``, ``absent`` or, at the fixation budget, ``gave_up``. For a still target a decision ends
the search: later frames are skipped and no new target is chosen until :meth:`reset`. With
motion on, ``found`` and ``absent`` only report: the controller keeps tracking, and each event is
re-armed when its probability falls back below the confidence level. ``gave_up`` ends the search
in both cases (a budget never applies once a search has decided).

The settings are checked here, once: :func:`check_confidence`, :func:`check_settle_time`,
:func:`start_cell` and the checks of :mod:`ipomdp_gaze.motion` and :mod:`ipomdp_gaze.stopping`
serve both the setters of :class:`GazeController` and the node, which checks a proposed
parameter set before it takes it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .belief import bayes_update, entropy, EvidenceError, map_cell
from .grid import Grid
from .inhibition import unvisited_choice
from .motion import Motion
from .observation import as_observation, check_evidence, CountObservation
from .still_evidence import cell_information, check_repeat_weight, StillEvidence
from .stopping import (ABSENT, check_absent_prior, check_confidence, check_max_fixations, decide,
                       FOUND, initial_log_belief)


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


def start_cell(grid: Grid, row: int | None = None, col: int | None = None) -> int:
    """
    Return the cell of the first fixation after a reset: ``(row, col)``, the centre where None.

    Raises
    ------
    ValueError
        If the cell is outside the grid.

    """
    centre_row, centre_col = grid.cell(grid.center_index)
    row = centre_row if row is None else int(row)
    col = centre_col if col is None else int(col)
    if not (0 <= row < grid.rows and 0 <= col < grid.cols):
        raise ValueError(f'start cell ({row}, {col}) is outside a {grid.rows}x{grid.cols} grid')
    return grid.index(row, col)


@dataclass(frozen=True)
class Found:
    """The found event: the most likely cell reached the confidence level."""

    cell: int
    probability: float
    fixations: int


@dataclass(frozen=True)
class Absent:
    """The absent event: ``P(absent)`` reached the confidence level."""

    probability: float
    fixations: int


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
    ended: no new target); ``found``, ``absent`` and ``gave_up`` are set on the frame that fired
    that event.
    """

    status: str
    reason: str = ''
    fixation: int | None = None
    found: Found | None = None
    absent: Absent | None = None
    gave_up: GaveUp | None = None

    @property
    def applied(self) -> bool:
        """Whether the frame updated the belief."""
        return self.status == 'applied'


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
    Belief, fixation and frame acceptance of one search (see the module docstring).

    Parameters
    ----------
    grid
        The visual array.
    observation
        The controller's model of its camera and detector: an observation model
        (:mod:`ipomdp_gaze.observation`) or an FPOC (the Gaussian model).
    policy
        Anything with ``select(belief (1, N), t, rng)``.
    start_cell
        First fixation after a reset (default: the centre cell).
    settle_time_s
        Frames stamped earlier than this after the target was sent are skipped.
    confidence
        ``found`` (``absent``) fires when the most likely cell's probability (``P(absent)``)
        reaches this.
    seed
        Seed of the generator handed to the policy (``random``, ``sample``).
    motion_sigma_cells, jump_prob
        The target's random walk, per second (0, 0: a still target).
    absent_prior
        Prior of "no target in the grid" (0: no absent hypothesis).
    max_fixations
        Fixation budget of a search (None or 0: none).
    inhibit_return
        For a still target (motion off): never fixate a cell twice in a search, the policy's
        best unvisited cell instead (:func:`ipomdp_gaze.inhibition.unvisited_choice`); once
        every cell has been fixated, all are open again. For a deterministic detector on a still
        scene, whose second look at a cell repeats the same counts.
    repeat_weight
        For a still target (motion off): the weight, in [0, 1], of a cell's evidence from views
        other than the one that saw it at its most informative offset
        (:mod:`ipomdp_gaze.still_evidence`). 1 (the default) counts every frame fully, as the
        naive-Bayes step does; 0 counts each cell's evidence once, for overlapping views of a
        still scene taken by a deterministic detector.

    """

    def __init__(self, grid: Grid, observation, policy, start_cell: int | None = None,
                 settle_time_s: float = 0.0, confidence: float = 0.95, seed: int = 0,
                 motion_sigma_cells: float = 0.0, jump_prob: float = 0.0,
                 absent_prior: float = 0.0, max_fixations: int | None = None,
                 inhibit_return: bool = False, repeat_weight: float = 1.0):
        self.grid = grid
        self._still = StillEvidence(grid.n_cells)
        self.repeat_weight = 1.0
        self.set_observation(observation)
        self.policy = policy
        self.set_start_cell(grid.center_index if start_cell is None else start_cell)
        self.set_settle_time(settle_time_s)
        self.set_confidence(confidence)
        self.set_motion(motion_sigma_cells, jump_prob)
        self.set_absent_prior(absent_prior)
        self.set_max_fixations(max_fixations)
        self.set_inhibit_return(inhibit_return)
        self.reseed(seed)
        self.enabled = True
        self.received = self.applied = self.rejected = self.skipped = 0
        self.last_rejection = ''
        self.set_repeat_weight(repeat_weight)
        self.reset(0.0)

    # -- configuration -------------------------------------------------------------------
    def set_observation(self, observation) -> None:
        """Use another observation model (or FPOC) for the following updates; keep the belief."""
        self.observation = as_observation(self.grid, observation)
        self._kernel = None                         # ELM's kernel, when repeat_weight < 1

    def set_policy(self, policy) -> None:
        """Use another policy from the next choice on."""
        self.policy = policy

    def set_start_cell(self, cell: int) -> None:
        """Set the first fixation after the next reset."""
        self.grid.cell(cell)
        self.start_cell = int(cell)

    def set_settle_time(self, settle_time_s: float) -> None:
        """Seconds after sending a target before a frame may be used."""
        self.settle_time_s = check_settle_time(settle_time_s)

    def set_confidence(self, confidence: float) -> None:
        """Probability of the most likely cell (or of absence) at which an event fires."""
        self.confidence = check_confidence(confidence)

    def set_motion(self, sigma_cells: float, jump_prob: float) -> None:
        """Set the target's random walk per second, used from the next applied frame on."""
        motion = Motion(self.grid, sigma_cells, jump_prob)
        changed = getattr(self, 'motion', None) is not None and motion.active != self.motion.active
        self.motion = motion
        if changed:
            self._restart_still_evidence()

    def set_absent_prior(self, absent_prior: float) -> None:
        """Prior of "no target in the grid" for the searches from the next :meth:`reset` on."""
        self.absent_prior = check_absent_prior(absent_prior)

    def set_max_fixations(self, max_fixations: int | None) -> None:
        """Fixation budget of a search (None or 0: none); checked after each applied frame."""
        self.max_fixations = check_max_fixations(max_fixations)

    def set_inhibit_return(self, inhibit_return: bool) -> None:
        """Whether the next choices avoid the cells already fixated in this search."""
        self.inhibit_return = bool(inhibit_return)

    def set_repeat_weight(self, repeat_weight: float) -> None:
        """
        Weight of a cell's repeated views (still target), from the next applied frame on.

        A change keeps the belief: the frames before it stay counted as they were.
        """
        weight = check_repeat_weight(repeat_weight)
        if weight != self.repeat_weight:
            self.repeat_weight = weight
            self._restart_still_evidence()

    def _restart_still_evidence(self) -> None:
        """Count the still scene's evidence per cell from here on, on top of the belief now."""
        self._still.reset()
        if hasattr(self, '_log_belief'):
            self._still_base = self._log_belief.copy()

    def reseed(self, seed: int) -> None:
        """Restart the policy's random stream."""
        self.rng = np.random.default_rng(seed)

    # -- state -----------------------------------------------------------------------------
    @property
    def belief(self) -> np.ndarray:
        """Cell probabilities ``B_i`` (N,), a copy; they sum to ``1 - P(absent)``."""
        return self._belief.copy()

    @property
    def absent_probability(self) -> float:
        """``P(absent)``: 0 without the absent hypothesis."""
        if self._log_belief.size == self.grid.n_cells:
            return 0.0
        return float(np.exp(self._log_belief[-1]))

    @property
    def decision(self) -> str:
        """
        Return what the search has decided: ``'found'``, ``'absent'``, ``'gave_up'`` or ``''``.

        With motion on this is the state of the tracker: ``found`` (``absent``) while that
        event has fired and its probability has not fallen back below the confidence level.
        """
        return self._decision

    @property
    def stopped(self) -> bool:
        """Whether the search has ended (frames are skipped, no target is sent until reset)."""
        return self._stopped

    @property
    def map_cell(self) -> int:
        """Return the most likely cell (ties to the lowest index)."""
        return int(map_cell(self._belief))

    @property
    def map_probability(self) -> float:
        """Probability of the most likely cell."""
        return float(self._belief[self.map_cell])

    @property
    def entropy_nats(self) -> float:
        """Entropy of the belief in nats (over the N + 1 hypotheses with the absent one)."""
        if self._log_belief.size == self.grid.n_cells:
            return float(entropy(self._belief))
        return float(entropy(np.exp(self._log_belief)))

    def counters(self) -> dict:
        """Frames received, applied, rejected and skipped (received = the other three)."""
        return {'received': self.received, 'applied': self.applied,
                'rejected': self.rejected, 'skipped': self.skipped}

    # -- events ----------------------------------------------------------------------------
    def reset(self, now_s: float) -> int:
        """
        Start a new search from the prior at the start cell; return it (sent at ``now_s``).

        The prior is uniform over the cells, with ``absent_prior`` on the absent hypothesis.
        """
        self._log_belief = initial_log_belief(self.grid.n_cells, self.absent_prior)
        self._belief = np.exp(self._log_belief[:self.grid.n_cells])
        self._still.reset()
        self._still_base = self._log_belief.copy()
        self.fixation = self.start_cell
        self.fixations = 0
        self._visited = np.zeros(self.grid.n_cells, dtype=bool)
        self.found = self.absent = self.gave_up = None
        self._decision, self._stopped, self._decided_once = '', False, False
        self.target_time_s = self.usable_time_s = self.update_time_s = float(now_s)
        return self.fixation

    def retarget(self, now_s: float) -> int:
        """Record that the current target is (re)sent at ``now_s``; frames settle from then on."""
        self.target_time_s = float(now_s)
        return self.fixation

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
        self.rejected += 1
        self.last_rejection = str(reason)
        return FrameResult('rejected', str(reason))

    def offer(self, evidence, stamp_s: float, now_s: float | None = None) -> FrameResult:
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

        """
        try:
            obs = check_evidence(evidence, self.grid.n_cells)
            if isinstance(self.observation, CountObservation):
                self.observation.counts(obs)    # negative or fractional counts: invalid frame
        except EvidenceError as exc:
            return self.reject(str(exc))
        self.received += 1
        if not self.enabled:
            self.skipped += 1
            return FrameResult('skipped', 'disabled')
        if self._stopped:
            self.skipped += 1
            return FrameResult('skipped', f'the search has ended ({self._decision}); ~/reset '
                                          f'starts a new one')
        if stamp_s < self.target_time_s + self.settle_time_s:
            self.skipped += 1
            return FrameResult('skipped', 'taken before the fixation settled')
        try:
            term = self.observation.log_likelihood_ratio(obs, self.fixation)
        except EvidenceError as exc:
            self.rejected += 1
            self.last_rejection = str(exc)
            return FrameResult('rejected', str(exc))
        n = self.grid.n_cells
        if self.motion.active and stamp_s > self.update_time_s:
            self.motion.over(stamp_s - self.update_time_s).predict_log(self._log_belief)
        self.update_time_s = max(self.update_time_s, float(stamp_s))
        if self.repeat_weight < 1.0 and not self.motion.active:
            self._add_still_frame(obs, term)
        else:
            if self._log_belief.size > n:
                term = np.append(term, 0.0)             # the absent hypothesis: ratio 1
            bayes_update(self._log_belief, term, out=self._log_belief)
        np.exp(self._log_belief[:n], out=self._belief)
        self.applied += 1
        self.fixations += 1
        self._visited[self.fixation] = True
        events = self._events()
        if not self._stopped:
            self.fixation = self.choose()
        self.target_time_s = self.usable_time_s = float(stamp_s if now_s is None else now_s)
        return FrameResult('applied', fixation=None if self._stopped else self.fixation,
                           **events)

    def _add_still_frame(self, obs: np.ndarray, term: np.ndarray) -> None:
        """Recompute the belief from the search's frames, a cell's repeated views weighted."""
        if self._kernel is None:
            self._kernel = np.asarray(self.observation.elm_kernel(), dtype=float)
        information = cell_information(self._kernel, self.grid, self.fixation)
        self._still.add(term, np.where(np.isnan(obs), 0.0, information))
        total = self._still.log_likelihood_ratio(self.repeat_weight)
        n = self.grid.n_cells
        if self._log_belief.size > n:
            total = np.append(total, 0.0)               # the absent hypothesis: ratio 1
        bayes_update(self._still_base, total, out=self._log_belief)

    def _events(self) -> dict:
        """Run the stop rules after an applied frame; return the events that fired."""
        events = {}
        peak = self._belief.max()
        absent = self.absent_probability
        # peak first: map_probability (the tie rule's cell) is only needed when it can fire.
        code = decide(peak, absent, self.confidence) if max(peak, absent) >= self.confidence \
            else 0
        if self.motion.active:
            if code == FOUND and self._decision != 'found':
                events['found'] = self.found = Found(self.map_cell, self.map_probability,
                                                     self.fixations)
            if code == ABSENT and self._decision != 'absent':
                events['absent'] = self.absent = Absent(absent, self.fixations)
            self._decision = {FOUND: 'found', ABSENT: 'absent'}.get(int(code), '')
        elif code == FOUND:
            events['found'] = self.found = Found(self.map_cell, self.map_probability,
                                                 self.fixations)
            self._decision, self._stopped = 'found', True
        elif code == ABSENT:
            events['absent'] = self.absent = Absent(absent, self.fixations)
            self._decision, self._stopped = 'absent', True
        self._decided_once = self._decided_once or bool(events)
        if not self._decided_once and self.max_fixations is not None \
                and self.fixations >= self.max_fixations:
            events['gave_up'] = self.gave_up = GaveUp(self.fixations)
            self._decision, self._stopped = 'gave_up', True
        return events

    def choose(self) -> int:
        """Ask the policy for the next fixation given the current belief."""
        if self.inhibit_return and not self.motion.active:
            if self._visited.all():
                self._visited[:] = False
            return unvisited_choice(self.policy, self._belief[None, :], self._visited,
                                    self.fixations, self.rng, self.grid)
        choice = self.policy.select(self._belief[None, :], self.fixations, self.rng)
        cell = int(np.asarray(choice).ravel()[0])
        self.grid.cell(cell)
        return cell
