# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Rooms of several faces on the pan/tilt task (issue 37): the scenes, the scores, the CLI."""
import hashlib

from ipomdp_gaze.cli import main
from ipomdp_gaze.drivers.scene_tasks import task_spec
from ipomdp_gaze.simulation.evaluation import match_faces
from ipomdp_gaze.vision.pan_tilt import MAX_FACES, PanTiltSceneSet, parse_faces
import numpy as np
import pytest

# Today's one-face scenes (before rooms existed): their face (cell, centre, side, index) and the
# image's mean and spread, over the whole scene and the face's square. Not a byte hash: the
# sha256 taken when rooms came in (same code, same seeds) did not reproduce on another machine
# (2026-12-03), where resizing and blending round a few pixels the other way; a crop, a face or
# a position that changed moves these numbers by far more than the tolerance.
TODAY = {('train', 0, 0): ((9, 4), (403.5, 712.5), 67, 43, (118.050, 38.407), (106.398, 37.091)),
         ('test', 5, 2): ((9, 6), (519.5, 712.5), 43, 86, (126.774, 38.758), (134.663, 33.083))}


def _sha(image) -> str:
    return hashlib.sha256(image.tobytes()).hexdigest()


def _stats(image) -> tuple[float, float]:
    pixels = np.asarray(image, dtype=float)
    return float(pixels.mean()), float(pixels.std())


@pytest.mark.parametrize('key', sorted(TODAY))
def test_one_face_scenes_are_todays(key):
    split, seed, index = key
    cell, centre, side, face, whole, face_square = TODAY[key]
    images = []
    for faces in (1, '1', (1, 1)):
        scene = PanTiltSceneSet(split, seed=seed, faces=faces).scene(index)
        images.append(scene.image.tobytes())
        assert (scene.cell, scene.face_centre_px, scene.face_px, scene.face_index) == \
            (cell, centre, side, face)
        assert [f.cell for f in scene.faces] == [cell]
        x, y, half = int(centre[0] - side / 2), int(centre[1] - side / 2), side
        assert _stats(scene.image) == pytest.approx(whole, abs=0.01)
        assert _stats(scene.image[y:y + half, x:x + half]) == pytest.approx(face_square, abs=0.01)
    assert len(set(images)) == 1           # one scene, however the count is spelled


def _squares_apart(faces) -> bool:
    for i, a in enumerate(faces):
        for b in faces[i + 1:]:
            ax, ay = (v - a.side_px / 2 for v in a.centre_px)
            bx, by = (v - b.side_px / 2 for v in b.centre_px)
            if ax < bx + b.side_px and bx < ax + a.side_px and \
                    ay < by + b.side_px and by < ay + a.side_px:
                return False
    return True


@pytest.mark.parametrize('count', [0, 2, 3, 4])
def test_rooms_hold_k_faces_apart_inside_the_reach_the_same_per_seed(count):
    rooms = PanTiltSceneSet('train', seed=7, faces=count)
    width, height = rooms.geometry.size_px
    for index in range(3):
        scene = rooms.scene(index)
        assert len(scene.faces) == count and scene.has_face == (count > 0)
        assert len({f.face_index for f in scene.faces}) == count
        assert all(f.face_index in rooms.faces for f in scene.faces)
        for f in scene.faces:
            lo, hi = rooms.face_px
            assert lo <= f.side_px <= hi
            assert 0 <= f.cell[0] < 11 and 0 <= f.cell[1] < 11
            assert rooms.geometry.cell_of_point(*f.centre_px) == f.cell
            x0, y0 = (v - f.side_px / 2 for v in f.centre_px)
            assert 0 <= x0 and x0 + f.side_px <= width and 0 <= y0 and y0 + f.side_px <= height
        assert _squares_apart(scene.faces)
        again = PanTiltSceneSet('train', seed=7, faces=count).scene(index)
        assert _sha(again.image) == _sha(scene.image) and again.faces == scene.faces
    if count == 0:           # the empty crop of the one-face scene
        empty = PanTiltSceneSet('train', seed=7, empty=True).scene(0)
        assert _sha(empty.image) == _sha(rooms.scene(0).image) and rooms.scene(0).cell is None
    else:                    # its first face is the one-face scene's
        assert rooms.scene(0).faces[0] == PanTiltSceneSet('train', seed=7).scene(0).faces[0]
    other = PanTiltSceneSet('train', seed=8, faces=count).scene(0)
    assert _sha(other.image) != _sha(rooms.scene(0).image)


