# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ranges of the search settings in the controller's parameter descriptors.

``ros2 param describe`` and rqt show a parameter's range from its descriptor; the settings
schema's interval is that range (its closed hull: a ROS range is closed, and an open end is named
in the constraints). rclpy enforces a descriptor's range before the node's callbacks, so the
node asks the settings' check first: a refused value gets the settings' reason, and the range
never refuses a value the settings take.
"""
from __future__ import annotations

import math

from conftest import config_path, REPO, wait_for
import numpy as np
import pytest

pytestmark = pytest.mark.ros

NODE = 'gaze_controller'
INT64_MAX = 2 ** 63 - 1


def _ranged():
    from ipomdp_gaze.search.settings import SCHEMA
    return [s for s in SCHEMA if s.interval is not None]


@pytest.fixture(scope='module')
def controller(probe, launch):
    """Start a controller of the shipped face config (a count model); the test is ros2 param."""
    from ipomdp_gaze.harness.watch import LATCHED
    from sensor_msgs.msg import JointState
    target = probe.latest(JointState, 'pan_tilt', LATCHED)
    proc = launch('controller', ['--params-file', config_path('faces_camera_controller.yaml')])
    assert wait_for(lambda: target.count, 30), proc.output()     # sent once it is declared
    return proc


def _describe(probe, names) -> dict:
    """``{name: ParameterDescriptor}`` from the node's DescribeParameters, as ros2 param does."""
    from rcl_interfaces.srv import DescribeParameters
    response = probe.call(DescribeParameters, f'/{NODE}/describe_parameters',
                          DescribeParameters.Request(names=list(names)))
    return {d.name: d for d in response.descriptors}


def test_describe_shows_the_range_of_every_setting_with_an_interval(probe, controller):
    settings = _ranged()
    described = _describe(probe, [s.parameter for s in settings])
    assert set(described) == {s.parameter for s in settings}
    for s in settings:
        d = described[s.parameter]
        low, high = s.interval.closed_hull()
        if s.kind == 'int':
            assert not d.floating_point_range and len(d.integer_range) == 1, s.parameter
            r = d.integer_range[0]
            assert (r.from_value, r.to_value, r.step) == (
                low, INT64_MAX if high == math.inf else high, 1), s.parameter
        else:
            assert not d.integer_range and len(d.floating_point_range) == 1, s.parameter
            r = d.floating_point_range[0]
            assert (r.from_value, r.to_value, r.step) == (low, high, 0.0), s.parameter
        assert s.help_text == d.description
    exact = {name: (d.floating_point_range or d.integer_range)[0]
             for name, d in described.items()}
    assert (exact['confidence'].from_value, exact['confidence'].to_value) == (0.0, 1.0)
    assert (exact['search.found_radius'].from_value,
            exact['search.found_radius'].to_value) == (0, 5)
    assert (exact['motion.dwell_s'].from_value, exact['motion.dwell_s'].to_value) == (0.0,
                                                                                      86400.0)
    # An open end or a missing bound is said in the constraints: the range is the closed hull.
    assert described['confidence'].additional_constraints == \
        'in (0, 1): 0 excluded, 1 excluded'
    assert described['absent.prior'].additional_constraints == 'in [0, 1): 1 excluded'
    assert described['motion.sigma_cells'].additional_constraints == '>= 0: finite'
    assert described['search.hotspot_scale'].additional_constraints == \
        '> 1: 1 excluded, finite'
    assert described['search.repeat_weight'].additional_constraints == ''
    # Settings without an interval have no range.
    plain = _describe(probe, ['search.inhibit_return', 'search.targets',
                              'search.false_alarm_scales'])
    assert all(not d.floating_point_range and not d.integer_range for d in plain.values())


@pytest.mark.parametrize('name, value, reason', [
    # outside the range: rclpy would refuse with 'Parameter ... out of range Min: ...'
    ('confidence', 1.5, 'confidence must be between 0 and 1 (exclusive), got 1.5'),
    ('search.found_radius', 6, 'search.found_radius must be an integer from 0 to 5 (cells), '
                               'got 6'),
    ('search.max_fixations', -1, 'search.max_fixations must be an integer >= 0 (0: no budget), '
                                 'got -1'),
    ('motion.dwell_s', -2.0, 'motion.dwell_s must be finite and > 0, got -2.0'),
    ('search.hotspot_prior', math.nan, 'search.hotspot_prior must be in [0, 0.5] (0: no '
                                       'hotspots), got nan'),
    # an open end, inside the closed range: the settings' check refuses it
    ('confidence', 1.0, 'confidence must be between 0 and 1 (exclusive), got 1.0'),
    ('absent.prior', 1.0, 'absent.prior must be a probability in [0, 1), got 1.0'),
    ('search.hotspot_scale', 1.0, 'search.hotspot_scale must be a finite factor > 1 of the '
                                  "model's false-alarm rates, got 1.0"),
    ('motion.sigma_cells', math.inf, 'motion.sigma_cells must be finite and >= 0, got inf'),
])
def test_a_refused_value_gets_the_settings_reason(probe, controller, name, value, reason):
    before = probe.get_parameters(NODE, [name])
    result = probe.set_parameters(NODE, {name: value})[0]
    assert not result.successful
    assert result.reason == reason
    result = probe.set_parameters_atomically(NODE, {name: value})
    assert (result.successful, result.reason) == (False, reason)
    assert probe.get_parameters(NODE, [name]) == before


