# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
rosbag2 bags of a search (MCAP storage), written and read in pure Python with ``rosbags``.

A bag is a directory with ``metadata.yaml`` and one ``.mcap`` file, as ``ros2 bag record -s
mcap`` writes it, or several (``<name>_0.mcap``, ``<name>_1.mcap``, ...) when split by size or
duration as ``ros2 bag record --max-bag-size/--max-bag-duration`` splits it
(:class:`SplitWriter`). :func:`open_writer` starts one (``compression='zstd'`` compresses the
MCAP chunks, as rosbag2's ``zstd`` storage presets do, so ``mcap`` readers and Foxglove still
read it); :func:`read_bag` returns every message of every file in time order, deserialized
(``rosbags`` message classes, with the fields of the ROS messages) and the bag's
``custom_data``, where the recorder keeps the package version, each node's parameters and the
hashes of the files they name. The custom data also goes into the MCAP file being written, as a
metadata record (:data:`CUSTOM_DATA_RECORD`) flushed as soon as it is set, and every chunk is
flushed once written, so a recording cut off (power lost, SIGKILL) keeps them; the writer's
``flush()`` also writes the chunk begun, synced (the recorder: every second), in two steps a
writer under a lock can take apart: ``hand_off()`` gives the bytes to the operating system and
returns a :class:`PendingSync`, whose ``sync()`` runs ``fsync`` without the writer. :func:`reindex`
rebuilds ``metadata.yaml`` of such a bag from its MCAP files, as ``ros2 bag reindex`` does.
No rclpy here.
"""
from __future__ import annotations

from dataclasses import dataclass
import io
import os
from pathlib import Path
import re
import shutil

from ipomdp_gaze.files.bag_metadata import check_document, check_embedded, file_storage, \
    MCAP_MAGIC, STORAGE_WORDS, StorageMismatch
from ipomdp_gaze.files.writable import folder_writable, write_text
import yaml

DISTRO_STORE = 'ROS2_JAZZY'
COMPRESSIONS = ('', 'zstd')
# After a split the file before stays open for the messages received before the split and
# written after it, until one received this long after the split is written (ns).
LATE_NS = 2_000_000_000
NO_MESSAGE_NS = 2 ** 63 - 1     # rosbag2's starting time of a file without messages
# The largest split limits of the recorder: 10 TB and a year (0 is no split).
MAX_BAG_SIZE_MB = 1.0e7
MAX_BAG_DURATION_S = 3.2e7
# The MCAP metadata record of custom data written while recording (a map of key -> value).
CUSTOM_DATA_RECORD = 'ipomdp_gaze/custom_data'
ROSBAG2_RECORD = 'rosbag2'          # the metadata record rosbags writes at close


def _need_rosbags() -> None:
    """Raise ValueError (one line) unless ``rosbags``, which reads and writes bags, is there."""
    try:
        import rosbags  # noqa: F401
    except ImportError:
        raise ValueError('recording and replaying bags needs the rosbags package (pip install '
                         "'rosbags>=0.11.6'; a rosdep or colcon install does not bring it)") \
            from None


def _typestore():
    _need_rosbags()
    from rosbags.typesys import get_typestore, Stores
    return get_typestore(getattr(Stores, DISTRO_STORE))


def check_new_bag(path) -> Path:
    """
    Return ``path`` as a Path if a bag can be created there: new, its folders creatable.

    Missing folders on the way are made with the bag (as ``rosbags`` does); the nearest one
    that exists must be a writable folder.

    Raises
    ------
    ValueError
        If ``path`` exists, or a file or an unwritable folder is in the way (checked before
        any node starts, so a demo does not run a search it cannot record).

    """
    path = Path(path)
    if path.exists():
        raise ValueError(f'{path} exists; a bag needs a new directory')
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise ValueError(f'{path}: {folder} is not a folder')
    if not folder_writable(folder):
        raise ValueError(f'{path}: the folder {folder} is not writable')
    return path


def open_writer(path, compression: str = '', max_file_bytes: int = 0,
                max_file_duration_ns: int = 0):
    """
    Create a bag at ``path`` (a new directory) and return its open writer.

    With ``max_file_bytes`` and ``max_file_duration_ns`` 0 it is the ``rosbags`` writer of one
    ``<name>.mcap``; with either, a :class:`SplitWriter` (the same calls) that splits the bag.
    Both have ``flush()``: the chunk begun is written and synced now (a smaller chunk); and
    ``hand_off()``, its first half: the chunk written to the file, a :class:`PendingSync` of it
    returned to be synced later, outside whatever lock guards the writer.

    Raises
    ------
    ValueError
        If ``path`` cannot be a new bag (:func:`check_new_bag`), ``compression`` is not ``''``
        or ``'zstd'`` or a limit is negative.

    """
    _need_rosbags()
    if compression not in COMPRESSIONS:
        raise ValueError(f"compression must be '' or 'zstd', got {compression!r}")
    for name, value in (('max_file_bytes', max_file_bytes),
                        ('max_file_duration_ns', max_file_duration_ns)):
        if value < 0:
            raise ValueError(f'{name} must be 0 (no split) or more, got {value}')
    path = check_new_bag(path)
    if max_file_bytes or max_file_duration_ns:
        return SplitWriter(path, compression, int(max_file_bytes), int(max_file_duration_ns))
    writer = _open_rosbags(path, compression)
    store = _typestore()
    add = writer.add_connection

    def add_connection(topic, msgtype, **kw):
        return add(topic, msgtype, typestore=store, **kw)
    writer.add_connection = add_connection
    writer.set_custom_data = lambda key, value: _keep_custom_data(writer, {key: value})
    writer.hand_off = lambda: PendingSync(_hand_off(writer, path))
    writer.flush = lambda: writer.hand_off().sync()
    return writer


class PendingSync:
    """
    Files whose bytes the operating system has, to ``fsync`` later: duplicates of their fds.

    :meth:`sync` needs nothing of the writer, so a recorder calls it after its lock is released
    (a message written meanwhile does not wait for the disk), and a file closed or split off
    meanwhile is still synced: the duplicate keeps the open file, never a closed fd's number.
    """

    def __init__(self, fds=()):
        self._fds = list(fds)

    def sync(self) -> None:
        """``fsync`` each file, then close the duplicates (all of them, also when one fails)."""
        try:
            for fd in self._fds:
                os.fsync(fd)
        finally:
            self.close()

    def close(self) -> None:
        """Close the duplicates unsynced (a hand-off that failed half way); again: nothing."""
        fds, self._fds = self._fds, []
        for fd in fds:
            os.close(fd)


def _hand_off(writer, path) -> list:
    """
    Write a ``rosbags`` MCAP writer's chunk begun to its file now; return a dup of its fd.

    ``rosbags`` writes a chunk when it holds about 1 MiB: minutes of a low-rate topic, and the
    topics themselves (their channel records) go into the first. A recording cut off then
    loses all of it; closed early (a smaller chunk) it is a complete chunk that
    :func:`reindex` recovers once synced (:class:`PendingSync`). Nothing begun: nothing to
    sync (``[]``). A closed writer (of the bag at ``path``) is refused (ValueError).
    """
    storage = writer.storage
    if storage is None:
        raise ValueError(f'{path}: the bag is closed')
    if not storage.chunk.bio.tell():
        return []
    storage.close_chunk()                   # written and flushed (_open_rosbags)
    return [os.dup(storage.bio.fileno())]


def _open_rosbags(path: Path, compression: str):
    """
    Open a ``rosbags`` MCAP writer at ``path`` whose chunks reach the file once written.

    ``rosbags`` writes each chunk (about 1 MiB of messages) through a buffered file: flushed
    after it, a chunk is in the file even if the process is killed right after.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    writer = Writer(path, version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP)
    _compress(writer, compression)
    writer.open()
    storage = writer.storage
    close_chunk = storage.close_chunk

    def flushed_close_chunk():
        close_chunk()
        storage.bio.flush()
    storage.close_chunk = flushed_close_chunk
    return writer


