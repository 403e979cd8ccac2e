# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The foveal detector's core without ROS: which image serves a fixation, and its counts."""
from pathlib import Path

from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.head_camera import observed_cells
from ipomdp_gaze.vision.detection import build_setup, DetectorLoop, model_camera, model_view
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


def test_the_shipped_camera_model_counts_the_frontal_and_the_profile_cascade(camera_setup):
    assert camera_setup.name == 'faces-pan-tilt-profile'
    detector = camera_setup.detector
    assert detector.cascade_names == ['haarcascade_frontalface_alt2.xml',
                                      'haarcascade_profileface.xml']
    assert detector.mirror == [False, True]
    assert model_camera(camera_setup.model) == shipped_camera()
    assert camera_setup.grid == GRID


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


def test_a_resent_fixation_keeps_waiting_from_the_first_command(fovea_setup):
    loop = DetectorLoop(fovea_setup)
    image = SceneSet('test', **PAPER_TASK, color='rgb', seed=2).scene(0).image
    cell = fovea_setup.grid.index(10, 10)
    assert loop.fixate(cell, 2.0, search_id=4).status == 'waiting'
    assert loop.fixate(cell, 3.0, search_id=4).status == 'waiting'       # re-sent at 3.0
    out = loop.add_image(2.5, image)              # the slow head's image, taken before 3.0
    assert out.status == 'published' and out.frame.stamp_s == 2.5
    # Another cell, or a new search, starts a new wait.
    assert loop.fixate(cell + 1, 4.0, search_id=4).status == 'waiting'
    assert loop.fixate(cell + 1, 5.0, search_id=5).status == 'waiting'
    assert loop.add_image(4.5, image).status == 'waiting'
    assert loop.add_image(5.5, image).status == 'published'
    # Served, the same command again wants a new image (the controller lost the frame).
    assert loop.fixate(cell + 1, 6.0, search_id=5).status == 'waiting'
    assert loop.values()['fixations_received'] == 5


def test_a_fixation_resent_on_a_clock_set_back_waits_from_the_new_time(fovea_setup):
    """Review: after /clock jumped back the wait kept the old time, and no image served it."""
    loop = DetectorLoop(fovea_setup)
    image = SceneSet('test', **PAPER_TASK, color='rgb', seed=2).scene(0).image
    cell = fovea_setup.grid.index(10, 10)
    assert loop.fixate(cell, 2002.0, search_id=1).status == 'waiting'
    assert loop.add_image(2001.0, image, now_s=2002.0).status == 'waiting'   # before the command
    # The clock set back to 100: the controller re-sends the same fixation of the same search.
    assert loop.fixate(cell, 101.0, search_id=1).status == 'waiting'
    out = loop.add_image(101.5, image, now_s=101.5)
    assert out.status == 'published' and out.frame.stamp_s == 101.5


def test_a_scan_asked_again_on_a_clock_set_back_is_not_served_an_old_image(fovea_setup):
    """Review: the set-back rule of fixate was missing from request_scan."""
    loop = DetectorLoop(fovea_setup)
    image = SceneSet('test', **PAPER_TASK, color='rgb', seed=2).scene(0).image
    assert loop.fixate(fovea_setup.grid.index(10, 10), 2002.0, search_id=1).status == 'waiting'
    assert loop.add_image(2001.9, image, token='old', now_s=2002.0).status == 'waiting'
    waiting = loop.request_scan(2, 101.0)
    assert waiting.status == 'waiting', waiting
    out = loop.add_image(101.5, image, token='new', now_s=101.5)
    assert out.status == 'published' and out.frame.token == 'new'


