# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Rooms with several faces (or none) on the pan/tilt task: the searchers and their scores.

A room is a pan/tilt scene with 0-4 faces (``PanTiltSceneSet(faces=...)``, ``evaluate --scenes
pan-tilt --faces K|LO-HI``). Its searchers, all on the same views of the task's
:class:`~ipomdp_gaze.drivers.scene_tasks.ViewCache`:

- ``many`` (optionally ``many:parameter=value,...``): the many-target session
  (:class:`ipomdp_gaze.search.many.OccupancySession`, ``search.targets: many``) on the task's
  model, with the configuration's settings less what it does not model (false-alarm scales,
  hotspots) and the choices of ``scene_tasks.ROOM_CHOICES``; its answer is every face of
  :meth:`~ipomdp_gaze.search.many.OccupancySession.faces`: one per cluster of occupied cells,
  split where the detector's raw boxes of its views, drawn into one picture of the room
  (:func:`room_boxes`), are distinct faces (docs/design.md section 11.3); ``many-cells``: one
  face per cluster, boxes unused; ``many-posterior``: a cell is decided empty by its posterior
  (``P(x_j) <= 1 - c``, ``OccupancySession(empty_by_evidence=False)``) instead of its evidence
  alone;
- ``pass-many`` (optionally ``pass-many:parameter=value,...``): the ``many`` session given the
  sweep as its policy, so one pass of the sweep's poses (the same views and head time as the
  sweeps; :class:`~ipomdp_gaze.search.many.OccupancySession`'s pass); its answer is the faces on
  their likelier side (``P(x_j) > 1/2``, split by the boxes) together with every detection
  grouped as ``detectMultiScale`` does with ``min_neighbors``
  :data:`~ipomdp_gaze.drivers.scene_tasks.ROOM_GROUP_MIN_NEIGHBORS` (the views' ``groups``) more
  than one cell from a face already named: grouping and the belief each see faces the other
  misses (docs/design.md section 11.7); ``pass-many-cells``: the same without the boxes (one face
  per cluster of cells, as the node answers);
- ``sweep-all-grouped3`` / ``sweep-all-grouped5``: one pass of the sweep's poses answering every
  detection grouped as ``detectMultiScale`` does (``min_neighbors`` 3 / 5), each at the cell of
  its box centre; a detection within one cell of one already answered is the same face (the
  sweep's views overlap);
- bounds, every view of the grid (row by row): ``every-view-grouped3`` / ``-5`` answer every
  grouped detection as above; ``every-view-many`` feeds every view to the ``many`` session
  (no stop rule) and answers as ``many`` does at its budget (every cell on its likelier side).

Scores (:func:`room_result`): a true face is found when an answer lies within one cell
(Chebyshev) of its cell, each face and each answer matched at most once
(:func:`ipomdp_gaze.simulation.evaluation.match_faces`); the other answers are false faces; the
room is *right* when every face was found and no false face named; *done* when the searcher ended
by its own rule (every cell decided, or the sweep's pass over), not at a budget; head time from
:mod:`ipomdp_gaze.model.head_time`.
"""
from __future__ import annotations

from dataclasses import replace
import math

from ipomdp_gaze.drivers.scene_report import scene_result, SceneResult
from ipomdp_gaze.drivers.scene_tasks import compare_settings, ROOM_MODEL
from ipomdp_gaze.drivers.sweep_rules import grouped_cells
from ipomdp_gaze.model.occupancy import count_faces
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.sensors import run_search
from ipomdp_gaze.simulation.evaluation import cells_apart, match_faces, wilson_interval
import numpy as np

# Cells (Chebyshev) within which occupied cells settle their neighbours (find's SETTLE_RADIUS)
# and within which occupied cells are one face (count_faces' FACE_RADIUS).
SETTLE_LINK = 1
FACE_LINK = 2
# Pixels per cell of the room picture the searcher's boxes are drawn into (room_boxes).
ROOM_CELL_PX = 100


def room_settings(settings, label: str = 'many'):
    """Return a label's many-target settings: ``settings``, ``ROOM_MODEL``, the label's."""
    return compare_settings(replace(settings, **ROOM_MODEL), label)


def room_session(spec, task, index: int, label: str = 'many'):
    """
    Run the many-target session of ``label`` on the scene the task's sensor holds.

    Returns ``(session, outcome, detector_s, faces)``: the ended session, its
    :class:`~ipomdp_gaze.search.sensors.SearchOutcome`, the detector's seconds per fixation and
    its faces (:meth:`~ipomdp_gaze.search.many.OccupancySession.faces`, ``link`` 2).
    """
    grid = task.model.grid
    settings = room_settings(spec.settings, label)
    name = label.split(':')[0]
    every = name == 'every-view-many'
    order = range(grid.n_cells) if every else None
    if every:            # every view, then the budget's answer: a bound on the belief
        settings = replace(settings, max_fixations=grid.n_cells, decide_at_budget=False,
                           confidence=1 - 1e-12)
    session = OccupancySession(grid, task.model, settings, link=SETTLE_LINK,
                               empty_by_evidence=name != 'many-posterior')
    if name.startswith('pass-many'):
        session.set_policy(task.sweep)              # one pass of its poses
    detector_s = []
    outcome = run_search(session, task.sensor, None,
                         seed=np.random.default_rng([spec.seed, index]),
                         limit=settings.max_fixations or 4 * grid.n_cells, restart=False,
                         on_frame=lambda frame, result: detector_s.append(frame.seconds),
                         fixations=order)
    if every:
        session = _Decided(session)
    boxes = None
    if name not in ('many-cells', 'pass-many-cells'):
        boxes = room_boxes(task, outcome.path)
    faces = session.faces(boxes, None, _room_px(grid), link=FACE_LINK) if boxes is not None \
        else session.faces(link=FACE_LINK)
    return session, outcome, detector_s, faces


class _Decided:
    """
    A finished session's faces, every cell on its likelier side (the every-view bound's answer).

    As ``many`` answers at its budget (``decide_at_budget``: occupied when ``P(x_j) > 1/2``).
    """

    def __init__(self, session):
        self.session = session

    def faces(self, boxes=None, scores=None, image_px=None, link: int = FACE_LINK):
        log_odds = self.session.log_odds
        return count_faces(log_odds, self.session.grid, log_odds > 0, boxes, scores, image_px,
                           link)


def _room_px(grid) -> tuple[int, int]:
    """``(width, height)`` of the room picture the grid tiles, :data:`ROOM_CELL_PX` per cell."""
    return grid.cols * ROOM_CELL_PX, grid.rows * ROOM_CELL_PX


def room_boxes(task, path) -> np.ndarray:
    """
    Every raw box of the views of ``path`` in one picture of the room that the grid tiles.

    A view's box ``(x, y, w, h)`` centred at pixel ``(u, v)`` with the head at cell
    ``(r_h, c_h)`` lies at grid position ``(r_h + atan((v - cy) / fy) / spacing, c_h +
    atan((u - cx) / fx) / spacing)`` (docs/design.md section 6.5); in the picture, cell ``(r, c)``
    spans ``[c, c + 1) x [r, r + 1)`` times :data:`ROOM_CELL_PX` with its centre at ``+ 0.5``,
    and the box keeps its angular size (``w / fx`` radians). The same face seen from several
    views then gives boxes at one place, which ``occupancy.merge_boxes`` merges. ``(M, 4)``.
    """
    grid, camera = task.model.grid, task.camera
    scale = ROOM_CELL_PX * 180.0 / (np.pi * grid.spacing_deg)
    out = []
    for cell in dict.fromkeys(int(c) for c in path):
        raw = np.asarray(task.sensor.boxes.get(cell, np.zeros((0, 4))), dtype=float)
        if not len(raw):
            continue
        raw = raw.reshape(-1, 4)
        head_r, head_c = grid.cell(cell)
        u = raw[:, 0] + (raw[:, 2] - 1) / 2
        v = raw[:, 1] + (raw[:, 3] - 1) / 2
        du, dv = camera.angles_deg(u, v)
        col = head_c + du / grid.spacing_deg
        row = head_r + dv / grid.spacing_deg
        w = raw[:, 2] / camera.fx * scale
        h = raw[:, 3] / camera.fy * scale
        out.append(np.stack([(col + 0.5) * ROOM_CELL_PX - w / 2,
                             (row + 0.5) * ROOM_CELL_PX - h / 2, w, h], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 4))


def room_search(spec, task, scene, index: int, label: str) -> SceneResult:
    """Search a room with the many-target session; answer every face it counted."""
    grid = task.model.grid
    session, outcome, detector_s, faces = room_session(spec, task, index, label)
    answers = [tuple(int(v) for v in grid.cell(f['cell'])) for f in faces]
    ended = bool(outcome.decision)
    decision = outcome.decision if ended else 'gave_up'
    reason = outcome.reason if ended else 'limit'
    done = ended and reason in ('', 'pass')          # a pass ends by its own rule, as a sweep
    return room_result(task, scene, index, label, answers, decision, reason, outcome.path,
                       outcome.detector_pixels, detector_s, done=done)


def room_sweep(spec, task, scene, index: int, rule: str) -> SceneResult:
    """
    One pass of the sweep's poses answering every grouped detection (module docstring).

    ``every-view-grouped3`` / ``-5``: the same over every pose of the grid (row by row), a
    bound on what grouping sees.
    """
    grid = task.model.grid
    answers, path, pixels, detector_s = [], [], 0, []
    poses = range(grid.n_cells) if rule.startswith('every-view') else task.sweep.poses
    for pose in poses:
        frame = task.sensor.observe(int(pose))
        path.append(int(pose))
        pixels += frame.detector_pixels
        detector_s.append(frame.seconds)
        for cell in grouped_cells(task, int(pose), int(rule[-1])):
            rc = tuple(int(v) for v in grid.cell(int(cell)))
            if all(cells_apart(rc, seen) > 1 for seen in answers):
                answers.append(rc)
    return room_result(task, scene, index, rule, answers, 'found' if answers else 'absent', '',
                       path, pixels, detector_s, done=True)


def room_result(task, scene, index, name, answers, decision, reason, path, pixels, detector_s,
                done: bool) -> SceneResult:
    """One room's :class:`SceneResult`: faces found, false faces, right and done."""
    truths = [tuple(int(v) for v in f.cell) for f in scene.faces]
    found = match_faces(answers, truths)
    first = answers[0] if answers else tuple(int(v) for v in task.model.grid.cell(
        task.model.grid.center_index))
    result = scene_result(task, scene, index, name, first, truths[0] if truths else None,
                          decision, reason, path, pixels, detector_s)
    return replace(result, has_face=bool(truths),
                   right=found == len(truths) and len(answers) == found,
                   face_cells=tuple(truths), answers=tuple(answers), faces_found=found,
                   done=bool(done))


def summarise_rooms(results: list) -> dict:
    """
    One searcher's room summary.

    ``faces``, ``recall`` (faces found over faces), ``false_per_scene``, ``rooms_right`` (every
    face found and no false face) [Wilson 95% CI], ``rooms_done`` (ended by its own rule) and
    ``rooms_done_right`` (done and right), ``head_time_s_mean`` (to the end of the search),
    fixations and, per count of faces, rooms and right.
    """
    faces = sum(len(r.face_cells) for r in results)
    found = sum(r.faces_found for r in results)
    false = sum(len(r.answers) - r.faces_found for r in results)
    right = sum(r.right for r in results)
    per = {}
    for r in results:
        row = per.setdefault(len(r.face_cells), {'scenes': 0, 'right': 0, 'found': 0,
                                                 'false': 0})
        row['scenes'] += 1
        row['right'] += int(r.right)
        row['found'] += r.faces_found
        row['false'] += len(r.answers) - r.faces_found
    fixations = np.array([r.fixations for r in results], dtype=float)
    n = len(results)
    return {'scenes': n, 'faces': faces, 'faces_found': found,
            'recall': found / faces if faces else None, 'false_faces': false,
            'false_per_scene': false / n, 'rooms_right': right / n,
            'rooms_right_ci95': wilson_interval(right, n),
            'rooms_done': sum(r.done for r in results) / n,
            'rooms_done_right': sum(r.done and r.right for r in results) / n,
            'head_time_s_mean': float(np.mean([r.head_time_s for r in results])),
            'fixations_mean': float(fixations.mean()),
            'fixations_p90': float(np.percentile(fixations, 90)),
            'per_face_count': dict(sorted(per.items()))}


def format_rooms(name: str, s: dict) -> list[str]:
    """Lines of the printed room report for one searcher."""
    recall = 'n/a' if s['recall'] is None else f"{s['recall']:.3f}"
    low, high = s['rooms_right_ci95']
    lines = [f"{name} ({counted(s['scenes'], 'room')}, {counted(s['faces'], 'face')}): recall "
             f'{recall}, false faces '
             f"{s['false_per_scene']:.3f} per room, rooms right {s['rooms_right']:.3f} "
             f"[{low:.3f}, {high:.3f}], done {s['rooms_done']:.3f} (done and right "
             f"{s['rooms_done_right']:.3f}), head time {s['head_time_s_mean']:.2f} s, fixations "
             f"mean {s['fixations_mean']:.2f} / p90 {s['fixations_p90']:.1f}"]
    lines.append('  per face count: ' + '; '.join(
        f"{k}: {counted(row['scenes'], 'room')}, right {row['right']}, found {row['found']}, "
        f"false {row['false']}" for k, row in s['per_face_count'].items()))
    return lines


def room_demo(faces, seed: int, out, max_fixations: int | None = None) -> int:
    """
    ``demo --scene faces --faces K`` offline: the scene camera's room of ``seed``, searched.

    The held-out room the scene camera shows with ``seed`` and ``scene.faces`` (scene 0 of that
    seed), the shipped pan/tilt model, camera and detector, and the many-target session as the
    rooms' configs run it on the node (``pass-many-cells``: one pass of the sweep, the grouped
    detections and the belief's faces; the settings of ``evaluate --faces``; ``max_fixations``
    replaces the budget).
    Prints every fixation, every face found and, last, ``found N of M faces: that is right``
    (every face found, nothing else named) or ``that is wrong``. Returns 0 when right, else 1.
    """
    from ipomdp_gaze.drivers.scene_tasks import SceneTask, task_spec
    spec = task_spec('pan-tilt', seed=seed, faces=faces, max_fixations=max_fixations)
    task = SceneTask.get(spec)
    scene = task.scene(0)
    grid = task.model.grid
    task.sensor.start(scene.image)
    out(f'the scene camera shows held-out room {seed} ({scene.background}, '
        f'{counted(len(scene.faces), "face")}); the many-target pass runs offline on the detector '
        f"node's views")
    session, outcome, _, found = room_session(spec, task, 0, 'pass-many-cells')
    for k, cell in enumerate(outcome.path, 1):
        pan, tilt = task.head.angles(int(cell))
        out(f'fixation {k}: cell {tuple(int(v) for v in grid.cell(int(cell)))} pan '
            f'{math.degrees(pan):+.1f} deg tilt {math.degrees(tilt):+.1f} deg')
    how = outcome.decision or 'gave_up'
    out(f"{how}{f' ({outcome.reason})' if outcome.reason else ''} after "
        f'{counted(outcome.fixations, "fixation")}: {counted(len(found), "face")}')
    for i, face in enumerate(found, 1):
        out(f"face {i}: cell {tuple(int(v) for v in grid.cell(face['cell']))} p="
            f"{face['probability']:.3f}")
    truths = [tuple(int(v) for v in f.cell) for f in scene.faces]
    out('the scene camera put the faces in cells ' + ', '.join(str(t) for t in truths)
        if truths else 'the scene camera put no face in the room')
    answers = [tuple(int(v) for v in grid.cell(f['cell'])) for f in found]
    n = match_faces(answers, truths)
    right = n == len(truths) and n == len(answers)
    out(f"found {n} of {counted(len(truths), 'face')}: that is {'right' if right else 'wrong'}")
    return 0 if right else 1
