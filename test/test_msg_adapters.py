# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""msg_adapters: every conversion between numpy and ROS messages (no DDS, no node)."""
from __future__ import annotations

import array
import math

from conftest import HAVE_ROS_MSGS
from ipomdp_gaze.files.render import MARK_RGB
from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
import numpy as np
import pytest

# The message packages (the `ros` extra): without them conftest skips every test here, and an
# installed but broken package fails them (IPOMDP_GAZE_REQUIRE_ROS: a skip fails too).
if HAVE_ROS_MSGS:
    from builtin_interfaces.msg import Time
    from diagnostic_msgs.msg import DiagnosticStatus
    from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays, images, joints, stamps
    from ipomdp_gaze.msg_adapters.grid_arrays import LayoutError
    from sensor_msgs.msg import Image, JointState
    from std_msgs.msg import (Float32MultiArray, Int32MultiArray, MultiArrayDimension,
                              MultiArrayLayout)

pytestmark = pytest.mark.ros

GRID = Grid(11, 11, 5.0)
DEG = math.pi / 180


def layout(*dims, offset=0):
    return MultiArrayLayout(dim=[MultiArrayDimension(label=label, size=size, stride=stride)
                                 for label, size, stride in dims], data_offset=offset)


def test_multiarray_layout_and_round_trip():
    values = np.random.default_rng(0).standard_normal(121)
    msg = grid_arrays.to_multiarray(values, GRID)
    dims = [(d.label, d.size, d.stride) for d in msg.layout.dim]
    assert dims == [('rows', 11, 121), ('cols', 11, 11)]
    assert msg.layout.data_offset == 0
    assert isinstance(msg.data, array.array) and msg.data.typecode == 'f'
    back = grid_arrays.from_multiarray(msg, GRID)
    np.testing.assert_array_equal(back, values.astype(np.float32))
    assert back.dtype == np.float64
    grid2d = grid_arrays.from_multiarray(grid_arrays.to_multiarray(values.reshape(11, 11), GRID),
                                         GRID)
    np.testing.assert_array_equal(grid2d, back)


def test_row_major_means_row_times_cols_plus_col():
    values = np.zeros((11, 11))
    values[2, 9] = 1.0
    msg = grid_arrays.to_multiarray(values, GRID)
    assert int(np.argmax(np.asarray(msg.data))) == 2 * 11 + 9


def test_to_multiarray_refuses_the_wrong_size():
    with pytest.raises(ValueError, match='121 values'):
        grid_arrays.to_multiarray(np.zeros(120), GRID)


@pytest.mark.parametrize('lay', [
    MultiArrayLayout(),
    layout(('cells', 121, 121)),
    layout(('rows', 11, 121), ('cols', 11, 11)),
    layout(('height', 11, 0), ('width', 11, 0)),
])
def test_accepted_layouts(lay):
    msg = Float32MultiArray(layout=lay, data=list(np.arange(121.0)))
    np.testing.assert_array_equal(grid_arrays.from_multiarray(msg, GRID), np.arange(121.0))


@pytest.mark.parametrize('lay, words', [
    (layout(('rows', 7, 49), ('cols', 7, 7)), 'layout is 7x7, the grid is 11x11'),
    (layout(('rows', 11, 121), ('cols', 11, 12)), 'stride 12, expected 11'),
    (layout(('rows', 11, 121), ('cols', 11, 11), offset=3), 'data_offset is 3'),
    (layout(('a', 11, 0), ('b', 11, 0), ('c', 1, 0)), '3 dimensions'),
    (layout(('cells', 120, 120)), 'layout is 120, the grid is 121'),
])
def test_layouts_that_disagree_with_the_grid(lay, words):
    msg = Float32MultiArray(layout=lay, data=[0.0] * 121)
    with pytest.raises(LayoutError, match=words):
        grid_arrays.from_multiarray(msg, GRID)


def test_empty_layout_with_the_wrong_length():
    with pytest.raises(EvidenceError, match='120 values, expected 121'):
        grid_arrays.from_multiarray(Float32MultiArray(data=[0.0] * 120), GRID)


def test_layout_error_is_an_evidence_error():
    assert issubclass(LayoutError, EvidenceError)


