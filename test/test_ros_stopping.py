# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Absent and found over DDS: the controller and the simulated camera as processes.

The controller has ``absent.prior`` 0.5 and ``confidence`` 0.999, so a wrong decision has a
probability of at most 0.001 per search and the seeds are fixed: a camera with an empty scene is
declared ``absent``, one with a target ``found`` at its cell. A still search then ends: frames are
skipped and no new target is sent until ``~/reset``. With motion on, the controller keeps
tracking after ``found``. Invalid values of the new parameters are refused with their reason.
"""
from __future__ import annotations

from conftest import config_path, wait_for
import numpy as np
import pytest

pytestmark = pytest.mark.ros

CONTROLLER, CAMERA = 'gaze_controller', 'simulated_camera'
CONFIDENCE = 0.999
SEARCH_TIMEOUT_S = 90.0


@pytest.fixture(scope='module')
def rig(launch, probe):
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.harness.watch import SearchRecord
    from std_msgs.msg import Float32MultiArray

    search = SearchRecord(probe, depth=200)
    rec = {'search': search, 'belief': search.beliefs, 'targets': search.targets,
           'found': search.found, 'truth': search.truth,
           'absent': probe.record(DiagnosticStatus, 'absent', 10),
           'gave_up': probe.record(DiagnosticStatus, 'gave_up', 10),
           'status': probe.search_status(CONTROLLER),
           'evidence': probe.publisher(Float32MultiArray, 'evidence', 10)}
    controller = launch('controller', [
        '--params-file', config_path('controller.yaml'), '-p', 'absent.prior:=0.5',
        '-p', f'confidence:={CONFIDENCE}', '-p', 'diagnostics_period_s:=0.2'])
    camera = launch('camera', ['--params-file', config_path('camera.yaml')])
    assert wait_for(lambda: rec['targets'] and rec['truth'], 60), \
        controller.output() + camera.output()
    return rec


def _search(probe, rec, camera_params, event):
    """
    Run one search from a reset; return its beliefs, its event and the other events during it.

    The beliefs are those since the reset's (uniform) one; the other events are those of the
    other kind (``found`` for ``absent``) from the reset on.
    """
    from ipomdp_gaze.msg_adapters.diagnostics import values_of
    other = 'found' if event == 'absent' else 'absent'
    assert probe.enable(False, CONTROLLER).success
    results = probe.set_parameters(CAMERA, camera_params)
    assert all(r.successful for r in results), [r.reason for r in results]
    n_truth = len(rec['truth'])
    assert probe.reset(CAMERA).success
    assert wait_for(lambda: len(rec['truth']) > n_truth)
    n_belief = len(rec['belief'])
    assert probe.reset(CONTROLLER).success
    assert wait_for(lambda: any(np.ptp(np.asarray(m.data)) == 0
                                for _, m in rec['belief'][n_belief:]))
    first = n_belief + next(i for i, (_, m) in enumerate(rec['belief'][n_belief:])
                            if np.ptp(np.asarray(m.data)) == 0) + 1
    # Events are counted from the reset's belief on, while the controller is still disabled: an
    # event of the search before (the start-up one, deciding while enable(False) was on its way
    # under load) may arrive after enable(False) has returned.
    n_event, n_other = len(rec[event]), len(rec[other])
    assert probe.enable(True, CONTROLLER).success
    assert wait_for(lambda: len(rec[event]) > n_event, SEARCH_TIMEOUT_S), f'no {event} event'
    msg = rec[event][n_event][1]
    # The deciding frame's belief is published before its event, but on another topic: under
    # load the event can be taken first. Wait for a belief per fixation (the callers check it).
    fixations = int(values_of(msg)['fixations'])
    wait_for(lambda: len(rec['belief']) - first >= fixations, 30)
    return [np.asarray(m.data, np.float64) for _, m in rec['belief'][first:]], msg, \
        len(rec[other]) - n_other


@pytest.fixture(scope='module')
def absent_search(rig, probe):
    return _search(probe, rig, {'empty_scene': True, 'seed': 5}, 'absent')


@pytest.fixture(scope='module')
def found_search(rig, probe, absent_search):
    return _search(probe, rig, {'empty_scene': False, 'target_row': 2, 'target_col': 8,
                                'seed': 6}, 'found')


def test_an_empty_scene_is_declared_absent(rig, absent_search):
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays
    beliefs, msg, founds = absent_search
    assert grid_arrays.cell_from_ground_truth(rig['truth'][-1][1], Grid(11, 11, 5.0)) is None
    absent = diagnostics.parse_absent(msg)
    assert absent['probability'] >= CONFIDENCE and founds == 0
    # The belief topic carries the cells: they sum to 1 - P(absent), first 0.5, then about 0.
    assert absent['fixations'] == len(beliefs)
    assert beliefs[-1].sum() == pytest.approx(1 - absent['probability'], abs=1e-5)
    assert all(b.sum() < 0.5 + 1e-5 for b in beliefs)
    assert msg.name.endswith('gaze_controller: absent')
    assert wait_for(lambda: rig['status'].values.get('decision') == 'absent', 10)
    assert float(rig['status'].values['absent_probability']) >= CONFIDENCE
    assert rig['status'].message == 'target absent'


def test_a_target_is_found_at_its_cell(rig, found_search):
    from ipomdp_gaze.msg_adapters import diagnostics
    beliefs, msg, absents = found_search
    found = diagnostics.parse_found(msg)
    assert (found['row'], found['col']) == (2, 8) and absents == 0
    assert found['probability'] >= CONFIDENCE and found['fixations'] == len(beliefs)
    assert int(np.argmax(beliefs[-1])) == found['cell']
    assert beliefs[-1].max() == pytest.approx(found['probability'], rel=1e-5)


def test_no_new_target_after_a_decision_until_reset(rig, probe, found_search):
    status = rig['status']
    assert wait_for(lambda: status.values.get('search_ended') == 'true', 10)
    n_target, n_belief = len(rig['targets']), len(rig['belief'])
    skipped = int(status.values['frames_skipped'])
    frame = np.random.default_rng(0).standard_normal(121).astype(np.float32)
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import grid_arrays
    msg = grid_arrays.to_multiarray(frame, Grid(11, 11, 5.0))
    for _ in range(3):              # frames that arrive after the decision are skipped
        count = int(status.values['frames_skipped'])
        rig['evidence'].publish(msg)
        assert wait_for(lambda: int(status.values['frames_skipped']) > count, 10)
    assert int(status.values['frames_skipped']) >= skipped + 3
    assert len(rig['targets']) == n_target and len(rig['belief']) == n_belief
    assert status.values['decision'] == 'found' and status.message == 'target found'
    # ~/reset starts a new search: the start cell is sent, and the camera's frame is used.
    assert probe.reset(CONTROLLER).success
    assert wait_for(lambda: len(rig['targets']) >= n_target + 2, 30)
    assert wait_for(lambda: status.values.get('search_ended') == 'false', 10)


def test_with_motion_the_controller_keeps_tracking_after_found(rig, probe, found_search):
    from ipomdp_gaze.msg_adapters import diagnostics
    moving = {'target_motion_sigma_cells': 0.5, 'target_motion_rate_hz': 4.0}
    try:
        results = probe.set_parameters(CONTROLLER, {'motion.sigma_cells': 1.0,
                                                    'absent.prior': 0.0})
        assert all(r.successful for r in results), [r.reason for r in results]
        _, msg, _ = _search(probe, rig, {**moving, 'empty_scene': False, 'target_row': -1,
                                         'target_col': -1, 'seed': 9}, 'found')
        n_target = len(rig['targets'])
        fixations = diagnostics.parse_found(msg)['fixations']
        assert wait_for(lambda: len(rig['targets']) >= n_target + 3, 30), 'tracking stopped'
        assert rig['status'].values.get('search_ended') == 'false'
        assert wait_for(lambda: int(rig['status'].values['fixations']) > fixations + 2, 10)
    finally:
        probe.set_parameters(CAMERA, {'target_motion_sigma_cells': 0.0,
                                      'target_motion_rate_hz': 0.0})
        probe.set_parameters(CONTROLLER, {'motion.sigma_cells': 0.0, 'absent.prior': 0.5})


@pytest.mark.parametrize('node, values, words', [
    (CONTROLLER, {'motion.sigma_cells': -1.0}, 'motion.sigma_cells must be finite and >= 0'),
    (CONTROLLER, {'motion.jump_prob': 1.0}, 'motion.jump_prob must be a probability in [0, 1)'),
    (CONTROLLER, {'motion.jump_prob': -0.1}, 'motion.jump_prob must be a probability'),
    (CONTROLLER, {'absent.prior': 1.0}, 'absent.prior must be a probability in [0, 1)'),
    (CONTROLLER, {'absent.prior': 2.5}, 'absent.prior must be a probability in [0, 1)'),
    (CONTROLLER, {'search.max_fixations': -3}, 'search.max_fixations'),
    (CONTROLLER, {'search.repeat_weight': 1.5}, 'search.repeat_weight'),
    (CONTROLLER, {'search.repeat_weight': -0.25}, 'search.repeat_weight'),
    (CONTROLLER, {'search.hotspot_prior': 0.75}, 'search.hotspot_prior must be in [0, 0.5]'),
    (CONTROLLER, {'search.hotspot_scale': 0.5}, 'search.hotspot_scale must be a finite factor'),
    (CAMERA, {'target_motion_sigma_cells': -0.5}, 'target_motion_sigma_cells must be finite'),
    (CAMERA, {'target_jump_prob': 1.0}, 'target_jump_prob must be a probability in [0, 1)'),
])
def test_bad_values_are_refused_with_a_reason(rig, probe, node, values, words):
    before = probe.get_parameters(node, list(values))
    result = probe.set_parameters(node, values)[0]
    assert not result.successful
    assert words in result.reason, result.reason
    assert probe.get_parameters(node, list(values)) == before
