# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ``ipomdp-gaze`` command line: one subcommand per job.

Each module under ``ipomdp_gaze.commands`` has ``add_parser(sub)``, which registers its
subcommands (one, or for :mod:`ipomdp_gaze.commands.nodes` one per node) with their arguments
and a ``run(args) -> int``. A bad argument or input file exits non-zero with one clear line on
stderr, never a traceback.
"""
from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
import warnings

from ipomdp_gaze.files.share_files import package_version

# Modules under ipomdp_gaze.commands, in the order --help lists their subcommands: evaluate,
# search, find, train, calibrate, reproduce, demo, record, reindex and replay, then the nodes:
# controller, camera, detector, scene_camera and recorder.
COMMANDS = ('evaluate', 'search', 'find', 'train', 'calibrate', 'reproduce', 'demo', 'record',
            'nodes')


class CliError(Exception):
    """A user-facing error: printed as one line, exit status 2."""


class _Parser(argparse.ArgumentParser):

    def error(self, message):
        self.exit(2, f'{self.prog}: error: {message}\n')


class _CommandParser(_Parser):
    """
    A subcommand's parser: an argument it does not know is refused under its own name.

    argparse hands a subcommand's unknown arguments back to the top-level parser, whose error
    named ``ipomdp-gaze`` alone (``ipomdp-gaze: error: unrecognized arguments: --foo`` for
    ``ipomdp-gaze controller --foo``); the command run is ``ipomdp-gaze controller``.
    """

    def parse_known_args(self, args=None, namespace=None):
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return namespace, extras


def build_parser() -> argparse.ArgumentParser:
    """Build the top-level parser with every subcommand registered."""
    parser = _Parser(
        prog='ipomdp-gaze',
        description='I-POMDP infomax gaze control (Butko & Movellan, ICDL 2008): '
                    'evaluate, train and run policies that choose where to look next.')
    parser.add_argument('--version', action='version',
                        version=f'%(prog)s {package_version()}')
    sub = parser.add_subparsers(dest='command', metavar='COMMAND',
                                parser_class=_CommandParser)
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(f'ipomdp_gaze.commands.{name}').add_parser(sub)
    return parser


def _one_line_warnings(command: str, default):
    """Return a ``warnings.showwarning`` that prints the package's own warnings in one line."""
    def show(message, category, filename, lineno, file=None, line=None):
        if category.__module__.startswith('ipomdp_gaze'):
            print(f'ipomdp-gaze {command}: warning: {message}', file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)
    return show


# BLAS libraries' thread counts, pinned to one unless the environment sets them: a long matrix
# product (training's gradient) sums in pieces per thread and rounds differently with their
# number, and training compounds it over epochs, so a curve regenerates exactly only on the
# same count (docs/reproduction.md). Set before numpy is first imported (build_parser), unless a
# variable the bundled OpenBLAS reads is set: a user's OMP_NUM_THREADS stands (an MKL or BLIS
# variable does not reach numpy's OpenBLAS, so it does not stop the pin).
OPENBLAS_THREAD_VARIABLES = ('OPENBLAS_NUM_THREADS', 'GOTO_NUM_THREADS', 'OMP_NUM_THREADS')


def main(argv=None) -> int:
    """Entry point of the console script."""
    if not any(os.environ.get(name) for name in OPENBLAS_THREAD_VARIABLES):
        os.environ['OPENBLAS_NUM_THREADS'] = os.environ['OMP_NUM_THREADS'] = '1'
        os.environ.setdefault('MKL_NUM_THREADS', '1')
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv:
        parser.print_help(sys.stderr)       # a bare command: what there is to run
        return 2
    args = parser.parse_args(argv)
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warnings(args.command, warnings.showwarning)
        return _run(args)


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a script's ``terminate()``): stopped as Ctrl-C stops, exit 143."""


def _terminate(signum, frame):
    raise Terminated()


# The commands that run pieces of work in this process or a pool: SIGTERM stops them as Ctrl-C
# does (the pool's pieces cancelled, no half-written file). The node commands keep rclpy's own
# handling; demo and record keep theirs.
WORK_COMMANDS = ('evaluate', 'train', 'reproduce', 'calibrate', 'find', 'search')

