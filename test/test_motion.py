# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The motion step against a dense transition matrix built cell by cell, and the target's walk."""
import math

from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import (axis_drift, axis_transition, check_probability,
                                      check_sigma_cells, LOG_UNDERFLOW, Motion, VelocityMotion)
import numpy as np
import pytest


def dense_transition(rows, cols, sigma, jump):
    """``T[s, d]`` from the definition: truncated 2-D Gaussian, renormalised per source, jump."""
    n = rows * cols
    radius = math.ceil(3 * sigma)
    t = np.zeros((n, n))
    for s in range(n):
        rs, cs = divmod(s, cols)
        for d in range(n):
            rd, cd = divmod(d, cols)
            if sigma == 0:
                t[s, d] = float(s == d)
            elif abs(rd - rs) <= radius and abs(cd - cs) <= radius:
                t[s, d] = math.exp(-((rd - rs) ** 2 + (cd - cs) ** 2) / (2 * sigma ** 2))
        t[s] /= t[s].sum()
    return (1 - jump) * t + jump / n


CASES = [(1, 1, 0.5, 0.0), (1, 6, 0.7, 0.0), (3, 4, 0.3, 0.0), (4, 3, 0.5, 0.1),
         (5, 5, 1.0, 0.0), (5, 5, 2.5, 0.05), (6, 2, 0.0, 0.2), (7, 7, 0.4, 0.001)]