def test_a_resent_scan_request_keeps_waiting_from_the_first_request(fovea_setup):
    """QA: a re-send restarted the scan's wait, so images slower than re-sends never served."""
    loop = DetectorLoop(fovea_setup)
    image = SceneSet('test', **PAPER_TASK, color='rgb', seed=2).scene(0).image
    assert loop.request_scan(7, 2.0).status == 'waiting'
    assert loop.request_scan(7, 3.0).status == 'waiting'         # re-sent after retry_period_s
    assert loop.waited_s(4.5) == 2.5                             # what the stuck warning reads
    out = loop.add_image(2.5, image, token='late', now_s=3.6)    # taken after the request
    assert out.status == 'published', out
    assert (out.frame.kind, out.frame.token, out.frame.search_id) == ('scan', 'late', 7)
    # Served, the same request again (its frame lost) wants a new image; so does a new search.
    assert loop.request_scan(7, 5.0).status == 'waiting'
    assert loop.add_image(4.8, image, now_s=5.1).status == 'waiting'
    assert loop.request_scan(8, 6.0).status == 'waiting'
    assert loop.add_image(5.5, image, now_s=6.1).status == 'waiting'
    out = loop.add_image(6.2, image, token='new', now_s=6.3)
    assert out.status == 'published' and (out.frame.token, out.frame.search_id) == ('new', 8)


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
    out = loop.set_camera(shipped_camera())
    assert loop.mismatch == '' and 'no joint state' in out.reason
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
    from ipomdp_gaze.model.head_camera import PinholeCamera
    loop = DetectorLoop(camera_setup, HEAD)
    loop.set_camera(PinholeCamera.from_fov(640, 480, 60.0))
    warning = loop.mismatch
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
    # an ensemble's members as calibrate was given them (the file fills in defaults and
    # fingerprints): the same detector, accepted; one member fewer is not
    members = [{'kind': 'haar', 'cascade': ['haarcascade_frontalface_alt2.xml',
                                            'haarcascade_profileface.xml'],
                'mirror': [False, True]}, {'kind': 'yunet', 'upscale': 2, 'weight': 5}]
    assert build_setup('camera', 'faces-pan-tilt-ensemble',
                       detector={'kind': 'ensemble', 'members': members}).observer is not None
    with pytest.raises(ValueError, match='detector.members .* contradicts'):
        build_setup('camera', 'faces-pan-tilt-ensemble', detector={'members': members[:1]})


def test_a_cascade_dir_without_the_cascades_is_refused_naming_the_folder_and_the_file(tmp_path):
    """A folder missing, or without a cascade, fell back to OpenCV's cascades unnoticed."""
    import cv2
    frontal, profile = 'haarcascade_frontalface_alt2.xml', 'haarcascade_profileface.xml'
    missing = tmp_path / 'cascades'
    for mode, source, folder, message in (
            ('fovea', 'faces-420', missing, f'detector.cascade_dir {missing} does not exist (it '
                                            f'was to hold {frontal})'),
            ('fovea', 'faces-420', tmp_path, f'detector.cascade_dir {tmp_path} has no {frontal} '
                                             "(a cascade of observation.file 'faces-420', looked "
                                             'for there only)'),
            ('camera', 'faces-pan-tilt-ensemble', missing,
             f'detector.cascade_dir {missing} does not exist (it was to hold {frontal}, '
             f'{profile})'),
            ('camera', 'faces-pan-tilt-40', missing, f'detector.cascade_dir {missing} does '
                                                     f'not exist (it was to hold {frontal})')):
        with pytest.raises(ValueError) as raised:
            build_setup(mode, source, cascade_dir=str(folder))
        assert str(raised.value) == message
    # the frontal cascade there, the profile one not: the camera model's profile is not taken
    # from OpenCV's
    (tmp_path / frontal).write_bytes((Path(cv2.data.haarcascades) / frontal).read_bytes())
    with pytest.raises(ValueError) as raised:
        build_setup('camera', cascade_dir=str(tmp_path))
    assert str(raised.value) == (f'detector.cascade_dir {tmp_path} has no {profile} (a cascade '
                                 "of observation.file 'faces-pan-tilt-profile', looked for there "
                                 'only)')
    with pytest.raises(ValueError, match='is a file; .* needs the cascades'):
        build_setup('camera', cascade_dir=str(tmp_path / frontal))
    setup = build_setup('fovea', cascade_dir=str(tmp_path))
    assert setup.detector.paths == [tmp_path / frontal]
    assert build_setup('fovea', cascade_dir=str(tmp_path / frontal)).detector.paths == [
        tmp_path / frontal]


