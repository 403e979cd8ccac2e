# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The report generators (``make pan-tilt``, ``make models``) run end to end on a few scenes."""
import gzip
import json
from pathlib import Path
import subprocess
import sys

BENCH = Path(__file__).resolve().parents[1] / 'bench'


def test_pan_tilt_report_runs_on_a_few_scenes_and_writes_its_tables(tmp_path):
    """``bench/pan_tilt.py`` (docs/pan_tilt.md) searches, scores and writes the report."""
    out, record = tmp_path / 'pan_tilt.md', tmp_path / 'pan_tilt.json.gz'
    run = subprocess.run(
        [sys.executable, str(BENCH / 'pan_tilt.py'), '--faces', '3', '--empty', '2',
         '--second-faces', '2', '--second-empty', '1', '--processes', '1',
         '--json', str(record), '--out', str(out)],
        capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    text = out.read_text()
    assert '### Scenes with a face' in text and '### Empty scenes' in text
    assert 'A second camera' in text
    data = json.loads(gzip.decompress(record.read_bytes()))
    main = data['runs']['main']['results']
    for name, group in main.items():
        assert len(group) == 5, name                   # 3 with a face and 2 empty, every searcher
        assert sum(r['face_cell'] is None for r in group) == 2


def test_models_script_refuses_an_unknown_model_with_one_line():
    """``bench/models.py`` names the models it knows when given another."""
    run = subprocess.run([sys.executable, str(BENCH / 'models.py'), '--only', 'faces-999'],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert 'unknown model(s) faces-999' in run.stderr and 'Traceback' not in run.stderr
