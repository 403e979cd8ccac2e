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
  answers near no face, the last decision and the detector pixels of all the searches;
- **full frame** (:func:`full_frame_rows`, used by ``bench/faces/faces.py``): one full-resolution
  scan of the model's detector, every answer box (OpenCV's grouped detections for Haar, YuNet's
  own boxes after its non-maximum suppression) a face, scored on the same cells.

Usage: ``python bench/faces/find_photos.py [--split train|test|all] [--groups] [--detector
haar|yunet |
--observation NAME]``. With ``--split train`` the groups are the training ones (the astronaut
three times on each training background), which may inform a choice; otherwise the test ones.
Prints markdown rows. ``bench/faces/faces.py`` (``make faces``) calls the row functions for its
tables.
"""
import argparse
from dataclasses import replace
import time
from types import SimpleNamespace

from ipomdp_gaze.commands.find import _Tasks, FIND_DETECTORS, SCAN_DEFAULT, search_one
from ipomdp_gaze.simulation.evaluation import answer_is_right
from ipomdp_gaze.vision.fullframe import cells_of_points, scan
from ipomdp_gaze.vision.photos import group_photo, real_photos, TRAIN_GROUP_BACKGROUNDS
from ipomdp_gaze.vision.search import FIND_SETTINGS
import numpy as np


def near(cell, cells) -> bool:
    """Whether ``cell`` is within one cell of any of ``cells``."""
    return any(answer_is_right(cell, truth) for truth in cells)


def truth_cells(boxes, shape, grid) -> list:
    """Return the cells ``(row, col)`` of the face boxes' centres."""
    if not len(boxes):
        return []
    centres = boxes[:, :2] + boxes[:, 2:] / 2
    return [tuple(grid.cell(c)) for c in cells_of_points(centres, shape, grid)]


def find_tasks(detector=None, observation=None) -> _Tasks:
    """Build ``find``'s models, foveas and policies for ``--detector`` or ``--observation``."""
    return _Tasks(SimpleNamespace(observation=observation, detector=detector, policy=None,
                                  policy_file=None))


def photo_rows(tasks, split, settings, scan=SCAN_DEFAULT) -> list[dict]:
    """``find --scan SCAN`` on each photo of ``split`` ('train', 'test', 'all'): a dict each."""
    rows = []
    for i, photo in enumerate(real_photos(None if split == 'all' else split)):
        image = photo.image
        task = tasks.task((image.shape[1], image.shape[0]))
        t0 = time.perf_counter()
        result = search_one(image, task, settings, np.random.default_rng([0, i]), False,
                            scan=scan)[0]
        seconds = time.perf_counter() - t0
        full = image.shape[0] * image.shape[1]
        face = bool(len(photo.boxes))
        if face:
            truth = truth_cells(photo.boxes, image.shape, task.model.grid)
            right = result.decision == 'found' and near(result.cell, truth)
        else:
            right = result.decision == 'absent'
        rows.append({'photo': photo.name, 'split': photo.split, 'face': face,
                     'size': (image.shape[1], image.shape[0]),
                     'model': str(task.model.meta.get('source')), 'decision': result.decision,
                     'stop': result.stop, 'method': result.method, 'right': bool(right),
                     'wrong_found': (not face) and result.decision == 'found',
                     'pixels_ratio': result.detector_pixels / full, 'seconds': seconds})
    return rows


def full_frame_rows(tasks, split) -> list[dict]:
    """One full-resolution scan per photo with the detector of ``find``'s model for its size."""
    rows = []
    for photo in real_photos(None if split == 'all' else split):
        image = photo.image
        task = tasks.task((image.shape[1], image.shape[0]))
        grid = task.model.grid
        result = scan(image, task.fovea.detector, grid, 1.0)
        answers = result.grouped_px
        cells = truth_cells(answers, image.shape, grid)
        truth = truth_cells(photo.boxes, image.shape, grid)
        rows.append({'photo': photo.name, 'split': photo.split, 'face': bool(len(truth)),
                     'found': sum(near(t, cells) for t in truth), 'faces': len(truth),
                     'wrong': sum(not near(c, truth) for c in cells),
                     'wrong_found': not len(truth) and bool(len(cells)),
                     'pixels_ratio': 1.0, 'seconds': result.seconds})
    return rows


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


