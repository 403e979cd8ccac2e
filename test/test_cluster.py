# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The heavy jobs on a real Dask cluster: a ``dask scheduler`` and two ``dask worker`` processes.

Every command gives the same output through ``--scheduler`` as in this process; a worker killed
mid-run loses nothing; an unreachable scheduler or a worker with other code is one clear line;
Ctrl-C stops a run at once and keeps its finished pieces.
"""
from dataclasses import dataclass
import gc
import json
import os
from pathlib import Path
import re
import signal
import socket
import subprocess
import sys
import threading
import time

from conftest import require_extra, wait_for
from ipomdp_gaze.cli import main as cli_main
from ipomdp_gaze.drivers import pieces
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.simulation import executor as executor_module
from ipomdp_gaze.simulation.executor import ClusterError, DaskExecutor
import numpy as np
import pytest

# The `cluster` extra: without it this module is skipped, unless a run requires the extras
# (IPOMDP_GAZE_REQUIRE_ROS, set by `make test`, which installs them); broken, it fails.
distributed = require_extra('distributed', 'cluster')

ROOT = Path(__file__).resolve().parents[1]
GRID, FPOC = Grid(5, 5, 0.42), make_fpoc('human')


@dataclass
class Cluster:
    """A running scheduler, its address, and how to start or kill a worker."""

    address: str
    folder: Path
    processes: list

    def start_worker(self, name: str) -> subprocess.Popen:
        """Start one single-threaded worker process (no nanny: killing it kills the worker)."""
        log = open(self.folder / f'{name}.log', 'w')
        proc = subprocess.Popen(
            [sys.executable, '-m', 'distributed.cli.dask_worker', self.address, '--name', name,
             '--nthreads', '1', '--no-nanny', '--no-dashboard', '--memory-limit', '0',
             '--host', '127.0.0.1'], stdout=log, stderr=subprocess.STDOUT,
            env={**os.environ, 'OMP_NUM_THREADS': '1'})
        log.close()
        self.processes.append(proc)
        return proc

    def workers(self) -> int:
        """Return the number of workers the scheduler knows."""
        with distributed.Client(self.address, timeout=20, set_as_default=False) as client:
            return len(client.scheduler_info(n_workers=-1)['workers'])


@pytest.fixture(scope='module')
def cluster(tmp_path_factory):
    """Start a scheduler and two workers on this machine; stop them after the module."""
    folder = tmp_path_factory.mktemp('dask')
    state = folder / 'scheduler.json'
    log = open(folder / 'scheduler.log', 'w')
    scheduler = subprocess.Popen(
        [sys.executable, '-m', 'distributed.cli.dask_scheduler', '--host', '127.0.0.1',
         '--port', '0', '--no-dashboard', '--scheduler-file', str(state)],
        stdout=log, stderr=subprocess.STDOUT)
    log.close()
    running = Cluster('', folder, [scheduler])
    try:
        assert wait_for(lambda: state.is_file() and state.stat().st_size > 0, 60), \
            (folder / 'scheduler.log').read_text()
        running.address = json.loads(state.read_text())['address']
        for name in ('w1', 'w2'):
            running.start_worker(name)
        with distributed.Client(running.address, timeout=20, set_as_default=False) as client:
            client.wait_for_workers(2, timeout=60)
        yield running
    finally:                    # the workers first: without a scheduler they retry for long
        from ipomdp_gaze.harness.processes import stop_processes
        stop_processes(running.processes)


def _run(argv, capsys) -> str:
    assert cli_main(argv) == 0, capsys.readouterr().err
    return capsys.readouterr().out


def test_evaluate_through_the_scheduler_matches_one_process(cluster, tmp_path, capsys):
    argv = ['evaluate', '--grid', '5x5', '--policy', 'elm', '--policy', 'greedy', '--policy',
            'random', '--episodes', '800', '--episodes-greedy', '300', '--bootstrap', '100',
            '--paired', '--quiet']
    _run([*argv, '--jobs', '1', '--json', str(tmp_path / 'here.json')], capsys)
    out = _run([*argv, '--scheduler', cluster.address, '--json', str(tmp_path / 'dask.json')],
               capsys)
    assert (tmp_path / 'here.json').read_bytes() == (tmp_path / 'dask.json').read_bytes()
    assert 'greedy' in out


def test_calibrate_through_the_scheduler_matches_one_process(cluster, tmp_path, capsys):
    argv = ['calibrate', '--scenes', '4', '--grid', '7x7', '--windows', '7,3', '--scales',
            '1/2,1', '--quiet']
    _run([*argv, '--jobs', '1', '--out', str(tmp_path / 'here.yaml')], capsys)
    _run([*argv, '--scheduler', cluster.address, '--out', str(tmp_path / 'dask.yaml')], capsys)

    def model(path):                    # the file minus its wall time
        return [line for line in path.read_text().splitlines() if 'wall_seconds' not in line]
    assert model(tmp_path / 'here.yaml') == model(tmp_path / 'dask.yaml')


def test_train_sweep_through_the_scheduler_matches_plain_trainings(cluster, tmp_path, capsys):
    small = ['train', '--grid', '4x4', '--epochs', '6', '--eval-every', '3',
             '--eval-episodes', '100', '--final-episodes', '300', '--quiet']
    out = _run([*small, '--seeds', '3,4', '--scheduler', cluster.address, '--out',
                str(tmp_path / 'k.yaml')], capsys)
    assert 'over 2 seeds: mean' in out
    for seed in (3, 4):
        _run([*small, '--seed', str(seed), '--out', str(tmp_path / f'plain{seed}.yaml')], capsys)
        for suffix in ('.yaml', '.csv'):
            swept = (tmp_path / f'k-seed{seed}').with_suffix(suffix).read_text().splitlines()
            plain = (tmp_path / f'plain{seed}').with_suffix(suffix).read_text().splitlines()
            if suffix == '.yaml':
                swept, plain = ([line for line in text if 'wall_seconds' not in line]
                                for text in (swept, plain))
            else:                       # the curve's last column is its wall time
                swept, plain = ([line.rsplit(',', 1)[0] for line in text]
                                for text in (swept, plain))
            assert swept == plain


def test_reproduce_through_the_scheduler_gives_the_local_report(cluster, tmp_path, capsys):
    from test_reproduce import _tables
    small = ['--episodes', '300', '--episodes-greedy', '12', '--episodes-planner', '12',
             '--bootstrap', '50', '--no-cache', '--quiet']
    _run(['reproduce', '--out', str(tmp_path / 'here'), '--jobs', '1', *small], capsys)
    assert cli_main(['reproduce', '--out', str(tmp_path / 'dask'), '--scheduler',
                     cluster.address, *small]) == 0
    log = capsys.readouterr().err               # the progress log goes to stderr
    assert '2 Dask workers' in log
    assert _tables(tmp_path / 'here' / 'reproduction.md') == \
        _tables(tmp_path / 'dask' / 'reproduction.md')


def test_an_unreachable_scheduler_is_one_line(capsys):
    with socket.socket() as sock:               # a port with nobody listening
        sock.bind(('127.0.0.1', 0))
        port = sock.getsockname()[1]
    for address, reason in ((f'tcp://127.0.0.1:{port}', 'cannot reach the Dask scheduler'),
                            ('tcp://127.0.0.1', 'wants [tcp://]HOST:PORT'),
                            ('tcp://127.0.0.1:8\u00b2', 'wants [tcp://]HOST:PORT')):   # int('²')
        assert cli_main(['evaluate', '--grid', '4x4', '--episodes', '10', '--scheduler',
                         address]) == 2
        err = capsys.readouterr().err
        assert reason in err and err.count('\n') == 1, err


@pytest.mark.parametrize('answer, reason', [
    (None, 'no Dask scheduler answered at'),                 # a port that listens, says nothing
    # What Dask makes of the babble (MemoryError: 'it answered ...') may come after the
    # deadline on a loaded machine (CI, once): then the refusal is the silent port's, one line.
    (b'SSH-2.0-OpenSSH_9.6\r\n' * 64,
     '(it answered what no Dask scheduler sends|no Dask scheduler answered at)'),
])
def test_a_port_that_is_no_scheduler_is_one_line_within_the_timeout(answer, reason):
    server = socket.socket()
    server.bind(('127.0.0.1', 0))
    server.listen(4)
    held = []

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            held.append(conn)
            if answer:
                conn.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    try:
        with pytest.raises(ClusterError, match='TLS expects'):
            DaskExecutor(f'tls://127.0.0.1:{server.getsockname()[1]}', timeout_s=5.0)
        with pytest.raises(ClusterError) as raised:
            DaskExecutor(f'tcp://127.0.0.1:{server.getsockname()[1]}', timeout_s=1.0)
        assert re.search(reason, str(raised.value)) and '\n' not in str(raised.value)
    finally:
        server.close()
        for conn in held:
            conn.close()


def test_a_client_that_failed_to_connect_is_closed_at_once():
    """
    Not left to the garbage collector, whose ``Client.__del__`` could deadlock the next start.

    The collector is off, so a failed client left open is still there to be seen.
    """
    from distributed import Client
    server = socket.socket()
    server.bind(('127.0.0.1', 0))
    server.listen(4)
    before = {id(o) for o in gc.get_objects() if isinstance(o, Client)}
    gc.disable()
    try:
        with pytest.raises(ClusterError, match='TLS expects'):
            DaskExecutor(f'tls://127.0.0.1:{server.getsockname()[1]}', timeout_s=5.0)
        made = [o for o in gc.get_objects() if isinstance(o, Client) and id(o) not in before]
        assert made and wait_for(lambda: all(c.status == 'closed' for c in made), 10.0), \
            [c.status for c in made]
    finally:
        gc.enable()
        server.close()


def test_the_scheduler_comes_from_the_environment(monkeypatch, capsys):
    monkeypatch.setenv('DASK_SCHEDULER_ADDRESS', 'not-an-address')
    assert cli_main(['evaluate', '--grid', '4x4', '--episodes', '10']) == 2
    assert "got 'not-an-address'" in capsys.readouterr().err


def test_workers_running_other_code_are_refused(cluster, monkeypatch):
    executor_module.source_digest.cache_clear()
    monkeypatch.setattr(executor_module, 'source_digest', lambda: '0' * 64)
    with pytest.raises(ClusterError, match='runs another ipomdp_gaze'):
        DaskExecutor(cluster.address)


def _greedy_runner(executor, cache=None):
    runner = pieces.Runner(GRID, FPOC, 480, 3, 20, executor, cache)
    runner.submit('greedy', make_baseline('greedy', GRID, FPOC), horizon=12, chunk=24,
                  recipe=('baseline', 'greedy'))
    return runner


def test_ctrl_c_stops_at_once_and_keeps_the_finished_pieces(tmp_path):
    """SIGINT to the command's process group, as a terminal sends it, after a piece is cached."""
    cache = tmp_path / 'cache'
    proc = subprocess.Popen(
        [sys.executable, str(ROOT / 'bench' / 'simulation' / 'planner_vs_greedy.py'),
         '--episodes', '4000', '--policies', 'greedy', '--horizon', '10', '--chunk', '50',
         '--jobs', '2', '--cache', str(cache), '--quiet'], start_new_session=True,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert wait_for(lambda: any(cache.glob('*.bin')) or proc.poll() is not None, 120)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode != 0 and 'KeyboardInterrupt' in err
    kept = list(cache.glob('*.bin'))
    assert 0 < len(kept) < 80 and not list(cache.glob('*.tmp'))
    # Each kept piece is the one a fresh run computes.
    GRID7, FPOC7 = Grid(7, 7, 0.42), FPOC       # the bench's task
    store = pieces.PieceCache(cache)
    runner = pieces.Runner(GRID7, FPOC7, 4000, 1, 20)
    greedy = make_baseline('greedy', GRID7, FPOC7)
    found = 0
    for start in range(0, 4000, 50):
        key = store.key(('baseline', 'greedy'), GRID7, FPOC7, runner.targets, 10, 1,
                        (start, start + 50))
        if (cache / f'{key}.bin').is_file() and found < 2:
            piece = store.load(key)
            fresh = pieces._simulate_rows(GRID7, runner.model, greedy, runner.targets, 10, 1,
                                          (start, start + 50))
            np.testing.assert_array_equal(piece[0], fresh[0])
            np.testing.assert_array_equal(piece[1], fresh[1])
            found += 1
    assert found > 0


def test_ctrl_c_on_a_cluster_run_cancels_its_pieces(cluster):
    """The command exits at once (status 130) and the scheduler drops every piece of the run."""
    proc = subprocess.Popen(
        [sys.executable, '-m', 'ipomdp_gaze.cli', 'evaluate', '--grid', '5x5', '--policy',
         'greedy', '--episodes', '4000', '--episodes-greedy', '4000', '--scheduler',
         cluster.address],
        start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = proc.stderr.readline()          # the first progress line, after 5 s
        assert first.startswith('evaluate: ') and '16/16' not in first, first
        os.killpg(proc.pid, signal.SIGINT)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130

    def tasks():
        with distributed.Client(cluster.address, timeout=20, set_as_default=False) as client:
            return client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks))
    assert wait_for(lambda: tasks() == 0, 30)


