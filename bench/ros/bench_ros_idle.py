# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
CPU of idle nodes: a controller whose evidence has stopped, and a foveal detector with no images.

Moved here from the fault tests (issue 26: no timing or CPU threshold in a test). The
controller runs the 11x11 task of ``test/test_robust_faults.py`` (re-sending its target every
0.3 s, ``/diagnostics`` every 0.2 s) with no camera at all, so no evidence ever comes; the
detector runs in ``fovea`` mode with no fixation and no image. Each process's user +
system CPU time is read from ``/proc/<pid>/stat`` over the same ``WINDOW_S`` seconds.
"""
import os
import time

from ipomdp_gaze.harness.processes import domain_id_for, isolated_nodes
from ipomdp_gaze.harness.watch import Watch

TITLE = 'Idle nodes: CPU with no evidence and no images'
ORDER = 62
WINDOW_S = 5.0
CONTROLLER = ['-p', 'grid.rows:=11', '-p', 'grid.cols:=11', '-p', 'grid.spacing_deg:=5.0',
              '-p', 'policy.name:=elm', '-p', 'retry_period_s:=0.3', '-p', 'stall_timeout_s:=1.0',
              '-p', 'diagnostics_period_s:=0.2']
CLOCK_TICKS = os.sysconf('SC_CLK_TCK')


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far, from ``/proc/<pid>/stat``."""
    with open(f'/proc/{pid}/stat') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


def bench(ctx) -> str:
    """Start both nodes, let them settle, and measure their CPU over the window."""
    window = 2.0 if ctx.quick else WINDOW_S
    domain = domain_id_for()
    with isolated_nodes(domain, prefix='ipomdp-gaze-bench-') as nodes:
        controller = nodes.start('controller', CONTROLLER)
        detector = nodes.start('detector', ['-p', 'mode:=fovea'])
        with Watch(domain, 'bench_idle', nodes) as watch:
            status = watch.search_status()
            if not watch.wait_until(lambda: status.message and status.message.startswith(
                    'no usable evidence'), 60):
                raise RuntimeError('the controller did not report the stall')
            if not watch.wait_until(lambda: watch.node.count_subscribers('image') > 0, 60):
                raise RuntimeError('the detector did not come up')
            pids = {'controller': controller.proc.pid, 'detector': detector.proc.pid}
            start = {k: cpu_seconds(p) for k, p in pids.items()}
            t0 = time.monotonic()
            watch.wait_until(lambda: False, window)
            elapsed = time.monotonic() - t0
            share = {k: (cpu_seconds(p) - start[k]) / elapsed for k, p in pids.items()}
            message = status.message
        codes = [code for _, code in nodes.stop()]
    return '\n'.join([
        f'Over {elapsed:.1f} s, with the controller\'s diagnostics saying "{message}":', '',
        '| node | CPU, share of one core |', '|---|---|',
        f"| gaze_controller, no evidence (re-sends every 0.3 s) | {share['controller']:.1%} |",
        f"| foveal_detector, fovea mode, no images | {share['detector']:.1%} |", '',
        f'Exit codes {codes}. The fault test used to require under 20% for the controller.',
    ]) + '\n'
