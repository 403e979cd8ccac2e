# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``find --all`` (the many-target belief) on composed group scenes against the detector alone.

Scenes: :func:`ipomdp_gaze.vision.photos.group_photo` with ``split='train'`` (the training
faces, each ``--copies`` times, every other one mirrored) on the training backgrounds
(:data:`~ipomdp_gaze.vision.photos.TRAIN_GROUP_BACKGROUNDS`), at ``--sizes``. ``--split test``
composes the test faces on the test backgrounds, for a report only: never choose on it.

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

Usage: ``python bench/many_faces.py [--split train|test] [--scenes N] [--copies C]
[--sizes 640x480,1280x886] [--detector yunet|haar] [--absent-prior P] [--confidence C]
[--old-loop]``;
prints one markdown row per method and size, totals over the scenes.
"""
import argparse
from dataclasses import replace
import time

from bench.find_photos import find_tasks
from ipomdp_gaze.commands.find import search_one
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.photos import (GROUP_BACKGROUNDS, group_photo,
                                       TRAIN_GROUP_BACKGROUNDS)
from ipomdp_gaze.vision.search import FIND_SETTINGS
import numpy as np

SCALES = (1.0, 1 / 2, 1 / 3, 1 / 4)


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


def scenes(split: str, count: int, size, copies: int):
    """Yield ``(name, image, boxes)`` of the composed group scenes of a split."""
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
        for name, image, truth in scenes(args.split, args.scenes, size, args.copies):
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
    args = p.parse_args(argv)
    rows = run(args)
    print(f'split {args.split}, {args.scenes} scenes per size, {args.copies} copies of each '
          f'face, detector {args.detector}, absent prior {args.absent_prior}, confidence '
          f'{args.confidence}')
    print('| size | method | faces | found | false | duplicates | s / scene | '
          'detector px / scene |')
    print('|---|---|---|---|---|---|---|---|')
    for r in rows:
        n = r['scenes']
        print(f"| {r['size']} | {r['method']} | {r['faces']} | {r['found']} | {r['false']} | "
              f"{r['duplicates']} | {r['seconds'] / n:.4f} | {r['pixels'] / n:,.0f} |")


if __name__ == '__main__':
    main()
