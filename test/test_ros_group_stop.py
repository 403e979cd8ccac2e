# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``search.group_stop`` over DDS: the controller process ends a search at a grouped detection.

This test plays the detector: a ``32FC4`` ``evidence_image`` (values, offsets, groups) with one
grouped detection makes the controller say ``found`` at that cell with ``ended: group``; frames
without groups (``32FC1``) never do, and the search goes on (docs/design.md section 6.15).
"""
from __future__ import annotations

from conftest import config_path, wait_for
import numpy as np
import pytest

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'


@pytest.fixture(scope='module')
def rig(launch, probe):
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.harness.watch import SearchRecord
    from ipomdp_gaze.model.grid import Grid
    from sensor_msgs.msg import Image
    search = SearchRecord(probe, depth=100)
    rig = {'grid': Grid(11, 11, 5.0), 'targets': search.targets, 'found': search.found,
           'beliefs': search.beliefs,
           'absent': probe.record(DiagnosticStatus, 'absent', 10),
           'image': probe.publisher(Image, 'evidence_image', 10)}
    proc = launch('controller', [
        '--params-file', config_path('controller.yaml'), '-p', 'settle_time_s:=0.0',
        '-p', 'policy.name:=elm', '-p', 'absent.prior:=0.5', '-p', 'confidence:=0.999',
        '-p', 'search.group_stop:=true', '-p', 'evidence_queue_depth:=10'])
    assert wait_for(lambda: rig['targets'], 30), proc.output()
    assert wait_for(lambda: rig['image'].get_subscription_count() > 0, 30)
    return rig


def _send(probe, rig, groups=None):
    from ipomdp_gaze.msg_adapters import images
    grid = rig['grid']
    values = np.zeros(grid.n_cells)
    offsets = None if groups is None else np.full((grid.n_cells, 2), np.nan)
    n = len(rig['beliefs'])
    stamp = probe.node.get_clock().now().to_msg()
    rig['image'].publish(images.evidence_image(values, grid, stamp, offsets=offsets,
                                               groups=groups))
    assert wait_for(lambda: len(rig['beliefs']) > n, 20)


def test_frames_without_groups_search_on_and_a_group_ends_the_search_there(probe, rig):
    from ipomdp_gaze.msg_adapters import diagnostics
    assert probe.reset(NODE).success
    n_found = len(rig['found'])
    for _ in range(2):
        _send(probe, rig)
    assert len(rig['found']) == n_found and not rig['absent']
    groups = np.zeros(rig['grid'].n_cells)
    groups[rig['grid'].index(2, 8)] = 1
    _send(probe, rig, groups)
    assert wait_for(lambda: len(rig['found']) > n_found, 20), 'no found event'
    msg = rig['found'][n_found][1]
    found = diagnostics.parse_found(msg)
    assert (found['row'], found['col'], found['ended'], found['fixations']) == (2, 8, 'group', 3)
    assert 'at a grouped detection of the detector' in msg.message
