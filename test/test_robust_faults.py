# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Fault injection: nodes killed mid-search and restarted, evidence that stops, a signal race.

- The camera is killed (SIGKILL) mid-search. The controller keeps its belief, reports the stall
  in ``/diagnostics`` (WARN, ``no usable evidence for X s``) and its log, and re-sends its
  target (its CPU use meanwhile is a benchmark, ``bench/ros/bench_ros_idle.py``, not a test
  threshold). A new camera gets the target, and its
  first frame updates the kept belief (checked against Bayes' rule); the search completes on
  the camera's target.
- The controller is killed and a new one started: the camera keeps serving, and the new
  controller's search completes.
- rclpy's signal handler can wake the executor before it shuts the context down; the nodes'
  spin loop must still return (the SIGTERM hang once seen as ``camera: exit status -9``).
"""
from __future__ import annotations

import math
import subprocess
import sys
import textwrap

from conftest import REPO, wait_for
import numpy as np
import pytest

pytestmark = pytest.mark.ros

TARGET = (2, 8)
DPRIME = 2.5                       # a weak camera: a search takes several fixations
STALL_S = 1.0
STALLED_RESENDS = 5                # re-sends (0.3 s apart) seen while no evidence comes
TASK = ['-p', 'grid.rows:=11', '-p', 'grid.cols:=11', '-p', 'grid.spacing_deg:=5.0',
        '-p', f'fpoc.dprime:={DPRIME}', '-p', 'fpoc.half_width_deg:=10.0',
        '-p', 'fpoc.half_height_deg:=10.0']
CONTROLLER_ARGS = TASK + ['-p', 'policy.name:=elm', '-p', 'retry_period_s:=0.3',
                          '-p', f'stall_timeout_s:={STALL_S}', '-p', 'diagnostics_period_s:=0.2',
                          '-p', 'confidence:=0.999']
CAMERA_ARGS = TASK + ['-p', f'target_row:={TARGET[0]}', '-p', f'target_col:={TARGET[1]}',
                      '-p', 'seed:=5']


class Watch:
    """What the probe sees of the search: beliefs, targets, camera poses and frames, status."""

    def __init__(self, probe):
        from ipomdp_gaze.harness.watch import SearchRecord
        from ipomdp_gaze.model.grid import Grid
        from ipomdp_gaze.model.head import PanTiltMap
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float32MultiArray
        self.grid = Grid(11, 11, 5.0)
        self.head = PanTiltMap(self.grid)
        self.search = SearchRecord(probe)
        self.beliefs, self.targets = self.search.beliefs, self.search.targets
        self.poses = probe.record(JointState, 'joint_states', 200)
        best_effort = QoSProfile(depth=200, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.frames = probe.record(Float32MultiArray, 'evidence', best_effort)
        self.diag = probe.search_status()

    def cell(self, msg) -> int:
        from ipomdp_gaze.msg_adapters import joints
        return self.head.nearest_cell(*joints.angles_from_joint_state(msg, self.head))

    def belief(self, i=-1) -> np.ndarray:
        return self.search.belief(i)

    def finished(self, since: int) -> bool:
        return self.search.reached(0.999, since) is not None


@pytest.fixture(scope='module')
def watch(probe):
    return Watch(probe)


def _posterior(belief, frame, fixation, grid) -> np.ndarray:
    """Bayes' rule offline: the kept belief updated with one camera frame."""
    from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
    d = dprime_matrix(grid, make_fpoc('camera', dprime=DPRIME, half_width_deg=10.0,
                                      half_height_deg=10.0))[:, fixation]
    o = np.asarray(frame, np.float32).astype(np.float64)
    term = np.where(np.isnan(o), 0.0, d * (np.nan_to_num(o) - d / 2))
    log_b = np.log(np.maximum(belief, 1e-300)) + term
    return np.exp(log_b - np.logaddexp.reduce(log_b))


def _kept_outside_view(kept, belief, fixation, grid) -> bool:
    """Whether ``belief`` is ``kept`` times one factor on the cells a frame says nothing of."""
    from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
    d = dprime_matrix(grid, make_fpoc('camera', dprime=DPRIME, half_width_deg=10.0,
                                      half_height_deg=10.0))[:, fixation]
    outside = (d == 0) & (kept > 1e-12)
    ratio = belief[outside] / kept[outside]
    return bool(outside.sum() >= 2 and np.allclose(ratio, ratio[0], rtol=1e-4))


def _matched(probe, topic: str) -> bool:
    """Whether the probe's subscriptions to ``topic`` have matched every publisher in the graph."""
    publishers = probe.node.count_publishers(f'/{topic}')
    subs = [s for s in probe.node.subscriptions if s.topic_name == f'/{topic}']
    return bool(subs) and all(s.get_publisher_count() >= publishers for s in subs)


def _mid_search(probe, watch):
    """Reset; wait for a search with a few applied frames that has not found the target."""
    for _ in range(5):
        n = len(watch.beliefs)
        assert probe.reset().success
        # A search ends at its found event (confidence 0.999), so one can stop short of 4.
        assert wait_for(lambda: len(watch.beliefs) >= n + 4 or watch.finished(n), 30), \
            'the search did not start'
        if not watch.finished(n):
            return
    pytest.fail('every search finished within 3 fixations')


def test_camera_killed_mid_search_then_restarted(nodes, probe, watch):
    controller = nodes.start('controller', CONTROLLER_ARGS)
    camera = nodes.start('camera', CAMERA_ARGS)
    assert wait_for(lambda: watch.diag.count > 0, 30), controller.output()
    # The first search may end before the probe sees the camera: wait for the camera itself.
    assert wait_for(lambda: probe.node.count_publishers('joint_states') > 0, 30), camera.output()
    _mid_search(probe, watch)

    nodes.kill(camera)
    watch.diag.wait_fresh()
    killed = int(watch.diag.values['pan_tilt_resends'])
    # A re-send after the kill: the frames in flight then have arrived or are lost.
    assert wait_for(lambda: int(watch.diag.values['pan_tilt_resends']) > killed, 30)
    kept_beliefs = len(watch.beliefs)
    kept = watch.belief()
    before = watch.diag.wait_fresh()
    resends = int(watch.diag.values['pan_tilt_resends'])
    # Evidence has stopped: the target is re-sent, and a warning is in /diagnostics and the log.
    assert wait_for(lambda: int(watch.diag.values['pan_tilt_resends']) >= resends
                    + STALLED_RESENDS and watch.diag.message.startswith('no usable'), 30), \
        (watch.diag.values, watch.diag.message)
    stalled = watch.diag.wait_fresh()
    assert stalled['applied'] == before['applied'] and len(watch.beliefs) == kept_beliefs
    assert watch.diag.level == 1, watch.diag.message                 # WARN
    assert watch.diag.message.startswith('no usable evidence for '), watch.diag.message
    waited = float(watch.diag.message.split()[4])
    assert waited >= STALL_S
    assert 'no usable evidence for' in controller.output()
    assert controller.running

    # A new camera. The test's probe must discover it before it sends anything worth checking,
    # so the controller is disabled meanwhile (a frame taken then is skipped); enabling it
    # re-sends the target, which reaches the new camera, and the camera's frame taken there
    # updates the kept belief by Bayes' rule.
    target = watch.cell(watch.targets[-1][1])
    assert probe.enable(False).success
    graph = probe.node
    publishers = graph.count_publishers('evidence'), graph.count_publishers('joint_states')
    camera = nodes.start('camera', CAMERA_ARGS)
    # The new camera is in the graph (the killed one may still be), and the probe's own
    # subscriptions have matched as many publishers as the graph holds (DDS matching follows
    # the graph), so the probe records what the new camera sends from now on, short of the race
    # said below.
    assert wait_for(lambda: graph.count_publishers('evidence') > publishers[0] and
                    graph.count_publishers('joint_states') > publishers[1] and
                    _matched(probe, 'evidence') and _matched(probe, 'joint_states'), 30), \
        camera.output()
    n_frames = len(watch.frames)
    assert len(watch.beliefs) == kept_beliefs
    assert probe.enable(True).success
    # The new camera serves the re-sent target: the first update is the kept belief times a
    # frame taken there (checked below). Its pose there is not required of the probe: on a
    # loaded machine the killed camera's endpoint can leave the graph while the new one is being
    # matched, so the counts above agree before the match and a pose sent in that gap is lost
    # (a CI replica saw the camera's next poses, 24, 30, 40, without the target's).
    assert wait_for(lambda: len(watch.beliefs) > kept_beliefs, 30), controller.output()
    first = watch.belief(kept_beliefs)
    if not any(np.allclose(first, _posterior(kept, frame.data, target, watch.grid), rtol=1e-4,
                           atol=1e-7) for _, frame in watch.frames[n_frames:]):
        # Frames travel best effort, so the probe may have lost the one the controller applied.
        # Then check what any camera frame at the target does: the cells out of its view keep
        # the kept belief's ratios, and so the kept belief was updated, not a fresh one.
        assert _kept_outside_view(kept, first, target, watch.grid), \
            'the first update after the restart is not the kept belief times a camera frame'
    assert wait_for(lambda: watch.finished(kept_beliefs), 60), 'the search did not complete'
    done = next(np.asarray(m.data) for _, m in watch.beliefs[kept_beliefs:]
                if max(m.data) >= 0.999)
    assert watch.grid.cell(int(np.argmax(done))) == TARGET
    assert watch.diag.wait_fresh()['applied'] > before['applied']
    assert watch.diag.message != '' and not watch.diag.message.startswith('no usable')


def test_controller_killed_and_restarted_camera_keeps_serving(nodes, probe, watch):
    controller, camera = nodes.last('controller'), nodes.last('camera')
    nodes.kill(controller)
    reply = probe.reset('simulated_camera')
    assert reply.success and f'({TARGET[0]}, {TARGET[1]})' in reply.message
    n, statuses = len(watch.beliefs), watch.diag.count
    controller = nodes.start('controller', CONTROLLER_ARGS)

    def found_by_the_new_controller() -> bool:
        # The belief topic is volatile: on a loaded machine the new controller can end its search
        # before this probe has matched its publisher, and then every belief of it is lost. Its
        # /diagnostics come every second whatever the timing, so they tell the answer too.
        return watch.finished(n) or (watch.diag.count > statuses + 1
                                     and watch.diag.values.get('decision') == 'found')

    assert wait_for(found_by_the_new_controller, 60), controller.output()[-2000:]
    if watch.finished(n):
        done = next(np.asarray(m.data) for _, m in watch.beliefs[n:] if max(m.data) >= 0.999)
        assert watch.grid.cell(int(np.argmax(done))) == TARGET
    else:
        values = watch.diag.values          # strings, as DiagnosticStatus carries them
        assert (int(values['most_likely_row']), int(values['most_likely_col'])) == TARGET
        assert float(values['most_likely_probability']) >= 0.999
    assert camera.running and controller.running


RACE = textwrap.dedent("""
    import gc, sys, threading, time
    import rclpy
    from rclpy.executors import Executor, ExternalShutdownException
    from rclpy.node import Node
    from ipomdp_gaze.nodes.spin import spin

    rclpy.init(args=[])
    node = Node('idle_node')                      # no timer of its own, like an idle camera

    def signal_like_rclpy():
        time.sleep(1.0)
        # rclpy's signal thread: first wake every executor, then shut the context down.
        for executor in [x for x in gc.get_objects() if isinstance(x, Executor)]:
            executor._sigint_gc.trigger()
        time.sleep(0.3)
        context = rclpy.get_default_context()
        with context.handle:
            context.handle.shutdown()

    threading.Thread(target=signal_like_rclpy, daemon=True).start()
    start = time.monotonic()
    try:
        spin(node)
    except ExternalShutdownException:
        pass
    print(f'returned after {time.monotonic() - start:.2f} s', flush=True)
""")


def test_spin_returns_when_the_signal_wakes_the_executor_before_shutdown(ros_env):
    # Before the fix the process never returned (the subprocess timeout ends it, and fails the
    # test); how soon it returns is not a test threshold.
    proc = subprocess.run([sys.executable, '-c', RACE], env=ros_env, cwd=REPO, timeout=60,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    seconds = float(proc.stdout.split()[-2])
    assert math.isfinite(seconds)
