# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The shipped Fast DDS profile for image publishers (``config/fastdds_large_images.xml``).

Fast DDS sends large samples through a shared-memory segment of the sending process, 512 KB by
default; on a loaded machine images that do not fit were lost and the detector waited seconds
for one (docs/ros_measured.md). The profile must load in the Fast DDS that rclpy ships, give the
process a 32 MiB segment, and still talk to a process that does not use it.
"""
import json
import subprocess
import sys

from conftest import config_path
import pytest

pytestmark = pytest.mark.ros

PROFILE = 'fastdds_large_images.xml'
SEGMENT_BYTES = 32 * 2 ** 20
# A publisher process: prints the sizes of its Fast DDS shared-memory segments, then streams
# 1920x1080 bgr8 images (reliable, depth 10, as a typical driver) until SIGTERM.
PUBLISHER = """
import json, os, re, sys, time
import rclpy
from rclpy.node import Node
from sensor_msgs.msg import Image
rclpy.init(args=[])
node = Node('profile_camera')
pub = node.create_publisher(Image, 'profile_image', 10)
sizes = set()
for line in open('/proc/self/maps'):
    path = line.split()[-1]
    if re.fullmatch(r'/dev/shm/fastrtps_[0-9a-f]+', path):
        sizes.add(os.path.getsize(path))
print(json.dumps(sorted(sizes)), flush=True)
data = bytes(1920 * 1080 * 3)
while rclpy.ok():
    try:
        pub.publish(Image(height=1080, width=1920, encoding='bgr8', step=3 * 1920, data=data))
    except Exception:
        break                                  # SIGTERM shut rclpy down
    time.sleep(0.1)
"""


def start_publisher(ros_env, profile):
    """Start the publisher process, with ``profile`` as its default Fast DDS profile or none."""
    env = dict(ros_env, RMW_IMPLEMENTATION='rmw_fastrtps_cpp')
    for key in ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE'):
        env.pop(key, None)
    if profile:
        env['FASTRTPS_DEFAULT_PROFILES_FILE'] = profile
    return subprocess.Popen([sys.executable, '-c', PUBLISHER], env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def segments(proc) -> list[int]:
    """Read the segment sizes the publisher prints first."""
    line = proc.stdout.readline()
    assert line, proc.stderr.read()[-2000:]
    return json.loads(line)


def stop(proc) -> str:
    """Stop the publisher; return what it wrote to stderr."""
    proc.terminate()
    try:
        _, err = proc.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    return err


def test_the_profile_loads_raises_the_segment_to_32_mib_and_a_plain_reader_is_served(
        ros_env, probe):
    """
    The profile loads without an XML error and makes the segment 32 MiB; images still flow.

    Without it the segment is smaller than one 640x480 bgr8 image; a reader without the profile
    (the detector's case) receives the images of a publisher that has it.
    """
    from sensor_msgs.msg import Image
    plain = start_publisher(ros_env, None)
    try:
        default_sizes = segments(plain)
    finally:
        stop(plain)
    assert default_sizes and max(default_sizes) < 640 * 480 * 3
    profile = config_path(PROFILE)
    got = probe.record(Image, 'profile_image', 1)
    proc = start_publisher(ros_env, profile)
    try:
        sizes = segments(proc)
        served = probe.wait_until(lambda: got, 30)
    finally:
        err = stop(proc)
    assert 'XMLPARSER' not in err and 'Error' not in err, err[-2000:]
    assert sizes and max(sizes) >= SEGMENT_BYTES
    assert served, 'a reader without the profile received no image'
    assert (got[0][1].width, got[0][1].height) == (1920, 1080)
