# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The controller process on detection counts (``observation.model: counts``), this test the detector.

Covers: the ``fixation`` topic with every target sent, re-sends included; count frames applied
with the count model (counts above K-1 clipped); negative, fractional and infinite counts
rejected and counted with the belief unchanged; an observation file for another grid refused at
start-up and at run time.
"""
from __future__ import annotations

from conftest import config_path, wait_for
import numpy as np
import pytest

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'


class Detector:
    """This test as the foveal detector: sees fixations and beliefs, sends count frames."""

    def __init__(self, probe, nodes):
        from ipomdp_gaze.files.observation_file import load_observation
        from ipomdp_gaze.harness.watch import LATCHED
        from std_msgs.msg import Float32MultiArray, Int32MultiArray
        self.model = load_observation('faces-420-nmpt')     # a model without the scan
        self.grid = self.model.grid
        self.probe = probe
        self.fixations = probe.record(Int32MultiArray, 'fixation', LATCHED)
        self.beliefs = probe.record(Float32MultiArray, 'belief', 100)
        self.status = probe.search_status(NODE)
        self.evidence = probe.publisher(Float32MultiArray, 'evidence', 10)
        self.proc = nodes.start('controller', [
            '--params-file', config_path('faces_fovea_controller.yaml'),
            '-p', 'observation.file:=faces-420-nmpt', '-p', "policy.file:=''",
            '-p', 'retry_period_s:=0.3', '-p', 'policy.name:=map',
            '-p', 'diagnostics_period_s:=0.2', '-p', 'evidence_queue_depth:=10'])
        assert wait_for(lambda: self.fixations and self.evidence.get_subscription_count() > 0,
                        60), self.proc.output()

    def fixation(self) -> int:
        from ipomdp_gaze.msg_adapters import grid_arrays
        return grid_arrays.read_fixation(self.fixations[-1][1], self.grid)[0]

    def belief(self) -> np.ndarray:
        return np.asarray(self.beliefs[-1][1].data, dtype=np.float64)

    def send(self, counts) -> None:
        from ipomdp_gaze.msg_adapters import grid_arrays
        self.evidence.publish(grid_arrays.to_multiarray(counts, self.grid))


@pytest.fixture(scope='module')
def detector(probe, nodes):
    return Detector(probe, nodes)


def test_fixation_is_published_with_every_target_and_every_resend(detector):
    assert detector.fixation() == detector.grid.center_index
    n = len(detector.fixations)
    assert wait_for(lambda: len(detector.fixations) >= n + 3, 20)     # re-sent every 0.3 s
    sent = {tuple(m.data) for _, m in detector.fixations[n:]}
    assert len(sent) == 1 and next(iter(sent))[:2] == (10, 10)    # [row, col, search_id]
    assert 'observation.model is counts: the fpoc.* parameters are ignored' in \
        detector.proc.output()


def test_count_frames_are_applied_with_the_count_model_and_clipped(detector):
    from ipomdp_gaze.model.belief import bayes_update
    start = detector.fixation()
    prior = np.full(detector.grid.n_cells, 1 / detector.grid.n_cells)
    if detector.beliefs:
        prior = detector.belief()
    counts = np.zeros(detector.grid.n_cells)
    counts[detector.grid.index(3, 4)] = 25                         # above K - 1 = 9
    counts[detector.grid.index(12, 6)] = 2
    nb, nf = len(detector.beliefs), len(detector.fixations)
    detector.send(counts)
    assert wait_for(lambda: len(detector.beliefs) > nb and len(detector.fixations) > nf, 20)
    clipped = np.minimum(counts, 9)
    log_b = np.log(prior)
    bayes_update(log_b, detector.model.log_likelihood_ratio(clipped, start), out=log_b)
    np.testing.assert_allclose(detector.belief(), np.exp(log_b), rtol=1e-4, atol=1e-7)
    assert detector.fixation() == int(np.argmax(np.exp(log_b)))       # policy map


@pytest.mark.parametrize('bad, words', [(-1.0, 'counts must be integers >= 0'),
                                        (0.5, 'counts must be integers >= 0'),
                                        (np.inf, 'evidence contains +/-inf')])
def test_invalid_count_frames_are_rejected_and_counted(detector, bad, words):
    before = detector.status.wait_fresh()
    nb = len(detector.beliefs)
    counts = np.zeros(detector.grid.n_cells)
    counts[7] = bad
    detector.send(counts)
    want = before['rejected'] + 1
    assert wait_for(lambda: detector.status.counter('rejected') == want, 20), \
        detector.status.values
    assert words in detector.status.values['last_rejection']
    after = detector.status.counters()
    assert after['applied'] == before['applied'] and len(detector.beliefs) == nb


def test_an_observation_file_for_another_grid_is_refused(probe, nodes, detector):
    result = probe.set_parameters(NODE, {'observation.file': 'faces-pan-tilt'})[0]
    assert not result.successful
    assert "'faces-pan-tilt' is a count model for a 11x11 grid, not this 21x21 grid" in \
        result.reason
    assert probe.get_parameters(NODE, ['observation.file'])['observation.file'] == 'faces-420-nmpt'
    for args, words in (
            (['-p', 'observation.model:=counts', '-p', 'observation.file:=faces-420'],
             "'faces-420' is a count model for a 21x21 grid, not this 11x11 grid"),
            (['-p', 'observation.model:=counts'],
             'observation.model counts needs observation.file'),
            (['-p', 'observation.model:=counts', '-p', 'observation.file:=faces-pan-tilt',
              '-p', 'grid.spacing_deg:=4.0'], 'calibrated on a pan/tilt grid of 5.0 deg/cell')):
        # In a namespace the file's gaze_controller block does not apply: the defaults do.
        bad = nodes.start('controller', ['--params-file', config_path('controller.yaml'),
                                         '-r', '__ns:=/bad', *args])
        assert wait_for(lambda: not bad.running, 60)
        nodes.killed.append(bad)                                   # exited on purpose
        assert bad.proc.returncode == 1
        assert words in bad.output() and 'Traceback' not in bad.output(), bad.output()
