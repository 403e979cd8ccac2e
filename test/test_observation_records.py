# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Hand-edited records of an observation file (detector, fovea, image): one line naming the file.

A detector record with a key of the wrong type (``scale_factor: [1]``, ``cascade: 5``, a
number as a key) reached the detector's ``float()`` or ``list()``: ``find`` printed a
``TypeError`` traceback and the detector's start-up said ``its detector or fovea record is
unusable (TypeError: float() argument must be ...)``. Now the line names the file, the key and
what it must be, wherever the file is read: as it is loaded (the image record, a key that is not
text), or where the detector and the fovea are built from it (``find``, ``build_setup`` of the
detector node, ``evaluate --scenes pan-tilt --scene-model``).
"""
import copy
from pathlib import Path

from ipomdp_gaze.files.observation_file import MODEL_DIR, ObservationFileError
import pytest
import yaml

SHIPPED = {}
K_NINE = '9 numbers (a 3x3 matrix, row-major)'


def _shipped(name: str) -> dict:
    if name not in SHIPPED:
        SHIPPED[name] = yaml.safe_load((MODEL_DIR / f'{name}.yaml').read_text())
    return copy.deepcopy(SHIPPED[name])


def _write(tmp_path: Path, name: str, change) -> Path:
    """Write the shipped model ``name`` with ``change(doc)`` made; return its path."""
    doc = _shipped(name)
    change(doc)
    path = tmp_path / 'edited.yaml'
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def _set(record: str, key, value):
    def change(doc):
        doc[record][key] = value
    return change


def _member(index: int, key: str, value):
    def change(doc):
        doc['detector']['members'][index][key] = value
    return change


def _camera(key: str, value):
    def change(doc):
        doc['image']['camera'][key] = value
    return change


# Read where the detector and the fovea are built: the model, the change, the line after the file.
BUILT = [
    ('faces-420', _set('detector', 'scale_factor', [1]),
     'detector.scale_factor must be a number, got [1]'),
    ('faces-420', _set('detector', 'scale_factor', 'x'),
     "detector.scale_factor must be a number, got 'x'"),
    ('faces-420', _set('detector', 'min_neighbors', [1]),
     'detector.min_neighbors must be an integer, got [1]'),
    ('faces-420', _set('detector', 'cascade', 5),
     'detector.cascade must be text or a list of text, got 5'),
    ('faces-420', _set('detector', 'min_size_px', 'big'),
     'detector.min_size_px must be an integer or a [width, height] pair of integers (or null), '
     "got 'big'"),
    ('faces-420', _set('detector', 'window_px', 20),
     'detector.window_px must be a [width, height] pair of integers, got 20'),
    ('faces-420-yunet', _set('detector', 'top_k', {'n': 1}),
     "detector.top_k must be an integer, got {'n': 1}"),
    ('faces-420', _set('fovea', 'windows_cells', 21),
     'fovea.windows_cells must be a list of integers, got 21'),
    ('faces-420', _set('fovea', 'interpolation', ['area']),
     "fovea.interpolation must be text, got ['area']"),
    ('faces-420', _set('fovea', 'scales', {'a': 1}),
     "fovea.scales must be a list of numbers (or null), got {'a': 1}"),
    ('faces-pan-tilt', _set('detector', 'scale_factor', [1.1]),
     'detector.scale_factor must be a number, got [1.1]'),
    ('faces-pan-tilt-ensemble', _member(0, 'mirror', 'both'),
     "detector.members[0].mirror must be true, false or a list of them, got 'both'"),
    ('faces-pan-tilt-ensemble', _member(1, 'weight', 'five'),
     "detector.members[1].weight must be an integer, got 'five'"),
    ('faces-pan-tilt-ensemble', _set('detector', 'members', 3),
     'detector.members must be a non-empty list of mappings, got 3'),
]

# Read as the file is loaded: the line after the file.
LOADED = [
    ('faces-420', _set('detector', 1, 'x'),
     'detector must map names (text) to values, got the key 1'),
    ('faces-420', _set('detector', 'kind', 5), 'detector.kind must be text, got 5'),
    ('faces-420', _set('fovea', 2, 3), 'fovea must map names (text) to values, got the key 2'),
    ('faces-420', _set('image', 'width', 'x'), "image.width must be an integer, got 'x'"),
    ('faces-pan-tilt', _set('image', 'view', ['pan_tilt']),
     "image.view must be text, got ['pan_tilt']"),
    ('faces-pan-tilt', _set('image', 'camera', [320, 240]),
     'image.camera must be a mapping, got [320, 240]'),
    ('faces-pan-tilt', _camera('K', 'x'), f"image.camera.K must be {K_NINE}, got 'x'"),
    # K of 8 numbers, or as rows, reached the camera with no file named (and the rows as
    # ``a camera record must be {width, height, K}``)
    ('faces-pan-tilt', _camera('K', [1, 0, 1, 0, 1, 1, 0, 0]),
     f'image.camera.K must be {K_NINE}, got [1, 0, 1, 0, 1, 1, 0, 0]'),
    ('faces-pan-tilt', _camera('K', [[1, 0, 1], [0, 1, 1], [0, 0, 1]]),
     f'image.camera.K must be {K_NINE}, got [[1, 0, 1], [0, 1, 1], [0, 0, 1]]'),
    ('faces-pan-tilt', _camera('K', [1, 2, 1, 0, 1, 1, 0, 0, 1]),
     'image.camera: K must be [fx, 0, cx, 0, fy, cy, 0, 0, 1], got [1.0, 2.0, 1.0, 0.0, 1.0, '
     '1.0, 0.0, 0.0, 1.0]'),
    ('faces-pan-tilt', _camera('K', [1, 0, 1, 0, 1, 1, 0, 0, float('nan')]),
     'image.camera: K must be 9 finite numbers (the 3x3 camera matrix, row-major), got '
     '[1, 0, 1, 0, 1, 1, 0, 0, nan]'),
    ('faces-pan-tilt', _camera('width', 320.5),
     'image.camera.width must be an integer, got 320.5'),
]


def _mode(name: str) -> str:
    return 'camera' if 'pan-tilt' in name else 'fovea'


@pytest.mark.parametrize('name, change, message', BUILT)
def test_a_bad_detector_or_fovea_record_names_the_file_and_the_key(tmp_path, name, change,
                                                                   message):
    from ipomdp_gaze.vision.detection import build_setup
    path = _write(tmp_path, name, change)
    with pytest.raises(ValueError) as raised:
        build_setup(_mode(name), str(path))
    assert str(raised.value) == f'observation.file {str(path)!r}: {message}'


@pytest.mark.parametrize('name, change, message', LOADED)
def test_a_bad_record_is_refused_as_the_file_is_loaded(tmp_path, name, change, message):
    from ipomdp_gaze.files.observation_file import load_observation
    from ipomdp_gaze.vision.detection import build_setup
    path = _write(tmp_path, name, change)
    with pytest.raises(ObservationFileError) as raised:
        load_observation(path)
    assert str(raised.value) == f'{path}: {message}'
    with pytest.raises(ValueError) as raised:
        build_setup(_mode(name), str(path))
    assert str(raised.value) == f'{path}: {message}'


@pytest.mark.parametrize('name, change, message', [
    case for case in BUILT + LOADED if case[0] in ('faces-420', 'faces-420-yunet')])
def test_find_names_the_file_and_the_key_in_one_line(tmp_path, run_find, name, change,
                                                     message):
    """``find --scan fovea --observation FILE``: a TypeError traceback, or the file's stem."""
    import cv2
    import numpy as np
    cv2.imwrite(str(tmp_path / 'grey.png'), np.full((420, 420, 3), 128, np.uint8))
    path = _write(tmp_path, name, change)
    run = run_find(tmp_path / 'grey.png', '--scan', 'fovea', '--observation', path)
    assert run.returncode == 2, (run.stdout, run.stderr)
    assert run.stderr.strip().splitlines() == [f'ipomdp-gaze find: error: {path}: {message}']


