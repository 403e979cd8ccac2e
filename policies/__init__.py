# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Fixation policies: baselines, learned families, training and shipped kernels."""
