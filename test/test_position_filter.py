# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The position filter against the batch Gaussian posterior, and the detections' positions."""
from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import bin_points, PinholeCamera, point_offsets
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.model.position_filter import measured_position, PositionFilter, walk_filter
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
import numpy as np
import pytest


def _batch_posterior(z, dts, r, q, s2, v2):
    """
    Return the last state's posterior mean and covariance from the joint Gaussian.

    States ``(x_k, v_k)`` of one axis; ``x_0 ~ N(z_0, r)``, ``v_0 ~ N(0, v2)``; ``s_k = F s_{k-1}
    + w_k``, ``w_k ~ N(0, Q(dt_k))``; ``z_k = x_k + e_k``, ``e_k ~ N(0, r)``, for k >= 1.
    """
    k = len(z)
    n = 2 * k
    # Every state as a linear map of the independent noises [s_0, w_1 .. w_{k-1}].
    maps = [np.eye(2, n)]
    covs = [np.diag([r, v2])]
    for i, dt in enumerate(dts, start=1):
        f = np.array([[1.0, dt], [0.0, 1.0]])
        m = f @ maps[-1]
        m[:, 2 * i:2 * i + 2] += np.eye(2)
        maps.append(m)
        cov = q * np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]])
        cov[0, 0] += s2 * dt
        covs.append(cov)
    noise = np.zeros((n, n))
    for i, c in enumerate(covs):
        noise[2 * i:2 * i + 2, 2 * i:2 * i + 2] = c
    mean0 = np.zeros(n)
    mean0[0] = z[0]
    states_mean = np.stack([m @ mean0 for m in maps])
    h = np.stack([maps[i][0] for i in range(1, k)])          # x_1 .. x_{k-1}
    last = maps[-1]
    s = h @ noise @ h.T + r * np.eye(k - 1)
    c = last @ noise @ h.T
    gain = c @ np.linalg.inv(s)
    resid = np.asarray(z[1:]) - states_mean[1:, 0]
    return states_mean[-1] + gain @ resid, last @ noise @ last.T - gain @ c.T


@pytest.mark.parametrize('seed', range(4))
def test_the_filter_is_the_batch_gaussian_posterior(seed):
    rng = np.random.default_rng(seed)
    r, q, s2, v2 = 0.03, 1.3, 0.02, 2.2
    k = 7
    z = rng.normal(size=(k, 2)) + np.arange(k)[:, None] * 0.4
    dts = rng.uniform(0.05, 0.5, size=k - 1)
    kf = PositionFilter(np.sqrt(r), q, np.sqrt(s2), np.sqrt(v2))
    kf.start(z[0])
    for zi, dt in zip(z[1:], dts):
        kf.predict(dt)
        kf.update(zi)
    for axis in (0, 1):
        mean, cov = _batch_posterior(z[:, axis], dts, r, q, s2, v2)
        assert kf.x[axis] == pytest.approx(mean[0], abs=1e-9)
        assert kf.v[axis] == pytest.approx(mean[1], abs=1e-9)
        np.testing.assert_allclose(kf.p, cov, atol=1e-9)
    np.testing.assert_allclose(kf.ahead(0.3), kf.x + 0.3 * kf.v)


def test_bad_filter_parameters_are_refused():
    with pytest.raises(ValueError, match='measurement_sigma_cells'):
        PositionFilter(0.0, 1.0)
    with pytest.raises(ValueError, match='>= 0'):
        PositionFilter(0.1, -1.0)


def test_point_offsets_are_each_cells_mean_offset():
    grid = Grid(5, 6, spacing_deg=5.0)
    camera = PinholeCamera.from_k(320, 240, [700.0, 0, 159.5, 0, 700.0, 119.5, 0, 0, 1])
    rng = np.random.default_rng(3)
    uv = np.stack([rng.uniform(0, 319, 80), rng.uniform(0, 239, 80)], axis=1)
    head = (2.0, 3.0)
    out = point_offsets(uv, camera, grid, head)
    _, raw, cells = bin_points(uv, camera, grid, head, 10)
    for cell in range(grid.n_cells):
        mine = cells == cell
        if not mine.any():
            assert np.isnan(out[cell]).all()
            continue
        du, dv = camera.angles_deg(uv[mine, 0], uv[mine, 1])
        pos = np.stack([head[0] + dv / 5.0, head[1] + du / 5.0], axis=1)
        np.testing.assert_allclose(out[cell], pos.mean(axis=0) - grid.cell(cell), atol=1e-12)
        assert np.abs(out[cell]).max() <= 0.5
    assert raw.sum() == (cells >= 0).sum()


def test_the_measured_position_is_the_boxes_mean_near_the_peak():
    grid = Grid(5, 5)
    values = np.zeros(25)
    offsets = np.full((25, 2), np.nan)
    # three boxes at (2.2, 2.1) and one at (2.6, 3.4): cells (2, 2) and (3, 3)
    values[grid.index(2, 2)], offsets[grid.index(2, 2)] = 3, (0.2, 0.1)
    values[grid.index(3, 3)], offsets[grid.index(3, 3)] = 1, (-0.4, 0.4)
    far = grid.index(0, 4)
    values[far], offsets[far] = 5, (0.0, 0.0)              # outside the 3 x 3: not counted
    z = measured_position(values, offsets, grid, grid.index(2, 2))
    np.testing.assert_allclose(z, [(3 * 2.2 + 2.6) / 4, (3 * 2.1 + 3.4) / 4])
    assert measured_position(np.zeros(25), offsets, grid, 0) is None


