# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The CLI's JSON records are strict JSON: no bare NaN or Infinity."""
import json
import math

from ipomdp_gaze.files import json_files
import pytest


def _strict(text):
    def refuse(constant):
        raise ValueError(f'not JSON: {constant}')
    return json.loads(text, parse_constant=refuse)


def test_a_number_that_is_not_finite_is_null_at_any_depth():
    record = {'mean': math.nan, 'rows': [1.5, math.inf, {'low': -math.inf, 'n': 3}],
              'pair': (math.nan, 2.0), 'name': 'walk', 'ok': True, 'none': None}
    assert _strict(json_files.dumps(record)) == {
        'mean': None, 'rows': [1.5, None, {'low': None, 'n': 3}], 'pair': [None, 2.0],
        'name': 'walk', 'ok': True, 'none': None}


def test_plain_json_would_have_written_nan():
    with pytest.raises(ValueError, match='NaN'):
        _strict(json.dumps({'mean': math.nan}))


def test_the_evaluation_of_walks_writes_strict_json(tmp_path):
    from ipomdp_gaze.cli import main
    out = tmp_path / 'walk.json'
    assert main(['evaluate', '--scenes', 'pan-tilt', '--motion', 'walk', '--episodes', '1',
                 '--walk-duration-s', '2', '--json', str(out), '--quiet']) == 0
    text = out.read_text()
    assert 'NaN' not in text and 'Infinity' not in text
    summary = _strict(text)
    assert summary


def test_a_folder_is_writable_when_a_file_can_be_made_there(tmp_path):
    from ipomdp_gaze.files.writable import folder_writable
    assert folder_writable(tmp_path)
    assert list(tmp_path.iterdir()) == []           # the probe leaves nothing behind
    assert not folder_writable('/proc')             # a virtual file system, even for root


def test_numpy_numbers_and_arrays_are_written_as_json():
    import numpy as np
    record = {'p': np.float32(0.25), 'n': np.int64(3), 'ok': np.bool_(True),
              'cells': np.array([[1, 2], [3, 4]]), 'mean': np.float64('nan'),
              'rates': np.array([0.5, np.inf])}
    assert _strict(json_files.dumps(record)) == {'p': 0.25, 'n': 3, 'ok': True,
                                                 'cells': [[1, 2], [3, 4]], 'mean': None,
                                                 'rates': [0.5, None]}


def test_find_log_and_json_are_strict_json(tmp_path, monkeypatch):
    """``find --log`` wrote the session's events with Python's ``json``: an infinite sum bare."""
    import dataclasses
    from pathlib import Path

    import ipomdp_gaze.commands.find as find
    from ipomdp_gaze.cli import main
    import skimage.data
    searched = find.search_one

    def search_one(*args, **kwargs):
        extra = {'event': 'frame', 'frame': {'sum': math.inf, 'peak': math.nan}}
        return [dataclasses.replace(r, log=tuple(r.log) + (extra,), seconds=math.inf)
                for r in searched(*args, **kwargs)]
    monkeypatch.setattr(find, 'search_one', search_one)
    log, out = tmp_path / 'find.log', tmp_path / 'find.json'
    photo = Path(skimage.data.__file__).parent / 'astronaut.png'
    assert main(['find', str(photo), '--scan', 'fovea', '--log', str(log), '--json',
                 str(out)]) == 0
    events = _strict(log.read_text())['events']
    assert events[-1] == {'event': 'frame', 'frame': {'sum': None, 'peak': None}}
    entry = _strict(out.read_text())['images'][0]
    assert entry['seconds'] is None and entry['decision'] == 'found'
