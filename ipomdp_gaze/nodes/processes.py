# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Start and stop nodes as separate processes (no ``ros2 launch`` here): the demo and tests.

Each node runs as ``python -m ipomdp_gaze.nodes.<name> --ros-args ...`` with its output in a log
file. :func:`ros_environment` isolates a run: its own ``ROS_DOMAIN_ID``, discovery limited to this
host, and node log files in a directory of its own.
"""
from __future__ import annotations

import os
from pathlib import Path
import signal
import subprocess
import sys

MAX_DOMAIN_ID = 101


def domain_id_for(pid: int | None = None) -> int:
    """Derive a ROS domain id in 0..101 from a process id (default: this process)."""
    return (os.getpid() if pid is None else int(pid)) % (MAX_DOMAIN_ID + 1)


def ros_environment(domain_id: int, log_dir, base: dict | None = None) -> dict:
    """Copy ``base`` (default ``os.environ``) and set it up for an isolated run."""
    if not 0 <= int(domain_id) <= MAX_DOMAIN_ID:
        raise ValueError(f'domain id must be in 0..{MAX_DOMAIN_ID}, got {domain_id}')
    env = dict(os.environ if base is None else base)
    env.update({'ROS_DOMAIN_ID': str(int(domain_id)),
                'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST',
                'ROS_LOG_DIR': str(log_dir), 'PYTHONUNBUFFERED': '1'})
    env.pop('ROS_LOCALHOST_ONLY', None)
    return env


class NodeProcess:
    """One node in its own process; its stdout and stderr go to ``log_path``."""

    def __init__(self, node: str, ros_args=(), env: dict | None = None, log_path=None):
        if node not in ('controller', 'camera'):
            raise ValueError(f"node must be 'controller' or 'camera', got {node!r}")
        self.node = node
        self.args = [sys.executable, '-m', f'ipomdp_gaze.nodes.{node}', '--ros-args',
                     *map(str, ros_args)]
        self.env = env
        self.log_path = Path(log_path) if log_path else None
        self.proc: subprocess.Popen | None = None

    def start(self) -> 'NodeProcess':
        """Start the process."""
        out = open(self.log_path, 'wb') if self.log_path else subprocess.DEVNULL
        try:
            self.proc = subprocess.Popen(self.args, env=self.env, stdout=out,
                                         stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        finally:
            if self.log_path:
                out.close()
        return self

    @property
    def running(self) -> bool:
        """Whether the process has been started and has not exited."""
        return self.proc is not None and self.proc.poll() is None

    def stop(self, timeout_s: float = 10.0) -> int | None:
        """SIGTERM (rclpy shuts down cleanly), then SIGKILL after ``timeout_s``; the exit code."""
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout_s)
        return self.proc.returncode

    def output(self) -> str:
        """Return what the process printed so far."""
        if self.log_path is None or not self.log_path.exists():
            return ''
        return self.log_path.read_text(errors='replace')
