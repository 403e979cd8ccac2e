# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Files: observation and YAML files, rosbag2 recordings, shared files, the belief image.

What the package reads and writes, and where its shared config files are found.
docs/design.md section 8 lists the modules of each group and the layer contract.
"""
