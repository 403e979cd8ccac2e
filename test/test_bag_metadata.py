# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A damaged or hand-edited ``metadata.yaml``: one line naming the file and the key, no traceback.

The ``rosbags`` reader's own text (``A metadata key is missing KeyError('duration').``) or a
``TypeError`` traceback was what ``replay`` said; ``record``'s summary and ``reindex`` read the
same metadata.
"""
from pathlib import Path

import pytest
import yaml

INFO = 'rosbag2_bagfile_information'


def _bag(path: Path) -> Path:
    """Write a closed bag of three std_msgs/String messages on /note at ``path``."""
    from ipomdp_gaze.files.bag import open_writer
    writer = open_writer(path)
    connection = writer.add_connection('/note', 'std_msgs/msg/String')
    for i in range(3):
        writer.write(connection, 1_000_000 * (i + 1),
                     bytes([0, 1, 0, 0]) + (3).to_bytes(4, 'little') + b'hi\0')
    writer.close()
    return path


def _edit(bag: Path, change) -> None:
    """Rewrite the bag's metadata.yaml with ``change`` made to its loaded document."""
    doc = yaml.safe_load((bag / 'metadata.yaml').read_text())
    doc = change(doc)
    (bag / 'metadata.yaml').write_text(yaml.safe_dump(doc))


def _drop(*keys):
    def change(doc):
        inner = doc[INFO]
        for key in keys[:-1]:
            inner = inner[key]
        del inner[keys[-1]]
        return doc
    return change


def _set(key, value):
    def change(doc):
        doc[INFO][key] = value
        return doc
    return change


def _topic(key, value):
    def change(doc):
        doc[INFO]['topics_with_message_count'][0]['topic_metadata'][key] = value
        return doc
    return change


HINT = (' (a damaged metadata.yaml? `ipomdp-gaze reindex --force {bag}` rebuilds it from the '
        'MCAP files)')
TOPIC = f'{INFO}.topics_with_message_count[0]'