def _walk_session(track_view, lead_s=0.3):
    grid = Grid(5, 9)
    target = np.broadcast_to([0.02] * 9 + [0.82], (5, 9, 10))
    null = np.broadcast_to([0.9, 0.09] + [0.00125] * 8, (5, 9, 10))
    settings = SearchSettings(confidence=0.9, motion_sigma_cells=0.1, motion_max_speed_cells=2.0,
                              motion_speed_cells=1.0, motion_turn_prob=0.1,
                              motion_track_view=track_view, motion_lead_s=lead_s,
                              motion_keep_probability=0.5, motion_position_sigma_cells=0.05)
    session = SearchSession(grid, CountObservation(grid, target, null), None, settings)
    session.reset(seed=0)
    session.start()
    return grid, session


def _walk_frames(grid, session, steps=12, dt=0.25):
    """Walk a face right along row 2 at 1 cell/s from column 1; every cell is seen."""
    chosen = []
    for k in range(steps):
        col = 1.0 + k * dt
        cell_col = int(np.floor(col + 0.5))
        counts = np.zeros(grid.n_cells)
        counts[grid.index(2, cell_col)] = 9
        offsets = np.full((grid.n_cells, 2), np.nan)
        offsets[grid.index(2, cell_col)] = (0.0, col - cell_col)
        step = session.update(Frame(counts, offsets=offsets), dt_s=dt if k else 0.0)
        chosen.append(step.fixation)
    return col, chosen


def test_the_view_follows_the_filtered_position_ahead():
    grid, session = _walk_session('position', lead_s=0.3)
    col, chosen = _walk_frames(grid, session)
    assert session.decision == 'found'
    # the last face position 3.75: 0.3 s ahead at 1 cell/s it is at 4.05, in column 4
    assert grid.cell(chosen[-1]) == (2, 4)
    assert session._position.v[1] == pytest.approx(1.0, abs=0.15)
    grid, peak = _walk_session('peak', lead_s=0.3)
    _, chosen = _walk_frames(grid, peak)
    assert grid.cell(chosen[-1])[1] <= 4


def test_without_offsets_position_looks_at_the_predicted_peak():
    grid, a = _walk_session('position')
    grid, b = _walk_session('peak')
    for k in range(8):
        counts = np.zeros(grid.n_cells)
        counts[grid.index(2, 1 + k // 4)] = 9
        sa = a.update(Frame(counts), dt_s=0.25)
        sb = b.update(Frame(counts), dt_s=0.25)
        assert sa.fixation == sb.fixation
    np.testing.assert_array_equal(a.belief, b.belief)


@pytest.mark.parametrize('offsets, words', [
    (np.zeros((3, 2)), 'shape'),
    (np.full((45, 2), 0.7), 'half a cell'),
    (np.full((45, 2), np.inf), 'half a cell'),
])
def test_bad_offsets_are_rejected_and_the_belief_kept(offsets, words):
    grid, session = _walk_session('position')
    before = session.belief.copy()
    step = session.update(Frame(np.zeros(grid.n_cells), offsets=offsets), dt_s=0.25)
    assert step.status == 'rejected' and words in step.reason
    np.testing.assert_array_equal(session.belief, before)
    with pytest.raises(EvidenceError, match=words):
        session.checked_frame(np.zeros(grid.n_cells), offsets=offsets)


@pytest.mark.parametrize('scale', [1e100, 1e300])
def test_huge_lengths_filter_as_the_same_lengths_scaled_down(scale):
    """
    QA: a measurement sigma of 1e308 cells was an OverflowError in ``sigma ** 2``.

    The filter's estimates depend only on ratios of its variances: lengths scaled up together
    give the same positions and velocities, and any finite lengths build a filter.
    """
    rng = np.random.default_rng(5)
    z = rng.normal(size=(6, 2)) + np.arange(6)[:, None] * 0.3
    filters = [walk_filter(0.14 * f, 0.3, 0.15 * f, 1.49 * f) for f in (1.0, scale)]
    for kf in filters:
        kf.start(z[0])
        for zi in z[1:]:
            kf.predict(0.2)
            kf.update(zi)
    np.testing.assert_allclose(filters[1].x, filters[0].x, rtol=1e-12)
    np.testing.assert_allclose(filters[1].v, filters[0].v, rtol=1e-12)
    for lengths in [(1e308, 0.0, 0.0), (0.1, 1e308, 1e308), (1e-300, 1e308, 0.0)]:
        kf = walk_filter(lengths[0], 0.3, *lengths[1:])
        kf.start(z[0])
        kf.predict(0.2)
        kf.update(z[1])
        assert np.isfinite(kf.ahead(0.3)).all()
