# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The evidence image's bytes: one decoder, for the node's messages and a bag's rows alike."""
from array import array

from ipomdp_gaze.files.evidence_bytes import decode_evidence
from ipomdp_gaze.model.belief import EvidenceError
import numpy as np
import pytest


def _encode(cells: np.ndarray, big: bool, pad: int = 0, rows: int = 2) -> tuple:
    """Rows of float32 cells ``(rows * cols, channels)`` as an image's bytes, ``pad`` per row."""
    channels = cells.shape[1]
    cols = cells.shape[0] // rows
    raw = cells.astype('>f4' if big else '<f4').reshape(rows, cols * channels)
    out = b''.join(r.tobytes() + b'\x07' * pad for r in raw)
    return out, 4 * channels * cols + pad, cols


@pytest.mark.parametrize('channels,encoding', [(1, '32FC1'), (3, '32fc3'), (4, '32FC4')])
@pytest.mark.parametrize('big', [False, True])
@pytest.mark.parametrize('pad', [0, 5])
def test_decode_reads_every_layout(channels, encoding, big, pad):
    rng = np.random.default_rng(7)
    cells = rng.normal(size=(6, channels)).astype(np.float32)
    data, step, cols = _encode(cells, big, pad)
    for field in (data, array('B', data), np.frombuffer(data, np.uint8), list(data)):
        values, offsets, groups = decode_evidence(encoding, 2, cols, step, big, field)
        np.testing.assert_array_equal(values, cells[:, 0].astype(np.float64))
        if channels == 1:
            assert offsets is None and groups is None
        else:
            np.testing.assert_array_equal(offsets, cells[:, 1:3])
        if channels == 4:
            np.testing.assert_array_equal(groups, cells[:, 3])
        elif channels == 3:
            assert groups is None


def test_decode_refuses_what_it_cannot_read():
    cells = np.zeros((6, 3), np.float32)
    data, step, cols = _encode(cells, False)
    with pytest.raises(EvidenceError, match="encoding is 'mono8'"):
        decode_evidence('mono8', 2, cols, step, False, data)
    with pytest.raises(EvidenceError, match='bytes'):
        decode_evidence('32FC3', 2, cols, step, False, data[:-1])
    with pytest.raises(EvidenceError, match='step'):
        decode_evidence('32FC4', 2, cols, step, False, data)   # 3 channels' rows read as 4


def test_the_adapter_reads_the_message_through_the_decoder():
    from ipomdp_gaze.model.grid import Grid
    images = pytest.importorskip('ipomdp_gaze.msg_adapters.images')
    grid = Grid(3, 4, 5.0)
    rng = np.random.default_rng(3)
    values, offsets = rng.normal(size=12), rng.uniform(-0.5, 0.5, size=(12, 2))
    groups = rng.integers(0, 3, size=12).astype(float)
    msg = images.evidence_image(values, grid, None, offsets=offsets, groups=groups)
    node = images.evidence_channels(msg, grid)
    bag = decode_evidence(msg.encoding, msg.height, msg.width, msg.step, msg.is_bigendian,
                          bytes(msg.data))
    for a, b in zip(node, bag):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(node[0], values, rtol=1e-6)
    np.testing.assert_array_equal(node[2], groups)
