# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Rooms of 0-4 faces on both lenses: every searcher on the same views; writes docs/rooms.md.

One run per lens on held-out rooms (``evaluate --scenes pan-tilt --faces 0-4 --split test``,
:mod:`ipomdp_gaze.drivers.rooms`): ``many`` (the many-target session with the rooms' settings,
infomax per second of head time, budget 20), ``pass-many`` (the same session given the sweep: one
pass of its poses, answering its belief's faces and the grouped detections; ``pass-many-cells``
without the views' boxes), and one pass of the sweep answering every grouped detection
(``min_neighbors`` 5 and 3). Optionally the every-view bounds on the first ``--bound`` rooms
(121 views each: about 15 s per room here). Scores: faces found within
one cell, each face and answer matched once; false faces per room; a room is right when every
face is found and nothing else named, done when the searcher ended by its own rule.

Regenerate with ``make rooms`` (``python bench/pan_tilt/rooms.py [--scenes 300] [--bound N]``;
about 15 minutes per lens at 300 rooms on two idle cores); ``--from-json`` rewrites the page
from the last run's record.
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
import gzip
import json
from pathlib import Path
import sys
import time
from types import SimpleNamespace

from ipomdp_gaze.drivers.rooms import summarise_rooms
from ipomdp_gaze.drivers.scene_eval import evaluate_scenes
from ipomdp_gaze.drivers.scene_report import paired_difference, SceneResult
from ipomdp_gaze.drivers.scene_tasks import task_spec
from ipomdp_gaze.model.head_camera import observed_cells
from ipomdp_gaze.model.head_time import covering_poses, head_time_s, shortest_tour
from ipomdp_gaze.simulation.evaluation import format_interval
from ipomdp_gaze.simulation.progress import Progress
from ipomdp_gaze.vision.detection import build_setup, DEFAULT_MODELS
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
LENSES = (('25 deg', ''), ('40 deg', 'faces-pan-tilt-40-profile'))
# The node's pass going on until every cell is decided (docs/design.md section 11.7; not shipped).
DECIDED = 'pass-many-cells:search.decide_after_pass=true,search.repeat_weight=1.0'
SEARCHERS = ('pass-many', 'pass-many-cells', DECIDED, 'sweep-all-grouped5', 'sweep-all-grouped3')
BOUNDS = ('every-view-grouped5', 'every-view-many')
SWEEP = 'sweep-all-grouped5'          # the grouped sweep a team keeps (no false face on training)
OURS = 'pass-many'
NODE = 'pass-many-cells'              # what the node answers (no boxes)
# The seed of every paired bootstrap on the page, a fresh generator for each (the published
# numbers were drawn so).
BOOTSTRAP_SEED = 0
LABELS = {
    'many': "`many`: infomax per second of head time, budget 20 (the node's search)",
    'pass-many': "`pass-many`: the sweep's pass, the belief's faces and the grouped ones",
    'pass-many-cells': '`pass-many-cells`: the same without the boxes (what the node says)',
    DECIDED: ('`pass-many-cells` with `search.decide_after_pass` and repeat weight 1.0: after '
              'the pass, on until every cell is decided (not shipped)'),
    'sweep-all-grouped5': 'one pass of the sweep, every grouped detection (`min_neighbors` 5)',
    'sweep-all-grouped3': 'one pass of the sweep, every grouped detection (`min_neighbors` 3)',
    'every-view-grouped5': 'bound: every view, every grouped detection (`min_neighbors` 5)',
    'every-view-many': 'bound: every view fed to the belief, every cell on its likelier side',
}


def run(args) -> dict:
    """Search the test rooms with every searcher on both lenses; return the JSON record."""
    record = {'args': {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
              'started': time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime()), 'runs': {}}
    with ProcessPoolExecutor(max_workers=args.processes) as pool:
        for lens, model in LENSES:
            spec = task_spec('pan-tilt', seed=args.seed, split='test', model=model, faces='0-4',
                             compare=SEARCHERS)
            runs = [(spec, args.scenes, 'rooms')]
            if args.bound:
                runs.append((replace(spec, compare=BOUNDS), args.bound, 'bounds'))
            out = {}
            for one, n, what in runs:
                t0 = time.perf_counter()
                with Progress(n, f'{lens} {what}', 'room') as bar:
                    done = evaluate_scenes(one, n, pool, progress=bar)
                print(f'{lens} {what}: {n} rooms in {time.perf_counter() - t0:.0f} s',
                      file=sys.stderr)
                out[what] = {name: [r.__dict__ for r in group] for name, group in done.items()}
            record['runs'][lens] = {'model': model or DEFAULT_MODELS['camera'],
                                    'settings': spec.settings.to_parameters(), **out}
    record['finished'] = time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime())
    return record


