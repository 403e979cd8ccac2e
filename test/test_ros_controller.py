# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The controller process alone, with this test playing the camera and the operator.

Covers: the kernel parameter set from another process through SetParameters (what ``ros2 param
set`` does), invalid parameter values rejected with their reason, malformed evidence rejected
and counted while the node keeps serving, NaN cells, ``reset``, ``enable`` and pan/tilt signs.
"""
from __future__ import annotations

import math

from conftest import config_path, wait_for
import numpy as np
import pytest
from robust_support import assert_throttled

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'
SPACING_RAD = math.radians(5.0)


class Camera:
    """This test as the camera: sends frames, sees the controller's beliefs and targets."""

    def __init__(self, probe, launch):
        from ipomdp_gaze.harness.watch import SearchRecord
        from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
        from ipomdp_gaze.model.grid import Grid
        from ipomdp_gaze.model.head import PanTiltMap
        from sensor_msgs.msg import Image
        from std_msgs.msg import Float32MultiArray
        self.grid = Grid(11, 11, 5.0)
        self.head = PanTiltMap(self.grid)
        self.d = dprime_matrix(self.grid, make_fpoc('camera', half_width_deg=10.0,
                                                    half_height_deg=10.0))
        self.probe = probe
        search = SearchRecord(probe, depth=100)
        self.beliefs, self.targets = search.beliefs, search.targets
        self.status = probe.search_status(NODE)
        self.evidence = probe.publisher(Float32MultiArray, 'evidence', 10)
        self.evidence_image = probe.publisher(Image, 'evidence_image', 10)
        self.proc = launch('controller', [
            '--params-file', config_path('controller.yaml'), '-p', 'settle_time_s:=0.0',
            '-p', 'diagnostics_period_s:=0.2', '-p', 'policy.name:=elm',
            # Frames sent back to back must all arrive (the default keeps only the newest).
            '-p', 'evidence_queue_depth:=10'])
        assert wait_for(lambda: self.targets, 30), self.proc.output()
        assert wait_for(lambda: self.evidence.get_subscription_count() > 0 and
                        self.evidence_image.get_subscription_count() > 0, 30)
        # The start-up belief went out before this probe was discovered: reset for a fresh one.
        _fresh_search(probe, self)

    # -- what the controller said ----------------------------------------------------------
    def belief(self, i=-1) -> np.ndarray:
        from ipomdp_gaze.msg_adapters import grid_arrays
        return grid_arrays.from_multiarray(self.beliefs[i][1], self.grid)

    def fixation(self, i=-1) -> int:
        from ipomdp_gaze.msg_adapters import joints
        return self.head.nearest_cell(*joints.angles_from_joint_state(self.targets[i][1],
                                                                      self.head))

    def counters(self) -> dict:
        return self.status.values

    def wait_counters(self, **want) -> dict:
        n = self.status.count
        ok = wait_for(lambda: self.status.count > n + 1 and all(
            self.counters().get(k) == str(v) for k, v in want.items()), 20)
        assert ok, f'diagnostics {self.counters()} never showed {want}'
        return self.counters()

    # -- sending -----------------------------------------------------------------------------
    def send(self, values, layout=None):
        from ipomdp_gaze.msg_adapters import grid_arrays
        from std_msgs.msg import Float32MultiArray
        if layout is None:
            msg = grid_arrays.to_multiarray(values, self.grid)
        else:
            msg = Float32MultiArray(layout=layout, data=list(np.asarray(values, np.float32)))
        self.evidence.publish(msg)

    def step(self, frame) -> tuple:
        """Send one valid frame; wait for the belief and the next target; return both."""
        nb, nt = len(self.beliefs), len(self.targets)
        self.send(frame)
        assert wait_for(lambda: len(self.beliefs) > nb and len(self.targets) > nt, 20)
        return self.belief(), self.fixation()

    def step_by_bayes(self, frame, belief=None, fixation=None) -> tuple:
        """
        Send one valid frame; check the new belief is Bayes' rule on the prior; return both.

        The prior is ``belief`` at ``fixation``, by default the last belief and target received.
        """
        if belief is None:
            belief, fixation = self.belief().astype(np.float64), self.fixation()
        got_belief, got_next = self.step(frame)
        np.testing.assert_allclose(got_belief, self.expected(belief, frame, fixation),
                                   rtol=1e-4, atol=1e-7)
        return got_belief, got_next

    def expected(self, belief, frame, fixation) -> np.ndarray:
        """Compute the posterior offline (float64 from the float32 frame)."""
        d = self.d[:, fixation]
        o = np.asarray(frame, np.float32).astype(np.float64)
        term = np.where(np.isnan(o), 0.0, d * (np.nan_to_num(o) - d / 2))
        log_b = np.log(np.maximum(belief, 1e-300)) + term
        return np.exp(log_b - np.logaddexp.reduce(log_b))


