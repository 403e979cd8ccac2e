# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Fuzz the live controller (its own process) with evidence and parameter requests.

Frames go out in bursts no larger than the controller's queue (``evidence_queue_depth``), and
the next burst waits until ``/diagnostics`` shows that every frame sent so far was received, so
none is lost and every counter can be predicted exactly. The mix: valid frames (NaN cells,
extreme finite values, empty and one-dimensional layouts, big-endian and padded images),
frames that must be skipped (old stamps, or sent while disabled) and frames that must be
rejected (wrong lengths, +/-inf, empty, every cell NaN, stamps far in the future, layouts that
lie about the data, wrong encodings, and valid frames while the FPOC's d' is so large that the
log-likelihood overflows). Between bursts
go parameter requests: wrong types and lengths, NaN kernels, read-only grid changes, bad policy
files and valid changes. Afterwards the node is alive, answers its services, its belief is
finite and normalised, and its counters match the prediction (received = applied + rejected +
skipped), with the rejections logged, throttled, with their reasons.

``make test`` sends 3,000 frames and 200 parameter requests; ``make soak`` 100,000 and 3,000.
"""
from __future__ import annotations

import math
import re
import time

from conftest import wait_for
import numpy as np
import pytest
from robust_support import assert_throttled, bad_policy_files

pytestmark = pytest.mark.ros

CONTROLLER = 'gaze_controller'
ROWS = COLS = 11
N = ROWS * COLS
QUEUE = 64
BURST = 48
KERNEL_SIZE = (2 * ROWS - 1) * (2 * COLS - 1)
VALID, REJECT, SKIP = 'valid', 'rejected', 'skipped'
# Read fine but refused where it would be used: skipped first while disabled.
REFUSED_IN_USE = 'refused in use'


@pytest.fixture(scope='module')
def fuzz(launch, probe, tmp_path_factory):
    """Start the controller; return the helpers that talk to it."""
    from std_msgs.msg import Float32MultiArray

    # Motion on: a tracker never ends its search, so every valid frame is applied (a still
    # search skips the frames after its found event until ~/reset, docs/design.md section 7.3).
    proc = launch('controller', [
        '-p', 'settle_time_s:=0.0', '-p', 'diagnostics_period_s:=0.02',
        '-p', f'evidence_queue_depth:={QUEUE}', '-p', 'policy.name:=elm',
        '-p', 'retry_period_s:=0.5', '-p', 'stall_timeout_s:=0.0',
        '-p', 'motion.sigma_cells:=0.5'])
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    qos = QoSProfile(depth=QUEUE, reliability=ReliabilityPolicy.RELIABLE)
    from sensor_msgs.msg import Image
    rig = {
        'proc': proc,
        'probe': probe,
        'diag': probe.search_status(),
        'belief': probe.latest(Float32MultiArray, 'belief', 10),
        'evidence': probe.publisher(Float32MultiArray, 'evidence', qos),
        'image': probe.publisher(Image, 'evidence_image', qos),
        'folder': tmp_path_factory.mktemp('fuzz_policies'),
    }
    assert wait_for(lambda: rig['evidence'].get_subscription_count() > 0 and
                    rig['image'].get_subscription_count() > 0, 30), proc.output()
    rig['diag'].wait_fresh()
    return rig


class Frames:
    """Every kind of frame, each with the outcome it must have (while the node is enabled)."""

    def __init__(self, rng: np.random.Generator):
        self.rng = rng

    def _values(self) -> np.ndarray:
        o = self.rng.standard_normal(N).astype(np.float32)
        o[self.rng.integers(N)] += 4.0
        return o

    def array(self, values, dims=None, offset=0, layout=True):
        import array

        from ipomdp_gaze.msg_adapters import grid_arrays
        from std_msgs.msg import Float32MultiArray, MultiArrayDimension, MultiArrayLayout
        msg = Float32MultiArray()
        if layout and dims is None:
            msg.layout = grid_arrays.grid_layout(_grid())
        elif dims is not None:
            msg.layout = MultiArrayLayout(
                dim=[MultiArrayDimension(label=lab, size=size, stride=stride)
                     for lab, size, stride in dims], data_offset=offset)
        msg.data = array.array('f', np.ascontiguousarray(values, np.float32).tobytes())
        return msg

    def image(self, values, encoding='32FC1', height=ROWS, width=COLS, big_endian=False,
              pad=0, stamp=(0, 0), data=None):
        from builtin_interfaces.msg import Time
        from sensor_msgs.msg import Image
        from std_msgs.msg import Header
        a = np.asarray(values, dtype='>f4' if big_endian else '<f4').reshape(-1)
        rows = a.tobytes()
        if pad > 0 and a.size == height * width:
            rows = b''.join(a[r * width:(r + 1) * width].tobytes() + bytes(pad)
                            for r in range(height))
        msg = Image(header=Header(stamp=Time(sec=stamp[0], nanosec=stamp[1])), height=height,
                    width=width, encoding=encoding, is_bigendian=int(big_endian),
                    step=4 * width + pad)
        msg.data = rows if data is None else data
        return msg

    def make(self, kind: str):
        """Return ``(topic, message, outcome)`` of one frame of this kind."""
        v = self._values()
        far_future = (2_147_483_000, 0)              # 2038, the end of int32 seconds
        kinds = {
            'valid': lambda: ('evidence', self.array(v), VALID),
            'valid-nan': lambda: ('evidence', self.array(np.where(
                self.rng.random(N) < 0.5, np.nan, v)), VALID),
            # every cell NaN: observed nothing, and no fixation is spent on it
            'all-nan': lambda: ('evidence', self.array(np.full(N, np.nan)), REFUSED_IN_USE),
            'valid-extreme': lambda: ('evidence', self.array(np.where(
                self.rng.random(N) < 0.1, self.rng.choice(
                    [3.4e38, -3.4e38, 1e30, -1e30, 1e-45, -0.0], N), v)), VALID),
            'valid-empty-layout': lambda: ('evidence', self.array(v, layout=False), VALID),
            'valid-1d-layout': lambda: ('evidence', self.array(v, [('cells', N, N)]), VALID),
            'valid-zero-strides': lambda: ('evidence', self.array(
                v, [('rows', ROWS, 0), ('cols', COLS, 0)]), VALID),
            'short': lambda: ('evidence', self.array(v[:-1]), REJECT),
            'long': lambda: ('evidence', self.array(np.append(v, 0.0)), REJECT),
            'empty': lambda: ('evidence', self.array(v[:0], layout=False), REJECT),
            'empty-with-layout': lambda: ('evidence', self.array(v[:0]), REJECT),
            'huge': lambda: ('evidence', self.array(np.zeros(10_000), layout=False), REJECT),
            '+inf': lambda: ('evidence', self.array(np.where(
                np.arange(N) == self.rng.integers(N), np.inf, v)), REJECT),
            '-inf': lambda: ('evidence', self.array(np.where(
                np.arange(N) == self.rng.integers(N), -np.inf, v)), REJECT),
            'layout-7x7': lambda: ('evidence', self.array(
                v[:49], [('rows', 7, 49), ('cols', 7, 7)]), REJECT),
            'layout-lies': lambda: ('evidence', self.array(
                v[:120], [('rows', ROWS, N), ('cols', COLS, COLS)]), REJECT),
            'layout-12x11': lambda: ('evidence', self.array(
                np.append(v, v[:COLS]), [('rows', 12, 132), ('cols', COLS, COLS)]), REJECT),
            'layout-stride': lambda: ('evidence', self.array(
                v, [('rows', ROWS, N), ('cols', COLS, 12)]), REJECT),
            'layout-offset': lambda: ('evidence', self.array(
                v, [('rows', ROWS, N), ('cols', COLS, COLS)], offset=3), REJECT),
            'layout-3d': lambda: ('evidence', self.array(
                v, [('a', 1, N), ('rows', ROWS, N), ('cols', COLS, COLS)]), REJECT),
            'layout-1d-wrong': lambda: ('evidence', self.array(v, [('cells', N - 1, N - 1)]),
                                        REJECT),
            'image': lambda: ('evidence_image', self.image(v), VALID),
            'image-big-endian': lambda: ('evidence_image', self.image(v, big_endian=True),
                                         VALID),
            'image-padded': lambda: ('evidence_image', self.image(v, pad=8), VALID),
            'image-lowercase': lambda: ('evidence_image', self.image(v, encoding='32fc1'),
                                        VALID),
            # beyond the stamp tolerance ahead of the controller's clock: its clock runs ahead
            'image-future-stamp': lambda: ('evidence_image', self.image(v, stamp=far_future),
                                           REFUSED_IN_USE),
            'image-all-nan': lambda: ('evidence_image', self.image(np.full(N, np.nan)),
                                      REFUSED_IN_USE),
            'image-old-stamp': lambda: ('evidence_image', self.image(v, stamp=(1, 0)), SKIP),
            'image-mono8': lambda: ('evidence_image', self.image(
                v, encoding='mono8', data=bytes(N)), REJECT),
            'image-rgb8': lambda: ('evidence_image', self.image(v, encoding='rgb8'), REJECT),
            'image-no-encoding': lambda: ('evidence_image', self.image(v, encoding=''), REJECT),
            'image-10x11': lambda: ('evidence_image', self.image(v[:110], height=10), REJECT),
            'image-0x0': lambda: ('evidence_image', self.image(v[:0], height=0, width=0),
                                  REJECT),
            'image-short-data': lambda: ('evidence_image', self.image(
                v, data=v.astype('<f4').tobytes()[:-4]), REJECT),
            'image-step-small': lambda: ('evidence_image', self.image(v, pad=-4), REJECT),
            'image-inf': lambda: ('evidence_image', self.image(np.where(
                np.arange(N) == 7, -np.inf, v)), REJECT),
        }
        self.kinds = list(kinds)
        return kinds[kind]()

    def kind_names(self) -> list:
        self.make('valid')
        return self.kinds


def _grid():
    from ipomdp_gaze.model.grid import Grid
    return Grid(ROWS, COLS, 5.0)


class ParameterFuzz:
    """Parameter requests with the answer each must get; valid ones are remembered."""

    def __init__(self, rng, files: dict, good_file: str):
        self.rng = rng
        self.files = files
        self.good_file = good_file
        self.expected: dict = {}

    def requests(self):
        """Return ``[(name, make_params(), successful, words in the reason)]``."""
        from rclpy.parameter import Parameter
        T = Parameter.Type
        nan, inf = math.nan, math.inf
        rng = self.rng

        def p(name, value, ptype=None):
            return Parameter(name, ptype, value) if ptype else Parameter(name, value=value)

        kernel = rng.standard_normal(KERNEL_SIZE).tolist()
        camera = p('fpoc.model', 'camera')
        bad_file, words = list(self.files.values())[rng.integers(len(self.files))]
        return [
            ('kernel-short', [p('policy.kernel', kernel[:-1])], False, 'must have 441 values'),
            ('kernel-long', [p('policy.kernel', kernel + [0.0])], False, 'must have 441'),
            ('kernel-nan', [p('policy.kernel', [nan] + kernel[1:])], False, 'must be finite'),
            ('kernel-inf', [p('policy.kernel', kernel[:-1] + [-inf])], False, 'finite'),
            ('kernel-all-nan', [p('policy.kernel', [nan] * KERNEL_SIZE)], False, 'finite'),
            ('kernel-ints', [p('policy.kernel', [int(v) for v in rng.integers(-3, 4,
                                                                              KERNEL_SIZE)])],
             True, ''),                                 # whole numbers: taken as doubles
            ('kernel-string', [p('policy.kernel', 'zeros')], False, 'Wrong parameter'),
            ('kernel-bools', [p('policy.kernel', [True] * KERNEL_SIZE)], False, 'Wrong'),
            ('grid-rows', [p('grid.rows', int(rng.integers(1, 300)))], False, 'read-only'),
            ('grid-cols', [p('grid.cols', 7)], False, 'read-only'),
            ('grid-spacing', [p('grid.spacing_deg', 1.0)], False, 'read-only'),
            ('grid-rows-string', [p('grid.rows', 'eleven')], False, ''),
            ('queue-depth', [p('evidence_queue_depth', 1)], False, 'read-only'),
            ('policy-name', [p('policy.name', 'saliency')], False, 'policy.name must be one of'),
            ('policy-name-int', [p('policy.name', 3)], False, 'Wrong parameter'),
            ('policy-action', [p('policy.action', 'softmax')], False, 'policy.action must be'),
            ('policy-file-bad', [p('policy.file', bad_file)], False, words),
            ('settle-negative', [p('settle_time_s', -1.0)], False, 'settle_time_s'),
            ('settle-nan', [p('settle_time_s', nan)], False, 'settle_time_s'),
            ('settle-int', [p('settle_time_s', 1)], False, 'Wrong parameter'),
            ('confidence-one', [p('confidence', 1.0)], False, 'confidence'),
            ('confidence-nan', [p('confidence', nan)], False, 'confidence'),
            # d' is only checked for the model that uses it: set both at once.
            ('dprime-negative', [camera, p('fpoc.dprime', -2.0)], False, 'dprime must be'),
            ('dprime-nan', [camera, p('fpoc.dprime', nan)], False, 'dprime must be finite'),
            ('dprime-inf', [camera, p('fpoc.dprime', inf)], False, 'dprime must be finite'),
            ('dprime-zero', [camera, p('fpoc.dprime', 0.0)], False, 'dprime must be finite'),
            ('dprime-text', [p('fpoc.dprime', 'four')], False, 'fpoc.dprime must be a number'),
            ('dprime-empty', [p('fpoc.dprime', [], T.DOUBLE_ARRAY)], False, 'fpoc.dprime'),
            ('fpoc-model', [p('fpoc.model', 'sonar')], False, 'fpoc.model must be one of'),
            ('fpoc-table-scalar', [p('fpoc.model', 'table')], False, 'table FPOC needs'),
            ('half-width-nan', [p('fpoc.half_width_deg', nan)], False, 'out of range'),
            ('start-row', [p('start_row', ROWS)], False, 'start_row must be -1 or in'),
            ('start-col', [p('start_col', -2)], False, 'start_col'),
            ('pan-limit', [p('pan_max_rad', 0.1)], False, 'outside the pan limits'),
            ('pan-limit-nan', [p('pan_min_rad', nan)], False, 'pan limits must be finite'),
            ('topic', [p('trajectory_topic', 'bad topic')], False, 'trajectory_topic'),
            ('image-scale', [p('belief_image_scale_px', 0)], False, 'out of range'),
            ('diagnostics-zero', [p('diagnostics_period_s', 0.0)], False, 'out of range'),
            ('seed-negative', [p('seed', -1)], False, 'out of range'),
            ('undeclared', [p('no.such.parameter', 1.0)], False, ''),
            # Valid changes: the node must take them, and keep its frames usable.
            ('policy-baseline', [p('policy.name', str(rng.choice(
                ['map', 'elm', 'center', 'spiral', 'random'])))], True, ''),
            ('kernel', [p('policy.kernel', kernel)], True, ''),
            ('policy-file', [p('policy.file', self.good_file)], True, ''),
            ('action', [p('policy.action', str(rng.choice(['argmax', 'sample'])))], True, ''),
            ('dprime', [p('fpoc.dprime', float(rng.uniform(2.0, 6.0)))], True, ''),
            ('human', [p('fpoc.model', str(rng.choice(['human', 'exponential', 'camera'])))],
             True, ''),
            ('confidence', [p('confidence', float(rng.uniform(0.5, 0.99)))], True, ''),
            ('seed', [p('seed', int(rng.integers(0, 1000)))], True, ''),
            ('start', [p('start_row', int(rng.integers(-1, ROWS)))], True, ''),
            ('retry', [p('retry_period_s', float(rng.choice([0.0, 0.5, 2.0])))], True, ''),
        ]

    def send(self, probe, count: int) -> dict:
        """Send ``count`` random requests; check each answer; return counts per outcome."""
        tally = {'accepted': 0, 'refused': 0}
        for _ in range(count):
            options = self.requests()
            name, values, successful, words = options[self.rng.integers(len(options))]
            if len(values) == 1:
                result = probe.set_parameters(CONTROLLER, values)[0]
            else:
                result = probe.set_parameters_atomically(CONTROLLER, values)
            assert result.successful == successful, (name, result.reason)
            if successful:
                tally['accepted'] += 1
                for v in values:
                    self.expected[v.name] = v.value
                if values[0].name in ('policy.kernel', 'policy.file'):
                    self.expected['policy.name'] = 'learned'
                    if values[0].name == 'policy.file':
                        self.expected['policy.kernel'] = []
            else:
                tally['refused'] += 1
                assert result.reason, name
                assert words in result.reason, (name, result.reason)
        return tally


def _publish(rig, topic, msg):
    rig['evidence' if topic == 'evidence' else 'image'].publish(msg)


def _wait_received(rig, total: int, timeout_s: float = 30.0) -> dict:
    diag = rig['diag']
    ok = wait_for(lambda: diag.counter('received') >= total, timeout_s, 0.002)
    assert ok, f'the controller received {diag.counter("received")} of {total} frames'
    return diag.counters()


def _run_fuzz(rig, messages: int, param_requests: int, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    frames = Frames(rng)
    kinds = frames.kind_names()
    diag, probe = rig['diag'], rig['probe']
    files = bad_policy_files(rig['folder'], ROWS, COLS)
    pfuzz = ParameterFuzz(rng, files, str(rig['folder'] / 'good.yaml'))
    start = diag.wait_fresh()
    want = {VALID: 0, REJECT: 0, SKIP: 0, 'applied': 0}
    sent, bursts = 0, max(1, math.ceil(messages / BURST))
    param_tally = {'accepted': 0, 'refused': 0}
    hostile_bursts = 0
    t0 = time.monotonic()
    for b in range(bursts):
        n = min(BURST, messages - sent)
        disabled = b % 10 == 9
        hostile = b % 25 == 12                     # d' so large every observed term overflows
        if disabled:
            assert probe.enable(False).success
        if hostile:
            hostile_bursts += 1
            policy = probe.get_parameters(CONTROLLER, ['policy.name'])['policy.name']
            # ELM's d'^2 would overflow.
            result = probe.set_parameters_atomically(CONTROLLER, _fpoc(1e300, 'map'))
            assert result.successful, result.reason
        for _ in range(n):
            kind = 'valid' if hostile else kinds[rng.integers(len(kinds))]
            topic, msg, outcome = frames.make(kind)
            _publish(rig, topic, msg)
            if hostile:
                outcome = REJECT
            elif outcome in (VALID, REFUSED_IN_USE) and disabled:
                outcome = SKIP
            elif outcome == REFUSED_IN_USE:
                outcome = REJECT
            want[outcome] += 1
            want['applied'] += outcome == VALID
        sent += n
        _wait_received(rig, start['received'] + sent)
        if disabled:
            assert probe.enable(True).success
        if hostile:
            result = probe.set_parameters_atomically(CONTROLLER, _fpoc(4.0, policy))
            assert result.successful, result.reason
            pfuzz.expected.update({'fpoc.model': 'camera', 'fpoc.dprime': 4.0})
            assert 'overflows' in diag.values.get('last_rejection', ''), \
                diag.values
        if b % 40 == 20:
            assert probe.reset().success
        share = param_requests * (b + 1) // bursts - param_requests * b // bursts
        for outcome, k in pfuzz.send(probe, share).items():
            param_tally[outcome] += k
    seconds = time.monotonic() - t0
    end = diag.wait_fresh()
    got = {k: end[k] - start[k] for k in ('received', 'applied', 'rejected', 'skipped')}
    return {'sent': sent, 'want': want, 'got': got, 'end': end, 'params': param_tally,
            'expected_params': pfuzz.expected, 'seconds': seconds,
            'hostile_bursts': hostile_bursts}


def _fpoc(dprime: float, policy: str) -> list:
    from rclpy.parameter import Parameter
    return [Parameter('fpoc.model', value='camera'), Parameter('fpoc.dprime', value=dprime),
            Parameter('policy.name', value=policy)]


@pytest.mark.parametrize('messages, param_requests', [
    pytest.param(3_000, 200, id='short'),
    pytest.param(100_000, 3_000, id='long', marks=pytest.mark.soak),
])
def test_fuzzed_controller_keeps_serving_and_counts_every_frame(fuzz, messages,
                                                                param_requests):
    report = _run_fuzz(fuzz, messages, param_requests, seed=messages)
    want, got, end = report['want'], report['got'], report['end']
    print(f"\nfuzz: sent {report['sent']} frames in {report['seconds']:.1f} s; controller "
          f"received {got['received']}, applied {got['applied']}, rejected {got['rejected']}, "
          f"skipped {got['skipped']} (predicted {want}); {report['params']['accepted']} "
          f"parameter requests accepted, {report['params']['refused']} refused")
    assert got['received'] == report['sent']
    assert got['applied'] == want['applied']
    assert got['rejected'] == want[REJECT]
    assert got['skipped'] == want[SKIP]
    assert end['received'] == end['applied'] + end['rejected'] + end['skipped']
    assert sum(report['params'].values()) == param_requests
    proc, diag = fuzz['proc'], fuzz['diag']
    assert proc.running, proc.output()[-3000:]
    # The valid parameter changes all took effect; nothing else changed.
    expected = report['expected_params']
    if expected:
        current = fuzz['probe'].get_parameters(CONTROLLER, list(expected))
        for name, value in expected.items():
            if isinstance(value, list) and value:
                np.testing.assert_array_equal(current[name], value, err_msg=name)
            else:
                assert current[name] == value or (value == [] and len(current[name]) == 0), name
    assert fuzz['probe'].get_parameters(
        CONTROLLER, ['grid.rows', 'grid.cols', 'evidence_queue_depth']) == {
        'grid.rows': ROWS, 'grid.cols': COLS, 'evidence_queue_depth': QUEUE}
    _assert_serving(fuzz)
    # Every rejection was counted with its reason; the log names the reason, throttled.
    warnings = [line for line in proc.output().splitlines()
                if 'rejected an evidence frame' in line]
    assert warnings and all(re.search(r'\(\d+ so far\): \S', line) for line in warnings)
    from ipomdp_gaze.nodes.controller import WARN_THROTTLE_S
    assert_throttled(warnings, WARN_THROTTLE_S)
    assert diag.values['last_rejection']


def _assert_serving(rig):
    """Check the services answer and a fresh search starts uniform and updates normally."""
    probe, belief, diag = rig['probe'], rig['belief'], rig['diag']
    frames = Frames(np.random.default_rng(0))
    assert probe.enable(True).success
    n = belief.count
    assert probe.reset().success
    assert wait_for(lambda: belief.count > n, 20)
    b = np.asarray(belief.msg.data, dtype=np.float64)
    np.testing.assert_allclose(b, 1 / N, rtol=1e-6)
    for kind in ('valid', 'valid-extreme', 'valid-nan'):
        n = belief.count
        _publish(rig, *frames.make(kind)[:2])
        assert wait_for(lambda: belief.count > n, 20), f'no belief after a {kind} frame'
        b = np.asarray(belief.msg.data, dtype=np.float64)
        assert b.size == N and np.all(np.isfinite(b)) and np.all(b >= 0)
        assert b.sum() == pytest.approx(1.0, abs=1e-5)
    diag.wait_fresh()
    values = diag.values
    assert math.isfinite(float(values['entropy_nats']))
    assert 0.0 <= float(values['most_likely_probability']) <= 1.0


def test_bad_policy_files_are_refused_parameters(fuzz, tmp_path):
    from rclpy.parameter import Parameter
    marker = tmp_path / 'unsafe-loader-was-used'
    files = bad_policy_files(tmp_path, ROWS, COLS, marker=marker)
    probe = fuzz['probe']
    before = probe.get_parameters(CONTROLLER, ['policy.name', 'policy.file', 'policy.kernel'])
    for name, (path, words) in files.items():
        result = probe.set_parameters(CONTROLLER, [Parameter('policy.file', value=path)])[0]
        assert not result.successful, name
        assert words in result.reason and '\n' not in result.reason, (name, result.reason)
    assert not marker.exists()
    after = probe.get_parameters(CONTROLLER, ['policy.name', 'policy.file', 'policy.kernel'])
    assert after['policy.name'] == before['policy.name']
    assert after['policy.file'] == before['policy.file']
    assert list(after['policy.kernel']) == list(before['policy.kernel'])
    assert fuzz['proc'].running
