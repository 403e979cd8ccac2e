# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The check of a rosbag2 bag's metadata (``metadata.yaml``) before anything reads the bag.

Every key the ``rosbags`` reader, ``replay``, ``record``'s summary and ``reindex`` read, with
its type: a damaged or hand-edited ``metadata.yaml`` is refused with one line naming the file
and the key (``rosbag2_bagfile_information.duration.nanoseconds``), not with the reader's own
exception text (``KeyError('duration')``) or a traceback; so is a file of the other storage
than ``storage_identifier`` says (MCAP under ``sqlite3``), which the reader took for a damaged
file of its own (``file is not a database``, ``File magic is invalid``). No rclpy here.
"""
from __future__ import annotations

from pathlib import Path, PurePath

from ipomdp_gaze.model.checks import short_repr

INFO = 'rosbag2_bagfile_information'
MAX_VERSION = 9                     # the newest rosbag2 metadata version rosbags reads
STORAGES = ('mcap', 'sqlite3')      # the storage plugins of the rosbags reader
COMPRESSION_MODES = ('', 'none', 'file', 'message')
# The first bytes of a file of each storage, and the storage in words.
MCAP_MAGIC = b'\x89MCAP0\r\n'
MAGICS = {'mcap': MCAP_MAGIC, 'sqlite3': b'SQLite format 3\x00'}
STORAGE_WORDS = {'mcap': 'an MCAP file', 'sqlite3': 'an SQLite database (sqlite3 storage)'}


class StorageMismatch(ValueError):
    """A bag file of another storage than its metadata.yaml's ``storage_identifier``."""

    def __init__(self, message: str, storage: str):
        super().__init__(message)
        self.storage = storage


def file_storage(file: Path) -> str | None:
    """
    Return the storage a bag file is by its first bytes: ``mcap``, ``sqlite3`` or None.

    None for neither (a file compressed whole, a damaged one): the reader says what it finds.
    """
    with open(file, 'rb') as f:
        head = f.read(max(len(magic) for magic in MAGICS.values()))
    return next((name for name, magic in MAGICS.items() if head.startswith(magic)), None)


class _Keys:
    """Read typed keys of a metadata mapping, refusing with one line naming the key."""

    def __init__(self, where: str):
        self.where = where

    def fail(self, key: str, what: str):
        raise ValueError(f'{self.where}: {key} {what}')

    def mapping(self, value, key: str) -> dict:
        if not isinstance(value, dict):
            self.fail(key, f'must be a mapping, got {short_repr(value)}')
        return value

    def get(self, mapping: dict, key: str, at: str, kind: str, required: bool = True):
        """Return ``mapping[key]`` (None if absent and not required), checked to be ``kind``."""
        name = f'{at}.{key}'
        if key not in mapping:
            if required:
                self.fail(name, 'is missing')
            return None
        value = mapping[key]
        if not required and value is None:
            return None
        checks = {'integer': _is_count, 'text': lambda v: isinstance(v, str),
                  'mapping': lambda v: isinstance(v, dict),
                  'list': lambda v: isinstance(v, list)}
        if not checks[kind](value):
            wanted = {'integer': 'an integer, 0 or more', 'text': 'text',
                      'mapping': 'a mapping', 'list': 'a list'}[kind]
            self.fail(name, f'must be {wanted}, got {short_repr(value)}')
        return value

    def nanoseconds(self, mapping: dict, key: str, at: str, field: str) -> int:
        inner = self.get(mapping, key, at, 'mapping')
        return self.get(inner, field, f'{at}.{key}', 'integer')


