# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Calibrate a count model from labelled images: the learned FPOC of a real detector and fovea.

Every labelled image is fixated at every cell (docs/design.md section 6), or at a lattice of
cells (:func:`lattice_fixations`) to save detector work. For each fixation k
and each observed cell j, the clipped count ``c_j`` is tallied at the offset
``(|r_j - r_k|, |c_j - c_k|)``: in the target table when j holds the face centre, in the null
table otherwise (every cell of a face-absent image is null). The tables are the tallies with a
Dirichlet(``prior``) prior per offset, ``p(c | offset) = (n_c + prior) / (n + K prior)``.

Target data are sparse: one cell per fixation holds the face, so an image gives each offset at
most a few target tallies, and offsets a face centre never reaches (the far corners) none.
``pool_radius`` pools the target tallies of offsets whose Euclidean distances
``sqrt(dr^2 + dc^2)`` are within that many cells of each other (a radial FPOC, the paper's
assumption), widened where fewer than ``min_tallies`` observations would remain; this trades
angular detail for far less noise.

With a fovea that scans once (``scan_once``) the whole-image windows are tallied apart, once per
image and without an offset (the scan does not depend on the fixation): ``scan_target[c]`` from
the cell holding the face centre, ``scan_null[c]`` from every other cell, with the same prior.

The work is one fovea pass per (image, fixation): :func:`tally_images` spreads images over
processes, each with its own detector (OpenCV objects cannot be shared), built by the factory
(:func:`ipomdp_gaze.vision.detectors.detector_from_spec`) from plain settings: ``kind`` (default
``haar``) and the detector's own options.

**What is tallied** is each cell's observation under a :class:`CellObservation` rule (the clipped
count by default; the best score in bins, or the count above a score threshold). Every tally also
keeps the best score of each observed cell holding a detection (:attr:`Tallies.scores`), from
which :func:`choose_edges` picks the bins of a ``score_bins`` rule on training data.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

from ipomdp_gaze.model.cell_observation import CellObservation, quantile_edges
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.vision.detector import DetectorFailed
from ipomdp_gaze.vision.detectors import detector_from_spec
from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig
import numpy as np


@dataclass
class Tallies:
    """Count tallies per offset, ``target[|dr|, |dc|, c]`` and ``null[...]``, and of the scan."""

    target: np.ndarray
    null: np.ndarray
    scan_target: np.ndarray
    scan_null: np.ndarray
    images: int = 0
    fixations: int = 0
    detector_pixels: int = 0
    seconds: float = 0.0
    scores: np.ndarray = None

    def __post_init__(self):
        if self.scores is None:
            self.scores = np.empty(0)

    @classmethod
    def empty(cls, grid: Grid, max_count: int) -> Tallies:
        """Zero tallies for a grid and K = ``max_count``."""
        shape = grid.shape + (max_count,)
        return cls(np.zeros(shape, dtype=np.int64), np.zeros(shape, dtype=np.int64),
                   np.zeros(max_count, dtype=np.int64), np.zeros(max_count, dtype=np.int64))

    def __iadd__(self, other: Tallies) -> Tallies:
        self.target += other.target
        self.null += other.null
        self.scan_target += other.scan_target
        self.scan_null += other.scan_null
        self.images += other.images
        self.fixations += other.fixations
        self.detector_pixels += other.detector_pixels
        self.seconds += other.seconds
        self.scores = np.concatenate([self.scores, other.scores])
        return self


def best_scores(cells, scores, observed=None) -> np.ndarray:
    """
    Return the best score of each cell holding a detection, ``(C,)``, in cell order.

    ``cells`` ``(M,)`` and ``scores`` ``(M,)`` describe the detections; with ``observed``
    (a boolean mask over cells) only those cells count.
    """
    cells = np.asarray(cells, dtype=np.int64)
    scores = np.asarray(scores, dtype=np.float64)
    keep = cells >= 0
    if observed is not None:
        keep &= np.asarray(observed)[np.clip(cells, 0, None)]
    cells, scores = cells[keep], scores[keep]
    if cells.size == 0:
        return np.empty(0)
    order = np.lexsort((-scores, cells))
    first = np.r_[True, cells[order][1:] != cells[order][:-1]]
    return scores[order][first]


