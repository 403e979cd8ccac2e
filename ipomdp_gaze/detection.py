# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The foveal detector's brain, without ROS: which image serves which fixation, and its counts.

:class:`DetectorLoop` is what the ``foveal_detector`` node wraps (docs/design.md section 6.6).
It turns camera images into count frames for the controller, one frame per fixation:

- the controller sends a fixation (a cell; re-sends count as new requests), and the loop waits
  for the **newest image captured after the fixation was commanded** (its stamp not earlier
  than the time the fixation arrived);
- in ``camera`` mode that image must also be paired with the head's joint state of the same
  stamp (within ``tolerance_s``), the head must be at the fixated cell (an image taken on the
  way there is not used) and the camera's intrinsics must be known; the detections are binned
  to pan/tilt cells with :mod:`ipomdp_gaze.head_camera`, cells outside the view are NaN;
- in ``fovea`` mode the grid tiles the image and the digital fovea is placed on the fixated cell
  (:class:`ipomdp_gaze.vision.fovea.Fovea`).

Every image is counted: ``received = processed + rejected + unused`` (unused: no fixation was
waiting for it, or a newer image served it). An image the detector cannot take (too small, or
not the size ``camera_info`` says) is rejected with the reason and the fixation keeps waiting.

:func:`build_setup` reads the observation file: its grid, fovea and detector settings are the
ones the counts mean anything with, so settings given next to it may only repeat them.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
import time

from ipomdp_gaze.grid import Grid
from ipomdp_gaze.head import PanTiltMap
from ipomdp_gaze.head_camera import PinholeCamera
from ipomdp_gaze.observation_file import load_observation
import numpy as np

MODES = ('fovea', 'camera')
# The observation model of each mode when none is given: the shipped face models.
DEFAULT_MODELS = {'fovea': 'faces-420-nmpt', 'camera': 'faces-pan-tilt'}
# The view a model was calibrated with (its image record), per mode.
MODE_VIEWS = {'fovea': 'fixed', 'camera': 'pan_tilt'}
# The Haar detector's settings with node parameters of their own (an empty or negative value:
# the file's); any detector's other settings go in detector.options.
DETECTOR_KEYS = ('cascade', 'scale_factor', 'min_neighbors')
TIMING_WINDOW = 100


def model_view(model) -> str:
    """``'pan_tilt'`` for a model calibrated through a head camera, else ``'fixed'``."""
    image = getattr(model, 'meta', {}).get('image') or {}
    return str(image.get('view', 'fixed'))


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
    notes: tuple = ()
    """What differs from the file in information-only detector settings (the OpenCV version)."""

    @property
    def grid(self) -> Grid:
        """Return the model's grid."""
        return self.model.grid


