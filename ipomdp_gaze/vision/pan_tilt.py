# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The pan/tilt face task: a scene a head camera looks around in, its views, and their counts.

Pixels and scenes; the geometry itself (pixel to cell with K and the head pose) is in
:mod:`ipomdp_gaze.model.head_camera` (docs/design.md section 6.5).

**The scene.** :class:`SceneGeometry` is a flat panorama indexed by direction: it spans the
grid's extreme cell centres plus half the camera's field of view on each side, at
``px_per_deg`` pixels per degree (by default the camera's own resolution on its optical axis,
``fx pi / 180``, so things appear at the same size at the centre of a view as in the scene).
:meth:`SceneGeometry.render` draws the view of a head pose with the mapping of
:mod:`ipomdp_gaze.model.head_camera`: view pixel ``(u, v)`` shows the scene in the direction
``(c_h + atan((u - cx) / fx) / spacing, r_h + atan((v - cy) / fy) / spacing)``, so rendering and
binning agree exactly. :class:`PanTiltSceneSet` pastes a face into such a scene, built like
:class:`ipomdp_gaze.vision.scenes.SceneSet` (the same faces, photos and train/test split).

**The detector on the whole view.** :class:`ViewObserver` runs the detector on the whole view
at the camera's resolution, not a digital fovea inside it: with a head, the cost of a fixation
is the saccade (0.15 s in the shipped configuration), so every pixel of a view the head moved
for is worth looking at, and a 320x240 view takes the detector about 25-35 ms on this project's
machine; the fovea's coarse windows would also shrink faces of a few degrees below the
cascade's 20 pixels. A detection's position is the centre of its box ``(x, y, w, h)`` in
OpenCV / ROS pixel coordinates, ``(x + (w - 1) / 2, y + (h - 1) / 2)``.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import os
import re
import time

import cv2
from ipomdp_gaze.model.cell_observation import CellObservation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import bin_points, PinholeCamera, point_offsets
from ipomdp_gaze.vision.detector import (box_centres_px, detect, detector_color,
                                         detector_window_px, group_support,
                                         to_detector_image)
from ipomdp_gaze.vision.image_files import decode_quietly, undecodable
from ipomdp_gaze.vision.scenes import _paste, load_background, load_faces, Scene, SceneFace, SPLITS
import numpy as np

# The shipped pan/tilt face task: an 11x11 grid of 5-degree cells (config/controller.yaml), a
# 320x240 camera with a 25-degree horizontal field of view (5 columns of cells), and faces of
# 30 to 70 pixels (2.4 to 5.5 degrees) in the scene.
PAN_TILT_GRID = Grid(11, 11, 5.0)
CAMERA_SIZE_PX = (320, 240)
CAMERA_HFOV_DEG = 25.0
FACE_PX = (30, 70)
# Faces a room may hold (PanTiltSceneSet's ``faces``), and the draws tried to place each one.
MAX_FACES = 8
_PLACE_TRIES = 1000
VIEW = 'pan_tilt'
_STREAM_TAG = 0x9A4711
_SPLIT_CODE = {'train': 0, 'test': 1}


def shipped_camera() -> PinholeCamera:
    """Return the camera of the shipped pan/tilt face task (320x240, 25-degree wide)."""
    return PinholeCamera.from_fov(*CAMERA_SIZE_PX, CAMERA_HFOV_DEG)


def box_centres_uv(boxes) -> np.ndarray:
    """Centres of boxes ``(M, 4)`` in OpenCV / ROS pixel coordinates, ``(M, 2)`` float64."""
    return box_centres_px(boxes) - 0.5


