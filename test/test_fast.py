# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""FFT scoring, the controller's per-frame path and large grids without N x N arrays."""
import importlib.util
import os
from pathlib import Path
import tracemalloc

from ipomdp_gaze.model.belief import argmax_ties_low, bayes_update, TIE_RTOL, uniform_log_belief
from ipomdp_gaze.model.fpoc import dprime_matrix, dprime_table, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
from ipomdp_gaze.model.observation import GaussianObservation
from ipomdp_gaze.policies import conv
from ipomdp_gaze.policies.baselines import elm_policy
from ipomdp_gaze.policies.conv import ConvPolicy, kernel_matrix, support_box
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.session import SearchSettings
import numpy as np
import pytest

SHAPES = [(7, 7), (5, 9), (11, 11), (13, 6), (20, 31)]
BENCH_RUN = Path(__file__).resolve().parents[1] / 'bench' / 'run.py'


def _kernels(grid, rng):
    """Asymmetric kernels: dense random, off-centre sparse, human d'^2 skewed by a ramp."""
    dense = rng.normal(size=grid.kernel_shape)
    sparse = np.zeros(grid.kernel_shape)
    sparse[:3, -4:] = rng.normal(size=(min(3, grid.kernel_shape[0]), 4))
    ramp = np.linspace(1.0, 2.0, grid.kernel_shape[1])[None, :]
    skewed = dprime_table(grid, make_fpoc('human')) ** 2 * ramp
    return {'dense': dense, 'sparse': sparse, 'skewed': skewed}


def _tied_beliefs(grid, rng):
    """Beliefs with exact ties: uniform, dyadic point masses, left-right mirror images."""
    n = grid.n_cells
    out = [np.full(n, 1.0 / n)]
    for masses in ([1.0], [0.5, 0.5], [0.25] * 4, [0.5, 0.25, 0.125, 0.125]):
        for _ in range(6):
            b = np.zeros(n)
            b[rng.choice(n, len(masses), replace=False)] = masses
            out.append(b)
    for _ in range(4):
        b = rng.dirichlet(np.ones(n)).reshape(grid.shape)
        out.append(((b + b[:, ::-1]) / 2).ravel())
    return np.array(out)


def test_kernel_matrix_matches_the_offset_definition():
    grid = Grid(4, 6)
    kernel = np.random.default_rng(0).normal(size=grid.kernel_shape)
    ri, ci = grid.pair_offset_index()
    np.testing.assert_array_equal(kernel_matrix(grid, kernel), kernel[ri, ci])


@pytest.mark.parametrize('shape', SHAPES)
def test_fft_scores_are_within_their_error_bound_of_the_direct_ones(shape):
    grid = Grid(*shape)
    rng = np.random.default_rng(1)
    beliefs = np.vstack([rng.dirichlet(np.full(grid.n_cells, a), size=20)
                         for a in (0.05, 1.0, 50.0)])
    for kernel in _kernels(grid, rng).values():
        direct = ConvPolicy(grid, kernel, method='direct').scores(beliefs)
        fft = ConvPolicy(grid, kernel, method='fft')
        error = np.abs(fft.scores(beliefs) - direct).max(axis=1)
        bound = fft.fft_error_bound(beliefs)
        assert np.all(error <= bound)
    # On a realistic kernel the bound is far below the tie tolerance, so exact re-scoring is rare.
    peak = np.abs(direct).max(axis=1)
    assert np.all(bound < 0.01 * TIE_RTOL * peak)


@pytest.mark.parametrize('shape', SHAPES)
def test_fft_and_direct_decisions_are_identical_on_random_beliefs(shape):
    grid = Grid(*shape)
    rng = np.random.default_rng(2)
    beliefs = rng.dirichlet(np.full(grid.n_cells, 0.3), size=60)
    for name, kernel in _kernels(grid, rng).items():
        direct = ConvPolicy(grid, kernel, method='direct')
        fft = ConvPolicy(grid, kernel, method='fft')
        expected = argmax_ties_low(beliefs @ kernel_matrix(grid, kernel).T)
        np.testing.assert_array_equal(direct.select(beliefs, 0, None), expected)
        np.testing.assert_array_equal(fft.select(beliefs, 0, None), expected, err_msg=name)
        assert [fft.decide(b) for b in beliefs[:10]] == list(expected[:10])


