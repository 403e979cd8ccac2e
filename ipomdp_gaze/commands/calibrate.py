# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze calibrate``: measure a count model of a real detector behind the digital fovea.

From labelled images (a folder and a CSV of face-centre pixels, a user's own data) or from
generated training scenes (``--scenes N``, the training split only: test faces and backgrounds
are never used), every image is fixated at every cell and the counts tallied per offset
(:mod:`ipomdp_gaze.vision.calibrate`). Writes the observation file, prints the hit and
false-alarm rates ``P(c > 0)`` per offset, and draws the learned FPOC.

``--pan-tilt`` calibrates the pan/tilt task instead (docs/design.md section 6.5): training
scenes spanning the pan/tilt grid are viewed through the scene camera's geometry from every
head pose, the detector runs on each whole view and its detections are binned to pan/tilt
cells, exactly as the ``scene_camera`` and ``foveal_detector`` nodes do. The file records no
wall time, so running the same command again writes the same file.

**Any detector.** ``--detector KIND`` (``haar``, ``yunet``, an ``ipomdp_gaze.detectors`` entry
point or ``package.module:Factory``, whose code then runs) with ``--detector-option NAME=VALUE``
for its own settings; the file records the detector's settings and fingerprint. ``--cells``
says what a cell's observation is: ``counts`` (the default), ``score_bins`` (the cell's best
score in K - 1 bins whose edges are chosen here, on the first ``--edge-images`` training images
or scenes, and recorded), ``threshold`` (detections scoring at least ``--threshold``) or, with
``--pan-tilt``, ``grouped`` (the support of the view's grouped boxes, ``--min-neighbors``, in
bins of ``--group-edges`` or of quantiles chosen on the edge scenes; ``--raw-levels`` keeps the
raw count of a cell without a group).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path
import sys
import time

from ipomdp_gaze.files.observation_file import MAX_K
from ipomdp_gaze.files.writable import write_figure
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.wording import counted
import numpy as np

from .common import C_INT_MAX, check_output_file, count_in, grid_arg, jobs_arg, nonneg_int, \
    number_arg, number_in, output_file, positive_float, positive_int, probability_arg, \
    scene_count, size_arg
from .running import add_run_args, executor_from_args, progress_from_args

# The two tasks of the face issue: image side and face sizes in pixels.
TASKS = {'paper': (420, (60, 140)), 'small': (840, (24, 140))}


# The largest whole number of a list flag (--windows, --face-px): OpenCV takes C ints.
MAX_WHOLE = C_INT_MAX
# --max-count: K, the counts 0..K-1 of a cell, as many as an observation file tabulates.
MAX_COUNT = count_in(2, MAX_K, f'K from 2 to {MAX_K} (the counts an observation file holds)')
# --min-neighbors: detectMultiScale's minNeighbors, an OpenCV int.
MIN_NEIGHBORS = count_in(1, C_INT_MAX, "a positive integer up to 2^31 - 1 (OpenCV's int)")
# --raw-levels: at least one group bin and the empty cell's 0 above them within K.
RAW_LEVELS = count_in(0, MAX_K - 3, f'an integer from 0 to {MAX_K - 3} (K is at most {MAX_K})')


def _numbers(kind):
    """Parse comma-separated numbers (``1/7`` too) for argparse; ``int``: whole ones only."""
    what = 'whole numbers' if kind is int else 'numbers'

    def parse(text: str):
        try:
            values = [eval_fraction(part) for part in text.split(',')]
        except (ValueError, ZeroDivisionError, OverflowError):
            values = None
        # a whole number: 2.5 is not cut to 2, infinity not an OverflowError (nor 1e21 later)
        whole = values is not None and all(math.isfinite(v) and v == int(v) and abs(v) <= MAX_WHOLE
                                           for v in values)
        if values is None or (kind is int and not whole):
            raise argparse.ArgumentTypeError(f'expected comma-separated {what}, got '
                                             f'{text!r}')
        return tuple(kind(v) for v in values)
    return parse