@dataclass(frozen=True, eq=False)
class ViewObservation:
    """
    The count observation of one view and what it cost.

    Attributes
    ----------
    counts : numpy.ndarray
        ``(N,)`` float64 detections per cell, clipped to ``0..max_count-1``; NaN outside the
        view.
    raw_counts : numpy.ndarray
        ``(N,)`` int64, not clipped.
    head : (float, float)
        The head's grid position ``(row, col)`` the view was binned with.
    centres_uv : numpy.ndarray
        ``(M, 2)`` centres of the raw detections in view pixels.
    cells : numpy.ndarray
        ``(M,)`` cell of each detection, -1 outside the grid.
    detector_pixels : int
        Pixels given to the detector (the whole view).
    seconds : float
        Wall time: grey conversion, detector and binning.
    scores : numpy.ndarray
        ``(M,)`` score of each detection (1 for a detector without scores).
    group_cells : numpy.ndarray
        ``grouped`` cells only: ``(G,)`` cell of each grouped box's centre, -1 off the grid.
    group_support : numpy.ndarray
        ``grouped`` cells only: ``(G,)`` raw boxes each group merged.
    offsets : numpy.ndarray
        ``(N, 2)`` mean offset ``(row, col)`` in cells of the detections centred in each cell
        from its centre, NaN where none (:func:`ipomdp_gaze.model.head_camera.point_offsets`).
    groups : numpy.ndarray or None
        With the observer's ``group_min_neighbors`` > 0: ``(N,)`` how many detections grouped
        as ``detectMultiScale`` groups (with that ``min_neighbors``) are centred in each cell.

    """

    counts: np.ndarray
    raw_counts: np.ndarray
    head: tuple
    centres_uv: np.ndarray
    cells: np.ndarray
    detector_pixels: int
    seconds: float
    scores: np.ndarray = None
    group_cells: np.ndarray = None
    group_support: np.ndarray = None
    offsets: np.ndarray = None
    groups: np.ndarray = None


def view_groups(boxes, min_neighbors: int, camera: PinholeCamera, grid: Grid, head,
                max_count: int, group=None) -> tuple[np.ndarray, np.ndarray]:
    """
    Group a view's raw boxes; return each group's cell and support, the largest box first.

    ``group``: a detector's own rule (``detector.group``, boxes only: support 1 each), else
    :func:`ipomdp_gaze.vision.detector.group_support` as ``detectMultiScale`` groups, on the
    boxes rounded to whole pixels (at least 1 px wide and high; a cascade's boxes are already
    whole). A group's centre is binned as a detection's (-1 off the grid).
    """
    if callable(group):
        grouped = np.asarray(group(boxes, min_neighbors), dtype=np.float64).reshape(-1, 4)
        support = np.ones(len(grouped), dtype=np.int64)
    else:
        boxes = np.round(np.asarray(boxes, dtype=np.float64).reshape(-1, 4))
        boxes[:, 2:] = np.maximum(boxes[:, 2:], 1.0)
        grouped, support = group_support(boxes, min_neighbors)
    if not len(grouped):
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    order = np.argsort(-(grouped[:, 2] * grouped[:, 3]), kind='stable')
    _, _, cells = bin_points(box_centres_uv(grouped[order]), camera, grid, head, max_count)
    return cells, support[order]


