# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Scenes from real photos with one known face, for calibration, training and testing (section 6).

Every ingredient ships inside the scikit-image wheel, so scenes are built offline and are the
same on every machine: the faces are the first 100 crops of :func:`skimage.data.lfw_subset` (25x25
grey; the last 100 crops are non-faces and are not used) and the backgrounds are photos from
:mod:`skimage.data` that contain no face. A scene is a random crop of a background with one face,
upscaled to a random size, pasted with feathered edges at a random position fully inside the image.

**The split** (docs/design.md section 6). ``split='train'`` draws faces 0-59 and the backgrounds
:data:`TRAIN_BACKGROUNDS`; it is the only split to calibrate or train on. ``split='test'`` draws
faces 60-99 and :data:`TEST_BACKGROUNDS` and is for measuring only: nothing may be fitted to it.

**Determinism.** Scene ``i`` of a :class:`SceneSet` depends only on the set's parameters, its seed
and ``i``: it is drawn from its own stream ``np.random.default_rng([tag, split, seed, i])``, so it
does not matter which other scenes were made, or in which order. Every scene takes the same
eight uniform draws in the same order (absent?, background, crop row, crop column, face, face
size, paste row, paste column), so sets that differ only in ``color`` have the same layout, and
raising ``absent_rate`` only removes faces from more scenes (a lower rate's absent scenes stay
absent).

**Pixel coordinates.** An image of ``H x W`` pixels spans ``[0, W) x [0, H)``: pixel ``(r, c)``
covers ``[c, c+1) x [r, r+1)``, as OpenCV's boxes do (a box ``(x, y, w, h)`` has its centre at
``(x + w/2, y + h/2)``). A face pasted on rows ``y0..y0+s-1`` and columns ``x0..x0+s-1`` therefore
has its centre at ``(x0 + s/2, y0 + s/2)``, and a point ``(x, y)`` lies in cell
``(floor(y * rows / H), floor(x * cols / W))`` of a ``rows x cols`` grid tiling the image.

**Colour.** Arrays are ``uint8``, RGB ``(H, W, 3)`` in memory with ``color='rgb'`` or grey
``(H, W)`` with ``color='gray'``. Grey backgrounds are replicated to three channels in RGB mode
and RGB ones converted with ``cv2.COLOR_RGB2GRAY`` in grey mode; the faces are grey and are
pasted into all three channels. Files are read and written with OpenCV, which stores BGR:
:func:`write_scene_set` and :func:`read_labelled_folder` convert, so callers only ever see RGB.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
import math
from pathlib import Path
from typing import Iterator, NamedTuple

import cv2
from ipomdp_gaze.model.checks import positive_int as _positive_int
import numpy as np

TRAIN_FACES = range(0, 60)
TEST_FACES = range(60, 100)
# `camera` (the cameraman) holds a real face: it is in the real-photo set
# (ipomdp_gaze.vision.photos), no longer a training background (docs/design.md section 6).
TRAIN_BACKGROUNDS = ('grass', 'brick', 'coffee', 'rocket', 'coins', 'immunohistochemistry')
TEST_BACKGROUNDS = ('gravel', 'chelsea', 'hubble_deep_field', 'retina', 'cell', 'moon', 'page')
SPLITS = {'train': (TRAIN_FACES, TRAIN_BACKGROUNDS), 'test': (TEST_FACES, TEST_BACKGROUNDS)}
COLORS = ('gray', 'rgb')
# The paper's task and the small/mixed-size task: keyword arguments for SceneSet.
PAPER_TASK = {'size_px': 420, 'face_px': (60, 140)}
SMALL_TASK = {'size_px': 840, 'face_px': (24, 140)}
DEFAULT_FEATHER = 0.15
# First word of every scene stream: keeps scene streams apart from other users of the same seed.
_STREAM_TAG = 0x5CE7E5
_SPLIT_CODE = {'train': 0, 'test': 1}
_N_DRAWS = 8
_N_FACES = 100

_faces: np.ndarray | None = None
_backgrounds: dict[tuple[str, str, int], np.ndarray] = {}
_masks: dict[tuple[int, float], np.ndarray] = {}


def load_faces() -> np.ndarray:
    """
    Return the 100 faces of ``lfw_subset`` as read-only ``float32`` grey levels in ``[0, 255]``.

    Loaded once per process (lazily, on first use) and shared. Shape ``(100, 25, 25)``; index
    ``k`` is face ``k`` of the split tables :data:`TRAIN_FACES` and :data:`TEST_FACES`.
    """
    global _faces
    if _faces is None:
        from skimage import data
        crops = data.lfw_subset()
        faces = (np.asarray(crops[:_N_FACES], dtype=np.float32) * 255.0)
        faces.setflags(write=False)
        _faces = faces
    return _faces


