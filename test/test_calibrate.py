# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Calibration of count models: tallies per offset, pooling, priors and the command."""
import subprocess
import sys

from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.vision.calibrate import (count_model, hit_false_alarm, pool_target, Tallies,
                                          tally_image)
from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig
from ipomdp_gaze.vision.scenes import SceneSet, write_scene_set
import numpy as np
import pytest

GRID = Grid(5, 5, 1.0)


def test_tally_image_counts_every_fixation_at_its_offset():
    """A detector that always reports the target cell: hits at every offset, no false alarms."""
    config = FoveaConfig(windows_cells=(5,), scales=(1.0,), max_count=3)

    def detector(gray):
        # The 50x50 image is one window: a detection centred in cell (1, 3) (x 35, y 15).
        return np.array([[33, 13, 4, 4], [33, 13, 4, 4], [33, 13, 4, 4], [33, 13, 4, 4]])

    fovea = Fovea(detector, GRID, config)
    image = np.zeros((50, 50), dtype=np.uint8)
    tallies = tally_image(fovea, image, target_cell=GRID.index(1, 3))
    assert tallies.images == 1 and tallies.fixations == 25
    # Every fixation sees count 4, clipped to K-1 = 2, in the target cell, at its own offset.
    assert tallies.target[:, :, 2].sum() == 25 and tallies.target[:, :, :2].sum() == 0
    rows, cols = np.meshgrid(range(5), range(5), indexing='ij')
    expected = np.zeros((5, 5), dtype=int)
    np.add.at(expected, (np.abs(rows - 1).ravel(), np.abs(cols - 3).ravel()), 1)
    np.testing.assert_array_equal(tallies.target[:, :, 2], expected)
    # Every other cell shows 0, at its offset, for each fixation: 24 null tallies per fixation.
    assert tallies.null[:, :, 0].sum() == 25 * 24 and tallies.null[:, :, 1:].sum() == 0
    absent = tally_image(fovea, image, target_cell=None)
    assert absent.target.sum() == 0 and absent.null[:, :, 2].sum() == 25


def test_count_model_uses_the_dirichlet_prior_and_pools_radially():
    tallies = Tallies.empty(GRID, 3)
    tallies.target[0, 0] = [0, 2, 8]
    tallies.null[0, 0] = [97, 2, 1]
    tallies.null[1:, :, 0] = 10
    tallies.null[0, 1:, 0] = 10
    model = count_model(tallies, GRID, prior=1.0, pool_radius=0.0, min_tallies=0)
    np.testing.assert_allclose(model.p_target[0, 0], [1 / 13, 3 / 13, 9 / 13])
    np.testing.assert_allclose(model.p_null[0, 0], [98 / 103, 3 / 103, 2 / 103])
    np.testing.assert_allclose(model.p_target[4, 4], [1 / 3] * 3)        # no data: the prior
    hit, fa = hit_false_alarm(model)
    assert hit[0, 0] == pytest.approx(12 / 13) and fa[0, 0] == pytest.approx(5 / 103)
    with pytest.raises(ValueError, match='no labelled face'):
        count_model(Tallies.empty(GRID, 3), GRID)


def test_pooling_sums_offsets_at_similar_distances_and_widens_where_data_are_thin():
    tallies = np.zeros((3, 3, 2))
    tallies[0, 1] = [1, 3]                      # distance 1
    tallies[1, 0] = [2, 2]                      # distance 1
    tallies[2, 2] = [0, 0]                      # distance 2.83: no data
    pooled = pool_target(tallies, 0.0)
    np.testing.assert_array_equal(pooled, tallies)
    pooled = pool_target(tallies, 0.1)
    np.testing.assert_array_equal(pooled[0, 1], [3, 5])
    np.testing.assert_array_equal(pooled[1, 0], [3, 5])
    wide = pool_target(tallies, 0.1, min_tallies=4)
    np.testing.assert_array_equal(wide[2, 2], [3, 5])       # borrowed from distance 1
    assert wide[2, 2].sum() >= 4


