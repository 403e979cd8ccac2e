# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The three-node face loop (scene camera, foveal detector, controller) with the detector killed.

The detector is killed (SIGKILL) in the middle of a camera-mode search of a held-out test
scene. Without it no evidence arrives: the controller keeps its belief and keeps re-sending its
target (``pan_tilt`` and ``fixation``). A new detector takes the latched fixation, the
re-sent target makes the scene camera take a new frame, and the search finishes on the face
(within one cell of its centre's cell) with every node still running.
"""
from __future__ import annotations

from conftest import wait_for
import numpy as np
import pytest

pytestmark = pytest.mark.ros

RETRY_S = 0.3


def _args(setup, node: str, extra=()) -> list:
    return next(list(args) for name, args in setup.nodes if name == node) + list(extra)


def test_detector_killed_mid_search_then_restarted_and_the_search_finishes(nodes, probe):
    from ipomdp_gaze.harness.demo import faces_setup
    from ipomdp_gaze.harness.watch import SearchRecord
    setup = faces_setup(fovea=False, seed=0)
    record = SearchRecord(probe, depth=200, updates_only=True)
    diag = probe.search_status()
    controller = nodes.start('controller', _args(setup, 'controller', [
        '-p', f'retry_period_s:={RETRY_S}', '-p', 'diagnostics_period_s:=0.1',
        '-p', 'confidence:=0.999', '-p', 'search.group_stop:=false',
        '-p', 'search.max_fixations:=20']))    # this search ends when the belief reaches 0.999
    detector = nodes.start('detector', _args(setup, 'detector'))
    assert wait_for(lambda: probe.node.count_subscribers('image') > 0, 60), detector.output()
    camera = nodes.start('scene_camera', _args(setup, 'scene_camera'))
    assert wait_for(lambda: diag.count > 0 and record.truth, 60), controller.output()

    def finished(since: int) -> bool:
        return record.reached(0.999, since) is not None

    for _ in range(5):                          # a search with an update that is not done
        n = len(record.beliefs)
        assert probe.reset().success
        assert wait_for(lambda: len(record.beliefs) >= n + 1, 60), controller.output()[-2000:]
        if not finished(n):
            break
    else:
        pytest.fail('every search finished at its first fixation')

    nodes.kill(detector)
    diag.wait_fresh()
    resends = int(diag.values['pan_tilt_resends'])
    assert wait_for(lambda: int(diag.values['pan_tilt_resends']) > resends, 30), diag.values
    kept = len(record.beliefs)                  # frames in flight at the kill have landed
    # No evidence without the detector, however often the controller re-sends its target.
    assert wait_for(lambda: int(diag.values['pan_tilt_resends']) >= resends + 4, 30), diag.values
    assert len(record.beliefs) == kept
    if finished(n):                             # a frame in flight ended it: search again
        n = len(record.beliefs)
        assert probe.reset().success
    detector = nodes.start('detector', _args(setup, 'detector'))
    assert wait_for(lambda: finished(n), 90), (detector.output()[-2000:],
                                               controller.output()[-2000:])
    assert len(record.beliefs) > kept           # the new detector's counts were applied
    done = record.belief(record.reached(0.999, n))
    row, col = setup.grid.cell(int(np.argmax(done)))
    truth = tuple(record.truth[-1][1].data)
    assert max(abs(row - truth[0]), abs(col - truth[1])) <= 1, ((row, col), truth)
    assert controller.running and camera.running and detector.running
