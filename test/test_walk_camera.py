# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The scene camera's walking face (``scene.motion: walk``, docs/design.md section 12.6).

Pure: the walk of the node's seed is the walk scene of that seed; at speed 0 every frame is the
still camera's, bit for bit; at speed > 0 the face moves; ``walk_truth`` round-trips through
its adapter; a walk where none exists (a fixed view, a user's file, an empty scene, a room,
other face sizes) is refused with the reason. Over DDS: a walk camera answering pan_tilt
commands one frame per arrival publishes frames whose face moves on the node's clock, each
``walk_truth`` with its frame's stamp; a bad combination ends the node with one line.
"""
from __future__ import annotations

import time

from conftest import wait_for
import numpy as np
import pytest

SEED = 3


def _values(**changes) -> dict:
    from ipomdp_gaze.nodes.scene_camera import scene_camera_params
    values = {p.name: p.default for p in scene_camera_params()}
    values.update({'seed': SEED, 'scene.motion': 'walk'}, **changes)
    return values


def _config(**changes):
    from ipomdp_gaze.nodes.scene_camera import _scene_config
    return _scene_config(_values(**changes))


def test_the_walk_is_the_walk_scene_of_the_seed():
    from ipomdp_gaze.vision.walks import WalkSceneSet
    cfg = _config(**{'scene.speed_deg_s': 7.0, 'scene.walk_duration_s': 12.0})
    want = WalkSceneSet('test', cfg.geometry, SEED, 7.0, 12.0).scene(0)
    np.testing.assert_array_equal(cfg.walk.walk.times_s, want.walk.times_s)
    np.testing.assert_array_equal(cfg.walk.walk.points_px, want.walk.points_px)
    assert cfg.walk.truth_at(0.0).cell == tuple(cfg.scene.cell)
    assert _config(**{'scene.motion': 'still'}).walk is None


def test_scene_split_train_walks_the_training_scene_of_the_seed():
    from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet
    from ipomdp_gaze.vision.walks import WalkSceneSet
    cfg = _config(**{'scene.split': 'train'})
    want = WalkSceneSet('train', cfg.geometry, SEED, 5.0, 30.0).scene(0)
    test = WalkSceneSet('test', cfg.geometry, SEED, 5.0, 30.0).scene(0)
    np.testing.assert_array_equal(cfg.walk.walk.points_px, want.walk.points_px)
    assert not np.array_equal(cfg.walk.image_at(0.0), test.image_at(0.0))
    np.testing.assert_array_equal(cfg.walk.image_at(4.0), want.image_at(4.0))
    still = _config(**{'scene.split': 'train', 'scene.motion': 'still'}).scene
    np.testing.assert_array_equal(
        still.image, PanTiltSceneSet('train', cfg.geometry, (30, 70), 'rgb', SEED).scene(0).image)


def test_a_parameter_changed_at_run_time_keeps_the_walk():
    from ipomdp_gaze.nodes.scene_camera import SceneCameraNode
    cfg = _config()
    values = dict(cfg.values, saccade_time_s=0.3)
    assert SceneCameraNode._build(None, values, previous=cfg).walk is cfg.walk


def test_at_speed_zero_every_frame_is_the_still_cameras_bit_for_bit():
    still = _config(**{'scene.motion': 'still'})
    walk = _config(**{'scene.speed_deg_s': 0.0})
    for t in (0.0, 3.3, 29.0, 45.0):
        for cell in (walk.grid.center_index, 0, walk.grid.index(*walk.scene.cell)):
            rc = walk.grid.cell(cell)
            np.testing.assert_array_equal(walk.geometry.render(walk.walk.image_at(t), rc),
                                          still.geometry.render(still.scene.image, rc))
        assert walk.walk.truth_at(t).cell == tuple(still.scene.cell)


def test_at_speed_above_zero_the_face_moves():
    cfg = _config(**{'scene.speed_deg_s': 10.0})
    times = np.arange(0.0, 30.0, 0.5)
    positions = np.array([cfg.walk.truth_at(t).position for t in times])
    steps = np.hypot(*np.diff(positions, axis=0).T)
    assert steps.max() > 0.5                          # 10 deg/s: a cell per half second
    assert len({cfg.walk.truth_at(t).cell for t in times}) > 3
    assert not np.array_equal(cfg.walk.image_at(0.0), cfg.walk.image_at(2.0))


def test_two_people_walk_each_on_their_own_path():
    cfg = _config(**{'scene.faces': '2'})
    assert cfg.walk.people == 2
    first = _config()
    assert np.array_equal(first.walk.walk.points_px, cfg.walk.walk.points_px)
    cells = [cfg.walk.truths_at(t) for t in (0.0, 5.0)]
    assert cells[0][0].cell != cells[0][1].cell
    assert [a.position != b.position for a, b in zip(*cells)] == [True, True]


@pytest.mark.parametrize('changes, why', [
    ({'view': 'fixed'}, 'the pan_tilt view'),
    ({'scene.file': 'photo.jpg'}, 'not scene.file'),
    ({'scene.empty': True}, 'not scene.empty'),
    ({'scene.faces': '5'}, "a number of faces from 1 to 4, not scene.faces '5'"),
    ({'scene.faces': '0-3'}, "a number of faces from 1 to 4, not scene.faces '0-3'"),
    ({'scene.face_px': [40, 60]}, 'not scene.face_px [40, 60]'),
])
def test_a_walk_where_there_is_none_is_refused_with_the_reason(changes, why):
    with pytest.raises(ValueError, match='scene.motion walk needs') as info:
        _config(**changes)
    assert why in str(info.value)


def test_walk_truth_round_trips_and_bad_messages_are_refused():
    from builtin_interfaces.msg import Time
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import grid_arrays
    grid = Grid(11, 11, 5.0)
    msg = grid_arrays.walk_truth(Time(sec=1764806400, nanosec=999999999), 2.25, (3.4, -0.6),
                                 None)
    truth = grid_arrays.read_walk_truth(msg, grid)
    assert truth == grid_arrays.WalkTruth((1764806400, 999999999), 2.25, (3.4, -0.6), None)
    msg = grid_arrays.walk_truth(Time(sec=5, nanosec=7), 0.0, (3.4, 9.6), (3, 10))
    assert grid_arrays.read_walk_truth(msg, grid).cell == (3, 10)
    for data in ([1.0] * 6, [5, 7, 0.0, 1.0, 1.0, 11, 2], [5, 7, 0.0, 1.0, 1.0, 1.5, 2],
                 [5.5, 7, 0.0, 1.0, 1.0, 1, 2], [5, 7, float('nan'), 1.0, 1.0, 1, 2]):
        msg.data = [float(v) for v in data]
        with pytest.raises(ValueError, match='walk_truth'):
            grid_arrays.read_walk_truth(msg, grid)


@pytest.mark.ros
def test_a_walk_camera_moves_the_face_on_its_clock_one_frame_per_arrival(probe, nodes):
    from ipomdp_gaze.harness.watch import LATCHED
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head import PanTiltMap
    from ipomdp_gaze.msg_adapters import grid_arrays, images, joints
    from sensor_msgs.msg import Image, JointState
    from std_msgs.msg import Float64MultiArray
    grid = Grid(11, 11, 5.0)
    head = PanTiltMap(grid, 'pan_joint', 'tilt_joint')
    truths = probe.record(Float64MultiArray, '/walk/walk_truth', 50)
    states = probe.record(JointState, '/walk/joint_states', 50)
    frames = probe.record(Image, '/walk/image', 50)
    command = probe.publisher(JointState, '/walk/pan_tilt', LATCHED)
    # the defaults are the shipped pan/tilt camera's
    cam = nodes.start('scene_camera', [
        '-r', '__ns:=/walk', '-p', f'seed:={SEED}', '-p', 'scene.motion:=walk',
        '-p', 'scene.speed_deg_s:=20.0'])
    assert wait_for(lambda: probe.matched('/walk/walk_truth') and probe.matched('/walk/image')
                    and cam.running, 60), cam.output()
    cells = [grid.center_index, grid.index(2, 2), grid.center_index, grid.index(8, 8)]
    for cell in cells * 2:
        n = len(truths)
        now = probe.node.get_clock().now().to_msg()
        command.publish(joints.joint_state(head, cell, now))
        assert wait_for(lambda: len(truths) > n and len(frames) > n, 20), cam.output()
        time.sleep(0.4)
    read = [grid_arrays.read_walk_truth(m, grid) for _, m in truths]
    assert len(read) >= len(cells) * 2 - 1                  # one frame per arrival
    times = [r.t_s for r in read]
    assert all(b - a >= 0.3 for a, b in zip(times, times[1:])), times
    stamps = [(r.stamp, t) for r, t in zip(read, times)]
    assert all(abs(b[0][0] + b[0][1] * 1e-9 - a[0][0] - a[0][1] * 1e-9 - (b[1] - a[1])) < 1e-6
               for a, b in zip(stamps, stamps[1:]))        # t is the stamp since the first
    positions = np.array([r.position for r in read])
    assert len({tuple(p) for p in positions}) > 1            # the face walked
    by_stamp = {(m.header.stamp.sec, m.header.stamp.nanosec): m for _, m in states}
    paired = [by_stamp.get(r.stamp) for r in read]
    assert all(m is not None for m in paired)                # each frame's pose, same stamp
    seen = [head.nearest_cell(*joints.angles_from_joint_state(m, head)) for m in paired]
    assert set(seen) <= set(cells)
    shapes = {images.rgb8_array(m).shape for _, m in frames}
    assert shapes == {(240, 320, 3)}


@pytest.mark.ros
def test_a_walk_camera_with_a_bad_combination_ends_with_one_line(nodes):
    bad = nodes.start('scene_camera', [
        '-r', '__ns:=/bad', '-p', 'scene.motion:=walk', '-p', 'scene.empty:=true'])
    assert wait_for(lambda: not bad.running, 60)
    nodes.killed.append(bad)                                     # exits on purpose
    assert bad.proc.returncode == 1
    assert 'scene_camera: error: scene.motion walk needs a face to walk, not scene.empty' \
        in bad.output(), bad.output()
    assert 'Traceback' not in bad.output()
