# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Images: the belief heatmap (``rgb8``) and per-cell evidence as ``32FC1``.

Float images look black in rqt_image_view unless its dynamic range is switched on, so the belief
is published as the colour-mapped ``rgb8`` picture of :func:`ipomdp_gaze.render.belief_heatmap`
(docs/design.md section 5).
"""
from __future__ import annotations

import sys

from ipomdp_gaze.belief import EvidenceError
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.render import belief_heatmap
import numpy as np
from sensor_msgs.msg import Image
from std_msgs.msg import Header

from .grid_arrays import LayoutError

_LITTLE = sys.byteorder == 'little'


def _uint8(data) -> np.ndarray:
    """View the bytes of an image's ``data`` field (bytes, array('B') or a list) as uint8."""
    try:
        return np.frombuffer(data, dtype=np.uint8)
    except TypeError:
        return np.asarray(data, dtype=np.uint8)


def belief_image(belief, grid: Grid, fixation: int | None, scale_px: int, stamp,
                 frame_id: str = '') -> Image:
    """Build a stamped ``rgb8`` ``sensor_msgs/Image`` of the belief heatmap."""
    img = belief_heatmap(belief, grid.shape, fixation, scale_px)
    height, width = img.shape[:2]
    msg = Image(header=Header(stamp=stamp, frame_id=frame_id), height=height, width=width,
                encoding='rgb8', is_bigendian=0, step=3 * width)
    # Assigned after construction: Image(data=...) converts the bytes twice (~50x slower).
    msg.data = img.tobytes()
    return msg


def rgb8_array(msg: Image) -> np.ndarray:
    """Read an ``rgb8`` image as ``(height, width, 3)`` uint8 pixels (row padding dropped)."""
    if msg.encoding != 'rgb8':
        raise ValueError(f'expected an rgb8 image, got encoding {msg.encoding!r}')
    buf = _uint8(msg.data)
    if msg.step < 3 * msg.width or buf.size != msg.step * msg.height:
        raise ValueError(f'image data has {buf.size} bytes, expected step {msg.step} x height '
                         f'{msg.height} with step >= {3 * msg.width}')
    return buf.reshape(msg.height, msg.step)[:, :3 * msg.width].reshape(msg.height, msg.width, 3)


def evidence_image(values, grid: Grid, stamp, frame_id: str = '') -> Image:
    """Per-cell evidence as a stamped ``32FC1`` image (height = rows, width = cols)."""
    a = np.ascontiguousarray(values, dtype=np.float32)
    if a.size != grid.n_cells:
        raise ValueError(f'expected {grid.n_cells} values, got {a.size}')
    msg = Image(header=Header(stamp=stamp, frame_id=frame_id), height=grid.rows,
                width=grid.cols, encoding='32FC1', is_bigendian=int(not _LITTLE),
                step=4 * grid.cols)
    msg.data = a.tobytes()
    return msg


def evidence_from_image(msg: Image, grid: Grid) -> np.ndarray:
    """
    Read a ``32FC1`` evidence image as float64 values, shape (N,), row-major.

    Raises
    ------
    LayoutError
        If the encoding is not ``32FC1`` or the size is not ``rows x cols``.
    EvidenceError
        If the data does not match the declared step and height.

    """
    if msg.encoding.upper() != '32FC1':
        raise LayoutError(f"evidence image encoding is {msg.encoding!r}, expected '32FC1'")
    if (msg.height, msg.width) != grid.shape:
        raise LayoutError(f'evidence image is {msg.height}x{msg.width} (height x width), '
                          f'the grid is {grid.rows}x{grid.cols}')
    buf = _uint8(msg.data)
    if msg.step < 4 * msg.width or buf.size != msg.step * msg.height:
        raise EvidenceError(f'evidence image has {buf.size} bytes, expected step {msg.step} x '
                            f'height {msg.height} with step >= {4 * msg.width}')
    rows = buf.reshape(msg.height, msg.step)[:, :4 * msg.width]
    dtype = np.dtype('>f4' if msg.is_bigendian else '<f4')
    return np.ascontiguousarray(rows).view(dtype).reshape(-1).astype(np.float64)
