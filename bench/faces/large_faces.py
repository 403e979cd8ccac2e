# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Faces as large as the picture: YuNet's largest side, and ``find`` on close-ups.

Two tables, on one split's faces and backgrounds (``--split train`` informs the choices;
``test`` is for the report only):

- ``--sides``: YuNet at full resolution on one face centred in a picture 1.6 times its side,
  per face side: the share of faces found strongly (score 0.7 or more, centre within a quarter
  side of the face's) and found at all. The largest 50 px step with at least 0.95 strong is the
  table's ``max_side_px`` (:data:`ipomdp_gaze.vision.scales.SCALE_TABLES`).
- close-ups (the default): one face filling 0.3-0.9 of the shorter side of a picture of
  800x600 to 2048x1536 (and portrait 1536x2048), at a random place on a background of the
  split: the split's lfw thumbnails (upscaled, so blurred) and, on the training split, the
  astronaut's head. ``find`` as shipped (YuNet, ``--scan coarse``) and ``find --all``: right
  when a face's centre lies within a quarter side of the truth's; other faces named;
  detector pixels over one full scan.

Usage: ``python bench/faces/large_faces.py [--split train|test] [--sides] [--pictures 8]
[--seed 11] [--fractions 0.3,0.45,0.6,0.75,0.9]``.
"""
import argparse
from dataclasses import replace
import sys
from types import SimpleNamespace

import cv2
from ipomdp_gaze.commands.find import _Tasks, search_one
from ipomdp_gaze.vision.detectors import make_detector
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.photos import load_photo, read_labels
from ipomdp_gaze.vision.scenes import load_background, load_faces, SPLITS
from ipomdp_gaze.vision.search import FIND_SETTINGS
import numpy as np

SIDES = (250, 300, 350, 400, 450, 500)
SIZES = ((800, 600), (1280, 960), (1600, 1200), (2048, 1536), (1536, 2048))
FRACTIONS = (0.3, 0.45, 0.6, 0.75, 0.9)
STRONG = 0.7


def split_faces(split: str) -> list:
    """Return the split's faces as RGB arrays: lfw thumbnails, and the astronaut's head (train)."""
    thumbnails = load_faces()
    faces = [np.dstack([thumbnails[k]] * 3) for k in SPLITS[split][0]]
    if split == 'train':
        x, y, w, h = (int(v) for v in read_labels()['astronaut'][0][0])
        margin = w // 4
        faces.insert(0, load_photo('astronaut')[y - margin:y + h + margin,
                                                x - margin:x + w + margin])
    return faces


def paste(background: np.ndarray, face: np.ndarray, side: float, x0: int, y0: int):
    """Paste ``face`` scaled to ``side`` px tall at ``(x0, y0)``; return the picture and box."""
    factor = side / face.shape[0]
    scaled = cv2.resize(face.astype(np.float32), (round(face.shape[1] * factor), round(side)),
                        interpolation=cv2.INTER_CUBIC)
    picture = background.copy()
    picture[y0:y0 + scaled.shape[0], x0:x0 + scaled.shape[1]] = \
        np.clip(scaled, 0, 255).astype(np.uint8)
    return picture, (x0, y0, scaled.shape[1], scaled.shape[0])


def near(box, truth) -> bool:
    x, y, w, h = box
    tx, ty, tw, th = truth
    return abs(x + w / 2 - tx - tw / 2) < tw / 4 and abs(y + h / 2 - ty - th / 2) < th / 4


def sides_table(split: str) -> list[str]:
    detector = make_detector('yunet')
    faces = split_faces(split)
    backgrounds = [load_background(name, 'rgb') for name in SPLITS[split][1][:3]]
    lines = ['| face side (px, at 1) | found strongly (0.7) | found |', '|---|---|---|']
    for side in SIDES:
        strong, seen = [], []
        for k, face in enumerate(faces):
            frame = round(1.6 * side)
            background = cv2.resize(backgrounds[k % len(backgrounds)], (frame, frame))
            offset = (frame - round(side)) // 2
            picture, truth = paste(background, face, side, offset, offset)
            found = scan(picture, detector, (21, 21), 1.0)
            scores = [score for box, score in zip(found.boxes_px, found.scores)
                      if near(box, truth)]
            strong.append(max(scores, default=0.0) >= STRONG)
            seen.append(bool(scores))
        lines.append(f'| {side} | {np.mean(strong):.3f} (of {len(strong)}) | '
                     f'{np.mean(seen):.3f} |')
    return lines


def close_ups(split: str, pictures: int, seed: int, fractions=FRACTIONS) -> list[str]:
    rng = np.random.default_rng(seed)
    faces = split_faces(split)
    names = SPLITS[split][1]
    tasks = _Tasks(SimpleNamespace(observation=None, detector='yunet', policy=None,
                                   policy_file=None))
    runs = {'find': (False, 'one'), 'find --all': (True, 'many')}
    right = {run: {f: [] for f in fractions} for run in runs}
    others = dict.fromkeys(runs, 0)
    ratios = {run: [] for run in runs}
    for k in range(pictures):
        face = faces[0] if k == 0 else faces[rng.integers(len(faces))]
        for width, height in SIZES:
            for fraction in fractions:
                background = cv2.resize(load_background(names[rng.integers(len(names))], 'rgb'),
                                        (width, height))
                side = fraction * min(width, height)
                face_w = round(face.shape[1] * side / face.shape[0])
                x0 = int(rng.integers(0, width - face_w + 1))
                y0 = int(rng.integers(0, height - round(side) + 1))
                picture, truth = paste(background, face, side, x0, y0)
                task = tasks.task((width, height))
                for run, (find_all, targets) in runs.items():
                    result = search_one(picture, task, replace(FIND_SETTINGS, targets=targets),
                                        np.random.default_rng(0), find_all)[0]
                    hits = [near(f.box, truth) for f in result.faces] \
                        if result.decision == 'found' else []
                    right[run][fraction].append(any(hits))
                    others[run] += len(hits) - sum(hits)
                    ratios[run].append(result.detector_pixels / (width * height))
    n = pictures * len(SIZES)
    lines = ['| search | ' + ' | '.join(f'face {f:g} of the side' for f in fractions)
             + ' | other faces named | px / full |',
             '|---|' + '---|' * (len(fractions) + 2)]
    for run in runs:
        cells = ' | '.join(f'{sum(right[run][f])}/{n}' for f in fractions)
        lines.append(f'| `{run}` | {cells} | {others[run]} | {np.mean(ratios[run]):.3f} |')
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--split', default='train', choices=('train', 'test'))
    parser.add_argument('--sides', action='store_true')
    parser.add_argument('--pictures', type=int, default=8)
    parser.add_argument('--seed', type=int, default=11)
    parser.add_argument('--fractions', type=lambda text: [float(v) for v in text.split(',')],
                        default=FRACTIONS, help='face sides, as fractions of the shorter side')
    args = parser.parse_args(argv)
    lines = (sides_table(args.split) if args.sides
             else close_ups(args.split, args.pictures, args.seed, args.fractions))
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    sys.exit(main())