def test_a_cascade_dir_for_a_detector_without_cascades_is_refused(tmp_path, monkeypatch):
    """A YuNet model uses no Haar cascade: a cascade_dir, existing or not, was ignored."""
    from ipomdp_gaze.vision.detection import check_cascade_dir
    for mode, source in (('fovea', 'faces-420-yunet'), ('camera', 'faces-pan-tilt-yunet')):
        for folder in (tmp_path, tmp_path / 'cascades'):
            with pytest.raises(ValueError) as raised:
                build_setup(mode, source, cascade_dir=str(folder))
            assert str(raised.value) == (f'detector.cascade_dir {folder} is not used: the '
                                         f'detector of observation.file {source!r}, yunet, '
                                         "uses no Haar cascade (leave it '')")
    with pytest.raises(ValueError, match="'x', ensemble, uses no Haar cascade"):
        check_cascade_dir(tmp_path, {'kind': 'ensemble', 'members': [{'kind': 'yunet'}]}, 'x')
    # a plug-in is given the folder when its from_settings takes it, so it is not refused
    (tmp_path / 'cascaded.py').write_text(
        'class Takes:\n'
        '    @classmethod\n'
        '    def from_settings(cls, settings, cascade_dir=None):\n'
        '        return cls()\n\n\n'
        'class Ignores:\n'
        '    @classmethod\n'
        '    def from_settings(cls, settings):\n'
        '        return cls()\n')
    monkeypatch.syspath_prepend(str(tmp_path))
    check_cascade_dir(tmp_path, {'kind': 'cascaded:Takes'}, 'x')
    with pytest.raises(ValueError, match="'x', cascaded:Ignores, uses no Haar cascade"):
        check_cascade_dir(tmp_path, {'kind': 'cascaded:Ignores'}, 'x')
    # an ensemble with a Haar member takes it (the folder holding its cascade)
    (tmp_path / 'mine.xml').write_text('')
    check_cascade_dir(tmp_path, {'kind': 'ensemble', 'members': [
        {'kind': 'yunet'}, {'kind': 'haar', 'cascade': 'mine.xml'}]}, 'x')


def test_an_image_from_the_future_or_the_past_is_rejected_and_counted(fovea_setup):
    loop = DetectorLoop(fovea_setup, stamp_tolerance_s=0.5, max_age_s=10.0)
    image = SceneSet('test', **PAPER_TASK, color='rgb', seed=2).scene(0).image
    out = loop.add_image(100.0 + 3600.0, image, now_s=100.0)         # an hour ahead
    assert out.status == 'rejected' and 'ahead of this node' in out.reason
    out = loop.add_image(100.0 - 60.0, image, now_s=100.0)           # a minute old
    assert out.status == 'rejected' and 'stale' in out.reason
    assert loop.add_image(100.3, image, now_s=100.0).status == 'idle'     # within tolerance
    # The image that arrived while idle, stamped after the fixation, does not answer it.
    waiting = loop.fixate(fovea_setup.grid.index(3, 3), 100.1)
    assert waiting.status == 'waiting'
    assert loop.add_image(100.2, image, now_s=100.2).status == 'published'
    values = loop.values()
    assert (values['images_received'], values['images_processed'], values['images_rejected'],
            values['images_unused'], values['images_future'], values['images_stale'],
            values['images_held']) == (4, 1, 2, 1, 1, 1, 0)


