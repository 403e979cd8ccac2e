# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Spin a node until SIGINT or SIGTERM, with a bounded wait so that the signal is never missed.

rclpy's signal handler (a thread of its own) first triggers the executors' signal guard
condition and then shuts the contexts down. An executor that wakes between the two sees its
context still running, consumes the guard condition and waits again; with no timer of its own
(an idle simulated camera) that wait has no timeout, so the process ignores the SIGTERM until it
is killed (``exit status -9`` in the tests). A timer that does nothing bounds every wait to
:data:`WAKE_PERIOD_S`, after which the executor sees the shut-down context and returns.
"""
from __future__ import annotations

import sys

import rclpy

WAKE_PERIOD_S = 0.25


def _wake() -> None:
    """Do nothing: the executor only needs to return from its wait."""


def spin(node, wake_period_s: float = WAKE_PERIOD_S) -> None:
    """
    Spin ``node`` until its context shuts down, waking at least every ``wake_period_s``.

    Raises
    ------
    rclpy.executors.ExternalShutdownException
        When a signal shut the context down (as :func:`rclpy.spin` does).

    """
    timer = node.create_timer(wake_period_s, _wake)
    try:
        rclpy.spin(node)
    finally:
        node.destroy_timer(timer)


def run_node(make_node, node_name: str, args=None) -> int:
    """
    Run a node with the Jazzy idiom: init, spin until SIGINT/SIGTERM, destroy, try_shutdown.

    An invalid start-up parameter (``ValueError`` or ``ParameterException`` from the node's
    constructor) prints one line naming it and returns 1; a clean shutdown returns 0. Only the
    constructor's errors are configuration errors: an exception that escapes a callback while
    spinning (a callback not guarded by :class:`ipomdp_gaze.nodes.guard.CallbackGuard`) is a
    bug, and is raised with its traceback.
    """
    from rclpy.exceptions import ParameterException
    from rclpy.executors import ExternalShutdownException
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    rclpy.init(args=args)
    node = None
    status = 0
    try:
        try:
            node = make_node()
        except (ValueError, ParameterException) as exc:
            print(f'{node_name}: error: {exc}', file=sys.stderr)
            status = 1
        else:
            spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except _rclpy.RCLError:
        # SIGTERM/SIGINT shut the context down while the executor was building its wait set.
        if rclpy.ok():
            raise
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status
