# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
One way to run pieces of work: in this process, in a local process pool, or on a Dask cluster.

Every heavy job (``reproduce``, ``evaluate``, ``calibrate``, ``train --seeds``, the benches)
splits its work into seeded pieces and hands them to an executor built by
:func:`make_executor`. All three executors have the ``concurrent.futures`` surface the jobs use:
``submit(fn, *args) -> Future``, ``workers``, ``close(cancel=False)`` and use as a context
manager. A piece's result depends only on its arguments (its seed travels with it), so a job
gives the same numbers bit for bit on one process, a local pool or a cluster of any size; a
piece lost with a dead Dask worker is simply run again elsewhere by the scheduler.

- ``make_executor(jobs=1)``: :class:`InlineExecutor`, every piece runs here when it is first
  waited for (``result()`` or :func:`track`), so progress moves piece by piece.
- ``make_executor(jobs=N)``: :class:`LocalExecutor`, N worker processes of this machine.
- ``make_executor(scheduler=ADDRESS)`` (or ``DASK_SCHEDULER_ADDRESS`` in the environment):
  :class:`DaskExecutor` on a running Dask scheduler (the extra ``ipomdp_gaze[cluster]``). It
  first checks that every worker runs the same package versions and the same ipomdp_gaze
  source as this process (:func:`source_digest`), so a piece computed there may be cached here.

Workers run pickled code that the client sends, and a Dask scheduler accepts any client by
default: run one only on a network you trust (docs/cluster.md). Results come back to this
process, which alone writes caches and files.

Writing a job for it (what ``evaluate``, ``calibrate`` and ``train --seeds`` do):

- a piece is a module-level function of ``ipomdp_gaze`` (pickled by reference, so importable on
  the workers) whose result depends only on its arguments: pass the seed, never a generator
  shared between pieces; fix the piece size, not the number of pieces per worker;
- submit every piece first, then collect in a fixed order (``future.result()``) so sums and
  concatenations do not depend on which piece finished first;
- write files and caches here, from results (``future.add_done_callback`` to keep each as soon as
  it is done); count progress the same way (:func:`track`, or ``Progress.update`` in a
  callback);
- on the command line, ``commands/running.py``: ``add_run_args(parser)`` (``--jobs``,
  ``--scheduler``, ``--quiet``), ``executor_from_args(args, pieces)`` and
  ``progress_from_args(args, total, desc, unit)``.

Typical use::

    with make_executor(jobs=args.jobs, scheduler=args.scheduler) as executor:
        progress = Progress(len(pieces), 'scenes')
        futures = [executor.submit(piece, *arguments) for arguments in pieces]
        for future in track(futures, progress):
            ...
        progress.close()