class ViewObserver:
    """
    Count detections of one view per pan/tilt grid cell (the detector on the whole view).

    Parameters
    ----------
    detector : callable
        ``detector(image) -> (M, 5)`` raw boxes with scores, or ``(M, 4)``, in the colour space
        it declares (:mod:`ipomdp_gaze.vision.detector`).
    grid : Grid
        The pan/tilt grid (its ``spacing_deg`` matters).
    max_count : int
        K: counts are clipped to ``0..K-1``.
    cells : CellObservation, optional
        What a cell's observation is (default: the clipped count); its K must be ``max_count``.
    group_min_neighbors : int
        > 0: also count each view's detections grouped with this ``min_neighbors`` per cell
        (``ViewObservation.groups``, what a many-target pass answers; docs/design.md section
        11.7); 0: not.

    """

    def __init__(self, detector, grid: Grid, max_count: int = 10,
                 cells: CellObservation | None = None, group_min_neighbors: int = 0):
        if not callable(detector):
            raise ValueError(f'detector must be callable, got {type(detector).__name__}')
        if isinstance(max_count, bool) or int(max_count) != max_count or max_count < 2:
            raise ValueError(f'max_count must be an int >= 2, got {max_count!r}')
        self.detector = detector
        self.grid = grid
        self.max_count = int(max_count)
        self.cells = CellObservation('counts', self.max_count) if cells is None else cells
        if not isinstance(self.cells, CellObservation) or self.cells.max_count != self.max_count:
            raise ValueError(f'cells must be a CellObservation with K = max_count '
                             f'({self.max_count}), got {self.cells!r}')
        if isinstance(group_min_neighbors, bool) or int(group_min_neighbors) != \
                group_min_neighbors or group_min_neighbors < 0:
            raise ValueError(f'group_min_neighbors must be an int >= 0, got '
                             f'{group_min_neighbors!r}')
        self.group_min_neighbors = int(group_min_neighbors)
        self._color = detector_color(detector)

    def observe(self, image: np.ndarray, camera: PinholeCamera, head_rc) -> ViewObservation:
        """
        Detect in a view taken with the head at ``head_rc`` and bin the detections to cells.

        Raises
        ------
        ValueError
            If the image is not a grey or RGB ``uint8`` image of the camera's size, or is
            smaller than the detector's window.

        """
        t0 = time.perf_counter()
        pixels = to_detector_image(image, self._color, detector_window_px(self.detector))
        if pixels.shape[:2] != (camera.height, camera.width):
            raise ValueError(f'the image is {pixels.shape[1]}x{pixels.shape[0]} px but '
                             f'camera_info says {camera.width}x{camera.height}')
        boxes, scores = detect(self.detector, pixels)
        centres = box_centres_uv(boxes)
        head = (float(head_rc[0]), float(head_rc[1]))
        counts, raw, cells = bin_points(centres, camera, self.grid, head, self.max_count)
        group_cells = group_support = groups = None
        if self.cells.kind == 'grouped':
            group_cells, group_support = view_groups(boxes, self.cells.min_neighbors, camera,
                                                     self.grid, head, self.max_count)
            kept = group_cells >= 0
            groups = (group_cells[kept], group_support[kept])
        if self.cells.kind != 'counts':
            inside = cells >= 0
            values = self.cells.values(cells[inside], scores[inside], self.grid.n_cells,
                                       groups)
            counts = np.where(np.isnan(counts), np.nan, values)
        per_cell = None
        if self.group_min_neighbors:
            found, _ = view_groups(boxes, self.group_min_neighbors, camera, self.grid, head,
                                   self.max_count, getattr(self.detector, 'group', None))
            per_cell = np.bincount(found[found >= 0], minlength=self.grid.n_cells).astype(float)
        return ViewObservation(counts, raw, head, centres, cells,
                               int(pixels.shape[0] * pixels.shape[1]),
                               time.perf_counter() - t0, scores, group_cells, group_support,
                               point_offsets(centres, camera, self.grid, head), per_cell)


