# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze evaluate``: fixations to 90% correct for baselines and policy files.

Beyond the paper (docs/design.md section 7) it simulates moving targets
(``--motion-sigma-cells``, ``--jump-prob``; per fixation), empty scenes at ``--absent-rate``
searched with the model's ``--absent-prior``, and the stopping rules at ``--confidence`` with a
``--max-fixations`` budget; every policy then also gets its decision rates and, for a moving
target, its first lock and tracking accuracy (``--compare-prediction`` adds each policy without
the prediction step and the paired difference).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
import sys

from ipomdp_gaze.drivers.pieces import concat_results, COSTLY_CHUNK, PLANNER_CHUNK, simulate_pieces
from ipomdp_gaze.drivers.rooms import format_rooms, room_settings, summarise_rooms
from ipomdp_gaze.drivers.scene_eval import evaluate_scenes
from ipomdp_gaze.drivers.scene_report import (format_summary, paired_map_difference, results_json,
                                              summarise, write_json)
from ipomdp_gaze.drivers.scene_tasks import (DEFAULT_BUDGET, MODEL_GROUPS, ROOM_BUDGET,
                                             task_spec, TASKS)
from ipomdp_gaze.drivers.tracking import (evaluate_walks, format_walks, summarise_walks,
                                          walk_spec, walks_json)
from ipomdp_gaze.files.observation_file import fingerprint
from ipomdp_gaze.model.motion import Motion
from ipomdp_gaze.model.observation import as_observation, GaussianObservation
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.policies.policy_file import check_training_prior, load_policy_spec
from ipomdp_gaze.policies.registry import build_policy, NAMED_POLICIES
from ipomdp_gaze.search.session import SearchSettings
from ipomdp_gaze.simulation.evaluation import (decision_summary, fixations_to_90_ci,
                                               paired_difference_ci, paired_tracking_difference,
                                               prior_chance, tracking_summary)
from ipomdp_gaze.simulation.executor import InlineExecutor
from ipomdp_gaze.simulation.simulate import check_prior, draw_present, draw_targets
from ipomdp_gaze.vision.pan_tilt import parse_faces
from ipomdp_gaze.vision.walks import DURATION_S as WALK_DURATION_S
from ipomdp_gaze.vision.walks import SPEED_DEG_S as WALK_SPEED_DEG_S
import numpy as np

from .common import (add_prior_arg, add_task_args, bootstrap_count, C_INT_MAX,
                     check_output_file, count_in, MAX_EPISODES, MAX_SCENES, nonneg_int,
                     number_arg, output_file, positive_int, read_prior, task_from_args)
from .running import add_run_args, executor_from_args, progress_from_args
from .search_args import add_scene_args, add_search_args, settings_from_args

NO_PREDICTION = ' (no prediction)'
# --episodes when not given: simulated episodes, scenes of --scenes, walks of --motion walk.
EPISODES, SCENE_EPISODES, WALK_EPISODES = 20000, 200, 100
EMPTY_SCENES = count_in(0, MAX_SCENES, f'a number of scenes from 0 to {MAX_SCENES}')
# detectMultiScale's minNeighbors, an OpenCV int
GROUP_MIN_NEIGHBORS = count_in(0, C_INT_MAX, "an integer from 0 to 2^31 - 1 (OpenCV's int)")


