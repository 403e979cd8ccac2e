# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze find``: find the face in image files with the digital fovea and a count model.

The observation model and the policy must load first (else one line, exit status 2). A folder
stands for its image files (by suffix, sorted by name). Each image must exist, decode, have 8
bits per channel and be large enough for the detector and the grid: a bad one is reported in one
line and the others are still searched; the exit status is then 2 at the end, else 0 (every
image got a decision). One line is printed per image, in input order: the path as given, the
**decision** (``found``, ``absent`` or ``gave_up``), how it **ended** (``confidence``: the
evidence reached ``--confidence``; ``forced:pixels`` / ``forced:budget``: the pixel cap or the
fixation budget forced the likelier answer below it, or on the many-target belief ended the
search with cells still undecided; :mod:`.search.answer`), ``cell (row,
col)`` and ``pixel (x, y)`` (``none`` unless found), ``p``, the probability of *that* answer
(the found cell's, or for ``absent`` that nobody is there), the fixations, the detector pixels
against one full-resolution scan's, the seconds, why it stopped and the method. On the
many-target belief (``--all``, ``--scan many``) each cell is decided on its own: ``absent`` means
every cell decided empty at ``--confidence`` (forced: every cell likelier empty than not), and
its probability is written ``p_nobody``, P(nobody here), the product over the cells, which can
be below the confidence or, when forced, below 0.5. There a forced end is the search's as a
whole: the limit put the cells still undecided on their likelier side, and a face whose
probability reached the confidence was decided by the evidence all the same.

**Outputs.** ``--json`` and ``--log`` take ``-`` for stdout (one of them; the lines then go to
stderr); ``--json`` has an entry ``{path, error}`` for each input that could not be searched.
Every output path (``--json``, ``--log``, each ``--plot`` file) is checked before any search: a
folder, an input image, a path through a file, a symbolic link loop or one written twice is
refused in one line naming its option (exit status 2), as are a bad ``--policy`` or
``--policy-file`` (built once on each model first); one that fails while written (a disk
that fills) is one line naming it, the other images and outputs still done (exit status 2).
``--scan`` does not apply to ``--all`` or ``--targets many``: stderr says so once.

**Scale first** (``--scan``, without ``--all``). By default (``coarse``) the detector runs on
the whole image at a coarse scale (1/2; Haar's ``faces-420``: 1/4) and then at each finer scale
of its calibrated table (:mod:`ipomdp_gaze.vision.scales`: 1/4, 1/3, 1/2, 1) until one call has
a strong box (YuNet: score 0.7; Haar: a merged box), looked at again round the box at the next
finer scale (a texture taken for a face at a coarse scale rarely survives); at full resolution
any box the detector keeps answers. ``found`` at that box's centre, else ``absent``; no belief
(``p`` n/a), method ``scales`` (:func:`ipomdp_gaze.vision.search.search_scales`). A face-free
image pays every scale, about 1.4 full scans of detector pixels (1/16 + 1/9 + 1/4 + 1 and any
confirming crop). ``--min-face PX`` ends the ladder at the coarsest scale that sees faces of
that side (one call whose strong box nothing confirms, when the first scale already sees them)
or on the frame enlarged until the detector does, at most 4x (stderr says so, and when they
would need more, that they may still be missed: :func:`min_face_notes`). ``--scan many``
answers the most probable face of the many-target search of ``--all`` (below); ``--scan
fovea`` is the paper's single-target search with the fovea (what ``find`` did before
``--scan``).

**Pixels.** The fovea (:func:`ipomdp_gaze.vision.search.search_image`) never spends more
detector pixels than one full-resolution scan of the image: it stops before a fixation that
would, and decides then (``decide_at_budget``; stop ``pixels``). When the fovea would cost more
or cannot see (a small image, an image at most half the model's calibrated size, a close-up
portrait: :func:`ipomdp_gaze.vision.search.full_frame_reason`) the whole frame is scanned once
instead and stderr says why. ``--all`` finds every face in one search over the many-target
belief (``--targets many``, its default: :func:`ipomdp_gaze.vision.search.search_many`;
docs/design.md section 11): one line per face with its box, then the image's line. It
starts with one detector call on the whole image at the coarsest scale its calibration says
sees faces of 1/10 of the shorter side (``--min-face PX``: of that side in the given image's
pixels; full resolution when no coarser scale sees it), and looks closer (a crop at a finer
scale, then the fovea's windows) only where that call leaves cells undecided
(:mod:`ipomdp_gaze.vision.scales`); a face found far smaller than assumed (a crowd), or none at
all, sends the whole image to a finer call (:data:`ipomdp_gaze.vision.search.CROWD_RATIO`),
within one full-resolution scan of the image as given. Faces far smaller than 1/10 on a large
image also need
``--max-side 0``: the default resize to 2048 px would shrink them below what the detector sees.
``--targets one`` keeps the old loop (:func:`ipomdp_gaze.vision.search.search_all`: find one
face, rule its cells out, search again).

**Images** are read with OpenCV (``IMREAD_ANYDEPTH | IMREAD_ANYCOLOR``: EXIF orientation applied,
an alpha channel dropped; OpenCV's and libpng's own messages silenced, our one line says it). A
16-bit image is converted to 8 bits (divided by 257, or from the 8-14 bits its values fit) with
a note; one larger than ``--max-side`` (2048) allows is resized before the search (a JPEG
decoded at 1/2, 1/4 or 1/8 first, so an 8000x6000 photo peaks at about 180 MB) and its answer
given in its own pixels: up to 2:1 its longer side to ``--max-side``, a panorama beyond 2:1 to
at most the pixels of a ``--max-side`` x 3/4 ``--max-side`` picture (:func:`resized_size`), so
that an 8000x300 panorama's faces are not shrunk to 11 px high. Colour arrays
arrive in OpenCV's BGR order and are converted to RGB; the fovea gives each window to the
detector in the colour space it declares (RGB for YuNet, grey for Haar; a grey image is repeated
into three channels for an RGB detector). ``seconds`` starts from the decoded
array, so reading and decoding are not in it; nor is the one-time set-up of the detector, the
fovea and the policy (the policy is run once on the uniform belief before the first image, so
e.g. ELM's N x N weight matrix is built then), nor with ``--all`` that of the many-target
belief (its information table, the fixation costs of an image size, the coarse pass's detector:
:func:`ipomdp_gaze.vision.search.prepare_many`).

**Model.** ``--observation`` names an ``ipomdp_gaze/observation-v1`` file (or a shipped model);
the fovea, the grid and the detector are rebuilt from what the file records (each window is
detected at most once per image: the detector is deterministic, so this saves work and changes
no count). Without it, each image uses the shipped model of ``--detector`` (YuNet's
``faces-<size>-yunet`` by default, chosen on training photos; ``haar``: ``faces-<size>``;
:func:`default_models`) calibrated at the size nearest its own (``|log(w/w0)| +
|log(h/h0)|``, ties to the first name); stderr says which model and policy are used. An image of
another size than its model's is searched, and its line says so.

**Policy.** ``--policy NAME`` (a baseline or ``nmpt``, built on the model) or ``--policy-file``;
by default the shipped kernel trained on the model (a file in ``ipomdp_gaze/policies/kernels/``
whose ``observation.name`` is the model's name), else ELM on the model, acting by argmax.
``--seed S`` seeds a sampling policy: image i (0-based) draws from ``default_rng([S, i])``.
"""
from __future__ import annotations

from dataclasses import replace
import errno
import math
import os
from pathlib import Path
import stat
import sys

import cv2
from ipomdp_gaze.files import json_files
from ipomdp_gaze.files.observation_file import load_observation, shipped_image_models
from ipomdp_gaze.files.writable import write_text
from ipomdp_gaze.model.belief import uniform_log_belief
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.policies.policy_file import default_policy_file
from ipomdp_gaze.policies.registry import build_policy, POLICY_NAMES
from ipomdp_gaze.search import answer
from ipomdp_gaze.search.many import check_many_settings
from ipomdp_gaze.vision.detectors import load_factory
from ipomdp_gaze.vision.fullframe import MAX_ENLARGED_PX
from ipomdp_gaze.vision.image_files import decode_quietly, undecodable
from ipomdp_gaze.vision.scales import (finest_scale, ladder_scales, max_enlargement,
                                       min_face_px, SCALE_TABLES)
from ipomdp_gaze.vision.search import (calibrated_size, check_image_size, clip_box,
                                       CROWD_RATIO, EMPTY_BY_EVIDENCE,
                                       FIND_SETTINGS, fovea_for_model, full_frame_reason,
                                       full_frame_search, prepare_many, search_all,
                                       search_first, search_image, search_many, search_scales,
                                       size_distance)
import numpy as np

from .common import check_output_file, nonneg_int, output_file, plot_format, positive_float
from .search_args import add_search_args, settings_from_args, TASK_DEFAULT

# greedy (the ideal searcher) needs a Gaussian FPOC; find's models count detections
POLICY_CHOICES = tuple(name for name in POLICY_NAMES if name not in ('learned', 'greedy'))
# The detectors with shipped find models; the first is the default, chosen on the training
# photos and training group pictures (docs/faces.md, "find on real photographs").
FIND_DETECTORS = ('yunet', 'haar')
READ_FLAGS = cv2.IMREAD_ANYDEPTH | cv2.IMREAD_ANYCOLOR
# --json - writes the JSON to stdout (the lines then go to stderr).
STDOUT = Path('-')
# Images longer than this on a side are resized before the search (--max-side; the detector
# node refuses images over its max_image_side_px instead). Measured on an 8000x6000 JPEG with
# no face (/usr/bin/time -v): 2048 (decoded at 1/2, then resized): 177 MB peak resident, 3.1 s;
# 4096: 386 MB, 5.5 s; no resizing: 658 MB, 12.5 s. The shipped models are calibrated at 420
# and 840 px, so a 2048 px image still holds every window at the resolution they were measured
# at.
MAX_SIDE_PX = 2048
# A picture at most this many times as long as it is high (or high as wide) is resized to
# --max-side on its longer side, as before 0.3.4: every published picture (640x480 to 4000x3000
# and 8000x6000, 1536x2048 portraits) and a 360 camera's 2:1 equirectangular frame. A wider one
# (a stitched pan sweep, 4:1 to 10:1) keeps at most the pixels of a --max-side x 3/4 --max-side
# picture (3.1 Mpx at 2048, the 4:3 size whose memory is measured above) instead: its longer
# side resized to --max-side made an 8000x300 panorama 2048x77 px, below the faces' size.
PANORAMA_RATIO = 2.0
PANORAMA_AREA_FRACTION = 0.75
# find without --all: how the search starts (--scan). 'coarse' (the default): full-frame
# detector calls from a coarse scale to finer ones until a strong box, confirmed by a look at
# the next finer scale round it (search_scales); 'many': the many-target search of --all (its
# coarse pass, the fovea only where cells stay undecided), answering its most probable face
# (search_first); 'fovea': the paper's single-target belief after the fovea's own scan
# (search_image, find before --scan). Chosen on training scenes and photos (docs/faces.md,
# "find without --all: scale first"): on 60 training scenes of each task 'coarse' was as right
# as each detector's best single-scale call in fewer seconds, 'many' lost at 840 and cost
# Haar's full-resolution call at 420, 'fovea' lost with YuNet.
SCAN_CHOICES = ('coarse', 'many', 'fovea')
SCAN_DEFAULT = 'coarse'
# The routes of search_route whose belief is the many-target occupancy: there an absent answer
# means every cell on its empty side, and its p is P(nobody here), the product over the cells.
OCCUPANCY_ROUTES = ('many', 'first')
# --scan coarse: the scale of the first full-frame call, per detector and model size (the
# shipped models' calibrated shorter side), chosen on 60 training scenes of each task (seed 1):
# Haar from 1/4 at 420 (right 0.983 as from 1/3 and 1/2, in the fewest seconds) and from 1/2 at
# 840 (0.950; from 1/4 and 1/3 a face-like texture of the backgrounds is answered at 0.917);
# YuNet from 1/2 (0.967 at 420 and 0.850 at 840 from every start, from 1/2 in the fewest).
LADDER_START = {('haar', 420): 0.25, ('haar', 840): 0.5, ('yunet', 420): 0.5,
                ('yunet', 840): 0.5}


def add_parser(sub):
    p = sub.add_parser(
        'find', help='find faces in images: the detector scale first, or the digital fovea',
        description='Find a face in each image (--all: every face). By default (--scan '
                    'coarse) the detector runs on the whole image from a coarse scale to finer '
                    'ones until a strong box, looked at again round the box at the next finer '
                    "scale, answers (found), else absent; --scan fovea is the paper's search: "
                    "scan the whole image once, fixate the policy's choice on the belief, "
                    'update it with the count model, stop when a cell (or "no face") reaches '
                    '--confidence, at --max-fixations, once every cell was fixated (gave_up) '
                    'or before spending more detector pixels than one full-resolution scan. '
                    'Small images are scanned whole instead. Print one line per image (path, '
                    'decision, cell (row, col) and pixel (x, y) found, probability, fixations, '
                    'detector pixels, seconds). Images are read with OpenCV (BGR converted to '
                    'RGB; grey for a grey detector such as Haar); 8 bits per channel.')
    p.add_argument('images', nargs='+', metavar='IMAGE',
                   help='image files (PNG, JPEG, ...) or folders (their image files, by name)')
    p.add_argument('--observation', default=None, metavar='FILE',
                   help='count model (ipomdp_gaze/observation-v1 file or shipped name); '
                        "default: the shipped model calibrated nearest each image's size "
                        'for --detector')
    p.add_argument('--detector', default=None, metavar='KIND',
                   help='the detector: yunet or haar use their shipped models (one per '
                        f'calibrated size; default {FIND_DETECTORS[0]}, chosen on training '
                        'photos: docs/faces.md); any other registered name or '
                        'package.module:Factory needs its model from ipomdp-gaze calibrate '
                        '--detector KIND, given with --observation (which must record KIND)')
    policy = p.add_mutually_exclusive_group()
    policy.add_argument('--policy', default=None, choices=POLICY_CHOICES,
                        help='a baseline or nmpt, built on the model (default: the shipped '
                             'kernel trained on the model, else elm)')
    policy.add_argument('--policy-file', default=None, metavar='FILE',
                        help='a policy YAML file or a shipped kernel name')
    add_search_args(p, FIND_SETTINGS, ('confidence', 'max_fixations', 'absent_prior',
                                       'repeat_weight', 'start_cell'))
    p.add_argument('--all', action='store_true',
                   help='find every face in one search over the many-target belief (an '
                        'occupancy per cell, infomax per detector pixel, within one '
                        'full-resolution scan of the image as given (before --max-side), and '
                        'at most one more for the looks that confirm weak boxes); each face is '
                        'printed with its box and '
                        'probability, counted once per cluster of occupied cells (split where '
                        "the detector's boxes are distinct faces; boxes cut to the image); "
                        '"absent" when every cell is decided empty at --confidence (or, forced '
                        'by a limit, is likelier empty than not), and its line gives '
                        'p_nobody=P(nobody here), the product over the cells of P(empty), which '
                        'may be below --confidence or 0.5 (the --plot title says so); '
                        'ended=forced:pixels (forced:budget) says the limit ended the search '
                        'while cells were still undecided and put them on their likelier '
                        'side: a face whose p reached --confidence was decided by the '
                        'evidence all the same, one below it was forced')
    add_search_args(p, None, ('targets',), task_default='many with --all, else one; --all '
                    '--targets one: find a face, rule the cells within 2 of it out, search '
                    'again: a line per search (face=K for a face, at a point without a box; '
                    'search=K for the last, which found none)')
    p.add_argument('--plot', type=output_file, default=None, metavar='OUT.png',
                   help='draw the image, the numbered fixations and the windows of the last '
                        'one, in the format the extension names (.png, .pdf, .svg, .jpg, ...; '
                        'others refused); with several images, OUT-<i>.ext for image i '
                        '(0-based)')
    p.add_argument('--json', type=output_file, default=None, metavar='OUT.json',
                   help='write {grid, axes, images: [{path, cell [row, col], pixel [x, y] '
                        '(null unless found), probability (of the answer: the cell found, or '
                        'that nobody is there for absent: with --all or --scan many '
                        'P(nobody here), the product over cells), fixations, detector_pixels, '
                        'full_scan_pixels, seconds, decision, ended (confidence, '
                        'forced:pixels, forced:budget, repeat, ...), confidence, '
                        'map_probability, absent_probability, stop, method, note, '
                        'resized_from, grid, and with --targets many faces: [{box [x, y, w, h], '
                        'cell [row, col], probability}]}]} in input order (--all --targets one: '
                        'one entry per face, with "face": K, then the last search, with '
                        '"search": K, as the lines; an input that could not be searched: '
                        '{path, error}); "-" writes it to stdout '
                        '(the lines then go to stderr)')
    p.add_argument('--max-side', type=nonneg_int, default=MAX_SIDE_PX, metavar='PX',
                   help='resize an image longer than this on a side before the search '
                        f'(default {MAX_SIDE_PX}; 0: never), a JPEG while it is decoded, as '
                        'the detector node bounds its images (max_image_side_px); its pixels '
                        'are then given in the original image. A panorama beyond 2:1 keeps '
                        'at most the pixels of a PX x 3/4 PX picture instead, at its own '
                        'aspect ratio (an 8000x300 one is searched as given)')
    p.add_argument('--min-face', type=positive_float, default=None, metavar='PX',
                   help="the smallest face side that matters, in the given image's pixels; "
                        'with --all or --scan many (default 1/10 of its shorter side) the '
                        'coarse pass runs at the coarsest scale whose calibration sees it, '
                        'full resolution when none does; with --scan coarse (default: full '
                        'resolution) the ladder ends at that scale, or on the image enlarged '
                        'until the detector sees such faces (at most 4x: smaller ones may '
                        "still be missed); a side the ladder's first scale or a coarser one "
                        'already sees (yunet: from 72 px in the searched image) leaves one '
                        'call, whose strong box answers with no finer look to confirm it (at '
                        "1/4 yunet's table counts 16x the false detections per Mpx of full "
                        'resolution); unused by '
                        '--scan fovea, --all --targets one and images scanned whole (faces '
                        'far below 1/10 on a large image: pass --max-side 0 too, or the '
                        'resize makes them smaller still)')
    p.add_argument('--scan', dest='scan_mode', choices=SCAN_CHOICES, default=None,
                   help='without --all: coarse (default) runs the detector on the whole image '
                        'from a coarse scale to finer ones until a strong box (looked at again '
                        'at the next finer scale) and answers it, about 1.4 full scans of '
                        'detector pixels on a face-free image; many: the most probable face of '
                        "--all's many-target search; fovea: the paper's single-target search "
                        'with the fovea within one full scan (find before --scan); --all and '
                        '--targets many do not use it (stderr says so when it is given)')
    p.add_argument('--log', type=output_file, default=None, metavar='OUT.jsonl',
                   help="write each image's search session event log (reset with the "
                        'settings, scan, start, one event per fixation with the frame and '
                        'belief summaries and the decision) as one JSON line per image (no '
                        'events with the default --scan coarse: it runs no search session); '
                        '"-" writes it to stdout (the lines then go to stderr)')
    p.add_argument('--seed', type=nonneg_int, default=0, metavar='S',
                   help='seed of a sampling policy (image i uses default_rng([S, i]))')
    p.set_defaults(run=run)


def _read_flags(file: Path, max_side: int) -> tuple[int, tuple | None]:
    """
    Return :data:`READ_FLAGS`, or a reduced decode for an image far over ``max_side``.

    OpenCV decodes a colour JPEG through a second full-size buffer (an 8000x6000 photo: 280 MB);
    ``IMREAD_REDUCED_COLOR_<k>`` decodes it at 1/k instead (libjpeg scales while decoding), for
    the largest k of 8, 4, 2 that keeps the longer side at least that of the resized picture
    (:func:`resized_size`: ``max_side`` up to 2:1). Other formats
    are decoded whole (and a 16-bit one converted with its note), then resized. The size comes
    from the file's header (Pillow, which reads no pixels) and is returned with the flags
    (None when the decode is not reduced), as displayed: width and height swapped when its
    EXIF orientation turns it a quarter (5-8), as OpenCV's decode does; a file Pillow cannot
    read is decoded whole. Pillow's
    decompression-bomb check is off for the header: it would warn in two lines over 89 Mpx
    and refuse over 179 Mpx, so that the photos the reduced decode is for were decoded whole.
    """
    if not max_side:
        return READ_FLAGS, None
    try:
        from PIL import Image
        bomb, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
        try:
            with Image.open(file) as header:
                size, kind = tuple(int(v) for v in header.size), header.format
                if header.getexif().get(EXIF_ORIENTATION) in QUARTER_TURNS:
                    size = size[::-1]
        finally:
            Image.MAX_IMAGE_PIXELS = bomb
    except Exception:           # noqa: B902 (any failure: OpenCV decodes it, or says why)
        return READ_FLAGS, None
    if kind != 'JPEG':          # only libjpeg scales while decoding; 16-bit PNGs keep depth
        return READ_FLAGS, None
    for k, flag in ((8, cv2.IMREAD_REDUCED_COLOR_8), (4, cv2.IMREAD_REDUCED_COLOR_4),
                    (2, cv2.IMREAD_REDUCED_COLOR_2)):
        if max(size) // k >= max(resized_size(*size, max_side)):
            return flag, size
    return READ_FLAGS, None


def _layers(file: Path) -> tuple[str, int, bool]:
    """
    Return the file's format, its pages or frames and whether it has an alpha channel.

    From the header by Pillow, which decodes no pixels (a GIF's frames are counted by skipping
    their blocks); ``('', 1, False)`` for a file Pillow cannot read. OpenCV decodes the first
    page of a multi-page TIFF and the first frame of an animated GIF, and drops the alpha channel:
    :func:`read_image` says so when it matters.
    """
    try:
        from PIL import Image
        bomb, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
        try:
            with Image.open(file) as header:
                alpha = 'A' in header.mode or 'transparency' in header.info
                return str(header.format or ''), int(getattr(header, 'n_frames', 1)), alpha
        finally:
            Image.MAX_IMAGE_PIXELS = bomb
    except Exception:           # noqa: B902 (any failure: OpenCV decodes it, or says why)
        return '', 1, False


def _pages_note(path: str, kind: str, pages: int) -> str:
    """Say that only the first page (TIFF) or frame (GIF, ...) of a file of several is searched."""
    what = 'pages' if kind == 'TIFF' else 'frames'
    return (f'{path}: {pages} {what} in the file ({"an animated " * (kind == "GIF")}{kind}); '
            f'only the first is searched')


# The EXIF orientation tag, and its values that turn the picture a quarter (width and height
# swap when it is displayed, and when OpenCV decodes it).
EXIF_ORIENTATION = 0x0112
QUARTER_TURNS = (5, 6, 7, 8)

# The bit depths a 16-bit file may hold (a 10-, 12- or 14-bit camera's raw values, 8-bit data
# stored in 16): a file is read as the smallest its largest value fits, so that a 10-bit frame
# is not divided by 257 into a nearly black picture.
SENSOR_BITS = (8, 10, 12, 14, 16)


def read_image(path: str, notes: list | None = None, max_side: int = 0,
               size: list | None = None) -> np.ndarray:
    """
    Read an image file as ``uint8`` grey ``(H, W)`` or RGB ``(H, W, 3)``.

    A 16-bit image is converted to 8 bits (``round(v / 257)``, 65535 -> 255; values that fit
    fewer bits, :data:`SENSOR_BITS`, scaled from that range instead), and ``notes``, when
    given, gets a line saying so; ``size``, when given, gets the decoded ``(width,
    height)``. With ``max_side``, an image over its size (:func:`resized_size`)
    is resized (:func:`shrink`) before its colours are converted, so that no second full-size
    copy is made (an 8000x6000 photo peaks at about 270 MB resident, most of it the decoded
    array).

    Raises
    ------
    ValueError
        Naming the file: missing, unreadable, not decodable (over OpenCV's pixel limit, out of
        memory), or of another depth (float).

    """
    file = Path(path)
    try:
        mode = os.stat(file).st_mode
    except OSError as exc:      # one stat: a folder on the way may refuse it (EACCES)
        raise ValueError(f'{path}: {_stat_error(exc)}') from None
    if stat.S_ISDIR(mode):      # a folder expand_inputs could not list
        try:
            os.scandir(file).close()
        except OSError as exc:
            raise ValueError(f'{path}: a folder find cannot list: {exc.strerror or exc}') \
                from None
        raise ValueError(f'{path}: not a file')
    if not stat.S_ISREG(mode):
        raise ValueError(f'{path}: not a file')
    try:
        data = np.fromfile(file, dtype=np.uint8)
    except OSError as exc:
        raise ValueError(f'{path}: cannot read: {exc.strerror or exc}') from None
    flags, header = _read_flags(file, max_side) if data.size else (READ_FLAGS, None)
    kind, pages, alpha = _layers(file) if data.size else ('', 1, False)
    if alpha and flags == READ_FLAGS:
        flags = cv2.IMREAD_UNCHANGED    # the same colours, and the alpha channel beside them
    try:
        image = decode_quietly(data, flags) if data.size else None
    except ValueError as exc:   # over OpenCV's pixel limit, or out of memory
        raise ValueError(f'{path}: {exc}') from None
    if image is None:
        raise ValueError(f'{path}: {undecodable(data)}')
    del data
    if pages > 1 and notes is not None:
        notes.append(_pages_note(path, kind, pages))
    if image.ndim == 3 and image.shape[2] in (2, 4):
        # the colours as READ_FLAGS decodes them (alpha dropped, nothing composited)
        hidden = not image[:, :, -1].any()
        image = np.ascontiguousarray(image[:, :, :-1])
        if hidden and notes is not None:
            notes.append(f'{path}: every pixel is fully transparent (alpha 0); searched in the '
                         'colours stored under it, which a viewer does not show')
    if image.dtype == np.uint16:
        high = int(image.max())
        bits = next(b for b in SENSOR_BITS if high < 2 ** b)
        image = cv2.convertScaleAbs(image, alpha=255.0 / (2 ** bits - 1))
        if notes is not None:
            notes.append(f'{path}: 16-bit image converted to 8 bits per channel (divided by '
                         f'257)' if bits == 16 else
                         f'{path}: 16-bit image with values up to {high}, read as {bits}-bit '
                         "(a camera's raw range), converted to 8 bits per channel (divided "
                         f'by {(2 ** bits - 1) / 255:.4g})')
    if image.dtype != np.uint8:
        bits = 8 * image.dtype.itemsize
        raise ValueError(f'{path}: {bits}-bit {image.dtype} image; find needs unsigned 8 or '
                         f'16 bits per channel (uint8 or uint16: convert it, e.g. to 8-bit PNG)')
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if size is not None:
        decoded = (image.shape[1], image.shape[0])
        if header is not None and decoded[0] != decoded[1] and \
                (header[0] > header[1]) != (decoded[0] > decoded[1]):
            header = header[::-1]               # the decode turned it, and the header did not
        size.append(decoded if header is None else header)
    image, _ = shrink(image, max_side)
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
    return image


def _stat_error(exc: OSError) -> str:
    """Say why a path cannot be stat-ed: missing, a link loop, or the system's reason."""
    if exc.errno in (errno.ENOENT, errno.ENOTDIR):
        return 'no such file'
    if exc.errno == errno.ELOOP:
        return 'a symbolic link loop'
    return f'cannot read: {exc.strerror or exc}'


def _loops(path: Path) -> bool:
    """Whether following ``path``'s links never ends (ELOOP: ``exists()`` just says False)."""
    try:
        os.stat(path)
    except OSError as exc:
        return exc.errno == errno.ELOOP
    return False


def resized_size(width: int, height: int, max_side: int) -> tuple[int, int]:
    """
    Return the ``(width, height)`` :func:`shrink` resizes a picture of that size to.

    Up to :data:`PANORAMA_RATIO` (2:1) the longer side is at most ``max_side``; a wider or
    taller picture keeps at most ``max_side`` x 3/4 ``max_side`` pixels
    (:data:`PANORAMA_AREA_FRACTION`) at its own aspect ratio, so that a panorama's faces are
    not shrunk to a few pixels high while its memory stays that of a 4:3 picture at
    ``max_side``. 0: never resized.
    """
    if not max_side:
        return width, height
    if max(width, height) <= PANORAMA_RATIO * min(width, height):
        if max(width, height) <= max_side:
            return width, height
        scale = max_side / max(width, height)
        return max(1, round(width * scale)), max(1, round(height * scale))
    area = max_side * max_side * PANORAMA_AREA_FRACTION
    if width * height <= area:
        return width, height
    scale = math.sqrt(area / (width * height))
    return max(1, math.floor(width * scale)), max(1, math.floor(height * scale))


def shrink(image: np.ndarray, max_side: int) -> tuple[np.ndarray, tuple]:
    """
    Resize ``image`` to :func:`resized_size` (``INTER_AREA``); ``max_side`` 0: never.

    Returns the image and the factors ``(sx, sy)`` from its pixels to the given image's.
    As the detector node does with ``max_image_side_px``, but resizing instead of refusing: a
    search over an 8000x6000 image would otherwise take seconds and gigabytes.
    """
    height, width = image.shape[:2]
    size = resized_size(width, height, max_side)
    if size == (width, height):
        return image, (1.0, 1.0)
    small = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
    return small, (width / size[0], height / size[1])


def model_name(model) -> str:
    """Return the model's name: its file's stem (``meta['source']``)."""
    return str(model.meta.get('source') or 'the observation model')


def nearest_model(models: list, image_px: tuple[int, int]):
    """Return the model calibrated at the size nearest ``image_px`` (ties: the first listed)."""
    sized = [(size_distance(image_px, size), i) for i, model in enumerate(models)
             if (size := calibrated_size(model)) is not None]
    return models[min(sized)[1]] if sized else models[0]


def build_find_policy(args, model, warn):
    """Build the policy for ``model``; return it and a description of it."""
    grid = model.grid
    if args.policy_file:
        return build_policy('learned', grid, model, file=args.policy_file, warn=warn), \
            f'policy file {args.policy_file}'
    if args.policy:
        return build_policy(args.policy, grid, model), f'policy {args.policy}'
    kernel = default_policy_file(model)
    if kernel is not None:
        return build_policy('learned', grid, model, file=kernel, action='argmax', warn=warn), \
            f'shipped kernel {kernel} (argmax)'
    return build_policy('elm', grid, model), 'policy elm (no shipped kernel for this model)'


class _Task:
    """A model with its fovea and policy, shared by the images that use it."""

    def __init__(self, args, model, shipped: bool, warn):
        name = model_name(model)
        try:
            self.fovea = fovea_for_model(model)
        except ValueError as exc:
            # the file given names it (the shipped models by their names)
            raise ValueError(f'{args.observation if not shipped else name}: {exc}') from None
        self.model = model
        self.policy, policy = build_find_policy(args, model, warn)
        self.policy.select(np.exp(uniform_log_belief(model.grid.n_cells, 1)), 1,
                           np.random.default_rng(0))
        size = calibrated_size(model)
        where = 'shipped ' if shipped else ''
        at = f', calibrated at {size[0]}x{size[1]} px' if size else ''
        self.description = (f'{where}observation model {name} ({model.grid.rows}x'
                            f'{model.grid.cols} grid{at}), {policy}')


def plot_image_search(image: np.ndarray, result, fovea, out_path: Path, title: str,
                      occupancy: bool = False) -> None:
    """Draw the image, the final belief, the numbered scan path, the windows, the cell found."""
    from ipomdp_gaze.vision.search_plots import annotate_image_search, save_figure
    save_figure(annotate_image_search(image, result, fovea, occupancy), out_path, title)


def plot_paths(out: Path, count: int) -> list[Path]:
    """``out`` for one image, else ``OUT-<i>.png`` (0-based) for each of ``count`` images."""
    if count == 1:
        return [out]
    return [out.with_name(f'{out.stem}-{i}{out.suffix or ".png"}') for i in range(count)]


# A folder's files that find reads (by suffix; a file named directly is decoded whatever its
# name: OpenCV tells formats by their content, a GIF by its first frame).
IMAGE_SUFFIXES = ('.png', '.jpg', '.jpeg', '.jpe', '.jfif', '.bmp', '.dib', '.tif', '.tiff',
                  '.webp', '.gif', '.pgm', '.ppm', '.pbm', '.pnm', '.jp2')


def expand_inputs(paths: list[str], skipped: list | None = None) -> list[str]:
    """
    Each path as given; a folder becomes its image files (by suffix), sorted by name.

    ``skipped``, when given, gets ``(folder, names)`` for each folder with other files or
    folders (not searched: a folder is not walked down), and ``(folder, [])`` for an empty
    one. A folder that cannot be listed stays
    as given, and :func:`read_image` reports it, as it does an entry that cannot be stat-ed:
    one line each, the other images still searched.

    Raises
    ------
    ValueError
        For an empty path (an unset shell variable), which would name the current folder.

    """
    out = []
    for path in paths:
        if not path.strip():
            raise ValueError(f'an empty image path ({path!r}: an unset shell variable?)')
        try:
            entries = sorted(Path(path).iterdir()) if os.path.isdir(path) else None
        except OSError:         # a folder that cannot be listed: read_image says why, alone
            entries = None
        if entries is None:
            out.append(path)
            continue
        kinds = {f: _kind(f) for f in entries}
        out.extend(str(f) for f in entries
                   if kinds[f] == 'file' and f.suffix.lower() in IMAGE_SUFFIXES)
        others = [f.name + '/' * (kinds[f] == 'folder') for f in entries
                  if not (kinds[f] == 'file' and f.suffix.lower() in IMAGE_SUFFIXES)]
        if (others or not entries) and skipped is not None:
            skipped.append((path, others))
    return out


def _kind(entry: Path) -> str:
    """
    ``'file'``, ``'folder'``, or ``'other'`` for a folder's entry.

    An entry that cannot be stat-ed (a link loop, a folder without search permission) is a file
    of its suffix, so that read_image reports it rather than the folder skip it unsaid.
    """
    try:
        mode = os.stat(entry).st_mode
    except OSError:
        return 'file'
    return 'folder' if stat.S_ISDIR(mode) else 'file' if stat.S_ISREG(mode) else 'other'


def _cell_text(result) -> str:
    if result.decision != 'found':
        return 'cell (row, col)=none pixel (x, y)=none'
    r, c = result.cell
    x, y = result.pixel
    return f'cell (row, col)=({r}, {c}) pixel (x, y)=({x:.1f}, {y:.1f})'


def format_line(path: str, result, face: int | None = None, occupancy: bool = False) -> str:
    """
    Format the one line printed per image (per face with ``--all``).

    ``ended`` says how the search ended (:func:`.search.answer.ended`: ``confidence``, or
    ``forced:pixels`` / ``forced:budget`` when a cost cap or the budget forced the decision
    below the confidence) and ``p`` is the probability of *that* answer: the found cell's, or
    for ``absent`` the probability that nobody is there. On the many-target belief
    (``occupancy``: ``--all``, ``--scan many``) ``absent`` means every cell on its empty side,
    and its probability is written ``p_nobody``: P(nobody here), the product over the cells,
    which can be below the confidence each cell reached (or below 0.5, when forced); a forced
    end there is the search's (cells still undecided put on their likelier side), and a face
    whose ``p`` reached the confidence was decided by the evidence all the same.
    """
    width, height = result.image_px
    p = result.answer_probability
    probability = 'n/a' if math.isnan(p) else f'{p:.3f}'
    which = ('' if face is None else f' face={face}' if result.decision == 'found' else
             f' search={face}')
    name = 'p_nobody' if occupancy and result.decision == 'absent' else 'p'
    line = (f'{path}:{which} decision={result.decision} ended={result.ended} '
            f'{_cell_text(result)} {name}={probability} fixations={result.fixations} '
            f'detector_pixels={result.detector_pixels} (full scan {width * height}) '
            f'seconds={result.seconds:.4f} stop={result.stop} method={result.method}')
    if not result.size_matches:
        w0, h0 = result.calibrated_px
        line += f' (image {width}x{height} px, model calibrated at {w0}x{h0})'
    if result.resized_from is not None:
        line += f' (resized from {result.resized_from[0]}x{result.resized_from[1]} px)'
    return line


def face_line(path: str, result, face: int) -> str:
    """Format the line of one face of a many-target search."""
    found = result.faces[face]
    x, y, w, h = found.box
    probability = 'n/a' if math.isnan(found.probability) else f'{found.probability:.3f}'
    return (f'{path}: face={face} box (x, y, w, h)=({x:.0f}, {y:.0f}, {w:.0f}, {h:.0f}) '
            f'cell (row, col)=({found.cell[0]}, {found.cell[1]}) p={probability}')


def plot_title(path: str, result, confidence: float, occupancy: bool = False,
               faces: int | None = None) -> str:
    """
    Return a plot's title: the decision, how it ended, the answer and its probability.

    ``faces``: the many-target search's count of faces (``--all``), which leads the title;
    ``occupancy``: the belief is the many-target one, where ``absent`` is said by its rule
    (:func:`nobody_text`).
    """
    name, p = Path(path).name, result.answer_probability
    tail = f'{counted(result.fixations, "fixation")} ({result.stop})'
    nobody = occupancy and result.decision == 'absent' and not math.isnan(p)
    if faces is not None:
        found = f'{name}: {counted(faces, "face")}'
        if faces and answer.forced(result.decision, result.stop):
            found += f' ({forced_faces_text(result, confidence)})'
        return f'{found} ({nobody_text(result, confidence)}), {tail}' if nobody else \
            f'{found}, {tail}'
    if nobody:
        return f'{name}: {nobody_text(result, confidence)}, {tail}'
    where = f', cell (row, col) {result.cell}' if result.decision == 'found' else ''
    heading = answer.heading(result.decision, _reason(result), _cause(result))
    return (f'{name}: {heading}{where}, {answer.probability_text(result.decision, p)}'
            f'{answer.confidence_clause(result.decision, _reason(result), p, confidence)}, '
            f'{tail}')


def forced_faces_text(result, confidence: float) -> str:
    """
    Say a many-target search a limit ended with faces: what was forced and what was not.

    The limit ends the search as a whole while some cells are still undecided, and puts those
    on their likelier side; a face whose probability reached the confidence was decided by the
    evidence all the same (a full-resolution pass that read the whole pixel budget, leaving a
    weak box's cell at even odds, names its sure faces at 0.991), one below it was forced.
    """
    probabilities = [face.probability for face in getattr(result, 'faces', ())]
    sure = sum(p >= confidence for p in probabilities if not math.isnan(p))
    which = (f'every face at the confidence {confidence:g}' if sure == len(probabilities) else
             f'no face at the confidence {confidence:g}' if not sure else
             f'{sure} of the faces at the confidence {confidence:g}, the others forced')
    return (f'search forced by {answer.limit_text(result.stop, _cause(result))}: cells '
            f'still undecided on their likelier side; {which}')


def nobody_text(result, confidence: float) -> str:
    """
    Say an ``absent`` of the many-target belief: its rule per cell, then ``P(nobody here)``.

    Each cell is decided on its own, so the product over the cells can be below the confidence
    each reached, or below 0.5 when a limit forced every cell to its likelier side.
    """
    reason = _reason(result)
    rule = ('every cell likelier empty than occupied' if answer.forced('absent', reason) else
            f'every cell decided empty at the confidence {confidence:g}')
    return (f'{answer.heading("absent", reason, _cause(result))}: {rule}, P(nobody here) '
            f'{result.answer_probability:.3f}')


def _reason(result) -> str:
    return result.method if result.method in ('full_frame', 'scales') else result.stop


def _cause(result) -> str:
    """Return what ended a search at its repeat stop (``ImageSearch.limit_cause``), else ''."""
    return getattr(result, 'limit_cause', '')


def entry(path: str, result, grid, confidence: float | None = None) -> dict:
    """
    Return one result's JSON entry: ``cell`` [row, col], ``pixel`` [x, y], null unless found.

    ``probability`` is the answer's (the found cell's; ``P(absent)`` for ``absent``),
    ``map_probability`` the most likely cell's, ``ended`` how the search ended.
    """
    found = result.decision == 'found'

    def number(value):
        return None if math.isnan(value) else float(value)
    return {'path': path, 'cell': list(result.cell) if found else None,
            'pixel': [result.pixel[0], result.pixel[1]] if found else None,
            'probability': number(result.answer_probability), 'fixations': result.fixations,
            'detector_pixels': result.detector_pixels,
            'full_scan_pixels': result.image_px[0] * result.image_px[1],
            'seconds': result.seconds, 'decision': result.decision, 'ended': result.ended,
            'confidence': confidence, 'map_probability': number(result.probability),
            'absent_probability': number(result.absent_probability), 'stop': result.stop,
            'method': result.method, 'note': result.note,
            'resized_from': None if result.resized_from is None else list(result.resized_from),
            'grid': {'rows': grid.rows, 'cols': grid.cols}}


def _note(message: str) -> None:
    print(f'ipomdp-gaze find: {message}', file=sys.stderr)


def _error(message: str) -> None:
    print(f'ipomdp-gaze find: error: {message}', file=sys.stderr)


def default_models(detector: str = FIND_DETECTORS[0]) -> list[str]:
    """
    Return the shipped models of a detector, one per size (default YuNet: faces-<size>-yunet).

    Chosen on training material only (docs/faces.md "find on real photographs"): on the seven
    training photos and eight training group pictures (the astronaut three times on each
    training background, 24 faces) both detectors find every face; YuNet answers ``found`` near
    no face once (``coffee``), Haar seven times (in the groups, five on one ``grass`` picture).
    The scene set's upscaled grey thumbnails favour Haar and keep it for the scene tasks.
    """
    return shipped_image_models(detector)


class _Tasks:
    """The model(s), built once: one task per model, shared by the images that use it."""

    def __init__(self, args):
        self.args = args
        detector = getattr(args, 'detector', None)
        if detector is not None:
            load_factory(detector)              # unknown or not importable: one line
        if args.observation:
            self.models, self.shipped = [load_observation(args.observation)], False
            recorded = (self.models[0].meta.get('detector') or {}).get('kind', 'haar')
            if detector is not None and recorded != detector:
                raise ValueError(f'--observation {args.observation} was calibrated with the '
                                 f'detector {recorded!r}, not --detector {detector!r}')
        else:
            detector = detector or FIND_DETECTORS[0]
            self.models = [load_observation(name) for name in default_models(detector)]
            if not self.models and detector in FIND_DETECTORS:
                raise ValueError(f'no observation model of the {detector} detector is shipped '
                                 f'with this install; pass --observation FILE (an '
                                 f'ipomdp_gaze/observation-v1 file, e.g. from ipomdp-gaze '
                                 f'calibrate)')
            if not self.models:
                raise ValueError(
                    f'no observation model of the detector {detector!r} is shipped (find '
                    f'ships models for {" and ".join(FIND_DETECTORS)}); calibrate one on '
                    f'labelled images, ipomdp-gaze calibrate --images DIR --labels faces.csv '
                    f'--detector {detector} --out model.yaml, then pass --observation '
                    f'model.yaml')
            self.shipped = True
        self.tasks = {}
        if args.policy or args.policy_file:     # a bad one: one line before any image
            flag = '--policy-file' if args.policy_file else '--policy'
            for model in self.models:
                try:
                    build_find_policy(args, model, lambda message: None)
                except ValueError as exc:
                    raise ValueError(f'{flag}: {exc}') from None
        if args.observation:                    # a bad model or policy: refused before any image
            self.task((0, 0))

    def task(self, size) -> _Task:
        model = nearest_model(self.models, size) if size != (0, 0) else self.models[0]
        if id(model) not in self.tasks:
            self.tasks[id(model)] = _Task(self.args, model, self.shipped, _note)
            _note(self.tasks[id(model)].description)
        return self.tasks[id(model)]


def _in_given_pixels(result, scale: tuple, given: tuple):
    """Return a result on a resized image with its pixels (boxes cut to it) in the given one's."""
    sx, sy = scale
    x, y = result.pixel
    faces = tuple(replace(face, box=clip_box((face.box[0] * sx, face.box[1] * sy,
                                              face.box[2] * sx, face.box[3] * sy), given))
                  for face in result.faces)
    return replace(result, pixel=(x * sx, y * sy), resized_from=tuple(given),
                   detections=tuple((u * sx, v * sy) for u, v in result.detections), faces=faces)


def scale_table(model):
    """Return the coarse-pass table of the model's detector (None: the fovea's own scan)."""
    kind = (model.meta.get('detector') or {}).get('kind', 'haar')
    return SCALE_TABLES.get(kind)


def ladder_start(model, scales) -> float:
    """Return the first scale of ``--scan coarse`` for a model (:data:`LADDER_START`)."""
    size = calibrated_size(model)
    side = min(size) if size else 420
    known = [key for key in LADDER_START if key[0] == scales.detector]
    if not known:
        return scales.rows[0].scale
    return LADDER_START[min(known, key=lambda key: abs(math.log(side / key[1])))]


def search_route(task, image_px: tuple[int, int], settings, find_all: bool,
                 scan: str = SCAN_DEFAULT) -> tuple[str, str]:
    """
    Return which search :func:`search_one` runs on an image of ``image_px``, and why whole.

    ``(route, reason)``: ``full_frame`` (a small image: :func:`full_frame_search`, ``reason``
    its :func:`full_frame_reason`), ``many`` (:func:`search_many`, ``--all``), ``all`` (the old
    loop, ``--all --targets one``), ``ladder`` (``--scan coarse``: :func:`search_scales`),
    ``first`` (``--scan many``: :func:`search_first`) or ``fovea`` (``--scan fovea``, or a
    detector without a scale table: :func:`search_image`); ``reason`` is '' but for
    ``full_frame``.
    """
    if settings.targets == 'many':
        route = 'many'
    elif find_all:
        route = 'all'
    elif scan == 'fovea' or scale_table(task.model) is None:
        route = 'fovea'
    else:
        route = 'ladder' if scan == 'coarse' else 'first'
    # the ladder uses no fovea: its reason is said of the image and the scan's scales
    reason = full_frame_reason(task.fovea, image_px, calibrated_size(task.model),
                               uses_fovea=route != 'ladder')
    return ('full_frame', reason) if reason else (route, '')


def search_one(image, task, settings, rng, find_all: bool,
               min_face: float | None = None, scan: str = SCAN_DEFAULT,
               empty_by_evidence: bool = EMPTY_BY_EVIDENCE,
               crowd_ratio: float = CROWD_RATIO, given_px: int | None = None) -> list:
    """
    Search one image: the fovea within one full scan's pixels, or the full frame (say why).

    ``min_face`` (``--min-face``, in this image's pixels): the smallest face that matters to
    the many-target search's coarse pass (``--all``, ``--scan many``; default 1/10 of the
    shorter side) and to the ladder of ``--scan coarse`` (default: it ends at full
    resolution); not to the full frame, the old loop or the fovea (:func:`search_route`);
    ``empty_by_evidence``: its rule for cells nobody occupies, ``crowd_ratio`` its step to a
    finer call for a crowd (:func:`search_many`). ``given_px``: the pixels of the image as
    given, before ``--max-side`` resized it (default this image's): the many-target search
    reads at most one full-resolution call of that image, the other searches of this one.
    """
    width, height = image.shape[1], image.shape[0]
    route, reason = search_route(task, (width, height), settings, find_all, scan)
    if route == 'full_frame':
        results = full_frame_search(image, task.fovea, reason, calibrated_size(task.model))
        if settings.targets == 'many':
            return [results[0]]
        return results if find_all else results[:1]
    budget = width * height
    scales = scale_table(task.model)
    if route == 'many':
        prepare_many(task.fovea, task.model, scales)      # one-time set-up
        budget = max(budget, given_px or 0)
        return [search_many(image, task.fovea, task.model, settings, pixel_budget=budget,
                            scales=scales, min_face=min_face,
                            empty_by_evidence=empty_by_evidence, crowd_ratio=crowd_ratio)]
    if route == 'all':
        return search_all(image, task.fovea, task.model, task.policy, settings, rng=rng,
                          pixel_budget=budget)
    if route == 'ladder':
        return [search_scales(image, task.fovea, task.model, scales,
                              start=ladder_start(task.model, scales),
                              finest=finest_scale(scales, min_face, (width, height)))]
    if route == 'first':
        prepare_many(task.fovea, task.model, scales)      # one-time set-up
        return [search_first(image, task.fovea, task.model, settings, pixel_budget=budget,
                             scales=scales, min_face=min_face)]
    return [search_image(image, task.fovea, task.model, task.policy, settings, rng=rng,
                         pixel_budget=budget)]


def min_face_notes(path: str, given: float | None, min_face: float | None, route: str,
                   model, image_px: tuple[int, int] | None = None) -> list[str]:
    """
    Return what stderr says about ``--min-face`` on one image (none: an empty list).

    ``given``: ``--min-face`` in the given image's pixels; ``min_face``: the same side in the
    searched image (after ``--max-side``), which the notes quote (and ``given`` beside it when
    the image was resized); ``route``: :func:`search_route`'s. On the ladder (``ladder``),
    when it ends on the frame enlarged beyond the table's finest row (its own rungs,
    :func:`~ipomdp_gaze.vision.scales.ladder_scales`, decide), saying so, and at the cap
    (:func:`~ipomdp_gaze.vision.scales.max_enlargement` of the searched image of ``image_px``)
    that such faces may still be missed; on
    the coarse pass (``many``, ``first``), when the faces are below the side the table sees at
    full resolution. Nothing on the other routes (a small image scanned whole, the old loop,
    the fovea), which do not use ``--min-face``.
    """
    table = scale_table(model)
    if min_face is None or table is None or route not in ('ladder', 'many', 'first'):
        return []
    finest = table.rows[-1]
    faces = (f'faces of {given:g} px are' if math.isclose(given, min_face) else
             f'faces of {given:g} px are {min_face:.3g} px in the searched image,')
    below = (f'{faces} below the {finest.min_side_px:.0f} px from which the {table.detector} '
             f'table sees faces at full resolution')
    if route != 'ladder':
        return ([f'{path}: {below}: they may be missed'] if min_face < finest.min_side_px
                else [])
    rungs = ladder_scales(table, ladder_start(model, table),
                          finest_scale(table, min_face, image_px))
    need = finest.min_side_px / min_face
    cap = max_enlargement(image_px)
    if need > cap and cap <= finest.scale:
        return [f'{path}: {below}: an image of this size is not enlarged (it would read more '
                f'than {MAX_ENLARGED_PX / 1e6:g} Mpx): faces of that size may be missed']
    if not rungs[-1] > finest.scale:
        return []
    note = f'{path}: {below}: the ladder ends on the image enlarged {rungs[-1]:.3g}x'
    if need > cap:
        note += (f', the most find enlarges an image of this size (they would need '
                 f'{need:.3g}x): faces of that size may still be missed')
    return [note]


# What each route leaves unused of the options given (search_route): the ladder takes no
# setting at all; the many-target searches keep their settings but choose by infomax.
FOVEA_OPTIONS = (('policy', '--policy'), ('policy_file', '--policy-file'),
                 ('confidence', '--confidence'), ('max_fixations', '--max-fixations'),
                 ('start_cell', '--start'), ('absent_prior', '--absent-prior'),
                 ('repeat_weight', '--repeat-weight'), ('seed', '--seed'))
UNUSED_BY_ROUTE = {'ladder': tuple(flag for _, flag in FOVEA_OPTIONS),
                   'many': ('--policy', '--policy-file', '--seed'),
                   'first': ('--policy', '--policy-file', '--seed')}


def unused_options(args, route: str, model) -> str | None:
    """
    Return the warning for options given that ``route`` does not use, or None.

    An option counts as given when it differs from find's default. A detector without a scale
    table searches with the fovea whatever ``--scan`` says: a note says so.
    """
    defaults = {'policy': None, 'policy_file': None, 'seed': 0, 'start_cell': None,
                **{key: getattr(FIND_SETTINGS, key) for key, _ in FOVEA_OPTIONS
                   if hasattr(FIND_SETTINGS, key)}}
    if route == 'fovea' and scale_table(model) is None and args.scan_mode != 'fovea':
        kind = model.meta.get('detector', {}).get('kind', 'its detector')
        return (f'note: --scan {args.scan_mode or SCAN_DEFAULT} needs a scale table, which '
                f'only the shipped detectors ({", ".join(FIND_DETECTORS)}) have: the model of '
                f'{kind} searches with the fovea (--scan fovea)'
                + (', without --min-face' if args.min_face is not None else ''))
    given = [flag for key, flag in FOVEA_OPTIONS
             if flag in UNUSED_BY_ROUTE.get(route, ())
             and getattr(args, key, defaults[key]) not in (defaults[key], TASK_DEFAULT)]
    if not given:
        return None
    how = {'ladder': 'the default scan (--scan coarse) calls the detector on the whole image '
                     'from coarse to fine and takes no fovea setting (--scan fovea',
           'many': 'the many-target search chooses its looks by infomax (--all --targets one',
           'first': '--scan many chooses its looks by infomax (--scan fovea'}[route]
    one = len(given) == 1
    return (f'warning: {", ".join(given)} {"is" if one else "are"} ignored: {how} uses '
            f'{"it" if one else "them"})')


def check_outputs(args, images: list[str], plots: list[Path]) -> None:
    """
    Refuse, before any search, an output that cannot be written: one line naming its option.

    ``--json``, ``--log`` (``-``: stdout, for one of them only) and each ``--plot`` file must
    not be a folder, an input image or another output, and must sit in a folder that exists or
    can be made (no file on the way).
    """
    outputs = [('--json', args.json), ('--log', args.log)] + [('--plot', plot) for plot in plots]
    outputs = [(flag, path) for flag, path in outputs if path is not None]
    if args.json == STDOUT and args.log == STDOUT:
        raise ValueError('--json - and --log - would both write to stdout: give one of them a '
                         'file')
    # realpath, not Path.resolve: a symbolic link loop is the input's own error, not a traceback
    inputs = {Path(os.path.realpath(image)) for image in images}
    seen = {}
    for flag, path in outputs:
        if path == STDOUT:
            continue
        try:
            os.stat(path)
        except OSError as exc:  # a folder on the way that refuses a look (EACCES) is named too
            if exc.errno not in (errno.ENOENT, errno.ENOTDIR, errno.ELOOP):
                raise ValueError(f'{flag} {path}: {exc.strerror or exc}') from None
        if path.is_dir():
            raise ValueError(f'{flag} {path}: is a directory')
        if _loops(path):
            raise ValueError(f'{flag} {path}: a symbolic link loop')
        resolved = Path(os.path.realpath(path))
        if resolved in inputs:
            raise ValueError(f'{flag} {path}: is an input image (it would be overwritten)')
        if resolved in seen:
            raise ValueError(f'{flag} {path}: {seen[resolved]} writes the same file')
        seen[resolved] = flag
        check_output_file(flag, path)


def _check_size(path: str, image: np.ndarray, given: tuple, fovea, max_side: int) -> None:
    """Check the searched image's size; name ``--max-side`` when the resize made it too small."""
    searched = (image.shape[1], image.shape[0])
    try:
        check_image_size(searched, fovea)
    except ValueError as exc:
        if searched == tuple(given):
            raise
        try:
            check_image_size(given, fovea)
        except ValueError as small:             # too small as given: not the resize's doing
            raise ValueError(f'{path}: {small}') from None
        need = str(exc).partition('too small: ')[2] or str(exc)
        raise ValueError(f'{path}: --max-side {max_side} resized it from {given[0]}x{given[1]} '
                         f'to {searched[0]}x{searched[1]} px, too small: {need} (give a larger '
                         f'--max-side, or 0 not to resize)') from None


def _write(text: str, out: Path, flag: str) -> bool:
    """
    Write ``text`` to ``out`` (``-``: stdout), saying where; False after one line if it fails.

    A disk that fills during the run (checked writable before it) costs this output only, and
    leaves the file that was there, or none, not half of one.
    """
    if out == STDOUT:
        sys.stdout.write(text)
        sys.stdout.flush()
        return True
    try:
        write_text(out, text)
    except OSError as exc:
        _error(f'{flag} {out}: cannot write: {exc.strerror or exc}')
        return False
    _note(f'wrote {out}')
    return True


def _plot(image, result, task, out: Path, title: str, occupancy: bool) -> bool:
    """Draw one image's plot to ``out``; False after one line naming it if it cannot be written."""
    try:
        plot_image_search(image, result, task.fovea, out, title, occupancy)
    except OSError as exc:      # a full disk: this plot is lost, not the other images' search
        _error(f'--plot {out}: cannot write: {exc.strerror or exc}')
        return False
    _note(f'wrote {out}')
    return True


def run(args) -> int:
    settings = settings_from_args(args, FIND_SETTINGS)  # bad settings: refused before any work
    if (args.all and args.targets is TASK_DEFAULT) or args.targets == 'many' \
            or (not args.all and args.scan_mode == 'many'):     # --scan many: the same belief
        check_many_settings(replace(settings, targets='many'))
    if args.plot:
        plot_format(args.plot)
    skipped = []
    images = expand_inputs(args.images, skipped)
    for folder, names in skipped:
        if not names:           # alone: the error below says it
            if images:
                _note(f'{folder}: an empty folder, nothing in it searched')
            continue
        files = sum(not name.endswith('/') for name in names)
        folders = len(names) - files
        what = ' and '.join(
            ([f'{files} file{"s" * (files > 1)} not named as an image'] if files else [])
            + ([f'{folders} folder{"s" * (folders > 1)}'] if folders else []))
        _note(f'{folder}: {what} skipped ({", ".join(names[:3])}{", ..." * (len(names) > 3)}; '
              f'name one to search it)')
    if not images:
        raise ValueError(f'no image files in {", ".join(args.images)}')
    plots = plot_paths(args.plot, len(images)) if args.plot else []
    check_outputs(args, images, plots)
    tasks = _Tasks(args)
    if args.scan_mode is not None and (args.all or args.targets == 'many'):
        _note(f'warning: --scan {args.scan_mode} is ignored: it chooses how find looks for one '
              f'face, and --all / --targets many search for every face')
    scan = args.scan_mode or SCAN_DEFAULT
    entries, logs, failed, grid, warned, unwritten = [], [], 0, None, set(), 0
    out = sys.stderr if STDOUT in (args.json, args.log) else sys.stdout
    for i, path in enumerate(images):
        notes = []
        try:
            sizes = []                          # the decoded size, before --max-side
            image = read_image(path, notes, args.max_side, sizes)
            given = sizes[0]
            scale = (given[0] / image.shape[1], given[1] / image.shape[0])
            if scale != (1.0, 1.0):
                wide = max(image.shape[:2]) > args.max_side     # a panorama's pixel bound
                notes.append(f'{path}: resized from {given[0]}x{given[1]} to '
                             f'{image.shape[1]}x{image.shape[0]} px before the search '
                             f'(--max-side {args.max_side}' +
                             (f': a panorama beyond {PANORAMA_RATIO:g}:1 keeps '
                              f'{PANORAMA_AREA_FRACTION * args.max_side ** 2 / 1e6:.2g} Mpx)'
                              if wide else ')'))
            task = tasks.task((image.shape[1], image.shape[0]))
            _check_size(path, image, given, task.fovea, args.max_side)
            settings = settings_from_args(args, FIND_SETTINGS, task.model.grid)
            if args.all and args.targets is TASK_DEFAULT:
                settings = replace(settings, targets='many')
        except (ValueError, MemoryError, cv2.error) as exc:
            # out of memory converting or resizing a decoded image: this image's error too
            if isinstance(exc, cv2.error) and 'Insufficient memory' not in str(exc):
                raise
            message = str(exc) if isinstance(exc, ValueError) else \
                f'{path}: out of memory reading it (a smaller image file)'
            _error(message if message.startswith(path) else f'{path}: {message}')
            reason = message[len(path) + 2:] if message.startswith(f'{path}: ') else message
            entries.append({'path': path, 'error': reason})
            failed += 1
            continue
        for note in notes:
            _note(note)
        grid = task.model.grid
        min_face = None if args.min_face is None else args.min_face / max(scale)
        route, _ = search_route(task, (image.shape[1], image.shape[0]), settings, args.all,
                                scan)
        warning = unused_options(args, route, task.model)
        if warning is not None and warning not in warned:
            warned.add(warning)
            _note(warning)
        for note in min_face_notes(path, args.min_face, min_face, route, task.model,
                                   (image.shape[1], image.shape[0])):
            _note(note + (' (--max-side 0 searches the image at its own size)'
                          if scale != (1.0, 1.0) else ''))
        if route == 'many' and args.min_face is None and scale != (1.0, 1.0):
            _note(f'{path}: --all looks for faces of {min_face_px(given):.0f} px or more '
                  f'(1/10 of the shorter side; a face found below {CROWD_RATIO:g} times '
                  'that, or none, sends it finer): '
                  '--min-face PX --max-side 0 looks for smaller faces')
        try:
            results = search_one(image, task, settings, np.random.default_rng([args.seed, i]),
                                 args.all, min_face, scan, given_px=given[0] * given[1])
        except (ValueError, MemoryError, cv2.error) as exc:
            # a detector that fails on this image (DetectorFailed, a box it should not give)
            # or runs out of memory: reported against the image, the others still searched
            if isinstance(exc, cv2.error) and 'Insufficient memory' not in str(exc):
                raise
            reason = (str(exc).removeprefix(f'{path}: ') if isinstance(exc, ValueError) else
                      f'out of memory searching it at {image.shape[1]}x{image.shape[0]} px '
                      f'(a smaller --max-side, or a larger --min-face, reads fewer pixels)')
            _error(f'{path}: {reason}')
            entries.append({'path': path, 'error': reason})
            failed += 1
            continue
        searched = results                      # in the searched image's pixels (the plot)
        if scale != (1.0, 1.0):
            results = [_in_given_pixels(r, scale, given) for r in results]
        if results[0].method == 'full_frame':
            _note(f'{path}: scanned the whole frame once: {results[0].note}' +
                  (f' ({image.shape[1]}x{image.shape[0]} px as --max-side {args.max_side} '
                   f'resized it; --max-side 0 searches it at its own size)'
                   if scale != (1.0, 1.0) else ''))
        many = settings.targets == 'many'
        occupancy = route in OCCUPANCY_ROUTES
        for k, result in enumerate(results):
            for face in range(len(result.faces) if many else 0):
                print(face_line(path, result, face), file=out, flush=True)
            print(format_line(path, result, k if args.all and not many else None, occupancy),
                  file=out, flush=True)
            extra = ({'faces': [face.to_dict() for face in result.faces]} if many else
                     {} if not args.all else
                     {'face': k} if result.decision == 'found' else {'search': k})
            entries.append({**entry(path, result, grid, settings.confidence), **extra})
        logs.append(json_files.dumps({'path': path,
                                      'events': [e for r in results for e in r.log]},
                                     indent=None))
        if plots:
            title = plot_title(path, results[0], settings.confidence, occupancy,
                               len(results[0].faces) if many else None)
            unwritten += not _plot(image, searched[0], task, plots[i], title, occupancy)
    if args.log:
        unwritten += not _write('\n'.join(logs) + '\n' if logs else '', args.log, '--log')
    if args.json:
        rows, cols = grid.shape if grid is not None else (None, None)
        unwritten += not _write(json_files.dumps({'grid': {'rows': rows, 'cols': cols},
                                                  'axes': {'cell': ['row', 'col'],
                                                           'pixel': ['x', 'y']},
                                                  'images': entries}) + '\n',
                                args.json, '--json')
    if failed:
        _error(f'{failed} of {counted(len(images), "input")} could not be searched')
    return 2 if failed or unwritten else 0
