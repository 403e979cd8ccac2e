# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Offline evaluation of the image tasks on held-out scenes (docs/design.md section 10.4).

Each scene goes through the search session, a real sensor and the real detector, as the nodes
and ``find`` run them.

Tasks (:data:`TASKS`):

- ``pan-tilt``: a camera on the pan/tilt head looking around a panorama with one face
  (:class:`ipomdp_gaze.vision.pan_tilt.PanTiltSceneSet`, test split), the shipped
  ``faces-pan-tilt`` model and the settings of ``config/faces_camera_controller.yaml``; scene
  ``seed + i`` is the scene the scene camera shows with parameter ``seed: seed + i`` (scene 0
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

from ipomdp_gaze.evaluation import wilson_interval
from ipomdp_gaze.executor import InlineExecutor, track
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.head import PanTiltMap
from ipomdp_gaze.observation_file import load_observation
from ipomdp_gaze.sensors import run_search
from ipomdp_gaze.session import SearchSession, SearchSettings
from ipomdp_gaze.yaml_files import yaml_parameters
import numpy as np

TASKS = ('pan-tilt', 'faces-420', 'faces-840')
# The budget every task's searches get unless told otherwise: the ROS bench's (60 fixations).
DEFAULT_BUDGET = 60
# The fixed-camera tasks: model, scene side (px), face sizes (px), as bench/faces.py.
_FOVEA_TASKS = {'faces-420': ('faces-420', 420, (60, 140)),
                'faces-840': ('faces-840', 840, (24, 140))}


@dataclass(frozen=True)
class TaskSpec:
    """What one task runs with: the model file, the policy, the settings and the scene seed."""

    task: str
    policy: str
    policy_file: str
    settings: SearchSettings
    seed: int


def task_spec(task: str, policy: str | None = None, policy_file: str | None = None,
              settings: SearchSettings | None = None, seed: int = 0,
              max_fixations: int = DEFAULT_BUDGET) -> TaskSpec:
    """
    Return the shipped configuration of ``task``, with any of its parts replaced.

    ``pan-tilt`` takes its policy and settings from ``config/faces_camera_controller.yaml``;
    the fixed-camera tasks take ``find``'s (the shipped kernel of the model, else ELM).
    """
    if task not in TASKS:
        raise ValueError(f"unknown scene task {task!r}; choose from {', '.join(TASKS)}")
    if task == 'pan-tilt':
        from ipomdp_gaze.nodes.config import config_file
        values = yaml_parameters(config_file('faces_camera_controller.yaml'), 'gaze_controller')
        base = SearchSettings.from_parameters(values, grid=Grid(values['grid.rows'],
                                                                values['grid.cols']))
        name = values.get('policy.name', 'elm')
        file = values.get('policy.file', '') if name == 'learned' else ''
    else:
        from ipomdp_gaze.policies.policy_file import default_policy_file
        from ipomdp_gaze.vision.search import FIND_SETTINGS
        base = FIND_SETTINGS
        file = default_policy_file(load_observation(_FOVEA_TASKS[task][0])) or ''
        name = 'learned' if file else 'elm'
    if policy is not None or policy_file:
        name, file = ('learned', policy_file) if policy_file else (policy, '')
    settings = settings or replace(base, max_fixations=max_fixations)
    return TaskSpec(task, name, file, settings, int(seed))


@dataclass(frozen=True)
class SceneResult:
    """One scene's search (times in seconds, angles in degrees)."""

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


class _Task:
    """The model, policy, sensor and scenes of a task, built once per process."""

    _cache: dict = {}

    @classmethod
    def get(cls, spec: TaskSpec) -> _Task:
        key = (spec.task, spec.policy, spec.policy_file, spec.seed)
        if key not in cls._cache:
            cls._cache = {key: cls(spec)}
        return cls._cache[key]

    def __init__(self, spec: TaskSpec):
        from ipomdp_gaze.policies.registry import build_policy
        self.spec = spec
        if spec.task == 'pan-tilt':
            from ipomdp_gaze.detection import build_setup
            from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry
            from ipomdp_gaze.vision.sensors import PanTiltSensor
            setup = build_setup('camera')
            self.model = setup.model
            geometry = SceneGeometry(self.model.grid, setup.camera)
            self.sensor = PanTiltSensor(setup.observer, geometry)
            self.head = PanTiltMap(self.model.grid)

            def scene(i):
                return PanTiltSceneSet('test', geometry, color='rgb', seed=spec.seed + i).scene(0)
        else:
            from ipomdp_gaze.vision.scenes import SceneSet
            from ipomdp_gaze.vision.fovea_model import fovea_for_model
            from ipomdp_gaze.vision.sensors import FoveaSensor
            name, size, faces = _FOVEA_TASKS[spec.task]
            self.model = load_observation(name)
            self.sensor = FoveaSensor(fovea_for_model(self.model))
            self.head = None
            scenes = SceneSet('test', size_px=size, face_px=faces, grid=self.model.grid.shape,
                              seed=spec.seed)

            def scene(i):
                return scenes[i]
        self.scene = scene
        self.policy = build_policy(spec.policy, self.model.grid, self.model,
                                   file=spec.policy_file or None)


def evaluate_scene(spec: TaskSpec, index: int) -> SceneResult:
    """Search scene ``index`` of ``spec``'s task; the policy's draws from ``[seed, index]``."""
    task = _Task.get(spec)
    scene = task.scene(index)
    grid = task.model.grid
    session = SearchSession(grid, task.model, task.policy, spec.settings)
    outcome = run_search(session, task.sensor, scene.image,
                         seed=np.random.default_rng([spec.seed, index]))
    cell = tuple(int(v) for v in grid.cell(outcome.cell))
    face = None if scene.cell is None else tuple(int(v) for v in scene.cell)
    if face is None:
        right = outcome.decision == 'absent'
    else:
        right = outcome.decision != 'absent' and max(abs(cell[0] - face[0]),
                                                     abs(cell[1] - face[1])) <= 1
    travel = 0.0
    if task.head is not None:
        travel = head_travel_deg(grid, outcome.path)
    return SceneResult(int(index), face is not None, str(scene.background), bool(right),
                       outcome.decision, outcome.reason, cell, face, outcome.fixations,
                       tuple(int(k) for k in outcome.path), outcome.detector_pixels,
                       outcome.seconds, travel)


def head_travel_deg(grid: Grid, path) -> float:
    """Sum over saccades of the angle the head turns, ``spacing * hypot(d_row, d_col)``."""
    if len(path) < 2:
        return 0.0
    rows, cols = grid.cell(np.asarray(path))
    return float(grid.spacing_deg * np.hypot(np.diff(rows), np.diff(cols)).sum())


def evaluate_scenes(spec: TaskSpec, episodes: int, executor=None, progress=None) -> list:
    """
    Search scenes ``0..episodes-1`` of ``spec``; one piece of work per scene, in scene order.

    ``executor`` is an :mod:`ipomdp_gaze.executor` executor (in-process when None: a local pool
    or a Dask cluster give the same results); ``progress`` anything with ``update(n)``.
    """
    executor = InlineExecutor() if executor is None else executor
    futures = [executor.submit(evaluate_scene, spec, i) for i in range(episodes)]
    for _ in track(futures, progress):
        pass
    return [future.result() for future in futures]


def summarise(results: list) -> dict:
    """Right [Wilson 95% CI], fixations mean / median / p90, decisions, pixels, head travel."""
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
        out[label] = {
            'scenes': len(group), 'right': right / len(group),
            'right_ci95': wilson_interval(right, len(group)),
            'fixations_mean': float(fixations.mean()),
            'fixations_median': float(np.median(fixations)),
            'fixations_p90': float(np.percentile(fixations, 90)),
            'decisions': dict(sorted(decisions.items())),
            'detector_pixels_mean': float(np.mean([r.detector_pixels for r in group])),
            'head_travel_deg_mean': float(np.mean([r.head_travel_deg for r in group])),
            'seconds_mean': float(np.mean([r.seconds for r in group])),
        }
    return out


def format_summary(spec: TaskSpec, summary: dict) -> list[str]:
    """Lines of the printed report."""
    lines = []
    for label, s in summary.items():
        low, high = s['right_ci95']
        what = 'with a face' if label == 'face' else 'empty'
        decisions = ', '.join(f'{k} {v}' for k, v in s['decisions'].items())
        line = (f"{spec.task} ({s['scenes']} scenes {what}): right {s['right']:.3f} "
                f"[{low:.3f}, {high:.3f}], fixations mean {s['fixations_mean']:.2f} / median "
                f"{s['fixations_median']:.1f} / p90 {s['fixations_p90']:.1f}; {decisions}; "
                f"detector pixels {s['detector_pixels_mean']:.0f} per search")
        if spec.task == 'pan-tilt':
            line += f"; head travel {s['head_travel_deg_mean']:.1f} deg"
        lines.append(line)
    return lines


def results_json(spec: TaskSpec, results: list, summary: dict) -> dict:
    """Return the JSON record: the configuration, the summary and one entry per scene."""
    return {'task': spec.task, 'policy': spec.policy, 'policy_file': spec.policy_file,
            'settings': spec.settings.to_parameters(), 'seed': spec.seed,
            'summary': summary,
            'scenes': [{'index': r.index, 'has_face': r.has_face, 'background': r.background,
                        'right': r.right, 'decision': r.decision, 'reason': r.reason,
                        'cell': list(r.cell),
                        'face_cell': None if r.face_cell is None else list(r.face_cell),
                        'fixations': r.fixations, 'path': list(r.path),
                        'detector_pixels': r.detector_pixels,
                        'seconds': r.seconds if math.isfinite(r.seconds) else None,
                        'head_travel_deg': r.head_travel_deg} for r in results]}


def write_json(path: Path, record: dict) -> None:
    """Write a JSON record (parents created)."""
    import json
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=1) + '\n')
