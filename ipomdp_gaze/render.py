# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Pictures of a belief: a colour-mapped heatmap (uint8 RGB) and a text grid, with no ROS.

Used by the Gymnasium environment's ``render`` and by the controller's ``belief_image`` adapter.
"""
from __future__ import annotations

import numpy as np

# Anchor colours of matplotlib's 'inferno' map (0, 0.25, 0.5, 0.75, 1), interpolated linearly:
# perceptually ordered, readable in greyscale, and no matplotlib import on the robot.
_ANCHORS = np.array([[0, 0, 4], [87, 16, 110], [188, 55, 84], [249, 142, 9], [252, 255, 164]],
                    dtype=float)


def colormap(values: np.ndarray) -> np.ndarray:
    """Map values in [0, 1] to uint8 RGB, shape ``values.shape + (3,)``."""
    v = np.clip(np.nan_to_num(np.asarray(values, dtype=float)), 0.0, 1.0) * (len(_ANCHORS) - 1)
    low = np.minimum(v.astype(int), len(_ANCHORS) - 2)
    frac = (v - low)[..., None]
    rgb = _ANCHORS[low] * (1 - frac) + _ANCHORS[low + 1] * frac
    return np.round(rgb).astype(np.uint8)


def belief_heatmap(belief: np.ndarray, rows: int, cols: int, fixation: int | None = None,
                   scale: int = 16) -> np.ndarray:
    """
    Draw a ``(rows*scale, cols*scale, 3)`` uint8 heatmap of the belief, normalised to its maximum.

    The fixated cell, if given, is outlined in cyan so the scan is visible in rqt_image_view.
    """
    grid = np.asarray(belief, dtype=float).reshape(rows, cols)
    peak = grid.max()
    image = colormap(grid / peak if peak > 0 else grid)
    image = np.repeat(np.repeat(image, scale, axis=0), scale, axis=1)
    if fixation is not None and scale >= 3:
        r, c = divmod(int(fixation), cols)
        y0, x0 = r * scale, c * scale
        box = image[y0:y0 + scale, x0:x0 + scale]
        box[[0, 1, -2, -1], :] = (0, 255, 255)
        box[:, [0, 1, -2, -1]] = (0, 255, 255)
    return image


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