def test_evaluate_scene_model_names_the_file_and_the_key(tmp_path, cli_here):
    """It said ``its detector or fovea record is unusable (TypeError: ...)``."""
    path = _write(tmp_path, 'faces-pan-tilt', _set('detector', 'min_neighbors', [0]))
    run = cli_here('evaluate', '--scenes', 'pan-tilt', '--scene-model', path, '--episodes', '1',
                   '--jobs', '1', '--quiet')
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        f'ipomdp-gaze evaluate: error: observation.file {str(path)!r}: detector.min_neighbors '
        'must be an integer, got [0]']


@pytest.mark.parametrize('k', [[1, 0, 1, 0, 1, 1, 0, 0], [[1, 0, 1], [0, 1, 1], [0, 0, 1]]])
def test_a_camera_k_not_of_9_numbers_names_the_file_and_the_key_in_find_and_evaluate(
        tmp_path, cli_here, k):
    """``evaluate --scene-model`` said ``K must be 9 finite numbers, got [...]``: no file."""
    import cv2
    import numpy as np
    cv2.imwrite(str(tmp_path / 'grey.png'), np.full((240, 320, 3), 128, np.uint8))
    path = _write(tmp_path, 'faces-pan-tilt', _camera('K', k))
    line = f'{path}: image.camera.K must be {K_NINE}, got {k!r}'
    for argv in (('find', tmp_path / 'grey.png', '--observation', path),
                 ('evaluate', '--scenes', 'pan-tilt', '--scene-model', path, '--episodes', '1',
                  '--jobs', '1', '--quiet')):
        run = cli_here(*argv)
        assert run.returncode == 2
        assert run.stderr.strip().splitlines() == [f'ipomdp-gaze {argv[0]}: error: {line}']


