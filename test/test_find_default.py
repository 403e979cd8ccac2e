# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze find IMAGE... --observation faces-420`` end to end on the scene task's model.

``find``'s default is YuNet's model, chosen for real photographs (test/test_find_photos.py runs
it with every default); the scene set's upscaled grey thumbnails are the Haar cascade's, so this
names the scene task's ``faces-420`` count model (calibrated at the images' 420x420 px, with its
one-time whole-image scan): ``find`` must use the shipped kernel trained on it, with every other
setting left at its default (the absent hypothesis included) but ``--scan fovea`` (the default
coarse scan has no policy: test/test_find_scan.py), and find the face of held-out test scenes
within one cell of its centre's cell. The scenes are
the first test scenes whose face OpenCV's full-frame scan finds (a choice that depends on the
detector only, never on the model or on ``find``).
"""
import json
import subprocess
import sys

import cv2
from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.vision.detector import HaarDetector
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.scenes import SceneSet
import numpy as np

GRID = Grid(21, 21)
SCENES = 3


def _scenes():
    detector, test = HaarDetector(), SceneSet('test', seed=0, size_px=420, face_px=(60, 140),
                                              grid=(21, 21))
    chosen = []
    for index in range(30):
        scene = test[index]
        found = scan(scene.image, detector, GRID).cell
        if found is not None and max(np.abs(np.subtract(GRID.cell(found), scene.cell))) <= 1:
            chosen.append(scene)
        if len(chosen) == SCENES:
            return chosen
    raise AssertionError('fewer than 3 of 30 test scenes have a face the full frame finds')


def test_find_with_every_default_finds_the_faces(tmp_path):
    model = load_observation('faces-420')
    assert model.has_scan and model.grid.shape == GRID.shape
    scenes = _scenes()
    paths = []
    for i, scene in enumerate(scenes):
        image = scene.image if scene.image.ndim == 2 else cv2.cvtColor(scene.image,
                                                                       cv2.COLOR_RGB2BGR)
        paths.append(tmp_path / f'scene{i}.png')
        cv2.imwrite(str(paths[-1]), image)
    out = tmp_path / 'found.json'
    run = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'find', *map(str, paths),
                          '--json', str(out), '--observation', 'faces-420', '--scan',
                          'fovea'],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert 'observation model faces-420 (21x21 grid, calibrated at 420x420 px)' \
        in run.stderr, run.stderr
    assert 'shipped kernel faces-420-infomax (argmax)' in run.stderr, run.stderr
    lines = run.stdout.strip().splitlines()
    assert [line.split(': ')[0] for line in lines] == [str(p) for p in paths]
    entries = json.loads(out.read_text())['images']
    for entry, scene in zip(entries, scenes):
        assert max(abs(entry['cell'][0] - scene.cell[0]),
                   abs(entry['cell'][1] - scene.cell[1])) <= 1, (entry, scene.cell)
        assert entry['stop'] == 'found' and entry['probability'] >= 0.9
        assert 1 <= entry['fixations'] and 0 < entry['detector_pixels'] < 420 * 420
