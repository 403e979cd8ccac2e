# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Conversions between numpy arrays and ROS messages."""
