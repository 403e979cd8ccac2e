# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Cost per frame of the detector's ``annotated_image`` (``publish_annotated: true``).

Times :func:`ipomdp_gaze.vision.annotate.annotate` plus building the cell map, as the node does
for every frame it publishes, on the two shipped geometries: the pan/tilt camera's 320x240 view
(11x11 grid, camera mode) and a 420x420 fixed-camera image (21x21 grid, four fovea windows),
each with a spread belief, 30 fixations and 40 raw detections; the median and the 90th
percentile over ``--repeats`` frames, and the detector's own time per frame for comparison.
Usage: ``python bench/faces/annotate.py [--repeats 200]``.
"""
import argparse
import time

from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.vision.annotate import annotate, fovea_cell_map, view_cell_map
from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig
from ipomdp_gaze.vision.pan_tilt import PAN_TILT_GRID, shipped_camera
import numpy as np


def timed(fn, repeats: int) -> np.ndarray:
    """Return the milliseconds of ``repeats`` calls (after two warm-up calls)."""
    fn()
    fn()
    out = np.empty(repeats)
    for i in range(repeats):
        t0 = time.perf_counter()
        fn()
        out[i] = (time.perf_counter() - t0) * 1e3
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--repeats', type=int, default=200)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(0)
    rows = []
    camera = shipped_camera()
    grid = PAN_TILT_GRID
    view = rng.integers(0, 256, (camera.height, camera.width, 3), dtype=np.uint8)
    belief = rng.dirichlet(np.full(grid.n_cells, 0.3))
    path = rng.choice(grid.n_cells, 30, replace=False)
    dets = rng.uniform(0, [camera.width, camera.height], (40, 2))

    def camera_frame():
        cell_map = view_cell_map(grid, camera, (5.2, 4.9))
        return annotate(view, cell_map, belief, path, (), dets, (int(path[-1]), 0.5))
    rows.append(('camera mode, 320x240 view, 11x11 grid', timed(camera_frame, args.repeats)))

    grid = Grid(21, 21)
    image = rng.integers(0, 256, (420, 420), dtype=np.uint8)
    fovea = Fovea(lambda gray: np.zeros((0, 4)), (21, 21), FoveaConfig())
    windows = [(*w.rect_px, w.whole_image) for w in fovea.window_rects(220, image.shape)]
    belief = rng.dirichlet(np.full(grid.n_cells, 0.3))
    path = rng.choice(grid.n_cells, 30, replace=False)
    dets = rng.uniform(0, 420, (40, 2))

    def fovea_frame():
        cell_map = fovea_cell_map(grid, 420, 420)
        return annotate(image, cell_map, belief, path, windows, dets, (int(path[-1]), 0.5))
    rows.append(('fovea mode, 420x420 image, 21x21 grid', timed(fovea_frame, args.repeats)))
    print('| geometry | median ms | p90 ms |')
    print('|---|---|---|')
    for name, ms in rows:
        print(f'| {name} | {np.median(ms):.2f} | {np.percentile(ms, 90):.2f} |')


if __name__ == '__main__':
    main()
