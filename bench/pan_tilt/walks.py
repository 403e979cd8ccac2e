# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
People who move: the tracker against track-last-detection on held-out walks; writes docs/walks.md.

One run per speed, every searcher on the same walk scenes and the same clock
(:mod:`ipomdp_gaze.drivers.tracking`): the tracker of ``config/faces_camera_tracking.yaml`` (the
search session with a walking target, its motion calibrated on training walks) and the baseline
a team would write (centre the last grouped detection, sweep again after three views without
one). Scores over the frames where the face is in the grid's reach: the face inside the view,
inside the head's own cell (the view's centre cell); the time to the first right answer; the
time from the face's return into reach to the first right answer after it.

Regenerate with ``make walks`` (``python bench/pan_tilt/walks.py [--scenes 50] [--speeds 5,15]``;
about 20 minutes per speed on two idle cores); ``--from-json`` rewrites the page from the last
run's record, and ``--cli-json A.json B.json`` builds the record from ``ipomdp-gaze evaluate
--scenes pan-tilt --motion walk --json`` runs instead of searching.
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
import json
import math
from pathlib import Path
import sys
import time

from ipomdp_gaze.commands.common import (check_output_file, nonneg_int, positive_float,
                                         positive_int)
from ipomdp_gaze.drivers.tracking import (evaluate_walks, summarise_walks, walk_spec,
                                          WalkResult, walks_json)
from ipomdp_gaze.simulation.progress import Progress
from ipomdp_gaze.vision.walks import calibrate_motion, check_speed

ROOT = Path(__file__).resolve().parents[2]
BASELINE = 'track-last-detection'


def speeds_arg(text: str) -> list[float]:
    """Parse ``--speeds``: comma-separated walking speeds in deg/s."""
    try:
        return [check_speed(float(v)) for v in text.split(',')]
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f'expected walking speeds in deg/s such as 5,15 '
                                         f'({exc})') from None


def run(args) -> dict:
    """Run every speed on the test walks; return the JSON record."""
    record = {'started': time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime()), 'runs': []}
    for speed in args.speeds:
        spec = walk_spec(speed, 'test', args.seed, args.duration_s)
        with ProcessPoolExecutor(max_workers=args.processes) as pool, \
                Progress(args.scenes, f'walks at {speed:g} deg/s', 'walk') as bar:
            results = evaluate_walks(spec, args.scenes, pool, progress=bar)
        summary = {name: summarise_walks(group, results.get(BASELINE))
                   for name, group in results.items()}
        record['runs'].append(walks_json(spec, results, summary))
    record['finished'] = time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime())
    return record


def from_cli(paths) -> dict:
    """Return a record built from ``evaluate --motion walk --json`` files."""
    runs = [json.loads(Path(p).read_text()) for p in paths]
    return {'started': 'see the runs', 'finished': 'see the runs', 'runs': runs}


def _results(run: dict) -> dict:
    def result(name, r):
        return WalkResult(searcher=name, frames=(),
                          **{k: v for k, v in r.items() if k != 'searcher'})
    return {name: [result(name, r) for r in group] for name, group in run['scenes'].items()}


def _fmt(value, digits=3) -> str:
    return '-' if value is None or (isinstance(value, float) and math.isnan(value)) \
        else f'{value:.{digits}f}'


def _diff(value) -> str:
    return '-' if not value else f'{value[0]:+.3f} [{value[1]:+.3f}, {value[2]:+.3f}]'


def _table(run: dict) -> list[str]:
    results = _results(run)
    summary = {name: summarise_walks(group, results.get(BASELINE))
               for name, group in results.items()}
    lines = ['| searcher | in view | in the centre cell | first find (found) | reacquire '
             '(reacquired / returns) | lost per walk |', '|---|---|---|---|---|---|']
    for name, s in summary.items():
        lines.append(f"| `{name}` | {_fmt(s['in_view'])} | {_fmt(s['in_centre'])} | "
                     f"{_fmt(s['first_find_s_mean'], 2)} s ({s['found']}/{s['scenes']}) | "
                     f"{_fmt(s['reacquire_s_mean'], 2)} s ({s['reacquired']}/{s['returns']}) | "
                     f"{_fmt(s['lost_mean'], 2)} |")
    track = summary.get('track', {})
    diffs = [_diff(track.get(f'{key}_minus_reference'))
             for key in ('in_view', 'in_centre', 'reacquire_s')]
    lines += ['', f'Paired differences, `track` minus `{BASELINE}` [95% interval, normal '
                  f'approximation over walks]: in view {diffs[0]}; in the centre cell '
                  f'{diffs[1]}; reacquire (s) {diffs[2]}.']
    return lines


def write_page(record: dict, out: Path, calibration: dict) -> None:
    """Write docs/walks.md from a run's record."""
    lines = ['# People who move: tracking on the pan/tilt head', '',
             '<!-- Generated by bench/pan_tilt/walks.py (`make walks`); do not edit by hand. -->',
             '', (__doc__ or '').split('\n\n')[1].replace('\n', ' '), '',
             'Test split only (test faces and backgrounds; every setting was chosen on training '
             'walks). The model of the walks, the belief and the session: docs/design.md '
             'section 12.', '',
             '## The motion, calibrated on 200 training walks', '',
             '| quantity | value |', '|---|---|']
    lines += [f'| `{k}` | {v:.4g} |' for k, v in calibration.items()]
    for run in record['runs']:
        n = len(next(iter(run['scenes'].values())))
        lines += ['', f"## {run['speed_deg_s']:g} deg/s, {n} {run['split']} walks of "
                      f"{run['duration_s']:g} s (seeds {run['seed']}..{run['seed'] + n - 1})",
                  '', f"Tracker settings: `{json.dumps(run['settings'])}`, search policy "
                      f"`{run['policy']}`.", '']
        lines += _table(run)
    out.write_text('\n'.join(lines) + '\n')


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--scenes', type=positive_int, default=50, help='test walks per speed')
    p.add_argument('--speeds', type=speeds_arg, default='5,15',
                   help='walking speeds, deg/s (comma-separated)')
    p.add_argument('--duration-s', type=positive_float, default=30.0)
    p.add_argument('--seed', type=nonneg_int, default=0)
    p.add_argument('--processes', type=positive_int, default=2)
    p.add_argument('--json', type=Path, default=ROOT / 'docs' / 'data' / 'walks.json')
    p.add_argument('--out', type=Path, default=ROOT / 'docs' / 'walks.md')
    p.add_argument('--from-json', action='store_true',
                   help='write the page from --json without searching')
    p.add_argument('--cli-json', nargs='+', type=Path, default=None, metavar='JSON',
                   help='build the record from evaluate --motion walk --json files')
    args = p.parse_args(argv)
    try:
        for speed in args.speeds:
            walk_spec(speed, 'test', args.seed, args.duration_s)
        check_output_file('--out', args.out)
        if not args.from_json:
            check_output_file('--json', args.json)
    except ValueError as exc:
        p.error(str(exc))
    if args.from_json:
        record = json.loads(args.json.read_text())
    else:
        record = from_cli(args.cli_json) if args.cli_json else run(args)
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(record) + '\n')
    fit = calibrate_motion('train', scenes=200)
    calibration = {k: fit[k] for k in ('velocity_sigma_cells', 'max_speed_cells', 'speed_cells',
                                       'turn_prob', 'return_prob', 'leave_prob', 'sigma_cells')}
    write_page(record, args.out, calibration)
    print(f'wrote {args.out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
