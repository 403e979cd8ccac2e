# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Conversions between numpy arrays and ROS 2 messages: the only place that touches message fields.

Submodules
----------
grid_arrays
    Grid-shaped ``Float32MultiArray`` (belief, evidence), the ``Int32MultiArray`` ground truth
    and a walking face's ``walk_truth`` per frame.
joints
    The head commands (``JointState``, ``Float64MultiArray``, ``JointTrajectory``) of the
    angles that :class:`ipomdp_gaze.model.head.PanTiltMap` gives a cell.
images
    The colour-mapped belief heatmap (``rgb8``) and ``32FC1`` evidence images.
diagnostics
    ``/diagnostics`` status and the search events (``found``, ``room_done``, ...).
people
    The people of a room (many-target mode): ``PoseArray`` head directions and their cells.
stamps
    ``builtin_interfaces/Time`` <-> seconds.

The model core and the policies never import this package; the nodes import nothing else to
read or fill a message.
"""
