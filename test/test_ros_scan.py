# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The one-time scan over DDS: the controller asks for it, takes it once per search, by search id.

The controller runs the shipped fovea configuration (``faces-420``, which has scan tables, and
its kernel); this test plays the detector. After a reset the controller sends the scan request
``fixation = [-1, -1, id]`` (and re-sends it) and takes nothing else; frames of another search
and fixation frames are skipped (counted); the scan frame tagged ``scan/<id>`` is applied once,
and the first fixation is the policy's choice on the scanned belief, exactly as the search session
of ``find`` picks it. A reset starts search ``id + 1``, whose scan is asked for again; the frames
of the previous search are skipped.
"""
from __future__ import annotations

from conftest import config_path, wait_for
import numpy as np
import pytest

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'


@pytest.fixture(scope='module')
def rig(probe, nodes):
    from ipomdp_gaze.harness.watch import LATCHED
    from sensor_msgs.msg import Image
    from std_msgs.msg import Int32MultiArray
    rec = {'fixations': probe.record(Int32MultiArray, 'fixation', LATCHED),
           'status': probe.search_status(NODE),
           'frames': probe.publisher(Image, 'evidence_image', 10)}
    rec['proc'] = nodes.start('controller', [
        '--params-file', config_path('faces_fovea_controller.yaml'),
        '-p', 'retry_period_s:=0.3', '-p', 'diagnostics_period_s:=0.2'])
    assert wait_for(lambda: rec['fixations'] and rec['frames'].get_subscription_count() > 0,
                    60), rec['proc'].output()
    return rec


def _last(rec) -> list:
    return list(rec['fixations'][-1][1].data)


def _send(rec, probe, counts, tag: str) -> None:
    from ipomdp_gaze.files.observation_file import load_observation
    from ipomdp_gaze.msg_adapters import images
    grid = load_observation('faces-420').grid
    stamp = probe.node.get_clock().now().to_msg()
    rec['frames'].publish(images.evidence_image(np.asarray(counts, float), grid, stamp, tag))


def _expected_first_fixation(scan_counts) -> int:
    """Return the search session's first fixation after this scan (find's rule)."""
    from ipomdp_gaze.files.observation_file import load_observation
    from ipomdp_gaze.policies.registry import build_policy
    from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
    model = load_observation('faces-420')
    policy = build_policy('learned', model.grid, model, file='faces-420-infomax')
    session = SearchSession(model.grid, model, policy,
                            SearchSettings(confidence=0.99, inhibit_return=True,
                                           stop_on_repeat=True))
    session.reset()
    session.scan(Frame(np.asarray(scan_counts, float), kind='scan'))
    return session.start()


def test_a_search_starts_with_the_scan_request_and_takes_only_its_scan(rig, probe):
    row, col, search_id = _last(rig)
    assert (row, col) == (-1, -1) and search_id >= 1
    n = len(rig['fixations'])
    assert wait_for(lambda: len(rig['fixations']) >= n + 2, 20)        # re-sent every 0.3 s
    assert {tuple(m.data) for _, m in rig['fixations'][n:]} == {(-1, -1, search_id)}
    status = rig['status']
    assert wait_for(lambda: status.counter('received') >= 0, 20)
    skipped = status.counter('skipped')
    zeros = np.zeros(21 * 21)
    _send(rig, probe, zeros, f'fixation/{search_id}')                 # not a scan: skipped
    _send(rig, probe, zeros, f'scan/{search_id + 7}')                 # another search's scan
    assert wait_for(lambda: status.counter('skipped') >= skipped + 2, 20), status.values
    assert _last(rig)[:2] == [-1, -1] and status.counter('applied') == 0
    scan = np.zeros(21 * 21)
    scan[4 * 21 + 15] = 6                                             # detections at (4, 15)
    _send(rig, probe, scan, f'scan/{search_id}')
    assert wait_for(lambda: _last(rig)[:2] != [-1, -1], 20), rig['proc'].output()
    row, col, same_id = _last(rig)
    assert same_id == search_id
    assert row * 21 + col == _expected_first_fixation(scan)
    assert wait_for(lambda: status.counter('applied') == 1, 20)
    _send(rig, probe, scan, f'scan/{search_id}')                      # a second scan: skipped
    assert wait_for(lambda: status.counter('skipped') >= skipped + 3, 20)
    assert status.counter('applied') == 1


def test_a_reset_starts_a_new_search_id_and_frames_of_the_old_one_are_skipped(rig, probe):
    old_id = _last(rig)[2]
    assert probe.reset(NODE).success
    assert wait_for(lambda: _last(rig) == [-1, -1, old_id + 1], 20)
    status = rig['status']
    skipped, applied = status.counter('skipped'), status.counter('applied')
    _send(rig, probe, np.zeros(21 * 21), f'fixation/{old_id}')
    _send(rig, probe, np.zeros(21 * 21), f'scan/{old_id}')
    assert wait_for(lambda: status.counter('skipped') >= skipped + 2, 20)
    assert status.counter('applied') == applied and _last(rig) == [-1, -1, old_id + 1]
    counters = status.counters()
    assert counters['received'] == counters['applied'] + counters['rejected'] + \
        counters['skipped']
