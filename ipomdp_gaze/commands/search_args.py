# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The search settings as CLI flags: the same names and checks as the node's parameters.

Each flag is parsed only as a number (or a cell); :class:`ipomdp_gaze.session.SearchSettings`
checks every value, so a bad one gets the same one-line message from every command and from the
``gaze_controller`` node (``confidence must be between 0 and 1 (exclusive), got 1.5``).
"""
from __future__ import annotations

import argparse
from dataclasses import replace

from ipomdp_gaze.session import SearchSettings

FLAGS = ('confidence', 'max_fixations', 'inhibit_return', 'repeat_weight', 'absent_prior',
         'start')


def cell_arg(text: str) -> tuple[int, int] | int:
    """Parse a cell: ``ROW,COL`` (row first, 0-based), or a flat row-major index."""
    parts = text.split(',')
    try:
        values = tuple(int(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) not in (1, 2):
        raise argparse.ArgumentTypeError(f'expected a cell as ROW,COL (or a row-major index), '
                                         f'got {text!r}')
    return values if len(values) == 2 else values[0]


def cell_index(cell, grid, what: str = 'cell') -> int:
    """Return the row-major index of a parsed cell on ``grid`` (ValueError when outside)."""
    if isinstance(cell, tuple):
        row, col = cell
        if not (0 <= row < grid.rows and 0 <= col < grid.cols):
            raise ValueError(f'{what} ({row}, {col}) is outside the {grid.rows}x{grid.cols} grid')
        return grid.index(row, col)
    if not 0 <= cell < grid.n_cells:
        raise ValueError(f'{what} {cell} is outside the {grid.rows}x{grid.cols} grid '
                         f'({grid.n_cells} cells)')
    return int(cell)


def add_search_args(parser: argparse.ArgumentParser, defaults: SearchSettings,
                    flags=FLAGS) -> None:
    """Add the flags of the settings a command lets users change, with its defaults shown."""
    d = defaults
    if 'confidence' in flags:
        parser.add_argument('--confidence', type=float, default=d.confidence, metavar='P',
                            help=f'found (absent) when the most likely cell (no target) reaches '
                                 f'P, in (0, 1) (default {d.confidence})')
    if 'max_fixations' in flags:
        parser.add_argument('--max-fixations', type=int, default=d.max_fixations, metavar='N',
                            help=f'fixation budget: gave_up when it runs out undecided; 0 = no '
                                 f'budget (default {d.max_fixations})')
    if 'inhibit_return' in flags:
        parser.add_argument('--inhibit-return', action=argparse.BooleanOptionalAction,
                            default=d.inhibit_return,
                            help="never fixate a cell twice in a search (the policy's best "
                                 'unvisited cell)')
    if 'repeat_weight' in flags:
        parser.add_argument('--repeat-weight', type=float, default=d.repeat_weight,
                            metavar='W',
                            help=f"weight in [0, 1] of a cell's evidence beyond its most "
                                 f'informative view, for a still scene (default '
                                 f'{d.repeat_weight})')
    if 'absent_prior' in flags:
        parser.add_argument('--absent-prior', type=float, default=d.absent_prior, metavar='P',
                            help=f'prior that no target is there at all, in [0, 1); above 0 a '
                                 f'search can end with absent (default {d.absent_prior})')
    if 'start' in flags:
        parser.add_argument('--start', type=cell_arg, default=d.start_cell, metavar='ROW,COL',
                            help="first fixation (default: the policy's choice after a scan, "
                                 "else the grid's centre)")


def settings_from_args(args, defaults: SearchSettings, grid=None) -> SearchSettings:
    """Return the settings of ``args`` (flags left out keep ``defaults``), checked once."""
    changes = {key: getattr(args, key) for key in FLAGS[:-1] if hasattr(args, key)}
    start = getattr(args, 'start', defaults.start_cell)
    if isinstance(start, int):          # a flat index: a cell only once the grid is known
        start = defaults.start_cell if grid is None else \
            grid.cell(cell_index(start, grid, 'start cell'))
    changes['start_cell'] = start
    settings = replace(defaults, **changes)
    if grid is not None:
        settings.check_grid(grid)
    return settings
