# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Calibrate each detector per scale on training groups: which face sides a full-frame call sees.

The table behind ``find --all``'s coarse pass (:mod:`ipomdp_gaze.vision.scales`). Training
material only, ``--scenes`` pictures per size from 320x240 to 1920x1440: with ``--faces photos``
(the default) :func:`ipomdp_gaze.vision.photos.group_photo` with ``split='train'`` (the
training photo's face, ``count`` copies, on the training group backgrounds); with ``lfw`` (or
``both``) also :func:`many_faces.lfw_group` (the training thumbnails, faces 0-59, upscaled and
so blurred). Faces are 48-90 px at 640 wide, scaled with the width, and each is counted at the
side it has in the detector's input (``side * scale``). Per scale (1, 1/2, 1/3, 1/4): the
smallest detector-input side from which the detector finds at least ``--recall`` of the faces
(of all above it, and of those up to 16 px larger), the recall of those faces, and the strong
detections (YuNet: score 0.7 or more; Haar: its grouped boxes) near no face per million
detector pixels, counted one more than were seen (none in 60 Mpx is taken as 1 in 60).

Usage: ``python bench/faces/scales.py [--detector yunet|haar] [--scenes 6] [--recall 0.95]
[--faces photos|lfw|both] [--weak]``; prints the
table as the Python literal :data:`ipomdp_gaze.vision.scales.SCALE_TABLES` holds.
"""
import argparse
import math
from pathlib import Path
import sys

from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.photos import group_photo, TRAIN_GROUP_BACKGROUNDS
from ipomdp_gaze.vision.scales import coarse_detector, SCALE_TABLES
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from find_photos import find_tasks  # noqa: E402, I100
from many_faces import lfw_group, SCALES  # noqa: E402

WIDTHS = ((320, 240), (480, 360), (640, 480), (960, 720), (1280, 960), (1920, 1440))
BIN_PX = 4
# the score from which a box counts as strong (its false detections are the table's)
STRONG_SCORE = {'yunet': 0.7}
# a face side counts as seen from the smallest side whose faces up to this much larger are found
WINDOW_PX = 16


def pictures(scenes: int, count: int, faces: str = 'photos'):
    """Yield ``(size, seed, image, boxes)``: training photo groups (and/or lfw groups)."""
    for size in WIDTHS:
        for seed in range(scenes):
            if faces in ('lfw', 'both'):
                yield (size, seed, *lfw_group(size, seed, 'train', count)[1:])
            if faces == 'lfw':
                continue
            background = TRAIN_GROUP_BACKGROUNDS[seed % len(TRAIN_GROUP_BACKGROUNDS)]
            yield (size, seed, *group_photo(size, seed, background, split='train',
                                            copies=count))


def measure(detector: str, scenes: int, count: int = 6, faces: str = 'photos',
            weak: bool = False) -> dict:
    """
    Return per scale the faces' detector-input sides, hits and the false detections.

    ``weak``: a hit is any box of the coarse pass's detector (YuNet keeping boxes from
    :data:`~ipomdp_gaze.vision.scales.WEAK_SCORE`), the boxes that draw finer windows.
    """
    tasks = find_tasks(detector=detector)
    out = {s: {'sides': [], 'hits': [], 'false': 0, 'pixels': 0} for s in SCALES}
    for size, seed, image, truth in pictures(scenes, count, faces):
        task = tasks.task(size)
        fovea_detector = task.fovea.detector
        if weak:
            fovea_detector = coarse_detector(fovea_detector, SCALE_TABLES[detector].weak_score)
        for s in SCALES:
            found = scan(image, fovea_detector, task.fovea.grid, s)
            boxes = found.grouped_px
            centres = boxes[:, :2] + boxes[:, 2:] / 2
            inside = ((truth[None, :, 0] <= centres[:, None, 0])
                      & (centres[:, None, 0] <= truth[None, :, 0] + truth[None, :, 2])
                      & (truth[None, :, 1] <= centres[:, None, 1])
                      & (centres[:, None, 1] <= truth[None, :, 1] + truth[None, :, 3]))
            row = out[s]
            row['sides'].extend(truth[:, 2] * s)
            row['hits'].extend(inside.any(axis=0))
            strong = np.ones(len(boxes), dtype=bool)
            if detector in STRONG_SCORE and len(boxes) == len(found.scores):
                strong = found.scores >= STRONG_SCORE[detector]
            row['false'] += int((~inside.any(axis=1) & strong).sum())
            row['pixels'] += found.detector_pixels
    return out


def table(measured: dict, recall: float) -> dict:
    """Return ``{scale: (min_side_px, recall, false_per_mpx)}`` from :func:`measure`."""
    rows = {}
    for s, m in measured.items():
        sides, hits = np.array(m['sides']), np.array(m['hits'], dtype=float)
        window = [hits[(sides >= e) & (sides < e + WINDOW_PX)] for e in
                  np.arange(0.0, sides.max() + BIN_PX, BIN_PX)]
        low = next((i * BIN_PX for i, w in enumerate(window)
                    if hits[sides >= i * BIN_PX].mean() >= recall
                    and (not w.size or w.mean() >= recall)),
                   math.inf)
        low = max(low, float(np.floor(sides.min() / BIN_PX) * BIN_PX))  # none measured below
        seen = sides >= low
        rows[round(s, 4)] = (float(low), round(float(hits[seen].mean()), 3)
                             if seen.any() else 0.0,
                             round((m['false'] + 1) / m['pixels'] * 1e6, 3))
    return rows


def main(argv=None):
    """Measure and print the table."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    p.add_argument('--detector', choices=('yunet', 'haar'), default='yunet')
    p.add_argument('--scenes', type=int, default=6)
    p.add_argument('--recall', type=float, default=0.95)
    p.add_argument('--faces', choices=('photos', 'lfw', 'both'), default='photos',
                   help="the training photo's face (sharp), the lfw thumbnails (upscaled, "
                        'blurred: found only larger), or both')
    p.add_argument('--weak', action='store_true',
                   help="count a face as seen when the coarse pass's detector leaves any box "
                        '(YuNet from the weak score): the sides that draw finer windows')
    args = p.parse_args(argv)
    measured = measure(args.detector, args.scenes, faces=args.faces, weak=args.weak)
    rows = table(measured, args.recall)
    print(f'# {args.detector}: scale: (min side px in the detector input, recall from it, '
          f'false detections per Mpx), {args.scenes} training scenes per size')
    print('# strong false detections seen / Mpx measured: ' + ', '.join(
        f"{s:.3g}: {m['false']} / {m['pixels'] / 1e6:.1f}" for s, m in measured.items()))
    print(repr(rows))


if __name__ == '__main__':
    main()