def load_background(name: str, color: str = 'gray', min_side: int = 0) -> np.ndarray:
    """
    Return the scikit-image photo ``name`` as read-only ``uint8``, grey or RGB.

    Parameters
    ----------
    name : str
        One of :data:`TRAIN_BACKGROUNDS` or :data:`TEST_BACKGROUNDS`.
    color : {'gray', 'rgb'}
        Grey photos are replicated to three channels for ``'rgb'``; RGB photos are converted with
        ``cv2.COLOR_RGB2GRAY`` for ``'gray'``.
    min_side : int
        If the shorter side is below this, the photo is upscaled (bicubic, aspect preserved) so
        that its shorter side is exactly ``min_side``: a scene is a crop of it.

    Cached per ``(name, color, min_side)`` for the life of the process.

    """
    if name not in TRAIN_BACKGROUNDS + TEST_BACKGROUNDS:
        raise ValueError(f'unknown background {name!r}; expected one of '
                         f'{TRAIN_BACKGROUNDS + TEST_BACKGROUNDS}')
    _check_color(color)
    key = (name, color, int(min_side))
    cached = _backgrounds.get(key)
    if cached is not None:
        return cached
    if min_side > 0:
        img = load_background(name, color)
        h, w = img.shape[:2]
        if min(h, w) < min_side:
            scale = min_side / min(h, w)
            size = (max(min_side, round(w * scale)), max(min_side, round(h * scale)))
            img = cv2.resize(img, size, interpolation=cv2.INTER_CUBIC)
    else:
        from skimage import data
        img = np.asarray(getattr(data, name)())
        if img.dtype != np.uint8:
            raise TypeError(f'skimage.data.{name}() is {img.dtype}, expected uint8')
        if img.ndim == 3 and img.shape[2] == 4:
            img = img[:, :, :3]
        if color == 'gray' and img.ndim == 3:
            img = cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_RGB2GRAY)
        elif color == 'rgb' and img.ndim == 2:
            img = np.repeat(img[:, :, None], 3, axis=2)
    img = np.ascontiguousarray(img)
    img.setflags(write=False)
    _backgrounds[key] = img
    return img


def feather_mask(side: int, feather: float = DEFAULT_FEATHER) -> np.ndarray:
    """
    Return the ``(side, side)`` alpha mask of a pasted face: 1 inside, 0 on the outermost pixels.

    Along each axis the weight rises as a raised cosine, ``(1 - cos(pi * d / m)) / 2``, from 0 on
    the border pixel (``d = 0``) to 1 at ``d = m = max(1, round(feather * side))`` pixels in; the
    mask is the product of the row and column weights. The face therefore fades into the
    background with no hard edge for a detector to latch on to, and its border pixels are exactly
    the background. ``feather = 0`` gives a hard-edged square of ones.
    """
    key = (int(side), float(feather))
    cached = _masks.get(key)
    if cached is not None:
        return cached
    if feather <= 0:
        mask = np.ones((side, side), dtype=np.float32)
    else:
        ramp = max(1, round(feather * side))
        d = np.minimum(np.arange(side), np.arange(side)[::-1]).astype(np.float64)
        w = 0.5 - 0.5 * np.cos(np.pi * np.minimum(d / ramp, 1.0))
        mask = np.outer(w, w).astype(np.float32)
    mask.setflags(write=False)
    if len(_masks) > 4096:
        _masks.clear()
    _masks[key] = mask
    return mask


def cell_of_point(x: float, y: float, size: tuple[int, int],
                  grid: tuple[int, int]) -> tuple[int, int]:
    """
    Return the ``(row, col)`` of the cell containing pixel point ``(x, y)``.

    ``size`` is the image's ``(H, W)`` and ``grid`` its tiling ``(rows, cols)``; the cell is
    ``(floor(y * rows / H), floor(x * cols / W))`` (the module's pixel convention).
    """
    h, w = size
    rows, cols = grid
    if not (0 <= x < w and 0 <= y < h):
        raise ValueError(f'point ({x}, {y}) is outside the {w}x{h} image')
    return int(math.floor(y * rows / h)), int(math.floor(x * cols / w))