def _results(group: dict) -> dict:
    return {name: [SceneResult.from_record(r) for r in rows] for name, rows in group.items()}


def _diff(a, b, key) -> str:
    if key == 'false_faces':                       # answers that found no face, per room
        a, b = ([SimpleNamespace(index=r.index, false_faces=len(r.answers) - r.faces_found)
                 for r in group] for group in (a, b))
    d, low, high = paired_difference(a, b, key, np.random.default_rng(BOOTSTRAP_SEED))
    return f'{d:+.3f} {format_interval(None if low is None else (low, high), "+.3f")}'


def _table(results: dict) -> list[str]:
    lines = ['| searcher | recall | false faces / room | rooms right [Wilson 95%] | done | '
             'done and right | head time (s) | views |', '|---|---|---|---|---|---|---|---|']
    for name, group in results.items():
        s = summarise_rooms(group)
        low, high = s['rooms_right_ci95']
        recall = 'n/a' if s['recall'] is None else f"{s['recall']:.3f}"
        lines.append(f"| {LABELS.get(name, name)} | {recall} ({s['faces_found']} of "
                     f"{s['faces']}) | {s['false_per_scene']:.3f} | {s['rooms_right']:.3f} "
                     f"[{low:.3f}, {high:.3f}] | {s['rooms_done']:.3f} | "
                     f"{s['rooms_done_right']:.3f} | {s['head_time_s_mean']:.2f} | "
                     f"{s['fixations_mean']:.1f} |")
    return lines


def _checks(results: dict, bounds: dict | None, name: str = OURS) -> list[str]:
    ours, sweep = summarise_rooms(results[name]), summarise_rooms(results[SWEEP])
    a, b = results[name], results[SWEEP]
    lines = [f'Paired over the same rooms, `{name}` minus the grouped sweep (`min_neighbors` '
             '5), bootstrap 95%: faces found per room ' + _diff(a, b, 'faces_found')
             + '; false faces per room ' + _diff(a, b, 'false_faces') + '; rooms right '
             + _diff(a, b, 'right') + '; head time ' + _diff(a, b, 'head_time_s')
             + ' s. Against `many`: faces found per room '
             + _diff(a, results['many'], 'faces_found') + '; head time '
             + _diff(a, results['many'], 'head_time_s') + ' s.', '',
             f"Issue 37's rooms items for `{name}` against one pass of the grouped sweep:", '']

    def verdict(ok):
        return 'met' if ok else '**not met**'
    if ours['recall'] is None:
        lines.append('- recall at least its: no faces in these rooms')
    else:
        lines.append(f"- recall at least its: {ours['recall']:.3f} against "
                     f"{sweep['recall']:.3f} ({verdict(ours['recall'] >= sweep['recall'])})")
    lines.append('- false faces per room at most its and at most 0.1: '
                 f"{ours['false_per_scene']:.3f} against {sweep['false_per_scene']:.3f} "
                 f"({verdict(ours['false_per_scene'] <= min(sweep['false_per_scene'], 0.1))})")
    lines.append(f"- mean head time to done at most its: {ours['head_time_s_mean']:.2f} s "
                 f"against {sweep['head_time_s_mean']:.2f} s "
                 f"({verdict(ours['head_time_s_mean'] <= sweep['head_time_s_mean'] + 1e-9)}); "
                 + (f"done {ours['rooms_done']:.3f}, by the pass's end: the belief decides every "
                    if name != DECIDED else f"done {ours['rooms_done']:.3f}, by the belief: it "
                    'decides every ')
                 + f'cell at `confidence` in {_decided(results[name])} of '
                 f'{len(results[name])} rooms')
    if bounds:
        n = len(next(iter(bounds.values())))
        first = [r for r in results[name] if r.index < n]
        found = sum(r.faces_found for r in first)
        for name in BOUNDS:
            bound = sum(r.faces_found for r in bounds[name])
            lines.append(f'- at least 0.95 of the faces the every-view bound finds (first {n} '
                         f'rooms; {LABELS[name]}): {found} of {bound} = '
                         f'{found / bound if bound else float("nan"):.3f} '
                         f'({verdict(bound == 0 or found >= 0.95 * bound)})')
    else:
        lines.append('- at least 0.95 of the faces the every-view bound finds: not run '
                     '(`--bound N`)')
    return lines