def _keep_custom_data(writer, items: dict) -> None:
    """
    Set ``items`` in a ``rosbags`` writer's custom data and write them into its MCAP file now.

    One metadata record :data:`CUSTOM_DATA_RECORD` of ``items``, flushed and synced to the
    disk: ``rosbags`` writes custom data only when it closes the file, which a recording cut
    off never does; :func:`reindex` reads it back.
    """
    from rosbags.rosbag2.storage_mcap import write_record, write_string, write_uint32
    for key, value in items.items():
        type(writer).set_custom_data(writer, key, value)     # the class's: not this wrapper
    if not items:
        return
    entries = io.BytesIO()
    for key, value in items.items():
        write_string(entries, key)
        write_string(entries, value)
    record = io.BytesIO()
    write_string(record, CUSTOM_DATA_RECORD)
    write_uint32(record, entries.tell())
    record.write(entries.getbuffer())
    bio = writer.storage.bio
    write_record(bio, 0x0C, record)
    bio.flush()
    os.fsync(bio.fileno())


def _compress(writer, compression: str) -> None:
    """Set ``zstd`` chunk compression on a ``rosbags`` writer not yet open (``''``: none)."""
    if compression:
        from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)


@dataclass(frozen=True)
class SplitConnection:
    """A topic of a :class:`SplitWriter`, what :meth:`SplitWriter.add_connection` returns."""

    index: int
    topic: str
    msgtype: str


