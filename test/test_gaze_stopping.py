# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The controller core with a moving or absent target: events, the end of a search, tracking."""
from __future__ import annotations

from dataclasses import replace

from ipomdp_gaze.model.belief import bayes_update
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import Motion
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
from ipomdp_gaze.model.stopping import initial_log_belief
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.health import HealthMonitor
from ipomdp_gaze.search.session import SearchSettings
import numpy as np
import pytest

GRID = Grid(11, 11, 5.0)
CAMERA = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)
D = dprime_matrix(GRID, CAMERA)


def controller(**kwargs):
    core = GazeController(GRID, CAMERA, build_policy('elm', GRID, CAMERA),
                          SearchSettings(**kwargs))
    core.reset(0.0)
    return core


def frame_at(core, target=None, rng=None, strength=1.0):
    """Make a frame seen from the current fixation: noise (or zeros) plus d' at the target."""
    k = core.fixation
    frame = np.zeros(GRID.n_cells) if rng is None else rng.standard_normal(GRID.n_cells)
    if target is not None:
        frame[target] += strength * D[target, k]
    frame[D[:, k] == 0] = np.nan
    return frame


def test_found_ends_a_still_search_until_reset():
    core = controller(confidence=0.95)
    target = GRID.center_index
    result = core.offer(frame_at(core, target, strength=10.0), 1.0)
    assert result.applied and result.found is not None and result.found.cell == target
    assert result.fixation is None and core.stopped and core.decision == 'found'
    fixation, belief = core.fixation, core.belief
    for t in (2.0, 3.0):
        later = core.offer(frame_at(core, target), t)
        assert later.status == 'skipped' and 'the search has ended (found)' in later.reason
        assert later.fixation is None and later.found is None
    assert core.fixation == fixation and core.fixations == 1
    np.testing.assert_array_equal(core.belief, belief)
    assert core.reset(4.0) == GRID.center_index and not core.stopped and core.decision == ''
    assert core.offer(frame_at(core), 5.0).fixation is not None


def test_absent_is_declared_for_an_empty_grid_and_ends_the_search():
    core = controller(absent_prior=0.5, confidence=0.99)
    np.testing.assert_allclose(core.belief.sum() + core.absent_probability, 1.0)
    assert core.absent_probability == pytest.approx(0.5)
    rng = np.random.default_rng(1)
    result = None
    for t in range(1, 60):
        result = core.offer(frame_at(core, rng=rng), float(t))
        np.testing.assert_allclose(core.belief.sum() + core.absent_probability, 1.0,
                                   rtol=1e-12)
        if result.absent is not None:
            break
    assert result.absent is not None and result.found is None
    assert result.absent.probability >= 0.99 and result.absent.fixations == core.fixations
    assert core.stopped and core.decision == 'absent' and result.fixation is None
    assert core.offer(frame_at(core, rng=rng), 100.0).status == 'skipped'


def test_the_absent_hypothesis_follows_bayes_over_n_plus_one_states():
    core = controller(absent_prior=0.3, confidence=0.999999)
    rng = np.random.default_rng(2)
    log_b = initial_log_belief(GRID.n_cells, 0.3)
    for t in range(1, 6):
        k = core.fixation
        frame = frame_at(core, rng=rng)
        log_b = bayes_update(log_b, np.append(llr(frame, D[:, k]), 0.0))
        assert core.offer(frame, float(t)).applied
        np.testing.assert_allclose(core.belief, np.exp(log_b[:-1]), rtol=1e-9)
        assert core.absent_probability == pytest.approx(np.exp(log_b[-1]), rel=1e-9)


def test_gave_up_at_the_budget_is_undecided_and_ends_the_search():
    core = controller(max_fixations=3)
    little = np.full(GRID.n_cells, np.nan)
    little[0] = 0.0                                   # one cell seen: nothing decided
    results = [core.offer(little, float(t)) for t in (1, 2, 3)]
    assert [r.gave_up for r in results[:2]] == [None, None]
    assert results[2].gave_up is not None and results[2].gave_up.fixations == 3
    assert results[2].found is None and results[2].absent is None
    assert core.stopped and core.decision == 'gave_up'
    assert core.offer(np.zeros(GRID.n_cells), 4.0).status == 'skipped'
    h = HealthMonitor(0.0).report(core, 30.0, 5.0)
    assert (h.level, h.message) == ('ok', 'gave up after 3 fixations')
    assert h.values['decision'] == 'gave_up' and h.values['search_ended'] is True


def test_a_decision_on_the_last_budgeted_fixation_is_not_giving_up():
    core = controller(max_fixations=1)
    result = core.offer(frame_at(core, GRID.center_index, strength=10.0), 1.0)
    assert result.found is not None and result.gave_up is None


def test_motion_predicts_over_the_time_since_the_last_update():
    core = controller(motion_sigma_cells=0.8, motion_jump_prob=0.1, absent_prior=0.2,
                      confidence=0.999999)
    rng = np.random.default_rng(3)
    log_b = initial_log_belief(GRID.n_cells, 0.2)
    last = 0.0
    for now in (0.5, 0.75, 2.0, 2.01):
        k = core.fixation
        frame = frame_at(core, target=30, rng=rng)
        Motion(GRID, 0.8 * np.sqrt(now - last), 1 - 0.9 ** (now - last)).predict_log(log_b)
        log_b = bayes_update(log_b, np.append(llr(frame, D[:, k]), 0.0))
        core.offer(frame, now)
        last = now
        np.testing.assert_allclose(core.belief, np.exp(log_b[:-1]), rtol=1e-9, atol=1e-300)
        assert core.absent_probability == pytest.approx(np.exp(log_b[-1]), rel=1e-9)


