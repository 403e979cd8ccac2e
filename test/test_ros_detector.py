# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The foveal_detector process alone, with this test as the camera driver and the controller.

Covers: an image published here gives exactly the counts the core computes for the same image
and fixation (fovea mode); camera mode marks the cells outside the view NaN and bins a pasted
face's detections into the right cells for a known pose and camera_info, and waits with a
warning while camera_info is missing; every malformed image is rejected with its reason and
counted while the node keeps serving; settings that contradict the observation file are
refused.
"""
from __future__ import annotations

from conftest import wait_for
import numpy as np
import pytest
from robust_support import assert_throttled

pytestmark = pytest.mark.ros

NODE = 'foveal_detector'


class Driver:
    """This test as the camera driver and the controller of one detector (in a namespace)."""

    def __init__(self, probe, nodes, namespace: str, mode: str, extra=()):
        from diagnostic_msgs.msg import DiagnosticArray
        from ipomdp_gaze.harness.watch import LATCHED
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import CameraInfo, Image, JointState
        from std_msgs.msg import Int32MultiArray
        self.probe, self.ns = probe, namespace
        best_effort = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.frames = probe.record(Image, f'{namespace}/evidence_image', best_effort)
        self.status = []
        name = f'{namespace}/{NODE}: detector'

        def on_diagnostics(msg):
            from ipomdp_gaze.msg_adapters import diagnostics
            for status in msg.status:
                if status.name == name:
                    self.status.append((status.level, status.message,
                                        diagnostics.values_of(status)))

        probe.node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics, 50)
        self.image = probe.publisher(Image, f'{namespace}/image')
        self.camera_info = probe.publisher(CameraInfo, f'{namespace}/camera_info')
        self.joint_states = probe.publisher(JointState, f'{namespace}/joint_states')
        self.fixation = probe.publisher(Int32MultiArray, f'{namespace}/fixation', LATCHED)
        self.proc = nodes.start('detector', ['-r', f'__ns:={namespace}', '-p', f'mode:={mode}',
                                             '-p', 'diagnostics_period_s:=0.2', *extra])
        assert wait_for(lambda: self.image.get_subscription_count() > 0 and self.status, 60), \
            self.proc.output()

    def now(self):
        return self.probe.node.get_clock().now().to_msg()

    def values(self) -> dict:
        return self.status[-1][2]

    def wait_values(self, **want) -> dict:
        n = len(self.status)
        ok = wait_for(lambda: len(self.status) > n + 1 and all(
            self.values().get(k) == str(v) for k, v in want.items()), 20)
        assert ok, f'diagnostics {self.values()} never showed {want}'
        return self.values()

    def fixate(self, grid, cell) -> None:
        """Send a fixation and wait until the detector has it."""
        from ipomdp_gaze.msg_adapters import grid_arrays
        n = int(self.wait_values()['fixations_received'])
        self.fixation.publish(grid_arrays.row_col(grid, cell))
        self.wait_values(fixations_received=n + 1)

    def frame_after(self, publish):
        """Call ``publish()`` and return the next evidence frame (counts, header stamp)."""
        from ipomdp_gaze.msg_adapters import images
        n = len(self.frames)
        publish()
        assert wait_for(lambda: len(self.frames) > n, 30), (self.values(),
                                                            self.proc.output()[-3000:])
        msg = self.frames[n][1]
        return images.evidence_from_image(msg, self.grid), msg.header.stamp


@pytest.fixture(scope='module')
def fovea(probe, nodes):
    from ipomdp_gaze.vision.detection import build_setup
    driver = Driver(probe, nodes, '/fov', 'fovea')
    driver.setup = build_setup('fovea')
    driver.grid = driver.setup.grid
    return driver


@pytest.fixture(scope='module')
def camera(probe, nodes):
    from ipomdp_gaze.vision.detection import build_setup
    driver = Driver(probe, nodes, '/cam', 'camera', ['-p', 'publish_offsets:=true'])
    driver.setup = build_setup('camera')
    driver.grid = driver.setup.grid
    return driver


def _scene(seed, color='rgb'):
    from ipomdp_gaze.vision.scenes import PAPER_TASK, SceneSet
    return SceneSet('test', **PAPER_TASK, color=color, seed=seed).scene(0)


@pytest.mark.parametrize('seed, encoding, row_col', [(0, 'rgb8', (10, 10)),
                                                     (1, 'bgr8', (3, 17)),
                                                     (2, 'mono8', (20, 0))])
def test_an_image_gives_exactly_the_counts_of_the_core(fovea, seed, encoding, row_col):
    from ipomdp_gaze.msg_adapters import images
    from ipomdp_gaze.vision.search import fovea_for_model
    scene = _scene(seed, 'gray' if encoding == 'mono8' else 'rgb')
    cell = fovea.grid.index(*row_col)
    fovea.fixate(fovea.grid, cell)
    stamp = fovea.now()
    msg = images.camera_image(scene.image, stamp)
    if encoding == 'bgr8':
        msg = images.camera_image(np.ascontiguousarray(scene.image[:, :, ::-1]), stamp)
        msg.encoding = 'bgr8'
    counts, got_stamp = fovea.frame_after(lambda: fovea.image.publish(msg))
    assert got_stamp == stamp                                   # the image's capture stamp
    core = fovea_for_model(fovea.setup.model)
    core.start(scene.image)
    np.testing.assert_array_equal(counts, core.observe(cell).counts)
    if scene.cell is not None and scene.cell == row_col:
        assert counts[cell] > 0


def test_an_image_taken_before_the_fixation_does_not_serve_it(fovea):
    from ipomdp_gaze.msg_adapters import images
    scene = _scene(3)
    early = fovea.now()
    fovea.fixate(fovea.grid, 0)
    n = len(fovea.frames)
    before = fovea.values()
    fovea.image.publish(images.camera_image(scene.image, early))
    # Wait until the node has taken the image (a counter that moves), then check it unused.
    values = fovea.wait_values(images_received=int(before['images_received']) + 1)
    assert values['images_processed'] == before['images_processed']
    assert int(values['images_unused']) == int(before['images_unused']) + 1
    assert values['waiting_for_image'] == 'true' and len(fovea.frames) == n
    counts, _ = fovea.frame_after(
        lambda: fovea.image.publish(images.camera_image(scene.image, fovea.now())))
    assert counts.shape == (441,)


def _bad_images():
    from sensor_msgs.msg import Image
    good = {'height': 30, 'width': 40, 'encoding': 'rgb8', 'step': 120, 'data': bytes(3600)}
    cases = [
        ({'encoding': '16UC1', 'step': 80, 'data': bytes(2400)},
         "unsupported image encoding '16UC1'"),
        ({'encoding': 'rgba8', 'step': 160, 'data': bytes(4800)}, 'unsupported image encoding'),
        ({'step': 100, 'data': bytes(3000)}, 'step 100 is less than width 40 x 3'),
        ({'data': bytes(3599)}, 'image data has 3599 bytes, expected step 120 x height 30'),
        ({'height': 31}, 'expected step 120 x height 31'),
        ({'width': 0, 'height': 0, 'step': 0, 'data': b''}, 'empty image'),
        ({'width': 5000, 'step': 15000}, 'larger than 4096 px'),
        ({'width': 10, 'height': 10, 'step': 30, 'data': bytes(300)},
         'smaller than the 20x20 the detector needs'),
    ]
    out = []
    for change, words in cases:
        fields = dict(good, **change)
        msg = Image(height=fields['height'], width=fields['width'],
                    encoding=fields['encoding'], step=fields['step'])
        msg.data = fields['data']
        out.append((msg, words))
    return out


def test_malformed_images_are_rejected_with_the_reason_and_the_node_keeps_serving(fovea):
    from ipomdp_gaze.msg_adapters import images
    fovea.fixate(fovea.grid, fovea.grid.index(4, 4))
    for msg, words in _bad_images():
        before = fovea.wait_values()
        msg.header.stamp = fovea.now()
        fovea.image.publish(msg)
        after = fovea.wait_values(images_rejected=int(before['images_rejected']) + 1)
        assert words in after['last_rejection'], after['last_rejection']
        assert after['images_processed'] == before['images_processed']
        assert int(after['images_received']) == int(after['images_processed']) + int(
            after['images_rejected']) + int(after['images_unused'])
    warnings = [line for line in fovea.proc.output().splitlines() if 'rejected an image' in line]
    assert warnings, warnings
    from ipomdp_gaze.nodes.detector import WARN_THROTTLE_S
    assert_throttled(warnings, WARN_THROTTLE_S)
    assert any(level == b'\x01' or level == 1 for level, _, _ in fovea.status)   # WARN
    counts, _ = fovea.frame_after(
        lambda: fovea.image.publish(images.camera_image(_scene(4).image, fovea.now())))
    seen = ~np.isnan(counts)             # the fovea's windows around (4, 4): counts, else NaN
    assert seen[fovea.grid.index(4, 4)] and np.all(counts[seen] >= 0)
    assert np.all(counts[seen] == np.floor(counts[seen]))


def _pose_frame(camera, scene, head_cell, stamp, info=True):
    """Publish joint_states, camera_info (optional) and the view of ``head_cell``."""
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import images, joints
    from ipomdp_gaze.vision.pan_tilt import SceneGeometry, shipped_camera
    geometry = SceneGeometry(camera.grid, shipped_camera())
    view = geometry.render(scene.image, camera.grid.cell(head_cell))
    camera.joint_states.publish(joints.joint_state(PanTiltMap(camera.grid), head_cell, stamp))
    if info:
        camera.camera_info.publish(images.camera_info(shipped_camera(), stamp))
    camera.image.publish(images.camera_image(view, stamp))
    return view


def test_camera_mode_waits_for_camera_info_with_a_warning(camera):
    from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry, shipped_camera
    scene = PanTiltSceneSet('test', SceneGeometry(camera.grid, shipped_camera()),
                            seed=5).scene(0)
    cell = camera.grid.index(*scene.cell)
    camera.fixate(camera.grid, cell)
    n = len(camera.frames)
    _pose_frame(camera, scene, cell, camera.now(), info=False)
    assert wait_for(lambda: camera.status and camera.status[-1][1] == 'no camera_info received',
                    20), camera.status[-1:]
    values = camera.values()
    assert values['camera_info'] == 'false' and values['waiting_for_image'] == 'true'
    assert 'no camera_info received' in values['waiting_because']
    assert len(camera.frames) == n and camera.proc.running
    assert wait_for(lambda: 'a fixation waits: no camera_info received' in camera.proc.output(),
                    20)


def test_camera_mode_warns_about_lens_distortion_it_does_not_model(camera):
    """QA: equidistant and rational_polynomial camera_info were taken silently."""
    from ipomdp_gaze.msg_adapters import images
    from ipomdp_gaze.vision.pan_tilt import shipped_camera
    info = images.camera_info(shipped_camera(), camera.now())
    info.distortion_model, info.d = 'equidistant', [-0.25, 0.05, 0.0, 0.0]
    camera.camera_info.publish(info)
    assert wait_for(lambda: 'camera_info has lens distortion (equidistant)' in
                    camera.proc.output(), 20), camera.proc.output()[-2000:]
    assert camera.proc.running


def test_a_fixation_without_images_is_warned_about_with_the_qos_hint(fovea):
    """QA: the detector stayed 'serving fixations' while a best-effort camera sent nothing."""
    fovea.fixate(fovea.setup.grid, fovea.setup.grid.index(2, 2))
    assert wait_for(lambda: fovea.status and fovea.status[-1][1] == 'no image arrives', 30), \
        fovea.status[-1:]
    assert wait_for(lambda: 'a fixation waits: no image captured since the fixation was '
                            'commanded' in fovea.proc.output(), 20)
    assert 'a best-effort camera needs image_best_effort: true' in fovea.proc.output()


@pytest.mark.parametrize('seed, offset', [(5, (0, 0)), (6, (1, -1)), (9, (-1, 1))])
def test_camera_mode_bins_a_face_to_its_cell_and_the_rest_is_nan(camera, seed, offset):
    from ipomdp_gaze.model.head_camera import observed_cells
    from ipomdp_gaze.msg_adapters import images
    from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry, shipped_camera
    grid = camera.grid
    scene = PanTiltSceneSet('test', SceneGeometry(grid, shipped_camera()), seed=seed).scene(0)
    row = min(max(scene.cell[0] + offset[0], 0), 10)
    col = min(max(scene.cell[1] + offset[1], 0), 10)
    head = grid.index(row, col)
    camera.fixate(grid, head)
    views, n = [], len(camera.frames)
    counts, _ = camera.frame_after(
        lambda: views.append(_pose_frame(camera, scene, head, camera.now())))
    seen = observed_cells(shipped_camera(), grid, (row, col))
    np.testing.assert_array_equal(~np.isnan(counts), seen)
    assert seen.sum() < grid.n_cells
    want = camera.setup.observer.observe(views[0], shipped_camera(), (row, col))
    np.testing.assert_array_equal(counts, want.counts)
    # publish_offsets: a 32FC3 image whose channels 2-3 are the core's per-cell offsets
    msg = camera.frames[n][1]
    assert msg.encoding == '32FC3'
    _, offsets = images.evidence_and_offsets(msg, grid)
    np.testing.assert_array_equal(offsets, want.offsets.astype(np.float32))
    assert np.isfinite(offsets[grid.index(*scene.cell)]).all()
    target = grid.index(*scene.cell)
    assert counts[target] > 0 and counts[target] == np.nanmax(counts)


def test_settings_that_contradict_the_observation_file_are_refused(probe, nodes, fovea):
    bad = nodes.start('detector', ['-r', '__ns:=/bad', '-p', 'grid.rows:=11'])
    assert wait_for(lambda: not bad.running, 60)
    assert bad.proc.returncode == 1
    lines = [line for line in bad.output().splitlines() if line.strip()]
    assert any('grid.rows 11 contradicts observation.file' in line for line in lines), lines
    assert 'Traceback' not in bad.output()
    nodes.killed.append(bad)                                     # exited on purpose
    result = probe.set_parameters('fov/' + NODE, {'detector.scale_factor': 1.3})[0]
    assert not result.successful
    assert 'detector.scale_factor 1.3 contradicts observation.file' in result.reason
    result = probe.set_parameters('fov/' + NODE, {'observation.file': 'faces-pan-tilt'})[0]
    assert not result.successful and 'calibrated with a pan_tilt view' in result.reason
    assert probe.set_parameters('fov/' + NODE, {'detector.scale_factor': 1.1})[0].successful


def test_a_cascade_dir_without_the_cascade_is_refused(probe, nodes, fovea, tmp_path):
    """It fell back to OpenCV's installed cascades unnoticed, at start and when set."""
    missing = tmp_path / 'cascades'
    bad = nodes.start('detector', ['-r', '__ns:=/nocascade', '-p',
                                   f'detector.cascade_dir:={missing}'])
    assert wait_for(lambda: not bad.running, 60)
    assert bad.proc.returncode == 1
    assert f'detector.cascade_dir {missing} does not exist (it was to hold ' \
        'haarcascade_frontalface_alt2.xml)' in bad.output()
    assert 'Traceback' not in bad.output()
    nodes.killed.append(bad)                                     # exited on purpose
    result = probe.set_parameters('fov/' + NODE, {'detector.cascade_dir': str(tmp_path)})[0]
    assert not result.successful
    assert f'detector.cascade_dir {tmp_path} has no haarcascade_frontalface_alt2.xml' in \
        result.reason
    assert probe.get_parameters('fov/' + NODE, ['detector.cascade_dir']) == {
        'detector.cascade_dir': ''}