def test_values_the_settings_take_are_never_refused_by_the_range(probe, controller):
    """The ends that are closed, just inside those that are open, and far out when unbounded."""
    from rclpy.parameter import Parameter
    defaults = probe.get_parameters(NODE, [s.parameter for s in _ranged()])
    taken = []
    for s in _ranged():
        low, high = s.interval.closed_hull()
        if s.kind == 'int':
            values = [low, 10 ** 12 if high == math.inf else high]
        else:
            values = [math.nextafter(low, math.inf) if s.interval.low_open else float(low),
                      1e12 if high == math.inf else
                      math.nextafter(high, -math.inf) if s.interval.high_open else float(high)]
        for value in values:
            s.check(value, s.parameter)             # the settings take it
            result = probe.set_parameters(NODE, {s.parameter: value})[0]
            taken.append((s.parameter, value, result.successful, result.reason))
        probe.set_parameters(NODE, {s.parameter: defaults[s.parameter]})
    assert [t for t in taken if not t[2]] == []
    assert probe.get_parameters(NODE, [s.parameter for s in _ranged()]) == defaults
    # Whole numbers for a double array are taken as doubles (before any check of the type).
    scales = probe.get_parameters(NODE, ['search.false_alarm_scales'])
    result = probe.set_parameters(NODE, [Parameter('search.false_alarm_scales',
                                                   Parameter.Type.INTEGER_ARRAY, [1, 3])])[0]
    assert result.successful, result.reason
    assert probe.get_parameters(NODE, ['search.false_alarm_scales']) == {
        'search.false_alarm_scales': [1.0, 3.0]}
    assert probe.set_parameters(NODE, scales)[0].successful


def test_rclpy_itself_takes_the_settings_values_and_refuses_outside_the_range(context):
    """The descriptors alone (no callback of ours): rclpy's check agrees with the settings."""
    from ipomdp_gaze.nodes.params import search_params
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    node = Node('ranges_alone', context=context)
    try:
        for p in search_params():
            node.declare_parameter(p.name, p.default, p.descriptor())
        wrong = []
        for s in _ranged():
            low, high = s.interval.closed_hull()
            inside = [low, high] if s.kind == 'int' else [low, high, (low + high) / 2]
            inside = [v for v in inside if math.isfinite(v)] + (
                [10 ** 15] if s.kind == 'int' and high == math.inf else
                [1e300] if high == math.inf else [])
            kind = int if s.kind == 'int' else float
            for value in map(kind, inside):
                if not node.set_parameters([Parameter(s.parameter, value=value)])[0].successful:
                    wrong.append((s.parameter, value))
            outside = [low - 1] + ([high + 1] if math.isfinite(high) else [])
            for value in map(kind, outside):
                with pytest.raises(ValueError):
                    s.check(value, s.parameter)
                if node.set_parameters([Parameter(s.parameter, value=value)])[0].successful:
                    wrong.append((s.parameter, value))
        assert wrong == []
    finally:
        node.destroy_node()


@pytest.mark.parametrize('override, message', [
    ('confidence:=1.5', 'confidence must be between 0 and 1 (exclusive), got 1.5'),
    ('search.found_radius:=9', 'search.found_radius must be an integer from 0 to 5 (cells), '
                               'got 9'),
])
def test_an_override_outside_the_range_ends_the_node_with_the_settings_reason(
        ros_env, override, message):
    import subprocess
    import sys
    run = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'controller', '--ros-args',
                          '-p', override], cwd=REPO, env=ros_env, capture_output=True,
                         text=True, timeout=60)
    assert run.returncode == 1, run.stderr
    assert run.stderr.strip().splitlines()[-1] == f'gaze_controller: error: {message}'


def test_the_simulated_camera_refuses_a_dprime_its_float32_frames_cannot_hold(context):
    """
    QA: the camera took ``fpoc.dprime`` 1e300 and published +inf at the target in every frame.

    A frame every controller refuses, and numpy warned of the cast's overflow at each frame. The
    value is refused when it is given (start-up or ``ros2 param set``), with the bound; the
    bound's own frames are finite and cast without a warning.
    """
    import warnings
    from ipomdp_gaze.nodes.camera import SimulatedCameraNode
    from rclpy.parameter import Parameter
    reason = ('fpoc.dprime must be at most 1e+38 in the simulated camera (its evidence frames are '
              "float32, where a larger d' is +inf), got {}")
    with pytest.raises(ValueError) as info:
        SimulatedCameraNode(context=context,
                            parameter_overrides=[Parameter('fpoc.dprime', value=1e300)])
    assert str(info.value) == reason.format('1e+300')
    camera = SimulatedCameraNode(context=context, parameter_overrides=[
        Parameter('target_row', value=5), Parameter('target_col', value=5)])
    try:
        assert 'at most 1e+38' in camera.describe_parameter('fpoc.dprime').additional_constraints
        result = camera.set_parameters([Parameter('fpoc.dprime', value=1e300)])[0]
        assert not result.successful and result.reason == reason.format('1e+300')
        result = camera.set_parameters_atomically([Parameter('fpoc.model', value='table'),
                                                   Parameter('fpoc.dprime', value=[1e39, 0.0])])
        assert not result.successful and result.reason == reason.format('1e+39')
        assert camera.get_parameter('fpoc.dprime').value == 4.0
        assert camera.set_parameters([Parameter('fpoc.dprime', value=1e38)])[0].successful
        frames = []
        camera._evidence_pub.publish = frames.append
        with warnings.catch_warnings():
            warnings.simplefilter('error')
            camera._publish_frame()                 # the target at the centre, in view
        values = np.asarray(frames[0].data)             # NaN: the cells out of view
        assert not np.isinf(values).any() and np.nanmax(values) > 9e37
    finally:
        camera.destroy_node()
