# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Pictures of a search, for ``find --plot`` and the demo's ``--plot`` and ``--animate``.

Each picture is an :func:`ipomdp_gaze.vision.annotate.annotate` image (the belief as an overlay,
the numbered fixations, the fovea windows, the detections, the cell found), enlarged to at least
:data:`MIN_SIDE_PX` so that fixation numbers stay readable, with a title and the belief's colour
scale. :func:`save_gif` writes an animation of such images (Pillow, which matplotlib needs).
"""
from __future__ import annotations

from pathlib import Path
import textwrap

import cv2
from ipomdp_gaze.files.writable import write_figure, write_file
import numpy as np

from .annotate import annotate, fovea_cell_map, LOG_RANGE

# draw_faces: one pixel of line per this many pixels of the picture's width
DRAW_WIDTH_PX = 300
# A picture's short side is enlarged to at least MIN_SIDE_PX (whole factors, nearest), its long
# side staying within MAX_ENLARGED_SIDE_PX (a panorama stays a few Mpx)
MIN_SIDE_PX = 640
MAX_ENLARGED_SIDE_PX = 4096


def enlarged(image: np.ndarray, min_side: int = MIN_SIDE_PX,
             max_side: int = MAX_ENLARGED_SIDE_PX) -> tuple[np.ndarray, int]:
    """
    Return the image scaled by a whole factor (nearest) so its short side >= min_side.

    The long side stays within ``max_side`` (a panorama is not blown up to megapixels that
    the figure shrinks again).
    """
    factor = max(1, int(np.ceil(min_side / max(1, min(image.shape[:2])))))
    factor = max(1, min(factor, max_side // max(1, max(image.shape[:2]))))
    if factor == 1:
        return image, 1
    return cv2.resize(image, (image.shape[1] * factor, image.shape[0] * factor),
                      interpolation=cv2.INTER_NEAREST), factor


def annotate_image_search(image: np.ndarray, result, fovea,
                          occupancy: bool = False) -> np.ndarray:
    """
    Draw an offline image search (:class:`ipomdp_gaze.vision.search.ImageSearch`) on its image.

    The image is enlarged first (:func:`enlarged`), then the final belief, the scan path, the
    last fixation's windows and the answer are drawn on it: ``found`` (``found, forced`` when a
    limit forced it), ``most likely`` when the search gave up; on an ``absent`` answer no cell
    is drawn as found, only the probability that nobody is there (``occupancy``: on the
    many-target belief, written ``P(nobody here)``, the product over the cells). A full-frame
    scan (a small image) has no fixations: its picture is the scan's detections (yellow
    crosses) and its belief.
    """
    from ipomdp_gaze.search import answer
    big, factor = enlarged(image)
    grid = fovea.grid
    cell_map = fovea_cell_map(grid, big.shape[1], big.shape[0])
    path = [grid.index(*cell) for cell in result.path]
    windows = [(x * factor, y * factor, w * factor, h * factor, win.whole_image)
               for win in fovea.window_rects(path[-1], image.shape)
               for x, y, w, h in [win.rect_px]] if path else []
    detections = None
    if getattr(result, 'detections', ()):
        detections = np.asarray(result.detections, dtype=np.float64) * factor
    reason = 'full_frame' if result.method in ('full_frame', 'scales') else result.stop
    label = ''
    faces = getattr(result, 'faces', ())
    if result.decision == 'absent':
        found = None
        p = result.answer_probability
        said = (f'P(nobody here) {p:.3f}, the product over the cells' if occupancy and
                not np.isnan(p) else answer.probability_text('absent', p))
        label = f'{answer.heading("absent", reason, getattr(result, "limit_cause", ""))}: ' \
            f'{said}'
    else:
        found = (grid.index(*result.cell), result.probability)
        if result.decision == 'gave_up':
            found_label = 'most likely'
        else:
            found_label = 'found, forced' if answer.forced('found', reason) else 'found'
    if faces:                   # many targets: every face's box instead of one answer
        found = None
    picture = annotate(big, cell_map, result.belief, path, windows, detections=detections,
                       found=found, label=label,
                       **({} if found is None else {'found_label': found_label}))
    return draw_faces(picture, faces, factor)


def draw_faces(picture: np.ndarray, faces, factor: int = 1) -> np.ndarray:
    """
    Draw each face's box (image pixels times ``factor``) and its number on an RGB picture.

    Lines and numbers grow with the picture (one line pixel per ``DRAW_WIDTH_PX`` of its
    width): a saved figure shows about 570 px of it, so a 2 px line on a 2048 px picture could
    fall between the pixels shown.
    """
    out = np.ascontiguousarray(picture)
    grow = max(1, factor, int(np.ceil(out.shape[1] / DRAW_WIDTH_PX)))
    thickness = max(2, grow)
    for i, face in enumerate(faces):
        x, y, w, h = (int(round(v * factor)) for v in face.box)
        cv2.rectangle(out, (x, y), (x + w, y + h), (0, 255, 0), thickness)
        cv2.putText(out, str(i), (x + 2 * grow, max(12 * grow, y - 4 * grow)),
                    cv2.FONT_HERSHEY_SIMPLEX, 0.5 * grow, (0, 255, 0), max(1, grow // 2 + 1))
    return out


def save_figure(picture: np.ndarray, out_path: Path, title: str) -> None:
    """Save an annotated picture with a title and the belief's scale (format: the suffix's)."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    import matplotlib.pyplot as plt
    height, width = picture.shape[:2]
    fig_w = 7.0
    fig, ax = plt.subplots(figsize=(fig_w, fig_w * height / width * 0.9 + 0.6))
    ax.imshow(picture, interpolation='nearest')
    ax.set_axis_off()
    ax.set_title(textwrap.fill(title, 80), fontsize=9)   # 80: a line fits the axes
    bar = fig.colorbar(ScalarMappable(Normalize(-LOG_RANGE, 0), 'inferno'), ax=ax,
                       fraction=0.04, pad=0.02)
    bar.set_label('log10 belief / most likely cell (overlay)', fontsize=8)
    fig.tight_layout()
    write_figure(fig, out_path, dpi=100)
    plt.close(fig)


def save_png(picture: np.ndarray, out_path: Path) -> None:
    """Save an RGB picture as it is (no title, no scale)."""
    ok, data = cv2.imencode('.png', np.ascontiguousarray(picture[:, :, ::-1]))
    if not ok:
        raise OSError(f'cannot encode a PNG of {out_path}')
    write_file(out_path, lambda temporary: temporary.write_bytes(data.tobytes()))


def save_gif(frames, out_path: Path, seconds_per_frame: float = 0.6,
             last_seconds: float = 2.0) -> int:
    """
    Write RGB pictures of one size as an animated GIF (looping); return the frame count.

    The last frame stays ``last_seconds`` so the answer can be read.

    Raises
    ------
    ValueError
        With no frame.

    """
    from PIL import Image
    frames = [np.asarray(f, dtype=np.uint8) for f in frames]
    if not frames:
        raise ValueError('no frame to animate: the search published no picture')
    images = [Image.fromarray(f) for f in frames]
    durations = [int(seconds_per_frame * 1000)] * (len(images) - 1) + [int(last_seconds * 1000)]
    write_file(out_path, lambda temporary: images[0].save(
        temporary, format='GIF', save_all=True, append_images=images[1:], duration=durations,
        loop=0, optimize=True))
    return len(images)
