# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Scenes from real photos (:mod:`ipomdp_gaze.vision.scenes`): determinism, split, truth, files."""
import math

import cv2
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.vision import scenes
from ipomdp_gaze.vision.scenes import read_labelled_folder, Scene, SceneSet, write_scene_set
import numpy as np
import pytest


def _square(scene: Scene) -> tuple[int, int, int]:
    """Return ``(x0, y0, side)`` of the pasted square, from the true centre and side."""
    x, y = scene.face_centre_px
    side = scene.face_px
    x0, y0 = x - side / 2.0, y - side / 2.0
    assert x0 == int(x0) and y0 == int(y0)
    return int(x0), int(y0), side


def test_lfw_subset_faces_are_the_first_hundred():
    from skimage import data
    crops = data.lfw_subset()
    assert crops.shape == (200, 25, 25) and crops.dtype == np.float64
    faces = scenes.load_faces()
    assert faces.shape == (100, 25, 25) and faces.dtype == np.float32
    np.testing.assert_allclose(faces, crops[:100] * 255.0, rtol=1e-6)
    assert not faces.flags.writeable


@pytest.mark.parametrize('name', scenes.TRAIN_BACKGROUNDS + scenes.TEST_BACKGROUNDS)
def test_every_background_loads_offline_in_both_colour_modes(name):
    grey = scenes.load_background(name, 'gray')
    rgb = scenes.load_background(name, 'rgb')
    assert grey.dtype == rgb.dtype == np.uint8
    assert grey.ndim == 2 and rgb.shape == grey.shape + (3,)
    big = scenes.load_background(name, 'gray', min_side=840)
    assert min(big.shape) == max(840, min(grey.shape))
    ratio = big.shape[1] / big.shape[0] / (grey.shape[1] / grey.shape[0])
    assert abs(ratio - 1.0) < 0.01


def test_splits_share_no_face_and_no_background():
    assert not set(scenes.TRAIN_FACES) & set(scenes.TEST_FACES)
    assert set(scenes.TRAIN_FACES) | set(scenes.TEST_FACES) == set(range(100))
    assert not set(scenes.TRAIN_BACKGROUNDS) & set(scenes.TEST_BACKGROUNDS)


def test_same_seed_and_index_give_the_same_scene_in_any_order():
    a = SceneSet('train', seed=3)
    forward = [a[i] for i in range(12)]
    b = SceneSet('train', seed=3)
    order = [11, 4, 0, 7, 7, 2, 9, 1, 10, 3, 5, 6, 8]
    backward = {i: b.scene(i) for i in order}
    scenes._backgrounds.clear()
    for i, scene in enumerate(forward):
        again = backward[i]
        assert np.array_equal(scene.image, again.image)
        assert (scene.face_centre_px, scene.face_px, scene.cell, scene.face_index,
                scene.background, scene.seed, scene.index) == \
            (again.face_centre_px, again.face_px, again.cell, again.face_index,
             again.background, again.seed, again.index)
        assert np.array_equal(scene.image, SceneSet('train', seed=3).scene(i).image)


def test_other_index_seed_or_split_gives_other_scenes():
    base = SceneSet('train', seed=0)
    images = [base[i].image for i in range(20)]
    for i in range(20):
        for j in range(i):
            assert not np.array_equal(images[i], images[j])
    for i in range(20):
        assert not np.array_equal(images[i], SceneSet('train', seed=1)[i].image)
        assert not np.array_equal(images[i], SceneSet('test', seed=0)[i].image)


def test_train_and_test_scenes_draw_only_from_their_split():
    for split, faces, backgrounds in (('train', scenes.TRAIN_FACES, scenes.TRAIN_BACKGROUNDS),
                                      ('test', scenes.TEST_FACES, scenes.TEST_BACKGROUNDS)):
        seen_faces, seen_backgrounds = set(), set()
        for seed in (0, 1):
            for scene in SceneSet(split, seed=seed, n=400, absent_rate=0.1):
                seen_backgrounds.add(scene.background)
                if scene.has_face:
                    seen_faces.add(scene.face_index)
        assert seen_faces <= set(faces) and seen_backgrounds <= set(backgrounds)
        # Every background and nearly every face of the split is drawn in 800 scenes.
        assert seen_backgrounds == set(backgrounds)
        assert len(seen_faces) >= len(faces) - 2


