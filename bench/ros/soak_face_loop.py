# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Soak the three-node face loop: a scene camera streaming at 30 Hz, the detector, the controller.

Runs ``scene_camera`` (camera on the pan/tilt head, a held-out test scene, ``rate_hz`` 30),
``foveal_detector`` (``camera`` mode, the shipped ``faces-pan-tilt`` model) and
``gaze_controller`` (``config/faces_camera_*.yaml``, a budget of 40 fixations per search) for
``--minutes``. Each time a search ends (``found`` or ``gave_up``) this process resets the
controller with a new random start cell (a valid parameter change) and the next search starts.
Checked, and reported in ``docs/benchmarks.md`` (section ``soak_face_loop``):

- **memory flat**: each node's resident memory (``/proc/<pid>/statm``, sampled every second),
  the largest of the first third of the run against the largest of the last third;
- **no fixation unanswered**: in every search that ended, each fixation the controller sent
  (re-sends of the same cell counted once) got an applied frame (a belief update); and no
  search stalled (each ended within ``STALL_S``);
- **counters exact**: the detector's ``images_received = processed + rejected + unused`` with
  nothing rejected, the controller's ``received = applied + rejected + skipped``, and no
  callback error in any node.

The exit status is 1 if a check fails. ``make soak`` runs it for 10 minutes::

    .venv/bin/python bench/ros/soak_face_loop.py --minutes 10
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
import sys
import threading
import time

BENCH = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(BENCH.parent), str(BENCH), str(BENCH / 'ros')]

from ipomdp_gaze.commands.common import (check_output_file, nonneg_int,  # noqa: E402
                                         positive_float)
import numpy as np  # noqa: E402

NAME, ORDER = 'soak_face_loop', 90
TITLE = 'Soak: the three-node face loop streaming at 30 Hz'
STALL_S = 60.0
BUDGET = 40
MIB = 2 ** 20
PAGE = os.sysconf('SC_PAGE_SIZE')
GROWTH_LIMIT_MIB = 16.0


def rss(pid: int) -> int:
    """Resident set size of a process in bytes (0 when it is gone)."""
    try:
        with open(f'/proc/{pid}/statm') as f:
            return int(f.read().split()[1]) * PAGE
    except OSError:
        return 0


class Sampler(threading.Thread):
    """Sample the RSS of some processes every ``period_s`` until stopped."""

    def __init__(self, pids: dict, period_s: float = 1.0):
        super().__init__(daemon=True)
        self.pids, self.period_s = pids, period_s
        self.samples = {name: [] for name in pids}
        self.halt = threading.Event()

    def run(self):
        while not self.halt.is_set():
            for name, pid in self.pids.items():
                self.samples[name].append(rss(pid))
            self.halt.wait(self.period_s)


class Events:
    """
    Fixations sent and beliefs applied, as ``(time, kind, value)``; search ends; statuses.

    A reset's belief (uniform, or at one of ``priors``: the controller's ``belief.prior``) is
    not a belief applied.
    """

    def __init__(self, watch, priors=()):
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
        from ipomdp_gaze.harness.watch import is_update, LATCHED
        from ipomdp_gaze.msg_adapters import diagnostics
        from std_msgs.msg import Float32MultiArray, Int32MultiArray
        self.log, self.ends, self.status = [], [], {}
        self.truth = None

        def on_fixation(msg):
            self.log.append((time.monotonic(), 'fixation', tuple(msg.data)))

        def on_belief(msg):
            if is_update(msg, priors):
                self.log.append((time.monotonic(), 'belief', int(np.argmax(msg.data))))

        def on_end(kind):
            def take(msg):
                self.ends.append((time.monotonic(), kind, diagnostics.values_of(msg)))
            return take

        def on_truth(msg):
            self.truth = tuple(msg.data)

        def on_diagnostics(msg):
            for item in msg.status:
                self.status[item.name] = diagnostics.values_of(item)

        node = watch.node
        node.create_subscription(Int32MultiArray, 'fixation', on_fixation, LATCHED)
        node.create_subscription(Float32MultiArray, 'belief', on_belief, 50)
        node.create_subscription(DiagnosticStatus, 'found', on_end('found'), 10)
        node.create_subscription(DiagnosticStatus, 'gave_up', on_end('gave_up'), 10)
        node.create_subscription(Int32MultiArray, 'ground_truth', on_truth, LATCHED)
        node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics, 50)

    def values(self, suffix: str) -> dict:
        """Return the latest status whose name ends with ``suffix``."""
        return next((v for k, v in self.status.items() if k.endswith(suffix)), {})


