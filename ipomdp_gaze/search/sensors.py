# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Sensors: what turns a scene and a fixation into a :class:`ipomdp_gaze.search.session.Frame`.

A sensor states its grid and whether it scans when built; :meth:`Sensor.start` gives it a scene,
:meth:`Sensor.scan` the one-time scan (None when it has none) and :meth:`Sensor.observe` the frame
of a fixation. The model's own sampler (:class:`ModelSensor`, the simulator) lives here; the
fovea over a still image and the pan/tilt view of a scene are in
:mod:`ipomdp_gaze.vision.sensors`. An offline search of any task is then ``session + sensor +
scene`` (:func:`run_search`).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import time
from typing import Protocol

from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import as_observation
from ipomdp_gaze.search.session import fixation_index, Frame, SearchSession
import numpy as np


class Sensor(Protocol):
    """Produces the frames of one scene at a time."""

    grid: Grid
    scans: bool

    def start(self, scene) -> None:
        """Look at a new scene (a target cell, an image, a panorama)."""

    def scan(self) -> Frame | None:
        """Return the one-time scan of the scene, or None for a sensor without one."""

    def observe(self, cell: int) -> Frame:
        """Return the frame of a fixation at ``cell`` (row-major index)."""


class ModelSensor:
    """
    The world as an observation model says it is: frames drawn from the model's own tables.

    The scene is the target's cell, or None for an empty scene. A fixation's frame draws every
    cell from ``p_N`` at its offset and the target's cell from ``p_T``
    (``model.sample``); the scan, for a count model with scan tables, draws every cell from the
    scan's null table and the target's from its target table (``model.sample_scan``). This is
    the world's model: a session may assume another one.
    """

    def __init__(self, grid: Grid, model, rng: np.random.Generator):
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f'rng must be a numpy.random.Generator (np.random.default_rng(seed)), '
                            f'got {type(rng).__name__}')
        self.grid = grid
        self.model = as_observation(grid, model)
        self.rng = rng
        self.scans = bool(getattr(self.model, 'has_scan', False))
        self.target: int | None = None

    def start(self, scene) -> None:
        """``scene``: the target's cell index (a whole number in the grid), or None (no target)."""
        self.target = None if scene is None else fixation_index(self.grid, scene)

    def scan(self) -> Frame | None:
        if not self.scans:
            return None
        values = self.model.sample_scan(self.target or 0, self.rng,
                                        present=self.target is not None)
        return Frame(values, kind='scan')

    def observe(self, cell: int) -> Frame:
        values = self.model.sample(self.target or 0, fixation_index(self.grid, cell), self.rng,
                                   present=self.target is not None)
        return Frame(values)


@dataclass(frozen=True)
class SearchOutcome:
    """
    One offline search: what it decided, where it looked and what it cost.

    ``decision`` is ``found``, ``absent`` or ``gave_up`` (``reason`` ``budget`` or ``repeat``),
    or '' when the driver's frame limit stopped it first; ``cell`` the most likely cell then,
    ``path`` the fixated cells, ``detector_pixels`` and ``seconds`` the sensor's cost plus, for
    ``seconds``, the session's (wall time from start to answer). ``limit_cause`` is a repeat
    stop's cause (the session's, :data:`ipomdp_gaze.search.answer.REPEATS`), else ''.
    """

    decision: str
    reason: str
    cell: int
    probability: float
    absent_probability: float
    fixations: int
    path: tuple
    detector_pixels: int
    seconds: float
    belief: np.ndarray
    log: tuple
    limit_cause: str = ''


def run_search(session: SearchSession, sensor: Sensor, scene, *, seed=None,
               limit: int | None = None, pixel_budget: int | None = None, exclude=(),
               restart: bool = True, fixations=None, on_frame=None,
               fixation_budget: int | None = None) -> SearchOutcome:
    """
    Search one scene: reset, scan once (if the sensor and model have one), fixate until the end.

    The one offline search loop: ``find``, ``search``, the image-task evaluation and the benches
    run it. ``limit`` caps the frames when the settings have no budget (an offline search must
    end). ``pixel_budget`` caps the detector pixels: before a scan or a fixation that would pass
    it (the sensor's ``scan_cost()`` / ``fixation_cost(cell)``) the search stops there
    (:meth:`SearchSession.stop`, reason ``pixels``); ``fixation_budget`` caps those of the
    fixations after the scan alone, the same way. ``exclude`` rules cells out after the scan
    (:meth:`SearchSession.exclude`, ``find --all``); ``restart=False`` keeps the scene the sensor
    already holds (a second search of the same image reuses its detections). ``fixations``, a
    sequence of cells, is fixated in that order instead of the policy's choices (every view of a
    scene, a recorded path); the search then also ends when they run out. ``on_frame(frame,
    result)`` is called after every fixation frame the session applied (a driver's per-frame
    record: the answer so far, the detector's time). A session that ends at ``start`` (a
    many-target scan that decided every cell) takes no fixation.

    Raises
    ------
    ValueError
        Without a budget, ``stop_on_repeat``, ``limit`` or ``fixations``; for a frame the
        session rejects.

    """
    settings = session.settings
    if not (settings.max_fixations or settings.stop_on_repeat or limit
            or fixations is not None):
        raise ValueError('an offline search needs a fixation budget (search.max_fixations) '
                         'or a frame limit')
    if sensor.grid.shape != session.grid.shape:
        raise ValueError(f'the sensor observes a {sensor.grid.rows}x{sensor.grid.cols} grid, '
                         f'the session searches {session.grid.rows}x{session.grid.cols}')
    t0 = time.perf_counter()
    budget = math.inf if pixel_budget is None or pixel_budget == math.inf else int(pixel_budget)
    pixels, over = 0, False
    after_scan = (math.inf if fixation_budget is None or fixation_budget == math.inf
                  else int(fixation_budget))
    order = None if fixations is None else iter([int(c) for c in fixations])
    if restart:
        sensor.start(scene)
    session.reset(seed=seed)
    if sensor.scans and settings.scan:
        over = pixel_budget is not None and sensor.scan_cost() > budget
        if not over:
            frame = sensor.scan()
            pixels += frame.detector_pixels
            _check(session.scan(frame))
    if len(exclude):
        session.exclude(exclude)
    budget = min(budget, pixels + after_scan)
    cell = session.start()
    while not over and not session.ended and (limit is None or session.fixations < limit):
        if order is not None:
            cell = next(order, None)
            if cell is None:
                break
            session.fixate(cell)
        if budget < math.inf and pixels + sensor.fixation_cost(cell) > budget:
            over = True
            break
        frame = sensor.observe(cell)
        pixels += frame.detector_pixels
        result = _check(session.update(frame))
        if on_frame is not None:
            on_frame(frame, result)
        if result.ended:
            break
        cell = result.fixation
    if over:
        session.stop('pixels')
    best = session.map_cell
    return SearchOutcome(session.decision, session.gave_up_reason, best,
                         session.map_probability, session.absent_probability,
                         session.fixations, session.path, int(pixels),
                         time.perf_counter() - t0, session.belief, session.log,
                         session.limit_cause)


def _check(result):
    if not result.applied:
        raise ValueError(f'the sensor produced a frame the session refused: {result.reason}')
    return result
