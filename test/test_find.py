# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze find`` on generated scenes, with a count model calibrated on train scenes."""
import errno
import json
import os
from pathlib import Path
import subprocess
import sys

import cv2
from ipomdp_gaze.cli import main
from ipomdp_gaze.files.observation_file import load_observation, save_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.vision.detector import HaarDetector
from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.scenes import SceneSet
import numpy as np
import pytest

GRID = Grid(21, 21)
TASK = {'size_px': 420, 'face_px': (60, 140), 'grid': (21, 21)}
TRAIN_SCENES = 8
JSON_KEYS = ['path', 'cell', 'pixel', 'probability', 'fixations', 'detector_pixels',
             'full_scan_pixels', 'seconds', 'decision', 'ended', 'confidence', 'map_probability',
             'absent_probability', 'stop', 'method', 'note', 'resized_from', 'grid']


def run_find(*args, cwd=None):
    return subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'find', *map(str, args)],
                          capture_output=True, text=True, timeout=300, cwd=cwd)


@pytest.fixture
def find_here(cli_here):
    """Run ``find`` in this process: its lines and status without an interpreter per run."""
    return lambda *args, cwd=None: cli_here('find', *args, cwd=cwd)


def calibrate(scenes, detector, config):
    """
    Count model from labelled scenes fixated at every cell (Dirichlet(1) prior).

    Target tallies are pooled over offsets at the same Chebyshev distance, because a handful of
    images gives each single offset only a few target observations.
    """
    fovea = Fovea(detector, GRID, config, reuse_windows=True)
    n, k = GRID.n_cells, config.max_count
    rows, cols = GRID.rows_cols()
    offset = (np.abs(rows[None, :] - rows[:, None]) * GRID.cols
              + np.abs(cols[None, :] - cols[:, None]))           # [fixation, cell]
    target, null = np.zeros(n * k), np.zeros(n * k)
    for scene in scenes:
        fovea.start(scene.image)
        frames = np.array([fovea.observe(f).counts for f in range(n)])
        seen = ~np.isnan(frames)
        flat = offset * k + np.where(seen, frames, 0).astype(np.intp)
        face = np.arange(n) == GRID.index(*scene.cell)
        target += np.bincount(flat[seen & face], minlength=n * k)
        null += np.bincount(flat[seen & ~face], minlength=n * k)
    target, null = target.reshape(GRID.shape + (k,)), null.reshape(GRID.shape + (k,))
    ring = np.maximum(*np.meshgrid(np.arange(GRID.rows), np.arange(GRID.cols), indexing='ij'))
    pooled = np.stack([target[ring == d].sum(axis=0) for d in range(ring.max() + 1)])[ring]
    p_target = (pooled + 1.0) / (pooled + 1.0).sum(axis=2, keepdims=True)
    p_null = (null + 1.0) / (null + 1.0).sum(axis=2, keepdims=True)
    meta = {'image': {'width': TASK['size_px'], 'height': TASK['size_px']},
            'fovea': config.to_dict(), 'detector': detector.settings()}
    return CountObservation(GRID, p_target, p_null, meta)


@pytest.fixture(scope='module')
def task(tmp_path_factory):
    """Calibrate a model on train scenes and write test scenes as PNG files."""
    root = tmp_path_factory.mktemp('find')
    detector, config = HaarDetector(), FoveaConfig()
    model = calibrate(SceneSet('train', seed=0, n=TRAIN_SCENES, **TASK), detector, config)
    model_path = save_observation(root / 'faces-test.yaml', model)
    # The test scene: the first one whose face the full-frame scan finds (within one cell), so
    # the choice depends on the detector only, never on the model or on find.
    test = SceneSet('test', seed=0, **TASK)
    chosen = []
    for index in range(20):
        scene = test[index]
        found = scan(scene.image, detector, GRID).cell
        if found is not None and max(np.abs(np.subtract(GRID.cell(found), scene.cell))) <= 1:
            chosen.append(scene)
        if len(chosen) == 2:
            break
    images = []
    for i, scene in enumerate(chosen):
        cv2.imwrite(str(root / f'scene{i}.png'), scene.image)
        images.append(root / f'scene{i}.png')
    return {'root': root, 'model': model_path, 'images': images, 'scenes': chosen}