def group_rows(tasks, split, settings) -> list[dict]:
    """
    ``find --all`` on each composed group picture of ``split``: one dict per picture.

    ``settings.targets`` many: the one many-target search's faces (what ``find --all`` runs);
    one: the single-target loop's found answers (``--all --targets one``).
    """
    rows = []
    for label, seed, image, boxes in group_pictures(split):
        size = (image.shape[1], image.shape[0])
        task = tasks.task(size)
        t0 = time.perf_counter()
        results = search_one(image, task, settings, np.random.default_rng([0, seed]), True)
        seconds = time.perf_counter() - t0
        truth = truth_cells(boxes, image.shape, task.model.grid)
        last = results[-1].decision
        if settings.targets == 'many':                    # one search, every face in it
            found = [face.cell for face in results[0].faces]
            # "no more faces": every cell decided (else the limit that stopped it)
            last = 'absent' if results[0].stop in ('found', 'absent') else last
        else:
            found = [r.cell for r in results if r.decision == 'found']
        rows.append({'group': label, 'faces': len(truth),
                     'found': sum(near(t, found) for t in truth),
                     'wrong': sum(not near(f, truth) for f in found),
                     'last': last, 'stop': results[-1].stop,
                     'searches': len(results),
                     'pixels_ratio': sum(r.detector_pixels for r in results)
                     / (size[0] * size[1]), 'seconds': seconds})
    return rows


def photos(tasks, split, settings) -> None:
    """Print one row per photo and the totals."""
    print('| photo | split | size | model | decision | stop | method | right | pixels / full |')
    print('|---|---|---|---|---|---|---|---|---|')
    rows = photo_rows(tasks, split, settings)
    for r in rows:
        print(f"| {r['photo']} | {r['split']} | {r['size'][0]}x{r['size'][1]} | {r['model']} | "
              f"{r['decision']} | {r['stop']} | {r['method']} | "
              f"{'yes' if r['right'] else 'no'} | {r['pixels_ratio']:.2f} |")
    faces = [r for r in rows if r['face']]
    empty = [r for r in rows if not r['face']]
    print(f"\nfaces found {sum(r['right'] for r in faces)}/{len(faces)}; absent on "
          f"{sum(r['right'] for r in empty)}/{len(empty)} face-free photos; "
          f"{sum(r['pixels_ratio'] > 1 for r in rows)} photos over one full scan")


def groups(tasks, split, settings) -> None:
    """Print one row per composed group picture searched with ``--all``, then the totals."""
    print('| group | faces found | found near no face | last | searches | pixels / full |')
    print('|---|---|---|---|---|---|')
    rows = group_rows(tasks, split, settings)
    for r in rows:
        print(f"| {r['group']} | {r['found']}/{r['faces']} | {r['wrong']} | {r['last']} "
              f"({r['stop']}) | {r['searches']} | {r['pixels_ratio']:.2f} |")
    print(f"\nfaces found {sum(r['found'] for r in rows)}/{sum(r['faces'] for r in rows)}; "
          f"{sum(r['wrong'] for r in rows)} found near no face; 'no more' after "
          f"{sum(r['last'] == 'absent' for r in rows)}/{len(rows)} pictures")


def main() -> None:
    """Parse the options and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--split', default='all', choices=('train', 'test', 'all'))
    parser.add_argument('--groups', action='store_true')
    source = parser.add_mutually_exclusive_group()
    source.add_argument('--observation', default=None)
    source.add_argument('--detector', default=None, choices=FIND_DETECTORS)
    parser.add_argument('--absent-prior', type=float, default=FIND_SETTINGS.absent_prior)
    args = parser.parse_args()
    settings = replace(FIND_SETTINGS, absent_prior=args.absent_prior)
    tasks = find_tasks(args.detector, args.observation)
    photos(tasks, args.split, settings)
    if args.groups:
        print()
        groups(tasks, 'train' if args.split == 'train' else 'test',
               replace(settings, targets='many'))


if __name__ == '__main__':
    main()
