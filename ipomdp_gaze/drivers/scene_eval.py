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
  scenes of ``bench/faces/faces.py``, ``SceneSet('test', ..., seed)[i]``) and ``find``'s model,
  kernel and settings.

A scene is *right* when the cell the search answers (its ``found`` cell, or the most likely cell
when it gave up) is within one cell (Chebyshev) of the face centre's cell. Each scene is one piece
of work (:func:`evaluate_scene`), seeded by its index, so the results do not depend on how the
pieces were spread over processes.
"""
from __future__ import annotations

from dataclasses import replace

from ipomdp_gaze.drivers.rooms import room_search, room_sweep
from ipomdp_gaze.drivers.scene_report import MAP_BUDGETS, scene_result, SceneResult
from ipomdp_gaze.drivers.scene_tasks import compare_settings, SceneTask, TaskSpec
from ipomdp_gaze.drivers.sweep_rules import ROOM_SWEEPS, sweep_rule, SWEEP_RULES
from ipomdp_gaze.search.sensors import run_search
from ipomdp_gaze.search.session import SearchSession, SearchSettings
from ipomdp_gaze.simulation.evaluation import answer_is_right
from ipomdp_gaze.simulation.executor import run_by_searcher
import numpy as np


def evaluate_scene(spec: TaskSpec, index: int) -> list:
    """
    Search scene ``index`` with ``spec``'s policy, then each of ``spec.compare`` on the same views.

    Returns one :class:`SceneResult` per searcher, ``spec``'s own first. Every session's policy
    draws come from ``[seed, index]``. Rooms (``spec.faces`` other than 1): the many-target
    session ``many`` first, then ``spec.compare`` (drivers/rooms.py).
    """
    task = SceneTask.get(spec)
    scene = task.scene(index)
    task.sensor.start(scene.image)
    if spec.rooms:
        return [room_search(spec, task, scene, index, 'many')] + [
            room_sweep(spec, task, scene, index, name) if name in ROOM_SWEEPS
            else room_search(spec, task, scene, index, name) for name in spec.compare]
    results = [_search(spec, task, scene, index, spec.policy_file or spec.policy, task.policy,
                       spec.settings)]
    for name in spec.compare:
        if name in SWEEP_RULES:
            results.append(sweep_rule(spec, task, scene, index, name))
        else:
            settings = spec.settings
            if name.split(':')[0] == 'sweep':
                settings = replace(settings, start_cell='policy')
            settings = compare_settings(settings, name)
            results.append(_search(spec, task, scene, index, name, task.compare[name],
                                   settings))
    return results


def _search(spec: TaskSpec, task: SceneTask, scene, index: int, name: str, policy,
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
    return scene_result(task, scene, index, name, answer, face, decision,
                        outcome.reason if ended else 'limit', outcome.path,
                        outcome.detector_pixels, detector_s, map_right)


def evaluate_scenes(spec: TaskSpec, episodes: int, executor=None,
                    progress=None) -> dict:
    """
    Search scenes ``0..episodes-1`` of ``spec``; one piece of work per scene, in scene order.

    Returns ``{searcher: [SceneResult per scene]}``, ``spec``'s policy first. ``executor`` is
    an :mod:`ipomdp_gaze.simulation.executor` executor (in-process when None: a local pool or a
    Dask
    cluster give the same results); ``progress`` anything with ``update(n)``.
    """
    return run_by_searcher(evaluate_scene, spec, episodes, executor, progress)
