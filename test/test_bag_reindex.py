# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A recording cut off (SIGKILL, power lost): ``ipomdp-gaze reindex`` rebuilds its metadata.yaml.

A writer in a process of its own is killed with SIGKILL while writing; that process also says,
as each MCAP chunk is written, which messages it holds: every one of them must be read back
after the reindex, a split bag's too. The recorder killed over DDS is in test_ros_record.py.
"""
from pathlib import Path
import subprocess
import sys
import textwrap

import pytest
import yaml

# The writer's process: its messages (std_msgs/String, ``message <i>`` padded to ``size``
# bytes, at i ms), each chunk's message times printed once the chunk is written (with
# ``flush_every`` > 0 the writer's flush() after every that many messages), then SIGKILL.
WRITER = textwrap.dedent("""
    import os, signal, sys
    from rosbags.rosbag2.storage_mcap import McapWriter
    from ipomdp_gaze.files.bag import open_writer
    path, count, size, max_bytes, close_after, flush_every = sys.argv[1], *map(int, sys.argv[2:])
    write, close_chunk = McapWriter.write, McapWriter.close_chunk

    def pending_write(self, connection, stamp, data):
        self.__dict__.setdefault('pending', []).append(stamp)    # in the chunk it may close
        write(self, connection, stamp, data)

    def said_close_chunk(self):
        close_chunk(self)
        print(*self.__dict__.pop('pending', []), flush=True)
    McapWriter.write, McapWriter.close_chunk = pending_write, said_close_chunk
    writer = open_writer(path, max_file_bytes=max_bytes)
    writer.set_custom_data('ipomdp_gaze/version', '9.9.9')
    connection = writer.add_connection('/note', 'std_msgs/msg/String')
    if flush_every:
        writer.flush()                          # the topic, before any message
    for i in range(count):
        if i == 3:
            writer.set_custom_data('ipomdp_gaze/parameters/source', 'confidence: 0.9\\n')
        text = f'message {i}'.encode().ljust(size, b'.') + b'\\0'
        writer.write(connection, 1_000_000 * (i + 1), bytes([0, 1, 0, 0])
                     + len(text).to_bytes(4, 'little') + text)
        if flush_every and (i + 1) % flush_every == 0:
            writer.flush()
    if close_after:
        writer.close()
    os.kill(os.getpid(), signal.SIGKILL)