def test_ground_truth_round_trip_and_checks():
    msg = grid_arrays.ground_truth(GRID, GRID.index(3, 8))
    assert isinstance(msg, Int32MultiArray) and list(msg.data) == [3, 8]
    assert grid_arrays.cell_from_ground_truth(msg, GRID) == 41
    with pytest.raises(ValueError, match='outside'):
        grid_arrays.cell_from_ground_truth(Int32MultiArray(data=[11, 0]), GRID)
    with pytest.raises(ValueError, match=r'\[row, col\]'):
        grid_arrays.cell_from_ground_truth(Int32MultiArray(data=[1]), GRID)


# -- pan/tilt messages --------------------------------------------------------------------------
def test_joint_state_messages():
    head = PanTiltMap(GRID, pan_joint='head_pan', tilt_joint='head_tilt')
    msg = joints.joint_state(head, GRID.index(0, 10), Time(sec=5, nanosec=7))
    assert list(msg.name) == ['head_pan', 'head_tilt']
    np.testing.assert_allclose(msg.position, [-25 * DEG, -25 * DEG])
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (5, 7)
    reordered = JointState(name=['other', 'head_tilt', 'head_pan'], position=[9.0, 0.1, 0.2])
    assert joints.angles_from_joint_state(reordered, head) == (0.2, 0.1)
    with pytest.raises(ValueError, match="not 'head_pan'"):
        joints.angles_from_joint_state(JointState(name=['pan'], position=[0.0]), head)
    with pytest.raises(ValueError, match='no finite position'):
        joints.angles_from_joint_state(
            JointState(name=['head_pan', 'head_tilt'], position=[0.0]), head)


def test_ros2_control_commands():
    head = PanTiltMap(GRID)
    cell = GRID.index(1, 2)
    fwd = joints.forward_command(head, cell)
    np.testing.assert_allclose(fwd.data, head.angles(cell))
    traj = joints.joint_trajectory(head, cell, 0.75)
    assert list(traj.joint_names) == ['pan_joint', 'tilt_joint']
    assert len(traj.points) == 1
    np.testing.assert_allclose(traj.points[0].positions, head.angles(cell))
    assert (traj.points[0].time_from_start.sec, traj.points[0].time_from_start.nanosec) == \
        (0, 750_000_000)
    assert (traj.header.stamp.sec, traj.header.stamp.nanosec) == (0, 0)


# -- images -------------------------------------------------------------------------------------
def test_belief_image_size_encoding_and_marks():
    belief = np.full(121, 0.1 / 120)
    peak, fixation = GRID.index(2, 3), GRID.index(8, 8)
    belief[peak] = 0.9
    msg = images.belief_image(belief, GRID, fixation, 16, Time(sec=1))
    assert (msg.height, msg.width, msg.encoding, msg.step) == (176, 176, 'rgb8', 528)
    img = images.rgb8_array(msg)
    assert tuple(img[2 * 16 + 8, 3 * 16 + 8]) == (253, 231, 37)      # the peak: yellow
    assert tuple(img[0, 0]) == (68, 1, 84)                           # near zero: dark purple
    assert tuple(img[8 * 16, 8 * 16 + 8]) == MARK_RGB         # outline of the fixation
    assert tuple(img[8 * 16 + 8, 8 * 16 + 8]) != MARK_RGB     # its inside is the belief


@pytest.mark.parametrize('big_endian', [False, True])
def test_evidence_image_round_trip(big_endian):
    values = np.random.default_rng(1).standard_normal(121)
    values[5] = np.nan
    msg = images.evidence_image(values, GRID, Time(sec=3))
    assert (msg.height, msg.width, msg.encoding, msg.step) == (11, 11, '32FC1', 44)
    if big_endian:
        raw = values.astype('>f4').tobytes()
        msg = Image(height=11, width=11, encoding='32FC1', is_bigendian=1, step=44, data=raw)
    back = images.evidence_from_image(msg, GRID)
    np.testing.assert_array_equal(back, values.astype(np.float32))