@pytest.mark.parametrize('shape', SHAPES + [(40, 40)])
def test_fft_and_direct_decisions_are_identical_on_tied_beliefs(shape):
    # Integer kernels and dyadic beliefs make every product and sum exact, so ties are exact
    # in the direct path while the FFT's round-off is ~1e-16: the tie rule must still agree.
    grid = Grid(*shape)
    rng = np.random.default_rng(3)
    beliefs = _tied_beliefs(grid, rng)
    integer = rng.integers(0, 3, size=grid.kernel_shape).astype(float)
    camera = dprime_table(grid, make_fpoc('camera')) ** 2
    camera[grid.rows - 1, grid.cols] += 1.0          # asymmetric, small support
    for kernel in (integer, camera):
        direct = ConvPolicy(grid, kernel, method='direct')
        fft = ConvPolicy(grid, kernel, method='fft')
        expected = argmax_ties_low(beliefs @ kernel_matrix(grid, kernel).T)
        np.testing.assert_array_equal(direct.select(beliefs, 0, None), expected)
        np.testing.assert_array_equal(fft.select(beliefs, 0, None), expected)
        assert [fft.decide(b) for b in beliefs] == list(expected)
        assert fft.rescored > 0                     # the ties did go through exact re-scoring


def test_a_flat_belief_on_a_large_grid_takes_the_massive_tie_path(monkeypatch):
    # Uniform belief, camera kernel: hundreds of interior cells tie exactly.
    grid = Grid(40, 40)
    kernel = dprime_table(grid, make_fpoc('camera')) ** 2
    kernel[grid.rows, grid.cols - 1] = 3.0
    calls = []
    original = ConvPolicy._decide_flat
    monkeypatch.setattr(ConvPolicy, '_decide_flat',
                        lambda self, *a: calls.append(1) or original(self, *a))
    fft = ConvPolicy(grid, kernel, method='fft')
    belief = np.full(grid.n_cells, 1.0 / grid.n_cells)
    expected = int(argmax_ties_low(belief @ kernel_matrix(grid, kernel).T))
    assert fft.decide(belief) == expected and calls


def test_a_truncation_that_drops_nothing_shares_the_lossless_fft_and_its_scores(monkeypatch):
    # The camera kernel is a box: the default truncation drops no entry, so the massive-tie
    # path's lossless pass reuses the scores it has; a kernel that truncation cuts does not.
    grid = Grid(40, 40)
    box = ConvPolicy(grid, dprime_table(grid, make_fpoc('camera')) ** 2, method='fft')
    assert box._fft(True) is box._fft()
    cut = ConvPolicy(grid, dprime_table(grid, make_fpoc('exponential')) ** 2, method='fft',
                     truncate=1e-3)
    assert cut._fft(True) is not cut._fft() and cut._fft(True).box != cut._fft().box
    scored = []
    original = ConvPolicy._fft_scores
    monkeypatch.setattr(ConvPolicy, '_fft_scores',
                        lambda self, *a: scored.append(a[1:]) or original(self, *a))
    belief = np.full(grid.n_cells, 1.0 / grid.n_cells)
    expected = int(argmax_ties_low(belief @ kernel_matrix(grid, box.kernel).T))
    assert box.decide(belief) == expected and scored == [()] and box.rescored == 2
    flat = []
    original_flat = ConvPolicy._decide_flat
    monkeypatch.setattr(ConvPolicy, '_decide_flat',
                        lambda self, *a: flat.append(a[3]) or original_flat(self, *a))
    assert box.decide(belief) == expected and flat == [box.fft_error_bound(belief, True)]