# The options that name a file a work command or the demo writes (``-`` is stdout, no file).
OUTPUT_OPTIONS = ('json', 'log', 'plot', 'out', 'resume', 'animate', 'record')


def writes_files(args) -> bool:
    """Whether the parsed command writes a file of its own besides stdout and stderr."""
    return args.command in WORK_COMMANDS + ('demo',) and any(
        getattr(args, name, None) is not None and str(getattr(args, name)) != '-'
        for name in OUTPUT_OPTIONS)


class _ReaderGone:
    """
    A stdout or stderr that, once its reader has gone (``| head -1``), discards what is written.

    Installed for a command that writes files: a pipe closed early must cost the lines it
    no longer wants, not ``--json`` and the other files, which are written at the end.
    """

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._discard()
            return len(text)

    def flush(self):
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._discard()

    def _discard(self):
        try:                                    # nothing still buffered reaches the pipe
            os.dup2(os.open(os.devnull, os.O_WRONLY), self._stream.fileno())
        except (OSError, ValueError, AttributeError):
            pass                                # not a file descriptor (a test's capture)
        self._stream = open(os.devnull, 'w')

    def __getattr__(self, name):
        return getattr(self._stream, name)


TOO_LARGE = ('ipomdp-gaze {}: error: out of memory: the task is too large for this machine (a '
             'smaller --grid or fewer {})')
# The counts each command sizes its work by (train has no --episodes).
TOO_LARGE_COUNTS = {'train': '--episodes-per-epoch, --eval-episodes or --final-episodes, or a '
                             'shorter --horizon'}


def too_large(command: str) -> str:
    """Return the line of a task too large for the machine, naming ``command``'s own counts."""
    return TOO_LARGE.format(command, TOO_LARGE_COUNTS.get(command, '--episodes'))


# numpy's refusals of an array too large to describe (a count such as --episodes 1e21 sizes
# it), before any memory is asked for: the same task too large as a MemoryError.
NUMPY_TOO_LARGE = ('Maximum allowed dimension exceeded',
                   'array is too big; `arr.size * arr.dtype.itemsize` is larger than the '
                   'maximum possible size.')


# The Python packages of ROS 2 a command may import (rclpy and the message packages): without
# them a ROS command says how to install them in one line instead of an import traceback.
ROS_MISSING = ('ipomdp-gaze {}: error: this command needs ROS 2 Jazzy (No module named {!r}): '
               'pip install "ros-jazzy-rclpy[fastrtps]" ros-jazzy-common-interfaces (the ros '
               'extra of setup.py) into this environment, or source a ROS 2 Jazzy install')


def ros_module(name: str | None) -> bool:
    """Whether ``name`` (a missing module's) is one of ROS 2's Python packages."""
    root = (name or '').split('.')[0]
    return root.startswith(('rcl', 'rosidl', 'rosbag2', 'rpyutils')) or root.endswith(
        ('_msgs', '_srvs', '_interfaces'))


def _run(args) -> int:
    """Run the parsed command; its errors as one line (exit 2)."""
    handles = args.command in WORK_COMMANDS and \
        threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminate) if handles else None
    streams = sys.stdout, sys.stderr
    if writes_files(args):
        sys.stdout, sys.stderr = _ReaderGone(sys.stdout), _ReaderGone(sys.stderr)
    try:
        return int(args.run(args) or 0)
    except BrokenPipeError:
        # The reader went away (``| head``): stop quietly, and let nothing flush to the pipe.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except (CliError, ValueError, OSError) as exc:
        if isinstance(exc, ValueError) and str(exc) in NUMPY_TOO_LARGE:
            print(too_large(args.command), file=sys.stderr)
        else:
            print(f'ipomdp-gaze {args.command}: error: {exc}', file=sys.stderr)
        return 2
    except MemoryError:
        print(too_large(args.command), file=sys.stderr)
        return 2
    except ModuleNotFoundError as exc:
        if not ros_module(exc.name):
            raise
        print(ROS_MISSING.format(args.command, exc.name), file=sys.stderr)
        return 2
    except Terminated:
        return 143
    except KeyboardInterrupt:
        return 130
    finally:
        sys.stdout, sys.stderr = streams
        if handles:
            signal.signal(signal.SIGTERM, previous)


if __name__ == '__main__':
    sys.exit(main())
