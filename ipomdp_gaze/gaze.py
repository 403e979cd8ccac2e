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

The settings are checked here, once: :func:`check_confidence`, :func:`check_settle_time` and
:func:`start_cell` serve both the setters of :class:`GazeController` and the node, which checks
a proposed parameter set before it takes it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .belief import bayes_update, entropy, EvidenceError, map_cell, uniform_log_belief
from .grid import Grid
from .observation import as_observation, check_evidence, CountObservation


def check_confidence(confidence: float) -> float:
    """
    Return the confidence level of the found event as a float.

    Raises
    ------
    ValueError
        Unless ``0 < confidence < 1``.

    """
    if not 0 < confidence < 1:
        raise ValueError(f'confidence must be between 0 and 1 (exclusive), got {confidence!r}')
    return float(confidence)


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
    """The found event: the most likely cell first reached the confidence level."""

    cell: int
    probability: float
    fixations: int


@dataclass(frozen=True)
class FrameResult:
    """
    What happened to one frame of evidence.

    ``status`` is ``'applied'``, ``'skipped'`` or ``'rejected'``; ``reason`` says why a frame was
    not applied; ``fixation`` is the new target after an applied frame; ``found`` is set on the
    frame that first made the most likely cell reach the confidence level.
    """

    status: str
    reason: str = ''
    fixation: int | None = None
    found: Found | None = None

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
        The found event fires when the most likely cell's probability first reaches this.
    seed
        Seed of the generator handed to the policy (``random``, ``sample``).

    """

    def __init__(self, grid: Grid, observation, policy, start_cell: int | None = None,
                 settle_time_s: float = 0.0, confidence: float = 0.95, seed: int = 0):
        self.grid = grid
        self.set_observation(observation)
        self.policy = policy
        self.set_start_cell(grid.center_index if start_cell is None else start_cell)
        self.set_settle_time(settle_time_s)
        self.set_confidence(confidence)
        self.reseed(seed)
        self.enabled = True
        self.received = self.applied = self.rejected = self.skipped = 0
        self.last_rejection = ''
        self._log_belief = uniform_log_belief(grid.n_cells)
        self._belief = np.exp(self._log_belief)
        self.fixation = self.start_cell
        self.fixations = 0
        self.target_time_s = 0.0
        self.usable_time_s = 0.0
        self.found: Found | None = None

    # -- configuration -------------------------------------------------------------------
    def set_observation(self, observation) -> None:
        """Use another observation model (or FPOC) for the following updates; keep the belief."""
        self.observation = as_observation(self.grid, observation)

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
        """Probability of the most likely cell at which the found event fires."""
        self.confidence = check_confidence(confidence)

    def reseed(self, seed: int) -> None:
        """Restart the policy's random stream."""
        self.rng = np.random.default_rng(seed)

    # -- state -----------------------------------------------------------------------------
    @property
    def belief(self) -> np.ndarray:
        """Probabilities ``B_i`` (N,), a copy."""
        return self._belief.copy()

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
        """Entropy of the belief in nats."""
        return float(entropy(self._belief))

    def counters(self) -> dict:
        """Frames received, applied, rejected and skipped (received = the other three)."""
        return {'received': self.received, 'applied': self.applied,
                'rejected': self.rejected, 'skipped': self.skipped}

    # -- events ----------------------------------------------------------------------------
    def reset(self, now_s: float) -> int:
        """Uniform belief, fixation back to the start cell; returns it (sent at ``now_s``)."""
        self._log_belief = uniform_log_belief(self.grid.n_cells)
        self._belief = np.exp(self._log_belief)
        self.fixation = self.start_cell
        self.fixations = 0
        self.found = None
        self.target_time_s = self.usable_time_s = float(now_s)
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
        if stamp_s < self.target_time_s + self.settle_time_s:
            self.skipped += 1
            return FrameResult('skipped', 'taken before the fixation settled')
        try:
            term = self.observation.log_likelihood_ratio(obs, self.fixation)
        except EvidenceError as exc:
            self.rejected += 1
            self.last_rejection = str(exc)
            return FrameResult('rejected', str(exc))
        bayes_update(self._log_belief, term, out=self._log_belief)
        np.exp(self._log_belief, out=self._belief)
        self.applied += 1
        self.fixations += 1
        found = None
        # max() first: map_probability (the tie rule's cell) is only needed when it can fire.
        if self.found is None and self._belief.max() >= self.confidence \
                and self.map_probability >= self.confidence:
            found = self.found = Found(self.map_cell, self.map_probability, self.fixations)
        self.fixation = self.choose()
        self.target_time_s = self.usable_time_s = float(stamp_s if now_s is None else now_s)
        return FrameResult('applied', fixation=self.fixation, found=found)

    def choose(self) -> int:
        """Ask the policy for the next fixation given the current belief."""
        choice = self.policy.select(self._belief[None, :], self.fixations, self.rng)
        cell = int(np.asarray(choice).ravel()[0])
        self.grid.cell(cell)
        return cell
