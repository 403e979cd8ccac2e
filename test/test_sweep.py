# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The blind sweep baseline, empty pan/tilt scenes and the head-time model (issue 22)."""
import itertools
import math

from ipomdp_gaze.drivers.scene_tasks import task_spec
from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_time import head_time_s, SACCADE_TIME_S, SETTLE_TIME_S
from ipomdp_gaze.model.view_reach import TILE_MARGIN_CELLS
from ipomdp_gaze.policies.baselines import axis_poses, SWEEP_STEP, sweep_tile_cells
from ipomdp_gaze.policies.registry import build_policy
import numpy as np
import pytest


def test_sweep_tiles_the_pan_tilt_grid_by_the_cameras_field_of_view():
    model = load_observation('faces-pan-tilt')          # 25 x 18.9 degrees over 5-degree cells
    assert sweep_tile_cells(model.grid, model) == (3, 5)
    sweep = build_policy('sweep', model.grid, model)
    rc = [divmod(int(k), 11) for k in sweep.poses]
    # Columns 1, 5, 9: the edge columns one cell from a view's centre, not at the image's
    # border where a face is cut; columns 3 and 7 are seen from both sides.
    assert len(rc) == 12 and rc[:4] == [(1, 1), (1, 5), (1, 9), (4, 9)]   # boustrophedon
    assert sorted({r for r, _ in rc}) == [1, 4, 6, 9]
    # Every cell belongs to one pose's tile, within the view's half-size of it.
    pr, pc = np.divmod(sweep.poses[sweep.owner], 11)
    rows, cols = np.divmod(np.arange(121), 11)
    assert np.all(np.abs(rows - pr) <= 1) and np.all(np.abs(cols - pc) <= 2)
    # The next pass repeats the order; the sweep ignores the belief.
    belief = np.random.default_rng(0).dirichlet(np.ones(121), size=1)
    assert sweep.select(belief, 13, None)[0] == sweep.poses[1]


def test_a_view_a_rounding_short_of_whole_cells_tiles_by_those_cells(monkeypatch):
    """QA: numpy 1.x's arctan made the 25-degree view 24.999999999999996 degrees, 4 cells."""
    from ipomdp_gaze.policies import baselines
    model = load_observation('faces-pan-tilt')
    monkeypatch.setattr(baselines, 'view_cells',
                        lambda grid, m: (3.776105319578252, 4.999999999999999))
    assert sweep_tile_cells(model.grid, model) == (3, 5)


def test_a_wider_lens_gets_fewer_poses_that_keep_the_edges_inside_the_image():
    model = load_observation('faces-pan-tilt-40')       # 40 x 30.5 degrees: 8 x 6.1 cells
    poses = build_policy('sweep', model.grid, model).poses
    rows, cols = np.divmod(poses, 11)
    assert sorted(set(cols)) == [3, 7] and sorted(set(rows)) == [2, 5, 8]


def _brute_covers(poses, n_cells, seen, well):
    for x in range(n_cells):
        offsets = [x - p for p in poses]
        if any(abs(d) <= well for d in offsets):
            continue
        if not (any(0 <= d <= seen for d in offsets) and any(-seen <= d <= 0 for d in offsets)):
            return False
    return True


@pytest.mark.parametrize('n_cells', range(1, 10))
def test_axis_poses_are_the_fewest_views_that_see_every_cell(n_cells):
    for view_cells in np.arange(0.5, 12.0, 0.25):
        seen = max(0, math.floor(view_cells / 2 - 0.5 + 1e-9))
        well = min(seen, max(0, math.floor(view_cells / 2 - 0.5 - TILE_MARGIN_CELLS + 1e-9)))
        poses = axis_poses(n_cells, view_cells)
        assert list(poses) == sorted(set(poses)) and 0 <= poses.min() <= poses.max() < n_cells
        assert _brute_covers(poses, n_cells, seen, well)
        fewest = next(k for k in range(1, n_cells + 1)
                      if any(_brute_covers(c, n_cells, seen, well)
                             for c in itertools.combinations(range(n_cells), k)))
        assert len(poses) == fewest, (n_cells, view_cells)


def test_sweep_without_a_field_of_view_is_a_raster_with_the_stated_step():
    from ipomdp_gaze.model.fpoc import HumanFPOC
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