@pytest.fixture(scope='module')
def cam(probe, launch):
    return Camera(probe, launch)


def _enable(probe, flag):
    return probe.enable(flag, NODE)


def _reset(probe):
    return probe.reset(NODE)


def _set(probe, **values):
    names = {k.replace('__', '.'): v for k, v in values.items()}
    return probe.set_parameters(NODE, names)


def _fresh_search(probe, cam):
    """Reset and wait for the uniform belief and the start target."""
    nb, nt = len(cam.beliefs), len(cam.targets)
    assert _reset(probe).success
    assert wait_for(lambda: len(cam.beliefs) > nb and len(cam.targets) > nt, 20)
    np.testing.assert_allclose(cam.belief(), 1 / 121, rtol=1e-6)


def _frames(seed, n):
    return np.random.default_rng(seed).standard_normal((n, 121)).astype(np.float32)


def _conv_choice(kernel, belief):
    """Evaluate the kernel's next fixation offline, and its margin over the runner-up."""
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.policies.conv import ConvPolicy
    policy = ConvPolicy(Grid(11, 11, 5.0), np.asarray(kernel).reshape(21, 21))
    scores = policy.scores(belief[None])[0]
    top2 = np.sort(scores)[-2:]
    return int(policy.select(belief[None], 1, None)[0]), top2[1] - top2[0]


def test_kernel_set_remotely_drives_the_next_fixation(probe, cam):
    kernel = np.random.default_rng(7).standard_normal(441)      # asymmetric on purpose
    assert 'disabled' in _enable(probe, False).message
    results = _set(probe, policy__kernel=kernel.tolist())
    assert results[0].successful, results[0].reason
    params = probe.get_parameters(NODE, ['policy.name', 'policy.kernel'])
    assert params['policy.name'] == 'learned'
    np.testing.assert_array_equal(params['policy.kernel'], kernel)
    nb = len(cam.beliefs)
    assert _reset(probe).success
    assert wait_for(lambda: len(cam.beliefs) > nb)
    nt = len(cam.targets)
    assert _enable(probe, True).message == 'enabled'
    assert wait_for(lambda: len(cam.targets) > nt)
    assert cam.fixation() == 60                                  # the start cell
    belief = np.full(121, 1 / 121)
    for frame in _frames(1, 3):
        fixation = cam.fixation()
        got_belief, got_next = cam.step(frame)
        belief = cam.expected(belief, frame, fixation)
        np.testing.assert_allclose(got_belief, belief, rtol=1e-4, atol=1e-7)
        want_next, margin = _conv_choice(kernel, belief)
        assert margin > 1e-4
        assert got_next == want_next
        belief = got_belief.astype(np.float64)


@pytest.mark.parametrize('bad, words', [
    (np.zeros(440).tolist(), 'policy.kernel must have 441 values'),
    ([float('nan')] + [0.0] * 440, 'must be finite'),
    ([1] * 440, 'policy.kernel must have 441 values'),      # whole numbers: the same checks
])
def test_bad_kernel_is_rejected_and_the_old_one_stays(probe, cam, bad, words):
    old = np.random.default_rng(8).standard_normal(441)
    assert _set(probe, policy__kernel=old.tolist())[0].successful
    result = _set(probe, policy__kernel=bad)[0]
    assert not result.successful and words in result.reason, result.reason
    np.testing.assert_array_equal(probe.get_parameters(NODE, ['policy.kernel'])['policy.kernel'],
                                  old)
    # The node still fixates by the old kernel.
    got_belief, got_next = cam.step_by_bayes(_frames(99, 1)[0])
    assert got_next == _conv_choice(old, got_belief.astype(np.float64))[0]