def add_parser(sub):
    p = sub.add_parser('evaluate', help='measure fixations to 90%% correct of policies',
                       description='Simulate searches with common random numbers across '
                                   'policies; print a table and optionally write JSON.')
    add_task_args(p)
    p.add_argument('--policy', action='append', default=[], choices=NAMED_POLICIES,
                   help='a baseline by name (repeatable; default map when no --policy-file is '
                        'given)')
    p.add_argument('--policy-file', action='append', default=[], type=Path, metavar='PATH',
                   help='a policy YAML file, keyed by its file stem (repeatable)')
    p.add_argument('--episodes', type=positive_int, default=None,
                   help=f'simulated episodes (default {EPISODES}), or scenes with --scenes '
                        f'(default {SCENE_EPISODES}; walks with --motion walk: {WALK_EPISODES})')
    p.add_argument('--scenes', default=None, choices=TASKS,
                   help='evaluate an image task on held-out scenes through the real detector '
                        'and sensor (the search session of the nodes and find) instead of '
                        'simulating: pan-tilt (config/faces_camera_controller.yaml), faces-420 '
                        "or faces-840 (find's settings); --policy, --policy-file, "
                        '--confidence, --max-fixations (default: the configuration budget, '
                        f'else {DEFAULT_BUDGET}; rooms of --faces: {ROOM_BUDGET}) and '
                        '--absent-prior change the shipped configuration')
    p.add_argument('--split', choices=('train', 'test'), default=None,
                   help='--scenes: training scenes (for every choice) or held-out test scenes '
                        '(default)')
    p.add_argument('--empty-scenes', type=EMPTY_SCENES, default=None, metavar='M',
                   help='--scenes pan-tilt: also M scenes without a face (the same photo crops), '
                        'reported apart per background')
    p.add_argument('--faces', default='1', metavar='K|LO-HI',
                   help='--scenes pan-tilt: rooms of K faces, or LO..HI drawn uniformly per '
                        'scene (0-8; default 1: the one-face scenes), searched by the '
                        'many-target session and scored by faces found, false faces, rooms '
                        'right and head time; --compare then takes many:parameter=value,... '
                        'and sweep-all-grouped3 / sweep-all-grouped5')
    p.add_argument('--motion', choices=('still', 'walk'), default='still',
                   help='--scenes pan-tilt: still faces (default) or faces that walk (the '
                        'tracker of config/faces_camera_tracking.yaml against '
                        'track-last-detection on the same walks, docs/design.md section 12)')
    p.add_argument('--speed-deg-s', type=number_arg, default=None, metavar='V',
                   help='--motion walk: walking speed in degrees per second, 0-20 (default '
                        f'{WALK_SPEED_DEG_S:g})')
    p.add_argument('--walk-duration-s', type=number_arg, default=None, metavar='S',
                   help=f'--motion walk: seconds per walk, 1-3600 (default '
                        f'{WALK_DURATION_S:g})')
    p.add_argument('--scene-model', default='', metavar='FILE',
                   help='--scenes pan-tilt: another pan/tilt observation file (its camera is the '
                        "scene camera's; with --motion walk, the tracker's instead of its "
                        "configuration's observation.file)")
    p.add_argument('--group-min-neighbors', type=GROUP_MIN_NEIGHBORS, default=None, metavar='N',
                   help="--scenes pan-tilt, one face: the grouping (detectMultiScale's "
                        'min_neighbors) the views report for search.group_stop, as the '
                        "detector node's publish_groups (default: the model's, config/"
                        "faces_camera_detector.yaml's for the shipped one, "
                        + ''.join(f'{n} for {m}, ' for m, n in MODEL_GROUPS.items())
                        + 'else none; 0: none)')
    p.add_argument('--compare', action='append', default=[], metavar='SEARCHER',
                   help='--scenes: another searcher on the same scenes and views (repeatable): '
                        'a policy name (sweep starts at its first pose) or a sweep answer rule '
                        '(sweep-tile, sweep-first-raw, sweep-first-grouped3, '
                        'sweep-first-grouped5); with --motion walk track-last-detection '
                        '(default; :neighbors=N,lost_frames=M)')
    add_prior_arg(p, 'the targets are drawn from it and every belief starts at it')
    p.add_argument('--episodes-greedy', type=positive_int, default=2000,
                   help='episodes for the slow searchers, greedy and switching (policies '
                        'whose class sets costly; default 2000)')
    p.add_argument('--horizon', type=positive_int, default=None,
                   help="fixations per episode (default N, the paper's T)")
    p.add_argument('--seed', type=nonneg_int, default=0)
    p.add_argument('--bootstrap', type=bootstrap_count, default=1000,
                   help='bootstrap resamples for the 95%% interval (at least 10; default 1000)')
    p.add_argument('--paired', action='store_true',
                   help='also give each policy minus the first, on the same episodes, with a '
                        'paired bootstrap 95%% interval')
    add_scene_args(p, 'simulated')
    add_search_args(p, None, ('confidence',), task_default='0.95')
    add_search_args(p, None, ('max_fixations',),
                    task_default='and 0: the horizon; also the horizon when --horizon is not '
                                 'given')
    p.add_argument('--compare-prediction', action='store_true',
                   help='moving target: also run each policy without the prediction step and '
                        'report the paired difference in tracking accuracy')
    p.add_argument('--json', type=output_file, default=None, metavar='OUT',
                   help='write results here')
    add_run_args(p)
    p.set_defaults(run=run)


