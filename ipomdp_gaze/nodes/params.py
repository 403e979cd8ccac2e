# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Parameters of the nodes: declarations with explicit types and descriptors, and changes at run time.

Both nodes describe the task with the same names (``grid.*``, ``fpoc.<name>`` with the names of
docs/design.md section 2, the pan/tilt joint mapping), so one YAML block can be shared. Every
parameter is declared with a ``ParameterDescriptor`` and an explicit type; the grid is read-only
after start. ``fpoc.dprime`` is dynamically typed because it is a number for the ``camera`` FPOC
and a list for the ``table`` FPOC.

A change (``ros2 param set``, ``-p`` and YAML overrides included) goes through one
:class:`ParameterTransaction` per node: it is checked whole and either taken whole or refused
with the reason.
"""
from __future__ import annotations

import array
from dataclasses import dataclass, replace
import math
from typing import Callable

from ipomdp_gaze.model.fpoc import CameraFPOC, MODELS
from ipomdp_gaze.search.controller_config import TABLE_ECC_DEG
from ipomdp_gaze.search.settings import SCHEMA
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
from rclpy.parameter import Parameter

T = Parameter.Type
ARRAY_TYPES = (T.BYTE_ARRAY, T.BOOL_ARRAY, T.INTEGER_ARRAY, T.DOUBLE_ARRAY, T.STRING_ARRAY)
INT_MAX = 2 ** 31 - 1
# The largest int64, the largest integer parameter: where a range with no upper bound ends.
INT64_MAX = 2 ** 63 - 1
# Rows or columns of a grid: 256x256 (65,536 cells) is the largest grid tested under load.
MAX_CELLS_PER_SIDE = 1024


@dataclass(frozen=True)
class Param:
    """
    One declared parameter: name, default, type, description and constraints.

    ``ptype`` is the parameter type; ``default=None`` declares the type only and then sets an
    empty array (array parameters).
    ``choices`` restricts strings; ``float_range``/``int_range`` are enforced by rclpy itself.
    ``range_check`` is the settings schema's ``check(value, name)`` of a search setting whose
    range the descriptor carries (its closed hull; ``constraints`` names what the hull takes that
    the check refuses): a value it refuses is refused with its reason before rclpy's range check
    (:meth:`ParameterTransaction.refusal`, :func:`declare`).
    A double array takes an integer array, as rcl reads ``-p name:=[1,2,1]`` or YAML's
    ``[1, 2, 1]``, as those doubles instead of refusing it for its type (:meth:`taken`).
    """

    name: str
    default: object
    ptype: Parameter.Type
    description: str
    read_only: bool = False
    dynamic: bool = False
    float_range: tuple | None = None
    int_range: tuple | None = None
    choices: tuple | None = None
    range_check: Callable | None = None
    constraints: str = ''

    def taken(self, parameter: Parameter) -> Parameter:
        """Return ``parameter`` as it is declared: for a double array, whole numbers as doubles."""
        if self.ptype == T.DOUBLE_ARRAY and parameter.type_ == T.INTEGER_ARRAY:
            return Parameter(parameter.name, T.DOUBLE_ARRAY, [float(v) for v in parameter.value])
        return parameter

    def descriptor(self) -> ParameterDescriptor:
        """Build the ``ParameterDescriptor`` to declare with."""
        d = ParameterDescriptor(description=self.description, read_only=self.read_only)
        if self.dynamic:
            d.dynamic_typing = True
        else:
            d.type = self.ptype.value
        if self.float_range is not None:
            d.floating_point_range = [FloatingPointRange(
                from_value=float(self.float_range[0]), to_value=float(self.float_range[1]),
                step=0.0)]
        if self.int_range is not None:
            low, high, step = (tuple(self.int_range) + (1,))[:3]
            d.integer_range = [IntegerRange(from_value=low, to_value=high, step=step)]
        if self.choices is not None:
            d.additional_constraints = 'one of: ' + ', '.join(repr(c) for c in self.choices)
        elif self.constraints:
            d.additional_constraints = self.constraints
        return d

    def range_refusal(self, parameter: Parameter) -> str | None:
        """Return why ``range_check`` refuses ``parameter`` of the declared type, or None."""
        if self.range_check is None or self.read_only or parameter.type_ != self.ptype:
            return None
        return self.check(parameter.value)

    def check(self, value) -> str | None:
        """Return why ``value`` is invalid, or None (types and other ranges are rclpy's job)."""
        if self.range_check is not None:
            try:
                self.range_check(value, self.name)
            except ValueError as exc:
                return str(exc)
        if self.choices is not None and value not in self.choices:
            return (f"{self.name} must be one of {', '.join(repr(c) for c in self.choices)}, "
                    f'got {value!r}')
        if self.dynamic and self.name == 'fpoc.dprime':
            # A list set at run time arrives from rclpy as an array.array('d').
            items = list(value) if isinstance(value, (list, tuple, array.array)) else [value]
            if not items or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                    for v in items):
                return f'fpoc.dprime must be a number or a list of numbers, got {value!r}'
        return None