@dataclass
class _Part:
    """One file of a split bag while it is written: its ``rosbags`` writer and what it holds."""

    index: int
    writer: object
    file: Path
    connections: list
    first_ns: int = NO_MESSAGE_NS
    last_ns: int = 0
    count: int = 0


class SplitWriter:
    """
    Write a bag split into files ``<name>_0.mcap``, ``<name>_1.mcap``, ... as rosbag2 does.

    A message starts a new file when the file being written holds ``max_file_bytes`` on disk
    (MCAP is written in chunks of about 1 MiB, so a file ends at the first chunk that reaches
    it) or the message is more than ``max_file_duration_ns`` after the file's first; every file
    has every topic. :meth:`close` writes ``metadata.yaml``: ``relative_file_paths`` and
    ``files`` (each file's ``path``, ``starting_time``, ``duration`` and ``message_count``), the
    topics with their counts over all files and ``custom_data``, so ``rosbags``' reader and
    ``ros2 bag play`` read the files in order as one bag.

    Messages arrive a little out of time order (the recorder's callbacks take the topics in
    their own order): one received before a split but written after it goes to the file before,
    which stays open until a message received ``LATE_NS`` after the split, so each file's
    messages come before the next file's. Each file is written by a ``rosbags`` writer of its
    own in a folder ``<name>_<i>`` of the bag, whose name it takes, and is moved up when closed.
    """

    def __init__(self, path, compression: str, max_file_bytes: int, max_file_duration_ns: int):
        self.path = Path(path)
        self.compression = compression
        self.max_file_bytes = max_file_bytes
        self.max_file_duration_ns = max_file_duration_ns
        self.custom_data: dict = {}
        self.files: list = []           # the closed files' entries of metadata.yaml's files
        self._store = _typestore()
        self._topics: list = []
        self._counts: list = []
        self._boundary_ns = 0
        self._template: dict = {}       # metadata.yaml of a closed file, its rosbags writer's
        self.path.mkdir(parents=True)
        self._parts = [self._open_part(0)]

    def _open_part(self, index: int) -> _Part:
        folder = self.path / f'{self.path.name}_{index}'
        writer = _open_rosbags(folder, self.compression)
        _keep_custom_data(writer, self.custom_data)
        connections = [writer.add_connection(c.topic, c.msgtype, typestore=self._store)
                       for c in self._topics]
        return _Part(index, writer, next(folder.glob('*.mcap')), connections)

    def add_connection(self, topic: str, msgtype: str) -> SplitConnection:
        """Add a topic to every file (those written later too); return it for :meth:`write`."""
        connection = SplitConnection(len(self._topics), topic, msgtype)
        for part in self._parts:
            part.connections.append(part.writer.add_connection(topic, msgtype,
                                                               typestore=self._store))
        self._topics.append(connection)
        self._counts.append(0)
        return connection

    def set_custom_data(self, key: str, value: str) -> None:
        """Set ``custom_data[key]`` of the bag (also in each file's own MCAP metadata)."""
        for part in self._parts:
            _keep_custom_data(part.writer, {key: value})
        self.custom_data[key] = value

    def write(self, connection: SplitConnection, time_ns: int, data: bytes) -> None:
        """Write a serialized message received at ``time_ns``, starting a new file if due."""
        if not self._parts:
            raise ValueError(f'{self.path}: the bag is closed')
        if len(self._parts) == 2:
            if time_ns < self._boundary_ns:
                self._put(self._parts[0], connection, time_ns, data)
                return
            if time_ns >= self._boundary_ns + LATE_NS:
                self._finish(self._parts[0])
        current = self._parts[-1]
        if current.count and self._full(current, time_ns):
            # Every message of the file before comes before the boundary, every later one after.
            self._boundary_ns = max(time_ns, current.last_ns + 1)
            self._parts.append(self._open_part(current.index + 1))
            if len(self._parts) == 3:
                self._finish(self._parts[0])
            if time_ns < self._boundary_ns:
                self._put(current, connection, time_ns, data)
                return
        self._put(self._parts[-1], connection, time_ns, data)

    def flush(self) -> None:
        """Write the open files' chunks begun to the disk now, synced (as the single file's)."""
        self.hand_off().sync()

    def hand_off(self) -> PendingSync:
        """Write the open files' chunks begun to their files; return them to sync later."""
        if not self._parts:
            raise ValueError(f'{self.path}: the bag is closed')
        fds = []
        try:
            for part in self._parts:
                fds += _hand_off(part.writer, part.file)
        except BaseException:
            PendingSync(fds).close()
            raise
        return PendingSync(fds)

    def _full(self, part: _Part, time_ns: int) -> bool:
        """Whether ``part`` is done before a message at ``time_ns``: its size or duration."""
        if self.max_file_bytes and part.file.stat().st_size >= self.max_file_bytes:
            return True
        return bool(self.max_file_duration_ns) and \
            time_ns - part.first_ns > self.max_file_duration_ns

    def _put(self, part: _Part, connection: SplitConnection, time_ns: int, data: bytes) -> None:
        part.writer.write(part.connections[connection.index], time_ns, data)
        part.first_ns = min(part.first_ns, time_ns)
        part.last_ns = max(part.last_ns, time_ns)
        part.count += 1
        self._counts[connection.index] += 1

    def _finish(self, part: _Part) -> None:
        """Close ``part``, move its file into the bag and keep its ``files`` entry."""
        self._parts.remove(part)            # never closed twice, also when closing fails
        part.writer.close()
        folder = part.file.parent
        name = f'{self.path.name}_{part.index}{part.file.suffix}'
        part.file.replace(self.path / name)
        meta = folder / 'metadata.yaml'
        self._template = yaml.safe_load(meta.read_text())['rosbag2_bagfile_information']
        meta.unlink()
        folder.rmdir()
        self.files.append({
            'path': name,
            'starting_time': {'nanoseconds_since_epoch': part.first_ns},
            'duration': {'nanoseconds': max(0, part.last_ns - part.first_ns)},
            'message_count': part.count})

    def close(self) -> None:
        """Close the open files and write ``metadata.yaml`` of the whole bag."""
        if not self._parts:
            raise ValueError(f'{self.path}: the bag is closed')
        while self._parts:
            self._finish(self._parts[0])
        info = dict(self._template)
        counts = {(c.topic, c.msgtype): n for c, n in zip(self._topics, self._counts)}
        info['topics_with_message_count'] = [
            dict(entry, message_count=counts.get((entry['topic_metadata']['name'],
                                                  entry['topic_metadata']['type']), 0))
            for entry in info.get('topics_with_message_count') or []]
        _write_metadata(self.path, _with_files(info, self.files, self.custom_data))


