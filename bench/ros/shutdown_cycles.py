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

    .venv/bin/python bench/ros/shutdown_cycles.py --cycles 50
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import sys
import tempfile
import time

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from ipomdp_gaze.commands.common import positive_float, positive_int  # noqa: E402
from ipomdp_gaze.files.share_files import config_file  # noqa: E402
from ipomdp_gaze.harness.processes import domain_id_for, NodeGroup, ros_environment  # noqa: E402


def main(argv=None) -> int:
    """Run the cycles and print one JSON line per cycle and a summary."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--cycles', type=positive_int, default=50)
    parser.add_argument('--frames', type=positive_int, default=3,
                        help='applied frames to wait for before stopping')
    parser.add_argument('--timeout-s', type=positive_float, default=10.0)
    parser.add_argument('--keep', default='', help='folder for the logs of hung nodes')
    args = parser.parse_args(argv)

    from ipomdp_gaze.harness.watch import Watch
    from std_msgs.msg import Float32MultiArray

    work = Path(tempfile.mkdtemp(prefix='shutdown_cycles_'))
    domain = domain_id_for()
    env = ros_environment(domain, work / 'ros_log')
    os.environ.update({k: env[k] for k in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOG_DIR')})
    keep = Path(args.keep) if args.keep else work
    controller_args = ['--params-file', str(config_file('controller.yaml'))]
    camera_args = ['--params-file', str(config_file('camera.yaml'))]
    hangs, times = 0, {'controller': [], 'camera': []}
    nodes = NodeGroup(env, work, stack_dump=True)
    with Watch(domain, 'shutdown_probe') as probe:
        beliefs = probe.latest(Float32MultiArray, 'belief', 100)
        for cycle in range(args.cycles):
            procs = {'controller': nodes.start('controller', controller_args),
                     'camera': nodes.start('camera', camera_args)}
            try:
                seen = beliefs.count
                probe.wait_until(lambda: beliefs.count - seen >= args.frames, 60, 0.05)
                row = {'cycle': cycle, 'beliefs': beliefs.count - seen}
                for name, proc in procs.items():
                    t0 = time.monotonic()
                    code = proc.stop(args.timeout_s)
                    seconds = time.monotonic() - t0
                    times[name].append(seconds)
                    row[name] = {'code': code, 'exit_s': round(seconds, 3)}
                    if code != 0:
                        hangs += 1
                        kept = keep / f'hung-{name}-{cycle}.log'
                        kept.write_bytes(proc.log_path.read_bytes())
                        row[name]['log'] = str(kept)
            finally:
                for proc in procs.values():
                    if proc.running:
                        proc.kill()
            print(json.dumps(row), flush=True)
    summary = {'cycles': args.cycles, 'bad_exits': hangs}
    for name, values in times.items():
        if values:
            values = sorted(values)
            summary[f'{name}_exit_s'] = {'median': values[len(values) // 2], 'max': values[-1]}
    print(json.dumps(summary), flush=True)
    return 1 if hangs else 0


if __name__ == '__main__':
    sys.exit(main())
