# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Scaling of the 7x7 ideal-searcher evaluation over workers (docs/benchmarks.md, docs/cluster.md).

Run: ``.venv/bin/python bench/simulation/bench_cluster.py [--episodes-greedy 1000] [--workers
1,2]``;
``bench/run.py --only cluster`` writes its section of docs/benchmarks.md.
The job is ``ipomdp-gaze evaluate --grid 7x7 --policy greedy`` (horizon N = 49), whose
``--episodes-greedy`` episodes go out in pieces of 250. It runs
(a) unsplit in this process (no pieces), (b) in pieces in this process, the same pieces
(c) on a local pool of 2 processes and (d) on a Dask cluster (a scheduler and N single-threaded
workers that this script starts on this machine), checks that every run gives the same JSON
bit for bit, and prints wall time, CPU time of every process, and the CPU-time speed-up: the
pieced run's CPU over the busiest worker's CPU plus the client's (the wall time the run would
take on otherwise idle cores). The machine is shared, so wall times move with its load; CPU
times do not.
"""
import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

from ipomdp_gaze.commands.common import positive_int
from ipomdp_gaze.commands.evaluate import evaluate
from ipomdp_gaze.drivers.pieces import COSTLY_CHUNK
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.simulation.executor import DaskExecutor, InlineExecutor, LocalExecutor

GRID, FPOC = Grid(7, 7, 0.42), make_fpoc('human')
TICK = os.sysconf('SC_CLK_TCK')
# Dask's statistical profiler samples every worker thread every 10 ms: off, as docs/cluster.md
# advises for CPU-bound pieces.
QUIET_WORKER = {'DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED': 'False'}


def cpu_of(pid: int) -> float:
    """Return the user + system CPU seconds of a process so far (from /proc)."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def job(executor, episodes_greedy, chunk=True):
    """Run the evaluation; return its JSON text and this process's CPU seconds."""
    policies = {'greedy': make_baseline('greedy', GRID, FPOC)}
    if not chunk:                       # one unsplit piece: a policy the runner does not split
        policies['greedy'].costly = False
    start = time.process_time()
    result = evaluate(GRID, FPOC, policies, episodes_greedy, None, 0, episodes_greedy,
                      bootstrap=200, executor=executor)
    result['policies']['greedy'].pop('episodes')
    return json.dumps(result, sort_keys=True), time.process_time() - start