def build_setup(mode: str, source: str = '', grid=(0, 0, 0.0), detector: dict | None = None,
                cascade_dir=None) -> DetectorSetup:
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
        Folder (or file) searched first for the cascade the file names.

    Raises
    ------
    ValueError
        Naming the problem: the model's view does not fit the mode, or a setting contradicts
        the file (the file wins: it says what the counts were measured with).

    """
    from ipomdp_gaze.vision.pan_tilt import ViewObserver
    from ipomdp_gaze.vision.cell_observation import cell_observation_of
    from ipomdp_gaze.vision.detectors import detector_from_settings
    from ipomdp_gaze.vision.search import fovea_for_model
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
    for key, asked in (detector or {}).items():
        if key not in recorded:
            raise ValueError(f'detector.{key}: the detector {recorded.get("kind")!r} of '
                             f'observation.file {name!r} has no setting {key!r} (it has '
                             f'{", ".join(sorted(recorded))})')
        if asked != recorded.get(key):
            raise ValueError(f'detector.{key} {asked!r} contradicts observation.file {name!r}, '
                             f'measured with {recorded.get(key)!r} (leave it unset to take it)')
    notes = []
    built = detector_from_settings(recorded, cascade_dir or None, notes.append)
    if mode == 'fovea':
        return DetectorSetup(mode, model, name, built,
                             fovea=fovea_for_model(model, built, reuse_windows=False),
                             notes=tuple(notes))
    observer = ViewObserver(built, g, model.max_count + 1,
                            cell_observation_of(model.meta, model.max_count + 1))
    return DetectorSetup(mode, model, name, built, observer=observer, camera=model_camera(model),
                         notes=tuple(notes))


def camera_mismatch(model_camera_: PinholeCamera | None, camera: PinholeCamera) -> str:
    """Say how ``camera`` differs from the camera a model was calibrated with ('' if not)."""
    if model_camera_ is None or model_camera_.matches(camera):
        return ''
    hfov, vfov = camera.fov_deg
    mh, mv = model_camera_.fov_deg
    return (f'camera_info describes a {camera.width}x{camera.height} camera with a '
            f'{hfov:.1f}x{vfov:.1f} deg field of view, but the model was calibrated with '
            f'{model_camera_.width}x{model_camera_.height} and {mh:.1f}x{mv:.1f} deg: its '
            f'counts may not follow the model')


@dataclass(frozen=True)
class Frame:
    """One count frame for the controller, and what it cost."""

    fixation: int
    stamp_s: float
    token: object
    counts: np.ndarray
    detector_pixels: int
    seconds: float


@dataclass(frozen=True)
class Outcome:
    """What happened when the loop tried to serve the waiting fixation."""

    status: str          # 'published', 'rejected', 'waiting' or 'idle'
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
        Images and joint states kept while a fixation waits (the newest).

    """

    def __init__(self, setup: DetectorSetup, head: PanTiltMap | None = None,
                 tolerance_s: float = 0.0, keep: int = 4):
        if setup.mode == 'camera' and head is None:
            raise ValueError('camera mode needs the head mapping (joint names, signs, offsets)')
        self.setup = setup
        self.head = head
        self.tolerance_s = float(tolerance_s)
        self.camera: PinholeCamera | None = None
        self.pending: tuple[int, float] | None = None
        self._images = deque(maxlen=keep)
        self._poses = deque(maxlen=50 * keep)
        self.received = self.processed = self.rejected = self.fixations = 0
        self.last_rejection = ''
        self.waiting = ''
        self._seconds = deque(maxlen=TIMING_WINDOW)
        self._pixels = deque(maxlen=TIMING_WINDOW)

    # -- inputs ------------------------------------------------------------------------------
    def fixate(self, cell: int, now_s: float) -> Outcome:
        """Take a fixation commanded at ``now_s``: wait for an image captured from then on."""
        self.setup.grid.cell(cell)
        self.fixations += 1
        self.pending = (int(cell), float(now_s))
        return self.serve()

    def add_image(self, stamp_s: float, image: np.ndarray, token=None) -> Outcome:
        """
        Take a decoded image captured at ``stamp_s``; serve the waiting fixation if due.

        ``token`` comes back in the :class:`Frame` the image serves (the node's exact stamp).
        """
        self.received += 1
        self._images.append((float(stamp_s), image, token))
        return self.serve()

    def reject(self, reason: str) -> Outcome:
        """Count an image message that could not even be decoded."""
        self.received += 1
        return self._rejected(reason)

    def add_pose(self, stamp_s: float, pan_rad: float, tilt_rad: float) -> Outcome:
        """Take the head's joint angles at ``stamp_s`` (``camera`` mode)."""
        self._poses.append((float(stamp_s), float(pan_rad), float(tilt_rad)))
        return self.serve()

    def set_camera(self, camera: PinholeCamera) -> str:
        """Use these intrinsics from now on; return a warning if the model expects others."""
        self.camera = camera
        return camera_mismatch(self.setup.camera, camera)

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
        best = None
        for stamp, pan, tilt in self._poses:
            gap = abs(stamp - stamp_s)
            if gap <= self.tolerance_s + 1e-9 and (best is None or gap < best[0]):
                best = (gap, pan, tilt)
        return None if best is None else best[1:]

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
        stamp, image, token = fresh[-1]
        if self.setup.mode == 'fovea':
            return self._count(cell, stamp, image, token)
        if self.camera is None:
            return Outcome('waiting', 'no camera_info received: camera mode needs the '
                                      'intrinsics K to map pixels to cells')
        pose = self._pose_at(stamp)
        if pose is None:
            return Outcome('waiting', 'no joint state with the stamp of the newest image')
        head_rc = self.head.position(*pose)
        at = self.head.nearest_cell(*pose)
        if at != cell:
            self._drop_through(stamp)
            return Outcome('waiting', f'the head is at {self.setup.grid.cell(at)}, not yet at '
                                      f'the fixation {self.setup.grid.cell(cell)}')
        return self._count(cell, stamp, image, token, head_rc)

    def _drop_through(self, stamp_s: float) -> None:
        while self._images and self._images[0][0] <= stamp_s:
            self._images.popleft()

    def _count(self, cell: int, stamp_s: float, image, token, head_rc=None) -> Outcome:
        setup = self.setup
        t0 = time.perf_counter()
        try:
            if setup.mode == 'fovea':
                setup.fovea.start(image)
                observation = setup.fovea.observe(cell)
                counts, pixels = observation.counts, observation.detector_pixels
            else:
                observation = setup.observer.observe(image, self.camera, head_rc)
                counts, pixels = observation.counts, observation.detector_pixels
        except ValueError as exc:
            self._drop_through(stamp_s)
            return self._rejected(str(exc))
        seconds = time.perf_counter() - t0
        self._drop_through(stamp_s)
        self.pending = None
        self.processed += 1
        self._seconds.append(seconds)
        self._pixels.append(pixels)
        return Outcome('published',
                       frame=Frame(cell, stamp_s, token, counts, int(pixels), seconds))

    # -- reporting -------------------------------------------------------------------------
    def values(self) -> dict:
        """Counters and costs for ``/diagnostics`` (times in ms, over the last frames)."""
        seconds = np.asarray(self._seconds, dtype=float)
        pixels = np.asarray(self._pixels, dtype=float)
        waiting = self.pending is not None
        return {
            'mode': self.setup.mode, 'observation': self.setup.name,
            'images_received': self.received, 'images_processed': self.processed,
            'images_rejected': self.rejected,
            'images_unused': self.received - self.processed - self.rejected,
            'fixations_received': self.fixations, 'waiting_for_image': waiting,
            'waiting_because': self.waiting if waiting else '',
            'camera_info': self.camera is not None,
            'detector_ms_last': 1e3 * seconds[-1] if seconds.size else 0.0,
            'detector_ms_median': 1e3 * float(np.median(seconds)) if seconds.size else 0.0,
            'pixels_per_fixation_last': int(pixels[-1]) if pixels.size else 0,
            'pixels_per_fixation_mean': float(pixels.mean()) if pixels.size else 0.0,
            'last_rejection': self.last_rejection,
        }