def _session(settings, policy=None):
    from ipomdp_gaze.search.session import SearchSession
    model = load_observation('faces-pan-tilt')
    return model, SearchSession(model.grid, model, policy, settings)


def test_found_radius_decides_on_the_belief_around_a_cell_and_answers_that_cell():
    from ipomdp_gaze.search.session import Frame, pooled_belief, SearchSettings
    grid = Grid(11, 11, 5.0)
    belief = np.zeros(121)
    belief[[grid.index(5, 8), grid.index(6, 8)]] = 0.5         # a face split over two cells
    pooled = pooled_belief(belief, grid, 1)
    assert pooled.max() == pytest.approx(1.0) and pooled[grid.index(5, 8)] == pytest.approx(1.0)
    assert pooled[grid.index(8, 8)] == 0.0
    # Frames that split a face's detections between two cells (at the same offset from the
    # fixation, so neither outweighs the other): the cell rule stays undecided, the radius rule
    # finds it (and answers within one cell of both).
    counts = np.zeros(121)
    counts[[grid.index(5, 4), grid.index(5, 6)]] = 9.0
    decisions = {}
    for radius in (0, 1):
        _, session = _session(SearchSettings(confidence=0.6, found_radius=radius,
                                             repeat_weight=1.0))
        session.reset(seed=0)
        session.start()
        result = session.update(Frame(counts))
        decisions[radius] = (result.decision, session.map_cell, session.map_probability)
    assert decisions[0][0] == '' and decisions[0][2] < 0.6
    assert decisions[1][0] == 'found' and decisions[1][2] >= 0.6
    r, c = grid.cell(decisions[1][1])
    assert all(max(abs(r - 5), abs(c - col)) <= 1 for col in (4, 6))   # right for either cell


def test_decide_at_budget_says_absent_or_found_instead_of_giving_up():
    from ipomdp_gaze.search.session import Frame, SearchSettings
    grid = Grid(11, 11, 5.0)
    empty = np.zeros(121)
    out = {}
    for deadline in (False, True):
        _, session = _session(SearchSettings(confidence=0.999, max_fixations=1,
                                             absent_prior=0.5, decide_at_budget=deadline))
        session.reset(seed=0)
        session.start()
        out[deadline] = session.update(Frame(empty))
    assert out[False].decision == 'gave_up'
    assert out[True].decision == 'absent' and out[True].reason == 'budget' and out[True].ended
    # Without the absent hypothesis the deadline answers found (the most likely square).
    _, session = _session(SearchSettings(confidence=0.999, max_fixations=1,
                                         decide_at_budget=True))
    session.reset(seed=0)
    session.start()
    assert session.update(Frame(empty)).decision == 'found'
    assert grid.n_cells == 121


def test_settings_refuse_a_bad_found_radius_with_the_parameter_name():
    from ipomdp_gaze.search.session import SearchSettings
    with pytest.raises(ValueError, match='search.found_radius must be an integer from 0 to 5'):
        SearchSettings(found_radius=-1)
    with pytest.raises(ValueError, match='search.decide_at_budget must be true or false'):
        SearchSettings(decide_at_budget='yes')


def test_coverage_takes_the_sweeps_tiles_while_the_belief_is_diffuse_then_elm():
    from ipomdp_gaze.policies.baselines import COVERAGE_PEAK
    model = load_observation('faces-pan-tilt')
    coverage = build_policy('coverage', model.grid, model)
    elm = build_policy('elm', model.grid, model)
    poses = {int(k) for k in build_policy('sweep', model.grid, model).poses}
    uniform = np.full((1, 121), 1 / 121)
    assert int(coverage.select(uniform, 0, None)[0]) in poses
    peaked = np.full((1, 121), (1 - 0.9) / 120)
    peaked[0, 3] = 0.9
    assert 0.9 >= COVERAGE_PEAK
    assert coverage.select(peaked, 0, None)[0] == elm.select(peaked, 0, None)[0]
    # Inhibition of return masks its scores: the best unvisited tile next.
    from ipomdp_gaze.model.inhibition import unvisited_choice
    visited = np.zeros(121, bool)
    visited[list(poses)[:11]] = True
    left = (poses - set(list(poses)[:11])).pop()
    assert unvisited_choice(coverage, uniform, visited, 1, None, model.grid) == left


