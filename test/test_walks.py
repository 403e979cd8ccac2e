# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Walk scenes: the still scene at speed 0, legs at the asked speed, leaving and coming back."""
import math

from ipomdp_gaze.drivers.tracking import return_time
from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet
from ipomdp_gaze.vision.walks import calibrate_motion, check_speed, WalkSceneSet
import numpy as np
import pytest


@pytest.mark.parametrize('index', [0, 3])
def test_a_walk_at_speed_zero_is_the_still_scene_bit_for_bit(index):
    walk = WalkSceneSet('train', seed=2, speed_deg_s=0).scene(index)
    still = PanTiltSceneSet('train', seed=2 + index).scene(0)
    for t in (0.0, 7.5, walk.duration_s):
        assert np.array_equal(walk.image_at(t), still.image)
        assert walk.truth_at(t).cell == tuple(still.cell)


@pytest.mark.parametrize('speed', [2.5, 15.0])
def test_every_leg_walks_at_the_asked_speed_and_pauses_stand_still(speed):
    walks = WalkSceneSet('train', seed=0, speed_deg_s=speed)
    ppd = walks.geometry.px_per_deg
    moved = 0
    for index in range(4):
        walk = walks.scene(index).walk
        steps = np.diff(walk.points_px, axis=0)
        seconds = np.diff(walk.times_s)
        distance = np.hypot(steps[:, 0], steps[:, 1])
        legs = distance > 0
        moved += legs.sum()
        np.testing.assert_allclose(distance[legs] / seconds[legs], speed * ppd, rtol=1e-9)
        assert np.all(seconds > 0)
    assert moved > 8


def test_the_face_leaves_the_reach_and_comes_back():
    walks = WalkSceneSet('train', seed=0, speed_deg_s=10)
    back = 0
    for index in range(6):
        scene = walks.scene(index)
        cells = [scene.truth_at(t).cell for t in np.arange(0, scene.duration_s, 0.05)]
        assert cells[0] is not None and None in cells
        when = return_time(scene)
        if when is not None:
            back += 1
            assert scene.truth_at(when + 0.01).cell is not None
            assert scene.truth_at(when - 0.02).cell is None
    assert back >= 4


def test_the_face_is_drawn_where_the_truth_says_and_clipped_at_the_edges():
    scene = WalkSceneSet('train', seed=1, speed_deg_s=12).scene(0)
    background = scene.background.astype(float)
    seen_out = False
    for t in np.arange(0.0, scene.duration_s, 0.7):
        image = scene.image_at(t)
        assert image.shape == scene.background.shape and image.dtype == np.uint8
        diff = np.abs(image.astype(float) - background).sum(axis=2)
        x, y = scene.truth_at(t).centre_px
        half = scene.side_px / 2
        inside = -half < x < image.shape[1] + half and -half < y < image.shape[0] + half
        if not inside:
            seen_out = True
            assert diff.sum() == 0
            continue
        ys, xs = np.nonzero(diff)
        assert xs.min() >= math.floor(x - half) - 1 and xs.max() <= math.ceil(x + half)
        assert ys.min() >= math.floor(y - half) - 1 and ys.max() <= math.ceil(y + half)
    assert seen_out


@pytest.mark.parametrize('value', [-1, 20.5, 'fast', True, float('nan')])
def test_a_bad_speed_is_refused_with_a_reason(value):
    with pytest.raises(ValueError, match='speed_deg_s must be a number from 0 to 20'):
        check_speed(value)


def test_motion_calibration_of_still_faces_is_no_motion():
    fit = calibrate_motion(scenes=5, speeds_deg_s=(0, 0))
    assert fit['sigma_cells'] == 0 and fit['leave_prob'] == 0 and fit['exits'] == 0
    assert fit['max_speed_cells'] == 0 and fit['turn_prob'] == 0


def test_motion_calibration_of_walks_at_one_speed_matches_the_path_geometry():
    speed, dt = 10.0, 0.2
    fit = calibrate_motion(scenes=20, speeds_deg_s=(speed, speed), dt_s=dt)
    per_s = speed / 5.0                                     # 5-degree cells
    ballistic = per_s * math.sqrt(dt / 2)                    # every pair moving, no pause
    assert 0.5 * ballistic < fit['sigma_cells'] <= ballistic * 1.001
    assert fit['max_speed_cells'] <= per_s * 1.001
    assert fit['speed_cells'] < per_s
    assert fit['exits'] >= 10 and 0 < fit['leave_prob'] < 1 and 0 < fit['return_prob'] < 1
    assert fit['velocity_sigma_cells'] < fit['sigma_cells']


def test_the_walk_plot_is_written(tmp_path):
    from ipomdp_gaze.vision.walks import plot_walk
    times = np.arange(0, 5, 0.25)
    face = np.stack([np.linspace(1, 4, times.size), np.linspace(2, 9, times.size)], axis=1)
    face[8:10] = np.nan
    head = np.round(face)
    head[8:10] = (4, 5)
    out = tmp_path / 'walk.png'
    plot_walk(times, face, head, out, 'a walk', events=[(1.0, 'found'), (2.0, 'lost')])
    assert out.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n' and out.stat().st_size > 5000


def test_a_long_walk_plot_title_stays_inside_the_figure(tmp_path, monkeypatch):
    """The walk demo's title, its scene camera's parameters, ran past both edges."""
    from ipomdp_gaze.vision import walks
    drawn = []
    monkeypatch.setattr(walks, 'write_figure', lambda fig, path, dpi: drawn.append(fig))
    monkeypatch.setattr('matplotlib.pyplot.close', lambda fig: None)
    title = ('the walking face and the gaze over ROS: seed:=1 motion:=walk speed_deg_s:=5.0 '
             'walk_duration_s:=5.0 split:=test')
    times = np.arange(0, 2, 0.5)
    walks.plot_walk(times, np.ones((4, 2)), np.ones((4, 2)), tmp_path / 'w.png', title)
    fig = drawn[0]
    renderer = fig.canvas.get_renderer()
    box = fig._suptitle.get_window_extent(renderer)
    assert 0 <= box.x0 and box.x1 <= fig.bbox.width and box.y1 <= fig.bbox.height
