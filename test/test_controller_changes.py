# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A run-time parameter change the controller's check accepts is one it can apply.

The node checks a change by building the whole configuration (``build_config``, in its set
callback) and applies it afterwards (``follow_config``, post-set); an error while applying
leaves the node half changed with the change already reported as taken. Each example starts
the controller core from a shipped parameter file, searches a few frames, draws a change of
several parameters (the model, the policy, the search settings, many targets), and either the
check refuses it in one line or it applies and the search goes on. ``search.false_alarm_scales``
on a Gaussian model was accepted and then raised while being applied, before this test.
"""
from __future__ import annotations

import os

from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.files.yaml_files import yaml_parameters
from ipomdp_gaze.nodes.controller import controller_params
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.controller_config import build_config, follow_config
import numpy as np
import pytest

pytestmark = pytest.mark.ros                # controller_params declares rclpy parameter types

EXAMPLES = 4 * int(os.environ.get('PROPERTY_EXAMPLES', '40'))
BASES = {
    'defaults': (),
    'faces camera': ('faces_camera_controller.yaml',),
    'rooms': ('faces_camera_controller.yaml', 'faces_camera_room_controller.yaml'),
    'tracking': ('faces_camera_tracking.yaml',),
}
CHANGES = {
    'observation.model': ['gaussian', 'counts'],
    'observation.file': ['', 'faces-pan-tilt-profile', 'faces-pan-tilt-40-profile'],
    'fpoc.model': ['camera', 'human'],
    'policy.name': ['elm', 'coverage', 'sweep', 'map', 'greedy', 'nmpt'],
    'confidence': [0.9, 0.99], 'search.max_fixations': [0, 5, 20],
    'search.inhibit_return': [False, True], 'search.repeat_weight': [1.0, 0.1],
    'search.head_speed_deg_s': [0.0, 120.0], 'search.head_tour': [False, True],
    'absent.prior': [0.0, 0.8], 'motion.sigma_cells': [0.0, 0.5],
    'motion.track_view': ['policy', 'peak', 'position'], 'start_row': [-1, 0],
    'start_col': [-1, 3], 'search.found_radius': [0, 1], 'search.decide_at_budget': [False, True],
    'search.group_stop': [False, True], 'search.absent_needs_coverage': [False, True],
    'search.false_alarm_scales': [[1.0], [0.5, 1.0, 4.0]], 'search.hotspot_prior': [0.0, 0.03],
    'search.targets': ['one', 'many'], 'search.stop_on_decision': [True, False],
    'belief.prior': [[], [1.0] * 60 + [0.0] + [2.0] * 60],
}
DEFAULTS = {p.name: p.default for p in controller_params()}


def _values(base: str) -> dict:
    values = dict(DEFAULTS)
    for name in BASES[base]:
        values.update(yaml_parameters(config_file(name), 'gaze_controller'))
    return values


def _frames(core, rng, count: int, t_s: float, counts: bool) -> float:
    for _ in range(count):
        t_s += 1.0
        n = core.grid.n_cells
        evidence = rng.poisson(0.3, n).astype(float) if counts else rng.standard_normal(n)
        core.offer(evidence, t_s, t_s)
    return t_s


@settings(deadline=None, max_examples=EXAMPLES, suppress_health_check=[HealthCheck.too_slow])
@given(base=st.sampled_from(sorted(BASES)), data=st.data(), seed=st.integers(0, 2**31 - 1))
def test_a_change_the_check_accepts_applies(base, data, seed):
    values = _values(base)
    old = build_config(values, build_policy)
    core = old.controller()
    rng = np.random.default_rng(seed)
    core.reset(0.0)
    t_s = _frames(core, rng, 3, 0.0, values['observation.model'] == 'counts')
    change = {k: data.draw(st.sampled_from(v)) for k, v in CHANGES.items()
              if data.draw(st.booleans())}
    new_values = dict(values, **change)
    try:
        new = build_config(new_values, build_policy, set(change), old)
    except ValueError as e:
        assert str(e) and '\n' not in str(e)
        return
    follow_config(core, new, old.values)
    _frames(core, rng, 4, t_s, new_values['observation.model'] == 'counts')
    assert 0 <= core.fixation < core.grid.n_cells


def test_a_policy_change_during_a_rooms_pass_keeps_the_pass():
    """The pass is the search's own: a new policy applies from the next search."""
    values = _values('rooms')
    old = build_config(values, build_policy)
    core = old.controller()
    rng = np.random.default_rng(0)
    core.reset(0.0)
    poses = list(core.session._s()['pass'])
    t_s = _frames(core, rng, 3, 0.0, True)
    new = build_config(dict(values, **{'policy.name': 'elm'}), build_policy, {'policy.name'}, old)
    follow_config(core, new, old.values)
    _frames(core, rng, len(poses) - 3, t_s, True)
    assert list(core.session.path) == poses and core.session.ended


