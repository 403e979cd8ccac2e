# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The model core at its edges, each case checked against what the docs promise."""
from dataclasses import replace
from types import SimpleNamespace

from ipomdp_gaze.files.observation_file import load_observation, save_observation
from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation, GaussianObservation
from ipomdp_gaze.model.stopping import first_decisions, GAVE_UP
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
from ipomdp_gaze.simulation.evaluation import paired_tracking_difference, tracking_summary
import numpy as np
import pytest


def _gaussian(grid):
    return GaussianObservation(grid, make_fpoc('camera', half_width_deg=1, half_height_deg=1))


def test_a_new_repeat_weight_keeps_the_many_target_belief_until_the_next_frame():
    grid = Grid(1, 3)
    settings = SearchSettings(targets='many', confidence=1 - 1e-12, start_cell=(0, 1))
    session = OccupancySession(grid, _gaussian(grid), settings)
    session.reset()
    session.start()
    for _ in range(2):
        session.update(Frame(np.ones(3)))
    before = session.log_odds
    session.configure(replace(settings, repeat_weight=0.0))
    np.testing.assert_array_equal(session.log_odds, before)
    # From the next frame on the still evidence is counted afresh: the first view of a cell
    # counts in full whatever the weight, as in a new search from this belief.
    term = session.observation.log_likelihood_ratio(np.ones(3), grid.index(0, 1))
    session.update(Frame(np.ones(3)))
    np.testing.assert_allclose(session.log_odds, before + term, rtol=1e-12)


def test_the_single_target_session_also_keeps_its_belief_on_a_new_repeat_weight():
    grid = Grid(1, 3)
    settings = SearchSettings(confidence=0.999, start_cell=(0, 1))
    session = SearchSession(grid, _gaussian(grid), None, settings)
    session.reset()
    session.start()
    for _ in range(2):
        session.update(Frame(np.ones(3)))
    before = session.belief
    session.configure(replace(settings, repeat_weight=0.0))
    np.testing.assert_allclose(session.belief, before, rtol=1e-12)


def test_tiny_count_probabilities_survive_the_observation_file(tmp_path):
    grid = Grid(1, 2)
    p_target = np.array([[[.5, .5 - 4e-13, 4e-13], [.6, .4 - 4e-13, 4e-13]]])
    p_null = np.array([[[.9, .1 - 6e-13, 6e-13]] * 2])
    model = CountObservation(grid, p_target, p_null)
    loaded = load_observation(save_observation(tmp_path / 'tiny.yaml', model))
    frame = np.array([2.0, 0.0])
    # log(4e-13 / 6e-13) for the count of 2: rounded to 12 decimals both were 0 and the cell
    # was ruled out (-50 per frame).
    np.testing.assert_allclose(loaded.log_likelihood_ratio(frame, 0),
                               model.log_likelihood_ratio(frame, 0), rtol=1e-9)
    np.testing.assert_allclose(loaded.p_null, model.p_null, rtol=1e-12, atol=0)


def test_a_resample_without_fixations_after_a_lock_has_no_tracking_accuracy():
    result = SimpleNamespace(target_path=np.array([[0] * 4, [5] * 4]),
                             guess=np.array([[0] * 4, [20] * 4]), present=None)
    summary = tracking_summary(result, 5, np.random.default_rng(0))
    # Search 0 locks at once and stays on; search 1 never locks, so has nothing after a lock.
    # Every resample with a ratio at all has 1: the interval is [1, 1], not [0, 1].
    assert summary['tracking_accuracy']['value'] == 1.0
    assert summary['tracking_accuracy']['ci95'] == [1.0, 1.0]
    other = SimpleNamespace(target_path=result.target_path,
                            guess=np.array([[0, 0, 20, 20], [20] * 4]), present=None)
    paired = paired_tracking_difference(result, other, 5, np.random.default_rng(0))
    assert paired['difference'] == pytest.approx(1.0 - 1.0 / 3.0)
    assert paired['ci95'] == pytest.approx([2.0 / 3.0, 2.0 / 3.0])


def test_a_budget_of_zero_is_no_budget_in_first_decisions():
    p = np.array([[0.5, 0.99], [0.5, 0.6]])
    kind, fixations = first_decisions(p, None, 0.95, max_fixations=0)
    np.testing.assert_array_equal(fixations, [2, 2])
    np.testing.assert_array_equal(kind, first_decisions(p, None, 0.95)[0])
    assert kind[1] == GAVE_UP
    kind, fixations = first_decisions(np.zeros((2, 0)), None, 0.95)
    np.testing.assert_array_equal(kind, [GAVE_UP, GAVE_UP])
    np.testing.assert_array_equal(fixations, [0, 0])