def test_with_motion_found_reports_keeps_tracking_and_rearms():
    core = controller(motion_sigma_cells=0.2, confidence=0.95)
    target = GRID.center_index
    first = core.offer(frame_at(core, target, strength=10.0), 1.0)
    assert first.found is not None and not core.stopped and first.fixation is not None
    assert core.decision == 'found'
    core.fixation = target
    again = core.offer(frame_at(core, target, strength=2.0), 1.1)
    assert again.applied and again.found is None and core.decision == 'found'  # still locked
    # A second later the belief has spread to the neighbours (sigma 0.2 cells), and strong
    # evidence that the target left its cell makes the probability fall: found is re-armed.
    core.fixation = target
    lost = core.offer(frame_at(core, target, strength=-3.0), 2.1)
    assert lost.found is None and core.map_probability < 0.95 and core.decision == ''
    assert lost.lost is not None and lost.lost.cell == target and lost.lost.fixations == 3
    assert lost.lost.probability == pytest.approx(core.map_probability)
    assert lost.lost.seconds_tracked == pytest.approx(1.1)
    core.fixation = target
    back = core.offer(frame_at(core, target, strength=10.0), 2.2)
    assert back.found is None and not core.stopped       # a find after a loss: reacquired
    assert back.reacquired is not None and back.reacquired.fixations == 4
    assert back.reacquired.cell == target and back.reacquired.seconds_lost == pytest.approx(0.1)
    assert (core.losses, core.reacquisitions) == (1, 1) and core.lost is None


def test_a_loss_names_the_cell_the_target_was_last_tracked_in():
    """After a reacquisition elsewhere, the next loss is at the new cell, not the first find's."""
    core = controller(motion_sigma_cells=0.2, confidence=0.95)
    first, second = GRID.center_index, GRID.index(2, 3)
    core.offer(frame_at(core, first, strength=10.0), 1.0)
    core.fixation = first
    assert core.offer(frame_at(core, first, strength=-3.0), 2.0).lost.cell == first
    core.fixation = second
    assert core.offer(frame_at(core, second, strength=10.0), 2.1).reacquired.cell == second
    core.fixation = second
    again = core.offer(frame_at(core, second, strength=-3.0), 3.1)
    assert again.lost is not None and again.lost.cell == second


def test_a_still_search_never_loses_what_it_found():
    """Without motion a decision ends the search: no lost, no reacquired."""
    core = controller(confidence=0.95)
    target = GRID.center_index
    first = core.offer(frame_at(core, target, strength=10.0), 1.0)
    assert first.found is not None and core.stopped and first.lost is None
    after = core.offer(frame_at(core, target, strength=-3.0), 2.0)
    assert after.status == 'skipped' and after.lost is None and core.losses == 0


def test_a_reset_forgets_the_loss():
    """After ~/reset the first find is found again, not reacquired."""
    core = controller(motion_sigma_cells=0.2, confidence=0.95)
    target = GRID.center_index
    core.offer(frame_at(core, target, strength=10.0), 1.0)
    core.fixation = target
    assert core.offer(frame_at(core, target, strength=-3.0), 2.0).lost is not None
    core.reset(3.0)
    assert (core.losses, core.reacquisitions, core.lost) == (0, 0, None)
    first = core.offer(frame_at(core, target, strength=10.0), 4.0)
    assert first.found is not None and first.reacquired is None


def test_absent_prior_changes_apply_from_the_next_reset():
    core = controller()
    core.configure(replace(core.settings, absent_prior=0.4))
    assert core.absent_probability == 0.0
    core.reset(1.0)
    assert core.absent_probability == pytest.approx(0.4)
    assert core.belief.sum() == pytest.approx(0.6)


@pytest.mark.parametrize('changes, message', [
    ({'motion_sigma_cells': -0.5}, r'^motion.sigma_cells must be finite and >= 0'),
    ({'motion_jump_prob': 1.0}, r'^motion.jump_prob must be a probability in \[0, 1\)'),
    ({'absent_prior': 1.0}, r'^absent.prior must be a probability in \[0, 1\)'),
    ({'absent_prior': -0.1}, r'^absent.prior must be a probability in \[0, 1\)'),
    ({'max_fixations': -2}, r'^search.max_fixations must be an integer >= 0'),
])
def test_bad_settings_are_refused_with_their_reason(changes, message):
    core = controller()
    before = core.settings
    with pytest.raises(ValueError, match=message):
        core.configure(replace(core.settings, **changes))
    assert core.settings is before


def test_a_decision_the_budget_forced_says_so():
    """Issue 35: found at the budget (decide_at_budget) carries the limit that forced it."""
    core = controller(confidence=0.999, max_fixations=1, decide_at_budget=True)
    result = core.offer(frame_at(core, GRID.center_index, strength=1.0), 1.0)
    assert result.found is not None and result.found.forced_by == 'budget'
    assert result.found.probability < 0.999
    confident = controller(confidence=0.95)
    result = confident.offer(frame_at(confident, GRID.center_index, strength=10.0), 1.0)
    assert result.found is not None and result.found.forced_by == ''