def test_counts_with_scales_to_a_gaussian_model_applies_in_one_change():
    """The model is checked against the settings that come with it, not those in force."""
    values = _values('faces camera')
    assert len(values['search.false_alarm_scales']) > 1
    old = build_config(values, build_policy)
    core = old.controller()
    change = {'observation.model': 'gaussian', 'observation.file': '',
              'search.false_alarm_scales': [1.0], 'search.hotspot_prior': 0.0}
    new = build_config(dict(values, **change), build_policy, set(change), old)
    follow_config(core, new, old.values)
    assert core.settings.false_alarm_scales == (1.0,)
    assert type(core.observation).__name__ == 'GaussianObservation'


def test_a_prior_follows_into_the_next_search_and_out_of_many_targets():
    """belief.prior: the next reset starts there; a switch to many targets drops it first."""
    values = _values('defaults')
    weights = np.arange(121, dtype=float)
    old = build_config(values, build_policy)
    core = old.controller()
    core.reset(0.0)
    _frames(core, np.random.default_rng(1), 2, 0.0, False)
    under_way = core.belief
    prior = build_config(dict(values, **{'belief.prior': list(weights)}), build_policy,
                         {'belief.prior'}, old)
    np.testing.assert_allclose(prior.prior, weights / weights.sum())
    follow_config(core, prior, old.values)
    np.testing.assert_array_equal(core.belief, under_way)          # from the next reset on
    core.reset(3.0)
    absent = values['absent.prior']
    np.testing.assert_allclose(core.belief, (1 - absent) * weights / weights.sum(), atol=1e-15)
    many = dict(prior.values, **{'search.targets': 'many', 'belief.prior': []})
    follow_config(core, build_config(many, build_policy, {'search.targets', 'belief.prior'},
                                     prior), prior.values)
    assert core.settings.targets == 'many' and core.prior is None
    with pytest.raises(ValueError, match=r"a prior over one target's cell \(belief.prior\) "
                                         'does not go with search.targets many'):
        build_config(dict(many, **{'belief.prior': list(weights)}), build_policy,
                     {'belief.prior'}, prior)
    for bad, message in (([1.0] * 120, 'belief.prior must hold one weight per cell, 121 values '
                                       'for a 11x11 grid'),
                         ([0.0] * 121, r'belief.prior weights must not all be 0 \(the target')):
        with pytest.raises(ValueError, match=message):
            build_config(dict(values, **{'belief.prior': bad}), build_policy)


def test_a_prior_given_with_a_switch_to_one_target_starts_the_new_search():
    """Many targets to one with belief.prior in one set: the search begun at once is at it."""
    values = _values('rooms')
    old = build_config(values, build_policy)
    core = old.controller()
    core.reset(0.0)
    _frames(core, np.random.default_rng(2), 2, 0.0, True)
    weights = np.arange(121, dtype=float)
    change = {'search.targets': 'one', 'belief.prior': list(weights)}
    new = build_config(dict(values, **change), build_policy, set(change), old)
    follow_config(core, new, old.values)
    assert core.settings.targets == 'one'
    absent = values['absent.prior']
    np.testing.assert_allclose(core.belief, (1 - absent) * weights / weights.sum(), atol=1e-15)


@pytest.mark.parametrize('change', [
    {'motion.position_sigma_cells': 1e308}, {'motion.sigma_cells': 1e200},
    {'motion.speed_cells': 1e200}, {'motion.max_speed_cells': 1e308}])
