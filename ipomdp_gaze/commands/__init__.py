# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Subcommands of ``ipomdp-gaze``; shared argument helpers live in :mod:`.common`."""