@pytest.mark.parametrize('values, words', [
    ({'policy.name': 'foo'}, "policy.name must be one of 'learned', 'map'"),
    ({'grid.rows': 7}, 'read-only'),
    ({'settle_time_s': -1.0}, 'settle_time_s'),
    ({'start_row': 11}, 'start_row must be -1 or in 0..10'),
    ({'pan_max_rad': 0.1}, 'outside the pan limits'),
    ({'confidence': 1.0}, 'confidence must be between 0 and 1'),
    ({'fpoc.model': 'sonar'}, 'fpoc.model must be one of'),
    ({'fpoc.dprime': -2.0}, 'dprime must be finite and > 0'),
    ({'policy.action': 'softmax'}, 'policy.action must be one of'),
    ({'trajectory_topic': 'bad topic'}, 'trajectory_topic'),
    # a substitution rcl does not know is refused, not half-applied
    ({'forward_command_topic': '/x{y}'}, 'forward_command_topic: topic name'),
    ({'trajectory_topic': '~/cmd{x}'}, 'unknown substitution: {x}'),
    # rcl's caret picture under the fault would span three lines (QA)
    ({'forward_command_topic': 'a//b'}, "must not contain repeated '/' ('a//b')"),
    ({'search.false_alarm_scales': [2.0]}, 'needs a count model'),
    ({'search.view_time_s': 0.0}, 'search.view_time_s must be finite and > 0'),
    # settings the model cannot serve are refused before any of them applies
    ({'search.false_alarm_scales': [1.0, 2.0]}, 'needs a count model'),
    ({'search.absent_needs_coverage': True}, 'needs a pan/tilt count model'),
    ({'belief.prior': [1.0] * 120}, 'belief.prior must hold one weight per cell, 121 values'),
    ({'belief.prior': [-1.0] + [1.0] * 120},
     'belief.prior weights must be >= 0: cell (0, 0) is -1'),
])
def test_invalid_parameters_are_rejected_with_a_reason(probe, cam, values, words):
    before = probe.get_parameters(NODE, list(values))
    result = probe.set_parameters(NODE, values)[0]
    assert not result.successful
    assert words in result.reason, result.reason
    assert '\n' not in result.reason, result.reason
    assert probe.get_parameters(NODE, list(values)) == before


def test_a_prior_set_remotely_is_where_the_next_search_starts(probe, cam):
    """belief.prior: the reset's belief is the prior, then Bayes' rule goes on from it."""
    from ipomdp_gaze.harness.watch import is_update
    weights = np.ones(121)
    weights[:11] = 0.0                           # the top row ruled out
    weights[60] = 20.0
    try:
        results = _set(probe, belief__prior=weights.tolist())
        assert results[0].successful, results[0].reason
        assert wait_for(lambda: 'belief.prior placing the target from the next search '
                        '(~/reset)' in cam.proc.output(), 20), cam.proc.output()[-2000:]
        cam.wait_counters(prior='belief.prior')
        nb, nt = len(cam.beliefs), len(cam.targets)
        assert _reset(probe).success
        assert wait_for(lambda: len(cam.beliefs) > nb and len(cam.targets) > nt, 20)
        prior = weights / weights.sum()
        np.testing.assert_allclose(cam.belief(), prior, rtol=1e-6)
        # The watch, the demo and the soak tell this reset from a fixation's update (QA).
        assert not is_update(cam.beliefs[-1][1], [prior]) and is_update(cam.beliefs[-1][1])
        for frame in _frames(3, 2):
            got_belief, _ = cam.step_by_bayes(frame)
            assert np.all(got_belief[:11] == 0)
            assert is_update(cam.beliefs[-1][1], [prior])
    finally:                                     # an empty array: the uniform prior again
        from rclpy.parameter import Parameter
        empty = Parameter('belief.prior', Parameter.Type.DOUBLE_ARRAY, [])
        assert _set(probe, belief__prior=empty)[0].successful
    cam.wait_counters(prior='uniform')
    _fresh_search(probe, cam)


