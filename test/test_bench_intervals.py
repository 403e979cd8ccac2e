# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The bench scripts print a missing bootstrap interval as ``-``, whatever the number of episodes.

A bootstrap interval is None from fewer than ``MIN_EPISODES`` episodes (scenes, rooms); the
scripts printed it as ``[nan, nan]``, as "beyond the horizon" or as "one room", or failed.
``MIN_EPISODES`` is raised here to 3 for runs of 2, so that "below" is not only "one".
"""
from __future__ import annotations

import gzip
import json
from pathlib import Path

from conftest import bench_module
import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / 'bench'


@pytest.fixture(params=[(1, None), (2, 3)], ids=['one', 'two-below-three'])
def few(request, monkeypatch):
    """Return a number of episodes below MIN_EPISODES (raised to 3 for the run of 2)."""
    episodes, minimum = request.param
    if minimum is not None:
        from ipomdp_gaze.drivers import scene_report
        from ipomdp_gaze.simulation import evaluation
        monkeypatch.setattr(evaluation, 'MIN_EPISODES', minimum)
        monkeypatch.setattr(scene_report, 'MIN_EPISODES', minimum)
    return episodes


def _no_bad_words(text: str) -> None:
    for bad in ('nan', 'beyond the horizon', 'one room', '[   -  ]'):
        assert bad not in text, (bad, text)


def test_format_interval():
    from ipomdp_gaze.simulation.evaluation import format_interval, MIN_EPISODES
    assert format_interval((1.0, 2.5)) == '[1.000, 2.500]'
    assert format_interval((-0.25, 0.5), '+.2f') == '[-0.25, +0.50]'
    assert format_interval(None) == '-'
    assert format_interval(None, episodes=MIN_EPISODES - 1) == '-'
    assert format_interval(None, episodes=MIN_EPISODES) == '[beyond the horizon]'


def test_planner_vs_greedy(few, capsys):
    bench_module('planner_vs_greedy').main(['--episodes', str(few), '--policies',
                                            'elm,tempered', '--jobs', '1', '--quiet'])
    out = capsys.readouterr().out
    _no_bad_words(out)
    lines = [line for line in out.splitlines() if 'indicator' in line or 'expected' in line]
    assert len(lines) == 6
    assert all(line.endswith(' -') or line.endswith('never') or 'not defined' in line
               for line in lines), lines
    assert any(line.endswith(' -') for line in lines)


def test_bench_planner(few, capsys):
    bench_module('bench_planner').main(['--episodes', str(few), '--episodes-fast', str(few),
                                        '--bootstrap', '50', '--skip-planner',
                                        '--tempered-seeds', '2'])
    out = capsys.readouterr().out
    _no_bad_words(out)
    rows = [line for line in out.splitlines() if line.startswith(('elm ', 'tempered_elm '))]
    assert rows and all('-' in row.split() or 'never' in row for row in rows), rows
    pooled = next(line for line in out.splitlines() if 'pooled' in line)
    # The seeds' differences are there: the pooled mean is printed, with no interval.
    assert pooled.split().count('-') == 2 or 'never' in pooled, pooled


def test_bench_training(few, capsys, tmp_path):
    bench_module('bench_training').main(['--epochs', '1', '--eval-every', '1',
                                         '--eval-episodes', '1', '--final-episodes', str(few)])
    out = capsys.readouterr().out
    _no_bad_words(out)
    conv = next(line for line in out.splitlines() if line.startswith('conv:'))
    assert ' -, minus ELM ' in conv or 'fixations to 90% never' in conv, conv


def _cut(record: dict, keep) -> dict:
    """Return the record with only the scenes (rooms) that ``keep(rows)`` keeps."""
    import copy
    record = copy.deepcopy(record)
    for run in record['runs'].values():
        for block in ('results', 'rooms', 'bounds'):
            if block in run:
                run[block] = {name: keep(rows) for name, rows in run[block].items()}
    return record


def test_pan_tilt_page(few, tmp_path):
    pan_tilt = bench_module('pan_tilt')
    record = json.loads(gzip.decompress((ROOT / 'docs' / 'data' / 'pan_tilt.json.gz')
                                        .read_bytes()))
    record.pop('ros', None)
    record.pop('ros_empty', None)
    faces = sorted({r['index'] for r in record['runs']['main']['results']['shipped']
                    if r['has_face']})[:few]
    empty = sorted({r['index'] for r in record['runs']['main']['results']['shipped']
                    if not r['has_face']})[:few]

    def keep(rows):
        return [r for r in rows if r['index'] in (faces if r['has_face'] else empty)]
    out = tmp_path / 'pan_tilt.md'
    pan_tilt.write_page(_cut(record, keep), out)
    text = out.read_text()
    _no_bad_words(text)
    assert 'lowest bound -)' in text
    assert "- MAP right minus the sweep's" in text and '4: ' in text
    checks = next(line for line in text.splitlines() if "MAP right minus the sweep's" in line)
    assert '[' not in checks.split(':', 1)[1], checks


def test_rooms_page(few, tmp_path):
    rooms = bench_module('rooms')
    record = json.loads(gzip.decompress((ROOT / 'docs' / 'data' / 'rooms.json.gz')
                                        .read_bytes()))
    # rooms with faces, among the first the every-view bounds ran on too
    first = record['runs']['25 deg']['rooms']['pass-many']
    kept = [r['index'] for r in first if r['face_cells'] and r['index'] < 100][:few]
    out = tmp_path / 'rooms.md'
    rooms.write_page(_cut(record, lambda rows: [r for r in rows if r['index'] in kept]), out)
    text = out.read_text()
    _no_bad_words(text)
    line = next(line for line in text.splitlines() if line.startswith('Paired over the same'))
    assert 'faces found per room ' in line and '[' not in line, line
