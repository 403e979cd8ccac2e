# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Start the controller and the simulated camera, let them search, SIGTERM both; repeat.

Each cycle starts both nodes as separate processes (as ``make test`` does), waits until the
controller has applied a few frames from the camera, then stops the controller and the camera
with SIGTERM, in that order (the order of the test fixtures), and times each exit. A node that
has not exited ``--timeout-s`` after SIGTERM gets SIGUSR1 first, which makes Python's
``faulthandler`` print every thread's stack to its log, and then SIGKILL; its log is kept.

Usage::

    .venv/bin/python bench/shutdown_cycles.py --cycles 50
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import signal
import subprocess
import sys
import tempfile
import time

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from ipomdp_gaze.nodes.config import config_file  # noqa: E402
from ipomdp_gaze.nodes.processes import domain_id_for, ros_environment  # noqa: E402

WRAPPER = ('import faulthandler, signal, sys; '
           'faulthandler.register(signal.SIGUSR1, all_threads=True); '
           'from ipomdp_gaze.nodes.{node} import main; sys.exit(main())')


def start(node: str, ros_args, env: dict, log: Path) -> subprocess.Popen:
    """Start a node with a faulthandler on SIGUSR1; output to ``log``."""
    with open(log, 'wb') as out:
        return subprocess.Popen(
            [sys.executable, '-c', WRAPPER.format(node=node), '--ros-args', *ros_args],
            env=env, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)


def stop(proc: subprocess.Popen, timeout_s: float) -> tuple:
    """SIGTERM, wait; on a hang SIGUSR1 (stack dump) then SIGKILL. Returns (code, seconds)."""
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout_s)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGUSR1)
        time.sleep(1.0)
        proc.kill()
        proc.wait(10)
    return proc.returncode, time.monotonic() - t0


def main(argv=None) -> int:
    """Run the cycles and print one JSON line per cycle and a summary."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--cycles', type=int, default=50)
    parser.add_argument('--frames', type=int, default=3,
                        help='applied frames to wait for before stopping')
    parser.add_argument('--timeout-s', type=float, default=10.0)
    parser.add_argument('--keep', default='', help='folder for the logs of hung nodes')
    args = parser.parse_args(argv)

    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from std_msgs.msg import Float32MultiArray

    work = Path(tempfile.mkdtemp(prefix='shutdown_cycles_'))
    domain = domain_id_for()
    env = ros_environment(domain, work / 'ros_log')
    os.environ.update({k: env[k] for k in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOG_DIR')})
    keep = Path(args.keep) if args.keep else work
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain, args=[])
    probe = Node('shutdown_probe', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(probe)
    beliefs = []
    probe.create_subscription(Float32MultiArray, 'belief', lambda m: beliefs.append(1), 100)
    controller_args = ['--params-file', str(config_file('controller.yaml'))]
    camera_args = ['--params-file', str(config_file('camera.yaml'))]
    hangs, times = 0, {'controller': [], 'camera': []}
    try:
        for cycle in range(args.cycles):
            beliefs.clear()
            logs = {n: work / f'{n}-{cycle}.log' for n in ('controller', 'camera')}
            procs = {'controller': start('controller', controller_args, env, logs['controller']),
                     'camera': start('camera', camera_args, env, logs['camera'])}
            try:
                deadline = time.monotonic() + 60
                while len(beliefs) < args.frames and time.monotonic() < deadline:
                    executor.spin_once(timeout_sec=0.05)
                row = {'cycle': cycle, 'beliefs': len(beliefs)}
                for name in ('controller', 'camera'):
                    code, seconds = stop(procs[name], args.timeout_s)
                    times[name].append(seconds)
                    row[name] = {'code': code, 'exit_s': round(seconds, 3)}
                    if code != 0:
                        hangs += 1
                        kept = keep / f'hung-{name}-{cycle}.log'
                        kept.write_bytes(logs[name].read_bytes())
                        row[name]['log'] = str(kept)
            finally:
                for proc in procs.values():
                    if proc.poll() is None:
                        proc.kill()
                        proc.wait(10)
            print(json.dumps(row), flush=True)
    finally:
        executor.shutdown(timeout_sec=1)
        probe.destroy_node()
        rclpy.shutdown(context=context)
    summary = {'cycles': args.cycles, 'bad_exits': hangs}
    for name, values in times.items():
        if values:
            values = sorted(values)
            summary[f'{name}_exit_s'] = {'median': values[len(values) // 2], 'max': values[-1]}
    print(json.dumps(summary), flush=True)
    return 1 if hangs else 0


if __name__ == '__main__':
    sys.exit(main())