@dataclass
class BagMessage:
    """One recorded message: topic, arrival time (ns), the message, its serialized size."""

    topic: str
    time_ns: int
    msg: object
    size: int


@dataclass
class Bag:
    """What a bag holds: messages in time order, custom data, file size and duration."""

    path: Path
    messages: list
    custom_data: dict
    size_bytes: int
    duration_s: float

    @property
    def namespace(self) -> str:
        """Return where the recorder resolved its relative topics (``/`` when not kept)."""
        return str(self.custom_data.get('ipomdp_gaze/namespace') or '/')

    def topic(self, name: str) -> list:
        """
        Return the messages of the topic ``name``, resolved in the recorder's namespace.

        ``pan_tilt`` of a bag recorded in ``/head1`` is ``/head1/pan_tilt``; a name with a
        leading slash (``/parameter_events``) is absolute, by the rule the recorder resolved its
        topics with (in the root namespace both are the same).
        """
        if not name.startswith('/') and self.namespace.strip('/'):
            name = self.namespace.strip('/') + '/' + name
        name = name.strip('/')
        return [m for m in self.messages if m.topic.lstrip('/') == name]

    def parameters(self, node: str) -> dict:
        """Return the recorded parameters of ``node`` (empty if the recorder had none)."""
        text = self.custom_data.get(f'ipomdp_gaze/parameters/{node}')
        return yaml.safe_load(text) if text else {}

    @property
    def megabytes_per_minute(self) -> float:
        """Size of the bag's files per minute of recording."""
        return self.size_bytes / 1e6 / max(self.duration_s / 60.0, 1e-9)


