# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A node's command line: what rcl cannot parse, and what rclpy would ignore silently.

The first is one line and exit 2; the second (a misspelt parameter, a params file for another
node) is a warning.
"""
from __future__ import annotations

from pathlib import Path
import select
import signal
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.ros
REPO = Path(__file__).resolve().parents[1]


def _cli(ros_env, *args, timeout=60):
    return subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', *args], cwd=REPO,
                          env=ros_env, capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize('command', ['controller', 'detector', 'record'])
@pytest.mark.parametrize('ros_args, message', [
    (['--params-file', 'no_such_file.yaml'], "Couldn't parse params file"),
    (['--params-file', 'setup.py'], "Couldn't parse params file"),
    (['-p', 'confidence'], "Couldn't parse parameter override rule: '-p confidence'"),
    (['--bogus'], 'unknown ROS arguments: --bogus'),
])
def test_unparsable_ros_args_exit_2_with_one_line(ros_env, tmp_path, command, ros_args,
                                                  message):
    first = [command] + ([str(tmp_path / 'bag')] if command == 'record' else [])
    run = _cli(ros_env, *first, '--ros-args', *ros_args)
    assert run.returncode == 2, run.stderr
    assert 'Traceback' not in run.stderr
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith(f'ipomdp-gaze {command}: error: ') and message in last  # as run
    assert '/src/' not in last                          # rcl's C source locations are cut
    assert not (tmp_path / 'bag').exists()


def test_misspelt_parameters_are_warned_about(context, tmp_path):
    from ipomdp_gaze.nodes.spin import warn_unused_parameters
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    node = Node('gaze_controller', context=context, parameter_overrides=[
        Parameter('confidance', value=0.9), Parameter('confidence', value=0.9)])
    try:
        node.declare_parameter('confidence', 0.99)
        right = tmp_path / 'right.yaml'
        right.write_text('/**:\n  ros__parameters:\n    confidence: 0.9\n')
        other = tmp_path / 'other.yaml'
        other.write_text('gaze_controler:\n  ros__parameters:\n    confidence: 0.9\n')
        warned = warn_unused_parameters(node, ['x', '--ros-args', '--params-file', str(right)])
        assert warned == ["parameter 'confidance' is not a parameter of this node; ignored "
                          "(did you mean 'confidence'?)"]
        warned = warn_unused_parameters(node, ['x', '--ros-args', '--params-file', str(other)])
        assert warned[-1] == (f'params file {other} has no section for node /gaze_controller '
                              '(its sections: /gaze_controler); none of it applies')
    finally:
        node.destroy_node()


def test_another_nodes_parameter_in_a_shared_section_is_not_warned_about(context, tmp_path):
    """
    QA: one params file with a ``/**:`` section for a launch's nodes warned in every node.

    ``parameter 'rate_hz' is not a parameter of this node; ignored``, for the cameras'
    parameters in the controller. rclpy merges every source into one set of overrides, but
    the params files say where each came from: another node's parameter in a wildcard section
    is one info line; in the node's own section or ``-p``, or a typo anywhere, a warning.
    """
    from ipomdp_gaze.nodes.spin import warn_unused_parameters
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    shared = tmp_path / 'shared.yaml'
    shared.write_text('/**:\n  ros__parameters:\n    rate_hz: 5.0\n    confidance: 0.9\n'
                      '    scene: {file: a.png}\n'
                      '/gaze_controller:\n  ros__parameters:\n    saccade_time_s: 0.1\n')
    given = ['rate_hz', 'confidance', 'scene.file', 'saccade_time_s', 'publish_image']
    node = Node('gaze_controller', context=context,
                parameter_overrides=[Parameter(name, value=1.0) for name in given])
    infos = []
    try:
        node.declare_parameter('confidence', 0.99)
        node.get_logger().info = infos.append
        argv = ['x', '--ros-args', '--params-file', str(shared), '-p', 'publish_image:=true']
        warned = warn_unused_parameters(node, argv)
        assert warned == [
            "parameter 'confidance' is not a parameter of this node; ignored (did you mean "
            "'confidence'?)",
            "parameter 'publish_image' is not a parameter of this node; ignored",
            "parameter 'saccade_time_s' is not a parameter of this node; ignored"]
        assert infos == ['2 parameters of other ipomdp_gaze nodes in a wildcard (/**) section, '
                         "not this node's: rate_hz, scene.file; ignored here"]
    finally:
        node.destroy_node()


@pytest.mark.parametrize('section, node, applies', [
    ('/gaze_controller', '/gaze_controller', True),
    ('/**', '/robot/gaze_controller', True),
    ('/**/gaze_controller', '/robot/gaze_controller', True),
    ('/robot/*', '/robot/gaze_controller', True),
    ('/robot/gaze_controller', '/gaze_controller', False),
    ('/gaze_controller', '/head1/gaze_controller', False),      # a bare key: the root only
    ('/gaze_controler', '/gaze_controller', False),
])
def test_params_file_sections_match_as_rcl_does(tmp_path, section, node, applies):
    from ipomdp_gaze.nodes.spin import _matches, params_file_sections
    path = tmp_path / 'p.yaml'
    path.write_text(f'{section}:\n  ros__parameters:\n    a: 1\n')
    assert params_file_sections(path) == [section]
    assert _matches(section, node) is applies


def test_nested_namespaces_and_unreadable_files(tmp_path):
    from ipomdp_gaze.nodes.spin import params_file_sections
    nested = tmp_path / 'n.yaml'
    nested.write_text('robot:\n  gaze_controller:\n    ros__parameters:\n      a: 1\n')
    assert params_file_sections(nested) == ['/robot/gaze_controller']
    assert params_file_sections(tmp_path / 'missing.yaml') == []