def test_calibrate_command_on_scenes_and_on_a_labelled_folder(tmp_path, cli_here):
    """Tiny runs: the hit rate at offset 0 beats the false-alarm rate (real detector)."""
    out = tmp_path / 'faces.yaml'
    done = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'calibrate', '--scenes', '6',
                           '--grid', '7x7', '--windows', '7,3', '--scales', '1/2,1',
                           '--processes', '1', '--out', str(out), '--quiet'],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    model = load_observation(out)
    hit, fa = hit_false_alarm(model)
    assert hit[0, 0] > fa[0, 0]
    assert model.meta['image'] == {'width': 420, 'height': 420}
    assert model.meta['fovea']['windows_cells'] == [7, 3]
    assert model.meta['calibration']['images'] == 6
    assert (tmp_path / 'faces.png').is_file() and 'hit' in done.stdout
    folder = tmp_path / 'labelled'
    write_scene_set([SceneSet('train', grid=(7, 7), seed=4)[i] for i in range(3)], folder)
    run = cli_here('calibrate', '--images', folder, '--labels', folder / 'labels.csv', '--grid',
                   '7x7', '--windows', '7,3', '--processes', '1', '--out',
                   tmp_path / 'mine.yaml', '--quiet')
    assert run.returncode == 0, run.stderr
    assert load_observation(tmp_path / 'mine.yaml').meta['calibration']['images'] == 3


@pytest.mark.parametrize('args, message', [
    (['--scenes', '2', '--labels', 'x.csv'], '--labels goes with --images'),
    (['--images', '.'], '--images needs --labels CSV'),
    (['--scenes', '2', '--windows', '3,7'], 'strictly decreasing'),
    (['--scenes', '2', '--scales', '1/0'], 'expected comma-separated numbers'),
    (['--scenes', '2', '--out', 'x.json'], '--out must end in .yaml'),
    (['--scenes', '2', '--scan-once', '--windows', '15,9,3'],
     'scan_once needs a whole-image window'),
])
def test_bad_arguments_are_one_line(args, message, tmp_path, cli_here):
    argv = list(args)
    if '--out' not in args:
        argv += ['--out', str(tmp_path / 'o.yaml')]
    run = cli_here('calibrate', *argv)
    assert run.returncode == 2 and 'Traceback' not in run.stderr
    assert message in run.stderr.strip().splitlines()[-1]


def test_a_csv_naming_pixels_outside_the_image_is_refused(tmp_path, cli_here):
    folder = tmp_path / 'labelled'
    write_scene_set([SceneSet('train', seed=5)[0]], folder)
    csv = folder / 'labels.csv'
    name = csv.read_text().splitlines()[1].split(',')[0]
    csv.write_text(f'path,x,y\n{name},999,5\n')
    run = cli_here('calibrate', '--images', folder, '--labels', csv, '--out',
                   tmp_path / 'o.yaml', '--quiet')
    assert run.returncode == 2 and 'Traceback' not in run.stderr
    assert 'outside' in run.stderr.strip().splitlines()[-1]


def test_scan_tallies_are_offset_free_and_build_the_scan_tables():
    """A detector that always reports cell (1, 3): the scan tallies it once per image."""
    config = FoveaConfig(windows_cells=(5, 3), scales=(1.0, 1.0), max_count=3, scan_once=True)

    def detector(gray):
        if gray.shape == (50, 50):                            # the whole-image window only
            return np.array([[33, 13, 4, 4]])
        return np.zeros((0, 4), dtype=int)

    fovea = Fovea(detector, GRID, config)
    tallies = tally_image(fovea, np.zeros((50, 50), dtype=np.uint8), GRID.index(1, 3))
    np.testing.assert_array_equal(tallies.scan_target, [0, 1, 0])
    np.testing.assert_array_equal(tallies.scan_null, [24, 0, 0])
    # The fixation frames (3-cell windows) never count the scan's box: 9 of them see the cell.
    assert tallies.target[:, :, 0].sum() == 9 and tallies.target[:, :, 1:].sum() == 0
    model = count_model(tallies, GRID, prior=1.0, scan=True)
    np.testing.assert_allclose(model.scan_target, [1 / 4, 2 / 4, 1 / 4])
    np.testing.assert_allclose(model.scan_null, [25 / 27, 1 / 27, 1 / 27])
    with pytest.raises(ValueError, match='no scan was tallied'):
        count_model(_no_scan(), GRID, scan=True)