def read_metadata(path) -> dict:
    """
    Return ``rosbag2_bagfile_information`` of a bag's ``metadata.yaml``, checked.

    Raises
    ------
    ValueError
        One line: no ``metadata.yaml``, or a key of it missing or of the wrong type, or a file
        it lists not in the bag or of the other storage
        (:func:`~ipomdp_gaze.files.bag_metadata.check_document`).

    """
    meta = Path(path) / 'metadata.yaml'
    if not meta.is_file():
        raise ValueError(f'{path} is not a rosbag2 bag: no metadata.yaml' + (
            f' (a recording cut off? `ipomdp-gaze reindex {path}` rebuilds it from the MCAP '
            'files)' if _has_mcap_files(Path(path)) else ''))
    try:
        doc = yaml.safe_load(meta.read_bytes().decode())
    except OSError as exc:
        raise ValueError(f'{meta} cannot be read: {exc.strerror}') from None
    except (UnicodeDecodeError, yaml.YAMLError):
        raise ValueError(f'{meta} is not rosbag2 metadata: not YAML text') from None
    try:
        return check_document(doc, meta, Path(path))
    except StorageMismatch:
        raise                           # the one key to set: no rebuild to suggest
    except ValueError as exc:
        raise ValueError(f'{exc}' + (
            f' (a damaged metadata.yaml? `ipomdp-gaze reindex --force {path}` rebuilds it from '
            'the MCAP files)' if _has_mcap_files(Path(path)) else '')) from None


def _has_mcap_files(path: Path) -> bool:
    """Whether ``path`` is a folder with MCAP files a :func:`reindex` would read."""
    try:
        return path.is_dir() and bool(_bag_files(path))
    except (OSError, ValueError):
        return False


def read_bag(path, topics=None) -> Bag:
    """
    Read a bag: every message (of ``topics``, relative names, if given), deserialized.

    A split bag's files are read as one bag: its messages in time order.

    Raises
    ------
    ValueError
        If ``path`` is not a readable rosbag2 bag.

    """
    _need_rosbags()
    from rosbags.rosbag2 import Reader
    from rosbags.rosbag2.errors import ReaderError
    path = Path(path)
    info = read_metadata(path)
    store = _typestore()
    wanted = None if topics is None else {t.lstrip('/') for t in topics}
    messages = []
    try:
        with Reader(path) as reader:
            connections = [c for c in reader.connections
                           if wanted is None or c.topic.lstrip('/') in wanted]
            for connection, stamp, raw in reader.messages(connections=connections):
                if connection.msgtype not in store.types:
                    raise ValueError(f'{path}: {connection.topic} holds {connection.msgtype}, '
                                     'a message type this reader does not know (record only '
                                     "the search's topics)")
                try:
                    msg = store.deserialize_cdr(raw, connection.msgtype)
                except Exception as exc:        # noqa: B902 (rosbags' serde errors vary)
                    raise ValueError(f'{path}: a {connection.msgtype} message on '
                                     f'{connection.topic} at {int(stamp)} ns cannot be read '
                                     f'(a damaged bag?): {exc}') from None
                messages.append(BagMessage(connection.topic, int(stamp), msg, len(raw)))
            duration = reader.duration * 1e-9
    except ReaderError as exc:
        # A file cut off under a metadata.yaml (copied before the recording ended, say).
        cut = 'magic' in str(exc) or 'footer' in str(exc).lower()
        raise ValueError(f'{path}: {exc}' + (
            f' (an unfinished MCAP file? `ipomdp-gaze reindex --force {path}` recovers it)'
            if cut else '')) from None
    # The files of a split bag one after the other, each in time order: one bag's order (a
    # stable sort keeps the order of messages received at the same time).
    messages.sort(key=lambda m: m.time_ns)
    size = sum(f.stat().st_size for f in path.iterdir() if f.is_file())
    return Bag(path, messages, dict(info.get('custom_data') or {}), size, duration)