@pytest.mark.parametrize('task,grid', [(scenes.PAPER_TASK, (21, 21)),
                                       (scenes.SMALL_TASK, (21, 21)),
                                       (scenes.PAPER_TASK, Grid(7, 5))])
def test_face_inside_the_image_with_centre_size_and_cell_consistent(task, grid):
    size = task['size_px']
    lo, hi = task['face_px']
    rows, cols = (grid.rows, grid.cols) if isinstance(grid, Grid) else grid
    sides = []
    for scene in SceneSet('train', grid=grid, seed=5, n=300, **task):
        assert scene.image.shape == (size, size)
        x0, y0, side = _square(scene)
        assert lo <= side <= hi
        assert 0 <= x0 and x0 + side <= size and 0 <= y0 and y0 + side <= size
        x, y = scene.face_centre_px
        assert scene.cell == (math.floor(y * rows / size), math.floor(x * cols / size))
        assert scene.cell == scenes.cell_of_point(x, y, (size, size), (rows, cols))
        sides.append(side)
    # Sizes spread over the whole range (uniform draws), not stuck at one end.
    assert min(sides) < lo + 0.1 * (hi - lo) and max(sides) > hi - 0.1 * (hi - lo)


def test_cell_of_point_edges():
    assert scenes.cell_of_point(0.0, 0.0, (420, 420), (21, 21)) == (0, 0)
    assert scenes.cell_of_point(19.99, 20.0, (420, 420), (21, 21)) == (1, 0)
    assert scenes.cell_of_point(419.5, 419.5, (420, 420), (21, 21)) == (20, 20)
    with pytest.raises(ValueError, match='outside'):
        scenes.cell_of_point(420.0, 3.0, (420, 420), (21, 21))


def test_absent_rate_matches_and_absent_scenes_carry_no_truth():
    n, rate = 2000, 0.3
    absent = [not scene.has_face for scene in SceneSet('train', absent_rate=rate, n=n, seed=2)]
    observed = np.mean(absent)
    se = math.sqrt(rate * (1 - rate) / n)
    assert abs(observed - rate) < 4 * se
    scene = next(s for s in SceneSet('test', absent_rate=rate, seed=2) if not s.has_face)
    assert (scene.face_centre_px, scene.face_px, scene.cell, scene.face_index) == \
        (None, None, None, None)
    assert scene.background in scenes.TEST_BACKGROUNDS
    assert all(s.has_face for s in SceneSet('train', absent_rate=0.0, n=300))


def test_raising_absent_rate_only_removes_faces():
    low = SceneSet('train', absent_rate=0.1, n=300, seed=4)
    high = SceneSet('train', absent_rate=0.4, n=300, seed=4)
    for a, b in zip(low, high):
        if not a.has_face:
            assert not b.has_face
        if b.has_face:
            assert np.array_equal(a.image, b.image) and a.face_centre_px == b.face_centre_px


def test_face_edges_are_feathered_into_the_background():
    with_face = SceneSet('train', absent_rate=0.0, seed=6)
    without = SceneSet('train', absent_rate=0.95, seed=6)
    checked = 0
    for i in range(60):
        empty = without[i]
        if empty.has_face:
            continue
        scene = with_face[i]
        x0, y0, side = _square(scene)
        diff = scene.image.astype(int) - empty.image.astype(int)
        inside = np.zeros(diff.shape, dtype=bool)
        inside[y0:y0 + side, x0:x0 + side] = True
        assert not diff[~inside].any()
        patch = diff[y0:y0 + side, x0:x0 + side]
        ring = np.concatenate([patch[0], patch[-1], patch[:, 0], patch[:, -1]])
        assert not ring.any()
        next_ring = np.concatenate([patch[1, 1:-1], patch[-2, 1:-1], patch[1:-1, 1],
                                    patch[1:-1, -2]])
        assert np.abs(next_ring).max() <= 0.05 * 255
        ramp = round(scenes.DEFAULT_FEATHER * side)
        core = patch[ramp:-ramp, ramp:-ramp]
        assert np.abs(core).mean() > 5
        checked += 1
    assert checked >= 30


