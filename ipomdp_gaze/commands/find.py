# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze find``: find the face in image files with the digital fovea and a count model.

The observation model and the policy must load first (else one line, exit status 2). A folder
stands for its image files (by suffix, sorted by name). Each image must exist, decode, have 8
bits per channel and be large enough for the detector and the grid: a bad one is reported in one
line and the others are still searched; the exit status is then 2 at the end, else 0 (every
image got a decision). One line is printed per image, in input order: the path as given, the
**decision** (``found``, ``absent`` or ``gave_up``), ``cell (row, col)`` and ``pixel (x, y)``
(``none`` unless found), the probability, the fixations, the detector pixels against one
full-resolution scan's, the seconds, why it stopped and the method.

**Pixels.** The fovea (:func:`ipomdp_gaze.vision.search.search_image`) never spends more
detector pixels than one full-resolution scan of the image: it stops before a fixation that
would, and decides then (``decide_at_budget``; stop ``pixels``). When the fovea would cost more
or cannot see (a small image, an image at most half the model's calibrated size, a close-up
portrait: :func:`ipomdp_gaze.vision.search.full_frame_reason`) the whole frame is scanned once
instead and stderr says why. ``--all`` finds every face in one search over the many-target
belief (``--targets many``, its default: :func:`ipomdp_gaze.vision.search.search_many`;
docs/design.md section 11): one line per face with its box, then the image's line;
``--targets one`` keeps the old loop (:func:`ipomdp_gaze.vision.search.search_all`: find one
face, rule its cells out, search again).

**Images** are read with OpenCV (``IMREAD_ANYDEPTH | IMREAD_ANYCOLOR``: EXIF orientation applied,
an alpha channel dropped, the bit depth kept so a 16-bit file is refused rather than silently
rescaled). Colour arrays arrive in OpenCV's BGR order and are converted to RGB; the fovea gives
each window to the detector in the colour space it declares (RGB for YuNet, grey for Haar; a grey
image is repeated into three channels for an RGB detector). ``seconds`` starts from the decoded
array, so reading and decoding are not in it; nor is the one-time set-up of the detector, the
fovea and the policy (the policy is run once on the uniform belief before the first image, so
e.g. ELM's N x N weight matrix is built then).

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
import json
import math
from pathlib import Path
import sys

import cv2
from ipomdp_gaze.files.observation_file import load_observation, shipped_image_models
from ipomdp_gaze.model.belief import uniform_log_belief
from ipomdp_gaze.policies.policy_file import default_policy_file
from ipomdp_gaze.policies.registry import build_policy, POLICY_NAMES
from ipomdp_gaze.vision.search import (calibrated_size, check_image_size, FIND_SETTINGS,
                                       fovea_for_model, full_frame_reason, full_frame_search,
                                       search_all, search_image, search_many, size_distance)
import numpy as np

from .common import nonneg_int
from .search_args import add_search_args, settings_from_args, TASK_DEFAULT

POLICY_CHOICES = tuple(name for name in POLICY_NAMES if name != 'learned')
# The detectors with shipped find models; the first is the default, chosen on the training
# photos and training group pictures (docs/faces.md, "find on real photographs").
FIND_DETECTORS = ('yunet', 'haar')
READ_FLAGS = cv2.IMREAD_ANYDEPTH | cv2.IMREAD_ANYCOLOR


def add_parser(sub):
    p = sub.add_parser(
        'find', help='find the face in images with the digital fovea and a count model',
        description='Search each image with the digital fovea: scan the whole image once '
                    "(when the model has scan tables) and fixate the policy's choice on the "
                    'scanned belief (without a scan: the grid centre), update the belief with '
                    'the count model, stop when a cell reaches --confidence (found), when '
                    '"no face" reaches it (absent), at --max-fixations or once every cell was '
                    'fixated (gave_up), and before spending more detector pixels than one '
                    'full-resolution scan (deciding then); small images are scanned whole '
                    'instead. Print one line per image (path, decision, cell (row, col) and '
                    'pixel (x, y) found, probability, fixations, detector pixels, seconds). '
                    'Images are read with OpenCV (BGR converted to RGB; grey for a grey '
                    'detector such as Haar); 8 bits per channel.')
    p.add_argument('images', nargs='+', metavar='IMAGE',
                   help='image files (PNG, JPEG, ...) or folders (their image files, by name)')
    source = p.add_mutually_exclusive_group()
    source.add_argument('--observation', default=None, metavar='FILE',
                        help='count model (ipomdp_gaze/observation-v1 file or shipped name); '
                             "default: the shipped model calibrated nearest each image's size "
                             'for --detector')
    source.add_argument('--detector', default=None, choices=FIND_DETECTORS,
                        help='the detector whose shipped models (one per calibrated size) are '
                             f'used (default {FIND_DETECTORS[0]}, chosen on training photos: '
                             'docs/faces.md)')
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
                        'occupancy per cell, infomax per detector pixel, within one full scan '
                        'of detector pixels); each face is printed with its box and '
                        'probability, counted once per cluster of occupied cells (split where '
                        "the detector's boxes are distinct faces)")
    add_search_args(p, None, ('targets',), task_default='many with --all, else one; --all '
                    '--targets one: find a face, rule the cells within 2 of it out, search '
                    'again')
    p.add_argument('--plot', type=Path, default=None, metavar='OUT.png',
                   help='draw the image, the numbered fixations and the windows of the last '
                        'one, in the format the extension names (.png, .pdf, .svg, .jpg, ...; '
                        'others refused); with several images, OUT-<i>.ext for image i '
                        '(0-based)')
    p.add_argument('--json', type=Path, default=None, metavar='OUT.json',
                   help='write {grid, axes, images: [{path, cell [row, col], pixel [x, y] '
                        '(null unless found), probability, fixations, detector_pixels, '
                        'full_scan_pixels, seconds, decision, absent_probability, stop, method, '
                        'note, grid, and with --targets many faces: [{box [x, y, w, h], cell '
                        '[row, col], probability}]}]} in input order (--all --targets one: one '
                        'entry per face, with "face", then the last decision)')
    p.add_argument('--log', type=Path, default=None, metavar='OUT.jsonl',
                   help="write each image's search session event log (reset with the "
                        'settings, scan, start, one event per fixation with the frame and '
                        'belief summaries and the decision) as one JSON line per image')
    p.add_argument('--seed', type=nonneg_int, default=0, metavar='S',
                   help='seed of a sampling policy (image i uses default_rng([S, i]))')
    p.set_defaults(run=run)


