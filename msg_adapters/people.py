# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The people of a room (many-target mode): ``geometry_msgs/PoseArray`` and ``Float32MultiArray``.

``targets`` (``PoseArray``): one pose per person, the head direction that looks at them. The
position is 0; the orientation is the rotation of the pan joint about z by ``pan_rad`` followed
by the tilt joint about the turned y axis by ``tilt_rad`` (REP 103: pan left and tilt down are
positive), ``q = (x, y, z, w) = (-sin(t/2) sin(p/2), sin(t/2) cos(p/2), cos(t/2) sin(p/2),
cos(t/2) cos(p/2))`` with ``p`` pan and ``t`` tilt: exactly the joint angles
:class:`ipomdp_gaze.model.head.PanTiltMap` sends for the person's cell.

``target_cells`` (``Float32MultiArray``): one row of 4 per person, most probable first,
``[row, col, cell, probability]``, with the layout
``dim[0] = {label: 'people', size: K, stride: 4 K}``,
``dim[1] = {label: 'row_col_cell_probability', size: 4, stride: 4}``, ``data_offset = 0``;
no one found is K = 0 and no data.
"""
from __future__ import annotations

import array
import math

from geometry_msgs.msg import Pose, PoseArray, Quaternion
from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.search.room import people_text
import numpy as np
from std_msgs.msg import Float32MultiArray, Header, MultiArrayDimension, MultiArrayLayout

FIELDS = ('row', 'col', 'cell', 'probability')
FIELDS_LABEL = '_'.join(FIELDS)


class PeopleLayoutError(EvidenceError):
    """A ``target_cells`` message that does not have the documented layout."""


def direction(pan_rad: float, tilt_rad: float) -> Quaternion:
    """Return the quaternion of the head direction ``(pan, tilt)`` (module docstring)."""
    cp, sp = math.cos(pan_rad / 2), math.sin(pan_rad / 2)
    ct, st = math.cos(tilt_rad / 2), math.sin(tilt_rad / 2)
    return Quaternion(x=-st * sp, y=st * cp, z=ct * sp, w=ct * cp)


def angles(q: Quaternion) -> tuple[float, float]:
    """Return ``(pan_rad, tilt_rad)`` of a head direction quaternion (the inverse of direction)."""
    pan = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
    tilt = math.asin(max(-1.0, min(1.0, 2 * (q.w * q.y - q.z * q.x))))
    return pan, tilt


def people_poses(head: PanTiltMap, cells, stamp, frame_id: str) -> PoseArray:
    """Build ``targets``: the head direction of each person's cell, in ``frame_id``."""
    poses = [Pose(orientation=direction(*head.angles(int(cell)))) for cell in cells]
    return PoseArray(header=Header(stamp=stamp, frame_id=frame_id), poses=poses)


def poses_angles(msg: PoseArray) -> list[tuple[float, float]]:
    """Return ``(pan_rad, tilt_rad)`` of every pose of a ``targets`` message."""
    return [angles(p.orientation) for p in msg.poses]


def people_array(grid: Grid, people) -> Float32MultiArray:
    """Build ``target_cells`` from ``(cell, probability)`` pairs (module docstring)."""
    rows = [(*grid.cell(int(cell)), int(cell), float(p)) for cell, p in people]
    data = np.asarray(rows, dtype=np.float32).reshape(-1)
    msg = Float32MultiArray(layout=MultiArrayLayout(
        dim=[MultiArrayDimension(label='people', size=len(rows), stride=len(rows) * len(FIELDS)),
             MultiArrayDimension(label=FIELDS_LABEL, size=len(FIELDS), stride=len(FIELDS))],
        data_offset=0))
    msg.data = array.array('f', data.tobytes())
    return msg


def read_people_array(msg, grid: Grid) -> list[tuple[int, float]]:
    """
    Return the ``(cell, probability)`` pairs of a ``target_cells`` message.

    Raises
    ------
    PeopleLayoutError
        If the layout is not the documented one, the data does not fill it, or a row's
        ``row, col, cell`` do not name one cell of ``grid`` or its probability is not in [0, 1].

    """
    dims = list(msg.layout.dim)
    n = len(FIELDS)
    if len(dims) != 2 or dims[1].label != FIELDS_LABEL or dims[1].size != n or \
            msg.layout.data_offset != 0:
        raise PeopleLayoutError(f'target_cells must have 2 dimensions, people x {n} '
                                f'({FIELDS_LABEL}) and data_offset 0')
    k = dims[0].size
    data = np.asarray(msg.data, dtype=np.float64)
    if data.size != k * n:
        raise PeopleLayoutError(f'target_cells says {people_text(k)} ({k * n} values), has '
                                f'{data.size} values')
    out = []
    for row, col, cell, p in data.reshape(k, n):
        if not (0 <= row < grid.rows and 0 <= col < grid.cols and row == int(row)
                and col == int(col) and grid.index(int(row), int(col)) == cell):
            raise PeopleLayoutError(f'target_cells row ({row}, {col}, cell {cell}) is not a '
                                    f'cell of the {grid.rows}x{grid.cols} grid')
        if not 0 <= p <= 1:
            raise PeopleLayoutError(f'target_cells probability {p} is not in [0, 1]')
        out.append((int(cell), float(p)))
    return out