def test_a_range_draws_each_count_and_a_room_of_one_is_todays_scene():
    rooms = PanTiltSceneSet('train', seed=3, faces='0-4')
    counts = [len(rooms.scene(i).faces) for i in range(20)]
    assert set(counts) <= set(range(5)) and len(set(counts)) >= 4
    one = counts.index(1)
    assert _sha(rooms.scene(one).image) == \
        _sha(PanTiltSceneSet('train', seed=3).scene(one).image)
    assert PanTiltSceneSet.from_kwargs(rooms.kwargs()).room == (0, 4)


@pytest.mark.parametrize('value, pair', [(0, (0, 0)), (4, (4, 4)), ('2', (2, 2)),
                                         ('0-4', (0, 4)), (' 1-3 ', (1, 3)), ((2, 2), (2, 2))])
def test_parse_faces_reads_k_and_lo_hi(value, pair):
    assert parse_faces(value) == pair


# Text int() takes that is not ASCII digits: a sign, an underscore, Arabic-Indic 2 and 0-4.
NOT_ASCII_COUNTS = ['+2', '1-+3', '0_2', '1 - 3', '\u0662', '1-\u0663', '\u0660-\u0664']


@pytest.mark.parametrize('value', ['', 'x', '3-1', '-1', '1-', '0-9', MAX_FACES + 1, 1.5,
                                   True, None, (1, 2, 3), '1-2-3', *NOT_ASCII_COUNTS])
def test_parse_faces_refuses_bad_values_with_one_message(value):
    with pytest.raises(ValueError, match=r'^faces must be a count K or a range LO-HI'):
        parse_faces(value)


def test_an_empty_set_refuses_faces():
    with pytest.raises(ValueError, match='give faces=0'):
        PanTiltSceneSet('train', empty=True, faces=2)


@pytest.mark.parametrize('answers, truths, found', [
    ([], [], 0),
    ([(5, 5)], [], 0),                                   # a false face in an empty room
    ([], [(5, 5)], 0),
    ([(5, 5)], [(6, 6)], 1),                             # one cell off diagonally: found
    ([(5, 5)], [(5, 7)], 0),                             # two cells off: not found
    ([(5, 5), (5, 6)], [(5, 5)], 1),                     # one face matched once: one false
    ([(5, 5)], [(5, 5), (5, 6)], 1),                     # one answer finds one face only
    ([(5, 6), (5, 4)], [(5, 5), (5, 7)], 2),             # the matching, not greedy order
    ([(0, 0), (3, 3), (9, 9)], [(1, 1), (3, 4), (7, 7)], 2),
])
def test_match_faces_counts_each_face_and_answer_once(answers, truths, found):
    assert match_faces(answers, truths) == found
    assert match_faces(answers[::-1], truths[::-1]) == found


def test_room_specs_take_room_searchers_only():
    spec = task_spec('pan-tilt', faces='0-4', compare=('sweep-all-grouped5',
                                                       'many:search.repeat_weight=0.1'))
    assert spec.rooms and spec.faces == (0, 4)
    assert spec.settings.targets == 'many' and spec.settings.repeat_weight == 0.1
    assert spec.settings.max_fixations == 20 and spec.settings.hotspot_prior == 0
    for name in ('many-cells', 'many-posterior:absent.prior=0.13', 'every-view-many',
                 'pass-many', 'pass-many:confidence=0.95', 'every-view-grouped3',
                 'sweep-all-grouped3'):
        assert task_spec('pan-tilt', faces=2, compare=(name,)).compare == (name,)
    with pytest.raises(ValueError, match='unknown room searcher'):
        task_spec('pan-tilt', faces=2, compare=('sweep-all-grouped3:confidence=0.9',))
    assert not task_spec('pan-tilt').rooms
    with pytest.raises(ValueError, match='unknown room searcher'):
        task_spec('pan-tilt', faces=2, compare=('sweep-first-grouped5',))
    with pytest.raises(ValueError, match='pan-tilt task'):
        task_spec('faces-420', faces=2)