def load_policies(args, grid, fpoc, prior=None) -> dict:
    """
    Name -> policy for every ``--policy`` and ``--policy-file`` (a file's row: its stem).

    Two rows of one name are refused (ValueError naming both), so that no row replaces another.
    ``prior`` (N,), the ``--prior`` read: a policy file trained on another prior is said.
    """
    names = args.policy or ([] if args.policy_file else ['map'])
    rows = [(name, f'--policy {name}', {}) for name in names]
    rows += [(path.stem, f'--policy-file {path}', {'file': str(path)})
             for path in args.policy_file]
    given = {}
    for name, source, _ in rows:
        if source == given.get(name):
            raise ValueError(f'{source} is given twice: each row once')
        if name in given:
            raise ValueError(f"{source}: its row would be named {name!r}, as {given[name]}'s "
                             "(a file's row is named by its stem): give them different names")
        given[name] = source
    # A policy file used off its training scenes is said, as off its FPOC or spacing.
    scene = {'motion_sigma_cells': args.motion_sigma_cells, 'jump_prob': args.motion_jump_prob,
             'absent_prior': args.absent_prior, 'absent_rate': args.absent_rate,
             'prior': None if prior is None else prior.reshape(grid.shape)}
    return {name: build_policy('learned', grid, fpoc, **file, scene=scene) if file
            else build_policy(name, grid, fpoc) for name, _, file in rows}