def within_one_cell(cell, scene):
    return max(abs(cell[0] - scene.cell[0]), abs(cell[1] - scene.cell[1])) <= 1


def test_find_locates_the_face_of_a_test_scene(task, tmp_path):
    out = tmp_path / 'out.json'
    result = run_find(task['images'][0], '--observation', task['model'], '--json', out,
                      '--scan', 'fovea')
    assert result.returncode == 0, result.stderr
    lines = result.stdout.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"{task['images'][0]}: decision=found ended=confidence "
                               'cell (row, col)=(')
    for word in ('pixel (x, y)=(', 'p=', 'fixations=', 'detector_pixels=', 'seconds='):
        assert word in lines[0]
    assert 'observation model faces-test' in result.stderr and 'policy elm' in result.stderr
    entry = json.loads(out.read_text())['images'][0]
    assert within_one_cell(entry['cell'], task['scenes'][0])
    assert entry['probability'] >= 0.9 and entry['stop'] == entry['decision'] == 'found'
    assert 0 < entry['detector_pixels'] < 420 * 420 and entry['seconds'] > 0


def test_json_has_one_entry_per_image_in_input_order(task, find_here):
    root = task['root']
    names = [path.name for path in reversed(task['images'])]
    out = root / 'two.json'
    result = find_here(*names, '--observation', task['model'], '--json', 'two.json',
                       '--scan', 'fovea', cwd=root)
    assert result.returncode == 0, result.stderr
    data = json.loads(out.read_text())
    assert list(data) == ['grid', 'axes', 'images'] and data['grid'] == {'rows': 21, 'cols': 21}
    assert data['axes'] == {'cell': ['row', 'col'], 'pixel': ['x', 'y']}
    assert [entry['path'] for entry in data['images']] == names
    lines = result.stdout.strip().splitlines()
    assert [line.split(': decision')[0] for line in lines] == names
    for entry, scene in zip(data['images'], reversed(task['scenes'])):
        assert list(entry) == JSON_KEYS
        assert isinstance(entry['cell'], list) and len(entry['pixel']) == 2
        row, col = entry['cell']
        assert entry['pixel'] == [col * 20 + 10.0, row * 20 + 10.0]
        assert isinstance(entry['fixations'], int) and isinstance(entry['detector_pixels'], int)
        assert within_one_cell(entry['cell'], scene)


def test_plot_writes_png_files(task, tmp_path, capsys):
    one = tmp_path / 'one.png'
    assert main(['find', str(task['images'][0]), '--observation', str(task['model']),
                 '--plot', str(one)]) == 0
    picture = cv2.imread(str(one))
    assert picture is not None and picture.shape[0] > 100
    many = tmp_path / 'many.png'
    assert main(['find', *map(str, task['images']), '--observation', str(task['model']),
                 '--plot', str(many)]) == 0
    assert cv2.imread(str(tmp_path / 'many-0.png')) is not None
    assert cv2.imread(str(tmp_path / 'many-1.png')) is not None
    assert not many.exists()
    assert 'wrote' in capsys.readouterr().err


def test_nmpt_policy_and_another_image_size(task, tmp_path, capsys):
    scene = task['scenes'][0]
    big = tmp_path / 'big.png'
    cv2.imwrite(str(big), cv2.resize(scene.image, (840, 840), interpolation=cv2.INTER_CUBIC))
    assert main(['find', str(big), '--observation', str(task['model']), '--policy', 'nmpt',
                 '--seed', '2']) == 0
    out = capsys.readouterr()
    assert '(image 840x840 px, model calibrated at 420x420)' in out.out
    assert 'policy nmpt' in out.err


def _model_copy(path, model, width, height):
    meta = dict(model.meta)
    meta.pop('source', None)
    meta['image'] = {'width': width, 'height': height}
    return save_observation(path, CountObservation(model.grid, model.p_target, model.p_null,
                                                   meta, model.scan_target, model.scan_null))


