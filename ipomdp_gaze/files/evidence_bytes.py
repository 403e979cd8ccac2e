# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The bytes of a per-cell evidence image: one decoder for live messages and recorded bags.

An evidence image (docs/design.md sections 5, 11.7 and 12.9) is ``rows x cols`` float32 pixels
with one channel (``32FC1``: the evidence), three (``32FC3``: and the detections' mean offset
from the cell centre) or four (``32FC4``: and the grouped detections). The node reads it through
``msg_adapters.images.evidence_channels`` and ``replay`` reads it from a bag
(:mod:`ipomdp_gaze.drivers.replay`); both decode here, so a recorded frame is read exactly as
the node read it live. No ROS types: only the message's fields.
"""
from __future__ import annotations

from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.wording import counted
import numpy as np

# Evidence image encodings and their channels.
EVIDENCE_ENCODINGS = {'32FC1': 1, '32FC3': 3, '32FC4': 4}


def evidence_encoding_channels(encoding: str) -> int:
    """
    Return the channels of an evidence image ``encoding`` (any case).

    Raises
    ------
    EvidenceError
        If it is not one of :data:`EVIDENCE_ENCODINGS`.

    """
    channels = EVIDENCE_ENCODINGS.get(str(encoding).upper())
    if channels is None:
        expected = ', '.join(repr(e) for e in EVIDENCE_ENCODINGS)
        raise EvidenceError(f'evidence image encoding is {encoding!r}, expected {expected}')
    return channels


def data_bytes(data) -> np.ndarray:
    """View a message's ``data`` field (bytes, ``array('B')``, an array or a list) as uint8."""
    try:
        return np.frombuffer(data, dtype=np.uint8)
    except TypeError:
        return np.asarray(data, dtype=np.uint8)


def decode_evidence(encoding: str, height: int, width: int, step: int, is_bigendian: bool,
                    data) -> tuple:
    """
    Decode an evidence image's fields; return ``(values (N,), offsets, groups)``.

    ``N = height * width`` in row-major order; ``offsets`` ``(N, 2)`` for three or four channels
    and ``groups`` ``(N,)`` for four, else None; float64 copies. Row padding (``step`` beyond
    the row's bytes) is skipped, and either byte order is read.

    Raises
    ------
    EvidenceError
        If the encoding is not an evidence encoding, or the data does not match the declared
        step and height.

    """
    channels = evidence_encoding_channels(encoding)
    row_bytes = 4 * channels * int(width)
    buf = data_bytes(data)
    if step < row_bytes or buf.size != step * height:
        raise EvidenceError(f'evidence image has {counted(buf.size, "byte")}, expected step '
                            f'{step} x height {height} with step >= {row_bytes}')
    rows = buf.reshape(height, step)[:, :row_bytes]
    dtype = np.dtype('>f4' if is_bigendian else '<f4')
    cells = np.ascontiguousarray(rows).view(dtype).reshape(-1, channels).astype(np.float64)
    offsets = cells[:, 1:3].copy() if channels >= 3 else None
    groups = cells[:, 3].copy() if channels == 4 else None
    return cells[:, 0].copy(), offsets, groups
