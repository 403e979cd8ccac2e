# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Worst time and memory per frame of the ``foveal_detector`` node, from small to 4096 px images.

For each mode and image size a fresh node (its own process, shipped models, a private domain)
serves ``FRAMES`` fixations, each answered by one image of that size (a held-out test scene or
pan/tilt view, enlarged with nearest neighbours; in ``camera`` mode with the ``camera_info`` of
the enlarged camera and the joint state of the same stamp). Reported per size: the node's worst
processing time of a frame (``detector_ms_last`` in ``/diagnostics``: the resize on arrival,
the fovea or view, the detector and the counts), the worst time from sending the image to
receiving its counts here (DDS transport of the image included), and the node's peak resident
memory (``VmHWM`` of ``/proc/<pid>/status``). Images more than twice the model's calibration
image on a side are resized on arrival (:mod:`ipomdp_gaze.vision.detection`), so the detector's
cost
stops growing with the image; what still grows is the message itself (a 4096x4096 ``rgb8``
image is 48 MiB, which rclpy deserialises into the node).
"""
import time

import cv2
from ipomdp_gaze.harness.processes import domain_id_for, isolated_nodes
from ipomdp_gaze.harness.watch import LATCHED, Watch
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.msg_adapters import grid_arrays, images, joints
from ipomdp_gaze.vision.detection import build_setup, scaled_camera
from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry, shipped_camera
from ipomdp_gaze.vision.scenes import PAPER_TASK, SceneSet
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import CameraInfo, Image, JointState
from std_msgs.msg import Int32MultiArray

TITLE = 'Foveal detector node: worst time and memory per frame, up to 4096 px images'
ORDER = 61
SIZES = {'fovea': [(420, 420), (840, 840), (2048, 2048), (4096, 4096)],
         'camera': [(320, 240), (640, 480), (2048, 1536), (4096, 3072)]}
MIB = 2 ** 20


def peak_rss(pid: int) -> int:
    """Peak resident set size of a process (``VmHWM``), bytes."""
    with open(f'/proc/{pid}/status') as f:
        for line in f:
            if line.startswith('VmHWM:'):
                return int(line.split()[1]) * 1024
    return 0


def pictures(mode: str, size, n: int):
    """``n`` ``(image, cell)`` pairs of this size; the cell is the fixation it answers."""
    setup = build_setup(mode)
    grid = setup.grid
    out = []
    for seed in range(n):
        if mode == 'fovea':
            image = SceneSet('test', **PAPER_TASK, color='rgb', seed=seed).scene(0).image
            cell = grid.index(10, 10)
        else:
            geometry = SceneGeometry(grid, shipped_camera())
            scene = PanTiltSceneSet('test', geometry, seed=seed).scene(0)
            cell = grid.index(*scene.cell)
            image = geometry.render(scene.image, scene.cell)
        out.append((cv2.resize(image, size, interpolation=cv2.INTER_NEAREST), cell))
    return grid, out


def measure(mode: str, size, n: int) -> dict:
    """Serve ``n`` fixations with images of ``size`` by a fresh node; worst costs."""
    grid, frames = pictures(mode, size, n)
    head = PanTiltMap(grid)
    camera = scaled_camera(shipped_camera(), *size)
    domain = domain_id_for()
    with isolated_nodes(domain, prefix='ipomdp-gaze-bench-') as nodes:
        proc = nodes.start('detector', ['-p', f'mode:={mode}', '-p', 'diagnostics_period_s:=0.05'])
        with Watch(domain, 'bench_pixel_worst', nodes) as watch:
            status = watch.status_values('foveal_detector: detector')
            counts = watch.record(Image, 'evidence_image',
                                  QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
            image_pub = watch.publisher(Image, 'image')
            info_pub = watch.publisher(CameraInfo, 'camera_info')
            joint_pub = watch.publisher(JointState, 'joint_states')
            fixation_pub = watch.publisher(Int32MultiArray, 'fixation', LATCHED)
            pubs = [image_pub] + ([info_pub, joint_pub] if mode == 'camera' else [])
            if not watch.wait_until(
                    lambda: status and all(p.get_subscription_count() for p in pubs), 60):
                raise RuntimeError('the detector did not come up')
            trips, node_ms = [], []
            for picture, cell in frames:
                asked = int(status[-1]['fixations_received'])
                fixation_pub.publish(grid_arrays.row_col(grid, cell))
                if not watch.wait_until(
                        lambda: int(status[-1]['fixations_received']) > asked, 30, 0.002):
                    raise RuntimeError('the detector did not take a fixation')
                stamp = watch.node.get_clock().now().to_msg()
                if mode == 'camera':
                    info_pub.publish(images.camera_info(camera, stamp))
                    joint_pub.publish(joints.joint_state(head, cell, stamp))
                msg = images.camera_image(picture, stamp)
                k = len(counts)
                t0 = time.monotonic()
                image_pub.publish(msg)
                # joint_states and camera_info are best effort, as a driver streams them: one
                # may be lost, so they are sent again (same stamp) until the counts come, as a
                # stream would.
                for _ in range(300):
                    if watch.wait_until(lambda: len(counts) > k, 0.2, 0.001):
                        break
                    if mode == 'camera':
                        info_pub.publish(images.camera_info(camera, stamp))
                        joint_pub.publish(joints.joint_state(head, cell, stamp))
                else:
                    raise RuntimeError(f'no counts for a {size} image: {status[-1]}')
                trips.append(counts[k][0] - t0)
                done = int(status[-1]['images_processed']) + 1
                watch.wait_until(lambda: int(status[-1]['images_processed']) >= done, 10)
                node_ms.append(float(status[-1]['detector_ms_last']))
            final = dict(status[-1])
            peak = peak_rss(proc.proc.pid)
        codes = [code for _, code in nodes.stop()]
    return {'node_ms': max(node_ms), 'trip_ms': 1e3 * max(trips), 'peak_mib': peak / MIB,
            'pixels': int(final['pixels_per_fixation_last']),
            'resized': int(final['images_resized']), 'processed': int(final['images_processed']),
            'held': int(final['images_held']), 'codes': codes}


def bench(ctx) -> str:
    """Measure each mode and size with a fresh node."""
    n = 2 if ctx.quick else 4
    lines = [f'{n} frames per size, a fresh node per size; worst of the {n}. The node resizes '
             "images more than twice its model's calibration image (fovea 420x420, camera "
             '320x240) on arrival.', '',
             '| mode | image | node ms per frame (worst) | image sent to counts ms (worst) | '
             'detector pixels | resized | node peak RSS MiB |', '|---|---|---|---|---|---|---|']
    for mode, sizes in SIZES.items():
        for size in sizes:
            ctx.log(f'{mode} {size[0]}x{size[1]}')
            r = measure(mode, size, n)
            lines.append(f"| {mode} | {size[0]}x{size[1]} | {r['node_ms']:.0f} | "
                         f"{r['trip_ms']:.0f} | {r['pixels']:,} | "
                         f"{r['resized']}/{r['processed']} | {r['peak_mib']:.0f} |")
            if any(r['codes']):
                lines.append(f"| | exit codes {r['codes']} | | | | | |")
    lines += ['', 'Before the resize rule (issue 26) a 2048x2048 camera-mode view took about '
              '1.5 s and 446 MB, and 4096x4096 about 6.3 s and 1.1 GB.']
    return '\n'.join(lines) + '\n'
