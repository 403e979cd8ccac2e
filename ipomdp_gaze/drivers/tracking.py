# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
People who move: search, track and search again on walk scenes (docs/design.md section 12).

Every searcher runs on the same walk scene (:mod:`ipomdp_gaze.vision.walks`) on one clock: a view
is taken when the head has moved there and settled (the head-time model of
:mod:`ipomdp_gaze.model.head_time`: a saccade, then ``SETTLE_TIME_S``), the face is drawn where it
is at that time, and the detector's :data:`DETECTOR_TIME_S` passes before the next move. The
searchers:

- ``track`` (the shipped tracker): the search session with the walk configuration's motion
  (``motion.*``, calibrated on training walks, :func:`calibrate_motion`): the belief predicted
  over the time between frames, updated with each view's counts; the session chooses every view
  (while ``found``, ``motion.track_view``: the predicted peak; otherwise the search policy).
  ``lost`` when ``found`` ends, ``found`` again after it a reacquisition; its answer is the most
  likely cell while ``found``;
- ``track-last-detection``, what a team would write: sweep the sweep policy's poses; centre the
  head on the last grouped detection (``min_neighbors`` :data:`BASELINE_NEIGHBORS`, the largest
  box); after :data:`BASELINE_LOST_FRAMES` views without one, lost: sweep again from the pose
  nearest to where it was last seen.