def _moonshot(results: dict, model: str) -> list[str]:
    """
    Issue 37's moonshot, report only: head time to done against the sweep's and a perfect detector.

    A perfect detector sees every face in any view that shows its cell and nothing else, so a
    room is done once every cell has been shown: the fewest views that show every cell
    (``covering_poses``), toured in the least saccade time (``shortest_tour``). Knowing where the
    faces are, one view centred on each face, toured the same way, finds everyone (a bound on
    finding, not on done). Both at the run's mean detector time per view.
    """
    setup = build_setup('camera', model)
    grid = setup.model.grid
    shown = np.array([observed_cells(setup.camera, grid, grid.cell(p))
                      for p in range(grid.n_cells)])
    cover = shortest_tour(grid, covering_poses(grid, shown))
    views = [r for group in results.values() for r in group if r.fixations]
    per_view = sum(r.detector_s for r in views) / sum(r.fixations for r in views)
    done_s = head_time_s(grid, cover, np.full(cover.size, per_view))
    oracle = [head_time_s(grid, tour, np.full(tour.size, per_view))
              for tour in (shortest_tour(grid, [grid.index(*f) for f in set(r.face_cells)])
                           for r in results[NODE])]
    node = summarise_rooms(results[NODE])['head_time_s_mean']
    sweep = summarise_rooms(results[SWEEP])['head_time_s_mean']
    return ["The moonshot (issue 37, report only; the detector's mean time per view in this "
            f'run, {per_view:.3f} s):', '',
            f"- rooms done in 80% of the sweep's head time: the node's pass "
            f'({LABELS[NODE].split(":")[0]}) takes {node:.2f} s, {node / sweep:.0%} of the '
            f"sweep's {sweep:.2f} s ({'met' if node <= 0.8 * sweep else '**not met**'})",
            *([f'- rooms decided by the belief (`search.decide_after_pass`): '
               f"{summarise_rooms(results[DECIDED])['head_time_s_mean']:.2f} s, "
               f"{summarise_rooms(results[DECIDED])['head_time_s_mean'] / sweep:.0%} of the "
               "sweep's"] if DECIDED in results else []),
            f'- a perfect detector would call a room done after the fewest views that show '
            f'every cell: {cover.size} views, toured in {done_s:.2f} s (the node: '
            f'{node / done_s:.2f}x that)',
            f'- knowing where the faces are, one view on each: {np.mean(oracle):.2f} s per room '
            'on average (0 for an empty room; finding everyone, not knowing that the room is '
            'done)']


def _decided(group) -> int:
    return sum(r.reason == '' and r.decision in ('found', 'absent') for r in group)


def write_page(record: dict, out: Path) -> None:
    """Write docs/rooms.md from a run's record."""
    lines = ['# Rooms of 0-4 faces: everyone in the room against the grouped sweep', '',
             '<!-- Generated by bench/pan_tilt/rooms.py (`make rooms`); do not edit by hand. -->',
             '', __doc__.strip().split('\n\n')[1].replace('\n', ' '), '',
             'Test split only (test faces and backgrounds; no choice was made on them), rooms '
             f"{record['args']['seed']}.. (room i is `ipomdp-gaze demo --scene faces --faces 0-4 "
             f"--seed i`), one run from {record['started']} to {record['finished']}. Every "
             'choice (the pass, the answer, `min_neighbors` 5) was made on training rooms '
             '(docs/design.md section 11.7). Head time: the head-time model of docs/pan_tilt.md '
             "(the detector's measured time per view, 0.1 s settling, saccades at 120 deg/s).",
             '']
    for lens, run in record['runs'].items():
        results = _results(run['rooms'])
        bounds = _results(run['bounds']) if 'bounds' in run else None
        n = len(results[OURS])
        lines += [f"## {lens} lens (`{run['model']}`), {n} rooms", '', *_table(results), '']
        if bounds:
            lines += [f'Every-view bounds on the first {len(bounds[BOUNDS[0]])} rooms:', '',
                      *_table({k: v for k, v in bounds.items() if k in BOUNDS}), '']
        for name in (OURS, NODE, DECIDED):
            if name in results:                    # a record from before DECIDED has none
                lines += [*_checks(results, bounds, name), '']
        lines += [*_moonshot(results, run['model']), '']
    out.write_text('\n'.join(lines).rstrip() + '\n')


def main(argv=None) -> int:
    """Run (or rewrite from ``--from-json``) and write the page."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--scenes', type=int, default=300)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--bound', type=int, default=0,
                        help='also run the every-view bounds on the first N rooms')
    parser.add_argument('--processes', type=int, default=2)
    parser.add_argument('--json', type=Path, default=ROOT / 'docs' / 'data' / 'rooms.json.gz',
                        help='the record of the run (gzip-compressed when the name ends in .gz)')
    parser.add_argument('--out', type=Path, default=ROOT / 'docs' / 'rooms.md')
    parser.add_argument('--from-json', action='store_true')
    args = parser.parse_args(argv)
    packed = args.json.suffix == '.gz'
    if args.from_json:
        data = args.json.read_bytes()
        record = json.loads(gzip.decompress(data) if packed else data)
    else:
        record = run(args)
        text = (json.dumps(record) + '\n').encode()
        args.json.write_bytes(gzip.compress(text, mtime=0) if packed else text)
    write_page(record, args.out)
    print(f'wrote {args.out}', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
