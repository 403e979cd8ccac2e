# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Policy files: a learned policy with the task it was trained for, as YAML.

Format ``ipomdp_gaze/policy-v1`` (issue 3)::

    format: ipomdp_gaze/policy-v1
    grid: {rows: 7, cols: 7, spacing_deg: 0.42}
    fpoc: {model: human, noise_contrast: 0.2, foveal_dprime: 2.0}   # or, for a count model:
    observation: {model: counts, name: faces-420, sha256: ...}      # (docs/design.md 9)
    reward: infomax                  # or fixate_target
    family: conv                     # or logistic
    action: argmax                   # or sample; argmax if absent
    kernel: [[...], ...]             # conv: (2*rows-1) x (2*cols-1); authoritative
    radial: {squared_distance: [...], weight: [...]}   # conv, optional: must agree with kernel
    theta: [[...], ...]              # logistic: N x N, score_k = sum_j theta[k][j] * B_j
    training: {epochs: .., episodes_per_epoch: 150, learning_rate: .., beta: .., seed: ..}
    evaluation: {episodes: .., fixations_to_90: .., ci95: [.., ..]}

Required: ``format``, ``grid``, ``reward``, ``family``, the family's array (``kernel`` or
``theta``) and the observation model it was trained on: ``fpoc`` (the Gaussian model of that FPOC;
every file before count models) or ``observation`` (a count model named by its file's stem and the
SHA-256 of its tables, :func:`ipomdp_gaze.files.observation_file.fingerprint`). Loading uses
``yaml.safe_load`` only and names exactly what is wrong with a file (:class:`PolicyFileError`). A
source is a path or the name of a shipped kernel (``ipomdp_gaze/policies/kernels/<name>.yaml``,
e.g. ``human-7x7-infomax``), installed once as package data and found with
:mod:`importlib.resources`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
import math
from pathlib import Path
from typing import Callable
import warnings

from ipomdp_gaze.files.observation_file import fingerprint
from ipomdp_gaze.files.yaml_files import check_header, in_folder, plain, read_yaml, write_yaml
from ipomdp_gaze.model.belief import check_prior, prior_is_uniform
from ipomdp_gaze.model.fpoc import FPOC, fpoc_from_dict
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation, GaussianObservation
import numpy as np

from .conv import ACTIONS, check_score_scale, ConvPolicy, radial_bins
from .logistic import LogisticPolicy

FORMAT = 'ipomdp_gaze/policy-v1'
FAMILIES = ('conv', 'logistic')
REWARDS = ('infomax', 'fixate_target')
# Shipped kernels are package data of ipomdp_gaze.policies (a plain directory: never zipped).
KERNEL_DIR = Path(str(resources.files(__package__).joinpath('kernels')))
REQUIRED = ('format', 'grid', 'reward', 'family')
KEYS = REQUIRED + ('fpoc', 'observation', 'action', 'kernel', 'radial', 'theta', 'training',
                   'evaluation')
OBSERVATION_MODELS = ('counts',)
ARRAY_KEY = {'conv': 'kernel', 'logistic': 'theta'}
# Radial weights and the kernel agree when every entry is within this of its shared weight.
RADIAL_RTOL = 1e-6


class PolicyFileError(ValueError):
    """A policy file (or policy specification) that cannot be used; the message says why."""


class PolicyFileWarning(UserWarning):
    """A policy file that loads but was made for a different task than the one it is used on."""