Leaving the ``with`` block on an exception or Ctrl-C cancels the pieces still queued or running.
"""
from __future__ import annotations

import concurrent.futures as cf
import functools
import hashlib
import os
from pathlib import Path
import signal
import socket
import sys
import threading

SCHEDULER_ENV = 'DASK_SCHEDULER_ADDRESS'
# Seconds to wait for a Dask scheduler before giving up with one line.
CONNECT_TIMEOUT_S = 10.0
# Beyond the connect timeout, how long a client that never finished connecting is waited for.
CONNECT_GRACE_S = 5.0


class ClusterError(OSError):
    """
    The cluster cannot be used (unreachable, mismatched workers, Dask missing): one line.

    An ``OSError``, as any other unusable resource, so the command line prints it as one line.
    """


@functools.lru_cache(maxsize=1)
def source_digest() -> str:
    """
    SHA-256 of every Python source of the package (a cached result is stale when it moves).

    Read once per process, as near as can be to when its code was imported: a worker that
    outlives a change of the files keeps the digest of the code it runs.
    """
    digest = hashlib.sha256()
    package = Path(__file__).resolve().parents[1]
    for folder in (package, package / 'policies'):
        for path in sorted(folder.resolve().rglob('*.py')):
            digest.update(path.read_bytes())
    return digest.hexdigest()


class _Executor:
    """What every executor shares: a context manager whose error exit cancels the rest."""

    workers = 1

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        self.close(cancel=kind is not None)
        return False

    def submit(self, fn, *args, **kwargs) -> cf.Future:
        raise NotImplementedError

    def close(self, cancel: bool = False) -> None:
        """Release the workers; ``cancel`` drops pieces not yet finished (Ctrl-C, an error)."""


class _InlineFuture(cf.Future):
    """
    A piece of :class:`InlineExecutor`: run in this process the first time it is waited for.

    ``result()``, ``exception()`` or :func:`track` run it (once); until then it is pending, so a
    progress count advances as each piece finishes, not all at once when they were submitted.
    Cancelling it before it ran drops it.
    """

    def __init__(self, fn, args, kwargs):
        super().__init__()
        self._call = (fn, args, kwargs)

    def run(self) -> None:
        """Run the piece now unless it ran or was cancelled (KeyboardInterrupt propagates)."""
        if self._call is None or not self.set_running_or_notify_cancel():
            self._call = None
            return
        fn, args, kwargs = self._call
        self._call = None
        try:
            result = fn(*args, **kwargs)
        except BaseException as exc:            # KeyboardInterrupt too: handed to the caller
            if not isinstance(exc, Exception):
                self.cancel_interrupted()
                raise
            self.set_exception(exc)
        else:
            self.set_result(result)

    def cancel_interrupted(self) -> None:
        """Mark a piece interrupted by Ctrl-C as finished with that interruption."""
        self.set_exception(KeyboardInterrupt())

    def result(self, timeout=None):
        """Run the piece if it has not run, then return its result."""
        self.run()
        return super().result(timeout)

    def exception(self, timeout=None):
        """Run the piece if it has not run, then return what it raised (or None)."""
        self.run()
        return super().exception(timeout)


class InlineExecutor(_Executor):
    """Run each piece in this process, in submission order, when it is first waited for."""

    def submit(self, fn, *args, **kwargs) -> cf.Future:
        """Return a future of ``fn(*args, **kwargs)`` that runs here when waited for."""
        return _InlineFuture(fn, args, kwargs)


def _die_with_parent() -> None:
    """
    Make this pool worker end when the process that made it dies (Linux ``PR_SET_PDEATHSIG``).

    A parent killed outright (SIGKILL, a script's timeout) runs no clean-up, and its workers
    would run on, holding its pipes open. Elsewhere (no ``prctl``) nothing changes. SIGTERM
    ends the worker (the default), whatever handler the parent had when it forked it: that is
    also how :meth:`LocalExecutor.close` stops them.
    """
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    parent = os.getppid()
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)           # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:                  # the parent died before the call
        os._exit(1)


class LocalExecutor(_Executor):
    """A pool of ``processes`` worker processes on this machine, started on the first piece."""

    def __init__(self, processes: int):
        self.workers = int(processes)
        self._pool = cf.ProcessPoolExecutor(self.workers, initializer=_die_with_parent)

    def submit(self, fn, *args, **kwargs) -> cf.Future:
        """Queue ``fn(*args, **kwargs)`` in the pool."""
        return self._pool.submit(fn, *args, **kwargs)

    def close(self, cancel: bool = False) -> None:
        """Wait for the pool; with ``cancel``, stop its processes at once instead."""
        if cancel:
            for process in list((self._pool._processes or {}).values()):
                try:
                    os.kill(process.pid, signal.SIGTERM)
                except OSError:
                    pass                        # already gone
            self._pool.shutdown(wait=False, cancel_futures=True)
        else:
            self._pool.shutdown()


class DaskExecutor(_Executor):
    """
    The pieces on a Dask cluster through ``distributed``'s ``concurrent.futures`` executor.

    Connecting checks the cluster (:meth:`check`). A worker that dies has its pieces run again
    on another one by the scheduler (up to Dask's ``allowed-failures``). A large array that
    many pieces share (a run's targets) goes to the cluster once, as a task of its own that
    the scheduler can recompute when the worker holding it dies (scattered data could not be).
    """

    # Arrays of at least this many bytes are sent once and shared by the pieces.
    SHARE_BYTES = 1 << 20

    def __init__(self, address: str, timeout_s: float = CONNECT_TIMEOUT_S, check: bool = True):
        try:
            from distributed import Client
        except ImportError:
            raise ClusterError('--scheduler needs Dask: pip install "ipomdp_gaze[cluster]" '
                               '(dask[distributed])') from None
        self.address = address
        _probe(address, timeout_s)
        self.client = _connect(Client, address, timeout_s)
        try:
            if check:
                self.check()
            self.workers = max(1, len(self.client.scheduler_info(n_workers=-1)['workers']))
        except BaseException:
            self.client.close()
            raise
        self._executor = self.client.get_executor(pure=False)
        self._shared = {}

    def check(self) -> None:
        """
        Refuse a cluster whose workers differ from this process.

        ``get_versions(check=True)`` compares Python, Dask and the other required packages;
        then every worker must hold ipomdp_gaze with the same :func:`source_digest` (so pieces
        computed there are what this code computes, and the piece cache key stays honest).
        """
        try:
            self.client.get_versions(check=True)
        except ValueError as exc:
            first = str(exc).strip().splitlines()[0]
            raise ClusterError(f'the Dask workers at {self.address} run other package versions '
                               f'than this process: {first}') from None
        mine = source_digest()
        theirs = self.client.run(_worker_source)
        for worker, digest in sorted(theirs.items()):
            if digest != mine:
                raise ClusterError(f'Dask worker {worker} runs another ipomdp_gaze (source '
                                   f'{digest[:12]}) than this process ({mine[:12]}): install '
                                   'the same code on every worker')
        if not theirs:
            raise ClusterError(f'the Dask scheduler at {self.address} has no workers')

    def submit(self, fn, *args, **kwargs) -> cf.Future:
        """Send ``fn(*args, **kwargs)`` to the cluster; the future resolves here."""
        return self._executor.submit(fn, *(self._share(a) for a in args), **kwargs)

    def _share(self, value):
        """Return a large array as the one cluster future that holds it (else ``value``)."""
        nbytes = getattr(value, 'nbytes', 0)
        if not isinstance(nbytes, int) or nbytes < self.SHARE_BYTES:
            return value
        from dask.base import tokenize
        key = f'ipomdp-array-{tokenize(value)}'
        if key not in self._shared:
            self._shared[key] = self.client.submit(_same, value, key=key)
        return self._shared[key]

    def close(self, cancel: bool = False) -> None:
        """Disconnect; with ``cancel``, the scheduler first drops the pieces still queued."""
        try:
            if cancel:
                self.client.cancel(list(self._executor._futures), force=True)
        finally:
            self._shared.clear()
            self.client.close()


def _same(value):
    """Return ``value`` (a task that holds a shared array on the cluster)."""
    return value


def _connect(client_class, address: str, timeout_s: float):
    """
    Return a ``Client`` of the scheduler at ``address``, or raise ClusterError in one line.

    A port that accepts the connection but is no Dask scheduler (the dashboard's 8787, a web
    server) never answers Dask's handshake, and ``Client``'s own timeout does not cover it; one
    that answers with other bytes makes Dask read garbage (a MemoryError, a TypeError for
    ``tls://`` without certificates). So the client is made in a daemon thread, waited for at
    most ``timeout_s`` and a little more, and any failure is the scheduler's, said in one line.
    A client that fails, or connects only after the wait, is closed by that thread: left to the
    garbage collector, its ``Client.__del__`` could run inside Dask's loop lock while the next
    client starts, and wait for that lock for ever; its complaints when collected are silenced.
    """
    made = {}
    lock = threading.Lock()
    finished = threading.Event()

    class HeldClient(client_class):
        """A client held from its first step, so that one which fails can be closed."""

        def start(self, **kwargs):
            made['half'] = self
            return super().start(**kwargs)

    def connect():
        try:
            made['client'] = HeldClient(address, timeout=timeout_s, set_as_default=False)
        except BaseException as exc:            # noqa: B902 (any failure is the scheduler's)
            made['error'] = exc
        with lock:
            finished.set()
            kept = 'client' in made and not made['late']
        if not kept and 'half' in made:
            _close_quietly(made['half'])

    made['late'] = False
    thread = threading.Thread(target=connect, name='dask-connect', daemon=True)
    deadline_s = timeout_s + min(CONNECT_GRACE_S, timeout_s)
    thread.start()
    finished.wait(deadline_s)
    with lock:
        made['late'] = not finished.is_set()
    if 'client' in made and not made['late']:
        return made['client']
    _quiet_client_collection()
    if made['late']:
        raise ClusterError(f'no Dask scheduler answered at {address} within {deadline_s:g} s '
                           '(something listens there: is it the dashboard? a scheduler listens '
                           'on 8786 by default, its dashboard on 8787)')
    exc = made['error']
    detail = 'it answered what no Dask scheduler sends' if isinstance(exc, MemoryError) else \
        (str(exc).strip().splitlines() or [type(exc).__name__])[-1]
    raise ClusterError(f'cannot reach the Dask scheduler at {address} within {timeout_s:g} s '
                       f'({type(exc).__name__}: {detail})')


def _close_quietly(client) -> None:
    """Close a client that failed to connect; an error in closing is not the one to report."""
    try:
        client.close()
    except Exception:                           # noqa: B902 (the connect failure came first)
        pass


def _quiet_client_collection() -> None:
    """Silence the 'Exception ignored in Client.__del__' of a client that failed to connect."""
    previous = sys.unraisablehook

    def hook(unraisable):
        if 'Client.__del__' not in repr(getattr(unraisable, 'object', None)):
            previous(unraisable)
    sys.unraisablehook = hook


def _probe(address: str, timeout_s: float) -> None:
    """
    Refuse a malformed or unreachable TCP address at once, with the reason, in one line.

    Dask would retry a refused connection until its timeout and then say only that it timed
    out; other transports (``ucx://`` ...) are left to Dask.
    """
    scheme, sep, rest = address.rpartition('://')
    if sep and scheme not in ('tcp', 'tls'):
        return
    host, colon, port = rest.rpartition(':')
    whole = port.isascii() and port.isdigit()               # int() refuses '²', isdigit not
    if not colon or not host or not whole or not 0 < int(port) < 65536:
        raise ClusterError(f'--scheduler wants [tcp://]HOST:PORT, e.g. tcp://10.0.0.5:8786, '
                           f'got {address!r}')
    try:
        socket.create_connection((host.strip('[]'), int(port)), timeout=timeout_s).close()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ClusterError(f'cannot reach the Dask scheduler at {address}: {reason}') from None


def _worker_source() -> str:
    """Return the source digest of the ipomdp_gaze a worker imports (run there)."""
    return source_digest()


def scheduler_address(scheduler: str | None = None) -> str | None:
    """Return the Dask scheduler to use: ``scheduler``, else ``$DASK_SCHEDULER_ADDRESS``."""
    return scheduler or os.environ.get(SCHEDULER_ENV) or None


def make_executor(jobs: int | None = None, scheduler: str | None = None,
                  pieces: int | None = None):
    """
    Return the executor for a job: Dask when a scheduler is given, else local ``jobs`` processes.

    ``jobs`` None means one process per core; 1 runs every piece in this process, and so does a
    small job, of ``pieces`` < 2 when the caller knows its size (no pool to start). Raises
    :class:`ClusterError` (one line) when the scheduler cannot be used.
    """
    address = scheduler_address(scheduler)
    if address:
        return DaskExecutor(address)
    jobs = (os.cpu_count() or 1) if jobs is None else int(jobs)
    if jobs < 1:
        raise ValueError(f'jobs must be >= 1, got {jobs}')
    small = pieces is not None and pieces < 2
    return InlineExecutor() if jobs == 1 or small else LocalExecutor(min(jobs, pieces or jobs))


def track(futures, progress=None, weights=None):
    """
    Yield the futures as they finish, advancing ``progress`` by each one's weight (default 1).

    ``progress`` is anything with ``update(n)``
    (:class:`ipomdp_gaze.simulation.progress.Progress`).
    Pieces of an :class:`InlineExecutor` are run here, one by one in submission order.
    """
    futures = list(futures)
    weights = [1] * len(futures) if weights is None else list(weights)
    weight = {id(f): w for f, w in zip(futures, weights)}
    inline = [f for f in futures if isinstance(f, _InlineFuture)]
    others = [f for f in futures if not isinstance(f, _InlineFuture)]
    for future in inline:
        future.run()
        if progress is not None:
            progress.update(weight[id(future)])
        yield future
    for future in cf.as_completed(others):
        if progress is not None:
            progress.update(weight[id(future)])
        yield future


def run_by_searcher(piece, spec, episodes: int, executor=None, progress=None) -> dict:
    """
    Run ``piece(spec, i)`` for scenes ``i`` in ``0..episodes-1``; group its results by searcher.

    Each piece returns a list of results with a ``searcher`` attribute; the answer is
    ``{searcher: [result per scene, in scene order]}``, in the order the searchers first appear.
    ``executor`` defaults to an :class:`InlineExecutor`; ``progress`` counts scenes as they end.
    """
    executor = InlineExecutor() if executor is None else executor
    futures = [executor.submit(piece, spec, i) for i in range(episodes)]
    for _ in track(futures, progress):
        pass
    out = {}
    for future in futures:
        for r in future.result():
            out.setdefault(r.searcher, []).append(r)
    return out
