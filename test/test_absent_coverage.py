# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``search.absent_needs_coverage``: no ``absent`` before the views have covered every cell (§6.16).

The views' reach against a brute-force walk over cells and views, the sweep's tiles covering the
grid, and the session: absent held back until the path covers every cell, the views in between
each covering a cell left, the belief the same Bayes posterior as without the setting, and
nothing changed for a model without a camera or a moving target.
"""
from __future__ import annotations

import copy
from dataclasses import replace

from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.view_reach import ViewReach
from ipomdp_gaze.policies.baselines import sweep_tiles
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
import numpy as np
import pytest

LENSES = ('faces-pan-tilt-profile', 'faces-pan-tilt-40-profile')
SETTINGS = SearchSettings(confidence=0.99, absent_prior=0.8, inhibit_return=True,
                          max_fixations=40, decide_at_budget=True, head_speed_deg_s=120.0,
                          view_time_s=0.15, head_tour=True)


def _brute_covered(grid, reach, views):
    """Walk every cell, quarter and view with plain Python."""
    out = []
    for cell in range(grid.n_cells):
        r, c = divmod(cell, grid.cols)
        quarters = {(a, b): False for a in (-1, 1) for b in (-1, 1)}
        for v in {int(v) for v in views}:
            dr, dc = r - v // grid.cols, c - v % grid.cols
            if abs(dr) > reach.seen[0] or abs(dc) > reach.seen[1]:
                continue
            for a, b in quarters:
                # whole along an axis when seen well, else only the half towards the view
                row_ok = abs(dr) <= reach.well[0] or (a < 0) == (dr > 0)
                col_ok = abs(dc) <= reach.well[1] or (b < 0) == (dc > 0)
                quarters[a, b] |= row_ok and col_ok
        out.append(all(quarters.values()))
    return np.array(out)


@pytest.mark.parametrize('seed', range(8))
def test_the_cells_views_cover_against_a_walk_by_hand(seed):
    rng = np.random.default_rng(seed)
    grid = Grid(int(rng.integers(3, 10)), int(rng.integers(3, 10)), 5.0)
    seen = tuple(int(v) for v in rng.integers(0, 4, size=2))
    well = tuple(int(rng.integers(0, s + 1)) for s in seen)
    reach = ViewReach(seen, well)
    views = rng.choice(grid.n_cells, size=int(rng.integers(0, 6)), replace=False)
    np.testing.assert_array_equal(reach.covered(grid, views), _brute_covered(grid, reach, views))
    sees_well = reach.sees_well(grid, [0, grid.n_cells - 1])
    for v in range(grid.n_cells):
        vr, vc = divmod(v, grid.cols)
        expected = any(abs(vr - r) <= well[0] and abs(vc - c) <= well[1]
                       for r, c in ((0, 0), (grid.rows - 1, grid.cols - 1)))
        assert sees_well[v] == expected


def test_a_quarter_cut_in_every_view_is_not_covered():
    """Two views that cut a cell along different axes both miss its far corner."""
    grid, reach = Grid(9, 9, 5.0), ViewReach((2, 2), (1, 1))
    cell = grid.index(5, 5)
    views = [grid.index(5, 3), grid.index(3, 7)]
    assert not reach.covered(grid, views)[cell]
    assert reach.covered(grid, views + [grid.index(7, 7)])[cell]
    assert reach.covered(grid, [grid.index(5, 4)])[cell]


def test_a_camera_record_it_cannot_read_is_refused_in_one_line():
    model = load_observation('faces-pan-tilt-40-profile')
    broken = copy.deepcopy(model)
    del broken.meta['image']['camera']['K']
    grid = model.grid
    policy = build_policy('elm', grid, model)
    SearchSession(grid, broken, policy, SETTINGS)          # the setting off: not read
    with pytest.raises(ValueError, match='a camera record must be') as e:
        SearchSession(grid, broken, policy, replace(SETTINGS, absent_needs_coverage=True))
    assert '\n' not in str(e.value)
    session = SearchSession(grid, broken, policy, SETTINGS)
    with pytest.raises(ValueError, match='a camera record must be'):
        session.configure(replace(SETTINGS, absent_needs_coverage=True))
    assert not session.settings.absent_needs_coverage      # refused: the settings before


@pytest.mark.parametrize('name', LENSES)
def test_the_sweeps_tiles_cover_every_cell_and_none_is_spare(name):
    model = load_observation(name)
    grid, reach = model.grid, ViewReach.of(model.grid, model)
    poses, _ = sweep_tiles(grid, model)
    assert reach.covered(grid, poses).all()
    for k in range(poses.size):
        assert not reach.covered(grid, np.delete(poses, k)).all()
    assert not reach.covered(grid, [grid.center_index]).all()
    assert ViewReach.of(grid, load_observation('faces-420')) is None


def _empty_room(name, settings, views=40):
    """Zero counts in every view until the search ends; return the session."""
    model = load_observation(name)
    grid = model.grid
    session = SearchSession(grid, model, build_policy('coverage', grid, model), settings)
    session.reset(seed=0)
    session.start()
    for _ in range(views):
        result = session.update(Frame(np.zeros(grid.n_cells, dtype=np.int64)))
        if result.ended:
            break
    return session, result


@pytest.mark.parametrize('name', LENSES)
def test_absent_waits_until_the_views_cover_every_cell(name):
    without, plain = _empty_room(name, SETTINGS)
    held, result = _empty_room(name, replace(SETTINGS, absent_needs_coverage=True))
    grid, reach = held.grid, held._reach
    assert result.decision == plain.decision == 'absent'
    assert reach.covered(grid, held.path).all()
    assert not reach.covered(grid, held.path[:-1]).all()      # it ends at the first chance
    assert len(held.path) >= len(without.path)
    # Up to the view where the search without the setting said absent, the paths agree; each
    # later view covered a cell the views before it had left.
    n = len(without.path)
    assert held.path[:n] == without.path
    if not reach.covered(grid, without.path).all():
        assert len(held.path) > n
    for k in range(n, len(held.path)):
        left = np.flatnonzero(~reach.covered(grid, held.path[:k]))
        assert reach.sees_well(grid, left)[held.path[k]]


def test_the_belief_is_the_same_posterior_and_found_is_not_held():
    name = 'faces-pan-tilt-40-profile'
    model = load_observation(name)
    grid = model.grid
    sessions = []
    for needs in (False, True):
        session = SearchSession(grid, model, build_policy('coverage', grid, model),
                                replace(SETTINGS, absent_needs_coverage=needs))
        session.reset(seed=0)
        session.start()
        sessions.append(session)
    counts = np.zeros(grid.n_cells, dtype=np.int64)
    for k in range(3):
        for session in sessions:
            session.fixate(grid.center_index + k)
            session.update(Frame(counts))
    np.testing.assert_allclose(sessions[0].log_belief, sessions[1].log_belief)
    strong = counts.copy()
    strong[grid.center_index] = 8
    decisions = [[], []]
    for _ in range(6):
        for session, out in zip(sessions, decisions):
            if not session.ended:
                session.fixate(grid.center_index)
                out.append(session.update(Frame(strong)).decision)
    assert decisions[0] == decisions[1] and decisions[0][-1] == 'found'
    assert not sessions[1]._reach.covered(grid, sessions[1].path).all()


def test_a_model_without_a_camera_is_refused_and_a_moving_target_unchanged():
    model = load_observation('faces-420')
    grid = model.grid
    settings = SearchSettings(confidence=0.99, absent_prior=0.8, absent_needs_coverage=True)
    with pytest.raises(ValueError, match='needs a pan/tilt count model') as e:
        SearchSession(grid, model, build_policy('elm', grid, model), settings)
    assert '\n' not in str(e.value)
    camera = load_observation(LENSES[1])
    session = SearchSession(camera.grid, camera, build_policy('elm', camera.grid, camera),
                            settings)
    blind = copy.deepcopy(camera)
    del blind.meta['image']
    with pytest.raises(ValueError, match='needs a pan/tilt count model'):
        session.set_observation(blind)
    assert session.observation is not blind                # refused: the model before
    moving = []
    for needs in (False, True):
        session, result = _empty_room(LENSES[1], replace(SETTINGS, absent_needs_coverage=needs,
                                                         motion_sigma_cells=0.5), views=12)
        moving.append((session.path, result.decision, session.absent_probability))
    assert moving[0] == moving[1]


@pytest.mark.parametrize('name', LENSES)
def test_absent_waits_only_for_the_cells_a_prior_allows(name):
    """A cell at prior 0 never holds the target: no view is spent covering it."""
    model = load_observation(name)
    grid = model.grid
    prior = np.ones(grid.shape)
    prior[:grid.rows // 2] = 0.0                    # the upper half ruled out
    prior = (prior / prior.sum()).ravel()
    allowed = np.flatnonzero(prior > 0)
    session = SearchSession(grid, model, build_policy('coverage', grid, model),
                            replace(SETTINGS, absent_needs_coverage=True, scan=False),
                            prior=prior)
    session.reset(seed=0)
    session.start()
    for _ in range(SETTINGS.max_fixations):
        result = session.update(Frame(np.zeros(grid.n_cells, dtype=np.int64)))
        if result.ended:
            break
    reach = session._reach
    assert result.decision == 'absent' and session.gave_up_reason == ''
    assert reach.covered(grid, session.path)[allowed].all()
    assert not reach.covered(grid, session.path[:-1])[allowed].all()  # at the first chance
    assert not reach.covered(grid, session.path).all()      # the ruled-out half left alone