@dataclass
class PolicySpec:
    """
    Everything a policy file holds, validated.

    ``kernel`` is set for the ``conv`` family, ``theta`` for ``logistic``; ``training`` and
    ``evaluation`` are the free-form records of how the policy was made and how well it did.
    """

    grid: Grid
    fpoc: FPOC | None
    reward: str
    family: str
    action: str = 'argmax'
    observation: dict | None = None
    kernel: np.ndarray | None = None
    theta: np.ndarray | None = None
    training: dict = field(default_factory=dict)
    evaluation: dict = field(default_factory=dict)
    path: Path | None = None

    @property
    def weights(self) -> np.ndarray:
        """Return the family's array: the kernel (conv) or theta (logistic)."""
        return self.kernel if self.family == 'conv' else self.theta

    def radial(self) -> dict | None:
        """Shared weights ``{'squared_distance', 'weight'}`` of a radial kernel, else None."""
        if self.family != 'conv' or np.shape(self.kernel) != self.grid.kernel_shape:
            return None
        values, bins = radial_bins(self.grid)
        weight = np.zeros(values.size)
        weight[bins.ravel()] = self.kernel.ravel()
        if not np.array_equal(weight[bins], self.kernel):
            return None
        return {'squared_distance': [int(v) for v in values],
                'weight': [float(w) for w in weight]}

    def make_policy(self, action: str | None = None):
        """Build the policy object (:class:`ConvPolicy` or :class:`LogisticPolicy`; ``.spec``)."""
        action = self.action if action is None else action
        if self.family == 'conv':
            policy = ConvPolicy(self.grid, self.kernel, action=action)
        else:
            policy = LogisticPolicy(self.grid, self.theta, action=action)
        if self.path is not None:
            policy.name = self.path.stem
        policy.spec = self          # checked again against a later prior without a second read
        return policy

    def to_dict(self) -> dict:
        """Return the YAML document as plain Python types (what :func:`save_policy` writes)."""
        doc = {'format': FORMAT, 'grid': self.grid.to_dict()}
        if self.observation is not None:
            doc['observation'] = plain(dict(self.observation))
        else:
            doc['fpoc'] = plain(self.fpoc.to_dict())
        doc.update({'reward': self.reward, 'family': self.family, 'action': self.action})
        if self.family == 'conv':
            doc['kernel'] = plain(self.kernel)
            radial = self.radial()
            if radial is not None:
                doc['radial'] = radial
        else:
            doc['theta'] = plain(self.theta)
        doc['training'] = plain(dict(self.training))
        doc['evaluation'] = plain(dict(self.evaluation))
        return doc


def shipped_kernels() -> list[str]:
    """Names of the kernels shipped with the package (stems of ``kernels/*.yaml``)."""
    return sorted(p.stem for p in KERNEL_DIR.glob('*.yaml'))


def resolve_source(source) -> Path:
    """
    Resolve a source: an existing path, or a shipped kernel name (with or without .yaml).

    Raises
    ------
    PolicyFileError
        If it is neither, listing the shipped names.

    """
    path = Path(source)
    if path.is_file():
        return path
    if path.is_dir():
        raise PolicyFileError(f'policy file {str(source)!r} is a folder, not a file')
    name = path.name[:-5] if path.name.endswith('.yaml') else path.name
    if str(source) in (name, name + '.yaml'):
        shipped = KERNEL_DIR / f'{name}.yaml'
        if shipped.is_file():
            return shipped
    names = ', '.join(shipped_kernels()) or 'none'
    raise PolicyFileError(f'policy file {str(source)!r} not found and not a shipped kernel '
                          f'name (shipped: {names})')


def _check_nesting(value, key: str, shape: tuple[int, int], what: str) -> None:
    """
    Refuse a list of lists that is too long or too deep before numpy walks it.

    YAML aliases let a file of a few hundred bytes describe a billion numbers (a list of aliases
    of a list of aliases ...); ``np.asarray`` would spend minutes and gigabytes on it. Only the
    expected ``shape[0] x shape[1]`` entries are ever looked at here.
    """
    if not isinstance(value, list) or not any(isinstance(row, list) for row in value):
        return
    if len(value) > shape[0]:
        raise PolicyFileError(f'{key} has {len(value)} rows but {what} needs {shape}')
    for row in value:
        if isinstance(row, list):
            if len(row) > shape[1]:
                raise PolicyFileError(f'{key} has a row of {len(row)} values but {what} needs '
                                      f'{shape}')
            if any(isinstance(x, (list, dict)) for x in row):
                raise PolicyFileError(f'{key} must be a 2-D list of lists, got more than 2 '
                                      f'dimensions')


