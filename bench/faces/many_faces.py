# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``find --all`` (the many-target belief) on composed group scenes against the detector alone.

Scenes (``--faces``): ``photos``, :func:`ipomdp_gaze.vision.photos.group_photo` with
``split='train'`` (the training photo faces, each ``--copies`` times, every other one mirrored)
on the training group backgrounds (:data:`~ipomdp_gaze.vision.photos.TRAIN_GROUP_BACKGROUNDS`);
or ``lfw``, :func:`lfw_group`: ``--copies`` distinct ``lfw_subset`` thumbnails of the split
(faces 0-59 for training) pasted as the scene set does (bicubic, feathered) on crops of the
split's backgrounds (:data:`~ipomdp_gaze.vision.scenes.TRAIN_BACKGROUNDS`), grey, at
``--sizes``. ``--split test`` composes test faces on test backgrounds, for a report only:
never choose on it.

Per scene, in the same run and on the same decoded image:

- ``find --all``: ``find``'s own path (:func:`ipomdp_gaze.commands.find.search_one` with the
  shipped models of ``--detector``, the model nearest the image's size, ``targets`` many);
- with ``--old-loop``, the single-target loop (``--targets one``: find a face, rule the cells
  within 2 of it out, search again; its answers are points, scored as boxes of size 0);