def tally_image(fovea: Fovea, image: np.ndarray, target_cell: int | None,
                fixations=None) -> Tallies:
    """
    Tally the clipped counts of one labelled image fixated at ``fixations`` (default: all).

    ``target_cell`` is the cell holding the face centre, or None for a face-absent image.
    """
    grid = fovea.grid
    fixations = np.arange(grid.n_cells) if fixations is None else np.asarray(fixations)
    fovea.start(image)
    scan = fovea.scan()
    frames = np.empty((fixations.size, grid.n_cells))
    scores = [np.empty(0)] if scan is None else [best_scores(scan.cells, scan.scores)]
    for i, k in enumerate(fixations):
        observation = fovea.observe(int(k))
        frames[i] = observation.counts
        scores.append(best_scores(observation.cells, observation.scores,
                                  ~np.isnan(observation.counts)))
    tallies = tally_frames(grid, fovea.config.max_count, frames, fixations, target_cell,
                           None if scan is None else scan.counts)
    tallies.detector_pixels = fovea.image_detector_pixels
    tallies.seconds = fovea.image_seconds
    tallies.scores = np.concatenate(scores)
    return tallies


def tally_frames(grid: Grid, max_count: int, frames: np.ndarray, fixations,
                 target_cell: int | None, scan_counts=None) -> Tallies:
    """
    Tally count frames ``(F, N)`` of one labelled image taken at ``fixations`` ``(F,)``.

    Each observed (not NaN) cell's count goes to its offset ``(|dr|, |dc|)`` from the frame's
    fixation: in the target table for ``target_cell``, in the null table for every other cell.
    ``scan_counts`` ``(N,)``, the image's one-time scan, goes to the offset-free scan tallies.
    """
    rows, cols = grid.shape
    fixations = np.asarray(fixations)
    r, c = grid.rows_cols()
    rk, ck = grid.cell(fixations)
    dr = np.abs(r[None, :] - rk[:, None])
    dc = np.abs(c[None, :] - ck[:, None])
    seen = ~np.isnan(frames)
    counts = np.where(seen, frames, 0).astype(np.intp)
    flat = (dr * cols + dc) * max_count + counts
    is_target = np.zeros(grid.n_cells, dtype=bool)
    if target_cell is not None:
        is_target[int(target_cell)] = True
    size = rows * cols * max_count
    null = np.bincount(flat[seen & ~is_target[None, :]], minlength=size)
    target = np.bincount(flat[seen & is_target[None, :]], minlength=size)
    shape = (rows, cols, max_count)
    scan_target = np.zeros(max_count, dtype=np.int64)
    scan_null = np.zeros(max_count, dtype=np.int64)
    if scan_counts is not None:
        scan_counts = np.asarray(scan_counts).astype(np.intp)
        scan_target = np.bincount(scan_counts[is_target], minlength=max_count)
        scan_null = np.bincount(scan_counts[~is_target], minlength=max_count)
    return Tallies(target.reshape(shape), null.reshape(shape), scan_target, scan_null, images=1,
                   fixations=int(fixations.size))


def _worker_tally(job) -> Tallies:
    """Tally a chunk of images in a worker process (its own detector and fovea)."""
    import cv2
    cv2.setNumThreads(1)
    detector_spec, grid_shape, config, items, fixations, cells, names = job
    config = FoveaConfig.from_dict(config)
    fovea = Fovea(detector_from_spec(detector_spec), grid_shape, config, reuse_windows=True,
                  cells=_cells(cells, config.max_count))
    total = Tallies.empty(fovea.grid, fovea.config.max_count)
    for item, name in zip(items, names):
        image, target = _resolve(item)
        with _failing_on(name):
            total += tally_image(fovea, image, target, fixations)
    return total


