# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The real-photo set: photographs our dependencies ship, their faces boxed by hand, and groups.

The scene set (:mod:`ipomdp_gaze.vision.scenes`) pastes 25x25 grey thumbnails, which favours
detectors of low-frequency grey patterns; a detector comparison needs real photographs as well
(docs/design.md section 6). Every photo here ships inside a wheel we already install, so the set
is the same offline on every machine:

- with faces: scikit-image's ``astronaut`` and ``camera`` (the cameraman, in profile) and
  matplotlib's ``grace_hopper.jpg`` sample;
- without a face: 17 scikit-image photos (not the binary ``horse`` silhouette) and matplotlib's
  ``Minduka_Present_Blue_Pack.png`` sample (``present``, a drawing of a gift box).

The labels are ``ipomdp_gaze/data/photos.csv``: one row per face, ``x, y, w, h`` in the photo's
pixels, boxed by hand (forehead to chin, cheek or ear to cheek); a face-free photo has one row
with an empty box. Its ``split`` column says which photos may inform a choice (``train``: the
astronaut, long used in docs/faces.md, and the face-free photos that are training backgrounds
of the scene set) and which are for measuring only (``test``).

:func:`group_photo` composes a group picture from the three faces (each cropped with a margin
round its box, pasted twice, the second mirrored) on a test photo without faces, at a given size:
real faces, several per image, with known boxes. With ``split='train'`` it composes from the
training face (the astronaut) on the training backgrounds only, which is what may inform a
choice such as ``find``'s default detector.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources
import math
from pathlib import Path

import cv2
import numpy as np

LABELS = Path(str(resources.files('ipomdp_gaze').joinpath('data', 'photos.csv')))
SKIMAGE_PHOTOS = ('astronaut', 'camera', 'brick', 'cell', 'chelsea', 'clock', 'coffee', 'coins',
                  'grass', 'gravel', 'hubble_deep_field', 'immunohistochemistry',
                  'microaneurysms', 'moon', 'page', 'retina', 'rocket', 'stereo_motorcycle',
                  'text')
MATPLOTLIB_PHOTOS = {'grace_hopper': 'grace_hopper.jpg',
                     'present': 'Minduka_Present_Blue_Pack.png'}
# Group pictures: (width, height) and the range of face sides in pixels at that size.
GROUP_SIZES = {(320, 240): (28, 44), (640, 480): (48, 90), (1280, 886): (90, 150)}
GROUP_BACKGROUNDS = ('stereo_motorcycle', 'gravel')
# Training groups: the training face on training backgrounds (for choices; the others measure).
TRAIN_GROUP_BACKGROUNDS = ('coffee', 'rocket', 'brick', 'grass')
FACE_MARGIN = 0.3
_STREAM_TAG = 0x6A0F0


@dataclass(frozen=True, eq=False)
class Photo:
    """A labelled photo: RGB ``uint8`` pixels, face boxes ``(F, 4)`` ``x, y, w, h``, split."""

    name: str
    image: np.ndarray
    boxes: np.ndarray
    split: str

    @property
    def centres_px(self) -> np.ndarray:
        """Face centres ``(F, 2)`` ``x + w/2, y + h/2`` in pixels."""
        return self.boxes[:, :2] + self.boxes[:, 2:] / 2.0


def load_photo(name: str) -> np.ndarray:
    """
    Return a photo of the set as an RGB ``uint8`` array ``(H, W, 3)``.

    Raises
    ------
    ValueError
        For a name that is not in the set.

    """
    if name in SKIMAGE_PHOTOS:
        from skimage import data
        image = getattr(data, name)()
        if isinstance(image, tuple):                    # stereo_motorcycle: (left, right, disp)
            image = image[0]
    elif name in MATPLOTLIB_PHOTOS:
        import matplotlib
        path = Path(matplotlib.get_data_path()) / 'sample_data' / MATPLOTLIB_PHOTOS[name]
        bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if bgr is None:
            raise FileNotFoundError(f'matplotlib sample {path} is missing')
        image = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    else:
        raise ValueError(f'unknown photo {name!r}; the set has '
                         f'{", ".join(SKIMAGE_PHOTOS + tuple(MATPLOTLIB_PHOTOS))}')
    image = np.asarray(image)
    if image.ndim == 2:
        image = np.repeat(image[:, :, None], 3, axis=2)
    return np.ascontiguousarray(image[:, :, :3].astype(np.uint8))


def read_labels(path=LABELS) -> dict:
    """Read the labels CSV: ``{photo: (boxes (F, 4) float64, split)}`` in file order."""
    labels = {}
    with open(path, newline='') as handle:
        rows = csv.DictReader(line for line in handle if not line.startswith('#'))
        for row in rows:
            boxes, split = labels.get(row['photo'], (np.empty((0, 4)), row['split']))
            if row['x']:
                box = [float(row[key]) for key in ('x', 'y', 'w', 'h')]
                boxes = np.vstack([boxes, box])
            labels[row['photo']] = (boxes, split)
    return labels


