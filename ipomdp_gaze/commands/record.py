# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze record PATH`` and ``ipomdp-gaze replay PATH``: a search to a bag, and back.

``reindex PATH`` rebuilds the ``metadata.yaml`` of a recording cut off (power lost, SIGKILL)
from its MCAP files (:func:`ipomdp_gaze.files.bag.reindex`), as ``ros2 bag reindex`` does.

``record`` runs the ``recorder`` node (:mod:`ipomdp_gaze.nodes.recorder`) until Ctrl-C or SIGTERM,
writing a rosbag2 bag with MCAP storage at PATH; ``replay`` re-runs a bag's frames through the
controller's core with the recorded settings or others (:mod:`ipomdp_gaze.drivers.replay`) and
prints where the decisions differ.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from ipomdp_gaze.model.wording import counted

from .common import bag_path, number_in
from .search_args import add_search_args


def add_parser(sub):
    p = sub.add_parser(
        'record', help='record a search to a rosbag2 bag (MCAP) with the recorder node',
        description='Run the recorder node: subscribe to the search topics and write them, '
                    "with the nodes' parameters, the package version and the hashes of the "
                    'model files, to a rosbag2 bag (metadata.yaml and MCAP, as ros2 bag record '
                    '-s mcap writes) at PATH, until Ctrl-C or SIGTERM. Same as `ros2 run '
                    'ipomdp_gaze recorder --ros-args -p path:=PATH`.')
    p.add_argument('path', type=bag_path, metavar='PATH', help='the bag directory to create')
    p.add_argument('--topics', default=None, metavar='T1,T2',
                   help='relative topics to record (default: every search topic)')
    p.add_argument('--compression', choices=('none', 'zstd'), default='none',
                   help='zstd-compress the MCAP chunks (default none)')
    add_split_args(p)
    p.add_argument('--ros-args', dest='ros_args', nargs=argparse.REMAINDER, default=None,
                   metavar='ARG', help='ROS arguments (remapping, namespace, -p nodes:=[...])')
    p.set_defaults(run=run_record)

    p = sub.add_parser(
        'reindex', help="rebuild a cut-off recording's metadata.yaml from its MCAP files",
        description='Rebuild metadata.yaml of a bag whose recording was cut off (the power '
                    'lost, the recorder killed with SIGKILL), as ros2 bag reindex does: from '
                    "the MCAP files in PATH, a split bag's file being written moved up from "
                    'its folder <name>_<i>/. An unfinished file (no summary) is rewritten with '
                    'every message of its complete chunks (MCAP is written in chunks of about '
                    '1 MiB: the messages of the last one, not yet written, are lost); the '
                    "recorder's custom data (package version, parameters, file hashes, "
                    'namespace) is taken from the files. Then replay and read_bag read it.')
    p.add_argument('path', type=bag_path, metavar='PATH', help='the bag directory')
    p.add_argument('--force', action='store_true',
                   help='rebuild metadata.yaml also when the bag has one')
    p.set_defaults(run=run_reindex)

    p = sub.add_parser(
        'replay', help='re-run a recorded search through the controller; print differences',
        description='Read a bag written by `ipomdp-gaze record` or `demo --record`, rebuild '
                    'the controller from the recorded parameters (or with the options below '
                    'changed; parameters set while recording are set at their time), offer it '
                    'the recorded frames as the node did and print where its fixations, events '
                    'and last decision differ from the recording. The frames were '
                    'taken where the recorded search looked, so the replay stops at the first '
                    'fixation that differs.')
    p.add_argument('path', type=bag_path, metavar='PATH', help='the bag directory')
    p.add_argument('--observation', default=None, metavar='FILE',
                   help='another count model (path or shipped name)')
    p.add_argument('--policy', default=None, help='another policy.name')
    p.add_argument('--policy-file', default=None, metavar='FILE',
                   help='another policy file or shipped kernel (selects learned)')
    add_search_args(p, None, ('confidence', 'max_fixations'), task_default="the recording's")
    p.add_argument('--new-search', action='store_true',
                   help='a fixed camera (detector in fovea mode) only: run a whole new search '
                        'on the last recorded image with these settings, instead of following '
                        'the recorded frames')
    p.set_defaults(run=run_replay)


def add_split_args(p, when: str = '') -> None:
    """Add ``--max-bag-size-mb`` and ``--max-bag-duration-s``, the recorder's split limits."""
    from ipomdp_gaze.files.bag import MAX_BAG_DURATION_S, MAX_BAG_SIZE_MB
    p.add_argument('--max-bag-size-mb', type=split_limit(MAX_BAG_SIZE_MB, 'MB'), default=0.0,
                   metavar='MB',
                   help=f'{when}split the bag into MCAP files of about MB megabytes (as ros2 bag '
                        'record --max-bag-size; default 0: one file)')
    p.add_argument('--max-bag-duration-s', type=split_limit(MAX_BAG_DURATION_S, 's'),
                   default=0.0, metavar='S',
                   help=f'{when}split the bag into MCAP files of S seconds (as ros2 bag record '
                        '--max-bag-duration; default 0: one file)')


