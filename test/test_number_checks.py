# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""A number given as text ('0.5') or as true/false is refused by the researcher API too."""
from ipomdp_gaze.model.belief import check_prior
from ipomdp_gaze.model.false_alarms import check_false_alarm_scales
from ipomdp_gaze.model.fpoc import make_fpoc, TableFPOC
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import PinholeCamera
from ipomdp_gaze.model.motion import Motion, VelocityMotion
from ipomdp_gaze.model.occupancy import prior_log_odds
from ipomdp_gaze.model.position_filter import PositionFilter, walk_filter
from ipomdp_gaze.model.stopping import first_decisions, initial_log_belief
from ipomdp_gaze.search.session import SearchSettings
import numpy as np
import pytest

GRID = Grid(3, 3)

# (what is built, the argument's name in the message); each gets a text and a bool value.
CALLS = [
    (lambda v: Motion(GRID, sigma_cells=v), 'sigma_cells'),
    (lambda v: Motion(GRID, jump_prob=v), 'jump_prob'),
    (lambda v: Motion(GRID, leave_prob=v), 'leave_prob'),
    (lambda v: VelocityMotion(GRID, max_speed_cells=v), 'max_speed_cells'),
    (lambda v: VelocityMotion(GRID, max_speed_cells=1.0, turn_prob=v), 'turn_prob'),
    (lambda v: VelocityMotion(GRID, max_speed_cells=1.0, speed_cells=v), 'speed_cells'),
    (lambda v: initial_log_belief(9, v), 'absent_prior'),
    (lambda v: first_decisions(np.zeros((1, 2)), np.zeros((1, 2)), v), 'confidence'),
    (lambda v: make_fpoc('human', foveal_dprime=v), 'foveal_dprime'),
    (lambda v: make_fpoc('human', noise_contrast=v), 'noise_contrast'),
    (lambda v: make_fpoc('exponential', scale_deg=v), 'scale_deg'),
    (lambda v: make_fpoc('camera', dprime=v), 'dprime'),
    (lambda v: prior_log_odds(9, v), 'q'),
    (lambda v: PinholeCamera(4, 4, v, 1.0, 1.5, 1.5), 'camera fx'),
    (lambda v: PinholeCamera.from_fov(4, 4, v), 'hfov_deg'),
    (lambda v: PositionFilter(v, 0.1), 'measurement_sigma_cells'),
    (lambda v: PositionFilter(0.5, v), 'accel_density'),
    (lambda v: PositionFilter(0.5, 0.1, sigma_cells=v), 'sigma_cells'),
    (lambda v: walk_filter(0.5, v), 'turn_prob'),
    (lambda v: walk_filter(0.5, 0.3, speed_cells=v), 'speed_cells'),
]


@pytest.mark.parametrize('value', ['0.5', True, np.True_])
@pytest.mark.parametrize('call, name', CALLS, ids=[name for _, name in CALLS])
def test_a_number_as_text_or_a_bool_is_refused_naming_the_argument(call, name, value):
    with pytest.raises(ValueError, match=f'^{name} must be a number, got {value!r}$'):
        call(value)


@pytest.mark.parametrize('call, name', CALLS, ids=[name for _, name in CALLS])
def test_a_number_is_still_taken_numpy_scalars_too(call, name):
    call(np.float64(0.5))
    call(0.5)


@pytest.mark.parametrize('values', [['0.5', '0.5'], [True, False], np.array(['1', '0'])])
def test_a_prior_of_text_or_bools_is_refused(values):
    with pytest.raises(ValueError, match='^prior must be numbers, one per cell, got '):
        check_prior(values, 2)


@pytest.mark.parametrize('kwargs, name', [({'ecc_deg': ['0', '1']}, 'ecc_deg'),
                                          ({'dprime': [True, False]}, 'dprime')])
def test_a_table_fpoc_of_text_or_bools_is_refused(kwargs, name):
    with pytest.raises(ValueError, match=f'^{name} must be a list of numbers, got '):
        TableFPOC(**kwargs)


@pytest.mark.parametrize('build', [lambda: Grid(3, 3, '1.5'), lambda: Grid(3, 3, True)])
def test_a_grid_spacing_as_text_or_a_bool_is_refused(build):
    with pytest.raises(ValueError, match='^spacing_deg must be a positive finite number'):
        build()


@pytest.mark.parametrize('scales', ['2', ['1', '2'], [1.0, True]])
def test_false_alarm_scales_as_text_or_bools_are_refused(scales):
    with pytest.raises(ValueError, match='^false_alarm_scales must be 1 to'):
        check_false_alarm_scales(scales)


def test_the_settings_and_the_checks_share_one_rule():
    """The schema's Python check and the model's give the same line for the same value."""
    with pytest.raises(ValueError, match=r"^confidence must be a number, got '0.9'$"):
        SearchSettings(confidence='0.9')
    with pytest.raises(ValueError, match=r"^confidence must be a number, got '0.9'$"):
        first_decisions(np.zeros((1, 2)), np.zeros((1, 2)), '0.9')
