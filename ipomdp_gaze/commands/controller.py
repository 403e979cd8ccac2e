# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze controller``: run the ``gaze_controller`` node (what ``ros2 run`` starts)."""
from __future__ import annotations

import argparse


def add_parser(sub):
    p = sub.add_parser(
        'controller', help='run the gaze_controller ROS 2 node',
        description='Run the gaze_controller node, exactly as `ros2 run ipomdp_gaze controller` '
                    'does; everything after --ros-args goes to ROS (-p name:=value, '
                    '--params-file FILE, -r from:=to, --log-level ...).')
    p.add_argument('--ros-args', dest='ros_args', nargs=argparse.REMAINDER, default=None,
                   metavar='ARG', help='ROS arguments')
    p.set_defaults(run=run)


def run(args) -> int:
    from ipomdp_gaze.nodes.controller import main
    ros = [] if args.ros_args is None else ['--ros-args', *args.ros_args]
    return main(['ipomdp-gaze-controller', *ros])
