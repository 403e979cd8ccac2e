# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The state and frame QoS profiles several nodes share; the command subscriptions, re-profilable.

A target (``pan_tilt``, ``fixation``) is state: reliable, depth 1, transient local, so a node
that starts later still gets the current one. A subscription that asks for transient local
matches no volatile publisher (a teleop tool, a driver of one's own): such a publisher is
reported as incompatible and its commands never arrive. The command subscriptions therefore
take ROS's start-up QoS overrides, e.g. ``--ros-args -p
qos_overrides./pan_tilt.subscription.durability:=volatile`` (the topic as resolved, namespace
included), which matches every publisher; the controller re-sends its target every
``retry_period_s``, so a volatile subscription still gets it.
"""
from __future__ import annotations

import copy

from rcl_interfaces.msg import SetParametersResult
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSPolicyKind, QoSProfile,
                       ReliabilityPolicy)
from rclpy.qos_overriding_options import InvalidQosOverridesError, QoSOverridingOptions

STATE_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
FRAME_QOS = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)
COMMAND_POLICIES = (QoSPolicyKind.DURABILITY, QoSPolicyKind.RELIABILITY, QoSPolicyKind.DEPTH,
                    QoSPolicyKind.HISTORY)


def _depth_check(name: str):
    """Return the overrides' check: a depth rcl can take (>= 1 to keep the last; >= 0)."""
    def check(profile: QoSProfile) -> SetParametersResult:
        least = 1 if profile.history == HistoryPolicy.KEEP_LAST else 0
        if profile.depth < least:           # rcl: 'invalid allocator' when negative
            return SetParametersResult(successful=False,
                                       reason=f'{name}.depth must be >= {least}, got '
                                              f'{profile.depth}')
        return SetParametersResult(successful=True)
    return check


def command_subscription(node, msg_type, topic: str, callback, qos: QoSProfile = STATE_QOS,
                         raw: bool = False):
    """
    Subscribe a command topic with ``qos`` (:data:`STATE_QOS`), overridable at start-up.

    rclpy writes the overrides into the profile it is given, so each subscription gets a copy
    of its own: the shared profile, which the node's publishers use too, stays as it is. ``raw``
    hands the callback the serialized message (the recorder). An
    override rclpy cannot take (``durability:=bogus``, ``depth:=-1``) raises ``ValueError``
    naming it, which the node's start-up prints as one line (rclpy raised a bare
    ``RuntimeError``, or rcl's 'invalid allocator').
    """
    profile = copy.copy(qos)
    name = f'qos_overrides.{node.resolve_topic_name(topic)}.subscription'
    options = QoSOverridingOptions(policy_kinds=COMMAND_POLICIES, callback=_depth_check(name))
    try:
        return node.create_subscription(msg_type, topic, callback, profile,
                                        qos_overriding_options=options, raw=raw)
    except InvalidQosOverridesError as exc:
        raise ValueError(str(exc).rpartition('are not valid: ')[2]) from None
    except RuntimeError as exc:
        if type(exc) is not RuntimeError:       # rcl's RCLError and the like: not an override
            raise
        raise ValueError(f'{name}: {exc}') from None
