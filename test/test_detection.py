# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The foveal detector's core without ROS: which image serves a fixation, and its counts."""
from ipomdp_gaze.detection import build_setup, DetectorLoop, model_camera, model_view
from ipomdp_gaze.head import PanTiltMap
from ipomdp_gaze.head_camera import observed_cells
from ipomdp_gaze.observation_file import load_observation
from ipomdp_gaze.vision.pan_tilt import (PAN_TILT_GRID, PanTiltSceneSet, SceneGeometry,
                                         shipped_camera)
from ipomdp_gaze.vision.scenes import PAPER_TASK, SceneSet
from ipomdp_gaze.vision.search import fovea_for_model
import numpy as np
import pytest

GRID = PAN_TILT_GRID
HEAD = PanTiltMap(GRID)


@pytest.fixture(scope='module')
def fovea_setup():
    return build_setup('fovea')


@pytest.fixture(scope='module')
def camera_setup():
    return build_setup('camera')


def test_the_shipped_models_say_which_view_they_were_calibrated_with():
    assert model_view(load_observation('faces-420')) == 'fixed'
    pan_tilt = load_observation('faces-pan-tilt')
    assert model_view(pan_tilt) == 'pan_tilt'
    assert model_camera(pan_tilt) == shipped_camera()
    assert pan_tilt.grid == GRID
    with pytest.raises(ValueError, match='pan/tilt camera'):
        fovea_for_model(pan_tilt)


def test_a_fixation_is_served_by_the_first_image_captured_after_it(fovea_setup):
    loop = DetectorLoop(fovea_setup)
    image = SceneSet('test', **PAPER_TASK, color='rgb', seed=2).scene(0).image
    assert loop.add_image(1.0, image).status == 'idle'               # nobody asked
    cell = fovea_setup.grid.index(10, 10)
    waiting = loop.fixate(cell, 2.0)
    assert waiting.status == 'waiting' and 'no image captured since' in waiting.reason
    assert loop.add_image(1.5, image).status == 'waiting'            # taken before it
    out = loop.add_image(2.5, image, token='stamp')
    assert out.status == 'published'
    frame = out.frame
    assert (frame.fixation, frame.stamp_s, frame.token) == (cell, 2.5, 'stamp')
    fovea = fovea_for_model(fovea_setup.model, reuse_windows=False)
    fovea.start(image)
    np.testing.assert_array_equal(frame.counts, fovea.observe(cell).counts)
    assert loop.add_image(3.0, image).status == 'idle'               # one frame per fixation
    values = loop.values()
    assert (values['images_received'], values['images_processed'], values['images_unused'],
            values['images_rejected'], values['fixations_received']) == (4, 1, 3, 0, 1)
    assert values['pixels_per_fixation_last'] == frame.detector_pixels > 0


def test_the_newest_waiting_image_serves_a_fixation(fovea_setup):
    loop = DetectorLoop(fovea_setup)
    old = SceneSet('test', **PAPER_TASK, color='rgb', seed=2).scene(0).image
    new = SceneSet('test', **PAPER_TASK, color='rgb', seed=3).scene(0).image
    loop.add_image(5.0, old)
    loop.add_image(6.0, new)
    frame = loop.fixate(3, 4.0).frame
    assert frame.stamp_s == 6.0


def test_an_image_the_detector_cannot_take_is_rejected_and_the_fixation_waits(fovea_setup):
    loop = DetectorLoop(fovea_setup)
    loop.fixate(0, 0.0)
    out = loop.add_image(1.0, np.zeros((10, 10), np.uint8))
    assert out.status == 'rejected' and 'smaller than the 20x20' in out.reason
    assert loop.pending is not None and loop.last_rejection == out.reason
    assert loop.reject('bad encoding').status == 'rejected'
    values = loop.values()
    assert (values['images_received'], values['images_rejected']) == (2, 2)
    image = SceneSet('test', **PAPER_TASK, seed=1).scene(0).image
    assert loop.add_image(2.0, image).status == 'published'


def _view(scene_seed, head_cell):
    geometry = SceneGeometry(GRID, shipped_camera())
    scene = PanTiltSceneSet('test', geometry, seed=scene_seed).scene(0)
    return scene, geometry.render(scene.image, GRID.cell(head_cell))