def test_a_huge_motion_length_is_applied_not_an_overflow(change):
    """
    QA: ``motion.position_sigma_cells`` 1e308 passed the check, then applying it overflowed.

    The position filter squared it (an OverflowError after the change was reported taken);
    ``motion.max_speed_cells`` 1e308 made a NaN belief. Every finite length applies.
    """
    values = dict(_values('tracking'), **{'motion.track_view': 'position'})
    old = build_config(values, build_policy)
    core = old.controller()
    rng = np.random.default_rng(0)
    core.reset(0.0)
    t_s = _frames(core, rng, 3, 0.0, True)
    new = build_config(dict(values, **change), build_policy, set(change), old)
    follow_config(core, new, old.values)
    _frames(core, rng, 4, t_s, True)
    assert 0 <= core.fixation < core.grid.n_cells
    assert not np.isnan(core.session.log_belief).any()


def test_a_table_fpoc_of_another_length_names_the_nodes_default():
    """
    QA: ``fpoc.model table`` with three ``fpoc.dprime`` named the Python class's default.

    The refusal said ``a value not given is its default: ecc_deg [0.0, 1.0]``; the node's
    default ``fpoc.ecc_deg`` is ``[0.0, 10.0]``, the one it used.
    """
    values = dict(DEFAULTS, **{'fpoc.model': 'table', 'fpoc.dprime': [1.0, 2.0, 3.0]})
    assert DEFAULTS['fpoc.ecc_deg'] == [0.0, 10.0]
    with pytest.raises(ValueError) as info:
        build_config(values, build_policy)
    assert str(info.value) == (
        'the table FPOC needs fpoc.ecc_deg and fpoc.dprime non-empty and of equal length, got '
        '2 fpoc.ecc_deg [0.0, 10.0] and 3 fpoc.dprime [1.0, 2.0, 3.0] (fpoc.ecc_deg not given '
        'is its default, [0.0, 10.0])')
    table = build_config(dict(values, **{'fpoc.dprime': [4.0, 1.0]}), build_policy)
    assert table.controller().session is not None


def test_the_label_of_a_many_target_search_names_the_policy_it_follows():
    """The log and /diagnostics named a policy the occupancy search does not run."""
    values = dict(DEFAULTS, **{'search.targets': 'many', 'policy.name': 'map'})
    assert build_config(values, build_policy).policy_label == \
        'occupancy infomax (policy.name map is not used with many targets)'
    room = _values('rooms')
    assert room['policy.name'] == 'sweep'
    assert build_config(room, build_policy).policy_label == 'sweep'
    walking = dict(room, **{'motion.sigma_cells': 0.5})          # a moving search makes no pass
    assert build_config(walking, build_policy).policy_label.startswith('occupancy infomax')
    one = dict(values, **{'search.targets': 'one'})
    assert build_config(one, build_policy).policy_label == 'map'


@pytest.mark.parametrize('name', ['greedy', 'tempered', 'switching'])
def test_a_policy_many_targets_do_not_use_is_not_refused_for_its_model(name):
    """
    QA: ``policy.name greedy`` was refused with ``search.targets many`` on the rooms' counts.

    Its reason (greedy needs the Gaussian model of an FPOC) is that of a policy the occupancy
    search does not use (docs/design.md section 11.6): it is kept unused, at start-up and by a
    change, and the search goes on; a switch to one target, which would use it, is refused.
    """
    room = _values('rooms')
    moving = dict(room, **{'policy.name': name, 'motion.sigma_cells': 0.5,
                           'motion.jump_prob': 0.01})
    cfg = build_config(moving, build_policy)
    assert cfg.policy is None and 'needs the Gaussian model of an FPOC' in cfg.policy_error
    assert cfg.policy_label == f'occupancy infomax (policy.name {name} is not used with many ' \
        'targets)'
    core = cfg.controller()
    core.reset(0.0)
    t_s = _frames(core, np.random.default_rng(3), 3, 0.0, True)
    still = build_config(room, build_policy)                 # the rooms' sweep, then greedy
    changed = build_config(dict(room, **{'policy.name': name}), build_policy, {'policy.name'},
                           still)
    assert changed.policy is None
    for change in ({'confidence': 0.9}, {'search.targets': 'one'}):
        values = dict(moving, **change)
        if 'search.targets' in change:
            with pytest.raises(ValueError, match='needs the Gaussian model of an FPOC, not a '
                                                 'count model'):
                build_config(values, build_policy, set(change), cfg)
            continue
        new = build_config(values, build_policy, set(change), cfg)
        follow_config(core, new, cfg.values)
        _frames(core, np.random.default_rng(4), 3, t_s, True)
        assert 0 <= core.fixation < core.grid.n_cells
