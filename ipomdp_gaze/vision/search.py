# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Search one image for the target with the digital fovea and a count model (docs/design.md 6).

:func:`search_image` is the whole loop of the CVPR 2009 follow-up on one decoded image:

1. start the fovea on the image (grey conversion); with a fovea that scans once
   (``scan_once``), observe the whole-image windows and apply their one Bayes step with the
   model's scan tables, ``model.scan_log_likelihood_ratio(counts)``; then fixate the **start
   cell**: the policy's choice on the scanned belief, or without a scan the grid's centre
   (docs/design.md section 4.2: on real pixels, as on the robot, the start cell replaces the
   policy's first choice); an explicit ``start_cell`` wins in both cases;
2. observe the fixation's detection counts and apply **one Bayes step** with the count model,
   ``bayes_update(log_b, model.log_likelihood_ratio(counts, k))`` (section 1.3);
3. stop with ``'found'`` when the most likely cell's probability reaches ``confidence``, with
   ``'budget'`` after ``max_fixations`` fixations, else ask the policy for the next fixation,
   ``policy.select(belief (1, N), t, rng)`` with ``t`` the number of fixations made so far;
4. stop with ``'repeat'`` **before** fixating a cell a second time (NMPT's rule,
   ``MIPOMDP::searchFrameUntilConfident``): the detector is deterministic, so the same fixation
   of the same image would return the same counts and the model, which assumes independent
   observations, would count the same evidence twice. ``stop_on_repeat=False`` lifts the rule.

The answer is the MAP cell at stop (tie rule of section 4.1) and the pixel at its centre.

**Cost.** ``detector_pixels`` is the number of pixels of every image the detector was given
(the resized windows; the whole-image window is detected once per image and counted once, see
:mod:`ipomdp_gaze.vision.fovea`). ``seconds`` is the wall time from the decoded image array to
the answer: grey conversion, every window's resizing and detection (the whole-image window
included), binning, the belief updates and the policy's decisions. Reading and decoding the file
is not included, nor is building the detector, the fovea or the policy (done once, not per image).

**Sizes.** The model must be for the fovea's grid (``rows x cols``), fovea settings and detector
(when its ``meta`` records them: a model is only valid with what it was measured with); a
mismatch is a :class:`ValueError`. An image of another pixel size than the model was calibrated
at (``model.meta['image']``) is allowed: the grid tiles any image, but faces then appear at
other sizes in the windows than during calibration, so the result says so (``calibrated_px``).

Part of the core: numpy and OpenCV only; the policy is any object with ``select``.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import operator
import time

from ipomdp_gaze.belief import bayes_update, map_cell, uniform_log_belief
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.inhibition import policy_choice, unvisited_choice
from ipomdp_gaze.vision.cell_observation import cell_observation_of
from ipomdp_gaze.vision.detector import detector_settings, detector_window_px
from ipomdp_gaze.vision.detectors import (compare_settings, detector_from_settings,  # noqa: F401
                                          info_keys_of)
from ipomdp_gaze.vision.fovea import cell_edges_px, Fovea, FoveaConfig
import numpy as np

# Operating point of `ipomdp-gaze find` until docs/faces.md reports a measured one.
DEFAULT_CONFIDENCE = 0.9
DEFAULT_MAX_FIXATIONS = 25
STOP_REASONS = ('found', 'budget', 'repeat')


@dataclass(frozen=True, eq=False)
class ImageSearch:
    """
    The outcome of :func:`search_image` on one image.

    Attributes
    ----------
    cell : (int, int)
        ``(row, col)`` of the most likely cell when the search stopped.
    pixel : (float, float)
        ``(x, y)`` of that cell's centre in image pixels (cell ``c`` spans columns
        ``floor(c W / cols)`` to ``floor((c + 1) W / cols)``, as the fovea tiles images).
    probability : float
        Its posterior probability.
    fixations : int
        Number of fixations made (observations applied).
    path : tuple of (int, int)
        The fixated cells ``(row, col)``, in order; the first is the start cell.
    stop : str
        ``'found'``, ``'budget'`` or ``'repeat'`` (module docstring).
    detector_pixels : int
        Pixels of all images given to the detector; the whole-image window counts once.
    seconds : float
        Wall time from the decoded image to the answer (module docstring).
    belief : numpy.ndarray
        ``(N,)`` posterior at stop, row-major.
    image_px : (int, int)
        ``(width, height)`` of the image searched.
    calibrated_px : (int, int) or None
        ``(width, height)`` the model was calibrated at (``model.meta['image']``), None if it
        does not say.

    """

    cell: tuple
    pixel: tuple
    probability: float
    fixations: int
    path: tuple
    stop: str
    detector_pixels: int
    seconds: float
    belief: np.ndarray
    image_px: tuple
    calibrated_px: tuple | None

    @property
    def size_matches(self) -> bool:
        """Whether the image has the size the model was calibrated at (True if unknown)."""
        return self.calibrated_px is None or self.calibrated_px == self.image_px