def grid_params() -> list[Param]:
    """``grid.rows``, ``grid.cols``, ``grid.spacing_deg`` (read-only)."""
    return [
        Param('grid.rows', 11, T.INTEGER, 'rows of the visual array (read-only)', read_only=True,
              int_range=(1, MAX_CELLS_PER_SIDE)),
        Param('grid.cols', 11, T.INTEGER, 'columns of the visual array (read-only)',
              read_only=True, int_range=(1, MAX_CELLS_PER_SIDE)),
        Param('grid.spacing_deg', 5.0, T.DOUBLE,
              'pan/tilt degrees between neighbouring cells (read-only)', read_only=True,
              float_range=(1e-6, 90.0)),
    ]


def fpoc_params(max_dprime: float | None = None) -> list[Param]:
    """
    ``fpoc.model`` and the union of every model's parameters (docs/design.md section 2).

    The defaults describe a camera whose field of view covers 5x5 cells of a 5-degree grid.
    ``max_dprime``: the largest d' the node takes (the simulated camera's float32 frames), named
    in the descriptor of ``fpoc.dprime`` (the node's build checks it).
    """
    bound = '' if max_dprime is None else f'at most {max_dprime:g} each (float32 frames)'
    return [
        Param('fpoc.model', 'camera', T.STRING, 'FPOC model', choices=tuple(MODELS)),
        Param('fpoc.dprime', 4.0, T.DOUBLE, "d' inside the field of view (camera: a number), "
              "or d' at each fpoc.ecc_deg (table: a list)", dynamic=True, constraints=bound),
        Param('fpoc.shape', 'rectangle', T.STRING, 'camera field of view shape',
              choices=CameraFPOC.SHAPES),
        Param('fpoc.half_width_deg', 10.0, T.DOUBLE, 'camera: half-width of the field of view',
              float_range=(0.0, 180.0)),
        Param('fpoc.half_height_deg', 10.0, T.DOUBLE,
              'camera: half-height of the field of view', float_range=(0.0, 180.0)),
        Param('fpoc.radius_deg', 10.0, T.DOUBLE, 'camera (circle): radius of the field of view',
              float_range=(0.0, 180.0)),
        Param('fpoc.noise_contrast', 0.20, T.DOUBLE, 'human: noise contrast n',
              float_range=(0.0, 10.0)),
        Param('fpoc.foveal_dprime', 2.0, T.DOUBLE, "human, exponential: d' at the fovea",
              float_range=(1e-6, 12.0)),
        Param('fpoc.scale_deg', 1.5, T.DOUBLE, 'exponential: fall-off scale in degrees',
              float_range=(1e-6, 180.0)),
        Param('fpoc.ecc_deg', list(TABLE_ECC_DEG), T.DOUBLE_ARRAY,
              'table: eccentricities in degrees (increasing)'),
    ]


