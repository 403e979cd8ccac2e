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


OUT_OF_MEMORY = 'out of memory decoding it'


def decode_error(exc: cv2.error) -> str:
    """Say in one line why ``cv2.imdecode`` raised: the pixel limit, memory, or its message."""
    text = str(exc)
    if 'CV_IO_MAX_IMAGE_PIXELS' in text:
        return ('more pixels than OpenCV decodes (OPENCV_IO_MAX_IMAGE_PIXELS: 2^30 unless '
                'that environment variable is set)')
    if 'Insufficient memory' in text:
        return OUT_OF_MEMORY
    return f'OpenCV cannot decode it: {exc.err or text.strip().splitlines()[-1]}'


JPEG_START = b'\xff\xd8\xff'
JPEG_END = b'\xff\xd9'


def undecodable(data: np.ndarray) -> str:
    """
    Say in one line why bytes that :func:`decode_quietly` returned None for are no image.

    A JPEG is named as one: ``cv2.imdecode`` refuses a truncated JPEG whole, though
    ``cv2.imread`` and viewers show its top part above grey (a search of it would give wrong
    answers), so "not an image" misled. A file cut short ends before the end-of-image marker
    (trailing zero padding aside).
    """
    head = bytes(data[:len(JPEG_START)])
    if head != JPEG_START:
        return 'not an image OpenCV can decode'
    if not bytes(data[-4096:]).rstrip(b'\x00').endswith(JPEG_END):
        return ('truncated or corrupt JPEG: it ends before its end-of-image marker (a copy or '
                'download cut short?); OpenCV decodes only its top part, so it is not searched')
    return 'truncated or corrupt JPEG: OpenCV cannot decode it'


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

    A GIF that OpenCV before 4.12 cannot decode is decoded by Pillow (:func:`_decode_gif`).

    An image OpenCV refuses to decode (over ``OPENCV_IO_MAX_IMAGE_PIXELS``, 2^30 by default) or
    has no memory for raises ValueError saying so in one line (the caller names the file): it
    raised ``cv2.error``, a traceback that ended the other files' work too.

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
            image = cv2.imdecode(data, flags)
        return _decode_gif(data) if image is None else image
    except cv2.error as exc:
        raise ValueError(decode_error(exc)) from None
    except MemoryError:
        raise ValueError(OUT_OF_MEMORY) from None
    finally:
        if logging is not None:
            logging.setLogLevel(level)


def _decode_gif(data: np.ndarray):
    """
    Decode a GIF's first frame by Pillow as OpenCV 4.12+ does (BGR, 3 channels); else None.

    OpenCV decodes GIF from 4.12 on, and the opencv-python-headless wheels of 4.12+ need numpy
    2: with ``numpy<2`` (the README's ROS install, which gets 4.11) or Ubuntu's OpenCV a GIF was
    "not an image OpenCV can decode". Pillow comes with matplotlib.
    """
    if bytes(data[:4]) != b'GIF8':
        return None
    try:
        from io import BytesIO
        from PIL import Image
        with Image.open(BytesIO(data.tobytes())) as gif:
            return np.ascontiguousarray(np.asarray(gif.convert('RGB'))[:, :, ::-1])
    except Exception:           # noqa: B902 (a damaged GIF: the caller says it is not an image)
        return None