@pytest.mark.parametrize('truncate', [1e-6, 1e-3, 1e-1])
def test_truncated_support_keeps_the_decisions(truncate):
    grid = Grid(40, 33)
    rng = np.random.default_rng(4)
    kernel = dprime_table(grid, make_fpoc('exponential')) ** 2
    kernel[:, :grid.cols] *= 1.3                     # asymmetric
    full = ConvPolicy(grid, kernel, method='fft')
    cut = ConvPolicy(grid, kernel, method='fft', truncate=truncate)
    assert cut.fft_shape[0] * cut.fft_shape[1] < full.fft_shape[0] * full.fft_shape[1]
    beliefs = np.vstack([rng.dirichlet(np.full(grid.n_cells, 0.3), size=40),
                         _tied_beliefs(grid, rng)])
    expected = argmax_ties_low(beliefs @ kernel_matrix(grid, kernel).T)
    np.testing.assert_array_equal(cut.select(beliefs, 0, None), expected)


def test_support_box_and_fft_size_follow_the_kernel_reach():
    grid = Grid(64, 64)
    kernel = dprime_table(grid, make_fpoc('human')) ** 2
    # Exactly 0 beyond 46 cells (numpy 2), or 45 (numpy 1.x): d' there is about 2e-16, where
    # the last bits of numpy's exp and pow decide whether it rounds to 0.
    reach = 63 - int(np.flatnonzero(kernel[63])[0])
    assert reach in (45, 46)
    box_r, box_c = support_box(kernel)
    assert (box_r.start, box_r.stop) == (63 - reach, 63 + reach + 1)
    assert (box_c.start, box_c.stop) == (63 - reach, 63 + reach + 1)
    p, q = ConvPolicy(grid, kernel, method='fft', truncate=0.0).fft_shape
    assert 64 + reach <= p < 2 * 64 - 1 and 64 + reach <= q < 2 * 64 - 1
    # The default truncation (1e-16 of the largest entry) stops at 27 cells.
    box_r, _ = support_box(kernel, conv.DEFAULT_TRUNCATE)
    assert (box_r.start, box_r.stop) == (63 - 27, 63 + 28)
    p, q = ConvPolicy(grid, kernel, method='fft').fft_shape
    assert 64 + 27 <= p < 64 + 46 and 64 + 27 <= q < 64 + 46
    assert support_box(np.zeros((5, 7))) == (slice(2, 3), slice(3, 4))


def test_auto_method_switches_at_the_break_even():
    small = Grid(1, conv.DIRECT_MAX_CELLS)
    policy = ConvPolicy(small, np.ones(small.kernel_shape))
    assert policy.uses_direct() and policy.uses_direct(batch=True)
    big = Grid(1, conv.DIRECT_MAX_CELLS + 1)
    policy = ConvPolicy(big, np.ones(big.kernel_shape))
    assert not policy.uses_direct()
    assert policy.uses_direct(batch=True) == (big.n_cells <= conv.DIRECT_MAX_CELLS_BATCH)


def test_bad_method_and_oversized_direct_are_refused():
    grid = Grid(5, 5)
    with pytest.raises(ValueError, match='valid methods: auto, direct, fft'):
        ConvPolicy(grid, np.ones(grid.kernel_shape), method='svd')
    with pytest.raises(ValueError, match='truncate'):
        ConvPolicy(grid, np.ones(grid.kernel_shape), truncate=1.5)
    big = Grid(128, 128)
    with pytest.raises(ValueError, match=r'N x N matrix of 2\.0 GiB'):
        ConvPolicy(big, np.ones(big.kernel_shape), method='direct')