def _array(doc: dict, key: str, shape: tuple[int, int], what: str) -> np.ndarray:
    value = doc[key]
    if value is None:
        raise PolicyFileError(f'{key} has no value: {what} needs a {shape[0]} x {shape[1]} list '
                              f'of lists of numbers')
    _check_nesting(value, key, shape, what)
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise PolicyFileError(f'{key} must be a list of lists of numbers '
                              f'(a {shape[0]} x {shape[1]} array)') from None
    if array.ndim != 2:
        raise PolicyFileError(f'{key} must be a 2-D list of lists, got {array.ndim} dimension(s)')
    if array.shape != shape:
        raise PolicyFileError(f'{key} has shape {array.shape} but {what} needs {shape}')
    bad = np.argwhere(~np.isfinite(array))
    if bad.size:
        r, c = (int(x) for x in bad[0])
        raise PolicyFileError(f'non-finite values in {key}: {bad.shape[0]} entries, the first '
                              f'at [{r}][{c}] is {array[r, c]}')
    return array


def _scale(weights: np.ndarray, key: str, axis: int | None = None) -> None:
    """Refuse weights whose scores can overflow (:func:`conv.check_score_scale`)."""
    try:
        check_score_scale(weights, key, axis)
    except ValueError as exc:
        raise PolicyFileError(str(exc)) from None


def _grid(block) -> Grid:
    if not isinstance(block, dict):
        raise PolicyFileError('grid must be a mapping {rows, cols, spacing_deg}')
    for key in ('rows', 'cols', 'spacing_deg'):
        if key not in block:
            raise PolicyFileError(f'missing key grid.{key}')
    unknown = sorted(set(block) - {'rows', 'cols', 'spacing_deg'})
    if unknown:
        raise PolicyFileError(f'unknown key grid.{unknown[0]}; valid: rows, cols, spacing_deg')
    for key in ('rows', 'cols'):
        value = block[key]
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise PolicyFileError(f'grid.{key} must be a positive integer, got {value!r}')
    spacing = block['spacing_deg']
    if isinstance(spacing, bool) or not isinstance(spacing, (int, float)) \
            or not math.isfinite(spacing) or spacing <= 0:
        raise PolicyFileError(f'grid.spacing_deg must be a positive number, got {spacing!r}')
    return Grid(block['rows'], block['cols'], float(spacing))


def _choice(doc: dict, key: str, valid: tuple[str, ...]) -> str:
    value = doc[key]
    if value not in valid:
        raise PolicyFileError(f"unknown {key} {value!r}; valid: {', '.join(valid)}")
    return value


def _check_radial(block, grid: Grid, kernel: np.ndarray) -> None:
    if not isinstance(block, dict):
        raise PolicyFileError('radial must be a mapping {squared_distance, weight}')
    for key in ('squared_distance', 'weight'):
        if key not in block:
            raise PolicyFileError(f'missing key radial.{key}')
    values, bins = radial_bins(grid)
    for key in ('squared_distance', 'weight'):
        value = block[key]
        if isinstance(value, list) and (len(value) > values.size or any(
                isinstance(x, (list, dict)) for x in value)):
            raise PolicyFileError(f'radial.{key} must be a list of {values.size} numbers')
    try:
        sq = np.asarray(block['squared_distance'], dtype=float)
        weight = np.asarray(block['weight'], dtype=float)
    except (TypeError, ValueError):
        raise PolicyFileError('radial.squared_distance and radial.weight must be lists of '
                              'numbers') from None
    if sq.shape != values.shape or not np.array_equal(sq, values):
        raise PolicyFileError(f'radial.squared_distance must list the {values.size} distinct '
                              f'squared distances of a {grid.rows}x{grid.cols} grid '
                              f'({", ".join(str(int(v)) for v in values[:4])}, ...)')
    if weight.shape != values.shape:
        raise PolicyFileError(f'radial.weight has {weight.size} values but '
                              f'radial.squared_distance has {values.size}')
    if not np.all(np.isfinite(weight)):
        raise PolicyFileError('non-finite values in radial.weight')
    expanded = weight[bins]
    tol = RADIAL_RTOL * max(1.0, float(np.max(np.abs(kernel))))
    off = np.argwhere(np.abs(expanded - kernel) > tol)
    if off.size:
        r, c = (int(x) for x in off[0])
        raise PolicyFileError(
            f'radial disagrees with kernel: squared_distance {int(values[bins[r, c]])} has '
            f'weight {float(expanded[r, c])!r} but kernel[{r}][{c}] is {float(kernel[r, c])!r}')