class SceneFace(NamedTuple):
    """One pasted face: its centre ``(x, y)`` and side in image pixels, its cell and which."""

    centre_px: tuple
    side_px: int
    cell: tuple
    face_index: int


@dataclass(frozen=True, eq=False)
class Scene:
    """
    One scene: an image and where its face is (ground truth).

    Attributes
    ----------
    image : ndarray
        Read-only ``uint8``, ``(H, W)`` grey or ``(H, W, 3)`` RGB.
    face_centre_px : (float, float) or None
        ``(x, y)`` of the pasted square's centre in image pixels; None when the scene has no face.
    face_px : int or None
        Side of the pasted face square in pixels.
    cell : (int, int) or None
        ``(row, col)`` of the face centre on the set's grid.
    face_index : int or None
        Which ``lfw_subset`` face (0-99) was pasted.
    background : str
        Name of the scikit-image photo the scene was cropped from.
    seed, index : int
        The set's seed and the scene's index in the set.
    faces : tuple of SceneFace
        Every face of a scene with several (a pan/tilt room, ``PanTiltSceneSet(faces=...)``),
        the first one the face above; empty for the other sets.

    """

    image: np.ndarray
    face_centre_px: tuple[float, float] | None
    face_px: int | None
    cell: tuple[int, int] | None
    face_index: int | None
    background: str
    seed: int
    index: int
    faces: tuple = ()

    @property
    def has_face(self) -> bool:
        """Whether the scene contains a face."""
        return self.face_centre_px is not None


