# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The search settings as CLI flags, generated from the schema (:mod:`ipomdp_gaze.search.settings`).

A command names the settings it lets users change; each flag's name, type, placeholder and help
come from the schema, as the node's parameters do. Each flag is parsed only as a number, a
true/false switch or a cell (``ROW,COL``, the one cell rule of :func:`.common.cell_arg`);
:class:`ipomdp_gaze.search.session.SearchSettings` checks every value, so a bad one gets the same
one-line message from every command and from the ``gaze_controller`` node
(``confidence must be between 0 and 1 (exclusive), got 1.5``).
"""
from __future__ import annotations

import argparse
from dataclasses import replace

from ipomdp_gaze.search.session import SearchSettings
from ipomdp_gaze.search.settings import by_key, SCHEMA

from .common import cell_arg, cell_index, integer_arg, number_arg, probability_arg

# A flag left at this default keeps the command's (or its task's) own setting.
TASK_DEFAULT = None


def _shown(value) -> str:
    if isinstance(value, tuple) and value and isinstance(value[0], float):
        return ' '.join(f'{v:g}' for v in value)
    return 'none' if value is None else str(value)


def add_search_args(parser: argparse.ArgumentParser, defaults: SearchSettings | None,
                    keys, schema=SCHEMA, task_default: str = "the task's") -> None:
    """
    Add the flags of the settings ``keys`` (field names) with the schema's help.

    ``defaults`` are the command's settings, shown in the help; None leaves every flag at
    :data:`TASK_DEFAULT` (the task's own value, named ``task_default`` in the help).
    """
    settings = by_key(schema)
    for key in keys:
        s = settings[key]
        default = TASK_DEFAULT if defaults is None else getattr(defaults, key)
        shown = task_default if defaults is None else _shown(default)
        help_ = f'{s.help_text} (parameter {s.parameter}; default {shown})'.replace('%', '%%')
        kwargs = {'dest': key, 'default': default, 'help': help_}
        if s.kind == 'bool':
            kwargs['action'] = argparse.BooleanOptionalAction
        else:
            kwargs['metavar'] = s.metavar or key.upper()
            kwargs['type'] = {'float': number_arg, 'int': integer_arg, 'floats': number_arg,
                              'cell': cell_arg, 'str': str}[s.kind]
            if s.kind == 'floats':
                kwargs['nargs'] = '+'
        parser.add_argument(s.flag, **kwargs)


def add_scene_args(parser: argparse.ArgumentParser, scenes: str) -> None:
    """
    Add the target's random walk per fixation, the absent hypothesis and ``--absent-rate``.

    docs/design.md section 7; ``scenes`` names the scenes whose empty fraction
    ``--absent-rate`` sets (``simulated``, ``training``). Each is None when not given, which
    means 0: a still target that is always there.
    """
    add_search_args(parser, None, ('motion_sigma_cells', 'motion_jump_prob', 'absent_prior'),
                    task_default='0')
    parser.add_argument('--absent-rate', type=probability_arg, default=None,
                        help=f'fraction of the {scenes} scenes that are empty (default 0)')


def settings_from_args(args, defaults: SearchSettings, grid=None,
                       schema=SCHEMA) -> SearchSettings:
    """
    Return the settings of ``args``, checked once.

    Flags a command does not have, or left at :data:`TASK_DEFAULT`, keep ``defaults``; a flat
    start index becomes a cell once ``grid`` is known.
    """
    changes = {}
    for s in schema:
        value = getattr(args, s.key, TASK_DEFAULT)
        if value is TASK_DEFAULT:
            continue
        if s.kind == 'cell' and isinstance(value, int):
            if grid is None:            # a flat index: a cell only once the grid is known
                continue
            value = grid.cell(cell_index(value, grid, s.flag))
        changes[s.key] = tuple(value) if s.kind == 'floats' else value
    settings = replace(defaults, **changes)
    if grid is not None:
        settings.check_grid(grid)
    return settings