def test_a_running_node_warns_about_a_typo(ros_env, tmp_path):
    params = tmp_path / 'typo.yaml'
    params.write_text('gaze_controller:\n  ros__parameters:\n    confidance: 0.95\n')
    proc = subprocess.Popen([sys.executable, '-m', 'ipomdp_gaze.cli', 'controller',
                             '--ros-args', '--params-file', str(params)], cwd=REPO,
                            env=ros_env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)
    seen, deadline = [], time.monotonic() + 60.0
    try:
        while time.monotonic() < deadline:        # the node logs while it starts up
            ready, _, _ = select.select([proc.stderr], [], [], 1.0)
            line = proc.stderr.readline() if ready else ''
            seen.append(line)
            if 'confidance' in line or proc.poll() is not None:
                break
    finally:
        proc.send_signal(signal.SIGINT)
        rest = proc.communicate(timeout=30)[1]
    assert proc.returncode == 0, ''.join(seen) + rest
    assert "parameter 'confidance' is not a parameter of this node; ignored (did you mean " \
        "'confidence'?)" in ''.join(seen)


@pytest.mark.parametrize('module', ['controller', 'camera', 'detector', 'scene_camera'])
def test_a_node_executable_answers_help_and_refuses_a_stray_argument(ros_env, module):
    """QA: `lib/ipomdp_gaze/controller --help` started a live node that moved the head."""
    def run(*args):
        return subprocess.run([sys.executable, '-m', f'ipomdp_gaze.nodes.{module}', *args],
                              cwd=REPO, env=ros_env, capture_output=True, text=True, timeout=60)
    helped = run('--help')
    assert helped.returncode == 0 and helped.stdout.startswith(
        f'usage: ros2 run ipomdp_gaze {module} [--ros-args'), helped.stdout + helped.stderr
    assert '[INFO]' not in helped.stdout + helped.stderr               # no node started
    stray = run('--seed', '3')
    assert stray.returncode == 2
    # Named by the program run (its node was named: gaze_controller for controller).
    assert stray.stderr.strip().splitlines()[-1] == (
        f'{module}: error: unexpected arguments --seed 3 (ROS arguments go after --ros-args; '
        '--help for usage)')


@pytest.mark.parametrize('path', sorted((REPO / 'config').glob('*.yaml')), ids=lambda p: p.name)
def test_every_shipped_params_file_applies_in_any_namespace(path):
    """QA: bare ``gaze_controller:`` sections applied only at the root, so under -r __ns:=/r1."""
    from ipomdp_gaze.nodes import NODE_NAMES
    from ipomdp_gaze.nodes.spin import _matches, params_file_sections
    sections = params_file_sections(path)
    assert len(sections) == 1 and sections[0].startswith('/**/'), sections
    assert sections[0][len('/**/'):] in NODE_NAMES.values()
    for namespace in ('', '/robot1', '/robot1/head'):
        assert _matches(sections[0], f'{namespace}/{sections[0][len("/**/"):]}')


@pytest.mark.parametrize('name, node_class', [('controller', 'GazeControllerNode'),
                                              ('camera', 'SimulatedCameraNode')])
def test_a_namespaced_node_takes_the_shipped_values(context, name, node_class):
    import importlib
    from ipomdp_gaze.files.yaml_files import yaml_parameters
    from ipomdp_gaze.nodes import NODE_NAMES
    path = REPO / 'config' / f'{name}.yaml'
    shipped = yaml_parameters(path, NODE_NAMES[name])
    make = getattr(importlib.import_module(f'ipomdp_gaze.nodes.{name}'), node_class)
    node = make(context=context, namespace='/robot1/head',
                cli_args=['--ros-args', '--params-file', str(path)])
    try:
        assert node.get_fully_qualified_name() == f'/robot1/head/{NODE_NAMES[name]}'
        for key, value in shipped.items():
            got = node.get_parameter(key).value
            assert (list(got) if hasattr(got, 'tolist') or hasattr(got, 'typecode') else got) \
                == value, key
    finally:
        node.destroy_node()


@pytest.mark.parametrize('nodes, fault', [
    ('[gaze controller]', "'gaze controller' is not a node name"),
    ('[gaze_controller, 9x]', "'9x' is not a node name"),
])
def test_a_recorder_node_name_it_cannot_ask_ends_it_with_one_line(
        ros_env, tmp_path, nodes, fault):
    """
    QA: a name in ``nodes`` the recorder cannot make a parameter client for.

    It was taken at start-up; half a second later the first ask raised out of the spin
    (InvalidServiceNameException, a traceback) and left a bag begun.
    """
    run = _cli(ros_env, 'record', str(tmp_path / 'bag'), '--ros-args', '-p', f'nodes:={nodes}',
               '-p', 'topics:=[belief]', timeout=30)
    assert run.returncode == 1, run.stdout + run.stderr
    assert 'Traceback' not in run.stderr, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('recorder: error: nodes: '), lines
    assert fault in lines[0]
    assert not (tmp_path / 'bag').exists()


def test_a_scene_file_that_is_not_there_ends_the_scene_camera_with_one_line(ros_env, tmp_path):
    """QA: OpenCV's imread printed its own 'can't open/read file' warning before our line."""
    missing = tmp_path / 'no_such_scene.png'
    run = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.nodes.scene_camera', '--ros-args',
                          '-p', f'scene.file:={missing}'], cwd=REPO, env=ros_env,
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 1, run.stdout + run.stderr
    assert run.stderr.strip().splitlines() == [
        f"scene_camera: error: scene.file '{missing}' is missing or not an image OpenCV can "
        'read'], run.stderr
