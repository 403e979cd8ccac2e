# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Haar against YuNet: time per frame and faces found, on pan/tilt views and real photographs.

One thread for OpenCV (``cv2.setNumThreads(1)``), every detector on the whole image at full
resolution, nothing fitted here:

- **pan/tilt views**: 320x240 views of test pan/tilt scenes (test faces and backgrounds), the
  head at the face's cell; a face counts as found when a raw detection's centre lies in the
  face's cell, and every view's raw detections elsewhere are false alarms;
- **real photos** (:mod:`ipomdp_gaze.vision.photos`): each labelled photo and the composed group
  pictures; a labelled face counts as found when the centre of an answer lies in its box, and
  an answer centred in no face box is a false alarm. The answer is OpenCV's grouped detections
  (``minNeighbors=3``) for Haar and YuNet's own boxes (after its non-maximum suppression, score
  at least the detector's ``score_threshold``, 0.5).

- **pan/tilt search** (offline, the search session and
  :func:`ipomdp_gaze.search.sensors.run_search`
  without ROS): each detector with its own pan/tilt model (``faces-pan-tilt``,
  ``faces-pan-tilt-yunet``), ELM with inhibition of return from the centre cell, repeated views
  weighted 0.1 (:class:`ipomdp_gaze.model.still_evidence.StillEvidence`), stop at 0.99 or after 60
  fixations; right = the answer within one cell of the face's cell
  (:func:`ipomdp_gaze.simulation.evaluation.answer_is_right`); seconds = detector and belief
  updates (the
  saccades of a real head are not included).

Usage: ``python bench/faces/detectors.py [--views 40] [--searches 40] [--repeat 3]
[--out docs/data/detectors.json]``.
"""
import argparse
import json
from pathlib import Path
import platform
import time

import cv2
from ipomdp_gaze.vision.detectors import make_detector
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, shipped_camera, ViewObserver
from ipomdp_gaze.vision.photos import group_photo, GROUP_SIZES, real_photos
import numpy as np

DETECTORS = ('haar', 'yunet')


def time_call(fn, repeat: int) -> tuple:
    """Return ``fn()``'s result and its median wall seconds over ``repeat`` calls."""
    seconds = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        seconds.append(time.perf_counter() - t0)
    return out, float(np.median(seconds))


def views(detector, n: int, repeat: int) -> dict:
    """Time and hits of ``detector`` on ``n`` test views with the head at the face's cell."""
    from ipomdp_gaze.vision.pan_tilt import PAN_TILT_GRID, SceneGeometry
    geometry = SceneGeometry(PAN_TILT_GRID, shipped_camera())
    scenes = PanTiltSceneSet('test', geometry, seed=0)
    observer = ViewObserver(detector, PAN_TILT_GRID, 10)
    hits, false_alarms, seconds = 0, 0, []
    for i in range(n):
        scene = scenes.scene(i)
        view = geometry.render(scene.image, scene.cell)
        obs, sec = time_call(lambda: observer.observe(view, geometry.camera, scene.cell), repeat)
        seconds.append(sec)
        target = PAN_TILT_GRID.index(*scene.cell)
        hits += int(obs.raw_counts[target] > 0)
        false_alarms += int(obs.raw_counts.sum() - obs.raw_counts[target])
    return {'views': n, 'found': hits, 'raw_false_alarms': false_alarms,
            'ms_per_view_median': round(1e3 * float(np.median(seconds)), 2)}


def photo_answer(detector, image, boxes, repeat: int) -> dict:
    """Full-frame answer on one photo: faces found, false alarms, milliseconds."""
    result, sec = time_call(lambda: scan(image, detector, (21, 21)), repeat)
    answers = result.grouped_px
    centres = answers[:, :2] + answers[:, 2:] / 2
    inside = np.array([[x <= cx < x + w and y <= cy < y + h for x, y, w, h in boxes]
                       for cx, cy in centres]).reshape(len(centres), len(boxes))
    return {'faces': int(len(boxes)), 'found': int(inside.any(axis=0).sum()),
            'false_alarms': int((~inside.any(axis=1)).sum()), 'ms': round(1e3 * sec, 1),
            'size': [int(image.shape[1]), int(image.shape[0])]}