def _observation(block) -> dict:
    """Check the ``observation`` block: ``{model: counts, name: <stem>, sha256: <64 hex>}``."""
    if not isinstance(block, dict):
        raise PolicyFileError('observation must be a mapping {model, name, sha256}')
    unknown = sorted(str(k) for k in set(block) - {'model', 'name', 'sha256'})
    if unknown:
        raise PolicyFileError(f'unknown key observation.{unknown[0]}; valid: model, name, sha256')
    if block.get('model') not in OBSERVATION_MODELS:
        raise PolicyFileError(f"unknown observation.model {block.get('model')!r}; valid: "
                              f"{', '.join(OBSERVATION_MODELS)}")
    digest = block.get('sha256')
    if not (isinstance(digest, str) and len(digest) == 64
            and all(ch in '0123456789abcdef' for ch in digest)):
        raise PolicyFileError("observation.sha256 must be the 64 hex digits of the model's "
                              'fingerprint')
    if not isinstance(block.get('name', ''), str):
        raise PolicyFileError('observation.name must be a string')
    return dict(block)


def observation_block(model: CountObservation) -> dict:
    """Return what a policy file trained on ``model`` records of it."""
    return {'model': model.name, 'name': str(model.meta.get('source', '')),
            'sha256': fingerprint(model)}


def _record(doc: dict, key: str) -> dict:
    block = doc.get(key)
    if block is None:
        return {}
    if not isinstance(block, dict):
        raise PolicyFileError(f'{key} must be a mapping')
    if key == 'training':
        for name, kind in (('epochs', 'a whole number'), ('wall_seconds', 'a number')):
            if name not in block:
                continue                        # left out: train --resume starts from 0
            value = block[name]                 # what train --resume goes on from; null is
            number = isinstance(value, (int, float)) and not isinstance(value, bool)  # refused
            if not (number and math.isfinite(value) and value >= 0
                    and (name != 'epochs' or value == int(value))):
                raise PolicyFileError(f'training.{name} must be {kind} >= 0, got {value!r}')
        for name in SCENE_KEYS:                 # what evaluate and the node compare (check_scene)
            value = block.get(name)
            if value is not None and (isinstance(value, bool)
                                      or not isinstance(value, (int, float))):
                raise PolicyFileError(f'training.{name} must be a number, got {value!r}')
    if key == 'evaluation':
        f90 = block.get('fixations_to_90')
        if f90 is not None and (isinstance(f90, bool) or not isinstance(f90, (int, float))):
            raise PolicyFileError(f'evaluation.fixations_to_90 must be a number or null, '
                                  f'got {f90!r}')
        ci = block.get('ci95')
        if ci is not None and not (isinstance(ci, list) and len(ci) == 2 and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in ci)):
            raise PolicyFileError(f'evaluation.ci95 must be [low, high] or null, got {ci!r}')
    return dict(block)


def spec_from_dict(doc, path: Path | None = None) -> PolicySpec:
    """
    Validate a parsed policy document and build its :class:`PolicySpec`.

    Raises
    ------
    PolicyFileError
        Naming the first problem found.

    """
    check_header(doc, 'a policy file', FORMAT, REQUIRED, KEYS, PolicyFileError)
    grid = _grid(doc['grid'])
    if 'fpoc' not in doc and 'observation' not in doc:
        raise PolicyFileError('missing key fpoc (or observation, for a count model): a policy '
                              'file names the observation model it was trained on')
    if 'fpoc' in doc and 'observation' in doc:
        raise PolicyFileError('a policy file names one observation model: fpoc or '
                              'observation, not both')
    fpoc = observation = None
    if 'fpoc' in doc:
        try:
            fpoc = fpoc_from_dict(doc['fpoc'])
        except ValueError as exc:
            raise PolicyFileError(f'fpoc: {exc}') from None
    else:
        observation = _observation(doc['observation'])
    reward = _choice(doc, 'reward', REWARDS)
    family = _choice(doc, 'family', FAMILIES)
    action = 'argmax' if doc.get('action') is None else _choice(doc, 'action', ACTIONS)
    key = ARRAY_KEY[family]
    other = ARRAY_KEY['logistic' if family == 'conv' else 'conv']
    if key not in doc:
        raise PolicyFileError(f'missing key {key} (required for family {family})')
    if other in doc:
        raise PolicyFileError(f'family {family} takes {key}, not {other}')
    if family == 'logistic' and 'radial' in doc:
        raise PolicyFileError('family logistic takes theta, not radial')
    kernel = theta = None
    if family == 'conv':
        kernel = _array(doc, 'kernel', grid.kernel_shape, f'a {grid.rows}x{grid.cols} grid')
        _scale(kernel, 'kernel')
        if 'radial' in doc:
            _check_radial(doc['radial'], grid, kernel)
    else:
        n = grid.n_cells
        theta = _array(doc, 'theta', (n, n), f'a {grid.rows}x{grid.cols} grid')
        _scale(theta, 'theta', axis=1)
    training, evaluation = _record(doc, 'training'), _record(doc, 'evaluation')
    for key, block in (('training', training), ('evaluation', evaluation)):
        if block.get('prior') is not None:
            _check_prior(block['prior'], grid, f'{key}.prior')
    return PolicySpec(grid=grid, fpoc=fpoc, reward=reward, family=family, action=action,
                      observation=observation, kernel=kernel, theta=theta,
                      training=training, evaluation=evaluation, path=path)


