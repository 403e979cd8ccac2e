# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The controller's configuration from a flat parameter mapping: one pure builder for every driver.

The ``gaze_controller`` node, ``ipomdp-gaze record`` / replay, the offline evaluation of the
pan/tilt task and the benches describe a controller with the node's parameter names
(``grid.*``, ``fpoc.*``, ``observation.*``, the joints, the search settings of
:mod:`ipomdp_gaze.search.settings`, ``policy.*``). :func:`build_config` turns such a mapping into
the
grid, FPOC, observation model, pan/tilt mapping, settings and policy, with every check the node
makes, so a recording replays and an evaluation runs exactly what the node would run.

The core does not import the policies (docs/design.md section 8): the caller passes
``build_policy`` (``ipomdp_gaze.policies.registry.build_policy``), and ``build_config`` calls it as
``build_policy(name, grid, observation, kernel, file, action, warn=...)``.
"""
from __future__ import annotations

import array
from dataclasses import dataclass
from typing import Callable, Mapping

from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.belief import prior_from_weights
from ipomdp_gaze.model.checks import short_repr
from ipomdp_gaze.model.fpoc import make_fpoc, parameter_names
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.observation import GaussianObservation
from ipomdp_gaze.search.gaze import (check_settle_time, GazeController, NO_PRIOR_WITH_MANY,
                                     STAMP_TOLERANCE_S)
from ipomdp_gaze.search.health import policy_label
from ipomdp_gaze.search.many import check_many_settings
from ipomdp_gaze.search.room import check_frame_id, check_room_times
from ipomdp_gaze.search.session import check_model_settings, SearchSettings
import numpy as np

POLICY_KEYS = ('policy.name', 'policy.file', 'policy.kernel', 'policy.action')
OBSERVATION_KEYS = ('observation.model', 'observation.file')


def grid_from(values: Mapping) -> Grid:
    """Build the grid described by ``grid.*``."""
    return Grid(values['grid.rows'], values['grid.cols'], values['grid.spacing_deg'])


# The nodes' default fpoc.ecc_deg (nodes/params.py declares it): the table FPOC's refusal names
# it, not the Python class's own default.
TABLE_ECC_DEG = (0.0, 10.0)


def fpoc_from(values: Mapping):
    """Build the FPOC described by ``fpoc.model`` and its ``fpoc.<name>`` parameters."""
    model = values['fpoc.model']
    kwargs = {}
    for name in parameter_names(model):
        value = values[f'fpoc.{name}']
        # lists: from YAML a list, set at run time an array.array('d') (rclpy's)
        kwargs[name] = list(value) if isinstance(value, (list, tuple, array.array)) else value
    if model == 'table' and not isinstance(kwargs['dprime'], list):
        raise ValueError('the table FPOC needs fpoc.dprime as a list matching fpoc.ecc_deg')
    if model == 'table' and not (kwargs['dprime'] and isinstance(kwargs['ecc_deg'], list)
                                 and len(kwargs['ecc_deg']) == len(kwargs['dprime'])):
        ecc, dprime = kwargs['ecc_deg'], kwargs['dprime']
        raise ValueError(f'the table FPOC needs fpoc.ecc_deg and fpoc.dprime non-empty and of '
                         f'equal length, got {len(ecc)} fpoc.ecc_deg {ecc} and {len(dprime)} '
                         f'fpoc.dprime {dprime} (fpoc.ecc_deg not given is its default, '
                         f'{list(TABLE_ECC_DEG)})')
    return make_fpoc(model, **kwargs)


def head_from(values: Mapping, grid: Grid) -> PanTiltMap:
    """Build the pan/tilt mapping; joint limits are used when they are given."""
    limits = {}
    if 'pan_min_rad' in values:
        limits = {'pan_limits_rad': (values['pan_min_rad'], values['pan_max_rad']),
                  'tilt_limits_rad': (values['tilt_min_rad'], values['tilt_max_rad'])}
    return PanTiltMap(grid, values['pan_joint'], values['tilt_joint'], values['pan_sign'],
                      values['tilt_sign'], values['pan_offset_rad'], values['tilt_offset_rad'],
                      **limits)


def row_col_from(values: Mapping, grid: Grid, row_name: str, col_name: str) -> tuple:
    """
    Return ``(row, col)`` from two parameters where -1 means "not fixed" (returned as None).

    Each coordinate stands on its own, so ``ros2 param set`` can change one at a time.

    Raises
    ------
    ValueError
        If a coordinate is outside the grid.

    """
    out = []
    for name, size in ((row_name, grid.rows), (col_name, grid.cols)):
        value = values[name]
        if value != -1 and not 0 <= value < size:
            raise ValueError(f'{name} must be -1 or in 0..{size - 1} for a '
                             f'{grid.rows}x{grid.cols} grid, got {value}')
        out.append(None if value == -1 else int(value))
    return tuple(out)


def prior_from(values: Mapping, grid: Grid):
    """
    Return ``belief.prior`` as probabilities (N,), or None for the uniform prior (no values).

    Raises
    ------
    ValueError
        The most fundamental reason first: any prior with ``search.targets`` many (whose
        belief is not over one target's cell); values that are not numbers; a count other
        than one per cell (rows x cols, row-major); then the first weight not finite, below
        0, or all of them 0 (:func:`~ipomdp_gaze.model.belief.prior_from_weights`).

    """
    weights = values.get('belief.prior')
    if weights is None or len(weights) == 0:
        return None
    if values.get('search.targets', 'one') == 'many':
        raise ValueError(NO_PRIOR_WITH_MANY)
    try:
        weights = np.asarray(list(weights), dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f'belief.prior must be numbers, one weight per cell, got '
                         f'{short_repr(weights)}') from None
    if weights.ndim != 1 or weights.size != grid.n_cells:
        raise ValueError(f'belief.prior must hold one weight per cell, {grid.n_cells} values '
                         f'for a {grid.rows}x{grid.cols} grid (row-major; none: uniform), got '
                         f'{len(weights)}')
    try:
        return prior_from_weights(weights, grid.shape)
    except ValueError as exc:
        raise ValueError(f'belief.prior {exc}') from None


def observation_from(values: Mapping, grid: Grid, fpoc):
    """
    Build the observation model the parameters select: Gaussian with the FPOC, or a count model.

    Raises
    ------
    ValueError
        For ``counts`` without a file, a file that does not load, or one for another grid (or,
        for a model calibrated through a pan/tilt camera, another spacing).

    """
    if values['observation.model'] != 'counts':
        return GaussianObservation(grid, fpoc)
    source = values['observation.file']
    if not source:
        raise ValueError('observation.model counts needs observation.file (a path or a shipped '
                         'count model name)')
    model = load_observation(source)
    if model.grid.shape != grid.shape:
        raise ValueError(f'observation.file {source!r} is a count model for a '
                         f'{model.grid.rows}x{model.grid.cols} grid, not this '
                         f'{grid.rows}x{grid.cols} grid')
    image = model.meta.get('image') or {}
    if image.get('view') == 'pan_tilt' and \
            abs(model.grid.spacing_deg - grid.spacing_deg) > 1e-9 * grid.spacing_deg:
        raise ValueError(f'observation.file {source!r} was calibrated on a pan/tilt grid of '
                         f'{model.grid.spacing_deg} deg/cell, not {grid.spacing_deg}')
    return model


@dataclass
class ControllerConfig:
    """
    Everything a controller derives from its parameters (``values`` keeps them all).

    ``policy`` is None when the many-target search does not use it and it cannot be built for
    this task (``policy_error`` says why; :func:`build_config`).

    ``warnings`` says what the configuration will not do (:func:`room_warnings`, then
    ``policy_warnings``, those of building the policy, kept with it while it is reused): the
    same for as long as their cause lasts, so that a node says each once (:func:`new_warnings`).
    """

    values: dict
    grid: Grid
    fpoc: object
    observation: object
    policy: object
    head: PanTiltMap
    settings: SearchSettings
    warnings: tuple = ()
    prior: np.ndarray | None = None
    policy_warnings: tuple = ()
    policy_error: str = ''

    @property
    def observation_label(self) -> str:
        """Describe the observation model for the log."""
        if self.values['observation.model'] == 'counts':
            model = self.observation
            return (f"count model {self.values['observation.file']!r} (K = "
                    f'{model.max_count + 1}; fpoc.* ignored)')
        return f'FPOC {self.fpoc.to_dict()}'

    @property
    def policy_label(self) -> str:
        """
        Describe the policy for the log and ``/diagnostics``.

        With ``search.targets: many`` only ``sweep`` on still targets is a policy the search
        follows (one pass); any other is kept but unused, the occupancy belief choosing by its
        own infomax (docs/design.md section 11.6): the label says so rather than name a policy
        not run.
        """
        v = self.values
        label = policy_label(v['policy.name'], v.get('policy.kernel'), v.get('policy.file', ''),
                             v.get('policy.action', 'argmax'))
        if policy_unused(v['policy.name'], self.settings):
            return f'occupancy infomax (policy.name {label} is not used with many targets)'
        return label

    def controller(self) -> GazeController:
        """Return a new :class:`ipomdp_gaze.search.gaze.GazeController` with this configuration."""
        v = self.values
        return GazeController(self.grid, self.observation, self.policy, self.settings,
                              v['settle_time_s'], v['seed'],
                              v.get('stamp_tolerance_s', STAMP_TOLERANCE_S), prior=self.prior)


def build_config(values: Mapping, build_policy: Callable, changed=None,
                 previous: ControllerConfig | None = None) -> ControllerConfig:
    """
    Derive a :class:`ControllerConfig` from the controller's parameter values.

    ``changed`` names the parameters that changed since ``previous`` (None: build everything);
    an unchanged count model or policy is taken from ``previous`` instead of loaded again.

    Raises
    ------
    ValueError
        Naming the parameter that is missing or refused (a missing one as ``KeyError``'s name).

    """
    try:
        grid = grid_from(values)
        fpoc = fpoc_from(values)
        observation_changed = changed is None or any(k in changed for k in OBSERVATION_KEYS)
        if previous is not None and not observation_changed and \
                values['observation.model'] == 'counts':
            observation = previous.observation
        else:
            observation = observation_from(values, grid, fpoc)
        head = head_from(values, grid)
        row_col_from(values, grid, 'start_row', 'start_col')
        settings = SearchSettings.from_parameters(values, grid=grid)
        prior = prior_from(values, grid)
        if settings.targets == 'many':
            check_many_settings(settings, grid)
        else:
            check_model_settings(settings, grid, observation)
        if 'room.dwell_s' in values:
            check_room_times(values['room.dwell_s'], values['room.recheck_period_s'])
        check_frame_id(str(values.get('room.frame_id', 'unset')))
        check_settle_time(values['settle_time_s'])
        policy_changed = changed is None or any(k in changed for k in POLICY_KEYS) or any(
            k.startswith('fpoc.') for k in changed) or observation_changed
        policy_error = ''
        if previous is not None and not policy_changed and previous.policy is not None:
            policy, policy_warnings = previous.policy, list(previous.policy_warnings)
        else:
            policy_warnings = []
            try:
                policy = build_policy(values['policy.name'], grid, observation,
                                      values.get('policy.kernel'), values.get('policy.file', ''),
                                      values.get('policy.action', 'argmax'),
                                      warn=policy_warnings.append)
            except ValueError as exc:
                # A setting with no effect is not refused: the many-target search does not
                # use the policy (greedy on a count model); one target would, and then the
                # policy is built again (previous.policy None) and refused with this reason.
                if not policy_unused(values['policy.name'], settings):
                    raise
                policy, policy_warnings, policy_error = None, [], str(exc)
    except KeyError as exc:
        raise ValueError(f'no controller parameter {exc}') from None
    return ControllerConfig(dict(values), grid, fpoc, observation, policy, head, settings,
                            tuple(room_warnings(settings) + policy_warnings), prior,
                            tuple(policy_warnings), policy_error)


def policy_unused(name: str, settings: SearchSettings) -> bool:
    """
    Whether the search ignores the policy ``name``: many targets, but for a still room's sweep.

    The occupancy belief chooses by its own infomax (docs/design.md section 11.6); only a
    ``sweep`` of still targets makes each search one pass of its poses (section 11.7).
    """
    return settings.targets == 'many' and (name != 'sweep' or settings.moving)


def new_warnings(new: ControllerConfig, old: ControllerConfig | None) -> list[str]:
    """
    Return the warnings of ``new`` that ``old`` (the configuration in force; None) did not have.

    A warning is said when its cause appears (at start-up, or by a change), not again on every
    change while the cause lasts, and again if it goes away and comes back.
    """
    said = set(old.warnings) if old is not None else set()
    return [text for text in new.warnings if text not in said]


def room_warnings(settings: SearchSettings) -> list[str]:
    """
    Say what a many-target search will not do with ``settings`` (warnings).

    ``search.stop_on_decision`` off is ignored: a still room's search ends when every cell is
    decided, and a moving room's never ends on a decision, whatever it says
    (:class:`ipomdp_gaze.search.many.OccupancySession` does not read it); then the moving
    room's (:func:`moving_room_warnings`).
    """
    out = []
    if settings.targets == 'many' and not settings.stop_on_decision:
        out.append('search.stop_on_decision false is ignored with search.targets many: a still '
                   "room's search ends when every cell is decided, a moving room's never ends "
                   'on a decision')
    return out + moving_room_warnings(settings)


def moving_room_warnings(settings: SearchSettings) -> list[str]:
    """
    Say what a many-target search of moving people will not do with ``settings`` (warnings).

    With motion the room is never done: nobody enters the belief but through its entry model
    (``motion.leave_prob``: people walk in from out of reach; ``motion.jump_prob``), so without
    one a person who comes in later is never found; and only ``motion.track_view`` peak or
    position keeps a person found in view for ``motion.dwell_s``.
    """
    if settings.targets != 'many' or not settings.moving:     # as the session's motion is
        return []
    out = []
    if settings.motion_leave_prob == 0 and settings.motion_jump_prob == 0:
        out.append('search.targets many with motion and no entry model: a person who comes in '
                   'after the start is never found (give motion.leave_prob, with absent.prior '
                   'for the people out of reach, or motion.jump_prob; room.recheck_period_s is '
                   'for a still room only)')
    if settings.motion_track_view == 'policy':
        out.append('motion.track_view policy: the people found are not kept in view in turn '
                   '(motion.dwell_s is not used); give motion.track_view peak or position')
    return out


def follow_config(core: GazeController, new: ControllerConfig, old_values: Mapping) -> None:
    """
    Make a controller core follow a new configuration: the node's and the replay's one way.

    The observation, the policy, the settings (a new ``search.targets`` starts a new search:
    :meth:`GazeController.configure`), the prior (from the next reset, or the search a switch to
    one target starts at once), the stamp tolerance, and the seed when it changed.
    """
    v = new.values
    core.set_observation(new.observation, new.settings)
    core.set_policy(new.policy)
    if new.prior is None:               # before a switch to many targets, which takes none
        core.set_prior(None)
    core.configure(new.settings, v['settle_time_s'], new.prior)   # a switch to one: at the prior
    core.set_prior(new.prior)
    if 'stamp_tolerance_s' in v:
        core.stamp_tolerance_s = v['stamp_tolerance_s']
    if v.get('seed') != old_values.get('seed'):
        core.reseed(v['seed'])