def _no_scan():
    tallies = Tallies.empty(GRID, 3)
    tallies.target[0, 0] = [1, 0, 0]
    return tallies


def test_lattice_fixations_keep_the_edges_and_calibration_can_use_them():
    from ipomdp_gaze.vision.calibrate import lattice_fixations, tally_images
    grid = Grid(5, 5, 1.0)
    cells = lattice_fixations(grid, 2)
    assert sorted(map(tuple, np.column_stack(grid.cell(cells)))) == \
        [(r, c) for r in (0, 2, 4) for c in (0, 2, 4)]
    assert sorted(lattice_fixations(grid, 3)) == sorted(
        r * 5 + c for r in (0, 3, 4) for c in (0, 3, 4))
    np.testing.assert_array_equal(np.sort(lattice_fixations(grid, 1)), np.arange(25))
    with pytest.raises(ValueError, match='positive integer'):
        lattice_fixations(grid, 0)
    items = [('scene', {'split': 'train', 'size_px': 100, 'face_px': (30, 40), 'grid': (5, 5),
                        'seed': 0}, i) for i in range(2)]
    config = FoveaConfig(windows_cells=(5, 3), scales=(1.0, 1.0), max_count=4)
    tallies = tally_images(items, {}, grid, config, processes=1, fixations=cells)
    assert tallies.images == 2 and tallies.fixations == 2 * 9
    assert tallies.null.sum() + tallies.target.sum() == 2 * 9 * 25     # 5-cell window: all seen


def _resized_copy(folder, scale: float, names) -> None:
    """Resize the named images of a labelled folder in place, and their labels."""
    import cv2
    rows = (folder / 'labels.csv').read_text().splitlines()
    out = [rows[0]]
    for row in rows[1:]:
        name, x, y = row.split(',')
        if name in names:
            image = cv2.imread(str(folder / name), cv2.IMREAD_UNCHANGED)
            cv2.imwrite(str(folder / name), cv2.resize(image, None, fx=scale, fy=scale,
                                                       interpolation=cv2.INTER_LINEAR))
            x, y = (f'{float(v) * scale:g}' if v else v for v in (x, y))
        out.append(f'{name},{x},{y}')
    (folder / 'labels.csv').write_text('\n'.join(out) + '\n')


def test_resize_calibrates_a_folder_of_several_sizes_as_the_images_resized_first(
        tmp_path, cli_here):
    """--resize: images and labels resized to one size give the model of that folder resized."""
    import cv2
    scenes = [SceneSet('train', grid=(7, 7), seed=4)[i] for i in range(3)]
    mixed, resized = tmp_path / 'mixed', tmp_path / 'resized'
    write_scene_set(scenes, mixed)
    names = [row.split(',')[0] for row in (mixed / 'labels.csv').read_text().splitlines()[1:]]
    _resized_copy(mixed, 1.5, names[1:])                      # 630x630 and 420x420 images
    common = ['--labels', mixed / 'labels.csv', '--grid', '7x7', '--windows', '7,3',
              '--processes', '1', '--quiet']
    run = cli_here('calibrate', '--images', mixed, *common, '--out', tmp_path / 'no.yaml')
    assert run.returncode == 2 and 'Traceback' not in run.stderr
    last = run.stderr.strip().splitlines()[-1]
    assert 'share one size' in last and '420x420, 630x630' in last and '--resize' in last
    run = cli_here('calibrate', '--images', mixed, *common, '--resize', '420x420', '--out',
                   tmp_path / 'mixed.yaml')
    assert run.returncode == 0, run.stderr
    # the same images resized by hand (area down to 420, as --resize does) and their labels
    write_scene_set(scenes, resized)
    rows = []
    for row in (mixed / 'labels.csv').read_text().splitlines()[1:]:
        name, x, y = row.split(',')
        image = cv2.imread(str(mixed / name), cv2.IMREAD_UNCHANGED)
        if image.shape[0] != 420:
            image = cv2.resize(image, (420, 420), interpolation=cv2.INTER_AREA)
            x, y = (f'{float(v) * 420 / 630!r}' if v else v for v in (x, y))
        cv2.imwrite(str(resized / name), image)
        rows.append(f'{name},{x},{y}')
    (resized / 'labels.csv').write_text('path,x,y\n' + '\n'.join(rows) + '\n')
    run = cli_here('calibrate', '--images', resized, '--labels', resized / 'labels.csv',
                   *common[2:], '--out', tmp_path / 'resized.yaml')
    assert run.returncode == 0, run.stderr
    mine, theirs = load_observation(tmp_path / 'mixed.yaml'), load_observation(
        tmp_path / 'resized.yaml')
    np.testing.assert_array_equal(mine.p_target, theirs.p_target)
    np.testing.assert_array_equal(mine.p_null, theirs.p_null)
    assert mine.meta['image'] == {'width': 420, 'height': 420}
    assert mine.meta['calibration']['source']['resize'] == [420, 420]
    assert 'resize' not in theirs.meta['calibration']['source']


