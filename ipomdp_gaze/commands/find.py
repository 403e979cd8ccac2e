# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze find``: find the face in image files with the digital fovea and a count model.

Every input is checked before any search: each image must exist, decode, have 8 bits per
channel and be large enough for the detector and the grid; the observation model and the policy
must load. A problem is one line naming the file, exit status 2. Then each image is searched
(:func:`ipomdp_gaze.vision.search.search_image`) and one line is printed per image, in input
order: the path as given, the cell and pixel found, its probability, the fixations, the detector
pixels and the seconds.

**Images** are read with OpenCV (``IMREAD_ANYDEPTH | IMREAD_ANYCOLOR``: EXIF orientation applied,
an alpha channel dropped, the bit depth kept so a 16-bit file is refused rather than silently
rescaled). Colour arrays arrive in OpenCV's BGR order and are converted to RGB; the fovea turns
them grey. ``seconds`` starts from the decoded array, so reading and decoding are not in it; nor
is the one-time set-up of the detector, the fovea and the policy (the policy is run once on the
uniform belief before the first image, so e.g. ELM's N x N weight matrix is built then).

**Model.** ``--observation`` names an ``ipomdp_gaze/observation-v1`` file (or a shipped model);
the fovea, the grid and the detector are rebuilt from what the file records (each window is
detected at most once per image: the detector is deterministic, so this saves work and changes
no count). Without it, each image uses the shipped face model (``faces-<size>``) calibrated at
the size nearest its own (``|log(w/w0)| + |log(h/h0)|``, ties to the first name); stderr says
which model and policy are used. An image of another size than its model's is searched, and its
line says so.

**Policy.** ``--policy NAME`` (a baseline or ``nmpt``, built on the model) or ``--policy-file``;
by default the shipped kernel trained on the model (a file in ``ipomdp_gaze/policies/kernels/``
whose ``observation.name`` is the model's name), else ELM on the model, acting by argmax.
``--seed S`` seeds a sampling policy: image i (0-based) draws from ``default_rng([S, i])``.
"""
from __future__ import annotations

import json
from pathlib import Path
import sys

import cv2
from ipomdp_gaze.belief import uniform_log_belief
from ipomdp_gaze.observation_file import load_observation, shipped_image_models
from ipomdp_gaze.policies.policy_file import default_policy_file
from ipomdp_gaze.policies.registry import build_policy, POLICY_NAMES
from ipomdp_gaze.vision.search import (calibrated_size, check_image_size, FIND_SETTINGS,
                                       fovea_for_model, search_image, size_distance)
import numpy as np

from .common import nonneg_int
from .search_args import add_search_args, settings_from_args

POLICY_CHOICES = tuple(name for name in POLICY_NAMES if name != 'learned')
READ_FLAGS = cv2.IMREAD_ANYDEPTH | cv2.IMREAD_ANYCOLOR


def add_parser(sub):
    p = sub.add_parser(
        'find', help='find the face in images with the digital fovea and a count model',
        description='Search each image with the digital fovea: scan the whole image once '
                    "(when the model has scan tables) and fixate the policy's choice on the "
                    'scanned belief (without a scan: the grid centre), update the belief with '
                    'the count model, stop when a cell reaches --confidence (found), when no '
                    'face reaches it (absent, with --absent-prior > 0), at --max-fixations or '
                    'once every cell was fixated (gave_up); print one line per image (path, '
                    'cell and pixel found, probability, fixations, detector pixels, seconds, '
                    'decision). Images are read with OpenCV (BGR converted to RGB, then grey); '
                    '8 bits per channel.')
    p.add_argument('images', nargs='+', metavar='IMAGE', help='image files (PNG, JPEG, ...)')
    p.add_argument('--observation', default=None, metavar='FILE',
                   help='count model (ipomdp_gaze/observation-v1 file or shipped name); default: '
                        "the shipped model calibrated nearest each image's size")
    policy = p.add_mutually_exclusive_group()
    policy.add_argument('--policy', default=None, choices=POLICY_CHOICES,
                        help='a baseline or nmpt, built on the model (default: the shipped '
                             'kernel trained on the model, else elm)')
    policy.add_argument('--policy-file', default=None, metavar='FILE',
                        help='a policy YAML file or a shipped kernel name')
    add_search_args(p, FIND_SETTINGS, ('confidence', 'max_fixations', 'absent_prior',
                                       'repeat_weight', 'start'))
    p.add_argument('--plot', type=Path, default=None, metavar='OUT.png',
                   help='draw the image, the numbered fixations and the windows of the last '
                        'one; with several images, OUT-<i>.png for image i (0-based)')
    p.add_argument('--json', type=Path, default=None, metavar='OUT.json',
                   help='write {grid, images: [{path, cell, pixel, probability, fixations, '
                        'detector_pixels, seconds, decision, absent_probability, stop}]} in '
                        'input order')
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


def format_line(path: str, result) -> str:
    """Format the one line printed per image."""
    r, c = result.cell
    x, y = result.pixel
    line = (f'{path}: cell ({r}, {c}) pixel ({x:.1f}, {y:.1f}) p={result.probability:.3f} '
            f'fixations={result.fixations} detector_pixels={result.detector_pixels} '
            f'seconds={result.seconds:.4f} decision={result.decision} stop={result.stop}')
    if not result.size_matches:
        w0, h0 = result.calibrated_px
        w, h = result.image_px
        line += f' (image {w}x{h} px, model calibrated at {w0}x{h0})'
    return line


def _note(message: str) -> None:
    print(f'ipomdp-gaze find: {message}', file=sys.stderr)


def prepare(args) -> list:
    """Check every input and build the tasks; return one ``_Task`` per image, in order."""
    if args.observation:
        models, shipped = [load_observation(args.observation)], False
    else:
        models = [load_observation(name) for name in shipped_image_models()]
        if not models:
            raise ValueError('no observation model is shipped with this install; pass '
                             '--observation FILE (an ipomdp_gaze/observation-v1 file, e.g. from '
                             'ipomdp-gaze calibrate)')
        shipped = True
    sizes = []
    for path in args.images:
        image = read_image(path)
        sizes.append((image.shape[1], image.shape[0]))
    tasks, per_image = {}, []
    for path, size in zip(args.images, sizes):
        model = nearest_model(models, size)
        if id(model) not in tasks:
            tasks[id(model)] = _Task(args, model, shipped, _note)
        task = tasks[id(model)]
        try:
            check_image_size(size, task.fovea)
        except ValueError as exc:
            raise ValueError(f'{path}: {exc}') from None
        per_image.append(task)
    grids = {task.model.grid.shape for task in per_image}
    if len(grids) > 1:
        raise ValueError(f'the images need shipped models with different grids '
                         f'({", ".join(f"{r}x{c}" for r, c in sorted(grids))}); pass '
                         f'--observation FILE')
    for task in {id(task): task for task in per_image}.values():
        _note(task.description)
    return per_image


def run(args) -> int:
    settings_from_args(args, FIND_SETTINGS)             # bad settings: refused before any work
    tasks = prepare(args)
    settings = [settings_from_args(args, FIND_SETTINGS, task.model.grid) for task in tasks]
    plots = plot_paths(args.plot, len(args.images)) if args.plot else []
    entries, logs = [], []
    for i, (path, task) in enumerate(zip(args.images, tasks)):
        image = read_image(path)
        result = search_image(image, task.fovea, task.model, task.policy, settings[i],
                              rng=np.random.default_rng([args.seed, i]))
        print(format_line(path, result), flush=True)
        entries.append({'path': path, 'cell': list(result.cell),
                        'pixel': [result.pixel[0], result.pixel[1]],
                        'probability': result.probability, 'fixations': result.fixations,
                        'detector_pixels': result.detector_pixels, 'seconds': result.seconds,
                        'decision': result.decision,
                        'absent_probability': result.absent_probability, 'stop': result.stop})
        logs.append(json.dumps({'path': path, 'events': list(result.log)}))
        if plots:
            title = (f'{Path(path).name}: cell {result.cell}, p={result.probability:.3f}, '
                     f'{result.fixations} fixations ({result.stop})')
            plot_image_search(image, result, task.fovea, plots[i], title)
            _note(f'wrote {plots[i]}')
    if args.log:
        args.log.parent.mkdir(parents=True, exist_ok=True)
        args.log.write_text('\n'.join(logs) + '\n')
        _note(f'wrote {args.log}')
    if args.json:
        rows, cols = tasks[0].model.grid.shape
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({'grid': {'rows': rows, 'cols': cols},
                                         'images': entries}, indent=1) + '\n')
        _note(f'wrote {args.json}')
    return 0