def unanswered(log: list, ends: list) -> tuple[int, int]:
    """
    Return ``(requests, unanswered)`` over the searches that ended.

    A request is a fixation (re-sends of the same cell merged); each must get one applied frame
    (one belief update) in its search. The controller sends the next fixation before it
    publishes the belief of the frame that answered the last one, so requests and updates are
    matched per search, not one by one: a search is closed by the first fixation after its end.
    """
    requests = missing = seg_requests = seg_updates = 0
    current, ended = None, False
    timeline = sorted(log + [(t, 'end', None) for t, _, _ in ends], key=lambda e: e[0])
    for _, kind, value in timeline:
        if kind == 'end':
            ended = True
        elif kind == 'fixation':
            if ended:
                requests += seg_requests
                missing += max(0, seg_requests - seg_updates)
                seg_requests = seg_updates = 0
                current, ended = None, False
            if value != current:
                seg_requests += 1
                current = value
        else:
            seg_updates += 1
    return requests, missing


def soak(minutes: float, seed: int) -> dict:
    """Run the loop for ``minutes``; return what was measured and checked."""
    from ipomdp_gaze.harness.demo import faces_setup
    from ipomdp_gaze.harness.processes import domain_id_for, isolated_nodes
    from ipomdp_gaze.harness.watch import Watch
    setup = faces_setup(fovea=False, seed=seed)
    args = {name: list(a) for name, a in setup.nodes}
    args['controller'] += ['-p', f'search.max_fixations:={BUDGET}',
                           '-p', 'diagnostics_period_s:=0.5']
    args['detector'] += ['-p', 'diagnostics_period_s:=0.5']
    args['scene_camera'] += ['-p', 'rate_hz:=30.0']
    rng = np.random.default_rng(seed)
    domain = domain_id_for()
    with isolated_nodes(domain, prefix='ipomdp-gaze-soak-') as nodes:
        procs = {name: nodes.start(name, args[name])
                 for name in ('controller', 'detector', 'scene_camera')}
        with Watch(domain, 'soak', nodes) as watch:
            events = Events(watch, setup.priors)
            if not watch.wait_until(lambda: events.ends or len(events.log) > 3, 120):
                raise RuntimeError('the loop did not start')
            sampler = Sampler({n: p.proc.pid for n, p in procs.items()})
            sampler.start()
            t0 = time.monotonic()
            end = t0 + 60.0 * minutes
            searches, stalls, right = 0, 0, 0
            while time.monotonic() < end:
                seen = len(events.ends)
                if not watch.wait_until(lambda: len(events.ends) > seen,
                                        min(STALL_S, max(0.1, end - time.monotonic()))):
                    if time.monotonic() < end:
                        stalls += 1
                    else:
                        break
                else:
                    searches += 1
                    _, kind, values = events.ends[-1]
                    if kind == 'found' and events.truth is not None:
                        right += (int(values['row']), int(values['col'])) == events.truth
                start = [int(x) for x in rng.integers(0, setup.grid.rows, 2)]
                watch.set_parameters('gaze_controller', {'start_row': start[0],
                                                         'start_col': start[1]})
                watch.reset()
            seconds = time.monotonic() - t0
            sampler.halt.set()
            sampler.join(5)
            time.sleep(1.5)                         # three more statuses of each node
            detector = events.values('foveal_detector: detector')
            controller = events.values('gaze_controller: search')
            guards = {k: v.get('callback_errors', '?') for k, v in events.status.items()
                      if k.endswith(': callbacks')}
            guards['foveal_detector'] = detector.get('callback_errors', '?')
            log, ends = list(events.log), list(events.ends)
            found = sum(kind == 'found' for _, kind, _ in ends)
        codes = {p.name: code for p, code in nodes.stop()}
    requests, missing = unanswered(log, ends)
    return {'seconds': seconds, 'searches': searches, 'found': found, 'right': right,
            'stalls': stalls, 'requests': requests, 'unanswered': missing,
            'samples': sampler.samples, 'detector': detector, 'controller': controller,
            'guards': guards, 'codes': codes}


