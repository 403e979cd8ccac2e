# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Images: the belief heatmap (``rgb8``), per-cell evidence as ``32FC1``, and camera images.

Float images look black in rqt_image_view unless its dynamic range is switched on, so the belief
is published as the colour-mapped ``rgb8`` picture of
:func:`ipomdp_gaze.files.render.belief_heatmap`
(docs/design.md section 5).

Camera images (``mono8``, ``rgb8``, ``bgr8``) are read without copying the pixels where numpy
allows it (:func:`image_array`: a view of the message's buffer, row padding and BGR order
included), and ``camera_info`` is read as a :class:`ipomdp_gaze.vision.pan_tilt.PinholeCamera`;
there is no cv_bridge wheel for pip installs, and none is needed.
"""
from __future__ import annotations

import sys

from ipomdp_gaze.files.evidence_bytes import data_bytes, decode_evidence, EVIDENCE_ENCODINGS
from ipomdp_gaze.files.render import belief_heatmap
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import PinholeCamera
import numpy as np
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Header

from .grid_arrays import LayoutError

_LITTLE = sys.byteorder == 'little'
# Camera image encodings read by image_array, and their channels.
IMAGE_ENCODINGS = {'mono8': 1, 'rgb8': 3, 'bgr8': 3}
# Default limit of image_array: larger images are refused (a 4096x4096 rgb8 image is 50 MB).
MAX_IMAGE_SIDE_PX = 4096


class ImageError(ValueError):
    """A camera image message that cannot be used; the message says why."""


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
    buf = data_bytes(msg.data)
    if msg.step < 3 * msg.width or buf.size != msg.step * msg.height:
        raise ValueError(f'image data has {buf.size} bytes, expected step {msg.step} x height '
                         f'{msg.height} with step >= {3 * msg.width}')
    return buf.reshape(msg.height, msg.step)[:, :3 * msg.width].reshape(msg.height, msg.width, 3)


def evidence_image(values, grid: Grid, stamp, frame_id: str = '', offsets=None,
                   groups=None) -> Image:
    """
    Per-cell evidence as a stamped image (height = rows, width = cols).

    ``32FC1``; with ``offsets`` ``(N, 2)``, ``32FC3``: per cell the evidence, then the mean
    offset ``(row, col)`` in cells of the detections centred in it (NaN where none); with
    ``groups`` ``(N,)`` too, ``32FC4``: then the number of grouped detections centred in it
    (``groups`` needs ``offsets``).
    """
    a = np.asarray(values, dtype=np.float32).reshape(-1)
    if a.size != grid.n_cells:
        raise ValueError(f'expected {grid.n_cells} values, got {a.size}')
    if groups is not None and offsets is None:
        raise ValueError('groups go in a 32FC4 image after the offsets: give both')
    channels = 1
    if offsets is not None:
        o = np.asarray(offsets, dtype=np.float32)
        if o.shape != (grid.n_cells, 2):
            raise ValueError(f'expected offsets of shape ({grid.n_cells}, 2), got {o.shape}')
        a = np.concatenate([a[:, None], o], axis=1)
        channels = 3
    if groups is not None:
        g = np.asarray(groups, dtype=np.float32)
        if g.shape != (grid.n_cells,):
            raise ValueError(f'expected groups of shape ({grid.n_cells},), got {g.shape}')
        a = np.concatenate([a, g[:, None]], axis=1)
        channels = 4
    msg = Image(header=Header(stamp=stamp, frame_id=frame_id), height=grid.rows,
                width=grid.cols, encoding=f'32FC{channels}', is_bigendian=int(not _LITTLE),
                step=4 * channels * grid.cols)
    msg.data = np.ascontiguousarray(a).tobytes()
    return msg


def frame_tag(kind: str, search_id: int | None) -> str:
    """``header.frame_id`` of a detector's frame: ``'scan/<id>'``, ``'fixation/<id>'`` or ''."""
    return '' if search_id is None else f'{kind}/{int(search_id)}'


def read_frame_tag(msg: Image) -> tuple[str, int | None]:
    """
    Return ``(kind, search_id)`` of an evidence image, from ``header.frame_id`` (``frame_tag``).

    Any other frame id (a detector that does not tag its frames) gives ``('fixation', None)``,
    so does a number that is not ASCII digits (``str.isdigit`` also takes ``'²'``, which ``int``
    refuses).
    """
    kind, _, number = msg.header.frame_id.partition('/')
    if kind in ('scan', 'fixation') and number.isascii() and number.isdigit():
        return kind, int(number)
    return 'fixation', None


def evidence_from_image(msg: Image, grid: Grid) -> np.ndarray:
    """
    Read an evidence image's values as float64, shape (N,), row-major (offsets dropped).

    Raises as :func:`evidence_and_offsets`.
    """
    return evidence_and_offsets(msg, grid)[0]


def evidence_and_offsets(msg: Image, grid: Grid) -> tuple[np.ndarray, np.ndarray | None]:
    """
    Read an evidence image's values (N,) and offsets (N, 2) or None (groups dropped).

    Raises as :func:`evidence_channels`.
    """
    return evidence_channels(msg, grid)[:2]


