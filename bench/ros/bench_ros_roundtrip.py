# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Round trip through the gaze_controller process: evidence frame in, belief and next target out.

Run: ``.venv/bin/python bench/ros/bench_ros_roundtrip.py [policy ...] [--quick]`` (default ``elm
map``). For each policy it starts the controller (shipped YAML, ``settle_time_s`` 0, no retries)
on a private domain; this process plays the camera: on every new ``pan_tilt`` it publishes one
11x11 evidence frame and times until the next ``pan_tilt`` (and the ``belief``) arrive; the
controller tracks (``motion.sigma_cells`` 0.5, docs/design.md section 7), so its search never ends
and each frame includes the prediction step. 20 warm-up and 200 timed round trips per policy
(``--quick``: 50); prints median and 90th percentile in ms. It also times the controller's work
for one frame in-process (message in, update, choice, messages out) without DDS.
"""
import argparse
import threading
import time

from builtin_interfaces.msg import Time
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.harness.processes import domain_id_for, isolated_nodes
from ipomdp_gaze.harness.watch import LATCHED, Watch
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.msg_adapters import grid_arrays, images, joints
from ipomdp_gaze.policies.registry import build_policy, POLICY_NAMES
from ipomdp_gaze.search.gaze import GazeController
import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float32MultiArray

GRID = Grid(11, 11, 5.0)
WARMUP, TIMED = 20, 200


def in_process(policy_name, repeats=2000):
    """Median microseconds of the controller's per-frame work without DDS."""
    fpoc = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)
    file = 'camera-11x11-infomax' if policy_name == 'learned' else ''   # the shipped YAML's
    core = GazeController(GRID, fpoc, build_policy(policy_name, GRID, fpoc, file=file),
                          settle_time_s=0.0)
    head = PanTiltMap(GRID)
    rng = np.random.default_rng(0)
    frames = [grid_arrays.to_multiarray(rng.standard_normal(121), GRID) for _ in range(50)]
    times = []
    for i in range(repeats):
        if i % 20 == 0 or core.stopped:            # a found event ends a still search
            core.reset(float(i))
        t0 = time.perf_counter()
        core.offer(grid_arrays.from_multiarray(frames[i % 50], GRID), float(i))
        grid_arrays.to_multiarray(core.belief, GRID)
        joints.joint_state(head, core.fixation, Time())
        t1 = time.perf_counter()
        images.belief_image(core.belief, GRID, core.fixation, 32, Time())
        t2 = time.perf_counter()
        times.append((t1 - t0, t2 - t1))
    t = np.median(np.array(times), axis=0) * 1e6
    return t[0], t[1]


def round_trips(policy_name, domain, timed=TIMED):
    """Median and p90 milliseconds of frame -> next pan_tilt, and frame -> belief."""
    with isolated_nodes(domain) as nodes:
        # Motion on: a tracker never ends its search, so every frame gets a next target.
        proc = nodes.start('controller', [
            '--params-file', str(config_file('controller.yaml')), '-p', 'settle_time_s:=0.0',
            '-p', 'retry_period_s:=0.0', '-p', f'policy.name:={policy_name}',
            '-p', 'motion.sigma_cells:=0.5'])
        rng = np.random.default_rng(1)
        state = {'sent': None, 'target': [], 'belief': [], 'stamps': set()}
        done = threading.Event()
        with Watch(domain, 'bench_camera', nodes) as watch:
            pub = watch.publisher(Float32MultiArray, 'evidence', 10)

            def send():
                if len(state['target']) >= WARMUP + timed:
                    done.set()
                    return
                msg = grid_arrays.to_multiarray(rng.standard_normal(121), GRID)
                state['sent'] = time.perf_counter()
                pub.publish(msg)

            def on_target(msg):
                key = (msg.header.stamp.sec, msg.header.stamp.nanosec)
                if key in state['stamps']:
                    return
                state['stamps'].add(key)
                if state['sent'] is not None:
                    state['target'].append(time.perf_counter() - state['sent'])
                if pub.get_subscription_count():
                    send()

            def on_belief(msg):
                if state['sent'] is not None:
                    state['belief'].append(time.perf_counter() - state['sent'])

            def kick():
                # The first target may arrive before the controller subscribes to our frames.
                if state['sent'] is None and pub.get_subscription_count() and state['stamps']:
                    send()

            watch.node.create_subscription(JointState, 'pan_tilt', on_target, LATCHED)
            watch.node.create_subscription(Float32MultiArray, 'belief', on_belief, 10)
            watch.node.create_timer(0.05, kick)
            watch.wait_until(done.is_set, 120)
        target = np.array(state['target'][WARMUP:]) * 1e3
        belief = np.array(state['belief'][WARMUP:]) * 1e3
        if target.size < timed:
            raise RuntimeError(f'only {target.size} round trips timed:\n{proc.output()}')
    return (np.median(target), np.percentile(target, 90), np.median(belief),
            np.percentile(belief, 90))


def policy_name(text: str) -> str:
    """Parse a policy name of the registry for argparse."""
    if text not in POLICY_NAMES:
        raise argparse.ArgumentTypeError(
            f"unknown policy {text!r}; valid policies: {', '.join(POLICY_NAMES)}")
    return text


def main(argv=None):
    """Time each policy in process and over DDS; print one line per policy."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('policies', nargs='*', metavar='policy', type=policy_name,
                        help=f"controller policies (default elm map): {', '.join(POLICY_NAMES)}")
    parser.add_argument('--quick', action='store_true',
                        help='a smoke run: 50 timed round trips and 200 in-process frames')
    args = parser.parse_args(argv)
    policies = args.policies or ['elm', 'map']
    timed, repeats = (50, 200) if args.quick else (TIMED, 2000)
    domain = domain_id_for()
    for name in policies:
        work, image = in_process(name, repeats)
        t50, t90, b50, b90 = round_trips(name, domain, timed)
        print(f'{name:8s} frame -> next pan_tilt: median {t50:.2f} ms, p90 {t90:.2f} ms; '
              f'frame -> belief: median {b50:.2f} ms, p90 {b90:.2f} ms '
              f'({timed} round trips); in-process work per frame {work:.0f} us '
              f'+ belief_image {image:.0f} us')


if __name__ == '__main__':
    main()
