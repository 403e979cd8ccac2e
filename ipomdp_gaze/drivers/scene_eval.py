# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Offline evaluation of the image tasks on held-out scenes (docs/design.md section 10.4).

Each scene goes through the search session, a real sensor and the real detector, as the nodes
and ``find`` run them.

Tasks (:data:`TASKS`):

- ``pan-tilt``: a camera on the pan/tilt head looking around a panorama with one face
  (:class:`ipomdp_gaze.vision.pan_tilt.PanTiltSceneSet`, test split), the shipped
  ``faces-pan-tilt-profile`` model and the settings of ``config/faces_camera_controller.yaml``;
  scene ``seed + i`` is the scene the scene camera shows with parameter ``seed: seed + i`` (scene 0
  of that seed), so ``ipomdp-gaze demo --scene faces --seed S`` and this evaluation search the
  same panorama;
- ``faces-420`` / ``faces-840``: the digital fovea over a still image with a face (the test
  scenes of ``bench/faces.py``, ``SceneSet('test', ..., seed)[i]``) and ``find``'s model,
  kernel and settings.

A scene is *right* when the cell the search answers (its ``found`` cell, or the most likely cell
when it gave up) is within one cell (Chebyshev) of the face centre's cell. Each scene is one piece
of work (:func:`evaluate_scene`), seeded by its index, so the results do not depend on how the
pieces were spread over processes.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import math
from pathlib import Path
import re

from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.files.yaml_files import yaml_parameters
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.search.sensors import run_search
from ipomdp_gaze.search.session import PARAMETER_NAMES, SearchSession, SearchSettings
from ipomdp_gaze.search.settings import check_parameters
from ipomdp_gaze.simulation.evaluation import answer_is_right, wilson_interval
from ipomdp_gaze.simulation.executor import InlineExecutor, track
import numpy as np

TASKS = ('pan-tilt', 'faces-420', 'faces-840')
# The budget every task's searches get unless told otherwise: the ROS bench's (60 fixations).
DEFAULT_BUDGET = 60
# The fixed-camera tasks: model, scene side (px), face sizes (px), as bench/faces.py.
_FOVEA_TASKS = {'faces-420': ('faces-420', 420, (60, 140)),
                'faces-840': ('faces-840', 840, (24, 140))}
# The head-time model of a pan/tilt search (seconds): per view the detector's time plus the
# controller's settle_time_s; per saccade the scene camera's saccade_time_s plus the largest joint
# angle over the joints' speed.
SETTLE_TIME_S = 0.1
SACCADE_TIME_S = 0.15
HEAD_SPEED_DEG_S = 120.0
# The MAP's accuracy is reported after every fixation count 1..MAP_BUDGETS.
MAP_BUDGETS = 20
# The sweep's answer rules, computed from one pass of its poses (the views the sweep policy takes):
# the cell with most raw detections in its own tile; the first view with a raw detection; the
# first view with a detection grouped as OpenCV does with min_neighbors 3 or 5.
SWEEP_RULES = ('sweep-tile', 'sweep-first-raw', 'sweep-first-grouped3', 'sweep-first-grouped5')
# OpenCV's detectMultiScale groups its raw windows with groupRectangles(eps=0.2).
_GROUP_EPS = 0.2


@dataclass(frozen=True)
class TaskSpec:
    """What one task runs with: the model file, the policy, the settings and the scene seed."""

    task: str
    policy: str
    policy_file: str
    settings: SearchSettings
    seed: int
    split: str = 'test'
    empty: bool = False
    model: str = ''
    compare: tuple = ()


