# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""I-POMDP infomax model of eye movement: the numpy model core (no rclpy)."""