def test_absurd_joint_angles_and_intrinsics_are_refused_and_counted(camera_setup):
    from ipomdp_gaze.model.head_camera import PinholeCamera
    loop = DetectorLoop(camera_setup, HEAD)
    cam = shipped_camera()
    for pan, tilt in ((1e308, 0.0), (0.0, -1e30), (7.0, 0.0)):
        out = loop.add_pose(1.0, pan, tilt, now_s=1.0)
        assert out.status == 'refused' and 'one turn' in out.reason
    assert loop.add_pose(1.0 + 1e6, 0.0, 0.0, now_s=1.0).status == 'refused'
    absurd = [PinholeCamera(cam.width, cam.height, 1e-300, cam.fy, cam.cx, cam.cy),
              PinholeCamera(cam.width, cam.height, 1e300, 1e300, cam.cx, cam.cy),
              PinholeCamera(cam.width, cam.height, cam.fx, cam.fy, 1e9, cam.cy),
              PinholeCamera(cam.width, cam.height, cam.fx, cam.fy, cam.cx, -3.0)]
    for camera in absurd:
        out = loop.set_camera(camera)
        assert out.status == 'refused' and out.reason.startswith('camera_info: ')
    assert loop.camera is None
    assert loop.set_camera(cam, max_side_px=100).status == 'refused'
    assert loop.set_camera(cam).status == 'idle' and loop.camera == cam
    values = loop.values()
    assert (values['joint_states_received'], values['joint_states_rejected'],
            values['camera_info_received'], values['camera_info_rejected']) == (4, 4, 6, 5)
    assert 'camera_info' in values['last_input_rejection']


@pytest.mark.parametrize('scale', [3, 4])
def test_a_large_view_is_resized_to_the_model_camera_with_the_same_counts(camera_setup, scale):
    import cv2
    from ipomdp_gaze.vision.detection import scaled_camera
    cam = shipped_camera()
    big_cam = scaled_camera(cam, cam.width * scale, cam.height * scale)
    scene, _ = _view(1, 0)
    target = GRID.index(*scene.cell)
    _, view = _view(1, target)
    big = cv2.resize(view, (big_cam.width, big_cam.height), interpolation=cv2.INTER_NEAREST)
    loop = DetectorLoop(camera_setup, HEAD)
    loop.set_camera(big_cam)
    loop.fixate(target, 0.0)
    loop.add_pose(1.0, *HEAD.angles(target), now_s=1.0)
    out = loop.add_image(1.0, big, now_s=1.0)
    assert out.status == 'published', out.reason
    assert out.frame.detector_pixels == cam.width * cam.height        # the model camera's cost
    small = cv2.resize(big, (cam.width, cam.height), interpolation=cv2.INTER_AREA)
    want = camera_setup.observer.observe(small, cam, GRID.cell(target)).counts
    np.testing.assert_array_equal(out.frame.counts, want)
    assert loop.values()['images_resized'] == 1
    # camera_info must still describe the view as sent.
    loop.fixate(target, 2.0)
    loop.set_camera(cam)
    loop.add_pose(3.0, *HEAD.angles(target), now_s=3.0)
    out = loop.add_image(3.0, big, now_s=3.0)
    assert out.status == 'rejected' and 'camera_info says 320x240' in out.reason


def test_no_more_than_keep_images_are_held(camera_setup):
    loop = DetectorLoop(camera_setup, HEAD, keep=4)
    _, view = _view(1, 0)
    for t in range(10):                                   # idle: nothing is held
        loop.add_image(float(t), view, now_s=float(t))
    assert loop.values()['images_held'] == 0
    loop.fixate(0, 10.0)                                  # waiting for camera_info
    for t in range(10, 20):
        loop.add_image(float(t), view, now_s=float(t))
    values = loop.values()
    assert values['images_held'] == 4 and values['images_unused'] == 20


