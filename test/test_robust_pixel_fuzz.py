# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Fuzz the live foveal detector (its own process) over DDS, in ``fovea`` and ``camera`` mode.

This test is the camera driver and the controller. It sends hostile messages one at a time and
waits, on ``/diagnostics``, until the node has counted each one, so every counter can be
predicted exactly: images with wrong encodings, steps and lengths that disagree with the size,
zero and huge sizes, random bytes, stamps an hour ahead or decades old, images too small for
the detector or taken before the fixation, one real 5000x5000 image; fixations outside the grid
or of the wrong length; in ``camera`` mode ``camera_info`` with NaN, skewed, absurd or
oversized intrinsics and ``joint_states`` with 1e308, NaN or out-of-turn angles, missing
positions or future stamps.
Between them go valid requests (a fixation, then an image; in ``camera`` mode with its
``camera_info`` and the joint state of its stamp), each of which must be answered with counts
stamped like its image. Afterwards every counter matches the prediction
(``images_received = images_processed + images_rejected + images_unused``), no callback
failed, the warnings were throttled, and the node is alive (it must exit 0 on SIGTERM at
teardown).

``make test`` sends 252 hostile messages per mode, every kind among them; ``make soak`` 10,080.
"""
from __future__ import annotations

import re
import time

from conftest import wait_for
import numpy as np
import pytest
from robust_support import assert_throttled

pytestmark = pytest.mark.ros

NODE = 'foveal_detector'
HOSTILE_PER_CYCLE = 12
COUNTERS = ('images_received', 'images_processed', 'images_rejected', 'images_future',
            'images_stale', 'fixations_received', 'fixations_rejected',
            'joint_states_received', 'joint_states_rejected', 'camera_info_received',
            'camera_info_rejected')


class Rig:
    """One detector process (in a namespace) and this test's publishers and recorders."""

    def __init__(self, probe, nodes, mode: str):
        from diagnostic_msgs.msg import DiagnosticArray
        from ipomdp_gaze.harness.watch import LATCHED
        from ipomdp_gaze.msg_adapters import diagnostics
        from ipomdp_gaze.nodes.detector import FRAME_QOS
        from ipomdp_gaze.vision.detection import build_setup
        from sensor_msgs.msg import CameraInfo, Image, JointState
        from std_msgs.msg import Int32MultiArray
        self.mode, self.probe = mode, probe
        ns = f'/fuzz_{mode}'
        self.setup = build_setup(mode)
        self.grid = self.setup.grid
        self.values, self.count = {}, 0
        name = f'{ns}/{NODE}: detector'

        def on_diagnostics(msg):
            for status in msg.status:
                if status.name == name:
                    self.values = diagnostics.values_of(status)
                    self.count += 1

        probe.node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics, 50)
        self.frames = probe.record(Image, f'{ns}/evidence_image', FRAME_QOS)
        self.image = probe.publisher(Image, f'{ns}/image')
        self.fixation = probe.publisher(Int32MultiArray, f'{ns}/fixation', LATCHED)
        self.camera_info = probe.publisher(CameraInfo, f'{ns}/camera_info')
        self.joint_states = probe.publisher(JointState, f'{ns}/joint_states')
        # Stale means a minute old here, so that a slow cycle on a busy machine cannot turn
        # an image taken before the fixation into a stale one.
        self.proc = nodes.start('detector', ['-r', f'__ns:={ns}', '-p', f'mode:={mode}',
                                             '-p', 'diagnostics_period_s:=0.01',
                                             '-p', 'max_image_age_s:=60.0'])
        self.fixation_sent = None
        pubs = [self.image, self.fixation] + (
            [self.camera_info, self.joint_states] if mode == 'camera' else [])
        assert wait_for(lambda: self.values and all(
            p.get_subscription_count() > 0 for p in pubs), 60), self.proc.output()

    def now(self):
        return self.probe.node.get_clock().now().to_msg()

    def counters(self) -> dict:
        return {k: int(self.values[k]) for k in COUNTERS}

    def wait_counts(self, want: dict, what: str, timeout_s: float = 20.0) -> None:
        """Wait until every counter in ``want`` has reached its value (they never go back)."""
        def reached():
            return all(int(self.values.get(k, -1)) >= v for k, v in want.items())
        assert wait_for(reached, timeout_s, 0.002), (what, want, self.values)