@pytest.mark.parametrize('change, message', [
    # a required key missing
    (_drop('duration'), f'{{meta}}: {INFO}.duration is missing'),
    (_drop('version'), f'{{meta}}: {INFO}.version is missing'),
    (_drop('relative_file_paths'), f'{{meta}}: {INFO}.relative_file_paths is missing'),
    (_drop('storage_identifier'), f'{{meta}}: {INFO}.storage_identifier is missing'),
    (_drop('starting_time', 'nanoseconds_since_epoch'),
     f'{{meta}}: {INFO}.starting_time.nanoseconds_since_epoch is missing'),
    (_drop('topics_with_message_count', 0, 'topic_metadata', 'type'),
     f'{{meta}}: {TOPIC}.topic_metadata.type is missing'),
    (_drop('topics_with_message_count', 0, 'message_count'),
     f'{{meta}}: {TOPIC}.message_count is missing'),
    # not a mapping
    (lambda doc: [1, 2], f'{{meta}} is not rosbag2 metadata: a mapping with the key {INFO} '
                         'expected, got [1, 2]'),
    (lambda doc: None, f'{{meta}} is not rosbag2 metadata: a mapping with the key {INFO} '
                       'expected, got None'),
    (lambda doc: {'other': doc[INFO]}, f'{{meta}} is not rosbag2 metadata: the key {INFO} is '
                                       "missing (its keys: 'other')"),
    (lambda doc: {INFO: 'text'}, f"{{meta}}: {INFO} must be a mapping, got 'text'"),
    # wrong types
    (_set('version', 'nine'), f'{{meta}}: {INFO}.version must be an integer, 0 or more, got '
                              "'nine'"),
    (_set('version', 10), f'{{meta}}: {INFO}.version is 10: this reader reads rosbag2 metadata '
                          'up to version 9'),
    (_set('message_count', -1), f'{{meta}}: {INFO}.message_count must be an integer, 0 or '
                                'more, got -1'),
    (_set('duration', {'nanoseconds': 'x'}), f'{{meta}}: {INFO}.duration.nanoseconds must be '
                                             "an integer, 0 or more, got 'x'"),
    (_set('duration', 5), f'{{meta}}: {INFO}.duration must be a mapping, got 5'),
    (_set('relative_file_paths', 'bag.mcap'), f'{{meta}}: {INFO}.relative_file_paths must be a '
                                              "list, got 'bag.mcap'"),
    (_set('relative_file_paths', [None]), f'{{meta}}: {INFO}.relative_file_paths[0] must be a '
                                          'file name, got None'),
    (_set('relative_file_paths', []), f'{{meta}}: {INFO}.relative_file_paths lists no file'),
    (_set('topics_with_message_count', [5]), f'{{meta}}: {TOPIC} must be a mapping, got 5'),
    (_set('custom_data', [1]), f'{{meta}}: {INFO}.custom_data must be a mapping, got [1]'),
    (_set('custom_data', {'ipomdp_gaze/version': 3}),
     f"{{meta}}: {INFO}.custom_data must map text to text, got 'ipomdp_gaze/version': 3"),
    (_set('files', 'x'), f"{{meta}}: {INFO}.files must be a list, got 'x'"),
    (_set('storage_identifier', 5), f'{{meta}}: {INFO}.storage_identifier must be text, got 5'),
    (_set('compression_mode', 'message'),
     f'{{meta}}: {INFO}.compression_format must be zstd (the one compression this reader '
     "reads) with compression_mode message, got ''"),
    (_topic('name', 5), f'{{meta}}: {TOPIC}.topic_metadata.name must be text, got 5'),
    (_topic('serialization_format', 'json'), f'{{meta}}: {TOPIC}.topic_metadata.'
                                             'serialization_format must be cdr (the one this '
                                             "reader reads), got 'json'"),
    # a file listed that is not there
    (_set('relative_file_paths', ['bag.mcap', 'bag_1.mcap']),
     '{meta} lists the file bag_1.mcap, which is not in {bag}'),
])
def test_a_damaged_metadata_yaml_is_one_line_naming_the_file_and_the_key(tmp_path, change,
                                                                         message):
    from ipomdp_gaze.files.bag import read_bag, read_metadata
    bag = _bag(tmp_path / 'bag')
    _edit(bag, change)
    expected = (message + HINT).format(meta=bag / 'metadata.yaml', bag=bag)
    for read in (read_metadata, read_bag):
        with pytest.raises(ValueError) as raised:
            read(bag)
        assert str(raised.value) == expected


def test_replay_of_a_bag_whose_metadata_misses_a_key_says_so_in_one_line(tmp_path, cli_here):
    """The reader's own text was said: ``A metadata key is missing KeyError('duration').``."""
    bag = _bag(tmp_path / 'bag')
    _edit(bag, _drop('duration'))
    run = cli_here('replay', bag)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        f"ipomdp-gaze replay: error: {bag / 'metadata.yaml'}: {INFO}.duration is missing"
        + HINT.format(bag=bag)]
    assert run.stdout == ''
    # the hint is right: reindex --force rebuilds a metadata.yaml replay reads
    assert cli_here('reindex', '--force', bag).returncode == 0
    from ipomdp_gaze.files.bag import read_bag
    assert len(read_bag(bag).messages) == 3


@pytest.mark.parametrize('change', [_set('duration', {'nanoseconds': 'x'}), _set('files', 'x'),
                                    _set('custom_data', [1])])
def test_replay_of_wrong_types_in_metadata_is_no_traceback(tmp_path, cli_here, change):
    """These were tracebacks (TypeError, AttributeError) with exit status 1."""
    bag = _bag(tmp_path / 'bag')
    _edit(bag, change)
    run = cli_here('replay', bag)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(
        f"ipomdp-gaze replay: error: {bag / 'metadata.yaml'}: {INFO}.")


def test_a_metadata_yaml_without_mcap_files_has_no_reindex_hint(tmp_path):
    from ipomdp_gaze.files.bag import read_metadata
    bag = tmp_path / 'bag'
    bag.mkdir()
    (bag / 'metadata.yaml').write_bytes(b'\xff\xfe not text')
    with pytest.raises(ValueError) as raised:
        read_metadata(bag)
    assert str(raised.value) == f'{bag / "metadata.yaml"} is not rosbag2 metadata: not YAML text'