def test_many_targets_on_one_cell_need_an_absent_prior():
    """QA: the refusal named search.absent.prior, a parameter no node has (absent.prior)."""
    grid = Grid(1, 1)
    with pytest.raises(ValueError, match=r'on 1 cell needs a larger absent\.prior \(got 0\)'):
        OccupancySession(grid, _gaussian(grid), SearchSettings(targets='many'))
    four = Grid(2, 2)
    with pytest.raises(ValueError, match=r'on 4 cells needs .* \(got 1e-70\)'):
        OccupancySession(four, _gaussian(four), SearchSettings(targets='many', absent_prior=1e-70))
    session = OccupancySession(grid, _gaussian(grid),
                               SearchSettings(targets='many', absent_prior=0.5))
    session.reset()
    np.testing.assert_allclose(session.belief, [0.5])


@pytest.mark.parametrize('scan', [False, True])
def test_without_a_policy_the_session_starts_at_the_centre(scan):
    grid = Grid(3, 3)
    table = np.full((3, 3, 2), 0.5)
    model = CountObservation(grid, table, table, scan_target=np.array([0.2, 0.8]),
                             scan_null=np.array([0.8, 0.2]))
    settings = SearchSettings(scan=True) if scan else SearchSettings(start_cell='policy')
    session = SearchSession(grid, model, None, settings)
    session.reset()
    if scan:
        assert session.scan(Frame(np.eye(1, 9, 2).ravel(), kind='scan')).status == 'applied'
    assert session.start() == grid.center_index


@pytest.mark.parametrize('frame', [np.array([0.5]), np.zeros((4, 1)), np.zeros(3),
                                   np.zeros((2, 2, 4)), ['a', 'b', 'c', 'd']])
def test_the_models_refuse_a_frame_of_another_grid(frame):
    grid = Grid(2, 2)
    counts = CountObservation(grid, np.full((2, 2, 2), 0.5), np.full((2, 2, 2), 0.5))
    for model in (_gaussian(grid), counts):
        with pytest.raises(EvidenceError, match='evidence'):
            model.log_likelihood_ratio(frame, 0)


def test_a_session_rejects_a_frame_of_strings_and_keeps_its_belief():
    grid = Grid(2, 2)
    session = SearchSession(grid, _gaussian(grid), None, SearchSettings())
    session.reset()
    session.start()
    before = session.belief
    result = session.update(Frame(np.array(['a', 'b', 'c', 'd'], dtype=object)))
    assert result.status == 'rejected' and 'numbers' in result.reason
    np.testing.assert_array_equal(session.belief, before)


@pytest.mark.parametrize('row, col', [(1.5, 0), (0, 0.25), ('1', 0), (float('nan'), 0)])
def test_a_cell_is_named_by_whole_numbers(row, col):
    with pytest.raises(ValueError, match='whole number'):
        Grid(3, 3).index(row, col)


def test_whole_floats_and_numpy_integers_still_name_cells():
    grid = Grid(3, 3)
    assert grid.index(np.int64(1), 2.0) == 5
    assert grid.cell(np.float64(4.0)) == (1, 1)
    with pytest.raises(ValueError, match='whole number'):
        grid.cell(1.7)


def test_a_simulation_refuses_a_dprime_whose_drawn_frames_overflow():
    # The simulator applies its own frames unchecked: past about 1.9e154, d (o - d/2) is +/-inf
    # and the belief NaN, and every search was scored wrong without a word (evaluate printed
    # "never" for a camera that sees perfectly); from about 1e153 the reward was NaN.
    from ipomdp_gaze.policies.baselines import MapPolicy
    from ipomdp_gaze.simulation.simulate import simulate
    grid = Grid(3, 3, 1.0)

    def camera(dprime):
        return make_fpoc('camera', dprime=dprime, half_width_deg=1, half_height_deg=1)
    for dprime in (1e154, 1e155):
        with pytest.raises(ValueError, match="d' up to 1e\\+150 can be simulated"):
            simulate(grid, camera(dprime), MapPolicy(), episodes=20, seed=0)
    result = simulate(grid, camera(1e150), MapPolicy(), episodes=20, seed=0)
    assert result.correct[:, -1].all()          # a perfect camera: every search ends right
    assert np.isfinite(result.infomax).all()


@pytest.mark.filterwarnings('error')
def test_elm_refuses_a_dprime_whose_square_overflows_in_one_line():
    # search --fpoc camera --fpoc-param dprime=1e300 printed numpy's two lines ("overflow
    # encountered in square", "return self.table ** 2") before its error.
    from ipomdp_gaze.policies.baselines import ELMPolicy
    grid = Grid(3, 3, 1.0)
    fpoc = make_fpoc('camera', dprime=1e300, half_width_deg=1, half_height_deg=1)
    assert np.isinf(GaussianObservation(grid, fpoc).elm_kernel()).any()
    with pytest.raises(ValueError, match='kernel must be finite'):
        ELMPolicy(grid, fpoc)