def evaluate(grid, fpoc, policies: dict, episodes: int, horizon, seed: int,
             episodes_greedy: int = 2000, bootstrap: int = 1000, progress=None,
             motion_sigma_cells: float | None = None, jump_prob: float | None = None,
             absent_prior: float | None = None, absent_rate: float | None = None,
             confidence: float | None = None, max_fixations: int | None = None,
             compare_prediction: bool = False, paired: bool = False, executor=None,
             bar=None, prior=None) -> dict:
    """
    Run every policy on the same targets, noise, target paths and empty scenes.

    Returns the JSON-ready result (docs/design.md section 9.2): per policy, fixations to 90%
    correct with its interval and percent correct. A slow searcher (its class sets ``costly``,
    as the ideal searcher's does) runs on the first ``episodes_greedy`` episodes only. When any
    option of docs/design.md section 7 is given (not None; the others then take their defaults
    0, 0, 0, 0, 0.95 and the horizon), the result also records all six and each policy gets
    ``decisions`` (:func:`ipomdp_gaze.simulation.evaluation.decision_summary`) and, for a moving
    target,
    ``tracking`` (:func:`ipomdp_gaze.simulation.evaluation.tracking_summary`). Without them the
    result is
    exactly the paper task's. With ``paired``, ``result['paired']`` holds each later policy
    minus the first: the difference of fixations to 90% on their common episodes with a paired
    bootstrap interval. The simulations run on ``executor``
    (:mod:`ipomdp_gaze.simulation.executor`;
    default: here), a slow searcher in pieces of ``COSTLY_CHUNK`` episodes
    (``PLANNER_CHUNK`` for the planner), with the same numbers wherever they run; ``bar``
    (:class:`ipomdp_gaze.simulation.progress.Progress`) counts episodes, ``progress(name, entry)``
    is
    called as each policy's entry is ready. ``prior`` (N,), summing to 1: where the targets
    are a priori (drawn from it, and every belief starts at it; default uniform), recorded in
    the result as ``prior``, rows of cells.
    """
    scene = (motion_sigma_cells, jump_prob, absent_prior, absent_rate, confidence,
             max_fixations)
    extended = compare_prediction or any(v is not None for v in scene)
    motion_sigma_cells, jump_prob, absent_prior, absent_rate = (
        0.0 if v is None else v for v in scene[:4])
    confidence = 0.95 if confidence is None else confidence
    if horizon is None:
        horizon = grid.n_cells if max_fixations is None else max_fixations
    if max_fixations is not None and max_fixations > horizon:
        raise ValueError(f'--max-fixations {max_fixations} is beyond the horizon {horizon}')
    model = as_observation(grid, fpoc)
    motion = Motion(grid, motion_sigma_cells, jump_prob)
    if prior is not None:
        prior = check_prior(prior, grid.n_cells)
    targets = draw_targets(grid.n_cells, episodes, seed, prior)
    present = draw_present(episodes, absent_rate, seed)
    task = ({'fpoc': model.fpoc.to_dict()} if isinstance(model, GaussianObservation)
            else {'observation': {**model.to_dict(), 'sha256': fingerprint(model)}})
    out = {'grid': grid.to_dict(), **task, 'episodes': episodes,
           'horizon': horizon, 'seed': seed}
    chance = prior_chance(prior)    # percent correct at t = 0: 1/N, or the prior's MAP cell's
    if prior is not None:
        out['prior'] = prior.reshape(grid.shape).tolist()
    if extended:
        out.update({'motion_sigma_cells': motion.sigma_cells, 'jump_prob': motion.jump_prob,
                    'absent_prior': float(absent_prior), 'absent_rate': float(absent_rate),
                    'confidence': float(confidence), 'max_fixations': max_fixations})
    out['policies'] = {}
    runs = [(name, policy, True) for name, policy in policies.items()]
    if compare_prediction and motion.active:
        runs += [(name + NO_PREDICTION, policy, False) for name, policy in policies.items()]
    # Every run goes to the executor first (a slow searcher in pieces), then is summarised in
    # order as its pieces come back.
    executor = InlineExecutor() if executor is None else executor
    submitted = []
    for name, policy, predict in runs:
        costly = getattr(policy, 'costly', False)
        n = min(episodes, episodes_greedy) if costly else episodes
        chunk = (PLANNER_CHUNK if getattr(policy, 'name', '') == 'planner' else COSTLY_CHUNK
                 ) if costly else None
        futures = simulate_pieces(executor, grid, model, policy, n, horizon, seed, chunk,
                                  targets=targets[:n], motion=motion, predict=predict,
                                  absent_prior=absent_prior, present=present[:n],
                                  prior=prior, progress=bar)
        submitted.append((name, n, futures))
    results = {}
    for name, n, futures in submitted:
        result = concat_results(f.result() for f in futures)
        results[name] = result
        point, ci = fixations_to_90_ci(result.correct, grid.n_cells,
                                       np.random.default_rng([seed, 99]), bootstrap,
                                       chance=chance)
        entry = out['policies'][name] = {
            'episodes': n, 'fixations_to_90': point, 'ci95': list(ci) if ci else None,
            'percent_correct': [round(float(x), 6) for x in result.percent_correct]}
        if extended:
            entry['decisions'] = decision_summary(result, confidence, max_fixations)
        if motion.active:
            entry['tracking'] = tracking_summary(result, grid.cols,
                                                 np.random.default_rng([seed, 98]), bootstrap)
        if progress:
            progress(name, entry)
    names = list(policies)
    if paired and len(names) > 1:
        out['paired'] = {}
        for name in names[1:]:
            a, z = results[name].correct, results[names[0]].correct
            diff, ci = paired_difference_ci(a, z, grid.n_cells,
                                            np.random.default_rng([seed, 95]), bootstrap,
                                            chance=chance)
            out['paired'][f'{name} - {names[0]}'] = {
                'episodes': int(min(a.shape[0], z.shape[0])),
                'difference': diff, 'ci95': list(ci) if ci else None}
    if motion.active and len(names) > 1:
        out['tracking_paired'] = {
            name: {'minus': names[0], **paired_tracking_difference(
                results[name], results[names[0]], grid.cols, np.random.default_rng([seed, 96]),
                bootstrap)} for name in names[1:]}
    if compare_prediction and motion.active:
        out['prediction_gain'] = {
            name: paired_tracking_difference(results[name], results[name + NO_PREDICTION],
                                             grid.cols, np.random.default_rng([seed, 97]),
                                             bootstrap) for name in policies}
    return out


