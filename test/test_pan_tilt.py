# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The pan/tilt face task without ROS: the scene, its rendered views, their counts, calibration."""
import math
import subprocess
import sys

from conftest import REPO
from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import observed_cells, pixel_cells
from ipomdp_gaze.vision.calibrate import count_model, tally_pan_tilt_scenes, tally_views
from ipomdp_gaze.vision.detector import HaarDetector
from ipomdp_gaze.vision.pan_tilt import (box_centres_uv, PAN_TILT_GRID, PanTiltSceneSet,
                                         read_scene_file, SceneGeometry, shipped_camera,
                                         user_scene, ViewObserver)
from ipomdp_gaze.vision.scenes import TEST_FACES, TRAIN_FACES
import numpy as np
import pytest

CAMERA = shipped_camera()
GEOMETRY = SceneGeometry(PAN_TILT_GRID, CAMERA)
SMALL = SceneGeometry(Grid(5, 5, 5.0), CAMERA)        # 25 poses: calibration tests stay quick


def test_the_scene_spans_the_grid_plus_half_the_view_at_the_camera_resolution():
    hfov, vfov = CAMERA.fov_deg
    assert GEOMETRY.px_per_deg == pytest.approx(CAMERA.fx * math.pi / 180)
    assert GEOMETRY.half_span_deg == pytest.approx((25 + hfov / 2, 25 + vfov / 2))
    assert GEOMETRY.size_px == (945, 868)
    assert SceneGeometry.from_dict(GEOMETRY.to_dict()) == GEOMETRY
    # The corners of the grid's area: cell edges, half a cell beyond the extreme centres.
    x0, x1, y0, y1 = GEOMETRY.grid_area_px()
    assert GEOMETRY.point_position(x0, y0) == pytest.approx((-0.5, -0.5))
    assert GEOMETRY.point_position(x1, y1) == pytest.approx((10.5, 10.5))


def _dot_scene(geometry, x, y):
    width, height = geometry.size_px
    scene = np.zeros((height, width), dtype=np.uint8)
    scene[y - 1:y + 2, x - 1:x + 2] = 255
    return scene


@pytest.mark.parametrize('head, dot', [((5, 5), (472, 434)), ((2, 8), (700, 230)),
                                       ((10, 0), (150, 760)), ((3.4, 6.7), (560, 300))])
def test_a_rendered_view_shows_each_direction_where_the_binning_puts_it(head, dot):
    scene = _dot_scene(GEOMETRY, *dot)
    view = GEOMETRY.render(scene, head)
    assert view.shape == (240, 320)
    v, u = np.unravel_index(np.argmax(view), view.shape)
    # The dot's centre is pixel (x, y) of the scene: its direction in grid units.
    row, col = GEOMETRY.point_position(dot[0] + 0.5, dot[1] + 0.5)
    du, dv = CAMERA.angles_deg(u, v)
    cells_per_px = 1 / (GEOMETRY.px_per_deg * 5.0)
    assert head[1] + du / 5.0 == pytest.approx(col, abs=1.01 * cells_per_px)
    assert head[0] + dv / 5.0 == pytest.approx(row, abs=1.01 * cells_per_px)
    assert pixel_cells(u, v, CAMERA, head, 5.0) == GEOMETRY.cell_of_point(dot[0] + 0.5,
                                                                          dot[1] + 0.5)


def test_a_dot_outside_the_field_of_view_is_not_in_the_view():
    view = GEOMETRY.render(_dot_scene(GEOMETRY, 900, 100), (8, 2))
    assert view.max() == 0


def test_render_refuses_a_scene_of_another_size():
    with pytest.raises(ValueError, match='945x868'):
        GEOMETRY.render(np.zeros((100, 100), np.uint8), (5, 5))


def test_scenes_are_deterministic_split_and_put_the_face_inside_the_grid():
    test = PanTiltSceneSet('test', GEOMETRY, seed=4)
    a, b = test.scene(3), PanTiltSceneSet('test', GEOMETRY, seed=4).scene(3)
    np.testing.assert_array_equal(a.image, b.image)
    assert a.image.shape == (868, 945, 3) and not a.image.flags.writeable
    for split, faces in (('train', TRAIN_FACES), ('test', TEST_FACES)):
        scenes = PanTiltSceneSet(split, GEOMETRY, seed=1)
        for i in range(12):
            scene = scenes.scene(i)
            assert scene.face_index in faces
            assert 30 <= scene.face_px <= 70
            assert scene.cell == GEOMETRY.cell_of_point(*scene.face_centre_px)
            assert 0 <= scene.cell[0] < 11 and 0 <= scene.cell[1] < 11
    assert not np.array_equal(PanTiltSceneSet('train', GEOMETRY, seed=4).scene(3).image,
                              a.image)
    assert PanTiltSceneSet.from_kwargs(test.kwargs()).scene(3).cell == a.cell


