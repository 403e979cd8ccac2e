# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Decode image files without OpenCV's and libpng's own messages (our one line says it)."""
from __future__ import annotations

from contextlib import contextmanager
import os
import sys

import cv2
import numpy as np

READ_FLAGS = cv2.IMREAD_ANYDEPTH | cv2.IMREAD_ANYCOLOR


@contextmanager
def _quiet_fd(fd: int = 2):
    """Send what C code writes to file descriptor ``fd`` (stderr) to /dev/null meanwhile."""
    try:
        saved = os.dup(fd)
    except OSError:                      # no such descriptor: nothing to silence
        yield
        return
    try:
        sys.stderr.flush()
        with open(os.devnull, 'wb') as null:
            os.dup2(null.fileno(), fd)
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)


def decode_quietly(data: np.ndarray, flags: int = READ_FLAGS):
    """
    ``cv2.imdecode`` with OpenCV's and libpng's own messages silenced (None if it fails).

    A corrupt file makes libpng and OpenCV print their own lines (``libpng error: PNG input
    buffer is incomplete``, ``[ERROR:0@...] global grfmt_png.cpp ...``) on stderr before our
    one-line message says the same; libpng writes to the file descriptor itself, so that is
    redirected for the call (OpenCV's own log level too, where its Python binding has
    ``cv2.utils.logging``: not in the 4.11-4.12 wheels, nor Ubuntu's 4.6, whose messages the
    redirection silences alone).
    """
    logging = getattr(getattr(cv2, 'utils', None), 'logging', None)
    level = logging.getLogLevel() if logging is not None else None
    if logging is not None:
        logging.setLogLevel(logging.LOG_LEVEL_SILENT)
    try:
        with _quiet_fd(2):
            return cv2.imdecode(data, flags)
    finally:
        if logging is not None:
            logging.setLogLevel(level)
