# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The foveal detector's brain, without ROS: which image serves which fixation, and its counts.

:class:`DetectorLoop` is what the ``foveal_detector`` node wraps (docs/design.md section 6.6).
It turns camera images into count frames for the controller, one frame per fixation:

- the controller sends a fixation (a cell; re-sends count as new requests), and the loop waits
  for the **newest image captured after the fixation was commanded**: its stamp not earlier
  than the time the fixation arrived, and the image itself arrived after the fixation (so an
  image stamped ahead by a camera whose clock runs fast cannot answer a later fixation);
- in ``camera`` mode that image must also be paired with the head's joint state of the same
  stamp (within ``tolerance_s``), the head must be at the fixated cell (an image taken on the
  way there is not used) and the camera's intrinsics must be known; the detections are binned
  to pan/tilt cells with :mod:`ipomdp_gaze.model.head_camera`, cells outside the view are NaN;
- in ``fovea`` mode the grid tiles the image and the digital fovea is placed on the fixated cell
  (:class:`ipomdp_gaze.vision.fovea.Fovea`).

Every image is counted: ``received = processed + rejected + unused`` (unused: no fixation was
waiting for it, or a newer image served it). An image the detector cannot take (too small, not
the size ``camera_info`` says, or one a plug-in detector fails on: ``DetectorFailed``) is
rejected with the reason and the fixation keeps waiting.

**Time sanity.** Each input is checked against the node's clock when it arrives: an image or
joint state stamped more than ``stamp_tolerance_s`` ahead of it is rejected (``images_future``;
a camera whose clock runs ahead), and one stamped more than ``max_age_s`` before it (``0``:
no limit) is rejected as stale (``images_stale``; a clock behind, or a replay).

**Finite but absurd values** are refused where they enter, counted like image rejections: joint
angles beyond :data:`MAX_JOINT_RAD` (``joint_states_rejected``) and intrinsics that no camera
has (:func:`check_camera`: a field of view outside :data:`FOV_RANGE_DEG` or a principal point
outside the image, ``camera_info_rejected``). As for images, ``<input>_received`` counts every
message of that input, the rejected ones included.

**Bounded cost per frame.** Images are held only while a fixation waits, at most ``keep`` (4)
of them. An image more than :data:`RESIZE_ABOVE` times wider or taller than the images the
model was calibrated on (420x420 for the shipped fovea models, the 320x240 camera of
``faces-pan-tilt-profile``) is resized (``cv2.INTER_AREA``, aspect kept) to fit that size when it
arrives; in ``camera`` mode ``camera_info``'s K is scaled with it. The detector then sees faces
at the pixel size the counts were calibrated at, and its cost is that of the model's images
whatever the driver sends. (Refusing such images instead would make every HD camera unusable;
the grid tiles the image in ``fovea`` mode and K follows the resize in ``camera`` mode, so the
cells seen do not change.)

