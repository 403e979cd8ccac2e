# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A moving many-target search whose `motion.keep_probability` is above its `confidence`, on DDS.

QA: with ``search.targets many`` and motion on, a person whose cells held it at the confidence
but below a higher keep probability was ``lost`` and ``reacquired`` in the same frame, at the
same cell (``0.00 s after it was lost``), the ``lost`` event naming a probability at the
confidence. One target holds ``found`` at the confidence whatever the keep probability; many
targets now do the same. The controller (weak evidence, so that the person's probability
hovers near the confidence) and the simulated camera, a still person, run as processes.
"""
from __future__ import annotations

from conftest import config_path, people_controller_args, wait_for
import pytest

pytestmark = pytest.mark.ros

CONTROLLER = 'gaze_controller'
PERSON = (2, 8)
CONFIDENCE = 0.95
DPRIME = '2.0'
FIXATIONS_AFTER_FOUND = 60
TIMEOUT_S = 120.0


def test_a_keep_probability_above_the_confidence_loses_nobody_held_at_the_confidence(
        launch, probe):
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.msg_adapters import diagnostics
    found = probe.record(DiagnosticStatus, 'found', 10)
    lost = probe.record(DiagnosticStatus, 'lost', 1000)
    again = probe.record(DiagnosticStatus, 'reacquired', 1000)
    status = probe.search_status(CONTROLLER)
    controller = launch('controller', people_controller_args(
        0.999, '-p', f'confidence:={CONFIDENCE}', '-p', f'fpoc.dprime:={DPRIME}'))
    assert wait_for(lambda: all(probe.matched(t) for t in ('found', 'lost', 'reacquired')),
                    30), controller.output()
    camera = launch('camera', ['--params-file', config_path('camera.yaml'),
                               '-p', f'fpoc.dprime:={DPRIME}', '-p', 'seed:=3',
                               '-p', f'target_row:={PERSON[0]}',
                               '-p', f'target_col:={PERSON[1]}'])

    def output():
        return controller.output() + camera.output()

    assert wait_for(lambda: bool(found), TIMEOUT_S), 'no found event\n' + output()
    first = diagnostics.parse_found(found[0][1])['fixations']
    assert wait_for(lambda: int(status.values.get('fixations', 0)) >= first +
                    FIXATIONS_AFTER_FOUND, TIMEOUT_S), output()
    losses = [diagnostics.parse_lost(msg) for _, msg in lost]
    # Lost only when the person's cells fell below the confidence, never held at it.
    assert all(e['probability'] < CONFIDENCE for e in losses), (losses, output())
    # The person stays still: it is not lost and reacquired in one frame at its cell.
    assert not [e for e in (diagnostics.parse_reacquired(m) for _, m in again)
                if e['seconds_lost'] == 0.0], output()
