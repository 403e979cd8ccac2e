# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Spin a node until shutdown, robust to a lost wake-up of the SIGTERM/SIGINT handler.

With the rclpy 7.1.6 wheels, ``rclpy.spin`` occasionally missed a shutdown signal and blocked in
``rcl_wait`` forever (seen 1 in 25 SIGTERMs of the simulated camera under load: py-spy showed the
main thread idle in ``WaitSet::wait`` after the signal). Waking every ``poll_s`` to re-check the
context bounds the shutdown delay instead; it costs one empty wait per ``poll_s`` when idle.
"""
from rclpy.executors import SingleThreadedExecutor

POLL_S = 0.1


def spin(node, poll_s: float = POLL_S) -> None:
    """Spin ``node`` on a SingleThreadedExecutor until its context is shut down."""
    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    try:
        while node.context.ok():
            executor.spin_once(timeout_sec=poll_s)
    finally:
        executor.remove_node(node)
        executor.shutdown(timeout_sec=0)
