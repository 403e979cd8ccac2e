# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The blind sweep baseline, empty pan/tilt scenes and the head-time model (issue 22)."""
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.observation_file import load_observation
from ipomdp_gaze.policies.baselines import SWEEP_STEP, sweep_tile_cells
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.vision.scene_eval import (head_time_s, SACCADE_TIME_S, SETTLE_TIME_S,
                                           task_spec)
import numpy as np
import pytest


def test_sweep_tiles_the_pan_tilt_grid_by_the_cameras_field_of_view():
    model = load_observation('faces-pan-tilt')          # 25 x 18.9 degrees over 5-degree cells
    assert sweep_tile_cells(model.grid, model) == (3, 5)
    sweep = build_policy('sweep', model.grid, model)
    rc = [divmod(int(k), 11) for k in sweep.poses]
    assert len(rc) == 12 and rc[:4] == [(1, 2), (1, 5), (1, 8), (4, 8)]   # boustrophedon
    # Every cell belongs to one pose's tile, within the view's half-size of it.
    pr, pc = np.divmod(sweep.poses[sweep.owner], 11)
    rows, cols = np.divmod(np.arange(121), 11)
    assert np.all(np.abs(rows - pr) <= 1) and np.all(np.abs(cols - pc) <= 2)
    # The next pass repeats the order; the sweep ignores the belief.
    belief = np.random.default_rng(0).dirichlet(np.ones(121), size=1)
    assert sweep.select(belief, 13, None)[0] == sweep.poses[1]


def test_sweep_without_a_field_of_view_is_a_raster_with_the_stated_step():
    from ipomdp_gaze.fpoc import HumanFPOC
    grid = Grid(7, 7, 1.0)
    sweep = build_policy('sweep', grid, HumanFPOC())
    rows, cols = np.divmod(sweep.poses, grid.cols)
    assert sorted(set(rows)) == sorted(set(cols)) == [1, 3, 5]     # 3 tiles of 3 cells, evenly
    grid = Grid(21, 21, 1.0)
    rows = np.divmod(build_policy('sweep', grid, HumanFPOC()).poses, 21)[0]
    assert sorted(set(np.diff(sorted(set(rows))))) == [SWEEP_STEP]


def test_head_time_counts_views_settling_and_saccades_from_the_centre():
    grid = Grid(11, 11, 5.0)
    centre = grid.center_index
    # Two views: the centre (no saccade), then 2 cells right and 1 down: largest angle 10 deg.
    path = [centre, grid.index(6, 7)]
    expected = 0.05 + 0.07 + 2 * SETTLE_TIME_S + SACCADE_TIME_S + 10.0 / 120.0
    assert head_time_s(grid, path, [0.05, 0.07]) == pytest.approx(expected)


def test_empty_pan_tilt_scenes_are_the_same_crops_without_a_face():
    from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet
    face = PanTiltSceneSet('train', seed=3).scene(0)
    empty = PanTiltSceneSet('train', seed=3, empty=True).scene(0)
    assert empty.cell is None and not empty.has_face and face.has_face
    assert empty.background == face.background and empty.image.shape == face.image.shape
    assert (empty.image != face.image).any()


def test_task_spec_refuses_unknown_searchers_and_splits():
    with pytest.raises(ValueError, match='unknown searcher'):
        task_spec('pan-tilt', compare=('nope',))
    with pytest.raises(ValueError, match='split'):
        task_spec('pan-tilt', split='validation')
    with pytest.raises(ValueError, match='pan/tilt answer rule'):
        task_spec('faces-420', compare=('sweep-tile',))