def test_malformed_evidence_is_rejected_counted_and_throttled(probe, cam):
    from sensor_msgs.msg import Image
    from std_msgs.msg import MultiArrayDimension, MultiArrayLayout

    before = cam.wait_counters()            # fresh: /diagnostics comes once a second
    belief, fixation, nb, nt = cam.belief(), cam.fixation(), len(cam.beliefs), len(cam.targets)
    seven = MultiArrayLayout(dim=[MultiArrayDimension(label='rows', size=7, stride=49),
                                  MultiArrayDimension(label='cols', size=7, stride=7)])
    good = _frames(5, 1)[0]
    cam.send(good[:120], layout=MultiArrayLayout())                  # wrong length
    cam.send(np.where(np.arange(121) == 3, np.inf, good))             # +inf
    cam.send(np.where(np.arange(121) == 4, -np.inf, good))            # -inf
    cam.send(good[:49], layout=seven)                                 # a 7x7 layout
    cam.send(good, layout=MultiArrayLayout(dim=seven.dim, data_offset=0))  # layout vs length
    cam.evidence_image.publish(Image(height=11, width=11, encoding='mono8', step=11,
                                     data=bytes(121)))
    rejected = int(before['frames_rejected']) + 6
    after = cam.wait_counters(frames_rejected=rejected)
    assert int(after['frames_applied']) == int(before['frames_applied'])
    assert int(after['frames_received']) == int(after['frames_applied']) + rejected + int(
        after['frames_skipped'])
    assert len(cam.beliefs) == nb and len(cam.targets) == nt          # belief unchanged
    warnings = [line for line in cam.proc.output().splitlines()
                if 'rejected an evidence frame' in line]
    assert warnings and len(warnings) <= rejected, warnings
    from ipomdp_gaze.nodes.controller import WARN_THROTTLE_S
    assert_throttled(warnings, WARN_THROTTLE_S)
    # The node keeps serving: a good frame is applied to the unchanged belief.
    cam.step_by_bayes(good, belief, fixation)


def test_nan_cells_are_unobserved(probe, cam):
    frame = _frames(6, 1)[0]
    frame[::3] = np.nan
    cam.step_by_bayes(frame)


def test_stamped_evidence_image_is_used(probe, cam):
    from ipomdp_gaze.msg_adapters import images
    belief, fixation = cam.belief().astype(np.float64), cam.fixation()
    frame = _frames(8, 1)[0]
    nb = len(cam.beliefs)
    stamp = cam.probe.node.get_clock().now().to_msg()
    cam.evidence_image.publish(images.evidence_image(frame, cam.grid, stamp))
    assert wait_for(lambda: len(cam.beliefs) > nb, 20)
    np.testing.assert_allclose(cam.belief(), cam.expected(belief, frame, fixation),
                               rtol=1e-4, atol=1e-7)


def test_evidence_image_with_a_non_ascii_digit_tag_is_read_as_untagged(probe, cam):
    # 'fixation/²' passed str.isdigit() and then failed int(): the frame was lost as a callback
    # error, outside frames_received. Any frame_id that is not a tag reads as untagged.
    from ipomdp_gaze.msg_adapters import images
    callbacks = probe.status_values('gaze_controller: callbacks')
    before = cam.wait_counters()
    belief, fixation = cam.belief().astype(np.float64), cam.fixation()
    frame = _frames(9, 1)[0]
    msg = images.evidence_image(frame, cam.grid, cam.probe.node.get_clock().now().to_msg())
    msg.header.frame_id = 'fixation/\u00b2'
    nb = len(cam.beliefs)
    cam.evidence_image.publish(msg)
    assert wait_for(lambda: len(cam.beliefs) > nb, 20)
    np.testing.assert_allclose(cam.belief(), cam.expected(belief, frame, fixation),
                               rtol=1e-4, atol=1e-7)
    after = cam.wait_counters(frames_applied=int(before['frames_applied']) + 1)
    assert int(after['frames_received']) == int(before['frames_received']) + 1
    n = len(callbacks)
    assert wait_for(lambda: len(callbacks) > n, 20)
    assert callbacks[-1]['callback_errors'] == '0', callbacks[-1]