def joint_params(limits: bool) -> list[Param]:
    """Joint names, REP 103 signs, offsets and (for the controller) joint limits."""
    params = [
        Param('pan_joint', 'pan_joint', T.STRING, 'name of the pan joint'),
        Param('tilt_joint', 'tilt_joint', T.STRING, 'name of the tilt joint'),
        Param('pan_sign', 1, T.INTEGER, '1 if positive pan turns left (REP 103), else -1',
              int_range=(-1, 1, 2)),
        Param('tilt_sign', 1, T.INTEGER, '1 if positive tilt looks down (REP 103), else -1',
              int_range=(-1, 1, 2)),
        Param('pan_offset_rad', 0.0, T.DOUBLE, 'pan of the centre column in radians',
              float_range=(-2 * math.pi, 2 * math.pi)),
        Param('tilt_offset_rad', 0.0, T.DOUBLE, 'tilt of the centre row in radians',
              float_range=(-2 * math.pi, 2 * math.pi)),
    ]
    if limits:
        params += [
            Param('pan_min_rad', -math.pi, T.DOUBLE, 'lower pan limit; every cell must fit'),
            Param('pan_max_rad', math.pi, T.DOUBLE, 'upper pan limit; every cell must fit'),
            Param('tilt_min_rad', -math.pi / 2, T.DOUBLE, 'lower tilt limit; every cell must fit'),
            Param('tilt_max_rad', math.pi / 2, T.DOUBLE, 'upper tilt limit; every cell must fit'),
        ]
    return params


def cell_params(prefix: str, what: str, unset: str) -> list[Param]:
    """
    ``<prefix>_row`` and ``<prefix>_col``: a cell, each coordinate -1 when it is not fixed.

    ``what`` names the cell (``'the target'``) and ``unset`` says what -1 means, with ``{}`` for
    the word row or column (``'a random {} at each reset'``);
    :func:`ipomdp_gaze.search.controller_config.row_col_from` reads them.
    """
    return [Param(f'{prefix}_{axis[:3]}', -1, T.INTEGER,
                  f'{axis} of {what} (-1: {unset.format(axis)})',
                  int_range=(-1, MAX_CELLS_PER_SIDE - 1)) for axis in ('row', 'column')]


_PARAMETER_TYPES = {'float': T.DOUBLE, 'int': T.INTEGER, 'bool': T.BOOL, 'floats': T.DOUBLE_ARRAY,
                    'str': T.STRING}


def search_params(schema=SCHEMA) -> list[Param]:
    """
    Return the search settings as parameters, generated from :mod:`ipomdp_gaze.search.settings`.

    The start cell is declared as ``start_row`` / ``start_col`` (:func:`cell_params`). A
    setting's interval becomes the descriptor's range (:func:`_ranged`).
    """
    return [_ranged(Param(s.parameter, list(s.default) if s.kind == 'floats' else s.default,
                          _PARAMETER_TYPES[s.kind], s.help_text), s)
            for s in schema if s.kind != 'cell']


def _ranged(param: Param, setting) -> Param:
    """
    Give ``param`` the range of ``setting``'s interval, if it has one.

    A ROS range is closed, so an open end is included and a missing bound is infinite (an
    integer's: int64's); what the hull takes that the setting refuses is named in the
    descriptor's constraints, and the setting's check stays the authority (``range_check``).
    """
    interval = setting.interval
    if interval is None:
        return param
    low, high = interval.closed_hull()
    if setting.kind == 'int':
        return replace(param, range_check=setting.check, int_range=(
            -INT64_MAX - 1 if low == -math.inf else int(low),
            INT64_MAX if high == math.inf else int(high)))
    wider = interval.open_ends()
    return replace(param, range_check=setting.check, float_range=(low, high),
                   constraints=f'{interval.text()}: {wider}' if wider else '')