class SceneSet:
    """
    A deterministic, unbounded (or ``n``-long) sequence of scenes of one split.

    Parameters
    ----------
    split : {'train', 'test'}
        Which faces and backgrounds to draw from (module docstring). Fit only to ``'train'``.
    size_px : int
        Side of the square scene; 420 in the paper's task, 840 in the small/mixed task
        (:data:`PAPER_TASK`, :data:`SMALL_TASK`).
    face_px : (int, int)
        Inclusive range of the face side, drawn uniformly in whole pixels.
    grid : (int, int) or Grid
        ``(rows, cols)`` tiling the image, for :attr:`Scene.cell`.
    absent_rate : float
        Probability in ``[0, 1)`` that a scene has no face (decided per scene from its stream).
    color : {'gray', 'rgb'}
        Grey ``(H, W)`` or RGB ``(H, W, 3)`` images.
    seed : int
        Non-negative; together with ``split`` and the index it fixes every scene.
    n : int, optional
        Length of the set (``len``, iteration); None for unbounded (``len`` raises TypeError and
        iteration never ends).
    feather : float
        Width of the alpha ramp at each edge of the face, as a fraction of its side
        (:func:`feather_mask`); in ``[0, 0.5]``.

    Raises
    ------
    ValueError
        For an unknown split or colour mode, a face range that is empty, non-integer, below 1 px or
        larger than the image, an ``absent_rate`` outside ``[0, 1)``, a bad grid, seed, ``n`` or
        ``feather``.

    Notes
    -----
    The face keeps its own brightness and contrast (it comes from a real photo with its own
    lighting). Matching it loosely to the local background (mean, or mean and standard
    deviation, moved halfway towards the background's) made no difference to OpenCV's
    ``haarcascade_frontalface_alt2`` on 100 train scenes (98% found either way, 97% with
    matching), so it is not done. Faces are upscaled bicubically on floats, clipped to
    ``[0, 255]`` and rounded; the feather ramp of 15% per edge was chosen on train scenes too
    (96.7% found with hard edges, 98.3% with 10-15%, 91.7% with 25%).

    """

    def __init__(self, split: str = 'train', size_px: int = 420,
                 face_px: tuple[int, int] = (60, 140), grid=(21, 21),
                 absent_rate: float = 0.0, color: str = 'gray', seed: int = 0,
                 n: int | None = None, feather: float = DEFAULT_FEATHER):
        if split not in SPLITS:
            raise ValueError(f'unknown split {split!r}; expected one of {tuple(SPLITS)}')
        _check_color(color)
        self.split = split
        self.color = color
        self.size_px = _positive_int('size_px', size_px)
        try:
            lo, hi = face_px
        except (TypeError, ValueError):
            raise ValueError(f'face_px must be a (min, max) pair of pixels, got {face_px!r}')
        lo, hi = _positive_int('face_px min', lo), _positive_int('face_px max', hi)
        if lo > hi:
            raise ValueError(f'face_px range is empty: min {lo} > max {hi}')
        if hi > self.size_px:
            raise ValueError(f'faces of up to {hi} px do not fit in a {self.size_px} px image')
        self.face_px = (lo, hi)
        rows, cols = (grid.rows, grid.cols) if hasattr(grid, 'rows') else _pair('grid', grid)
        self.grid = (_positive_int('grid rows', rows), _positive_int('grid cols', cols))
        rate = float(absent_rate)
        if not 0.0 <= rate < 1.0:
            raise ValueError(f'absent_rate must be in [0, 1), got {absent_rate!r}')
        self.absent_rate = rate
        if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) \
                or seed < 0:
            raise ValueError(f'seed must be a non-negative integer, got {seed!r}')
        self.seed = int(seed)
        self.n = None if n is None else _positive_int('n', n, allow_zero=True)
        feather = float(feather)
        if not 0.0 <= feather <= 0.5:
            raise ValueError(f'feather must be in [0, 0.5], got {feather!r}')
        self.feather = feather
        faces, backgrounds = SPLITS[split]
        self.faces = faces
        self.backgrounds = backgrounds

    def __repr__(self) -> str:
        return (f'SceneSet(split={self.split!r}, size_px={self.size_px}, '
                f'face_px={self.face_px}, grid={self.grid}, absent_rate={self.absent_rate}, '
                f'color={self.color!r}, seed={self.seed}, n={self.n}, feather={self.feather})')

    def __len__(self) -> int:
        if self.n is None:
            raise TypeError('this SceneSet is unbounded (n=None); pass n to give it a length')
        return self.n

    def __getitem__(self, index: int) -> Scene:
        if isinstance(index, (bool, np.bool_)) or not isinstance(index, (int, np.integer)):
            raise TypeError(f'scene indices are integers, got {index!r}')
        index = int(index)
        if self.n is not None:
            if index < 0:
                index += self.n
            if not 0 <= index < self.n:
                raise IndexError(f'scene index out of range for a set of {self.n}')
        elif index < 0:
            raise IndexError('negative indices need a bounded set (pass n)')
        return self.scene(index)

    def __iter__(self) -> Iterator[Scene]:
        index = 0
        while self.n is None or index < self.n:
            yield self.scene(index)
            index += 1

    def scene(self, index: int) -> Scene:
        """Build scene ``index`` (any non-negative integer, also beyond ``n``)."""
        index = int(index)
        if index < 0:
            raise IndexError(f'scene indices are non-negative, got {index}')
        rng = np.random.default_rng([_STREAM_TAG, _SPLIT_CODE[self.split], self.seed, index])
        u_absent, u_bg, u_cy, u_cx, u_face, u_size, u_py, u_px = rng.random(_N_DRAWS)
        size = self.size_px
        name = self.backgrounds[_pick(u_bg, len(self.backgrounds))]
        photo = load_background(name, self.color, min_side=size)
        top = _pick(u_cy, photo.shape[0] - size + 1)
        left = _pick(u_cx, photo.shape[1] - size + 1)
        image = photo[top:top + size, left:left + size].copy()
        if u_absent < self.absent_rate:
            image.setflags(write=False)
            return Scene(image, None, None, None, None, name, self.seed, index)
        face_index = self.faces[_pick(u_face, len(self.faces))]
        lo, hi = self.face_px
        side = lo + _pick(u_size, hi - lo + 1)
        y0 = _pick(u_py, size - side + 1)
        x0 = _pick(u_px, size - side + 1)
        _paste(image, load_faces()[face_index], y0, x0, side, self.feather)
        image.setflags(write=False)
        centre = (x0 + side / 2.0, y0 + side / 2.0)
        cell = cell_of_point(centre[0], centre[1], (size, size), self.grid)
        return Scene(image, centre, side, cell, int(face_index), name, self.seed, index)


def _paste(image: np.ndarray, face: np.ndarray, y0: int, x0: int, side: int,
           feather: float) -> None:
    """Alpha-blend ``face`` (float grey, any size) resized to ``side`` into ``image`` in place."""
    resized = np.clip(cv2.resize(face, (side, side), interpolation=cv2.INTER_CUBIC), 0.0, 255.0)
    alpha = feather_mask(side, feather)
    region = image[y0:y0 + side, x0:x0 + side]
    if region.ndim == 3:
        resized, alpha = resized[:, :, None], alpha[:, :, None]
    bg = region.astype(np.float32)
    region[...] = np.rint(bg + alpha * (resized - bg)).astype(np.uint8)


