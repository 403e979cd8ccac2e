# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze controller``, ``camera``, ``detector``, ``scene_camera``: run a node (``ros2 run``).

One subcommand per executable of :data:`ipomdp_gaze.nodes.NODE_NAMES`, in that order; each runs
the node's ``main`` exactly as ``ros2 run ipomdp_gaze <executable>`` does.
"""
from __future__ import annotations

import argparse
import importlib

from ipomdp_gaze.nodes import NODE_NAMES


def add_parser(sub):
    """Register one subcommand per node executable."""
    for executable, node in NODE_NAMES.items():
        p = sub.add_parser(
            executable, help=f'run the {node} ROS 2 node',
            description=f'Run the {node} node, exactly as `ros2 run ipomdp_gaze {executable}` '
                        'does; everything after --ros-args goes to ROS (-p name:=value, '
                        '--params-file FILE, -r from:=to, --log-level ...).')
        p.add_argument('--ros-args', dest='ros_args', nargs=argparse.REMAINDER, default=None,
                       metavar='ARG', help='ROS arguments')
        p.set_defaults(run=run, executable=executable)


def run(args) -> int:
    """Run the node until shutdown; its exit status."""
    main = importlib.import_module(f'ipomdp_gaze.nodes.{args.executable}').main
    ros = [] if args.ros_args is None else ['--ros-args', *args.ros_args]
    return main([f'ipomdp-gaze {args.executable}', *ros])     # argv[0]: the command as run