def pan_tilt_searches(kind: str, model_name: str, n: int) -> dict:
    """Search ``n`` test pan/tilt scenes offline with ``kind`` and its pan/tilt model."""
    from ipomdp_gaze.files.observation_file import load_observation
    from ipomdp_gaze.model.cell_observation import cell_observation_of
    from ipomdp_gaze.policies.registry import build_policy
    from ipomdp_gaze.search.sensors import run_search
    from ipomdp_gaze.search.session import SearchSession, SearchSettings
    from ipomdp_gaze.simulation.evaluation import answer_is_right
    from ipomdp_gaze.vision.detectors import detector_from_settings
    from ipomdp_gaze.vision.pan_tilt import SceneGeometry
    from ipomdp_gaze.vision.sensors import PanTiltSensor
    model = load_observation(model_name)
    grid = model.grid
    detector = detector_from_settings(dict(model.meta['detector']))
    assert detector_settings_kind(detector) == kind
    k = model.max_count + 1
    observer = ViewObserver(detector, grid, k, cell_observation_of(model.meta, k))
    geometry = SceneGeometry(grid, shipped_camera())
    scenes = PanTiltSceneSet('test', geometry, seed=0)
    sensor = PanTiltSensor(observer, geometry)
    settings = SearchSettings(confidence=0.99, max_fixations=60, inhibit_return=True,
                              repeat_weight=0.1)
    session = SearchSession(grid, model, build_policy('elm', grid, model), settings)
    right, fixations, found, seconds = 0, [], 0, []
    for i in range(n):
        scene = scenes.scene(i)
        outcome = run_search(session, sensor, scene.image, seed=0)
        right += int(answer_is_right(grid.cell(outcome.cell), scene.cell))
        found += int(outcome.decision == 'found')
        fixations.append(outcome.fixations)
        seconds.append(outcome.seconds)
    return {'model': model_name, 'searches': n, 'right': right, 'found': found,
            'fixations_mean': round(float(np.mean(fixations)), 2),
            'seconds_median': round(float(np.median(seconds)), 3)}


def detector_settings_kind(detector) -> str:
    """Return the kind a detector records."""
    from ipomdp_gaze.vision.detector import detector_settings
    return detector_settings(detector)['kind']


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--views', type=int, default=40)
    parser.add_argument('--repeat', type=int, default=3)
    parser.add_argument('--searches', type=int, default=40)
    parser.add_argument('--out', type=Path, default=Path('docs/data/detectors.json'))
    args = parser.parse_args()
    cv2.setNumThreads(1)
    out = {'opencv': cv2.__version__, 'machine': platform.machine(), 'threads': 1,
           'views': {}, 'photos': {}, 'pan_tilt_search': {}}
    pictures = [(p.name, p.split, p.image, p.boxes) for p in real_photos()]
    pictures += [(f'group-{w}x{h}', 'test', *group_photo((w, h), seed=0))
                 for w, h in GROUP_SIZES]
    for kind in DETECTORS:
        detector = make_detector(kind)
        out['views'][kind] = views(detector, args.views, args.repeat)
        print(kind, 'views', out['views'][kind], flush=True)
        out['photos'][kind] = {}
        for name, split, image, boxes in pictures:
            row = photo_answer(detector, image, boxes, args.repeat)
            row['split'] = split
            out['photos'][kind][name] = row
            print(kind, name, row, flush=True)
    for kind, model in (('haar', 'faces-pan-tilt'), ('yunet', 'faces-pan-tilt-yunet')):
        out['pan_tilt_search'][kind] = pan_tilt_searches(kind, model, args.searches)
        print(kind, 'pan/tilt search', out['pan_tilt_search'][kind], flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=1) + '\n')
    print(f'wrote {args.out}')


if __name__ == '__main__':
    main()