@contextmanager
def _failing_on(name: str):
    """Name the image or scene a plug-in detector failed on (its error named only itself)."""
    try:
        yield
    except DetectorFailed as exc:
        raise DetectorFailed(f'{name}: {exc}') from None


def item_name(item, index: int) -> str:
    """Name item ``index`` of :func:`tally_images` when no name is given: its scene or number."""
    if _is_scene(item):
        return f"training scene {item[2]} (seed {item[1]['seed']})"
    return f'image {index + 1}'


def lattice_fixations(grid: Grid, stride: int) -> np.ndarray:
    """
    Cells whose row and column are multiples of ``stride``, plus the last row and column.

    Calibrating from these fixations only still reaches every offset (the target can be
    anywhere) at a fraction of the detector work: windows of neighbouring fixations overlap.
    """
    if isinstance(stride, bool) or not isinstance(stride, (int, np.integer)) or stride < 1:
        raise ValueError(f'the fixation stride must be a positive integer, got {stride!r}')
    rows = np.union1d(np.arange(0, grid.rows, stride), [grid.rows - 1])
    cols = np.union1d(np.arange(0, grid.cols, stride), [grid.cols - 1])
    return (rows[:, None] * grid.cols + cols[None, :]).ravel()


def _cells(cells: dict | None, max_count: int) -> CellObservation:
    """Return the cell observation rule of a job (None: counts clipped at ``max_count``)."""
    return CellObservation('counts', max_count) if cells is None else \
        CellObservation.from_dict(cells)


def choose_edges(tallies: Tallies, max_count: int) -> CellObservation:
    """
    Return the ``score_bins`` rule of K = ``max_count`` whose bins share out the training scores.

    The edges are :func:`ipomdp_gaze.model.cell_observation.quantile_edges` of
    ``tallies.scores`` (the best score of every observed cell holding a detection), ``K - 1``
    bins; a detector with fewer distinct scores gets fewer bins (a smaller K).
    """
    edges = quantile_edges(tallies.scores, max_count - 1)
    return CellObservation('score_bins', len(edges) + 2, edges)


def choose_group_edges(tallies: Tallies, max_count: int, min_neighbors: int,
                       raw_levels: int = 0) -> CellObservation:
    """
    Return the ``grouped`` rule of K = ``max_count`` whose group bins share out training supports.

    ``tallies.scores`` holds the largest group support of every observed cell holding a group
    (tallied with a ``grouped`` rule); :func:`quantile_edges` cuts them into
    ``K - 1 - raw_levels`` bins, fewer when supports repeat (a smaller K).
    """
    edges = quantile_edges(tallies.scores, max_count - 1 - raw_levels)
    return CellObservation('grouped', len(edges) + raw_levels + 2, edges,
                           min_neighbors=min_neighbors, raw_levels=raw_levels)


def _is_scene(item) -> bool:
    return len(item) == 3 and isinstance(item[0], str) and item[0] == 'scene'


def _resolve(item):
    """Return ``(image, target_cell)`` of an item, regenerating ``('scene', kwargs, i)``."""
    if _is_scene(item):
        from ipomdp_gaze.vision.scenes import SceneSet
        scene = SceneSet(**item[1]).scene(item[2])
        if scene.cell is None:
            return scene.image, None
        rows, cols = item[1]['grid']
        return scene.image, scene.cell[0] * cols + scene.cell[1]
    return item


def _run_jobs(worker, jobs: list, total: Tallies, processes: int, progress,
              executor=None) -> Tallies:
    """
    Add ``worker(job)`` of every job to ``total``, on ``executor`` (an executor of ``simulation``).

    Without an executor, ``processes`` local workers (1: here). ``job[3]`` is the job's list of
    images or scenes: ``progress`` gets its length as each job finishes. The parts are added in
    job order, so the tallies are the same wherever the jobs ran.
    """
    from ipomdp_gaze.simulation.executor import make_executor
    own = executor is None
    executor = make_executor(processes) if own else executor
    try:
        futures = []
        for job in jobs:
            future = executor.submit(worker, job)
            if progress:
                future.add_done_callback(
                    lambda f, n=len(job[3]): f.cancelled() or f.exception() or progress(n))
            futures.append(future)
        for future in futures:
            total += future.result()
    except BaseException:
        if own:
            executor.close(cancel=True)
        raise
    if own:
        executor.close()
    return total