@dataclass(frozen=True)
class SceneGeometry:
    """
    A panorama a pan/tilt camera looks around in (module docstring).

    Parameters
    ----------
    grid : Grid
        The pan/tilt grid.
    camera : PinholeCamera
        The camera on the head.
    px_per_deg : float, optional
        Scene pixels per degree (default: the camera's at its optical axis, ``fx pi / 180``).

    """

    grid: Grid
    camera: PinholeCamera
    px_per_deg: float | None = None

    def __post_init__(self):
        ppd = self.camera.fx * math.pi / 180 if self.px_per_deg is None else \
            float(self.px_per_deg)
        if not math.isfinite(ppd) or ppd <= 0:
            raise ValueError(f'px_per_deg must be > 0, got {ppd!r}')
        object.__setattr__(self, 'px_per_deg', float(ppd))

    @property
    def half_span_deg(self) -> tuple[float, float]:
        """Half the scene's width and height in degrees: grid reach plus half the view."""
        hfov, vfov = self.camera.fov_deg
        g = self.grid
        return ((g.cols - 1) / 2 * g.spacing_deg + hfov / 2,
                (g.rows - 1) / 2 * g.spacing_deg + vfov / 2)

    @property
    def size_px(self) -> tuple[int, int]:
        """``(width, height)`` of the scene in pixels."""
        half_w, half_h = self.half_span_deg
        return (int(math.ceil(2 * half_w * self.px_per_deg)),
                int(math.ceil(2 * half_h * self.px_per_deg)))

    def to_dict(self) -> dict:
        """Plain types for YAML: grid, camera and pixels per degree."""
        return {'grid': {'rows': self.grid.rows, 'cols': self.grid.cols,
                         'spacing_deg': self.grid.spacing_deg},
                'camera': self.camera.to_dict(), 'px_per_deg': self.px_per_deg}

    @classmethod
    def from_dict(cls, data: dict) -> SceneGeometry:
        """Inverse of :meth:`to_dict`."""
        g = data['grid']
        return cls(Grid(g['rows'], g['cols'], g['spacing_deg']),
                   PinholeCamera.from_dict(data['camera']), data['px_per_deg'])

    def _origin_deg(self) -> tuple[float, float]:
        """Direction ``(x, y)`` in degrees from the grid centre of the scene's top-left corner."""
        half_w, half_h = self.half_span_deg
        return -half_w, -half_h

    def direction_deg(self, row, col):
        """Direction ``(x, y)`` in degrees from the grid centre of grid position ``(row, col)``."""
        g = self.grid
        return ((np.asarray(col, dtype=float) - (g.cols - 1) / 2) * g.spacing_deg,
                (np.asarray(row, dtype=float) - (g.rows - 1) / 2) * g.spacing_deg)

    def point_position(self, x, y):
        """Grid position ``(row, col)`` (not rounded) of scene point ``(x, y)`` (pixel corners)."""
        x0, y0 = self._origin_deg()
        g = self.grid
        return ((y0 + np.asarray(y, dtype=float) / self.px_per_deg) / g.spacing_deg
                + (g.rows - 1) / 2,
                (x0 + np.asarray(x, dtype=float) / self.px_per_deg) / g.spacing_deg
                + (g.cols - 1) / 2)

    def cell_of_point(self, x: float, y: float) -> tuple[int, int]:
        """
        Nearest cell ``(row, col)`` of scene point ``(x, y)`` (e.g. a face centre).

        Raises
        ------
        ValueError
            If the point's direction is outside the grid.

        """
        row, col = self.point_position(x, y)
        r, c = int(math.floor(row + 0.5)), int(math.floor(col + 0.5))
        if not (0 <= r < self.grid.rows and 0 <= c < self.grid.cols):
            raise ValueError(f'scene point ({x}, {y}) looks at grid position ({row:.2f}, '
                             f'{col:.2f}), outside the {self.grid.rows}x{self.grid.cols} grid')
        return r, c

    def grid_area_px(self) -> tuple[float, float, float, float]:
        """Scene points ``x0 <= x < x1, y0 <= y < y1`` whose nearest cell is in the grid."""
        x0, y0 = self._origin_deg()
        g = self.grid
        left, top = self.direction_deg(-0.5, -0.5)
        right, bottom = self.direction_deg(g.rows - 0.5, g.cols - 0.5)
        ppd = self.px_per_deg
        return ((float(left) - x0) * ppd, (float(right) - x0) * ppd,
                (float(top) - y0) * ppd, (float(bottom) - y0) * ppd)

    def view_maps(self, head_rc) -> tuple[np.ndarray, np.ndarray]:
        """``cv2.remap`` maps ``(H, W)`` float32: the scene pixel each view pixel shows."""
        cam = self.camera
        du, dv = cam.angles_deg(np.arange(cam.width), np.arange(cam.height))
        head_x, head_y = self.direction_deg(head_rc[0], head_rc[1])
        x0, y0 = self._origin_deg()
        xs = ((head_x + du - x0) * self.px_per_deg - 0.5).astype(np.float32)
        ys = ((head_y + dv - y0) * self.px_per_deg - 0.5).astype(np.float32)
        return (np.broadcast_to(xs[None, :], (cam.height, cam.width)).copy(),
                np.broadcast_to(ys[:, None], (cam.height, cam.width)).copy())

    def render(self, scene: np.ndarray, head_rc) -> np.ndarray:
        """
        Draw the view of a head at grid position ``head_rc`` (bilinear, edges replicated).

        Raises
        ------
        ValueError
            If ``scene`` is not a ``uint8`` grey or RGB image of :attr:`size_px`.

        """
        if not isinstance(scene, np.ndarray) or scene.dtype != np.uint8 or \
                scene.ndim not in (2, 3):
            raise ValueError('the scene must be a uint8 grey or RGB image')
        if (scene.shape[1], scene.shape[0]) != self.size_px:
            raise ValueError(f'the scene is {scene.shape[1]}x{scene.shape[0]} px, the geometry '
                             f'needs {self.size_px[0]}x{self.size_px[1]}')
        map_x, map_y = self.view_maps(head_rc)
        return cv2.remap(scene, map_x, map_y, cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)


# A room's face count as text: K or LO-HI in ASCII digits.
FACES_TEXT = re.compile(r'([0-9]+)(?:-([0-9]+))?')


