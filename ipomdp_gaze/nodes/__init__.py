# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 nodes: thin wrappers around the model core, and the processes that run them."""

# Executable (module under ipomdp_gaze.nodes, ``ros2 run`` name, CLI subcommand) -> node name.
NODE_NAMES = {'controller': 'gaze_controller', 'camera': 'simulated_camera',
              'detector': 'foveal_detector', 'scene_camera': 'scene_camera',
              'recorder': 'recorder'}
