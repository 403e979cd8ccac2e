# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
What the offline evaluation of the image tasks reports: one scene's result and the summaries.

:class:`SceneResult` is one searcher's search of one scene, scored by the one right-answer rule
(:func:`ipomdp_gaze.simulation.evaluation.answer_is_right`) and the head-time model
(:mod:`ipomdp_gaze.model.head_time`); :func:`summarise`, :func:`paired_map_difference`,
:func:`format_summary`, :func:`results_json` and :func:`write_json` turn results into numbers,
lines and files (docs/design.md section 10.4).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from pathlib import Path

from ipomdp_gaze.files import json_files
from ipomdp_gaze.files.writable import write_text
from ipomdp_gaze.model.head_time import head_time_s, head_travel_deg
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.simulation.evaluation import answer_is_right, MIN_EPISODES, wilson_interval
import numpy as np

# The MAP's accuracy is reported after every fixation count 1..MAP_BUDGETS.
MAP_BUDGETS = 20


@dataclass(frozen=True)
class SceneResult:
    """
    One searcher's search of one scene (times in seconds, angles in degrees).

    ``map_right[k]`` is whether the answer after ``k + 1`` fixations (the MAP cell, or the
    answer of a search that stopped sooner) is right; ``head_time_s`` the head-time model's total
    (module constants) and ``detector_s`` its detector part. A room with several faces
    (drivers/rooms.py) also has every face's cell, every answered cell, the faces found and
    whether the searcher ended by its own rule (``done``).
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
    face_cells: tuple = ()
    answers: tuple = ()
    faces_found: int = 0
    done: bool = False

    @classmethod
    def from_record(cls, row: dict) -> SceneResult:
        """Rebuild one from its JSON record (``__dict__``): its lists back to tuples."""
        def value(key, v):
            if key in ('face_cells', 'answers'):
                return tuple(map(tuple, v))
            return tuple(v) if isinstance(v, list) else v
        return cls(**{k: value(k, v) for k, v in row.items()})


def scene_result(task, scene, index, name, answer, face, decision, reason, path, pixels,
                 detector_s, map_right=()) -> SceneResult:
    """Return the :class:`SceneResult` of one search: right, head travel and head time."""
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


def paired_difference(a: list, b: list, key: str, rng: np.random.Generator,
                      n_boot: int = 2000) -> tuple:
    """
    Mean of ``key`` in ``a`` minus ``b`` over the scenes both hold, paired bootstrap 95%.

    Scenes are matched by their index; ``key`` is a number or a fixed-length sequence per scene
    (then every returned value is an array over its entries). Returns ``(difference, low,
    high)``; the scenes are resampled together for every entry, drawn from ``rng`` (the
    published reports pass a fresh ``default_rng(0)`` to each call). From fewer than
    :data:`~ipomdp_gaze.simulation.evaluation.MIN_EPISODES` scenes ``low`` and ``high`` are None:
    every resample of one scene is that scene, an interval of no width (nothing is drawn).
    """
    first = {r.index: getattr(r, key) for r in a}
    pairs = [(first[r.index], getattr(r, key)) for r in b if r.index in first]
    if not pairs:
        raise ValueError('paired differences need scenes that both searchers ran')
    diff = np.array([x for x, _ in pairs], dtype=float) - np.array([y for _, y in pairs],
                                                                   dtype=float)
    if len(diff) < MIN_EPISODES:
        return diff.mean(axis=0), None, None
    picks = rng.integers(0, len(diff), size=(n_boot, len(diff)))
    low, high = np.percentile(diff[picks].mean(axis=1), [2.5, 97.5], axis=0)
    return diff.mean(axis=0), low, high


def paired_map_difference(a: list, b: list, rng: np.random.Generator, budgets=range(4, 13),
                          n_boot: int = 2000) -> dict:
    """
    MAP accuracy of ``a`` minus ``b`` (same scenes with a face) per budget, paired bootstrap 95%.

    Returns ``{budget: (difference, low, high)}`` (:func:`paired_difference` of ``map_right``,
    resampled from ``rng``; ``low`` and ``high`` None from one scene).
    """
    fa, fb = [r for r in a if r.has_face], [r for r in b if r.has_face]
    if len(fa) != len(fb) or not fa:
        raise ValueError('paired differences need the same scenes with a face for both')
    diff, low, high = paired_difference(fa, fb, 'map_right', rng, n_boot)
    return {int(k): (float(diff[k - 1]), None if low is None else float(low[k - 1]),
                     None if high is None else float(high[k - 1])) for k in budgets}


def format_summary(spec, summary: dict, name: str = '') -> list[str]:
    """Lines of the printed report for one searcher."""
    lines = []
    for label, s in summary.items():
        low, high = s['right_ci95']
        what = 'with a face' if label == 'face' else 'empty'
        decisions = ', '.join(f'{k} {v}' for k, v in s['decisions'].items())
        line = (f"{name or spec.task} ({counted(s['scenes'], 'scene')} {what}): right "
                f"{s['right']:.3f} "
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
            lines.append(f"  {bg}: {counted(row['scenes'], 'scene')}, absent {row['absent']}, "
                         f"wrong found {row['wrong_found']}")
    return lines


def results_json(spec, results, summary: dict) -> dict:
    """
    Return the JSON record: the configuration, and per searcher the summary and every scene.

    ``results`` and ``summary`` are ``{searcher: ...}``.
    """
    return {'task': spec.task, 'policy': spec.policy, 'policy_file': spec.policy_file,
            'settings': spec.settings.to_parameters(), 'seed': spec.seed, 'split': spec.split,
            'empty': spec.empty, 'model': spec.model, 'compare': list(spec.compare),
            'faces': list(spec.faces),
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
                               'map_right': [bool(v) for v in r.map_right],
                               **({'face_cells': [list(c) for c in r.face_cells],
                                   'answers': [list(c) for c in r.answers],
                                   'faces_found': r.faces_found, 'done': r.done}
                                  if spec.faces != (1, 1) else {})} for r in group]
                       for name, group in results.items()}}


def write_json(path: Path, record: dict) -> None:
    """Write a JSON record (parents created), whole or not at all."""
    write_text(path, json_files.dumps(record) + '\n')
