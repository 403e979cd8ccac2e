# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The tracking configuration's motion is the calibration on training walks, not a hand pick."""
from ipomdp_gaze.drivers.tracking import walk_settings
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
    assert settings.motion_track_view == 'peak' and settings.max_fixations == 0
    assert policy == 'coverage'
