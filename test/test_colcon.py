# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Build the package with colcon into a temporary workspace and start it as ``ros2 run`` would.

``ros2 run ipomdp_gaze controller`` looks the package up in the ament index and executes
``<prefix>/lib/ipomdp_gaze/controller``; the stand-in below does exactly that after sourcing the
workspace's ``install/setup.bash``. The started controller must then talk over DDS.
"""
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys

from conftest import wait_for
import pytest

ROOT = Path(__file__).resolve().parents[1]
IGNORE = shutil.ignore_patterns('.venv', '.git', 'build', 'install', 'log', '__pycache__',
                                '*.egg-info', '.pytest_cache', '.hypothesis', 'docs', 'out')
ROS2RUN = (
    'import os, sys\n'
    'from ament_index_python.packages import get_package_prefix\n'
    'package, executable = sys.argv[1:3]\n'
    'path = os.path.join(get_package_prefix(package), "lib", package, executable)\n'
    'os.execv(path, [path] + sys.argv[3:])\n')


@pytest.fixture(scope='module')
def workspace(tmp_path_factory):
    ws = tmp_path_factory.mktemp('colcon_ws')
    shutil.copytree(ROOT, ws / 'src' / 'ipomdp_gaze', ignore=IGNORE)
    colcon = Path(sys.executable).parent / 'colcon'
    env = dict(os.environ, PATH=f'{colcon.parent}{os.pathsep}{os.environ["PATH"]}')
    out = subprocess.run([str(colcon), 'build', '--base-paths', 'src'], cwd=ws, env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    return ws


@pytest.mark.ros
def test_install_tree_has_executables_index_marker_and_share_files(workspace):
    prefix = workspace / 'install' / 'ipomdp_gaze'
    for exe in ('controller', 'camera'):
        path = prefix / 'lib' / 'ipomdp_gaze' / exe
        assert path.is_file() and os.access(path, os.X_OK), path
    share = prefix / 'share'
    assert (share / 'ament_index' / 'resource_index' / 'packages' / 'ipomdp_gaze').is_file()
    for name in ('package.xml', 'config/controller.yaml', 'config/camera.yaml',
                 'launch/gaze_demo.launch.py'):
        assert (share / 'ipomdp_gaze' / name).is_file(), name


@pytest.mark.ros
def test_ros2_run_starts_the_installed_controller(workspace, ros_env, probe, tmp_path):
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    received = probe.record(JointState, '/colcon_check/pan_tilt', latched)
    (tmp_path / 'ros2run.py').write_text(ROS2RUN)
    script = ('source install/setup.bash && '
              f'exec "{sys.executable}" "{tmp_path / "ros2run.py"}" ipomdp_gaze controller '
              '--ros-args -r __ns:=/colcon_check '
              '--params-file install/ipomdp_gaze/share/ipomdp_gaze/config/controller.yaml')
    env = {k: v for k, v in ros_env.items() if not k.startswith('AMENT_')}
    env.pop('COLCON_PREFIX_PATH', None)
    log = open(tmp_path / 'controller.log', 'w')
    proc = subprocess.Popen(['bash', '-c', script], cwd=workspace, env=env, stdout=log,
                            stderr=subprocess.STDOUT)
    try:
        assert wait_for(lambda: received, 60), (tmp_path / 'controller.log').read_text()[-3000:]
        msg = received[-1][1]
        assert len(msg.position) == 2 and list(msg.name)
    finally:
        proc.send_signal(signal.SIGTERM)
        code = proc.wait(20)
        log.close()
    assert code == 0, (tmp_path / 'controller.log').read_text()[-3000:]


@pytest.mark.ros
def test_sourced_workspace_imports_the_installed_copy(workspace):
    code = ('import ipomdp_gaze, ipomdp_gaze.policies as p; print(ipomdp_gaze.__file__); '
            'print(p.__file__)')
    script = f'source install/setup.bash && "{sys.executable}" -c "{code}"'
    out = subprocess.run(['bash', '-c', script], cwd=workspace, capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0, out.stderr
    for line in out.stdout.split():
        assert line.startswith(str(workspace / 'install' / 'ipomdp_gaze')), line