def test_camera_mode_needs_k_and_the_joint_state_of_the_image(camera_setup):
    loop = DetectorLoop(camera_setup, HEAD)
    scene, _ = _view(1, 0)
    target = GRID.index(*scene.cell)
    _, view = _view(1, target)                                   # the head on the face
    loop.fixate(target, 0.0)
    out = loop.add_image(1.0, view)
    assert out.status == 'waiting' and out.reason.startswith('no camera_info')
    assert loop.waiting.startswith('no camera_info')
    assert loop.set_camera(shipped_camera()) == ''
    assert 'no joint state' in loop.serve().reason
    loop.add_pose(0.9, *HEAD.angles(target))                      # another stamp
    assert 'no joint state' in loop.serve().reason
    out = loop.add_pose(1.0, *HEAD.angles(target))
    assert out.status == 'published'
    counts = out.frame.counts
    assert counts[target] == np.nanmax(counts) > 0                # the face, in its cell
    want = camera_setup.observer.observe(view, shipped_camera(), GRID.cell(target)).counts
    np.testing.assert_array_equal(counts, want)
    np.testing.assert_array_equal(~np.isnan(counts),
                                  observed_cells(shipped_camera(), GRID, GRID.cell(target)))


def test_camera_mode_waits_while_the_head_is_not_at_the_fixation(camera_setup):
    loop = DetectorLoop(camera_setup, HEAD, tolerance_s=0.01)
    loop.set_camera(shipped_camera())
    _, on_the_way = _view(2, GRID.index(5, 5))
    loop.fixate(GRID.index(2, 2), 0.0)
    loop.add_pose(1.005, *HEAD.angles(GRID.index(5, 5)))          # within the tolerance
    out = loop.add_image(1.0, on_the_way)
    assert out.status == 'waiting' and 'not yet at the fixation (2, 2)' in out.reason
    _, there = _view(2, GRID.index(2, 2))
    loop.add_pose(2.0, *HEAD.angles(GRID.index(2, 2)))
    assert loop.add_image(2.0, there).status == 'published'


def test_camera_info_of_another_camera_is_warned_about(camera_setup):
    from ipomdp_gaze.head_camera import PinholeCamera
    loop = DetectorLoop(camera_setup, HEAD)
    warning = loop.set_camera(PinholeCamera.from_fov(640, 480, 60.0))
    assert '640x480 camera with a 60.0x' in warning and 'calibrated with 320x240' in warning


@pytest.mark.parametrize('kwargs, words', [
    ({'mode': 'fovea', 'source': 'faces-pan-tilt'}, 'calibrated with a pan_tilt view'),
    ({'mode': 'camera', 'source': 'faces-420'}, 'calibrated with a fixed view'),
    ({'mode': 'fovea', 'grid': (11, 0, 0.0)}, 'grid.rows 11 contradicts'),
    ({'mode': 'camera', 'grid': (0, 0, 2.0)}, 'grid.spacing_deg 2.0 contradicts'),
    ({'mode': 'fovea', 'detector': {'scale_factor': 1.2}}, 'detector.scale_factor 1.2 contra'),
    ({'mode': 'fovea', 'detector': {'min_neighbors': 3}}, 'detector.min_neighbors 3 contra'),
    ({'mode': 'fovea', 'source': 'no-such-model'}, 'not found and not a shipped model'),
    ({'mode': 'eyes'}, 'mode must be one of fovea, camera'),
])
def test_settings_that_contradict_the_observation_file_are_refused(kwargs, words):
    with pytest.raises(ValueError, match=words):
        build_setup(**kwargs)


def test_settings_that_repeat_the_observation_file_are_accepted():
    setup = build_setup('fovea', 'faces-420', (21, 21, 0.0),
                        {'scale_factor': 1.1, 'min_neighbors': 0,
                         'cascade': 'haarcascade_frontalface_alt2.xml'})
    assert setup.grid.shape == (21, 21) and setup.fovea is not None
    assert build_setup('camera', grid=(11, 11, 5.0)).observer is not None


def test_another_opencv_version_is_a_note_and_another_cascade_is_refused(tmp_path):
    from ipomdp_gaze.observation_file import load_observation, save_observation
    model = load_observation('faces-420-nmpt')
    model.meta['detector'] = {**model.meta['detector'], 'opencv': '4.5.0'}
    path = save_observation(tmp_path / 'old.yaml', model)
    setup = build_setup('fovea', str(path))
    assert len(setup.notes) == 1 and "detector opencv '4.5.0'" in setup.notes[0]
    model.meta['detector']['cascade_sha256'] = '0' * 64
    path = save_observation(tmp_path / 'other.yaml', model)
    with pytest.raises(ValueError, match='differs from the one the observation model'):
        build_setup('fovea', str(path))