def _pick(u: float, n: int) -> int:
    """Map a uniform draw in ``[0, 1)`` to an integer in ``0..n-1``."""
    return min(int(u * n), n - 1)


def _check_color(color) -> None:
    if color not in COLORS:
        raise ValueError(f'unknown color mode {color!r}; expected one of {COLORS}')


def _pair(name: str, value) -> tuple:
    try:
        a, b = value
    except (TypeError, ValueError):
        raise ValueError(f'{name} must be a (rows, cols) pair, got {value!r}')
    return a, b


class LabelledImage(NamedTuple):
    """An image read from a labelled folder and its face centre ``(x, y)`` in pixels, or None."""

    image: np.ndarray
    centre_px: tuple[float, float] | None


def write_scene_set(scenes, folder, csv_name: str = 'labels.csv') -> Path:
    """
    Write scenes as PNG files plus a CSV ``path,x,y`` of face centres; return the CSV's path.

    The format is the one :func:`read_labelled_folder` reads, i.e. what the ``calibrate`` command
    accepts as a user's own labelled data: one row per image, ``path`` relative to ``folder``,
    ``x,y`` the face centre in pixels (module convention) or both empty when there is no face.
    Files are named ``scene_<index>.png``; RGB scenes are stored as colour PNGs (converted to
    OpenCV's BGR on writing), grey ones as grey PNGs. PNG is lossless, so reading back gives the
    same arrays.

    Parameters
    ----------
    scenes : iterable of Scene
        For example a bounded :class:`SceneSet` (an unbounded one never ends). Indices must be
        distinct (they name the files); a repeated one raises ValueError.
    folder : path-like
        Created if missing; existing files of the same names are overwritten.
    csv_name : str
        Name of the CSV inside ``folder``.

    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    csv_path = folder / csv_name
    with open(csv_path, 'w', newline='', encoding='utf-8') as stream:
        writer = csv.writer(stream)
        writer.writerow(['path', 'x', 'y'])
        names = set()
        for scene in scenes:
            name = f'scene_{scene.index:06d}.png'
            if name in names:
                raise ValueError(f'two scenes with index {scene.index}: files are named by index, '
                                 'so write scenes of one set only')
            names.add(name)
            image = scene.image
            if image.ndim == 3:
                image = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
            if not cv2.imwrite(str(folder / name), image):
                raise OSError(f'could not write {folder / name}')
            centre = scene.face_centre_px
            writer.writerow([name, '', ''] if centre is None
                            else [name, repr(float(centre[0])), repr(float(centre[1]))])
    return csv_path


def labels_path(folder, csv_path) -> Path:
    """
    Return the label CSV of a labelled folder: ``csv_path``, or, relative and missing, inside it.

    FileNotFoundError if neither is a file.
    """
    csv_path = Path(csv_path)
    if not csv_path.exists() and not csv_path.is_absolute() and (Path(folder) / csv_path).exists():
        csv_path = Path(folder) / csv_path
    if csv_path.is_dir():
        raise FileNotFoundError(f'label CSV {csv_path} is a folder, not a CSV file')
    if not csv_path.is_file():
        raise FileNotFoundError(f'label CSV {csv_path} does not exist')
    return csv_path


# Excel's "CSV UTF-8" starts with a byte order mark, which utf-8 read as part of 'path'.
LABELS_ENCODING = 'utf-8-sig'


def _not_text(csv_path: Path, exc: UnicodeDecodeError) -> ValueError:
    """Return the one-line refusal of a label CSV not in UTF-8 text (an image given instead)."""
    return ValueError(f'{csv_path}: not a UTF-8 text CSV (path,x,y): byte {exc.start} is '
                      f'{exc.object[exc.start:exc.start + 1]!r}')


def labelled_names(folder, csv_path) -> list[str]:
    """Return the ``path`` entries of a label CSV, in order (as :func:`read_labelled_folder`)."""
    csv_path = labels_path(folder, csv_path)
    try:
        with open(csv_path, newline='', encoding=LABELS_ENCODING) as stream:
            return [(row.get('path') or '').strip() for row in csv.DictReader(stream)]
    except UnicodeDecodeError as exc:
        raise _not_text(csv_path, exc) from None


def read_labelled_folder(folder, csv_path) -> list[LabelledImage]:
    """
    Read a folder of images and a CSV ``path,x,y`` of face-centre pixels.

    Parameters
    ----------
    folder : path-like
        Where the CSV's relative ``path`` entries are looked up (absolute paths are used as is).
    csv_path : path-like
        A CSV with a header naming at least the columns ``path``, ``x`` and ``y``. ``x, y`` is
        the face centre in pixels, with ``(0, 0)`` the top-left corner of the top-left pixel
        (module docstring), inside ``[0, W) x [0, H)``; both empty means the image has no face.
        A relative ``csv_path`` that does not exist is also looked up inside ``folder``.

    Returns
    -------
    list of LabelledImage
        ``(image, centre_px)`` pairs in CSV order. Images are ``uint8``, grey ``(H, W)`` or RGB
        ``(H, W, 3)`` (OpenCV reads BGR; it is converted, and an alpha channel is dropped), turned
        as their EXIF orientation says, as a viewer and ``find`` show them.

    Raises
    ------
    FileNotFoundError
        If the folder, the CSV or an image it names does not exist.
    ValueError
        If the CSV lacks a column or has no rows, a coordinate is not a finite number or only one
        of ``x, y`` is given, an image cannot be decoded or is not 8-bit, or a centre lies outside
        its image. Messages name the file and the CSV line.

    """
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f'image folder {folder} ' + (
            'is a file, not a folder' if folder.exists() else 'does not exist'))
    csv_path = labels_path(folder, csv_path)
    try:
        return _read_labels(folder, csv_path)
    except UnicodeDecodeError as exc:
        raise _not_text(csv_path, exc) from None


def _read_labels(folder: Path, csv_path: Path) -> list[LabelledImage]:
    """Read a label CSV's images and centres (:func:`read_labelled_folder`)."""
    out = []
    with open(csv_path, newline='', encoding=LABELS_ENCODING) as stream:
        reader = csv.DictReader(stream)
        missing = {'path', 'x', 'y'} - set(reader.fieldnames or ())
        if missing:
            raise ValueError(f'{csv_path}: header must name the columns path,x,y; '
                             f"missing {', '.join(sorted(missing))}")
        for row in reader:
            where = f'{csv_path}, line {reader.line_num}'
            name = (row['path'] or '').strip()
            if not name:
                raise ValueError(f'{where}: empty path')
            image_path = Path(name) if Path(name).is_absolute() else folder / name
            image = _read_image(image_path, where)
            centre = _parse_centre(row['x'], row['y'], where)
            if centre is not None:
                h, w = image.shape[:2]
                if not (0 <= centre[0] < w and 0 <= centre[1] < h):
                    raise ValueError(f'{where}: face centre ({centre[0]}, {centre[1]}) is outside '
                                     f'the {w}x{h} image {image_path}')
            out.append(LabelledImage(image, centre))
    if not out:
        raise ValueError(f'{csv_path}: no images listed')
    return out