def test_a_large_fovea_image_is_resized_to_the_model_image(fovea_setup):
    import cv2
    image = SceneSet('test', **PAPER_TASK, color='rgb', seed=2).scene(0).image     # 420x420
    big = cv2.resize(image, (1700, 1300), interpolation=cv2.INTER_NEAREST)
    loop = DetectorLoop(fovea_setup)
    cell = fovea_setup.grid.index(10, 10)
    loop.fixate(cell, 0.0)
    out = loop.add_image(1.0, big, now_s=1.0)
    small = cv2.resize(big, (549, 420), interpolation=cv2.INTER_AREA)   # its short side 420
    fovea = fovea_for_model(fovea_setup.model, reuse_windows=False)
    fovea.start(small)
    want = fovea.observe(cell)
    np.testing.assert_array_equal(out.frame.counts, want.counts)
    assert out.frame.detector_pixels == want.detector_pixels
    assert loop.values()['images_resized'] == 1
    loop.fixate(cell, 2.0)
    assert loop.add_image(3.0, cv2.resize(image, (840, 840)), now_s=3.0).status == 'published'
    assert loop.values()['images_resized'] == 1            # twice the model's side: kept


def test_another_opencv_version_is_a_note_and_another_cascade_is_refused(tmp_path):
    from ipomdp_gaze.files.observation_file import load_observation, save_observation
    model = load_observation('faces-420-nmpt')
    model.meta['detector'] = {**model.meta['detector'], 'opencv': '4.5.0'}
    path = save_observation(tmp_path / 'old.yaml', model)
    setup = build_setup('fovea', str(path))
    assert len(setup.notes) == 1 and "detector opencv '4.5.0'" in setup.notes[0]
    model.meta['detector']['cascade_sha256'] = '0' * 64
    path = save_observation(tmp_path / 'other.yaml', model)
    with pytest.raises(ValueError, match='differs from the one the observation model'):
        build_setup('fovea', str(path))


def test_the_ensemble_model_counts_its_members_boxes_by_weight_and_checks_each(tmp_path):
    import cv2
    from ipomdp_gaze.files.observation_file import save_observation
    from ipomdp_gaze.model.head_camera import bin_points
    from ipomdp_gaze.vision.pan_tilt import box_centres_uv
    setup = build_setup('camera', 'faces-pan-tilt-ensemble')
    haar, yunet = setup.detector.members
    assert setup.detector.weights == [1, 5] and yunet.upscale == 2.0
    scenes = PanTiltSceneSet('train', seed=1000)
    scene = scenes.scene(0)
    view = scenes.geometry.render(scene.image, scene.cell)
    observed = setup.observer.observe(view, setup.camera, scene.cell)
    gray = cv2.cvtColor(view, cv2.COLOR_RGB2GRAY)
    boxes = np.concatenate([haar(gray), np.repeat(yunet(view)[:, :4], 5, axis=0)])
    _, raw, _ = bin_points(box_centres_uv(boxes), setup.camera, GRID, scene.cell, 1000)
    assert np.array_equal(observed.raw_counts, raw)
    in_face_cell = raw[GRID.index(*scene.cell)]
    yunet_in_cell = int(np.sum(bin_points(box_centres_uv(yunet(view)[:, :4]), setup.camera,
                                          GRID, scene.cell, 1000)[2] == GRID.index(*scene.cell)))
    assert in_face_cell >= 5 * yunet_in_cell and yunet_in_cell >= 1
    model = load_observation('faces-pan-tilt-ensemble')
    members = model.meta['detector']['members']
    model.meta['detector'] = {**model.meta['detector'],
                              'members': [members[0], {**members[1], 'model_sha256': '0' * 64}]}
    with pytest.raises(ValueError, match='ensemble member 1: the installed YuNet model'):
        build_setup('camera', str(save_observation(tmp_path / 'other.yaml', model)))


def test_the_detector_logic_does_not_import_finds_driver():
    """detection.py (core) builds its fovea without vision.search (layers only import down)."""
    import subprocess
    import sys
    code = ('import sys\n'
            'from ipomdp_gaze.vision.detection import build_setup\n'
            "build_setup('fovea'); build_setup('camera')\n"
            "print('ipomdp_gaze.vision.search' in sys.modules)\n")
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == 'False'