@dataclass
class Reindexed:
    """What :func:`reindex` did: the bag's new metadata and the files it recovered."""

    info: dict                      # metadata.yaml's rosbag2_bagfile_information
    recovered: dict                 # file name -> messages recovered of an unfinished file


def _bag_files(path: Path) -> list:
    """
    Return the bag's MCAP files in order, each ``(file, name in the bag)``.

    Those in the bag and those of a split bag still in a folder ``<name>_<i>/`` (a file being
    written: ``<name>_<i>/<name>_<i>.mcap``), in the order of their index ``_<i>``. ``<name>``
    is the bag's folder name or that of its split files (a bag renamed after the recording):
    another bag kept in a subfolder (``reindex`` of the folder holding it) is not one of its
    files, and is left alone (it was moved up, its metadata.yaml deleted).
    """
    found = [(f, f.name) for f in path.glob('*.mcap') if f.is_file()]
    prefixes = {path.resolve().name} | {
        m.group(1) for m in (re.fullmatch(r'(.+)_\d+\.mcap', name) for _, name in found) if m}
    for folder in path.iterdir():
        file = folder / f'{folder.name}.mcap'
        split = re.fullmatch(r'(.+)_\d+', folder.name)
        if split and split.group(1) in prefixes and folder.is_dir() and file.is_file():
            found.append((file, file.name))
    names = [name for _, name in found]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise ValueError(f'{path}: {twice[0]} is there twice (in the bag and in a folder); '
                         'keep one')

    def order(entry):
        index = re.fullmatch(r'.*_(\d+)\.mcap', entry[1])
        return (int(index.group(1)) if index else -1, entry[1])
    return sorted(found, key=order)


def _closed_metadata(file: Path):
    """Return the ``rosbag2`` metadata a closed MCAP file carries, or None if not closed."""
    from mcap.reader import make_reader
    with open(file, 'rb') as f:
        f.seek(0, os.SEEK_END)
        if f.tell() < 2 * len(MCAP_MAGIC):
            return None
        f.seek(-len(MCAP_MAGIC), os.SEEK_END)
        if f.read() != MCAP_MAGIC:
            return None
        f.seek(0)
        try:
            for record in make_reader(f).iter_metadata():
                if record.name == ROSBAG2_RECORD:
                    info = yaml.safe_load(record.metadata['serialized_metadata'])
                    # damaged: the file is rewritten as an unfinished one
                    return info if check_embedded(info, file) else None
        except Exception:           # noqa: B902 (a damaged summary: rewritten as unfinished)
            return None
    return None


def _complete_records(file: Path):
    """
    Yield the records of an MCAP ``file`` in order (a chunk's with its compression).

    Up to the footer, or to the first record cut off (the truncation) or damaged: the ``mcap``
    stream reader reads a record only when it is whole, and a chunk is broken up only then.
    """
    from mcap.records import Chunk, Footer
    from mcap.stream_reader import breakup_chunk, StreamReader
    with open(file, 'rb') as f:
        records = StreamReader(f, emit_chunks=True,
                               record_size_limit=max(file.stat().st_size, 1)).records
        while True:
            try:
                record = next(records)
                if isinstance(record, Chunk):
                    compression = 'zstd' if record.compression == 'zstd' else ''
                    inner = [(r, compression) for r in breakup_chunk(record)]
                else:
                    inner = [(record, '')]
            except StopIteration:
                return
            except Exception:       # noqa: B902 (the cut: any record cut anywhere)
                return
            if isinstance(record, Footer):
                return
            yield from inner