# The largest Haar pyramid step, the detector node's (a step of 1e21 is std::bad_alloc).
MAX_SCALE_FACTOR = 10.0
# --scale-factor: detectMultiScale's pyramid step, > 1 and at most MAX_SCALE_FACTOR.
SCALE_FACTOR = number_in(1.0, MAX_SCALE_FACTOR, f'a number > 1 and at most {MAX_SCALE_FACTOR:g}',
                         low_open=True)
# --pan-tilt's angles: the cell spacing (up to a right angle) and the lens's field of view.
SPACING_DEG = number_in(0.0, 90.0, 'degrees in (0, 90]', low_open=True)
HFOV_DEG = number_in(0.0, 180.0, 'degrees in (0, 180)', low_open=True, high_open=True)


def eval_fraction(text: str) -> float:
    """Read ``'0.25'`` or ``'1/7'`` as a number."""
    num, sep, den = text.strip().partition('/')
    return float(num) / float(den) if sep else float(num)


# calibrate --resize: the relative difference of aspect ratios taken as the same (a 1000x667
# photo is 3:2 within 0.05%, a 1024x768 frame 4:3 exactly); beyond it faces would be squashed.
RESIZE_ASPECT_TOL = 0.02


def add_parser(sub):
    p = sub.add_parser('calibrate', help='measure a count model of a detector behind the fovea',
                       description='Fixate every cell of labelled images, tally the detector '
                                   'counts per offset from the fixation with and without the '
                                   'face, and write an ipomdp_gaze/observation-v1 file.')
    p.add_argument('--pan-tilt', action='store_true',
                   help='calibrate the pan/tilt task: a head camera looking around training '
                        'scenes (--scenes N; the shipped faces-pan-tilt model)')
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument('--scenes', type=scene_count, metavar='N',
                        help='N generated training scenes (training faces and backgrounds only)')
    source.add_argument('--images', type=Path, metavar='FOLDER',
                        help='a folder of images, labelled by --labels')
    p.add_argument('--labels', type=Path, metavar='CSV',
                   help='CSV "path,x,y" of face-centre pixels (empty x,y: no face)')
    p.add_argument('--resize', type=size_arg, default=None, metavar='WIDTHxHEIGHT',
                   help='--images: resize every image (and its label) to this size, for a '
                        'folder of several sizes of one aspect ratio (within 2%%); the model is '
                        'calibrated at it')
    p.add_argument('--task', choices=tuple(TASKS), default=None,
                   help='scene size and face sizes of --scenes: paper (420 px, faces 60-140) '
                        'or small (840 px, faces 24-140); default paper')
    p.add_argument('--absent-rate', type=probability_arg, default=None,
                   help='fraction of --scenes without a face (default 0)')
    p.add_argument('--seed', type=nonneg_int, default=0, help='scene seed (default 0)')
    p.add_argument('--grid', type=grid_arg, default=None,
                   help='grid tiling each image (default 21x21), or the pan/tilt grid '
                        '(default 11x11)')
    p.add_argument('--spacing-deg', type=SPACING_DEG, default=None,
                   help='--pan-tilt: degrees between neighbouring cells (default 5)')
    p.add_argument('--camera', type=size_arg, default=None, metavar='WIDTHxHEIGHT',
                   help='--pan-tilt: camera image size in pixels (default 320x240)')
    p.add_argument('--hfov-deg', type=HFOV_DEG, default=None,
                   help='--pan-tilt: horizontal field of view, edge to edge (default 25)')
    p.add_argument('--face-px', type=_numbers(int), default=None, metavar='MIN,MAX',
                   help='--pan-tilt: face sides in scene pixels (default 30,70)')
    p.add_argument('--null-scenes', type=nonneg_int, default=None, metavar='M',
                   help='--pan-tilt: the first M scenes are viewed from every pose (null '
                        'tables); the others only from poses that see the face (default 40)')
    p.add_argument('--windows', type=_numbers(int), default=None, metavar='W,...',
                   help='fovea window sides in cells, largest first (default 21,15,9,3)')
    p.add_argument('--scales', type=_numbers(float), default=None, metavar='S,...',
                   help='resize factor per window, e.g. 1/7,1/5,1/3,1 (default: NMPT, the '
                        'pixel size of the smallest window)')
    p.add_argument('--interpolation', default=None,
                   help='window resampling: area (default), nearest, linear, cubic')
    p.add_argument('--scan-once', action='store_true',
                   help='observe the whole-image window once per image, with its own table '
                        '(the shipped models), instead of in every fixation (NMPT)')
    p.add_argument('--max-count', type=MAX_COUNT, default=10,
                   help='K: counts are clipped to 0..K-1 (default 10)')
    p.add_argument('--scale-factor', type=SCALE_FACTOR, default=1.1,
                   help='haar: detectMultiScale scale factor (default 1.1)')
    p.add_argument('--detector', default='haar', metavar='KIND',
                   help='detector: haar (default), yunet, an ipomdp_gaze.detectors entry point '
                        'or package.module:Factory (this imports and runs that module)')
    p.add_argument('--detector-option', action='append', default=[], metavar='NAME=VALUE',
                   help="one of the detector's own settings (repeat for more; YAML values)")
    p.add_argument('--cells', choices=('counts', 'score_bins', 'threshold', 'grouped'),
                   default='counts',
                   help="a cell's observation: the count of detections centred in it "
                        '(default), its best score in K - 1 bins chosen on training data, '
                        'the count of detections scoring at least --threshold, or (--pan-tilt) '
                        'the support of its largest group of raw boxes grouped as OpenCV does')
    p.add_argument('--min-neighbors', type=MIN_NEIGHBORS, default=None, metavar='N',
                   help='--cells grouped: groups of at most N raw boxes are dropped (default 1)')
    p.add_argument('--raw-levels', type=RAW_LEVELS, default=None, metavar='R',
                   help='--cells grouped: a cell without a group reads its raw count clipped '
                        'to R (default 0: it reads 0)')
    p.add_argument('--group-edges', type=_edges_arg, default=None, metavar='E1,E2,...',
                   help='--cells grouped: fixed increasing edges on the support (K is then '
                        'their number + R + 2); default: K - 1 - R bins at quantiles of the '
                        'supports on the edge scenes')
    p.add_argument('--threshold', type=number_arg, default=None,
                   help='--cells threshold: the lowest score counted')
    p.add_argument('--edge-images', type=positive_int, default=20, metavar='M',
                   help='--cells score_bins: choose the bin edges on the first M training '
                        'images or scenes (default 20)')
    p.add_argument('--prior', type=positive_float, default=1.0,
                   help='Dirichlet prior per count (default 1)')
    p.add_argument('--pool-radius', type=number_arg, default=None,
                   help='pool target tallies of offsets within this distance in cells '
                        '(default 0.5; --pan-tilt 0: none, a view is not round)')
    p.add_argument('--min-tallies', type=nonneg_int, default=None,
                   help='widen the pooling where an offset has fewer target observations '
                        '(default 50; --pan-tilt 0)')
    p.add_argument('--fixation-stride', type=positive_int, default=1, metavar='S',
                   help='fixate the cells whose row and column are multiples of S (and the '
                        'last row and column) instead of every cell (default 1: every cell)')
    p.add_argument('--processes', dest='jobs', type=jobs_arg, help=argparse.SUPPRESS)
    p.add_argument('--out', type=output_file, required=True, metavar='FILE.yaml')
    p.add_argument('--plot', type=output_file, default=None, metavar='PNG',
                   help='figure of the learned FPOC (default: beside --out)')
    add_run_args(p)
    p.set_defaults(run=run)