:func:`build_setup` reads the observation file: its grid, fovea and detector settings are the
ones the counts mean anything with, so settings given next to it may only repeat them.
"""
from __future__ import annotations

import bisect
from collections import deque
from dataclasses import dataclass, field
import math
from pathlib import Path
import time

from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.head_camera import PinholeCamera
from ipomdp_gaze.search.gaze import STAMP_TOLERANCE_S
import numpy as np

MODES = ('fovea', 'camera')
# The observation model of each mode when none is given: the shipped face models.
DEFAULT_MODELS = {'fovea': 'faces-420', 'camera': 'faces-pan-tilt-profile'}
# The view a model was calibrated with (its image record), per mode.
MODE_VIEWS = {'fovea': 'fixed', 'camera': 'pan_tilt'}
# The Haar detector's settings with node parameters of their own (an empty or negative value:
# the file's); any detector's other settings go in detector.options.
DETECTOR_KEYS = ('cascade', 'scale_factor', 'min_neighbors')
TIMING_WINDOW = 100
# Joint angles farther than this from zero are absurd: no pan/tilt head turns more than a turn.
MAX_JOINT_RAD = 2 * math.pi
# Fields of view (degrees, edge to edge) a camera_info may describe.
FOV_RANGE_DEG = (0.5, 175.0)
# Images more than this many times the model's image width or height are resized (far larger).
RESIZE_ABOVE = 2.0
# Defaults of the time sanity rule (seconds): images stamped ahead by more than
# STAMP_TOLERANCE_S (the controller's tolerance too) or older than MAX_AGE_S are refused.
MAX_AGE_S = 10.0
# Joint states are kept for as long as an image may be old (max_age_s; this long without a
# limit), at most this many: a 1 kHz joint_state_broadcaster and a camera 0.5 s late still pair.
POSE_SPAN_S = 10.0
MAX_POSES = 100_000


class PoseHistory:
    """
    The head's joint angles by stamp over the last ``span_s`` seconds, looked up by bisection.

    Kept by time, not by count: at 500 Hz a count of 200 held 0.4 s, and an image 0.5 s late
    found no joint state to pair with. At most ``cap`` are kept (the oldest go first).
    """

    def __init__(self, span_s: float = POSE_SPAN_S, cap: int = MAX_POSES):
        self.span_s, self.cap = float(span_s), int(cap)
        self.stamps: list[float] = []
        self.poses: list[tuple[float, float]] = []

    def __len__(self) -> int:
        return len(self.stamps)

    def add(self, stamp_s: float, pan: float, tilt: float) -> None:
        """
        Keep a joint state (in stamp order; equal stamps after the earlier ones).

        One stamped more than ``span_s`` before the newest kept says the clock went back (a
        simulation reset, a bag played in a loop; a live node refuses joint states that old):
        the history starts again from it, so that no pose of before the jump answers.
        """
        if self.stamps and stamp_s < self.stamps[-1] - self.span_s:
            self.stamps.clear()
            self.poses.clear()
        i = bisect.bisect_right(self.stamps, stamp_s)
        self.stamps.insert(i, stamp_s)
        self.poses.insert(i, (pan, tilt))
        old = max(bisect.bisect_left(self.stamps, self.stamps[-1] - self.span_s),
                  len(self.stamps) - self.cap)
        if old > 0 and (old >= 1024 or 2 * old > len(self.stamps)):     # amortised
            del self.stamps[:old]
            del self.poses[:old]

    def nearest(self, stamp_s: float, tolerance_s: float):
        """Return the angles stamped closest to ``stamp_s`` within the tolerance, or None."""
        i = bisect.bisect_left(self.stamps, stamp_s)
        best = None
        for j in (i - 1, i):
            if 0 <= j < len(self.stamps):
                gap = abs(self.stamps[j] - stamp_s)
                if gap <= tolerance_s + 1e-9 and (best is None or gap < best[0]):
                    best = (gap, *self.poses[j])
        return None if best is None else best[1:]

    def gap(self, stamp_s: float) -> float:
        """Return how far the joint state stamped closest to ``stamp_s`` is from it (inf: none)."""
        i = bisect.bisect_left(self.stamps, stamp_s)
        return min((abs(self.stamps[j] - stamp_s) for j in (i - 1, i)
                    if 0 <= j < len(self.stamps)), default=math.inf)


def model_view(model) -> str:
    """``'pan_tilt'`` for a model calibrated through a head camera, else ``'fixed'``."""
    image = getattr(model, 'meta', {}).get('image') or {}
    return str(image.get('view', 'fixed'))


def model_image_size(model) -> tuple[int, int] | None:
    """Return the ``(width, height)`` of the images a model was calibrated on, or None."""
    image = getattr(model, 'meta', {}).get('image') or {}
    try:
        size = int(image['width']), int(image['height'])
    except (KeyError, TypeError, ValueError, OverflowError):
        return None
    return size if min(size) > 0 else None


def model_camera(model) -> PinholeCamera | None:
    """Return the head camera a pan/tilt model was calibrated with, or None."""
    image = getattr(model, 'meta', {}).get('image') or {}
    if image.get('camera') is None:
        return None
    return PinholeCamera.from_dict(image['camera'])


@dataclass
class DetectorSetup:
    """What the detector works with: the model, its detector and the fovea or view observer."""

    mode: str
    model: object
    name: str
    detector: object
    fovea: object = None
    observer: object = None
    camera: PinholeCamera | None = None
    image_size: tuple[int, int] | None = None
    notes: tuple = ()
    """What differs from the file in information-only detector settings (the OpenCV version)."""

    @property
    def grid(self) -> Grid:
        """Return the model's grid."""
        return self.model.grid