def dask_cluster(workers: int, folder: Path):
    """Start a scheduler and ``workers`` single-threaded workers; return (address, processes)."""
    state = folder / f'scheduler-{workers}.json'
    procs = [subprocess.Popen([sys.executable, '-m', 'distributed.cli.dask_scheduler',
                               '--host', '127.0.0.1', '--port', '0', '--no-dashboard',
                               '--scheduler-file', str(state)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    while not (state.is_file() and state.stat().st_size):
        time.sleep(0.1)
    address = json.loads(state.read_text())['address']
    for i in range(workers):
        procs.append(subprocess.Popen(
            [sys.executable, '-m', 'distributed.cli.dask_worker', address, '--nthreads', '1',
             '--no-nanny', '--no-dashboard', '--memory-limit', '0', '--host', '127.0.0.1'],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            env={**os.environ, 'OMP_NUM_THREADS': '1', **QUIET_WORKER}))
    import distributed
    with distributed.Client(address, timeout=30, set_as_default=False) as client:
        client.wait_for_workers(workers, timeout=120)
    return address, procs


def stop(procs) -> None:
    """Stop the workers, then the scheduler (a worker without one retries for a long time)."""
    from ipomdp_gaze.harness.processes import stop_processes
    stop_processes(procs)


TITLE = 'Cluster: the 7x7 ideal-searcher evaluation over workers'
ORDER = 95


def measure(episodes_greedy: int, workers=(1, 2), log=print) -> list:
    """
    Run the evaluation every way; return rows ``(label, wall, cpu, busiest, client, same)``.

    ``busiest`` is the CPU seconds of the busiest worker plus the client's: the wall time of
    the run on idle cores. ``same`` says whether the JSON equals the first run's, bit for bit.
    """
    n, rows, reference = episodes_greedy, [], []
    pieces = -(-n // COSTLY_CHUNK)

    def record(label, text, wall, cpu, busiest, client):
        reference.append(text)
        row = (label, wall, cpu, busiest, client, text == reference[0])
        rows.append(row)
        log(f'{label:<34} wall {wall:7.1f} s  CPU {cpu:7.1f} s  busiest {busiest:7.1f} s  '
            f'client {client:5.1f} s  same JSON: {row[-1]}')

    for label, chunk in (('this process, unsplit', False),
                         (f'this process, {pieces} piece{"s" * (pieces > 1)}', True)):
        wall = time.perf_counter()
        text, cpu = job(InlineExecutor(), n, chunk)
        record(label, text, time.perf_counter() - wall, cpu, cpu, cpu)
    wall = time.perf_counter()
    with LocalExecutor(2) as executor:
        text, client = job(executor, n)
        wall = time.perf_counter() - wall
        pool_cpu = [cpu_of(pid) for pid in executor._pool._processes]  # forked at 0 s
    record('local pool, 2 processes', text, wall, sum(pool_cpu) + client,
           max(pool_cpu) + client, client)
    for count in workers:
        with tempfile.TemporaryDirectory() as folder:
            address, procs = dask_cluster(count, Path(folder))
            try:
                start = {p.pid: cpu_of(p.pid) for p in procs}
                wall = time.perf_counter()
                with DaskExecutor(address) as executor:
                    text, client = job(executor, n)
                wall = time.perf_counter() - wall
                used = {p.pid: cpu_of(p.pid) - start[p.pid] for p in procs}
            finally:
                stop(procs)
        worker_cpu = [used[p.pid] for p in procs[1:]]
        record(f'Dask, {count} worker{"s" * (count > 1)} (+ scheduler '
               f'{used[procs[0].pid]:.1f} s CPU)', text, wall, sum(worker_cpu) + client,
               max(worker_cpu) + client, client)
    return rows


def table(rows, episodes_greedy: int) -> str:
    """Markdown table of :func:`measure`'s rows with the speed-ups over the pieced run."""
    pieced = rows[1]
    pieces = -(-episodes_greedy // COSTLY_CHUNK)
    lines = [f'`ipomdp-gaze evaluate --grid 7x7 --policy greedy --episodes-greedy '
             f'{episodes_greedy}` (horizon 49, {pieces} piece{"s" * (pieces > 1)} of '
             f'{COSTLY_CHUNK} episodes), '
             'run by `bench/simulation/bench_cluster.py`. Dask workers are single-threaded '
             'processes on this machine, started by the benchmark. *Busiest* is the CPU time of '
             "the busiest worker plus the client's: the run's wall time on otherwise idle cores. "
             'The machine is shared (wall times move with its load), so the CPU-time speed-up '
             '(pieced CPU / busiest) is the honest measure; the wall-time one is shown too.', '',
             '| run | wall s | CPU s (all) | busiest s | speed-up (CPU time) | '
             'speed-up (wall) | same JSON |', '|---|---|---|---|---|---|---|']
    for label, wall, cpu, busiest, client, same in rows:
        lines.append(f'| {label} | {wall:.1f} | {cpu:.1f} | {busiest:.1f} | '
                     f'{pieced[2] / busiest:.2f}x | {pieced[1] / wall:.2f}x | '
                     f"{'yes' if same else 'NO'} |")
    overhead = 100 * (pieced[2] / rows[0][2] - 1)
    lines += ['', f'Piece overhead: {pieces} piece{"s" * (pieces > 1)} cost {overhead:+.1f}% '
              'CPU against the '
              "unsplit run in the same process (each piece draws the whole run's noise and "
              'keeps its own rows); a Dask round trip per piece is milliseconds against '
              f'seconds of work.']
    return '\n'.join(lines) + '\n'


def bench(ctx) -> str:
    """Markdown section for ``bench/run.py`` (``--quick``: 250 episodes, 1 piece)."""
    n = 250 if ctx.quick else 1000
    return table(measure(n, log=ctx.log), n)


def worker_counts(text: str) -> list:
    """Parse ``--workers``: comma-separated Dask worker counts, each a positive integer."""
    try:
        return [positive_int(count) for count in text.split(',')]
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(
            f'expected positive integers separated by commas, got {text!r}') from None


def main(argv=None):
    """Run every way and print the log, then the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--episodes-greedy', type=positive_int, default=1000)
    parser.add_argument('--workers', type=worker_counts, default='1,2',
                        help='Dask worker counts to run, comma-separated (default 1,2)')
    args = parser.parse_args(argv)
    rows = measure(args.episodes_greedy, args.workers, lambda text: print(text, flush=True))
    print()
    print(table(rows, args.episodes_greedy))


if __name__ == '__main__':
    main()