def _check_prior(value, grid: Grid, name: str) -> None:
    """Refuse a recorded prior that is not rows x cols probabilities summing to 1."""
    try:
        values = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise PolicyFileError(f'{name} must be rows of numbers') from None
    if values.shape != grid.shape:
        raise PolicyFileError(f'{name}: a {grid.rows}x{grid.cols} grid needs {grid.rows} rows of '
                              f'{grid.cols} numbers, got shape {values.shape}')
    try:
        check_prior(values, grid.n_cells, grid.shape)
    except ValueError as exc:
        raise PolicyFileError(f'{name}: {exc}') from None


def load_policy_spec(source) -> PolicySpec:
    """
    Read and validate a policy file given by path or shipped kernel name.

    Raises
    ------
    PolicyFileError
        If the file is missing, is not YAML, or breaks the schema; the message names the file
        and the problem.

    """
    path = resolve_source(source)
    doc = read_yaml(path, PolicyFileError, shipped=in_folder(path, KERNEL_DIR))
    try:
        return spec_from_dict(doc, path=path)
    except PolicyFileError as exc:
        raise PolicyFileError(f'{path}: {exc}') from None


def _warn(message: str) -> None:
    warnings.warn(message, PolicyFileWarning, stacklevel=3)


def check_task(spec: PolicySpec, grid: Grid | None = None, fpoc=None,
               warn: Callable[[str], None] | None = None) -> None:
    """
    Check a policy against the task it is used on.

    A different number of rows or columns is an error (the policy cannot act on that grid); a
    different spacing or observation model (``fpoc``: an FPOC, a Gaussian or a count model) is
    allowed (the policy is used off its training task) and reported through ``warn(message)``
    (default: a :class:`PolicyFileWarning`).
    """
    warn = _warn if warn is None else warn
    where = f'{spec.path}: ' if spec.path is not None else ''
    if grid is not None:
        if (grid.rows, grid.cols) != (spec.grid.rows, spec.grid.cols):
            raise PolicyFileError(f'{where}policy is for a {spec.grid.rows}x{spec.grid.cols} '
                                  f'grid but the task grid is {grid.rows}x{grid.cols}')
        if not math.isclose(grid.spacing_deg, spec.grid.spacing_deg, rel_tol=1e-9):
            warn(f'{where}policy was trained at spacing_deg {spec.grid.spacing_deg} but is used '
                 f'at {grid.spacing_deg}')
    if isinstance(fpoc, GaussianObservation):
        fpoc = fpoc.fpoc
    trained = (f'FPOC {spec.fpoc.to_dict()}' if spec.observation is None else
               f"count model {spec.observation.get('name') or spec.observation['sha256'][:12]}")
    if isinstance(fpoc, CountObservation):
        if spec.observation is None or spec.observation['sha256'] != fingerprint(fpoc):
            name = fpoc.meta.get('source') or fingerprint(fpoc)[:12]
            warn(f'{where}policy was trained for {trained} but is used with count model {name}')
    elif fpoc is not None and (spec.observation is not None or fpoc != spec.fpoc):
        warn(f'{where}policy was trained for {trained} but is used with FPOC {fpoc.to_dict()}')


