# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The image tasks of the offline evaluation: which scenes, model, policy, settings and sensor.

:func:`task_spec` describes a run (:class:`TaskSpec`, picklable, checked once); :class:`SceneTask`
builds, once per process, the model, policy, sensor and scenes it names, with a sensor that
renders and detects each view of a scene once for every searcher (:class:`ViewCache`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import re

from ipomdp_gaze.drivers.sweep_rules import ROOM_SWEEPS, SWEEP_RULES
from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.files.yaml_files import yaml_parameters
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.policies.policy_file import default_policy_file
from ipomdp_gaze.policies.registry import build_policy, NAMED_POLICIES
from ipomdp_gaze.search.session import PARAMETER_NAMES, SearchSettings
from ipomdp_gaze.search.settings import check_parameters
from ipomdp_gaze.vision.detection import build_setup, DEFAULT_MODELS
from ipomdp_gaze.vision.detector import as_detections
from ipomdp_gaze.vision.fovea_model import fovea_for_model
from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, parse_faces, SceneGeometry
from ipomdp_gaze.vision.scenes import SceneSet
from ipomdp_gaze.vision.search import SCENE_SETTINGS
from ipomdp_gaze.vision.sensors import FoveaSensor, PanTiltSensor
import numpy as np
import yaml

TASKS = ('pan-tilt', 'faces-420', 'faces-840')
# The budget every task's searches get unless told otherwise: the ROS bench's (60 fixations).
DEFAULT_BUDGET = 60
# The fixed-camera tasks: model, scene side (px), face sizes (px), as bench/faces/faces.py.
# The searchers of rooms with several faces (drivers/rooms.py): the many-target session (its
# faces split by the detector's boxes, or one per cluster of cells), the sweep's one pass with
# the session's belief and the grouped detections together, and the sweeps answering every
# grouped detection.
ROOM_SEARCHERS = ('many', 'many-cells', 'many-posterior', 'every-view-many',
                  'pass-many', 'pass-many-cells') + ROOM_SWEEPS
# What rooms change in the pan/tilt configuration: the many-target setting, without what the
# occupancy belief does not model (false-alarm scales, hotspots, coverage's tour; the choice per
# second of head time it keeps: docs/design.md section 11.5) ...
ROOM_MODEL = {'targets': 'many', 'false_alarm_scales': (1.0,), 'hotspot_prior': 0.0,
              'head_tour': False}
# ... and the settings chosen on training rooms (docs/design.md section 11.5): repeated views
# of a cell weigh 0.1 (at 1, texture seen from several views became false faces), within the
# budget of 20 fixations (40 found one more face of 50 in twice the head time).
ROOM_CHOICES = {'repeat_weight': 0.1}
# The grouping a room's views also report (Frame.groups), which pass-many answers: the grouped
# sweep a team keeps (no false face on the training rooms, where 3 named some; section 11.7).
ROOM_GROUP_MIN_NEIGHBORS = 5
# The one-face scenes' views report the grouping search.group_stop stops at: for the shipped
# camera model, the shipped detector configuration's (config/faces_camera_detector.yaml,
# publish_groups); for another, the grouping chosen on its training scenes (docs/design.md
# section 6.15); none for a model whose group stop was never measured (YuNet does not group).
DETECTOR_CONFIG = 'faces_camera_detector.yaml'
MODEL_GROUPS = {'faces-pan-tilt-40-profile': 3}
ROOM_BUDGET = 20
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
    split: str = 'test'
    empty: bool = False
    model: str = ''
    compare: tuple = ()
    faces: tuple = (1, 1)
    group_min_neighbors: int = 0

    @property
    def rooms(self) -> bool:
        """Whether the scenes are rooms of :attr:`faces` faces other than exactly one."""
        return self.faces != (1, 1)


def task_spec(task: str, policy: str | None = None, policy_file: str | None = None,
              settings: SearchSettings | None = None, seed: int = 0,
              max_fixations: int | None = None, split: str = 'test', empty: bool = False,
              model: str = '', compare=(), faces=1,
              group_min_neighbors: int | None = None) -> TaskSpec:
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
    ``faces`` (pan-tilt: K or ``LO-HI``, ``vision.pan_tilt.parse_faces``) other than 1 makes
    the scenes rooms of that many faces, searched by the many-target session ``many`` and
    compared with :data:`ROOM_SEARCHERS` only (drivers/rooms.py); the settings are then the
    configuration's with :data:`ROOM_MODEL` and :data:`ROOM_CHOICES`, and the budget
    :data:`ROOM_BUDGET` unless ``max_fixations`` is given.
    ``group_min_neighbors`` (pan-tilt, one face; refused otherwise): the grouping the views
    report for ``search.group_stop`` (``Frame.groups``), by default the model's
    (:func:`model_groups`); rooms report :data:`ROOM_GROUP_MIN_NEIGHBORS`. A ``compare``
    label's ``search.targets`` must be the task's (``one``; ``many`` for rooms).
    """
    if task not in TASKS:
        raise ValueError(f"unknown scene task {task!r}; choose from {', '.join(TASKS)}")
    if split not in ('train', 'test'):
        raise ValueError(f"split must be 'train' or 'test', got {split!r}")
    if (empty or model) and task != 'pan-tilt':
        raise ValueError('empty scenes and another model are for the pan-tilt task')
    faces = parse_faces(faces)
    if faces != (1, 1) and (task != 'pan-tilt' or empty):
        raise ValueError('rooms of several faces are for the pan-tilt task (0 faces: faces=0, '
                         'not empty)')
    targets = 'one' if faces == (1, 1) else 'many'
    for label in compare:
        name = label.split(':')[0]
        if ':' in label and compare_settings(replace(SearchSettings(), targets=targets),
                                             label).targets != targets:
            # the searchers of a task all hold its targets: a label's own would be ignored
            raise ValueError(f'searcher {label!r}: '
                             + ('search.targets many is for rooms of several faces (faces K or '
                                'LO-HI, --faces)' if targets == 'one' else
                                'a room searcher looks for everyone (search.targets many); '
                                'one face: faces 1, without --faces'))
        if faces != (1, 1):
            if name not in ROOM_SEARCHERS or (':' in label and name in ROOM_SWEEPS):
                raise ValueError(f'unknown room searcher {label!r}; choose from '
                                 f"{', '.join(ROOM_SEARCHERS)} (many:parameter=value,...)")
            continue
        if name not in NAMED_POLICIES and name not in SWEEP_RULES:
            raise ValueError(f'unknown searcher {name!r}; choose from '
                             f"{', '.join(NAMED_POLICIES + SWEEP_RULES)}")
        if name in SWEEP_RULES and task != 'pan-tilt':
            raise ValueError(f'{name} is a pan/tilt answer rule')
    if task == 'pan-tilt':
        path = config_file('faces_camera_controller.yaml')
        values = yaml_parameters(path, 'gaze_controller')
        base = check_parameters(values, grid=Grid(values['grid.rows'], values['grid.cols']),
                                where=f'{path}: ')
        name = values.get('policy.name', 'elm')
        file = values.get('policy.file', '') if name == 'learned' else ''
    else:
        base = SCENE_SETTINGS
        file = default_policy_file(load_observation(_FOVEA_TASKS[task][0])) or ''
        name = 'learned' if file else 'elm'
    if policy is not None or policy_file:
        name, file = ('learned', policy_file) if policy_file else (policy, '')
    # the results are kept per searcher's label: one given twice counted each scene twice
    own = 'many' if faces != (1, 1) else file or name
    labels = [own, *compare]
    for label in compare:
        if labels.count(label) > 1:
            twice = "is the task's own search" if label == own else 'is given twice'
            raise ValueError(f'searcher {label!r} {twice}: its scenes would be counted twice')
    if faces != (1, 1):
        base = replace(base, **ROOM_MODEL, **ROOM_CHOICES)
        if max_fixations is None:
            max_fixations = ROOM_BUDGET
    if max_fixations is None:
        max_fixations = base.max_fixations or DEFAULT_BUDGET
    settings = settings or replace(base, max_fixations=max_fixations)
    if group_min_neighbors is not None and (task != 'pan-tilt' or faces != (1, 1)):
        # not silently dropped: fixed-camera tasks report no groups, rooms their own grouping
        raise ValueError('group_min_neighbors (--group-min-neighbors) is for the pan-tilt task '
                         f'with one face; rooms report the grouping {ROOM_GROUP_MIN_NEIGHBORS} '
                         'of config/faces_camera_room_detector.yaml, the fixed-camera tasks '
                         'none')
    if task != 'pan-tilt':
        groups = 0
    elif faces != (1, 1):
        groups = ROOM_GROUP_MIN_NEIGHBORS
    else:
        groups = model_groups(model) if group_min_neighbors is None \
            else int(group_min_neighbors)
        if groups < 0:
            raise ValueError(f'group_min_neighbors must be >= 0, got {groups}')
    return TaskSpec(task, name, file, settings, int(seed), split, bool(empty), model,
                    tuple(compare), faces, groups)


def model_groups(model: str = '') -> int:
    """
    Return the grouping a pan/tilt model's views report for ``search.group_stop`` (0: none).

    The shipped detector configuration's ``publish_groups`` for its own model (``model`` ''
    is the shipped one), :data:`MODEL_GROUPS` for the others.
    """
    values = yaml_parameters(config_file(DETECTOR_CONFIG), 'foveal_detector')
    if (model or DEFAULT_MODELS['camera']) == values.get('observation.file'):
        return int(values.get('publish_groups', 0))
    return MODEL_GROUPS.get(model, 0)


def compare_settings(settings: SearchSettings, label: str) -> SearchSettings:
    """
    Return ``settings`` changed by a searcher label's ``:parameter=value,...`` part.

    Values are read as YAML (``0.1``, ``true``, ``60``, ``[1, 2, 4, 8]``: commas inside brackets
    belong to the value).
    """
    if ':' not in label:
        return settings
    values = {}
    for item in re.split(r',(?![^\[]*\])', label.split(':', 1)[1]):
        key, sep, value = item.partition('=')
        if not sep or key.strip() not in PARAMETER_NAMES.values():
            raise ValueError(f'searcher {label!r}: expected parameter=value with a parameter '
                             f"of {', '.join(PARAMETER_NAMES.values())}, got {item!r}")
        values[key.strip()] = yaml.safe_load(value)
    return SearchSettings.from_parameters(values, base=settings)


class Recording:
    """A detector that keeps the raw boxes of its last call (for the grouped answer rules)."""

    def __init__(self, detector):
        self.detector = detector
        self.boxes = np.zeros((0, 4), dtype=np.int64)

    def __call__(self, gray):
        self.boxes = self.detector(gray)
        return self.boxes

    def __getattr__(self, name):
        return getattr(self.detector, name)


class ViewCache:
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
                self.boxes[cell] = as_detections(self.recorder.boxes)[0]
        return self.frames[cell]


class SceneTask:
    """The model, policy, sensor and scenes of a task, built once per process."""

    _cache: dict = {}

    @classmethod
    def get(cls, spec: TaskSpec) -> SceneTask:
        key = (spec.task, spec.policy, spec.policy_file, spec.seed, spec.split, spec.empty,
               spec.model, spec.compare, spec.faces, spec.group_min_neighbors)
        if key not in cls._cache:
            cls._cache = {key: cls(spec)}
        return cls._cache[key]

    def __init__(self, spec: TaskSpec):
        self.spec = spec
        if spec.task == 'pan-tilt':
            setup = build_setup('camera', spec.model)
            self.model = setup.model
            geometry = SceneGeometry(self.model.grid, setup.camera)
            recorder = Recording(setup.observer.detector)
            setup.observer.detector = recorder
            setup.observer.group_min_neighbors = spec.group_min_neighbors
            self.sensor = ViewCache(PanTiltSensor(setup.observer, geometry), recorder)
            self.camera = setup.camera
            self.max_count = setup.observer.max_count
            self.head = PanTiltMap(self.model.grid)

            def scene(i):
                return PanTiltSceneSet(spec.split, geometry, color='rgb', seed=spec.seed + i,
                                       empty=spec.empty, faces=spec.faces).scene(0)
        else:
            name, size, faces = _FOVEA_TASKS[spec.task]
            self.model = load_observation(name)
            self.sensor = ViewCache(FoveaSensor(fovea_for_model(self.model)))
            self.head = None
            scenes = SceneSet(spec.split, size_px=size, face_px=faces, grid=self.model.grid.shape,
                              seed=spec.seed)

            def scene(i):
                return scenes[i]
        self.scene = scene
        self.policy = build_policy(spec.policy, self.model.grid, self.model,
                                   file=spec.policy_file or None)
        self.compare = {label: build_policy(label.split(':')[0], self.model.grid, self.model)
                        for label in spec.compare
                        if label not in SWEEP_RULES and not spec.rooms}
        if spec.rooms or any(name in SWEEP_RULES for name in spec.compare):
            self.sweep = build_policy('sweep', self.model.grid, self.model)
