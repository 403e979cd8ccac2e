# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Several people who walk: find each, follow them in turn, find them again (design section 12.10).

Walk scenes with K people (:class:`ipomdp_gaze.vision.walks.WalkSceneSet` ``faces=K``), every
searcher on the same scenes and the same clock as the one-person walks
(:func:`ipomdp_gaze.drivers.tracking.run_walk`'s: a view when the head has moved and settled,
the detector's time after it). The searchers:

- ``people`` (shipped): the moving many-target session of :data:`PEOPLE_CONFIG` over
  :data:`~ipomdp_gaze.drivers.tracking.WALK_CONFIG` (``search.targets many``): one track per
  person found, the head's time shared ``motion.dwell_s`` each with a view for new people after
  each round; its answers are the people it follows;
- ``track``: the one-target tracker of the walk configuration (what the product did before);
- ``track-last-detection``: the baseline a team would write (centre the last grouped detection).

Scores per scene, over each person's frames in the grid's reach, averaged over the people of the
scene: ``in_view`` (the person inside the view), ``max_gap_s`` (the longest time the person was in
reach without being in view, from a view to the next one that has it, or to the walk's end);
``tracked`` (the person named by an answer, within one cell: the searcher knows where it is);
``found`` (the share of the people that some answer named, within one cell, at some frame);
``false_per_frame`` (answers within one cell of nobody in reach, per frame); ``id_switches``
(per scene, summed over its people: how often the number of the answer naming a person, the
nearest within one cell, changed from one frame that names it to the next that names it, as
multi-object tracking's identity switches count; a one-target searcher's answer is number 1).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from ipomdp_gaze.drivers.tracking import (_baseline_kwargs, LastDetectionTracker,
                                          normal_interval, run_on_clock, SessionTracker,
                                          walk_settings, WalkTask)
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.session import Frame, SearchSettings
from ipomdp_gaze.simulation.evaluation import cells_apart
from ipomdp_gaze.simulation.executor import run_by_searcher
from ipomdp_gaze.vision.walks import check_speed, DURATION_S, WalkSceneSet
import numpy as np

PEOPLE_CONFIG = 'faces_camera_people.yaml'
# Occupied cells within this many cells are one person (the rooms' link, docs/design.md 11.5).
PEOPLE_LINK = 1


def people_settings() -> tuple[SearchSettings, str, dict]:
    """Return the settings of the walk configuration with :data:`PEOPLE_CONFIG` over it."""
    return walk_settings(None, config_file(PEOPLE_CONFIG))


class PeopleTracker:
    """The moving many-target session: its answers are the people it follows."""

    def __init__(self, task: WalkTask, settings: SearchSettings, seed):
        self.task = task
        self.session = OccupancySession(task.grid, task.model, settings, link=PEOPLE_LINK)
        self.session.reset(seed=seed)
        self.last_t = None

    def first(self) -> int:
        return self.session.start()

    def step(self, t_s: float, obs, boxes) -> tuple:
        """Apply the view taken at ``t_s``; return ``(next head, answers, events)``."""
        dt = 0.0 if self.last_t is None else t_s - self.last_t
        self.last_t = t_s
        result = self.session.update(Frame(obs.counts, offsets=obs.offsets), dt_s=dt)
        grid = self.task.grid
        found = self.session.tracks.found
        answers = [tuple(int(v) for v in grid.cell(t.cell)) for t in found]
        return (result.fixation, answers, [e['event'] for e in self.session.people_events],
                [t.person for t in found])


class OneTracker:
    """A one-target searcher (``track`` or the baseline) answering at most one person."""

    def __init__(self, tracker):
        self.tracker = tracker

    def first(self) -> int:
        return self.tracker.first()

    def step(self, t_s: float, obs, boxes) -> tuple:
        nxt, answer, event = self.tracker.step(t_s, obs, boxes)
        answers = [] if answer is None else [answer]
        return nxt, answers, [event] if event else [], [1] * len(answers)


@dataclass(frozen=True)
class PeopleFrame:
    """
    One view: when, the head, each person's cell (None out of reach), in view, answers.

    ``numbers`` are the answers' person numbers (empty: unknown, counted as no switch).
    """

    t_s: float
    head: tuple
    cells: tuple
    in_view: tuple
    answers: tuple
    events: tuple = ()
    numbers: tuple = ()


@dataclass(frozen=True)
class PeopleResult:
    """One searcher on one scene of several people: the scores of the module docstring."""

    searcher: str
    index: int
    people: int
    in_view: float
    tracked: float
    max_gap_s: float
    found: float
    false_per_frame: float
    frames: int
    id_switches: float = math.nan

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in ('searcher', 'index', 'people', 'in_view',
                                              'tracked', 'max_gap_s', 'found',
                                              'false_per_frame', 'frames', 'id_switches')}


def run_people(task: WalkTask, scene, tracker) -> list:
    """Run one searcher over a scene of several walking people on the walks' clock."""
    def record(t, head, stepped):
        _, answers, events, numbers = stepped
        truths = scene.truths_at(t)
        return PeopleFrame(
            t, tuple(int(v) for v in task.grid.cell(head)), tuple(tr.cell for tr in truths),
            tuple(tr.cell is not None and task.in_view(tr, head) for tr in truths),
            tuple(answers), tuple(events), tuple(int(n) for n in numbers))
    return run_on_clock(task, scene, tracker, record)


def people_result(searcher: str, index: int, scene, frames: list) -> PeopleResult:
    """Score a searcher's frames (module docstring)."""
    people = scene.people
    in_view, tracked, gaps, found = [], [], [], []
    for p in range(people):
        reach = [f for f in frames if f.cells[p] is not None]
        if reach:
            in_view.append(sum(f.in_view[p] for f in reach) / len(reach))
            tracked.append(sum(any(cells_apart(a, f.cells[p]) <= 1 for a in f.answers)
                               for f in reach) / len(reach))
        gap, since = 0.0, None
        for f in frames:
            if f.cells[p] is None:
                since = None
            elif f.in_view[p]:
                if since is not None:
                    gap = max(gap, f.t_s - since)
                since = f.t_s
            elif since is None:
                since = f.t_s
        if since is not None:
            gap = max(gap, scene.duration_s - since)
        gaps.append(gap)
        found.append(any(f.cells[p] is not None and
                         any(cells_apart(a, f.cells[p]) <= 1 for a in f.answers)
                         for f in frames))
    false = sum(sum(all(c is None or cells_apart(a, c) > 1 for c in f.cells) for a in f.answers)
                for f in frames)
    return PeopleResult(searcher, index, people,
                        float(np.mean(in_view)) if in_view else math.nan,
                        float(np.mean(tracked)) if tracked else math.nan,
                        float(np.mean(gaps)), float(np.mean(found)),
                        false / len(frames) if frames else math.nan, len(frames),
                        float(id_switches(frames, people)))


def naming_number(frame: PeopleFrame, person: int) -> int | None:
    """Return the number of the answer naming ``person`` (the nearest within one cell), or None."""
    cell = frame.cells[person]
    if cell is None or not frame.numbers:
        return None
    near = [(cells_apart(a, cell), n) for a, n in zip(frame.answers, frame.numbers)
            if cells_apart(a, cell) <= 1]
    return min(near)[1] if near else None


def id_switches(frames: list, people: int) -> int:
    """Return how often a person's naming number changed between frames naming it (docstring)."""
    switches = 0
    for p in range(people):
        named = [n for n in (naming_number(f, p) for f in frames) if n is not None]
        switches += sum(a != b for a, b in zip(named, named[1:]))
    return switches


@dataclass(frozen=True)
class PeopleSpec:
    """What a people-walk evaluation runs."""

    split: str
    seed: int
    speed_deg_s: float
    faces: int
    duration_s: float
    settings: SearchSettings
    track_settings: SearchSettings
    policy: str
    model: str
    compare: tuple = ('track', 'track-last-detection')


def people_spec(speed_deg_s: float, faces: int = 2, split: str = 'test', seed: int = 0,
                duration_s: float = DURATION_S, settings: SearchSettings | None = None,
                compare=('track', 'track-last-detection')) -> PeopleSpec:
    """Return a checked people-walk evaluation (module docstring)."""
    check_speed(speed_deg_s)
    if split not in ('train', 'test'):
        raise ValueError(f"split must be 'train' or 'test', got {split!r}")
    for name in compare:
        if name != 'track':
            _baseline_kwargs(name)
    base, policy, values = people_settings()
    track, _, _ = walk_settings()
    return PeopleSpec(split, int(seed), float(speed_deg_s), int(faces), float(duration_s),
                      settings or base, track, policy, values.get('observation.file', ''),
                      tuple(compare))


def evaluate_people_walk(spec: PeopleSpec, index: int) -> list:
    """Run ``people`` and each of ``spec.compare`` on scene ``index`` (one piece of work)."""
    task = WalkTask.get(spec.track_settings, spec.policy, spec.model)
    scene = WalkSceneSet(spec.split, task.geometry, spec.seed, spec.speed_deg_s,
                         spec.duration_s, faces=spec.faces).scene(index)
    seed = np.random.default_rng([spec.seed, index])
    out = [people_result('people', index, scene,
                         run_people(task, scene, PeopleTracker(task, spec.settings, seed)))]
    for name in spec.compare:
        if name == 'track':
            rng = np.random.default_rng([spec.seed, index])
            one = SessionTracker(task, spec.track_settings, rng)
        else:
            one = LastDetectionTracker(task, **_baseline_kwargs(name))
        out.append(people_result(name, index, scene, run_people(task, scene, OneTracker(one))))
    return out


def evaluate_people_walks(spec: PeopleSpec, episodes: int, executor=None,
                          progress=None) -> dict:
    """Run scenes ``0..episodes-1``; return ``{searcher: [PeopleResult per scene]}``."""
    return run_by_searcher(evaluate_people_walk, spec, episodes, executor, progress)


def summarise_people(results: list, reference: list | None = None) -> dict:
    """Return means over scenes, and paired 95% intervals of differences to ``reference``."""
    s = {'scenes': len(results)}
    for key in ('in_view', 'tracked', 'max_gap_s', 'found', 'false_per_frame', 'id_switches'):
        values = np.array([getattr(r, key) for r in results], dtype=float)
        # a score a record lacks (id_switches before 0.3.8) is NaN in every scene: no mean
        s[key] = float(np.nanmean(values)) if np.any(~np.isnan(values)) else math.nan
        if reference is not None and reference is not results and len(results) > 1:
            d = values - np.array([getattr(r, key) for r in reference], dtype=float)
            d = d[~np.isnan(d)]
            bound = 1.0 if key in ('in_view', 'tracked') else math.inf     # fractions
            if d.size:
                s[f'{key}_minus_reference'] = normal_interval(d, bound)
    return s
