# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze find`` on the real-photo set, per model: the done-when checks of docs/faces.md.

For each model (by default each detector's shipped models, chosen nearest each image's size as
``find`` does; or one ``--observation`` for every image) and ``find``'s default settings:

- **photos** (:mod:`ipomdp_gaze.vision.photos`): a photo with a face is right when ``find``
  says ``found`` within one cell (Chebyshev) of a labelled face's centre cell; a face-free photo
  is right when it says ``absent``; detector pixels against one full-resolution scan (W x H);
- **groups** (``find --all``): composed group pictures, faces found (within one cell), found
  answers near no face, the last decision and the detector pixels of all the searches.

Usage: ``python bench/find_photos.py [--split train|test|all] [--groups] [--detector haar|yunet |
--observation NAME]``. With ``--split train`` the groups are the training ones (the astronaut
three times on each training background), which may inform a choice; otherwise the test ones.
Prints markdown rows.
"""
import argparse
from dataclasses import replace
from types import SimpleNamespace

from ipomdp_gaze.commands.find import _Tasks, FIND_DETECTORS, search_one
from ipomdp_gaze.vision.fullframe import cells_of_points
from ipomdp_gaze.vision.photos import group_photo, real_photos, TRAIN_GROUP_BACKGROUNDS
from ipomdp_gaze.vision.search import FIND_SETTINGS
import numpy as np


def near(cell, cells) -> bool:
    """Whether ``cell`` is within one cell of any of ``cells``."""
    return any(max(abs(cell[0] - r), abs(cell[1] - c)) <= 1 for r, c in cells)


def truth_cells(boxes, shape, grid) -> list:
    """Return the cells ``(row, col)`` of the face boxes' centres."""
    centres = boxes[:, :2] + boxes[:, 2:] / 2
    return [tuple(grid.cell(c)) for c in cells_of_points(centres, shape, grid)]


def photos(tasks, split, settings) -> None:
    """Print one row per photo and the totals."""
    print('| photo | split | size | model | decision | stop | method | right | pixels / full |')
    print('|---|---|---|---|---|---|---|---|---|')
    faces = absent = empty = over = 0
    n_faces = 0
    for i, photo in enumerate(real_photos(None if split == 'all' else split)):
        image = photo.image
        task = tasks.task((image.shape[1], image.shape[0]))
        result = search_one(image, task, settings, np.random.default_rng([0, i]), False)[0]
        full = image.shape[0] * image.shape[1]
        if len(photo.boxes):
            n_faces += 1
            truth = truth_cells(photo.boxes, image.shape, task.model.grid)
            right = result.decision == 'found' and near(result.cell, truth)
            faces += right
        else:
            empty += 1
            right = result.decision == 'absent'
            absent += right
        over += result.detector_pixels > full
        print(f'| {photo.name} | {photo.split} | {image.shape[1]}x{image.shape[0]} | '
              f'{task.model.meta.get("source")} | {result.decision} | {result.stop} | '
              f'{result.method} | {"yes" if right else "no"} | '
              f'{result.detector_pixels / full:.2f} |')
    print(f'\nfaces found {faces}/{n_faces}; absent on {absent}/{empty} face-free photos; '
          f'{over} photos over one full scan')


def group_pictures(split):
    """Yield ``(label, seed, image, boxes)``: the composed group pictures of a split."""
    if split == 'train':        # the training face, 3 times, on each training background
        for seed, background in enumerate(TRAIN_GROUP_BACKGROUNDS):
            for size in ((640, 480), (1280, 886)):
                yield (f'{size[0]}x{size[1]} {background}', seed,
                       *group_photo(size, seed, background, split='train', copies=3))
        return
    for seed in (0, 1, 2):
        for size in ((640, 480), (1280, 886)):
            yield f'{size[0]}x{size[1]} seed {seed}', seed, *group_photo(size, seed)


def groups(tasks, split, settings) -> None:
    """Print one row per composed group picture searched with ``--all``, then the totals."""
    print('| group | faces found | found near no face | last | searches | pixels / full |')
    print('|---|---|---|---|---|---|')
    totals = dict.fromkeys(('faces', 'hit', 'wrong', 'pictures', 'no_more'), 0)
    for label, seed, image, boxes in group_pictures(split):
        size = (image.shape[1], image.shape[0])
        task = tasks.task(size)
        results = search_one(image, task, settings, np.random.default_rng([0, seed]),
                             True)
        truth = truth_cells(boxes, image.shape, task.model.grid)
        found = [r.cell for r in results if r.decision == 'found']
        hit = sum(near(t, found) for t in truth)
        wrong = sum(not near(f, truth) for f in found)
        pixels = sum(r.detector_pixels for r in results)
        totals['faces'] += len(truth)
        totals['hit'] += hit
        totals['wrong'] += wrong
        totals['pictures'] += 1
        totals['no_more'] += results[-1].decision == 'absent'
        print(f'| {label} | {hit}/{len(truth)} | {wrong} | '
              f'{results[-1].decision} ({results[-1].stop}) | {len(results)} | '
              f'{pixels / (size[0] * size[1]):.2f} |')
    print(f"\nfaces found {totals['hit']}/{totals['faces']}; {totals['wrong']} found near no "
          f"face; 'no more' after {totals['no_more']}/{totals['pictures']} pictures")


def main() -> None:
    """Parse the options and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--split', default='all', choices=('train', 'test', 'all'))
    parser.add_argument('--groups', action='store_true')
    parser.add_argument('--observation', default=None)
    parser.add_argument('--detector', default=None, choices=FIND_DETECTORS)
    parser.add_argument('--absent-prior', type=float, default=FIND_SETTINGS.absent_prior)
    args = parser.parse_args()
    settings = replace(FIND_SETTINGS, absent_prior=args.absent_prior)
    tasks = _Tasks(SimpleNamespace(observation=args.observation, detector=args.detector,
                                   policy=None, policy_file=None))
    photos(tasks, args.split, settings)
    if args.groups:
        print()
        groups(tasks, 'train' if args.split == 'train' else 'test', settings)


if __name__ == '__main__':
    main()
