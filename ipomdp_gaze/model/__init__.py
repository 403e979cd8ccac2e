# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The model: grid, FPOC, observation models, belief, motion and stopping.

Also the false-alarm mixture, still-scene evidence, inhibition of return, the pan/tilt
geometry and the scalar checks.
docs/design.md section 8 lists the modules of each group and the layer contract.
"""
