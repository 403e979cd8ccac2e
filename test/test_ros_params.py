# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
:class:`ipomdp_gaze.nodes.params.ParameterTransaction` on an in-process node (no other process).

A parameter set is checked whole: each value against its declaration, then the configuration
built from the current and the proposed values. It is taken whole (the new configuration is
applied and logged) or refused whole with the reason, and overrides given at start-up go through
the same callbacks.
"""
from __future__ import annotations

import pytest

pytestmark = pytest.mark.ros


def _params():
    from ipomdp_gaze.nodes.params import Param, T
    return [Param('gain', 1, T.INTEGER, 'a gain', int_range=(0, 10)),
            Param('mode', 'x', T.STRING, 'a mode', choices=('x', 'y'))]


def _build(values, changed, previous):
    """Build the configuration: the values (gain 7 only works in mode x)."""
    if values['gain'] == 7 and values['mode'] != 'x':
        raise ValueError(f"gain 7 needs mode 'x', got {values['mode']!r}")
    return dict(values, changed=sorted(changed or ()), previous=previous)


class Recorder:
    """The transaction's ``apply`` and ``while_declaring`` callbacks, recorded."""

    def __init__(self):
        self.applied, self.declaring = [], []

    def apply(self, old, new):
        self.applied.append((old, new))
        return f"mode {new['mode']}"

    def while_declaring(self, params):
        self.declaring.append([(p.name, p.value) for p in params])
        for p in params:
            if p.name == 'gain' and p.value == 9:
                raise ValueError('gain 9 is refused while declaring')


def _node(context, overrides=()):
    from ipomdp_gaze.nodes.params import ParameterTransaction
    from rclpy.node import Node
    node = Node('transaction_test', context=context, parameter_overrides=list(overrides))
    rec = Recorder()
    tx = ParameterTransaction(node, _params(), _build, rec.apply, rec.while_declaring)
    tx.declare()
    tx.start(_build(tx.values(), None, None))
    return node, tx, rec


def test_a_set_is_built_applied_and_logged(context, capfd):
    from rclpy.parameter import Parameter
    node, tx, rec = _node(context)
    try:
        first = tx.config
        assert first == {'gain': 1, 'mode': 'x', 'changed': [], 'previous': None}
        assert rec.declaring == [[('gain', 1)], [('mode', 'x')]]
        result = node.set_parameters_atomically([Parameter('gain', value=7)])
        assert result.successful, result.reason
        assert tx.config == {'gain': 7, 'mode': 'x', 'changed': ['gain'], 'previous': first}
        assert rec.applied == [(first, tx.config)]
        assert wait_log(capfd, 'parameters set: gain=7; mode x')
    finally:
        node.destroy_node()


def test_a_set_is_refused_whole_with_the_reason(context):
    from rclpy.parameter import Parameter
    node, tx, rec = _node(context)
    try:
        assert node.set_parameters_atomically([Parameter('gain', value=7)]).successful
        config = tx.config
        result = node.set_parameters_atomically([Parameter('gain', value=3),
                                                 Parameter('mode', value='z')])
        assert not result.successful
        assert result.reason == "mode must be one of 'x', 'y', got 'z'"
        result = node.set_parameters_atomically([Parameter('gain', value=2),
                                                 Parameter('mode', value='y')])
        assert result.successful, result.reason
        result = node.set_parameters([Parameter('gain', value=7)])[0]
        assert not result.successful and result.reason == "gain 7 needs mode 'x', got 'y'"
        assert (node.get_parameter('gain').value, node.get_parameter('mode').value) == (2, 'y')
        assert tx.config['gain'] == 2 and tx.config['previous'] == config
        assert len(rec.applied) == 2                  # only the sets that were taken
    finally:
        node.destroy_node()


def test_overrides_go_through_the_checks_while_declaring(context):
    from rclpy.exceptions import InvalidParameterValueException
    from rclpy.parameter import Parameter
    node, tx, rec = _node(context, [Parameter('gain', value=4)])
    try:
        assert tx.config['gain'] == 4 and rec.declaring[0] == [('gain', 4)]
        assert rec.applied == []                      # nothing is applied before start
    finally:
        node.destroy_node()
    with pytest.raises(InvalidParameterValueException, match='gain 9 is refused'):
        _node(context, [Parameter('gain', value=9)])
    with pytest.raises(InvalidParameterValueException, match="mode must be one of 'x', 'y'"):
        _node(context, [Parameter('mode', value='z')])


def wait_log(capfd, words, timeout_s=5.0) -> bool:
    """Whether ``words`` appear on this process's stderr (rcutils logs there) in time."""
    import time
    deadline, seen = time.monotonic() + timeout_s, ''
    while True:
        seen += capfd.readouterr().err
        if words in seen or time.monotonic() > deadline:
            return words in seen
        time.sleep(0.05)


def _declared_with(ros_env, ros_args):
    """Declare two arrays with defaults on a node given ``ros_args``; return node and values."""
    import rclpy
    from ipomdp_gaze.nodes.params import Param, ParameterTransaction, T
    from rclpy.node import Node
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(ros_env['ROS_DOMAIN_ID']),
               args=['node', '--ros-args', *ros_args])
    node = Node('empty_arrays', context=context)
    params = [Param('scales', [1.0], T.DOUBLE_ARRAY, 'factors'),
              Param('names', ['a'], T.STRING_ARRAY, 'names (read-only)', read_only=True)]
    try:
        tx = ParameterTransaction(node, params, lambda values, *_: values, lambda *_: None)
        tx.declare()
        return {p.name: node.get_parameter(p.name) for p in params}
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def test_an_empty_list_for_an_array_with_a_default_is_its_empty_array(ros_env):
    """
    QA: ``-p name:=[]`` (or YAML's ``[]``) reaches rclpy as NOT_SET, without a type.

    An array declared with a default then ended the node on 'The parameter ... is not
    initialized' (``-p search.false_alarm_scales:=[]``, the recorder's ``-p nodes:=[]``),
    instead of the node judging the empty array; a read-only one cannot be set after it is
    declared, and says so.
    """
    from rclpy.parameter import Parameter
    got = _declared_with(ros_env, ['-p', 'scales:=[]'])
    assert got['scales'].type_ == Parameter.Type.DOUBLE_ARRAY and list(got['scales'].value) == []
    assert list(got['names'].value) == ['a']
    with pytest.raises(ValueError, match='names is given as an empty list.*read-only array '
                                         'needs at least one value'):
        _declared_with(ros_env, ['-p', 'names:=[]'])


def test_every_description_says_read_only_exactly_when_it_is():
    """``ros2 param describe`` shows the text: a read-only parameter says so, and no other."""
    from ipomdp_gaze.nodes.camera import camera_params
    from ipomdp_gaze.nodes.controller import controller_params
    from ipomdp_gaze.nodes.detector import detector_params
    from ipomdp_gaze.nodes.recorder import recorder_params
    from ipomdp_gaze.nodes.scene_camera import scene_camera_params
    wrong = [p.name for params in (camera_params(), controller_params(), detector_params(),
                                   recorder_params(), scene_camera_params())
             for p in params if p.read_only != ('read-only' in p.description)]
    assert wrong == []