def test_the_face_demo_can_show_the_scene_without_its_face():
    from ipomdp_gaze.harness.demo import faces_setup
    setup = faces_setup(seed=3, empty=True)
    camera = dict(setup.nodes)['scene_camera']
    assert 'scene.empty:=true' in camera and 'seed:=3' in camera
    assert 'scene.empty:=true' not in dict(faces_setup(seed=3).nodes)['scene_camera']


def test_the_scene_camera_builds_the_empty_scene_it_is_asked_for():
    from ipomdp_gaze.nodes.scene_camera import _scene_config, scene_camera_params
    values = {p.name: p.default for p in scene_camera_params()}
    values.update({'seed': 5, 'scene.empty': True})
    empty = _scene_config(values).scene
    values['scene.empty'] = False
    face = _scene_config(values).scene
    assert empty.cell is None and face.cell is not None
    assert empty.background == face.background


def test_evaluate_scenes_refuses_bad_searchers_and_empty_fovea_scenes_in_one_line():
    import subprocess
    import sys
    for args, message in ((['--scenes', 'faces-420', '--empty-scenes', '1'],
                           '--empty-scenes is for --scenes pan-tilt'),
                          (['--scenes', 'pan-tilt', '--compare', 'elm:search.bogus=1'],
                           "searcher 'elm:search.bogus=1': expected parameter=value")):
        out = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'evaluate', '--episodes',
                              '1', *args], capture_output=True, text=True, timeout=120)
        assert out.returncode != 0 and message in out.stderr
        assert 'Traceback' not in out.stderr


def test_every_searcher_of_a_scene_shares_its_views_and_the_sweep_rules_follow_the_poses():
    from ipomdp_gaze.drivers.scene_eval import evaluate_scene
    from ipomdp_gaze.drivers.scene_tasks import SceneTask
    from ipomdp_gaze.drivers.sweep_rules import SWEEP_RULES
    spec = task_spec('pan-tilt', split='train', seed=7, compare=('sweep',) + SWEEP_RULES)
    results = {r.searcher: r for r in evaluate_scene(spec, 0)}
    assert list(results) == ['coverage', 'sweep'] + list(SWEEP_RULES)
    poses = tuple(int(k) for k in SceneTask.get(spec).sweep.poses)
    assert results['sweep-tile'].path == poses and results['sweep-tile'].fixations == 12
    for rule in SWEEP_RULES[1:]:
        path = results[rule].path
        assert path == poses[:len(path)]
        assert results[rule].decision in ('found', 'absent')
        if results[rule].decision == 'absent':              # nothing seen in the whole pass
            assert len(path) == 12
    assert results['sweep'].path[:len(poses)] == poses[:results['sweep'].fixations]
    # Every view was rendered and detected once for all six searchers.
    seen = set().union(*(r.path for r in results.values()))
    assert set(SceneTask.get(spec).sensor.frames) == seen
    for r in results.values():
        assert r.head_time_s > r.detector_s > 0
        if r.map_right:
            assert len(r.map_right) == 20 and r.map_right[-1] == r.right


def test_the_pan_tilt_task_runs_with_yunet_whose_boxes_carry_a_score():
    # YuNet returns (M, 5) boxes with a score; the view cache keeps boxes only, so the sweep's
    # grouped answer rules work for a scoring detector too.
    from ipomdp_gaze.drivers.scene_eval import evaluate_scene
    from ipomdp_gaze.drivers.scene_tasks import SceneTask
    from ipomdp_gaze.drivers.sweep_rules import SWEEP_RULES
    spec = task_spec('pan-tilt', split='train', seed=7, model='faces-pan-tilt-yunet',
                     compare=SWEEP_RULES)
    results = {r.searcher: r for r in evaluate_scene(spec, 0)}
    assert list(results) == ['coverage'] + list(SWEEP_RULES)
    boxes = SceneTask.get(spec).sensor.boxes
    assert boxes and all(b.ndim == 2 and b.shape[1] == 4 for b in boxes.values())
    assert any(len(b) for b in boxes.values())                 # YuNet saw the face somewhere