def read_image(path: str) -> np.ndarray:
    """
    Read an image file as ``uint8`` grey ``(H, W)`` or RGB ``(H, W, 3)``.

    Raises
    ------
    ValueError
        Naming the file: missing, unreadable, not decodable, or not 8 bits per channel.

    """
    file = Path(path)
    if not file.exists():
        raise ValueError(f'{path}: no such file')
    if not file.is_file():
        raise ValueError(f'{path}: not a file')
    try:
        data = np.fromfile(file, dtype=np.uint8)
    except OSError as exc:
        raise ValueError(f'{path}: cannot read: {exc.strerror or exc}') from None
    image = cv2.imdecode(data, READ_FLAGS) if data.size else None
    if image is None:
        raise ValueError(f'{path}: not an image OpenCV can decode')
    if image.dtype != np.uint8:
        bits = 8 * image.dtype.itemsize
        raise ValueError(f'{path}: {bits}-bit {image.dtype} image; find needs 8 bits per '
                         f'channel (convert it, e.g. to 8-bit PNG)')
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
    return image


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
            raise ValueError(f'{name}: {exc}') from None
        self.model = model
        self.policy, policy = build_find_policy(args, model, warn)
        self.policy.select(np.exp(uniform_log_belief(model.grid.n_cells, 1)), 1,
                           np.random.default_rng(0))
        size = calibrated_size(model)
        where = 'shipped ' if shipped else ''
        at = f', calibrated at {size[0]}x{size[1]} px' if size else ''
        self.description = (f'{where}observation model {name} ({model.grid.rows}x'
                            f'{model.grid.cols} grid{at}), {policy}')


def plot_image_search(image: np.ndarray, result, fovea, out_path: Path, title: str) -> None:
    """Draw the image, the final belief, the numbered scan path, the windows, the cell found."""
    from ipomdp_gaze.vision.search_plots import annotate_image_search, save_figure
    save_figure(annotate_image_search(image, result, fovea), out_path, title)


def plot_paths(out: Path, count: int) -> list[Path]:
    """``out`` for one image, else ``OUT-<i>.png`` (0-based) for each of ``count`` images."""
    if count == 1:
        return [out]
    return [out.with_name(f'{out.stem}-{i}{out.suffix or ".png"}') for i in range(count)]