def test_a_cascade_dir_with_yunet_is_refused(probe, nodes, fovea, tmp_path):
    """A YuNet model uses no Haar cascade: the folder was accepted and ignored (start, set)."""
    bad = nodes.start('detector', ['-r', '__ns:=/yunetcascade', '-p',
                                   'observation.file:=faces-420-yunet', '-p',
                                   f'detector.cascade_dir:={tmp_path}'])
    assert wait_for(lambda: not bad.running, 60)
    assert bad.proc.returncode == 1
    assert f'detector.cascade_dir {tmp_path} is not used: the detector of observation.file ' \
        "'faces-420-yunet', yunet, uses no Haar cascade (leave it '')" in bad.output()
    assert 'Traceback' not in bad.output()
    nodes.killed.append(bad)                                     # exited on purpose
    # (detector.scale_factor back at 0.0, unset: a test before may have set the file's 1.1,
    # which YuNet's file would refuse first)
    result = probe.set_parameters_atomically('fov/' + NODE, {
        'observation.file': 'faces-420-yunet', 'detector.cascade_dir': str(tmp_path),
        'detector.scale_factor': 0.0})
    assert not result.successful
    assert f'detector.cascade_dir {tmp_path} is not used' in result.reason
    assert probe.get_parameters('fov/' + NODE, ['observation.file', 'detector.cascade_dir']) \
        == {'observation.file': '', 'detector.cascade_dir': ''}