@pytest.mark.parametrize('value', ['5-2', 'x', '9', '+2', '\u0662'])
def test_evaluate_refuses_a_bad_faces_value_with_one_line(value, capsys):
    assert main(['evaluate', '--scenes', 'pan-tilt', '--faces', value, '--episodes', '1']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f'ipomdp-gaze evaluate: error: faces must be a count K or a range LO-HI '
                   f"with 0 <= LO <= HI <= {MAX_FACES}, got '{value}'"]


def test_evaluate_scores_a_small_room_run(tmp_path, capsys):
    import json
    out = tmp_path / 'rooms.json'
    assert main(['evaluate', '--scenes', 'pan-tilt', '--faces', '2', '--split', 'train',
                 '--episodes', '1', '--seed', '1000', '--compare', 'sweep-all-grouped5',
                 '--jobs', '1', '--json', str(out)]) == 0
    record = json.loads(out.read_text())
    assert record['faces'] == [2, 2]
    for name in ('many', 'sweep-all-grouped5'):
        s = record['summary'][name]
        assert s['faces'] == 2 and 0 <= s['recall'] <= 1 and s['false_per_scene'] >= 0
        scene = record['scenes'][name][0]
        assert len(scene['face_cells']) == 2
        assert scene['faces_found'] == match_faces(scene['answers'], scene['face_cells'])
    assert np.isfinite(record['summary']['many']['head_time_s_mean'])


def test_pass_many_takes_the_sweeps_views_and_answers_its_belief_and_the_grouped(tmp_path):
    import json

    from ipomdp_gaze.drivers.rooms import room_session
    from ipomdp_gaze.drivers.scene_tasks import ROOM_GROUP_MIN_NEIGHBORS, SceneTask
    from ipomdp_gaze.drivers.sweep_rules import grouped_cells
    from ipomdp_gaze.simulation.evaluation import cells_apart
    out = tmp_path / 'rooms.json'
    # Training room 1002 holds 4 faces; the grouped sweep finds 3 of them, the belief 4.
    assert main(['evaluate', '--scenes', 'pan-tilt', '--faces', '0-4', '--split', 'train',
                 '--episodes', '1', '--seed', '1002', '--compare', 'pass-many',
                 '--compare', 'sweep-all-grouped5', '--jobs', '1', '--json', str(out)]) == 0
    record = json.loads(out.read_text())
    passed, swept = record['scenes']['pass-many'][0], record['scenes']['sweep-all-grouped5'][0]
    assert passed['path'] == swept['path'] and passed['head_time_s'] == swept['head_time_s']
    assert passed['done'] and passed['fixations'] == len(swept['path'])
    # Every grouped detection is answered (the same face when within one cell) ...
    assert all(min(cells_apart(tuple(g), tuple(a)) for a in passed['answers']) <= 1
               for g in swept['answers'])
    # ... besides the belief's faces after those views, each on its likelier side.
    spec = task_spec('pan-tilt', faces='0-4', split='train', seed=1002)
    task = SceneTask.get(spec)
    task.sensor.start(task.scene(0).image)
    session, outcome, _, faces = room_session(spec, task, 0, 'pass-many')
    assert list(outcome.path) == swept['path'] and outcome.reason == 'pass'
    # The views' groups are the grouped sweep's detections, per cell.
    grid = task.model.grid
    for pose in swept['path']:
        cells = grouped_cells(task, pose, ROOM_GROUP_MIN_NEIGHBORS)
        assert task.sensor.observe(pose).groups.tolist() == np.bincount(
            cells, minlength=grid.n_cells).tolist()
    belief = [list(grid.cell(f['cell'])) for f in faces if not f.get('grouped')]
    assert passed['answers'][:len(belief)] == belief
    assert all(session.log_odds[f['cell']] > 0 for f in faces if not f.get('grouped'))
    assert passed['faces_found'] >= swept['faces_found']
    assert passed['faces_found'] > swept['faces_found']     # this room: grouping misses one