def test_a_worker_killed_mid_run_changes_nothing(cluster, monkeypatch):
    """
    The scheduler runs the dead worker's pieces again elsewhere: the same matrices.

    The run's targets go to the cluster once, shared by the pieces (a threshold of 1 byte makes
    them count as large), so the lost worker may take the only copy with it.
    """
    monkeypatch.setattr(DaskExecutor, 'SHARE_BYTES', 1)
    here = _greedy_runner(None)
    here.collect()
    first_done = threading.Event()
    with DaskExecutor(cluster.address) as executor:
        runner = _greedy_runner(executor)
        futures = runner.pending('greedy')
        for future in futures:
            future.add_done_callback(lambda f: first_done.set())
        assert first_done.wait(120)
        victim = cluster.processes[1]           # worker w1
        victim.kill()
        victim.wait(timeout=20)
        assert not all(f.done() for f in futures)   # pieces were still to run
        runner.collect()
    assert wait_for(lambda: cluster.workers() == 1, 30)
    np.testing.assert_array_equal(runner.correct['greedy'], here.correct['greedy'])
    np.testing.assert_array_equal(runner.map_prob['greedy'], here.map_prob['greedy'])
    assert runner.decisions['greedy'] == here.decisions['greedy']


def _children(pid: int) -> list[int]:
    """Return the child processes of ``pid`` (Linux /proc)."""
    try:
        text = Path(f'/proc/{pid}/task/{pid}/children').read_text()
    except OSError:
        return []
    return [int(p) for p in text.split()]


