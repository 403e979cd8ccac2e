# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``find`` without ``--all`` on the face scenes: the coarse pass first against the fovea and scans.

For each scene task (faces-420, faces-840) and detector (Haar, YuNet), on the same scenes in one
process (sequential, so the wall times compare): ``find --scan coarse`` (the default: one
full-frame call at the scale the detector's table chooses, then the fovea only where cells stay
undecided, :func:`ipomdp_gaze.vision.search.search_first`), ``find --scan fovea`` (the paper's
single-target belief after the fovea's scan, find before), both with ``find``'s own settings and
models (``search_one``), the same with the task's smallest face given (``--min-face``), and the
detector alone on the full frame at 1, 0.75, 0.5 and 1/3, YuNet also enlarged 2x and 1.5x (Haar:
the cell with the most raw detections; YuNet: the best-scoring box, as docs/faces.md's tables).
A find answer is right when it says ``found`` within one cell (Chebyshev) of the face.

Usage: ``python bench/faces/find_scale.py --split train --scenes 80 [--seed 1] [--tasks
paper,small] [--detectors haar,yunet] [--json OUT]``. The training split (seed 1) informs
choices; the test split (seed 0) is for the report only.
"""
import argparse
import json
from pathlib import Path
import sys
import time
from types import SimpleNamespace

import cv2
from ipomdp_gaze.commands.find import _Tasks, ladder_start, scale_table, SCAN_CHOICES, search_one
from ipomdp_gaze.simulation.evaluation import cells_apart, wilson_interval
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.photos import load_photo, read_labels
from ipomdp_gaze.vision.scenes import SceneSet
from ipomdp_gaze.vision.search import FIND_SETTINGS, search_scales
import numpy as np
import skimage.data

sys.path.insert(0, str(Path(__file__).resolve().parent))
from faces import best_score_cell, TASKS  # noqa: E402, I100
import find_photos  # noqa: E402, I100

SCALES = (1.0, 0.75, 0.5, 1 / 3)
# YuNet sees faces from 48 px at full resolution (its scale table): the frame enlarged too
UPSCALES = (2.0, 1.5)
# --looks: the enlarged look at a weak finest-scale box (search_scales), as (label, options):
# without it (nor the faint look), and at other bounds and scores than the shipped: the box at
# 128 px, resized at most 2x (at least 1/2), a box of 0.6; the faint look at a faint small box
# when nothing answered: without it, and at other look scores than the shipped 0.8
LOOKS = (('no enlarged look', {'look_upscale': 0}),
         ('no faint look', {'faint_score': 0}),
         ('faint look at 0.6', {'faint_look_score': 0.6}),
         ('faint look at 0.7', {'faint_look_score': 0.7}),
         ('look at most 1.5x, at 0.5', {'look_upscale': 1.5, 'look_score': 0.5}),
         ('look at most 2x, at 0.5', {'look_upscale': 2.0, 'look_score': 0.5}),
         ('look at most 2x, at 0.6 (shipped)', {'look_upscale': 2.0, 'look_score': 0.6}),
         ('look at most 2x, at 0.7', {'look_upscale': 2.0, 'look_score': 0.7}),
         ('look at most 3x, at 0.5', {'look_upscale': 3.0, 'look_score': 0.5}),
         ('look at most 3x, at 0.7', {'look_upscale': 3.0, 'look_score': 0.7}))
# --augmented: face-free images to choose the look on (training only): the face-free training
# photos and three photos of no split, each at these sizes, 4 rotations, and mirrored
AUGMENT_PHOTOS = ('horse', 'logo', 'colorwheel')
AUGMENT_SIZES = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0)
NAMES = {'haar': 'Haar', 'yunet': 'YuNet'}


def run(task: str, detector: str, split: str, n: int, seed: int, starts=(), looks=()) -> dict:
    """Return each method's rows on ``n`` scenes of ``split``: right, seconds, pixels."""
    _, size, faces = TASKS[task]
    tasks = _Tasks(SimpleNamespace(observation=None, detector=detector, policy=None,
                                   policy_file=None))
    find = tasks.task((size, size))
    grid = find.model.grid
    scenes = SceneSet(split, size_px=size, face_px=faces, grid=grid.shape, seed=seed)
    settings = FIND_SETTINGS
    table = scale_table(find.model)
    rows = {}

    def add(label, right, seconds, pixels, fixations=0):
        row = rows.setdefault(label, {'right': [], 'seconds': [], 'pixels': [],
                                      'fixations': []})
        row['right'].append(bool(right))
        row['seconds'].append(seconds)
        row['pixels'].append(pixels)
        row['fixations'].append(fixations)
    for i in range(n):
        scene = scenes[i]
        for mode in SCAN_CHOICES:
            t0 = time.perf_counter()
            result = search_one(scene.image, find, settings, np.random.default_rng([seed, i]),
                                False, scan=mode)[0]
            seconds = time.perf_counter() - t0
            right = result.decision == 'found' and cells_apart(result.cell, scene.cell) <= 1
            add(f'find --scan {mode}', right, seconds, result.detector_pixels,
                result.fixations)
        # the task's smallest face given, as a user who knows it would (--min-face)
        t0 = time.perf_counter()
        result = search_one(scene.image, find, settings, np.random.default_rng([seed, i]), False,
                            min_face=faces[0], scan='coarse')[0]
        right = result.decision == 'found' and cells_apart(result.cell, scene.cell) <= 1
        add(f'find --scan coarse --min-face {faces[0]}', right, time.perf_counter() - t0,
            result.detector_pixels)
        for start in starts:
            t0 = time.perf_counter()
            result = search_scales(scene.image, find.fovea, find.model, table, start=start)
            seconds = time.perf_counter() - t0
            right = result.decision == 'found' and cells_apart(result.cell, scene.cell) <= 1
            add(f'find --scan coarse from x{start:.2g}', right, seconds,
                result.detector_pixels)
        for label, options in (looks if table.strong_score > 0 else ()):   # scores only
            t0 = time.perf_counter()
            result = search_scales(scene.image, find.fovea, find.model, table,
                                   start=ladder_start(find.model, table), **options)
            seconds = time.perf_counter() - t0
            right = result.decision == 'found' and cells_apart(result.cell, scene.cell) <= 1
            add(f'find --scan coarse, {label}', right, seconds, result.detector_pixels)
        for scale in SCALES + (UPSCALES if detector == 'yunet' else ()):
            found = scan(scene.image, find.fovea.detector, grid, scale=scale)
            if detector == 'yunet':
                cell = best_score_cell(found, scene.image.shape[:2], grid)
            else:
                cell = None if found.cell is None else tuple(grid.cell(found.cell))
            right = cell is not None and cells_apart(cell, scene.cell) <= 1
            add(f'full frame x{scale:.2g}', right, found.seconds, found.detector_pixels)
    out = []
    for label, row in rows.items():
        hits = int(np.sum(row['right']))
        out.append({'label': label, 'right': hits / n, 'ci': wilson_interval(hits, n),
                    'median_ms': 1e3 * float(np.median(row['seconds'])),
                    'mean_ms': 1e3 * float(np.mean(row['seconds'])),
                    'pixels': float(np.mean(row['pixels'])),
                    'fixations': float(np.mean(row['fixations']))})
    return {'task': task, 'model': find.model.meta.get('source', ''), 'size': size,
            'detector': detector, 'split': split, 'n': n, 'seed': seed, 'rows': out}


def table(result: dict) -> list[str]:
    """Return the markdown rows of one task and detector."""
    lines = [f"#### {NAMES[result['detector']]}, {result['size']}x{result['size']} "
             f"({result['n']} {result['split']} scenes, seed {result['seed']})", '',
             '| method | right [95% CI] | median ms | mean ms | detector pixels | fixations |',
             '|---|---|---|---|---|---|']
    for r in result['rows']:
        lo, hi = r['ci']
        lines.append(f"| {r['label']} | {r['right']:.3f} [{lo:.3f}, {hi:.3f}] | "
                     f"{r['median_ms']:.1f} | {r['mean_ms']:.1f} | {r['pixels']:,.0f} | "
                     f"{r['fixations']:.1f} |")
    return lines + ['']


def photo_table(split: str, detectors, scans) -> list[str]:
    """Return ``find --scan`` on the real photos of ``split``: one row per detector and scan."""
    lines = [f'#### `find` without `--all` on the {split} photos', '',
             '| detector | scan | faces found | face-free: absent | px / full (mean, max) | '
             'median ms | mean ms |', '|---|---|---|---|---|---|---|']
    for detector in detectors:
        tasks = find_photos.find_tasks(detector)
        for mode in scans:
            rows = find_photos.photo_rows(tasks, split, FIND_SETTINGS, scan=mode)
            faces = [r for r in rows if r['face']]
            empty = [r for r in rows if not r['face']]
            ratios = [r['pixels_ratio'] for r in rows]
            ms = [1e3 * r['seconds'] for r in rows]
            lines.append(f'| {NAMES[detector]} | {mode} | '
                         f"{sum(r['right'] for r in faces)}/{len(faces)} | "
                         f"{sum(r['right'] for r in empty)}/{len(empty)} | "
                         f'{np.mean(ratios):.2f}, {np.max(ratios):.2f} | '
                         f'{np.median(ms):.0f} | {np.mean(ms):.0f} |')
            for r in rows:
                if not r['right']:
                    lines.append(f"|  | (wrong: {r['photo']}: {r['decision']}) | | | | | |")
    return lines + ['']


def augmented_images():
    """Yield ``(label, image)``: the face-free training photos and AUGMENT_PHOTOS, augmented."""
    labels = read_labels()
    names = [name for name, (boxes, split) in labels.items()
             if split == 'train' and not len(boxes)] + list(AUGMENT_PHOTOS)
    for name in names:
        image = load_photo(name) if name in labels else getattr(skimage.data, name)()
        if image.dtype == bool:
            image = image.astype(np.uint8) * 255
        image = image[..., :3] if image.ndim == 3 else image
        for factor in AUGMENT_SIZES:
            sized = cv2.resize(image, None, fx=factor, fy=factor,
                               interpolation=cv2.INTER_AREA if factor < 1 else cv2.INTER_LINEAR)
            for turns in range(4):
                for mirror in (False, True):
                    turned = np.rot90(sized, turns)
                    yield (f'{name} x{factor:g} rot{90 * turns}{" mirrored" * mirror}',
                           np.ascontiguousarray(turned[:, ::-1] if mirror else turned))


def augmented_table(detector: str) -> list[str]:
    """Return ``--scan coarse`` with each enlarged look (LOOKS) on the augmented face-free set."""
    tasks = find_photos.find_tasks(detector)
    answered = {label: [] for label, _ in LOOKS}
    pixels = {label: [] for label in answered}
    n = 0
    for name, image in augmented_images():
        find = tasks.task((image.shape[1], image.shape[0]))
        table = scale_table(find.model)
        start = ladder_start(find.model, table)
        n += 1
        for label, options in LOOKS:
            result = search_scales(image, find.fovea, find.model, table, start=start, **options)
            if result.decision == 'found':
                answered[label].append(name)
            pixels[label].append(result.detector_pixels / (image.shape[0] * image.shape[1]))
    lines = [f'##### {NAMES[detector]}, face-free training photos augmented ({n} images: '
             f'{len(AUGMENT_SIZES)} sizes, 4 rotations, mirrored)', '',
             '| `--scan coarse` | face-free images answered `found` | px / full (mean) |',
             '|---|---|---|']
    for label in answered:
        lines.append(f'| {label} | {len(answered[label])} of {n} | '
                     f'{np.mean(pixels[label]):.3f} |')
    return lines + ['']


def main(argv=None) -> int:
    """Run the tasks and print (and optionally write) the tables."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--split', default='train', choices=('train', 'test'))
    parser.add_argument('--scenes', type=int, default=80)
    parser.add_argument('--seed', type=int, default=None,
                        help='scene seed (default: 1 for train, 0 for test)')
    parser.add_argument('--tasks', default='paper,small')
    parser.add_argument('--detectors', default='haar,yunet')
    parser.add_argument('--json', type=Path, default=None)
    parser.add_argument('--photos', action='store_true',
                        help='also find on the real photos of the split (every --scan)')
    parser.add_argument('--no-scenes', action='store_true')
    parser.add_argument('--starts', default='',
                        help='also --scan coarse from each of these first scales (e.g. '
                             '0.25,0.3333,0.5): the choice of its start')
    parser.add_argument('--looks', action='store_true',
                        help='also --scan coarse with each enlarged look of LOOKS')
    parser.add_argument('--augmented', action='store_true',
                        help='--scan coarse with each enlarged look on the face-free training '
                             'photos augmented (training only)')
    args = parser.parse_args(argv)
    seed = args.seed if args.seed is not None else (1 if args.split == 'train' else 0)
    results = []
    if args.augmented:
        for detector in args.detectors.split(','):
            print('\n'.join(augmented_table(detector)), flush=True)
    if args.photos:
        print('\n'.join(photo_table(args.split, args.detectors.split(','), SCAN_CHOICES)),
              flush=True)
    for task in ([] if args.no_scenes else args.tasks.split(',')):
        for detector in args.detectors.split(','):
            starts = [float(v) for v in args.starts.split(',') if v]
            result = run(task, detector, args.split, args.scenes, seed, starts,
                         LOOKS if args.looks else ())
            results.append(result)
            print('\n'.join(table(result)), flush=True)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