def calibrated_size(model) -> tuple[int, int] | None:
    """
    ``(width, height)`` a model was calibrated at, from ``model.meta['image']``, or None.

    Raises
    ------
    ValueError
        If ``meta['image']`` is present but is not ``{width, height}`` of positive integers.

    """
    block = getattr(model, 'meta', {}).get('image')
    if block is None:
        return None
    try:
        width, height = block['width'], block['height']
    except (TypeError, KeyError):
        raise ValueError(f"the model's image record must be {{width, height}}, got "
                         f'{block!r}') from None
    for name, value in (('width', width), ('height', height)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"the model's image.{name} must be a positive integer, got "
                             f'{value!r}')
    return (int(width), int(height))


def check_model(model, fovea: Fovea) -> None:
    """
    Check that ``model`` was measured on ``fovea``'s grid, fovea settings and detector.

    The grid must match always; the fovea settings and the detector only when the model's
    ``meta`` records them (``meta['fovea']``, ``meta['detector']``). For the detector, every
    setting is compared except those recorded for information (the detector's ``info_keys``: the
    OpenCV version and the cascade's window size).

    Raises
    ------
    ValueError
        Naming what differs.

    """
    grid = getattr(model, 'grid', None)
    if grid is None or not hasattr(model, 'log_likelihood_ratio'):
        raise ValueError(f'expected an observation model with a grid, got {type(model).__name__}')
    if grid.shape != fovea.grid.shape:
        raise ValueError(f'the observation model is for a {grid.rows}x{grid.cols} grid but the '
                         f'fovea tiles images with {fovea.grid.rows}x{fovea.grid.cols}')
    scan = bool(getattr(model, 'has_scan', False))
    if scan != fovea.config.scan_once:
        raise ValueError('the fovea scans the whole image once but the observation model has '
                         'no scan tables' if fovea.config.scan_once else
                         'the observation model has scan tables but the fovea does not scan '
                         '(scan_once false)')
    meta = getattr(model, 'meta', {})
    if meta.get('fovea') is not None:
        try:
            measured = FoveaConfig.from_dict(dict(meta['fovea']))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"the model's fovea record is invalid: {exc}") from None
        if measured != fovea.config:
            raise ValueError(f'the observation model was measured with fovea '
                             f'{measured.to_dict()} but the fovea is {fovea.config.to_dict()}')
    if meta.get('detector') is not None:
        compare_settings(dict(meta['detector']), detector_settings(fovea.detector),
                         info_keys_of(fovea.detector))
    if fovea.cells != cell_observation_of(meta, fovea.config.max_count):
        raise ValueError(f'the observation model records cells {meta.get("cells")!r} but the '
                         f'fovea observes {fovea.cells.to_dict()}')


def check_image_size(image_px: tuple[int, int], fovea: Fovea) -> None:
    """
    Check that an image of ``(width, height)`` pixels is large enough for ``fovea``.

    It must be at least the detector's window (:func:`detector_window_px`) and have at least one
    pixel per cell along each side (what :meth:`Fovea.start` needs).

    Raises
    ------
    ValueError
        Naming the sizes.

    """
    width, height = image_px
    min_width, min_height = detector_window_px(fovea.detector)
    min_width, min_height = max(min_width, fovea.grid.cols), max(min_height, fovea.grid.rows)
    if width < min_width or height < min_height:
        raise ValueError(f'image of {width}x{height} pixels (WxH) is too small: the detector '
                         f'and the {fovea.grid.rows}x{fovea.grid.cols} grid need at least '
                         f'{min_width}x{min_height}')