@pytest.mark.parametrize('big_endian', [False, True])
def test_evidence_image_with_offsets_round_trip(big_endian):
    rng = np.random.default_rng(2)
    values = rng.integers(0, 10, 121).astype(float)
    offsets = np.where(values[:, None] > 0, rng.uniform(-0.5, 0.5, (121, 2)), np.nan)
    msg = images.evidence_image(values, GRID, Time(sec=3), 'fixation/4', offsets)
    assert (msg.height, msg.width, msg.encoding, msg.step) == (11, 11, '32FC3', 132)
    if big_endian:
        raw = np.concatenate([values[:, None], offsets], axis=1).astype('>f4').tobytes()
        msg = Image(height=11, width=11, encoding='32FC3', is_bigendian=1, step=132, data=raw)
    back, back_offsets = images.evidence_and_offsets(msg, GRID)
    np.testing.assert_array_equal(back, values.astype(np.float32))
    np.testing.assert_array_equal(back_offsets, offsets.astype(np.float32))
    np.testing.assert_array_equal(images.evidence_from_image(msg, GRID), back)
    plain = images.evidence_and_offsets(images.evidence_image(values, GRID, Time(sec=3)), GRID)
    assert plain[1] is None
    with pytest.raises(EvidenceError, match='step'):
        images.evidence_and_offsets(Image(height=11, width=11, encoding='32FC3', step=44,
                                          data=np.zeros(121, '<f4').tobytes()), GRID)
    with pytest.raises(ValueError, match='offsets of shape'):
        images.evidence_image(values, GRID, Time(sec=3), '', offsets[:5])


@pytest.mark.parametrize('big_endian', [False, True])
def test_evidence_image_with_groups_round_trip(big_endian):
    rng = np.random.default_rng(3)
    values = rng.integers(0, 10, 121).astype(float)
    offsets = np.where(values[:, None] > 0, rng.uniform(-0.5, 0.5, (121, 2)), np.nan)
    groups = np.where(values > 6, rng.integers(1, 3, 121), 0).astype(float)
    msg = images.evidence_image(values, GRID, Time(sec=3), 'fixation/4', offsets, groups)
    assert (msg.height, msg.width, msg.encoding, msg.step) == (11, 11, '32FC4', 176)
    if big_endian:
        raw = np.concatenate([values[:, None], offsets, groups[:, None]],
                             axis=1).astype('>f4').tobytes()
        msg = Image(height=11, width=11, encoding='32FC4', is_bigendian=1, step=176, data=raw)
    back, back_offsets, back_groups = images.evidence_channels(msg, GRID)
    np.testing.assert_array_equal(back, values.astype(np.float32))
    np.testing.assert_array_equal(back_offsets, offsets.astype(np.float32))
    np.testing.assert_array_equal(back_groups, groups)
    two = images.evidence_and_offsets(msg, GRID)
    assert len(two) == 2 and np.array_equal(two[1], back_offsets, equal_nan=True)
    three = images.evidence_image(values, GRID, Time(sec=3), '', offsets)
    assert images.evidence_channels(three, GRID)[2] is None
    with pytest.raises(ValueError, match='give both'):
        images.evidence_image(values, GRID, Time(sec=3), '', None, groups)
    with pytest.raises(ValueError, match='groups of shape'):
        images.evidence_image(values, GRID, Time(sec=3), '', offsets, groups[:5])
    with pytest.raises(EvidenceError, match='step'):
        images.evidence_channels(Image(height=11, width=11, encoding='32FC4', step=132,
                                       data=np.zeros(363, '<f4').tobytes()), GRID)


def test_evidence_image_with_row_padding():
    values = np.arange(121, dtype=np.float32).reshape(11, 11)
    padded = np.zeros((11, 12), dtype='<f4')
    padded[:, :11] = values
    msg = Image(height=11, width=11, encoding='32FC1', step=48, data=padded.tobytes())
    np.testing.assert_array_equal(images.evidence_from_image(msg, GRID), values.ravel())


@pytest.mark.parametrize('kwargs, err, words', [
    ({'encoding': 'mono8'}, LayoutError, "encoding is 'mono8'"),
    ({'height': 7, 'width': 7, 'step': 28}, LayoutError, '7x7'),
    ({'step': 40}, EvidenceError, 'step'),
])
def test_bad_evidence_images(kwargs, err, words):
    fields = {'height': 11, 'width': 11, 'encoding': '32FC1', 'step': 44,
              'data': np.zeros(121, '<f4').tobytes()}
    fields.update(kwargs)
    with pytest.raises(err, match=words):
        images.evidence_from_image(Image(**fields), GRID)


# -- diagnostics and stamps ---------------------------------------------------------------------
def test_a_lost_event_never_says_minus_zero():
    from ipomdp_gaze.msg_adapters.diagnostics import lost_status
    message = lost_status('x', 1, 2, 3, -1e-17, -0.0, 4, 1.0).message
    assert 'most likely cell now 0.0000, nobody here 0.0000' in message and '-0' not in message


