# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The count observation model: Bayes against brute force, samples against the tables, files."""
from ipomdp_gaze.files.observation_file import (fingerprint, load_observation, model_from_dict,
                                                model_to_dict, ObservationFileError,
                                                save_observation)
from ipomdp_gaze.model.belief import bayes_update, EvidenceError, uniform_log_belief
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation, MAX_LOG_RATIO
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.simulation.simulate import simulate
import numpy as np
import pytest
from scipy.stats import chi2

GRID = Grid(4, 5, 1.0)
K = 4


def tables(seed, grid=GRID, k=K):
    """Random tables whose target side has more mass on high counts near the fixation."""
    rng = np.random.default_rng(seed)
    null = rng.dirichlet(np.full(k, 2.0), size=grid.shape)
    target = rng.dirichlet(np.full(k, 2.0), size=grid.shape)
    target[0, 0] = [0.05, 0.15, 0.3, 0.5]
    null[0, 0] = [0.7, 0.2, 0.07, 0.03]
    return target, null


MODEL = CountObservation(GRID, *tables(0))


def brute_force_posterior(model, prior, frames, fixations):
    """Posterior over the target's cell from products of table probabilities over all cells."""
    grid = model.grid
    post = prior.copy()
    for frame, k in zip(frames, fixations):
        rk, ck = grid.cell(k)
        for i in range(grid.n_cells):                       # hypothesis: target at i
            for j in range(grid.n_cells):
                if np.isnan(frame[j]):
                    continue
                rj, cj = grid.cell(j)
                table = model.p_target if i == j else model.p_null
                c = int(min(frame[j], model.max_count))
                post[i] *= table[abs(rj - rk), abs(cj - ck), c]
    return post / post.sum()


@pytest.mark.parametrize('seed', range(6))
def test_update_matches_brute_force_bayes(seed):
    rng = np.random.default_rng(seed)
    prior = rng.dirichlet(np.ones(GRID.n_cells))
    log_b = np.log(prior)
    frames, fixations = [], []
    for _ in range(3):
        k = int(rng.integers(GRID.n_cells))
        frame = rng.integers(0, K + 3, GRID.n_cells).astype(float)   # some above K-1: clipped
        frame[rng.random(GRID.n_cells) < 0.2] = np.nan                 # some unobserved cells
        frames.append(frame)
        fixations.append(k)
        log_b = bayes_update(log_b, MODEL.log_likelihood_ratio(frame, k))
    np.testing.assert_allclose(np.exp(log_b), brute_force_posterior(MODEL, prior, frames,
                                                                    fixations), rtol=1e-9)


def test_batched_ratio_equals_single_frames():
    rng = np.random.default_rng(1)
    fixations = rng.integers(0, GRID.n_cells, 9)
    frames = rng.integers(0, K, (9, GRID.n_cells)).astype(float)
    batch = MODEL.log_likelihood_ratio(frames, fixations)
    for e in range(9):
        np.testing.assert_array_equal(batch[e], MODEL.log_likelihood_ratio(frames[e],
                                                                           fixations[e]))


@pytest.mark.parametrize('bad, words', [(-1.0, 'integers >= 0'), (1.5, 'integers >= 0'),
                                        (np.inf, 'integers >= 0')])
def test_invalid_counts_are_refused(bad, words):
    frame = np.zeros(GRID.n_cells)
    frame[7] = bad
    with pytest.raises(EvidenceError, match=f'{words}.*cell 7'):
        MODEL.log_likelihood_ratio(frame, 0)


def test_a_count_impossible_under_both_hypotheses_is_refused_one_impossible_is_decisive():
    target, null = tables(2)
    target[0, 0] = [0.0, 0.0, 0.5, 0.5]
    null[0, 0] = [0.5, 0.5, 0.0, 0.0]
    target[0, 1], null[0, 1] = [0.5, 0.5, 0.0, 0.0], [0.5, 0.5, 0.0, 0.0]
    model = CountObservation(GRID, target, null)
    frame = np.zeros(GRID.n_cells)
    frame[0] = 3                                   # only possible with the target: decisive
    log_b = bayes_update(uniform_log_belief(GRID.n_cells), model.log_likelihood_ratio(frame, 0))
    assert np.exp(log_b[0]) > 0.999999
    frame[1] = 3                                   # impossible either way at offset (0, 1)
    with pytest.raises(EvidenceError, match='probability 0 with and without'):
        model.log_likelihood_ratio(frame, 0)


