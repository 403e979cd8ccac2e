# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Offline drivers that build a policy by name: replay, image-task evaluation, cluster pieces."""