def parse_faces(value) -> tuple[int, int]:
    """
    Return a room's face count as ``(lo, hi)``: an int K, a pair, or the text ``K`` / ``LO-HI``.

    The text is ASCII digits only: ``int`` alone would also take ``'+2'``, ``'0_2'`` and the
    digits of other scripts (Arabic-Indic ones).

    Raises
    ------
    ValueError
        Unless ``0 <= lo <= hi <= MAX_FACES`` (one line naming the value).

    """
    text = value.strip() if isinstance(value, str) else value
    try:
        if isinstance(text, str):
            match = FACES_TEXT.fullmatch(text)
            if match is None:
                raise ValueError
            lo, hi = match.groups()
            pair = (int(lo), int(hi if hi is not None else lo))
        elif isinstance(text, (tuple, list)):
            pair = tuple(text)
            if len(pair) != 2:
                raise ValueError
        else:
            pair = (text, text)
        if any(isinstance(v, bool) or int(v) != v for v in pair):
            raise ValueError
        lo, hi = (int(v) for v in pair)
    except (TypeError, ValueError):
        lo = hi = -1
    if not 0 <= lo <= hi <= MAX_FACES:
        raise ValueError(f'faces must be a count K or a range LO-HI with 0 <= LO <= HI <= '
                         f'{MAX_FACES}, got {value!r}')
    return lo, hi


