# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The harness that runs the nodes as a user would: processes, a watching node, the demo.

Not nodes themselves: `processes` starts and stops node processes on a private ROS domain,
`watch` follows a search over DDS from this process, `demo` runs the `ipomdp-gaze demo` searches.
Tests and benches use them too.
"""