def real_photos(split: str | None = None) -> list[Photo]:
    """Every labelled photo (or those of one ``split``), in the labels' order."""
    return [Photo(name, load_photo(name), boxes, photo_split)
            for name, (boxes, photo_split) in read_labels().items()
            if split is None or photo_split == split]


def face_crops(split: str | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """
    Crop each labelled face (of one ``split``) with :data:`FACE_MARGIN` round its box.

    Returns ``(crop, box)`` pairs: the RGB crop and the face box ``x, y, w, h`` in its pixels.
    """
    crops = []
    for name, (boxes, photo_split) in read_labels().items():
        if len(boxes) == 0 or (split is not None and photo_split != split):
            continue
        image = load_photo(name)
        height, width = image.shape[:2]
        for x, y, w, h in boxes:
            side = max(w, h) * (1 + 2 * FACE_MARGIN)
            cx, cy = x + w / 2, y + h / 2
            x0, y0 = int(max(0, cx - side / 2)), int(max(0, cy - side / 2))
            x1, y1 = int(min(width, cx + side / 2)), int(min(height, cy + side / 2))
            crops.append((image[y0:y1, x0:x1], np.array([x - x0, y - y0, w, h])))
    return crops


def group_photo(size_px=(640, 480), seed: int = 0, background: str | None = None,
                split: str | None = None, copies: int = 2):
    """
    Compose a group picture: every labelled face ``copies`` times (every other one mirrored).

    ``split``: the faces of that split only (default every face); ``background``: a face-free
    photo (default the first of :data:`GROUP_BACKGROUNDS`, or of
    :data:`TRAIN_GROUP_BACKGROUNDS` for ``split='train'``).

    Faces get larger sides drawn uniformly from :data:`GROUP_SIZES` for the size (scaled with
    the width for another size) and places that keep their crops, margins included, from
    overlapping; the background photo is resized to cover the picture and centre-cropped.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The RGB ``uint8`` picture ``(H, W, 3)`` and the face boxes ``(F, 4)`` ``x, y, w, h``.

    """
    width, height = (int(v) for v in size_px)
    low, high = GROUP_SIZES.get((width, height), tuple(v * width / 640 for v in (48, 90)))
    rng = np.random.default_rng([_STREAM_TAG, width, height, int(seed)])
    if background is None:
        background = (TRAIN_GROUP_BACKGROUNDS if split == 'train' else GROUP_BACKGROUNDS)[0]
    back = load_photo(background)
    scale = max(width / back.shape[1], height / back.shape[0])
    back = cv2.resize(back, (math.ceil(back.shape[1] * scale), math.ceil(back.shape[0] * scale)),
                      interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_CUBIC)
    top, left = (back.shape[0] - height) // 2, (back.shape[1] - width) // 2
    image = np.ascontiguousarray(back[top:top + height, left:left + width])
    crops = face_crops(split)
    mirrored = [(crop[:, ::-1], np.array([crop.shape[1] - x - w, y, w, h]))
                for crop, (x, y, w, h) in crops]
    boxes, taken = [], []
    for crop, box in [pair for k in range(copies) for pair in (mirrored if k % 2 else crops)]:
        crop_h, crop_w = crop.shape[:2]
        for _ in range(200):
            side = rng.uniform(low, high)                   # the face's larger side
            k = side / max(box[2], box[3])
            out_w, out_h = int(round(crop_w * k)), int(round(crop_h * k))
            if out_w >= width or out_h >= height:
                continue
            x0 = int(rng.integers(0, width - out_w))
            y0 = int(rng.integers(0, height - out_h))
            if all(x0 + out_w <= a or a + aw <= x0 or y0 + out_h <= b or b + bh <= y0
                   for a, b, aw, bh in taken):
                break
        else:
            raise ValueError(f'{copies * len(crops)} faces of {low}-{high} px do not fit in '
                             f'{width}x{height}')
        taken.append((x0, y0, out_w, out_h))
        _paste_rgb(image, crop, x0, y0, out_w, out_h)
        scale = (out_w / crop_w, out_h / crop_h)
        boxes.append([x0 + box[0] * scale[0], y0 + box[1] * scale[1], box[2] * scale[0],
                      box[3] * scale[1]])
    return image, np.round(np.array(boxes), 1)


def _paste_rgb(image: np.ndarray, crop: np.ndarray, x0: int, y0: int, out_w: int,
               out_h: int) -> None:
    """Paste ``crop`` resized to ``out_w`` x ``out_h`` at ``(x0, y0)``, edges feathered."""
    from ipomdp_gaze.vision.scenes import feather_mask
    resized = cv2.resize(np.ascontiguousarray(crop), (out_w, out_h),
                         interpolation=cv2.INTER_AREA).astype(np.float32)
    alpha = cv2.resize(feather_mask(max(out_w, out_h), 0.15), (out_w, out_h))[:, :, None]
    region = image[y0:y0 + out_h, x0:x0 + out_w].astype(np.float32)
    image[y0:y0 + out_h, x0:x0 + out_w] = np.rint(region + alpha * (resized - region)).astype(
        np.uint8)
