# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Domain ids of concurrent runs: each process holds its own (no rclpy needed)."""
from __future__ import annotations

import subprocess
import sys
import textwrap

from conftest import REPO

HOLD = textwrap.dedent("""
    import sys
    from ipomdp_gaze.harness.processes import domain_id_for
    print(domain_id_for(), domain_id_for(), flush=True)
    sys.stdin.read()                     # hold the domain until the test closes stdin
""")


def test_concurrent_runs_never_share_a_domain_id():
    procs = [subprocess.Popen([sys.executable, '-c', HOLD], cwd=REPO, stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True) for _ in range(6)]
    try:
        ids = []
        for proc in procs:
            first, again = map(int, proc.stdout.readline().split())
            assert first == again                  # a process keeps its domain
            ids.append(first)
    finally:
        for proc in procs:
            proc.stdin.close()
            proc.wait(30)
    assert len(set(ids)) == len(ids), ids
    assert all(1 <= i <= 101 for i in ids), ids


STUBBORN = textwrap.dedent("""
    import signal, sys, time
    signal.signal(signal.SIGTERM, signal.SIG_IGN)        # ignores SIGTERM: needs SIGKILL
    print('ready', flush=True)
    time.sleep(120)
""")


def test_stop_processes_terminates_the_polite_and_kills_the_stubborn():
    from ipomdp_gaze.harness.processes import stop_processes
    polite = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(120)'])
    stubborn = subprocess.Popen([sys.executable, '-c', STUBBORN], stdout=subprocess.PIPE,
                                text=True)
    assert stubborn.stdout.readline().strip() == 'ready'
    stop_processes([polite, stubborn], timeout_s=1.0)
    assert polite.returncode == -15                      # SIGTERM
    assert stubborn.returncode == -9                     # SIGKILL after the wait
    stubborn.stdout.close()


def test_the_demos_say_a_node_never_started_so():
    """A node left unstarted (an earlier one did not come up) read 'exit status None'."""
    from ipomdp_gaze.harness.processes import exit_states
    codes = {'scene_camera': None, 'detector': -15, 'controller': 0, 'camera': 1}
    alive = {'scene_camera': False, 'detector': True, 'controller': True, 'camera': False}
    assert exit_states(codes, alive) == ('scene_camera not started, detector exit status -15, '
                                         'controller exit status 0, camera exit status 1 (had '
                                         'already exited)')