def test_record_summary_of_damaged_metadata_says_nothing_readable(tmp_path):
    """``record``'s summary reads the metadata too: a wrong type was a TypeError there."""
    from ipomdp_gaze.commands.record import describe_written
    bag = _bag(tmp_path / 'bag')
    _edit(bag, _set('duration', {'nanoseconds': 'x'}))
    assert describe_written(bag) == (
        f'ipomdp-gaze record: nothing readable was written ({bag / "metadata.yaml"}: '
        f"{INFO}.duration.nanoseconds must be an integer, 0 or more, got 'x'" + HINT.format(
            bag=bag) + ')')


def test_reindex_rewrites_a_closed_file_whose_own_rosbag2_record_is_damaged(tmp_path):
    """The file's rosbag2 metadata record without ``files`` was a KeyError traceback."""
    from mcap.writer import Writer
    from ipomdp_gaze.files.bag import read_bag, reindex
    bag = tmp_path / 'bag'
    bag.mkdir()
    with open(bag / 'bag.mcap', 'wb') as f:
        writer = Writer(f)
        writer.start(profile='ros2')
        schema = writer.register_schema('std_msgs/msg/String', 'ros2msg', b'string data')
        channel = writer.register_channel('/note', 'cdr', schema)
        for i in range(3):
            writer.add_message(channel, 1_000 * (i + 1), bytes([0, 1, 0, 0])
                               + (3).to_bytes(4, 'little') + b'hi\0', 1_000 * (i + 1))
        writer.add_metadata('rosbag2', {'serialized_metadata': 'version: 9\n'})
        writer.finish()
    done = reindex(bag)
    assert done.recovered == {'bag.mcap': 3}
    assert [m.msg.data for m in read_bag(bag).messages] == ['hi'] * 3


def _sqlite_bag(path: Path) -> Path:
    """Write the bag of :func:`_bag` with rosbags' sqlite3 storage (a ``.db3`` file)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3)
    writer.open()
    connection = writer.add_connection('/note', 'std_msgs/msg/String',
                                       typestore=get_typestore(Stores.LATEST))
    for i in range(3):
        writer.write(connection, 1_000_000 * (i + 1),
                     bytes([0, 1, 0, 0]) + (3).to_bytes(4, 'little') + b'hi\0')
    writer.close()
    return path


@pytest.mark.parametrize('make, file, said, really', [
    (_bag, 'bag.mcap', 'sqlite3', 'an MCAP file'),
    (_sqlite_bag, 'bag.db3', 'mcap', 'an SQLite database (sqlite3 storage)'),
])
def test_a_bag_file_of_the_other_storage_is_one_line_saying_both(tmp_path, cli_here, make, file,
                                                                 said, really):
    """The reader's text was said: ``Cannot open database ...: file is not a database``."""
    from ipomdp_gaze.commands.record import describe_written
    from ipomdp_gaze.files.bag import read_bag, read_metadata
    bag = make(tmp_path / 'bag')
    _edit(bag, _set('storage_identifier', said))
    actual = 'mcap' if said == 'sqlite3' else 'sqlite3'
    expected = (f"{bag / file} is {really}, but {bag / 'metadata.yaml'} says "
                f'storage_identifier: {said} (set it to {actual})')
    for read in (read_metadata, read_bag):
        with pytest.raises(ValueError) as raised:
            read(bag)
        assert str(raised.value) == expected
    run = cli_here('replay', bag)
    assert run.returncode == 2 and run.stdout == ''
    assert run.stderr.strip().splitlines() == [f'ipomdp-gaze replay: error: {expected}']
    assert describe_written(bag) == (f'ipomdp-gaze record: nothing readable was written '
                                     f'({expected})')
    # the advice is right: the bag reads once the key says what the file is
    _edit(bag, _set('storage_identifier', actual))
    assert [m.msg.data for m in read_bag(bag).messages] == ['hi'] * 3