def test_select_with_one_row_and_one_belief_agree():
    grid = Grid(9, 8)
    rng = np.random.default_rng(5)
    for method in ('direct', 'fft'):
        policy = ConvPolicy(grid, rng.normal(size=grid.kernel_shape), method=method)
        b = rng.dirichlet(np.ones(grid.n_cells))
        one = policy.select(b[None, :], 0, rng)
        assert one.shape == (1,) and one[0] == policy.select(b, 0, rng) == policy.decide(b)


def test_sampled_action_still_follows_the_softmax_on_the_fft_path():
    grid = Grid(1, 3)
    kernel = np.array([[0.0, 0.0, 0.0, np.log(2), np.log(4)]])
    policy = ConvPolicy(grid, kernel, action='sample', method='fft')
    belief = np.tile([[0.0, 0.0, 1.0]], (30000, 1))
    k = policy.select(belief, 0, np.random.default_rng(0))
    freq = np.bincount(k, minlength=3) / k.size
    expected = np.array([4, 2, 1]) / 7
    assert np.all(np.abs(freq - expected) < 4 * np.sqrt(expected * (1 - expected) / k.size))


# -- the controller's per-frame path -------------------------------------------------------------

@pytest.mark.parametrize('shape', [(7, 7), (4, 9)])
def test_dprime_window_is_a_column_of_the_dprime_matrix(shape):
    grid = Grid(*shape)
    fpoc = make_fpoc('human')
    model, d = GaussianObservation(grid, fpoc), dprime_matrix(grid, fpoc)
    for k in range(grid.n_cells):
        np.testing.assert_array_equal(model.dprime(k), d[:, k])
        np.testing.assert_array_equal(model.dprime_window(k), d[:, k].reshape(shape))
    ks = np.arange(grid.n_cells)[::-1]
    np.testing.assert_array_equal(model.dprime(ks), d[:, ks].T)


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
def test_controller_update_equals_the_bayes_step(dtype):
    grid = Grid(6, 8)
    fpoc = make_fpoc('human')
    d = dprime_matrix(grid, fpoc)
    # A confidence the 40 updates never reach, so the search does not end at found.
    core = GazeController(grid, fpoc, elm_policy(grid, fpoc), SearchSettings(confidence=1 - 1e-12))
    core.reset(0.0)
    rng = np.random.default_rng(6)
    log_b = uniform_log_belief(grid.n_cells)
    for t in range(40):
        k = core.fixation
        frame = rng.normal(size=grid.n_cells).astype(dtype)
        if t % 3 == 0:
            frame[rng.choice(grid.n_cells, 5, replace=False)] = np.nan
        assert core.offer(frame, float(t)).applied
        log_b = bayes_update(log_b, llr(frame.astype(float), d[:, k]))
        np.testing.assert_allclose(core.belief, np.exp(log_b), rtol=1e-12, atol=1e-15)
    assert core.map_cell == int(argmax_ties_low(np.exp(log_b)))


def test_controller_rejects_bad_frames_and_keeps_the_belief():
    grid = Grid(5, 5)
    fpoc = make_fpoc('human')
    core = GazeController(grid, fpoc, elm_policy(grid, fpoc))
    core.reset(0.0)
    assert core.offer(np.full(25, 0.5), 1.0).applied
    before = core.belief
    bad = np.zeros(25)
    bad[3] = -np.inf
    reasons = [core.offer(bad, 2.0).reason]
    bad[3], bad[4] = np.nan, np.inf
    reasons.append(core.offer(bad, 2.0).reason)
    reasons.append(core.offer(np.zeros(24), 2.0).reason)
    reasons.append(core.offer(np.zeros((1, 25)), 2.0).reason)
    assert ['inf' in reasons[0], 'inf' in reasons[1], '24 values' in reasons[2],
            'expected 25' in reasons[3]] == [True] * 4
    assert core.rejected == 4
    np.testing.assert_array_equal(core.belief, before)
    model = GaussianObservation(grid, fpoc)
    with pytest.raises(ValueError, match='outside a 5x5 grid'):
        model.log_likelihood_ratio(np.zeros(25), 25)
    with pytest.raises(ValueError, match='integer cell index'):
        model.log_likelihood_ratio(np.zeros(25), 2.0)
    core.reset(3.0)
    np.testing.assert_allclose(core.belief, 1 / 25)