def task_spec(task: str, policy: str | None = None, policy_file: str | None = None,
              settings: SearchSettings | None = None, seed: int = 0,
              max_fixations: int | None = None, split: str = 'test', empty: bool = False,
              model: str = '', compare=()) -> TaskSpec:
    """
    Return the shipped configuration of ``task``, with any of its parts replaced.

    ``pan-tilt`` takes its policy and settings from ``config/faces_camera_controller.yaml``;
    the fixed-camera tasks take ``find``'s (the shipped kernel of the model, else ELM). The
    budget ``max_fixations`` is the configuration's when it has one, else
    :data:`DEFAULT_BUDGET`.
    ``split`` picks training or held-out test scenes, ``empty`` the same scenes without a face
    (pan-tilt), ``model`` another pan/tilt observation file (its camera is the sensor's) and
    ``compare`` more searchers run on the same scenes and views: policy names (with the same
    settings; ``sweep`` starts at its own first pose), optionally with changed settings as
    ``name:parameter=value,...`` (parameter names of docs/design.md section 10.1, e.g.
    ``elm:search.repeat_weight=0.1,absent.prior=0``), and :data:`SWEEP_RULES`.
    """
    if task not in TASKS:
        raise ValueError(f"unknown scene task {task!r}; choose from {', '.join(TASKS)}")
    if split not in ('train', 'test'):
        raise ValueError(f"split must be 'train' or 'test', got {split!r}")
    if (empty or model) and task != 'pan-tilt':
        raise ValueError('empty scenes and another model are for the pan-tilt task')
    from ipomdp_gaze.policies.registry import NAMED_POLICIES
    for label in compare:
        name = label.split(':')[0]
        if ':' in label:
            compare_settings(SearchSettings(), label)
        if name not in NAMED_POLICIES and name not in SWEEP_RULES:
            raise ValueError(f'unknown searcher {name!r}; choose from '
                             f"{', '.join(NAMED_POLICIES + SWEEP_RULES)}")
        if name in SWEEP_RULES and task != 'pan-tilt':
            raise ValueError(f'{name} is a pan/tilt answer rule')
    if task == 'pan-tilt':
        from ipomdp_gaze.files.share_files import config_file
        path = config_file('faces_camera_controller.yaml')
        values = yaml_parameters(path, 'gaze_controller')
        base = check_parameters(values, grid=Grid(values['grid.rows'], values['grid.cols']),
                                where=f'{path}: ')
        name = values.get('policy.name', 'elm')
        file = values.get('policy.file', '') if name == 'learned' else ''
    else:
        from ipomdp_gaze.policies.policy_file import default_policy_file
        from ipomdp_gaze.vision.search import SCENE_SETTINGS
        base = SCENE_SETTINGS
        file = default_policy_file(load_observation(_FOVEA_TASKS[task][0])) or ''
        name = 'learned' if file else 'elm'
    if policy is not None or policy_file:
        name, file = ('learned', policy_file) if policy_file else (policy, '')
    if max_fixations is None:
        max_fixations = base.max_fixations or DEFAULT_BUDGET
    settings = settings or replace(base, max_fixations=max_fixations)
    return TaskSpec(task, name, file, settings, int(seed), split, bool(empty), model,
                    tuple(compare))


def compare_settings(settings: SearchSettings, label: str) -> SearchSettings:
    """
    Return ``settings`` changed by a searcher label's ``:parameter=value,...`` part.

    Values are read as YAML (``0.1``, ``true``, ``60``, ``[1, 2, 4, 8]``: commas inside brackets
    belong to the value).
    """
    if ':' not in label:
        return settings
    import yaml
    values = {}
    for item in re.split(r',(?![^\[]*\])', label.split(':', 1)[1]):
        key, sep, value = item.partition('=')
        if not sep or key.strip() not in PARAMETER_NAMES.values():
            raise ValueError(f'searcher {label!r}: expected parameter=value with a parameter '
                             f"of {', '.join(PARAMETER_NAMES.values())}, got {item!r}")
        values[key.strip()] = yaml.safe_load(value)
    return SearchSettings.from_parameters(values, base=settings)


@dataclass(frozen=True)
class SceneResult:
    """
    One searcher's search of one scene (times in seconds, angles in degrees).

    ``map_right[k]`` is whether the answer after ``k + 1`` fixations (the MAP cell, or the
    answer of a search that stopped sooner) is right; ``head_time_s`` the head-time model's total
    (module constants) and ``detector_s`` its detector part.
    """

    searcher: str
    index: int
    has_face: bool
    background: str
    right: bool
    decision: str
    reason: str
    cell: tuple
    face_cell: tuple | None
    fixations: int
    path: tuple
    detector_pixels: int
    seconds: float
    head_travel_deg: float
    map_right: tuple = ()
    head_time_s: float = 0.0
    detector_s: float = 0.0


class _Recording:
    """A detector that keeps the raw boxes of its last call (for the grouped answer rules)."""

    def __init__(self, detector):
        self.detector = detector
        self.boxes = np.zeros((0, 4), dtype=np.int64)

    def __call__(self, gray):
        self.boxes = self.detector(gray)
        return self.boxes

    def __getattr__(self, name):
        return getattr(self.detector, name)