def evidence_channels(msg: Image, grid: Grid) -> tuple:
    """
    Read a ``32FC1``, ``32FC3`` or ``32FC4`` evidence image (:func:`evidence_image`).

    Returns ``(values (N,), offsets (N, 2) or None, groups (N,) or None)``.

    Raises
    ------
    LayoutError
        If the encoding is not one of those or the size is not ``rows x cols``.
    EvidenceError
        If the data does not match the declared step and height.

    """
    if str(msg.encoding).upper() not in EVIDENCE_ENCODINGS:
        raise LayoutError(f"evidence image encoding is {msg.encoding!r}, expected '32FC1', "
                          f"'32FC3' or '32FC4'")
    if (msg.height, msg.width) != grid.shape:
        raise LayoutError(f'evidence image is {msg.height}x{msg.width} (height x width), '
                          f'the grid is {grid.rows}x{grid.cols}')
    return decode_evidence(msg.encoding, msg.height, msg.width, msg.step, msg.is_bigendian,
                           msg.data)


def image_array(msg: Image, max_side_px: int = MAX_IMAGE_SIDE_PX) -> np.ndarray:
    """
    Read a ``mono8``, ``rgb8`` or ``bgr8`` image as ``(H, W)`` grey or ``(H, W, 3)`` RGB uint8.

    The pixels are not copied: the result is a read-only view of the message's buffer (row
    padding is sliced off, ``bgr8`` is viewed with its channels reversed), valid while the
    message is.

    Raises
    ------
    ImageError
        For another encoding, an empty image, a side above ``max_side_px``, or a ``step`` or
        data length that disagrees with the width and height.

    """
    channels = IMAGE_ENCODINGS.get(msg.encoding)
    if channels is None:
        raise ImageError(f'unsupported image encoding {msg.encoding!r} (expected one of '
                         f"{', '.join(IMAGE_ENCODINGS)})")
    width, height, step = int(msg.width), int(msg.height), int(msg.step)
    buf = data_bytes(msg.data)
    if width == 0 or height == 0 or buf.size == 0:
        raise ImageError(f'empty image ({width}x{height} px, {buf.size} bytes)')
    if width > max_side_px or height > max_side_px:
        raise ImageError(f'image of {width}x{height} px is larger than {max_side_px} px on a '
                         f'side')
    if step < channels * width:
        raise ImageError(f'step {step} is less than width {width} x {channels} bytes '
                         f'({msg.encoding})')
    if buf.size != step * height:
        raise ImageError(f'image data has {buf.size} bytes, expected step {step} x height '
                         f'{height} = {step * height}')
    rows = buf.reshape(height, step)[:, :channels * width]
    if channels == 1:
        view = rows
    else:
        view = rows.reshape(height, width, 3)
        if msg.encoding == 'bgr8':
            view = view[:, :, ::-1]
    view.flags.writeable = False
    return view


def camera_image(pixels, stamp, frame_id: str = '') -> Image:
    """Build a stamped ``rgb8`` (``(H, W, 3)``) or ``mono8`` (``(H, W)``) image of uint8 pixels."""
    a = np.ascontiguousarray(pixels, dtype=np.uint8)
    if a.ndim == 3 and a.shape[2] == 3:
        encoding, channels = 'rgb8', 3
    elif a.ndim == 2:
        encoding, channels = 'mono8', 1
    else:
        raise ValueError(f'expected (H, W) grey or (H, W, 3) RGB pixels, got shape {a.shape}')
    msg = Image(header=Header(stamp=stamp, frame_id=frame_id), height=a.shape[0],
                width=a.shape[1], encoding=encoding, is_bigendian=0, step=channels * a.shape[1])
    msg.data = a.tobytes()
    return msg


def camera_info(camera: PinholeCamera, stamp, frame_id: str = '') -> CameraInfo:
    """Build the ``camera_info`` of a distortion-free pinhole camera (K, P, identity R)."""
    k = camera.k
    return CameraInfo(header=Header(stamp=stamp, frame_id=frame_id), width=camera.width,
                      height=camera.height, distortion_model='plumb_bob', d=[0.0] * 5, k=k,
                      r=[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                      p=[k[0], 0.0, k[2], 0.0, 0.0, k[4], k[5], 0.0, 0.0, 0.0, 1.0, 0.0])


def camera_from_info(msg: CameraInfo) -> PinholeCamera:
    """
    Read a ``camera_info``: the camera of the images it goes with (distortion is not used).

    ``width``, ``height`` and K describe the full sensor; a driver that bins or crops says so
    with ``binning_x/y`` and ``roi`` (REP 104: the region in full-resolution pixels, then
    binned), and the images are that region, binned: K is shifted by the region's offset and
    divided by the binning, and the size is the region's (the whole sensor without one).

    Raises
    ------
    ImageError
        For a zero size, a region outside the sensor or a K that is not a pinhole camera's.

    """
    if msg.width == 0 or msg.height == 0:
        raise ImageError(f'camera_info has no image size ({msg.width}x{msg.height})')
    bx, by = max(1, int(msg.binning_x)), max(1, int(msg.binning_y))
    roi = msg.roi
    x0, y0 = int(roi.x_offset), int(roi.y_offset)
    width = int(roi.width) or int(msg.width) - x0
    height = int(roi.height) or int(msg.height) - y0
    if width <= 0 or height <= 0 or x0 + width > msg.width or y0 + height > msg.height:
        raise ImageError(f'camera_info: its roi ({x0}, {y0}, {roi.width}x{roi.height}) is not '
                         f'inside the {msg.width}x{msg.height} sensor')
    k = [float(v) for v in msg.k]
    if (bx, by, x0, y0, width, height) != (1, 1, 0, 0, msg.width, msg.height):
        k[0], k[2] = k[0] / bx, (k[2] - x0) / bx
        k[4], k[5] = k[4] / by, (k[5] - y0) / by
    try:
        return PinholeCamera.from_k(width // bx, height // by, k)
    except ValueError as exc:
        raise ImageError(f'camera_info: {exc}') from None
