# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
ROS loop: simulated camera -> evidence -> gaze_controller -> pan_tilt -> camera, two processes.

Each camera frame and the pose it was taken at (``joint_states``) carry one stamp; the camera
sends its next frame as soon as the next ``pan_tilt`` arrives (``saccade_time_s`` 0), so the gap
between consecutive frame stamps is one full loop (camera -> controller -> camera over DDS). A
third process (this one) only listens. The controller tracks (``motion.sigma_cells`` 0.5,
docs/design.md section 7): its search never ends, and each frame includes the prediction step.
At 256x256 the camera streams at 60 Hz instead, and the
controller's own counters in ``/diagnostics`` say how many frames it applied, skipped (stale or
superseded) or never saw (dropped by the keep-last queue), with its RSS from /proc.
Run: ``.venv/bin/python bench/ros/bench_ros_loop.py`` or ``make bench``.
"""
import sys
import time

from ipomdp_gaze.harness.processes import domain_id_for, isolated_nodes
from ipomdp_gaze.harness.watch import Watch
import numpy as np
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState
from std_msgs.msg import Float32MultiArray

TITLE = 'ROS loop: camera -> controller -> camera (separate processes)'
ORDER = 30
# (label, rows, spacing_deg, camera half field of view in degrees)
LOOPS = (('11x11', 11, 5.0, 10.0), ('128x128', 128, 0.5, 2.0))
STREAM = ('256x256 at 60 Hz', 256, 0.25, 1.0, 60.0)


def _task_args(rows, spacing, half):
    return ['-p', f'grid.rows:={rows}', '-p', f'grid.cols:={rows}',
            '-p', f'grid.spacing_deg:={spacing}', '-p', 'fpoc.model:=camera',
            '-p', f'fpoc.half_width_deg:={half}', '-p', f'fpoc.half_height_deg:={half}']


def _rss_mib(pid):
    with open(f'/proc/{pid}/status') as fh:
        for line in fh:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024
    return float('nan')


class _Listener(Watch):
    """This process's node: frame stamps from ``joint_states`` and the controller's counters."""

    def __init__(self, domain, nodes, count_frames=False):
        super().__init__(domain, 'bench_listener', nodes)
        self.stamps = []
        self.status = self.search_status()
        self.frames = self.latest(Float32MultiArray, 'evidence', qos_profile_sensor_data) \
            if count_frames else None
        self.node.create_subscription(JointState, 'joint_states', self._on_pose, 100)

    def _on_pose(self, msg):
        self.stamps.append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)

    @property
    def counters(self) -> dict:
        return self.status.values


def _start(nodes, rows, spacing, half, camera_args, controller_args=()):
    task = _task_args(rows, spacing, half)
    # Motion on: a tracker never ends its search (a still one stops at found), so the loop runs.
    controller = nodes.start('controller', [
        *task, '-p', 'policy.name:=elm', '-p', 'settle_time_s:=0.0', '-p', 'retry_period_s:=0.5',
        '-p', 'motion.sigma_cells:=0.5',
        '-p', 'pan_min_rad:=-3.0', '-p', 'pan_max_rad:=3.0', '-p', 'tilt_min_rad:=-1.5',
        '-p', 'tilt_max_rad:=1.5', *controller_args])
    camera = nodes.start('camera', [*task, *camera_args])
    return controller, camera


def loop(rows, spacing, half, seconds, domain):
    """Loop periods (ms) and sustained fixations per second with a frame-per-command camera."""
    with isolated_nodes(domain) as nodes:
        controller, camera = _start(nodes, rows, spacing, half,
                                    ['-p', 'saccade_time_s:=0.0', '-p', 'rate_hz:=0.0'])
        with _Listener(domain, nodes) as listener:
            if not listener.wait_until(lambda: len(listener.stamps) >= 20, 60, 0.2):
                raise RuntimeError('the loop did not start:\n' + controller.output()[-2000:]
                                   + camera.output()[-2000:])
            first = len(listener.stamps)
            time.sleep(seconds)
            stamps = np.array(listener.stamps[first:])
    periods = np.diff(stamps) * 1e3
    return {'median_ms': float(np.median(periods)), 'p99_ms': float(np.percentile(periods, 99)),
            'fixations_per_s': float(periods.size / (stamps[-1] - stamps[0])),
            'loops': int(periods.size)}


def stream(rows, spacing, half, rate_hz, seconds, domain):
    """Stream camera frames: sent vs applied, skipped and lost; controller RSS (MiB)."""
    with isolated_nodes(domain) as nodes:
        controller, camera = _start(nodes, rows, spacing, half,
                                    ['-p', 'saccade_time_s:=0.0', '-p', f'rate_hz:={rate_hz}'],
                                    ['-p', 'diagnostics_period_s:=0.5'])
        with _Listener(domain, nodes, count_frames=True) as listener:
            listener.wait_until(lambda: listener.counters.get('frames_applied', '0')
                                not in ('', '0'), 90, 0.5)
            rss0 = _rss_mib(controller.proc.pid)
            c0, n0 = dict(listener.counters), listener.frames.count
            time.sleep(seconds)
            time.sleep(1.2)                              # one more diagnostics period
            c1, n1 = dict(listener.counters), listener.frames.count
            rss1 = _rss_mib(controller.proc.pid)

    def delta(key):
        return int(float(c1.get(key, 'nan'))) - int(float(c0.get(key, 'nan')))
    sent = n1 - n0
    received, applied, skipped = (delta('frames_received'), delta('frames_applied'),
                                  delta('frames_skipped'))
    return {'sent': sent, 'received': received, 'applied': applied, 'skipped': skipped,
            'rss0': rss0, 'rss1': rss1, 'seconds': seconds}


def bench(ctx=None) -> str:
    quick = bool(getattr(ctx, 'quick', False))
    seconds = 4.0 if quick else 15.0
    domain = domain_id_for()
    lines = ['| grid | loops timed | loop median (ms) | loop p99 (ms) | fixations per second |',
             '|---|---|---|---|---|']
    for label, rows, spacing, half in LOOPS:
        r = loop(rows, spacing, half, seconds, domain)
        lines.append(f"| {label} | {r['loops']} | {r['median_ms']:.2f} | {r['p99_ms']:.2f} | "
                     f"{r['fixations_per_s']:.0f} |")
    label, rows, spacing, half, rate = STREAM
    s = stream(rows, spacing, half, rate, seconds, domain)
    lost = max(s['sent'] - s['received'], 0)      # 'sent' is this listener's lower bound
    lines += ['', f"{label} (camera streaming, controller ELM by FFT), over {s['seconds']:.0f} s: "
              f"this process saw {s['sent']} camera frames (best effort, so a lower bound of "
              f"what was sent); the controller received {s['received']} "
              f"(lost to the keep-last queue: at least {lost}), applied {s['applied']} and "
              f"skipped {s['skipped']} (stale: taken before the latest target settled, or "
              f'superseded); '
              f"controller RSS {s['rss0']:.0f} MiB before, {s['rss1']:.0f} MiB after.",
              '', "Each loop includes two DDS hops, the controller's update and decision and the "
              "camera's frame generation; the camera stamps a frame when it sends it.", '']
    return '\n'.join(lines)


if __name__ == '__main__':
    print(bench())
    sys.exit(0)
