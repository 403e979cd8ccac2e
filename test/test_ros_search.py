# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The launch test with the simulated camera: both nodes as processes with the shipped YAML files.

A probe node watches ``belief``, ``pan_tilt``, ``belief_image``, ``found`` and ``ground_truth``.
For several seeds and targets the most likely cell is the target once its probability passes
0.999, where the controller (confidence 0.999) declares ``found`` and ends the search (the outcome
is asserted, not the trajectory: timing varies on a loaded machine).
"""
from __future__ import annotations

import math

from conftest import config_path, wait_for
import numpy as np
import pytest

pytestmark = pytest.mark.ros

CONTROLLER, CAMERA = 'gaze_controller', 'simulated_camera'
SEARCH_TIMEOUT_S = 60.0
CONFIDENCE = 0.999
# (camera seed, target or None for the camera's random draw, controller start cell or None).
CASES = [(11, None, None), (12, (0, 10), (0, 0)), (13, (10, 1), None), (14, None, (7, 2))]


@pytest.fixture(scope='module')
def rig(launch, probe):
    from ipomdp_gaze.harness.watch import SearchRecord
    from sensor_msgs.msg import Image

    search = SearchRecord(probe, depth=100)
    rec = {'belief': search.beliefs, 'pan_tilt': search.targets, 'found': search.found,
           'truth': search.truth, 'image': probe.record(Image, 'belief_image', 10)}
    controller = launch('controller', ['--params-file', config_path('controller.yaml'),
                                       '-p', f'confidence:={CONFIDENCE}'])
    camera = launch('camera', ['--params-file', config_path('camera.yaml')])
    assert wait_for(lambda: rec['pan_tilt'] and rec['truth'], 30), \
        controller.output() + camera.output()
    return rec


def _reset(probe, node):
    response = probe.reset(node)
    assert response.success, response.message
    return response.message


def _enable(probe, flag):
    response = probe.enable(flag, CONTROLLER)
    assert response.success
    return response.message


def _search(probe, rec, seed, target, start):
    """Run one search from a reset; return (beliefs, targets, truth, found) of this search."""
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import grid_arrays
    grid = Grid(11, 11, 5.0)
    _enable(probe, False)
    camera_params = {'seed': seed, 'target_row': -1, 'target_col': -1}
    if target is not None:
        camera_params.update({'target_row': target[0], 'target_col': target[1]})
    assert all(r.successful for r in probe.set_parameters(CAMERA, camera_params))
    start_params = {'start_row': -1, 'start_col': -1} if start is None else \
        {'start_row': start[0], 'start_col': start[1]}
    assert all(r.successful for r in probe.set_parameters(CONTROLLER, start_params))
    n_truth = len(rec['truth'])
    _reset(probe, CAMERA)
    assert wait_for(lambda: len(rec['truth']) > n_truth)
    truth = grid_arrays.cell_from_ground_truth(rec['truth'][-1][1], grid)
    n_belief, n_found, n_target = len(rec['belief']), len(rec['found']), len(rec['pan_tilt'])
    _reset(probe, CONTROLLER)
    # The reset publishes a uniform belief; everything after it belongs to this search.
    assert wait_for(lambda: any(np.ptp(np.asarray(m.data)) == 0
                                for _, m in rec['belief'][n_belief:]))
    first = n_belief + next(i for i, (_, m) in enumerate(rec['belief'][n_belief:])
                            if np.ptp(np.asarray(m.data)) == 0) + 1
    _enable(probe, True)

    def confident():
        return any(np.max(np.asarray(m.data)) >= CONFIDENCE for _, m in rec['belief'][first:])

    assert wait_for(confident, SEARCH_TIMEOUT_S), 'no belief reached 0.999'
    assert wait_for(lambda: len(rec['found']) > n_found, 10)
    beliefs = [grid_arrays.from_multiarray(m, grid) for _, m in rec['belief'][first:]]
    return beliefs, [m for _, m in rec['pan_tilt'][n_target:]], truth, rec['found'][n_found][1]


@pytest.fixture(scope='module')
def searches(rig, probe):
    return [(case, _search(probe, rig, *case)) for case in CASES]


def test_most_likely_cell_is_the_target_at_0999(searches):
    for (seed, target, _), (beliefs, _, truth, _) in searches:
        if target is not None:
            assert truth == target[0] * 11 + target[1]
        done = next(b for b in beliefs if b.max() >= CONFIDENCE)
        assert int(np.argmax(done)) == truth, f'seed {seed}: wrong cell at p >= 0.999'
    assert len({truth for _, (_, _, truth, _) in searches}) == len(CASES)


def test_found_event(searches):
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import diagnostics
    head = PanTiltMap(Grid(11, 11, 5.0))
    for _, (beliefs, _, _, found_msg) in searches:
        found = diagnostics.parse_found(found_msg)
        i = next(i for i, b in enumerate(beliefs) if b.max() >= CONFIDENCE)
        assert found['fixations'] == i + 1
        assert found['cell'] == int(np.argmax(beliefs[i])) == found['row'] * 11 + found['col']
        assert found['probability'] == pytest.approx(beliefs[i].max(), rel=1e-5)
        assert (found['pan_rad'], found['tilt_rad']) == pytest.approx(
            head.angles(found['cell']), abs=1e-5)


def test_belief_layout_and_normalisation(rig, searches):
    for _, msg in rig['belief']:
        dims = [(d.label, d.size, d.stride) for d in msg.layout.dim]
        assert dims == [('rows', 11, 121), ('cols', 11, 11)] and msg.layout.data_offset == 0
        b = np.asarray(msg.data, dtype=np.float64)
        assert b.size == 121 and np.all(b >= 0)
        assert b.sum() == pytest.approx(1.0, abs=1e-5)


def test_pan_tilt_angles_signs_and_start_cells(rig, searches):
    from rclpy.time import Time
    spacing = math.radians(5.0)
    for _, msg in rig['pan_tilt']:
        assert list(msg.name) == ['pan_joint', 'tilt_joint']
        assert Time.from_msg(msg.header.stamp).nanoseconds > 0
        col = 5 - msg.position[0] / spacing      # pan = -(col - 5) * spacing
        row = 5 + msg.position[1] / spacing      # tilt = (row - 5) * spacing
        assert abs(col - round(col)) < 1e-9 and abs(row - round(row)) < 1e-9
    for (_, _, start), (_, targets, _, _) in searches:
        row, col = (5, 5) if start is None else start
        assert targets[0].position[0] == pytest.approx(-(col - 5) * spacing, abs=1e-12)
        assert targets[0].position[1] == pytest.approx((row - 5) * spacing, abs=1e-12)


def test_belief_image_size_encoding_and_fixation_mark(rig, searches):
    from ipomdp_gaze.files.render import MARK_RGB
    from ipomdp_gaze.msg_adapters import images
    assert rig['image'], 'no belief_image received'
    msg = rig['image'][-1][1]
    assert (msg.encoding, msg.height, msg.width, msg.step) == ('rgb8', 352, 352, 1056)
    img = images.rgb8_array(msg)
    marked = np.all(img == MARK_RGB, axis=2)
    rows, cols = np.nonzero(marked)
    assert rows.size and rows.max() - rows.min() == 31 and cols.max() - cols.min() == 31


def test_shipped_kernel_or_the_elm_fallback(rig, probe):
    from ipomdp_gaze.policies.policy_file import shipped_kernels
    params = probe.get_parameters(CONTROLLER, ['policy.name', 'policy.file', 'policy.fallback'])
    assert params['policy.file'] == 'camera-11x11-infomax'
    if 'camera-11x11-infomax' in shipped_kernels():
        assert params['policy.name'] == 'learned'
    else:
        assert params['policy.name'] == params['policy.fallback'] == 'elm'
