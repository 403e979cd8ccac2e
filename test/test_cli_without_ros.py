# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The CLI where ROS 2's Python packages are not installed (``pip install ipomdp_gaze`` alone).

Each run is a fresh interpreter in which rclpy and the message packages cannot be imported
(``sys.modules[name] = None``). A command that needs ROS says so in one line with how to install
it (it was a ``ModuleNotFoundError`` traceback from ``demo``); the offline room demo (``demo
--faces``) needs no ROS and runs.
"""
import subprocess
import sys

from ipomdp_gaze.cli import ros_module
import pytest

BLOCK = ('rclpy', 'diagnostic_msgs', 'sensor_msgs', 'std_msgs', 'geometry_msgs', 'std_srvs',
         'rcl_interfaces', 'builtin_interfaces')


def _cli(*argv: str) -> subprocess.CompletedProcess:
    code = ('import sys\n'
            f'for name in {BLOCK!r}:\n'
            '    sys.modules[name] = None\n'
            'from ipomdp_gaze.cli import main\n'
            f'sys.exit(main({list(argv)!r}))\n')
    return subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=300)


@pytest.mark.parametrize('name, ros', [
    ('rclpy', True), ('rclpy.node', True), ('diagnostic_msgs', True), ('std_srvs.srv', True),
    ('rcl_interfaces.msg', True), ('rosidl_runtime_py', True), ('rosbag2_py', True),
    ('numpy', False), ('cv2', False), ('yaml', False), (None, False)])
def test_ros_modules_are_told_from_others(name, ros):
    assert ros_module(name) is ros


def test_a_ros_demo_without_ros_says_what_to_install_in_one_line():
    run = _cli('demo', '--scene', 'faces', '--seed', '1')
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and 'Traceback' not in run.stderr, run.stderr
    assert lines[0].startswith('ipomdp-gaze demo: error: this command needs ROS 2 Jazzy (No '
                               "module named '")
    assert 'pip install "ros-jazzy-rclpy[fastrtps]" ros-jazzy-common-interfaces' in lines[0]


def test_the_offline_room_demo_runs_without_ros():
    run = _cli('demo', '--scene', 'faces', '--faces', '0-4', '--seed', '3')
    assert run.returncode in (0, 1), run.stderr
    assert 'Traceback' not in run.stderr
    assert run.stdout.strip().splitlines()[-1].startswith('found ')
