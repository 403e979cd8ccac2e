# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The settings schema is the one description of every search setting.

The settings object, the node's parameter declarations, the CLI flags and the YAML check are
generated from :data:`ipomdp_gaze.search.settings.SCHEMA`: a setting added there appears in all
four
with no other edit, and each refuses a bad value with the same message.
"""
from __future__ import annotations

import argparse
from dataclasses import fields, replace
import pickle
import re

from conftest import REPO
from ipomdp_gaze.commands.search_args import add_search_args, settings_from_args
from ipomdp_gaze.files.yaml_files import yaml_parameters
from ipomdp_gaze.model.checks import check_sigma_cells
from ipomdp_gaze.search.session import PARAMETER_NAMES, SearchSettings
from ipomdp_gaze.search.settings import check_parameters, SCHEMA, Setting, settings_class
import numpy as np
import pytest

NEW = Setting('dwell_s', 'search.dwell_s', 'float', 1.5, check_sigma_cells,
              'seconds each found person is kept in view', bounds='>= 0', metavar='S')
EXTENDED = SCHEMA + (NEW,)
Extended = settings_class(EXTENDED, name='Extended', module=__name__)


def test_the_settings_object_has_one_field_per_setting_in_schema_order():
    assert [f.name for f in fields(SearchSettings)] == [s.key for s in SCHEMA]
    assert PARAMETER_NAMES == {s.key: s.parameter for s in SCHEMA}
    defaults = SearchSettings()
    for s in SCHEMA:
        assert getattr(defaults, s.key) == s.default, s.key


def test_the_settings_object_is_frozen_and_pickles_across_processes():
    settings = SearchSettings(confidence=0.99, false_alarm_scales=[2.0, 1.0])
    assert settings.false_alarm_scales == (1.0, 2.0)
    with pytest.raises(AttributeError):
        settings.confidence = 0.5
    assert pickle.loads(pickle.dumps(settings)) == settings
    assert replace(settings, max_fixations=3).max_fixations == 3


def test_an_added_setting_is_a_checked_field():
    assert Extended().dwell_s == 1.5
    assert Extended(dwell_s=2).dwell_s == 2.0
    with pytest.raises(ValueError, match=r'^search.dwell_s must be finite and >= 0, got -1'):
        Extended(dwell_s=-1)
    assert Extended.from_parameters({'search.dwell_s': 3.0}).dwell_s == 3.0
    assert Extended(dwell_s=4.0).to_parameters()['search.dwell_s'] == 4.0


def test_an_added_setting_is_a_cli_flag_with_the_same_check():
    parser = argparse.ArgumentParser()
    add_search_args(parser, Extended(), ('confidence', 'dwell_s'), schema=EXTENDED)
    assert 'seconds each found person is kept in view, >= 0' in parser.format_help()
    args = parser.parse_args(['--dwell-s', '2.5', '--confidence', '0.9'])
    settings = settings_from_args(args, Extended(), schema=EXTENDED)
    assert (settings.dwell_s, settings.confidence) == (2.5, 0.9)
    args = parser.parse_args(['--dwell-s', '-2'])
    with pytest.raises(ValueError, match=r'^search.dwell_s must be finite and >= 0, got -2.0'):
        settings_from_args(args, Extended(), schema=EXTENDED)


def test_an_added_setting_is_checked_in_yaml():
    assert check_parameters({'search.dwell_s': 2.0}, Extended).dwell_s == 2.0
    with pytest.raises(ValueError, match=r"^my.yaml: search.dwell_s must be a number, got 'x'"):
        check_parameters({'search.dwell_s': 'x'}, Extended, where='my.yaml: ')
    with pytest.raises(ValueError, match=r'search.dwell_s must be finite and >= 0, got -3'):
        check_parameters({'search.dwell_s': -3}, Extended)
    # Without the setting the name is a typo in the search namespace.
    with pytest.raises(ValueError, match=r"unknown search parameter 'search.dwell_s'"):
        check_parameters({'search.dwell_s': 2.0})


@pytest.mark.ros
def test_an_added_setting_is_a_node_parameter():
    from ipomdp_gaze.nodes.params import search_params
    from rclpy.parameter import Parameter
    declared = {p.name: p for p in search_params(EXTENDED)}
    param = declared['search.dwell_s']
    assert (param.default, param.ptype) == (1.5, Parameter.Type.DOUBLE)
    assert param.description == 'seconds each found person is kept in view, >= 0'


@pytest.mark.ros
def test_the_controller_declares_every_setting_from_the_schema():
    from ipomdp_gaze.nodes.controller import controller_params
    from ipomdp_gaze.nodes.params import search_params
    declared = {p.name: p for p in controller_params()}
    for param in search_params():
        assert declared[param.name] == param
    assert {'start_row', 'start_col'} <= set(declared)       # the start cell, as two integers
    names = {s.parameter for s in SCHEMA if s.kind != 'cell'}
    assert names <= set(declared)


@pytest.mark.parametrize('kind, value, message', [
    ('int', 2.5, 'search.max_fixations must be an integer, got 2.5'),
    ('bool', 1, 'search.inhibit_return must be true or false, got 1'),
    ('floats', 2.0, 'search.false_alarm_scales must be a list of numbers, got 2.0'),
])
def test_yaml_values_of_the_wrong_kind_are_refused(kind, value, message):
    name = next(s.parameter for s in SCHEMA if s.kind == kind)
    with pytest.raises(ValueError, match=message.replace('.', r'\.')):
        check_parameters({name: value})


FLOATS = [s for s in SCHEMA if s.kind == 'float']


@pytest.mark.parametrize('setting', FLOATS, ids=[s.key for s in FLOATS])
def test_a_number_given_from_python_as_a_string_or_a_bool_is_refused_as_in_yaml(setting):
    """
    QA: SearchSettings(confidence='0.9') was taken, float() in the checks read the string.

    A float setting from Python refuses a string and a bool (numpy's too) with the message
    of the YAML check, which refuses YAML's '0.9' and true so; numbers, numpy's too, pass.
    """
    text = str(setting.default)
    for value in (text, True, np.bool_(False)):
        message = f'{setting.parameter} must be a number, got {value!r}'
        with pytest.raises(ValueError, match=f'^{re.escape(message)}$'):
            SearchSettings(**{setting.key: value})
    with pytest.raises(ValueError, match=re.escape(f'{setting.parameter} must be a number, '
                                                   'got True')):
        check_parameters({setting.parameter: True})
    for number in (setting.default, np.float64(setting.default)):
        value = getattr(SearchSettings(**{setting.key: number}), setting.key)
        assert value == setting.default and type(value) is float


@pytest.mark.parametrize('value', ['2', '12', [True], ['2.0'], (1.0, '2')])
def test_a_list_of_numbers_given_from_python_as_strings_or_bools_is_refused(value):
    """QA: false_alarm_scales='2' was the factor 2 ('12': 1 and 2), [True] the factor 1."""
    message = f'search.false_alarm_scales must be a list of numbers, got {value!r}'
    with pytest.raises(ValueError, match=f'^{re.escape(message)}$'):
        SearchSettings(false_alarm_scales=value)
    assert SearchSettings(false_alarm_scales=np.array([2.0, 1.0])).false_alarm_scales == \
        (1.0, 2.0)
    assert SearchSettings(false_alarm_scales=[np.int64(4), 2]).false_alarm_scales == (2.0, 4.0)


def test_a_typo_in_a_settings_namespace_is_refused_other_parameters_pass():
    with pytest.raises(ValueError, match=r"unknown search parameter 'search.max_fixation'"):
        check_parameters({'search.max_fixation': 5})
    settings = check_parameters({'grid.rows': 11, 'policy.name': 'elm', 'confidence': 0.9})
    assert settings.confidence == 0.9


# A controller file given after another (a second --params-file, as its header says).
OVERLAYS = {'faces_camera_room_controller.yaml': 'faces_camera_controller.yaml',
            'faces_camera_people.yaml': 'faces_camera_tracking.yaml'}
CONTROLLER_FILES = sorted(path.name for path in (REPO / 'config').glob('*.yaml')
                          if '/**/gaze_controller:' in path.read_text())


def test_the_yaml_check_covers_every_shipped_controller_file():
    assert {'controller.yaml', 'faces_camera_controller.yaml', 'faces_camera_tracking.yaml',
            'faces_fovea_controller.yaml', *OVERLAYS} <= set(CONTROLLER_FILES)
    for overlay, base in OVERLAYS.items():
        assert base in CONTROLLER_FILES and base not in OVERLAYS
        assert base in (REPO / 'config' / overlay).read_text().split('/**/')[0], overlay


@pytest.mark.parametrize('name', CONTROLLER_FILES)
def test_every_shipped_controller_file_passes_the_yaml_check(name):
    values = yaml_parameters(REPO / 'config' / name, 'gaze_controller')
    if name in OVERLAYS:
        base = yaml_parameters(REPO / 'config' / OVERLAYS[name], 'gaze_controller')
        values = {**base, **values}
    settings = check_parameters(values, where=f'{name}: ')
    for s in SCHEMA:
        if s.parameter in values:
            expected = values[s.parameter]
            got = getattr(settings, s.key)
            assert (list(got) if isinstance(got, tuple) else got) == \
                (sorted(expected) if s.kind == 'floats' else expected), s.parameter


@pytest.mark.parametrize('key, value, message', [
    ('motion_lead_s', 1e6, r'motion.lead_s must be at most 60 s'),
    ('motion_lead_s', -0.1, r'motion.lead_s must be finite and >= 0'),
    ('motion_dwell_s', 1e6, r'motion.dwell_s must be at most 86400 s \(a day\)'),
    ('motion_dwell_s', 0.0, r'motion.dwell_s must be finite and > 0'),
])
def test_motion_durations_have_an_upper_bound(key, value, message):
    """QA: a lead of 1e6 s sent the head to the grid's corner; a dwell of 1e6 s was taken."""
    with pytest.raises(ValueError, match=message):
        SearchSettings(**{key: value})
    assert getattr(SearchSettings(**{key: 60.0 if key == 'motion_lead_s' else 86400.0}),
                   key) in (60.0, 86400.0)


@pytest.mark.parametrize('changes, message', [
    ({'found_radius': 6}, 'search.found_radius must be an integer from 0 to 5'),
    ({'found_radius': -1}, 'search.found_radius must be an integer from 0 to 5'),
    ({'start_cell': (0, -1)}, r'start_cell must be \(row, col\) with row, col >= 0'),
    ({'start_cell': (-1, 0)}, r'start_cell must be \(row, col\) with row, col >= 0'),
])
def test_the_bounds_of_cell_settings_are_refused_on_both_sides(changes, message):
    with pytest.raises(ValueError, match=message):
        SearchSettings(**changes)


def test_the_edges_of_cell_settings_and_numpy_booleans_are_accepted():
    settings = SearchSettings(found_radius=5, start_cell=(0, 0), inhibit_return=np.True_,
                              stop_on_repeat=np.False_)
    assert settings.found_radius == 5 and settings.start_cell == (0, 0)
    assert settings.inhibit_return is True and settings.stop_on_repeat is False


def test_each_interval_is_what_its_settings_check_takes():
    """The interval (help, the node's descriptor range) and the check must not drift apart."""
    import math
    ranged = [s for s in SCHEMA if s.interval is not None]
    assert {s.parameter for s in ranged} >= {'confidence', 'search.found_radius',
                                             'search.max_fixations', 'motion.dwell_s'}
    for s in ranged:
        iv, whole = s.interval, s.kind == 'int'
        for end, is_open, outward in ((iv.low, iv.low_open, -math.inf),
                                      (iv.high, iv.high_open, math.inf)):
            if end is None:                      # no bound: any finite number, not infinity
                s.check(10 ** 12 if whole else math.copysign(1e12, outward), s.parameter)
                if not whole:
                    with pytest.raises(ValueError, match=s.parameter):
                        s.check(outward, s.parameter)
                continue
            if is_open:
                with pytest.raises(ValueError, match=s.parameter):
                    s.check(float(end), s.parameter)
                s.check(math.nextafter(end, -outward), s.parameter)
            else:
                s.check(int(end) if whole else float(end), s.parameter)
            beyond = int(end) + int(math.copysign(1, outward)) if whole else \
                math.nextafter(end, outward)
            with pytest.raises(ValueError, match=s.parameter):
                s.check(beyond, s.parameter)
        with pytest.raises(ValueError, match=s.parameter):
            s.check(math.nan, s.parameter)
    assert SCHEMA[0].help_text.endswith(', in (0, 1)')
    assert next(s for s in SCHEMA if s.key == 'max_fixations').help_text.endswith(
        ', >= 0 (0: none)')
    assert next(s for s in SCHEMA if s.key == 'found_radius').help_text.endswith(', 0 to 5')


def test_an_interval_is_for_numbers_with_closed_integer_ends():
    from ipomdp_gaze.search.settings import Interval
    with pytest.raises(ValueError, match='an interval is for a float or an int with closed'):
        Setting('x', 'search.x', 'int', 1, check_sigma_cells, 'x',
                interval=Interval(0, low_open=True))
    with pytest.raises(ValueError, match='an interval is for a float or an int'):
        Setting('x', 'search.x', 'str', 'a', check_sigma_cells, 'x', interval=Interval(0))