IMAGE_SUFFIXES = ('.png', '.jpg', '.jpeg', '.bmp', '.tif', '.tiff', '.webp', '.pgm', '.ppm',
                  '.pbm', '.jp2')


def expand_inputs(paths: list[str]) -> list[str]:
    """Each path as given; a folder becomes its image files (by suffix), sorted by name."""
    out = []
    for path in paths:
        folder = Path(path)
        if folder.is_dir():
            out.extend(str(f) for f in sorted(folder.iterdir())
                       if f.is_file() and f.suffix.lower() in IMAGE_SUFFIXES)
        else:
            out.append(path)
    return out


def plot_format(path: Path) -> Path:
    """Check that matplotlib writes the format ``path``'s extension names (ValueError if not)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    formats = FigureCanvasAgg(Figure()).get_supported_filetypes()
    suffix = path.suffix.lower().lstrip('.')
    if suffix not in formats:
        raise ValueError(f'--plot {path}: the extension names no format matplotlib writes '
                         f'(use one of {", ".join("." + k for k in sorted(formats))})')
    return path


def _cell_text(result) -> str:
    if result.decision != 'found':
        return 'cell (row, col)=none pixel (x, y)=none'
    r, c = result.cell
    x, y = result.pixel
    return f'cell (row, col)=({r}, {c}) pixel (x, y)=({x:.1f}, {y:.1f})'


def format_line(path: str, result, face: int | None = None) -> str:
    """Format the one line printed per image (per face with ``--all``)."""
    width, height = result.image_px
    probability = 'n/a' if math.isnan(result.probability) else f'{result.probability:.3f}'
    which = '' if face is None else f' face={face}'
    line = (f'{path}:{which} decision={result.decision} {_cell_text(result)} '
            f'p={probability} fixations={result.fixations} '
            f'detector_pixels={result.detector_pixels} (full scan {width * height}) '
            f'seconds={result.seconds:.4f} stop={result.stop} method={result.method}')
    if not result.size_matches:
        w0, h0 = result.calibrated_px
        line += f' (image {width}x{height} px, model calibrated at {w0}x{h0})'
    return line


def face_line(path: str, result, face: int) -> str:
    """Format the line of one face of a many-target search."""
    found = result.faces[face]
    x, y, w, h = found.box
    probability = 'n/a' if math.isnan(found.probability) else f'{found.probability:.3f}'
    return (f'{path}: face={face} box (x, y, w, h)=({x:.0f}, {y:.0f}, {w:.0f}, {h:.0f}) '
            f'cell (row, col)=({found.cell[0]}, {found.cell[1]}) p={probability}')


def entry(path: str, result, grid) -> dict:
    """Return one result's JSON entry: ``cell`` [row, col], ``pixel`` [x, y], null unless found."""
    found = result.decision == 'found'

    def number(value):
        return None if math.isnan(value) else float(value)
    return {'path': path, 'cell': list(result.cell) if found else None,
            'pixel': [result.pixel[0], result.pixel[1]] if found else None,
            'probability': number(result.probability), 'fixations': result.fixations,
            'detector_pixels': result.detector_pixels,
            'full_scan_pixels': result.image_px[0] * result.image_px[1],
            'seconds': result.seconds, 'decision': result.decision,
            'absent_probability': number(result.absent_probability), 'stop': result.stop,
            'method': result.method, 'note': result.note,
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
        if args.observation:
            self.models, self.shipped = [load_observation(args.observation)], False
        else:
            detector = getattr(args, 'detector', None) or FIND_DETECTORS[0]
            self.models = [load_observation(name) for name in default_models(detector)]
            if not self.models:
                raise ValueError(f'no observation model of the {detector} detector is shipped '
                                 f'with this install; pass --observation FILE (an '
                                 f'ipomdp_gaze/observation-v1 file, e.g. from ipomdp-gaze '
                                 f'calibrate)')
            self.shipped = True
        self.tasks = {}
        if args.observation:                    # a bad model or policy: refused before any image
            self.task((0, 0))

    def task(self, size) -> _Task:
        model = nearest_model(self.models, size) if size != (0, 0) else self.models[0]
        if id(model) not in self.tasks:
            self.tasks[id(model)] = _Task(self.args, model, self.shipped, _note)
            _note(self.tasks[id(model)].description)
        return self.tasks[id(model)]


def search_one(image, task, settings, rng, find_all: bool) -> list:
    """Search one image: the fovea within one full scan's pixels, or the full frame (say why)."""
    width, height = image.shape[1], image.shape[0]
    reason = full_frame_reason(task.fovea, (width, height), calibrated_size(task.model))
    if reason:
        results = full_frame_search(image, task.fovea, reason, calibrated_size(task.model))
        if settings.targets == 'many':
            return [results[0]]
        return results if find_all else results[:1]
    budget = width * height
    if settings.targets == 'many':
        return [search_many(image, task.fovea, task.model, settings, pixel_budget=budget)]
    if find_all:
        return search_all(image, task.fovea, task.model, task.policy, settings, rng=rng,
                          pixel_budget=budget)
    return [search_image(image, task.fovea, task.model, task.policy, settings, rng=rng,
                         pixel_budget=budget)]


def run(args) -> int:
    settings_from_args(args, FIND_SETTINGS)             # bad settings: refused before any work
    if args.plot:
        plot_format(args.plot)
    images = expand_inputs(args.images)
    if not images:
        raise ValueError(f'no image files in {", ".join(args.images)}')
    tasks = _Tasks(args)
    plots = plot_paths(args.plot, len(images)) if args.plot else []
    entries, logs, failed, grid = [], [], 0, None
    for i, path in enumerate(images):
        try:
            image = read_image(path)
            task = tasks.task((image.shape[1], image.shape[0]))
            check_image_size((image.shape[1], image.shape[0]), task.fovea)
            settings = settings_from_args(args, FIND_SETTINGS, task.model.grid)
            if args.all and args.targets is TASK_DEFAULT:
                settings = replace(settings, targets='many')
        except ValueError as exc:
            message = str(exc)
            _error(message if message.startswith(path) else f'{path}: {message}')
            failed += 1
            continue
        grid = task.model.grid
        results = search_one(image, task, settings, np.random.default_rng([args.seed, i]),
                             args.all)
        if results[0].method == 'full_frame':
            _note(f'{path}: scanned the whole frame once: {results[0].note}')
        many = settings.targets == 'many'
        for k, result in enumerate(results):
            for face in range(len(result.faces) if many else 0):
                print(face_line(path, result, face), flush=True)
            print(format_line(path, result, k if args.all and not many else None), flush=True)
            extra = ({'faces': [face.to_dict() for face in result.faces]} if many else
                     {'face': k} if args.all else {})
            entries.append({**entry(path, result, grid), **extra})
        logs.append(json.dumps({'path': path, 'events': [e for r in results for e in r.log]}))
        if plots and results[0].method == 'fovea':
            result = results[0]
            title = (f'{Path(path).name}: {result.decision}, cell (row, col) {result.cell}, '
                     f'p={result.probability:.3f}, {result.fixations} fixations ({result.stop})')
            if many:
                title = (f'{Path(path).name}: {len(result.faces)} faces, {result.fixations} '
                         f'fixations ({result.stop})')
            plot_image_search(image, result, task.fovea, plots[i], title)
            _note(f'wrote {plots[i]}')
        elif plots and many:
            from ipomdp_gaze.vision.search_plots import draw_faces, enlarged, save_figure
            big, factor = enlarged(image if image.ndim == 3 else np.dstack([image] * 3))
            save_figure(draw_faces(big, results[0].faces, factor), plots[i],
                        f'{Path(path).name}: {len(results[0].faces)} faces (full frame)')
            _note(f'wrote {plots[i]}')
        elif plots:
            _note(f'{path}: no plot (the full frame was scanned, no fixations to draw)')
    if args.log:
        args.log.parent.mkdir(parents=True, exist_ok=True)
        args.log.write_text('\n'.join(logs) + '\n')
        _note(f'wrote {args.log}')
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        rows, cols = grid.shape if grid is not None else (None, None)
        args.json.write_text(json.dumps({'grid': {'rows': rows, 'cols': cols},
                                         'axes': {'cell': ['row', 'col'], 'pixel': ['x', 'y']},
                                         'images': entries}, indent=1) + '\n')
        _note(f'wrote {args.json}')
    if failed:
        _error(f'{failed} of {len(images)} inputs could not be searched')
        return 2
    return 0
