# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Non-square and even grids through the pan/tilt mapping, the head camera and the messages.

Every other pan/tilt and message-adapter test uses a square grid with an odd side (11x11, 5x5),
on which rows and columns, and a cell and the centre, cannot be confused. Here the grids are
4x6, 6x4, 2x8, 1x5 and 8x8: row-major order is ``r * cols + c``, the centre of an even side lies
between two cells (pan or tilt 0 is not a cell), and ``height = rows``, ``width = cols``.
"""
from __future__ import annotations

import math

from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.head_camera import bin_points, observed_cells, PinholeCamera
import numpy as np
import pytest

GRIDS = [Grid(4, 6, 5.0), Grid(6, 4, 5.0), Grid(2, 8, 3.0), Grid(1, 5, 4.0), Grid(8, 8, 2.0)]
IDS = [f'{g.rows}x{g.cols}' for g in GRIDS]
DEG = math.pi / 180


@pytest.mark.parametrize('row, col, pan_deg, tilt_deg', [
    (0, 0, 12.5, -7.5), (0, 5, -12.5, -7.5), (3, 0, 12.5, 7.5), (1, 2, 2.5, -2.5),
    (2, 3, -2.5, 2.5)])
def test_pan_tilt_of_a_4x6_grid(row, col, pan_deg, tilt_deg):
    grid = Grid(4, 6, 5.0)
    pan, tilt = PanTiltMap(grid).angles(grid.index(row, col))
    assert grid.index(row, col) == row * 6 + col
    assert pan == pytest.approx(pan_deg * DEG) and tilt == pytest.approx(tilt_deg * DEG)


@pytest.mark.parametrize('grid', GRIDS, ids=IDS)
@pytest.mark.parametrize('kwargs', [{}, {'pan_sign': -1, 'tilt_offset_rad': 0.05},
                                    {'tilt_sign': -1, 'pan_offset_rad': -0.1}])
def test_every_cell_round_trips_through_its_angles(grid, kwargs):
    head = PanTiltMap(grid, **kwargs)
    cells = np.arange(grid.n_cells)
    pan, tilt = head.angles(cells)
    assert [head.nearest_cell(p, t) for p, t in zip(pan, tilt)] == list(cells)
    row, col = grid.cell(cells)
    for c in cells:
        assert head.position(pan[c], tilt[c]) == pytest.approx((row[c], col[c]))
    # The grid's centre is between cells on an even side: pan 0 and tilt 0 with no offset.
    if not kwargs and grid.cols % 2 == 0:
        assert not np.any(np.isclose(pan, 0.0))
    if not kwargs and grid.rows % 2 == 0:
        assert not np.any(np.isclose(tilt, 0.0))


@pytest.mark.parametrize('grid', GRIDS, ids=IDS)
def test_a_point_at_the_image_centre_is_counted_in_the_head_cell(grid):
    # A camera whose field of view is about 3 x 2 cells, so that views are not square either.
    width, height = 300, 200
    fx = (width / 2) / math.tan(math.radians(1.5 * grid.spacing_deg))
    camera = PinholeCamera(width, height, fx, fx, (width - 1) / 2, (height - 1) / 2)
    centre = np.array([[camera.cx, camera.cy]])
    for cell in range(grid.n_cells):
        head_rc = grid.cell(cell)
        counts, raw, cells = bin_points(centre, camera, grid, head_rc, 10)
        assert cells.tolist() == [cell] and raw[cell] == 1 and counts[cell] == 1
        seen = observed_cells(camera, grid, head_rc).reshape(grid.shape)
        rows, cols = np.nonzero(seen)
        assert seen[head_rc] and np.all(np.abs(rows - head_rc[0]) <= 1)
        assert np.all(np.abs(cols - head_rc[1]) <= 2)
        np.testing.assert_array_equal(np.isnan(counts), ~seen.reshape(-1))


@pytest.mark.ros
@pytest.mark.parametrize('grid', GRIDS, ids=IDS)
def test_multiarray_layout_and_row_major_order(grid):
    from ipomdp_gaze.msg_adapters import grid_arrays
    values = np.zeros(grid.shape)
    values[grid.rows - 1, 1 % grid.cols] = 1.0
    msg = grid_arrays.to_multiarray(values, grid)
    dims = [(d.label, d.size, d.stride) for d in msg.layout.dim]
    assert dims == [('rows', grid.rows, grid.n_cells), ('cols', grid.cols, grid.cols)]
    assert int(np.argmax(np.asarray(msg.data))) == (grid.rows - 1) * grid.cols + 1 % grid.cols
    np.testing.assert_array_equal(grid_arrays.from_multiarray(msg, grid), values.reshape(-1))
    transposed = Grid(grid.cols, grid.rows, grid.spacing_deg)
    if transposed.shape != grid.shape:
        with pytest.raises(ValueError):
            grid_arrays.from_multiarray(msg, transposed)


@pytest.mark.ros
@pytest.mark.parametrize('grid', GRIDS, ids=IDS)
def test_evidence_image_is_rows_high_and_cols_wide(grid):
    from builtin_interfaces.msg import Time
    from ipomdp_gaze.msg_adapters import images
    values = np.arange(grid.n_cells, dtype=np.float64)
    msg = images.evidence_image(values, grid, Time(sec=2))
    assert (msg.height, msg.width, msg.step) == (grid.rows, grid.cols, 4 * grid.cols)
    np.testing.assert_array_equal(images.evidence_from_image(msg, grid), values)
    transposed = Grid(grid.cols, grid.rows, grid.spacing_deg)
    if transposed.shape != grid.shape:
        with pytest.raises(ValueError, match=f'{grid.rows}x{grid.cols}'):
            images.evidence_from_image(msg, transposed)
    belief = np.full(grid.n_cells, 1.0 / grid.n_cells)
    picture = images.belief_image(belief, grid, grid.n_cells - 1, 8, Time(sec=2))
    assert (picture.height, picture.width) == (8 * grid.rows, 8 * grid.cols)


@pytest.mark.ros
@pytest.mark.parametrize('grid', GRIDS, ids=IDS)
def test_row_col_and_joint_states_of_the_last_cell(grid):
    from builtin_interfaces.msg import Time
    from ipomdp_gaze.msg_adapters import grid_arrays, joints
    last = grid.n_cells - 1
    msg = grid_arrays.row_col(grid, last)
    assert list(msg.data) == [grid.rows - 1, grid.cols - 1]
    assert grid_arrays.cell_from_row_col(msg, grid, 'fixation') == last
    with pytest.raises(ValueError):
        grid_arrays.cell_from_row_col(grid_arrays.row_col(Grid(grid.rows + 1, grid.cols + 1),
                                                          grid.n_cells + grid.cols + 1),
                                      grid, 'fixation')
    head = PanTiltMap(grid)
    for cell in (0, last, grid.index(grid.rows // 2, grid.cols // 2)):
        state = joints.joint_state(head, cell, Time(sec=1))
        assert head.nearest_cell(*joints.angles_from_joint_state(state, head)) == cell