@pytest.fixture(scope='module')
def rigs(probe, nodes):
    return {}


def _rig(rigs, probe, nodes, mode) -> Rig:
    if mode not in rigs:
        rigs[mode] = Rig(probe, nodes, mode)
    return rigs[mode]


class Messages:
    """Hostile messages of every kind, each with the counters it must move."""

    def __init__(self, rig: Rig, rng: np.random.Generator):
        from ipomdp_gaze.model.head import PanTiltMap
        self.rig, self.rng = rig, rng
        self.head = PanTiltMap(rig.grid) if rig.mode == 'camera' else None

    def _image(self, width, height, encoding='mono8', step=None, data=None, stamp=None):
        from builtin_interfaces.msg import Time
        from sensor_msgs.msg import Image
        from std_msgs.msg import Header
        channels = 3 if encoding in ('rgb8', 'bgr8') else 1
        step = channels * width if step is None else step
        msg = Image(header=Header(stamp=stamp or self.rig.now()), height=height, width=width,
                    encoding=encoding, step=step)
        msg.data = bytes(step * height) if data is None else data
        if isinstance(stamp, tuple):
            msg.header.stamp = Time(sec=stamp[0], nanosec=stamp[1])
        return msg

    def _ahead(self, seconds: float):
        from ipomdp_gaze.msg_adapters import stamps
        now = self.rig.now()
        return stamps.from_seconds(stamps.to_seconds(now) + seconds)

    def _before(self):
        """Return a stamp before the waiting fixation was sent (a second ago if none waits)."""
        from ipomdp_gaze.msg_adapters import stamps
        sent = self.rig.fixation_sent
        if sent is None:
            return self._ahead(-1.0)
        return stamps.from_seconds(stamps.to_seconds(sent) - 0.2)

    def image_kinds(self, pending: bool) -> dict:
        """``{kind: (make, counters moved)}`` for the image topic."""
        rng = self.rng
        rej = {'images_rejected': 1}

        def random_bytes():
            width, height = (int(x) for x in rng.integers(1, 64, 2))
            encoding = str(rng.choice(['mono8', 'rgb8', 'bgr8']))
            channels = 1 if encoding == 'mono8' else 3
            size = channels * width * height + int(rng.integers(1, 50)) * int(rng.choice([-1, 1]))
            size = max(size, 1) if size != channels * width * height else size + 1
            return self._image(width, height, encoding,
                               data=rng.integers(0, 256, size, dtype=np.uint8).tobytes())

        # An image the detector can decode but that must not answer: too small (fovea mode,
        # a fixation waiting: rejected by the detector; otherwise never used), or taken a
        # second before now (before the waiting fixation: never used).
        tiny_rejected = pending and self.rig.mode == 'fovea'
        kinds = {
            'encoding-16UC1': (lambda: self._image(40, 30, '16UC1', step=80), rej),
            'encoding-rgba8': (lambda: self._image(40, 30, 'rgba8', step=160), rej),
            'encoding-empty': (lambda: self._image(40, 30, ''), rej),
            'encoding-32FC1': (lambda: self._image(4, 3, '32FC1', step=16), rej),
            'step-small': (lambda: self._image(40, 30, 'rgb8', step=119), rej),
            'data-short': (lambda: self._image(40, 30, data=bytes(1199)), rej),
            'data-long': (lambda: self._image(40, 30, data=bytes(1201)), rej),
            'empty-0x0': (lambda: self._image(0, 0, data=b''), rej),
            'zero-width': (lambda: self._image(0, 30, step=0, data=b''), rej),
            'huge-declared': (lambda: self._image(5000, 5000, data=bytes(16)), rej),
            'max-side': (lambda: self._image(2 ** 31 - 1, 1, data=bytes(16)), rej),
            'random-bytes': (random_bytes, rej),
            'future-stamp': (lambda: self._image(40, 30, stamp=self._ahead(3600.0)),
                             {'images_rejected': 1, 'images_future': 1}),
            'int32-end-stamp': (lambda: self._image(40, 30, stamp=(2 ** 31 - 1, 999_999_999)),
                                {'images_rejected': 1, 'images_future': 1}),
            'stale-stamp': (lambda: self._image(40, 30, stamp=(1, 0)),
                            {'images_rejected': 1, 'images_stale': 1}),
            'tiny': (lambda: self._image(10, 10), rej if tiny_rejected else {}),
            'taken-before': (lambda: self._image(64, 48, 'rgb8', stamp=self._before()), {}),
        }
        return {k: (make, {'images_received': 1, **moved}) for k, (make, moved) in kinds.items()}

    def fixation_kinds(self) -> dict:
        from std_msgs.msg import Int32MultiArray
        g = self.rig.grid

        def fix(data):
            msg = Int32MultiArray()
            msg.data = list(data)
            return msg

        bad = {'fixation-row-out': [g.rows, 0], 'fixation-col-out': [0, g.cols],
               'fixation-negative': [-1, 3], 'fixation-short': [3], 'fixation-empty': [],
               'fixation-long': [1, 2, 3, 4], 'fixation-negative-search-id': [1, 2, -3],
               'fixation-int32-max': [2 ** 31 - 1, 0]}
        moved = {'fixations_received': 1, 'fixations_rejected': 1}
        return {k: ((lambda d=d: fix(d)), moved) for k, d in bad.items()}

    def camera_kinds(self) -> dict:
        from ipomdp_gaze.msg_adapters import images, joints
        from ipomdp_gaze.vision.pan_tilt import shipped_camera
        from sensor_msgs.msg import JointState
        cam = shipped_camera()
        head = self.head
        nan, inf = float('nan'), float('inf')

        def info(width=cam.width, height=cam.height, k=None):
            msg = images.camera_info(cam, self.rig.now())
            msg.width, msg.height = width, height
            if k is not None:
                msg.k = [float(x) for x in k]
            return msg

        k = cam.k

        def with_k(i, value):
            out = list(k)
            out[i] = value
            return out

        def joint(pan, tilt, stamp=None, names=None, positions=None):
            msg = joints.joint_state(head, head.grid.center_index, stamp or self.rig.now())
            if names is not None:
                msg.name = names
            msg.position = [pan, tilt] if positions is None else positions
            return msg

        # A refused message is received and rejected, as an image is.
        info_rej = {'camera_info_received': 1, 'camera_info_rejected': 1}
        js_rej = {'joint_states_received': 1, 'joint_states_rejected': 1}
        kinds = {
            'info-zero-size': (lambda: info(0, 0), info_rej),
            'info-k-nan': (lambda: info(k=with_k(0, nan)), info_rej),
            'info-k-inf': (lambda: info(k=with_k(5, inf)), info_rej),
            'info-skew': (lambda: info(k=with_k(1, 3.0)), info_rej),
            'info-fx-tiny': (lambda: info(k=with_k(0, 1e-300)), info_rej),
            'info-fx-huge': (lambda: info(k=with_k(4, 1e300)), info_rej),
            'info-cx-outside': (lambda: info(k=with_k(2, 1e9)), info_rej),
            'info-negative-f': (lambda: info(k=with_k(0, -cam.fx)), info_rej),
            'info-too-large': (lambda: info(5000, 5000, k=with_k(2, 2500.0)), info_rej),
            'info-valid': (lambda: info(), {'camera_info_received': 1}),
            'js-1e308': (lambda: joint(1e308, 0.0), js_rej),
            'js-minus-1e308': (lambda: joint(0.0, -1e308), js_rej),
            'js-nan': (lambda: joint(nan, 0.0), js_rej),
            'js-inf': (lambda: joint(0.0, inf), js_rej),
            'js-7-rad': (lambda: joint(7.0, 0.0), js_rej),
            'js-no-position': (lambda: joint(0.0, 0.0, positions=[0.0]), js_rej),
            'js-future': (lambda: joint(0.0, 0.0, stamp=self._ahead(3600.0)), js_rej),
            'js-other-joints': (lambda: JointState(name=['wheel'], position=[1e308]), {}),
            'js-pan-alone': (lambda: joint(0.0, 0.0, names=[head.pan_joint, 'wheel']), js_rej),
            'js-valid': (lambda: joint(0.0, 0.0), {'joint_states_received': 1}),
        }
        return kinds

    def topic(self, kind: str) -> str:
        if kind.startswith('info-'):
            return 'camera_info'
        if kind.startswith('js-'):
            return 'joint_states'
        if kind.startswith('fixation-'):
            return 'fixation'
        return 'image'


