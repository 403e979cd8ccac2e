# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The tracking configuration's motion is the calibration on training walks, not a hand pick."""
from ipomdp_gaze.drivers.tracking import calibrate_position_sigma, walk_settings
from ipomdp_gaze.vision.walks import calibrate_motion
import pytest


def test_the_shipped_motion_is_the_calibration_of_training_walks():
    settings, policy, _ = walk_settings()
    fit = calibrate_motion('train', scenes=200)
    assert settings.motion_sigma_cells == pytest.approx(fit['velocity_sigma_cells'], abs=0.005)
    assert settings.motion_max_speed_cells == pytest.approx(fit['max_speed_cells'], abs=0.05)
    assert settings.motion_speed_cells == pytest.approx(fit['speed_cells'], abs=0.005)
    assert settings.motion_turn_prob == pytest.approx(fit['turn_prob'], abs=0.005)
    assert settings.motion_leave_prob == pytest.approx(fit['return_prob'], abs=0.005)
    assert settings.motion_track_view == 'position' and settings.max_fixations == 0
    assert policy == 'coverage'


def test_the_shipped_position_noise_is_the_calibration_of_training_walks():
    """
    ``motion.position_sigma_cells`` is 100 training walks' root mean square error (0.139).

    Recomputed here on the first 30 of them (120 views); the errors have heavy tails, so the
    tolerance is three standard errors of that smaller sample's estimate (about 0.07).
    """
    settings, _, _ = walk_settings()
    fit = calibrate_position_sigma('train', scenes=30)
    assert fit['views'] == 120 and fit['measured'] >= 108
    assert abs(settings.motion_position_sigma_cells - fit['sigma_cells']) <= 3 * fit['se_cells']
    assert max(abs(b) for b in fit['bias_cells']) < 0.1