def _is_count(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def check_document(doc, meta: Path, folder: Path) -> dict:
    """
    Return ``rosbag2_bagfile_information`` of a loaded ``metadata.yaml`` if a reader can use it.

    ``folder`` is the bag: every file ``relative_file_paths`` lists must be a file in it.

    Raises
    ------
    ValueError
        One line naming ``meta`` and the key missing or wrong, or the file listed but absent.
    StorageMismatch
        For a listed file of the other storage than ``storage_identifier`` (a ValueError).

    """
    keys = _Keys(str(meta))
    if not isinstance(doc, dict):
        raise ValueError(f'{meta} is not rosbag2 metadata: a mapping with the key {INFO} '
                         f'expected, got {short_repr(doc)}')
    if INFO not in doc:
        raise ValueError(f'{meta} is not rosbag2 metadata: the key {INFO} is missing (its '
                         f"keys: {short_repr(', '.join(map(str, doc)) or 'none')})")
    info = keys.mapping(doc[INFO], INFO)
    check_info(info, keys, require_files=False)
    paths = keys.get(info, 'relative_file_paths', INFO, 'list')
    if not paths:
        keys.fail(f'{INFO}.relative_file_paths', 'lists no file')
    for i, name in enumerate(paths):
        if not isinstance(name, str) or not name:
            keys.fail(f'{INFO}.relative_file_paths[{i}]', f'must be a file name, got '
                      f'{short_repr(name)}')
        file = folder / PurePath(name).name
        if not file.is_file():
            raise ValueError(f'{meta} lists the file {name}, which is not in {folder}')
        storage, actual = info['storage_identifier'], file_storage(file)
        if actual is not None and actual != storage:
            raise StorageMismatch(f'{file} is {STORAGE_WORDS[actual]}, but {meta} says '
                                  f'storage_identifier: {storage} (set it to {actual})', actual)
    return info


def check_info(info: dict, keys: _Keys, require_files: bool, at: str = INFO) -> None:
    """
    Check the keys and types of a bag's information ``info`` (refused by ``keys``' one line).

    ``require_files``: its ``files`` entries too (those ``reindex`` merges), which a
    ``metadata.yaml`` older than version 5 does not have.
    """
    version = keys.get(info, 'version', at, 'integer')
    if version > MAX_VERSION:
        keys.fail(f'{at}.version', f'is {version}: this reader reads rosbag2 metadata up to '
                  f'version {MAX_VERSION}')
    storage = keys.get(info, 'storage_identifier', at, 'text')
    if storage not in STORAGES:
        keys.fail(f'{at}.storage_identifier', f"must be one of {', '.join(STORAGES)}, got "
                  f'{short_repr(storage)}')
    mode = keys.get(info, 'compression_mode', at, 'text', required=False) or ''
    if mode.lower() not in COMPRESSION_MODES:
        keys.fail(f'{at}.compression_mode', f"must be one of {', '.join(COMPRESSION_MODES[1:])} "
                  f'or empty, got {short_repr(mode)}')
    compression = keys.get(info, 'compression_format', at, 'text', required=False) or ''
    if mode.lower() not in ('', 'none') and compression != 'zstd':
        keys.fail(f'{at}.compression_format', f'must be zstd (the one compression this reader '
                  f'reads) with compression_mode {mode}, got {short_repr(compression)}')
    keys.get(info, 'message_count', at, 'integer')
    keys.nanoseconds(info, 'duration', at, 'nanoseconds')
    keys.nanoseconds(info, 'starting_time', at, 'nanoseconds_since_epoch')
    topics = keys.get(info, 'topics_with_message_count', at, 'list')
    for i, entry in enumerate(topics):
        where = f'{at}.topics_with_message_count[{i}]'
        keys.mapping(entry, where)
        keys.get(entry, 'message_count', where, 'integer')
        topic = keys.get(entry, 'topic_metadata', where, 'mapping')
        for key in ('name', 'type', 'serialization_format'):
            keys.get(topic, key, f'{where}.topic_metadata', 'text')
        if topic['serialization_format'] != 'cdr':
            keys.fail(f'{where}.topic_metadata.serialization_format', 'must be cdr (the one '
                      f"this reader reads), got {short_repr(topic['serialization_format'])}")
    files = keys.get(info, 'files', at, 'list', required=require_files) or []
    for i, entry in enumerate(files):
        where = f'{at}.files[{i}]'
        keys.mapping(entry, where)
        keys.get(entry, 'path', where, 'text')
        if require_files:
            keys.get(entry, 'message_count', where, 'integer')
            keys.nanoseconds(entry, 'duration', where, 'nanoseconds')
            keys.nanoseconds(entry, 'starting_time', where, 'nanoseconds_since_epoch')
    custom = keys.get(info, 'custom_data', at, 'mapping', required=False) or {}
    for key, value in custom.items():
        if not isinstance(key, str) or not isinstance(value, str):
            keys.fail(f'{at}.custom_data', f'must map text to text, got {short_repr(key)}: '
                      f'{short_repr(value)}')


def check_embedded(info, file: Path) -> bool:
    """Whether the ``rosbag2`` metadata a closed MCAP ``file`` carries is whole (for reindex)."""
    if not isinstance(info, dict):
        return False
    try:
        check_info(info, _Keys(str(file)), require_files=True, at='rosbag2')
    except ValueError:
        return False
    return True
