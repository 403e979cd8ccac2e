# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Pan/tilt head geometry without ROS: REP 103 angles of cells, signs, offsets and limits."""
import math

from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
import numpy as np
import pytest

GRID = Grid(11, 11, 5.0)
DEG = math.pi / 180


@pytest.mark.parametrize('row, col, pan_deg, tilt_deg', [
    (5, 5, 0.0, 0.0),
    (0, 0, 25.0, -25.0),       # top left: turn left (+pan), look up (-tilt)
    (10, 10, -25.0, 25.0),     # bottom right: turn right, look down
    (5, 6, -5.0, 0.0),
    (4, 5, 0.0, -5.0),
])
def test_rep103_angles_of_known_cells(row, col, pan_deg, tilt_deg):
    head = PanTiltMap(GRID)
    pan, tilt = head.angles(GRID.index(row, col))
    assert pan == pytest.approx(pan_deg * DEG, abs=1e-12)
    assert tilt == pytest.approx(tilt_deg * DEG, abs=1e-12)


def test_signs_and_offsets():
    head = PanTiltMap(GRID, pan_sign=-1, tilt_sign=-1, pan_offset_rad=0.1,
                      tilt_offset_rad=-0.2)
    pan, tilt = head.angles(GRID.index(0, 0))
    assert pan == pytest.approx(-25 * DEG + 0.1)
    assert tilt == pytest.approx(25 * DEG - 0.2)


@pytest.mark.parametrize('kwargs', [{}, {'pan_sign': -1}, {'tilt_sign': -1, 'pan_offset_rad': 0.3},
                                    {'tilt_offset_rad': -0.05}])
def test_nearest_cell_inverts_angles(kwargs):
    head = PanTiltMap(GRID, **kwargs)
    cells = np.arange(GRID.n_cells)
    pan, tilt = head.angles(cells)
    jitter = 0.4 * head.spacing_rad
    back = [head.nearest_cell(p + jitter, t - jitter) for p, t in zip(pan, tilt)]
    assert back == list(cells)


def test_nearest_cell_clips_to_the_grid():
    head = PanTiltMap(GRID)
    assert head.nearest_cell(3.0, -3.0) == GRID.index(0, 0)
    with pytest.raises(ValueError, match='finite'):
        head.nearest_cell(float('nan'), 0.0)


def test_limits_must_contain_every_cell():
    with pytest.raises(ValueError, match=r'cell \(\d+, 0\) needs pan 0.4363 rad.*limits'):
        PanTiltMap(GRID, pan_limits_rad=(-1.0, 0.4))
    with pytest.raises(ValueError, match='min < max'):
        PanTiltMap(GRID, tilt_limits_rad=(1.0, -1.0))
    with pytest.raises(ValueError, match='must differ'):
        PanTiltMap(GRID, pan_joint='head', tilt_joint='head')
    with pytest.raises(ValueError, match='pan_sign'):
        PanTiltMap(GRID, pan_sign=2)