def build_setup(mode: str, source: str = '', grid=(0, 0, 0.0), detector: dict | None = None,
                cascade_dir=None, unused_cascade_dir: str = 'refuse') -> DetectorSetup:
    """
    Load the observation model of ``mode`` and build its detector and fovea (or view observer).

    Parameters
    ----------
    mode : {'fovea', 'camera'}
        See the module docstring.
    source : str
        Observation file path or shipped name; ``''`` for :data:`DEFAULT_MODELS` of the mode.
    grid : (int, int, float)
        ``rows, cols, spacing_deg`` asked for; 0 takes the file's. Another value must repeat it.
    detector : dict, optional
        Detector settings asked for (``kind`` and the detector's own settings, e.g. those of
        :data:`DETECTOR_KEYS` for ``haar``); each must repeat the file's.
    cascade_dir : str, optional
        Folder holding the cascades the file names (or a cascade file), instead of OpenCV's;
        refused if it does not exist or lacks one of them (:func:`check_cascade_dir`).
    unused_cascade_dir : {'refuse', 'ignore'}
        What a ``cascade_dir`` given to a detector that takes none (YuNet) gets: refused (a
        node's parameter), or ignored (``replay``: a bag recorded before 0.3.9, whose node
        accepted and ignored it, searches as it did).

    Raises
    ------
    ValueError
        Naming the problem: the model's view does not fit the mode, or a setting contradicts
        the file (the file wins: it says what the counts were measured with).

    """
    from ipomdp_gaze.model.cell_observation import cell_observation_of
    from ipomdp_gaze.vision.detectors import detector_from_settings
    from ipomdp_gaze.vision.fovea_model import check_records, fovea_for_model
    from ipomdp_gaze.vision.pan_tilt import ViewObserver
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    name = source or DEFAULT_MODELS[mode]
    model = load_observation(name)
    view = model_view(model)
    if view != MODE_VIEWS[mode]:
        raise ValueError(f'observation.file {name!r} was calibrated with a {view} view; {mode} '
                         f'mode needs a model calibrated with a {MODE_VIEWS[mode]} view '
                         f'(e.g. {DEFAULT_MODELS[mode]})')
    rows, cols, spacing = grid
    g = model.grid
    for key, asked, has in (('rows', rows, g.rows), ('cols', cols, g.cols)):
        if asked and asked != has:
            raise ValueError(f'grid.{key} {asked} contradicts observation.file {name!r}, a '
                             f'{g.rows}x{g.cols} grid (leave grid.{key} at 0 to take it)')
    if spacing and mode == 'camera' and abs(spacing - g.spacing_deg) > 1e-9 * g.spacing_deg:
        raise ValueError(f'grid.spacing_deg {spacing} contradicts observation.file {name!r}, '
                         f'calibrated at {g.spacing_deg} deg/cell (leave it at 0.0 to take it)')
    recorded = dict(model.meta.get('detector') or {})
    if not recorded:
        raise ValueError(f'observation.file {name!r} does not record its detector')
    try:
        check_records(model)
    except ValueError as exc:
        raise ValueError(f'observation.file {name!r}: {exc}') from None
    for key, asked in (detector or {}).items():
        if key not in recorded:
            raise ValueError(f'detector.{key}: the detector {recorded.get("kind")!r} of '
                             f'observation.file {name!r} has no setting {key!r} (it has '
                             f'{", ".join(sorted(recorded))})')
    if unused_cascade_dir not in ('refuse', 'ignore'):
        raise ValueError(f"unused_cascade_dir must be 'refuse' or 'ignore', got "
                         f'{unused_cascade_dir!r}')
    if cascade_dir and unused_cascade_dir == 'ignore' and not _takes_cascade_dir(recorded):
        cascade_dir = None
    if cascade_dir:
        check_cascade_dir(cascade_dir, recorded, name)
    differs = sorted(key for key, asked in (detector or {}).items() if asked != recorded[key])
    if differs and not _builds_the_same(recorded, detector, cascade_dir):
        key = differs[0]
        raise ValueError(f'detector.{key} {detector[key]!r} contradicts observation.file '
                         f'{name!r}, measured with {recorded[key]!r} (leave it unset to take it)')
    notes = []
    try:
        built = detector_from_settings(recorded, cascade_dir or None, notes.append)
        if mode == 'fovea':
            return DetectorSetup(mode, model, name, built,
                                 fovea=fovea_for_model(model, built, reuse_windows=False),
                                 image_size=model_image_size(model), notes=tuple(notes))
        observer = ViewObserver(built, g, model.max_count + 1,
                                cell_observation_of(model.meta, model.max_count + 1))
        return DetectorSetup(mode, model, name, built, observer=observer,
                             camera=model_camera(model), image_size=model_image_size(model),
                             notes=tuple(notes))
    except ValueError as exc:
        raise ValueError(_one_line(exc)) from None
    except (TypeError, KeyError, IndexError, OverflowError, AttributeError, OSError) as exc:
        # A record of the file with the wrong types (a fuzzed or hand-edited file).
        raise ValueError(f'observation.file {name!r}: its detector or fovea record is unusable '
                         f'({type(exc).__name__}: {_one_line(exc)})') from None


def check_cascade_dir(cascade_dir, recorded: dict, name: str) -> None:
    """
    Refuse a ``detector.cascade_dir`` that does not exist or lacks a cascade of ``recorded``.

    Without the check, a cascade missing there was taken from OpenCV's installed ones unnoticed;
    and a detector that is given no cascade folder (YuNet) ignored it: that is refused too.
    ``name`` is the observation file recording the detector ``recorded``.
    """
    path = Path(cascade_dir)
    if not _takes_cascade_dir(recorded):
        kind = recorded.get('kind') if isinstance(recorded, dict) else None
        raise ValueError(f'detector.cascade_dir {path} is not used: the detector of '
                         f'observation.file {name!r}, {kind}, uses no Haar cascade (leave it '
                         "'')")
    names = _cascade_names(recorded)
    looked = f' (it was to hold {", ".join(names)})' if names else ''
    if not path.exists():
        raise ValueError(f'detector.cascade_dir {path} does not exist{looked}')
    if not path.is_dir():
        if len(names) > 1:
            raise ValueError(f'detector.cascade_dir {path} is a file; observation.file {name!r} '
                             f'needs the cascades {", ".join(names)}: give their folder')
        return
    missing = [n for n in names if not (path / n).is_file()]
    if missing:
        raise ValueError(f'detector.cascade_dir {path} has no {missing[0]} (a cascade of '
                         f'observation.file {name!r}, looked for there only)')


