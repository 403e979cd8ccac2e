# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Argument helpers shared by the subcommands: grid, FPOC and policy selection."""
from __future__ import annotations

import argparse
import math

from ipomdp_gaze.fpoc import make_fpoc, MODELS, parameter_names
from ipomdp_gaze.grid import Grid, parse_grid
import yaml


def grid_arg(text: str) -> tuple[int, int]:
    """Parse ``ROWSxCOLS`` for argparse."""
    try:
        return parse_grid(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _int_at_least(text: str, low: int, what: str) -> int:
    """Parse an integer >= ``low`` for argparse; ``what`` names it in the error."""
    try:
        value = int(text)
    except ValueError:
        value = low - 1
    if value < low:
        raise argparse.ArgumentTypeError(f'expected {what}, got {text!r}')
    return value


def positive_int(text: str) -> int:
    """Parse an integer >= 1 for argparse."""
    return _int_at_least(text, 1, 'a positive integer')


def nonneg_int(text: str) -> int:
    """Parse an integer >= 0 (seeds) for argparse."""
    return _int_at_least(text, 0, 'an integer >= 0')


def positive_float(text: str) -> float:
    """Parse a finite number > 0 for argparse."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a positive number, got {text!r}') from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f'expected a positive number, got {text!r}')
    return value


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
    """``--grid``, ``--spacing-deg``, ``--fpoc`` and repeated ``--fpoc-param name=value``."""
    parser.add_argument('--grid', type=grid_arg, default=parse_grid(grid),
                        help=f'visual array ROWSxCOLS (default {grid})')
    parser.add_argument('--spacing-deg', type=positive_float, default=spacing,
                        help=f'degrees between neighbouring cells (default {spacing})')
    parser.add_argument('--fpoc', choices=tuple(MODELS), default=fpoc,
                        help=f'FPOC model (default {fpoc})')
    parser.add_argument('--fpoc-param', type=fpoc_param, action='append', default=[],
                        metavar='NAME=VALUE',
                        help='FPOC parameter by its docs/design.md name, e.g. foveal_dprime=2.5 '
                             '(repeatable)')


def task_from_args(args) -> tuple[Grid, object]:
    """Build ``(grid, fpoc)`` from :func:`add_task_args` arguments; errors name the problem."""
    grid = Grid(args.grid[0], args.grid[1], args.spacing_deg)
    params = dict(args.fpoc_param)
    names = parameter_names(args.fpoc)
    for name in params:
        if name not in names:
            raise ValueError(f'unknown FPOC parameter {name!r} for {args.fpoc!r}; valid: '
                             f"{', '.join(names)}")
    return grid, make_fpoc(args.fpoc, **params)