def test_a_users_image_is_resized_to_the_scene_and_its_face_centre_scaled():
    image = np.zeros((434, 472, 3), np.uint8)
    scene = user_scene(image, (236.0, 217.0), GEOMETRY)
    assert scene.image.shape == (868, 945, 3)
    assert scene.cell == (5, 5)
    assert user_scene(image, (10.0, 10.0), grid=(21, 21)).cell == (0, 0)
    with pytest.raises(ValueError, match='outside'):
        user_scene(image, (500.0, 10.0), GEOMETRY)


@pytest.mark.parametrize('width, height', [(400, 300), (200, 400)])
def test_a_users_image_of_another_shape_is_fitted_to_the_scene_not_stretched(width, height):
    """QA: a 4:3 photo was stretched to the 945x868 scene: its faces a fifth narrower."""
    image = np.zeros((height, width, 3), np.uint8)
    image[100:140, 150:190] = 255                         # a 40 px square, centre (170, 120)
    scene = user_scene(image, (170.0, 120.0), GEOMETRY)
    assert scene.image.shape == (868, 945, 3)
    rows, cols = np.nonzero(scene.image[:, :, 0] > 200)
    side_x, side_y = np.ptp(cols) + 1, np.ptp(rows) + 1
    assert abs(side_x - side_y) <= 1                      # square, as in the photo
    x, y = scene.face_centre_px
    assert abs(x - (cols.min() + cols.max() + 1) / 2) <= 1
    assert abs(y - (rows.min() + rows.max() + 1) / 2) <= 1
    assert scene.cell == GEOMETRY.cell_of_point(x, y)
    assert np.all(scene.image[0, 0] == 128)               # a band beside the photo


class Boxes:
    """A detector that returns fixed boxes, whatever the image."""

    window_px = (20, 20)

    def __init__(self, boxes):
        self.boxes = np.asarray(boxes, dtype=np.int64)

    def __call__(self, gray):
        return self.boxes


def test_the_observer_bins_box_centres_with_the_head_pose_and_k():
    # A 21 px box whose centre is the principal point, and one 5 degrees to the right.
    step = round(CAMERA.fx * math.tan(math.radians(5.0)))
    boxes = [[149, 109, 22, 22], [149 + step, 109, 22, 22]]
    observer = ViewObserver(Boxes(boxes), PAN_TILT_GRID, 10)
    obs = observer.observe(np.zeros((240, 320), np.uint8), CAMERA, (2, 3))
    assert box_centres_uv(boxes)[0] == pytest.approx((159.5, 119.5))
    assert obs.counts[PAN_TILT_GRID.index(2, 3)] == 1
    assert obs.counts[PAN_TILT_GRID.index(2, 4)] == 1
    seen = observed_cells(CAMERA, PAN_TILT_GRID, (2, 3))
    np.testing.assert_array_equal(np.isnan(obs.counts), ~seen)
    assert obs.detector_pixels == 320 * 240
    with pytest.raises(ValueError, match='camera_info says 320x240'):
        observer.observe(np.zeros((100, 120), np.uint8), CAMERA, (2, 3))


def test_the_haar_detector_finds_a_pasted_face_in_its_cell_from_several_poses():
    scene = PanTiltSceneSet('train', GEOMETRY, seed=0).scene(0)
    observer = ViewObserver(HaarDetector(), PAN_TILT_GRID, 10)
    target = PAN_TILT_GRID.index(*scene.cell)
    r, c = scene.cell
    for head in ((r, c), (r, max(c - 1, 0)), (min(r + 1, 10), c)):
        obs = observer.observe(GEOMETRY.render(scene.image, head), CAMERA, head)
        assert obs.raw_counts[target] >= 3
        assert obs.raw_counts[target] == obs.raw_counts.max()


@pytest.fixture(scope='module')
def small_scenes():
    return PanTiltSceneSet('train', SMALL, seed=0)


def test_tallying_views_learns_a_camera_fpoc(small_scenes):
    tallies = tally_pan_tilt_scenes(small_scenes, range(6), {}, 10, processes=1)
    assert tallies.images == 6 and tallies.fixations == 6 * 25
    model = count_model(tallies, SMALL.grid, pool_radius=0.0, min_tallies=0)
    hit = 1 - model.p_target[:, :, 0]
    false_alarm = 1 - model.p_null[:, :, 0]
    assert hit[0, 0] > false_alarm[0, 0] + 0.3
    seen = tallies.target[0, 0].sum(), tallies.null[0, 0].sum()
    assert 1 - tallies.target[0, 0, 0] / seen[0] > 0.5 > 0.2 > 1 - tallies.null[0, 0, 0] / seen[1]
    # Offsets no view shows (3 and 4 cells off: the view is 5 cells wide) say nothing.
    np.testing.assert_array_equal(model.p_target[3:, :], model.p_null[3:, :])
    assert not model.observed(SMALL.grid.index(0, 0)).reshape(5, 5)[3:, :].any()
    assert (model.elm_kernel()[:2, :] == 0).all()