def test_disable_skips_frames_enable_resends_reset_restarts(probe, cam):
    before = cam.wait_counters()            # fresh: /diagnostics comes once a second
    fixation, nb, nt = cam.fixation(), len(cam.beliefs), len(cam.targets)
    assert _enable(probe, False).message == 'disabled'
    assert _enable(probe, False).message == 'already disabled'
    cam.send(_frames(9, 1)[0])
    cam.wait_counters(frames_skipped=int(before['frames_skipped']) + 1, enabled='false')
    assert len(cam.beliefs) == nb and len(cam.targets) == nt
    old_stamp = cam.targets[-1][1].header.stamp
    assert _enable(probe, True).message == 'enabled'
    assert wait_for(lambda: len(cam.targets) > nt)
    assert cam.fixation() == fixation and cam.targets[-1][1].header.stamp != old_stamp
    cam.step(_frames(10, 1)[0])
    _fresh_search(probe, cam)
    assert cam.fixation() == 60
    assert _reset(probe).message == 'belief reset; looking at (5, 5)'


@pytest.mark.parametrize('params, cell, pan_deg, tilt_deg', [
    ({'start_row': 0, 'start_col': 0}, (0, 0), 25.0, -25.0),
    ({'start_row': 10, 'start_col': 3}, (10, 3), 10.0, 25.0),
    ({'start_row': 10, 'start_col': 3, 'pan_sign': -1}, (10, 3), -10.0, 25.0),
    ({'start_row': 2, 'start_col': 8, 'tilt_sign': -1, 'pan_offset_rad': 0.5},
     (2, 8), -15.0 + math.degrees(0.5), 15.0),
])
def test_pan_tilt_of_known_cells_and_signs(probe, cam, params, cell, pan_deg, tilt_deg):
    defaults = {'start_row': -1, 'start_col': -1, 'pan_sign': 1, 'tilt_sign': 1,
                'pan_offset_rad': 0.0}
    try:
        results = probe.set_parameters(NODE, params)
        assert all(r.successful for r in results), [r.reason for r in results]
        want = (math.radians(pan_deg), math.radians(tilt_deg))
        assert _reset(probe).message == f'belief reset; looking at {cell}'
        # A sign or offset change re-sends the current target first; the reset's comes last.
        wait_for(lambda: np.allclose(cam.targets[-1][1].position, want, atol=1e-9), 20)
        msg = cam.targets[-1][1]
        assert list(msg.name) == ['pan_joint', 'tilt_joint']
        assert msg.position[0] == pytest.approx(want[0], abs=1e-9)
        assert msg.position[1] == pytest.approx(want[1], abs=1e-9)
    finally:
        probe.set_parameters(NODE, defaults)


@pytest.fixture(scope='module')
def policy_files(tmp_path_factory):
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.policies.policy_file import PolicySpec, save_policy
    folder = tmp_path_factory.mktemp('policies')
    camera = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)
    files = {}
    for name, grid, fpoc in (('match', Grid(11, 11, 5.0), camera),
                             ('human', Grid(11, 11, 5.0), make_fpoc('human')),
                             ('small', Grid(7, 7, 5.0), camera)):
        kernel = np.random.default_rng(len(files) + 20).standard_normal(grid.kernel_shape)
        spec = PolicySpec(grid=grid, fpoc=fpoc, reward='infomax', family='conv', kernel=kernel)
        files[name] = (str(save_policy(folder / f'{name}.yaml', spec)), kernel)
    return files


def test_policy_file_set_remotely(probe, cam, policy_files):
    path, kernel = policy_files['match']
    result = _set(probe, policy__file=path)[0]
    assert result.successful and result.reason == ''
    params = probe.get_parameters(NODE, ['policy.name', 'policy.kernel'])
    assert params['policy.name'] == 'learned' and list(params['policy.kernel']) == []
    got_belief, got_next = cam.step_by_bayes(_frames(30, 1)[0])
    assert got_next == _conv_choice(kernel, got_belief.astype(np.float64))[0]
    # Trained on another FPOC: accepted, with a warning in the node's log.
    assert _set(probe, policy__file=policy_files['human'][0])[0].successful
    assert wait_for(lambda: 'policy was trained for FPOC' in cam.proc.output(), 10)
    # Another grid, or no such file: refused, nothing changes.
    for source, words in ((policy_files['small'][0], 'policy is for a 7x7 grid'),
                          ('/no/such/file.yaml', 'not found')):
        result = _set(probe, policy__file=source)[0]
        assert not result.successful and words in result.reason, result.reason
        assert probe.get_parameters(NODE, ['policy.file'])['policy.file'] == \
            policy_files['human'][0]


