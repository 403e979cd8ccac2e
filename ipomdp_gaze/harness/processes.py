# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Start, watch and stop nodes as separate processes (no ``ros2 launch`` here): demo, tests, benches.

Each node runs as ``python -m ipomdp_gaze.nodes.<name> --ros-args ...`` with its output in a log
file. :func:`ros_environment` isolates a run: its own ``ROS_DOMAIN_ID``, discovery limited to this
host, and node log files in a directory of its own. A :class:`NodeGroup` holds the processes of
one run (:func:`isolated_nodes` makes one in a temporary folder); what they publish is watched
from this process by :class:`ipomdp_gaze.harness.watch.Watch`. This module does not import rclpy.
"""
from __future__ import annotations

from contextlib import contextmanager
import os
from pathlib import Path
import signal
import subprocess
import sys
import tempfile
import time

from ipomdp_gaze.nodes import NODE_NAMES

MAX_DOMAIN_ID = 101
# Fast DDS maps domain ids to UDP ports: on Linux 0..101 and 215..232 are valid (ROS 2's
# "ROS_DOMAIN_ID" concept page); runs pick their own in 1..101 (reserve_domain_id).
LINUX_EXTRA_DOMAINS = range(215, 233)


def valid_domain_id(domain_id) -> bool:
    """Whether ``domain_id`` is a ROS domain id Fast DDS takes on Linux (0..101, 215..232)."""
    return 0 <= int(domain_id) <= MAX_DOMAIN_ID or int(domain_id) in LINUX_EXTRA_DOMAINS


# Run a node with a faulthandler: SIGUSR1 prints every thread's stack to its log.
STACK_DUMP_MAIN = ('import faulthandler, signal, sys; '
                   'faulthandler.register(signal.SIGUSR1, all_threads=True); '
                   'from ipomdp_gaze.nodes.{node} import main; sys.exit(main())')


_RESERVED: dict[int, object] = {}


def domain_id_for(pid: int | None = None) -> int:
    """
    Return a ROS domain id for this run: one no other run on this host holds.

    With ``pid``, the old derivation ``pid mod 102`` (no reservation). Without, this process
    reserves a domain in 1..101 (0 is the default domain of a real robot) by holding an
    exclusive ``flock`` on ``<tmp>/ipomdp_gaze-ros-domains/<id>.lock`` until it exits, starting
    from its pid and taking the next free one; later calls return the same id. Two test runs,
    benches or demos at once therefore never share a domain (the pid modulo 102 once collided).

    Raises
    ------
    RuntimeError
        If every domain 1..101 is held by another process.

    """
    if pid is not None:
        return int(pid) % (MAX_DOMAIN_ID + 1)
    if _RESERVED:
        return next(iter(_RESERVED))
    import fcntl
    folder = Path(tempfile.gettempdir()) / 'ipomdp_gaze-ros-domains'
    folder.mkdir(parents=True, exist_ok=True)
    start = os.getpid()
    for k in range(MAX_DOMAIN_ID):
        domain = 1 + (start + k) % MAX_DOMAIN_ID
        handle = open(folder / f'{domain}.lock', 'a')
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        _RESERVED[domain] = handle            # held (and the lock with it) until exit
        return domain
    raise RuntimeError(f'every ROS domain id 1..{MAX_DOMAIN_ID} is held by another run '
                       f'(locks in {folder})')


def ros_environment(domain_id: int, log_dir, base: dict | None = None) -> dict:
    """Copy ``base`` (default ``os.environ``) and set it up for an isolated run."""
    if not valid_domain_id(domain_id):
        raise ValueError(f'domain id must be in 0..{MAX_DOMAIN_ID} or 215..232, got {domain_id}')
    env = dict(os.environ if base is None else base)
    env.update({'ROS_DOMAIN_ID': str(int(domain_id)),
                'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST',
                'ROS_LOG_DIR': str(log_dir), 'PYTHONUNBUFFERED': '1'})
    env.pop('ROS_LOCALHOST_ONLY', None)
    return env


def wait_for(condition, timeout_s: float = 20.0, interval_s: float = 0.02) -> bool:
    """Poll ``condition()`` until it is true or ``timeout_s`` passes; return its last value."""
    deadline = time.monotonic() + timeout_s
    while True:
        if condition():
            return True
        if time.monotonic() > deadline:
            return bool(condition())
        time.sleep(interval_s)


def stop_processes(procs, timeout_s: float = 10.0) -> None:
    """
    Stop ``subprocess.Popen`` processes, the last started first: SIGTERM, SIGKILL after a wait.

    The reverse order matters for a cluster: workers first, since a worker without its
    scheduler retries for a long time.
    """
    for proc in reversed(list(procs)):
        proc.terminate()
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def exit_states(codes: dict, alive: dict) -> str:
    """
    Say how each node of a run ended, for the demos' last line.

    ``codes`` maps a node to its exit code (None: never started, as when an earlier node did
    not come up in time), ``alive`` whether it was running when stopped; ``detector exit
    status 0``, ``camera exit status 1 (had already exited)``, ``scene_camera not started``.
    """
    return ', '.join(f'{k} not started' if v is None else f'{k} exit status {v}'
                     + ('' if alive.get(k, True) else ' (had already exited)')
                     for k, v in codes.items())


class NodeExited(RuntimeError):
    """A node process that should be running has exited."""


class NodeProcess:
    """
    One node in its own process; its stdout and stderr go to ``log_path``.

    With ``stack_dump``, the node runs with a faulthandler on SIGUSR1, and :meth:`stop` sends it
    SIGUSR1 before SIGKILL, so a node that hangs on SIGTERM leaves every thread's stack in its log.
    """

    def __init__(self, node: str, ros_args=(), env: dict | None = None, log_path=None,
                 stack_dump: bool = False):
        if node not in NODE_NAMES:
            raise ValueError(f"node must be one of {', '.join(NODE_NAMES)}, got {node!r}")
        self.node = node
        self.name = NODE_NAMES[node]
        main = ['-c', STACK_DUMP_MAIN.format(node=node)] if stack_dump else \
            ['-m', f'ipomdp_gaze.nodes.{node}']
        self.args = [sys.executable, *main, '--ros-args', *map(str, ros_args)]
        self.stack_dump = stack_dump
        self.env = env
        self.log_path = Path(log_path) if log_path else None
        self.proc: subprocess.Popen | None = None

    def start(self) -> 'NodeProcess':
        """Start the process."""
        out = open(self.log_path, 'wb') if self.log_path else subprocess.DEVNULL
        try:
            self.proc = subprocess.Popen(self.args, env=self.env, stdout=out,
                                         stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        finally:
            if self.log_path:
                out.close()
        return self

    @property
    def running(self) -> bool:
        """Whether the process has been started and has not exited."""
        return self.proc is not None and self.proc.poll() is None

    def stop(self, timeout_s: float = 10.0) -> int | None:
        """SIGTERM (rclpy shuts down cleanly), then SIGKILL after ``timeout_s``; the exit code."""
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                if self.stack_dump:
                    self.proc.send_signal(signal.SIGUSR1)
                    time.sleep(1.0)
                self.proc.kill()
                self.proc.wait(timeout_s)
        return self.proc.returncode

    def kill(self) -> None:
        """SIGKILL: no clean-up at all, as in a crash."""
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait(10)

    def output(self) -> str:
        """Return what the process printed so far."""
        if self.log_path is None or not self.log_path.exists():
            return ''
        return self.log_path.read_text(errors='replace')


class NodeGroup:
    """
    The node processes of one run: one environment, their logs in one folder.

    Parameters
    ----------
    env : dict
        Environment of every node (:func:`ros_environment`).
    log_dir : path
        Folder of the log files, ``<node>-<n>.log`` (n counts the processes started).
    stack_dump : bool
        See :class:`NodeProcess`.

    """

    def __init__(self, env: dict, log_dir, stack_dump: bool = False):
        self.env = env
        self.log_dir = Path(log_dir)
        self.stack_dump = stack_dump
        self.processes: list[NodeProcess] = []
        self.killed: list[NodeProcess] = []
        self._count = 0

    @property
    def domain_id(self) -> int:
        """Return the ROS domain of the nodes."""
        return int(self.env['ROS_DOMAIN_ID'])

    def add(self, node: str, ros_args=()) -> NodeProcess:
        """Prepare a node process (a key of ``NODE_NAMES``) of this run, not started yet."""
        log = self.log_dir / f'{node}-{self._count}.log'
        self._count += 1
        proc = NodeProcess(node, ros_args, self.env, log, self.stack_dump)
        self.processes.append(proc)
        return proc

    def start(self, node: str, ros_args=()) -> NodeProcess:
        """Start a node process (a key of ``NODE_NAMES``)."""
        return self.add(node, ros_args).start()

    def kill(self, proc: NodeProcess) -> None:
        """SIGKILL a node on purpose; it is not expected to run any more."""
        proc.kill()
        self.killed.append(proc)

    def last(self, node: str) -> NodeProcess:
        """Return the process of this node started last."""
        return next(p for p in reversed(self.processes) if p.node == node)

    def check(self) -> None:
        """
        Raise :class:`NodeExited` if a node that was started and not killed has exited.

        Raises
        ------
        NodeExited
            Naming the node and its exit status (its output is in its log).

        """
        for proc in self.processes:
            if proc.proc is not None and proc not in self.killed and not proc.running:
                raise NodeExited(f'the {proc.node} node exited with status '
                                 f'{proc.proc.returncode} (its output is below)')

    def stop(self, procs=None, timeout_s: float = 10.0) -> list[tuple[NodeProcess, int | None]]:
        """Stop ``procs`` in that order (default: every node not killed, in the order added)."""
        if procs is None:
            procs = [p for p in self.processes if p not in self.killed]
        return [(p, p.stop(timeout_s)) for p in procs]

    def close(self) -> list[str]:
        """Stop every node not killed; describe each that did not exit with status 0."""
        return [f'{p.node}: exit status {code}\n{p.output()[-3000:]}'
                for p, code in self.stop() if code]


@contextmanager
def isolated_nodes(domain_id: int | None = None, prefix: str = 'ipomdp-gaze-',
                   stack_dump: bool = False):
    """
    Yield a :class:`NodeGroup` on a domain of its own with its logs in a temporary folder.

    The domain defaults to the one :func:`domain_id_for` reserves for this process. Every node
    still running at the end is stopped (SIGTERM), and the folder is removed.
    """
    domain = domain_id_for() if domain_id is None else domain_id
    with tempfile.TemporaryDirectory(prefix=prefix) as tmp:
        group = NodeGroup(ros_environment(domain, Path(tmp) / 'ros_log'), tmp, stack_dump)
        try:
            yield group
        finally:
            group.stop()