def tally_images(items, detector_kwargs: dict, grid: Grid, config: FoveaConfig,
                 processes: int = 2, progress=None, fixations=None, executor=None,
                 cells: CellObservation | None = None, names=None) -> Tallies:
    """
    Tally many labelled images, spread over ``processes`` worker processes.

    Parameters
    ----------
    items : list
        ``(image, target_cell)`` pairs (target None when the image has no face), or
        ``('scene', SceneSet keyword arguments, index)`` triples regenerated in the workers.
    detector_kwargs : dict
        The detector's ``kind`` (default ``haar``) and options
        (:func:`ipomdp_gaze.vision.detectors.detector_from_spec`).
    grid, config
        The grid tiling each image and the fovea.
    processes : int
        Worker processes (1: in this process) when no ``executor`` is given.
    progress : callable, optional
        Called with the number of images done after each chunk.
    fixations : array of int, optional
        The fixated cells of every image (default: all; see :func:`lattice_fixations`).
    executor : optional
        Where the chunks run (:func:`ipomdp_gaze.simulation.executor.make_executor`); the tallies
        do not
        depend on it.
    cells : CellObservation, optional
        What a cell's observation is (default: the clipped count); its K is the fovea's.
    names : list of str, optional
        Each item's name (its file) for the one error line of a plug-in detector that fails on
        it (:class:`~ipomdp_gaze.vision.detector.DetectorFailed`); default :func:`item_name`.

    """
    if names is None:
        names = [item_name(item, i) for i, item in enumerate(items)]
    if len(names) != len(items):
        raise ValueError(f'{len(names)} names for {len(items)} items')
    total = Tallies.empty(grid, config.max_count)
    workers = processes if executor is None else executor.workers
    chunk = max(1, min(8, len(items) // max(1, 4 * workers)))
    rule = None if cells is None else cells.to_dict()
    jobs = [(dict(detector_kwargs), grid.shape, config.to_dict(), items[i:i + chunk], fixations,
             rule, list(names[i:i + chunk])) for i in range(0, len(items), chunk)]
    return _run_jobs(_worker_tally, jobs, total, processes, progress, executor)


def tally_views(observer, geometry, scene_image: np.ndarray, target_cell: int | None,
                fixations=None) -> Tallies:
    """
    Tally one pan/tilt scene viewed with the head at every cell of ``fixations`` (default: all).

    Each view is rendered by ``geometry`` (:class:`ipomdp_gaze.vision.pan_tilt.SceneGeometry`)
    and observed by ``observer`` (:class:`ipomdp_gaze.vision.pan_tilt.ViewObserver`), exactly as
    the ``scene_camera`` and ``foveal_detector`` nodes do; cells outside a view are not tallied.
    ``scores`` keeps each observed cell's best score, or with ``grouped`` cells its best group
    support (what :func:`choose_group_edges` bins).
    """
    grid = observer.grid
    fixations = np.arange(grid.n_cells) if fixations is None else np.asarray(fixations)
    frames = np.empty((fixations.size, grid.n_cells))
    pixels, seconds, scores = 0, 0.0, [np.empty(0)]
    for i, k in enumerate(fixations):
        view = geometry.render(scene_image, grid.cell(int(k)))
        with _failing_on(f'the view at cell {tuple(int(v) for v in grid.cell(int(k)))}'):
            observation = observer.observe(view, geometry.camera, grid.cell(int(k)))
        frames[i] = observation.counts
        pixels += observation.detector_pixels
        seconds += observation.seconds
        if observation.group_support is None:
            scores.append(best_scores(observation.cells, observation.scores,
                                      ~np.isnan(observation.counts)))
        else:
            scores.append(best_scores(observation.group_cells, observation.group_support,
                                      ~np.isnan(observation.counts)))
    tallies = tally_frames(grid, observer.max_count, frames, fixations, target_cell)
    tallies.detector_pixels, tallies.seconds = pixels, seconds
    tallies.scores = np.concatenate(scores)
    return tallies


def _worker_tally_views(job) -> Tallies:
    """Tally pan/tilt scenes in a worker process (its own detector)."""
    import cv2
    from ipomdp_gaze.model.head_camera import observed_cells
    from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, ViewObserver
    cv2.setNumThreads(1)
    detector_spec, max_count, scene_kwargs, indices, null_scenes, cells = job
    scenes = PanTiltSceneSet.from_kwargs(scene_kwargs)
    geometry = scenes.geometry
    grid = geometry.grid
    observer = ViewObserver(detector_from_spec(detector_spec), grid, max_count,
                            _cells(cells, max_count))
    total = Tallies.empty(grid, max_count)
    poses = np.arange(grid.n_cells)
    for index in indices:
        scene = scenes.scene(index)
        target = grid.index(*scene.cell)
        with _failing_on(f'pan/tilt training scene {index} (seed {scenes.seed})'):
            if index < null_scenes:
                total += tally_views(observer, geometry, scene.image, target)
                continue
            sees = [k for k in poses
                    if observed_cells(geometry.camera, grid, grid.cell(int(k)))[target]]
            part = tally_views(observer, geometry, scene.image, target, sees)
        part.null[...] = 0
        total += part
    return total


def tally_pan_tilt_scenes(scenes, indices, detector_kwargs: dict, max_count: int,
                          null_scenes: int | None = None, processes: int = 2,
                          progress=None, executor=None,
                          cells: CellObservation | None = None) -> Tallies:
    """
    Tally pan/tilt scenes, the head at every pose, in worker processes.

    The target tables need many faces and only the views that show the face; the null tables
    need many views but few scenes. So scene ``i`` of ``indices`` is viewed from every pose (all
    its cells tallied) when ``i < null_scenes``, and otherwise only from the poses whose view
    shows the face's cell, of which only the face's cell is tallied. Both tables stay unbiased
    (every tally of a table is taken under the same rule for every scene it uses), and the
    calibration costs a fraction of viewing every scene from every pose.

    Parameters
    ----------
    scenes : PanTiltSceneSet
        The scenes (regenerated in the workers from :meth:`PanTiltSceneSet.kwargs`).
    indices : sequence of int
        Which scenes.
    detector_kwargs : dict
        The detector's ``kind`` (default ``haar``) and options.
    max_count : int
        K.
    null_scenes : int, optional
        Scene indices below this are viewed from every pose (default: all of them).
    processes : int
        Worker processes (1: in this process) when no ``executor`` is given.
    progress : callable, optional
        Called with the number of scenes done after each chunk.
    executor : optional
        Where the chunks run (:func:`ipomdp_gaze.simulation.executor.make_executor`).
    cells : CellObservation, optional
        What a cell's observation is (default: the clipped count); its K must be ``max_count``.

    """
    indices = [int(i) for i in indices]
    null_scenes = max(indices, default=0) + 1 if null_scenes is None else int(null_scenes)
    grid = scenes.geometry.grid
    total = Tallies.empty(grid, max_count)
    workers = processes if executor is None else executor.workers
    chunk = max(1, min(4, len(indices) // max(1, 4 * workers)))
    rule = None if cells is None else cells.to_dict()
    jobs = [(dict(detector_kwargs), int(max_count), scenes.kwargs(), indices[i:i + chunk],
             null_scenes, rule) for i in range(0, len(indices), chunk)]
    return _run_jobs(_worker_tally_views, jobs, total, processes, progress, executor)


def pool_target(tallies: np.ndarray, pool_radius: float, min_tallies: int = 0) -> np.ndarray:
    """
    Pool the target tallies of offsets at similar Euclidean distances from the fixation.

    Each offset sums the tallies of every offset whose distance ``sqrt(dr^2 + dc^2)`` is within
    ``pool_radius`` cells of its own; where that holds fewer than ``min_tallies`` observations
    the radius grows in half-cell steps until it does (offsets a face never reaches, such as
    the far corners, borrow from the nearest distances that have data).
    """
    rows, cols, _ = tallies.shape
    flat = tallies.reshape(rows * cols, -1).astype(float)
    if pool_radius <= 0 and min_tallies <= 0:
        return flat.reshape(tallies.shape)
    dr, dc = np.meshgrid(np.arange(rows), np.arange(cols), indexing='ij')
    dist = np.hypot(dr, dc).reshape(-1)
    gap = np.abs(dist[:, None] - dist[None, :])                          # (RC, RC)
    pooled = np.full_like(flat, np.nan)
    radius = max(pool_radius, 0.0)
    while np.isnan(pooled[:, 0]).any():
        candidate = (gap <= radius + 1e-9).astype(float) @ flat
        enough = np.isnan(pooled[:, 0]) & ((candidate.sum(axis=1) >= min_tallies)
                                           | (radius > dist.max()))
        pooled[enough] = candidate[enough]
        radius += 0.5
    return pooled.reshape(tallies.shape)


def count_model(tallies: Tallies, grid: Grid, prior: float = 1.0, pool_radius: float = 0.5,
                min_tallies: int = 50, meta: dict | None = None,
                scan: bool = False) -> CountObservation:
    """
    Build the count model: Dirichlet(``prior``) estimates, target tallies pooled radially.

    An offset never observed at all (no target and no null tally: outside a pan/tilt camera's
    view) gets the same table for both hypotheses, so it adds nothing to the belief or to ELM.

    With ``scan`` the model also gets the scan tables, from the scan tallies with the same prior.

    Raises
    ------
    ValueError
        For a prior that is not positive or tallies with no target observation at all.

    """
    if not np.isfinite(prior) or prior <= 0:
        raise ValueError(f'prior must be a positive number, got {prior!r}')
    if tallies.target.sum() == 0:
        raise ValueError('no labelled face was observed: the target table would be the prior')
    target = pool_target(tallies.target, pool_radius, min_tallies) + prior
    null = tallies.null.astype(float) + prior
    target /= target.sum(axis=2, keepdims=True)
    null /= null.sum(axis=2, keepdims=True)
    # An offset no frame ever observed (outside a pan/tilt camera's view) says nothing.
    unseen = (tallies.target.sum(axis=2) == 0) & (tallies.null.sum(axis=2) == 0)
    target[unseen] = null[unseen]
    scan_target = scan_null = None
    if scan:
        if tallies.scan_null.sum() == 0:
            raise ValueError('scan tables asked for, but no scan was tallied (fovea scan_once '
                             'false)')
        scan_target = (tallies.scan_target + prior) / (tallies.scan_target.sum()
                                                       + prior * tallies.scan_target.size)
        scan_null = (tallies.scan_null + prior) / (tallies.scan_null.sum()
                                                   + prior * tallies.scan_null.size)
    return CountObservation(grid, target, null, meta, scan_target, scan_null)


def hit_false_alarm(model: CountObservation) -> tuple[np.ndarray, np.ndarray]:
    """
    ``P(c > 0 | target, offset)`` and ``P(c > 0 | no target, offset)``, each (rows, cols).

    Offsets whose two tables are the same (never observed, e.g. outside a pan/tilt camera's
    view) are NaN in both.
    """
    same = np.all(model.p_target == model.p_null, axis=2)
    return (np.where(same, np.nan, 1.0 - model.p_target[:, :, 0]),
            np.where(same, np.nan, 1.0 - model.p_null[:, :, 0]))