class _ViewCache:
    """
    A sensor that renders and detects each view of a scene once, for every searcher.

    A still scene and a deterministic detector give the same frame at the same pose, so the
    searchers of one scene share the views (and the detector time measured for each).
    """

    def __init__(self, sensor, recorder=None):
        self.sensor = sensor
        self.recorder = recorder
        self.grid = sensor.grid
        self.scans = sensor.scans
        self.frames = {}
        self.boxes = {}

    def start(self, scene) -> None:
        self.sensor.start(scene)
        self.frames, self.boxes = {}, {}

    def scan(self):
        return self.sensor.scan()

    def observe(self, cell: int):
        cell = int(cell)
        if cell not in self.frames:
            self.frames[cell] = self.sensor.observe(cell)
            if self.recorder is not None:
                # boxes only: a scoring detector (YuNet) returns (M, 5) with its scores
                from ipomdp_gaze.vision.detector import as_detections
                self.boxes[cell] = as_detections(self.recorder.boxes)[0]
        return self.frames[cell]


class _Task:
    """The model, policy, sensor and scenes of a task, built once per process."""

    _cache: dict = {}

    @classmethod
    def get(cls, spec: TaskSpec) -> _Task:
        key = (spec.task, spec.policy, spec.policy_file, spec.seed, spec.split, spec.empty,
               spec.model, spec.compare)
        if key not in cls._cache:
            cls._cache = {key: cls(spec)}
        return cls._cache[key]

    def __init__(self, spec: TaskSpec):
        from ipomdp_gaze.policies.registry import build_policy
        self.spec = spec
        if spec.task == 'pan-tilt':
            from ipomdp_gaze.vision.detection import build_setup
            from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry
            from ipomdp_gaze.vision.sensors import PanTiltSensor
            setup = build_setup('camera', spec.model)
            self.model = setup.model
            geometry = SceneGeometry(self.model.grid, setup.camera)
            recorder = _Recording(setup.observer.detector)
            setup.observer.detector = recorder
            self.sensor = _ViewCache(PanTiltSensor(setup.observer, geometry), recorder)
            self.camera = setup.camera
            self.max_count = setup.observer.max_count
            self.head = PanTiltMap(self.model.grid)

            def scene(i):
                return PanTiltSceneSet(spec.split, geometry, color='rgb', seed=spec.seed + i,
                                       empty=spec.empty).scene(0)
        else:
            from ipomdp_gaze.vision.fovea_model import fovea_for_model
            from ipomdp_gaze.vision.scenes import SceneSet
            from ipomdp_gaze.vision.sensors import FoveaSensor
            name, size, faces = _FOVEA_TASKS[spec.task]
            self.model = load_observation(name)
            self.sensor = _ViewCache(FoveaSensor(fovea_for_model(self.model)))
            self.head = None
            scenes = SceneSet(spec.split, size_px=size, face_px=faces, grid=self.model.grid.shape,
                              seed=spec.seed)

            def scene(i):
                return scenes[i]
        self.scene = scene
        self.policy = build_policy(spec.policy, self.model.grid, self.model,
                                   file=spec.policy_file or None)
        self.compare = {label: build_policy(label.split(':')[0], self.model.grid, self.model)
                        for label in spec.compare if label not in SWEEP_RULES}
        if any(name in SWEEP_RULES for name in spec.compare):
            self.sweep = build_policy('sweep', self.model.grid, self.model)


def evaluate_scene(spec: TaskSpec, index: int) -> list:
    """
    Search scene ``index`` with ``spec``'s policy, then each of ``spec.compare`` on the same views.

    Returns one :class:`SceneResult` per searcher, ``spec``'s own first. Every session's policy
    draws come from ``[seed, index]``.
    """
    task = _Task.get(spec)
    scene = task.scene(index)
    task.sensor.start(scene.image)
    results = [_search(spec, task, scene, index, spec.policy_file or spec.policy, task.policy,
                       spec.settings)]
    for name in spec.compare:
        if name in SWEEP_RULES:
            results.append(_sweep_rule(spec, task, scene, index, name))
        else:
            settings = spec.settings
            if name.split(':')[0] == 'sweep':
                settings = replace(settings, start_cell='policy')
            settings = compare_settings(settings, name)
            results.append(_search(spec, task, scene, index, name, task.compare[name],
                                   settings))
    return results