def test_the_room_demo_ends_with_one_verdict_line():
    from ipomdp_gaze.drivers.rooms import room_demo
    lines = []
    status = room_demo(2, 1, lines.append)
    last = lines[-1]
    assert last.startswith('found ') and last.endswith(('that is right', 'that is wrong'))
    assert ' of 2 faces: that is ' in last
    assert status == (0 if last.endswith('right') else 1)
    assert sum(line.startswith('fixation ') for line in lines) >= 1


def test_the_room_demo_of_nobody_says_so():
    """It said 'the scene camera put the faces in cells (none)'."""
    from ipomdp_gaze.drivers.rooms import room_demo
    lines = []
    room_demo(0, 0, lines.append)
    assert lines[-2:] == ['the scene camera put no face in the room',
                          'found 0 of 0 faces: that is right']


@pytest.mark.parametrize('args', [['--faces', '2'], ['--scene', 'faces', '--faces', '2',
                                                     '--fovea'],
                                  ['--scene', 'faces', '--faces', '0-3', '--empty'],
                                  ['--scene', 'faces', '--faces', '2', '--plot', 'x.png'],
                                  ['--scene', 'faces', '--faces', '2-1'],
                                  ['--scene', 'faces', '--faces', '+2'],
                                  ['--scene', 'faces', '--faces', '\u0662'],
                                  ['--scene', 'faces', '--faces', '2', '--timeout', '5'],
                                  ['--scene', 'faces', '--faces', '2', '--domain-id', '220'],
                                  ['--scene', 'faces', '--faces', '0-2', '--verbose']])