def split_limit(maximum: float, unit: str):
    """Return the argparse type of a split limit: 0 (no split) to ``maximum`` ``unit``."""
    return number_in(0.0, maximum, f'0 (no split) to {maximum:g} {unit}')


def run_record(args) -> int:
    from ipomdp_gaze.nodes.recorder import main, TOPICS
    from ipomdp_gaze.files.bag import check_new_bag
    check_new_bag(args.path)
    ros = ['-p', f'path:={args.path.resolve()}']
    if args.topics:
        topics = [t.strip() for t in args.topics.split(',') if t.strip()]
        unknown = [t for t in topics if t not in TOPICS]
        if unknown:
            raise ValueError(f"--topics: unknown {', '.join(unknown)}; known: "
                             f"{', '.join(TOPICS)}")
        ros += ['-p', f"topics:=[{','.join(topics)}]"]
    if args.compression != 'none':
        ros += ['-p', f'compression:={args.compression}']
    from ipomdp_gaze.nodes.recorder import split_overrides
    ros += split_overrides(args.max_bag_size_mb, args.max_bag_duration_s)
    status = main(['ipomdp-gaze record', '--ros-args', *ros, *(args.ros_args or [])])
    if args.path.exists():          # else the recorder refused to start: its error says why
        print(describe_written(args.path), flush=True)
    return status


def run_reindex(args) -> int:
    from ipomdp_gaze.files.bag import reindex
    done = reindex(args.path, force=args.force)
    print(describe_written(args.path, 'rebuilt'))
    for name, count in done.recovered.items():
        print(f'{name}: unfinished, {counted(count, "message")} recovered')
    custom = done.info.get('custom_data') or {}
    nodes = sorted(k.split('/', 2)[2] for k in custom if k.startswith('ipomdp_gaze/parameters/'))
    print(f"package {custom.get('ipomdp_gaze/version', 'unknown')}; parameters of "
          f"{', '.join(nodes) or 'no node'}")
    return 0


def describe_written(path: Path, verb: str = 'wrote') -> str:
    """
    Say what a stopped recording wrote: messages per topic, seconds and megabytes.

    From the bag's ``metadata.yaml`` (written when the recorder closes the bag, on Ctrl-C or
    SIGTERM), so it is what a reader will find.
    """
    from ipomdp_gaze.files.bag import read_metadata
    try:
        info = read_metadata(path)
    except ValueError as exc:
        return f'ipomdp-gaze record: nothing readable was written ({exc})'
    counts = {t['topic_metadata']['name'].lstrip('/'): int(t['message_count'])
              for t in info.get('topics_with_message_count') or []}
    seconds = int((info.get('duration') or {}).get('nanoseconds', 0)) * 1e-9
    size = sum(f.stat().st_size for f in Path(path).iterdir() if f.is_file())
    topics = ', '.join(f'{topic} {n}' for topic, n in sorted(counts.items()) if n)
    files = len(info.get('relative_file_paths') or [])
    messages = counted(int(info.get('message_count', 0)), 'message')
    return (f'{verb} {path}: {messages} over {seconds:.1f} s, '
            f'{size / 1e6:.2f} MB' + (f' in {files} files' if files > 1 else '')
            + (f' ({topics})' if topics else ''))


def run_replay(args) -> int:
    from ipomdp_gaze.drivers.replay import check_options, describe_settings, describe_size, replay
    from ipomdp_gaze.files.bag import read_bag
    if not args.path.is_dir():
        raise ValueError(f'{args.path} is not a bag directory')
    bag = read_bag(args.path)
    overrides = {'observation': args.observation, 'policy': args.policy,
                 'policy_file': args.policy_file, 'confidence': args.confidence,
                 'max_fixations': args.max_fixations}
    check_options(bag, overrides)           # a bad option: its one line, nothing said before it
    print(f'{args.path}: {counted(len(bag.messages), "message")}, {describe_size(bag)}; package '
          f"{bag.custom_data.get('ipomdp_gaze/version', 'unknown')}")
    if args.new_search:
        from ipomdp_gaze.drivers.replay import new_search
        print(describe_settings(bag, overrides, args.new_search))
        new_search(bag, overrides)
        return 0
    # The replay first: the settings line says which recorded changes it applied. A replay
    # refused (a recorded change an option breaks, say) still says the settings it was given.
    try:
        result = replay(bag, overrides, out=lambda line: None)
    except ValueError:
        print(describe_settings(bag, overrides), flush=True)
        raise
    print(describe_settings(bag, overrides, result=result))
    for line in result.lines:
        print(line)
    print(f'{counted(result.frames, "frame")} recorded, {result.applied} applied by the replay')
    if result.stopped_early and bag.parameters('foveal_detector').get('mode') == 'fovea':
        print('the recording is of a fixed camera: --new-search runs a whole new search on '
              'its last image with these settings')
    return 0
