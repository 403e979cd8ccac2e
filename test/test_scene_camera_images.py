# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``bench/ros/scene_camera_images.py`` counts the images the scene camera published and the gaps.

The bench reads the camera's ``camera_info`` to know what was published, and that subscription
may itself miss messages: published is taken from the span of every stamp seen (the camera's
timer stamps are evenly spaced), and images the evidence answered are counted as published.
"""
from conftest import bench_module
import numpy as np

PERIOD_NS = 100_000_000                     # 10 Hz


def record(used, info, fixations, evidence_s) -> dict:
    """Build a measured run as ``run`` returns it (stamps in ns, times in seconds)."""
    return {'seconds': 10.0, 'profile': False, 'segments': [549408], 'rate_hz': 0.0,
            'info_stamps': list(info), 'used_stamps': list(used), 'image_reader': False,
            'reader_stamps': [], 'received': len(used),
            'detector': {'images_rejected': 0, 'detector_ms_median': 3.0}, 'searches': 1,
            'evidence': list(evidence_s), 'fixations': fixations, 'span': (0.0, 10.0),
            'cpu': {'camera': 0.02}, 'load': 1.0}


def test_lost_images_and_camera_info_missed_here_are_counted_from_the_stamps():
    """101 images sent, 6 in a row not answered (a 0.7 s gap), camera_info missed for 10."""
    bench = bench_module('scene_camera_images')
    sent = np.arange(101) * PERIOD_NS
    used = np.concatenate([sent[:51], sent[57:]])          # 5.1 s to 5.6 s never answered
    info = np.concatenate([sent[:90], sent[-1:]])           # the watch missed 9.0 s to 9.9 s
    fixations = [(4.95, (1, 1, 1)), (5.05, (2, 2, 1))]
    summary = bench.report(record(used, info, fixations, used * 1e-9 + 0.01))
    assert summary['published'] == 101
    assert summary['camera_info_missed_here'] == 10        # answered, camera_info not seen
    assert summary['images_skipped_between_used'] == 6
    assert summary['stamp_gaps_over_0.5s'] == [0.7]
    assert summary['waits_over_0.5s'] == [0.66]             # 5.05 s to 5.71 s
    assert summary['camera_rate_hz'] == 10.0


def test_a_run_without_fixations_is_reported_without_waits():
    """A reviewer's catch: the summary of a run no fixation was answered in crashed."""
    bench = bench_module('scene_camera_images')
    sent = np.arange(11) * PERIOD_NS
    summary = bench.report(record(sent, sent, [], []))
    assert summary['fixations'] == 0 and summary['wait_max_ms'] is None
    assert summary['published'] == 11 and summary['waits_over_0.5s'] == []
