# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
rosbag2 bags of a search (MCAP storage), written and read in pure Python with ``rosbags``.

A bag is a directory with ``metadata.yaml`` and one ``.mcap`` file, as ``ros2 bag record -s
mcap`` writes it. :func:`open_writer` starts one (``compression='zstd'`` compresses the MCAP
chunks, as rosbag2's ``zstd`` storage presets do, so ``mcap`` readers and Foxglove still read
it); :func:`read_bag` returns every message deserialized (``rosbags`` message classes, with
the fields of the ROS messages) and the bag's ``custom_data``, where the recorder keeps the
package version, each node's parameters and the hashes of the files they name. No rclpy here.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ipomdp_gaze.files.writable import folder_writable
import yaml

DISTRO_STORE = 'ROS2_JAZZY'
COMPRESSIONS = ('', 'zstd')


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


def open_writer(path, compression: str = ''):
    """
    Create a bag at ``path`` (a new directory) and return the open ``rosbags`` writer.

    Raises
    ------
    ValueError
        If ``path`` cannot be a new bag (:func:`check_new_bag`) or ``compression`` is not
        ``''`` or ``'zstd'``.

    """
    _need_rosbags()
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
    if compression not in COMPRESSIONS:
        raise ValueError(f"compression must be '' or 'zstd', got {compression!r}")
    path = check_new_bag(path)
    writer = Writer(path, version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP)
    if compression:
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    writer.open()
    store = _typestore()
    add = writer.add_connection

    def add_connection(topic, msgtype, **kw):
        return add(topic, msgtype, typestore=store, **kw)
    writer.add_connection = add_connection
    return writer


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
    """Return ``rosbag2_bagfile_information`` of a bag's ``metadata.yaml``."""
    meta = Path(path) / 'metadata.yaml'
    if not meta.is_file():
        raise ValueError(f'{path} is not a rosbag2 bag: no metadata.yaml')
    try:
        return yaml.safe_load(meta.read_text())['rosbag2_bagfile_information']
    except (yaml.YAMLError, KeyError, TypeError):
        raise ValueError(f'{meta} is not rosbag2 metadata') from None


def read_bag(path, topics=None) -> Bag:
    """
    Read a bag: every message (of ``topics``, relative names, if given), deserialized.

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
        raise ValueError(f'{path}: {exc}') from None
    size = sum(f.stat().st_size for f in path.iterdir() if f.is_file())
    return Bag(path, messages, dict(info.get('custom_data') or {}), size, duration)