class PanTiltSceneSet:
    """
    Deterministic scenes of the pan/tilt task: a photo crop with faces inside the grid's reach.

    Scene ``i`` is drawn from its own stream ``default_rng([tag, split, seed, i])``, from the
    faces and photos of ``split`` (the split of :mod:`ipomdp_gaze.vision.scenes`: calibrate and
    train on ``'train'`` only). The face, ``face_px`` pixels on a side, is pasted with feathered
    edges so that its centre's nearest cell is inside the grid (anywhere in it, uniformly); the
    scene is ``geometry.size_px`` and RGB (``color='rgb'``) or grey.

    **Rooms** (``faces`` K or ``(lo, hi)``, default 1: the scenes above, bit for bit). A range
    draws the scene's count uniformly in ``lo..hi`` from the same stream, after the seven draws
    of a one-face scene; a count of 0 is the empty crop (``empty``), and the first face is the
    one-face scene's. Each further face (another face of the split, its own size and place,
    drawn the same way) is redrawn until its square overlaps no face already pasted. A scene
    with K faces has them all in :attr:`Scene.faces`, the first also as its ``cell``.
    """

    def __init__(self, split: str = 'test', geometry: SceneGeometry | None = None,
                 face_px: tuple[int, int] = FACE_PX, color: str = 'rgb', seed: int = 0,
                 empty: bool = False, faces=1):
        if split not in SPLITS:
            raise ValueError(f'unknown split {split!r}; expected one of {tuple(SPLITS)}')
        self.split = split
        self.geometry = SceneGeometry(PAN_TILT_GRID, shipped_camera()) if geometry is None \
            else geometry
        lo, hi = (int(v) for v in face_px)
        width, height = self.geometry.size_px
        if not 1 <= lo <= hi or hi > min(width, height):
            raise ValueError(f'face_px must be 1 <= min <= max <= the scene side, got {face_px}')
        self.face_px = (lo, hi)
        if color not in ('rgb', 'gray'):
            raise ValueError(f"color must be 'rgb' or 'gray', got {color!r}")
        self.color = color
        if isinstance(seed, bool) or int(seed) != seed or seed < 0:
            raise ValueError(f'seed must be a non-negative integer, got {seed!r}')
        self.seed = int(seed)
        self.empty = bool(empty)
        self.room = parse_faces(faces)
        if self.empty and self.room != (1, 1):
            raise ValueError('an empty set has no faces: give faces=0 instead of empty=True')
        self.faces, self.backgrounds = SPLITS[split]

    def kwargs(self) -> dict:
        """Keyword arguments that rebuild this set (for worker processes)."""
        return {'split': self.split, 'geometry': self.geometry.to_dict(),
                'face_px': self.face_px, 'color': self.color, 'seed': self.seed,
                'empty': self.empty, 'faces': self.room}

    @classmethod
    def from_kwargs(cls, kwargs: dict) -> PanTiltSceneSet:
        """Inverse of :meth:`kwargs`."""
        values = dict(kwargs)
        values['geometry'] = SceneGeometry.from_dict(values['geometry'])
        return cls(**values)

    def scene(self, index: int) -> Scene:
        """
        Build scene ``index``; its ``cell`` is the face centre's cell on the pan/tilt grid.

        An ``empty`` set's scene ``index`` is the same photo crop with no face (``cell`` None):
        "nobody is here" on the backgrounds the faces are searched on.
        """
        index = int(index)
        if index < 0:
            raise IndexError(f'scene indices are non-negative, got {index}')
        rng = np.random.default_rng([_STREAM_TAG, _SPLIT_CODE[self.split], self.seed, index])
        u_bg, u_top, u_left, u_face, u_size, u_x, u_y = rng.random(7)
        geometry = self.geometry
        width, height = geometry.size_px
        name = self.backgrounds[_pick(u_bg, len(self.backgrounds))]
        photo = load_background(name, self.color, min_side=max(width, height))
        top = _pick(u_top, photo.shape[0] - height + 1)
        left = _pick(u_left, photo.shape[1] - width + 1)
        image = photo[top:top + height, left:left + width].copy()
        lo, hi = self.room
        count = lo if lo == hi else lo + _pick(rng.random(), hi - lo + 1)
        if self.empty or count == 0:
            image.setflags(write=False)
            return Scene(image, None, None, None, None, name, self.seed, index)
        placed = [self._face(u_face, u_size, u_x, u_y)]
        for _ in range(count - 1):
            for _ in range(_PLACE_TRIES):
                face = self._face(*rng.random(4))
                if face[0] not in [f[0] for f in placed] and \
                        not any(_overlap(face, f) for f in placed):
                    placed.append(face)
                    break
            else:
                raise ValueError(f'could not place {count} non-overlapping faces in scene '
                                 f'{index}')
        faces = []
        for face_index, side, x0, y0 in placed:
            _paste(image, load_faces()[face_index], y0, x0, side, 0.15)
            centre = (x0 + side / 2.0, y0 + side / 2.0)
            faces.append(SceneFace(centre, side, geometry.cell_of_point(*centre),
                                   int(face_index)))
        image.setflags(write=False)
        first = faces[0]
        return Scene(image, first.centre_px, first.side_px, first.cell, first.face_index, name,
                     self.seed, index, tuple(faces))

    def _face(self, u_face: float, u_size: float, u_x: float, u_y: float) -> tuple:
        """``(face_index, side, x0, y0)`` of a face drawn from four uniform draws."""
        geometry = self.geometry
        width, height = geometry.size_px
        face_index = self.faces[_pick(u_face, len(self.faces))]
        lo, hi = self.face_px
        side = lo + _pick(u_size, hi - lo + 1)
        x_lo, x_hi, y_lo, y_hi = geometry.grid_area_px()
        # Top-left corners whose face centre (x0 + side / 2) lies in the grid's area.
        x0_min, x0_max = _corner_range(x_lo, x_hi, side, width)
        y0_min, y0_max = _corner_range(y_lo, y_hi, side, height)
        x0 = x0_min + _pick(u_x, x0_max - x0_min + 1)
        y0 = y0_min + _pick(u_y, y0_max - y0_min + 1)
        return int(face_index), int(side), int(x0), int(y0)


def _overlap(a: tuple, b: tuple) -> bool:
    """Whether two pasted squares ``(face, side, x0, y0)`` share a pixel."""
    return (a[2] < b[2] + b[1] and b[2] < a[2] + a[1]
            and a[3] < b[3] + b[1] and b[3] < a[3] + a[1])


def _corner_range(lo: float, hi: float, side: int, size: int) -> tuple[int, int]:
    """Integer corners ``x0`` with ``lo <= x0 + side / 2 < hi`` and the face inside the image."""
    first = max(int(math.ceil(lo - side / 2.0)), 0)
    last = min(int(math.ceil(hi - side / 2.0)) - 1, size - side)
    if first > last:
        raise ValueError(f'a face of {side} px does not fit the grid area of the scene')
    return first, last


def _pick(u: float, n: int) -> int:
    """Map a uniform draw in ``[0, 1)`` to an integer in ``0..n-1``."""
    return min(int(u * n), n - 1)


# A user's image whose aspect ratio is within this (relative) of the pan/tilt scene's is resized
# to fill it (faces at most 2% narrower or wider, as calibrate --resize takes); another is fitted
# inside, its aspect kept, on this grey.
SCENE_ASPECT_TOL = 0.02
SCENE_PAD_GREY = 128


