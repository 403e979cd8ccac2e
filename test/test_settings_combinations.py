# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Any settings the schema accepts run a search: no combination raises past the settings check.

A user can set every parameter of the node or the YAML at once, and change one while a search
runs. Each example draws a model (both pan/tilt lenses and the fovea), a policy and a value for
each of a random subset of the settings; the settings object either refuses them with a
``ValueError`` (its one line) or the session (one target or many) starts, applies frames of
random counts, unobserved cells, grouped detections and detection offsets, takes a run-time
change, and keeps a normalised belief whose answer is a cell. ``start_cell: policy`` with
head time in the choice raised ``TypeError`` before this test (the first view was timed from no
fixation).
"""
from __future__ import annotations

import os
import warnings

from hypothesis import event, given, HealthCheck, settings
from hypothesis import strategies as st
from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.session import Frame, OrderError, SearchSession, SearchSettings
import numpy as np

# A few ms each: eight times the property tests' examples (a combination of four settings is
# drawn about once in a hundred).
EXAMPLES = 8 * int(os.environ.get('PROPERTY_EXAMPLES', '40'))
MODELS = ('faces-pan-tilt-profile', 'faces-pan-tilt-40-profile', 'faces-420')
POLICIES = ('elm', 'coverage', 'sweep', 'map', 'random', 'center', 'spiral')
# Values per setting: the default's neighbours that the shipped configurations and the docs use.
VALUES = {
    'confidence': [0.9, 0.99, 0.999], 'max_fixations': [0, 3, 20],
    'inhibit_return': [False, True], 'stop_on_repeat': [False, True],
    'repeat_weight': [1.0, 0.3, 0.0], 'head_speed_deg_s': [0.0, 120.0],
    'view_time_s': [0.15, 0.4], 'head_tour': [False, True], 'absent_prior': [0.0, 0.5, 0.8],
    'motion_sigma_cells': [0.0, 0.5], 'motion_jump_prob': [0.0, 0.05],
    'motion_leave_prob': [0.0, 0.05], 'motion_max_speed_cells': [0.0, 1.0],
    'motion_speed_cells': [0.0, 0.5], 'motion_turn_prob': [0.0, 0.2],
    'motion_track_view': ['policy', 'peak', 'position'], 'motion_lead_s': [0.0, 0.3],
    'motion_keep_probability': [0.0, 0.5], 'start_cell': [None, 'policy', (0, 0)],
    'scan': [True, False], 'found_radius': [0, 1, 2], 'stop_on_decision': [True, False],
    'decide_at_budget': [False, True], 'group_stop': [False, True],
    'group_probability': [0.0, 0.05], 'absent_needs_coverage': [False, True],
    'false_alarm_scales': [(1.0,), (0.5, 1.0, 4.0)], 'hotspot_prior': [0.0, 0.03],
    'targets': ['one', 'many'],
}
LOADED = {name: load_observation(name) for name in MODELS}


def _choices(draw):
    return {key: draw(st.sampled_from(values)) for key, values in VALUES.items()
            if draw(st.booleans())}


@settings(deadline=None, max_examples=EXAMPLES, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), seed=st.integers(0, 2**31 - 1))
def test_accepted_settings_run_a_search_and_take_a_change(data, seed):
    model = LOADED[data.draw(st.sampled_from(MODELS))]
    grid = model.grid
    chosen = _choices(data.draw)
    try:
        configured = SearchSettings(**chosen)
    except ValueError as e:
        assert str(e) and '\n' not in str(e)
        return
    many = configured.targets == 'many'
    event(f'built {configured.targets}')
    try:
        if many:
            session = OccupancySession(grid, model, configured)
        else:
            policy = build_policy(data.draw(st.sampled_from(POLICIES)), grid, model)
            session = SearchSession(grid, model, policy, configured)
    except ValueError as e:                 # e.g. many with the one-target evidence options
        assert str(e) and '\n' not in str(e)
        return
    rng = np.random.default_rng(seed)
    change_at = int(rng.integers(0, 8))
    with warnings.catch_warnings():
        warnings.simplefilter('error', RuntimeWarning)
        session.reset(seed=seed)
        session.start()
        for k in range(12):
            counts = rng.poisson(rng.choice([0.05, 0.5, 3.0]), grid.n_cells).astype(float)
            counts[rng.random(grid.n_cells) < 0.2 * rng.random()] = np.nan
            groups = (rng.random(grid.n_cells) < 0.02).astype(float) if k % 2 else None
            offsets = None
            if k % 3 == 1:                    # where in its cell each cell's detections lie
                offsets = rng.uniform(-0.5, 0.5, (grid.n_cells, 2))
                offsets[rng.random(grid.n_cells) < 0.5] = np.nan
            try:
                result = session.update(Frame(counts, groups=groups, seconds=0.1,
                                              offsets=offsets))
            except OrderError:                # the search ended: nothing more to apply
                break
            if k == change_at:
                changed = dict(chosen, **_choices(data.draw))
                changed['targets'] = configured.targets
                try:
                    session.configure(SearchSettings(**changed))
                except ValueError as e:
                    assert str(e) and '\n' not in str(e)
            if getattr(result, 'ended', False):
                break
        belief = np.asarray(session.belief)
    assert np.all(np.isfinite(belief)) and np.all(belief >= 0)
    if not many:
        assert abs(belief.sum() + session.absent_probability - 1.0) < 1e-9
        assert 0 <= session.map_cell < grid.n_cells