class Valid:
    """Valid requests: a fixation, then an image (camera mode: camera_info, joint state)."""

    def __init__(self, rig: Rig):
        from ipomdp_gaze.model.head import PanTiltMap
        from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry, shipped_camera
        from ipomdp_gaze.vision.scenes import PAPER_TASK, SceneSet
        self.rig = rig
        self.views = []
        if rig.mode == 'fovea':
            for seed in range(3):
                self.views.append((None, SceneSet('test', **PAPER_TASK, color='rgb',
                                                  seed=seed).scene(0).image))
        else:
            self.head = PanTiltMap(rig.grid)
            geometry = SceneGeometry(rig.grid, shipped_camera())
            for seed in range(3):
                scene = PanTiltSceneSet('test', geometry, seed=seed).scene(0)
                for cell in (scene.cell, (5, 5)):
                    self.views.append((cell, geometry.render(scene.image, cell)))

    def fixate(self, want: dict, i: int) -> int:
        from ipomdp_gaze.msg_adapters import grid_arrays
        rig = self.rig
        cell, _ = self.views[i % len(self.views)]
        index = rig.grid.index(*cell) if cell is not None else int(
            np.random.default_rng(i).integers(rig.grid.n_cells))
        want['fixations_received'] += 1
        rig.fixation_sent = rig.now()
        rig.fixation.publish(grid_arrays.row_col(rig.grid, index))
        rig.wait_counts({'fixations_received': want['fixations_received']}, 'valid fixation')
        return index

    def answer(self, want: dict, i: int, index: int) -> None:
        from ipomdp_gaze.msg_adapters import images, joints
        from ipomdp_gaze.vision.pan_tilt import shipped_camera
        rig = self.rig
        _, view = self.views[i % len(self.views)]
        stamp = rig.now()
        if rig.mode == 'camera':
            want['camera_info_received'] += 1
            rig.camera_info.publish(images.camera_info(shipped_camera(), stamp))
            rig.wait_counts({'camera_info_received': want['camera_info_received']}, 'info')
            want['joint_states_received'] += 1
            rig.joint_states.publish(joints.joint_state(self.head, index, stamp))
            rig.wait_counts({'joint_states_received': want['joint_states_received']}, 'pose')
        n = len(rig.frames)
        want['images_received'] += 1
        want['images_processed'] += 1
        rig.image.publish(images.camera_image(view, stamp))
        assert wait_for(lambda: len(rig.frames) > n, 30), ('no counts', rig.values)
        frame = rig.frames[n][1]
        assert frame.header.stamp == stamp
        counts = images.evidence_from_image(frame, rig.grid)
        assert counts.shape == (rig.grid.n_cells,)
        rig.wait_counts({'images_processed': want['images_processed']}, 'processed')
        rig.fixation_sent = None


