# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The clutter map of a moving target's search (``model.clutter_map``) against Bayes."""
import itertools

from ipomdp_gaze.model.belief import bayes_update, normalize_log
from ipomdp_gaze.model.clutter_map import ClutterMap
from ipomdp_gaze.model.false_alarms import scaled_null
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.model.stopping import with_absent
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
import numpy as np
import pytest

MOVING = {'motion_sigma_cells': 0.5, 'motion_leave_prob': 0.1, 'absent_prior': 0.5,
          'inhibit_return': False}


def _model(rng, rows=2, cols=2, k=3):
    """Return a count model whose target and null tables differ at every offset."""
    grid = Grid(rows, cols)
    target = rng.dirichlet([1.0, 2.0, 3.0][:k], size=(rows, cols))
    null = rng.dirichlet([20.0, 1.0, 0.5][:k], size=(rows, cols))
    return grid, CountObservation(grid, target, null)


def _brute_force(model, hot_table, counts, fixation, log_belief, pi):
    """
    One frame's posterior by enumerating (face cell or absent, which cells are hotspots).

    The prior: the face's belief ``log_belief`` (N + 1, absent last) times independent hotspot
    states with probabilities ``pi``; a cell's count follows the target table if the face is in
    it, else the hotspot's or the null table. Returns P(face j | frame) and P(hot_i | frame).
    """
    grid = model.grid
    n = grid.n_cells
    offsets = model.offsets(fixation)
    face_post = np.zeros(n + 1)
    hot_post = np.zeros(n)
    b = np.exp(log_belief)
    for face in range(n + 1):
        for hot in itertools.product((False, True), repeat=n):
            p = b[face] * np.prod([pi[i] if hot[i] else 1 - pi[i] for i in range(n)])
            for i in range(n):
                c = int(counts[i])
                table = model.p_target if i == face else (hot_table if hot[i] else model.p_null)
                p *= table.reshape(n, -1)[offsets[i], c]
            face_post[face] += p
            hot_post += p * np.asarray(hot)
    total = face_post.sum()
    return face_post / total, hot_post / total