def test_direct_decide_allocates_no_arrays():
    grid = Grid(32, 32)                              # 8 KiB per float64 array
    fpoc = make_fpoc('human')
    policy = ConvPolicy(grid, dprime_table(grid, fpoc) ** 2, method='direct')
    beliefs = np.random.default_rng(7).dirichlet(np.ones(grid.n_cells), size=6)
    k = policy.decide(beliefs[0])                    # builds W once
    tracemalloc.start()
    try:
        for belief in beliefs:
            k = policy.decide(belief)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 4096                               # a few Python scalars, not one array
    assert k == int(argmax_ties_low(beliefs[-1] @ kernel_matrix(grid, policy.kernel).T))


def test_a_256x256_controller_never_builds_an_n_by_n_array():
    grid = Grid(256, 256)
    fpoc = make_fpoc('human')
    tracemalloc.start()
    try:
        policy = elm_policy(grid, fpoc)
        core = GazeController(grid, fpoc, policy)
        core.reset(0.0)
        rng = np.random.default_rng(8)
        for t in range(3):
            assert core.offer(rng.normal(size=grid.n_cells), float(t)).applied
        k = policy.decide(core.belief)
        assert core.fixation == k
        beliefs = np.vstack([core.belief, np.roll(core.belief, 1000)])
        batch = policy.select(beliefs, 0, rng)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # One N x N float64 matrix would be 32 GiB; everything here stays below 64 MiB.
    assert peak < 64 * 2 ** 20
    assert batch[0] == k and 0 <= batch[1] < grid.n_cells
    assert not policy.uses_direct() and policy.fft_shape[0] < 2 * 256 - 1


def test_elm_at_512x512_agrees_with_a_windowed_direct_sum():
    grid = Grid(512, 512)
    fpoc = make_fpoc('human')
    policy = elm_policy(grid, fpoc)
    rng = np.random.default_rng(9)
    belief = np.zeros(grid.n_cells)
    cells = rng.choice(grid.n_cells, 30, replace=False)
    belief[cells] = rng.dirichlet(np.ones(30))
    k = policy.decide(belief)
    # Exact scores of all cells: each belief cell adds its weight times a window of the kernel.
    kernel = dprime_table(grid, fpoc) ** 2
    rows, cols = grid.shape
    scores = np.zeros(grid.shape)
    for j in cells:
        rj, cj = grid.cell(int(j))
        scores += belief[j] * kernel[rj:rj + rows, cj:cj + cols][::-1, ::-1]
    assert k == int(argmax_ties_low(scores.ravel()))
    assert np.isclose(policy.exact_scores(belief, [k])[0], scores.flat[k], rtol=1e-12)


# -- bench runner ---------------------------------------------------------------------------------

def test_bench_report_sections_round_trip_for_partial_runs(tmp_path):
    saved = dict(os.environ)                          # the runner pins BLAS threads on import
    try:
        spec = importlib.util.spec_from_file_location('bench_run', BENCH_RUN)
        run = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(run)
    finally:
        os.environ.clear()
        os.environ.update(saved)
    text = run.compose({'b': 'B body\n', 'a': 'A body\n'}, {'a': 10.0, 'b': 30.0},
                       {'a': 'Alpha', 'b': 'Beta'})
    assert text.index('## Alpha') < text.index('## Beta')
    for name in run.PENDING:                          # e.g. the ROS loop, until it lands
        assert (f'bench_{name}.py' in text) == (name not in run.discover())
    path = tmp_path / 'benchmarks.md'
    path.write_text(text)
    assert run.previous(path) == ({'a': 'A body\n', 'b': 'B body\n'},
                                  {'a': 'Alpha', 'b': 'Beta'}, {'a': 10.0, 'b': 30.0})