@pytest.mark.parametrize('rows, cols, sigma, jump', CASES)
def test_transition_matches_the_dense_definition(rows, cols, sigma, jump):
    motion = Motion(Grid(rows, cols), sigma, jump)
    expected = dense_transition(rows, cols, sigma, jump)
    np.testing.assert_allclose(motion.transition_matrix(), expected, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(motion.transition_matrix().sum(axis=1), 1.0, rtol=1e-12)


@pytest.mark.parametrize('rows, cols, sigma, jump', CASES)
def test_prediction_is_the_belief_times_the_transition(rows, cols, sigma, jump):
    rng = np.random.default_rng(rows * 10 + cols)
    n = rows * cols
    motion = Motion(Grid(rows, cols), sigma, jump)
    t = dense_transition(rows, cols, sigma, jump)
    cells = rng.dirichlet(np.ones(n + 1), size=4)[:, :n]         # mass below 1: absent kept out
    np.testing.assert_allclose(motion.predict(cells), cells @ t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(motion.predict(cells[0]), cells[0] @ t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(motion.predict(cells).sum(axis=1), cells.sum(axis=1), rtol=1e-12)


def test_truncation_at_ceil_three_sigma_and_edges_keep_their_mass():
    grid = Grid(9, 9)
    motion = Motion(grid, 0.4, 0.0)                  # ceil(1.2) = 2 cells
    t = motion.transition_matrix()
    centre = grid.index(4, 4)
    row = t[centre].reshape(9, 9)
    assert row[4, 6] > 0 and row[6, 6] > 0 and row[4, 7] == 0 and row[1, 4] == 0
    corner = t[0].reshape(9, 9)                      # reaches only 3x3 cells: all its mass there
    assert corner[:3, :3].sum() == pytest.approx(1.0, rel=1e-12)
    assert np.all(corner[3:, :] == 0) and np.all(corner[:, 3:] == 0)
    # The corner's row is the centre's kernel cut to the grid and renormalised.
    np.testing.assert_allclose(corner[:3, :3], row[4:7, 4:7] / row[4:7, 4:7].sum(), rtol=1e-12)


def test_jump_alone_mixes_in_the_uniform_share_of_the_cell_mass():
    motion = Motion(Grid(3, 3), 0.0, 0.25)
    cells = np.array([0.5, 0, 0, 0, 0.2, 0, 0, 0, 0.1])          # 0.2 absent
    np.testing.assert_allclose(motion.predict(cells), 0.75 * cells + 0.25 * 0.8 / 9, rtol=1e-12)


def test_still_target_is_no_prediction_at_all():
    motion = Motion(Grid(4, 4))
    assert not motion.active
    log_b = np.log(np.random.default_rng(0).dirichlet(np.ones(16)))
    before = log_b.copy()
    assert motion.predict_log(log_b) is log_b
    np.testing.assert_array_equal(log_b, before)


def test_log_prediction_moves_the_cells_and_leaves_the_absent_mass():
    rng = np.random.default_rng(5)
    grid = Grid(4, 5)
    motion = Motion(grid, 0.8, 0.05)
    p = rng.dirichlet(np.ones(21), size=3)
    log_b = np.log(p)
    motion.predict_log(log_b)
    np.testing.assert_allclose(np.exp(log_b[:, :20]), motion.predict(p[:, :20]), rtol=1e-12)
    np.testing.assert_allclose(np.exp(log_b[:, 20]), p[:, 20], rtol=1e-12)


def test_log_prediction_of_a_certain_belief_and_of_zero_cells():
    grid = Grid(5, 5)
    log_b = np.full(25, -np.inf)
    log_b[12] = 0.0
    Motion(grid, 0.3, 0.0).predict_log(log_b)        # reaches the 3x3 block only
    b = np.exp(log_b).reshape(5, 5)
    assert b.sum() == pytest.approx(1.0) and np.all(b[1:4, 1:4] > 0)
    assert np.all(np.isneginf(log_b.reshape(5, 5)[0]))


def test_walk_of_the_target_follows_the_transition_rows():
    grid = Grid(4, 5)
    motion = Motion(grid, 0.9, 0.1)
    t = motion.transition_matrix()
    draws = 200_000
    for start in (0, 7, 19):
        moved = motion.move(np.full(draws, start), np.random.default_rng(start))
        freq = np.bincount(moved, minlength=20) / draws
        se = np.sqrt(t[start] * (1 - t[start]) / draws)
        assert np.all(np.abs(freq - t[start]) <= 5 * se + 1e-12), start


def test_walk_draws_do_not_depend_on_the_positions():
    motion = Motion(Grid(6, 6), 0.7, 0.3)
    a = motion.move(np.zeros(1000, int), np.random.default_rng(1))
    b = motion.move(np.full(1000, 35), np.random.default_rng(1))
    u = np.random.default_rng(1).random((1000, 4))
    jumped = u[:, 2] < 0.3
    np.testing.assert_array_equal(a[jumped], b[jumped])
    np.testing.assert_array_equal(a[jumped], (u[jumped, 3] * 36).astype(int))
    # Without a jump the row move comes from u[:, 0] alone: a smaller draw never moves further.
    rows = a[~jumped] // 6
    order = np.argsort(u[~jumped, 0])
    assert np.all(np.diff(rows[order]) >= 0)


def test_walk_stays_on_the_grid_at_the_edges():
    grid = Grid(3, 7)
    moved = Motion(grid, 3.0, 0.0).move(np.array([0, 6, 14, 20] * 5000),
                                        np.random.default_rng(2))
    assert moved.min() >= 0 and moved.max() < 21
    assert set(np.unique(moved)) == set(range(21))


def test_per_second_motion_scales_with_elapsed_time():
    motion = Motion(Grid(5, 5), 0.6, 0.2)
    half = motion.over(0.25)
    assert half.sigma_cells == pytest.approx(0.3)
    assert half.jump_prob == pytest.approx(1 - 0.8 ** 0.25)
    assert motion.over(1.0).sigma_cells == pytest.approx(0.6)
    assert not motion.over(0.0).active and not motion.over(-1.0).active
    # A very long gap (a clock jump): the jump probability saturates below 1, the belief is
    # then uniform over the cells and the absent mass is kept.
    far = motion.over(1e9)
    assert far.jump_prob < 1.0
    log_b = np.log(np.append(np.full(25, 0.6 / 25) * np.linspace(0.1, 1.9, 25), 0.4))
    far.predict_log(log_b)
    np.testing.assert_allclose(np.exp(log_b), np.append(np.full(25, 0.6 / 25), 0.4), rtol=1e-9)
    # A subnormal gap (5e-324 s): a step of 1e-162 cells, nothing moves (a ZeroDivisionError)
    before = log_b.copy()
    motion.over(5e-324).predict_log(log_b)
    np.testing.assert_allclose(log_b, before, rtol=1e-12)


def test_axis_matrix_rows_sum_to_one_and_zero_sigma_is_identity():
    np.testing.assert_allclose(axis_transition(8, 1.3).sum(axis=1), 1.0)
    np.testing.assert_array_equal(axis_transition(4, 0.0), np.eye(4))


@pytest.mark.parametrize('sigma', [0.022, 0.025, 0.5 * (1 / 500) ** 0.5, 1e-160, 5e-324])
def test_a_step_below_resolution_is_exactly_the_identity_and_predicts_nothing(sigma):
    """
    ``g(1)`` underflows: the general formula gives the identity, and so does the shortcut.

    A sigma whose square is 0 (below 1.5e-162: a step over a subnormal time, ``0.3 *
    sqrt(5e-324)`` cells) was a ZeroDivisionError, in a moving search's update too.
    """
    np.testing.assert_array_equal(axis_transition(9, sigma), np.eye(9))
    np.testing.assert_array_equal(axis_transition(9, sigma), _dense_axis(9, sigma))
    grid = Grid(9, 9, 1.0)
    log_b = np.log(np.random.default_rng(5).dirichlet(np.ones(82)))
    still = Motion(grid, sigma, 0.0, 0.2)
    assert still.is_identity() and not still.is_identity(with_absent=True)
    before = log_b[:81].copy()
    assert still.predict_log(log_b[:81]) is not None
    np.testing.assert_array_equal(log_b[:81], before)         # bit for bit, no round trip
    tiny = before.copy()
    tiny[[3, 4, 5]] = tiny.max() + np.array([-745.0, LOG_UNDERFLOW, -2000.0])
    with np.errstate(divide='ignore'):
        round_trip = np.log(np.exp(tiny - tiny.max()))     # what a step of probabilities keeps
    still.predict_log(tiny)
    np.testing.assert_array_equal(np.isinf(tiny), np.isinf(round_trip))
    assert np.isinf(tiny).sum() == 2 and np.isfinite(tiny[3])
    moved = log_b.copy()
    still.predict_log(moved)                                 # the absent column still leaves
    assert not np.array_equal(moved, log_b)
    assert not Motion(grid, sigma, 0.01).is_identity()
    assert not Motion(grid, 0.05).is_identity()


def _dense_axis(size, sigma):
    """Return the axis matrix as first written: ``g`` evaluated for every pair of positions."""
    if sigma == 0:
        return np.eye(size)
    x = np.arange(size)
    offset = x[None, :] - x[:, None]
    with np.errstate(over='ignore'):            # a tiny sigma: exp(-inf) = 0 off the diagonal
        weights = np.where(np.abs(offset) <= math.ceil(3 * sigma),
                           np.exp(-0.5 * (offset / sigma) ** 2), 0.0)
    return weights / weights.sum(axis=1, keepdims=True)


@pytest.mark.parametrize('size', [1, 2, 7, 11, 16, 128])
@pytest.mark.parametrize('sigma', [0.0, 0.01, 0.5 * math.sqrt(0.0021), 0.3, 1.0, 2.7, 40.0])
def test_axis_matrix_built_along_its_diagonals_is_the_dense_formula_bit_for_bit(size, sigma):
    np.testing.assert_array_equal(axis_transition(size, sigma), _dense_axis(size, sigma))
    assert axis_transition(size, sigma).tobytes() == _dense_axis(size, sigma).tobytes()


def test_motion_over_a_time_step_is_reused_for_the_same_step_only():
    motion = Motion(Grid(5, 4), 0.6, 0.2)
    step = motion.over(0.25)
    assert motion.over(0.25) is step
    other = motion.over(0.5)
    assert other is not step and other.sigma_cells == pytest.approx(0.6 * math.sqrt(0.5))
    again = motion.over(0.25)
    assert again.sigma_cells == step.sigma_cells and again.jump_prob == step.jump_prob
    # Another motion (a new setting) does not see this one's steps.
    assert Motion(Grid(5, 4), 1.2, 0.2).over(0.25).sigma_cells == pytest.approx(0.6)


def test_the_target_walk_builds_its_step_distribution_on_first_use_only():
    motion = Motion(Grid(5, 5), 0.7, 0.1)
    first = motion.move(np.arange(25), np.random.default_rng(0))
    again = Motion(Grid(5, 5), 0.7, 0.1).move(np.arange(25), np.random.default_rng(0))
    np.testing.assert_array_equal(first, again)


@pytest.mark.parametrize('value', [-0.1, float('nan'), float('inf'), 'x', None])
def test_bad_sigma_is_refused_with_a_reason(value):
    with pytest.raises(ValueError, match='sigma_cells must be'):
        check_sigma_cells(value)
    with pytest.raises(ValueError, match='sigma_cells must be'):
        Motion(Grid(3, 3), value)


@pytest.mark.parametrize('value', [-0.01, 1.0, 1.5, float('nan')])
def test_bad_probability_is_refused_with_a_reason(value):
    with pytest.raises(ValueError, match=r'jump_prob must be a probability in \[0, 1\)'):
        check_probability(value, 'jump_prob')
    with pytest.raises(ValueError, match='jump_prob must be a probability'):
        Motion(Grid(3, 3), 0.5, value)


@pytest.mark.parametrize('rows, cols, sigma, jump', CASES)
@pytest.mark.parametrize('leave', [0.0, 0.03, 0.4])
def test_leaving_and_coming_back_is_the_belief_times_the_dense_chain(rows, cols, sigma, jump,
                                                                     leave):
    """With the absent column: the (N + 1)-state chain built by hand, brute force."""
    n = rows * cols
    chain = np.zeros((n + 1, n + 1))
    chain[:n, :n] = (1 - leave) * dense_transition(rows, cols, sigma, jump)
    chain[:n, n] = leave
    chain[n, :n] = leave / n
    chain[n, n] = 1 - leave
    rng = np.random.default_rng(rows * 31 + cols)
    belief = rng.dirichlet(np.ones(n + 1))
    log_b = np.log(belief)
    Motion(Grid(rows, cols), sigma, jump, leave).predict_log(log_b)
    np.testing.assert_allclose(np.exp(log_b), belief @ chain, rtol=1e-9, atol=1e-15)


def test_leaving_needs_an_absent_column_and_scales_with_time():
    """Without the absent hypothesis leave_prob changes nothing; per second it compounds."""
    grid = Grid(4, 4)
    log_b = np.log(np.full(16, 1 / 16))
    Motion(grid, 0.0, 0.0, 0.5).predict_log(log_b)
    np.testing.assert_allclose(np.exp(log_b), 1 / 16)
    over = Motion(grid, 0.0, 0.0, 0.2).over(2.5)
    assert over.leave_prob == pytest.approx(1 - 0.8 ** 2.5)
    assert Motion(grid, leave_prob=0.1).active and not Motion(grid).active


def dense_drift(size, sigma, shift):
    """One axis: shift by linear interpolation (mass past the ends leaves), then the step."""
    out = np.zeros((size, size))
    step = dense_transition(1, size, sigma, 0.0)
    for x in range(size):
        to = x + shift
        low = math.floor(to)
        for target, weight in ((low, 1 - (to - low)), (low + 1, to - low)):
            if 0 <= target < size:
                out[x] += weight * step[target]
    return out


@pytest.mark.parametrize('shift', [-3.2, -0.4, 0.0, 0.75, 2.0, 12.0])
@pytest.mark.parametrize('sigma', [0.0, 0.6])
def test_a_drifting_axis_is_the_shift_then_the_step(shift, sigma):
    np.testing.assert_allclose(axis_drift(6, sigma, shift), dense_drift(6, sigma, shift),
                               atol=1e-15)


@pytest.mark.parametrize('absent', [True, False])
def test_the_walking_target_is_the_exact_filter_of_the_joint_chain(absent):
    """Cells x velocities and absent x exit cell, state by state: drift, jump, turn, back."""
    rows, cols, classes, dt = 4, 5, 3, 0.7
    grid = Grid(rows, cols)
    n, k = grid.n_cells, classes * classes
    motion = VelocityMotion(grid, 0.4, 0.05, 0.1, 1.5, 0.2, speed_cells=1.0, classes=classes)
    rng = np.random.default_rng(1)
    motion.velocity = rng.dirichlet(np.ones(k), size=n).T.reshape(classes, classes, n)
    motion.entry = rng.dirichlet(np.ones(n))
    prior = motion.prior.reshape(-1)
    belief = rng.dirichlet(np.ones(n + 1)) if absent else rng.dirichlet(np.ones(n))
    sigma = 0.4 * math.sqrt(dt)
    jump, turn, back = (1 - (1 - p) ** dt for p in (0.05, 0.2, 0.1))
    size = n * k + n                    # (velocity, cell) states, then (absent, exit cell)
    chain = np.zeros((size, size))
    for a in range(classes):
        for b in range(classes):
            v = a * classes + b
            move = np.kron(dense_drift(rows, sigma, motion.speeds[a] * dt),
                           dense_drift(cols, sigma, motion.speeds[b] * dt))
            out = 1 - move.sum(axis=1)
            move = (1 - jump) * move + jump * move.sum(axis=1, keepdims=True) / n
            for w in range(k):
                stay = (1 - turn) * (v == w) + turn * prior[w]
                chain[v * n:(v + 1) * n, w * n:(w + 1) * n] = move * stay
            chain[v * n:(v + 1) * n, n * k:] = np.diag(out)       # left where it walked out
    for exit_cell in range(n):
        chain[n * k + exit_cell, exit_cell::n][:k] = back * prior
        chain[n * k + exit_cell, n * k + exit_cell] = 1 - back
    np.testing.assert_allclose(chain.sum(axis=1), 1.0)
    joint = np.append((motion.velocity.reshape(k, n) * belief[:n]).reshape(-1),
                      (belief[n] if absent else 0.0) * motion.entry)
    after = joint @ chain
    log_b = np.log(belief)
    motion.predict_over(log_b, dt)
    moving = after[:n * k].reshape(k, n)
    cells = moving.sum(axis=0)
    if not absent:                      # no absent hypothesis: what walked out is renormalised
        cells = cells / cells.sum()
    else:
        gone = after[n * k:]
        assert np.exp(log_b[n]) == pytest.approx(gone.sum(), rel=1e-10)
        np.testing.assert_allclose(motion.entry, gone / gone.sum(), rtol=1e-9)
    np.testing.assert_allclose(np.exp(log_b[:n]), cells, rtol=1e-10)
    np.testing.assert_allclose(motion.velocity.reshape(k, n), moving / moving.sum(axis=0),
                               rtol=1e-9)


def test_a_look_ahead_leaves_the_velocities_and_a_reset_forgets_them():
    grid = Grid(5, 5)
    motion = VelocityMotion(grid, 0.2, max_speed_cells=2.0, turn_prob=0.1, speed_cells=1.0)
    log_b = np.log(np.full(25, 1 / 25))
    motion.velocity[:, :, 3] = 0
    motion.velocity[4, 8, 3] = 1
    before = motion.velocity.copy()
    motion.predict_over(log_b.copy(), 0.5, update=False)
    assert np.array_equal(motion.velocity, before)
    motion.reset()
    np.testing.assert_allclose(motion.velocity[:, :, 3], motion.prior)
    assert motion.active and motion.velocity_mean(np.full(25, 1 / 25)) == pytest.approx([0, 0])


@pytest.mark.parametrize('kwargs, message', [({'max_speed_cells': 0}, 'max_speed_cells'),
                                             ({'max_speed_cells': 1, 'classes': 1}, 'classes'),
                                             ({'max_speed_cells': 1, 'turn_prob': 1.0},
                                              'turn_prob')])
def test_bad_velocity_settings_are_refused_with_a_reason(kwargs, message):
    with pytest.raises(ValueError, match=message):
        VelocityMotion(Grid(3, 3), **kwargs)


@pytest.mark.parametrize('rows, cols, sigma', [(128, 128, 0.022), (128, 96, 0.3),
                                               (256, 256, 0.5 * (1 / 60) ** 0.5)])
def test_a_short_step_on_a_long_axis_predicts_as_the_matrix_product(rows, cols, sigma):
    """The step's diagonals (or, for a step of a hundredth of a cell, the identity) added."""
    motion = Motion(Grid(rows, cols, 1.0), sigma, 0.01)
    assert motion._bands is not None
    cells = np.random.default_rng(3).random((2, rows * cols))
    cells[1, :rows * cols // 2] = 0.0                # cells the step leaves at exactly 0
    grid_b = cells.reshape(2, rows, cols)
    product = 0.99 * np.matmul(motion._row_t, np.matmul(grid_b, motion.col_matrix)).reshape(
        cells.shape) + 0.01 * cells.sum(axis=-1, keepdims=True) / (rows * cols)
    np.testing.assert_allclose(motion.predict(cells), product, rtol=1e-13, atol=0)
    np.testing.assert_array_equal(motion.predict(cells) == 0, product == 0)
    if motion._bands == ():
        np.testing.assert_array_equal(motion.predict(cells), product)


@pytest.mark.parametrize('sigma', [2.0 ** 40, 1e200, 1e308])
def test_a_step_far_wider_than_the_grid_spreads_evenly_without_overflowing(sigma):
    """
    QA: ``motion.sigma_cells`` 1e200 passed its check, then ``sigma ** 2`` overflowed.

    The node took the value and failed to apply it (an OverflowError counted as a callback
    error, the parameter set but the search not following it); ``evaluate`` printed a
    traceback. Every g(k) on the axis is 1.0: the step is the uniform one, over any time.
    """
    assert np.array_equal(axis_transition(11, sigma), np.full((11, 11), 1 / 11))
    grid = Grid(3, 4, 5.0)
    motion = Motion(grid, sigma).over(4.0)
    belief = np.log(np.arange(1.0, 13.0) / 78.0)
    assert np.allclose(np.exp(motion.predict_log(belief.copy())), 1 / 12)


def test_evaluate_with_a_huge_motion_sigma_runs(cli_here):
    run = cli_here('evaluate', '--grid', '3x3', '--policy', 'map', '--episodes', 4,
                   '--motion-sigma-cells', '1e200', '--seed', 0, '--quiet')
    assert run.returncode == 0, run.stderr
    assert 'Traceback' not in run.stderr


@pytest.mark.parametrize('speed', [1e200, 1e308])
def test_a_walk_far_faster_than_the_grid_leaves_it_without_a_nan(speed):
    """
    QA: ``motion.max_speed_cells`` 1e308 made a NaN belief (``linspace(-speed, speed)``).

    Every moving velocity walks off the grid in any step, as one of a few grid lengths does:
    the prediction is that of a speed the grid's size.
    """
    grid = Grid(3, 4, 5.0)
    belief = np.log(np.arange(1.0, 13.0) / 78.0)
    fast, slow = (VelocityMotion(grid, 0.5, 0.0, 0.0, s, 0.2, 0.0) for s in (speed, 40.0))
    assert np.isfinite(fast.speeds).all()
    np.testing.assert_allclose(fast.predict_over(belief.copy(), 2.0),
                               slow.predict_over(belief.copy(), 2.0), rtol=1e-12)