def _takes_cascade_dir(recorded) -> bool:
    """
    Whether the detector a record rebuilds is given ``cascade_dir`` (a member of it, or itself).

    Haar is; YuNet is not; a plug-in is when its ``from_settings`` takes it (as
    :func:`~ipomdp_gaze.vision.detectors.detector_from_settings` passes it). A record whose kind
    cannot be loaded is left to the build, which names its fault.
    """
    from ipomdp_gaze.vision.detectors import load_factory, takes_cascade_dir
    if not isinstance(recorded, dict):
        return True
    kind = recorded.get('kind')
    if kind == 'ensemble':
        members = recorded.get('members')
        return not isinstance(members, list) or any(_takes_cascade_dir(m) for m in members)
    if kind == 'haar':
        return True
    try:
        return takes_cascade_dir(load_factory(kind))
    except (ValueError, TypeError):
        return True


def _cascade_names(recorded) -> list:
    """Return the file names of the Haar cascades a detector record names (members too)."""
    if not isinstance(recorded, dict):
        return []
    if recorded.get('kind') == 'ensemble':
        members = recorded.get('members')
        return [n for m in (members if isinstance(members, list) else [])
                for n in _cascade_names(m)]
    if recorded.get('kind') != 'haar':
        return []
    from ipomdp_gaze.vision.detector import REFERENCE_CASCADE
    cascade = recorded.get('cascade', REFERENCE_CASCADE)
    cascades = cascade if isinstance(cascade, list) else [cascade]
    return [Path(str(c)).name for c in cascades]


def _builds_the_same(recorded: dict, asked: dict, cascade_dir) -> bool:
    """
    Whether the settings ``asked`` over ``recorded`` build the recorded detector.

    Options written as given (an ensemble's members without the defaults and fingerprints the
    file fills in) repeat the file when the detector they build records what it does.
    """
    from ipomdp_gaze.vision.detector import detector_settings
    from ipomdp_gaze.vision.detectors import (compare_settings, info_keys_of, load_factory,
                                              make_detector, option_names)
    try:
        kind = asked.get('kind', recorded['kind'])
        takes = option_names(load_factory(kind))
        if takes is not None and any(asked[key] != recorded.get(key)
                                     for key in asked if key != 'kind' and key not in takes):
            return False                # a fingerprint or record-only key: only the file's
        options = {key: value for key, value in {**recorded, **asked}.items()
                   if key != 'kind' and (takes is None or key in takes)}
        if cascade_dir and (takes is None or 'cascade_dir' in takes):
            options['cascade_dir'] = cascade_dir
        built = make_detector(kind, **options)
        compare_settings(recorded, detector_settings(built), info_keys_of(built))
    except Exception:                           # noqa: B902 (whatever fails: not the same)
        return False
    return True


def _one_line(exc: BaseException) -> str:
    """Return an exception's message on one line (its lines joined with '; ')."""
    return '; '.join(line.strip() for line in str(exc).splitlines() if line.strip())


def camera_mismatch(model_camera_: PinholeCamera | None, camera: PinholeCamera) -> str:
    """
    Say how ``camera`` differs from the camera a model was calibrated with ('' if not).

    As the detector sees it: an image that :func:`resized_size` shrinks is compared at the size
    it is shrunk to (a 1280x960 camera of the model's field of view is the model's camera).
    """
    if model_camera_ is None:
        return ''
    model_size = (model_camera_.width, model_camera_.height)
    size = resized_size((camera.width, camera.height), model_size)
    if model_camera_.matches(camera if size is None else scaled_camera(camera, *size)):
        return ''
    hfov, vfov = camera.fov_deg
    mh, mv = model_camera_.fov_deg
    return (f'camera_info describes a {camera.width}x{camera.height} camera with a '
            f'{hfov:.1f}x{vfov:.1f} deg field of view, but the model was calibrated with '
            f'{model_camera_.width}x{model_camera_.height} and {mh:.1f}x{mv:.1f} deg: its '
            f'counts may not follow the model, and cells it does not see may be answered '
            f'absent (calibrate a model for this camera: ipomdp-gaze calibrate --pan-tilt '
            f'--camera {camera.width}x{camera.height} --hfov-deg {hfov:.1f}, with the '
            f'detector options of the model you use; bench/faces/models.py has their recipes)')