def _search(spec: TaskSpec, task: _Task, scene, index: int, name: str, policy,
            settings: SearchSettings) -> SceneResult:
    """One session over the task's (cached) sensor; the MAP cell is kept after every frame."""
    grid = task.model.grid
    session = SearchSession(grid, task.model, policy, settings)
    maps, detector_s = [], []

    def record(frame, result):
        maps.append(session.map_cell)
        detector_s.append(frame.seconds)

    outcome = run_search(session, task.sensor, None,
                         seed=np.random.default_rng([spec.seed, index]),
                         limit=settings.max_fixations or 4 * grid.n_cells, restart=False,
                         on_frame=record)
    face = None if scene.cell is None else tuple(int(v) for v in scene.cell)
    answer = tuple(int(v) for v in grid.cell(outcome.cell))
    ended = bool(outcome.decision)
    decision = outcome.decision if ended else 'gave_up'
    n = len(maps)
    map_right = tuple(
        answer_is_right(tuple(int(v) for v in grid.cell(maps[k - 1])), face) if k < n
        else answer_is_right(answer, face, decision) for k in range(1, MAP_BUDGETS + 1))
    return _result(task, scene, index, name, answer, face, decision,
                   outcome.reason if ended else 'limit', outcome.path,
                   outcome.detector_pixels, detector_s, map_right)


def _result(task, scene, index, name, answer, face, decision, reason, path, pixels,
            detector_s, map_right=()) -> SceneResult:
    grid = task.model.grid
    travel = head_time = 0.0
    if task.head is not None:
        travel = head_travel_deg(grid, path)
        head_time = head_time_s(grid, path, detector_s)
    return SceneResult(str(name), int(index), face is not None, str(scene.background),
                       answer_is_right(answer, face, decision), decision, reason, answer, face,
                       len(path), tuple(int(k) for k in path), int(pixels),
                       float(sum(detector_s)), travel, tuple(map_right), head_time,
                       float(sum(detector_s)))


def _sweep_rule(spec: TaskSpec, task: _Task, scene, index: int, rule: str) -> SceneResult:
    """
    One pass of the sweep's poses, answered by ``rule`` (:data:`SWEEP_RULES`), without a belief.

    ``sweep-tile``: after the pass, the cell with most detections in its own tile (ties: the
    lowest index); ``sweep-first-*``: stop at the first view with a detection in the grid (raw,
    or grouped with min_neighbors 3 / 5: the largest group) and answer its cell. No detection
    in the whole pass: ``absent``.
    """
    from ipomdp_gaze.model.head_camera import bin_points
    from ipomdp_gaze.vision.detector import box_centres_px, group_boxes
    grid = task.model.grid
    poses, owner = task.sweep.poses, task.sweep.owner
    best = np.full(grid.n_cells, -1.0)
    path, pixels, detector_s = [], 0, []
    answer, decision = None, 'absent'
    for p, pose in enumerate(poses):
        frame = task.sensor.observe(int(pose))
        path.append(int(pose))
        pixels += frame.detector_pixels
        detector_s.append(frame.seconds)
        counts = np.nan_to_num(np.asarray(frame.values, dtype=float), nan=-1.0)
        if rule == 'sweep-tile':
            mine = owner == p
            best[mine] = counts[mine]
            continue
        if rule == 'sweep-first-raw':
            if counts.max() > 0:
                answer = int(np.argmax(counts))
                break
            continue
        # the detector's own grouping (YuNet's boxes are already suppressed), as fullframe.scan
        group = getattr(task.sensor.recorder.detector, 'group', None)
        raw = task.sensor.boxes[int(pose)]
        boxes = np.asarray(group(raw, int(rule[-1])) if callable(group)
                           else group_boxes(np.round(raw), int(rule[-1]))).reshape(-1, 4)
        if len(boxes):
            order = np.argsort(-(boxes[:, 2] * boxes[:, 3]), kind='stable')
            centres = box_centres_px(boxes[order]) - 0.5
            _, _, cells = bin_points(centres, task.camera, grid, grid.cell(int(pose)),
                                     task.max_count)
            inside = cells[cells >= 0]
            if inside.size:
                answer = int(inside[0])
                break
    if rule == 'sweep-tile' and best.max() > 0:
        answer = int(np.argmax(best))
    if answer is not None:
        decision = 'found'
    cell = tuple(int(v) for v in grid.cell(grid.center_index if answer is None else answer))
    face = None if scene.cell is None else tuple(int(v) for v in scene.cell)
    return _result(task, scene, index, rule, cell, face, decision, '', tuple(path), pixels,
                   detector_s)


