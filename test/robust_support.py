# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Helpers of the robustness tests: /proc readings and policy files that must be refused.

The controller's diagnostics, services and parameters are reached through the ``probe`` fixture
(:class:`ipomdp_gaze.harness.watch.Watch`). ``make soak`` runs the long versions
(``pytest -m soak``); ``make test`` runs the short ones.
"""
from __future__ import annotations

import os
import re
import threading
import time

CLOCK_TICKS = os.sysconf('SC_CLK_TCK')
PAGE_BYTES = os.sysconf('SC_PAGE_SIZE')


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far, from ``/proc/<pid>/stat``."""
    with open(f'/proc/{pid}/stat') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    # Fields after the command name start at field 3 (state); utime and stime are 14 and 15.
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


def rss_bytes(pid: int) -> int:
    """Resident set size of a process, from ``/proc/<pid>/statm``."""
    with open(f'/proc/{pid}/statm') as f:
        return int(f.read().split()[1]) * PAGE_BYTES


def cpu_fraction(pid: int, seconds: float) -> float:
    """Share of one core a process used over the next ``seconds`` (1.0 = one core)."""
    c0, t0 = cpu_seconds(pid), time.monotonic()
    time.sleep(seconds)
    return (cpu_seconds(pid) - c0) / (time.monotonic() - t0)


class RssSampler:
    """
    Sample a process's RSS and CPU time in a thread every ``period_s`` until :meth:`stop`.

    ``count`` (optional) is read with each sample, e.g. the frames the process has taken so far,
    so that a test can compare memory and CPU with the work done rather than with time.
    """

    def __init__(self, pid: int, period_s: float = 0.25, count=None):
        self.pid, self.period_s, self.count = pid, period_s, count or (lambda: 0)
        self.samples: list[tuple[float, int, float, int]] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        t0 = time.monotonic()
        while not self._stop.is_set():
            try:
                self.samples.append((time.monotonic() - t0, rss_bytes(self.pid),
                                     cpu_seconds(self.pid), self.count()))
            except OSError:
                return
            self._stop.wait(self.period_s)

    def stop(self) -> list[tuple[float, int, float, int]]:
        """Stop sampling; return ``[(seconds, rss_bytes, cpu_seconds, count), ...]``."""
        self._stop.set()
        self._thread.join(5)
        return self.samples


def log_times(lines) -> list[float]:
    """Return the times (s) in the `[LEVEL] [seconds.nanoseconds] [node]:` prefix of log lines."""
    return [float(re.search(r'\[(\d+\.\d+)\]', line).group(1)) for line in lines]


def assert_throttled(lines, period_s: float) -> None:
    """
    Check warnings of one call site were throttled to one per ``period_s`` (the node's setting).

    Holds at any machine speed: it compares the warnings' own time stamps, not their number with
    the length of a run. The 0.25 s slack covers the stamp being taken a moment after the
    throttle's own clock reading, on a loaded machine.
    """
    times = log_times(lines)
    gaps = [b - a for a, b in zip(times, times[1:])]
    assert all(gap >= period_s - 0.25 for gap in gaps), (period_s, gaps)


def bad_policy_files(folder, grid_rows: int = 11, grid_cols: int = 11, marker=None) -> dict:
    """
    Write policy files that must all be refused; return ``{name: (path, words in the error)}``.

    ``marker`` is a path that a ``!!python/object`` tag would create if the YAML were read with
    an unsafe loader.
    """
    from pathlib import Path

    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.policies.policy_file import PolicySpec, save_policy
    import numpy as np
    import yaml

    folder = Path(folder)
    grid = Grid(grid_rows, grid_cols, 5.0)
    fpoc = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)
    good = PolicySpec(grid=grid, fpoc=fpoc, reward='infomax', family='conv',
                      kernel=np.zeros(grid.kernel_shape))
    doc = yaml.safe_load(save_policy(folder / 'good.yaml', good).read_text())
    del doc['kernel']
    head = yaml.safe_dump(doc, sort_keys=False)
    rows, cols = grid.kernel_shape
    row = '[' + ', '.join(['0.0'] * cols) + ']'
    bomb = '&a0 [' + ', '.join(['1.0'] * 10) + ']'
    for level in range(1, 9):             # 10^9 numbers in about 300 bytes
        bomb = f'&a{level} [{bomb}, ' + ', '.join([f'*a{level - 1}'] * 9) + ']'
    marker = Path(marker) if marker else folder / 'unsafe-loader-was-used'
    kernel_with = {
        'nan': '[' + ', '.join([row] * (rows - 1) + ['[.nan' + ', 0.0' * (cols - 1) + ']']) + ']',
        'inf': '[' + ', '.join([row] * (rows - 1) + ['[-.inf' + ', 0.0' * (cols - 1) + ']']) + ']',
        'shape': '[' + ', '.join([row] * (rows - 1)) + ']',
        'ragged': '[' + ', '.join([row] * (rows - 1) + ['[0.0]']) + ']',
        'text': '[' + ', '.join([row] * (rows - 1) + ['[big' + ', 0.0' * (cols - 1) + ']']) + ']',
        'bomb': bomb,
        'deep': '[' * 20000 + ']' * 20000,
        'python': '!!python/object/apply:os.system ["touch ' + str(marker) + '"]',
    }
    small = PolicySpec(grid=Grid(3, 3, 5.0), fpoc=fpoc, reward='infomax', family='conv',
                       kernel=np.zeros((5, 5)))
    cases = {
        'not-yaml': ('kernel: [[1.0, 2.0\n  - {: ]', 'not YAML'),
        'binary': (bytes(range(256)) * 4, 'cannot read'),
        'empty': ('', 'mapping'),
        'a-list': ('- 1\n- 2\n', 'mapping'),
        'format': (head.replace('ipomdp_gaze/policy-v1', 'other/v9') + f'kernel: {bomb}\n',
                   'format'),
        'no-kernel': (head, 'kernel'),
        'kernel-nan': (head + f"kernel: {kernel_with['nan']}\n", 'non-finite values in kernel'),
        'kernel-inf': (head + f"kernel: {kernel_with['inf']}\n", 'non-finite values in kernel'),
        'kernel-shape': (head + f"kernel: {kernel_with['shape']}\n", 'kernel has shape'),
        'kernel-ragged': (head + f"kernel: {kernel_with['ragged']}\n", 'kernel'),
        'kernel-text': (head + f"kernel: {kernel_with['text']}\n", 'list of lists of numbers'),
        'alias-bomb': (head + f"kernel: {kernel_with['bomb']}\n", 'more than 2 dimensions'),
        'deep-nesting': (head + f"kernel: {kernel_with['deep']}\n", 'nested too deeply'),
        'python-tag': (f"{kernel_with['python']}\n", 'not YAML'),
        'python-tag-kernel': (head + f"kernel: {kernel_with['python']}\n", 'not YAML'),
        'other-grid': (save_policy(folder / 'small.yaml', small).read_text(),
                       'policy is for a 3x3 grid'),
    }
    out = {}
    for name, (content, words) in cases.items():
        path = folder / f'{name}.yaml'
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content)
        out[name] = (str(path), words)
    out['directory'] = (str(folder), 'is a folder, not a file')
    out['missing'] = (str(folder / 'no-such-policy.yaml'), 'not found')
    return out