def test_feather_mask_shape():
    mask = scenes.feather_mask(100, 0.15)
    assert mask.shape == (100, 100)
    assert not mask[0].any() and not mask[:, -1].any()
    assert np.all(mask[15:85, 15:85] == 1.0)
    assert np.allclose(mask, mask.T) and np.allclose(mask, mask[::-1, ::-1])
    profile = mask[50, :16]
    assert np.all(np.diff(profile) > 0)
    assert np.all(scenes.feather_mask(7, 0.0) == 1.0)


def test_grey_and_rgb_scenes_share_the_layout():
    grey = SceneSet('train', color='gray', seed=8, n=20, absent_rate=0.2)
    rgb = SceneSet('train', color='rgb', seed=8, n=20, absent_rate=0.2)
    for g, c in zip(grey, rgb):
        assert g.image.dtype == c.image.dtype == np.uint8
        assert g.image.shape == (420, 420) and c.image.shape == (420, 420, 3)
        assert not g.image.flags.writeable and not c.image.flags.writeable
        assert (g.face_centre_px, g.face_px, g.cell, g.face_index, g.background) == \
            (c.face_centre_px, c.face_px, c.cell, c.face_index, c.background)
        if g.has_face:
            # Full alpha at the centre: the grey face is in all three channels.
            x, y = (int(v) for v in g.face_centre_px)
            assert np.abs(c.image[y, x].astype(int) - int(g.image[y, x])).max() <= 1
    grey_photo = SceneSet('train', color='rgb', seed=0)
    scene = next(s for s in grey_photo if s.background == 'grass')
    assert np.array_equal(scene.image[:, :, 0], scene.image[:, :, 2])


def test_sequence_protocol():
    bounded = SceneSet('test', n=5)
    assert len(bounded) == 5 and len(list(bounded)) == 5
    assert np.array_equal(bounded[-1].image, bounded[4].image)
    assert bounded[4].index == 4
    with pytest.raises(IndexError):
        bounded[5]
    unbounded = SceneSet('test')
    with pytest.raises(TypeError, match='unbounded'):
        len(unbounded)
    assert unbounded[10_000].index == 10_000
    with pytest.raises(IndexError):
        unbounded[-1]
    with pytest.raises(TypeError):
        bounded['1']
    assert 'test' in repr(bounded)


@pytest.mark.parametrize('kwargs,match', [
    ({'split': 'validation'}, 'unknown split'),
    ({'color': 'bgr'}, 'unknown color'),
    ({'face_px': (60, 500)}, 'do not fit'),
    ({'size_px': 100}, 'do not fit'),
    ({'face_px': (140, 60)}, 'empty'),
    ({'face_px': (0, 60)}, 'face_px min'),
    ({'face_px': (20.5, 60)}, 'face_px min'),
    ({'face_px': 60}, 'pair'),
    ({'absent_rate': 1.0}, 'absent_rate'),
    ({'absent_rate': -0.1}, 'absent_rate'),
    ({'seed': -1}, 'seed'),
    ({'seed': 1.5}, 'seed'),
    ({'grid': (21, 0)}, 'grid cols'),
    ({'grid': 21}, 'grid'),
    ({'n': -3}, 'n must'),
    ({'feather': 0.7}, 'feather'),
])
def test_bad_parameters_raise_clear_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SceneSet(**kwargs)


def test_unknown_background_and_colour():
    with pytest.raises(ValueError, match='unknown background'):
        scenes.load_background('astronaut')
    with pytest.raises(ValueError, match='unknown background'):
        scenes.load_background('camera')          # holds a face: a real photo, not a background
    with pytest.raises(ValueError, match='unknown color'):
        scenes.load_background('grass', 'grey')


