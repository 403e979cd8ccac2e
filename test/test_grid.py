# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Grid geometry: row-major indices, offsets and the offset table."""
from ipomdp_gaze.model.grid import Grid, parse_grid
import numpy as np
import pytest


def test_index_cell_round_trip():
    g = Grid(3, 5)
    for i in range(g.n_cells):
        assert g.index(*g.cell(i)) == i
    assert g.cell(7) == (1, 2)
    assert g.center_index == 7


def test_offsets_are_in_degrees_dx_columns_dy_rows():
    g = Grid(3, 3, 2.0)
    dx, dy = g.offsets_deg(0)
    assert dx[g.index(0, 2)] == 4.0 and dy[g.index(2, 0)] == 4.0
    assert dx[g.index(2, 0)] == 0.0


def test_offset_table_matches_pair_offsets():
    g = Grid(4, 3, 0.5)
    tx, ty = g.offset_table_deg()
    assert tx.shape == g.kernel_shape == (7, 5)
    ri, ci = g.pair_offset_index()
    for k in range(g.n_cells):
        dx, dy = g.offsets_deg(k)
        np.testing.assert_allclose(tx[ri[k], ci[k]], dx)
        np.testing.assert_allclose(ty[ri[k], ci[k]], dy)


@pytest.mark.parametrize('text', ['7', '7x', 'x7', '0x3', 'ax3', '7x7x7'])
def test_bad_grid_strings(text):
    with pytest.raises(ValueError):
        parse_grid(text)


def test_bad_grid_values():
    with pytest.raises(ValueError, match='spacing_deg'):
        Grid(3, 3, 0.0)
    with pytest.raises(ValueError, match='rows'):
        Grid(0, 3)


@pytest.mark.parametrize('args, message', [
    ((None, 3), 'rows must be a positive integer, got None'),
    (('x', 3), "rows must be a positive integer, got 'x'"),
    ((float('inf'), 3), 'rows must be a positive integer, got inf'),
    ((3, float('nan')), 'cols must be a positive integer, got nan'),
    (([3], 3), r'rows must be a positive integer, got \[3\]'),
    ((3, 3, None), 'spacing_deg must be a positive finite number, got None'),
    ((3, 3, 'x'), "spacing_deg must be a positive finite number, got 'x'"),
])
def test_grid_values_that_are_no_numbers_are_named(args, message):
    """QA: None, 'x' and inf were int()'s TypeError, ValueError and OverflowError."""
    with pytest.raises(ValueError, match=message):
        Grid(*args)


def test_fixation_window_gives_each_cells_offset_from_the_fixation():
    grid = Grid(3, 5, 2.0)
    dx, dy = grid.offset_table_deg()
    for fixation in (0, 7, 14):
        r, c = grid.cell(fixation)
        want_dx, want_dy = grid.offsets_deg(fixation)
        np.testing.assert_array_equal(grid.fixation_window(dx, r, c).ravel(), want_dx)
        np.testing.assert_array_equal(grid.fixation_window(dy, r, c).ravel(), want_dy)
