# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A bag split into MCAP files by size or duration, as ``ros2 bag record --max-bag-size`` does.

Written with :func:`ipomdp_gaze.files.bag.open_writer` and read back with ``rosbags``' own
reader (what ``ros2 bag play`` reads: the files one after the other) and with ``read_bag``; the
recorder's split over DDS is in test_ros_record.py.
"""
from pathlib import Path
import re

import numpy as np
import pytest
import yaml


def _int32(value: int) -> bytes:
    """Serialize ``value`` as a ``std_msgs/msg/Int32`` (CDR, little endian)."""
    return bytes([0, 1, 0, 0]) + value.to_bytes(4, 'little', signed=True)


def _write(path: Path, messages: list, **limits) -> None:
    """Write ``(topic, time_ns)`` messages, each an Int32 of its time in µs, in this order."""
    from ipomdp_gaze.files.bag import open_writer
    writer = open_writer(path, **limits)
    writer.set_custom_data('ipomdp_gaze/version', 'test')
    connections = {}
    for topic, stamp in messages:
        if topic not in connections:
            connections[topic] = writer.add_connection(topic, 'std_msgs/msg/Int32')
        writer.write(connections[topic], stamp, _int32(stamp // 1000))
    writer.set_custom_data('ipomdp_gaze/namespace', '/head1')
    writer.close()


def _meta(path: Path) -> dict:
    return yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']


def _rosbags(path: Path) -> list:
    """``(topic, time_ns, data)`` in the order rosbags' reader gives them."""
    from rosbags.rosbag2 import Reader
    with Reader(path) as reader:
        return [(c.topic, t, bytes(d)) for c, t, d in reader.messages()]


# Received in this order: a message can come a little after a later one (another topic the
# executor took first), also around a split.
ARRIVALS = [('/a', 0), ('/b', 400_000_000), ('/a', 1_100_000_000), ('/b', 1_000_000_000),
            ('/b', 1_500_000_000), ('/a', 2_300_000_000), ('/b', 2_200_000_000),
            ('/a', 3_000_000_000), ('/b', 3_200_000_000), ('/a', 3_300_000_000)]


