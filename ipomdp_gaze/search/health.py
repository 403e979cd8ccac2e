# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
What the gaze controller says about itself: its health and the values it reports.

Once per diagnostics period the ``gaze_controller`` node asks :class:`HealthMonitor` for a
:class:`Health` report of its :class:`ipomdp_gaze.search.gaze.GazeController` and publishes it on
``/diagnostics``. The decision itself is :func:`classify`, from what happened since the last
period:

- ``ok``, ``searching``: frames arrive and are used;
- ``ok``, ``disabled``: gaze control is switched off (frames are skipped);
- ``warn``, ``no usable evidence for X s``: no frame was applied for longer than the stall
  timeout, either because no frames arrive or because none of those that arrive is usable (then
  with the last rejection); the node also logs it;
- ``ok``, ``target found``: the found event has fired in this search (with motion on: while
  the tracker is confident);
- ``ok``, ``target absent`` / ``gave up after N fixations``: the search decided that the grid is
  empty, or spent its fixation budget (docs/design.md section 7). A search that has ended is
  never reported as stalled: it waits for ``~/reset`` and expects no frames;
- ``ok``, ``waiting for evidence``: no frame arrived in the period, not yet for the stall
  timeout (a head that takes longer than a period per view is healthy: only the stall warns);
- ``warn``, ``evidence rejected: <reason>``: a frame was rejected in the period (replaces any
  ``ok`` report).

No ROS here: the node fills the message (:mod:`ipomdp_gaze.msg_adapters.diagnostics`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from ipomdp_gaze.model.belief import prior_is_uniform
from ipomdp_gaze.model.wording import counted

MIN_PERIOD_S = 1e-9


@dataclass(frozen=True)
class Health:
    """
    One health report.

    ``level`` is ``'ok'`` or ``'warn'`` (a ``DiagnosticStatus`` level), ``message`` the one-line
    status, ``detail`` says why the controller is stalled (empty otherwise), and ``values`` are
    the key/value pairs of the status, in the order they are published.
    """

    level: str
    message: str
    detail: str = ''
    values: dict = field(default_factory=dict)

    @property
    def stalled(self) -> bool:
        """Whether no frame was applied for longer than the stall timeout."""
        return bool(self.detail)


def classify(enabled: bool, stall_timeout_s: float, seconds_without_evidence: float,
             arrived: int, rejected: int, last_rejection: str, found: bool,
             decision: str = '', stopped: bool = False, fixations: int = 0) -> Health:
    """
    Classify the controller's health from what happened since the last report.

    Parameters
    ----------
    enabled
        Whether gaze control is enabled.
    stall_timeout_s
        Report a stall when no frame was applied for longer than this (0: never).
    seconds_without_evidence
        Seconds since the last applied frame (or the last reset or enable).
    arrived
        Frames received since the last report (applied, rejected or skipped).
    rejected
        Frames rejected since the last report.
    last_rejection
        The reason of the last rejected frame.
    found
        Whether the found event holds: it fired in this search (with motion on: and the
        tracker is still confident).
    decision
        ``'found'``, ``'absent'``, ``'gave_up'`` or ``''`` (:attr:`GazeController.decision`).
    stopped
        Whether the search has ended (it waits for a reset).
    fixations
        Fixations of the search so far (for the gave-up message).

    """
    level, message, detail = 'ok', 'searching', ''
    ended = {'found': 'target found', 'absent': 'target absent',
             'gave_up': f'gave up after {counted(fixations, "fixation")}'}
    if not enabled:
        message = 'disabled'
    elif stopped:
        message = ended.get(decision, 'search ended')
    elif 0 < stall_timeout_s < seconds_without_evidence:
        level, message = 'warn', f'no usable evidence for {seconds_without_evidence:.1f} s'
        if arrived == 0:
            detail = 'no frames arrive'
        else:
            detail = f'{counted(arrived, "frame")} arrived, none usable'
            if rejected:
                detail += f'; last rejection: {last_rejection}'
    elif found:
        message = ended['found']
    elif decision == 'absent':
        message = ended['absent']
    elif arrived == 0:
        message = 'waiting for evidence'
    if rejected and last_rejection and level == 'ok':
        level, message = 'warn', f'evidence rejected: {last_rejection}'
    return Health(level, message, detail)


def policy_label(name: str, kernel=None, file: str = '', action: str = 'argmax') -> str:
    """
    Describe the policy set by ``policy.name``, ``policy.kernel``, ``policy.file``, ``action``.

    A baseline is its name; a learned policy names where its kernel comes from and its action
    rule, e.g. ``learned (camera-11x11-infomax, argmax)``.
    """
    if name != 'learned':
        return name
    if kernel is not None and len(kernel):
        return f'learned (policy.kernel, {action})'
    return f'learned ({file}, {action})'


class HealthMonitor:
    """
    Health reports of a :class:`ipomdp_gaze.search.gaze.GazeController`, one per period.

    It remembers when the last report was made and the frame counters at that time, so each
    report speaks of the period since (frames arrived, rejections, the evidence rate).

    Parameters
    ----------
    now_s
        When monitoring starts (seconds on the controller's clock).
    received, rejected
        The controller's counters at that time.

    """

    def __init__(self, now_s: float, received: int = 0, rejected: int = 0):
        self._last_s = float(now_s)
        self._received = int(received)
        self._rejected = int(rejected)

    def report(self, core, now_s: float, stall_timeout_s: float, policy: str = '',
               dropped: int = 0, resends: int = 0) -> Health:
        """
        Classify ``core`` at ``now_s`` and gather the values of its status.

        Parameters
        ----------
        core : GazeController
            The controller.
        now_s
            The current time.
        stall_timeout_s
            See :func:`classify`.
        policy
            The policy's label (:func:`policy_label`).
        dropped
            Frames lost on the way to the node (``frames_dropped``).
        resends
            How often the current target was re-sent (``pan_tilt_resends``).

        """
        arrived = core.received - self._received
        rate = arrived / max(now_s - self._last_s, MIN_PERIOD_S)
        without_s = core.seconds_without_evidence(now_s)
        health = classify(core.enabled, stall_timeout_s, without_s, arrived,
                          core.rejected - self._rejected, core.last_rejection,
                          core.decision == 'found', core.decision, core.stopped, core.fixations)
        self._last_s, self._received, self._rejected = now_s, core.received, core.rejected
        counters = core.counters()
        grid = core.grid
        map_row, map_col = grid.cell(core.map_cell)
        fix_row, fix_col = grid.cell(core.fixation)
        values = {
            'policy': policy, 'enabled': core.enabled, 'evidence_rate_hz': rate,
            'frames_received': counters['received'], 'frames_applied': counters['applied'],
            'frames_rejected': counters['rejected'], 'frames_skipped': counters['skipped'],
            'frames_dropped': dropped, 'seconds_without_evidence': without_s,
            'fixations': core.fixations, 'fixation_row': fix_row, 'fixation_col': fix_col,
            'entropy_nats': core.entropy_nats, 'most_likely_row': map_row,
            'most_likely_col': map_col, 'most_likely_probability': core.map_probability,
            'found': core.decision == 'found', 'pan_tilt_resends': resends,
            'last_rejection': core.last_rejection,
            'absent_probability': core.absent_probability, 'decision': core.decision,
            'search_ended': core.stopped, 'lost': core.losses,
            'reacquired': core.reacquisitions,
            'prior': 'uniform' if prior_is_uniform(getattr(core, 'prior', None))
            else 'belief.prior'}
        return replace(health, values=values)