def check_camera(camera: PinholeCamera, max_side_px: int | None = None) -> None:
    """
    Refuse intrinsics that are finite but absurd.

    Raises
    ------
    ValueError
        If a side is above ``max_side_px``, a field of view is outside :data:`FOV_RANGE_DEG`, or
        the principal point ``(cx, cy)`` lies outside the image.

    """
    if max_side_px and max(camera.width, camera.height) > max_side_px:
        raise ValueError(f'camera_info describes a {camera.width}x{camera.height} image, larger '
                         f'than {max_side_px} px on a side')
    low, high = FOV_RANGE_DEG
    for axis, fov in zip(('horizontal', 'vertical'), camera.fov_deg):
        if not low <= fov <= high:
            raise ValueError(f'camera_info K gives a {axis} field of view of {fov:.4g} deg, '
                             f'outside [{low}, {high}] (fx {camera.fx:.6g}, fy {camera.fy:.6g})')
    if not (-0.5 <= camera.cx <= camera.width - 0.5 and -0.5 <= camera.cy <= camera.height - 0.5):
        raise ValueError(f'camera_info principal point ({camera.cx:.6g}, {camera.cy:.6g}) lies '
                         f'outside the {camera.width}x{camera.height} image')


def scaled_camera(camera: PinholeCamera, width: int, height: int) -> PinholeCamera:
    """Return the camera as seen through an image resized to ``width x height`` (K scaled)."""
    sx, sy = width / camera.width, height / camera.height
    return PinholeCamera(width, height, camera.fx * sx, camera.fy * sy,
                         (camera.cx + 0.5) * sx - 0.5, (camera.cy + 0.5) * sy - 0.5)


def resized_size(size: tuple[int, int], model_size: tuple[int, int] | None,
                 mode: str = 'camera') -> tuple[int, int] | None:
    """
    Return the ``(width, height)`` an image of ``size`` is resized to, or None to keep it.

    ``camera`` mode: an image more than :data:`RESIZE_ABOVE` times the model's image width or
    height is scaled (aspect kept) to fit within the model's image size: a camera of the
    model's field of view then has the model's pixels per degree. ``fovea`` mode (a fixed
    camera, no field of view to match): the image's shorter side stands for the model's
    (square) side, so an image whose shorter side is more than :data:`RESIZE_ABOVE` times the
    model's shorter side is scaled to it; a wide frame (16:9) keeps its height's worth of
    pixels instead of shrinking to fit the model's width (a 1280x720 frame fitted into 420x420
    halved its faces, and the search answered a false alarm).
    """
    width, height = size
    if model_size is None:
        return None
    if mode == 'fovea':
        side, model_side = min(width, height), min(model_size)
        if side <= RESIZE_ABOVE * model_side:
            return None
        scale = model_side / side
    elif width <= RESIZE_ABOVE * model_size[0] and height <= RESIZE_ABOVE * model_size[1]:
        return None
    else:
        scale = min(model_size[0] / width, model_size[1] / height)
    return max(1, round(width * scale)), max(1, round(height * scale))