def test_a_bag_split_by_duration_lists_its_files_as_rosbag2_does(tmp_path):
    bag = tmp_path / 'session'
    _write(bag, ARRIVALS, max_file_duration_ns=1_000_000_000)
    meta = _meta(bag)
    names = ['session_0.mcap', 'session_1.mcap', 'session_2.mcap']
    assert sorted(p.name for p in bag.iterdir()) == sorted(names + ['metadata.yaml'])
    assert meta['version'] == 9 and meta['storage_identifier'] == 'mcap'
    assert meta['relative_file_paths'] == names
    # A file ends before a message more than 1 s after its first (1.1 s, 2.3 s; not 3.3 s,
    # exactly 1 s after); a message received before that split but written after it (1.0 s,
    # 2.2 s) is in the file before.
    assert meta['files'] == [
        {'path': 'session_0.mcap', 'starting_time': {'nanoseconds_since_epoch': 0},
         'duration': {'nanoseconds': 1_000_000_000}, 'message_count': 3},
        {'path': 'session_1.mcap', 'starting_time': {'nanoseconds_since_epoch': 1_100_000_000},
         'duration': {'nanoseconds': 1_100_000_000}, 'message_count': 3},
        {'path': 'session_2.mcap', 'starting_time': {'nanoseconds_since_epoch': 2_300_000_000},
         'duration': {'nanoseconds': 1_000_000_000}, 'message_count': 4}]
    assert meta['message_count'] == 10
    assert meta['starting_time'] == {'nanoseconds_since_epoch': 0}
    assert meta['duration'] == {'nanoseconds': 3_300_000_000}
    assert {t['topic_metadata']['name']: t['message_count']
            for t in meta['topics_with_message_count']} == {'/a': 5, '/b': 5}
    assert meta['custom_data'] == {'ipomdp_gaze/version': 'test',
                                   'ipomdp_gaze/namespace': '/head1'}
    # rosbags reads the files one after the other: every message, in time order.
    read = _rosbags(bag)
    assert [(topic, stamp) for topic, stamp, _ in read] == sorted(ARRIVALS, key=lambda m: m[1])
    assert all(data == _int32(stamp // 1000) for _, stamp, data in read)


def test_a_split_bag_reads_as_the_unsplit_bag_of_the_same_messages(tmp_path):
    from ipomdp_gaze.files.bag import read_bag
    _write(tmp_path / 'one', ARRIVALS)
    _write(tmp_path / 'split', ARRIVALS, max_file_duration_ns=500_000_000)
    one, split = read_bag(tmp_path / 'one'), read_bag(tmp_path / 'split')
    assert [p.name for p in (tmp_path / 'one').glob('*.mcap')] == ['one.mcap']
    assert len(_meta(tmp_path / 'split')['relative_file_paths']) == 4
    assert [(m.topic, m.time_ns, m.msg.data) for m in split.messages] == \
        [(m.topic, m.time_ns, m.msg.data) for m in one.messages]
    assert [m.time_ns for m in split.messages] == sorted(t for _, t in ARRIVALS)
    assert split.custom_data == one.custom_data and split.namespace == '/head1'
    assert split.duration_s == one.duration_s
    assert split.size_bytes == sum(p.stat().st_size for p in (tmp_path / 'split').iterdir())


@pytest.mark.parametrize('compression', ['', 'zstd'])
def test_a_bag_split_by_size_has_files_of_that_size_on_disk(tmp_path, compression):
    from ipomdp_gaze.files.bag import open_writer, read_bag
    rng = np.random.default_rng(3)
    writer = open_writer(tmp_path / 'bag', compression, max_file_bytes=1_500_000)
    image = writer.add_connection('/image', 'sensor_msgs/msg/Image')
    from ipomdp_gaze.files.bag import _typestore
    store = _typestore()
    Image = store.types['sensor_msgs/msg/Image']
    Header = store.types['std_msgs/msg/Header']
    Time = store.types['builtin_interfaces/msg/Time']
    for i in range(40):                     # 40 noisy 320x240 images: 9.2 MB
        pixels = rng.integers(0, 256, 320 * 240 * 3, dtype=np.uint8)
        msg = Image(Header(Time(i, 0), 'camera'), 240, 320, 'rgb8', 0, 960, pixels)
        writer.write(image, i * 100_000_000, store.serialize_cdr(msg, Image.__msgtype__))
    writer.close()
    meta = _meta(tmp_path / 'bag')
    files = [tmp_path / 'bag' / name for name in meta['relative_file_paths']]
    sizes = [f.stat().st_size for f in files]
    assert len(files) >= 3, sizes
    assert all(size >= 1_500_000 for size in sizes[:-1]), sizes
    assert [f['message_count'] for f in meta['files']] and \
        sum(f['message_count'] for f in meta['files']) == 40
    read = read_bag(tmp_path / 'bag')
    assert [m.msg.header.stamp.sec for m in read.messages] == list(range(40))
    assert [t for _, t, _ in _rosbags(tmp_path / 'bag')] == [i * 100_000_000 for i in range(40)]


def test_a_bag_with_nothing_recorded_is_one_empty_file(tmp_path):
    from ipomdp_gaze.files.bag import read_bag
    _write(tmp_path / 'bag', [], max_file_bytes=1_000_000)
    meta = _meta(tmp_path / 'bag')
    assert meta['relative_file_paths'] == ['bag_0.mcap'] and meta['message_count'] == 0
    assert read_bag(tmp_path / 'bag').messages == []


@pytest.mark.parametrize('limits, message', [
    ({'max_file_bytes': -1}, 'max_file_bytes must be 0 (no split) or more, got -1'),
    ({'max_file_duration_ns': -5}, 'max_file_duration_ns must be 0 (no split) or more, got -5'),
])
def test_a_negative_split_limit_is_refused(tmp_path, limits, message):
    from ipomdp_gaze.files.bag import open_writer
    with pytest.raises(ValueError, match=re.escape(message)):
        open_writer(tmp_path / 'bag', **limits)
    assert not (tmp_path / 'bag').exists()


def test_record_says_how_many_files_it_wrote(tmp_path):
    from ipomdp_gaze.commands.record import describe_written
    _write(tmp_path / 'bag', ARRIVALS, max_file_duration_ns=1_000_000_000)
    size = sum(p.stat().st_size for p in (tmp_path / 'bag').iterdir()) / 1e6
    assert describe_written(tmp_path / 'bag') == (
        f"wrote {tmp_path / 'bag'}: 10 messages over 3.3 s, {size:.2f} MB in 3 files (a 5, b 5)")


@pytest.mark.parametrize('flag, value, message', [
    ('--max-bag-size-mb', '-1',
     "argument --max-bag-size-mb: expected 0 (no split) to 1e+07 MB, got '-1'"),
    ('--max-bag-duration-s', 'nan',
     "argument --max-bag-duration-s: expected 0 (no split) to 3.2e+07 s, got 'nan'"),
    ('--max-bag-duration-s', 'soon',
     "argument --max-bag-duration-s: expected 0 (no split) to 3.2e+07 s, got 'soon'"),
])
def test_record_and_demo_refuse_a_bad_split_limit_with_one_line(cli_here, tmp_path, flag,
                                                                value, message):
    for command in (['record', tmp_path / 'bag'], ['demo', '--record', tmp_path / 'bag']):
        run = cli_here(*command, flag, value)
        assert run.returncode == 2
        assert run.stderr.strip().splitlines()[-1].endswith(message), run.stderr
        assert not (tmp_path / 'bag').exists()


def test_the_demo_refuses_a_split_without_a_bag(cli_here):
    run = cli_here('demo', '--max-bag-size-mb', '100')
    assert run.returncode == 2
    assert run.stderr.strip().splitlines()[-1].endswith(
        '--max-bag-size-mb splits the bag of --record, which is not given'), run.stderr


def test_a_message_later_than_the_file_before_stays_open_for_is_still_read_in_time_order(
        tmp_path, monkeypatch):
    """Received at 1.0 s but written after one at 1.7 s: the first file was closed by then."""
    from ipomdp_gaze.files import bag
    monkeypatch.setattr(bag, 'LATE_NS', 500_000_000)
    late = [('/a', 0), ('/a', 1_100_000_000), ('/a', 1_700_000_000), ('/b', 1_000_000_000)]
    _write(tmp_path / 'bag', late, max_file_duration_ns=1_000_000_000)
    assert [f['message_count'] for f in _meta(tmp_path / 'bag')['files']] == [1, 3]
    assert [(m.topic, m.time_ns) for m in bag.read_bag(tmp_path / 'bag').messages] == \
        sorted(late, key=lambda m: m[1])


@pytest.mark.parametrize('limits', [{}, {'max_file_duration_ns': 1_000_000_000}],
                         ids=['one file', 'split'])
def test_a_flush_of_a_closed_bag_is_refused_as_a_write_is(tmp_path, limits):
    """Review: one file's flush() raised AttributeError, a split bag's did nothing silently."""
    from ipomdp_gaze.files.bag import open_writer
    writer = open_writer(tmp_path / 'bag', **limits)
    connection = writer.add_connection('/a', 'std_msgs/msg/Int32')
    writer.write(connection, 0, _int32(0))
    writer.flush()
    writer.close()
    with pytest.raises(ValueError, match='the bag is closed'):
        writer.flush()


@pytest.mark.parametrize('limits, name', [({}, 'bag.mcap'),
                                          ({'max_file_duration_ns': 1_000_000_000}, 'bag_0.mcap')],
                         ids=['one file', 'split'])
def test_a_hand_off_is_synced_without_the_writer_even_once_it_is_closed(tmp_path, monkeypatch,
                                                                        limits, name):
    """
    The recorder syncs outside its lock what hand_off() gave the system (its flush held the lock).

    The bytes are in the file at the hand-off; the sync, after the writer closed (the file
    moved, for a split bag), syncs that file through a duplicate descriptor, then closes it.
    """
    import os
    from ipomdp_gaze.files.bag import open_writer, read_bag
    writer = open_writer(tmp_path / 'bag', **limits)
    connection = writer.add_connection('/a', 'std_msgs/msg/Int32')
    writer.write(connection, 5, _int32(1234567))
    pending = writer.hand_off()
    file = next((tmp_path / 'bag').rglob('*.mcap'))
    assert _int32(1234567) in file.read_bytes()             # the system has it already
    writer.close()
    synced, real_fsync = [], os.fsync

    def fsync(fd):
        synced.append(os.fstat(fd).st_ino)
        real_fsync(fd)
    monkeypatch.setattr(os, 'fsync', fsync)
    pending.sync()
    assert synced == [(tmp_path / 'bag' / name).stat().st_ino]
    pending.sync()                                          # done: nothing left to sync
    assert len(synced) == 1
    assert [m.time_ns for m in read_bag(tmp_path / 'bag').messages] == [5]
    with pytest.raises(ValueError, match='the bag is closed'):
        writer.hand_off()


def test_a_hand_off_closes_its_duplicates_also_when_fsync_fails(tmp_path, monkeypatch):
    import os
    from ipomdp_gaze.files.bag import open_writer
    writer = open_writer(tmp_path / 'bag')
    connection = writer.add_connection('/a', 'std_msgs/msg/Int32')
    writer.hand_off().sync()                                # the topic's records
    assert writer.hand_off()._fds == []                    # nothing begun: nothing to sync
    writer.write(connection, 5, _int32(1))
    pending = writer.hand_off()
    fds = list(pending._fds)
    assert len(fds) == 1 and fds[0] != writer.storage.bio.fileno()

    def failing_fsync(fd):
        raise OSError(5, 'Input/output error')
    monkeypatch.setattr(os, 'fsync', failing_fsync)
    with pytest.raises(OSError, match='Input/output error'):
        pending.sync()
    with pytest.raises(OSError):                            # closed although fsync failed
        os.fstat(fds[0])
    writer.close()