SCENE_KEYS = ('motion_sigma_cells', 'jump_prob', 'absent_prior', 'absent_rate')


def check_scene(spec: PolicySpec, scene: dict, warn: Callable[[str], None] | None = None) -> None:
    """
    Report (through ``warn``) each setting of docs/design.md section 7 that differs from training.

    ``scene`` maps :data:`SCENE_KEYS` to the values used now (missing or None: 0, the paper's
    task), and ``prior`` to rows of cells (missing, None or equal cells: uniform); a policy file
    records the non-zero ones, and a prior given to training, under ``training``.
    """
    warn = _warn if warn is None else warn
    where = f'{spec.path}: ' if spec.path is not None else ''
    for key in SCENE_KEYS:
        trained = float(spec.training.get(key) or 0.0)
        used = float(scene.get(key) or 0.0)
        if not math.isclose(trained, used, rel_tol=1e-9, abs_tol=1e-12):
            warn(f'{where}policy was trained with {key} {trained:g} but is used with {used:g}')
    check_training_prior(spec, scene.get('prior'), warn)


def check_training_prior(spec: PolicySpec, prior,
                         warn: Callable[[str], None] | None = None) -> None:
    """
    Report (through ``warn``) a policy used with another prior than its training's.

    ``prior`` is the one it is used with: rows of cells or probabilities (N,); None or equal
    cells is the uniform prior, as is a file without ``training.prior``. :func:`check_scene`
    says it with the other settings; ``evaluate --scenes`` (uniform) and the gaze controller
    (``belief.prior``) say it alone.
    """
    warn = _warn if warn is None else warn
    where = f'{spec.path}: ' if spec.path is not None else ''
    trained, used = spec.training.get('prior'), prior
    # A uniform prior given as rows of cells (train --prior of a uniform file) is the default.
    trained = None if prior_is_uniform(trained) else trained
    used = None if prior_is_uniform(used) else used
    if trained is None and used is not None:
        warn(f'{where}policy was trained with a uniform prior but is used with another')
    elif trained is not None and used is None:
        warn(f'{where}policy was trained with a prior that is not uniform but is used with '
             'the uniform one')
    elif trained is not None and not np.allclose(np.array(trained, dtype=float),
                                                 np.array(used, dtype=float).reshape(
                                                     np.shape(trained)),
                                                 rtol=1e-9, atol=1e-12):
        warn(f'{where}policy was trained with another prior than the one it is used with')


def load_policy(source, grid: Grid | None = None, fpoc: FPOC | None = None,
                action: str | None = None, warn: Callable[[str], None] | None = None,
                scene: dict | None = None):
    """
    Load a policy file (path or shipped name) as a policy object with ``select``.

    Parameters
    ----------
    source : str or Path
        A policy file or a shipped kernel name such as ``'camera-11x11-infomax'``.
    grid, fpoc : optional
        The task it will be used on: see :func:`check_task`.
    action : {'argmax', 'sample'}, optional
        Overrides the file's action rule.
    warn : callable, optional
        Receives a message when the policy is used off its training task.
    scene : dict, optional
        The scenes it will be used on: see :func:`check_scene` (None: not checked).

    """
    spec = load_policy_spec(source)
    check_task(spec, grid, fpoc, warn)
    if scene is not None:
        check_scene(spec, scene, warn)
    if action is not None and action not in ACTIONS:
        raise PolicyFileError(f"unknown action {action!r}; valid: {', '.join(ACTIONS)}")
    return spec.make_policy(action)


def save_policy(path, spec: PolicySpec) -> Path:
    """Write ``spec`` as a policy file (validated first, so what is written always loads)."""
    doc = spec.to_dict()
    spec_from_dict(doc)
    return write_yaml(path, doc)


def default_policy_file(model) -> str | None:
    """Return the shipped kernel whose ``observation.name`` is the model's name, or None."""
    name = model.meta.get('source')
    if not name:
        return None
    for kernel in shipped_kernels():
        spec = load_policy_spec(kernel)
        if spec.observation is not None and spec.observation.get('name') == name:
            return kernel
    return None
