# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Observation files: a count model with the task it was measured on, as YAML.

Format ``ipomdp_gaze/observation-v1`` (docs/design.md section 9)::

    format: ipomdp_gaze/observation-v1
    model: counts
    grid: {rows: 21, cols: 21}            # spacing_deg too for a pan/tilt grid
    image: {width: 420, height: 420}      # the image size it was calibrated at
    fovea: {...}                          # the fovea settings it was measured with
    detector: {...}                       # the detector settings it was measured with
    cells: {kind: score_bins, ...}        # optional: what a cell's observation is (absent:
                                          # the clipped count; ipomdp_gaze.model.cell_observation)
    target: [[[p0, p1, ...], ...], ...]   # P(c | target, |dr|, |dc|): rows x cols x K
    null: [[[...]]]                       # P(c | no target, |dr|, |dc|): rows x cols x K
    scan: {target: [...], null: [...]}    # optional: P(c | target), P(c | no target) of the
                                          # one-time whole-image scan (fovea scan_once), K each
    calibration: {...}                    # free-form record of how it was measured

Loading uses ``yaml.safe_load`` only and names exactly what is wrong
(:class:`ObservationFileError`, one line): missing or unknown keys, shapes, probabilities that are
not finite, negative or do not sum to 1. A source is a path or the name of a shipped model
(``ipomdp_gaze/models/<name>.yaml``, package data found with :mod:`importlib.resources`).
"""
from __future__ import annotations

import hashlib
from importlib import resources
import math
from pathlib import Path
import re

from ipomdp_gaze.files.yaml_files import check_header, check_record, in_folder, plain, read_yaml, \
    write_yaml
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import PinholeCamera
from ipomdp_gaze.model.observation import CountObservation
import numpy as np

FORMAT = 'ipomdp_gaze/observation-v1'
# What a policy file says it is (ipomdp_gaze.policies.policy_file.FORMAT; not imported: the
# core imports no policies), so one given as a count model is named for what it is.
POLICY_FORMAT = 'ipomdp_gaze/policy-v1'
MODELS = ('counts',)
REQUIRED = ('format', 'model', 'grid', 'target', 'null')
KEYS = REQUIRED + ('image', 'fovea', 'detector', 'cells', 'calibration', 'scan')
RECORDS = ('image', 'fovea', 'detector', 'cells', 'calibration')
# The YAML types of the records' keys checked as the file is read (check_record): the detector's
# and the fovea's own keys are checked where they are known (ipomdp_gaze.vision), calibration is
# free-form.
RECORD_TYPES = {'image': {'width': 'integer', 'height': 'integer', 'view': 'text',
                          'camera': 'mapping'},
                'detector': {'kind': 'text'}, 'fovea': {}, 'cells': {}}
CAMERA_TYPES = {'width': 'integer', 'height': 'integer', 'K': 'matrix3x3'}
MODEL_DIR = Path(str(resources.files('ipomdp_gaze').joinpath('models')))
# Counts per cell a file may tabulate (K); far above any detector's clipped count.
MAX_K = 256


class ObservationFileError(ValueError):
    """An observation file that cannot be used; the message says why."""


def shipped_observations() -> list[str]:
    """Names of the observation models shipped with the package."""
    return sorted(p.stem for p in MODEL_DIR.glob('*.yaml')) if MODEL_DIR.is_dir() else []


def shipped_image_models(detector: str = 'haar') -> list[str]:
    """
    Return the shipped models ``find`` chooses from, one per image size.

    ``faces-<size>`` for the Haar cascade, ``faces-<size>-yunet`` for ``detector='yunet'``.

    Other shipped models are for other uses: ``faces-<size>-nmpt`` are NMPT's reference fovea
    (reported in docs/faces.md, not the default), and a pan/tilt model tiles a head's grid, not
    an image.
    """
    suffix = '' if detector == 'haar' else f'-{detector}'
    return [name for name in shipped_observations()
            if re.fullmatch(r'faces-\d+' + re.escape(suffix), name)]


def resolve_source(source) -> Path:
    """Return an existing path, or the file of a shipped model name (with or without .yaml)."""
    path = Path(source)
    if path.is_file():
        return path
    if path.is_dir():
        raise ObservationFileError(f'observation file {str(source)!r} is a folder, not a file')
    name = path.name[:-5] if path.name.endswith('.yaml') else path.name
    if str(source) in (name, name + '.yaml') and (MODEL_DIR / f'{name}.yaml').is_file():
        return MODEL_DIR / f'{name}.yaml'
    names = ', '.join(shipped_observations()) or 'none'
    raise ObservationFileError(f'observation file {str(source)!r} not found and not a shipped '
                               f'model name (shipped: {names})')


def fingerprint(model: CountObservation) -> str:
    """SHA-256 of the tables (float64, C order; the scan's too): names a model in a policy file."""
    digest = hashlib.sha256()
    tables = [model.p_target, model.p_null]
    if getattr(model, 'has_scan', False):
        tables += [model.scan_target, model.scan_null]
    for table in tables:
        digest.update(np.ascontiguousarray(table, dtype=np.float64).tobytes())
    return digest.hexdigest()


def _grid(block) -> Grid:
    if not isinstance(block, dict):
        raise ObservationFileError('grid must be a mapping {rows, cols[, spacing_deg]}')
    unknown = sorted(set(block) - {'rows', 'cols', 'spacing_deg'})
    if unknown:
        raise ObservationFileError(f'unknown key grid.{unknown[0]}; valid: rows, cols, '
                                   f'spacing_deg')
    for key in ('rows', 'cols'):
        value = block.get(key)
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ObservationFileError(f'grid.{key} must be a positive integer, got {value!r}')
    spacing = block.get('spacing_deg', 1.0)
    if isinstance(spacing, bool) or not isinstance(spacing, (int, float)) \
            or not math.isfinite(spacing) or spacing <= 0:
        raise ObservationFileError(f'grid.spacing_deg must be a positive number, got '
                                   f'{spacing!r}')
    return Grid(block['rows'], block['cols'], float(spacing))


def _table(doc: dict, key: str, grid: Grid) -> np.ndarray:
    """Read a rows x cols x K list of lists, refused before numpy walks an oversized one."""
    value = doc[key]
    shape = f'{grid.rows} x {grid.cols} x K'
    if not isinstance(value, list) or len(value) != grid.rows:
        raise ObservationFileError(f'{key} must be a {shape} list of lists (one row per |dr| '
                                   f'in 0..{grid.rows - 1})')
    for row in value:
        if not isinstance(row, list) or len(row) != grid.cols:
            raise ObservationFileError(f'{key} must be a {shape} list of lists (one entry per '
                                       f'|dc| in 0..{grid.cols - 1})')
        for cell in row:
            if not isinstance(cell, list) or not 2 <= len(cell) <= MAX_K or any(
                    isinstance(x, (list, dict, bool)) or not isinstance(x, (int, float))
                    for x in cell):
                raise ObservationFileError(f'{key} must hold, per offset, a list of 2 to {MAX_K} '
                                           f'probabilities (one per count)')
    try:
        return np.asarray(value, dtype=float)
    except ValueError:
        raise ObservationFileError(f'{key} must have the same number of counts K at every '
                                   f'offset') from None


def _scan(block) -> tuple:
    """Read the optional ``scan`` block: ``(target, null)`` lists of probabilities, or Nones."""
    if block is None:
        return None, None
    if not isinstance(block, dict) or set(block) != {'target', 'null'}:
        raise ObservationFileError('scan must be a mapping {target, null} of count '
                                   'probabilities')
    for key in ('target', 'null'):
        value = block[key]
        if not isinstance(value, list) or not 2 <= len(value) <= MAX_K or any(
                isinstance(x, (list, dict, bool)) or not isinstance(x, (int, float))
                for x in value):
            raise ObservationFileError(f'scan.{key} must be a list of 2 to {MAX_K} '
                                       f'probabilities (one per count)')
    return block['target'], block['null']


def _check_record(block: dict, key: str) -> None:
    """Check the types of a record's keys (its camera's too): ObservationFileError if wrong."""
    try:
        if key in RECORD_TYPES:
            check_record(block, RECORD_TYPES[key], key)
        if key == 'image' and block.get('camera') is not None:
            check_record(block['camera'], CAMERA_TYPES, 'image.camera')
            try:                # the camera as a whole: its keys, K's zeros (here, not in use)
                PinholeCamera.from_dict(block['camera'])
            except ValueError as exc:
                raise ValueError(f'image.camera: {exc}') from None
    except ValueError as exc:
        raise ObservationFileError(str(exc)) from None


def model_from_dict(doc, source: str = '') -> CountObservation:
    """
    Validate a parsed observation document and build its model.

    Raises
    ------
    ObservationFileError
        Naming the first problem found.

    """
    check_header(doc, 'an observation file', FORMAT, REQUIRED, KEYS, ObservationFileError)
    if doc['model'] not in MODELS:
        raise ObservationFileError(f"unknown model {doc['model']!r}; valid: {', '.join(MODELS)}")
    grid = _grid(doc['grid'])
    meta = {}
    for key in RECORDS:
        block = doc.get(key)
        if block is not None and not isinstance(block, dict):
            raise ObservationFileError(f'{key} must be a mapping')
        if block is not None:
            _check_record(block, key)
            meta[key] = dict(block)
    target, null = _table(doc, 'target', grid), _table(doc, 'null', grid)
    scan_target, scan_null = _scan(doc.get('scan'))
    try:
        model = CountObservation(grid, target, null, meta, scan_target, scan_null)
    except ValueError as exc:
        raise ObservationFileError(str(exc)) from None
    if 'cells' in meta:
        from ipomdp_gaze.model.cell_observation import cell_observation_of
        try:
            cell_observation_of(meta, model.max_count + 1)
        except (TypeError, ValueError) as exc:
            raise ObservationFileError(f'cells: {exc}') from None
    if source:
        model.meta['source'] = source
    return model


def load_observation(source) -> CountObservation:
    """
    Read and validate an observation file given by path or shipped name.

    Raises
    ------
    ObservationFileError
        If the file is missing, is not YAML or breaks the format; the message names the file.

    """
    path = resolve_source(source)
    doc = read_yaml(path, ObservationFileError, shipped=in_folder(path, MODEL_DIR))
    if isinstance(doc, dict) and doc.get('format') == POLICY_FORMAT:
        raise ObservationFileError(f'{path} is a policy file ({POLICY_FORMAT}), not an '
                                   f'observation model ({FORMAT}): pass it as --policy-file '
                                   f'(node: policy.file)')
    try:
        return model_from_dict(doc, source=path.stem)
    except ObservationFileError as exc:
        raise ObservationFileError(f'{path}: {exc}') from None


def model_to_dict(model: CountObservation) -> dict:
    """Return the YAML document of a count model (plain Python types)."""
    grid = {'rows': model.grid.rows, 'cols': model.grid.cols}
    if model.grid.spacing_deg != 1.0:
        grid['spacing_deg'] = model.grid.spacing_deg
    doc = {'format': FORMAT, 'model': model.name, 'grid': grid}
    for key in RECORDS[:4]:
        if key in model.meta:
            doc[key] = plain(model.meta[key])
    doc['target'] = model.p_target.tolist()
    doc['null'] = model.p_null.tolist()
    if model.has_scan:
        doc['scan'] = {'target': model.scan_target.tolist(),
                       'null': model.scan_null.tolist()}
    if 'calibration' in model.meta:
        doc['calibration'] = plain(model.meta['calibration'])
    return doc


def save_observation(path, model: CountObservation) -> Path:
    """Write ``model`` as an observation file (validated first, so what is written loads)."""
    doc = model_to_dict(model)
    model_from_dict(doc)
    return write_yaml(path, doc)