def _items(args, grid: Grid):
    """
    Labelled items for the workers, the image size they share, their source and their names.

    The names (each image's file as the label CSV gives it, under ``--images``; None for
    ``--scenes``, whose scenes are named by index and seed) are what a failure is reported
    against.
    """
    if args.scenes is not None:
        if args.labels is not None:
            raise ValueError('--labels goes with --images, not --scenes')
        size, faces = TASKS[args.task]
        kwargs = {'split': 'train', 'size_px': size, 'face_px': faces, 'grid': grid.shape,
                  'absent_rate': args.absent_rate, 'seed': args.seed}
        from ipomdp_gaze.vision.scenes import SceneSet
        SceneSet(**kwargs)                                   # validate before the workers
        return [('scene', kwargs, i) for i in range(args.scenes)], (size, size), kwargs, None
    if args.labels is None:
        raise ValueError('--images needs --labels CSV')
    from ipomdp_gaze.vision.scenes import cell_of_point, labelled_names, read_labelled_folder
    labelled = read_labelled_folder(args.images, args.labels)
    if not labelled:
        raise ValueError(f'{args.labels} lists no images')
    entries = labelled_names(args.images, args.labels)
    if args.resize is not None:
        labelled = resize_labelled(labelled, args.resize, names=entries)
    shapes = {item.image.shape[:2] for item in labelled}
    if len(shapes) > 1:
        raise ValueError(f'images must share one size to calibrate one model, got '
                         f'{", ".join(f"{w}x{h}" for h, w in sorted(shapes))} px (--resize '
                         f'WIDTHxHEIGHT resizes them and their labels)')
    shape = shapes.pop()
    items = []
    for item in labelled:
        cell = None
        if item.centre_px is not None:
            r, c = cell_of_point(item.centre_px[0], item.centre_px[1], shape, grid.shape)
            cell = r * grid.cols + c
        items.append((item.image, cell))
    source = {'images': str(args.images), 'labels': str(args.labels)}
    if args.resize is not None:
        source['resize'] = list(args.resize)
    return items, shape, source, [str(Path(args.images) / entry) for entry in entries]