def test_samples_match_the_tables():
    """Chi-square of sampled counts against the table, at the target and elsewhere."""
    episodes = 30000
    rng = np.random.default_rng(3)
    targets = np.full(episodes, GRID.index(1, 2))
    fixations = np.full(episodes, GRID.index(1, 1))
    frames = MODEL.sample(targets, fixations, rng)
    for cell, table in ((GRID.index(1, 2), MODEL.p_target[0, 1]),
                        (GRID.index(3, 4), MODEL.p_null[2, 3]),
                        (GRID.index(1, 1), MODEL.p_null[0, 0])):
        observed = np.bincount(frames[:, cell].astype(int), minlength=K)
        expected = episodes * table
        stat = np.sum((observed - expected) ** 2 / expected)
        assert stat < chi2.ppf(0.999, K - 1), (cell, observed, expected)


def test_samples_are_common_random_numbers_and_a_scalar_is_one_frame():
    a = MODEL.sample(np.array([0, 5]), np.array([3, 3]), np.random.default_rng(4))
    b = MODEL.sample(np.array([0, 5]), np.array([3, 3]), np.random.default_rng(4))
    np.testing.assert_array_equal(a, b)
    one = MODEL.sample(5, 3, np.random.default_rng(4))
    assert one.shape == (GRID.n_cells,)
    batch_of_one = MODEL.sample(np.array([5]), np.array([3]), np.random.default_rng(4))
    np.testing.assert_array_equal(one, batch_of_one[0])


def test_elm_kernel_is_twice_the_kl_divergence_per_offset():
    kernel = MODEL.elm_kernel()
    assert kernel.shape == GRID.kernel_shape
    for dr in range(-3, 4):
        for dc in range(-4, 5):
            pt, pn = MODEL.p_target[abs(dr), abs(dc)], MODEL.p_null[abs(dr), abs(dc)]
            assert kernel[dr + 3, dc + 4] == pytest.approx(2 * np.sum(pt * np.log(pt / pn)))
    elm = make_baseline('elm', GRID, MODEL)
    np.testing.assert_array_equal(elm.kernel, kernel)


def test_simulated_search_with_elm_on_the_count_model_finds_the_target():
    result = simulate(GRID, MODEL, make_baseline('elm', GRID, MODEL), episodes=400, horizon=40,
                      seed=5)
    chance = 1 / GRID.n_cells
    assert result.percent_correct[-1] > 0.9 > chance
    again = simulate(GRID, MODEL, make_baseline('elm', GRID, MODEL), episodes=400, horizon=40,
                     seed=5)
    np.testing.assert_array_equal(result.fixations, again.fixations)


def test_file_round_trip_and_fingerprint(tmp_path):
    model = CountObservation(GRID, *tables(6), meta={'image': {'width': 420, 'height': 420},
                                                     'detector': {'scale_factor': 1.1}})
    path = save_observation(tmp_path / 'faces.yaml', model)
    back = load_observation(path)
    np.testing.assert_allclose(back.p_target, model.p_target, atol=1e-11)
    assert back.meta['image'] == {'width': 420, 'height': 420}
    assert back.meta['source'] == 'faces'
    assert fingerprint(back) == fingerprint(load_observation(path))


def _doc():
    return model_to_dict(CountObservation(GRID, *tables(7)))


