# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Publishers without rclpy's default QoS event handlers, for every node of the package.

rclpy gives each publisher two event handlers (incompatible QoS, incompatible type) that only log
a warning, and its single-threaded executor rebuilds its wait set with every one of them on each
wake. On the controller that doubled the cost of a wake, which sits on the camera -> controller ->
camera loop (docs/design.md section 5.1). An incompatible pair is still reported by the
subscriber's side: our subscriptions keep their default handlers, as do rclpy's and rclcpp's.
"""
from __future__ import annotations

from rclpy.event_handler import PublisherEventCallbacks


class QuietPublishers:
    """
    Mixin before ``rclpy.node.Node``: publishers get no default event handlers.

    It covers the node's own ``/parameter_events`` publisher too, which ``Node.__init__``
    creates through this method. Event callbacks passed explicitly are kept.
    """

    def create_publisher(self, msg_type, topic, qos_profile, *, event_callbacks=None, **kwargs):
        """Create a publisher as ``Node.create_publisher`` does, without default handlers."""
        if event_callbacks is None:
            event_callbacks = PublisherEventCallbacks(use_default_callbacks=False)
        return super().create_publisher(msg_type, topic, qos_profile,
                                        event_callbacks=event_callbacks, **kwargs)
