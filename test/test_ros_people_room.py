# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Several people, followed in turn, on real pixels over DDS (docs/design.md section 12.10).

Three processes on the shipped configurations: the scene camera shows held-out room 0 of two
faces (``scene.faces '2'``, the room of ``test_ros_room``), the detector sends its 32FC4
frames (counts, the detections' offsets and the grouped detections, which a tracker ignores),
and the controller runs ``config/faces_camera_tracking.yaml`` with
``config/faces_camera_people.yaml`` after it: many targets that may move. Both people are found,
each once, with its own number; ``~/target_cells`` lists both; then the head goes from one to
the other (``motion.dwell_s`` each), with a view for new people after each round; the search
never ends.
"""
from __future__ import annotations

from conftest import config_path, wait_for
import pytest

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'
SEED = 0
SEARCH_S = 240.0        # a generous limit on a loaded machine, not a measure


def room_faces() -> list[tuple[int, int]]:
    from ipomdp_gaze.drivers.scene_tasks import SceneTask, task_spec
    scene = SceneTask.get(task_spec('pan-tilt', seed=SEED, faces=2)).scene(0)
    return [tuple(int(v) for v in f.cell) for f in scene.faces]


@pytest.fixture(scope='module')
def rig(probe, nodes):
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.harness.watch import LATCHED
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float32MultiArray
    rec = {'found': probe.record(DiagnosticStatus, 'found', 10),
           'cells': probe.record(Float32MultiArray, f'/{NODE}/target_cells', LATCHED),
           'pan_tilt': probe.record(JointState, 'pan_tilt', LATCHED, distinct_stamps=True),
           'status': probe.search_status(NODE)}
    rec['controller'] = nodes.start('controller', [      # README's chain, the bench's settings
        '--params-file', config_path('faces_camera_tracking.yaml'),
        '--params-file', config_path('faces_camera_people.yaml'),
        '-p', 'motion.dwell_s:=1.0', '-p', 'diagnostics_period_s:=0.2'])
    assert wait_for(lambda: rec['pan_tilt'] and probe.matched('found'), 60), \
        rec['controller'].output()
    nodes.start('detector', ['--params-file', config_path('faces_camera_detector.yaml')])
    nodes.start('scene_camera', ['--params-file', config_path('faces_camera_scene_camera.yaml'),
                                 '-p', f'seed:={SEED}', '-p', "scene.faces:='2'"])
    return rec


def _found(rec) -> list[dict]:
    from ipomdp_gaze.msg_adapters import diagnostics
    return [dict(diagnostics.parse_found(m), person=diagnostics.person_of(m))
            for _, m in rec['found']]


def test_both_people_are_found_each_once_with_their_own_numbers(rig):
    from ipomdp_gaze.simulation.evaluation import match_faces
    assert wait_for(lambda: len(_found(rig)) >= 2, SEARCH_S), rig['controller'].output()[-3000:]
    found = _found(rig)[:2]
    assert sorted(f['person'] for f in found) == [1, 2], found
    answers = [(f['row'], f['col']) for f in found]
    assert match_faces(answers, room_faces()) == 2, (answers, room_faces())


def test_the_head_goes_from_one_person_to_the_other(rig):
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import joints, people
    grid = Grid(11, 11, 5.0)
    assert wait_for(lambda: len(_found(rig)) >= 2, SEARCH_S)
    assert wait_for(lambda: rig['cells'] and
                    len(people.read_people_array(rig['cells'][-1][1], grid)) == 2, 30)
    head = PanTiltMap(grid, 'pan_joint', 'tilt_joint')
    since = len(rig['pan_tilt'])
    assert wait_for(lambda: len(rig['pan_tilt']) >= since + 30, 120)
    looked = [grid.cell(head.nearest_cell(*joints.angles_from_joint_state(msg, head)))
              for _, msg in rig['pan_tilt'][since:since + 30]]
    near = [[max(abs(r - fr), abs(c - fc)) <= 1 for fr, fc in room_faces()] for r, c in looked]
    assert sum(n[0] for n in near) >= 5 and sum(n[1] for n in near) >= 5, (looked, room_faces())
    status = rig['status'].values
    assert status['search_ended'] == 'false' and len(_found(rig)) == 2
