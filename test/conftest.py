# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Shared fixtures; the ROS ones run real nodes over real DDS, isolated per test run.

Every run gets its own ``ROS_DOMAIN_ID`` (1..101, reserved with a lock file so that two runs at
once never share one: :func:`ipomdp_gaze.nodes.processes.domain_id_for`), discovery
limited to this host and node log files in a temporary directory. Nodes under test run as
separate processes (as a user runs them, :class:`ipomdp_gaze.nodes.processes.NodeGroup`); the
test's own node (``probe``, an :class:`ipomdp_gaze.nodes.watch.Watch`) spins a
``SingleThreadedExecutor`` in a thread with a stop flag and is joined at teardown (ROS_NOTES.md
section 7). The demo and the benches watch their nodes the same way.
"""
from __future__ import annotations

import importlib.util
import os
from pathlib import Path
import signal

from hypothesis import settings
from ipomdp_gaze.nodes.processes import wait_for  # noqa: F401 (the tests import it from here)
import pytest

# Property tests: the same examples on every CI run (CI=1), fresh ones on a developer's machine.
settings.register_profile('ci', derandomize=True, deadline=None, print_blob=True)
if os.environ.get('CI'):
    settings.load_profile('ci')

# A run started in the background by a shell without job control (`make test &`, nohup) has
# SIGINT ignored, and every process it starts inherits that. The Ctrl-C tests send SIGINT as a
# terminal does, to processes that take it as a terminal's do: give them the default back.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

HAVE_RCLPY = importlib.util.find_spec('rclpy') is not None
HAVE_ROS_MSGS = importlib.util.find_spec('std_msgs') is not None
# The message adapters need the ROS message packages (the `ros` extra): without them
# test_msg_adapters.py reports itself skipped, and an installed but broken package fails.
REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope='session')
def ros_env(tmp_path_factory):
    """Environment of an isolated ROS run; this process uses it too (set before rclpy.init)."""
    if not HAVE_RCLPY:
        pytest.skip('rclpy is not installed (pip install -e ".[ros]")')
    from ipomdp_gaze.nodes.processes import domain_id_for, ros_environment
    env = ros_environment(domain_id_for(), tmp_path_factory.mktemp('ros_log'))
    keys = ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOG_DIR', 'ROS_LOCALHOST_ONLY')
    saved = {k: os.environ.get(k) for k in keys}
    for k in keys:
        if k in env:
            os.environ[k] = env[k]
        else:
            os.environ.pop(k, None)
    yield env
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


@pytest.fixture(scope='module')
def probe(ros_env):
    """Provide the test's own node (a ``Watch``) on this run's domain, shared by a module."""
    from ipomdp_gaze.nodes.watch import Watch
    with Watch(int(ros_env['ROS_DOMAIN_ID']), 'test_probe') as watch:
        yield watch


@pytest.fixture(scope='module')
def nodes(ros_env, tmp_path_factory):
    """
    Provide the node processes of a module (a ``NodeGroup``; ``nodes.start`` starts one).

    At teardown every process not killed on purpose gets SIGTERM and must exit with status 0
    (a clean shutdown).
    """
    from ipomdp_gaze.nodes.processes import NodeGroup
    group = NodeGroup(ros_env, tmp_path_factory.mktemp('node_output'))
    yield group
    bad = group.close()
    assert not bad, 'nodes did not shut down cleanly:\n' + '\n'.join(bad)


@pytest.fixture(scope='module')
def launch(nodes):
    """Provide ``nodes.start``, which starts a node process (``controller`` or ``camera``)."""
    return nodes.start


def config_path(name: str) -> str:
    """Find a shipped config file as the nodes do."""
    from ipomdp_gaze.files.share_files import config_file
    return str(config_file(name))