def format_table(result: dict) -> str:
    """Format a plain-text table of fixations to 90% correct."""
    lines = [f"{'policy':<24} {'episodes':>8} {'fix->90%':>9} {'95% CI':>17} {'pc@1':>6} "
             f"{'pc@5':>6} {'pc@10':>6}"]
    for name, r in result['policies'].items():
        pc = r['percent_correct']
        f90 = '   never' if r['fixations_to_90'] is None else f"{r['fixations_to_90']:9.2f}"
        ci = '' if r['ci95'] is None else f"[{r['ci95'][0]:.2f}, {r['ci95'][1]:.2f}]"
        at = [f'{pc[t - 1]:6.3f}' if t <= len(pc) else '     -' for t in (1, 5, 10)]
        lines.append(f"{name:<24} {r['episodes']:>8} {f90:>9} {ci:>17} {' '.join(at)}")
    for label, r in result.get('paired', {}).items():
        if r['difference'] is None:
            lines.append(f'{label}: not defined (a policy never reaches 90%)')
            continue
        ci = '' if r['ci95'] is None else f" [{r['ci95'][0]:+.2f}, {r['ci95'][1]:+.2f}]"
        lines.append(f"{label}: {r['difference']:+.2f}{ci} fixations to 90% "
                     f"({r['episodes']} paired episodes)")
    return '\n'.join(lines)


def format_decisions(result: dict) -> str:
    """Format the decision rates (over decided searches) and the tracking accuracy."""
    lines = [f"{'policy':<24} {'decided':>8} {'wrong/dec':>10} {'upper95':>8} {'gave up':>8} "
             f"{'fix->dec':>9} {'track':>7}"]
    for name, r in result['policies'].items():
        d = r['decisions']
        wrong = d['decided']['wrong']
        fix = d['all']['fixations_to_decision']['mean']
        track = r.get('tracking', {}).get('tracking_accuracy', {}).get('value')
        lines.append(
            f"{name:<24} {d['decided']['searches']:>8} "
            f"{'-' if wrong['rate'] is None else format(wrong['rate'], '.4f'):>10} "
            f"{'-' if wrong['ci95'] is None else format(wrong['ci95'][1], '.4f'):>8} "
            f"{d['all']['gave_up']['rate']:>8.4f} "
            f"{'-' if fix is None else format(fix, '.2f'):>9} "
            f"{'-' if track is None else format(track, '.4f'):>7}")
    return '\n'.join(lines)


def check_settings(args) -> SearchSettings:
    """Check the search settings given as flags before any work (the session's messages)."""
    return settings_from_args(args, SearchSettings())


def _scene_episodes(args, default: int, what: str) -> int:
    """
    Return ``--episodes`` of ``--scenes`` (``default`` if not given): at most :data:`MAX_SCENES`.

    A piece of work is queued per scene (or walk): 2^63 - 1 of them filled the memory.
    """
    episodes = args.episodes or default
    if episodes > MAX_SCENES:
        raise ValueError(f'--episodes {episodes}: at most {MAX_SCENES} {what} with --scenes')
    return episodes