def resize_labelled(labelled, size_px: tuple[int, int], tolerance: float = RESIZE_ASPECT_TOL,
                    names=None):
    """
    Return labelled images resized to ``size_px`` ``(width, height)``, their face centres too.

    Each image keeps its content (no crop, no padding), so an aspect ratio more than
    ``tolerance`` (relative) from the size's would squash the faces the model is calibrated
    on: refused, naming the image (by ``names[i]``, its label CSV entry, when given).
    """
    import cv2
    from ipomdp_gaze.vision.scenes import LabelledImage
    width, height = size_px
    out = []
    for index, item in enumerate(labelled):
        h, w = item.image.shape[:2]
        if abs((w / h) / (width / height) - 1.0) > tolerance:
            name = names[index] if names is not None else f'image {index + 1} of --labels'
            raise ValueError(f'--resize {width}x{height}: {name} is {w}x{h} px, another aspect '
                             f'ratio (crop it to {width}:{height} first, and move its label)')
        shrink = width * height < w * h
        image = item.image if (w, h) == (width, height) else cv2.resize(
            item.image, (width, height),
            interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
        centre = None if item.centre_px is None else \
            (item.centre_px[0] * width / w, item.centre_px[1] * height / h)
        out.append(LabelledImage(image, centre))
    return out


def rate_table(model, size: int = 6) -> str:
    """Hit / false-alarm rates ``P(c > 0)`` for offsets up to ``size - 1`` cells, as text."""
    from ipomdp_gaze.vision.calibrate import hit_false_alarm
    hit, fa = hit_false_alarm(model)
    size = min(size, hit.shape[0], hit.shape[1])
    head = '|dr| \\ |dc| ' + ''.join(f'{dc:>14d}' for dc in range(size))
    lines = ['P(count > 0): hit (target in the cell) / false alarm (no target); -: never seen',
             head]
    for dr in range(size):
        cells = [f'  {hit[dr, dc]:.3f}/{fa[dr, dc]:.4f}' if np.isfinite(hit[dr, dc])
                 else f'{"-":>14}' for dc in range(size)]
        lines.append(f'{dr:>11d} ' + ''.join(cells))
    if model.has_scan:
        lines.append(f'whole-image scan: hit {1 - model.scan_target[0]:.3f} / false alarm '
                     f'{1 - model.scan_null[0]:.4f}')
    return '\n'.join(lines)


def plot_fpoc(model, path: Path, title: str) -> None:
    """Heatmaps of the hit and false-alarm rates by offset, and both against distance."""
    import matplotlib
    matplotlib.use('Agg')
    from ipomdp_gaze.vision.calibrate import hit_false_alarm
    import matplotlib.pyplot as plt
    hit, fa = hit_false_alarm(model)
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for ax, data, name in ((axes[0], hit, 'P(c > 0 | target)'),
                           (axes[1], fa, 'P(c > 0 | no target)')):
        image = ax.imshow(data, origin='upper', cmap='viridis')
        fig.colorbar(image, ax=ax)
        ax.set(title=name, xlabel='|dc| (cells)', ylabel='|dr| (cells)')
    dr, dc = np.meshgrid(np.arange(hit.shape[0]), np.arange(hit.shape[1]), indexing='ij')
    dist = np.hypot(dr, dc).ravel()
    axes[2].plot(dist, hit.ravel(), 'o', ms=3, label='target')
    axes[2].plot(dist, fa.ravel(), 's', ms=3, label='no target')
    axes[2].set(yscale='log', xlabel='distance from the fixation (cells)',
                ylabel='P(c > 0)', title='learned FPOC')
    axes[2].legend()
    axes[2].grid(True, alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    write_figure(fig, path, dpi=100)
    plt.close(fig)


# Options of the image task that mean nothing for --pan-tilt, and the reverse.
IMAGE_ONLY = ('images', 'labels', 'resize', 'windows', 'scales', 'interpolation', 'absent_rate',
              'task', 'scan_once', 'fixation_stride')
PAN_TILT_ONLY = ('spacing_deg', 'camera', 'hfov_deg', 'face_px', 'null_scenes')
IMAGE_DEFAULTS = {'windows': (21, 15, 9, 3), 'interpolation': 'area', 'absent_rate': 0.0,
                  'task': 'paper', 'scan_once': False, 'fixation_stride': 1}


def _edges_arg(text: str) -> tuple:
    """Parse ``E1,E2,...``: increasing numbers (checked by the cell observation rule)."""
    try:
        return tuple(float(v) for v in text.split(','))
    except ValueError:
        raise argparse.ArgumentTypeError(f'edges must be numbers separated by commas, got '
                                         f'{text!r}') from None


def _check_options(args) -> None:
    """Refuse options of the other task; fill in the defaults of this one."""
    if args.cells == 'grouped' and not args.pan_tilt:
        raise ValueError('--cells grouped needs --pan-tilt: the fovea sees a face at several '
                         'scales and would group them apart')
    for name in ('min_neighbors', 'raw_levels', 'group_edges'):
        if args.cells != 'grouped' and getattr(args, name) is not None:
            raise ValueError(f"--{name.replace('_', '-')} goes with --cells grouped")
    for name in PAN_TILT_ONLY if not args.pan_tilt else IMAGE_ONLY:
        value = getattr(args, name)
        if value is not None and value != IMAGE_DEFAULTS.get(name):
            flag = '--' + name.replace('_', '-')
            raise ValueError(f'{flag} needs --pan-tilt' if not args.pan_tilt else
                             f'{flag} is for the image task, not --pan-tilt')
    if args.pan_tilt:
        args.grid = args.grid or (11, 11)
        args.pool_radius = 0.0 if args.pool_radius is None else args.pool_radius
        args.min_tallies = 0 if args.min_tallies is None else args.min_tallies
    else:
        for name, default in IMAGE_DEFAULTS.items():
            if getattr(args, name) is None:
                setattr(args, name, default)
        args.grid = args.grid or (21, 21)
        args.pool_radius = 0.5 if args.pool_radius is None else args.pool_radius
        args.min_tallies = 50 if args.min_tallies is None else args.min_tallies
    if not np.isfinite(args.pool_radius) or args.pool_radius < 0:
        raise ValueError(f'--pool-radius must be >= 0, got {args.pool_radius}')


def _detector(args):
    """Return the detector's plain settings for the workers, and the detector built from them."""
    from ipomdp_gaze.vision.detector import detector_settings
    from ipomdp_gaze.vision.detectors import (check_detector_record, detector_from_settings,
                                              detector_from_spec, load_factory, parse_options)
    spec = {'kind': args.detector, **parse_options(args.detector_option)}
    load_factory(args.detector)                     # an unknown --detector: its own line
    try:            # the types of the record the model will hold, in the file check's words
        check_detector_record(spec)
    except ValueError as exc:
        raise ValueError(f'--detector-option: {exc}') from None
    if args.detector == 'haar':
        spec.setdefault('scale_factor', args.scale_factor)
    elif args.scale_factor != 1.1:
        raise ValueError('--scale-factor is a haar setting; use --detector-option')
    detector = detector_from_spec(spec)
    # find and the node rebuild it from what the model records: check that now, not after
    try:
        detector_from_settings(detector_settings(detector))
    except ValueError as exc:
        raise ValueError(f'the detector cannot be rebuilt from the settings its model would '
                         f'record, so the model could not be used (is its settings() right?): '
                         f'{exc}') from None
    return spec, detector


def _cell_rule(args, pilot):
    """Return the cell observation rule of ``--cells``; ``pilot()`` tallies the edge images."""
    from ipomdp_gaze.model.cell_observation import CellObservation
    from ipomdp_gaze.vision.calibrate import choose_edges, choose_group_edges
    if args.cells == 'threshold':
        if args.threshold is None:
            raise ValueError('--cells threshold needs --threshold T')
        return CellObservation('threshold', args.max_count, threshold=args.threshold)
    if args.threshold is not None:
        raise ValueError('--threshold goes with --cells threshold')
    if args.cells == 'grouped':
        neighbors = 1 if args.min_neighbors is None else args.min_neighbors
        levels = args.raw_levels or 0
        if args.group_edges is not None:
            if len(args.group_edges) + levels + 2 > MAX_K:
                raise ValueError(f'--group-edges and --raw-levels make K = '
                                 f'{len(args.group_edges) + levels + 2} counts; an observation '
                                 f'file holds at most {MAX_K}')
            return CellObservation('grouped', len(args.group_edges) + levels + 2,
                                   args.group_edges, min_neighbors=neighbors, raw_levels=levels)
        if levels > args.max_count - 3:
            raise ValueError(f'--raw-levels {levels} leaves no group bin below --max-count '
                             f'{args.max_count} (at most {args.max_count - 3})')
        provisional = CellObservation('grouped', levels + 2, min_neighbors=neighbors,
                                      raw_levels=levels)
        return choose_group_edges(pilot(provisional), args.max_count, neighbors, levels)
    return choose_edges(pilot(None), args.max_count)


def _record_cells(meta: dict, cells, args) -> None:
    """Record the cell observation rule (none for plain counts: older files stay the same)."""
    if cells is not None:
        meta['cells'] = cells.to_dict()
        if cells.kind == 'score_bins' or (cells.kind == 'grouped' and
                                          args.group_edges is None):
            meta['calibration']['edges_from'] = args.edge_images


def run_pan_tilt(args) -> int:
    """Calibrate the pan/tilt task (``--pan-tilt``); see the module docstring."""
    from ipomdp_gaze.files.observation_file import save_observation
    from ipomdp_gaze.model.head_camera import PinholeCamera
    from ipomdp_gaze.vision.calibrate import count_model, tally_pan_tilt_scenes
    from ipomdp_gaze.vision.detector import detector_settings
    from ipomdp_gaze.vision.pan_tilt import (CAMERA_HFOV_DEG, CAMERA_SIZE_PX, FACE_PX,
                                             PanTiltSceneSet, SceneGeometry)
    if args.scenes is None:
        raise ValueError('--pan-tilt needs --scenes N (training scenes)')
    grid = Grid(args.grid[0], args.grid[1], args.spacing_deg or 5.0)
    width, height = tuple(args.camera) if args.camera else CAMERA_SIZE_PX
    camera = PinholeCamera.from_fov(width, height, args.hfov_deg or CAMERA_HFOV_DEG)
    geometry = SceneGeometry(grid, camera)
    face_px = tuple(args.face_px) if args.face_px else FACE_PX
    if len(face_px) != 2:
        raise ValueError(f"--face-px must be MIN,MAX, got {','.join(map(str, face_px))}")
    side = min(geometry.size_px)
    if not 1 <= face_px[0] <= face_px[1] <= side:
        # (the scenes' own check named face_px, a default the user had not given, in Python)
        raise ValueError(f'--face-px {face_px[0]},{face_px[1]}: faces must be MIN <= MAX pixels '
                         f'from 1 to {side}, the side of the scene that the grid, --camera and '
                         '--hfov-deg make')
    null_scenes = min(40 if args.null_scenes is None else args.null_scenes, args.scenes)
    scenes = PanTiltSceneSet('train', geometry, face_px, 'rgb', args.seed)
    detector_kwargs, detector = _detector(args)
    cells, max_count = None, args.max_count
    start = time.perf_counter()
    with executor_from_args(args) as executor:
        if args.cells != 'counts':
            cells = _cell_rule(args, lambda rule: tally_pan_tilt_scenes(
                scenes, range(min(args.edge_images, args.scenes)), detector_kwargs,
                args.max_count if rule is None else rule.max_count, None, executor=executor,
                cells=rule))
            max_count = cells.max_count
        with progress_from_args(args, args.scenes, 'calibrate', 'scene') as bar:
            tallies = tally_pan_tilt_scenes(scenes, range(args.scenes), detector_kwargs,
                                            max_count, null_scenes, progress=bar.update,
                                            executor=executor, cells=cells)
    wall = time.perf_counter() - start
    meta = {'image': {'width': width, 'height': height, 'view': 'pan_tilt',
                      'camera': camera.to_dict()},
            'detector': detector_settings(detector),
            'calibration': {'source': {'pan_tilt_scenes': args.scenes, 'split': 'train',
                                       'seed': args.seed, 'null_scenes': null_scenes,
                                       'face_px': list(face_px),
                                       'scene_px': list(geometry.size_px),
                                       'px_per_deg': round(geometry.px_per_deg, 9)},
                            'images': tallies.images, 'fixations': tallies.fixations,
                            'prior': args.prior, 'pool_radius': args.pool_radius,
                            'min_tallies': args.min_tallies,
                            'detector_pixels': int(tallies.detector_pixels)}}
    _record_cells(meta, cells, args)
    model = count_model(tallies, grid, args.prior, args.pool_radius, args.min_tallies, meta)
    save_observation(args.out, model)
    print(rate_table(model, size=4))
    plot = args.plot if args.plot is not None else args.out.with_suffix('.png')
    hfov, vfov = camera.fov_deg
    plot_fpoc(model, plot, f'{args.out.stem}: {tallies.images} pan/tilt scenes, '
                           f'{grid.rows}x{grid.cols} grid of {grid.spacing_deg:g} deg, '
                           f'{width}x{height} camera, {hfov:.1f}x{vfov:.1f} deg view')
    print(f'calibrated on {counted(tallies.images, "scene")} '
          f'({counted(tallies.fixations, "view")}) in {wall:.1f} s')
    print(f'ipomdp-gaze calibrate: wrote {args.out} and {plot}', file=sys.stderr)
    return 0


def run(args) -> int:
    from ipomdp_gaze.files.observation_file import save_observation
    from ipomdp_gaze.vision.calibrate import count_model, lattice_fixations, tally_images
    from ipomdp_gaze.vision.detector import detector_settings
    from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig
    if args.out.suffix != '.yaml':
        raise ValueError(f'--out must end in .yaml, got {args.out}')
    check_output_file('--out', args.out)
    if args.plot is not None:
        check_output_file('--plot', args.plot, plot=True)
    else:
        check_output_file('--out', args.out.with_suffix('.png'))
    _check_options(args)
    if args.pan_tilt:
        return run_pan_tilt(args)
    grid = Grid(args.grid[0], args.grid[1], 1.0)
    config = FoveaConfig(windows_cells=args.windows, scales=args.scales,
                         max_count=args.max_count, interpolation=args.interpolation,
                         scan_once=args.scan_once)
    detector_kwargs, detector = _detector(args)
    Fovea(detector, grid, config)        # refuses a bad configuration before any work
    items, (height, width), source, names = _items(args, grid)
    start = time.perf_counter()
    fixations = None if args.fixation_stride == 1 else \
        lattice_fixations(grid, args.fixation_stride)
    cells = None
    with executor_from_args(args) as executor:
        if args.cells != 'counts':
            cells = _cell_rule(args, lambda rule: tally_images(
                items[:args.edge_images], detector_kwargs, grid, config, fixations=fixations,
                executor=executor, names=None if names is None else names[:args.edge_images]))
            config = dataclasses.replace(config, max_count=cells.max_count)
        with progress_from_args(args, len(items), 'calibrate', 'image') as bar:
            tallies = tally_images(items, detector_kwargs, grid, config, progress=bar.update,
                                   fixations=fixations, executor=executor, cells=cells,
                                   names=names)
    wall = time.perf_counter() - start
    meta = {'image': {'width': int(width), 'height': int(height)}, 'fovea': config.to_dict(),
            'detector': detector_settings(detector),
            'calibration': {'source': {'scenes': args.scenes, 'task': args.task,
                                       'seed': args.seed, 'absent_rate': args.absent_rate}
                            if args.scenes is not None else source,
                            'images': tallies.images, 'fixations': tallies.fixations,
                            'prior': args.prior, 'pool_radius': args.pool_radius,
                            'min_tallies': args.min_tallies,
                            'fixation_stride': args.fixation_stride,
                            'detector_pixels': int(tallies.detector_pixels),
                            'wall_seconds': round(wall, 1)}}
    _record_cells(meta, cells, args)
    model = count_model(tallies, grid, args.prior, args.pool_radius, args.min_tallies, meta,
                        scan=config.scan_once)
    save_observation(args.out, model)
    print(rate_table(model))
    plot = args.plot if args.plot is not None else args.out.with_suffix('.png')
    plot_fpoc(model, plot, f'{args.out.stem}: {counted(tallies.images, "image")} of '
                           f'{width}x{height} px, '
                           f'{grid.rows}x{grid.cols} grid, windows {list(config.windows_cells)}')
    print(f'calibrated on {counted(tallies.images, "image")} '
          f'({counted(tallies.fixations, "fixation")}) in {wall:.1f} s')
    print(f'ipomdp-gaze calibrate: wrote {args.out} and {plot}', file=sys.stderr)
    return 0