- the detector alone on the whole image at each of ``--scales`` (1, 1/2, 1/3, 1/4 by default,
  :func:`ipomdp_gaze.vision.fullframe.scan`), every answer box (YuNet's own boxes after its
  non-maximum suppression, OpenCV's grouping for Haar) a face.

A reported box is a found face when its centre lies in a true face box that no earlier box
matched (boxes taken most probable first), a **duplicate** when it lies in an already matched
one, else a **false face**. Seconds are wall time from the decoded array (as ``find`` reports
them); detector pixels are the pixels given to the detector.

Usage: ``python bench/faces/many_faces.py [--split train|test] [--scenes N] [--copies C]
[--sizes 640x480,1280x886] [--detector yunet|haar] [--absent-prior P] [--confidence C]
[--old-loop] [--faces photos|lfw] [--write docs/faces.md --section KEY]``; prints one
markdown row per method and size, totals over the scenes (``make faces-groups`` writes the
training and test tables into docs/faces.md). ``find``'s one-time set-up (the belief's tables,
the fixation costs of a size) is built on a first scene before the timed ones, as ``find``
leaves it out of its seconds.
"""
import argparse
from dataclasses import replace
from pathlib import Path
import time

from find_photos import find_tasks
from ipomdp_gaze.commands.find import search_one
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.photos import (GROUP_BACKGROUNDS, group_photo,
                                       TRAIN_GROUP_BACKGROUNDS)
from ipomdp_gaze.vision.scenes import (_paste as paste, DEFAULT_FEATHER, load_background,
                                       load_faces, SPLITS)
from ipomdp_gaze.vision.search import FIND_SETTINGS
import numpy as np

SCALES = (1.0, 1 / 2, 1 / 3, 1 / 4)
SPLITS_CODE = {'train': 0, 'test': 1}


def score(boxes, truth) -> tuple[int, int, int]:
    """Return (found, false, duplicates) of reported boxes ``(F, 4)`` against true boxes."""
    matched = np.zeros(len(truth), dtype=bool)
    found = false = duplicates = 0
    for x, y, w, h in np.asarray(boxes, dtype=float).reshape(-1, 4):
        cx, cy = x + w / 2, y + h / 2
        inside = ((truth[:, 0] <= cx) & (cx <= truth[:, 0] + truth[:, 2])
                  & (truth[:, 1] <= cy) & (cy <= truth[:, 1] + truth[:, 3]))
        if not inside.any():
            false += 1
        elif (inside & ~matched).any():
            matched[np.flatnonzero(inside & ~matched)[0]] = True
            found += 1
        else:
            duplicates += 1
    return found, false, duplicates


def lfw_group(size, seed: int, split: str, count: int):
    """
    Paste ``count`` distinct thumbnails of the split on a crop of one of its backgrounds.

    Sides uniform in 48-90 px scaled with the width (as the photo groups), places that do not
    overlap; returns the grey image as RGB ``(H, W, 3)`` and the pasted squares ``(F, 4)``.
    """
    width, height = size
    rng = np.random.default_rng([0x3A17, width, height, seed, SPLITS_CODE[split]])
    faces_range, backgrounds = SPLITS[split]
    name = backgrounds[seed % len(backgrounds)]
    back = load_background(name, 'gray', min_side=max(width, height))
    y = int(rng.integers(0, back.shape[0] - height + 1))
    x = int(rng.integers(0, back.shape[1] - width + 1))
    image = np.array(back[y:y + height, x:x + width])
    low, high = 48 * width / 640, 90 * width / 640
    boxes = []
    for face in rng.choice(np.array(faces_range), size=count, replace=False):
        for _ in range(200):
            side = int(rng.uniform(low, high))
            x0 = int(rng.integers(0, width - side))
            y0 = int(rng.integers(0, height - side))
            if all(x0 + side <= a or a + w <= x0 or y0 + side <= b or b + h <= y0
                   for a, b, w, h in boxes):
                break
        else:
            raise ValueError(f'{count} faces do not fit in {width}x{height}')
        paste(image, load_faces()[face], y0, x0, side, DEFAULT_FEATHER)
        boxes.append((x0, y0, side, side))
    return name, np.repeat(image[:, :, None], 3, axis=2), np.array(boxes, dtype=float)


def scenes(split: str, count: int, size, copies: int, faces: str = 'photos'):
    """Yield ``(name, image, boxes)`` of the composed group scenes of a split."""
    if faces == 'lfw':
        for i in range(count):
            name, image, boxes = lfw_group(size, i, split, copies)
            yield f'lfw-{name}-{i}', image, boxes
        return
    backgrounds = TRAIN_GROUP_BACKGROUNDS if split == 'train' else GROUP_BACKGROUNDS
    for i in range(count):
        background = backgrounds[i % len(backgrounds)]
        image, boxes = group_photo(size, seed=i, background=background, split=split,
                                   copies=copies)
        yield f'{background}-{i}', image, boxes


def run(args) -> list[dict]:
    """Measure every method on every scene; return one dict per (size, method)."""
    tasks = find_tasks(detector=args.detector)
    settings = replace(FIND_SETTINGS, targets='many', absent_prior=args.absent_prior,
                       confidence=args.confidence)
    rows = []
    for size in args.sizes:
        totals = {}
        # find's one-time set-up (the belief's information table, the fixation costs of the
        # size) is not in its seconds (ipomdp_gaze.commands.find): built on a first scene here
        _, image, _ = next(iter(scenes(args.split, 1, size, args.copies, args.faces)))
        search_one(image, tasks.task((image.shape[1], image.shape[0])), settings,
                   np.random.default_rng(0), True)
        for name, image, truth in scenes(args.split, args.scenes, size, args.copies,
                                         args.faces):
            task = tasks.task((image.shape[1], image.shape[0]))
            t0 = time.perf_counter()
            [result] = search_one(image, task, settings, np.random.default_rng(0), True)
            seconds = time.perf_counter() - t0
            boxes = np.array([f.box for f in result.faces]).reshape(-1, 4)
            _add(totals, 'find --all', score(boxes, truth), len(truth), seconds,
                 result.detector_pixels)
            if args.verbose:
                print(name, len(truth), score(boxes, truth), result.fixations, result.stop,
                      f'{seconds:.3f}')
            if args.old_loop:
                t0 = time.perf_counter()
                results = search_one(image, task, replace(settings, targets='one'),
                                     np.random.default_rng(0), True)
                seconds = time.perf_counter() - t0
                points = np.array([[*r.pixel, 0.0, 0.0] for r in results
                                   if r.decision == 'found']).reshape(-1, 4)
                _add(totals, 'find --all --targets one (old loop)', score(points, truth),
                     len(truth), seconds,
                     sum(r.detector_pixels for r in results) if results[0].method == 'fovea'
                     else results[0].detector_pixels)
            for scale in SCALES:
                t0 = time.perf_counter()
                alone = scan(image, task.fovea.detector, task.fovea.grid, scale)
                seconds = time.perf_counter() - t0
                _add(totals, f'detector at {scale:.3g}', score(alone.grouped_px, truth),
                     len(truth), seconds, alone.detector_pixels)
        for method, t in totals.items():
            rows.append({'size': f'{size[0]}x{size[1]}', 'method': method, **t})
    return rows


def _add(totals, method, counts, n_true, seconds, pixels):
    t = totals.setdefault(method, {'scenes': 0, 'faces': 0, 'found': 0, 'false': 0,
                                   'duplicates': 0, 'seconds': 0.0, 'pixels': 0})
    t['scenes'] += 1
    t['faces'] += n_true
    t['found'] += counts[0]
    t['false'] += counts[1]
    t['duplicates'] += counts[2]
    t['seconds'] += seconds
    t['pixels'] += int(pixels)


def _size(text):
    width, height = (int(v) for v in text.split('x'))
    return (width, height)


def main(argv=None):
    """Parse the flags, measure, print markdown rows."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    p.add_argument('--split', choices=('train', 'test'), default='train')
    p.add_argument('--scenes', type=int, default=8)
    p.add_argument('--copies', type=int, default=6)
    p.add_argument('--sizes', type=lambda t: [_size(s) for s in t.split(',')],
                   default=[(640, 480), (1280, 886)])
    p.add_argument('--detector', choices=('yunet', 'haar'), default='yunet')
    p.add_argument('--absent-prior', type=float, default=FIND_SETTINGS.absent_prior)
    p.add_argument('--confidence', type=float, default=FIND_SETTINGS.confidence)
    p.add_argument('--verbose', action='store_true')
    p.add_argument('--old-loop', action='store_true')
    p.add_argument('--faces', choices=('photos', 'lfw'), default='photos')
    p.add_argument('--empty-by-evidence', action='store_true',
                   help="decide a cell empty by its evidence alone (OccupancySession's "
                        'empty_by_evidence) instead of its posterior')
    p.add_argument('--write', type=Path, default=None, metavar='FILE.md',
                   help='also write the table into FILE.md between <!-- SECTION --> and '
                        '<!-- /SECTION --> (appended when they are not there)')
    p.add_argument('--section', default='many-faces')
    args = p.parse_args(argv)
    if args.empty_by_evidence:
        import functools
        from ipomdp_gaze.commands import find
        find.search_many = functools.partial(find.search_many, empty_by_evidence=True)
    rows = run(args)
    lines = [f'split {args.split}, {args.faces} faces, {args.scenes} scenes per size, '
             f'{args.copies} copies (lfw: faces) per scene, detector {args.detector}, absent '
             f'prior {args.absent_prior}, confidence {args.confidence}, empty by evidence '
             f'{args.empty_by_evidence}:', '',
             '| size | method | faces | found | false | duplicates | s / scene | '
             'detector px / scene |', '|---|---|---|---|---|---|---|---|']
    for r in rows:
        n = r['scenes']
        lines.append(f"| {r['size']} | {r['method']} | {r['faces']} | {r['found']} | "
                     f"{r['false']} | {r['duplicates']} | {r['seconds'] / n:.4f} | "
                     f"{r['pixels'] / n:,.0f} |")
    print('\n'.join(lines))
    if args.write:
        write_section(args.write, args.section, lines)


def write_section(path, key: str, lines: list) -> None:
    """Replace the text between ``<!-- key -->`` and ``<!-- /key -->`` in ``path`` (append)."""
    begin, end = f'<!-- {key} -->', f'<!-- /{key} -->'
    text = path.read_text() if path.exists() else ''
    block = '\n'.join([begin, *lines, end])
    if begin in text and end in text:
        text = text[:text.index(begin)] + block + text[text.index(end) + len(end):]
    else:
        text = text.rstrip('\n') + '\n\n' + block + '\n'
    path.write_text(text)


if __name__ == '__main__':
    main()