def run_scenes(args) -> int:
    """``evaluate --scenes TASK``: held-out scenes through the search session (scene_eval)."""
    if len(args.policy) + len(args.policy_file) > 1:
        raise ValueError('--scenes evaluates one policy at a time (others: --compare)')
    spec = task_spec(args.scenes, args.policy[0] if args.policy else None,
                     str(args.policy_file[0]) if args.policy_file else None, seed=args.seed,
                     max_fixations=args.max_fixations, split=args.split, model=args.scene_model,
                     compare=tuple(args.compare), empty=False, faces=parse_faces(args.faces),
                     group_min_neighbors=args.group_min_neighbors)
    changes = {key: value for key, value in (('confidence', args.confidence),
                                             ('absent_prior', args.absent_prior))
               if value is not None}
    spec = replace(spec, settings=replace(spec.settings, **changes))
    if spec.rooms and (args.policy or args.policy_file):
        raise ValueError('--faces rooms are searched by the many-target session, which chooses '
                         'its views by its own infomax: no --policy or --policy-file (other '
                         'searchers: --compare)')
    if spec.policy_file and not spec.rooms:
        # Every scene starts uniform: a file trained on a prior is said, as without --scenes.
        check_training_prior(load_policy_spec(spec.policy_file), None)
    episodes = _scene_episodes(args, SCENE_EPISODES, 'scenes')
    if args.empty_scenes and args.scenes != 'pan-tilt':
        raise ValueError('--empty-scenes is for --scenes pan-tilt')
    if args.empty_scenes and spec.rooms:
        raise ValueError('--empty-scenes is for one-face scenes: rooms take --faces 0 or a '
                         'range from 0')
    specs = [(spec, episodes)]
    if args.empty_scenes:
        specs.append((replace(spec, empty=True), args.empty_scenes))
    total = sum(n for _, n in specs)
    results = {}
    with executor_from_args(args, total) as executor, \
            progress_from_args(args, total, f'{args.scenes} scenes', 'scene') as bar:
        for one, n in specs:
            for name, group in evaluate_scenes(one, n, executor, progress=bar).items():
                results.setdefault(name, []).extend(group)
    if spec.rooms:
        return _report_rooms(args, spec, results, episodes)
    summary = {name: summarise(group) for name, group in results.items()}
    print(f'{args.scenes}: policy {spec.policy_file or spec.policy}, {args.split} scenes '
          f'{args.seed}..{args.seed + episodes - 1}'
          + (f' (+ {args.empty_scenes} empty)' if args.empty_scenes else '')
          + f', settings {spec.settings.to_parameters()}')
    for name, s in summary.items():
        for line in format_summary(spec, s, name if len(summary) > 1 else ''):
            print(line)
    main = next(iter(results))
    if 'sweep' in results and main != 'sweep':
        # seed 0, as the published comparisons were drawn
        diff = paired_map_difference(results[main], results['sweep'], np.random.default_rng(0))
        if any(lo is None for _, lo, _ in diff.values()):      # one scene: no interval
            print(f'MAP right, {main} minus sweep (one scene with a face: no interval): '
                  + '; '.join(f'{k}: {d:+.3f}' for k, (d, _, _) in diff.items()))
        else:
            print(f'MAP right, {main} minus sweep [paired bootstrap 95%]: '
                  + '; '.join(f'{k}: {d:+.3f} [{lo:+.3f}, {hi:+.3f}]'
                              for k, (d, lo, hi) in diff.items()))
    if args.json:
        _write_json(args.json, results_json(spec, results, summary))
    return 0


def _write_json(path: Path, record: dict) -> None:
    """Write ``--json`` whole or not at all; say so on stderr (stdout holds the results only)."""
    try:
        write_json(path, record)
    except OSError as exc:
        raise ValueError(f'--json {path}: cannot write: {exc.strerror or exc}') from None
    print(f'ipomdp-gaze evaluate: wrote {path}', file=sys.stderr)


