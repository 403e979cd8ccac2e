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


def test_figure_labels_of_a_dense_cluster_neither_overlap_nor_leave_the_axes():
    """``bench/faces.py`` labels its speed-accuracy points so that each stays readable."""
    import importlib.util
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from matplotlib.text import Text
    import numpy as np
    spec = importlib.util.spec_from_file_location('bench_faces', BENCH / 'faces.py')
    faces = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(faces)
    fig, ax = plt.subplots(figsize=(6, 4))
    rng = np.random.default_rng(0)
    points = [(3 + rng.random(), 0.95 + 0.03 * rng.random()) for _ in range(12)]  # one cluster
    points += [(1.0, 0.4), (30.0, 0.5)]                                           # near edges
    ax.plot(*zip(*points), 'o')
    ax.set(xscale='log', xlim=(0.8, 40), ylim=(0.3, 1.05))
    fig.tight_layout()
    faces._place_labels(fig, [(ax, f'searcher number {i} @0.99', p) for i, p in enumerate(points)])
    renderer = fig.canvas.get_renderer()
    boxes = []
    for note in ax.texts:
        note.update_positions(renderer)
        boxes.append(Text.get_window_extent(note, renderer))
    assert len(boxes) == len(points)
    inside = ax.get_window_extent(renderer)
    for i, box in enumerate(boxes):
        assert inside.contains(box.x0, box.y0) and inside.contains(box.x1, box.y1), ax.texts[i]
        assert not any(box.overlaps(other) for other in boxes[i + 1:]), ax.texts[i]
    plt.close(fig)
