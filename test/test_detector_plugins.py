# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Detectors from outside the package: the factory, ``calibrate``, ``find`` and the detector node.

A tiny colour-blob detector is written to a temporary folder that is put on the path, once as a
plain module (``blobdet:BlobDetector``) and once declared as the entry point ``blob`` of a
``*.dist-info`` folder there (what ``pip install`` of a plug-in package leaves). Each is
calibrated on labelled images with scores in bins, used by ``find``, and served by a
``foveal_detector`` process over DDS, which must publish exactly the core's observation.
"""
from __future__ import annotations

import csv
import json
import textwrap

from conftest import wait_for
import cv2
from ipomdp_gaze.cli import main as cli
import numpy as np
import pytest

BLOB = '''
import numpy as np
import cv2


class BlobDetector:
    """Red squares; the score is how red the box is on average (0..1)."""

    color = 'rgb'
    window_px = (4, 4)

    def __init__(self, min_red=150):
        self.min_red = int(min_red)

    def __call__(self, rgb):
        r, g, b = (rgb[:, :, i].astype(int) for i in range(3))
        mask = ((r > self.min_red) & (g < 100) & (b < 100)).astype(np.uint8)
        n, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=4)
        rows = []
        for x, y, w, h, area in stats[1:]:
            box = rgb[y:y + h, x:x + w].astype(float)
            red = (box[:, :, 0] - (box[:, :, 1] + box[:, :, 2]) / 2).mean() / 255
            rows.append([x, y, w, h, min(max(red, 0.01), 1.0)])
        return np.array(rows, dtype=float).reshape(-1, 5)

    def settings(self):
        return {'kind': 'ignored: the factory records the name it built this by',
                'min_red': self.min_red}


class Fussy(BlobDetector):
    """Raises on an image with a white pixel (a plug-in's bug on some images)."""

    def __call__(self, rgb):
        if (rgb.min(axis=2) == 255).any():
            raise RuntimeError('cannot handle this one')
        return super().__call__(rgb)


class Grumpy(BlobDetector):
    """Raises on every image."""

    def __call__(self, rgb):
        raise RuntimeError('not today')


class Forgetful(BlobDetector):
    """Its settings() leave out the option it was built with."""

    def settings(self):
        return {}


class Picky:
    """An option its factory converts (and refuses with numpy's or Python's own message)."""

    def __init__(self, temperature=1.0):
        self.temperature = float(temperature)

    def __call__(self, gray):
        return np.empty((0, 4))


class Astray:
    """Three boxes wholly outside any image it is given (corners taken for sizes) and one in."""

    def __call__(self, gray):
        h, w = gray.shape[:2]
        return np.array([[-20, -20, 10, 10], [w + 5, 2, 8, 8], [2, h, 4, 4], [1, 1, 4, 4]])


class Lopsided(Astray):
    """A window_px of one side."""

    window_px = (20,)


class Secretive(Astray):
    """Its settings() raise."""

    def settings(self):
        raise RuntimeError('settings are secret')


class Listy(Astray):
    """Its settings() are not a mapping."""

    def settings(self):
        return [('size', 3)]


class Needy(Astray):
    """Raises as it is built, with an error that is not about its options."""

    def __init__(self, device='gpu'):
        raise RuntimeError('no GPU found')


class Boastful(BlobDetector):
    """Its settings() name an option its factory does not take."""

    def settings(self):
        return {'min_red': self.min_red, 'max_red': 255}


class Misshapen:
    """Answers in a way given by its option: rows of 3, NaN, a negative width, complex."""

    def __init__(self, mode='short'):
        self.mode = mode

    def __call__(self, gray):
        return {'short': np.array([[1.0, 2.0, 3.0]]),
                'nan': np.array([[np.nan, 1, 5, 5, 0.5]]),
                'negative': np.array([[10, 10, -5, 5, 0.5]]),
                'complex': np.array([[1, 1, 5, 5]], complex), 'none': None,
                'empty short': np.empty((0, 3))}[self.mode]
'''
SIZE, CELLS, SQUARE = 84, 7, 14
KINDS = {'module': 'blobdet:BlobDetector', 'entry point': 'blob'}


@pytest.fixture(scope='module')
def plugin_dir(tmp_path_factory):
    """Write the plug-in module and a dist-info declaring its entry point to a folder."""
    folder = tmp_path_factory.mktemp('plugin')
    (folder / 'blobdet.py').write_text(textwrap.dedent(BLOB))
    (folder / 'brokendet.py').write_text(          # a plug-in whose weights are not installed
        "raise FileNotFoundError(2, 'No such file or directory', '/nowhere/weights.onnx')\n")
    info = folder / 'blobdet_plugin-0.1.dist-info'
    info.mkdir()
    (info / 'METADATA').write_text('Metadata-Version: 2.1\nName: blobdet-plugin\nVersion: 0.1\n')
    (info / 'entry_points.txt').write_text('[ipomdp_gaze.detectors]\n'
                                           'blob = blobdet:BlobDetector\n'
                                           'blob_broken = brokendet:Thing\n')
    return folder


@pytest.fixture()
def on_path(plugin_dir, monkeypatch):
    monkeypatch.syspath_prepend(str(plugin_dir))
    return plugin_dir


def blob_image(rng, cell=None) -> np.ndarray:
    """Draw a noisy grey 84x84 RGB image, with a red square centred in ``cell`` (row, col)."""
    image = np.repeat(rng.integers(60, 140, (SIZE, SIZE, 1), dtype=np.uint8), 3, axis=2)
    if cell is not None:
        side = SIZE // CELLS
        cx, cy = cell[1] * side + side // 2, cell[0] * side + side // 2
        red = int(rng.integers(170, 256))
        image[cy - SQUARE // 2:cy + SQUARE // 2, cx - SQUARE // 2:cx + SQUARE // 2] = \
            (red, 30, 30)
    return image


def labelled_folder(folder, n=16, seed=0):
    """Write ``n`` labelled images (every fourth without a square) and their CSV."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / 'labels.csv', 'w', newline='') as handle:
        writer = csv.writer(handle)
        writer.writerow(['path', 'x', 'y'])
        for i in range(n):
            cell = None if i % 4 == 3 else tuple(int(v) for v in rng.integers(1, CELLS - 1, 2))
            cv2.imwrite(str(folder / f'{i}.png'), blob_image(rng, cell)[:, :, ::-1])
            side = SIZE // CELLS
            centre = ('', '') if cell is None else (cell[1] * side + side // 2,
                                                    cell[0] * side + side // 2)
            writer.writerow([f'{i}.png', *centre])
    return folder / 'labels.csv'


def calibrate(tmp_path, kind):
    labels = labelled_folder(tmp_path / 'images')
    out = tmp_path / 'blob.yaml'
    rc = cli(['calibrate', '--images', str(tmp_path / 'images'), '--labels', str(labels),
              '--grid', f'{CELLS}x{CELLS}', '--windows', f'{CELLS},3', '--max-count', '4',
              '--detector', kind, '--detector-option', 'min_red=150', '--cells',
              'score_bins', '--edge-images', '8', '--min-tallies', '0', '--processes', '1',
              '--quiet', '--out', str(out)])
    assert rc == 0
    return out


def test_the_factory_builds_shipped_and_outside_detectors_by_name(on_path):
    from ipomdp_gaze.vision.detectors import detector_from_settings, detector_kinds, make_detector
    assert {'haar', 'yunet', 'blob'} <= set(detector_kinds())
    for kind in KINDS.values():
        detector = make_detector(kind, min_red=120)
        from ipomdp_gaze.vision.detector import detector_settings
        settings = detector_settings(detector)
        assert settings == {'kind': kind, 'min_red': 120}
        assert detector_settings(detector_from_settings(settings)) == settings
    with pytest.raises(ValueError, match="unknown detector 'nope'; known: haar, yunet"):
        make_detector('nope')
    with pytest.raises(ValueError, match="cannot import module 'no_such_module'"):
        make_detector('no_such_module:Thing')
    with pytest.raises(ValueError, match="module 'blobdet' has no 'Nothing'"):
        make_detector('blobdet:Nothing')
    with pytest.raises(ValueError, match="detector 'blob' has no option 'colour' "
                                         r'\(its options: min_red\)'):
        make_detector('blob', colour='red')
    with pytest.raises(ValueError, match='min_red 120 but the detector has 150'):
        from ipomdp_gaze.vision.detectors import compare_settings
        compare_settings({'kind': 'blob', 'min_red': 120}, {'kind': 'blob', 'min_red': 150})


@pytest.mark.parametrize('how', list(KINDS))
def test_an_outside_detector_is_calibrated_with_score_bins_and_found_by_find(
        on_path, tmp_path, how, capsys):
    from ipomdp_gaze.files.observation_file import load_observation
    out = calibrate(tmp_path, KINDS[how])
    model = load_observation(out)
    assert model.meta['detector'] == {'kind': KINDS[how], 'min_red': 150}
    cells = model.meta['cells']
    assert cells['kind'] == 'score_bins' and cells['max_count'] == model.max_count + 1
    assert len(cells['edges']) == cells['max_count'] - 2
    assert np.all(np.diff(cells['edges']) > 0)
    # Bin 0 is "no detection": at the fixation it is far likelier without the target.
    assert model.p_target[0, 0, 0] < 0.5 < model.p_null[0, 0, 0]
    image = blob_image(np.random.default_rng(7), (2, 4))
    path = tmp_path / 'test.png'
    cv2.imwrite(str(path), image[:, :, ::-1])
    capsys.readouterr()
    assert cli(['find', str(path), '--observation', str(out), '--policy', 'elm',
                '--json', str(tmp_path / 'found.json')]) == 0
    found = json.loads((tmp_path / 'found.json').read_text())['images'][0]
    assert found['cell'] == [2, 4]
    # find --detector takes the plug-in by its name and searches with its calibrated model
    # (today: refused, "choose from 'yunet', 'haar'"); without a model it says how to make one.
    assert cli(['find', str(path), '--detector', KINDS[how], '--observation', str(out),
                '--policy', 'elm', '--json', str(tmp_path / 'named.json')]) == 0
    assert json.loads((tmp_path / 'named.json').read_text())['images'][0]['cell'] == [2, 4]
    capsys.readouterr()
    assert cli(['find', str(path), '--detector', KINDS[how]]) == 2
    err = capsys.readouterr().err
    assert f'calibrate one on labelled images, ipomdp-gaze calibrate --images DIR --labels ' \
        f'faces.csv --detector {KINDS[how]} --out model.yaml' in err


def test_an_unknown_detector_in_calibrate_is_one_line(tmp_path, capsys):
    labels = labelled_folder(tmp_path / 'images', n=2)
    rc = cli(['calibrate', '--images', str(tmp_path / 'images'), '--labels', str(labels),
              '--detector', 'nope', '--out', str(tmp_path / 'x.yaml'), '--quiet'])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "unknown detector 'nope'" in err[0]


@pytest.mark.ros
@pytest.mark.parametrize('how', list(KINDS))
def test_the_detector_node_serves_an_outside_detector(ros_env, probe, plugin_dir, tmp_path,
                                                      how, monkeypatch):
    import os

    from ipomdp_gaze.harness.processes import NodeGroup
    from ipomdp_gaze.harness.watch import LATCHED
    from ipomdp_gaze.msg_adapters import grid_arrays, images
    from ipomdp_gaze.vision.detection import build_setup
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import Image
    from std_msgs.msg import Int32MultiArray
    monkeypatch.syspath_prepend(str(plugin_dir))
    out = calibrate(tmp_path, KINDS[how])
    env = dict(ros_env)
    env['PYTHONPATH'] = os.pathsep.join(p for p in (str(plugin_dir), env.get('PYTHONPATH'))
                                        if p)
    ns = '/blob_' + how.replace(' ', '_')
    (tmp_path / 'logs').mkdir()
    group = NodeGroup(env, tmp_path / 'logs')
    try:
        frames = probe.record(Image, f'{ns}/evidence_image',
                              QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
        image_pub = probe.publisher(Image, f'{ns}/image')
        fixation_pub = probe.publisher(Int32MultiArray, f'{ns}/fixation', LATCHED)
        proc = group.start('detector', ['-r', f'__ns:={ns}', '-p', f'observation.file:={out}',
                                        '-p', f'detector.kind:={KINDS[how]}',
                                        '-p', 'detector.options:=["min_red=150"]'])
        assert wait_for(lambda: image_pub.get_subscription_count() > 0, 60), proc.output()
        setup = build_setup('fovea', str(out))
        grid = setup.grid
        cell = grid.index(2, 4)
        fixation_pub.publish(grid_arrays.row_col(grid, cell))
        image = blob_image(np.random.default_rng(3), (2, 4))

        def served():
            image_pub.publish(images.camera_image(image, probe.node.get_clock().now().to_msg()))
            return wait_for(lambda: len(frames) > 0, 1.0)
        assert wait_for(served, 30), proc.output()
        counts = images.evidence_from_image(frames[0][1], grid)
        setup.fovea.start(image)
        expected = setup.fovea.observe(cell).counts
        np.testing.assert_array_equal(counts, expected)
        assert counts[cell] > 0                   # the square's score bin, not "nothing"
        # its start-up line names it by kind and options, not <blobdet.BlobDetector object at>
        assert f'detector {KINDS[how]}(min_red=150); waiting' in proc.output(), proc.output()
    finally:
        bad = group.close()
    assert not bad, bad


@pytest.mark.parametrize('extra, words', [
    (['--cells', 'threshold'], '--cells threshold needs --threshold T'),
    (['--cells', 'score_bins', '--threshold', '0.5'], '--threshold goes with --cells threshold'),
    (['--scale-factor', '1.2'], '--scale-factor is a haar setting'),
    (['--detector-option', 'min_red'], 'a detector option must be NAME=VALUE'),
])
def test_calibrate_refuses_options_that_do_not_fit_in_one_line(on_path, tmp_path, capsys,
                                                               extra, words):
    labels = labelled_folder(tmp_path / 'images', n=2)
    rc = cli(['calibrate', '--images', str(tmp_path / 'images'), '--labels', str(labels),
              '--detector', 'blob', '--out', str(tmp_path / 'x.yaml'), '--quiet', *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and words in err[0], err


def test_a_threshold_model_counts_only_boxes_scoring_above_it(on_path, tmp_path):
    from ipomdp_gaze.files.observation_file import load_observation
    from ipomdp_gaze.vision.search import fovea_for_model
    labels = labelled_folder(tmp_path / 'images')
    out = tmp_path / 'above.yaml'
    assert cli(['calibrate', '--images', str(tmp_path / 'images'), '--labels', str(labels),
                '--grid', f'{CELLS}x{CELLS}', '--windows', f'{CELLS},3', '--max-count', '3',
                '--detector', 'blob', '--cells', 'threshold', '--threshold', '0.6',
                '--min-tallies', '0', '--processes', '1', '--quiet', '--out', str(out)]) == 0
    model = load_observation(out)
    assert model.meta['cells'] == {'kind': 'threshold', 'max_count': 3, 'threshold': 0.6}
    fovea = fovea_for_model(model)
    cell = fovea.grid.index(3, 3)
    # Scores (red - 30) / 255: 0.86, 0.51; both windows (7 and 3 cells) see the square.
    for red, expected in ((250, 2), (160, 0)):
        image = np.full((SIZE, SIZE, 3), 100, np.uint8)
        image[35:49, 35:49] = (red, 30, 30)              # centred in cell (3, 3)
        fovea.start(image)
        assert len(fovea.detector(image)) == 1
        assert fovea.observe(cell).counts[cell] == expected


def test_options_a_plugin_leaves_out_of_its_settings_are_recorded_and_rebuilt(on_path):
    from ipomdp_gaze.vision.detector import detector_settings
    from ipomdp_gaze.vision.detectors import detector_from_settings, make_detector
    settings = detector_settings(make_detector('blobdet:Forgetful', min_red=120))
    assert settings == {'kind': 'blobdet:Forgetful', 'min_red': 120}
    assert detector_from_settings(settings).min_red == 120
    # a shipped detector (rebuilt by its from_settings) records only its own settings
    haar = detector_settings(make_detector('haar', scale_factor=1.2))
    assert 'cascade_dir' not in haar and haar['scale_factor'] == 1.2


def test_boxes_that_miss_the_image_are_not_counted_at_its_edge(on_path):
    from ipomdp_gaze.vision.detector import detect
    from ipomdp_gaze.vision.detectors import make_detector
    astray = make_detector('blobdet:Astray')
    boxes, scores = detect(astray, np.zeros((30, 40), np.uint8))
    np.testing.assert_array_equal(boxes, [[1, 1, 4, 4]])
    np.testing.assert_array_equal(scores, [1.0])
    # an image smaller than the detector's window_px is not given to it
    astray.window_px = (41, 10)
    boxes, scores = detect(astray, np.zeros((30, 40), np.uint8))
    assert boxes.shape == (0, 4) and scores.shape == (0,)


def test_a_detector_that_fails_on_one_image_is_reported_against_it(on_path, tmp_path, capsys):
    """The other images are still searched and written (the README's promise for bad files)."""
    model = calibrate(tmp_path, 'blobdet:Fussy')
    good, bad = tmp_path / 'good.png', tmp_path / 'bad.png'
    image = blob_image(np.random.default_rng(7), (2, 4))
    cv2.imwrite(str(good), image[:, :, ::-1])
    cv2.imwrite(str(bad), np.full_like(image, 255))
    capsys.readouterr()
    out = tmp_path / 'found.json'
    assert cli(['find', str(bad), str(good), '--observation', str(model), '--json',
                str(out)]) == 2
    err = capsys.readouterr().err
    assert (f'ipomdp-gaze find: error: {bad}: the detector blobdet:Fussy raised RuntimeError: '
            'cannot handle this one') in err and 'Traceback' not in err
    bad_entry, good_entry = json.loads(out.read_text())['images']
    assert bad_entry['error'].startswith('the detector blobdet:Fussy raised')
    assert good_entry['cell'] == [2, 4]


@pytest.mark.parametrize('processes', ['1', '2'])
def test_calibrate_names_the_image_a_plugin_fails_on(on_path, tmp_path, capsys, processes):
    """QA: the one error line named the detector but not which of the images it failed on."""
    labels = labelled_folder(tmp_path / 'images', n=4)
    bad = tmp_path / 'images' / '2.png'
    image = cv2.imread(str(bad))
    image[0, 0] = 255                                   # Fussy raises on a white pixel
    cv2.imwrite(str(bad), image)
    out = tmp_path / 'x.yaml'
    capsys.readouterr()
    rc = cli(['calibrate', '--images', str(tmp_path / 'images'), '--labels', str(labels),
              '--grid', f'{CELLS}x{CELLS}', '--windows', f'{CELLS},3', '--max-count', '4',
              '--detector', 'blobdet:Fussy', '--processes', processes, '--quiet', '--out',
              str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and not out.exists()
    assert err == [f'ipomdp-gaze calibrate: error: {bad}: the detector blobdet:Fussy raised '
                   'RuntimeError: cannot handle this one']


@pytest.mark.parametrize('task, where', [
    ([], 'training scene 0 (seed 3)'),
    (['--pan-tilt'], 'pan/tilt training scene 0 (seed 3): the view at cell (0, 0)')])
def test_calibrate_names_the_scene_a_plugin_fails_on(on_path, tmp_path, capsys, task, where):
    out = tmp_path / 'x.yaml'
    capsys.readouterr()
    rc = cli(['calibrate', *task, '--scenes', '2', '--seed', '3', '--detector', 'blobdet:Grumpy',
              '--processes', '1', '--quiet', '--out', str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and not out.exists()
    assert err == [f'ipomdp-gaze calibrate: error: {where}: the detector blobdet:Grumpy raised '
                   'RuntimeError: not today']


def test_a_plugin_that_fails_to_load_or_refuses_an_option_is_named(on_path):
    from ipomdp_gaze.vision.detectors import make_detector
    with pytest.raises(ValueError, match=r"^detector 'brokendet:Thing': importing module "
                                         r"'brokendet' failed: FileNotFoundError: .*weights"):
        make_detector('brokendet:Thing')
    with pytest.raises(ValueError, match=r"^detector 'blobdet:Picky': bad options "
                                         r"\['temperature'\] \(could not convert"):
        make_detector('blobdet:Picky', temperature='abc')
    with pytest.raises(ValueError, match='is its package installed, or its folder on '
                                         'PYTHONPATH'):
        make_detector('not_installed_anywhere:Thing')
    # the same module by its entry point (a traceback before: only ImportError was caught)
    with pytest.raises(ValueError, match=r"^detector 'blob_broken': loading its entry point "
                                         r"'brokendet:Thing' failed: FileNotFoundError: "
                                         r'.*weights'):
        make_detector('blob_broken')


def test_an_ensemble_calls_each_member_that_sees_the_image_and_our_bugs_stay_bugs(on_path):
    """Review: the ensemble's window_px is its largest member's; the package's errors propagate."""
    from ipomdp_gaze.vision.detector import detect
    from ipomdp_gaze.vision.detectors import make_detector
    ensemble = make_detector('ensemble', members=[{'kind': 'haar'},
                                                  {'kind': 'blobdet:Astray'}])
    assert ensemble.window_px[0] > 12                 # Haar's 20: larger than the image below
    boxes, _ = detect(ensemble, np.zeros((12, 12), np.uint8))
    np.testing.assert_array_equal(boxes, [[1, 1, 4, 4]])     # Astray's box inside: it was asked

    def broken(self, image):
        raise IndexError('a bug of ours')

    ours = type('Ours', (), {'__module__': 'ipomdp_gaze.vision.detector', '__call__': broken})
    with pytest.raises(IndexError, match='a bug of ours'):      # a traceback, not one line
        detect(ours(), np.zeros((40, 40), np.uint8))


def test_a_fingerprint_or_an_impossible_value_in_the_nodes_options_is_refused_in_one_line():
    """Review: only options the factory takes were rebuilt; the others passed unchecked."""
    from ipomdp_gaze.vision.detection import build_setup
    for asked in ({'model_sha256': 'bogus'}, {'top_k': float('inf')},
                  {'window_px': [99, 99]}, {'opencv': '3.0'}):
        with pytest.raises(ValueError, match=f'detector.{next(iter(asked))} .* contradicts'):
            build_setup('camera', 'faces-pan-tilt-yunet', detector=asked)


def test_a_plugin_entry_point_that_raises_as_it_loads_is_one_line_in_find(on_path, tmp_path,
                                                                          capsys):
    """A plug-in's module failing with other than ImportError gave find a traceback."""
    path = tmp_path / 'test.png'
    cv2.imwrite(str(path), blob_image(np.random.default_rng(7), (2, 4)))
    capsys.readouterr()
    assert cli(['find', str(path), '--detector', 'blob_broken']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "detector 'blob_broken': loading its entry point" in err[0], err


@pytest.mark.parametrize('mode, words', [
    ('short', 'boxes of shape (M, 5) x, y, w, h, score or (M, 4), got (1, 3)'),
    ('nan', 'a box or score that is not a finite number'),
    ('negative', 'every box must have a positive width and height'),
    ('complex', 'a detector must return real numbers, got complex ones'),
    ('none', 'got None (no return statement?)'),
    ('empty short', 'boxes of shape (M, 5) x, y, w, h, score or (M, 4), got (0, 3)'),
])
def test_a_plugins_malformed_answer_is_named_against_the_detector(on_path, mode, words):
    """Complex lost its imaginary part with a warning, None was "got ()"; none named it."""
    import warnings

    from ipomdp_gaze.vision.detector import detect, DetectorFailed
    from ipomdp_gaze.vision.detectors import make_detector
    detector = make_detector('blobdet:Misshapen', mode=mode)
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        with pytest.raises(DetectorFailed) as caught:
            detect(detector, np.zeros((30, 40), np.uint8))
    message = str(caught.value)
    assert message.startswith('the detector blobdet:Misshapen returned bad boxes: ')
    assert words in message and '\n' not in message


def test_a_plugin_without_a_repr_is_described_by_its_kind_and_options(on_path):
    """The node's start-up line and an ensemble's repr showed <blobdet.Forgetful object at>."""
    from ipomdp_gaze.vision.detector import describe_detector
    from ipomdp_gaze.vision.detectors import make_detector
    assert describe_detector(make_detector('blobdet:Forgetful', min_red=120)) == \
        'blobdet:Forgetful(min_red=120)'
    ensemble = make_detector('ensemble', members=[{'kind': 'blob', 'min_red': 99, 'weight': 2}])
    assert repr(ensemble) == 'EnsembleDetector([blob(min_red=99) x2])'
    haar = make_detector('haar')
    assert describe_detector(haar) == repr(haar)


def test_a_name_two_installed_packages_declare_is_refused(on_path, tmp_path, monkeypatch):
    """The one later on sys.path was loaded silently (a dict kept the last entry point)."""
    from ipomdp_gaze.vision.detectors import make_detector
    for dist, target in (('twin_a', 'blobdet:BlobDetector'), ('twin_b', 'blobdet:Fussy')):
        info = tmp_path / f'{dist}-0.1.dist-info'
        info.mkdir()
        (info / 'METADATA').write_text(f'Metadata-Version: 2.1\nName: {dist}\nVersion: 0.1\n')
        (info / 'entry_points.txt').write_text(f'[ipomdp_gaze.detectors]\ntwin = {target}\n')
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ValueError, match=r"^detector 'twin' is declared by more than one "
                                         r'installed package \(twin_a 0.1: blobdet:BlobDetector; '
                                         r'twin_b 0.1: blobdet:Fussy\); uninstall one'):
        make_detector('twin')
    assert type(make_detector('blob')).__name__ == 'BlobDetector'   # one declaration: fine


@pytest.mark.parametrize('kind, words', [
    ('blobdet:Lopsided', 'window_px must be (width, height) in pixels, got (20,)'),
    ('blobdet:Secretive', 'its settings() raised RuntimeError: settings are secret'),
    ('blobdet:Listy', 'its settings() must return a dict of its options, got list'),
    ('blobdet:Needy', 'building it failed: RuntimeError: no GPU found'),
])
def test_a_plugin_that_breaks_as_it_is_built_is_one_line(on_path, tmp_path, capsys, kind,
                                                         words):
    """These were tracebacks in calibrate, find and the node (IndexError, RuntimeError)."""
    from ipomdp_gaze.vision.detectors import detector_from_settings, make_detector
    with pytest.raises(ValueError) as caught:
        make_detector(kind)
    assert str(caught.value) == f'detector {kind!r}: {words}'
    with pytest.raises(ValueError) as caught:            # a model file naming it
        detector_from_settings({'kind': kind})
    assert str(caught.value) == f'detector {kind!r}: {words}'
    labels = labelled_folder(tmp_path / 'images', n=2)
    capsys.readouterr()
    rc = cli(['calibrate', '--images', str(tmp_path / 'images'), '--labels', str(labels),
              '--detector', kind, '--out', str(tmp_path / 'x.yaml'), '--quiet'])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and err == [f'ipomdp-gaze calibrate: error: detector {kind!r}: {words}']


def test_calibrate_refuses_a_plugin_its_recorded_settings_cannot_rebuild(on_path, tmp_path,
                                                                         capsys):
    """The model was written, and find and the node refused it: now checked before the work."""
    labels = labelled_folder(tmp_path / 'images', n=2)
    out = tmp_path / 'x.yaml'
    capsys.readouterr()
    rc = cli(['calibrate', '--images', str(tmp_path / 'images'), '--labels', str(labels),
              '--detector', 'blobdet:Boastful', '--out', str(out), '--quiet'])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and not out.exists(), err
    assert 'the detector cannot be rebuilt from the settings its model would record' in err[0]
    assert "unexpected keyword argument 'max_red'" in err[0]