def declare(node, params: list[Param]) -> None:
    """
    Declare every parameter (YAML and ``-p`` overrides go through the node's callbacks).

    rclpy checks an override's type before any callback (no pre-set while declaring), so the
    overrides, a private dict of rclpy 7 (without it nothing is rewritten), are rewritten
    first: whole numbers for a double array become doubles (:meth:`Param.taken`). An array
    given as an empty list (``-p name:=[]``, YAML's ``[]``) has no type for rcl, and rclpy
    hands it over as NOT_SET: declared with a default it was refused as 'not initialized'. It
    is set as the declared type's empty array (the node then judges it), or, for a read-only
    array, which can only take its override, refused with that reason. An override that a
    parameter's ``range_check`` refuses is refused with its reason (a ``ValueError``), before
    rclpy's range check would refuse it with its own.
    """
    overrides = getattr(node, '_parameter_overrides', None) or {}
    for p in params:
        given = overrides.get(p.name)
        if given is not None:
            overrides[p.name] = given = p.taken(given)
            reason = p.range_refusal(given)
            if reason:
                raise ValueError(reason)
        empty = p.ptype in ARRAY_TYPES and given is not None and given.type_ == T.NOT_SET
        if empty and p.default is not None and p.read_only:
            raise ValueError(f'{p.name} is given as an empty list, which ROS cannot type: a '
                             'read-only array needs at least one value')
        if p.default is None or empty:
            node.declare_parameter(p.name, p.ptype, p.descriptor())
            if node.get_parameter_or(p.name).type_ == T.NOT_SET:
                result = node.set_parameters([Parameter(p.name, p.ptype, [])])[0]
                if empty and not result.successful:
                    raise ValueError(f'{p.name} []: {result.reason}')
        else:
            node.declare_parameter(p.name, p.default, p.descriptor())


def current_values(node, params: list[Param]) -> dict:
    """``{name: value}`` of the declared parameters."""
    return {p.name: node.get_parameter(p.name).value for p in params}


def short_repr(value, limit: int = 6) -> str:
    """Repr a parameter value for the log, with long arrays shortened to their length."""
    if isinstance(value, (list, tuple)) or hasattr(value, 'typecode'):
        items = list(value)
        if len(items) > limit:
            return f'[{len(items)} values: {items[0]!r}, {items[1]!r}, ...]'
        return repr(items)
    return repr(value)


# rclpy declares these itself for an overridable subscription, read-only, while it is made.
QOS_OVERRIDES = 'qos_overrides.'