@pytest.mark.parametrize('color', ['gray', 'rgb'])
def test_folder_round_trip(tmp_path, color):
    written = list(SceneSet('train', color=color, absent_rate=0.3, seed=9, n=12))
    assert any(not s.has_face for s in written) and any(s.has_face for s in written)
    csv_path = write_scene_set(written, tmp_path / 'set')
    assert csv_path == tmp_path / 'set' / 'labels.csv'
    lines = csv_path.read_text().splitlines()
    assert lines[0] == 'path,x,y' and len(lines) == 13
    read = read_labelled_folder(tmp_path / 'set', csv_path)
    assert len(read) == len(written)
    for scene, (image, centre) in zip(written, read):
        assert image.dtype == np.uint8 and np.array_equal(image, scene.image)
        assert centre == scene.face_centre_px
    with pytest.raises(ValueError, match='index 0'):
        write_scene_set([written[0], written[0]], tmp_path / 'twice')
    # The CSV name alone is looked up in the folder.
    assert len(read_labelled_folder(tmp_path / 'set', 'labels.csv')) == 12
    if color == 'rgb':
        # On disk the PNG is BGR (OpenCV's order); in memory it is RGB again.
        on_disk = cv2.imread(str(tmp_path / 'set' / 'scene_000000.png'), cv2.IMREAD_COLOR)
        assert np.array_equal(on_disk, written[0].image[:, :, ::-1])


def _folder(tmp_path, rows, image=None, name='a.png'):
    """Write one image and a CSV of ``rows`` (text after the header); return (folder, csv)."""
    if image is None:
        image = np.zeros((40, 60), dtype=np.uint8)
    cv2.imwrite(str(tmp_path / name), image)
    csv_path = tmp_path / 'labels.csv'
    csv_path.write_text('path,x,y\n' + rows)
    return tmp_path, csv_path


def test_reader_accepts_user_images(tmp_path):
    bgra = np.zeros((40, 60, 4), dtype=np.uint8)
    bgra[..., 0] = 200
    folder, csv_path = _folder(tmp_path, 'a.png,59.5,39.9\nb.png,,\n', image=bgra)
    cv2.imwrite(str(tmp_path / 'b.png'), np.full((10, 10), 7, dtype=np.uint8))
    (first, centre), (second, none) = read_labelled_folder(folder, csv_path)
    assert first.shape == (40, 60, 3) and np.all(first[..., 2] == 200) and centre == (59.5, 39.9)
    assert second.shape == (10, 10) and none is None


def test_reader_turns_an_image_as_its_exif_orientation_says(tmp_path):
    """
    A phone's photo stored sideways (EXIF orientation 6) is labelled as a viewer shows it.

    find searches it turned; the reader took the stored pixels (IMREAD_UNCHANGED ignores EXIF),
    so that a centre inside the picture was 'outside the 40x30 image', or at another place.
    """
    from PIL import Image
    shown = np.zeros((40, 30, 3), dtype=np.uint8)           # 30 wide, 40 high, as displayed
    shown[30:40, 0:10] = 255                                # the "face": bottom-left corner
    stored = np.rot90(shown, k=1)                           # turned back a quarter: 40x30
    exif = Image.Exif()
    exif[0x0112] = 6                                        # display: turn 90 degrees clockwise
    Image.fromarray(np.ascontiguousarray(stored)).save(tmp_path / 'a.jpg', quality=95,
                                                       exif=exif.tobytes())
    (tmp_path / 'labels.csv').write_text('path,x,y\na.jpg,5,35\n')
    ((image, centre),) = read_labelled_folder(tmp_path, tmp_path / 'labels.csv')
    assert image.shape == (40, 30, 3) and centre == (5.0, 35.0)
    assert image[35, 5].min() > 200 and image[5, 25].max() < 50


