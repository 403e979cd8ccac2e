# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The simulated head's saccades, shared by ``simulated_camera`` and ``scene_camera``."""
from __future__ import annotations

from ipomdp_gaze.model.head_time import SACCADE_TIME_S
from ipomdp_gaze.msg_adapters import joints
from ipomdp_gaze.vision.detection import MAX_JOINT_RAD

from .params import Param, T


def saccade_params(max_rate_hz: float) -> list[Param]:
    """Return ``saccade_time_s`` and ``rate_hz`` (frames per second up to ``max_rate_hz``)."""
    return [
        Param('saccade_time_s', SACCADE_TIME_S, T.DOUBLE, 'time to move to a new cell',
              float_range=(0.0, 60.0)),
        Param('rate_hz', 0.0, T.DOUBLE,
              'frames per second like a video camera (0: one frame per arrival)',
              float_range=(0.0, float(max_rate_hz))),
    ]


class SaccadeMixin:
    """
    Pose, goal, the saccade and frame timers, and pan/tilt commands of a simulated head.

    The node sets ``pose``, ``goal``, ``moving``, ``guard``, ``_saccade_timer`` and
    ``_frame_timer`` (None until :meth:`_make_saccade_timers`), and implements
    :meth:`_arrived` (the head reached its goal) and ``_publish_frame``.
    """

    _command_stamp: tuple | None = None     # the last pan/tilt command's header stamp

    def _make_saccade_timers(self, values: dict) -> None:
        """Rebuild the saccade timer (None: instantaneous) and the frame timer (``rate_hz``)."""
        for timer in (self._saccade_timer, self._frame_timer):
            if timer is not None:
                self.destroy_timer(timer)
        self._saccade_timer = self._frame_timer = None
        if self.moving:
            self._arrive()
        if values['saccade_time_s'] > 0:
            self._saccade_timer = self.create_timer(values['saccade_time_s'],
                                                    self.guard.wrap(self._on_arrival))
            self._saccade_timer.cancel()
        if values['rate_hz'] > 0:
            self._frame_timer = self.create_timer(1.0 / values['rate_hz'],
                                                  self.guard.wrap(self._publish_frame))

    @staticmethod
    def _command_stamp_of(msg) -> tuple:
        """Return a command's header stamp as ``(sec, nanosec)``: a re-send repeats it."""
        return int(msg.header.stamp.sec), int(msg.header.stamp.nanosec)

    def _commanded_cell(self, msg, head):
        """
        Return the cell nearest a ``pan_tilt`` command, or None (warned, throttled).

        A command more than a cell beyond the grid is warned about (throttled) and clipped to
        the edge, as a head stops at its joint limits; one beyond a turn (:data:`MAX_JOINT_RAD`,
        the detector's bound on joint angles) is malformed: ignored (warned, throttled), the
        head stays where it is.
        """
        try:
            pan_rad, tilt_rad = joints.angles_from_joint_state(msg, head)
            if not (abs(pan_rad) <= MAX_JOINT_RAD and abs(tilt_rad) <= MAX_JOINT_RAD):
                raise ValueError(f'pan/tilt {pan_rad:.4g}, {tilt_rad:.4g} rad: beyond '
                                 f'+/-{MAX_JOINT_RAD:.4f} rad (one turn)')
            row, col = head.position(pan_rad, tilt_rad)
        except ValueError as exc:
            self.get_logger().warning(f'ignored a pan_tilt command: {exc}',
                                      throttle_duration_sec=5.0)
            return None
        rows, cols = head.grid.rows, head.grid.cols
        if not (-1.0 <= row <= rows and -1.0 <= col <= cols):
            self.get_logger().warning(
                f'a pan_tilt command ({pan_rad:.4f}, {tilt_rad:.4f}) rad points at row '
                f'{row:.1f}, col {col:.1f}, beyond the {rows}x{cols} grid: the head stops at '
                'the nearest edge cell', throttle_duration_sec=5.0)
        return head.nearest_cell(pan_rad, tilt_rad)

    def _saccade_to(self, goal: int, stamp=None) -> None:
        """
        Start a saccade to ``goal``, commanded by a message stamped ``stamp`` (``(sec, nsec)``).

        A re-sent command (the same stamp: the controller's ``retry_period_s``) does not restart
        a saccade: under way, it goes on; at the goal already, the head does not move and the
        camera arrives at once (a frame now, with ``rate_hz`` 0), since the controller is still
        waiting for it. A new command to where the head stands settles again for
        ``saccade_time_s`` (the controller skips frames taken before its settle time).
        """
        resent = stamp is not None and stamp == self._command_stamp
        self._command_stamp = stamp
        if goal == self.goal and self.moving:
            return
        if resent and goal == self.pose and not self.moving:
            self._arrive()
            return
        self.goal, self.moving = goal, True
        if self._saccade_timer is None:
            self._arrive()
        else:
            self._saccade_timer.reset()

    def _on_arrival(self) -> None:
        self._saccade_timer.cancel()
        if self.moving:
            self._arrive()

    def _arrive(self) -> None:
        self.pose, self.moving = self.goal, False
        self._arrived()

    def _arrived(self) -> None:
        raise NotImplementedError