def check_image(image, fovea: Fovea) -> tuple[int, int]:
    """
    Check that ``fovea`` can search ``image``; return its ``(width, height)``.

    The image must be ``uint8`` grey ``(H, W)`` or RGB ``(H, W, 3)`` and large enough
    (:func:`check_image_size`).

    Raises
    ------
    ValueError
        Naming the problem (dtype, shape or size).

    """
    if not isinstance(image, np.ndarray):
        raise ValueError(f'image must be a numpy array, got {type(image).__name__}')
    if image.dtype != np.uint8:
        raise ValueError(f'image must be 8-bit (uint8, 0..255), got dtype {image.dtype}')
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
        raise ValueError(f'image must be (H, W) grey or (H, W, 3) RGB, got shape {image.shape}')
    image_px = (int(image.shape[1]), int(image.shape[0]))
    check_image_size(image_px, fovea)
    return image_px


def cell_centre_px(grid: Grid, cell: int, image_px: tuple[int, int]) -> tuple[float, float]:
    """``(x, y)`` centre of a cell of an image of ``(width, height)`` pixels tiled by ``grid``."""
    row, col = grid.cell(cell)
    width, height = image_px
    x0, x1 = cell_edges_px(width, grid.cols)[[col, col + 1]]
    y0, y1 = cell_edges_px(height, grid.rows)[[row, row + 1]]
    return (float(x0 + x1) / 2.0, float(y0 + y1) / 2.0)


def _start_index(grid: Grid, start_cell) -> int:
    if start_cell is None:
        return grid.center_index
    if np.ndim(start_cell) == 1 and len(start_cell) == 2:
        try:
            row, col = (operator.index(v) for v in start_cell)
        except TypeError:
            raise ValueError(f'start_cell (row, col) must be integers, got '
                             f'{start_cell!r}') from None
        if not (0 <= row < grid.rows and 0 <= col < grid.cols):
            raise ValueError(f'start cell {tuple(start_cell)} is outside the {grid.rows}x'
                             f'{grid.cols} grid')
        return grid.index(row, col)
    try:
        index = operator.index(start_cell)
    except TypeError:
        raise ValueError(f'start_cell must be a cell index or (row, col), got '
                         f'{start_cell!r}') from None
    if not 0 <= index < grid.n_cells:
        raise ValueError(f'start cell {index} is outside the {grid.rows}x{grid.cols} grid')
    return index


