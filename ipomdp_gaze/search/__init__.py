# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The search: settings, the search session, sensors and the controller's logic.

The settings schema (one description of every setting), the session every driver runs,
the sensors that make frames, and the controller (gaze, health) built from parameters.
docs/design.md section 8 lists the modules of each group and the layer contract.
"""