def test_lost_and_reacquired_events_round_trip():
    lost = diagnostics.lost_status('/gaze_controller: lost', 2, 9, 31, 0.41, 0.35, 17, 4.25)
    assert lost.level == DiagnosticStatus.WARN and 'row 2, col 9' in lost.message
    assert diagnostics.parse_lost(lost) == {
        'row': 2, 'col': 9, 'cell': 31, 'probability': 0.41, 'absent_probability': 0.35,
        'fixations': 17, 'seconds_tracked': 4.25}
    again = diagnostics.reacquired_status('/gaze_controller: reacquired', 4, 1, 45, -0.3, 0.05,
                                          0.97, 25, 1.5)
    assert again.level == DiagnosticStatus.OK and '1.50 s after it was lost' in again.message
    assert diagnostics.parse_reacquired(again) == {
        'row': 4, 'col': 1, 'cell': 45, 'pan_rad': -0.3, 'tilt_rad': 0.05, 'probability': 0.97,
        'fixations': 25, 'seconds_lost': 1.5}
    with pytest.raises(ValueError, match='lacks'):
        diagnostics.parse_lost(diagnostics.found_status('x', 1, 1, 12, 0.0, 0.0, 0.9, 3))


def test_found_event_round_trip():
    msg = diagnostics.found_status('/gaze_controller: found', 3, 7, 40, 0.1, -0.2, 0.9734, 6)
    assert 'row 3, col 7' in msg.message
    assert diagnostics.parse_found(msg) == {
        'row': 3, 'col': 7, 'cell': 40, 'fixations': 6, 'pan_rad': 0.1, 'tilt_rad': -0.2,
        'probability': 0.9734, 'ended': 'confidence', 'confidence': None, 'radius': 0}
    # Issue 35: a decision the fixation budget forced says so, with the confidence it missed.
    forced = diagnostics.found_status('/gaze_controller: found', 3, 7, 40, 0.1, -0.2, 0.62, 20,
                                      'budget', 0.95)
    assert forced.message.endswith('after 20 fixations, forced by the fixation budget below '
                                   'the confidence 0.95')
    assert diagnostics.parse_found(forced)['ended'] == 'forced:budget'
    assert diagnostics.parse_found(forced)['confidence'] == 0.95
    absent = diagnostics.absent_status('/gaze_controller: absent', 0.993, 13, '', 0.99)
    assert absent.message == ('no target in the grid: probability 0.9930 that nobody is there '
                              'after 13 fixations (reached the confidence 0.99)')
    assert diagnostics.parse_absent(absent) == {'probability': 0.993, 'fixations': 13,
                                                'ended': 'confidence', 'confidence': 0.99}
    msg.values = msg.values[:2]
    with pytest.raises(ValueError, match='lacks'):
        diagnostics.parse_found(msg)


def test_status_levels_and_values():
    status = diagnostics.status('x', 'warn', 'no evidence received', {'enabled': True, 'r': 0.5})
    assert status.level == diagnostics.LEVELS['warn']
    assert diagnostics.values_of(status) == {'enabled': 'true', 'r': '0.5'}
    array_msg = diagnostics.diagnostic_array([status], Time(sec=2))
    assert array_msg.header.stamp.sec == 2 and len(array_msg.status) == 1


def test_stamps():
    t = stamps.from_seconds(12.25)
    assert (t.sec, t.nanosec) == (12, 250_000_000)
    assert stamps.to_seconds(t) == 12.25
    assert stamps.is_zero(Time()) and not stamps.is_zero(t)
    with pytest.raises(ValueError):
        stamps.from_seconds(-1.0)


def _image_msg(pixels: np.ndarray, encoding: str, pad: int = 0) -> Image:
    """Build an image message of ``pixels`` (in the encoding's channel order), rows padded."""
    height, width = pixels.shape[:2]
    rows = pixels.reshape(height, -1)
    step = rows.shape[1] + pad
    data = np.zeros((height, step), np.uint8)
    data[:, :rows.shape[1]] = rows
    msg = Image(height=height, width=width, encoding=encoding, step=step)
    msg.data = data.tobytes()
    return msg


@pytest.mark.parametrize('encoding, pad', [('mono8', 0), ('rgb8', 0), ('bgr8', 0),
                                           ('mono8', 5), ('rgb8', 3), ('bgr8', 7)])
