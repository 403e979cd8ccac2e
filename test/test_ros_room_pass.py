# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The many-target pass over DDS: the node's people are the offline ``pass-many-cells`` answer.

Three processes on the shipped pan/tilt face configuration with the rooms' (controller:
``policy.name sweep``, one pass of the sweep's poses, docs/design.md section 11.7; detector:
the grouped detections per cell, ``publish_groups 5``, a ``32FC4`` ``evidence_image``). The
scene camera shows held-out room 2 of two faces, where the grouping names a face. The head
takes the sweep's poses in order, ``room_done`` says the pass ended it, and the people are
those of the offline session on the same room and views (``drivers.rooms.room_session``).
"""
from __future__ import annotations

from conftest import config_path, offline_room, start_room, wait_for
import pytest

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'
SEED = 2
SEARCH_S = 240.0        # a generous limit for one search on a loaded machine, not a measure


@pytest.fixture(scope='module')
def offline():
    """Run the offline pass on the room the scene camera shows: its path, its people's cells."""
    task, outcome, faces = offline_room(SEED, 2)
    return {'path': [int(c) for c in outcome.path], 'people': sorted(f['cell'] for f in faces),
            'grouped': sum(bool(f.get('grouped')) for f in faces), 'poses': task.sweep.poses}


@pytest.fixture(scope='module')
def rig(probe, nodes):
    return start_room(probe, nodes, SEED, 2)


def test_the_node_makes_one_pass_and_names_the_offline_sessions_people(rig, offline):
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import diagnostics, joints, people
    assert wait_for(lambda: rig['done'], SEARCH_S), rig['controller'].output()[-3000:]
    done = diagnostics.parse_room_done(rig['done'][0][1])
    assert done['ended'] == 'forced:pass' and done['fixations'] == len(offline['poses']), done
    assert 'forced by the end of its pass' in rig['done'][0][1].message
    assert offline['path'] == [int(p) for p in offline['poses']]
    grid = Grid(11, 11, 5.0)
    head = PanTiltMap(grid, 'pan_joint', 'tilt_joint')
    sent = [head.nearest_cell(*joints.angles_from_joint_state(msg, head))
            for _, msg in rig['pan_tilt'][:len(offline['poses'])]]
    assert sent == offline['path']
    found = sorted(cell for cell, _ in people.read_people_array(rig['cells'][-1][1], grid))
    assert found == offline['people'] and done['people'] == len(found)
    assert offline['grouped'] >= 1          # the groups travelled: a face is named by one


def test_a_fovea_detector_refuses_groups_with_the_reason(nodes):
    det = nodes.start('detector', ['-r', '__ns:=/fov', '--params-file',
                                   config_path('faces_fovea_detector.yaml'),
                                   '-p', 'publish_groups:=5'])
    assert wait_for(lambda: not det.running, 60)
    assert det.proc.returncode == 1
    assert 'publish_groups is for camera mode with publish_image: true' in det.output()
    assert 'Traceback' not in det.output()
    nodes.killed.append(det)                                     # exited on purpose