def test_resize_refuses_another_aspect_ratio_naming_the_image(tmp_path, cli_here):
    import cv2
    folder = tmp_path / 'labelled'
    write_scene_set([SceneSet('train', grid=(7, 7), seed=4)[i] for i in range(2)], folder)
    name = (folder / 'labels.csv').read_text().splitlines()[2].split(',')[0]
    image = cv2.imread(str(folder / name), cv2.IMREAD_UNCHANGED)
    cv2.imwrite(str(folder / name), image[:300])                 # 420x300: 7:5, not 1:1
    rows = (folder / 'labels.csv').read_text().splitlines()
    rows[2] = f'{name},,'
    (folder / 'labels.csv').write_text('\n'.join(rows) + '\n')
    run = cli_here('calibrate', '--images', folder, '--labels', folder / 'labels.csv',
                   '--resize', '210x210', '--out', tmp_path / 'o.yaml', '--quiet')
    assert run.returncode == 2 and 'Traceback' not in run.stderr
    last = run.stderr.strip().splitlines()[-1]
    assert f'--resize 210x210: {name} is 420x300 px, another aspect ratio' in last


def test_resize_labelled_scales_each_centre_with_its_image():
    from ipomdp_gaze.commands.calibrate import resize_labelled
    from ipomdp_gaze.vision.scenes import LabelledImage
    items = [LabelledImage(np.zeros((100, 150), np.uint8), (30.0, 90.0)),
             LabelledImage(np.zeros((200, 301), np.uint8), None),    # 3:2 within 0.5%
             LabelledImage(np.zeros((60, 90, 3), np.uint8), (0.0, 59.5))]
    out = resize_labelled(items, (300, 200))
    assert [item.image.shape for item in out] == [(200, 300), (200, 300), (200, 300, 3)]
    assert out[0].centre_px == (60.0, 180.0) and out[1].centre_px is None
    assert out[2].centre_px == pytest.approx((0.0, 59.5 * 200 / 60))


@pytest.mark.parametrize('args, message', [
    (['--pan-tilt', '--scenes', '2', '--camera', '320'], 'WIDTHxHEIGHT'),
    (['--images', '.', '--labels', 'x.csv', '--resize', '0x10'], 'WIDTHxHEIGHT'),
    (['--pan-tilt', '--scenes', '2', '--resize', '320x240'],
     '--resize is for the image task'),
])
def test_bad_sizes_are_one_line(args, message, tmp_path, cli_here):
    run = cli_here('calibrate', *args, '--out', tmp_path / 'o.yaml')
    assert run.returncode == 2 and 'Traceback' not in run.stderr
    assert message in run.stderr.strip().splitlines()[-1]
