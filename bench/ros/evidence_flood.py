# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Publish evidence frames at a fixed rate (or as fast as possible) for the load tests.

A camera that is faster than the controller: ``--rate-hz`` frames per second of a
``--rows`` x ``--cols`` grid on ``evidence`` (best effort, keep last 1, like the simulated
camera), for ``--seconds`` (with ``--stop-file``: at least that long, then until the file
exists, at most ``--max-seconds``), then optionally a ``--burst`` of frames as fast as possible. It
waits until the controller subscribes and sends one frame alone first (the controller counts
dropped frames from the first sequence number it sees), and finally, with ``--marker``, sends
one frame one value short that the controller must reject: being the newest frame, it is never
dropped, so counting it shows that the newest frame got through. Prints one JSON line: frames
sent (the first frame, the burst and the marker included), seconds, achieved rate.

Usage (in the controller's ROS domain)::

    .venv/bin/python bench/ros/evidence_flood.py --rows 11 --cols 11 --rate-hz 1000 --seconds 60
"""
from __future__ import annotations

import argparse
import array
import json
from pathlib import Path
import sys
import time


def main(argv=None) -> int:
    """Flood ``evidence``; print the counts as JSON."""
    from ipomdp_gaze.commands.common import (nonneg_float, nonneg_int, positive_float,
                                             positive_int)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--rows', type=positive_int, default=11)
    parser.add_argument('--cols', type=positive_int, default=11)
    parser.add_argument('--rate-hz', type=nonneg_float, default=1000.0,
                        help='0: as fast as possible')
    parser.add_argument('--seconds', type=nonneg_float, default=5.0)
    parser.add_argument('--frames', type=nonneg_int, default=0,
                        help='stop after this many (0: none)')
    parser.add_argument('--stop-file', default='', metavar='PATH',
                        help='after --seconds, go on until this file exists (a test that needs '
                             'the controller to have taken some frames, on any machine)')
    parser.add_argument('--max-seconds', type=positive_float, default=60.0,
                        help='with --stop-file: stop after this long in any case')
    parser.add_argument('--burst', type=nonneg_int, default=0,
                        help='then this many frames as fast as possible')
    parser.add_argument('--marker', action='store_true', help='end with one invalid frame')
    parser.add_argument('--seed', type=nonneg_int, default=0)
    args = parser.parse_args(argv)

    from ipomdp_gaze.harness.processes import wait_for
    import numpy as np
    import rclpy
    from rclpy.node import Node
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import Float32MultiArray, MultiArrayDimension, MultiArrayLayout

    rclpy.init(args=[])
    node = Node('evidence_flood')
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                     reliability=ReliabilityPolicy.BEST_EFFORT)
    pub = node.create_publisher(Float32MultiArray, 'evidence', qos)
    rows, cols = args.rows, args.cols
    n = rows * cols
    layout = MultiArrayLayout(dim=[MultiArrayDimension(label='rows', size=rows, stride=n),
                                   MultiArrayDimension(label='cols', size=cols, stride=cols)])
    rng = np.random.default_rng(args.seed)
    frames = []
    for _ in range(8):
        msg = Float32MultiArray(layout=layout)
        values = rng.standard_normal(n).astype(np.float32)
        values[rng.integers(n)] += 4.0
        msg.data = array.array('f', values.tobytes())
        frames.append(msg)
    if not wait_for(lambda: pub.get_subscription_count() >= 1, 60.0, 0.05):
        print(json.dumps({'error': 'no subscriber on evidence'}), flush=True)
        return 1
    time.sleep(0.5)                       # let the subscriber's side of the match settle too
    # One frame alone first: the controller counts drops from the first number it sees.
    pub.publish(frames[0])
    time.sleep(0.5)
    period = 1.0 / args.rate_hz if args.rate_hz > 0 else 0.0
    sent = 1
    late = 0
    t0 = time.monotonic()
    end = t0 + args.seconds
    stop = Path(args.stop_file) if args.stop_file else None
    while True:
        now = time.monotonic()
        if now >= end and (stop is None or now >= t0 + args.max_seconds or stop.exists()):
            break
        if args.frames and sent >= args.frames:
            break
        if period:
            due = t0 + (sent - 1) * period
            if due > now:
                time.sleep(due - now)
            elif now - due > period:
                late += 1
        pub.publish(frames[sent % len(frames)])
        sent += 1
    seconds = time.monotonic() - t0
    t_burst = time.monotonic()
    for _ in range(args.burst):
        pub.publish(frames[sent % len(frames)])
        sent += 1
    burst_seconds = time.monotonic() - t_burst
    if args.marker:
        time.sleep(0.3)
        marker = Float32MultiArray()
        marker.data = array.array('f', bytes(4 * (n - 1)))
        pub.publish(marker)
        sent += 1
    print(json.dumps({'sent': sent, 'seconds': round(seconds, 3),
                      'rate_hz': round((sent - 1 - args.burst - args.marker) / seconds, 1),
                      'burst': args.burst, 'burst_seconds': round(burst_seconds, 4),
                      'late_frames': late, 'marker': bool(args.marker)}), flush=True)
    time.sleep(0.3)                       # best effort: give the last frame time to leave
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
