# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The options every heavy command shares: where its pieces run, and whether it shows progress."""
from __future__ import annotations

import os

from ipomdp_gaze.simulation.executor import make_executor, SCHEDULER_ENV
from ipomdp_gaze.simulation.progress import Progress

from .common import jobs_arg


def add_run_args(p, jobs_help: str = '') -> None:
    """Add ``--jobs``, ``--scheduler`` and ``--quiet`` to a command's parser."""
    p.add_argument('--jobs', type=jobs_arg, default=os.cpu_count() or 1,
                   help='worker processes on this machine (default: one per core; 1 runs '
                        'everything in this process; the numbers do not depend on it)'
                        + jobs_help)
    p.add_argument('--scheduler', default=None, metavar='ADDRESS',
                   help='run the pieces on the Dask cluster of this scheduler, e.g. '
                        f'tcp://host:8786 (default ${SCHEDULER_ENV}; docs/cluster.md)')
    p.add_argument('--quiet', action='store_true',
                   help='no progress on stderr (a bar on a terminal, else a line every few '
                        'seconds)')


def executor_from_args(args, pieces: int | None = None):
    """
    Return the executor of ``--jobs`` / ``--scheduler`` (``ClusterError``: one line).

    ``pieces``, when known, lets a small job run here and a pool start no idle processes.
    """
    return make_executor(args.jobs, args.scheduler, pieces)


def progress_from_args(args, total, desc: str, unit: str = 'piece') -> Progress:
    """Return a :class:`Progress` on stderr, silent with ``--quiet``."""
    return Progress(total, desc, unit, quiet=getattr(args, 'quiet', False))
