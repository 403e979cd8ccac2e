# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Every driver of the search session refuses a bad setting with the same message.

The offline image-task evaluation runs the session with the real detector.

The CLI (``search``, ``find``, ``evaluate --scenes``) and the ``gaze_controller`` node (a parameter
set, in process) are given the same bad values; the line the CLI prints and the reason the node
returns carry the message of :class:`ipomdp_gaze.search.session.SearchSettings`. The node also
takes
``policy.file`` alone as the learned policy at start-up.
"""
from __future__ import annotations

from contextlib import contextmanager
import json
import subprocess
import sys

from conftest import REPO
from ipomdp_gaze.search.session import SearchSettings
import pytest

BAD = [  # (CLI flag, value, node parameter, ROS type name, settings field, value)
    ('--confidence', '1.5', 'confidence', 'DOUBLE', 'confidence', 1.5),
    ('--confidence', '0', 'confidence', 'DOUBLE', 'confidence', 0.0),
    ('--max-fixations', '-3', 'search.max_fixations', 'INTEGER', 'max_fixations', -3),
    ('--absent-prior', '1.0', 'absent.prior', 'DOUBLE', 'absent_prior', 1.0),
    ('--repeat-weight', '2.0', 'search.repeat_weight', 'DOUBLE', 'repeat_weight', 2.0),
]
# The commands that take each flag.
COMMANDS = {
    '--confidence': ('find', 'evaluate-scenes', 'evaluate', 'search'),
    '--max-fixations': ('find', 'evaluate-scenes', 'evaluate'),
    '--absent-prior': ('find', 'evaluate-scenes', 'evaluate'),
    '--repeat-weight': ('find',),
}
ARGS = {'find': ['find', str(REPO / 'docs' / 'figures' / 'search_example.png')],
        'evaluate-scenes': ['evaluate', '--scenes', 'faces-420', '--episodes', '1'],
        'evaluate': ['evaluate', '--episodes', '10'], 'search': ['search']}


def cli(*args, timeout=300):
    return subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', *args], cwd=REPO,
                          capture_output=True, text=True, timeout=timeout)


def message(field, value) -> str:
    with pytest.raises(ValueError) as info:
        SearchSettings(**{field: value})
    return str(info.value)


@pytest.mark.parametrize('flag, text, _param, _type, field, value', BAD)
def test_the_cli_prints_the_settings_message_in_one_line(flag, text, _param, _type, field,
                                                         value):
    expected = message(field, value)
    for command in (ARGS[name] for name in COMMANDS[flag]):
        out = cli(*command, flag, text)
        assert out.returncode == 2, (command, out.stderr)
        assert out.stderr.strip() == f'ipomdp-gaze {command[0]}: error: {expected}', command
        assert 'Traceback' not in out.stderr


@contextmanager
def controller_node(ros_env, overrides=None):
    """Run a ``gaze_controller`` in this process, on its own context, with these overrides."""
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    import rclpy
    from rclpy.parameter import Parameter
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=int(ros_env['ROS_DOMAIN_ID']), args=[])
    try:
        params = [Parameter(name, value=value) for name, value in (overrides or {}).items()]
        node = GazeControllerNode(context=ctx, parameter_overrides=params)
        try:
            yield node
        finally:
            node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


@pytest.mark.ros
def test_the_node_refuses_the_same_values_with_the_same_message(ros_env):
    from rclpy.parameter import Parameter
    with controller_node(ros_env) as node:
        for _flag, _text, param, type_name, field, value in BAD:
            before = node.get_parameter(param).value
            result = node.set_parameters([Parameter(
                param, getattr(Parameter.Type, type_name), value)])[0]
            assert not result.successful
            assert message(field, value) in result.reason, (param, result.reason)
            assert node.get_parameter(param).value == before
            assert node.core.settings == SearchSettings.from_parameters(
                {p: node.get_parameter(p).value for p in
                 ('confidence', 'search.max_fixations', 'absent.prior',
                  'search.repeat_weight', 'search.inhibit_return')})


@pytest.mark.ros
@pytest.mark.parametrize('overrides, expected, policy', [
    ({'policy.file': 'camera-11x11-infomax'}, 'learned', 'camera-11x11-infomax'),
    ({'policy.file': 'camera-11x11-infomax', 'policy.name': 'map'}, 'map', 'map'),
    ({}, 'elm', 'elm'),
])
def test_policy_file_alone_selects_learned_at_start_up(ros_env, overrides, expected, policy):
    with controller_node(ros_env, overrides) as node:
        assert node.get_parameter('policy.name').value == expected
        assert node.core.policy.name == policy


@pytest.mark.ros
def test_a_missing_policy_file_alone_is_refused_at_start_up(ros_env):
    with pytest.raises(Exception, match='nothere.yaml'):
        with controller_node(ros_env, {'policy.file': 'nothere.yaml'}):
            pass


def test_evaluate_scenes_runs_the_pan_tilt_task_and_writes_json(tmp_path):
    out = cli('evaluate', '--scenes', 'pan-tilt', '--episodes', '2', '--seed', '4',
              '--max-fixations', '6', '--json', str(tmp_path / 'pt.json'))
    assert out.returncode == 0, out.stderr
    assert 'pan-tilt (2 scenes with a face): right' in out.stdout
    record = json.loads((tmp_path / 'pt.json').read_text())
    assert record['settings']['search.max_fixations'] == 6
    from ipomdp_gaze.files.share_files import config_file
    from ipomdp_gaze.files.yaml_files import yaml_parameters
    shipped = yaml_parameters(config_file('faces_camera_controller.yaml'), 'gaze_controller')
    for name in ('search.repeat_weight', 'absent.prior', 'search.hotspot_prior'):
        assert record['settings'][name] == shipped[name]           # the shipped config's
    assert record['settings']['search.found_radius'] == 1
    scenes = record['scenes']['coverage']
    assert [s['index'] for s in scenes] == [0, 1]
    for s in scenes:
        assert 1 <= s['fixations'] <= 6 and len(s['path']) == s['fixations']
        assert s['path'][0] == 60                                  # the centre cell first
        assert s['decision'] in ('found', 'absent')                # decided at the deadline
        assert s['right'] == (s['decision'] == 'found' and max(
            abs(a - b) for a, b in zip(s['cell'], s['face_cell'])) <= 1)
        assert s['head_travel_deg'] >= 5.0 * (s['fixations'] - 1) - 1e-9
        # A stopped search keeps its answer: the MAP after its last fixation onwards is it.
        assert len(s['map_right']) == 20 and set(s['map_right'][s['fixations'] - 1:]) == \
            {s['right']}


def test_find_with_an_absent_prior_says_absent_on_a_face_free_photo(tmp_path):
    import cv2
    from skimage import data
    path = tmp_path / 'brick.png'
    cv2.imwrite(str(path), data.brick())
    # every view counting fully, the evidence decides before the pixel deadline
    out = cli('find', str(path), '--absent-prior', '0.5', '--json', str(tmp_path / 'o.json'),
              '--observation', 'faces-420', '--repeat-weight', '1', '--policy', 'elm',
              '--scan', 'fovea')
    assert out.returncode == 0, out.stderr
    entry = json.loads((tmp_path / 'o.json').read_text())['images'][0]
    assert entry['decision'] == entry['stop'] == 'absent'       # the evidence decided
    assert entry['absent_probability'] >= 0.99 and 'decision=absent' in out.stdout
    # the fovea's defaults (the absent hypothesis on): absent, by the evidence or at the pixel
    # deadline (the default --scan coarse has no belief: test/test_find_scan.py)
    out = cli('find', str(path), '--json', str(tmp_path / 'o.json'), '--scan', 'fovea')
    entry = json.loads((tmp_path / 'o.json').read_text())['images'][0]
    assert out.returncode == 0 and entry['decision'] == 'absent', out.stderr
    assert entry['stop'] in ('absent', 'pixels') and entry['cell'] is None
    assert entry['absent_probability'] > 0.5 and entry['detector_pixels'] <= 512 * 512


def test_find_saves_each_images_event_log(tmp_path):
    import cv2
    from skimage import data
    path = tmp_path / 'astronaut.png'
    cv2.imwrite(str(path), cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR))
    out = cli('find', str(path), '--log', str(tmp_path / 'log.jsonl'), '--json',
              str(tmp_path / 'o.json'), '--scan', 'fovea')
    assert out.returncode == 0, out.stderr
    entry = json.loads((tmp_path / 'o.json').read_text())['images'][0]
    lines = (tmp_path / 'log.jsonl').read_text().splitlines()
    assert len(lines) == 1
    events = json.loads(lines[0])['events']
    assert [e['event'] for e in events[:3]] == ['reset', 'scan', 'start']
    frames = [e for e in events if e['event'] == 'frame']
    assert len(frames) == entry['fixations']
    assert frames[-1]['decision'] == entry['decision']
    assert frames[-1]['belief']['map_cell'] == entry['cell']
    assert events[0]['settings']['confidence'] == 0.99


@pytest.mark.ros
def test_an_unexpected_error_in_a_parameter_set_is_counted_and_refused(ros_env, monkeypatch):
    """The controller's parameter callback is guarded: the set is refused, the node lives on."""
    from ipomdp_gaze.nodes import controller as module
    from rclpy.parameter import Parameter

    def broken(*args, **kwargs):
        raise RuntimeError('injected fault in build_policy')

    with controller_node(ros_env) as node:
        monkeypatch.setattr(module, 'build_policy', broken)
        result = node.set_parameters([Parameter('policy.name', value='map')])[0]
        assert not result.successful
        assert result.reason.startswith('internal error: RuntimeError: injected fault')
        assert node.guard.errors == 1 and node.get_parameter('policy.name').value == 'elm'
        monkeypatch.undo()
        assert node.set_parameters([Parameter('policy.name', value='map')])[0].successful
        assert node.core.policy.name == 'map'