def test_an_absurd_joint_angle_is_refused_and_counted_and_the_node_lives(camera):
    """The fault of issue 26: pan = 1e308 under the stamp of a valid image, a fixation waiting."""
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import images, joints
    from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry, shipped_camera
    from sensor_msgs.msg import JointState
    grid = camera.grid
    head = PanTiltMap(grid)
    scene = PanTiltSceneSet('test', SceneGeometry(grid, shipped_camera()), seed=5).scene(0)
    cell = grid.index(*scene.cell)
    camera.fixate(grid, cell)
    before = camera.wait_values()
    n = len(camera.frames)
    stamp = camera.now()
    view = SceneGeometry(grid, shipped_camera()).render(scene.image, scene.cell)
    camera.camera_info.publish(images.camera_info(shipped_camera(), stamp))
    camera.image.publish(images.camera_image(view, stamp))
    absurd = joints.joint_state(head, cell, stamp)
    absurd.position = [1e308, 0.0]
    camera.joint_states.publish(absurd)
    after = camera.wait_values(
        joint_states_rejected=int(before['joint_states_rejected']) + 1)
    reason = after['last_input_rejection']
    assert '1e+308' in reason and 'one turn' in reason
    assert camera.proc.running and len(camera.frames) == n
    assert after['waiting_for_image'] == 'true' and after['callback_errors'] == '0'
    # Joint states of other joints are not the head's: neither used nor refused.
    camera.joint_states.publish(JointState(name=['wheel'], position=[1e308]))
    # The valid joint state of the same stamp then serves the waiting fixation.
    counts, got = camera.frame_after(
        lambda: camera.joint_states.publish(joints.joint_state(head, cell, stamp)))
    assert got == stamp and counts[cell] > 0
    final = camera.wait_values()
    assert final['joint_states_rejected'] == after['joint_states_rejected']
    assert 'ignored a message' in camera.proc.output()