Scores per scene (:func:`walk_result`), over the frames where the face is within the grid's
reach: ``in_view`` (the face centre inside the camera's view) and ``in_centre`` (the face in the
head's cell); ``first_find_s``, the time of the first frame whose answer is within one cell of
the face; ``reacquire_s``, from the face's return into reach to the first such frame after it.
A searcher that never finds is charged the rest of the walk (censored), and counted.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import math

from ipomdp_gaze.drivers.scene_tasks import Recording
from ipomdp_gaze.drivers.sweep_rules import group_cells
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.files.yaml_files import yaml_parameters
from ipomdp_gaze.model.head_time import HEAD_SPEED_DEG_S, SACCADE_TIME_S, SETTLE_TIME_S
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
from ipomdp_gaze.search.settings import check_parameters
from ipomdp_gaze.simulation.evaluation import cells_apart, wilson_interval
from ipomdp_gaze.simulation.executor import run_by_searcher
from ipomdp_gaze.vision.detection import build_setup
from ipomdp_gaze.vision.detector import as_detections
from ipomdp_gaze.vision.pan_tilt import SceneGeometry
from ipomdp_gaze.vision.walks import check_speed, DURATION_S, WalkSceneSet
import numpy as np

# The shortest and longest walk evaluated, in seconds: the scene camera's bounds on
# scene.walk_duration_s (a walk of 0.4 s had no frame to score: 'in view nan').
MIN_DURATION_S = 1.0
MAX_DURATION_S = 3600.0

# The detector's time per 320x240 view on the clock (s): a constant, so that where the face is
# when a view is taken does not depend on the machine (the median measured here, bench/pan_tilt).
DETECTOR_TIME_S = 0.03
TRACKERS = ('track-last-detection',)
# The baseline: grouped detections with min_neighbors 3 (the pan/tilt sweep rules' best on the
# still scenes, docs/pan_tilt.md) and the views without one after which it sweeps again (3: set
# before any measurement; other values via track-last-detection:neighbors=N,lost_frames=M).
BASELINE_NEIGHBORS = 3
BASELINE_LOST_FRAMES = 3
WALK_CONFIG = 'faces_camera_tracking.yaml'


@dataclass(frozen=True)
class WalkFrame:
    """One view on the walk's clock: when, where the head and the face were, the answer."""

    t_s: float
    head: tuple
    cell: tuple | None
    in_view: bool
    in_centre: bool
    answer: tuple | None
    event: str = ''


@dataclass(frozen=True)
class WalkResult:
    """One searcher on one walk scene: its frames and the scores of the module docstring."""

    searcher: str
    index: int
    frames: tuple
    reach_frames: int
    in_view: float
    in_centre: float
    first_find_s: float
    found: bool
    reacquire_s: float | None
    reacquired: bool | None
    lost: int
    reacquired_events: int

    def to_dict(self) -> dict:
        """Plain types, without the frames."""
        return {'searcher': self.searcher, 'index': self.index,
                'reach_frames': self.reach_frames, 'in_view': self.in_view,
                'in_centre': self.in_centre, 'first_find_s': self.first_find_s,
                'found': self.found, 'reacquire_s': self.reacquire_s,
                'reacquired': self.reacquired, 'lost': self.lost,
                'reacquired_events': self.reacquired_events}


def walk_settings(path=None, *more) -> tuple[SearchSettings, str, dict]:
    """
    Return the walk configuration's settings, policy name and parameters (``WALK_CONFIG``).

    ``more`` parameter files are read after it, each over the ones before (as ``--params-file``
    does on the node).
    """
    from ipomdp_gaze.model.grid import Grid
    paths = [config_file(WALK_CONFIG) if path is None else path, *more]
    values = {}
    for p in paths:
        values.update(yaml_parameters(p, 'gaze_controller'))
    settings = check_parameters(values, grid=Grid(values['grid.rows'], values['grid.cols']),
                                where=f'{paths[-1]}: ')
    return settings, values.get('policy.name', 'coverage'), values


class WalkTask:
    """The model, detector, view geometry and policies of the walk evaluation (per process)."""

    _cache: dict = {}

    @classmethod
    def get(cls, settings: SearchSettings, policy: str, model: str = '') -> WalkTask:
        key = (settings, policy, model)
        if key not in cls._cache:
            cls._cache = {key: cls(settings, policy, model)}
        return cls._cache[key]

    def __init__(self, settings: SearchSettings, policy: str, model: str = ''):
        setup = build_setup('camera', model)
        self.model = setup.model
        self.grid = self.model.grid
        self.camera = setup.camera
        self.observer = setup.observer
        self.geometry = SceneGeometry(self.grid, self.camera)
        self.settings = settings
        self.policy = build_policy(policy, self.grid, self.model)
        self.sweep = build_policy('sweep', self.grid, self.model)
        self.recorder = Recording(setup.observer.detector)
        self.observer.detector = self.recorder
        self.detector = self.recorder.detector

    def view(self, scene, t_s: float, head: int):
        """Take the view at ``head`` of the scene at ``t_s``: its observation and raw boxes."""
        head_rc = self.grid.cell(int(head))
        image = self.geometry.render(scene.image_at(t_s), head_rc)
        obs = self.observer.observe(image, self.camera, head_rc)
        return obs, as_detections(self.recorder.boxes)[0]

    def in_view(self, truth, head: int) -> bool:
        """Whether the face centre is inside the camera's view with the head at ``head``."""
        return face_in_view(self.camera, self.grid, truth.position, self.grid.cell(int(head)))


def face_in_view(camera, grid, position, head_rc) -> bool:
    """Whether grid position ``(row, col)`` is in ``camera``'s view, the head at ``head_rc``."""
    row, col = position
    r, c = head_rc
    spacing = grid.spacing_deg
    left, top = camera.angles_deg(-0.5, -0.5)
    right, bottom = camera.angles_deg(camera.width - 0.5, camera.height - 0.5)
    dx, dy = (col - c) * spacing, (row - r) * spacing
    return bool(left <= dx <= right and top <= dy <= bottom)


class SessionTracker:
    """The search session on the walk: ``found`` is having the face, the peak cell the answer."""

    def __init__(self, task: WalkTask, settings: SearchSettings, seed):
        self.task = task
        self.session = SearchSession(task.grid, task.model, task.policy, settings)
        self.session.reset(seed=seed)
        self.last_t = None
        self.had = False

    def first(self) -> int:
        return self.session.start()

    def step(self, t_s: float, obs, boxes) -> tuple:
        """Apply the view taken at ``t_s``; return ``(next head, answer, event)``."""
        session = self.session
        dt = 0.0 if self.last_t is None else t_s - self.last_t
        self.last_t = t_s
        result = session.update(Frame(obs.counts, detector_pixels=obs.detector_pixels,
                                      offsets=obs.offsets), dt_s=dt)
        has = session.decision == 'found'
        event = '' if has == self.had else ('found' if has else 'lost')
        self.had = has
        peak = int(np.argmax(session.belief))       # the most likely cell, not its square's
        answer = tuple(int(v) for v in self.task.grid.cell(peak)) if has else None
        return result.fixation, answer, event


class LastDetectionTracker:
    """The baseline of the module docstring: centre the last grouped detection, else sweep."""

    def __init__(self, task: WalkTask, neighbors: int = BASELINE_NEIGHBORS,
                 lost_frames: int = BASELINE_LOST_FRAMES):
        self.task = task
        self.neighbors, self.lost_frames = int(neighbors), int(lost_frames)
        self.poses = np.asarray(task.sweep.poses, dtype=np.int64)
        self.pose = 0
        self.last = None
        self.misses = 0

    def first(self) -> int:
        return int(self.poses[0])

    def step(self, t_s: float, obs, boxes) -> tuple:
        """Apply the view; return ``(next head, answer, event)``."""
        task = self.task
        grid = task.grid
        head = obs.head
        cells = group_cells(task.detector, boxes, task.camera, grid, head,
                            task.observer.max_count, self.neighbors) \
            if boxes is not None and len(boxes) else np.zeros(0, dtype=np.int64)
        had = self.last is not None
        if cells.size:
            self.last, self.misses = int(cells[0]), 0
        elif self.last is not None:
            self.misses += 1
            if self.misses >= self.lost_frames:
                rows, cols = grid.cell(self.poses)
                r, c = grid.cell(self.last)
                self.pose = int(np.argmin(np.maximum(abs(rows - r), abs(cols - c))))
                self.last = None
        has = self.last is not None
        event = '' if has == had else ('found' if has else 'lost')
        if has:
            return self.last, tuple(int(v) for v in grid.cell(self.last)), event
        here = int(grid.index(*(int(round(v)) for v in head)))
        if here == int(self.poses[self.pose]):
            self.pose = (self.pose + 1) % len(self.poses)
        return int(self.poses[self.pose]), None, event


def run_on_clock(task: WalkTask, scene, tracker, record) -> list:
    """
    Run one searcher over a walk scene on the clock of the module docstring.

    ``record(t_s, head, stepped)`` makes the frame of each view from the tracker's
    ``(next head, answer, event)``; returns the frames.
    """
    grid = task.grid
    head = int(tracker.first())
    previous = grid.center_index
    t, frames = 0.0, []
    while True:
        if head != previous:
            r0, c0 = grid.cell(previous)
            r1, c1 = grid.cell(head)
            step_deg = max(abs(r1 - r0), abs(c1 - c0)) * grid.spacing_deg
            t += SACCADE_TIME_S + step_deg / HEAD_SPEED_DEG_S
        t += SETTLE_TIME_S
        if t > scene.duration_s:
            break
        obs, boxes = task.view(scene, t, head)
        stepped = tracker.step(t, obs, boxes)
        frames.append(record(t, head, stepped))
        t += DETECTOR_TIME_S
        previous, head = head, int(stepped[0])
    return frames


def run_walk(task: WalkTask, scene, tracker) -> list:
    """Run one searcher over a walk scene on the clock of the module docstring."""
    def record(t, head, stepped):
        _, answer, event = stepped
        truth = scene.truth_at(t)
        head_rc = tuple(int(v) for v in task.grid.cell(head))
        return WalkFrame(t, head_rc, truth.cell, task.in_view(truth, head) and
                         truth.cell is not None, truth.cell == head_rc, answer, event)
    return run_on_clock(task, scene, tracker, record)


def walk_result(searcher: str, index: int, scene, frames: list) -> WalkResult:
    """Score a searcher's frames on a walk scene (module docstring)."""
    reach = [f for f in frames if f.cell is not None]
    n = len(reach)
    in_view = sum(f.in_view for f in reach) / n if n else math.nan
    in_centre = sum(f.in_centre for f in reach) / n if n else math.nan

    def right(f):
        return f.cell is not None and f.answer is not None and cells_apart(f.answer, f.cell) <= 1

    duration = scene.duration_s
    first = next((f.t_s for f in frames if right(f)), None)
    back = return_time(scene)
    reacquire, reacquired = None, None
    if back is not None:
        hit = next((f.t_s for f in frames if f.t_s >= back and right(f)), None)
        reacquired = hit is not None
        reacquire = (hit if reacquired else duration) - back
    lost = sum(f.event == 'lost' for f in frames)
    found_events = [i for i, f in enumerate(frames) if f.event == 'found']
    again = max(len(found_events) - 1, 0)
    return WalkResult(searcher, index, tuple(frames), n, in_view, in_centre,
                      first if first is not None else duration, first is not None, reacquire,
                      reacquired, lost, again)


def return_time(scene, step_s: float = 0.01) -> float | None:
    """Return when the face comes back into the grid's reach after leaving it (None: never)."""
    times = np.arange(0.0, scene.duration_s, step_s)
    inside = np.array([scene.truth_at(t).cell is not None for t in times])
    out = np.flatnonzero(~inside)
    if not out.size:
        return None
    back = np.flatnonzero(inside[out[0]:])
    return float(times[out[0] + back[0]]) if back.size else None


@dataclass(frozen=True)
class WalkSpec:
    """What a walk evaluation runs: scenes, the tracker's settings and the searchers compared."""

    split: str
    seed: int
    speed_deg_s: float
    duration_s: float
    settings: SearchSettings
    policy: str
    compare: tuple = ('track-last-detection',)
    model: str = ''          # the pan/tilt observation file; '' for the camera mode's default


def walk_spec(speed_deg_s: float, split: str = 'test', seed: int = 0,
              duration_s: float = DURATION_S, compare=('track-last-detection',),
              settings: SearchSettings | None = None, config=None,
              model: str | None = None) -> WalkSpec:
    """
    Return a checked walk evaluation: ``config`` (default :data:`WALK_CONFIG`) and its policy.

    ``compare`` names the other searchers, ``track-last-detection`` optionally with
    ``:neighbors=N,lost_frames=M``. ``model``: a pan/tilt observation file (path or shipped
    name) instead of the configuration's ``observation.file``.
    """
    check_speed(speed_deg_s)
    if split not in ('train', 'test'):
        raise ValueError(f"split must be 'train' or 'test', got {split!r}")
    if not (math.isfinite(duration_s) and MIN_DURATION_S <= duration_s <= MAX_DURATION_S):
        # a walk of 1e9 s ran for ever
        raise ValueError(f'the walk duration must be from {MIN_DURATION_S:g} to '
                         f"{MAX_DURATION_S:g} s (as the scene camera's scene.walk_duration_s), "
                         f'got {duration_s!r}')
    for name in compare:
        _baseline_kwargs(name)
        if list(compare).count(name) > 1:        # kept per label: its walks counted twice
            raise ValueError(f'searcher {name!r} is given twice: its walks would be counted '
                             'twice')
    base, policy, values = walk_settings(config)
    model = values.get('observation.file', '') if model is None else str(model)
    return WalkSpec(split, int(seed), float(speed_deg_s), float(duration_s),
                    settings or base, policy, tuple(compare), model)


def _baseline_kwargs(name: str) -> dict:
    """Return the baseline's keyword arguments of a searcher label, or raise ValueError."""
    label, _, rest = name.partition(':')
    if label not in TRACKERS:
        raise ValueError(f"unknown walk searcher {name!r}; choose from {', '.join(TRACKERS)}")
    kwargs = {}
    for item in filter(None, rest.split(',')):
        key, sep, value = item.partition('=')
        whole = value.isascii() and value.isdigit()         # int() refuses '²', isdigit not
        if not sep or key not in ('neighbors', 'lost_frames') or not whole or int(value) < 1:
            raise ValueError(f'searcher {name!r}: expected neighbors=N or lost_frames=M with '
                             f'N, M >= 1, got {item!r}')
        kwargs[key] = int(value)
    return kwargs


def evaluate_walk(spec: WalkSpec, index: int) -> list:
    """Run ``track`` and each of ``spec.compare`` on walk scene ``index`` (one piece of work)."""
    task = WalkTask.get(spec.settings, spec.policy, spec.model)
    scene = WalkSceneSet(spec.split, task.geometry, spec.seed, spec.speed_deg_s,
                         spec.duration_s).scene(index)
    tracker = SessionTracker(task, spec.settings, np.random.default_rng([spec.seed, index]))
    out = [walk_result('track', index, scene, run_walk(task, scene, tracker))]
    for name in spec.compare:
        baseline = LastDetectionTracker(task, **_baseline_kwargs(name))
        out.append(walk_result(name, index, scene, run_walk(task, scene, baseline)))
    return out


def evaluate_walks(spec: WalkSpec, episodes: int, executor=None, progress=None) -> dict:
    """Run walk scenes ``0..episodes-1``; return ``{searcher: [WalkResult per scene]}``."""
    return run_by_searcher(evaluate_walk, spec, episodes, executor, progress)


def format_walks(name: str, s: dict, reference: str = '') -> list[str]:
    """Return a searcher's summary lines (and its paired differences to ``reference``)."""
    censored = ', a walk without a find charged to its end' if s['found'] < s['scenes'] else ''
    returns = (f"reacquired {s['reacquired']} of {s['returns']} returns, "
               f"{s['reacquire_s_mean']:.2f} s after the return" if s['returns']
               else 'no walk left and came back')
    lines = [f"{name}: in view {s['in_view']:.3f}, in the centre cell {s['in_centre']:.3f} of "
             f"the frames in reach; first find {s['first_find_s_mean']:.2f} s (found in "
             f"{s['found']} of {s['scenes']}{censored}); {returns}; lost "
             f"{s['lost_mean']:.2f} times per walk"]
    for key in ('in_view', 'in_centre', 'reacquire_s'):
        diff = s.get(f'{key}_minus_reference')
        if diff:
            lines.append(f'  {key} minus {reference} [paired 95%, {counted(diff[3], "walk")}]: '
                         f'{diff[0]:+.3f} [{diff[1]:+.3f}, {diff[2]:+.3f}]')
    return lines


def walks_json(spec: WalkSpec, results: dict, summary: dict) -> dict:
    """Return the JSON record of a walk evaluation: configuration, summaries, every scene."""
    return {'task': 'pan-tilt', 'motion': 'walk', 'speed_deg_s': spec.speed_deg_s,
            'duration_s': spec.duration_s, 'split': spec.split, 'seed': spec.seed,
            'policy': spec.policy, 'model': spec.model,
            'settings': spec.settings.to_parameters(),
            'compare': list(spec.compare), 'summary': summary,
            'scenes': {name: [r.to_dict() for r in group] for name, group in results.items()}}


def summarise_walks(results: list, reference: list | None = None) -> dict:
    """Return the means over scenes and paired 95% intervals of differences to ``reference``."""
    def mean(values):
        values = [v for v in values if v is not None and not math.isnan(v)]
        return float(np.mean(values)) if values else math.nan

    found = sum(r.found for r in results)
    back = [r for r in results if r.reacquired is not None]
    s = {'scenes': len(results), 'in_view': mean([r.in_view for r in results]),
         'in_centre': mean([r.in_centre for r in results]),
         'first_find_s_mean': mean([r.first_find_s for r in results]),
         'found': found, 'found_interval': list(wilson_interval(found, len(results))),
         'reacquire_s_mean': mean([r.reacquire_s for r in back]),
         'reacquired': sum(bool(r.reacquired) for r in back), 'returns': len(back),
         'lost_mean': mean([r.lost for r in results])}
    if reference is not None and reference is not results:
        for key in ('in_view', 'in_centre', 'reacquire_s'):
            d = np.array([(a.to_dict()[key] or 0.0) - (b.to_dict()[key] or 0.0)
                          for a, b in zip(results, reference)
                          if a.to_dict()[key] is not None and b.to_dict()[key] is not None])
            d = d[~np.isnan(d)]
            if d.size > 1:
                # a difference of two fractions lies in [-1, 1]; of seconds, anywhere
                bound = 1.0 if key != 'reacquire_s' else math.inf
                s[f'{key}_minus_reference'] = normal_interval(d, bound) + [int(d.size)]
    return s


def normal_interval(d: np.ndarray, bound: float = math.inf) -> list:
    """
    Return ``[mean, low, high]``: the mean of paired differences and its 95% normal interval.

    The interval is cut to ``[-bound, bound]``, where the differences can lie (1 for fractions).
    """
    half = 1.96 * d.std(ddof=1) / math.sqrt(d.size) if d.size > 1 else math.nan
    return [float(d.mean()), float(max(d.mean() - half, -bound)),
            float(min(d.mean() + half, bound))]


def with_motion(settings: SearchSettings, sigma_cells: float, jump_prob: float = 0.0):
    """Return ``settings`` with a moving target's motion (per second)."""
    return replace(settings, motion_sigma_cells=float(sigma_cells),
                   motion_jump_prob=float(jump_prob))


def calibrate_position_sigma(split: str = 'train', scenes: int = 100, views: int = 4,
                             speeds_deg_s=(0.0, 20.0), seed: int = 0,
                             model: str | None = None) -> dict:
    """
    Fit ``motion.position_sigma_cells`` on walks of ``split`` (docs/design.md section 12.9).

    Scene ``i`` walks at a speed drawn uniformly in ``speeds_deg_s`` (as
    :func:`~ipomdp_gaze.vision.walks.calibrate_motion`); at ``views`` times drawn uniformly
    while its face is in reach, the head looks at the face's cell (as while tracking), the
    detector runs on the view, and the detections' mean position around that cell
    (:func:`~ipomdp_gaze.model.position_filter.measured_position`) is compared with the face
    centre. ``sigma_cells`` is the root mean square error per axis over the views with a
    measurement within the gate, ``se_cells`` its standard error (delta method over the
    squared errors: ``sd(e^2) / (2 sigma sqrt(n))``); also returned: the bias per axis, the
    views measured and the views taken.
    """
    from ipomdp_gaze.model.position_filter import GATE_CELLS, measured_position
    lo, hi = (check_speed(v) for v in speeds_deg_s)
    base, policy, values = walk_settings()
    task = WalkTask.get(base, policy, values.get('observation.file', '') if model is None
                        else str(model))
    grid = task.grid
    rng = np.random.default_rng([7, int(seed)])
    errors, taken = [], 0
    for i in range(int(scenes)):
        speed = lo + rng.random() * (hi - lo)
        scene = WalkSceneSet(split, task.geometry, seed, speed).scene(i)
        times = np.arange(0.0, scene.duration_s, 0.05)
        reach = [t for t in times if scene.truth_at(t).cell is not None]
        for t in rng.choice(reach, size=min(int(views), len(reach)), replace=False):
            truth = scene.truth_at(float(t))
            head = int(grid.index(*truth.cell))
            obs, _ = task.view(scene, float(t), head)
            taken += 1
            z = measured_position(obs.counts, obs.offsets, grid, head)
            if z is not None and np.max(np.abs(z - np.asarray(truth.cell))) <= GATE_CELLS:
                errors.append(z - np.asarray(truth.position, dtype=np.float64))
    e = np.asarray(errors, dtype=np.float64).reshape(-1, 2)
    if not len(e):
        raise ValueError('no view measured a position: no face detected on these walks')
    sq = (e ** 2).reshape(-1)
    sigma = float(np.sqrt(sq.mean()))
    se = float(sq.std(ddof=1) / (2 * sigma * np.sqrt(sq.size))) if sq.size > 1 else math.inf
    return {'sigma_cells': sigma, 'se_cells': se,
            'bias_cells': [float(v) for v in e.mean(axis=0)],
            'measured': int(len(e)), 'views': int(taken)}
