# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The ``grouped`` cell observation: a view's raw boxes grouped as OpenCV does, per cell."""
from ipomdp_gaze.files.observation_file import (load_observation, model_from_dict, model_to_dict,
                                                ObservationFileError, save_observation)
from ipomdp_gaze.model.cell_observation import cell_observation_of, CellObservation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import PinholeCamera
from ipomdp_gaze.vision.detector import group_boxes, group_support
from ipomdp_gaze.vision.fovea import Fovea
from ipomdp_gaze.vision.pan_tilt import ViewObserver
import numpy as np
import pytest

# Three nearly equal boxes (one group of 3), two (a group of 2) and one alone, which grouping with
# min_neighbors 1 drops: OpenCV merges boxes whose sides and corners differ by < 0.2 of their size.
BOXES = np.array([[10, 10, 20, 20], [11, 10, 20, 20], [10, 11, 21, 21],
                  [100, 100, 20, 20], [101, 100, 20, 20], [200, 50, 30, 30]])


def test_group_support_is_the_number_of_raw_boxes_each_group_merged():
    grouped, support = group_support(BOXES, 1)
    # Each group is the mean box, rounded: (10 + 11 + 10) / 3 -> 10, (100 + 101) / 2 -> 100.
    np.testing.assert_array_equal(grouped, [[10, 10, 20, 20], [100, 100, 20, 20]])
    np.testing.assert_array_equal(support, [3, 2])
    np.testing.assert_array_equal(group_boxes(BOXES, 1), grouped)
    # min_neighbors 2 drops the group of 2 as well; 0 does not group (every box its own).
    np.testing.assert_array_equal(group_support(BOXES, 2)[1], [3])
    np.testing.assert_array_equal(group_support(BOXES, 0)[1], np.ones(6))


def test_a_cell_reads_its_largest_group_in_bins_else_its_raw_count():
    # Raw boxes in cells 0 (x3), 2 (x2) and 3; groups: support 3 and 7 in cell 0, 2 in cell 2.
    cells = np.array([0, 0, 0, 2, 2, 3])
    groups = (np.array([0, 0, 2]), np.array([3, 7, 2]))
    alone = CellObservation('grouped', 4, edges=(3, 5), min_neighbors=1)
    # cell 0: largest support 7 >= 5 -> bin 3; cell 2: 2 < 3 -> bin 1; cell 3 has no group -> 0
    np.testing.assert_array_equal(alone.values(cells, np.ones(6), 5, groups), [3, 0, 1, 0, 0])
    with_raw = CellObservation('grouped', 5, edges=(3,), min_neighbors=1, raw_levels=2)
    # groups start above the raw levels: cell 0 7 >= 3 -> 2 + 2 = 4, cell 2 2 < 3 -> 3; cell 3
    # (one raw box, no group) -> 1; a support exactly on an edge goes to the upper bin.
    np.testing.assert_array_equal(with_raw.values(cells, np.ones(6), 5, groups), [4, 0, 3, 1, 0])
    np.testing.assert_array_equal(with_raw.values([1, 1, 1], np.ones(3), 2, ([], [])), [0, 2])
    np.testing.assert_array_equal(with_raw.values([0], [1.0], 2, ([1], [3])), [1, 4])