def _read_image(path: Path, where: str) -> np.ndarray:
    """
    Decode a labelled image as ``find`` does: EXIF orientation applied, an alpha channel dropped.

    Labels are pixels of the picture as a viewer shows it (and as ``find`` searches it): read
    with ``IMREAD_UNCHANGED``, a phone's photo stored sideways with an EXIF turn was calibrated
    sideways, its face centre at another place.
    """
    if not path.is_file():
        raise FileNotFoundError(f'{where}: image {path} does not exist')
    from .image_files import decode_quietly, READ_FLAGS, undecodable
    data = np.fromfile(path, dtype=np.uint8)
    try:
        image = decode_quietly(data, READ_FLAGS) if data.size else None
    except ValueError as exc:   # over OpenCV's pixel limit, or out of memory
        raise ValueError(f'{where}: {path}: {exc}') from None
    if image is None:
        raise ValueError(f'{where}: cannot decode {path} as an image: {undecodable(data)}')
    if image.dtype != np.uint8:
        raise ValueError(f'{where}: {path} is {image.dtype}; only 8-bit images are supported')
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
    return image


def _parse_centre(x_text, y_text, where: str) -> tuple[float, float] | None:
    x_text, y_text = (x_text or '').strip(), (y_text or '').strip()
    if not x_text and not y_text:
        return None
    if not x_text or not y_text:
        raise ValueError(f'{where}: give both x and y, or leave both empty for no face')
    try:
        x, y = float(x_text), float(y_text)
    except ValueError:
        raise ValueError(f'{where}: x, y must be numbers, got {x_text!r}, {y_text!r}')
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f'{where}: x, y must be finite, got {x_text!r}, {y_text!r}')
    return x, y