def run_walks(args) -> int:
    """``evaluate --scenes pan-tilt --motion walk``: the tracker and the baseline on walks."""
    if args.policy or args.policy_file or args.empty_scenes:
        raise ValueError('--motion walk takes the tracking configuration: no --policy, '
                         '--policy-file or --empty-scenes')
    spec = walk_spec(WALK_SPEED_DEG_S if args.speed_deg_s is None else args.speed_deg_s,
                     args.split, args.seed,
                     WALK_DURATION_S if args.walk_duration_s is None else args.walk_duration_s,
                     tuple(args.compare) or ('track-last-detection',),
                     model=args.scene_model or None)
    changes = {key: value for key, value in (('confidence', args.confidence),
                                             ('absent_prior', args.absent_prior))
               if value is not None}
    spec = replace(spec, settings=replace(spec.settings, **changes))
    episodes = _scene_episodes(args, WALK_EPISODES, 'walks')
    with executor_from_args(args, episodes) as executor, \
            progress_from_args(args, episodes, 'walks', 'walk') as bar:
        results = evaluate_walks(spec, episodes, executor, progress=bar)
    reference = spec.compare[0] if spec.compare else None
    summary = {name: summarise_walks(group, results.get(reference))
               for name, group in results.items()}
    print(f'pan-tilt walks at {spec.speed_deg_s:g} deg/s, {spec.duration_s:g} s each, '
          f'{args.split} scenes {args.seed}..{args.seed + episodes - 1}, tracker policy '
          f'{spec.policy}, settings {spec.settings.to_parameters()}')
    for name, s in summary.items():
        for line in format_walks(name, s, reference if name != reference else ''):
            print(line)
    if args.json:
        _write_json(args.json, walks_json(spec, results, summary))
    return 0


def _report_rooms(args, spec, results: dict, episodes: int) -> int:
    """Print (and write) the room summaries of ``evaluate --scenes pan-tilt --faces``."""
    summary = {name: summarise_rooms(group) for name, group in results.items()}
    lo, hi = spec.faces
    count = f'{lo}' if lo == hi else f'{lo}-{hi}'
    print(f'{args.scenes}: rooms of {counted(count, "face")}, {args.split} scenes {args.seed}..'
          f'{args.seed + episodes - 1}, many-target settings '
          f'{room_settings(spec.settings).to_parameters()}')
    for name, s in summary.items():
        for line in format_rooms(name, s):
            print(line)
    if args.json:
        _write_json(args.json, results_json(spec, results, summary))
    return 0


# Options of the simulated task, which --scenes does not read: (flag, attribute).
SIMULATION_ONLY = (('--grid', 'grid'), ('--spacing-deg', 'spacing_deg'), ('--fpoc', 'fpoc'),
                   ('--fpoc-param', 'fpoc_param'), ('--observation', 'observation'),
                   ('--horizon', 'horizon'), ('--motion-sigma-cells', 'motion_sigma_cells'),
                   ('--jump-prob', 'motion_jump_prob'), ('--absent-rate', 'absent_rate'),
                   ('--compare-prediction', 'compare_prediction'), ('--paired', 'paired'),
                   ('--prior', 'prior'))
# Options of the scene tasks, which the simulated task does not read.
SCENES_ONLY = (('--compare', 'compare'), ('--empty-scenes', 'empty_scenes'), ('--split', 'split'),
               ('--scene-model', 'scene_model'), ('--group-min-neighbors', 'group_min_neighbors'))
# Options of the still pan/tilt scenes, which --motion walk does not read.
STILL_SCENES_ONLY = (('--max-fixations', 'max_fixations'),
                     ('--group-min-neighbors', 'group_min_neighbors'))


def _refuse_unused(args, options, why: str) -> None:
    """Refuse any of ``options`` given on the command line (ValueError naming them and why)."""
    given = [flag for flag, name in options
             if getattr(args, name) not in (None, [], '')
             and getattr(args, name) is not False]       # a 0 is given
    if given:
        raise ValueError(f'{", ".join(given)}: not used here: {why}')