def test_the_view_observer_groups_the_raw_boxes_and_bins_the_group_centres():
    camera = PinholeCamera.from_fov(320, 240, 25.0)
    grid = Grid(5, 5, 5.0)
    rule = CellObservation('grouped', 5, edges=(3, 5), min_neighbors=1, raw_levels=1)
    # The three boxes of the group of 3 around pixel (160, 120), the view's centre (the head's
    # cell (2, 2)); two boxes alone far to the left; one box alone at the bottom right.
    boxes = np.array([[150, 110, 20, 20], [151, 110, 20, 20], [150, 111, 21, 21],
                      [5, 110, 20, 20], [40, 110, 30, 30], [290, 200, 24, 24]])
    observer = ViewObserver(lambda image: boxes, grid, 5, rule)
    seen = observer.observe(np.zeros((240, 320), dtype=np.uint8), camera, (2, 2))
    np.testing.assert_array_equal(seen.group_support, [3])
    assert seen.group_cells.tolist() == [grid.index(2, 2)]
    values = seen.counts
    assert values[grid.index(2, 2)] == 3       # a group of 3: raw_levels + 1 + 1 (3 >= edge 3)
    # The boxes alone read their raw count clipped to 1, wherever their centres fall.
    alone = np.unique(seen.cells[3:])
    assert alone.size >= 2 and np.all(alone >= 0) and grid.index(2, 2) not in alone
    assert np.all(values[alone] == 1)
    others = np.setdiff1d(np.flatnonzero(np.isfinite(values)), np.r_[alone, grid.index(2, 2)])
    assert np.all(values[others] == 0)


def test_a_grouped_rule_survives_an_observation_file(tmp_path):
    rule = CellObservation('grouped', 5, edges=(4.0, 9.0), min_neighbors=2, raw_levels=1)
    assert CellObservation.from_dict(rule.to_dict()) == rule
    assert rule.to_dict() == {'kind': 'grouped', 'max_count': 5, 'edges': [4.0, 9.0],
                              'min_neighbors': 2, 'raw_levels': 1}
    model = load_observation('faces-pan-tilt')
    doc = model_to_dict(model)
    doc['target'] = np.full(model.grid.shape + (5,), 0.2).tolist()
    doc['null'] = doc['target']
    doc['cells'] = rule.to_dict()
    saved = model_from_dict(doc)
    save_observation(tmp_path / 'g.yaml', saved)
    assert cell_observation_of(load_observation(tmp_path / 'g.yaml').meta, 5) == rule
    doc['cells'] = dict(rule.to_dict(), min_neighbors=0)
    with pytest.raises(ObservationFileError, match='cells: grouped needs min_neighbors >= 1'):
        model_from_dict(doc)


@pytest.mark.parametrize('kwargs, words', [
    ({'kind': 'grouped', 'max_count': 4, 'edges': (3, 5)}, 'grouped needs min_neighbors >= 1'),
    ({'kind': 'grouped', 'max_count': 4, 'edges': (3,), 'min_neighbors': 1},
     'grouped with K = 4 and raw_levels 0 needs 2 edges, got 1'),
    ({'kind': 'grouped', 'max_count': 4, 'edges': (3,), 'min_neighbors': 1, 'raw_levels': 2},
     'raw_levels 2 needs 0 edges, got 1'),
    ({'kind': 'grouped', 'max_count': 4, 'min_neighbors': 1, 'raw_levels': 3},
     'leaves no bin for a group with raw_levels 3'),
    ({'kind': 'grouped', 'max_count': 4, 'edges': (5, 3), 'min_neighbors': 1},
     'strictly increasing'),
    ({'kind': 'grouped', 'max_count': 4, 'edges': (3, 5), 'min_neighbors': -1},
     'min_neighbors must be an int >= 0'),
    ({'kind': 'counts', 'max_count': 4, 'raw_levels': 1}, 'raw_levels are for grouped'),
    ({'kind': 'score_bins', 'max_count': 3, 'edges': (0.5,), 'min_neighbors': 1},
     'min_neighbors and raw_levels are for grouped, not score_bins'),
])
def test_bad_grouped_rules_are_refused_naming_the_problem(kwargs, words):
    with pytest.raises(ValueError, match=words):
        CellObservation(**kwargs)


def test_grouped_values_need_the_groups_and_the_fovea_refuses_them():
    rule = CellObservation('grouped', 3, edges=(4,), min_neighbors=1)
    with pytest.raises(ValueError, match='grouped cells need the grouped boxes'):
        rule.values([0], [1.0], 2)
    with pytest.raises(ValueError, match='grouped cells are for one whole view'):
        Fovea(lambda image: np.empty((0, 4)), Grid(3, 3), cells=CellObservation(
            'grouped', 10, edges=tuple(range(2, 10)), min_neighbors=1))