def test_scenes_past_null_scenes_only_add_target_tallies(small_scenes):
    full = tally_pan_tilt_scenes(small_scenes, [0, 1], {}, 10, processes=1)
    part = tally_pan_tilt_scenes(small_scenes, [0, 1], {}, 10, null_scenes=1, processes=1)
    first = tally_pan_tilt_scenes(small_scenes, [0], {}, 10, processes=1)
    np.testing.assert_array_equal(part.target, full.target)
    np.testing.assert_array_equal(part.null, first.null)
    assert part.fixations < full.fixations


def test_tally_views_is_what_the_observer_sees_at_every_pose(small_scenes):
    scene = small_scenes.scene(2)
    observer = ViewObserver(HaarDetector(), SMALL.grid, 10)
    target = SMALL.grid.index(*scene.cell)
    tallies = tally_views(observer, SMALL, scene.image, target, fixations=[12])
    counts = observer.observe(SMALL.render(scene.image, (2, 2)), CAMERA, (2, 2)).counts
    assert tallies.target.sum() == 1 and tallies.null.sum() == np.isfinite(counts).sum() - 1
    dr, dc = abs(scene.cell[0] - 2), abs(scene.cell[1] - 2)
    assert tallies.target[dr, dc, int(counts[target])] == 1


def test_calibrate_pan_tilt_writes_the_same_file_twice(tmp_path, cli_here):
    """Once on the command line, once in this process (no second interpreter): same bytes."""
    outs = []
    for run in ('a', 'b'):
        out = tmp_path / f'{run}.yaml'
        args = ['calibrate', '--pan-tilt', '--grid', '5x5', '--scenes', '2', '--null-scenes',
                '1', '--processes', '1', '--quiet', '--out', str(out)]
        result = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', *args], cwd=REPO,
                                capture_output=True, text=True, timeout=300) if run == 'a' \
            else cli_here(*args)
        assert result.returncode == 0, result.stderr
        assert 'calibrated on 2 scenes' in result.stdout
        outs.append(out.read_bytes())
    assert outs[0] == outs[1]
    model = load_observation(tmp_path / 'a.yaml')
    assert model.grid == Grid(5, 5, 5.0)
    image = model.meta['image']
    assert image['view'] == 'pan_tilt' and (image['width'], image['height']) == (320, 240)
    assert image['camera']['K'] == pytest.approx(CAMERA.k)
    assert (tmp_path / 'a.png').is_file()


@pytest.mark.parametrize('args, message', [
    (['--pan-tilt', '--images', 'x', '--labels', 'y.csv'], '--images is for the image task'),
    (['--pan-tilt', '--scenes', '2', '--windows', '21,3'], '--windows is for the image task'),
    (['--scenes', '2', '--hfov-deg', '30'], '--hfov-deg needs --pan-tilt'),
    (['--scenes', '2', '--null-scenes', '1'], '--null-scenes needs --pan-tilt'),
])
def test_calibrate_refuses_options_of_the_other_task(tmp_path, cli_here, args, message):
    run = cli_here('calibrate', *args, '--out', tmp_path / 'm.yaml')
    assert run.returncode == 2
    err = run.stderr
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], err


def test_a_truncated_jpeg_scene_file_is_refused_with_the_reason(tmp_path):
    """cv2.imread showed a JPEG cut short as its top part above grey, a scene of wrong pixels."""
    import cv2
    image = np.random.default_rng(0).integers(0, 256, (240, 320, 3), dtype=np.uint8)
    ok, data = cv2.imencode('.jpg', image)
    assert ok
    whole, cut = tmp_path / 'whole.jpg', tmp_path / 'cut.jpg'
    whole.write_bytes(data.tobytes())
    cut.write_bytes(data.tobytes()[:len(data) // 2])
    assert read_scene_file(whole).shape == (240, 320, 3)
    with pytest.raises(ValueError, match=r"cut\.jpg': truncated or corrupt JPEG: it ends before"):
        read_scene_file(cut)


def test_an_empty_scene_file_is_refused_in_our_words(tmp_path):
    """The reason for no bytes is ours, not OpenCV's assertion ('!buf.empty()')."""
    empty = tmp_path / 'empty.jpg'
    empty.write_bytes(b'')
    with pytest.raises(ValueError) as refused:
        read_scene_file(empty)
    assert str(refused.value) == f"scene.file '{empty}': not an image OpenCV can decode"
