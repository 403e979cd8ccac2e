# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The search drawn on the camera image (``ipomdp_gaze.vision.annotate``) and its files."""
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import observed_cells, pixel_cells
from ipomdp_gaze.vision.annotate import annotate, fovea_cell_map, grid_canvas, view_cell_map
from ipomdp_gaze.vision.fovea import cell_edges_px
from ipomdp_gaze.vision.pan_tilt import PAN_TILT_GRID, shipped_camera
from ipomdp_gaze.vision.search_plots import save_gif, save_png
import numpy as np
import pytest

GRID = Grid(21, 21)


def test_the_fovea_map_tiles_the_image_with_the_fovea_cell_edges():
    cell_map = fovea_cell_map(GRID, 431, 420)
    boxes = cell_map.cell_boxes()
    x_edges, y_edges = cell_edges_px(431, 21), cell_edges_px(420, 21)
    rows, cols = GRID.cell(np.arange(GRID.n_cells))
    assert np.array_equal(boxes[:, 0], x_edges[cols])
    assert np.array_equal(boxes[:, 2], x_edges[cols + 1] - 1)
    assert np.array_equal(boxes[:, 1], y_edges[rows])
    assert np.array_equal(boxes[:, 3], y_edges[rows + 1] - 1)


@pytest.mark.parametrize('head_rc', [(5, 5), (0, 10), (10.4, 0.3)])
def test_the_view_map_agrees_with_the_detector_binning(head_rc):
    camera = shipped_camera()
    cell_map = view_cell_map(PAN_TILT_GRID, camera, head_rc)
    v, u = np.mgrid[0:camera.height:7, 0:camera.width:7]
    rows, cols = pixel_cells(u.ravel(), v.ravel(), camera, head_rc, PAN_TILT_GRID.spacing_deg)
    inside = (rows >= 0) & (rows < 11) & (cols >= 0) & (cols < 11)
    expected = np.where(inside, rows * 11 + cols, -1)
    assert np.array_equal(cell_map.cell_index()[v.ravel(), u.ravel()], expected)
    boxes = cell_map.cell_boxes()
    shown = (boxes[:, 2] >= boxes[:, 0]) & (boxes[:, 3] >= boxes[:, 1])
    assert np.array_equal(shown, observed_cells(camera, PAN_TILT_GRID, head_rc))


def _box(cell, cell_map):
    x0, y0, x1, y1 = cell_map.cell_boxes()[cell]
    return slice(y0 + 3, y1 - 2), slice(x0 + 3, x1 - 2)


def test_the_belief_overlay_tints_likely_cells_and_leaves_the_input_alone():
    image = np.full((420, 420), 128, dtype=np.uint8)
    before = image.copy()
    cell_map = fovea_cell_map(GRID, 420, 420)
    belief = np.full(GRID.n_cells, 1e-9)
    belief[100] = 0.5
    belief[300] = 0.5e-2
    out = annotate(image, cell_map, belief)
    assert out.shape == (420, 420, 3) and out.dtype == np.uint8
    assert np.array_equal(image, before)
    likely, medium, unlikely = (out[_box(c, cell_map)].reshape(-1, 3).mean(axis=0)
                                for c in (100, 300, 0))
    assert likely[0] > 128 and likely[1] > 128            # yellow: brighter red and green
    assert unlikely.sum() < 3 * 128                        # darkened where the belief is low
    assert unlikely.sum() < medium.sum() < likely.sum()


def test_off_grid_pixels_of_a_camera_view_are_untouched():
    camera = shipped_camera()
    cell_map = view_cell_map(PAN_TILT_GRID, camera, (5, 0))       # looking at the left edge
    image = np.random.default_rng(0).integers(0, 256, (camera.height, camera.width, 3),
                                              dtype=np.uint8)
    out = annotate(image, cell_map, np.full(121, 1 / 121))
    off = cell_map.cols < 0
    assert off.any() and (~off).any()
    assert np.array_equal(out[40:200][:, off], image[40:200][:, off])
    assert not np.array_equal(out[:, ~off], image[:, ~off])


def test_fixations_detections_windows_and_the_answer_are_drawn_where_they_belong():
    canvas, cell_map = grid_canvas(GRID, 20)
    plain = annotate(canvas, cell_map)
    out = annotate(canvas, cell_map, fixations=[0, 220], windows=[(0, 0, 60, 60, False)],
                   detections=[[300.0, 300.0]], found=(440, 0.97))
    x0, y0, x1, y1 = cell_map.cell_boxes()[440]
    green = out[y0 - 2:y1 + 3, x0 - 2:x1 + 3]
    assert ((green[..., 1] > 200) & (green[..., 0] < 80)).any()        # the found rectangle
    assert (out[300, 296:305] == [255, 230, 0]).all(axis=1).any()        # a detection cross
    assert (out[0:60, 0] == [0, 255, 255]).all()                         # a window's edge
    centre = out[210, 210]                                               # fixation 2 disc
    assert not np.array_equal(centre, plain[210, 210])


@pytest.mark.parametrize('kwargs, message', [
    ({'belief': np.ones(5)}, 'belief has 5 cells, the grid 441'),
    ({'image': np.zeros((10, 10), np.uint8)}, 'the image is 10x10 px but the cell map is for'),
    ({'image': np.zeros((420, 420), np.float32)}, 'expected a grey (H, W) or RGB'),
])
def test_bad_inputs_are_refused_with_the_reason(kwargs, message):
    args = {'image': np.zeros((420, 420), np.uint8), 'cell_map': fovea_cell_map(GRID, 420, 420)}
    args.update(kwargs)
    with pytest.raises(ValueError, match=message.replace('(', r'\(').replace(')', r'\)')):
        annotate(**args)


def test_pictures_are_written_as_png_and_a_looping_gif(tmp_path):
    from PIL import Image
    canvas, cell_map = grid_canvas(Grid(5, 5), 20)
    frames = [annotate(canvas, cell_map, np.eye(25)[i] * 0.9 + 0.004, list(range(i + 1)))
              for i in range(3)]
    save_png(frames[-1], tmp_path / 'last.png')
    assert np.array_equal(np.asarray(Image.open(tmp_path / 'last.png').convert('RGB')),
                          frames[-1])
    assert save_gif(frames, tmp_path / 'search.gif') == 3
    gif = Image.open(tmp_path / 'search.gif')
    assert gif.n_frames == 3 and gif.info['loop'] == 0
    with pytest.raises(ValueError, match='no frame to animate'):
        save_gif([], tmp_path / 'none.gif')