def _on_the_face(camera_setup, tolerance_s: float):
    """Return a camera-mode loop with the shipped camera, a scene's face cell, the view on it."""
    loop = DetectorLoop(camera_setup, HEAD, tolerance_s=tolerance_s)
    loop.set_camera(shipped_camera())
    scene, _ = _view(1, 0)
    target = GRID.index(*scene.cell)
    return loop, target, _view(1, target)[1]


def test_a_fast_joint_state_stream_pairs_with_an_image_half_a_second_late(camera_setup):
    # a 500 Hz joint_state_broadcaster and a camera whose images arrive 0.5 s after they were
    # taken: the joint states of the image's time are 250 messages back (a count of 200 lost them)
    loop, target, view = _on_the_face(camera_setup, 0.002)
    loop.fixate(target, 10.0)
    for k in range(1001):                                         # 10.0 .. 12.0 s at 500 Hz
        loop.add_pose(10.0 + k / 500, *HEAD.angles(target))
    out = loop.add_image(11.5, view)                              # taken at 11.5, arrives at 12
    assert out.status == 'published', out.reason


def test_a_joint_state_the_image_cannot_pair_with_says_how_far_the_nearest_is(camera_setup):
    loop, target, view = _on_the_face(camera_setup, 0.0)
    loop.fixate(target, 0.0)
    assert loop.add_image(1.0, view).reason == (
        'no joint state with the stamp of the newest image (no joint state received; '
        'joint_state_tolerance_s 0 s)')
    assert loop.add_pose(1.004, *HEAD.angles(target)).reason == (
        'no joint state with the stamp of the newest image (the nearest is 0.004 s from it; '
        'joint_state_tolerance_s 0 s)')
    assert loop.waited_s(3.5) == 3.5 and DetectorLoop(camera_setup, HEAD).waited_s(3.5) == 0


def test_the_pose_history_is_the_nearest_stamp_of_a_plain_search():
    from ipomdp_gaze.vision.detection import PoseHistory
    rng = np.random.default_rng(4)
    history, added = PoseHistory(span_s=0.5), {}
    for i in range(3000):
        stamp = float(np.round(i * 0.001 + rng.normal(0, 0.002), 4))   # mostly in order
        history.add(stamp, float(i), 0.0)
        added[float(i)] = stamp
        if i % 37:
            continue
        newest = max(added.values())
        for query, tolerance in ((stamp - 0.1, 0.001), (stamp, 0.0), (stamp - 0.3, 0.01)):
            near = sorted((abs(s - query), s, p) for p, s in added.items()
                          if s >= newest - 0.5 and abs(s - query) <= tolerance + 1e-9)
            got = history.nearest(query, tolerance)
            if not near:
                assert got is None
            else:
                assert got is not None and abs(added[got[0]] - query) == near[0][0]
    assert history.stamps == sorted(history.stamps)
    assert min(history.stamps) >= max(added.values()) - 1.0        # the old ones trimmed


def test_the_pose_history_keeps_at_most_about_its_cap_and_the_newest():
    from ipomdp_gaze.vision.detection import PoseHistory
    history = PoseHistory(span_s=100.0, cap=300)
    for i in range(5000):
        history.add(i * 0.001, float(i), 0.0)
    assert len(history) <= 600 and history.nearest(4.999, 0.0) == (4999.0, 0.0)
    assert history.nearest(4.7, 0.0) == (4700.0, 0.0)