def _running(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie nobody reaped has ended)."""
    try:
        status = Path(f'/proc/{pid}/status').read_text()
    except OSError:
        return False
    return '\nState:\tZ' not in status


@pytest.mark.parametrize('how, code', [(signal.SIGTERM, 143), (signal.SIGKILL, -9)])
def test_a_killed_run_leaves_no_pool_worker_behind(tmp_path, how, code):
    """QA: kill or a script's timeout left the --jobs workers running, holding its pipes."""
    proc = subprocess.Popen(
        [sys.executable, '-m', 'ipomdp_gaze.cli', 'evaluate', '--grid', '9x9', '--policy',
         'greedy', '--episodes', '20000', '--episodes-greedy', '20000', '--jobs', '2',
         '--quiet', '--json', str(tmp_path / 'out.json')], cwd=ROOT,
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        assert wait_for(lambda: len(_children(proc.pid)) >= 2 or proc.poll() is not None, 120)
        workers = _children(proc.pid)
        time.sleep(1.0)                                 # the pieces are running
        proc.send_signal(how)
        proc.wait(timeout=60)
        assert proc.returncode == code, proc.stderr.read()
        assert wait_for(lambda: not any(_running(w) for w in workers), 30), workers
        assert not (tmp_path / 'out.json').exists()
    finally:
        if proc.poll() is None:
            proc.kill()