def search_image(image: np.ndarray, fovea: Fovea, model, policy,
                 confidence: float = DEFAULT_CONFIDENCE,
                 max_fixations: int = DEFAULT_MAX_FIXATIONS, stop_on_repeat: bool = True,
                 start_cell=None, rng: np.random.Generator | None = None,
                 inhibit_return: bool = False) -> ImageSearch:
    """
    Search one decoded image with the fovea, the count model and a policy (module docstring).

    Parameters
    ----------
    image : numpy.ndarray
        ``uint8`` grey ``(H, W)`` or RGB ``(H, W, 3)`` (an OpenCV BGR array must be converted
        to RGB first, see :func:`ipomdp_gaze.vision.detector.to_gray`).
    fovea : Fovea
        The digital fovea (its detector, grid and windows); restarted on ``image``.
    model : CountObservation
        The observation model; checked against the fovea with :func:`check_model`.
    policy : object
        ``policy.select(belief, t, rng)`` with ``belief`` of shape ``(1, N)``, returning one
        cell index (an array of one, or a scalar).
    confidence : float
        Stop (``'found'``) when the most likely cell's probability reaches this, in (0, 1).
    max_fixations : int
        Fixation budget (``'budget'``), at least 1.
    stop_on_repeat : bool
        Stop (``'repeat'``) instead of fixating a cell a second time (NMPT's rule).
    inhibit_return : bool
        Never fixate a cell twice: the next fixation is the policy's best unvisited cell
        (:func:`ipomdp_gaze.inhibition.unvisited_choice`). On a static image with a
        deterministic detector a second look repeats the same counts, which the Bayes step
        would count twice; with this on, the search spends its budget on new cells instead.
    start_cell : int or (int, int), optional
        First fixation (index or ``(row, col)``); by default the grid's centre, or with a
        scan the policy's (best unvisited) choice on the scanned belief.
    rng : numpy.random.Generator, optional
        Passed to the policy; ``np.random.default_rng(0)`` by default.

    Raises
    ------
    ValueError
        For a model that does not fit the fovea, a bad image, bad settings, or a policy choice
        outside the grid.

    """
    t0 = time.perf_counter()
    check_model(model, fovea)
    grid = fovea.grid
    confidence = float(confidence)
    if not 0.0 < confidence < 1.0:
        raise ValueError(f'confidence must be strictly between 0 and 1, got {confidence!r}')
    if isinstance(max_fixations, bool) or not isinstance(max_fixations, (int, np.integer)) \
            or max_fixations < 1:
        raise ValueError(f'max_fixations must be an integer >= 1, got {max_fixations!r}')
    fixation = _start_index(grid, start_cell)
    calibrated = calibrated_size(model)
    image_px = check_image(image, fovea)
    rng = np.random.default_rng(0) if rng is None else rng
    fovea.start(image)
    log_belief = uniform_log_belief(grid.n_cells)
    belief = np.exp(log_belief)[None, :]                # what the policy sees: (1, N)
    visited = np.zeros(grid.n_cells, dtype=bool)
    path, pixels = [], 0
    scan = fovea.scan()
    if scan is not None:
        pixels += scan.detector_pixels
        bayes_update(log_belief, model.scan_log_likelihood_ratio(scan.counts), out=log_belief)
        np.exp(log_belief, out=belief[0])
        if start_cell is None:
            fixation = unvisited_choice(policy, belief, visited, 0, rng, grid)
    while True:
        observation = fovea.observe(fixation)
        visited[fixation] = True
        path.append(fixation)
        pixels += observation.detector_pixels
        bayes_update(log_belief, model.log_likelihood_ratio(observation.counts, fixation),
                     out=log_belief)
        np.exp(log_belief, out=belief[0])
        best = int(map_cell(belief[0]))
        if belief[0, best] >= confidence:
            stop = 'found'
            break
        if len(path) >= max_fixations:
            stop = 'budget'
            break
        if inhibit_return:
            if visited.all():
                stop = 'repeat'
                break
            following = unvisited_choice(policy, belief, visited, len(path), rng, grid)
        else:
            following = policy_choice(policy.select(belief, len(path), rng), grid.n_cells)
        if stop_on_repeat and visited[following]:
            stop = 'repeat'
            break
        fixation = following
    cell = tuple(int(v) for v in grid.cell(best))
    pixel = cell_centre_px(grid, best, image_px)
    seconds = time.perf_counter() - t0
    return ImageSearch(cell=cell, pixel=pixel, probability=float(belief[0, best]),
                       fixations=len(path),
                       path=tuple(tuple(int(v) for v in grid.cell(k)) for k in path), stop=stop,
                       detector_pixels=int(pixels), seconds=seconds, belief=belief[0].copy(),
                       image_px=image_px, calibrated_px=calibrated)


def fovea_for_model(model, detector=None, reuse_windows: bool = True) -> Fovea:
    """
    Build the fovea an observation model was measured with: its grid, fovea and detector.

    ``detector`` defaults to :func:`detector_from_settings` of ``meta['detector']``; the fovea
    settings come from ``meta['fovea']`` (the reference :class:`FoveaConfig` if absent).
    ``reuse_windows`` keeps every window's detections per image (the detector is deterministic,
    so this changes the cost, never the counts).

    Raises
    ------
    ValueError
        If the model records neither a detector nor is given one, a record is invalid, or the
        model was calibrated through a pan/tilt camera (``meta['image']['view']``).

    """
    meta = getattr(model, 'meta', {})
    if (meta.get('image') or {}).get('view') == 'pan_tilt':
        raise ValueError('the observation model was calibrated through a pan/tilt camera '
                         '(image view pan_tilt): it describes views of a head camera, not a '
                         'fovea over a still image; use a fixed-view model such as faces-420')
    if detector is None:
        if meta.get('detector') is None:
            raise ValueError('the observation model does not record its detector '
                             '(meta detector); pass one')
        detector = detector_from_settings(dict(meta['detector']))
    config = FoveaConfig() if meta.get('fovea') is None else \
        FoveaConfig.from_dict(dict(meta['fovea']))
    fovea = Fovea(detector, model.grid, config, reuse_windows=reuse_windows,
                  cells=cell_observation_of(meta, config.max_count))
    check_model(model, fovea)
    return fovea


def size_distance(image_px: tuple[int, int], calibrated_px: tuple[int, int]) -> float:
    """How far apart two image sizes are in scale: ``|log(w/w0)| + |log(h/h0)|``."""
    return abs(math.log(image_px[0] / calibrated_px[0])) + \
        abs(math.log(image_px[1] / calibrated_px[1]))