@pytest.mark.parametrize('change, words', [
    (lambda d: d.pop('null'), 'missing key null'),
    (lambda d: d.update(extra=1), 'unknown key extra'),
    (lambda d: d.update(format='x'), 'wrong format string'),
    (lambda d: d.update(model='gaussian'), 'unknown model'),
    (lambda d: d['grid'].update(rows=0), 'grid.rows must be a positive integer'),
    (lambda d: d['target'].pop(), 'target must be a 4 x 5 x K list'),
    (lambda d: d['target'][0][0].append(0.0) or d['target'][0][0].append(0.0),
     'same number of counts'),
    (lambda d: d['null'][1][2].__setitem__(0, -0.1), 'null table must be finite and >= 0'),
    (lambda d: d['null'][1][2].__setitem__(0, 5.0), r'offset \(1, 2\) sums to'),
    (lambda d: d['target'][0][0].__setitem__(1, float('nan')), 'finite'),
    (lambda d: d['target'][0][0].__setitem__(1, [1.0]), 'probabilities'),
    (lambda d: d.update(fovea=[1]), 'fovea must be a mapping'),
])
def test_malformed_documents_name_the_problem(change, words):
    doc = _doc()
    change(doc)
    with pytest.raises(ObservationFileError, match=words):
        model_from_dict(doc)