def head_time_s(grid: Grid, path, detector_s) -> float:
    """
    Return the head-time model's seconds for a path: views, and saccades from the centre.

    Per view the detector's time plus :data:`SETTLE_TIME_S`; per saccade
    :data:`SACCADE_TIME_S` plus the largest joint angle over :data:`HEAD_SPEED_DEG_S`.
    """
    if not len(path):
        return 0.0
    rows, cols = grid.cell(np.concatenate([[grid.center_index], np.asarray(path)]))
    step = np.maximum(np.abs(np.diff(rows)), np.abs(np.diff(cols))) * grid.spacing_deg
    moves = step > 0
    return float(np.sum(detector_s) + SETTLE_TIME_S * len(path)
                 + np.sum(SACCADE_TIME_S + step[moves] / HEAD_SPEED_DEG_S))


def head_travel_deg(grid: Grid, path) -> float:
    """Sum over saccades of the angle the head turns, ``spacing * hypot(d_row, d_col)``."""
    if len(path) < 2:
        return 0.0
    rows, cols = grid.cell(np.asarray(path))
    return float(grid.spacing_deg * np.hypot(np.diff(rows), np.diff(cols)).sum())


def evaluate_scenes(spec: TaskSpec, episodes: int, executor=None,
                    progress=None) -> dict:
    """
    Search scenes ``0..episodes-1`` of ``spec``; one piece of work per scene, in scene order.

    Returns ``{searcher: [SceneResult per scene]}``, ``spec``'s policy first. ``executor`` is
    an :mod:`ipomdp_gaze.simulation.executor` executor (in-process when None: a local pool or a
    Dask
    cluster give the same results); ``progress`` anything with ``update(n)``.
    """
    executor = InlineExecutor() if executor is None else executor
    futures = [executor.submit(evaluate_scene, spec, i) for i in range(episodes)]
    for _ in track(futures, progress):
        pass
    out = {}
    for future in futures:
        for r in future.result():
            out.setdefault(r.searcher, []).append(r)
    return out


def summarise(results: list) -> dict:
    """
    One searcher's summary, scenes with a face and empty scenes apart.

    Right [Wilson 95% CI], fixations mean / median / p90, decisions, pixels, head travel, the
    head-time model's seconds, the MAP's accuracy after 1..MAP_BUDGETS fixations (scenes with a
    face) and, for empty scenes, ``absent`` and wrong ``found`` per background.
    """
    out = {}
    with_face = [r for r in results if r.has_face]
    empty = [r for r in results if not r.has_face]
    for label, group in (('face', with_face), ('empty', empty)):
        if not group:
            continue
        right = sum(r.right for r in group)
        fixations = np.array([r.fixations for r in group], dtype=float)
        decisions = {}
        for r in group:
            key = r.decision if r.decision != 'gave_up' else f'gave_up ({r.reason})'
            decisions[key] = decisions.get(key, 0) + 1
        s = out[label] = {
            'scenes': len(group), 'right': right / len(group),
            'right_ci95': wilson_interval(right, len(group)),
            'fixations_mean': float(fixations.mean()),
            'fixations_median': float(np.median(fixations)),
            'fixations_p90': float(np.percentile(fixations, 90)),
            'decisions': dict(sorted(decisions.items())),
            'detector_pixels_mean': float(np.mean([r.detector_pixels for r in group])),
            'head_travel_deg_mean': float(np.mean([r.head_travel_deg for r in group])),
            'head_time_s_mean': float(np.mean([r.head_time_s for r in group])),
            'detector_s_per_view': float(sum(r.detector_s for r in group)
                                         / max(1, fixations.sum())),
            'seconds_mean': float(np.mean([r.seconds for r in group])),
        }
        if label == 'face' and group[0].map_right:
            s['map_right_after'] = np.mean([r.map_right for r in group], axis=0).tolist()
        if label == 'empty':
            per = {}
            for r in group:
                row = per.setdefault(r.background, {'scenes': 0, 'absent': 0, 'wrong_found': 0})
                row['scenes'] += 1
                row['absent'] += r.decision == 'absent'
                row['wrong_found'] += r.decision == 'found'
            s['per_background'] = dict(sorted(per.items()))
            s['absent'] = sum(r.decision == 'absent' for r in group) / len(group)
            s['wrong_found'] = sum(r.decision == 'found' for r in group) / len(group)
    return out


