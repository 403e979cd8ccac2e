# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A pass that goes on until the room is decided (``search.decide_after_pass``), over DDS.

The rooms' three processes as in ``test_ros_room_pass.py``, the controller with
``search.decide_after_pass`` and ``search.repeat_weight 1.0`` (docs/design.md section 11.7), on
held-out room 2 of two faces: after the sweep's 12 poses the head takes the views the offline
session takes on the same room, ``room_done`` comes at the confidence, not forced by the pass,
and the people are the offline session's.
"""
from __future__ import annotations

from conftest import offline_room, start_room, wait_for
import pytest

pytestmark = pytest.mark.ros

SEED = 2
LABEL = 'pass-many-cells:search.decide_after_pass=true,search.repeat_weight=1.0'
SEARCH_S = 240.0        # a generous limit for one search on a loaded machine, not a measure


@pytest.fixture(scope='module')
def offline():
    """Run the offline session on the room the scene camera shows: its path, its people."""
    task, outcome, faces = offline_room(SEED, 2, LABEL)
    return {'path': [int(c) for c in outcome.path], 'people': sorted(f['cell'] for f in faces),
            'reason': outcome.reason, 'poses': [int(p) for p in task.sweep.poses]}


@pytest.fixture(scope='module')
def rig(probe, nodes):
    return start_room(probe, nodes, SEED, 2, extra=(
        '-p', 'search.decide_after_pass:=true', '-p', 'search.repeat_weight:=1.0'))


def test_the_node_goes_on_after_its_pass_until_the_room_is_decided(rig, offline):
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import diagnostics, joints, people
    # the offline session decides this room two views after its pass
    assert offline['reason'] == '' and offline['path'][:12] == offline['poses']
    assert len(offline['path']) > len(offline['poses'])
    assert wait_for(lambda: rig['done'], SEARCH_S), rig['controller'].output()[-3000:]
    done = diagnostics.parse_room_done(rig['done'][0][1])
    assert done['ended'] == 'confidence' and done['fixations'] == len(offline['path']), done
    assert 'forced' not in rig['done'][0][1].message
    grid = Grid(11, 11, 5.0)
    head = PanTiltMap(grid, 'pan_joint', 'tilt_joint')
    sent = [head.nearest_cell(*joints.angles_from_joint_state(msg, head))
            for _, msg in rig['pan_tilt'][:len(offline['path'])]]
    assert sent == offline['path']
    named = people.read_people_array(rig['cells'][-1][1], grid)
    found = sorted(cell for cell, _ in named)
    assert found == offline['people'] and done['people'] == len(found) == 2
    assert all(p >= 0.99 for _, p in named)           # decided, not on their likelier side