def test_unreadable_and_missing_files(tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('format: [unclosed\n')
    with pytest.raises(ObservationFileError, match='not YAML at line'):
        load_observation(bad)
    with pytest.raises(ObservationFileError, match='not found and not a shipped model'):
        load_observation(tmp_path / 'missing.yaml')
    with pytest.raises(ObservationFileError, match=r"'.*' is a folder, not a file"):
        load_observation(tmp_path)                      # QA: it said 'not found'


# ---- the one-time scan -------------------------------------------------------------------------

SCAN_TARGET = np.array([0.2, 0.3, 0.25, 0.25])
SCAN_NULL = np.array([0.9, 0.06, 0.03, 0.01])


def test_scan_update_matches_brute_force_bayes():
    model = CountObservation(GRID, *tables(8), scan_target=SCAN_TARGET, scan_null=SCAN_NULL)
    rng = np.random.default_rng(3)
    prior = rng.dirichlet(np.ones(GRID.n_cells))
    counts = rng.integers(0, K + 2, GRID.n_cells).astype(float)
    counts[3] = np.nan
    post = np.exp(bayes_update(np.log(prior), model.scan_log_likelihood_ratio(counts)))
    brute = prior.copy()
    for i in range(GRID.n_cells):
        for j in range(GRID.n_cells):
            if not np.isnan(counts[j]):
                c = int(min(counts[j], K - 1))
                brute[i] *= (SCAN_TARGET if i == j else SCAN_NULL)[c]
    np.testing.assert_allclose(post, brute / brute.sum(), rtol=1e-9)


def test_scan_tables_are_validated_and_only_models_with_them_scan():
    with pytest.raises(ValueError, match='both scan_target and scan_null'):
        CountObservation(GRID, *tables(0), scan_target=SCAN_TARGET)
    with pytest.raises(ValueError, match='K = 4 entries'):
        CountObservation(GRID, *tables(0), scan_target=SCAN_TARGET[:3], scan_null=SCAN_NULL[:3])
    with pytest.raises(ValueError, match='scan null table must sum to 1'):
        CountObservation(GRID, *tables(0), scan_target=SCAN_TARGET, scan_null=SCAN_NULL * 2)
    with pytest.raises(ValueError, match='no scan tables'):
        MODEL.scan_log_likelihood_ratio(np.zeros(GRID.n_cells))
    with pytest.raises(EvidenceError, match='integers >= 0'):
        CountObservation(GRID, *tables(0), scan_target=SCAN_TARGET, scan_null=SCAN_NULL) \
            .scan_log_likelihood_ratio(np.full(GRID.n_cells, -1.0))


def test_scan_tables_round_trip_through_the_file_and_the_fingerprint(tmp_path):
    plain = CountObservation(GRID, *tables(6))
    model = CountObservation(GRID, *tables(6), scan_target=SCAN_TARGET, scan_null=SCAN_NULL)
    path = save_observation(tmp_path / 'scan.yaml', model)
    back = load_observation(path)
    assert back.has_scan and back == load_observation(path) and back != plain
    np.testing.assert_allclose(back.scan_null, SCAN_NULL, atol=1e-12)
    assert fingerprint(back) == fingerprint(load_observation(path))
    assert fingerprint(model) != fingerprint(plain)
    doc = model_to_dict(model)
    doc['scan'] = {'target': [0.5, 0.5]}
    with pytest.raises(ObservationFileError, match='scan must be a mapping'):
        model_from_dict(doc)
    doc['scan'] = {'target': [0.5, 0.5], 'null': [0.5, 0.5]}
    with pytest.raises(ObservationFileError, match='K = 4 entries'):
        model_from_dict(doc)


@pytest.mark.parametrize('scale', [0.5, 2.0])
def test_tables_that_do_not_sum_to_one_are_refused_below_as_above(scale):
    target, null = tables(0)
    null[1, 2] *= scale
    with pytest.raises(ValueError, match=r'null table must sum to 1 over counts at every '
                                         r'offset: offset \(1, 2\)'):
        CountObservation(GRID, target, null)
    with pytest.raises(ValueError, match='scan target table must sum to 1'):
        CountObservation(GRID, *tables(0), scan_target=SCAN_TARGET * scale,
                         scan_null=SCAN_NULL)


def test_tables_of_a_single_count_are_refused():
    one = np.ones(GRID.shape + (1,))
    with pytest.raises(ValueError, match='K >= 2'):
        CountObservation(GRID, one, one)


def test_a_count_one_hypothesis_rules_out_gives_the_clipped_ratio_on_either_side():
    target, null = tables(2)
    target[0, 0] = [0.0, 0.0, 0.5, 0.5]
    null[0, 0] = [0.5, 0.5, 0.0, 0.0]
    model = CountObservation(GRID, target, null)
    frame = np.full(GRID.n_cells, np.nan)
    frame[0] = 3                                   # impossible without the target
    assert model.log_likelihood_ratio(frame, 0)[0] == MAX_LOG_RATIO
    frame[0] = 0                                   # impossible with the target
    assert model.log_likelihood_ratio(frame, 0)[0] == -MAX_LOG_RATIO


def test_cells_at_offsets_whose_tables_agree_are_not_observed_and_learn_nothing():
    target, null = tables(4)
    target[2:] = null[2:]                          # offsets |dr| >= 2 say nothing
    model = CountObservation(GRID, target, null)
    rows, _ = GRID.rows_cols()
    for k, row in ((GRID.index(0, 0), 0), (GRID.index(3, 4), 3)):
        np.testing.assert_array_equal(model.observed(k), np.abs(rows - row) < 2)
        term = model.log_likelihood_ratio(np.full(GRID.n_cells, 2.0), k)
        assert np.all(term[np.abs(rows - row) >= 2] == 0.0)


def test_the_elm_kernel_is_twice_the_kl_by_hand_with_zero_probabilities():
    """0 log 0 = 0 where p_target is 0; where p_null is 0 and p_target is not, 2 * the cap."""
    target, null = tables(5)
    target[0, 1] = [0.0, 0.2, 0.3, 0.5]            # a count the target never gives
    target[2, 3], null[2, 3] = [0.25] * 4, [0.5, 0.5, 0.0, 0.0]
    model = CountObservation(GRID, target, null)
    kernel = model.elm_kernel()
    assert kernel.shape == GRID.kernel_shape and np.isfinite(kernel).all()
    rows, cols = GRID.shape
    for dr in range(-(rows - 1), rows):
        for dc in range(-(cols - 1), cols):
            pt, pn = target[abs(dr), abs(dc)], null[abs(dr), abs(dc)]
            if np.any((pt > 0) & (pn == 0)):
                expected = 2 * MAX_LOG_RATIO
            else:
                expected = 2 * sum(p * np.log(p / q) for p, q in zip(pt, pn) if p > 0)
            assert kernel[dr + rows - 1, dc + cols - 1] == pytest.approx(expected, rel=1e-12)
