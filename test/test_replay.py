# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Which recorded search a replay follows (``replay.last_search``), on bags built by hand.

A bag may hold the first search of a demo and the one started by ``~/reset``. The reset is the
last uniform ``belief``; the target sent with it (an enabled controller) can arrive before that
belief, while a disabled controller sends its first target only when enabled again.
"""
from pathlib import Path
from types import SimpleNamespace

from ipomdp_gaze.drivers.replay import last_search
from ipomdp_gaze.files.bag import Bag, BagMessage
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
import numpy as np
import pytest

GRID = Grid(11, 11, 5.0)
HEAD = PanTiltMap(GRID)
START = GRID.center_index
OTHER = GRID.index(2, 3)


def _target(cell: int, stamp_s: float, arrival_s: float) -> BagMessage:
    pan, tilt = HEAD.angles(cell)
    sec = int(stamp_s)
    msg = SimpleNamespace(header=SimpleNamespace(stamp=SimpleNamespace(
        sec=sec, nanosec=int(round((stamp_s - sec) * 1e9)))),
        name=[HEAD.pan_joint, HEAD.tilt_joint], position=[pan, tilt])
    return BagMessage('/pan_tilt', int(arrival_s * 1e9), msg, 0)


def _belief(uniform: bool, arrival_s: float) -> BagMessage:
    data = np.full(GRID.n_cells, 1 / GRID.n_cells)
    if not uniform:
        data[OTHER] *= 2
    return BagMessage('/belief', int(arrival_s * 1e9), SimpleNamespace(data=data), 0)


def _bag(messages) -> Bag:
    return Bag(Path('bag'), sorted(messages, key=lambda m: m.time_ns), {}, 0, 0.0)


def _first_target(bag: Bag) -> tuple:
    cut = last_search(bag, HEAD, START)
    first = cut.topic('pan_tilt')[0].msg.header.stamp
    return first.sec + 1e-9 * first.nanosec, len(cut.topic('belief'))


def test_an_enabled_reset_is_pinned_by_the_target_that_arrived_before_its_belief():
    old = [_target(START, 100.0, 100.001), _belief(False, 100.3), _target(OTHER, 100.31, 100.32)]
    # The reset's target is stamped just after the belief was published and arrives first.
    reset = [_target(START, 101.0005, 101.001), _belief(True, 101.002),
             _belief(False, 101.3), _target(OTHER, 101.31, 101.32)]
    assert _first_target(_bag(old + reset)) == (101.0005, 2)


def test_a_disabled_reset_starts_at_its_belief_and_the_next_target_is_the_first():
    # The first search's target at the start cell is older than the window: not this search's.
    old = [_target(START, 100.0, 100.001), _belief(False, 100.3)]
    reset = [_belief(True, 101.0), _target(START, 101.02, 101.021), _belief(False, 101.3)]
    assert _first_target(_bag(old + reset)) == (101.02, 2)


def _frame(arrival_s: float, size: int) -> BagMessage:
    return BagMessage('/evidence_image', int(arrival_s * 1e9), SimpleNamespace(), size)


def test_the_rate_per_minute_is_not_extrapolated_from_a_short_search():
    """Issue 35: 0.6 s of frames gave '749.1 MB per minute'; say it is too short instead."""
    from ipomdp_gaze.drivers.replay import describe_size
    short = [_belief(True, 0.0)] + [_frame(0.1 + 0.15 * i, 1_000_000) for i in range(5)]
    bag = Bag(Path('bag'), short, {}, 5_000_000, 0.8)
    text = describe_size(bag)
    assert 'MB per minute of search (over' not in text, text
    assert '5 frames over 0.8 s: too short a search to extrapolate MB per minute of search' \
        in text and '375.0 MB per minute of recording' in text
    long = [_belief(True, 0.0)] + [_frame(0.5 * i, 1_000_000) for i in range(1, 11)]
    text = describe_size(Bag(Path('bag'), long, {}, 10_000_000, 5.0))
    assert '120.0 MB per minute of search (over 5.0 s of frames)' in text


def test_a_decision_is_said_in_the_shared_words():
    from ipomdp_gaze.drivers.replay import Decision
    assert Decision('found', GRID.index(5, 9), 0.994, 9).describe(GRID) == \
        'found at (5, 9) p=0.994 after 9 fixations'
    assert Decision('absent', None, 0.993, 13).describe(GRID) == \
        'absent p=0.993 that nobody is here after 13 fixations'
    assert Decision('found', GRID.index(6, 9), 0.62, 20, 'budget').describe(GRID) == \
        'found, forced by the fixation budget at (6, 9) p=0.620 after 20 fixations'


def test_record_says_what_it_wrote(tmp_path):
    """Issue 35: ``record`` printed nothing on Ctrl-C about what it wrote."""
    from ipomdp_gaze.commands.record import describe_written
    bag = tmp_path / 'bag'
    bag.mkdir()
    (bag / 'bag_0.mcap').write_bytes(b'x' * 1_500_000)
    topic = '  - {{topic_metadata: {{name: /{}, type: {}, serialization_format: cdr}}, ' \
        'message_count: {}}}\n'
    (bag / 'metadata.yaml').write_text(
        'rosbag2_bagfile_information:\n  version: 9\n  message_count: 12\n'
        '  storage_identifier: mcap\n  relative_file_paths: [bag_0.mcap]\n'
        '  starting_time: {nanoseconds_since_epoch: 1000}\n'
        '  duration: {nanoseconds: 2500000000}\n  topics_with_message_count:\n'
        + topic.format('belief', 'std_msgs/msg/Float64MultiArray', 9)
        + topic.format('found', 'geometry_msgs/msg/PointStamped', 1)
        + topic.format('pan_tilt', 'sensor_msgs/msg/JointState', 2)
        + topic.format('absent', 'std_msgs/msg/Float64', 0))
    assert describe_written(bag) == (f'wrote {bag}: 12 messages over 2.5 s, 1.50 MB (belief 9, '
                                     f'found 1, pan_tilt 2)')
    assert describe_written(tmp_path / 'none').startswith(
        'ipomdp-gaze record: nothing readable was written')


def test_a_damaged_message_in_a_bag_is_one_line_naming_it(tmp_path):
    from ipomdp_gaze.files.bag import open_writer, read_bag
    writer = open_writer(tmp_path / 'bag')
    conn = writer.add_connection('/note', 'std_msgs/msg/String')
    good = bytes([0, 1, 0, 0]) + (3).to_bytes(4, 'little') + b'hi\x00'
    writer.write(conn, 1_000, good)
    writer.write(conn, 2_000, bytes([0, 1, 0, 0]) + (10 ** 9).to_bytes(4, 'little') + b'hi\x00')
    writer.close()
    with pytest.raises(ValueError) as raised:
        read_bag(tmp_path / 'bag')
    message = str(raised.value)
    assert message.startswith(f'{tmp_path / "bag"}: a std_msgs/msg/String message on /note at '
                              '2000 ns cannot be read (a damaged bag?): ')
    assert '\n' not in message


def test_a_message_type_the_reader_does_not_know_is_named(tmp_path):
    from ipomdp_gaze.files.bag import open_writer, read_bag
    from rosbags.rosbag2 import StoragePlugin, Writer
    writer = Writer(tmp_path / 'bag', version=Writer.VERSION_LATEST,
                    storage_plugin=StoragePlugin.MCAP)
    writer.open()
    from rosbags.typesys import get_types_from_msg, get_typestore, Stores
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg('int32 x', 'my_robot/msg/Thing'))
    conn = writer.add_connection('/thing', 'my_robot/msg/Thing', typestore=store)
    writer.write(conn, 1_000, bytes([0, 1, 0, 0]) + (7).to_bytes(4, 'little'))
    writer.close()
    with pytest.raises(ValueError, match='/thing holds my_robot/msg/Thing, a message type this '
                                         'reader does not know'):
        read_bag(tmp_path / 'bag')
    assert open_writer                              # the writer of the package's own bags


def test_bags_without_rosbags_installed_are_one_line(tmp_path, monkeypatch):
    """QA: a rosdep/colcon install has no rosbags; the recorder died with a 16-line traceback."""
    import sys
    from ipomdp_gaze.files import bag
    monkeypatch.setitem(sys.modules, 'rosbags', None)          # import rosbags: ImportError
    for call in (lambda: bag.open_writer(tmp_path / 'new'), lambda: bag.read_bag(tmp_path)):
        with pytest.raises(ValueError, match=r'needs the rosbags package \(pip install '):
            call()
