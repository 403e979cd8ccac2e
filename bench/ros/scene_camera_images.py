# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Images from the package's ``scene_camera`` to the detector: lost or late with Fast DDS's defaults.

Runs the fixed-camera face loop as ``faces_demo.launch.py mode:=fovea`` does, each node in its
own process with the shipped files (``config/faces_fovea_*.yaml``): ``scene_camera`` streams a
420x420 ``rgb8`` image (529,200 bytes, more than Fast DDS's 512 KB shared-memory segment) at
10 Hz, reliable, depth 2; ``foveal_detector`` reads it (reliable, depth 1); ``gaze_controller``
searches, and this process resets it each time a search ends, so the loop runs for the
whole ``--seconds`` (``--rate-hz`` changes the camera's rate). With ``--profile`` only the
camera's process gets ``FASTRTPS_DEFAULT_PROFILES_FILE=config/fastdds_large_images.xml`` (a
32 MiB segment). Reported:

- the camera's shared-memory segments (``/dev/shm/fastrtps_*`` it maps), to show which ran;
- images **published** against images the detector **received** (its ``images_received``),
  both counted from the detector's first status a second after the camera's first image (the
  detector and this process may match the camera at different times). Published: from the
  first to the last stamp at the camera's period (its timer's stamps are evenly spaced), of the
  ``camera_info`` the camera sends with each image, read here, and of the images the evidence
  answered (each ``evidence_image`` carries its image's stamp); ``camera_info_missed_here``
  counts those answered whose ``camera_info`` this process did not get. An image that arrives
  while the detector works replaces the one in its depth-1 queue and is in no counter, so
  ``detector_ms`` is given too;
- **gaps**: images the camera sent between two images the evidence answered, and the stamp
  gaps between them over 0.5 s (every image answers a fixation here: the controller asks for
  the next cell within milliseconds); and each fixation's wait for its ``evidence_image``
  (fixations while the camera streamed; re-sends counted once) with the waits over 0.5 s;
- with ``--image-reader``, this process reads ``image`` too (reliable, depth 10: a second
  reader such as a viewer or the recorder): the images it received and its gaps over 0.5 s;
- the CPU of each process (share of one core).

Run a default and a ``--profile`` run side by side (two domains) to have them under the same
load; the machine's load moves every time. Example::

    .venv/bin/python bench/ros/scene_camera_images.py --seconds 180 --domain 219 &
    .venv/bin/python bench/ros/scene_camera_images.py --seconds 180 --domain 220 --profile
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import re
import sys
import time

sys.path.insert(0, str(Path(__file__).resolve().parent))

from camera_rates import fixation_waits, Sampler  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
PROFILE = ROOT / 'config' / 'fastdds_large_images.xml'
PROFILE_VARIABLES = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')


def shm_segments(pid: int) -> list[int]:
    """Return the sizes of the Fast DDS shared-memory segments process ``pid`` maps."""
    sizes = set()
    try:
        with open(f'/proc/{pid}/maps') as f:
            for line in f:
                path = line.split()[-1]
                if re.fullmatch(r'/dev/shm/fastrtps_[0-9a-f]+', path):
                    sizes.add(os.path.getsize(path))
    except OSError:
        pass
    return sorted(sizes)


def camera_env(base: dict, profile: bool) -> dict:
    """Return the camera's environment: ``base`` with the shipped profile or with none."""
    env = {k: v for k, v in base.items() if k not in PROFILE_VARIABLES}
    if profile:
        env['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(PROFILE)
    return env


def _ns(stamp) -> int:
    """Return a ``builtin_interfaces/Time`` in nanoseconds."""
    return stamp.sec * 10 ** 9 + stamp.nanosec


def run(args) -> dict:
    """Run the loop for ``args.seconds``; return what was measured."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    from ipomdp_gaze.harness.processes import isolated_nodes, NodeProcess
    from ipomdp_gaze.harness.watch import LATCHED, Watch
    from ipomdp_gaze.msg_adapters import diagnostics
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import CameraInfo, Image
    from std_msgs.msg import Int32MultiArray
    cfg = ROOT / 'config'
    with isolated_nodes(args.domain, prefix='scene-camera-images-') as nodes:
        controller = nodes.start('controller', ['--params-file',
                                                cfg / 'faces_fovea_controller.yaml'])
        detector = nodes.start('detector', ['--params-file', cfg / 'faces_fovea_detector.yaml'])
        with Watch(args.domain, 'scene_camera_images', nodes) as watch:
            evidence = watch.record(Image, 'evidence_image', QoSProfile(
                depth=50, reliability=ReliabilityPolicy.BEST_EFFORT))
            infos = watch.record(CameraInfo, 'camera_info', QoSProfile(
                depth=50, reliability=ReliabilityPolicy.RELIABLE))
            fixations = watch.record(Int32MultiArray, 'fixation', LATCHED)
            seen_images = []
            if args.image_reader:
                watch.node.create_subscription(
                    Image, 'image',
                    lambda m: seen_images.append((time.monotonic(), _ns(m.header.stamp))),
                    QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
            ends = []
            for kind in ('found', 'gave_up'):
                watch.node.create_subscription(DiagnosticStatus, kind,
                                               lambda m, k=kind: ends.append(k), 10)
            status = []

            def on_diagnostics(msg):
                status.extend((time.monotonic(), diagnostics.values_of(item))
                              for item in msg.status
                              if item.name.endswith('foveal_detector: detector'))
            watch.node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics, 50)
            control = watch.status_values('gaze_controller: search')
            if not watch.wait_until(lambda: status and control, 60):
                raise RuntimeError('the nodes did not come up')
            rate = ['-p', f'rate_hz:={args.rate_hz}'] if args.rate_hz else []
            camera = NodeProcess('scene_camera', [
                '--params-file', cfg / 'faces_fovea_scene_camera.yaml', *rate],
                camera_env(nodes.env, args.profile), nodes.log_dir / 'scene_camera.log')
            nodes.processes.append(camera)
            camera.start()
            pids = {'controller': controller.proc.pid, 'detector': detector.proc.pid,
                    'camera': camera.proc.pid}
            sampler = Sampler(lambda: pids)
            sampler.start()
            if not watch.wait_until(lambda: infos, 60):
                raise RuntimeError('the scene camera sent nothing')
            segments = shm_segments(camera.proc.pid)
            t0 = time.monotonic()
            seen = 0
            while time.monotonic() - t0 < args.seconds:
                nodes.check()
                if len(ends) > seen:
                    seen = len(ends)
                    watch.reset()
                time.sleep(0.05)
            camera.stop()
            time.sleep(2.5)                 # the detector's next diagnostics: its last count
            sampler.halt.set()
            sampler.join(5)
            sent = [(t, _ns(m.header.stamp)) for t, m in list(infos)]
            used = [(t, _ns(m.header.stamp)) for t, m in list(evidence)]
            # counted from the first status a second after the camera's first image on: the
            # watch and the detector may match the camera at different times
            t_from, counted_from = next((t, v) for t, v in status if t > sent[0][0] + 1.0)
            result = {
                'seconds': args.seconds, 'profile': args.profile, 'segments': segments,
                'rate_hz': args.rate_hz,
                'info_stamps': sorted({s for t, s in sent if t > t_from}),
                'used_stamps': sorted({s for t, s in used if t > t_from}),
                'image_reader': args.image_reader,
                'reader_stamps': sorted({s for t, s in list(seen_images) if t > t_from}),
                'received': int(status[-1][1]['images_received']) - int(
                    counted_from['images_received']),
                'detector': dict(status[-1][1]), 'searches': len(ends),
                'evidence': [t for t, _ in used],
                'fixations': [(t, tuple(m.data)) for t, m in list(fixations)],
                'span': (sent[0][0], sent[-1][0]),
                'cpu': {name: float(np.mean([c for _, c, _ in s])) if s else None
                        for name, s in sampler.samples.items()},
                'load': os.getloadavg()[0]}
    return result


def report(r: dict) -> dict:
    """Summarise a run: images published and received, gaps and waits over 0.5 s."""
    d = r['detector']
    waits, left_out = fixation_waits(r['fixations'], r['evidence'], [r['span']])
    slow = np.sort(waits[waits > 0.5])[::-1]
    info, used = np.asarray(r['info_stamps']), np.asarray(r['used_stamps'])
    published = np.union1d(info, used)
    steps_s = np.diff(used) * 1e-9
    period_s = float(np.median(np.diff(published))) * 1e-9
    reader = {}
    if r.get('image_reader'):
        seen = np.asarray(r['reader_stamps'])
        published = np.union1d(published, seen)
        gaps_s = np.diff(seen) * 1e-9
        reader = {'second_reader_received': int(seen.size),
                  'second_reader_gaps_over_0.5s': [round(float(g), 2)
                                                   for g in np.sort(gaps_s[gaps_s > 0.5])]}
    return {
        'profile': r['profile'], 'seconds': r['seconds'], 'camera_shm_bytes': r['segments'],
        'camera_rate_hz': round(1 / period_s, 2),
        'published': int(round((published[-1] - published[0]) * 1e-9 / period_s)) + 1,
        'published_seen_here': int(published.size), 'received': r['received'],
        'camera_info_missed_here': int(np.setdiff1d(used, info).size),
        'used': int(used.size),
        'rejected': int(d['images_rejected']),
        'detector_ms_median': round(float(d['detector_ms_median']), 1),
        'images_skipped_between_used': int(np.sum(np.round(steps_s / period_s) - 1)),
        'stamp_gaps_over_0.5s': [round(float(g), 2) for g in np.sort(steps_s[steps_s > 0.5])],
        'fixations': int(waits.size), 'left_out': left_out,
        # a run with no fixation answered (a controller that never started) has no waits
        'wait_median_ms': round(1e3 * float(np.median(waits)), 1) if waits.size else None,
        'wait_p99_ms': round(1e3 * float(np.percentile(waits, 99)), 1) if waits.size else None,
        'wait_max_ms': round(1e3 * float(waits.max()), 1) if waits.size else None,
        'waits_over_0.5s': [round(float(w), 2) for w in slow],
        'searches': r['searches'],
        'cpu_percent': {k: round(100 * v) for k, v in r['cpu'].items() if v is not None},
        'load': round(r['load'], 1), **reader}


def main() -> int:
    """Parse the arguments, run, print one JSON line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--seconds', type=float, default=180.0)
    parser.add_argument('--profile', action='store_true',
                        help="the camera's process gets config/fastdds_large_images.xml")
    parser.add_argument('--rate-hz', type=float, default=0.0,
                        help="the camera's rate_hz (0: the shipped file's, 10 Hz)")
    parser.add_argument('--image-reader', action='store_true',
                        help='this process reads image too (reliable, depth 10), as a viewer '
                             'or the recorder would')
    parser.add_argument('--domain', type=int, default=None)
    args = parser.parse_args()
    if args.domain is None:
        from ipomdp_gaze.harness.processes import domain_id_for
        args.domain = domain_id_for()
    print(json.dumps(report(run(args))), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