class _Recovery:
    """The ``rosbags`` writer of a file recovered (opened with the first chunk's compression)."""

    def __init__(self, file: Path, folder: Path):
        self.file, self.folder = file, folder
        self.store = _typestore()
        self.writer = None
        self.schemas, self.connections, self.custom = {}, {}, {}
        self.count = 0

    def _writer(self, compression: str):
        if self.writer is None:
            self.writer = _open_rosbags(self.folder, compression)
        return self.writer

    def take(self, record, compression: str) -> None:
        """Write a record read: a message, its topic, its type, or keep custom data."""
        from mcap.records import Channel, Message, Metadata, Schema
        if isinstance(record, Schema):
            self.schemas[record.id] = record
        elif isinstance(record, Channel) and record.id not in self.connections:
            # every topic, in the order recorded, those without a message too (once: a
            # closed file's summary repeats its channels)
            msgtype = self.schemas[record.schema_id].name
            if msgtype not in self.store.types:
                raise ValueError(f'{self.file}: {record.topic} holds {msgtype}, a message type '
                                 'this reader does not know')
            self.connections[record.id] = self._writer(compression).add_connection(
                record.topic, msgtype, typestore=self.store)
        elif isinstance(record, Message):
            self._writer(compression).write(self.connections[record.channel_id],
                                            record.log_time, record.data)
            self.count += 1
        elif isinstance(record, Metadata) and record.name == CUSTOM_DATA_RECORD:
            self.custom.update(record.metadata)

    def close(self) -> dict:
        """Close the new file (with the custom data) and return its metadata."""
        writer = self._writer('')
        for key, value in self.custom.items():
            writer.set_custom_data(key, value)
        writer.close()
        return yaml.safe_load((self.folder / 'metadata.yaml').read_text())[
            'rosbag2_bagfile_information']


def _recover(file: Path, folder: Path) -> tuple:
    """
    Rewrite the complete records of an unfinished MCAP ``file`` into ``folder`` (a new bag).

    Every message of a complete chunk (:func:`_complete_records`) is written again by a
    ``rosbags`` writer, which closes the file with its summary. Return the new file's metadata
    (as ``rosbags`` writes it), the custom data its :data:`CUSTOM_DATA_RECORD` records held
    and the number of messages. A failure to write (a full disk) is raised, not taken for the
    end of what was recorded.
    """
    recovery = _Recovery(file, folder)
    for record, compression in _complete_records(file):
        recovery.take(record, compression)
    return recovery.close(), recovery.custom, recovery.count


def _merge(infos: list, custom_data: dict) -> dict:
    """Return the metadata of a bag of these files (each one's metadata, in order)."""
    info = dict(infos[-1])
    topics, counts = {}, {}
    for one in infos:
        for entry in one.get('topics_with_message_count') or []:
            key = (entry['topic_metadata']['name'], entry['topic_metadata']['type'])
            topics.setdefault(key, entry['topic_metadata'])
            counts[key] = counts.get(key, 0) + int(entry['message_count'])
    info['topics_with_message_count'] = [{'topic_metadata': topics[key],
                                          'message_count': counts[key]} for key in topics]
    return _with_files(info, [entry for one in infos for entry in one['files']], custom_data)


def _with_files(info: dict, files: list, custom_data: dict) -> dict:
    """
    Return ``info`` with a bag's files (metadata.yaml's ``files`` entries, in order).

    Their paths, total message count, starting time and duration, and ``custom_data``.
    """
    starts = [f['starting_time']['nanoseconds_since_epoch'] for f in files if f['message_count']]
    ends = [f['starting_time']['nanoseconds_since_epoch'] + f['duration']['nanoseconds']
            for f in files if f['message_count']]
    return dict(info, relative_file_paths=[f['path'] for f in files], files=files,
                message_count=sum(f['message_count'] for f in files),
                starting_time={'nanoseconds_since_epoch': min(starts, default=NO_MESSAGE_NS)},
                duration={'nanoseconds': max(ends) - min(starts) if starts else 0},
                custom_data=dict(custom_data) or None)


