# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The search settings schema: every setting described once (docs/design.md section 10.1).

Each :class:`Setting` gives a setting's field name, its parameter name (node, YAML, event log and
every refusal message), its kind, default, the check of its values
(:mod:`ipomdp_gaze.model.checks`)
and its help. Everything else is generated from :data:`SCHEMA`:

- :class:`ipomdp_gaze.search.session.SearchSettings`, the frozen settings object, by
  :func:`settings_class` (its fields, defaults and checks);
- the ``gaze_controller`` node's parameter declarations (``nodes/params.py``,
  ``search_params``), with the same help;
- the CLI flags of every command (``commands/search_args.py``, ``add_search_args``): a command
  names the settings it exposes, the flag, type and help come from here;
- the YAML check of parameter files (:func:`check_parameters`).

A setting added to the schema therefore appears in the node, the CLI and the YAML check with no
other edit. The module is pure: no rclpy, no argparse.
"""
from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, field, make_dataclass, replace
import math
from typing import Callable, Mapping

from ipomdp_gaze.model.checks import (check_budget, check_confidence, check_flag,
                                      check_positive_cells, check_probability, check_radius,
                                      check_seconds, check_sigma_cells, check_start_cell,
                                      check_targets, check_track_view, is_number,
                                      MAX_FOUND_RADIUS)
from ipomdp_gaze.model.false_alarms import (check_false_alarm_scales, check_hotspot_prior,
                                            check_hotspot_scale, DEFAULT_HOTSPOT_SCALE,
                                            MAX_HOTSPOT_PRIOR)
from ipomdp_gaze.model.still_evidence import check_repeat_weight
from ipomdp_gaze.search.room import MAX_PERIOD_S

# A prediction further ahead than a minute says nothing about where a walking person is (the
# head would chase the grid's corner); a dwell is bounded as room.dwell_s is (MAX_PERIOD_S).
MAX_LEAD_S = 60.0


def check_lead_s(value, name: str) -> float:
    """Return ``motion.lead_s``: seconds in [0, :data:`MAX_LEAD_S`]."""
    seconds = check_sigma_cells(value, name)
    if seconds > MAX_LEAD_S:
        raise ValueError(f'{name} must be at most {MAX_LEAD_S:g} s (a prediction that far ahead '
                         f'says nothing of where the target is), got {value!r}')
    return seconds


def check_dwell_s(value, name: str) -> float:
    """Return ``motion.dwell_s``: seconds in (0, ``room.MAX_PERIOD_S``] (a day)."""
    seconds = check_seconds(value, name)
    if seconds > MAX_PERIOD_S:
        raise ValueError(f'{name} must be at most {MAX_PERIOD_S:g} s (a day), got {value!r}')
    return seconds


# What a setting's values are: the node declares them with the matching parameter type and a
# CLI flag parses them so (a cell is ``ROW,COL``; the node declares it as two integers).
KINDS = ('float', 'int', 'bool', 'floats', 'cell', 'str')


@dataclass(frozen=True)
class Interval:
    """
    The numbers a setting allows: from ``low`` to ``high`` (None: no bound), each end open or not.

    The help's range text and the node's descriptor range come from it; the setting's check
    stays the authority (it also refuses NaN and, with a missing bound, infinity).
    """

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    def text(self, kind: str = 'float') -> str:
        """Return the range as help shows it: ``in (0, 1)``, ``>= 0``, ``0 to 5`` (integers)."""
        low, high = self.low, self.high
        if low is not None and high is not None:
            if kind == 'int':
                return f'{low:g} to {high:g}'
            return (f"in {'(' if self.low_open else '['}{low:g}, {high:g}"
                    f"{')' if self.high_open else ']'}")
        if low is not None:
            return f"{'>' if self.low_open else '>='} {low:g}"
        if high is not None:
            return f"{'<' if self.high_open else '<='} {high:g}"
        return ''

    def closed_hull(self) -> tuple[float, float]:
        """Return ``(low, high)`` with the open ends included and a missing bound infinite."""
        return (-math.inf if self.low is None else self.low,
                math.inf if self.high is None else self.high)

    def open_ends(self) -> str:
        """Return what the closed hull takes that the setting does not (a ROS range is closed)."""
        ends = ((self.low, self.low_open), (self.high, self.high_open))
        out = [f'{end:g} excluded' for end, is_open in ends if is_open and end is not None]
        if self.low is None or self.high is None:
            out.append('finite')
        return ', '.join(out)


@dataclass(frozen=True)
class Setting:
    """
    One search setting: everything every driver needs to know about it.

    ``key`` is the field of the settings object, ``parameter`` the node / YAML name,
    ``kind`` one of :data:`KINDS`, ``check(value, parameter)`` returns the value in its plain
    type or raises ``ValueError`` with one line. ``interval`` is the range of a number
    (:class:`Interval`): the help shows it and the node declares it in the parameter's
    descriptor; ``bounds`` is other text on the allowed values (after the range, in brackets).
    ``flag`` is the CLI flag (default ``--key-with-dashes``) and ``metavar`` its placeholder.
    """

    key: str
    parameter: str
    kind: str
    default: object
    check: Callable
    help: str  # noqa: A003 (the schema's word, as argparse's)
    bounds: str = ''
    interval: Interval | None = None
    flag: str = ''
    metavar: str = ''

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f'setting {self.key}: kind must be one of {KINDS}, got {self.kind!r}')
        if self.interval is not None and (self.kind not in ('float', 'int') or (
                self.kind == 'int' and (self.interval.low_open or self.interval.high_open))):
            raise ValueError(f'setting {self.key}: an interval is for a float or an int with '
                             'closed ends')
        if not self.flag:
            object.__setattr__(self, 'flag', '--' + self.key.replace('_', '-'))

    @property
    def bounds_text(self) -> str:
        """Return the allowed values as text: the interval, then ``bounds``."""
        if self.interval is None:
            return self.bounds
        text = self.interval.text(self.kind)
        return f'{text} ({self.bounds})' if self.bounds else text

    @property
    def help_text(self) -> str:
        """Return the help with the allowed range, as the descriptor and ``--help`` show it."""
        return f'{self.help}, {self.bounds_text}' if self.bounds_text else self.help


SCHEMA: tuple[Setting, ...] = (
    Setting('confidence', 'confidence', 'float', 0.95, check_confidence,
            'found (absent) fires when the most likely cell (no target) reaches this probability',
            interval=Interval(0, 1, low_open=True, high_open=True), metavar='P'),
    Setting('max_fixations', 'search.max_fixations', 'int', 0, check_budget,
            'fixation budget of a search: gave_up when it runs out undecided',
            interval=Interval(0), bounds='0: none', metavar='N'),
    Setting('inhibit_return', 'search.inhibit_return', 'bool', False, check_flag,
            'still target: never fixate a cell twice in a search (a deterministic detector on a '
            'still scene repeats its counts; the Bayes step would count them twice)'),
    Setting('stop_on_repeat', 'search.stop_on_repeat', 'bool', False, check_flag,
            'give up (gave_up) instead of fixating a cell a second time; with inhibit_return: '
            'once every cell has been fixated (find does this)'),
    Setting('repeat_weight', 'search.repeat_weight', 'float', 1.0, check_repeat_weight,
            'still target: weight of the evidence a cell gets from views other than the one that '
            'saw it at its most informative offset (1: every frame counts fully, naive Bayes; 0: '
            'the evidence of each cell once, for overlapping views of a still scene and a '
            'deterministic detector)', interval=Interval(0, 1), metavar='W'),
    Setting('head_speed_deg_s', 'search.head_speed_deg_s', 'float', 0.0, check_sigma_cells,
            'still target, policy elm or coverage, or search.targets many (others choose as '
            'before): the view with the best score per second of head time, the move at this '
            'joint speed plus '
            "search.view_time_s (0: every view costs alike, the paper's choice)",
            interval=Interval(0),
            metavar='DEG_S'),
    Setting('view_time_s', 'search.view_time_s', 'float', 0.4, check_seconds,
            'with search.head_speed_deg_s: the seconds of a view besides the move (detector, '
            'settling and the start of the saccade)', interval=Interval(0, low_open=True),
            metavar='SECONDS'),
    Setting('head_tour', 'search.head_tour', 'bool', False, check_flag,
            'with search.head_speed_deg_s and policy coverage: while the belief is diffuse, a '
            'tile view also costs the longer tour of the tiles left that starting there '
            'commits to (nearest-neighbour tours)'),
    Setting('absent_prior', 'absent.prior', 'float', 0.0, check_probability,
            'prior that no target is in the grid (0: always there); a change starts a new '
            'search', interval=Interval(0, 1, high_open=True), metavar='P'),
    Setting('motion_sigma_cells', 'motion.sigma_cells', 'float', 0.0, check_sigma_cells,
            'the target moves: standard deviation of its random walk in cells per second (per '
            'fixation in simulation; 0: a still target)', interval=Interval(0),
            metavar='CELLS'),
    Setting('motion_jump_prob', 'motion.jump_prob', 'float', 0.0, check_probability,
            'probability per second (per fixation in simulation) that the target jumps to a '
            'random cell', interval=Interval(0, 1, high_open=True), flag='--jump-prob',
            metavar='P'),
    Setting('motion_leave_prob', 'motion.leave_prob', 'float', 0.0, check_probability,
            'with absent.prior: probability per second that the target leaves the grid, and '
            'that an absent one comes back (a person walking out of reach and in again)',
            interval=Interval(0, 1, high_open=True), metavar='P'),
    Setting('motion_max_speed_cells', 'motion.max_speed_cells', 'float', 0.0,
            check_sigma_cells,
            'the target walks: it keeps a velocity (a belief over 9 x 9 velocities up to this '
            'many cells per second on each axis) until it turns, leaves by walking past the '
            "grid's edge and comes back at its border (motion.leave_prob per second); 0: a "
            'random walk only',
            interval=Interval(0), metavar='CELLS'),
    Setting('motion_speed_cells', 'motion.speed_cells', 'float', 0.0, check_sigma_cells,
            'with motion.max_speed_cells: how fast targets usually go, the standard deviation '
            'per axis of the velocity prior in cells per second (0: every velocity alike)',
            interval=Interval(0), metavar='CELLS'),
    Setting('motion_turn_prob', 'motion.turn_prob', 'float', 0.0, check_probability,
            'with motion.max_speed_cells: probability per second that the target turns (its '
            'velocity drawn anew)', interval=Interval(0, 1, high_open=True), metavar='P'),
    Setting('motion_track_view', 'motion.track_view', 'str', 'policy', check_track_view,
            'moving target, once found: policy (the search policy chooses the view), peak '
            '(look at the most likely cell of the belief predicted motion.lead_s ahead) or '
            "position (look at the cell of the position the detections' filter predicts "
            'motion.lead_s ahead; docs/design.md section 12.9)',
            bounds='policy, peak or position', metavar='policy|peak|position'),
    Setting('motion_lead_s', 'motion.lead_s', 'float', 0.0, check_lead_s,
            'with motion.track_view peak or position: how far ahead the target is predicted '
            '(the time from a frame to the next: saccade, settling and the detector)',
            interval=Interval(0, MAX_LEAD_S), metavar='SECONDS'),
    Setting('motion_position_sigma_cells', 'motion.position_sigma_cells', 'float', 0.1,
            check_positive_cells,
            "with motion.track_view position: the standard deviation of the detections' mean "
            'position around the target, in cells (calibrated on training walks)',
            interval=Interval(0, low_open=True), metavar='CELLS'),
    Setting('motion_keep_probability', 'motion.keep_probability', 'float', 0.0,
            check_probability,
            'moving target: once found, it stays found while the answer holds at least this '
            'probability, and is lost below it (0: the confidence)',
            interval=Interval(0, 1, high_open=True), metavar='P'),
    Setting('motion_dwell_s', 'motion.dwell_s', 'float', 2.0, check_dwell_s,
            'search.targets many, moving targets: seconds of views each person found gets in '
            'turn before the next; after each round the search looks for people not found yet '
            '(one view, or up to half as long while the room is undecided; docs/design.md '
            'section 12.10)', interval=Interval(0, MAX_PERIOD_S, low_open=True),
            metavar='SECONDS'),
    Setting('start_cell', 'start_cell', 'cell', None, check_start_cell,
            "the first fixation (default: the policy's choice after a scan, else the grid's "
            'centre)', flag='--start', metavar='ROW,COL'),
    Setting('scan', 'search.scan', 'bool', True, check_flag,
            'with a count model that has scan tables: start each search with the one-time '
            'whole-image scan (asked of the detector as fixation [-1, -1, search_id])'),
    Setting('found_radius', 'search.found_radius', 'int', 0, check_radius,
            'found when the belief within this many cells of a cell reaches the '
            'confidence, and that cell is the answer (0: the cell alone)',
            interval=Interval(0, MAX_FOUND_RADIUS), metavar='CELLS'),
    Setting('stop_on_decision', 'search.stop_on_decision', 'bool', True, check_flag,
            'one target: found and absent end a search (off: they are only reported, as for a '
            'moving target, and the search goes on to its budget: to measure what every view '
            'would give; ignored with search.targets many)'),
    Setting('decide_at_budget', 'search.decide_at_budget', 'bool', False, check_flag,
            'still target: when the budget runs out undecided, say absent or found (whichever '
            'is more probable) instead of gave_up'),
    Setting('group_stop', 'search.group_stop', 'bool', False, check_flag,
            "still target, one target: a frame that carries the detector's grouped detections "
            '(its publish_groups) with one in the grid ends the search found at the likeliest '
            'cell holding one, as a sweep that stops at its first grouped detection does '
            '(docs/design.md section 6.15)'),
    Setting('group_probability', 'search.group_probability', 'float', 0.0, check_probability,
            'with search.group_stop: a grouped detection ends the search only where the belief '
            'gives its cell (its found_radius square) at least this probability after the frame '
            "(0: every group; the belief's veto of texture the detector groups)",
            interval=Interval(0, 1, high_open=True), metavar='P'),
    Setting('absent_needs_coverage', 'search.absent_needs_coverage', 'bool', False, check_flag,
            "still target, one target, a pan/tilt count model: absent only once the search's "
            'views have covered every cell (each quarter of it seen whole by some view, as the '
            "sweep's tiles see them); while P(absent) is at the confidence and a cell is left, "
            'the next view is one that covers it (the budget still decides; refused for a model '
            'without a camera, no effect on a moving target; docs/design.md section 6.16)'),
    Setting('decide_after_pass', 'search.decide_after_pass', 'bool', False, check_flag,
            "search.targets many, one pass of the sweep's poses (policy sweep): after the last "
            'pose the room is not done yet: the search goes on (the infomax choice per second of '
            'head time) until every cell is decided at the confidence, a cell empty by its '
            'posterior now that every cell was seen well, or the budget (off: the pass ends '
            'the search; docs/design.md section 11.7)'),
    Setting('false_alarm_scales', 'search.false_alarm_scales', 'floats', (1.0,),
            check_false_alarm_scales,
            'still target, count model: the scene may fire the detector this many times as '
            'often as the model expects, each factor equally likely, learned from every '
            "cell's counts during the search ([1.0]: the model's rates as calibrated)",
            metavar='F'),
    Setting('hotspot_prior', 'search.hotspot_prior', 'float', 0.0, check_hotspot_prior,
            'count model: prior that a cell is a hotspot that fires in every view '
            '(hotspot_scale times the false-alarm rate; a still target: kept over all views, '
            'a moving one: a clutter map learned frame by frame; 0: none)',
            interval=Interval(0, MAX_HOTSPOT_PRIOR), metavar='P'),
    Setting('hotspot_scale', 'search.hotspot_scale', 'float', DEFAULT_HOTSPOT_SCALE,
            check_hotspot_scale,
            "count model: a hotspot's factor of the model's false-alarm rate",
            interval=Interval(1, low_open=True), metavar='F'),
    Setting('targets', 'search.targets', 'str', 'one', check_targets,
            "the belief: one target or none (the paper's) or many (an occupancy per cell, "
            'ipomdp_gaze.many; the gaze_controller node then keeps the people found in view, '
            'docs/design.md section 11.6)', bounds='one or many',
            metavar='one|many'),
)


def parameter_names(schema=SCHEMA) -> dict:
    """Return ``{field: parameter name}`` of every setting."""
    return {s.key: s.parameter for s in schema}


def by_key(schema=SCHEMA) -> dict:
    """Return ``{field: Setting}``."""
    return {s.key: s for s in schema}


class SettingsBase:
    """What every generated settings class shares: the checks, conversions and helpers."""

    SCHEMA: tuple = ()

    def __post_init__(self):
        for s in self.SCHEMA:
            value = getattr(self, s.key)
            if not _python_kind(s.kind, value):
                raise ValueError(f'{s.parameter} must be {_KIND_WORDS[s.kind]}, got {value!r}')
            object.__setattr__(self, s.key, s.check(value, s.parameter))

    @property
    def moving(self) -> bool:
        """Whether the target is modelled as moving."""
        return self.motion_sigma_cells > 0 or self.motion_jump_prob > 0 \
            or self.motion_leave_prob > 0 or self.motion_max_speed_cells > 0

    def check_grid(self, grid) -> None:
        """Refuse a start cell outside ``grid`` (ValueError naming both)."""
        if isinstance(self.start_cell, tuple):
            row, col = self.start_cell
            if row >= grid.rows or col >= grid.cols:
                raise ValueError(f'start cell ({row}, {col}) is outside a {grid.rows}x'
                                 f'{grid.cols} grid')

    def to_parameters(self) -> dict:
        """Return the settings under their parameter names, as YAML files and event logs."""
        out = {}
        for s in self.SCHEMA:
            value = getattr(self, s.key)
            out[s.parameter] = list(value) if isinstance(value, tuple) else value
        return out

    @classmethod
    def from_parameters(cls, values: Mapping, base=None, grid=None):
        """
        Build settings from parameter names (node parameters, a YAML block, CLI flags).

        Unknown names are ignored (a node has many other parameters). ``start_row`` and
        ``start_col`` give ``start_cell`` as the node declares it: -1 is the centre's row
        (column) of ``grid``, both -1 the default rule. With ``grid`` the start cell is checked
        against it.
        """
        changes = {s.key: values[s.parameter] for s in cls.SCHEMA if s.parameter in values}
        if 'start_row' in values or 'start_col' in values:
            row, col = values.get('start_row', -1), values.get('start_col', -1)
            if row == -1 and col == -1:
                changes['start_cell'] = None
            elif grid is None:
                raise ValueError('start_row / start_col of -1 (the centre) need the grid')
            else:
                centre_row, centre_col = grid.cell(grid.center_index)
                changes['start_cell'] = (centre_row if row == -1 else row,
                                         centre_col if col == -1 else col)
        settings = replace(base or cls(), **changes)
        if grid is not None:
            settings.check_grid(grid)
        return settings


def _docstring(schema) -> str:
    lines = ['How a search decides and stops, checked once (the same message from every driver).',
             '', 'Generated from :data:`ipomdp_gaze.search.settings.SCHEMA`; each field is',
             'checked when the object is built and keeps its plain type.', '', 'Attributes',
             '----------']
    for s in schema:
        lines += [f'{s.key} : {s.kind}', f'    ``{s.parameter}``: {s.help_text}.']
    return '\n'.join(lines) + '\n'


def settings_class(schema=SCHEMA, name: str = 'SearchSettings', module: str = __name__):
    """
    Return a frozen dataclass with one checked field per setting of ``schema``.

    ``module`` is where the class is importable from (pickling across processes needs it).
    """
    fields_ = [(s.key, object, field(default=s.default)) for s in schema]
    cls = make_dataclass(name, fields_, bases=(SettingsBase,), frozen=True,
                         namespace={'SCHEMA': tuple(schema), '__doc__': _docstring(schema)})
    cls.__module__ = module
    return cls


_KIND_WORDS = {'float': 'a number', 'int': 'an integer', 'bool': 'true or false',
               'floats': 'a list of numbers', 'cell': '[row, col]', 'str': 'a string'}


def _python_kind(kind: str, value) -> bool:
    """
    Whether a value given from Python has its setting's kind, as :func:`_check_kind` for YAML.

    A number is no string and no bool (``confidence='0.9'`` and ``True`` are refused, as YAML's
    ``'0.9'`` and ``true`` are: :func:`ipomdp_gaze.model.checks.is_number`); a list of numbers
    is a collection of numbers, not a string (``'2'`` was the factor 2). The other kinds' checks
    refuse the wrong kind themselves.
    """
    if kind == 'float':
        return is_number(value)
    if kind == 'floats':
        return not isinstance(value, (str, bytes)) and (
            not isinstance(value, Collection) or all(is_number(v) for v in value))
    return True


def _check_kind(setting: Setting, value, where: str) -> None:
    """Refuse a YAML value of the wrong kind (a string for a number, 1 for true)."""
    kind = setting.kind
    ok = {'float': is_number(value),
          'int': isinstance(value, int) and not isinstance(value, bool),
          'bool': isinstance(value, bool),
          'floats': isinstance(value, list) and all(is_number(v) for v in value),
          'cell': value is None or isinstance(value, (list, str)),
          'str': isinstance(value, str)}[kind]
    if not ok:
        raise ValueError(f'{where}{setting.parameter} must be {_KIND_WORDS[kind]}, got {value!r}')


def check_parameters(values: Mapping, settings_cls=None, base=None, grid=None, where: str = ''):
    """
    Check the search settings of a flat parameter mapping (a YAML ``ros__parameters`` block).

    Each setting present must have the kind the node declares (YAML ``1`` is not ``true``), and
    the whole goes through the settings' own checks; a parameter in a settings namespace
    (``search.``, ``motion.``, ``absent.``) that no setting has is refused, so a typo does not
    pass silently. Returns the settings object. ``where`` prefixes messages (a file name).
    """
    if settings_cls is None:
        from ipomdp_gaze.search.session import SearchSettings as settings_cls
    schema = settings_cls.SCHEMA
    known = {s.parameter: s for s in schema}
    namespaces = {s.parameter.split('.')[0] + '.' for s in schema if '.' in s.parameter}
    for name, value in values.items():
        if name in known:
            _check_kind(known[name], value, where)
        elif name.startswith(tuple(namespaces)):
            raise ValueError(f'{where}unknown search parameter {name!r}; known: '
                             f"{', '.join(sorted(known))}")
    try:
        return settings_cls.from_parameters(values, base=base, grid=grid)
    except ValueError as exc:
        raise ValueError(f'{where}{exc}') from None
