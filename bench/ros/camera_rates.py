# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The pixel loop fed like a real camera: ``foveal_detector`` and ``gaze_controller`` at 15-30 Hz.

Starts the controller and the detector with the shipped fovea-mode files
(``config/faces_fovea_*.yaml``, each in its own process; ``--mode camera``: below) and a
camera process (this script with ``--publish``) that streams ``sensor_msgs/Image`` on
``image`` at ``--rate-hz``, reliable, depth 10 (a typical driver's default QoS): a held-out
test scene with one face, scaled to ``--size``, ``mono8``, ``rgb8`` or ``bgr8``, stamped when it
is sent. Each time a search ends this process resets the controller, so the loop runs for the
whole ``--seconds``. Reported:

- **latency**: image stamp to its ``evidence_image`` arriving here (median, p90, max; the
  evidence carries the image's stamp);
- **which image answers a fixation**: images the camera sent between the fixation reaching this
  process and the image that answered it (0: the first one sent after it);
- **each fixation's wait**: from the fixation reaching this process to the next
  ``evidence_image``, for fixations commanded while the camera streamed (the first one, commanded
  before the camera's first image, waits for the camera process to start), and the waits over
  0.5 s;
- the loop's rate (fixations answered per second) and the detector's own ``detector_ms``;
- each process's CPU (share of one core) and resident memory, sampled every second (growth:
  the largest of the last third against the largest of the first third);
- with ``--stall S``, the camera stops for S seconds in the middle and comes back (a new
  process); with ``--switch WxH``, it changes to that size halfway; with ``--bad-every N``,
  every N-th image is sent as ``rgba8`` (an encoding the node refuses); with ``--stamp-lag S``
  each image is stamped S seconds before it is sent (a camera whose images arrive S late);
  ``--detector-args`` adds to the detector's ``--ros-args`` (``'-p image_best_effort:=true'``);
  ``--mode camera`` runs the camera-mode files (``config/faces_camera_*.yaml``) with a head in
  the camera process that is at once where ``pan_tilt`` says, and ``joint_states`` and
  ``camera_info`` (25 degrees wide, the model camera's field of view) stamped like each image.

The machine's other load moves every time here; the numbers describe one run. Example::

    .venv/bin/python bench/ros/camera_rates.py --size 1920x1080 --encoding bgr8 --rate-hz 30 \
        --seconds 60
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
import subprocess
import sys
import threading
import time

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
PAGE = os.sysconf('SC_PAGE_SIZE')
TICK = os.sysconf('SC_CLK_TCK')
MIB = 2 ** 20


def size_arg(text: str) -> tuple[int, int]:
    """Parse ``WxH``."""
    width, _, height = text.partition('x')
    return int(width), int(height)


def scene_pixels(size: tuple[int, int], encoding: str) -> np.ndarray:
    """Return a held-out test scene with one face, resized to ``size``, in ``encoding``."""
    import cv2
    from ipomdp_gaze.vision.scenes import PAPER_TASK, SceneSet
    image = SceneSet('test', **PAPER_TASK, color='rgb', seed=0).scene(0).image
    image = cv2.resize(image, size, interpolation=cv2.INTER_LINEAR)
    if encoding == 'mono8':
        return cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    if encoding == 'bgr8':
        return np.ascontiguousarray(image[:, :, ::-1])
    return image


def publish(args) -> None:
    """Be the camera process: stream images until ``--seconds`` pass or SIGTERM."""
    import rclpy
    from rclpy.duration import Duration
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import Image
    from std_msgs.msg import Header
    rclpy.init(args=[])
    node = Node('camera_rates_camera')
    pub = node.create_publisher(Image, 'image',
                                QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    head = Head(node) if args.mode == 'camera' else None
    sizes = [size_arg(args.size)] + ([size_arg(args.switch)] if args.switch else [])
    frames = [(scene_pixels(s, args.encoding), s) for s in sizes]
    channels = 1 if args.encoding == 'mono8' else 3
    log = open(args.log, 'a') if args.log else None
    period = 1.0 / args.rate_hz
    t0 = time.monotonic()
    n = 0
    try:
        while time.monotonic() - t0 < args.seconds:
            due = t0 + n * period
            time.sleep(max(0.0, due - time.monotonic()))
            half = time.monotonic() - t0 > args.seconds / 2
            pixels, (w, h) = frames[1 if half and len(frames) > 1 else 0]
            bad = args.bad_every and n % args.bad_every == args.bad_every - 1
            stamp = node.get_clock().now() - Duration(seconds=args.stamp_lag)
            msg = Image(header=Header(stamp=stamp.to_msg(), frame_id='camera'), height=h,
                        width=w, encoding='rgba8' if bad else args.encoding, is_bigendian=0,
                        step=(4 if bad else channels) * w)
            msg.data = (np.zeros((h, w, 4), np.uint8) if bad else pixels).tobytes()
            pub.publish(msg)
            if head is not None:
                head.publish(stamp.to_msg(), w, h)
            if log:
                log.write(f'{stamp.nanoseconds} {int(bool(bad))} {w} {h}\n')
            n += 1
    except KeyboardInterrupt:
        pass
    finally:
        if log:
            log.close()
        rclpy.try_shutdown()            # ends the head's spin thread first
        if head is not None:
            head.thread.join(5)
        node.destroy_node()


class Head:
    """
    Camera mode: a head that is where ``pan_tilt`` says at once, and a camera of 25 degrees.

    With each image it publishes ``joint_states`` and ``camera_info`` under the image's stamp
    (the field of view of the model's camera, any size); it spins in a thread of its own.
    """

    def __init__(self, node):
        from ipomdp_gaze.nodes.qos import STATE_QOS
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import CameraInfo, JointState
        self.node, self.position = node, [0.0, 0.0]
        self.CameraInfo, self.JointState = CameraInfo, JointState
        self.joints = node.create_publisher(JointState, 'joint_states', 10)
        self.info = node.create_publisher(CameraInfo, 'camera_info', 10)
        node.create_subscription(JointState, 'pan_tilt', self._on_target, STATE_QOS)
        self.executor = SingleThreadedExecutor(context=node.context)
        self.executor.add_node(node)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        from rclpy.executors import ExternalShutdownException
        try:
            self.executor.spin()
        except ExternalShutdownException:
            pass

    def _on_target(self, msg) -> None:
        self.position = [float(msg.position[0]), float(msg.position[1])]

    def publish(self, stamp, width: int, height: int) -> None:
        """Publish the head's pose and the camera's intrinsics stamped like an image."""
        import math
        from ipomdp_gaze.model.head_camera import PinholeCamera
        from ipomdp_gaze.msg_adapters import images
        from std_msgs.msg import Header
        fx = (width / 2) / math.tan(math.radians(12.5))
        camera = PinholeCamera(width, height, fx, fx, (width - 1) / 2, (height - 1) / 2)
        self.info.publish(images.camera_info(camera, stamp))
        self.joints.publish(self.JointState(header=Header(stamp=stamp),
                                            name=['pan_joint', 'tilt_joint'],
                                            position=list(self.position)))


class Sampler(threading.Thread):
    """CPU (share of one core) and RSS of some processes, every ``period_s``."""

    def __init__(self, pids, period_s: float = 1.0):
        super().__init__(daemon=True)
        self.pids, self.period_s = pids, period_s
        self.samples = {'controller': [], 'detector': [], 'camera': []}
        self.halt = threading.Event()

    @staticmethod
    def _read(pid: int):
        try:
            with open(f'/proc/{pid}/stat') as f:
                fields = f.read().rpartition(')')[2].split()
            with open(f'/proc/{pid}/statm') as f:
                rss = int(f.read().split()[1]) * PAGE
        except OSError:
            return None
        return (int(fields[11]) + int(fields[12])) / TICK, rss

    def run(self):
        last = {}
        while not self.halt.is_set():
            now = time.monotonic()
            for name, pid in list(self.pids().items()):
                got = self._read(pid)
                if got is None:
                    continue
                if (name, pid) in last:
                    t, cpu = last[name, pid]
                    share = (got[0] - cpu) / (now - t)
                    self.samples.setdefault(name, []).append((now, share, got[1]))
                last[name, pid] = (now, got[0])
            self.halt.wait(self.period_s)


def camera_process(args, seconds: float, log: str, env: dict) -> subprocess.Popen:
    """Start the camera process."""
    cmd = [sys.executable, __file__, '--publish', '--size', args.size, '--encoding',
           args.encoding, '--rate-hz', str(args.rate_hz), '--seconds', str(seconds),
           '--log', log, '--bad-every', str(args.bad_every),
           '--stamp-lag', str(args.stamp_lag), '--mode', args.mode]
    if args.switch:
        cmd += ['--switch', args.switch]
    return subprocess.Popen(cmd, env=env, stdin=subprocess.DEVNULL)


def run(args) -> dict:
    """Run the loop; return what was measured."""
    import tempfile
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.harness.processes import isolated_nodes
    from ipomdp_gaze.harness.watch import LATCHED, Watch
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import Image
    from std_msgs.msg import Int32MultiArray
    cfg = ROOT / 'config'
    mode = args.mode
    tmp = tempfile.mkdtemp(prefix='camera-rates-')
    log = os.path.join(tmp, 'camera.log')
    with isolated_nodes(args.domain, prefix='camera-rates-') as nodes:
        procs = {
            'controller': nodes.start('controller', [
                '--params-file', cfg / f'faces_{mode}_controller.yaml']),
            'detector': nodes.start('detector', [
                '--params-file', cfg / f'faces_{mode}_detector.yaml',
                *args.detector_args.split()]),
        }
        cameras = []
        with Watch(args.domain, 'camera_rates', nodes) as watch:
            frames_qos = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
            evidence = watch.record(Image, 'evidence_image', frames_qos)
            fixations = watch.record(Int32MultiArray, 'fixation', LATCHED)
            ends = []
            for kind in ('found', 'gave_up'):
                watch.node.create_subscription(DiagnosticStatus, kind,
                                               lambda m, k=kind: ends.append(k), 10)
            status = watch.status_values('foveal_detector: detector')
            control = watch.status_values('gaze_controller: search')
            if not watch.wait_until(lambda: status and control, 60):
                raise RuntimeError('the nodes did not come up')
            pids = {'controller': procs['controller'].proc.pid,
                    'detector': procs['detector'].proc.pid}

            def live():
                out = dict(pids)
                if cameras and cameras[-1].poll() is None:
                    out['camera'] = cameras[-1].pid
                return out
            sampler = Sampler(live)
            sampler.start()
            seen = [0]

            def keep_searching(until):
                """Reset the controller after each search until ``until()`` is true."""
                while not until():
                    if len(ends) > seen[0]:
                        seen[0] = len(ends)
                        watch.reset()
                    time.sleep(0.05)
            t0 = time.monotonic()
            if args.stall:
                first = (args.seconds - args.stall) / 2
                cameras.append(camera_process(args, first, log, nodes.env))
                keep_searching(lambda: cameras[-1].poll() is not None)
                stall_from = time.monotonic()
                keep_searching(lambda: time.monotonic() > stall_from + args.stall)
                stall_to = time.monotonic()
                cameras.append(camera_process(args, args.seconds - args.stall - first, log,
                                              nodes.env))
            else:
                stall_from = stall_to = None
                cameras.append(camera_process(args, args.seconds, log, nodes.env))
            keep_searching(lambda: cameras[-1].poll() is not None)
            seconds = time.monotonic() - t0
            time.sleep(2.5)
            sampler.halt.set()
            sampler.join(5)
            final = dict(status[-1])
            final_control = dict(control[-1])
            rec = [(t, m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec, m.header.frame_id)
                   for t, m in list(evidence)]
            fix = [(t, tuple(m.data)) for t, m in list(fixations)]
        codes = {p.name: code for p, code in nodes.stop()}
        warnings = [line for line in procs['detector'].output().splitlines() if 'WARN' in line]
    sent = np.loadtxt(log, ndmin=2)
    return {'seconds': seconds, 'evidence': rec, 'fixations': fix, 'sent': sent,
            'detector': final, 'controller': final_control, 'samples': sampler.samples,
            'codes': codes, 'warnings': warnings, 'searches': len(ends),
            'stall': (stall_from, stall_to),
            'wall_to_mono': time.time() - time.monotonic()}


def streaming_spans(sent_s: np.ndarray, stall) -> list[tuple[float, float]]:
    """
    Return the spans (first image sent, last image sent) of each camera process.

    ``sent_s`` are the send times of the images in the bench's monotonic clock; with a stall
    (``stall`` is its (from, to), else (None, None)) the first camera sent before it and the
    second after it.
    """
    if not sent_s.size:
        return []
    if stall[0] is None:
        return [(float(sent_s[0]), float(sent_s[-1]))]
    parts = (sent_s[sent_s <= stall[0]], sent_s[sent_s >= stall[1]])
    return [(float(p[0]), float(p[-1])) for p in parts if p.size]


def fixation_waits(fixations, evidence_s, spans) -> tuple[np.ndarray, int]:
    """
    Return the wait of each fixation for its evidence, and how many were left out.

    A fixation counts once (not its re-sends) and only if it was commanded while a camera
    streamed (within one of ``spans``): one commanded before the camera's first image, or in a
    stall, waits for the camera process to start, not for the transport.
    """
    waits, left_out = [], 0
    for i, (t, data) in enumerate(fixations):
        if i and data == fixations[i - 1][1]:
            continue                                # a re-send of the same fixation
        if not any(first <= t <= last for first, last in spans):
            left_out += 1
            continue
        j = int(np.searchsorted(evidence_s, t, side='right'))
        if j < len(evidence_s):
            waits.append(evidence_s[j] - t)
    return np.asarray(waits, dtype=float), left_out


def report(r: dict, args) -> str:
    """Text summary of a run."""
    off = r['wall_to_mono']
    lines = [f'{args.size} {args.encoding} at {args.rate_hz:g} Hz for {r["seconds"]:.0f} s'
             + (f', switching to {args.switch} halfway' if args.switch else '')
             + (f', camera stopped {args.stall:g} s' if args.stall else '')
             + (f', every {args.bad_every}th image rgba8' if args.bad_every else '')
             + (f', stamped {args.stamp_lag:g} s before sending' if args.stamp_lag else '')]
    sent = r['sent']
    good = sent[sent[:, 1] == 0, 0] * 1e-9 if sent.size else np.zeros(0)
    lat = np.asarray([t + off - stamp for t, stamp, _ in r['evidence']])
    fixes = [t + off for t, _ in r['fixations']]
    skipped = []
    for t, stamp, _ in r['evidence']:
        before = [f for f in fixes if f <= stamp]
        if not before:
            continue
        first = np.searchsorted(good, before[-1])
        answered = np.searchsorted(good, stamp - 1e-6)
        skipped.append(int(answered - first))
    d, c = r['detector'], r['controller']
    span = r['seconds']
    lines.append(f'images sent {len(sent)} ({int(sent[:, 1].sum()) if sent.size else 0} bad); '
                 f'detector: received {d["images_received"]} = processed '
                 f'{d["images_processed"]} + rejected {d["images_rejected"]} + unused '
                 f'{d["images_unused"]}; fixations {d["fixations_received"]}, detector_ms median '
                 f'{float(d["detector_ms_median"]):.1f}; last rejection {d["last_rejection"]!r}')
    lines.append(f'controller: frames received {c.get("frames_received")} applied '
                 f'{c.get("frames_applied")} rejected {c.get("frames_rejected")} skipped '
                 f'{c.get("frames_skipped")} dropped {c.get("frames_dropped")}; searches ended '
                 f'{r["searches"]}')
    if lat.size:
        lines.append(f'evidence frames {lat.size} ({lat.size / span:.1f}/s); latency image stamp '
                     f'-> evidence here: median {1e3 * np.median(lat):.1f} ms, p90 '
                     f'{1e3 * np.percentile(lat, 90):.1f} ms, max {1e3 * lat.max():.1f} ms')
    sent_s = sent[:, 0] * 1e-9 - off if sent.size else np.zeros(0)
    waits, before = fixation_waits(r['fixations'], [te for te, _, _ in r['evidence']],
                                   streaming_spans(sent_s, r['stall']))
    if waits.size:
        slow = np.sort(waits[waits > 0.5])[::-1]
        lines.append(f'fixation -> its evidence here ({before} commanded while the camera was '
                     f'not streaming left out): median '
                     f'{1e3 * np.median(waits):.1f} ms, p90 {1e3 * np.percentile(waits, 90):.1f} '
                     f'ms, max {1e3 * waits.max():.0f} ms; over 0.5 s: {slow.size} of '
                     f'{waits.size}' + (f' ({", ".join(f"{w:.2f}" for w in slow[:8])} s)'
                                        if slow.size else ''))
    if skipped:
        s = np.asarray(skipped)
        lines.append(f'images sent between the fixation and the one that answered it: '
                     f'0 in {np.mean(s == 0):.0%}, 1 in {np.mean(s == 1):.0%}, more in '
                     f'{np.mean(s > 1):.0%} (max {s.max()})')
    for name, samples in r['samples'].items():
        if not samples:
            continue
        a = np.asarray([(cpu, rss) for _, cpu, rss in samples])
        third = max(1, len(a) // 3)
        lines.append(f'{name}: CPU mean {100 * a[:, 0].mean():.0f}% of a core (max '
                     f'{100 * a[:, 0].max():.0f}%), RSS first third max '
                     f'{a[:third, 1].max() / MIB:.1f} MiB, last third max '
                     f'{a[-third:, 1].max() / MIB:.1f} MiB')
    if r['stall'][0] is not None:
        t_from, t_to = r['stall']
        back = [t + off for t, _, _ in r['evidence'] if t > t_to]
        first = good[good > t_to + off]
        lines.append(f'camera stopped {t_to - t_from:.1f} s; first evidence after it came back: '
                     f'{1e3 * (back[0] - first[0]):.0f} ms after its first image'
                     if back and first.size else 'camera stopped; NO evidence after it came back')
    warned = r['warnings']
    lines.append(f'detector warnings logged: {len(warned)}'
                 + ''.join(f'\n  {line[:160]}' for line in warned[:6]))
    with_load = os.getloadavg()
    lines.append(f'exit codes {r["codes"]}; load average {with_load[0]:.1f}')
    return '\n'.join(lines)


def main() -> int:
    """Parse arguments; run the camera process or the whole measurement."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--size', default='640x480')
    parser.add_argument('--encoding', default='bgr8', choices=('mono8', 'rgb8', 'bgr8'))
    parser.add_argument('--rate-hz', type=float, default=30.0)
    parser.add_argument('--seconds', type=float, default=60.0)
    parser.add_argument('--switch', default='')
    parser.add_argument('--stall', type=float, default=0.0)
    parser.add_argument('--bad-every', type=int, default=0)
    parser.add_argument('--mode', default='fovea', choices=('fovea', 'camera'),
                        help='camera: the head follows pan_tilt at once, with joint_states and '
                             'camera_info stamped like each image')
    parser.add_argument('--stamp-lag', type=float, default=0.0,
                        help='stamp each image this many seconds before it is sent')
    parser.add_argument('--detector-args', default='',
                        help="more of the detector's --ros-args, e.g. '-p NAME:=VALUE'")
    parser.add_argument('--domain', type=int, default=None)
    parser.add_argument('--save', default='', help='pickle the raw measurements here')
    parser.add_argument('--publish', action='store_true', help=argparse.SUPPRESS)
    parser.add_argument('--log', default='', help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.publish:
        publish(args)
        return 0
    if args.domain is None:
        from ipomdp_gaze.harness.processes import domain_id_for
        args.domain = domain_id_for()
    result = run(args)
    if args.save:
        import pickle
        with open(args.save, 'wb') as f:
            pickle.dump((result, vars(args)), f)
    print(report(result, args))
    return 0


if __name__ == '__main__':
    sys.exit(main())
