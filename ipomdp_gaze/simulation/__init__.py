# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Simulation and evaluation: the batched simulator, accuracy, gym, executors.

Percent correct and its intervals, the Gymnasium environment, and the executors and
progress of long jobs.
docs/design.md section 8 lists the modules of each group and the layer contract.
"""
