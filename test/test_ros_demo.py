# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze demo`` end to end: two node processes, a found target, a clean exit."""
from __future__ import annotations

from pathlib import Path
import re
import subprocess
import sys

from conftest import REPO
import pytest

pytestmark = pytest.mark.ros


def node_processes(domain_id: int) -> list:
    """Pids of ipomdp_gaze node processes running on ``domain_id``."""
    found = []
    for proc in Path('/proc').iterdir():
        if not proc.name.isdigit():
            continue
        try:
            cmdline = (proc / 'cmdline').read_bytes()
            environ = (proc / 'environ').read_bytes().split(b'\0')
        except OSError:
            continue
        if b'ipomdp_gaze.nodes.' in cmdline and f'ROS_DOMAIN_ID={domain_id}'.encode() in environ:
            found.append(int(proc.name))
    return found


@pytest.mark.parametrize('options, grid_line', [
    (['--target', '2,9', '--seed', '1'], '11x11 grid at 5.0 deg/cell'),
    (['--fpoc', 'human', '--target', '6,3', '--seed', '2'], '11x11 grid at 0.42 deg/cell'),
])
def test_demo_finds_the_target_and_stops_both_nodes(ros_env, options, grid_line):
    domain = int(ros_env['ROS_DOMAIN_ID'])
    run = subprocess.run(
        [sys.executable, '-m', 'ipomdp_gaze.cli', 'demo', '--domain-id', str(domain), *options],
        cwd=REPO, env=ros_env, capture_output=True, text=True, timeout=180)
    out = run.stdout
    assert run.returncode == 0, out + run.stderr
    assert grid_line in out
    fixations = re.findall(r'^fixation +(\d+): looked at \((\d+), (\d+)\) +pan +([-+]\d+\.\d+) deg'
                           r' +tilt +([-+]\d+\.\d+) deg +-> +most likely \((\d+), (\d+)\) '
                           r'p=(\d\.\d+) +entropy (\d+\.\d+) nats$', out, re.M)
    found = re.search(r'^found: the target is most likely at \((\d+), (\d+)\).* probability '
                      r'(\d\.\d+), after (\d+) fixations? \(reached the confidence 0\.95\)$',
                      out, re.M)
    assert fixations and found, out
    assert [int(f[0]) for f in fixations] == list(range(1, len(fixations) + 1))
    assert int(found.group(4)) == len(fixations)
    assert fixations[0][1:3] == ('5', '5')                 # the first fixation is the centre
    assert float(found.group(3)) >= 0.95
    assert (fixations[-1][5], fixations[-1][6]) == found.group(1, 2)
    hidden = options[options.index('--target') + 1].replace(',', ', ')
    # The answer must be the ground truth (the target hidden with --target), and say so.
    assert f'({found.group(1)}, {found.group(2)})' == f'({hidden})', out
    assert f'hid the target at ({hidden}): that is right' in out
    assert 'stopped both nodes (camera exit status 0, controller exit status 0)' in out
    assert node_processes(domain) == []


def test_a_demo_timeout_too_short_for_the_nodes_names_it(ros_env):
    """No node comes up in a millisecond: the line said only 'did not come up in time'."""
    domain = int(ros_env['ROS_DOMAIN_ID'])
    run = subprocess.run(
        [sys.executable, '-m', 'ipomdp_gaze.cli', 'demo', '--domain-id', str(domain),
         '--timeout', '0.001'], cwd=REPO, env=ros_env, capture_output=True, text=True,
        timeout=180)
    assert run.returncode != 0
    assert "ipomdp-gaze demo: error: gaze_controller did not come up within the demo's " \
        '--timeout of 0.001 s' in run.stderr, run.stderr
    assert node_processes(domain) == []                   # and the one it started is stopped
