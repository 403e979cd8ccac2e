# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Object detectors for the digital fovea: the interface, OpenCV's Viola-Jones cascade, grey images.

**The interface** (docs/design.md section 6) is deliberately small, so any detector can be plugged
in (:mod:`ipomdp_gaze.vision.detectors` finds and builds them by name). A detector is a callable
``detector(image) -> boxes`` that takes a ``uint8`` image in the colour space it declares and
returns an array of shape ``(M, 5)``, one row ``x, y, w, h, score`` per *raw* detection in that
image's pixels, as floats (or ``(M, 4)``: every score is then 1). Raw means ungrouped: the count
observation model counts the raw detections, so overlapping hits of one face are the evidence,
not noise to be merged. :func:`as_detections` reads any such answer. The attributes:

- ``color``: ``'gray'`` (a 2-D image, the default when absent) or ``'rgb'`` (``(H, W, 3)`` in
  RGB order); :func:`to_detector_image` converts every input to it;
- ``window_px``: ``(width, height)`` of the smallest image the detector can see anything in.
  :func:`to_gray` rejects input images smaller than that;
- ``settings()``: a plain dict recorded in observation files, with ``kind`` (the name the
  factory builds it by) and every option needed to rebuild it, so a model is only ever applied
  with the detector it was measured with; ``info_keys`` names the settings recorded for
  information only (the OpenCV version, the window), which may differ when it is rebuilt;
- ``group(boxes, min_neighbors)``: how to merge raw boxes into final detections (else
  :func:`group_boxes`).

:class:`HaarDetector` is the reference detector of Butko & Movellan's CVPR 2009 follow-up:
``haarcascade_frontalface_alt2.xml`` with ``detectMultiScale(gray, 1.1, minNeighbors=0)``. It
returns ``(M, 4)`` integer boxes (its detections carry no score).

**Pixel coordinates.** A box ``(x, y, w, h)`` covers ``[x, x+w) x [y, y+h)`` and has its centre at
``(x + w/2, y + h/2)``; pixel ``(r, c)`` covers ``[c, c+1) x [r, r+1)``.
"""
from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Protocol, runtime_checkable

import cv2
import numpy as np

REFERENCE_CASCADE = 'haarcascade_frontalface_alt2.xml'
# Debian/Ubuntu's python3-opencv has no cv2.data; the cascades come with the opencv-data package.
SYSTEM_CASCADE_DIRS = (Path('/usr/share/opencv4/haarcascades'),)
# detectMultiScale's own grouping: clusters of rectangles whose sides and corners differ by less
# than eps = 0.2 of the mean size merge; clusters of at most min_neighbors rectangles are dropped.
GROUP_EPS = 0.2
DEFAULT_MIN_NEIGHBORS = 3
# Smallest image side anything is done with: a 1x1 image has no spatial structure at all.
MIN_SIDE_PX = 2
# The colour spaces a detector may declare (its ``color`` attribute).
COLORS = ('gray', 'rgb')
# Settings recorded for information only unless a detector names its own (``info_keys``).
INFO_KEYS = ('opencv', 'window_px')
# Set by the factory (ipomdp_gaze.vision.detectors) on what it builds: the kind it built it by.
KIND_ATTRIBUTE = '_ipomdp_gaze_kind'
# ... and the options it was built with, recorded where its own settings() leaves them out.
OPTIONS_ATTRIBUTE = '_ipomdp_gaze_options'


@runtime_checkable
class Detector(Protocol):
    """
    A detector: ``detector(image) -> (M, 5)`` raw boxes ``x, y, w, h, score`` (module docstring).

    ``color`` (``'gray'`` or ``'rgb'``), ``window_px`` and ``settings()`` are read when present.
    """

    def __call__(self, image: np.ndarray) -> np.ndarray:
        """Detect objects in a ``uint8`` image; return the raw boxes in its pixels."""


def as_detections(result) -> tuple[np.ndarray, np.ndarray]:
    """
    Read a detector's answer: boxes ``(M, 4)`` ``float64`` ``x, y, w, h`` and scores ``(M,)``.

    ``result`` is ``(M, 5)`` rows ``x, y, w, h, score`` or ``(M, 4)`` (every score 1), any
    numeric type; OpenCV's empty tuple and a plain list are accepted.

    Raises
    ------
    ValueError
        If the shape is not ``(M, 4)`` or ``(M, 5)``, a number is not finite or real, or a box
        has no positive width and height.

    """
    if result is None:
        raise ValueError('a detector must return boxes, (M, 5) x, y, w, h, score or (M, 4), '
                         'got None (no return statement?)')
    if np.iscomplexobj(result):
        raise ValueError('a detector must return real numbers, got complex ones')
    try:
        array = np.asarray(result, dtype=np.float64) if np.size(result) else np.empty((0, 5))
        shape = np.shape(result)
    except (TypeError, ValueError):
        raise ValueError(f'a detector must return one array of boxes, (M, 5) x, y, w, h, score '
                         f'or (M, 4), got a {type(result).__name__} that is not one (boxes '
                         f'and scores apart?)') from None
    if len(shape) == 2 and not array.size:
        array = np.empty(shape)             # no box, but of the width it answers with
    if array.ndim != 2 or array.shape[1] not in (4, 5):
        raise ValueError(f'a detector must return boxes of shape (M, 5) x, y, w, h, score or '
                         f'(M, 4), got {array.shape}')
    if not np.all(np.isfinite(array)):
        raise ValueError('a detector returned a box or score that is not a finite number')
    if np.any(array[:, 2:4] <= 0):
        raise ValueError('every box must have a positive width and height')
    scores = array[:, 4].copy() if array.shape[1] == 5 else np.ones(len(array))
    return np.ascontiguousarray(array[:, :4]), scores


class DetectorFailed(ValueError):
    """A detector raised on an image: its own error, named as the detector's (:func:`detect`)."""