def report(r: dict) -> tuple[str, bool]:
    """Markdown of the run and whether every check passed."""
    d, c = r['detector'], r['controller']
    keys = ('images_received', 'images_processed', 'images_rejected', 'images_unused')
    di = {k: int(d.get(k, -1)) for k in keys}
    ci = {k: int(c.get(f'frames_{k}', -1)) for k in ('received', 'applied', 'rejected',
                                                     'skipped', 'dropped')}
    rows, ok = [], True
    for name, samples in r['samples'].items():
        third = max(1, len(samples) // 3)
        early, late = max(samples[:third]) / MIB, max(samples[-third:]) / MIB
        flat = late - early <= GROWTH_LIMIT_MIB
        ok &= flat
        rows.append(f'| {name} | {early:.1f} | {late:.1f} | {max(samples) / MIB:.1f} | '
                    f"{'yes' if flat else 'NO'} |")
    det_exact = di['images_received'] == di['images_processed'] + di['images_rejected'] + \
        di['images_unused'] and di['images_rejected'] == 0
    ctl_exact = ci['received'] == ci['applied'] + ci['rejected'] + ci['skipped']
    guards_ok = all(v == '0' for v in r['guards'].values())
    answered = r['unanswered'] == 0 and r['stalls'] == 0
    exits = all(code == 0 for code in r['codes'].values())
    ok &= det_exact and ctl_exact and guards_ok and answered and exits and r['searches'] > 0
    lines = [
        f"{r['seconds'] / 60:.1f} minutes: {r['searches']} searches ({r['found']} found, "
        f"{r['right']} of them on the ground-truth cell; budget {BUDGET} fixations), "
        f"{r['stalls']} stalled (no end within {STALL_S:.0f} s). In the searches that ended "
        f"the controller sent {r['requests']} fixations (re-sends of a cell merged); "
        f"{r['unanswered']} were left without an applied frame.", '',
        '| node | RSS MiB, max of first third | max of last third | peak | flat (<= '
        f'{GROWTH_LIMIT_MIB:.0f} MiB growth) |', '|---|---|---|---|---|', *rows, '',
        f"Detector: images received {di['images_received']} = processed "
        f"{di['images_processed']} + rejected {di['images_rejected']} + unused "
        f"{di['images_unused']}: {'exact' if det_exact else 'NOT EXACT'}; fixations "
        f"{d.get('fixations_received')}, median detector time {d.get('detector_ms_median')} ms.",
        f"Controller: frames received {ci['received']} = applied {ci['applied']} + rejected "
        f"{ci['rejected']} + skipped {ci['skipped']} (dropped {ci['dropped']}): "
        f"{'exact' if ctl_exact else 'NOT EXACT'}; pan_tilt re-sends "
        f"{c.get('pan_tilt_resends')}.",
        f"Callback errors: {r['guards']}. Exit statuses after SIGTERM: {r['codes']}.", '',
        f"**{'All checks passed.' if ok else 'A CHECK FAILED.'}**", '',
        "The scene camera's growth is its cache of rendered views (one 320x240 RGB view per "
        'head cell, at most 121, 27.9 MB), filled as searches visit new cells.',
    ]
    return '\n'.join(lines) + '\n', ok


def write_section(body: str, out: Path) -> None:
    """Put the section into the benchmark report, keeping the other sections."""
    import run
    sections, titles, order = run.previous(out)
    sections[NAME] = body + f'\n*Measured {run.machine()}.*\n'
    titles[NAME], order[NAME] = TITLE, ORDER
    out.write_text(run.compose(sections, order, titles))


def main(argv=None) -> int:
    """Run the soak and write its section."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--minutes', type=positive_float, default=10.0)
    parser.add_argument('--seed', type=nonneg_int, default=0, help='test scene and start cells')
    parser.add_argument('--out', type=Path, default=BENCH.parent / 'docs' / 'benchmarks.md')
    parser.add_argument('--no-write', action='store_true', help='print only')
    args = parser.parse_args(argv)
    if not args.no_write:
        try:
            check_output_file('--out', args.out)
        except ValueError as exc:
            parser.error(str(exc))
    result = soak(args.minutes, args.seed)
    body, ok = report(result)
    print(body)
    if not args.no_write:
        write_section(body, args.out)
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