def test_a_larger_camera_of_the_models_field_of_view_is_the_models_camera(camera_setup):
    from ipomdp_gaze.model.head_camera import PinholeCamera
    model = shipped_camera()
    loop = DetectorLoop(camera_setup, HEAD)
    big = PinholeCamera(4 * model.width, 4 * model.height, 4 * model.fx, 4 * model.fy,
                        (model.cx + 0.5) * 4 - 0.5, (model.cy + 0.5) * 4 - 0.5)
    loop.set_camera(big)                     # resized on arrival to exactly the model's camera
    assert loop.mismatch == ''
    wide = PinholeCamera(4 * model.width, 3 * model.height, 4 * model.fx, 4 * model.fy,
                         (model.cx + 0.5) * 4 - 0.5, (model.cy + 0.5) * 3 - 0.5)
    loop.set_camera(wide)                    # another aspect: another vertical field of view
    assert 'calibrated with 320x240' in loop.mismatch


def test_the_pose_history_starts_again_when_the_clock_goes_back():
    from ipomdp_gaze.vision.detection import PoseHistory
    history = PoseHistory(span_s=10.0)
    for k in range(3001):                          # 100-130 s at pose A
        history.add(100.0 + k / 100, 1.0, 0.0)
    for k in range(12001):                         # a simulation reset: 0-120 s at pose B
        history.add(k / 100, 2.0, 0.0)
    assert history.nearest(119.99, 0.0) == (2.0, 0.0)
    assert history.nearest(105.0, 0.0) == (2.0, 0.0)


def test_a_wide_frame_keeps_its_height_in_fovea_mode_and_a_camera_fits_its_model():
    """QA: a 16:9 frame fitted into 420x420 halved its faces; fovea mode scales its short side."""
    from ipomdp_gaze.vision.detection import resized_size
    model = (420, 420)
    assert resized_size((1280, 720), model, 'fovea') is None          # 720 <= 2 x 420: as is
    assert resized_size((1920, 1080), model, 'fovea') == (747, 420)
    assert resized_size((4000, 3000), model, 'fovea') == (560, 420)
    assert resized_size((1080, 1080), model, 'fovea') == (420, 420)   # square: as before
    assert resized_size((1280, 960), (320, 240), 'camera') == (320, 240)
    assert resized_size((1280, 640), (320, 240), 'camera') == (320, 160)   # pixels per degree


def test_the_face_of_a_letterboxed_hd_frame_gets_the_most_detections(fovea_setup):
    import cv2
    from skimage import data
    photo = data.astronaut()
    frame = np.zeros((1080, 1920, 3), np.uint8)
    photo_px = cv2.resize(photo, (1080, 1080), interpolation=cv2.INTER_AREA)
    frame[:, 420:1500] = photo_px
    face_x, face_y = 420 + 223 * 1080 / 512, 122 * 1080 / 512          # the astronaut's face
    face = (int(face_y * 21 / 1080), int(face_x * 21 / 1920))
    loop = DetectorLoop(fovea_setup)
    loop.request_scan(1, 0.0)
    out = loop.add_image(1.0, frame)
    counts = np.nan_to_num(out.frame.counts).reshape(21, 21)
    peak = np.unravel_index(np.argmax(counts), counts.shape)
    assert max(abs(peak[0] - face[0]), abs(peak[1] - face[1])) <= 1, (peak, face, counts.max())


def test_replay_ignores_a_recorded_cascade_dir_its_detector_never_used(tmp_path):
    """A bag from before 0.3.9 may hold one with YuNet (accepted and ignored then): replay's."""
    folder = tmp_path / 'cascades'
    setup = build_setup('fovea', 'faces-420-yunet', cascade_dir=str(folder),
                        unused_cascade_dir='ignore')
    assert type(setup.detector) is type(build_setup('fovea', 'faces-420-yunet').detector)
    # a detector that uses cascades still has its folder checked
    with pytest.raises(ValueError, match=f'detector.cascade_dir {folder} does not exist'):
        build_setup('fovea', 'faces-420', cascade_dir=str(folder), unused_cascade_dir='ignore')
    with pytest.raises(ValueError, match="unused_cascade_dir must be 'refuse' or 'ignore'"):
        build_setup('fovea', 'faces-420-yunet', unused_cascade_dir='skip')