def _write_metadata(path: Path, info: dict) -> None:
    """Write a bag's ``metadata.yaml`` whole or not at all."""
    write_text(path / 'metadata.yaml', yaml.safe_dump({'rosbag2_bagfile_information': info},
                                                      default_flow_style=False,
                                                      sort_keys=False))


def reindex(path, force: bool = False) -> Reindexed:
    """
    Rebuild ``metadata.yaml`` of a bag from its MCAP files, as ``ros2 bag reindex`` does.

    For a recording cut off (power lost, the recorder killed): no ``metadata.yaml``, and the
    file being written (a split bag's in its folder ``<name>_<i>/``) has no summary. A closed
    file keeps its own metadata; an unfinished one is rewritten with every message of its
    complete chunks (those written before the last chunk was begun) and moved into the bag.
    The custom data (package version, parameters, file hashes, namespace) is what the files
    carry, later files' over earlier ones'.

    Raises
    ------
    ValueError
        If ``path`` is not a folder, holds no MCAP file, a file named as one that is not
        MCAP, or already has ``metadata.yaml`` (unless ``force``).

    """
    _need_rosbags()
    path = Path(path)
    if not path.is_dir():
        raise ValueError(f'{path} is not a bag directory')
    meta = path / 'metadata.yaml'
    if meta.exists() and not force:
        raise ValueError(f'{path} has a metadata.yaml already; --force rebuilds it from the '
                         'MCAP files')
    files = _bag_files(path)
    if not files:
        raise ValueError(f'{path}: no MCAP files to reindex (<name>.mcap, or <name>_<i>.mcap '
                         'of a split bag)')
    if not folder_writable(path):
        raise ValueError(f'{path}: the folder is not writable')
    for file, _ in files:
        # a file that does not begin as MCAP is not a recording cut off: it would be replaced
        # by an empty recovered one
        storage = file_storage(file)
        if storage == 'sqlite3':        # rosbag2's other storage, named .mcap: rosbag2 reads it
            db3 = file.stem if re.fullmatch(r'.+_\d+', file.stem) else f'{file.stem}_0'
            raise ValueError(f'{file} is {STORAGE_WORDS[storage]}, not an MCAP file: rename it '
                             f'{db3}.db3 and rebuild the metadata.yaml with `ros2 bag reindex '
                             f'{path} -s sqlite3` (ipomdp-gaze reindex reads MCAP files); '
                             'nothing was changed')
        if storage != 'mcap':
            raise ValueError(f'{file} is not an MCAP file (it does not begin with the MCAP '
                             'magic); nothing was changed')
    infos, custom, recovered = [], {}, {}
    for file, name in files:
        info = _closed_metadata(file)
        if info is not None:
            custom.update(info.get('custom_data') or {})
            if file.parent != path:         # closed, not yet moved up (killed in between)
                file.replace(path / name)
        else:
            scratch = path / f'.reindex_{Path(name).stem}'
            if scratch.exists():
                raise ValueError(f'{scratch} exists (an earlier reindex stopped?); remove it')
            try:
                info, found, count = _recover(file, scratch / Path(name).stem)
            except BaseException:
                shutil.rmtree(scratch, ignore_errors=True)
                raise
            custom.update(found)
            (scratch / Path(name).stem / name).replace(path / name)
            (scratch / Path(name).stem / 'metadata.yaml').unlink()
            (scratch / Path(name).stem).rmdir()
            scratch.rmdir()
            recovered[name] = count
        if file.parent != path:
            # the folder a split bag's file was written in: nothing else of it is kept
            for leftover in (file, file.parent / 'metadata.yaml'):
                if leftover.exists():
                    leftover.unlink()
            file.parent.rmdir()
        info = dict(info, files=[dict(entry, path=name) for entry in info['files']])
        infos.append(info)
    merged = _merge(infos, custom)
    _write_metadata(path, merged)
    return Reindexed(merged, recovered)
