# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Helpers of the robustness tests: /proc readings, the controller's diagnostics, parameter calls.

``make soak`` runs the long versions (``pytest -m soak``); ``make test`` runs the short ones.
"""
from __future__ import annotations

from collections import deque
import os
import threading
import time

from conftest import wait_for

CONTROLLER = 'gaze_controller'
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
    """Sample a process's RSS and CPU time in a thread every ``period_s`` until :meth:`stop`."""

    def __init__(self, pid: int, period_s: float = 0.25):
        self.pid, self.period_s = pid, period_s
        self.samples: list[tuple[float, int, float]] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        t0 = time.monotonic()
        while not self._stop.is_set():
            try:
                self.samples.append((time.monotonic() - t0, rss_bytes(self.pid),
                                     cpu_seconds(self.pid)))
            except OSError:
                return
            self._stop.wait(self.period_s)

    def stop(self) -> list[tuple[float, int, float]]:
        """Stop sampling; return ``[(seconds, rss_bytes, cpu_seconds), ...]``."""
        self._stop.set()
        self._thread.join(5)
        return self.samples


class Diagnostics:
    """The latest ``<node>: search`` status of the controller on ``/diagnostics`` (level: int)."""

    def __init__(self, probe, node: str = CONTROLLER):
        from diagnostic_msgs.msg import DiagnosticArray
        self.suffix = f'{node}: search'
        self.values: dict = {}
        self.level = self.message = None
        self.count = 0
        self.history = deque(maxlen=200)
        probe.node.create_subscription(DiagnosticArray, '/diagnostics', self._on_message, 50)

    def _on_message(self, msg):
        for status in msg.status:
            if status.name.endswith(self.suffix):
                self.values = {kv.key: kv.value for kv in status.values}
                level = status.level
                self.level = int.from_bytes(level, 'little') if isinstance(level, bytes) \
                    else int(level)
                self.message = status.message
                self.history.append((self.level, self.message))
                self.count += 1

    def counter(self, name: str) -> int:
        """Return the counter ``frames_<name>`` (-1 before the first status)."""
        return int(self.values.get(f'frames_{name}', -1))

    def counters(self) -> dict:
        """Return the frame counters received, applied, rejected, skipped and dropped."""
        return {k: self.counter(k) for k in ('received', 'applied', 'rejected', 'skipped',
                                             'dropped')}

    def wait_fresh(self, timeout_s: float = 20.0) -> dict:
        """Wait for a status published after this call; return the counters."""
        n = self.count
        assert wait_for(lambda: self.count > n + 1, timeout_s), 'no /diagnostics from the node'
        return self.counters()


class Latest:
    """Keep only the latest message of a topic and how many arrived (no unbounded list)."""

    def __init__(self, probe, msg_type, topic: str, qos=10):
        self.msg = None
        self.count = 0
        probe.node.create_subscription(msg_type, topic, self._on_message, qos)

    def _on_message(self, msg):
        self.msg = msg
        self.count += 1


class Parameters:
    """Persistent SetParameters / GetParameters clients of one node (no discovery per call)."""

    def __init__(self, probe, node: str = CONTROLLER, timeout_s: float = 30.0):
        from rcl_interfaces.srv import GetParameters, SetParameters, SetParametersAtomically
        self.timeout_s = timeout_s
        self._set = probe.node.create_client(SetParameters, f'/{node}/set_parameters')
        self._atomic = probe.node.create_client(SetParametersAtomically,
                                                f'/{node}/set_parameters_atomically')
        self._get = probe.node.create_client(GetParameters, f'/{node}/get_parameters')
        for client in (self._set, self._atomic, self._get):
            assert client.wait_for_service(timeout_sec=timeout_s), f'{node} has no services'

    def _call(self, client, request):
        future = client.call_async(request)
        assert wait_for(future.done, self.timeout_s, 0.001), 'parameter service did not answer'
        return future.result()

    def set_each(self, params: list) -> list:
        """Set ``rclpy.parameter.Parameter`` objects one by one (``ros2 param set``)."""
        from rcl_interfaces.srv import SetParameters
        request = SetParameters.Request(parameters=[p.to_parameter_msg() for p in params])
        return list(self._call(self._set, request).results)

    def set_atomically(self, params: list):
        """Set ``rclpy.parameter.Parameter`` objects all or none; return the result."""
        from rcl_interfaces.srv import SetParametersAtomically
        request = SetParametersAtomically.Request(
            parameters=[p.to_parameter_msg() for p in params])
        return self._call(self._atomic, request).result

    def get(self, names) -> dict:
        """Return ``{name: python value}``."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python
        response = self._call(self._get, GetParameters.Request(names=list(names)))
        return {n: parameter_value_to_python(v) for n, v in zip(names, response.values)}


class Services:
    """Persistent ``~/reset`` and ``~/enable`` clients of the controller."""

    def __init__(self, probe, node: str = CONTROLLER, timeout_s: float = 30.0):
        from std_srvs.srv import SetBool, Trigger
        self.timeout_s = timeout_s
        self._reset = probe.node.create_client(Trigger, f'/{node}/reset')
        self._enable = probe.node.create_client(SetBool, f'/{node}/enable')
        for client in (self._reset, self._enable):
            assert client.wait_for_service(timeout_sec=timeout_s), f'{node} has no services'

    def _call(self, client, request):
        future = client.call_async(request)
        assert wait_for(future.done, self.timeout_s, 0.001), 'service did not answer'
        return future.result()

    def reset(self):
        """Call ``~/reset``; return the response."""
        from std_srvs.srv import Trigger
        return self._call(self._reset, Trigger.Request())

    def enable(self, flag: bool):
        """Call ``~/enable``; return the response."""
        from std_srvs.srv import SetBool
        return self._call(self._enable, SetBool.Request(data=bool(flag)))


def bad_policy_files(folder, grid_rows: int = 11, grid_cols: int = 11, marker=None) -> dict:
    """
    Write policy files that must all be refused; return ``{name: (path, words in the error)}``.

    ``marker`` is a path that a ``!!python/object`` tag would create if the YAML were read with
    an unsafe loader.
    """
    from pathlib import Path

    from ipomdp_gaze.fpoc import make_fpoc
    from ipomdp_gaze.grid import Grid
    import numpy as np
    from ipomdp_gaze.policies.policy_file import PolicySpec, save_policy
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
    out['directory'] = (str(folder), 'not found')
    out['missing'] = (str(folder / 'no-such-policy.yaml'), 'not found')
    return out
