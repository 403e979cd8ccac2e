# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Argument helpers shared by the subcommands: grid, FPOC, policy selection and outputs."""
from __future__ import annotations

import argparse
import math
import os
from pathlib import Path
import re

from ipomdp_gaze.files.writable import folder_writable
from ipomdp_gaze.model.belief import prior_from_weights
from ipomdp_gaze.model.fpoc import make_fpoc, MODELS, parameter_names
from ipomdp_gaze.model.grid import Grid, parse_grid
from ipomdp_gaze.model.observation import MATRIX_MAX_CELLS
from ipomdp_gaze.model.wording import counted
import numpy as np
import yaml


def grid_arg(text: str) -> tuple[int, int]:
    """Parse ``ROWSxCOLS`` for argparse."""
    try:
        return parse_grid(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def size_arg(text: str) -> tuple[int, int]:
    """Parse an image size ``WIDTHxHEIGHT`` in pixels for argparse (two positive integers)."""
    match = re.fullmatch(r'\s*(\d+)\s*[xX]\s*(\d+)\s*', str(text))
    if not match or min(int(match.group(1)), int(match.group(2))) < 1:
        raise argparse.ArgumentTypeError(f'a size must look like WIDTHxHEIGHT in pixels, e.g. '
                                         f'640x480, got {text!r}')
    return int(match.group(1)), int(match.group(2))


def cell_arg(text: str):
    """
    Parse a cell for argparse: ``ROW,COL`` (every command), or a flat row-major index.

    Returns ``(row, col)`` or the flat index as an int; :func:`cell_index` checks it against
    the grid once the grid is known.
    """
    parts = str(text).split(',')
    try:
        values = [int(x) for x in parts]
    except ValueError:
        values = []
    if len(values) not in (1, 2) or min(values) < 0:
        raise argparse.ArgumentTypeError(f'expected a cell as ROW,COL (or a flat index), got '
                                         f'{text!r}')
    return values[0] if len(values) == 1 else tuple(values)


def cell_index(value, grid, flag: str) -> int:
    """
    Return the row-major index of a :func:`cell_arg` value on ``grid``.

    Raises
    ------
    ValueError
        If the cell is outside the grid; the message names ``flag`` and the grid.

    """
    if isinstance(value, tuple):
        row, col = value
        if not (0 <= row < grid.rows and 0 <= col < grid.cols):
            raise ValueError(f'{flag} {row},{col} is outside the {grid.rows}x{grid.cols} grid '
                             f'(rows 0..{grid.rows - 1}, columns 0..{grid.cols - 1})')
        return row * grid.cols + col
    if not 0 <= value < grid.n_cells:
        raise ValueError(f'{flag} {value} is outside the {grid.n_cells}-cell grid (give '
                         f'ROW,COL, or a flat index 0..{grid.n_cells - 1})')
    return int(value)


# The largest ROS integer parameter (int64): seeds go to the nodes as parameters.
INT64_MAX = 2 ** 63 - 1


def _int_at_least(text: str, low: int, what: str, high: int | None = None) -> int:
    """Parse an integer from ``low`` to ``high`` for argparse; ``what`` names it in the error."""
    try:
        value = int(text)
    except ValueError:
        value = low - 1
    if value < low or (high is not None and value > high):
        raise argparse.ArgumentTypeError(f'expected {what}, got {text!r}')
    return value


def positive_int(text: str) -> int:
    """Parse an integer from 1 to 2^63 - 1 for argparse (beyond, numpy takes it as an object)."""
    value = _int_at_least(text, 1, 'a positive integer')
    if value > INT64_MAX:
        raise argparse.ArgumentTypeError(f'expected a positive integer up to 2^63 - 1, got '
                                         f'{text!r}')
    return value


# The most worker processes --jobs starts on this machine (a semaphore counts them in a C int).
MAX_JOBS = 4096


def jobs_arg(text: str) -> int:
    """Parse ``--jobs``: 1 to :data:`MAX_JOBS` worker processes."""
    return _int_at_least(text, 1, f'a number of worker processes from 1 to {MAX_JOBS}', MAX_JOBS)


def count_in(low: int, high: int, what: str):
    """Return an argparse type: a whole number from ``low`` to ``high``; ``what`` words it."""
    def parse(text: str) -> int:
        return _int_at_least(text, low, what, high)
    return parse


# The most scenes a command searches or tallies (calibrate --scenes, evaluate --scenes'
# --episodes and --empty-scenes): at a second or so of detector time each, more than a day on
# one core, 500 times the 200 the shipped models were calibrated on. A count beyond ran for
# ever, a piece of work queued per scene, instead of being refused.
MAX_SCENES = 100_000
# The most epochs train runs (the shipped kernels took at most 7700): a day or so of a 7x7
# grid's training; 2^63 - 1 ran for ever.
MAX_EPOCHS = 1_000_000
# The most simulated episodes a command runs at once (evaluate --episodes, train --eval-episodes
# and --final-episodes): 10 times the paper's 20000, docs/reproduction.md's largest run; about
# 3 GB and 40 s a policy on the 7x7 grid. 2^63 - 1 ran out of memory or for ever.
MAX_EPISODES = 200_000
# The most episodes train pools per update (--episodes-per-epoch): 133 times the paper's 150,
# 1.3 GB and 7 s an epoch on the 7x7 grid (every epoch holds its episodes' eligibility traces).
MAX_EPOCH_EPISODES = 20_000
# The largest C int, OpenCV's: detectMultiScale's minNeighbors (a larger one was OpenCV's
# "integer won't fit into a C int").
C_INT_MAX = 2 ** 31 - 1

scene_count = count_in(1, MAX_SCENES, f'a number of scenes from 1 to {MAX_SCENES}')


# A 95% percentile interval from fewer bootstrap resamples has no 2.5% tail to speak of (one
# resample gives the estimate twice).
MIN_BOOTSTRAP = 10


def bootstrap_count(text: str) -> int:
    """Parse ``--bootstrap``: resamples for a 95% interval, at least :data:`MIN_BOOTSTRAP`."""
    return _int_at_least(text, MIN_BOOTSTRAP, f'at least {MIN_BOOTSTRAP} resamples (a 95% '
                         'interval from fewer is degenerate)')


def nonneg_int(text: str) -> int:
    """Parse an integer from 0 to 2^63 - 1 (seeds: a ROS integer parameter is int64)."""
    return _int_at_least(text, 0, 'an integer from 0 to 2^63 - 1', INT64_MAX)


def _path(text: str, what: str) -> Path:
    """Parse a path for argparse: an empty one would be the current folder (``Path('')``)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f'an empty {what} ({text!r}: an unset shell '
                                         'variable?)')
    return Path(text)


def bag_path(text: str) -> Path:
    """Parse a bag's directory for argparse (not empty)."""
    return _path(text, 'bag path')


def file_arg(text: str) -> Path:
    """Parse an input file's path for argparse (not empty)."""
    return _path(text, 'file path')


def number_in(low: float, high: float, what: str, low_open: bool = False,
              high_open: bool = False):
    """
    Return an argparse type: a finite number from ``low`` to ``high``, each end in or not.

    ``what`` words the range for the one refusal, ``expected {what}, got 'text'``, of text
    that is no number, of NaN and infinity, and of a number outside the range.
    """
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        above = value > low if low_open else value >= low
        below = value < high if high_open else value <= high
        if not (math.isfinite(value) and above and below):        # NaN too
            raise argparse.ArgumentTypeError(f'expected {what}, got {text!r}')
        return value
    return parse


# A finite number > 0 (a spacing, a scale, a step size).
positive_float = number_in(0.0, math.inf, 'a positive number', low_open=True)
# A finite number >= 0 (a motion sigma).
nonneg_float = number_in(0.0, math.inf, 'a number >= 0')
# A probability in [0, 1) (a jump probability, a prior, a rate).
probability_arg = number_in(0.0, 1.0, 'a probability in [0, 1)', high_open=True)


def number_arg(text: str) -> float:
    """
    Parse a number for argparse (its range is the setting's check, which names the flag).

    argparse's own refusal of ``type=float`` names the Python type (``invalid float value``).
    """
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number, got {text!r}') from None


def integer_arg(text: str) -> int:
    """Parse a whole number for argparse (``2.5`` too is refused, not cut to 2)."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected an integer, got {text!r}') from None


def fpoc_param(text: str) -> tuple[str, object]:
    """Parse ``name=value`` for argparse; the value is read as YAML (numbers, lists, words)."""
    name, sep, value = text.partition('=')
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f'expected name=value, got {text!r}')
    try:
        parsed = yaml.safe_load(value)
    except yaml.YAMLError:
        raise argparse.ArgumentTypeError(f'cannot parse the value of {text!r}') from None
    return name.strip(), parsed


def add_task_args(parser: argparse.ArgumentParser, grid: str = '7x7', spacing: float = 0.42,
                  fpoc: str = 'human') -> None:
    """
    ``--grid``, ``--spacing-deg``, ``--fpoc``, repeated ``--fpoc-param`` and ``--observation``.

    The task is the Gaussian model of an FPOC on a grid, or a count model read from an
    observation file (which brings its own grid). Defaults are applied by
    :func:`task_from_args`, so options given next to ``--observation`` can be refused.
    """
    parser.add_argument('--grid', type=grid_arg, default=None,
                        help=f'visual array ROWSxCOLS (default {grid})')
    parser.add_argument('--spacing-deg', type=positive_float, default=None,
                        help=f'degrees between neighbouring cells (default {spacing})')
    parser.add_argument('--fpoc', choices=tuple(MODELS), default=None,
                        help=f'FPOC model (default {fpoc})')
    parser.add_argument('--fpoc-param', type=fpoc_param, action='append', default=[],
                        metavar='NAME=VALUE',
                        help='FPOC parameter by its docs/design.md name, e.g. foveal_dprime=2.5 '
                             '(repeatable)')
    parser.add_argument('--observation', default=None, metavar='FILE',
                        help='a count model (ipomdp_gaze/observation-v1 file or shipped name) '
                             'instead of an FPOC; it brings its grid')
    parser.set_defaults(task_defaults=(parse_grid(grid), spacing, fpoc))


def task_from_args(args) -> tuple[Grid, object]:
    """
    Build ``(grid, model)`` from :func:`add_task_args` arguments; errors name the problem.

    ``model`` is an FPOC (the Gaussian model) or the count model of ``--observation``.
    """
    if getattr(args, 'observation', None):
        from ipomdp_gaze.files.observation_file import load_observation
        options = (('grid', args.grid), ('fpoc', args.fpoc), ('fpoc-param', args.fpoc_param),
                   ('spacing-deg', args.spacing_deg))
        given = [f'--{name}' for name, value in options if value]
        if given:
            raise ValueError(f'{given[0]} cannot be combined with --observation (the '
                             f'observation file sets the task)')
        model = load_observation(args.observation)
        return model.grid, model
    default_grid, default_spacing, default_fpoc = args.task_defaults
    args.grid = default_grid if args.grid is None else args.grid
    args.spacing_deg = default_spacing if args.spacing_deg is None else args.spacing_deg
    args.fpoc = default_fpoc if args.fpoc is None else args.fpoc
    grid = Grid(args.grid[0], args.grid[1], args.spacing_deg)
    if grid.n_cells > MATRIX_MAX_CELLS:
        # Checked before any FPOC is evaluated on the grid: a clean error, no numpy warning.
        raise ValueError(f'a {grid.rows}x{grid.cols} grid has {grid.n_cells} cells; the '
                         f'offline commands hold N x N matrices and take at most '
                         f'{MATRIX_MAX_CELLS} cells (e.g. 64x64)')
    params = dict(args.fpoc_param)
    names = parameter_names(args.fpoc)
    for name in params:
        if name not in names:
            raise ValueError(f'unknown FPOC parameter {name!r} for {args.fpoc!r}; valid: '
                             f"{', '.join(names)}")
    return grid, make_fpoc(args.fpoc, **params)


def output_file(text: str) -> Path:
    """
    Parse the path of a file to write for argparse; refuse one that ends in ``/``.

    ``--json results/`` names a folder, but a ``Path`` drops the slash: a file ``results``
    was written where the user meant a folder.
    """
    if text.endswith(('/', os.sep)) and text.strip('/' + os.sep):
        raise argparse.ArgumentTypeError(f'{text!r} ends in / and names a folder: give the '
                                         f'name of a file to write in it')
    return Path(text)


def check_output_file(flag: str, path: Path, plot: bool = False) -> Path:
    """
    Refuse, before any work, an output file that cannot be written: one line naming ``flag``.

    The path must not be a folder, and must sit in a folder that exists or can be made (no
    file on the way) and takes a new file; an existing file must be writable. ``plot``: the
    extension must name a format matplotlib writes (:func:`plot_format`).
    """
    path = Path(path)
    if path.is_dir():
        raise ValueError(f'{flag} {path}: is a directory')
    if plot:
        plot_format(path, flag)
    if path.exists():
        # written in place (/dev/null in a folder nobody writes to, a file of one's own)
        if not os.access(path, os.W_OK):
            raise ValueError(f'{flag} {path}: not writable')
        return path
    check_output_folder(flag, path.parent, path)
    return path


def parse_with_outputs(parser, argv, **outputs: str):
    """
    Parse ``argv``; refuse each output file given that cannot be written, as a usage error.

    ``outputs`` maps an attribute of the parsed arguments to its flag (``json='--json'``): a
    file that :func:`check_output_file` refuses ends the program with ``parser.error``'s one
    line and status 2, before any work.
    """
    args = parser.parse_args(argv)
    try:
        for name, flag in outputs.items():
            if getattr(args, name):
                check_output_file(flag, getattr(args, name))
    except ValueError as exc:
        parser.error(str(exc))
    return args


def check_output_folder(flag: str, folder: Path, named: Path | None = None) -> Path:
    """
    Refuse, before any work, a folder to write in that cannot be: one line naming ``flag``.

    Its first existing ancestor (the rest is made when written) must be a folder that takes a
    new file. ``named``: the path the message names (default ``folder``).
    """
    named = Path(folder) if named is None else named
    existing = Path(folder)
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise ValueError(f'{flag} {named}: {existing} is not a folder')
    if not folder_writable(existing):
        raise ValueError(f'{flag} {named}: not writable')
    return Path(folder)


def plot_format(path: Path, flag: str = '--plot') -> Path:
    """Check that matplotlib writes the format ``path``'s extension names (ValueError if not)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    formats = FigureCanvasAgg(Figure()).get_supported_filetypes()
    suffix = path.suffix.lower().lstrip('.')
    if suffix not in formats:
        raise ValueError(f'{flag} {path}: the extension names no format matplotlib writes '
                         f'(use one of {", ".join("." + k for k in sorted(formats))})')
    return path


def add_prior_arg(parser: argparse.ArgumentParser, use: str) -> None:
    """Add ``--prior FILE``, where the target is a priori (:func:`read_prior`); ``use``: how."""
    parser.add_argument('--prior', type=file_arg, default=None, metavar='FILE',
                        help='where the target is a priori: a text file of ROWS lines of COLS '
                             'non-negative weights (spaces or commas; # comments), scaled to '
                             f'sum 1; {use} (default uniform)')


def read_prior(path: Path, grid) -> np.ndarray:
    """
    Read a prior over the target's cell: ``grid.rows`` lines of ``grid.cols`` weights >= 0.

    Spaces or commas between numbers, ``#`` comments; scaled to sum 1. UTF-8, with or without
    the byte-order mark a spreadsheet or Notepad writes first. ValueError (one line) for a file
    that cannot be read, the wrong shape, or weights that are not numbers >= 0 with a positive
    sum.
    """
    try:
        text = Path(path).read_text(encoding='utf-8-sig')
    except UnicodeDecodeError:
        raise ValueError(f'--prior {path}: cannot read it (not UTF-8 text)') from None
    except OSError as exc:
        raise ValueError(f'--prior {path}: cannot read it '
                         f'({"a folder, not a file" if Path(path).is_dir() else exc.strerror})'
                         ) from None
    rows = []
    for line in text.splitlines():
        line = line.split('#', 1)[0].replace(',', ' ').split()
        if line:
            try:
                rows.append([float(v) for v in line])
            except ValueError:
                raise ValueError(f'--prior {path}: not a number in {" ".join(line)!r}') from None
    if len(rows) != grid.rows or any(len(r) != grid.cols for r in rows):
        widths = '/'.join(sorted({str(len(r)) for r in rows}) or '0')
        shape = f'{counted(len(rows), "line")} of {widths}'
        raise ValueError(f'--prior {path}: a {grid.rows}x{grid.cols} grid needs {grid.rows} '
                         f'lines of {grid.cols} weights, got {shape}')
    try:
        return prior_from_weights(rows, grid.shape)
    except ValueError as exc:
        raise ValueError(f'--prior {path}: {exc}') from None