@pytest.mark.parametrize('rows,error,match', [
    ('a.png,60,10\n', ValueError, 'outside the 60x40'),
    ('a.png,10,-0.5\n', ValueError, 'outside'),
    ('a.png,10,\n', ValueError, 'both x and y'),
    ('a.png,ten,3\n', ValueError, 'numbers'),
    ('a.png,nan,3\n', ValueError, 'finite'),
    ('missing.png,1,1\n', FileNotFoundError, 'missing.png'),
    (',1,1\n', ValueError, 'empty path'),
    ('', ValueError, 'no images'),
])
def test_reader_rejects_bad_labels(tmp_path, rows, error, match):
    folder, csv_path = _folder(tmp_path, rows)
    with pytest.raises(error, match=match):
        read_labelled_folder(folder, csv_path)


def test_reader_rejects_bad_files(tmp_path):
    folder, csv_path = _folder(tmp_path, 'a.png,1,1\n')
    (tmp_path / 'bad.csv').write_text('file,x,y\na.png,1,1\n')
    with pytest.raises(ValueError, match='missing'):
        read_labelled_folder(folder, tmp_path / 'bad.csv')
    with pytest.raises(FileNotFoundError, match='label CSV'):
        read_labelled_folder(folder, tmp_path / 'nope.csv')
    with pytest.raises(FileNotFoundError, match='folder'):
        read_labelled_folder(tmp_path / 'nowhere', csv_path)
    (tmp_path / 'a.png').write_bytes(b'not a png at all')
    with pytest.raises(ValueError, match='line 2: cannot decode'):
        read_labelled_folder(folder, csv_path)
    cv2.imwrite(str(tmp_path / 'a.png'), np.zeros((8, 8), dtype=np.uint16))
    with pytest.raises(ValueError, match='uint16'):
        read_labelled_folder(folder, csv_path)


def test_reader_takes_excel_csv_and_names_a_label_file_that_is_no_csv(tmp_path, cli_here):
    """
    QA: Excel's "CSV UTF-8" (a byte order mark first) was "missing ['path']" of its own header.

    An image given as ``--labels`` was refused by the codec alone ('utf-8' codec can't
    decode byte 0x89), naming no file; a folder "did not exist".
    """
    from ipomdp_gaze.vision.scenes import labelled_names
    folder, csv_path = _folder(tmp_path, 'a.png,1,1\n')
    csv_path.write_bytes(b'\xef\xbb\xbf' + csv_path.read_bytes())
    ((image, centre),) = read_labelled_folder(folder, csv_path)
    assert centre == (1.0, 1.0) and labelled_names(folder, csv_path) == ['a.png']
    image_path = tmp_path / 'a.png'
    for read in (read_labelled_folder, labelled_names):
        with pytest.raises(ValueError) as refused:
            read(folder, image_path)
        assert str(refused.value) == \
            f"{image_path}: not a UTF-8 text CSV (path,x,y): byte 0 is b'\\x89'"
    run = cli_here('calibrate', '--images', folder, '--labels', tmp_path, '--out',
                   tmp_path / 'out.yaml')
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        f'ipomdp-gaze calibrate: error: label CSV {tmp_path} is a folder, not a CSV file']


def test_opencv_cascade_finds_the_pasted_faces():
    """
    The real detector finds most pasted faces: the scenes are usable for calibration.

    Measured with OpenCV 4.14: all 30 of these train scenes (196 of the first 200; 60-140 px
    faces at 420x420) have a grouped detection (``detectMultiScale(gray, 1.1, 3)``) centred
    within one face side of the truth. The bar is lower to leave room for other OpenCV 4.x
    builds and cascades that miss one hard face (face 30 caused 3 of the 4 misses).
    """
    cascade = cv2.CascadeClassifier(cv2.data.haarcascades + 'haarcascade_frontalface_alt2.xml')
    assert not cascade.empty()
    found = 0
    scene_set = SceneSet('train', seed=0, n=30, **scenes.PAPER_TASK)
    for scene in scene_set:
        x, y = scene.face_centre_px
        boxes = cascade.detectMultiScale(scene.image, 1.1, 3)
        found += any(math.hypot(bx + bw / 2 - x, by + bh / 2 - y) <= scene.face_px
                     for bx, by, bw, bh in boxes)
    assert found / len(scene_set) >= 0.8, f'{found}/{len(scene_set)} faces found'
