# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Live searches over DDS with the shipped YAML files, beside the same task simulated offline.

Run: ``.venv/bin/python bench/bench_ros_search.py [searches]`` (default 30). Starts
``gaze_controller`` and ``simulated_camera`` as processes on a private domain, then repeats:
disable, camera reset (a new random target), controller reset, enable, wait for ``found``.
Prints fixations to ``found`` (median, 90th percentile), the fraction found at the right cell and
the wall time per search, and the same numbers from the numpy core on 2,000 simulated searches.
"""
from pathlib import Path
import sys
import tempfile
import threading
import time

from diagnostic_msgs.msg import DiagnosticStatus
from ipomdp_gaze.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.gaze import build_policy, GazeController
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.nodes.config import config_file
from ipomdp_gaze.nodes.processes import domain_id_for, NodeProcess, ros_environment
from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Int32MultiArray
from std_srvs.srv import SetBool, Trigger

GRID = Grid(11, 11, 5.0)
FPOC = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)


def offline(policy_name, searches=2000, seed=0, confidence=0.95):
    """Fixations to ``found`` and correctness of the core alone with the camera model."""
    rng = np.random.default_rng(seed)
    d = dprime_matrix(GRID, FPOC)
    file = 'camera-11x11-infomax' if policy_name == 'learned' else ''
    core = GazeController(GRID, FPOC, build_policy(policy_name, GRID, FPOC, file=file),
                          confidence=confidence)
    fixations, right = [], []
    for _ in range(searches):
        target = int(rng.integers(GRID.n_cells))
        core.reset(0.0)
        t = 0
        while core.found is None and t < 500:
            frame = rng.standard_normal(GRID.n_cells)
            frame[target] += d[target, core.fixation]
            frame[d[:, core.fixation] == 0] = np.nan
            t += 1
            core.offer(frame, float(t))
        fixations.append(core.found.fixations)
        right.append(core.found.cell == target)
    return np.array(fixations), np.array(right)


class Rig:
    """The probe side: service calls and the latest found / ground truth."""

    def __init__(self, context):
        self.node = Node('bench_search', context=context)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.found, self.truth = [], []
        self.node.create_subscription(DiagnosticStatus, 'found', self.found.append, 10)
        self.node.create_subscription(Int32MultiArray, 'ground_truth', self.truth.append,
                                      latched)
        self.clients = {}
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self):
        while not self.stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)

    def call(self, srv, name, request):
        if name not in self.clients:
            self.clients[name] = self.node.create_client(srv, name)
            assert self.clients[name].wait_for_service(timeout_sec=30), name
        future = self.clients[name].call_async(request)
        while not future.done():
            time.sleep(0.005)
        return future.result()

    def close(self):
        self.stop.set()
        self.thread.join(10)
        self.executor.shutdown(timeout_sec=1)
        self.node.destroy_node()


def wait(condition, timeout_s=60.0):
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise RuntimeError('timed out')
        time.sleep(0.005)


def live(searches, domain):
    """Fixations, correctness and seconds of each live search."""
    with tempfile.TemporaryDirectory() as tmp:
        env = ros_environment(domain, Path(tmp) / 'log')
        procs = [NodeProcess('controller', ['--params-file', str(config_file('controller.yaml'))],
                             env, Path(tmp) / 'c.log').start(),
                 NodeProcess('camera', ['--params-file', str(config_file('camera.yaml'))],
                             env, Path(tmp) / 'k.log').start()]
        context = rclpy.Context()
        rclpy.init(context=context, domain_id=domain, args=[])
        rig = Rig(context)
        out = []
        try:
            wait(lambda: rig.truth)
            for _ in range(searches):
                rig.call(SetBool, '/gaze_controller/enable', SetBool.Request(data=False))
                n_truth = len(rig.truth)
                rig.call(Trigger, '/simulated_camera/reset', Trigger.Request())
                wait(lambda: len(rig.truth) > n_truth)
                rig.call(Trigger, '/gaze_controller/reset', Trigger.Request())
                n_found = len(rig.found)
                t0 = time.perf_counter()
                rig.call(SetBool, '/gaze_controller/enable', SetBool.Request(data=True))
                wait(lambda: len(rig.found) > n_found)
                seconds = time.perf_counter() - t0
                found = diagnostics.parse_found(rig.found[n_found])
                truth = grid_arrays.cell_from_ground_truth(rig.truth[-1], GRID)
                out.append((found['fixations'], found['cell'] == truth, seconds))
        finally:
            rig.close()
            rclpy.try_shutdown(context=context)
            codes = [p.stop() for p in procs]
        policy = 'learned' if 'policy learned' in procs[0].output() else 'elm'
        return np.array(out), policy, codes


def main():
    searches = int(sys.argv[1]) if len(sys.argv) > 1 else 30
    results, policy, codes = live(searches, domain_id_for())
    fix, right, secs = results[:, 0], results[:, 1], results[:, 2]
    print(f'live over DDS ({policy}, {searches} searches, node exit codes {codes}): '
          f'fixations to found median {np.median(fix):.0f}, p90 {np.percentile(fix, 90):.1f}, '
          f'mean {fix.mean():.2f}; right {right.mean():.3f}; seconds per search median '
          f'{np.median(secs):.2f}, p90 {np.percentile(secs, 90):.2f}; '
          f'seconds per fixation {secs.sum() / fix.sum():.3f}')
    fix, right = offline(policy)
    print(f'offline core ({policy}, 2000 searches): fixations to found median '
          f'{np.median(fix):.0f}, p90 {np.percentile(fix, 90):.1f}, mean {fix.mean():.2f}; '
          f'right {right.mean():.3f}')


if __name__ == '__main__':
    main()
