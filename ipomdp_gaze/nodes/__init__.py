# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 nodes: thin wrappers around the model core."""
