# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Detector cost of the digital fovea against full-frame scans, on a real photo with a real face.

Run: ``.venv/bin/python bench/simulation/bench_fovea.py [--quick] [--size 420] [--threads N]
[--json OUT]``.

The image is scikit-image's ``astronaut`` resized to ``size x size`` grey (``cv2.INTER_AREA``);
the detector is the reference ``HaarDetector`` (alt2, 1.1, minNeighbors=0) on a 21x21 grid.
Measured, as medians over repetitions (``time.perf_counter``, wall time):

- the full-frame scan at scales 1, 3/4, 1/2, 1/3: detector pixels, seconds (grey conversion,
  resize, detector, grouping, binning) and the cells found (NMPT's and OpenCV's rule);
- the reference fovea: one fixation *including* the whole-image window (``start`` plus the
  first fixation of an image) and one fixation *excluding* it (later fixations, over random
  cells), with the interpolations ``area`` (the default) and ``nearest`` (NMPT's), and what the
  fovea fixated on the face cell counts there.

OpenCV parallelises ``detectMultiScale`` over ``cv2.getNumThreads()`` threads; ``--threads``
sets that number for the whole run (both methods alike).
"""
import argparse
import json
from pathlib import Path
import time

import cv2
from ipomdp_gaze.commands.common import nonneg_int, parse_with_outputs
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.vision.detectors import make_detector
from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig
from ipomdp_gaze.vision.fullframe import scan
import numpy as np
from skimage import data

GRID = Grid(21, 21)
SCALES = (1.0, 0.75, 0.5, 1 / 3)
FACE_PX_512 = (225.0, 115.0)           # the astronaut's face centre on the 512x512 original


def astronaut_gray(size_px: int) -> tuple[np.ndarray, int]:
    """Return the astronaut as ``size x size`` grey and the row-major cell of her face centre."""
    gray = cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2GRAY)
    gray = cv2.resize(gray, (size_px, size_px), interpolation=cv2.INTER_AREA)
    x, y = (v * size_px / 512 for v in FACE_PX_512)
    return gray, GRID.index(int(y * GRID.rows // size_px), int(x * GRID.cols // size_px))


def bench_scans(gray, detector, repeats):
    """Median seconds, pixels and answers of the full-frame scan at each scale."""
    rows = []
    for scale in SCALES:
        results = [scan(gray, detector, GRID, scale) for _ in range(repeats)]
        last = results[-1]
        rows.append({'scale': round(scale, 4), 'detector_pixels': last.detector_pixels,
                     'seconds': float(np.median([r.seconds for r in results])),
                     'raw_detections': int(last.counts.sum()), 'cell': last.cell,
                     'grouped_cell': last.grouped_cell})
    return rows


def bench_fovea(gray, detector, face, interpolation, repeats, rng):
    """Median cost of a fixation with and without the whole-image window, and the face view."""
    fovea = Fovea(detector, GRID, FoveaConfig(interpolation=interpolation))
    first, later, first_pixels, later_pixels = [], [], set(), set()
    for _ in range(repeats):
        t0 = time.perf_counter()
        fovea.start(gray)
        observation = fovea.observe(int(rng.integers(GRID.n_cells)))
        first.append(time.perf_counter() - t0)
        first_pixels.add(observation.detector_pixels)
        for fixation in rng.integers(GRID.n_cells, size=5):
            observation = fovea.observe(int(fixation))
            later.append(observation.seconds)
            later_pixels.add(observation.detector_pixels)
    fovea.start(gray)
    at_face = fovea.observe(face)
    per_window = np.bincount(at_face.window_index, minlength=len(at_face.windows))
    return {'interpolation': interpolation,
            'with_whole_image': {'seconds': float(np.median(first)),
                                 'detector_pixels': sorted(first_pixels)},
            'without_whole_image': {'seconds': float(np.median(later)),
                                    'detector_pixels': sorted(later_pixels)},
            'windows_px': [list(w.resized_px) for w in at_face.windows],
            'at_face': {'count_at_face': float(at_face.counts[face]),
                        'best_cell': int(np.nanargmax(at_face.counts)),
                        'raw_detections_per_window': per_window.tolist()}}


def image_side(text: str) -> int:
    """Parse ``--size``: at least a pixel per cell of the grid (the detector needs 20x20)."""
    try:
        side = int(text)
    except ValueError:
        side = 0
    if side < GRID.cols:
        raise argparse.ArgumentTypeError(f'expected an integer >= {GRID.cols} (a pixel per cell '
                                         f'of the {GRID.rows}x{GRID.cols} grid), got {text!r}')
    return side


def main(argv=None):
    """Run the benchmark and print (and optionally save) the numbers."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--quick', action='store_true', help='fewer repetitions')
    parser.add_argument('--size', type=image_side, default=420, help='image side in pixels')
    parser.add_argument('--threads', type=nonneg_int, default=None,
                        help='cv2.setNumThreads(N) (0: no threads)')
    parser.add_argument('--json', type=Path, default=None, metavar='OUT')
    args = parse_with_outputs(parser, argv, json='--json')
    if args.threads is not None:
        cv2.setNumThreads(args.threads)
    repeats = 5 if args.quick else 30
    gray, face = astronaut_gray(args.size)
    detector = make_detector('haar')
    rng = np.random.default_rng(0)
    report = {'image_px': [args.size, args.size], 'grid': list(GRID.shape), 'face_cell': face,
              'threads': cv2.getNumThreads(), 'opencv': cv2.__version__,
              'detector': detector.settings(), 'repeats': repeats,
              'full_frame': bench_scans(gray, detector, repeats),
              'fovea': [bench_fovea(gray, detector, face, name, repeats, rng)
                        for name in ('area', 'nearest')]}
    full = report['full_frame'][0]
    print(f'astronaut {args.size}x{args.size} grey, face cell {GRID.cell(face)}, '
          f'{report["threads"]} OpenCV threads, medians of {repeats}')
    for row in report['full_frame']:
        print(f'  full frame x{row["scale"]:.3f}: {row["detector_pixels"]:7d} px '
              f'{1e3 * row["seconds"]:7.2f} ms  raw {row["raw_detections"]:3d}  '
              f'NMPT cell {row["cell"] and GRID.cell(row["cell"])}  '
              f'grouped cell {row["grouped_cell"] and GRID.cell(row["grouped_cell"])}')
    for row in report['fovea']:
        with_whole, without = row['with_whole_image'], row['without_whole_image']
        print(f'  fovea ({row["interpolation"]}): with whole-image window '
              f'{with_whole["detector_pixels"]} px {1e3 * with_whole["seconds"]:.2f} ms; '
              f'without {without["detector_pixels"]} px {1e3 * without["seconds"]:.2f} ms '
              f'({without["seconds"] / full["seconds"]:.3f} of a full scan); at the face '
              f'{row["at_face"]}')
    if args.json:
        args.json.write_text(json.dumps(report, indent=2))
    return report


if __name__ == '__main__':
    main()
