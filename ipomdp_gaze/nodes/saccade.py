# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The simulated head's saccades, shared by ``simulated_camera`` and ``scene_camera``."""
from __future__ import annotations


class SaccadeMixin:
    """
    Pose, goal and the saccade timer of a simulated pan/tilt head.

    The node sets ``pose``, ``goal``, ``moving`` and ``_saccade_timer`` (None: saccades are
    instantaneous; else a cancelled timer of the saccade time calling :meth:`_on_arrival`) and
    implements :meth:`_arrived`, called when the head reaches its goal.
    """

    def _saccade_to(self, goal: int) -> None:
        """Start a saccade to ``goal`` (a re-sent goal does not restart one under way)."""
        if goal == self.goal and self.moving:
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