def test_ros2_control_outputs_follow_their_topic_parameters(probe, cam):
    from std_msgs.msg import Float64MultiArray
    from trajectory_msgs.msg import JointTrajectory
    forward = probe.record(Float64MultiArray, 'head/commands', 10)
    trajectory = probe.record(JointTrajectory, 'head/joint_trajectory', 10)
    results = _set(probe, forward_command_topic='head/commands',
                   trajectory_topic='head/joint_trajectory', trajectory_duration_s=0.25)
    assert all(r.successful for r in results)
    # A publisher created at run time needs discovery before its messages arrive.
    assert wait_for(lambda: probe.node.count_publishers('head/commands') > 0 and
                    probe.node.count_publishers('head/joint_trajectory') > 0, 20)
    for _ in range(10):
        cam.step(_frames(40 + len(forward), 1)[0])
        if forward and trajectory:
            break
    assert forward and trajectory
    target = cam.targets[-1][1]
    np.testing.assert_allclose(forward[-1][1].data, target.position)
    point = trajectory[-1][1].points[0]
    assert list(trajectory[-1][1].joint_names) == ['pan_joint', 'tilt_joint']
    np.testing.assert_allclose(point.positions, target.position)
    assert (point.time_from_start.sec, point.time_from_start.nanosec) == (0, 250_000_000)
    assert all(r.successful for r in _set(probe, forward_command_topic='', trajectory_topic=''))
    assert wait_for(lambda: probe.node.count_publishers('head/commands') == 0, 20)
    n = len(forward)
    cam.step(_frames(50, 1)[0])
    assert len(forward) == n


def test_a_frame_taken_before_the_head_settled_is_asked_for_again_once_it_has(probe, cam):
    import time
    from std_msgs.msg import Int32MultiArray
    fixations = probe.record(Int32MultiArray, 'fixation', 20)
    assert all(r.successful for r in _set(probe, settle_time_s=0.8, retry_period_s=60.0))
    try:
        _fresh_search(probe, cam)
        assert wait_for(lambda: fixations, 10)
        n_fix, n_targets, nb = len(fixations), len(cam.targets), len(cam.beliefs)
        skipped = int(cam.counters().get('frames_skipped', 0))
        sent = time.monotonic()
        cam.send(_frames(60, 1)[0])            # a detector's image of a head that came fast
        # asked again for the fixation alone once it settled: not after retry_period_s (60 s),
        # and no new target for the head
        assert wait_for(lambda: len(fixations) > n_fix, 10)
        assert 0.3 < time.monotonic() - sent < 5.0
        assert len(cam.targets) == n_targets and len(cam.beliefs) == nb
        assert list(fixations[-1][1].data) == list(fixations[n_fix - 1][1].data)
        assert int(cam.wait_counters()['frames_skipped']) == skipped + 1
        cam.step(_frames(61, 1)[0])            # the image taken after it: applied
    finally:
        assert all(r.successful for r in _set(probe, settle_time_s=0.0, retry_period_s=1.0))


def test_a_prior_given_at_start_up_is_said_and_a_bad_one_ends_the_node(nodes):
    """QA (upgrading): the start-up line says belief.prior places the target; a bad one: a line."""
    weights = ', '.join(['1.0'] * 120 + ['5.0'])
    good = nodes.start('controller', ['-r', '__ns:=/prior', '-p', f'belief.prior:=[{weights}]'])
    assert wait_for(lambda: 'first fixation' in good.output(), 60), good.output()
    assert 'a still target placed by belief.prior (not uniform over the cells)' in good.output()
    assert good.stop() == 0
    nodes.killed.append(good)
    short = ', '.join(['1.0'] * 120)
    bad = nodes.start('controller', ['-r', '__ns:=/prior_bad', '-p', f'belief.prior:=[{short}]'])
    assert wait_for(lambda: not bad.running, 60)
    nodes.killed.append(bad)                                   # exited on purpose
    assert bad.proc.returncode == 1
    assert 'belief.prior must hold one weight per cell, 121 values' in bad.output()
    assert 'Traceback' not in bad.output(), bad.output()
