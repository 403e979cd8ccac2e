# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The scalar checks every layer uses: one place for each rule and its message.

Each check takes the value and the name users know it by (a parameter, a flag, a field), returns
the value in its plain Python type and raises ``ValueError`` with one line that starts with the
name and ends with ``got <value>``. Booleans are never numbers here (``True`` is not a count),
nor is text (``'0.5'``): :func:`is_number` is the one rule, for the settings' YAML and Python
values and for the researcher API (the belief, motion, FPOC, occupancy and camera objects).
The search settings (:mod:`ipomdp_gaze.search.settings`) name the check of each setting.
"""
from __future__ import annotations

import math
import numbers
import operator

import numpy as np


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


def short_repr(value, limit: int = 40) -> str:
    """Return ``repr(value)`` cut to ``limit`` characters, for a one-line message."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + '...'


def is_number(value) -> bool:
    """Whether ``value`` is a real number (numpy's too): no bool, no text such as ``'0.5'``."""
    return isinstance(value, numbers.Real) and not _is_bool(value)


def check_number(value, name: str) -> float:
    """Return a number as a float; anything else (``'0.5'``, ``True``, None) names ``name``."""
    if not is_number(value):
        raise ValueError(f'{name} must be a number, got {value!r}')
    return float(value)


def check_flag(value, name: str) -> bool:
    """Return a true/false value as a bool (not 0/1, not a string)."""
    if not _is_bool(value):
        raise ValueError(f'{name} must be true or false, got {value!r}')
    return bool(value)


def positive_int(name: str, value, allow_zero: bool = False) -> int:
    """Return an integer >= 1 (>= 0 with ``allow_zero``); floats such as 2.0 are refused."""
    floor = 0 if allow_zero else 1
    if _is_bool(value) or not isinstance(value, (int, np.integer)) or value < floor:
        kind = 'a non-negative' if allow_zero else 'a positive'
        raise ValueError(f'{name} must be {kind} integer, got {value!r}')
    return int(value)


def finite(name: str, value, positive: bool = False) -> float:
    """Return a finite number (> 0 with ``positive``) as a float."""
    checked = check_number(value, name)
    if not math.isfinite(checked) or (positive and checked <= 0):
        bound = 'finite and > 0' if positive else 'finite'
        raise ValueError(f'{name} must be {bound}, got {value!r}')
    return checked


def check_confidence(confidence, name: str = 'confidence') -> float:
    """
    Return the confidence level of a decision as a float: strictly between 0 and 1.

    1 is refused: a posterior reaches it only by rounding, so a search at 1 would never stop by
    evidence; 0 would decide before any frame.
    """
    if not 0.0 < check_number(confidence, name) < 1.0:
        raise ValueError(f'{name} must be between 0 and 1 (exclusive), got {confidence!r}')
    return float(confidence)


def check_budget(value, name: str = 'search.max_fixations') -> int:
    """Return a fixation budget as an int >= 0; 0 means no budget (everywhere)."""
    try:
        budget = -1 if _is_bool(value) else operator.index(value)
    except TypeError:
        budget = -1
    if budget < 0:
        raise ValueError(f'{name} must be an integer >= 0 (0: no budget), got {value!r}')
    return budget


def check_probability(value, name: str) -> float:
    """
    Return a probability in ``[0, 1)`` (a jump probability, a prior or a rate) as a float.

    1 is refused: it would make the hypothesis certain before any evidence.
    """
    p = check_number(value, name)
    if not 0.0 <= p < 1.0:
        raise ValueError(f'{name} must be a probability in [0, 1), got {value!r}')
    return p


def check_sigma_cells(value, name: str = 'sigma_cells') -> float:
    """Return a motion standard deviation in cells: a finite number >= 0."""
    sigma = check_number(value, name)
    if not math.isfinite(sigma) or sigma < 0:
        raise ValueError(f'{name} must be finite and >= 0, got {value!r}')
    return sigma


def check_in_range(value, name: str, low: float, high: float, note: str = '') -> float:
    """Return a number in the closed interval ``[low, high]`` as a float (``note`` explains)."""
    if not is_number(value) or not low <= float(value) <= high:
        raise ValueError(f'{name} must be in [{low:g}, {high:g}]{note}, got {value!r}')
    return float(value)


def check_factor_above_one(value, name: str, what: str) -> float:
    """Return a finite factor > 1 as a float (``what``: of what it is a factor)."""
    if not (is_number(value) and math.isfinite(float(value)) and float(value) > 1.0):
        raise ValueError(f'{name} must be a finite factor > 1 of {what}, got {value!r}')
    return float(value)


# The largest search.found_radius in cells: an 11 x 11 square of cells around the answer.
MAX_FOUND_RADIUS = 5


def check_radius(value, name: str) -> int:
    """Return a radius in cells, an integer from 0 to :data:`MAX_FOUND_RADIUS`."""
    if _is_bool(value) or not isinstance(value, (int, np.integer)) \
            or not 0 <= value <= MAX_FOUND_RADIUS:
        raise ValueError(f'{name} must be an integer from 0 to {MAX_FOUND_RADIUS} (cells), got '
                         f'{value!r}')
    return int(value)


def check_start_cell(value, name: str = 'start_cell'):
    """Return a start cell: ``(row, col)`` integers >= 0 (no bools), ``'policy'`` or None."""
    if value is None or (isinstance(value, str) and value == 'policy'):
        return value
    try:
        items = tuple(value)
        if any(_is_bool(v) for v in items):
            raise TypeError(value)
        row, col = (operator.index(v) for v in items)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be (row, col) integers, 'policy' or none (the "
                         f'default), got {value!r}') from None
    if row < 0 or col < 0:
        raise ValueError(f'{name} must be (row, col) with row, col >= 0, got {value!r}')
    return (int(row), int(col))


# search.targets: the paper's one target (or none), or many (an occupancy per cell,
# ipomdp_gaze.many).
TARGETS = ('one', 'many')


def check_targets(value, name: str = 'search.targets') -> str:
    """Return ``'one'`` or ``'many'``: the belief a search holds (docs/design.md section 11)."""
    if not (isinstance(value, str) and value in TARGETS):
        raise ValueError(f"{name} must be one of {', '.join(TARGETS)}, got {value!r}")
    return value


# motion.track_view: where the head looks while a moving target is found: the search policy's
# choice, or the peak of the belief predicted motion.lead_s ahead (docs/design.md section 12.4).
TRACK_VIEWS = ('policy', 'peak', 'position')


def check_track_view(value, name: str = 'motion.track_view') -> str:
    """Return ``'policy'``, ``'peak'`` or ``'position'``: how a found moving target is seen."""
    if not (isinstance(value, str) and value in TRACK_VIEWS):
        raise ValueError(f"{name} must be one of {', '.join(TRACK_VIEWS)}, got {value!r}")
    return value


def check_positive_cells(value, name: str = 'position_sigma_cells') -> float:
    """Return a length in cells that must be > 0 (a finite number)."""
    return finite(name, value, positive=True)


def check_seconds(value, name: str) -> float:
    """Return a duration in seconds: a finite number > 0."""
    return finite(name, value, positive=True)
