# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``bench/ros/camera_rates.py`` counts a fixation's wait only while the camera streams.

The first fixation is commanded before the camera process sends its first image (the camera is
started once the nodes are up), and one commanded in a ``--stall`` waits for the camera to come
back; their waits measured the camera's start-up, not the transport, and were reported as
fixations that waited seconds for an image although the camera kept sending.
"""
from argparse import Namespace

from conftest import bench_module
import numpy as np

WALL_S = 1000.0                          # the wall clock minus the bench's monotonic one


def run_record(fixations, evidence_s, sent_s, stall=(None, None)) -> dict:
    """Build a measured run as ``run`` returns it (times in the bench's monotonic clock)."""
    sent = np.asarray([[(t + WALL_S) * 1e9, 0, 640, 480] for t in sent_s])
    return {'seconds': 10.0, 'evidence': [(t, t + WALL_S - 0.01, 'camera') for t in evidence_s],
            'fixations': fixations, 'sent': sent,
            'detector': {'images_received': len(sent_s), 'images_processed': len(evidence_s),
                         'images_rejected': 0, 'images_unused': 0, 'fixations_received': 3,
                         'detector_ms_median': 5.0, 'last_rejection': ''},
            'controller': {}, 'samples': {}, 'codes': {}, 'warnings': [], 'searches': 0,
            'stall': stall, 'wall_to_mono': WALL_S}


def wait_line(record) -> str:
    """Return the report's line on fixation waits."""
    rates = bench_module('camera_rates')
    args = Namespace(size='640x480', encoding='bgr8', rate_hz=30.0, switch='', stall=0.0,
                     bad_every=0, stamp_lag=0.0)
    return next(line for line in rates.report(record, args).splitlines()
                if line.startswith('fixation -> its evidence'))


def test_a_fixation_before_the_cameras_first_image_is_left_out_one_while_it_streams_counts():
    """3 s of camera start-up is not a wait; a 1.2 s wait while the camera streams is."""
    sent = np.arange(3.0, 10.0, 1 / 30)
    fixations = [(0.0, (-1, -1, 1)), (0.5, (-1, -1, 1)),          # before the camera, re-sent
                 (5.0, (4, 4, 1)), (7.0, (5, 5, 1))]
    line = wait_line(run_record(fixations, [3.02, 5.03, 8.2], sent))
    assert '1 commanded while the camera was not streaming left out' in line
    assert 'max 1200 ms; over 0.5 s: 1 of 2 (1.20 s)' in line


def test_a_fixation_in_a_stall_is_left_out():
    """With ``--stall`` the camera's two spans count; a fixation between them does not."""
    sent = np.concatenate([np.arange(1.0, 4.0, 1 / 30), np.arange(7.0, 10.0, 1 / 30)])
    fixations = [(2.0, (1, 1, 1)), (5.0, (2, 2, 1)), (8.0, (3, 3, 1))]
    line = wait_line(run_record(fixations, [2.04, 7.03, 8.05], sent, stall=(4.2, 6.0)))
    assert '1 commanded while the camera was not streaming left out' in line
    assert 'over 0.5 s: 0 of 2' in line
