# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The one belief heatmap (Gymnasium render and the controller's belief_image) and text grid."""
from ipomdp_gaze.files.render import belief_heatmap, belief_text, colour_map, MARK_RGB
import numpy as np
import pytest


def test_heatmap_colours_size_and_fixation_outline():
    belief = np.full(12, 0.1 / 11)
    belief[5] = 0.9
    img = belief_heatmap(belief, (3, 4), fixation=10, scale_px=16)
    assert img.dtype == np.uint8 and img.shape == (48, 64, 3)
    assert tuple(img[1 * 16 + 8, 1 * 16 + 8]) == (253, 231, 37)      # the peak: yellow
    level = np.round(0.1 / 11 / 0.9 * 255) / 255                     # 256 colour levels
    assert tuple(img[0, 0]) == tuple(colour_map(np.array(level)))
    assert tuple(img[2 * 16, 2 * 16 + 8]) == MARK_RGB                 # outline of cell (2, 2)
    assert tuple(img[2 * 16 + 1, 2 * 16 + 8]) == MARK_RGB             # two pixels wide at 16 px
    assert tuple(img[2 * 16 + 2, 2 * 16 + 8]) != MARK_RGB
    assert tuple(img[2 * 16 + 8, 2 * 16 + 8]) != MARK_RGB             # its inside is the belief
    assert not np.any(np.all(belief_heatmap(belief, (3, 4)) == MARK_RGB, axis=2))


def test_colour_map_ends_and_is_monotone_in_brightness():
    assert tuple(colour_map(np.array(0.0))) == (68, 1, 84)
    assert tuple(colour_map(np.array(1.0))) == (253, 231, 37)
    rgb = colour_map(np.linspace(0, 1, 50)).astype(float)
    assert np.all(np.diff(rgb @ [0.2126, 0.7152, 0.0722]) > 0)


def test_flat_and_degenerate_beliefs_and_bad_arguments():
    assert np.all(belief_heatmap(np.zeros(4), (2, 2), scale_px=1) == (68, 1, 84))
    assert np.all(belief_heatmap(np.full(4, 0.25), (2, 2), scale_px=1) == (253, 231, 37))
    with pytest.raises(ValueError, match='scale_px'):
        belief_heatmap(np.full(4, 0.25), (2, 2), scale_px=0)
    with pytest.raises(ValueError, match='outside a 2x2 grid'):
        belief_heatmap(np.full(4, 0.25), (2, 2), fixation=4)


def test_text_grid_brackets_the_fixation():
    text = belief_text(np.array([0.5, 0.25, 0.125, 0.125]), 2, 2, fixation=1)
    assert text == '  50.0 [ 25.0]\n  12.5   12.5 \n'
