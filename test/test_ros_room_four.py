# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A room of four over DDS, two of them in the corners of the pan/tilt range: the order published.

Three processes on the shipped pan/tilt face configuration with the rooms' (as
``test_ros_room_pass.py``): the scene camera shows held-out room 4 of four faces, at cells
(3, 9), (0, 0), (10, 10) and (2, 1). The node's people are those of the offline pass on the
same room, published most probable first as README's "Everyone in the room" says (the pass
lists its grouped detections first, and the node published that order), the corners at the
ends of the head's range, and the head keeps them in view in that order.
"""
from __future__ import annotations

import math

from conftest import offline_room, start_room, wait_for
import pytest

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'
SEED = 4
SEARCH_S = 240.0        # a generous limit for one search on a loaded machine, not a measure


@pytest.fixture(scope='module')
def offline():
    """Run the offline pass on the room the scene camera shows: its people's cells."""
    task, _, faces = offline_room(SEED, 4)
    truth = [tuple(int(v) for v in f.cell) for f in task.scene(0).faces]
    return {'people': sorted(f['cell'] for f in faces), 'truth': truth}


@pytest.fixture(scope='module')
def rig(probe, nodes):
    return start_room(probe, nodes, SEED, 4)


def test_four_people_corners_included_are_published_most_probable_first(rig, offline):
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import diagnostics, joints, people
    assert wait_for(lambda: rig['done'], SEARCH_S), rig['controller'].output()[-3000:]
    done = diagnostics.parse_room_done(rig['done'][0][1])
    grid = Grid(11, 11, 5.0)
    found = people.read_people_array(rig['cells'][-1][1], grid)
    cells = [cell for cell, _ in found]
    assert sorted(cells) == offline['people'] and done['people'] == len(cells) == 4, found
    assert sorted(grid.cell(c) for c in cells) == sorted(offline['truth'])
    probabilities = [p for _, p in found]
    assert probabilities == sorted(probabilities, reverse=True), found
    # ~/targets in the same order; the corners at the ends of the +-25 degree range
    head = PanTiltMap(grid, 'pan_joint', 'tilt_joint')
    angles = people.poses_angles(rig['targets'][-1][1])
    for (pan, tilt), cell in zip(angles, cells, strict=True):
        assert (pan, tilt) == pytest.approx(head.angles(cell), abs=1e-9)
    edge = math.radians(25.0)
    corners = {grid.index(0, 0), grid.index(10, 10)}
    assert sorted(abs(a) for c, pair in zip(cells, angles) if c in corners for a in pair) == \
        pytest.approx([edge] * 4, abs=1e-9)
    # the head goes to them in that order, round and round
    assert wait_for(lambda: len(rig['pan_tilt']) >= 12 + 5, 60)
    sent = [head.nearest_cell(*joints.angles_from_joint_state(msg, head))
            for _, msg in rig['pan_tilt'][12:12 + 5]]
    assert sent == cells + cells[:1], (sent, cells)
