# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""A camera on the pan/tilt head without ROS: K, pixel to cell, the cells a view shows."""
import math

from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.head_camera import (bin_points, observed_cells, PinholeCamera, pixel_cells,
                                           view_extent)
import numpy as np
import pytest

GRID = Grid(11, 11, 5.0)
CAMERA = PinholeCamera.from_fov(320, 240, 25.0)


def test_camera_from_fov_has_square_pixels_and_the_centre_as_principal_point():
    assert CAMERA.fx == pytest.approx(160 / math.tan(math.radians(12.5)))
    assert CAMERA.fy == CAMERA.fx
    assert (CAMERA.cx, CAMERA.cy) == (159.5, 119.5)
    hfov, vfov = CAMERA.fov_deg
    assert hfov == pytest.approx(25.0)
    assert vfov == pytest.approx(2 * math.degrees(math.atan(120 / CAMERA.fx)))
    assert CAMERA.k == [CAMERA.fx, 0.0, 159.5, 0.0, CAMERA.fy, 119.5, 0.0, 0.0, 1.0]
    assert PinholeCamera.from_dict(CAMERA.to_dict()) == CAMERA
    assert PinholeCamera.from_k(320, 240, CAMERA.k).matches(CAMERA)


@pytest.mark.parametrize('k, match', [
    ([1.0] * 8, '9 finite'),
    ([500.0, 0, 160, 0, 500.0, 120, 0, 0, float('nan')], '9 finite'),
    ([500.0, 3.0, 160, 0, 500.0, 120, 0, 0, 1], r'\[fx, 0, cx'),
    ([500.0, 0, 160, 0, 500.0, 120, 0, 0, 2], r'\[fx, 0, cx'),
    ([0.0, 0, 160, 0, 500.0, 120, 0, 0, 1], 'fx and fy'),
])
def test_a_k_that_is_not_a_pinhole_camera_is_refused(k, match):
    with pytest.raises(ValueError, match=match):
        PinholeCamera.from_k(320, 240, k)


@pytest.mark.parametrize('k', [[[500.0, 0, 160], [0, 500.0, 120], [0, 0, 1]],
                               ['500', 0, 160, 0, 500.0, 120, 0, 0, 1], 5.0])
def test_a_k_as_rows_text_or_one_number_is_9_numbers_row_major(k):
    """Rows were ``a camera record must be {width, height, K}`` (a TypeError); text was taken."""
    with pytest.raises(ValueError, match=r'^K must be 9 finite numbers \(the 3x3 camera matrix, '
                       r'row-major\), got '):
        PinholeCamera.from_dict({'width': 320, 'height': 240, 'K': k})


def test_the_principal_point_shows_the_head_cell_and_one_spacing_off_the_next_cell():
    head = (4, 7)
    row, col = pixel_cells(CAMERA.cx, CAMERA.cy, CAMERA, head, 5.0)
    assert (row, col) == (4, 7)
    step = CAMERA.fx * math.tan(math.radians(5.0))
    row, col = pixel_cells([CAMERA.cx + step, CAMERA.cx], [CAMERA.cy, CAMERA.cy - step], CAMERA,
                           head, 5.0)
    assert list(row) == [4, 3] and list(col) == [8, 7]


def test_pixel_cells_is_the_formula_with_halves_rounded_up():
    rng = np.random.default_rng(3)
    u, v = rng.uniform(0, 319, 500), rng.uniform(0, 239, 500)
    head = (5.3, 2.6)                              # an unrounded head position
    row, col = pixel_cells(u, v, CAMERA, head, 5.0)
    for i in range(u.size):
        want_col = math.floor(head[1] + math.degrees(math.atan((u[i] - 159.5) / CAMERA.fx)) / 5
                              + 0.5)
        want_row = math.floor(head[0] + math.degrees(math.atan((v[i] - 119.5) / CAMERA.fy)) / 5
                              + 0.5)
        assert (row[i], col[i]) == (want_row, want_col)
    half = CAMERA.fx * math.tan(math.radians(2.5))  # exactly half a cell right of the centre
    assert pixel_cells(CAMERA.cx + half, CAMERA.cy, CAMERA, (0, 0), 5.0)[1] == 1


@pytest.mark.parametrize('head, extent', [
    ((5, 5), (3, 7, 3, 7)),        # 5 columns (+-12.5 deg) and 5 rows, the outer two partly
    ((0, 0), (0, 2, 0, 2)),        # clipped to the grid
    ((10, 4), (8, 10, 2, 6)),
])
def test_a_view_shows_a_rectangle_of_cells(head, extent):
    assert view_extent(CAMERA, GRID, head) == extent
    mask = observed_cells(CAMERA, GRID, head).reshape(GRID.shape)
    row0, row1, col0, col1 = extent
    want = np.zeros(GRID.shape, dtype=bool)
    want[row0:row1 + 1, col0:col1 + 1] = True
    np.testing.assert_array_equal(mask, want)
    # Brute force: the cells some pixel centre of the view falls in.
    u, v = np.meshgrid(np.arange(320), np.arange(240))
    rows, cols = pixel_cells(u.ravel(), v.ravel(), CAMERA, head, 5.0)
    inside = (rows >= 0) & (rows < 11) & (cols >= 0) & (cols < 11)
    seen = np.zeros(GRID.shape, dtype=bool)
    seen[rows[inside], cols[inside]] = True
    np.testing.assert_array_equal(seen, want)


def test_a_view_beside_the_grid_shows_nothing():
    assert not observed_cells(CAMERA, GRID, (5, 20)).any()


def test_bin_points_counts_clips_and_marks_the_rest_unobserved():
    head = (5, 5)
    step = CAMERA.fx * math.tan(math.radians(5.0))
    points = np.array([[CAMERA.cx, CAMERA.cy]] * 12 + [[CAMERA.cx + step, CAMERA.cy]] * 2
                      + [[CAMERA.cx - 2 * step, CAMERA.cy - step]])
    counts, raw, cells = bin_points(points, CAMERA, GRID, head, max_count=10)
    assert raw[GRID.index(5, 5)] == 12 and counts[GRID.index(5, 5)] == 9     # clipped to K-1
    assert counts[GRID.index(5, 6)] == 2 and counts[GRID.index(4, 3)] == 1
    assert list(cells[:1]) == [GRID.index(5, 5)]
    observed = observed_cells(CAMERA, GRID, head)
    assert np.isnan(counts[~observed]).all()
    assert np.nansum(counts) == 12
    assert (counts[observed] >= 0).all() and np.nansum(counts[observed]) == 9 + 2 + 1


def test_points_whose_cell_is_outside_the_grid_are_dropped():
    counts, raw, cells = bin_points([[0.0, 0.0]], CAMERA, GRID, (0, 0), 10)
    assert list(cells) == [-1] and raw.sum() == 0
    assert np.nansum(counts) == 0


@pytest.mark.parametrize('kwargs', [{}, {'pan_sign': -1, 'tilt_offset_rad': 0.1},
                                    {'tilt_sign': -1, 'pan_offset_rad': -0.2}])
def test_head_position_inverts_angles_without_rounding(kwargs):
    head = PanTiltMap(GRID, **kwargs)
    for cell in (0, 17, 60, 120):
        row, col = head.position(*head.angles(cell))
        assert (row, col) == pytest.approx(GRID.cell(cell), abs=1e-12)
    pan, tilt = head.angles(GRID.index(5, 5))
    row, col = head.position(pan - head.pan_sign * math.radians(1.0), tilt)
    assert (row, col) == pytest.approx((5.0, 5.2))