def test_the_shipped_models_pass_the_record_checks():
    from ipomdp_gaze.files.observation_file import load_observation, shipped_observations
    from ipomdp_gaze.vision.fovea_model import check_records
    for name in shipped_observations():
        check_records(load_observation(name))


def _ensemble_in_ensemble(recursive: bool):
    """Make the detector an ensemble whose member is an ensemble (itself: a YAML alias)."""
    def change(doc):
        inner = {'kind': 'ensemble', 'members': [dict(doc['detector'], weight=1)]}
        doc['detector'] = {'kind': 'ensemble', 'members': [inner], 'window_px': [20, 20],
                           'opencv': doc['detector']['opencv']}
        if recursive:
            doc['detector']['members'][0] = doc['detector']
    return change


@pytest.mark.parametrize('recursive', [False, True])
def test_an_ensemble_holding_an_ensemble_is_one_line_even_as_its_own_member(
        tmp_path, recursive):
    """An alias making the ensemble its own member was a RecursionError in the record check."""
    from ipomdp_gaze.vision.detection import build_setup
    from ipomdp_gaze.vision.detectors import detector_from_settings
    path = _write(tmp_path, 'faces-420', _ensemble_in_ensemble(recursive))
    assert ('*id' in path.read_text()) == recursive
    message = 'detector.members[0]: an ensemble cannot hold an ensemble'
    with pytest.raises(ValueError) as raised:
        build_setup('fovea', str(path))
    assert str(raised.value) == f'observation.file {str(path)!r}: {message}'
    with pytest.raises(ValueError, match=r'detector\.members\[0\]: an ensemble cannot hold'):
        detector_from_settings(yaml.safe_load(path.read_text())['detector'])


def test_a_plug_ins_own_record_types_attribute_is_not_taken_for_a_declaration(tmp_path,
                                                                              monkeypatch):
    """Only a map of names to the record kinds declares types; a plug-in's other one is ignored."""
    from ipomdp_gaze.vision.detectors import check_detector_record
    (tmp_path / 'typed.py').write_text(
        'class Other:\n'
        "    record_types = {'x': float}\n\n\n"
        'class Listed:\n'
        "    record_types = ['x']\n\n\n"
        'class Declared:\n'
        "    record_types = {'x': 'number'}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    for kind in ('typed:Other', 'typed:Listed'):
        assert check_detector_record({'kind': kind, 'x': 'text'}) == {'kind': kind, 'x': 'text'}
    with pytest.raises(ValueError, match=r'^detector\.x must be a number, got'):
        check_detector_record({'kind': 'typed:Declared', 'x': 'text'})