def _pieces(args, policies) -> int:
    """Return how many pieces :func:`evaluate` submits for these arguments."""
    count = 0
    for policy in policies.values():
        if getattr(policy, 'costly', False):
            chunk = PLANNER_CHUNK if getattr(policy, 'name', '') == 'planner' else COSTLY_CHUNK
            count += -(-min(args.episodes, args.episodes_greedy) // chunk)
        else:
            count += 1
    moving = bool(args.motion_sigma_cells) or bool(args.motion_jump_prob)
    return 2 * count if args.compare_prediction and moving else count


def run(args) -> int:
    check_settings(args)
    if args.json is not None:
        if str(args.json) == '-':
            raise ValueError('--json -: evaluate prints its table to stdout; give --json a file')
        check_output_file('--json', args.json)
    faces = parse_faces(args.faces)          # one line for a bad K or LO-HI, before any work
    if faces != (1, 1) and args.scenes != 'pan-tilt':
        raise ValueError('--faces is for --scenes pan-tilt')
    if not args.scenes:
        _refuse_unused(args, SCENES_ONLY, 'only --scenes reads it (the simulated task draws its '
                       'own targets)')
    args.split = args.split or 'test'
    if args.scenes:
        model = ('its model: --scene-model' if args.scenes == 'pan-tilt' else
                 'with its shipped model; another model is tried with find, or on the pan-tilt '
                 'scenes with --scene-model')
        _refuse_unused(args, SIMULATION_ONLY, f'--scenes {args.scenes} runs the real detector on '
                       f'scenes, not the simulated task ({model})')
        if args.scene_model and args.scenes != 'pan-tilt':
            raise ValueError(f'--scene-model is for --scenes pan-tilt; --scenes {args.scenes} '
                             'runs its shipped model')
    if args.motion == 'walk':
        if args.scenes != 'pan-tilt' or faces != (1, 1):
            raise ValueError('--motion walk is for --scenes pan-tilt with one face')
        _refuse_unused(args, STILL_SCENES_ONLY, '--motion walk runs the tracking '
                       "configuration for the walk's duration")
        return run_walks(args)
    for flag, value in (('--speed-deg-s', args.speed_deg_s),
                        ('--walk-duration-s', args.walk_duration_s)):
        if value is not None:
            raise ValueError(f'{flag} goes with --motion walk')
    if args.scenes:
        return run_scenes(args)
    args.episodes = args.episodes or EPISODES
    if args.episodes > MAX_EPISODES:
        raise ValueError(f'--episodes {args.episodes}: at most {MAX_EPISODES} simulated episodes')
    args.max_fixations = args.max_fixations or None           # 0: no budget, the horizon
    grid, fpoc = task_from_args(args)
    prior = None if args.prior is None else read_prior(args.prior, grid)
    policies = load_policies(args, grid, fpoc, prior)
    if args.paired and len(policies) < 2:
        raise ValueError('--paired compares each policy after the first with the first: give '
                         'two or more (--policy, --policy-file)')
    with executor_from_args(args, _pieces(args, policies)) as executor, \
            progress_from_args(args, 0, 'evaluate', 'episode') as bar:
        result = evaluate(grid, fpoc, policies, args.episodes, args.horizon, args.seed,
                          args.episodes_greedy, args.bootstrap,
                          motion_sigma_cells=args.motion_sigma_cells,
                          jump_prob=args.motion_jump_prob,
                          absent_prior=args.absent_prior, absent_rate=args.absent_rate,
                          confidence=args.confidence, max_fixations=args.max_fixations,
                          compare_prediction=args.compare_prediction, paired=args.paired,
                          executor=executor, bar=bar, prior=prior)
    task = (f'count model {args.observation}' if args.observation else
            f'{grid.spacing_deg} deg/cell, FPOC {fpoc.to_dict()}')
    print(f"{grid.rows}x{grid.cols} grid, {task}, horizon {result['horizon']}, seed {args.seed}"
          + ('' if prior is None else f', prior {args.prior}'))
    print(format_table(result))
    if 'confidence' in result:
        print(f"motion sigma {result['motion_sigma_cells']} cells, jump {result['jump_prob']} "
              f"per fixation; absent prior {result['absent_prior']}, rate "
              f"{result['absent_rate']}; confidence {result['confidence']}, budget "
              f"{result['max_fixations'] or result['horizon']}")
        print(format_decisions(result))
    for name, gain in result.get('tracking_paired', {}).items():
        ci = gain['ci95']
        print(f"{name}: tracking accuracy minus {gain['minus']}'s {gain['difference']:+.4f}"
              + (f' [{ci[0]:+.4f}, {ci[1]:+.4f}]' if ci else ''))
    for name, gain in result.get('prediction_gain', {}).items():
        ci = gain['ci95']
        print(f'{name}: tracking accuracy with minus without prediction '
              f"{gain['difference']:+.4f}" + (f' [{ci[0]:+.4f}, {ci[1]:+.4f}]' if ci else ''))
    if args.json:
        _write_json(args.json, result)
    return 0