def resize_view(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Resize a view to ``(width, height)`` by pixel area averaging (a new array)."""
    import cv2
    return cv2.resize(np.ascontiguousarray(image), size, interpolation=cv2.INTER_AREA)


@dataclass(frozen=True)
class Frame:
    """
    One count frame for the controller, and what it cost.

    ``kind`` is ``'fixation'`` or ``'scan'`` (the one-time scan, ``fixation`` None then);
    ``search_id`` the search it was asked for (None: the request did not say). ``image``,
    ``detections_px`` (raw detection centres ``(M, 2)`` in its pixels), ``windows`` (fovea
    windows) and ``head_rc`` (camera mode) say how it was made, for pictures of the search.
    ``offsets`` (camera mode): the mean offset ``(row, col)`` in cells of the detections
    centred in each cell, NaN where none (``ViewObservation.offsets``); ``groups`` (camera mode,
    an observer with ``group_min_neighbors``): the grouped detections per cell
    (``ViewObservation.groups``).
    """

    fixation: int | None
    stamp_s: float
    token: object
    counts: np.ndarray
    detector_pixels: int
    seconds: float
    kind: str = 'fixation'
    search_id: int | None = None
    image: np.ndarray | None = field(default=None, compare=False, repr=False)
    detections_px: np.ndarray | None = field(default=None, compare=False, repr=False)
    windows: tuple = field(default=(), compare=False, repr=False)
    head_rc: tuple | None = field(default=None, compare=False, repr=False)
    offsets: np.ndarray | None = field(default=None, compare=False, repr=False)
    groups: np.ndarray | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class Outcome:
    """What happened when the loop tried to serve the waiting fixation."""

    status: str          # 'published', 'rejected', 'refused', 'waiting' or 'idle'
    reason: str = ''
    frame: Frame | None = None


class DetectorLoop:
    """
    Serve each fixation with the counts of one image (see the module docstring).

    Parameters
    ----------
    setup : DetectorSetup
        From :func:`build_setup`.
    head : PanTiltMap, optional
        ``camera`` mode: the joint mapping that turns a joint state into the head's position.
    tolerance_s : float
        ``camera`` mode: a joint state pairs with an image stamped at most this far apart.
    keep : int
        Images kept while a fixation waits (the newest; none while no fixation waits); joint
        states are kept by time (:class:`PoseHistory`, as long as ``max_age_s``).

    stamp_tolerance_s : float
        Inputs stamped more than this ahead of the clock on arrival are rejected.
    max_age_s : float
        Inputs stamped more than this before the clock on arrival are rejected (0: no limit).

    """

    def __init__(self, setup: DetectorSetup, head: PanTiltMap | None = None,
                 tolerance_s: float = 0.0, keep: int = 4,
                 stamp_tolerance_s: float = STAMP_TOLERANCE_S, max_age_s: float = MAX_AGE_S):
        if setup.mode == 'camera' and head is None:
            raise ValueError('camera mode needs the head mapping (joint names, signs, offsets)')
        self.setup = setup
        self.head = head
        self.tolerance_s = float(tolerance_s)
        self.stamp_tolerance_s = float(stamp_tolerance_s)
        self.max_age_s = float(max_age_s)
        self.camera: PinholeCamera | None = None
        self.pending: tuple[int | None, float] | None = None
        self.search_id: int | None = None
        self.scans = 0
        self._images = deque(maxlen=keep)
        self._poses = PoseHistory(self.max_age_s if self.max_age_s > 0 else POSE_SPAN_S)
        self.received = self.processed = self.rejected = self.fixations = 0
        self.future = self.stale = self.resized = 0
        # Other inputs: received and refused (joint_states, camera_info, fixation).
        self.inputs = {k: [0, 0] for k in ('joint_states', 'camera_info', 'fixation')}
        self.last_rejection = ''
        self.last_refusal = ''
        self.mismatch = ''
        self.waiting = ''
        self._seconds = deque(maxlen=TIMING_WINDOW)
        self._pixels = deque(maxlen=TIMING_WINDOW)

    # -- inputs ------------------------------------------------------------------------------
    def _stamp_problem(self, stamp_s: float, now_s: float | None) -> str:
        """Why a stamp breaks the time sanity rule ('' if it does not, or no clock is given)."""
        if now_s is None:
            return ''
        ahead = stamp_s - now_s
        if not math.isfinite(ahead):
            return f'stamp {stamp_s!r} is not a finite time'
        if ahead > self.stamp_tolerance_s:
            return (f"stamped {ahead:.3f} s ahead of this node's clock (more than "
                    f'stamp_tolerance_s {self.stamp_tolerance_s:g} s): its clock runs ahead')
        if self.max_age_s > 0 and -ahead > self.max_age_s:
            return (f'stamped {-ahead:.3f} s before it arrived (more than max_image_age_s '
                    f'{self.max_age_s:g} s): stale, or its clock runs behind')
        return ''

    def fixate(self, cell: int, now_s: float, search_id: int | None = None) -> Outcome:
        """
        Take a fixation commanded at ``now_s``: wait for an image captured from then on.

        ``search_id`` (the controller's, when it says) comes back with the frame; a new id is a
        new search, and whatever the previous one still waited for is dropped. The same fixation
        of the same search re-sent while it still waits (the controller's ``retry_period_s``)
        keeps waiting from the first command: restarting the wait would throw away the image a
        slow head takes on arrival, and every re-send would do it again. A re-send before the
        first command's time is a clock set back (sim time: a simulator's reset, a looped bag):
        the wait starts again from it, and the images kept, stamped on the old clock, go.
        """
        cell = int(cell)
        self.setup.grid.cell(cell)
        self.fixations += 1
        self.inputs['fixation'][0] += 1
        now_s = float(now_s)
        self._clock_went_back(now_s)
        resent = self.pending is not None and self.pending[0] == cell \
            and search_id == self.search_id
        self.search_id = search_id
        if not resent:
            self.pending = (cell, now_s)
        return self.serve()

    def request_scan(self, search_id: int, now_s: float) -> Outcome:
        """
        Take a request for the one-time scan of search ``search_id`` (docs/design.md 10.3).

        Served with the next image captured from ``now_s`` on: the fovea's whole-image windows
        (``fovea`` mode with a scanning fovea); a sensor without a scan (``camera`` mode, or a
        fovea that does not scan) answers with a frame of NaN (nothing observed), so the
        controller can start its search all the same. A re-send of the request waiting (the
        same search) keeps waiting from the first, as a re-sent fixation does: restarting the
        wait at every ``retry_period_s`` starved the scan of a camera whose images take longer
        than that to arrive, and hid the wait from the stuck warning.
        """
        self.fixations += 1
        self.inputs['fixation'][0] += 1
        now_s = float(now_s)
        self._clock_went_back(now_s)
        resent = self.pending is not None and self.pending[0] is None \
            and int(search_id) == self.search_id
        self.search_id = int(search_id)
        if not resent:
            self.pending = (None, now_s)
        return self.serve()

    def _clock_went_back(self, now_s: float) -> None:
        """Before a command stamped earlier than the one waiting: the images kept go."""
        if self.pending is not None and now_s < self.pending[1]:
            self._images.clear()
            self.pending = None

    def add_image(self, stamp_s: float, image: np.ndarray, token=None,
                  now_s: float | None = None) -> Outcome:
        """
        Take a decoded image captured at ``stamp_s`` and arrived at ``now_s``; serve if due.

        ``token`` comes back in the :class:`Frame` the image serves (the node's exact stamp).
        With ``now_s``, the time sanity rule applies and an image that arrived while no fixation
        waited is not kept (it can serve no fixation).
        """
        self.received += 1
        problem = self._stamp_problem(float(stamp_s), now_s)
        if problem:
            if 'ahead' in problem:
                self.future += 1
            else:
                self.stale += 1
            return self._rejected(f'image {problem}')
        if now_s is not None and (self.pending is None or now_s < self.pending[1]):
            return Outcome('idle')
        size = (image.shape[1], image.shape[0])
        t0 = time.perf_counter()
        if image.ndim in (2, 3):
            target = resized_size(size, self.setup.image_size, self.setup.mode)
            if target is not None:
                image = resize_view(image, target)
                self.resized += 1
        self._images.append((float(stamp_s), image, token, size, time.perf_counter() - t0))
        return self.serve()

    def reject(self, reason: str) -> Outcome:
        """Count an image message that could not even be decoded."""
        self.received += 1
        return self._rejected(reason)

    def refuse(self, kind: str, reason: str) -> Outcome:
        """Count a ``joint_states``, ``camera_info`` or ``fixation`` message refused at entry."""
        counts = self.inputs[kind]
        counts[0] += 1
        counts[1] += 1
        self.last_refusal = f'{kind}: {reason}'
        return Outcome('refused', f'{kind}: {reason}')

    def add_pose(self, stamp_s: float, pan_rad: float, tilt_rad: float,
                 now_s: float | None = None) -> Outcome:
        """Take the head's joint angles at ``stamp_s`` (``camera`` mode); refuse absurd ones."""
        pan, tilt = float(pan_rad), float(tilt_rad)
        if not (abs(pan) <= MAX_JOINT_RAD and abs(tilt) <= MAX_JOINT_RAD):
            return self.refuse('joint_states', f'pan/tilt {pan!r}, {tilt!r} rad: beyond '
                                               f'+/-{MAX_JOINT_RAD:.4f} rad (one turn)')
        problem = self._stamp_problem(float(stamp_s), now_s)
        if problem:
            return self.refuse('joint_states', problem)
        self.inputs['joint_states'][0] += 1
        self._poses.add(float(stamp_s), pan, tilt)
        return self.serve()

    def set_camera(self, camera: PinholeCamera, max_side_px: int | None = None) -> Outcome:
        """
        Use these intrinsics from now on unless :func:`check_camera` refuses them.

        Returns the outcome of serving the waiting fixation (``refused`` with the reason when
        refused); a warning when the model expects another camera is in ``mismatch``.
        """
        try:
            check_camera(camera, max_side_px)
        except ValueError as exc:
            return self.refuse('camera_info', str(exc))
        self.inputs['camera_info'][0] += 1
        self.mismatch = ''
        if camera != self.camera:
            self.camera = camera
            self.mismatch = camera_mismatch(self.setup.camera, camera)
        return self.serve()

    def set_max_age(self, max_age_s: float) -> None:
        """Refuse inputs older than ``max_age_s`` (0: no limit); keep joint states that long."""
        self.max_age_s = float(max_age_s)
        self._poses.span_s = self.max_age_s if self.max_age_s > 0 else POSE_SPAN_S

    def waited_s(self, now_s: float) -> float:
        """Return how long the waiting fixation has waited for a usable image (0: none waits)."""
        return 0.0 if self.pending is None else max(0.0, float(now_s) - self.pending[1])

    def set_setup(self, setup: DetectorSetup) -> None:
        """Use another model and detector from the next image on."""
        self.setup = setup

    # -- serving ---------------------------------------------------------------------------
    def _rejected(self, reason: str) -> Outcome:
        self.rejected += 1
        self.last_rejection = str(reason)
        return Outcome('rejected', str(reason))

    def _pose_at(self, stamp_s: float):
        """Return the joint angles stamped closest to ``stamp_s`` within the tolerance, or None."""
        return self._poses.nearest(stamp_s, self.tolerance_s)

    def serve(self) -> Outcome:
        """Serve the waiting fixation with the newest usable image, if there is one."""
        outcome = self._serve()
        self.waiting = outcome.reason if outcome.status == 'waiting' else ''
        return outcome

    def _serve(self) -> Outcome:
        if self.pending is None:
            return Outcome('idle')
        cell, since = self.pending
        fresh = [item for item in self._images if item[0] >= since]
        if not fresh:
            return Outcome('waiting', 'no image captured since the fixation was commanded')
        stamp, image, token, size, prep_s = fresh[-1]
        if self.setup.mode == 'fovea' or cell is None:
            return self._count(cell, stamp, image, token, prep_s=prep_s)
        if self.camera is None:
            return Outcome('waiting', 'no camera_info received: camera mode needs the '
                                      'intrinsics K to map pixels to cells')
        pose = self._pose_at(stamp)
        if pose is None:
            gap = self._poses.gap(stamp)
            nearest = ('no joint state received' if not math.isfinite(gap) else
                       f'the nearest is {gap:.3g} s from it')
            return Outcome('waiting', f'no joint state with the stamp of the newest image '
                                      f'({nearest}; joint_state_tolerance_s '
                                      f'{self.tolerance_s:g} s)')
        head_rc = self.head.position(*pose)
        at = self.head.nearest_cell(*pose)
        if at != cell:
            self._drop_through(stamp)
            return Outcome('waiting', f'the head is at {self.setup.grid.cell(at)}, not yet at '
                                      f'the fixation {self.setup.grid.cell(cell)}')
        return self._count(cell, stamp, image, token, head_rc, size, prep_s)

    def _drop_through(self, stamp_s: float) -> None:
        while self._images and self._images[0][0] <= stamp_s:
            self._images.popleft()

    def _view_camera(self, image, size) -> PinholeCamera:
        """Return the camera_info camera as seen through ``image`` (K scaled if resized)."""
        camera = self.camera
        if (camera.width, camera.height) != tuple(size):
            raise ValueError(f'the image is {size[0]}x{size[1]} px but camera_info says '
                             f'{camera.width}x{camera.height}')
        height, width = image.shape[:2]
        if (width, height) == tuple(size):
            return camera
        return scaled_camera(camera, width, height)

    def _count(self, cell: int, stamp_s: float, image, token, head_rc=None,
               size=None, prep_s: float = 0.0) -> Outcome:
        """Detect and count; the frame's ``seconds`` include the resize on arrival."""
        setup = self.setup
        t0 = time.perf_counter()
        offsets = groups = None
        try:
            if cell is None:
                counts, pixels, centres, windows = self._scan(image)
            elif setup.mode == 'fovea':
                setup.fovea.start(image)
                observation = setup.fovea.observe(cell)
                counts, pixels = observation.counts, observation.detector_pixels
                centres, windows = observation.centres_px - 0.5, observation.windows
            else:
                camera = self._view_camera(image, size)
                observation = setup.observer.observe(image, camera, head_rc)
                counts, pixels = observation.counts, observation.detector_pixels
                centres, windows = observation.centres_uv, ()
                offsets, groups = observation.offsets, observation.groups
        except ValueError as exc:
            self._drop_through(stamp_s)
            return self._rejected(str(exc))
        seconds = time.perf_counter() - t0 + prep_s
        self._drop_through(stamp_s)
        self.pending = None
        self.processed += 1
        self.scans += cell is None
        self._seconds.append(seconds)
        self._pixels.append(pixels)
        return Outcome('published', frame=Frame(
            cell, stamp_s, token, counts, int(pixels), seconds,
            'scan' if cell is None else 'fixation', self.search_id, image, centres, windows,
            head_rc, offsets, groups))

    def _scan(self, image) -> tuple[np.ndarray, int, np.ndarray, tuple]:
        """
        Return the one-time scan of an image: counts, pixels, detections, windows.

        A sensor without a scan gives NaN everywhere (nothing observed) and no detections.
        """
        fovea = self.setup.fovea
        if self.setup.mode == 'fovea' and fovea.config.scan_once:
            fovea.start(image)
            scan = fovea.scan()
            return scan.counts, scan.detector_pixels, scan.centres_px - 0.5, scan.windows
        return np.full(self.setup.grid.n_cells, np.nan), 0, np.zeros((0, 2)), ()

    # -- reporting -------------------------------------------------------------------------
    def values(self) -> dict:
        """Counters and costs for ``/diagnostics`` (times in ms, over the last frames)."""
        seconds = np.asarray(self._seconds, dtype=float)
        pixels = np.asarray(self._pixels, dtype=float)
        waiting = self.pending is not None
        return {
            'mode': self.setup.mode, 'observation': self.setup.name,
            'images_received': self.received, 'images_processed': self.processed,
            'scans_served': self.scans, 'search_id': -1 if self.search_id is None
            else self.search_id,
            'images_rejected': self.rejected,
            'images_unused': self.received - self.processed - self.rejected,
            'images_future': self.future, 'images_stale': self.stale,
            'images_resized': self.resized, 'images_held': len(self._images),
            'fixations_received': self.inputs['fixation'][0], 'waiting_for_image': waiting,
            'waiting_because': self.waiting if waiting else '',
            'camera_info': self.camera is not None,
            'detector_ms_last': 1e3 * seconds[-1] if seconds.size else 0.0,
            'detector_ms_median': 1e3 * float(np.median(seconds)) if seconds.size else 0.0,
            'pixels_per_fixation_last': int(pixels[-1]) if pixels.size else 0,
            'pixels_per_fixation_mean': float(pixels.mean()) if pixels.size else 0.0,
            'last_rejection': self.last_rejection,
            'fixations_rejected': self.inputs['fixation'][1],
            **{f'{kind}_{what}': self.inputs[kind][i] for kind in ('joint_states', 'camera_info')
               for i, what in enumerate(('received', 'rejected'))},
            'last_input_rejection': self.last_refusal,
        }
