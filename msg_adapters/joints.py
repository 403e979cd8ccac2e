# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The head command messages: ``JointState``, ``Float64MultiArray`` and ``JointTrajectory``.

The angles of a cell come from :class:`ipomdp_gaze.model.head.PanTiltMap` (REP 103 signs, offsets
and
joint limits, docs/design.md section 5); this module only reads and fills the messages.
"""
from __future__ import annotations

import math

from builtin_interfaces.msg import Duration
from ipomdp_gaze.model.head import PanTiltMap
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from .stamps import from_seconds


def joint_state(head: PanTiltMap, cell: int, stamp) -> JointState:
    """Build a stamped ``JointState`` with the pan and tilt positions of ``cell``."""
    pan, tilt = head.angles(cell)
    return JointState(header=Header(stamp=stamp), name=[head.pan_joint, head.tilt_joint],
                      position=[pan, tilt])


def angles_from_joint_state(msg: JointState, head: PanTiltMap) -> tuple[float, float]:
    """
    ``(pan_rad, tilt_rad)`` from a ``JointState`` that names both joints.

    Raises
    ------
    ValueError
        If a joint is missing, has no position, or the position is not finite.

    """
    names = list(msg.name)
    positions = list(msg.position)
    out = []
    for joint in (head.pan_joint, head.tilt_joint):
        if joint not in names:
            raise ValueError(f'joint state names {names}, not {joint!r}')
        i = names.index(joint)
        if i >= len(positions) or not math.isfinite(positions[i]):
            raise ValueError(f'joint state has no finite position for {joint!r}')
        out.append(float(positions[i]))
    return out[0], out[1]


def forward_command(head: PanTiltMap, cell: int) -> Float64MultiArray:
    """``[pan_rad, tilt_rad]`` for a ros2_control forward_command_controller (joint order)."""
    msg = Float64MultiArray()
    msg.data = list(head.angles(cell))
    return msg


def joint_trajectory(head: PanTiltMap, cell: int, duration_s: float) -> JointTrajectory:
    """
    Build a one-point ``JointTrajectory`` reaching ``cell`` after ``duration_s``.

    The header stamp is left at zero, which a joint_trajectory_controller reads as "start now".
    """
    duration = from_seconds(duration_s)
    point = JointTrajectoryPoint(
        positions=list(head.angles(cell)), velocities=[0.0, 0.0],
        time_from_start=Duration(sec=duration.sec, nanosec=duration.nanosec))
    return JointTrajectory(joint_names=[head.pan_joint, head.tilt_joint], points=[point])