@pytest.mark.parametrize('seed', range(6))
def test_one_frame_gives_the_brute_force_marginals(seed):
    rng = np.random.default_rng(seed)
    grid, model = _model(rng)
    n = grid.n_cells
    clutter = ClutterMap(model, 0.1, 3.0)
    clutter.log_odds[:] = rng.normal(-1.0, 1.5, n)      # any factorised prior of hotspots
    pi = clutter.probability.copy()
    log_belief = normalize_log(rng.normal(0.0, 1.0, n + 1))
    counts = rng.integers(0, 3, n).astype(float)
    fixation = int(rng.integers(n))
    want_face, want_hot = _brute_force(model, scaled_null(model.p_target, model.p_null, 3.0),
                                       counts, fixation, log_belief, pi)
    ratio = model.log_likelihood_ratio(counts, fixation)
    face = clutter.step(log_belief, counts, fixation, ratio)
    posterior = np.exp(bayes_update(log_belief.copy(), with_absent(face, log_belief)))
    np.testing.assert_allclose(posterior, want_face, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(clutter.probability, want_hot, rtol=1e-10, atol=1e-14)


def test_without_the_absent_hypothesis_too():
    rng = np.random.default_rng(11)
    grid, model = _model(rng, 1, 3)
    clutter = ClutterMap(model, 0.2, 4.0)
    log_belief = normalize_log(rng.normal(0.0, 1.0, grid.n_cells))
    counts = np.array([2.0, 0.0, 1.0])
    want_face, want_hot = _brute_force(model, scaled_null(model.p_target, model.p_null, 4.0),
                                       counts, 1, np.append(log_belief, -np.inf),
                                       clutter.probability.copy())
    ratio = model.log_likelihood_ratio(counts, 1)
    face = clutter.step(log_belief, counts, 1, ratio)
    np.testing.assert_allclose(np.exp(bayes_update(log_belief.copy(), face)), want_face[:-1],
                               rtol=1e-10)
    np.testing.assert_allclose(clutter.probability, want_hot, rtol=1e-10)


def test_an_unobserved_cell_learns_nothing_and_gives_no_term():
    rng = np.random.default_rng(3)
    _, model = _model(rng)
    clutter = ClutterMap(model, 0.05, 20.0)
    counts = np.array([1.0, np.nan, 2.0, 0.0])
    ratio = model.log_likelihood_ratio(counts, 0)
    face = clutter.step(normalize_log(np.zeros(5)), counts, 0, ratio)
    assert face[1] == 0.0 and clutter.probability[1] == pytest.approx(0.05, rel=1e-12)


def _spot_session(model, grid, prior, frames=30, face=None, rng=None):
    """Run a moving-target session whose every view fires 4 at ``spot``; return found frames."""
    settings = SearchSettings(confidence=0.95, hotspot_prior=prior, hotspot_scale=20.0,
                              motion_keep_probability=0.5, **MOVING)
    session = SearchSession(grid, model, None, settings)
    session.reset(seed=0)
    session.start()
    spot = grid.index(2, 2)
    found = 0
    for k in range(frames):
        session.fixate(spot if k % 2 else grid.index(2, 3))
        counts = np.zeros(grid.n_cells)
        if face is None:
            counts[spot] = 4.0
        else:
            offsets = model.offsets(session.fixation)
            table = np.where(np.arange(grid.n_cells)[:, None] == face,
                             model.p_target.reshape(-1, model.p_target.shape[2])[offsets],
                             model.p_null.reshape(-1, model.p_null.shape[2])[offsets])
            counts = np.array([rng.choice(table.shape[1], p=row) for row in table], float)
        session.update(Frame(counts), dt_s=0.2)
        found += session.decision == 'found'
    return found, session


def _tables(grid):
    """Return tables where a face gives 9 in most views, the background 0; 4 is rare for both."""
    target = np.broadcast_to([0.01] * 9 + [0.91], (grid.rows, grid.cols, 10))
    null = np.broadcast_to([0.982, 0.01] + [0.001] * 8, (grid.rows, grid.cols, 10))
    return CountObservation(grid, target, null)


def test_a_spot_firing_in_every_view_holds_found_only_without_the_clutter_map():
    grid = Grid(5, 5)
    model = _tables(grid)
    held = {prior: _spot_session(model, grid, prior)[0] for prior in (0.0, 0.03)}
    assert held[0.0] >= 25                     # without it: found on (nearly) every frame
    assert held[0.03] <= 2                     # with it: a view or two, then a hotspot
    _, session = _spot_session(model, grid, 0.03)
    assert session.hotspot_probability[grid.index(2, 2)] > 0.99


def test_a_face_is_still_found_and_held_with_the_clutter_map():
    grid = Grid(5, 5)
    model = _tables(grid)
    face = grid.index(2, 2)
    for seed in range(5):
        found, session = _spot_session(model, grid, 0.03, face=face,
                                       rng=np.random.default_rng(seed))
        assert found >= 25
        assert session.hotspot_probability[face] < 0.2


def test_a_still_target_keeps_the_still_hotspots_and_no_clutter_map():
    rng = np.random.default_rng(2)
    grid, model = _model(rng, 3, 3)
    session = SearchSession(grid, model, None, SearchSettings(hotspot_prior=0.05))
    session.reset(seed=0)
    session.start()
    session.update(Frame(np.ones(grid.n_cells)))
    assert session.hotspot_probability is None and session._active_mixture() is not None


def test_a_new_search_forgets_the_map():
    grid = Grid(5, 5)
    _, session = _spot_session(_tables(grid), grid, 0.03)
    session.reset(seed=0)
    np.testing.assert_allclose(session.hotspot_probability, 0.03, rtol=1e-12)