def test_camera_images_are_read_without_copying_the_pixels(encoding, pad):
    rng = np.random.default_rng(1)
    shape = (6, 9) if encoding == 'mono8' else (6, 9, 3)
    rgb = rng.integers(0, 256, shape, dtype=np.uint8)
    sent = rgb[:, :, ::-1] if encoding == 'bgr8' else rgb
    msg = _image_msg(np.ascontiguousarray(sent), encoding, pad)
    got = images.image_array(msg)
    np.testing.assert_array_equal(got, rgb)                  # RGB order, padding dropped
    assert np.shares_memory(got, np.frombuffer(msg.data, np.uint8))
    assert not got.flags.writeable


def test_camera_image_and_camera_info_round_trip():
    rgb = np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3)
    stamp = Time(sec=3, nanosec=7)
    msg = images.camera_image(rgb, stamp, 'cam')
    assert (msg.encoding, msg.step, msg.header.frame_id) == ('rgb8', 15, 'cam')
    np.testing.assert_array_equal(images.image_array(msg), rgb)
    assert images.camera_image(rgb[:, :, 0], stamp).encoding == 'mono8'
    from ipomdp_gaze.model.head_camera import PinholeCamera
    camera = PinholeCamera.from_fov(320, 240, 25.0)
    info = images.camera_info(camera, stamp, 'cam')
    assert (info.width, info.height, info.header.stamp) == (320, 240, stamp)
    assert list(info.p)[:3] == [camera.fx, 0.0, camera.cx]
    assert images.camera_from_info(info) == camera


@pytest.mark.parametrize('change, words', [
    ({'encoding': '16UC1'}, "unsupported image encoding '16UC1'"),
    ({'encoding': 'rgba8'}, "unsupported image encoding 'rgba8'"),
    ({'width': 0}, 'empty image'),
    ({'data': b''}, 'empty image'),
    ({'width': 5000, 'step': 15000}, 'larger than 4096 px'),
    ({'step': 20}, 'step 20 is less than width 9 x 3'),
    ({'step': 40}, 'expected step 40 x height 6'),
    ({'height': 7}, 'expected step 27 x height 7'),
    ({'data': bytes(161)}, 'image data has 161 bytes'),
])
def test_malformed_camera_images_are_refused_with_the_reason(change, words):
    msg = _image_msg(np.zeros((6, 9, 3), np.uint8), 'rgb8')
    for key, value in change.items():
        setattr(msg, key, value)
    with pytest.raises(images.ImageError, match=words):
        images.image_array(msg)


def test_bad_camera_info_is_refused():
    from sensor_msgs.msg import CameraInfo
    with pytest.raises(images.ImageError, match='no image size'):
        images.camera_from_info(CameraInfo())
    with pytest.raises(images.ImageError, match='fx and fy'):
        images.camera_from_info(CameraInfo(width=4, height=3, k=[0.0] * 8 + [1.0]))


def test_fixation_messages_are_row_col():
    msg = grid_arrays.row_col(GRID, GRID.index(3, 8))
    assert isinstance(msg, Int32MultiArray) and list(msg.data) == [3, 8]
    assert grid_arrays.cell_from_row_col(msg, GRID, 'fixation') == GRID.index(3, 8)
    msg.data = [3, 11]
    with pytest.raises(ValueError, match=r'fixation \(3, 11\) is outside'):
        grid_arrays.cell_from_row_col(msg, GRID, 'fixation')


def test_a_binned_or_cropped_camera_info_describes_the_images_it_goes_with():
    """QA: REP 104's binning and roi were ignored, so every binned image was 'the wrong size'."""
    from ipomdp_gaze.model.head_camera import PinholeCamera
    from sensor_msgs.msg import CameraInfo, RegionOfInterest
    k = [800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0]
    binned = images.camera_from_info(CameraInfo(width=640, height=480, k=k, binning_x=2,
                                                binning_y=2))
    assert binned == PinholeCamera.from_k(320, 240, [400.0, 0, 160.0, 0, 400.0, 120.0, 0, 0, 1])
    roi = RegionOfInterest(x_offset=100, y_offset=40, width=320, height=240)
    cropped = images.camera_from_info(CameraInfo(width=640, height=480, k=k, roi=roi))
    assert cropped == PinholeCamera.from_k(320, 240, [800.0, 0, 220.0, 0, 800.0, 200.0, 0, 0, 1])
    assert cropped.fov_deg[0] < 0.55 * binned.fov_deg[0]             # about half the view
    roi = RegionOfInterest(x_offset=400, y_offset=0, width=320, height=240)
    with pytest.raises(images.ImageError, match=r'its roi \(400, 0, 320x240\) is not inside'):
        images.camera_from_info(CameraInfo(width=640, height=480, k=k, roi=roi))