@pytest.mark.parametrize('args, message', [
    (['--scenes', '2', '--cells', 'grouped'], '--cells grouped needs --pan-tilt'),
    (['--pan-tilt', '--scenes', '2', '--raw-levels', '1'], '--raw-levels goes with --cells '
                                                           'grouped'),
    (['--pan-tilt', '--scenes', '2', '--cells', 'grouped', '--group-edges', '5,3'],
     'strictly increasing'),
    (['--pan-tilt', '--scenes', '2', '--cells', 'grouped', '--raw-levels', '8'],
     '--raw-levels 8 leaves no group bin'),
])
def test_calibrate_refuses_grouped_settings_that_cannot_work(tmp_path, cli_here, args, message):
    run = cli_here('calibrate', *args, '--out', tmp_path / 'm.yaml')
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], run.stderr


@pytest.mark.parametrize('extra, kind_k', [
    ([], None),
    (['--group-edges', '3,6,10', '--min-neighbors', '2'], 6),
])
def test_calibrate_grouped_on_two_tiny_training_scenes_writes_a_valid_model(
        tmp_path, cli_here, extra, kind_k):
    out = tmp_path / 'g.yaml'
    run = cli_here('calibrate', '--pan-tilt', '--grid', '5x5', '--scenes', '2', '--null-scenes',
                   '1', '--processes', '1', '--quiet', '--cells', 'grouped', '--raw-levels', '1',
                   *extra, '--out', out)
    assert run.returncode == 0, run.stderr
    model = load_observation(out)
    rule = cell_observation_of(model.meta, model.max_count + 1)
    assert rule.kind == 'grouped' and rule.raw_levels == 1
    if kind_k is None:
        # Quantile edges of the supports seen on the two edge scenes: at most K - 1 - 1 bins.
        assert rule.min_neighbors == 1 and 3 <= rule.max_count <= 10
        assert model.meta['calibration']['edges_from'] == 20
    else:
        assert rule.max_count == kind_k and rule.edges == (3.0, 6.0, 10.0)
        assert rule.min_neighbors == 2 and 'edges_from' not in model.meta['calibration']
    # Tables over the rule's K, each offset a distribution; the face's own cell says more often
    # than the null that a group is there.
    assert model.p_target.shape == (5, 5, rule.max_count)
    np.testing.assert_allclose(model.p_target.sum(axis=-1), 1.0)
    np.testing.assert_allclose(model.p_null.sum(axis=-1), 1.0)
    grouped = slice(rule.raw_levels + 1, None)
    assert model.p_target[0, 0, grouped].sum() > model.p_null[0, 0, grouped].sum()


def test_the_detector_nodes_setup_observes_grouped_cells_from_the_file(tmp_path):
    """``build_setup`` (the ROS detector node's) gives the view observer the file's rule."""
    from ipomdp_gaze.vision.detection import build_setup
    rule = CellObservation('grouped', 5, edges=(4.0, 9.0), min_neighbors=1, raw_levels=1)
    model = load_observation('faces-pan-tilt')
    doc = model_to_dict(model)
    doc['target'] = np.full(model.grid.shape + (5,), 0.2).tolist()
    doc['null'] = doc['target']
    doc['cells'] = rule.to_dict()
    save_observation(tmp_path / 'g.yaml', model_from_dict(doc))
    setup = build_setup('camera', str(tmp_path / 'g.yaml'))
    assert setup.observer.cells == rule
    camera = setup.camera
    image = np.zeros((camera.height, camera.width), dtype=np.uint8)
    values = setup.observer.observe(image, camera, (5, 5)).counts
    assert np.nanmax(values) == 0 and np.isnan(values).any()
