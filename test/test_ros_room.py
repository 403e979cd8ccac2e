# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Many-target mode over DDS: a room of two faces found, kept in view in turn, searched again.

Three processes on the shipped pan/tilt face configuration (``config/faces_camera_*.yaml``,
the controller's with ``faces_camera_room_controller.yaml`` after it, the detector's with
``faces_camera_room_detector.yaml``): the
scene camera shows held-out room 0 of two faces (``scene.faces '2'``), the detector bins its
detections to cells, and the controller runs ``search.targets many`` with the rooms' settings
(docs/design.md section 11.5). The controller publishes both people on ``~/targets`` (their head
directions) and ``~/target_cells``, the ``room_done`` event, then sends the head to one person and
the other in turn; ``~/reset`` forgets them and searches again, and a periodic re-check searches
again and finds nobody new. Settings it refuses are refused with the reason.
"""
from __future__ import annotations

from conftest import start_room, wait_for
import pytest

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'
SEED = 0
SEARCH_S = 240.0        # a generous limit for one search on a loaded machine, not a measure


def room_faces() -> list[tuple[int, int]]:
    """Return the cells of the faces the scene camera's room of ``SEED`` holds."""
    from ipomdp_gaze.drivers.scene_tasks import SceneTask, task_spec
    scene = SceneTask.get(task_spec('pan-tilt', seed=SEED, faces=2)).scene(0)
    return [tuple(int(v) for v in f.cell) for f in scene.faces]


@pytest.fixture(scope='module')
def rig(probe, nodes):
    return start_room(probe, nodes, SEED, 2)


def _people(rec) -> list[tuple[int, float]]:
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import people
    return people.read_people_array(rec['cells'][-1][1], Grid(11, 11, 5.0))


def _done(rec, n: int) -> dict:
    from ipomdp_gaze.msg_adapters import diagnostics
    assert wait_for(lambda: len(rec['done']) >= n, SEARCH_S), rec['controller'].output()[-3000:]
    return diagnostics.parse_room_done(rec['done'][n - 1][1])


def _cells_in_turn(rec, since: int, count: int) -> list[int]:
    """Return the cells of ``count`` head targets sent after the ``since``-th one."""
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import joints
    head = PanTiltMap(Grid(11, 11, 5.0), 'pan_joint', 'tilt_joint')
    assert wait_for(lambda: len(rec['pan_tilt']) >= since + count, 60)
    return [head.nearest_cell(*joints.angles_from_joint_state(msg, head))
            for _, msg in rec['pan_tilt'][since:since + count]]


def test_the_room_is_searched_its_people_published_and_kept_in_view_in_turn(rig):
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import people
    from ipomdp_gaze.simulation.evaluation import match_faces
    done = _done(rig, 1)
    assert done['people'] == 2 and done['new_people'] == 2 and not done['recheck'], done
    assert done['fixations'] >= 1
    grid = Grid(11, 11, 5.0)
    found = _people(rig)
    cells = [cell for cell, _ in found]
    answers = [tuple(int(v) for v in grid.cell(c)) for c in cells]
    assert match_faces(answers, room_faces()) == 2, (answers, room_faces())
    assert all(0.5 < p <= 1 for _, p in found)
    head = PanTiltMap(grid, 'pan_joint', 'tilt_joint')
    poses = rig['targets'][-1][1]
    assert poses.header.frame_id == 'pan_tilt_base'
    for (pan, tilt), cell in zip(people.poses_angles(poses), cells, strict=True):
        assert (pan, tilt) == pytest.approx(head.angles(cell), abs=1e-9)
    # Then the head goes from one person to the other and back, each in view in turn.
    since = len(rig['pan_tilt'])
    turn = _cells_in_turn(rig, since, 4)
    assert set(turn) == set(cells) and all(a != b for a, b in zip(turn, turn[1:])), turn


def test_reset_forgets_the_people_and_searches_the_room_again(rig, probe):
    first = _done(rig, 1)
    n = len(rig['cells'])
    response = probe.reset(NODE)
    assert response.success and response.message.startswith('belief reset')
    assert wait_for(lambda: len(rig['cells']) > n, 20)
    assert _people(rig) == []                                     # nobody known any more
    done = _done(rig, 2)
    assert done['search_id'] == first['search_id'] + 1, done
    assert done['people'] == 2 and done['new_people'] == 2 and not done['recheck'], done


def test_a_periodic_recheck_searches_again_and_finds_nobody_new(rig, probe):
    before = _done(rig, 2)
    results = probe.set_parameters(NODE, {'room.recheck_period_s': 1.0})
    assert results[0].successful, results[0].reason
    done = _done(rig, 3)
    assert done['recheck'] and done['people'] == 2 and done['new_people'] == 0, done
    assert done['search_id'] == before['search_id'] + 1
    assert probe.set_parameters(NODE, {'room.recheck_period_s': 0.0})[0].successful


@pytest.mark.parametrize('params, words', [
    ({'room.recheck_period_s': 0.1}, 'room.recheck_period_s must be 0 (never) or in '
                                     '[room.dwell_s, 86400] seconds, got 0.1'),
    ({'search.hotspot_prior': 0.03}, 'search.targets many does not model false-alarm scales, '
                                     'nor hotspots of a still scene'),
    ({'search.false_alarm_scales': [1.0, 3.0]}, 'search.targets many does not model '
                                                'false-alarm scales'),
    ({'room.frame_id': ' '}, 'room.frame_id must name the frame of ~/targets'),
    # QA: accepted, then ~/targets named a frame tf2 refuses to look up
    ({'room.frame_id': '/pan_tilt_base'}, 'room.frame_id must name the frame of ~/targets (a TF '
                                          "frame), got '/pan_tilt_base': tf2 frame ids have no "
                                          "leading '/'"),
    ({'room.frame_id': 'pan_tilt_base '}, "got 'pan_tilt_base '"),
])
def test_settings_the_many_target_mode_does_not_model_are_refused(rig, probe, params, words):
    result = probe.set_parameters(NODE, params)[0]
    assert not result.successful and words in result.reason, result.reason


def test_search_targets_changes_at_run_time_and_starts_a_new_search(rig, probe):
    """One target: the paper's search (its found event has the config's radius), no room."""
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.msg_adapters import diagnostics
    found = probe.record(DiagnosticStatus, 'found', 10)
    last = _done(rig, 3)
    assert wait_for(lambda: probe.matched('found') > 0, 20)
    n, rooms = len(rig['cells']), len(rig['done'])
    assert probe.set_parameters(NODE, {'search.targets': 'one'})[0].successful
    assert wait_for(lambda: len(rig['cells']) > n, 20)
    assert _people(rig) == []                              # the people forgotten
    assert wait_for(lambda: any(diagnostics.parse_found(m)['radius'] == 1 for _, m in found),
                    SEARCH_S), rig['controller'].output()[-3000:]
    assert len(rig['done']) == rooms                       # one target: no room_done
    assert probe.set_parameters(NODE, {'search.targets': 'many'})[0].successful
    done = _done(rig, rooms + 1)
    # one search id per search: the one-target search, then this one (a switch of
    # search.targets once counted twice)
    assert done['search_id'] == last['search_id'] + 2 and done['people'] == 2, (done, last)