def paired_map_difference(a: list, b: list, budgets=range(4, 13), n_boot: int = 2000,
                          seed: int = 0) -> dict:
    """
    MAP accuracy of ``a`` minus ``b`` (same scenes with a face) per budget, paired bootstrap 95%.

    Returns ``{budget: (difference, low, high)}``; the scenes are resampled together for all
    budgets.
    """
    fa = np.array([r.map_right for r in a if r.has_face], dtype=float)
    fb = np.array([r.map_right for r in b if r.has_face], dtype=float)
    if fa.shape != fb.shape or not fa.size:
        raise ValueError('paired differences need the same scenes with a face for both')
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, len(fa), size=(n_boot, len(fa)))
    diff = fa - fb
    boot = diff[picks].mean(axis=1)
    out = {}
    for k in budgets:
        low, high = np.percentile(boot[:, k - 1], [2.5, 97.5])
        out[int(k)] = (float(diff[:, k - 1].mean()), float(low), float(high))
    return out


def format_summary(spec: TaskSpec, summary: dict, name: str = '') -> list[str]:
    """Lines of the printed report for one searcher."""
    lines = []
    for label, s in summary.items():
        low, high = s['right_ci95']
        what = 'with a face' if label == 'face' else 'empty'
        decisions = ', '.join(f'{k} {v}' for k, v in s['decisions'].items())
        line = (f"{name or spec.task} ({s['scenes']} scenes {what}): right {s['right']:.3f} "
                f"[{low:.3f}, {high:.3f}], fixations mean {s['fixations_mean']:.2f} / median "
                f"{s['fixations_median']:.1f} / p90 {s['fixations_p90']:.1f}; {decisions}; "
                f"detector pixels {s['detector_pixels_mean']:.0f} per search")
        if spec.task == 'pan-tilt':
            line += (f"; head travel {s['head_travel_deg_mean']:.1f} deg; head time "
                     f"{s['head_time_s_mean']:.2f} s (detector {s['detector_s_per_view']:.3f} "
                     's per view)')
        lines.append(line)
        if 'map_right_after' in s:
            acc = s['map_right_after']
            lines.append('  MAP right after 1..20 fixations: '
                         + ' '.join(f'{v:.2f}' for v in acc))
        for bg, row in s.get('per_background', {}).items():
            lines.append(f"  {bg}: {row['scenes']} scenes, absent {row['absent']}, wrong found "
                         f"{row['wrong_found']}")
    return lines


def results_json(spec: TaskSpec, results, summary: dict) -> dict:
    """
    Return the JSON record: the configuration, and per searcher the summary and every scene.

    ``results`` and ``summary`` are ``{searcher: ...}``.
    """
    return {'task': spec.task, 'policy': spec.policy, 'policy_file': spec.policy_file,
            'settings': spec.settings.to_parameters(), 'seed': spec.seed, 'split': spec.split,
            'empty': spec.empty, 'model': spec.model, 'compare': list(spec.compare),
            'summary': summary,
            'scenes': {name: [{'index': r.index, 'has_face': r.has_face,
                               'background': r.background, 'right': r.right,
                               'decision': r.decision, 'reason': r.reason,
                               'cell': list(r.cell),
                               'face_cell': None if r.face_cell is None else list(r.face_cell),
                               'fixations': r.fixations, 'path': list(r.path),
                               'detector_pixels': r.detector_pixels,
                               'seconds': r.seconds if math.isfinite(r.seconds) else None,
                               'head_travel_deg': r.head_travel_deg,
                               'head_time_s': r.head_time_s,
                               'map_right': [bool(v) for v in r.map_right]} for r in group]
                       for name, group in results.items()}}


def write_json(path: Path, record: dict) -> None:
    """Write a JSON record (parents created)."""
    import json
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=1) + '\n')