def test_the_demo_refuses_faces_where_they_do_not_apply_in_one_line(args, capsys):
    assert main(['demo', *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith('ipomdp-gaze demo: error: ')


def test_the_scene_camera_builds_a_room_and_refuses_one_on_a_fixed_view():
    from ipomdp_gaze.nodes.scene_camera import _scene_config, scene_camera_params
    values = {p.name: p.default for p in scene_camera_params()}
    values.update({'seed': 5, 'scene.faces': '3'})
    room = _scene_config(values).scene
    assert len(room.faces) == 3
    assert room.faces == PanTiltSceneSet('test', seed=5, faces=3).scene(0).faces
    values['scene.faces'] = '1'
    assert _scene_config(values).scene.faces == room.faces[:1]
    values.update({'view': 'fixed', 'scene.faces': '2'})
    with pytest.raises(ValueError, match='scene.faces is for the pan_tilt view'):
        _scene_config(values)


@pytest.mark.parametrize('change, said', [
    ({'scene.file': 'photo.png'}, 'scene.faces is for the held-out scenes, not scene.file'),
    ({'scene.empty': True}, 'scene.empty shows the one-face scene without its face: leave '
                            "scene.faces '1'")])
def test_the_scene_camera_refuses_a_room_it_would_not_show(change, said):
    """A user's photo ignored scene.faces; scene.empty's refusal named the API's faces=0."""
    from ipomdp_gaze.nodes.scene_camera import _scene_config, scene_camera_params
    values = {p.name: p.default for p in scene_camera_params()}
    values.update({'scene.faces': '2', **change})
    with pytest.raises(ValueError) as caught:
        _scene_config(values)
    assert str(caught.value).startswith(said)


@pytest.mark.parametrize('faces', ['9', 'two', '2-1', '-1', '2.0', *NOT_ASCII_COUNTS])
def test_the_scene_camera_refuses_a_bad_face_count_by_its_parameter(faces):
    """
    QA: the refusal said 'faces must be ...', not the parameter scene.faces.

    QA: '+2' and Arabic-Indic digits were taken as counts (int() reads them).
    """
    from ipomdp_gaze.nodes.scene_camera import _scene_config, scene_camera_params
    values = {p.name: p.default for p in scene_camera_params()}
    values['scene.faces'] = faces
    with pytest.raises(ValueError) as caught:
        _scene_config(values)
    assert str(caught.value) == (f'scene.faces must be a count K or a range LO-HI with 0 <= LO '
                                 f'<= HI <= {MAX_FACES}, got {faces!r}')


def test_room_boxes_put_one_face_seen_from_two_views_at_one_place():
    import math
    from types import SimpleNamespace

    from ipomdp_gaze.drivers.rooms import room_boxes, ROOM_CELL_PX
    from ipomdp_gaze.vision.pan_tilt import PAN_TILT_GRID, shipped_camera
    camera, grid = shipped_camera(), PAN_TILT_GRID
    side = 40
    # the face at grid position (5, 6): centred in the view from (5, 6), 5 degrees right of
    # the centre of the view from (5, 5)
    u = camera.cx + camera.fx * math.tan(math.radians(5.0))
    boxes = {grid.index(5, 6): np.array([[camera.cx - (side - 1) / 2,
                                          camera.cy - (side - 1) / 2, side, side]]),
             grid.index(5, 5): np.array([[u - (side - 1) / 2, camera.cy - (side - 1) / 2,
                                          side, side]]),
             grid.index(0, 0): np.zeros((0, 4))}
    task = SimpleNamespace(model=SimpleNamespace(grid=grid), camera=camera,
                           sensor=SimpleNamespace(boxes=boxes))
    out = room_boxes(task, [grid.index(5, 5), grid.index(0, 0), grid.index(5, 6),
                            grid.index(5, 6)])
    assert out.shape == (2, 4)
    centres = out[:, :2] + out[:, 2:] / 2
    np.testing.assert_allclose(centres, [[6.5 * ROOM_CELL_PX, 5.5 * ROOM_CELL_PX]] * 2, atol=1e-6)
    width = side / camera.fx * 180 / math.pi / grid.spacing_deg * ROOM_CELL_PX
    np.testing.assert_allclose(out[:, 2], [width, width])
    assert room_boxes(task, [grid.index(0, 0)]).shape == (0, 4)


@pytest.mark.parametrize('args, said', [
    (['--faces', '2', '--compare', 'many:search.targets=one'],
     "searcher 'many:search.targets=one': a room searcher looks for everyone"),
    (['--compare', 'elm:search.targets=many'],
     "searcher 'elm:search.targets=many': search.targets many is for rooms")])
def test_evaluate_refuses_what_a_room_or_one_face_would_ignore(args, said, capsys):
    """A label's search.targets other than the task's was run as if not given."""
    assert main(['evaluate', '--scenes', 'pan-tilt', *args, '--episodes', '1', '--jobs', '1',
                 '--quiet']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f'ipomdp-gaze evaluate: error: {said}')


def test_task_spec_takes_a_label_of_the_tasks_own_targets():
    label = 'many:search.targets=many'
    assert task_spec('pan-tilt', faces=2, compare=(label,)).compare == (label,)


@pytest.mark.parametrize('args', [['--faces', '2'], []])
def test_evaluate_refuses_a_grouping_the_task_does_not_take(args, capsys):
    """Rooms report their own grouping and faces-420 none: --group-min-neighbors was dropped."""
    scenes = 'pan-tilt' if args else 'faces-420'
    assert main(['evaluate', '--scenes', scenes, *args, '--group-min-neighbors', '3',
                 '--episodes', '1', '--jobs', '1', '--quiet']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ['ipomdp-gaze evaluate: error: group_min_neighbors (--group-min-neighbors) is '
                   'for the pan-tilt task with one face; rooms report the grouping 5 of '
                   'config/faces_camera_room_detector.yaml, the fixed-camera tasks none']


@pytest.mark.parametrize('kwargs, said', [
    ({'faces': 2, 'compare': ('many',)}, "searcher 'many' is the task's own search"),
    ({'faces': 2, 'compare': ('pass-many', 'pass-many')}, "searcher 'pass-many' is given twice"),
    ({'compare': ('coverage',)}, "searcher 'coverage' is the task's own search")])
def test_a_searcher_given_twice_is_refused(kwargs, said):
    """Results are kept per label: a second 'many' made 1 room read as 2, its head time doubled."""
    with pytest.raises(ValueError) as caught:
        task_spec('pan-tilt', **kwargs)
    assert str(caught.value) == f'{said}: its scenes would be counted twice'
    assert task_spec('pan-tilt', policy='map', compare=('coverage',)).compare == ('coverage',)