def _fuzz(rig: Rig, hostile: int, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    messages, valid = Messages(rig, rng), Valid(rig)
    want = rig.counters()
    sent = {'hostile': 0, 'valid': 0}
    kinds_used = set()
    t0 = time.monotonic()
    cycles = -(-hostile // HOSTILE_PER_CYCLE)
    # One real 5000x5000 image (25 MB), once: refused for its size, before anything is copied.
    want['images_received'] += 1
    want['images_rejected'] += 1
    rig.image.publish(messages._image(5000, 5000))
    rig.wait_counts({k: want[k] for k in ('images_received', 'images_rejected')}, '5000x5000')
    assert 'larger than 4096 px' in rig.values['last_rejection']
    sent['hostile'] += 1
    for i in range(cycles):
        split = int(rng.integers(0, HOSTILE_PER_CYCLE + 1))    # some while idle, some waiting
        index = None
        for j in range(HOSTILE_PER_CYCLE):
            if j == split:
                index = valid.fixate(want, i)
            pending = index is not None
            kinds = {**messages.image_kinds(pending), **messages.fixation_kinds()}
            if rig.mode == 'camera':
                kinds.update(messages.camera_kinds())
            names = sorted(kinds)
            kind = names[int(rng.integers(len(names)))]
            make, moved = kinds[kind]
            kinds_used.add(kind)
            for key, step in moved.items():
                want[key] += step
            getattr(rig, messages.topic(kind)).publish(make())
            sent['hostile'] += 1
            if moved:
                rig.wait_counts({k: want[k] for k in moved}, kind)
        if index is None:
            index = valid.fixate(want, i)
        valid.answer(want, i, index)
        sent['valid'] += 1
    seconds = time.monotonic() - t0
    n = rig.count
    assert wait_for(lambda: rig.count > n + 1, 10)
    every = {*messages.image_kinds(False), *messages.image_kinds(True), *messages.fixation_kinds()}
    if rig.mode == 'camera':
        every |= set(messages.camera_kinds())
    return {'want': want, 'got': rig.counters(), 'values': dict(rig.values), 'sent': sent,
            'kinds': kinds_used, 'every_kind': every, 'seconds': seconds}


@pytest.mark.parametrize('mode, hostile', [
    # 252 messages per mode draw every kind (25 in fovea mode, 44 in camera mode; checked below)
    # about 6 to 10 times each: what they test is each kind handled and counted exactly, and
    # the kinds interleaved with valid requests, not a rate, so more draws add no decision.
    pytest.param('fovea', 252, id='fovea-252'),
    pytest.param('camera', 252, id='camera-252'),
    pytest.param('fovea', 10080, id='fovea-10080', marks=pytest.mark.soak),
    pytest.param('camera', 10080, id='camera-10080', marks=pytest.mark.soak),
])
def test_fuzzed_detector_answers_valid_requests_and_counts_every_message(
        rigs, probe, nodes, mode, hostile):
    rig = _rig(rigs, probe, nodes, mode)
    report = _fuzz(rig, hostile, seed=hostile + len(mode))
    want, got, values = report['want'], report['got'], report['values']
    print(f"\n{mode} fuzz: {report['sent']['hostile']} hostile messages of "
          f"{len(report['kinds'])} kinds and {report['sent']['valid']} valid requests in "
          f"{report['seconds']:.1f} s; counters {got}")
    assert report['sent']['hostile'] >= hostile
    assert report['kinds'] == report['every_kind'], report['every_kind'] - report['kinds']
    assert got == want
    assert int(values['images_received']) == int(values['images_processed']) + int(
        values['images_rejected']) + int(values['images_unused'])
    assert values['callback_errors'] == '0', values['last_callback_error']
    assert int(values['images_held']) <= 4
    assert rig.proc.running, rig.proc.output()[-3000:]
    # The warnings name their reasons and are throttled (one per call site per throttle period).
    from ipomdp_gaze.nodes.detector import WARN_THROTTLE_S
    lines = rig.proc.output().splitlines()
    rejected = [s for s in lines if 'rejected an image' in s]
    ignored = [s for s in lines if 'ignored a message' in s]
    assert rejected and all(re.search(r'\(\d+ so far\): \S', s) for s in rejected)
    assert ignored and all(re.search(r'\(\d+ so far\): \S', s) for s in ignored)
    assert_throttled(rejected, WARN_THROTTLE_S)
    assert_throttled(ignored, WARN_THROTTLE_S)
    assert 'Traceback' not in rig.proc.output()