class ParameterTransaction:
    """
    Declare a node's parameters and take every change whole or not at all.

    For each proposed set of parameters (one ``ros2 param set``, an atomic set, or a YAML or
    ``-p`` override while declaring) the on-set callback checks each :class:`Param`, then builds
    a candidate configuration from the current values and the proposed ones with
    ``build(values, changed, previous)``; a ``ValueError`` refuses the whole set with its message
    as the reason. The candidate is kept pending; once rclpy has stored the values, the post-set
    callback makes it :attr:`config` and calls ``apply(old, new)``, then logs
    ``parameters set: name=value, ...`` followed by what ``apply`` returned (if anything).

    Parameters
    ----------
    node : rclpy.node.Node
        The node; the callbacks are registered at once, so they see the overrides too.
    params : list of Param
        Every parameter of the node, in declaration order.
    build : callable
        ``build(values, changed, previous) -> config``: ``values`` maps every name to its value,
        ``changed`` is the set of proposed names and ``previous`` the config in force (both None
        for the first config).
    apply : callable
        ``apply(old, new) -> str or None``: make the node follow the new config; the returned
        text is appended to the log line.
    while_declaring : callable, optional
        ``while_declaring(params)``, raising ``ValueError`` for an override that the parameters
        declared so far already rule out (until :attr:`ready`, nothing is built).
    pre_set : callable, optional
        The node's own pre-set step, ``pre_set(params) -> params`` (rclpy would join the lists
        of two pre-set callbacks), run after whole numbers become doubles (:meth:`Param.taken`).

    """

    def __init__(self, node, params: list[Param], build, apply, while_declaring=None,
                 pre_set=None):
        self.node = node
        self.params = params
        self._by_name = {p.name: p for p in params}
        self._build = build
        self._apply = apply
        self._while_declaring = while_declaring
        self._node_pre_set = pre_set
        self.ready = False
        self.config = None
        self._pending = None
        node.add_pre_set_parameters_callback(self._pre_set)
        node.add_on_set_parameters_callback(self._on_set)
        node.add_post_set_parameters_callback(self._post_set)

    def declare(self) -> None:
        """Declare every parameter (YAML and ``-p`` overrides go through the callbacks)."""
        declare(self.node, self.params)

    def values(self) -> dict:
        """``{name: value}`` of every parameter now."""
        return current_values(self.node, self.params)

    def start(self, config) -> None:
        """Take ``config`` as the one in force and build every later change."""
        self.config = config
        self.ready = True

    def refusal(self, params: list[Parameter]) -> SetParametersResult | None:
        """
        Return the refusal of a set by a parameter's ``range_check``, or None.

        rclpy checks a descriptor's range before any callback and refuses with its own text
        ('Parameter confidence out of range Min: 0.0, Max: 1.0, value: 1.5'): a node asks this
        first (:class:`RangeReasons`), so such a value gets the settings' reason instead.
        """
        for p in params:
            spec = self._by_name.get(p.name)
            reason = spec.range_refusal(spec.taken(p)) if spec is not None else None
            if reason:
                return SetParametersResult(successful=False, reason=reason)
        return None

    def _pre_set(self, params: list[Parameter]) -> list[Parameter]:
        params = [self._by_name[p.name].taken(p) if p.name in self._by_name else p
                  for p in params]
        return params if self._node_pre_set is None else self._node_pre_set(params)

    def _on_set(self, params: list[Parameter]) -> SetParametersResult:
        if all(p.name.startswith(QOS_OVERRIDES) for p in params):
            self._pending = None    # rclpy's read-only QoS overrides (nodes/qos.py): not ours
            return SetParametersResult(successful=True)
        for p in params:
            spec = self._by_name.get(p.name)
            reason = spec.check(p.value) if spec is not None else None
            if reason:
                return SetParametersResult(successful=False, reason=reason)
        try:
            if not self.ready:
                if self._while_declaring is not None:
                    self._while_declaring(params)
                return SetParametersResult(successful=True)
            values = self.values()
            values.update({p.name: p.value for p in params})
            self._pending = None
            self._pending = self._build(values, {p.name for p in params}, self.config)
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        # rclpy drops the reason of a successful set, so a warning goes to the log (post-set).
        return SetParametersResult(successful=True)

    def _post_set(self, params: list[Parameter]) -> None:
        if not self.ready or self._pending is None:
            return
        old, self.config, self._pending = self.config, self._pending, None
        extra = self._apply(old, self.config)
        changed = ', '.join(f'{p.name}={short_repr(p.value)}' for p in params)
        self.node.get_logger().info(f'parameters set: {changed}' + (f'; {extra}' if extra else ''))


class RangeReasons:
    """
    Mixin before ``rclpy.node.Node``: a set a ``range_check`` refuses gets the check's reason.

    Every set (``ros2 param set``, the parameter services, the node's own) is first asked of
    the node's ``_transaction`` (:meth:`ParameterTransaction.refusal`); a set it does not refuse
    goes on as ``Node``'s, with rclpy's descriptor checks and the callbacks.
    """

    def _range_refusal(self, parameter_list):
        transaction = getattr(self, '_transaction', None)
        return None if transaction is None else transaction.refusal(parameter_list)

    def set_parameters(self, parameter_list):
        """Set parameters one by one as ``Node.set_parameters`` does; return the results."""
        results = []
        for p in parameter_list:
            refused = self._range_refusal([p])
            results.append(refused if refused is not None else super().set_parameters([p])[0])
        return results

    def set_parameters_atomically(self, parameter_list):
        """Set parameters all or none as ``Node.set_parameters_atomically`` does."""
        refused = self._range_refusal(parameter_list)
        return refused if refused is not None else \
            super().set_parameters_atomically(parameter_list)
