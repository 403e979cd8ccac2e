# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Pictures of a belief, with no ROS: the one colour-mapped heatmap and a text grid.

The heatmap is what the Gymnasium environment's ``render`` returns and what the controller
publishes as ``belief_image`` (through :mod:`ipomdp_gaze.msg_adapters.images`): each cell becomes
a ``scale_px x scale_px`` block coloured by ``B_i / max(B)`` on a viridis-like map (dark purple =
0, yellow = the most likely cell; perceptually ordered and readable in greyscale), and the
current fixation gets a red outline, so the scan is visible in rqt_image_view.
"""
from __future__ import annotations

import numpy as np

# Viridis sampled at 0, 1/4, 1/2, 3/4, 1 (matplotlib's values), interpolated linearly: no
# matplotlib import on the robot.
_ANCHORS = np.array([[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98],
                     [253, 231, 37]], dtype=float)
MARK_RGB = (255, 0, 0)


def colour_map(values: np.ndarray) -> np.ndarray:
    """Map values in [0, 1] to ``uint8`` RGB (shape ``values.shape + (3,)``)."""
    v = np.clip(np.nan_to_num(np.asarray(values, dtype=float)), 0.0, 1.0)
    x = np.linspace(0.0, 1.0, len(_ANCHORS))
    rgb = np.stack([np.interp(v, x, _ANCHORS[:, ch]) for ch in range(3)], axis=-1)
    return np.round(rgb).astype(np.uint8)


_LUT = colour_map(np.linspace(0.0, 1.0, 256))


def belief_heatmap(belief, shape: tuple[int, int], fixation: int | None = None,
                   scale_px: int = 16) -> np.ndarray:
    """
    Draw the belief as a ``(rows*scale_px, cols*scale_px, 3)`` uint8 heatmap.

    Parameters
    ----------
    belief : array (N,)
        Probabilities, row-major; normalised to their maximum for the colours.
    shape : (rows, cols)
        The grid.
    fixation : int, optional
        Cell outlined in :data:`MARK_RGB` (a line of ``max(1, scale_px // 8)`` pixels).
    scale_px : int
        Pixels per cell side.

    """
    if scale_px < 1:
        raise ValueError(f'scale_px must be >= 1, got {scale_px}')
    rows, cols = shape
    b = np.asarray(belief, dtype=float).reshape(rows, cols)
    peak = b.max()
    level = np.clip(np.nan_to_num(b / peak if peak > 0 else b), 0.0, 1.0)
    rgb = _LUT[np.round(level * (len(_LUT) - 1)).astype(np.intp)]
    # Columns first, then whole rows: both repeats copy contiguous memory (fast).
    img = np.repeat(np.repeat(rgb, scale_px, axis=1), scale_px, axis=0)
    if fixation is not None:
        row, col = divmod(int(fixation), cols)
        if not 0 <= row < rows:
            raise ValueError(f'fixation {fixation} is outside a {rows}x{cols} grid')
        width = max(1, scale_px // 8)
        r0, c0 = row * scale_px, col * scale_px
        block = img[r0:r0 + scale_px, c0:c0 + scale_px]
        block[:width] = MARK_RGB
        block[-width:] = MARK_RGB
        block[:, :width] = MARK_RGB
        block[:, -width:] = MARK_RGB
    return img


def belief_text(belief: np.ndarray, rows: int, cols: int, fixation: int | None = None) -> str:
    """Probabilities as a text grid in percent; the fixated cell is bracketed."""
    grid = np.asarray(belief, dtype=float).reshape(rows, cols)
    lines = []
    for r in range(rows):
        cells = []
        for c in range(cols):
            text = f'{100 * grid[r, c]:5.1f}'
            cells.append(f'[{text}]' if fixation == r * cols + c else f' {text} ')
        lines.append(''.join(cells))
    return '\n'.join(lines) + '\n'