""")


def _killed(path: Path, count: int, size: int = 100_000, max_bytes: int = 0,
            close: bool = False, flush_every: int = 0) -> list:
    """Write ``count`` messages to a bag at ``path``, SIGKILL; return the times written out."""
    run = subprocess.run([sys.executable, '-c', WRITER, str(path), str(count), str(size),
                          str(max_bytes), str(int(close)), str(flush_every)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == -9, run.stdout + run.stderr
    return sorted(int(stamp) for stamp in run.stdout.split())


def _texts(bag) -> list:
    return [m.msg.data.rstrip('.') for m in bag.messages]


def test_a_killed_recording_is_unreadable_until_reindexed_then_keeps_every_written_chunk(
        tmp_path, cli_here):
    from ipomdp_gaze.files.bag import read_bag
    bag = tmp_path / 'bag'
    written = _killed(bag, 40)
    assert 10 < len(written) < 40               # whole chunks written, the last one not
    assert sorted(p.name for p in bag.iterdir()) == ['bag.mcap']
    refused = cli_here('replay', bag)
    assert refused.returncode == 2
    assert refused.stderr.strip().splitlines() == [
        f'ipomdp-gaze replay: error: {bag} is not a rosbag2 bag: no metadata.yaml (a recording '
        f'cut off? `ipomdp-gaze reindex {bag}` rebuilds it from the MCAP files)']
    run = cli_here('reindex', bag)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.splitlines() == [
        f'rebuilt {bag}: {len(written)} messages over {(written[-1] - written[0]) * 1e-9:.1f} s, '
        f'{(bag / "bag.mcap").stat().st_size / 1e6:.2f} MB (note {len(written)})',
        f'bag.mcap: unfinished, {len(written)} messages recovered',
        'package 9.9.9; parameters of source']
    read = read_bag(bag)
    assert [m.time_ns for m in read.messages] == written
    assert _texts(read) == [f'message {i}' for i in range(len(written))]
    assert read.custom_data == {'ipomdp_gaze/version': '9.9.9',
                                'ipomdp_gaze/parameters/source': 'confidence: 0.9\n'}
    assert read.parameters('source') == {'confidence': 0.9}
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['relative_file_paths'] == ['bag.mcap']
    assert meta['files'][0]['message_count'] == meta['message_count'] == len(written)
    assert [(t['topic_metadata']['name'], t['message_count'])
            for t in meta['topics_with_message_count']] == [('/note', len(written))]
    assert sorted(p.name for p in bag.iterdir()) == ['bag.mcap', 'metadata.yaml']


@pytest.mark.parametrize('max_bytes', [0, 10**6], ids=['one file', 'split'])
def test_a_flushed_chunk_of_a_few_small_messages_survives_the_kill(tmp_path, max_bytes):
    """
    A low-rate topic fills a 1 MiB chunk in minutes: flush() writes the chunk begun.

    Before it, a recording cut off before its first MiB kept nothing, not even its topics.
    """
    from ipomdp_gaze.files.bag import read_bag, reindex
    bag = tmp_path / 'bag'
    written = _killed(bag, 7, size=10, max_bytes=max_bytes, flush_every=5)
    assert written == [1_000_000 * (i + 1) for i in range(5)]
    done = reindex(bag)
    assert sum(done.recovered.values()) == 5
    read = read_bag(bag)
    assert [m.time_ns for m in read.messages] == written
    assert _texts(read) == [f'message {i}' for i in range(5)]
    assert read.custom_data['ipomdp_gaze/parameters/source'] == 'confidence: 0.9\n'
    nothing = tmp_path / 'nothing'                 # flushed before any message: the topic
    assert _killed(nothing, 0, size=10, max_bytes=max_bytes, flush_every=5) == []
    assert [(t['topic_metadata']['name'], t['message_count']) for t in
            reindex(nothing).info['topics_with_message_count']] == [('/note', 0)]


def test_an_unfinished_split_bag_moves_its_open_file_up_and_lists_every_file(tmp_path):
    """The closed files as they are; the open one (in ``bag_<i>/``) recovered and moved up."""
    from ipomdp_gaze.files.bag import read_bag, reindex
    bag = tmp_path / 'bag'
    written = _killed(bag, 70, max_bytes=2_000_000)
    assert len(written) < 70
    folders = [p.name for p in bag.iterdir() if p.is_dir()]
    assert folders and not (bag / 'metadata.yaml').exists()
    done = reindex(bag)
    names = [f'bag_{i}.mcap' for i in range(len(done.info['files']))]
    assert len(names) >= 3 and done.info['relative_file_paths'] == names
    assert sorted(p.name for p in bag.iterdir()) == sorted(names + ['metadata.yaml'])
    assert set(done.recovered) == {f'{name}.mcap' for name in folders}
    read = read_bag(bag)
    assert [m.time_ns for m in read.messages] == written
    assert _texts(read) == [f'message {i}' for i in range(len(written))]
    assert [f['message_count'] for f in done.info['files']] == \
        [len([s for s in written if f['starting_time']['nanoseconds_since_epoch'] <= s <=
              f['starting_time']['nanoseconds_since_epoch'] + f['duration']['nanoseconds']])
         for f in done.info['files']]
    assert read.custom_data['ipomdp_gaze/version'] == '9.9.9'
    assert read.parameters('source') == {'confidence': 0.9}
    # a closed split bag's metadata.yaml rebuilt (--force) is the one its writer wrote
    first = yaml.safe_load((bag / 'metadata.yaml').read_text())
    reindex(bag, force=True)
    assert yaml.safe_load((bag / 'metadata.yaml').read_text()) == first


@pytest.mark.parametrize('max_bytes', [0, 20_000])
def test_a_closed_bag_rebuilt_with_force_has_the_metadata_its_writer_wrote(tmp_path, cli_here,
                                                                           max_bytes):
    bag = tmp_path / 'bag'
    written = _killed(bag, 30, size=1000, max_bytes=max_bytes, close=True)
    assert len(written) == 30
    wrote = yaml.safe_load((bag / 'metadata.yaml').read_text())
    refused = cli_here('reindex', bag)
    assert refused.returncode == 2
    assert refused.stderr.strip().splitlines() == [
        f'ipomdp-gaze reindex: error: {bag} has a metadata.yaml already; --force rebuilds it '
        'from the MCAP files']
    assert cli_here('reindex', bag, '--force').returncode == 0
    assert yaml.safe_load((bag / 'metadata.yaml').read_text()) == wrote


@pytest.mark.parametrize('make, message', [
    (lambda p: p.mkdir(), '{p}: no MCAP files to reindex (<name>.mcap, or <name>_<i>.mcap of a '
                          'split bag)'),
    (lambda p: None, '{p} is not a bag directory'),
])
def test_reindex_refuses_a_folder_without_mcap_files_with_one_line(tmp_path, cli_here, make,
                                                                   message):
    path = tmp_path / 'bag'
    make(path)
    run = cli_here('reindex', path)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        'ipomdp-gaze reindex: error: ' + message.format(p=path)]


@pytest.mark.parametrize('content', [b'', b'hello, not a bag', b'\x89MCA'])
def test_reindex_refuses_a_file_that_is_not_mcap_and_changes_nothing(
        tmp_path, cli_here, content):
    """QA: a file named .mcap that is not MCAP was replaced by an empty recovered bag."""
    bag = tmp_path / 'bag'
    _killed(bag, 40)
    other = bag / 'bag_1.mcap'
    other.write_bytes(content)
    before = {p.name: p.read_bytes() for p in bag.iterdir()}
    run = cli_here('reindex', bag)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        f'ipomdp-gaze reindex: error: {other} is not an MCAP file (it does not begin with the '
        'MCAP magic); nothing was changed']
    assert {p.name: p.read_bytes() for p in bag.iterdir()} == before


def test_a_write_failing_while_recovering_is_raised_and_leaves_the_bag_as_it_was(
        tmp_path, monkeypatch):
    """Review: a full disk while rewriting was taken for the cut: a shorter file replaced it."""
    from ipomdp_gaze.files.bag import reindex
    from rosbags.rosbag2 import Writer
    bag = tmp_path / 'bag'
    _killed(bag, 40)
    before = (bag / 'bag.mcap').read_bytes()
    write, written = Writer.write, []

    def full(self, *args):
        if len(written) == 5:
            raise OSError(28, 'No space left on device')
        written.append(args)
        write(self, *args)
    monkeypatch.setattr(Writer, 'write', full)
    with pytest.raises(OSError, match='No space left'):
        reindex(bag)
    assert sorted(p.name for p in bag.iterdir()) == ['bag.mcap']
    assert (bag / 'bag.mcap').read_bytes() == before


@pytest.mark.parametrize('name', ['run', 'run_1'])
def test_reindex_of_the_folder_holding_a_bag_leaves_that_bag_alone(tmp_path, name):
    """
    QA: ``reindex recordings/`` took ``recordings/run/run.mcap`` for a split bag's open file.

    It moved the MCAP file up into ``recordings/``, deleted the bag's metadata.yaml and its
    folder: the recording was no longer a bag.
    """
    from ipomdp_gaze.files.bag import read_bag, reindex
    folder = tmp_path / 'recordings'
    bag = folder / name
    _killed(bag, 5, size=1000, close=True)
    before = {p.name: p.read_bytes() for p in bag.iterdir()}
    with pytest.raises(ValueError, match='no MCAP files to reindex'):
        reindex(folder)
    assert sorted(p.name for p in folder.iterdir()) == [name]
    assert {p.name: p.read_bytes() for p in bag.iterdir()} == before
    assert len(read_bag(bag).messages) == 5


def test_a_split_bag_renamed_after_the_kill_still_finds_its_open_file(tmp_path):
    """Its open file's folder is named after the files (``bag_<i>/``), not the new folder."""
    from ipomdp_gaze.files.bag import read_bag, reindex
    written = _killed(tmp_path / 'bag', 70, max_bytes=2_000_000)
    renamed = tmp_path / 'renamed'
    (tmp_path / 'bag').rename(renamed)
    assert any(p.is_dir() for p in renamed.iterdir())
    done = reindex(renamed)
    assert done.recovered
    assert [m.time_ns for m in read_bag(renamed).messages] == written