def read_scene_file(path) -> np.ndarray:
    """
    Read a user's scene image as ``uint8`` RGB ``(H, W, 3)`` (grey files are replicated).

    Raises
    ------
    ValueError
        If the file is missing, cannot be decoded or is not 8 bits per channel.

    """
    # Read as find reads (image_files): OpenCV's own messages silenced, and a truncated JPEG,
    # which cv2.imread shows as its top part above grey, refused with the reason.
    if not os.path.isfile(path):
        raise ValueError(f'scene.file {str(path)!r} is missing or not an image OpenCV can read')
    data = np.fromfile(str(path), dtype=np.uint8)
    try:
        image = decode_quietly(data) if data.size else None   # imdecode asserts on no bytes
    except ValueError as exc:
        raise ValueError(f'scene.file {str(path)!r}: {exc}') from None
    if image is None:
        raise ValueError(f'scene.file {str(path)!r}: {undecodable(data)}')
    if image.dtype != np.uint8:
        raise ValueError(f'scene.file {str(path)!r} is {image.dtype}; 8 bits per channel only')
    if image.ndim == 2:
        return np.repeat(image[:, :, None], 3, axis=2)
    if image.shape[2] == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2RGB)
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


def _fit_scene(image: np.ndarray, centre, size: tuple[int, int]) -> tuple:
    """Return ``image`` fitted to ``size`` (:func:`user_scene`) and ``centre`` mapped with it."""
    height, width = image.shape[:2]
    if (width, height) == size:
        return image, centre
    sx, sy = size[0] / width, size[1] / height
    if abs(sx / sy - 1.0) <= SCENE_ASPECT_TOL:
        fitted, (x0, y0) = cv2.resize(image, size, interpolation=cv2.INTER_AREA), (0, 0)
    else:
        scale = min(sx, sy)
        inner = (max(1, round(width * scale)), max(1, round(height * scale)))
        sx, sy = inner[0] / width, inner[1] / height
        x0, y0 = (size[0] - inner[0]) // 2, (size[1] - inner[1]) // 2
        fitted = np.full((size[1], size[0]) + image.shape[2:], SCENE_PAD_GREY, image.dtype)
        fitted[y0:y0 + inner[1], x0:x0 + inner[0]] = cv2.resize(
            image, inner, interpolation=cv2.INTER_AREA).reshape(
                (inner[1], inner[0]) + image.shape[2:])
    if centre is not None:
        centre = (x0 + centre[0] * sx, y0 + centre[1] * sy)
    return fitted, centre


def user_scene(image: np.ndarray, face_centre_px, geometry: SceneGeometry | None = None,
               grid=None) -> Scene:
    """
    Make a user's image a scene: for a pan/tilt ``geometry`` fitted to its size, else as is.

    ``face_centre_px`` ``(x, y)`` in the image's pixels (or None) gives the scene's ``cell``: on
    the pan/tilt grid of ``geometry``, or on ``grid`` ``(rows, cols)`` tiling the image.

    An image of the scene's shape (within :data:`SCENE_ASPECT_TOL`) is resized to fill it; one
    of another shape is scaled to fit inside it, its aspect kept, and centred on grey
    (:data:`SCENE_PAD_GREY`): stretched to fill it, a 4:3 photo's faces came out a fifth
    narrower than they are, and the detector's counts are for faces as they are.

    Raises
    ------
    ValueError
        If the face centre is outside the image or its cell outside the grid.

    """
    height, width = image.shape[:2]
    centre = None if face_centre_px is None else tuple(float(v) for v in face_centre_px)
    if centre is not None and not (0 <= centre[0] < width and 0 <= centre[1] < height):
        raise ValueError(f'the face centre {centre} is outside the {width}x{height} image')
    if geometry is not None:
        image, centre = _fit_scene(image, centre, geometry.size_px)
        cell = None if centre is None else geometry.cell_of_point(*centre)
    else:
        from ipomdp_gaze.vision.scenes import cell_of_point
        cell = None if centre is None else \
            cell_of_point(centre[0], centre[1], (height, width), tuple(grid))
    image = np.ascontiguousarray(image)
    image.setflags(write=False)
    return Scene(image, centre, None, cell, None, 'file', 0, 0)