@pytest.mark.parametrize('detector, suffix', [(None, '-yunet'), ('haar', '')])
def test_default_model_is_the_shipped_one_calibrated_nearest(task, tmp_path, monkeypatch,
                                                             capsys, detector, suffix):
    """The detector's shipped models (YuNet's by default) nearest each image's size."""
    import ipomdp_gaze.files.observation_file as observation_file
    models = tmp_path / 'models'
    monkeypatch.setattr(observation_file, 'MODEL_DIR', models)
    flags = ['--detector', detector] if detector else []
    assert main(['find', str(task['images'][0]), *flags]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'pass --observation FILE' in err[0]
    model = load_observation(task['model'])
    _model_copy(models / f'faces-420{suffix}.yaml', model, 420, 420)
    _model_copy(models / f'faces-800{suffix}.yaml', model, 800, 800)
    _model_copy(models / 'faces-840-nmpt.yaml', model, 840, 840)     # a reference: never chosen
    other = '' if suffix else '-yunet'          # the other detector's model: not chosen
    _model_copy(models / f'faces-420{other}.yaml', model, 420, 420)
    big = tmp_path / 'big.png'
    cv2.imwrite(str(big), cv2.resize(task['scenes'][0].image, (840, 840)))
    assert main(['find', str(task['images'][0]), str(big), *flags]) == 0
    err = capsys.readouterr().err
    assert f'shipped observation model faces-420{suffix} ' in err
    assert f'shipped observation model faces-800{suffix} ' in err and 'nmpt' not in err
    assert f'faces-420{other} ' not in err


def test_default_policy_is_the_shipped_kernel_of_the_model(task, tmp_path, monkeypatch,
                                                           capsys):
    from ipomdp_gaze.policies import policy_file
    from ipomdp_gaze.policies.baselines import elm_policy
    kernels = tmp_path / 'kernels'
    kernels.mkdir()
    monkeypatch.setattr(policy_file, 'KERNEL_DIR', kernels)
    model = load_observation(task['model'])
    spec = policy_file.PolicySpec(grid=model.grid, fpoc=None, reward='infomax', family='conv',
                                  observation=policy_file.observation_block(model),
                                  kernel=elm_policy(model.grid, model).kernel)
    policy_file.save_policy(kernels / 'faces-test-infomax.yaml', spec)
    assert main(['find', str(task['images'][0]), '--observation', str(task['model'])]) == 0
    assert 'shipped kernel faces-test-infomax (argmax)' in capsys.readouterr().err


@pytest.mark.parametrize('make, message', [
    (lambda d: d / 'missing.png', 'no such file'),
    (lambda d: _write(d / 'text.png', b'not an image'), 'not an image OpenCV can decode'),
    # QA: cv2.imread shows a truncated JPEG's top part above grey; imdecode refuses it whole,
    # and the message said it was not an image at all
    (lambda d: _write(d / 'cut.jpg', _jpeg_bytes()[:3000]), 'truncated or corrupt JPEG: it ends '
     'before its end-of-image marker (a copy or download cut short?)'),
    (lambda d: _write(d / 'scrambled.jpg', _jpeg_bytes()[:600] + bytes(2000) + b'\xff\xd9'),
     'truncated or corrupt JPEG: OpenCV cannot decode it'),
    # 16-bit images are converted (test_find_truth.py); a float image is still refused.
    (lambda d: _png(d / 'deep.tiff', np.zeros((420, 420), dtype=np.float32)),
     '32-bit float32 image; find needs unsigned 8 or 16 bits per channel'),
    # signed: "16-bit int16 image; find needs 8 or 16 bits" said it was what find needs
    (lambda d: _png(d / 'signed.tiff', np.zeros((420, 420), dtype=np.int16)),
     '16-bit int16 image; find needs unsigned 8 or 16 bits per channel (uint8 or uint16: '
     'convert it, e.g. to 8-bit PNG)'),
    (lambda d: _png(d / 'dot.png', np.zeros((1, 1), dtype=np.uint8)), 'too small'),
    # a link to itself: was a RuntimeError traceback (Path.resolve) before any image
    (lambda d: _link(d / 'loop.png', 'loop.png'), 'a symbolic link loop'),
])
def test_a_bad_image_is_one_error_line_and_the_others_are_searched(task, tmp_path, make,
                                                                   message, find_here):
    bad = make(tmp_path)
    result = find_here(task['images'][0], bad, task['images'][1], '--observation', task['model'])
    assert result.returncode == 2                       # non-zero at the end
    out = result.stdout.strip().splitlines()
    searched = [line.split(':')[0] for line in out]
    assert searched == [str(task['images'][0]), str(task['images'][1])]
    assert 'Traceback' not in result.stderr
    errors = [line for line in result.stderr.splitlines() if 'error:' in line]
    assert len(errors) == 2, errors
    assert errors[0].startswith(f'ipomdp-gaze find: error: {bad}: ') and message in errors[0]
    assert errors[1] == 'ipomdp-gaze find: error: 1 of 3 inputs could not be searched'


def test_a_malformed_observation_file_is_one_error_line(task, tmp_path, find_here):
    broken = _write(tmp_path / 'broken.yaml', b'format: ipomdp_gaze/observation-v1\nmodel: [\n')
    result = find_here(task['images'][0], '--observation', broken)
    assert result.returncode == 2 and result.stdout == ''
    assert 'Traceback' not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and str(broken) in lines[0] and 'not YAML' in lines[0]
    truncated = _write(tmp_path / 'short.yaml', Path(task['model']).read_bytes()[:2000])
    result = find_here(task['images'][0], '--observation', truncated)
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1


def _write(path, data: bytes):
    path.write_bytes(data)
    return path


def _jpeg_bytes() -> bytes:
    """Return a 320x240 JPEG of seeded noise (about 20 kB)."""
    image = np.random.default_rng(0).integers(0, 256, (240, 320, 3), dtype=np.uint8)
    return cv2.imencode('.jpg', image)[1].tobytes()


def _png(path, image):
    assert cv2.imwrite(str(path), image)
    return path


def _link(path, target):
    path.symlink_to(target)
    return path


def test_a_folder_or_file_find_may_not_look_at_is_one_line_each(task, tmp_path, monkeypatch,
                                                                find_here):
    """
    A folder without read permission, or a file in one without search permission: one line each.

    Was ``error: [Errno 13] Permission denied`` for the whole run, no image searched. Root reads
    them all, so the refusals are those of a user's own process, made here by os.stat,
    os.listdir and os.scandir (as the system would) for these paths only.
    """
    locked, noexec = tmp_path / 'locked', tmp_path / 'noexec'
    for folder in (locked, noexec):
        folder.mkdir()
        (folder / 'a.png').write_bytes(Path(task['images'][0]).read_bytes())
    stat, listdir, scandir = os.stat, os.listdir, os.scandir

    def refuse(call, refused):
        def wrapped(path='.', *args, **kwargs):
            if Path(os.fsdecode(path)) in refused:
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
            return call(path, *args, **kwargs)
        return wrapped
    monkeypatch.setattr(os, 'stat', refuse(stat, {noexec / 'a.png'}))
    monkeypatch.setattr(os, 'listdir', refuse(listdir, {locked}))
    monkeypatch.setattr(os, 'scandir', refuse(scandir, {locked}))
    result = find_here(locked, noexec, task['images'][1], '--observation', task['model'])
    assert result.returncode == 2 and 'Traceback' not in result.stderr
    assert [line.split(':')[0] for line in result.stdout.splitlines()] == [
        str(task['images'][1])]
    errors = [line for line in result.stderr.splitlines() if 'error:' in line]
    assert errors == [
        f'ipomdp-gaze find: error: {locked}: a folder find cannot list: Permission denied',
        f'ipomdp-gaze find: error: {noexec / "a.png"}: cannot read: Permission denied',
        'ipomdp-gaze find: error: 2 of 3 inputs could not be searched']