@pytest.mark.parametrize('name, db3', [('bag_0.mcap', 'bag_0.db3'), ('bag.mcap', 'bag_0.db3')])
def test_reindex_of_an_sqlite_bag_named_mcap_says_what_it_is_and_what_to_do(
        tmp_path, cli_here, name, db3):
    """It said only ``is not an MCAP file``: an SQLite rosbag2 file is no damaged MCAP one."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores
    bag = tmp_path / 'bag'
    typestore = get_typestore(Stores.ROS2_JAZZY)
    with Writer(bag, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
        connection = writer.add_connection('/note', 'std_msgs/msg/String', typestore=typestore)
        writer.write(connection, 1, typestore.serialize_cdr(
            typestore.types['std_msgs/msg/String'](data='x'), 'std_msgs/msg/String'))
    (bag / 'metadata.yaml').unlink()
    (bag / 'bag.db3').rename(bag / name)
    before = {p.name: p.read_bytes() for p in bag.iterdir()}
    run = cli_here('reindex', bag)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        f'ipomdp-gaze reindex: error: {bag / name} is an SQLite database (sqlite3 storage), not '
        f'an MCAP file: rename it {db3} and rebuild the metadata.yaml with `ros2 bag reindex '
        f'{bag} -s sqlite3` (ipomdp-gaze reindex reads MCAP files); nothing was changed']
    assert {p.name: p.read_bytes() for p in bag.iterdir()} == before
