# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``search.group_stop``: a grouped detection ends a still one-target search (docs/design.md 6.15).

The stop fires after the frame's Bayes step (the belief is the brute-force posterior either
way), answers the likeliest of the cells holding a group, never fires when it is off, for a
moving target, or without groups; bad groups are refused with the belief unchanged; and the
event's words say how the search ended.
"""
from __future__ import annotations

from dataclasses import replace

from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.answer import ended, heading
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
import numpy as np
import pytest
from test_session import brute_force_log_posterior, count_model, GRID

SETTINGS = SearchSettings(confidence=0.999, absent_prior=0.5, inhibit_return=True,
                          group_stop=True, max_fixations=30, decide_at_budget=True)


def started(settings=SETTINGS, seed=3):
    model = count_model(seed, scan=False)
    session = SearchSession(GRID, model, build_policy('elm', GRID, model), settings)
    session.reset(seed=0)
    return model, session, session.start()


def test_a_grouped_detection_ends_the_search_at_the_likeliest_cell_holding_one():
    model, session, k = started()
    counts = np.zeros(GRID.n_cells)
    counts[[0, 5]] = [1, 3]
    groups = np.zeros(GRID.n_cells)
    groups[[0, 5, 11]] = [1, 2, 1]
    result = session.update(Frame(counts, groups=groups))
    posterior = brute_force_log_posterior(model, None, [(k, counts)], 0.5)
    np.testing.assert_allclose(session.log_belief, posterior, atol=1e-9)
    likeliest = [0, 5, 11][int(np.argmax(session._pooled()[[0, 5, 11]]))]
    assert (result.decision, result.reason, result.ended) == ('found', 'group', True)
    assert result.map_cell == session.map_cell == likeliest
    assert result.terminated and result.fixation is None
    assert session.map_probability == pytest.approx(session._pooled()[likeliest])
    assert ended(result.decision, result.reason) == 'group'
    assert heading(result.decision, result.reason) == 'found at a grouped detection'


def test_the_likeliest_group_cell_follows_the_belief_not_the_order():
    for strong in (2, 9):
        model, session, k = started()
        counts = np.zeros(GRID.n_cells)
        counts[strong] = 3
        groups = np.zeros(GRID.n_cells)
        groups[[2, 9]] = 1
        result = session.update(Frame(counts, groups=groups))
        pooled = session._pooled()
        assert result.map_cell == (2 if pooled[2] >= pooled[9] else 9)


@pytest.mark.parametrize('change', [{'group_stop': False}, {'motion_sigma_cells': 0.5},
                                    {'stop_on_decision': False}])
def test_no_stop_when_off_for_a_moving_target_or_without_stopping(change):
    _, session, _ = started(replace(SETTINGS, **change))
    groups = np.zeros(GRID.n_cells)
    groups[4] = 1
    result = session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
    assert result.reason != 'group' and not result.ended


def test_frames_without_groups_or_with_none_in_the_grid_search_on():
    _, session, _ = started()
    for groups in (None, np.zeros(GRID.n_cells)):
        result = session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
        assert not result.ended and result.reason == ''


def test_the_confidence_comes_before_a_group_and_a_group_before_the_budget():
    model = count_model(4, scan=False)
    p_null, p_target = model.p_null.copy(), model.p_target.copy()
    p_null[0, 0], p_target[0, 0] = [0.7, 0.2, 0.1, 0.0], [0.1, 0.1, 0.1, 0.7]
    sure = CountObservation(GRID, p_target, p_null)     # a count of 3 only the target gives
    session = SearchSession(GRID, sure, build_policy('elm', GRID, sure),
                            replace(SETTINGS, confidence=0.6, max_fixations=1))
    session.reset(seed=0)
    k = session.start()
    counts = np.zeros(GRID.n_cells)
    counts[k] = 3
    far = GRID.n_cells - 1 if k != GRID.n_cells - 1 else 0
    groups = np.zeros(GRID.n_cells)
    groups[far] = 1
    result = session.update(Frame(counts, groups=groups))
    assert (result.decision, result.reason, result.map_cell) == ('found', '', k)
    _, session, _ = started(replace(SETTINGS, max_fixations=1))
    result = session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
    assert (result.decision, result.reason, result.map_cell) == ('found', 'group', far)


@pytest.mark.parametrize('groups, message', [(np.full(GRID.n_cells, 0.5), 'whole numbers'),
                                             (np.zeros(GRID.n_cells - 1), 'shape'),
                                             (np.full(GRID.n_cells, -1.0), 'whole numbers')])
def test_bad_groups_are_refused_and_the_belief_is_unchanged(groups, message):
    _, session, _ = started()
    before = session.log_belief
    result = session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
    assert result.status == 'rejected' and message in result.reason
    np.testing.assert_array_equal(session.log_belief, before)
    assert session.fixations == 0


def test_a_reset_forgets_the_group_answer():
    _, session, _ = started()
    groups = np.zeros(GRID.n_cells)
    groups[7] = 1
    session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
    assert session.map_cell == 7
    session.reset()
    assert session.map_cell == int(np.argmax(session._pooled())) and not session.ended


def test_the_belief_vetoes_a_group_where_it_gives_the_cell_less_than_group_probability():
    _, session, k = started()
    groups = np.zeros(GRID.n_cells)
    groups[7] = 1
    probe = session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
    p = session.map_probability                 # the group's cell after that frame
    for threshold, stops in ((p * 0.99, True), (min(p * 1.01, 0.999), False)):
        _, session, _ = started(replace(SETTINGS, group_probability=threshold))
        result = session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
        assert (result.reason == 'group') == stops and result.ended == stops
    assert probe.reason == 'group'


def test_the_settings_name_the_group_stop_as_the_node_and_yaml_do():
    settings = SearchSettings.from_parameters({'search.group_stop': True,
                                               'search.group_probability': 0.05})
    assert (settings.group_stop, settings.group_probability) == (True, 0.05)
    with pytest.raises(ValueError, match='search.group_probability'):
        SearchSettings.from_parameters({'search.group_probability': 1.0})


def test_a_group_in_an_excluded_cell_does_not_end_the_search():
    _, session, _ = started(replace(SETTINGS, group_probability=0.0))
    session.exclude([7])
    groups = np.zeros(GRID.n_cells)
    groups[7] = 1
    result = session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
    assert not result.ended and result.reason == ''
    groups[3] = 1                                   # an open cell with a group: that one
    result = session.update(Frame(np.zeros(GRID.n_cells), groups=groups))
    assert (result.reason, result.map_cell) == ('group', 3)


def test_the_offline_views_report_each_models_grouping():
    from ipomdp_gaze.drivers.scene_tasks import (MODEL_GROUPS, model_groups,
                                                 ROOM_GROUP_MIN_NEIGHBORS, SceneTask, task_spec)
    from ipomdp_gaze.files.share_files import config_file
    from ipomdp_gaze.files.yaml_files import yaml_parameters
    detector = yaml_parameters(config_file('faces_camera_detector.yaml'), 'foveal_detector')
    controller = yaml_parameters(config_file('faces_camera_controller.yaml'), 'gaze_controller')
    assert controller['search.group_stop'] and detector['publish_groups'] > 0
    assert model_groups() == model_groups(detector['observation.file']) \
        == detector['publish_groups']
    assert model_groups('faces-pan-tilt-40-profile') == MODEL_GROUPS['faces-pan-tilt-40-profile']
    assert model_groups('faces-pan-tilt-yunet') == 0          # YuNet does not group
    spec = task_spec('pan-tilt', split='train', seed=1000)
    assert spec.group_min_neighbors == detector['publish_groups'] and spec.settings.group_stop
    assert task_spec('pan-tilt', group_min_neighbors=2).group_min_neighbors == 2
    assert task_spec('pan-tilt', faces='0-4').group_min_neighbors == ROOM_GROUP_MIN_NEIGHBORS
    assert task_spec('faces-420').group_min_neighbors == 0
    with pytest.raises(ValueError, match='group_min_neighbors'):
        task_spec('pan-tilt', group_min_neighbors=-1)
    task = SceneTask.get(spec)
    assert task.sensor.sensor.observer.group_min_neighbors == detector['publish_groups']
    task.sensor.start(task.scene(0).image)
    frame = task.sensor.observe(task.model.grid.center_index)
    assert frame.groups is not None and frame.groups.shape == (task.model.grid.n_cells,)