def detect(detector, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Call ``detector`` on ``image`` and read its answer (:func:`as_detections`).

    An image smaller than the detector's ``window_px`` (a window of the fovea) is not given to
    it: it sees nothing there. Boxes that do not overlap the image are dropped (a plug-in's
    bug, or boxes given as corners: they must not be counted in the cells at the image's
    edge). An exception the detector from outside the package raises (a plug-in's bug, a
    missing weight file), and an answer of it that :func:`as_detections` refuses, become
    :class:`DetectorFailed` naming the detector, so that a driver reports it against the image
    and goes on; the package's own detectors' errors, and running out of memory, stay what they
    are.
    """
    height, width = image.shape[:2]
    # an ensemble's window_px is its largest member's; each member checks its own
    window = (0, 0) if hasattr(detector, 'members') else detector_window_px(detector)
    if width < window[0] or height < window[1]:
        return np.empty((0, 4)), np.empty(0)
    own = type(detector).__module__.split('.')[0] == 'ipomdp_gaze'
    kind = getattr(detector, KIND_ATTRIBUTE, None) or type(detector).__name__
    try:
        result = detector(image)
    except MemoryError:
        raise
    except Exception as exc:                    # noqa: B902 (any error of a user's detector)
        if own or (type(exc).__name__ == 'error' and 'Insufficient memory' in str(exc)):
            raise                               # our bug (a traceback), or OpenCV's memory
        raise DetectorFailed(f'the detector {kind} raised {type(exc).__name__}: '
                             f'{exc}') from exc
    try:
        boxes, scores = as_detections(result)
    except ValueError as exc:
        if own:
            raise
        raise DetectorFailed(f'the detector {kind} returned bad boxes: {exc}') from None
    overlap = ((boxes[:, 0] < width) & (boxes[:, 1] < height)
               & (boxes[:, 0] + boxes[:, 2] > 0) & (boxes[:, 1] + boxes[:, 3] > 0))
    if overlap.all():
        return boxes, scores
    return boxes[overlap], scores[overlap]


def detector_color(detector) -> str:
    """Return the colour space ``detector`` takes: its ``color`` attribute, else ``'gray'``."""
    color = getattr(detector, 'color', 'gray')
    if color not in COLORS:
        raise ValueError(f"a detector's color must be one of {', '.join(COLORS)}, got "
                         f'{color!r}')
    return color


def as_boxes(boxes) -> np.ndarray:
    """
    Return ``boxes`` as an ``int64`` array of shape ``(M, 4)``, rows ``x, y, w, h``.

    OpenCV returns an empty tuple when nothing is found; a user's detector may return a list.

    Raises
    ------
    ValueError
        If the boxes are not ``(M, 4)`` integers with positive widths and heights.

    """
    array = np.asarray(boxes)
    if array.size == 0:
        return np.empty((0, 4), dtype=np.int64)
    if array.ndim != 2 or array.shape[1] != 4:
        raise ValueError(f'a detector must return boxes of shape (M, 4), got {array.shape}')
    if not np.issubdtype(array.dtype, np.integer):
        if not np.array_equal(array, np.round(array)):
            raise ValueError('a detector must return integer boxes x, y, w, h in pixels')
    array = array.astype(np.int64)
    if np.any(array[:, 2:] <= 0):
        raise ValueError('every box must have a positive width and height')
    return array


def box_centres_px(boxes: np.ndarray) -> np.ndarray:
    """Centres ``(x + w/2, y + h/2)`` of boxes ``(M, 4)``, as ``float64`` of shape ``(M, 2)``."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return boxes[:, :2] + boxes[:, 2:] / 2.0


def group_boxes(boxes, min_neighbors: int = DEFAULT_MIN_NEIGHBORS,
                eps: float = GROUP_EPS) -> np.ndarray:
    """
    Merge raw detections as ``detectMultiScale(..., minNeighbors=min_neighbors)`` does.

    Calls ``cv2.groupRectangles(boxes, min_neighbors, eps)``, the grouping OpenCV applies inside
    ``detectMultiScale`` (with ``eps = 0.2``): rectangles are clustered when their corners differ
    by less than ``eps`` times their mean size, each cluster of more than ``min_neighbors``
    rectangles becomes its mean rectangle and the rest are dropped, as are grouped rectangles
    lying inside a larger one. Grouping the raw (``minNeighbors=0``) detections of an image with
    the default ``min_neighbors=3`` therefore gives OpenCV's default answer without running the
    cascade twice. ``min_neighbors=0`` returns the boxes unchanged, as OpenCV does.

    Returns
    -------
    numpy.ndarray
        ``int64`` of shape ``(G, 4)``, rows ``x, y, w, h``.

    """
    return group_support(boxes, min_neighbors, eps)[0]


def group_support(boxes, min_neighbors: int = DEFAULT_MIN_NEIGHBORS,
                  eps: float = GROUP_EPS) -> tuple[np.ndarray, np.ndarray]:
    """
    Return :func:`group_boxes`' grouped boxes and the support of each, ``(G, 4)`` and ``(G,)``.

    The support is OpenCV's group weight: the number of raw boxes the group merged (1 for every
    box when ``min_neighbors`` is 0, which does not group).
    """
    boxes = as_boxes(boxes)
    if min_neighbors < 0:
        raise ValueError(f'min_neighbors must be >= 0, got {min_neighbors!r}')
    if len(boxes) == 0 or min_neighbors == 0:
        return boxes, np.ones(len(boxes), dtype=np.int64)
    grouped, weights = cv2.groupRectangles(boxes.tolist(), int(min_neighbors), float(eps))
    grouped = as_boxes(grouped)
    return grouped, np.asarray(weights, dtype=np.int64).reshape(len(grouped))


def find_cascade(name: str = REFERENCE_CASCADE, path=None) -> Path:
    """
    Find a cascade file: ``path`` first, then OpenCV's own copy, then the system's.

    Parameters
    ----------
    name : str
        File name of the cascade, e.g. ``'haarcascade_frontalface_alt2.xml'``. A name with a
        folder in it (``'models/my.xml'``) is itself the first place searched.
    path : str or os.PathLike, optional
        A folder holding the file name of ``name``, or a cascade file: the one place searched
        (another cascade found elsewhere would be used unnoticed). Without it, the places below
        are searched for the file name of ``name``.

    Returns
    -------
    pathlib.Path
        ``path``'s file; or the first existing file of: ``name`` if it has a folder in it,
        ``cv2.data.haarcascades`` (pip's opencv-python wheels; Debian's python3-opencv has no
        ``cv2.data``), then :data:`SYSTEM_CASCADE_DIRS` (Debian's opencv-data package).

    Raises
    ------
    ValueError
        If ``path`` is given and does not exist, or is a folder without the file.
    FileNotFoundError
        If no place has the file; the message lists every place searched, in order.

    """
    places = []
    file_name = Path(name).name
    if path is not None:
        return _cascade_in(Path(path), file_name)
    if len(Path(name).parts) > 1:
        places.append(Path(name))
    data = getattr(cv2, 'data', None)
    if data is not None and getattr(data, 'haarcascades', None):
        places.append(Path(data.haarcascades) / file_name)
    places += [folder / file_name for folder in SYSTEM_CASCADE_DIRS]
    for place in places:
        if place.is_file():
            return place
    searched = '\n  '.join(str(place) for place in places)
    raise FileNotFoundError(
        f'cascade {name!r} not found; searched, in order:\n  {searched}\n'
        'install opencv-python-headless<5 (pip) or opencv-data (apt), or pass its path')


def _cascade_in(path: Path, file_name: str) -> Path:
    """Return the cascade ``file_name`` in the folder ``path`` (or ``path``, a file)."""
    if not path.exists():
        raise ValueError(f'cascade folder {path} does not exist (it was to hold {file_name})')
    if not path.is_dir():
        return path
    if not (path / file_name).is_file():
        raise ValueError(f'cascade folder {path} has no {file_name}')
    return path / file_name


def _size_pair(name: str, value) -> tuple[int, int] | None:
    """``None``, or ``(width, height)`` in pixels from one side or a pair of positive ints."""
    if value is None:
        return None
    pair = (value, value) if np.ndim(value) == 0 else tuple(value)
    if len(pair) != 2 or any(isinstance(v, bool) or int(v) != v or v < 1 for v in pair):
        raise ValueError(f'{name} must be a positive int or a (width, height) pair, got {value!r}')
    return (int(pair[0]), int(pair[1]))


class HaarDetector:
    """
    OpenCV's Viola-Jones cascades returning raw, ungrouped detections (the CVPR 2009 detector).

    Detector kind ``haar``: grey images in, ``(M, 4)`` integer boxes out (no scores). With one
    cascade it is the reference detector. With several, every cascade runs on the image and the
    raw boxes of all are returned together, so a count model counts them all: a face one cascade
    barely sees (a turned head for the frontal cascade) may be seen by another (the profile
    cascade). A cascade trained on one side only (``haarcascade_profileface.xml`` sees faces
    turned to one side) also runs on the mirrored image when its ``mirror`` flag is set; its
    boxes are mapped back to the image's own pixels.

    Parameters
    ----------
    cascade : str, os.PathLike or list of them
        Cascade file name or path, resolved with :func:`find_cascade`, or several.
    scale_factor : float
        Scale step of ``detectMultiScale``'s image pyramid (> 1).
    min_neighbors : int
        ``detectMultiScale``'s ``minNeighbors``; 0 (the reference) returns raw detections.
    min_size_px, max_size_px : int or (int, int), optional
        Smallest and largest box ``(width, height)`` searched for, in the pixels of the image the
        detector is given (for the fovea: the resized window), or ``None`` for no limit.
    cascade_dir : str or os.PathLike, optional
        Folder holding the cascades (or a cascade file), instead of the default places; one
        that does not exist, or lacks a cascade, is refused.
    mirror : bool or list of bool
        Per cascade (one flag for all): also detect in the mirrored image.

    """

    kind = 'haar'
    color = 'gray'
    info_keys = INFO_KEYS
    # The YAML types of its record's keys (ipomdp_gaze.files.yaml_files.check_record).
    record_types = {'cascade': 'texts', 'cascade_sha256': 'texts', 'scale_factor': 'number',
                    'min_neighbors': 'integer', 'min_size_px': 'size?', 'max_size_px': 'size?',
                    'mirror': 'flags', 'window_px': 'pair', 'opencv': 'text'}

    def __init__(self, cascade=REFERENCE_CASCADE, scale_factor: float = 1.1,
                 min_neighbors: int = 0, min_size_px=None, max_size_px=None, cascade_dir=None,
                 mirror=False):
        scale_factor = float(scale_factor)
        if not np.isfinite(scale_factor) or scale_factor <= 1.0:
            raise ValueError(f'scale_factor must be a finite number > 1, got {scale_factor!r}')
        if isinstance(min_neighbors, bool) or int(min_neighbors) != min_neighbors \
                or min_neighbors < 0:
            raise ValueError(f'min_neighbors must be an int >= 0, got {min_neighbors!r}')
        names = [cascade] if isinstance(cascade, (str, Path)) else list(cascade)
        if not names or not all(isinstance(name, (str, Path)) for name in names):
            raise ValueError(f'cascade must be a file name or a non-empty list of them, '
                             f'got {cascade!r}')
        self.mirror = _mirror_flags(mirror, len(names))
        self.scale_factor = scale_factor
        self.min_neighbors = int(min_neighbors)
        self.min_size_px = _size_pair('min_size_px', min_size_px)
        self.max_size_px = _size_pair('max_size_px', max_size_px)
        self.paths = [find_cascade(str(name), cascade_dir) for name in names]
        self.path = self.paths[0]
        self.cascade_names = [path.name for path in self.paths]
        self.cascade_name = self.cascade_names[0]
        self._classifiers = []
        windows = []
        for path in self.paths:
            classifier = cv2.CascadeClassifier(str(path))
            if classifier.empty():
                raise ValueError(f'{path} is not a cascade OpenCV can load')
            width, height = classifier.getOriginalWindowSize()
            windows.append((int(width), int(height)))
            self._classifiers.append(classifier)
        self._windows = windows
        self.window_px = (min(w for w, _ in windows), min(h for _, h in windows))
        self._sha256s = [hashlib.sha256(path.read_bytes()).hexdigest() for path in self.paths]
        self._options = {}
        if self.min_size_px is not None:
            self._options['minSize'] = self.min_size_px
        if self.max_size_px is not None:
            self._options['maxSize'] = self.max_size_px

    @property
    def single(self) -> bool:
        """Tell whether this is the one-cascade detector (recorded as the reference is)."""
        return len(self.paths) == 1 and not self.mirror[0]

    @classmethod
    def from_settings(cls, settings: dict, cascade_dir=None) -> HaarDetector:
        """
        Rebuild the detector :meth:`settings` describes (an observation model's record).

        Each cascade is looked up by file name (:func:`find_cascade`, in ``cascade_dir`` if
        given), and a copy whose SHA-256 differs from the recorded one is refused.

        Raises
        ------
        ValueError
            For a cascade that differs from the recorded one, or bad settings.
        FileNotFoundError
            If a cascade file is not installed.

        """
        options = {key: settings[key] for key in ('cascade', 'scale_factor', 'min_neighbors',
                                                  'min_size_px', 'max_size_px', 'mirror')
                   if key in settings}
        detector = cls(cascade_dir=cascade_dir, **options)
        recorded = settings.get('cascade_sha256')
        if recorded is not None:
            recorded = [recorded] if isinstance(recorded, str) else list(recorded)
            for path, want, have in zip(detector.paths, recorded, detector._sha256s):
                if want != have:
                    raise ValueError(f'the installed cascade {path} differs from the one the '
                                     f'observation model was measured with (SHA-256 '
                                     f'{str(want)[:12]}...)')
        return detector

    def __call__(self, gray: np.ndarray) -> np.ndarray:
        """
        Raw boxes ``(M, 4)`` ``int64`` ``x, y, w, h`` in the pixels of ``gray`` (2-D ``uint8``).

        An image smaller than a cascade's window (``window_px`` is the smallest) holds no
        detection of that cascade: a foveal window resized below the window size simply sees
        nothing. The rows are sorted (lexicographically by ``x, y, w, h``): OpenCV searches in
        parallel and returns them in an order that changes from run to run, which would make the
        grouped boxes' order, and so ties between them, irreproducible.
        """
        if gray.ndim != 2 or gray.dtype != np.uint8:
            raise ValueError(f'the detector needs a 2-D uint8 image, got {gray.dtype} '
                             f'of shape {gray.shape}')
        found = []
        mirrored = None
        for classifier, (width, height), mirror in zip(self._classifiers, self._windows,
                                                       self.mirror):
            if gray.shape[1] < width or gray.shape[0] < height:
                continue
            found.append(self._detect(classifier, gray))
            if mirror:
                if mirrored is None:
                    mirrored = np.ascontiguousarray(gray[:, ::-1])
                flipped = self._detect(classifier, mirrored)
                flipped[:, 0] = gray.shape[1] - flipped[:, 0] - flipped[:, 2]
                found.append(flipped)
        boxes = np.concatenate(found) if found else np.empty((0, 4), dtype=np.int64)
        return boxes[np.lexsort(boxes.T[::-1])]

    def _detect(self, classifier, gray: np.ndarray) -> np.ndarray:
        return as_boxes(classifier.detectMultiScale(
            gray, scaleFactor=self.scale_factor, minNeighbors=self.min_neighbors,
            **self._options))

    def group(self, boxes, min_neighbors: int = DEFAULT_MIN_NEIGHBORS) -> np.ndarray:
        """Group raw boxes as OpenCV does: :func:`group_boxes` with ``eps = 0.2``."""
        return group_boxes(boxes, min_neighbors, GROUP_EPS)

    def settings(self) -> dict:
        """
        Plain-typed settings, as recorded in an observation file.

        The file's name and SHA-256 identify the cascade wherever it was installed from; the
        OpenCV version is recorded because cascade evaluation has changed between releases.
        Several cascades (or a mirrored one) are recorded as lists, with ``mirror``.
        """
        out = {
            'kind': 'haar',
            'cascade': self.cascade_name if self.single else list(self.cascade_names),
            'cascade_sha256': self._sha256s[0] if self.single else list(self._sha256s),
            'scale_factor': self.scale_factor,
            'min_neighbors': self.min_neighbors,
            'min_size_px': None if self.min_size_px is None else list(self.min_size_px),
            'max_size_px': None if self.max_size_px is None else list(self.max_size_px),
            'window_px': list(self.window_px),
            'opencv': cv2.__version__,
        }
        if not self.single:
            out['mirror'] = list(self.mirror)
        return out

    def __repr__(self) -> str:
        """Show the cascades and the detectMultiScale arguments."""
        cascade = repr(self.cascade_name) if self.single else repr(self.cascade_names)
        mirror = '' if self.single else f', mirror={self.mirror}'
        return (f'HaarDetector({cascade}, scale_factor={self.scale_factor}, '
                f'min_neighbors={self.min_neighbors}, min_size_px={self.min_size_px}, '
                f'max_size_px={self.max_size_px}{mirror})')


def _mirror_flags(mirror, n: int) -> list[bool]:
    """One ``mirror`` flag per cascade, from one bool or a list of ``n``."""
    flags = [mirror] * n if isinstance(mirror, (bool, np.bool_)) else mirror
    try:
        flags = list(flags)
    except TypeError:
        flags = None
    if flags is None or len(flags) != n or not all(isinstance(f, (bool, np.bool_))
                                                   for f in flags):
        raise ValueError(f'mirror must be true, false or a list of {n} of them (one per '
                         f'cascade), got {mirror!r}')
    return [bool(f) for f in flags]


def detector_settings(detector) -> dict:
    """
    Return ``detector.settings()`` (if it has one) with the detector's ``kind`` first.

    ``kind`` is the name the factory (:func:`ipomdp_gaze.vision.detectors.make_detector`) built
    the detector by; for a detector built otherwise, the kind its settings give, else its class
    as ``module:Class``, so that the factory can rebuild it when it takes no options. A
    detector its factory rebuilds as ``factory(**options)`` (no ``from_settings``) has the
    options it was built with recorded too where ``settings()`` does not give them (a plug-in
    without ``settings()``, or one that forgets an option), so that a model file rebuilds the
    detector it was calibrated with.
    """
    settings = getattr(detector, 'settings', None)
    out = {**getattr(detector, OPTIONS_ATTRIBUTE, {}),
           **(dict(settings()) if callable(settings) else {})}
    kind = getattr(detector, KIND_ATTRIBUTE, None)
    if kind is None and 'kind' not in out:
        kind = f'{type(detector).__module__}:{type(detector).__qualname__}'
    if kind is not None:
        out['kind'] = kind
    return {'kind': out.pop('kind'), **out}


def describe_detector(detector) -> str:
    """
    Name a detector for a log line: its own ``repr``, else its kind and settings.

    A plug-in without a ``__repr__`` of its own would show as ``<module.Class object at 0x...>``,
    which says neither the name it was built by nor its options.
    """
    if type(detector).__repr__ is not object.__repr__:
        return repr(detector)
    settings = detector_settings(detector)
    kind = settings.pop('kind')
    return f'{kind}({", ".join(f"{key}={value!r}" for key, value in settings.items())})'


def detector_window_px(detector) -> tuple[int, int]:
    """Smallest ``(width, height)`` the detector can see anything in (at least 2x2 pixels)."""
    window = getattr(detector, 'window_px', None)
    if window is None:
        return (MIN_SIDE_PX, MIN_SIDE_PX)
    return (max(int(window[0]), MIN_SIDE_PX), max(int(window[1]), MIN_SIDE_PX))


def to_gray(image, min_size_px=(MIN_SIDE_PX, MIN_SIDE_PX)) -> np.ndarray:
    """
    Return a 2-D ``uint8`` grey image (C-contiguous) from a grey or an RGB ``uint8`` image.

    Parameters
    ----------
    image : numpy.ndarray
        ``(H, W)`` grey or ``(H, W, 3)`` in **RGB** channel order (what scikit-image, PIL and
        the project's scenes use; an array read with ``cv2.imread`` is BGR and must be converted
        first, ``cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)``), ``uint8``. Converted with
        ``cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)`` (``0.299 R + 0.587 G + 0.114 B``).
    min_size_px : (int, int)
        Smallest accepted ``(width, height)``: the detector's window (20x20 for the reference
        cascade; see :func:`detector_window_px`). Never below 2x2.

    Raises
    ------
    ValueError
        Naming the problem: not an array, not ``uint8``, a shape other than ``(H, W)`` or
        ``(H, W, 3)`` (e.g. 4-channel RGBA), or smaller than ``min_size_px``.

    """
    if not isinstance(image, np.ndarray):
        raise ValueError(f'image must be a numpy array, got {type(image).__name__}')
    if image.dtype != np.uint8:
        raise ValueError(f'image must be uint8 (0..255), got dtype {image.dtype}')
    if image.ndim == 3 and image.shape[2] != 3:
        raise ValueError(f'a colour image must have 3 channels (RGB), got {image.shape[2]} '
                         f'(shape {image.shape}); convert RGBA or other layouts first')
    if image.ndim not in (2, 3):
        raise ValueError(f'image must be (H, W) grey or (H, W, 3) RGB, got shape {image.shape}')
    min_width, min_height = (max(int(v), MIN_SIDE_PX) for v in min_size_px)
    height, width = image.shape[:2]
    if width < min_width or height < min_height:
        raise ValueError(f'image of {width}x{height} pixels (WxH) is smaller than the '
                         f'{min_width}x{min_height} the detector needs')
    if image.ndim == 3:
        return cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2GRAY)
    return np.ascontiguousarray(image)


def to_detector_image(image, color: str = 'gray',
                      min_size_px=(MIN_SIDE_PX, MIN_SIDE_PX)) -> np.ndarray:
    """
    Return ``image`` in a detector's colour space (C-contiguous ``uint8``).

    ``'gray'``: :func:`to_gray`. ``'rgb'``: an ``(H, W, 3)`` RGB image as given, a grey one with
    its value in all three channels. Checks as :func:`to_gray` does.
    """
    gray = to_gray(image, min_size_px)
    if color == 'gray':
        return gray
    if color != 'rgb':
        raise ValueError(f"color must be one of {', '.join(COLORS)}, got {color!r}")
    if image.ndim == 2:
        return cv2.cvtColor(gray, cv2.COLOR_GRAY2RGB)
    return np.ascontiguousarray(image)
