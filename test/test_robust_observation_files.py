# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Observation files fuzzed (hypothesis), as the policy files are: every bad one is one clear line.

Starting from a valid count model, the files are truncated anywhere, given tables of the wrong
shape, NaN, inf, negative, text or null entries, huge tables (a K of 257, thousands of rows, an
alias bomb of 10^9 numbers in a few hundred bytes), YAML tags (``!!python/object`` must never
run), wrong grids and format lines, missing and unknown keys, and records (image, fovea,
detector) with wrong types. ``load_observation`` must either return a model or raise
``ObservationFileError`` with one line that names the file; the foveal detector's start-up
(``build_setup``) must either build or raise a one-line ``ValueError``, and the detector node
must exit 1 with that line and no traceback. Nothing else may escape.
"""
from __future__ import annotations

import copy
import os
from pathlib import Path
import subprocess
import sys

from conftest import REPO
from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
from ipomdp_gaze.files.observation_file import (load_observation, model_to_dict,
                                                ObservationFileError, resolve_source)
import pytest
import yaml

EXAMPLES = int(os.environ.get('PROPERTY_EXAMPLES', '60'))
FUZZ = settings(deadline=None, max_examples=EXAMPLES,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.function_scoped_fixture])
BAD_VALUES = [float('nan'), float('inf'), -float('inf'), -0.5, 2.0, 'x', None, True, [], {},
              1e308, -1e-300]
MARKER = Path(os.environ.get('TMPDIR', '/tmp')) / 'ipomdp-gaze-unsafe-yaml-loader-was-used'


def _small_doc() -> dict:
    """Return a valid 3x3 count model (K = 3) with the records of the shipped fovea model."""
    shipped = model_to_dict(load_observation('faces-420-nmpt'))
    p = [[[0.7, 0.2, 0.1]] * 3 for _ in range(3)]
    q = [[[0.9, 0.08, 0.02]] * 3 for _ in range(3)]
    doc = {'format': shipped['format'], 'model': 'counts', 'grid': {'rows': 3, 'cols': 3},
           'target': p, 'null': q}
    for key in ('image', 'fovea', 'detector'):
        doc[key] = shipped[key]
    return doc


BASE = _small_doc()
BASE_TEXT = yaml.safe_dump(BASE, sort_keys=False)


def _bomb() -> str:
    bomb = '&a0 [' + ', '.join(['0.1'] * 10) + ']'
    for level in range(1, 9):
        bomb = f'&a{level} [{bomb}, ' + ', '.join([f'*a{level - 1}'] * 9) + ']'
    return bomb


@st.composite
def bad_documents(draw):
    """Return the text of an observation file, most of them broken in one way or more."""
    kind = draw(st.sampled_from(['truncate', 'table-value', 'table-shape', 'huge-k',
                                 'huge-rows', 'bomb', 'tag', 'grid', 'keys', 'records',
                                 'scan', 'deep']))
    doc = copy.deepcopy(BASE)
    if kind == 'truncate':
        return BASE_TEXT[:draw(st.integers(0, len(BASE_TEXT)))]
    table = draw(st.sampled_from(['target', 'null']))
    if kind == 'table-value':
        for _ in range(draw(st.integers(1, 4))):
            r, c, k = (draw(st.integers(0, 2)) for _ in range(3))
            doc[table][r][c] = list(doc[table][r][c])
            doc[table][r][c][k] = draw(st.sampled_from(BAD_VALUES))
    elif kind == 'table-shape':
        numbers = st.floats(0, 1) | st.sampled_from(BAD_VALUES)
        doc[table] = draw(st.recursive(numbers, lambda inner: st.lists(inner, max_size=5),
                                       max_leaves=40))
    elif kind == 'huge-k':
        doc[table][0][0] = [1.0 / 257] * draw(st.sampled_from([257, 1000, 5000]))
    elif kind == 'huge-rows':
        rows = draw(st.sampled_from([4, 1000, 5000]))
        doc[table] = [[[0.5, 0.5]] * 3] * rows
    elif kind == 'bomb':
        text = yaml.safe_dump({k: v for k, v in doc.items() if k != table}, sort_keys=False)
        return text + f'{table}: {_bomb()}\n'
    elif kind == 'tag':
        tag = draw(st.sampled_from([
            f'!!python/object/apply:os.system ["touch {MARKER}"]',
            '!!python/name:os.system', '!!binary aGVsbG8=', '!!set {a, b}',
            '!!timestamp 2001-12-14', '!!python/tuple [1, 2]', '!custom 3']))
        key = draw(st.sampled_from(['target', 'grid', 'image', 'format', 'detector']))
        text = yaml.safe_dump({k: v for k, v in doc.items() if k != key}, sort_keys=False)
        return text + f'{key}: {tag}\n'
    elif kind == 'grid':
        key = draw(st.sampled_from(['rows', 'cols', 'spacing_deg', 'depth']))
        doc['grid'][key] = draw(st.sampled_from(
            [0, -1, 10 ** 9, 2 ** 63, 2.5, 'a', None, True, float('nan'), [3], 4]))
    elif kind == 'keys':
        key = draw(st.sampled_from(sorted(doc) + ['unknown', 'scan']))
        if key in doc and draw(st.booleans()):
            del doc[key]
        else:
            doc[key] = draw(st.sampled_from(BAD_VALUES + ['ipomdp_gaze/observation-v9']))
    elif kind == 'records':
        key = draw(st.sampled_from(['image', 'fovea', 'detector']))
        block = dict(doc[key]) if isinstance(doc[key], dict) else {}
        if block and draw(st.booleans()):
            field = draw(st.sampled_from(sorted(block)))
            block[field] = draw(st.sampled_from(BAD_VALUES + [-3, 0, 10 ** 12, 'none.xml',
                                                              [1, 2, 3], {'a': 1}]))
            doc[key] = block
        else:
            doc[key] = draw(st.sampled_from(BAD_VALUES))
    elif kind == 'scan':
        doc['scan'] = draw(st.sampled_from([
            {'target': [0.5, 0.5], 'null': [0.5, 0.5]}, {'target': [0.5, 0.5]},
            {'target': [float('nan'), 1.0], 'null': [0.5, 0.5]}, [0.5, 0.5],
            {'target': [0.2] * 5, 'null': [0.5, 0.5]}, {'target': [1.0] * 300, 'null': [1.0]}]))
    elif kind == 'deep':
        return BASE_TEXT + 'calibration: ' + '[' * 20000 + ']' * 20000 + '\n'
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True)


def _check_one_line(message: str, path: Path) -> None:
    assert '\n' not in message and message.startswith(f'{path}: '), message
    assert 'Traceback' not in message


@FUZZ
@given(bad_documents())
def test_a_fuzzed_observation_file_loads_or_gives_one_line(tmp_path_factory, text):
    path = tmp_path_factory.mktemp('obs') / 'fuzzed.yaml'
    path.write_text(text)
    try:
        model = load_observation(str(path))
    except ObservationFileError as exc:
        _check_one_line(str(exc), path)
    else:
        assert model.grid.n_cells >= 1
    assert not MARKER.exists()


@FUZZ
@given(bad_documents())
def test_the_detector_setup_builds_or_gives_one_line(tmp_path_factory, text):
    from ipomdp_gaze.vision.detection import build_setup
    path = tmp_path_factory.mktemp('obs') / 'fuzzed.yaml'
    path.write_text(text)
    try:
        setup = build_setup('fovea', str(path))
    except ValueError as exc:
        assert '\n' not in str(exc), str(exc)
    else:
        assert setup.fovea is not None
    assert not MARKER.exists()


@pytest.mark.ros
@pytest.mark.parametrize('case', ['truncated', 'nan', 'tag', 'fovea-type'])
def test_the_detector_node_exits_1_with_one_line(ros_env, tmp_path, case):
    doc = copy.deepcopy(BASE)
    path = tmp_path / f'{case}.yaml'
    if case == 'truncated':
        text = BASE_TEXT[:len(BASE_TEXT) // 2]
    elif case == 'tag':
        text = yaml.safe_dump(doc, sort_keys=False) + f'image: !!python/object/apply:os.system ' \
            f'["touch {MARKER}"]\n'
        text = text.replace('image:', 'imag_:', 1)
    else:
        if case == 'nan':
            doc['target'][1][1] = [float('nan'), 0.5, 0.5]
        else:
            doc['fovea'] = {**doc['fovea'], 'windows': 'many'}
        text = yaml.safe_dump(doc, sort_keys=False)
    path.write_text(text)
    proc = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.nodes.detector', '--ros-args',
                           '-p', f'observation.file:={path}'], cwd=REPO, env=ros_env,
                          capture_output=True, text=True, timeout=120)
    lines = [line for line in (proc.stdout + proc.stderr).splitlines()
             if line.startswith('foveal_detector: error: ')]
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert len(lines) == 1 and 'Traceback' not in proc.stderr, proc.stderr
    assert str(resolve_source(str(path))) in lines[0] or 'fovea' in lines[0], lines[0]
    assert not MARKER.exists()
