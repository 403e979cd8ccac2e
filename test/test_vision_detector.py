# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The detector interface, the Haar cascade, grey conversion and the full-frame scan baseline."""
import cv2
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.vision import detector as detector_module
from ipomdp_gaze.vision.detector import (as_boxes, find_cascade, group_boxes, HaarDetector,
                                         REFERENCE_CASCADE, to_gray)
from ipomdp_gaze.vision.fullframe import cells_of_points, scan
import numpy as np
import pytest
from skimage import data

# The astronaut's face, checked by eye on the 512x512 image: the nose tip, midway between the
# eyes and the mouth, is at about (225, 115); OpenCV's grouped detection is (177, 66, 97, 97).
ASTRONAUT_FACE_PX = (225.0, 115.0)
GRID = Grid(21, 21)


def face_cell_rc(image_shape, grid=GRID):
    """``(row, col)`` of the astronaut's face centre on ``grid`` over an image of this shape."""
    height, width = image_shape[:2]
    x, y = ASTRONAUT_FACE_PX[0] * width / 512, ASTRONAUT_FACE_PX[1] * height / 512
    return int(y * grid.rows // height), int(x * grid.cols // width)


def chebyshev(cell, rc, grid=GRID):
    row, col = grid.cell(cell)
    return max(abs(row - rc[0]), abs(col - rc[1]))


@pytest.fixture(scope='module')
def astronaut():
    return data.astronaut()


@pytest.fixture(scope='module')
def haar():
    return HaarDetector()


class FakeDetector:
    """Record the shapes it is called with; return fixed boxes (no ``window_px``, no group)."""

    def __init__(self, boxes=()):
        self.boxes = np.asarray(boxes, dtype=np.int64).reshape(-1, 4)
        self.shapes = []

    def __call__(self, gray):
        self.shapes.append(gray.shape)
        return self.boxes


# ---- to_gray -----------------------------------------------------------------------------------

def test_to_gray_passes_grey_and_converts_rgb_in_rgb_order():
    grey = np.arange(30 * 40, dtype=np.uint8).reshape(30, 40)
    out = to_gray(grey)
    assert out.dtype == np.uint8 and out.shape == (30, 40) and np.array_equal(out, grey)
    assert to_gray(grey[:, ::2]).flags.c_contiguous
    red = np.zeros((30, 40, 3), np.uint8)
    red[..., 0] = 255                                  # RGB: channel 0 is red (0.299 R)
    assert np.all(to_gray(red) == 76)
    blue = red[..., ::-1].copy()                       # channel 2 is blue (0.114 B)
    assert np.all(to_gray(blue) == 29)
    rgb = np.random.default_rng(0).integers(0, 256, (25, 31, 3), dtype=np.uint8)
    assert np.array_equal(to_gray(rgb), cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY))


@pytest.mark.parametrize('image, reason', [
    (np.zeros((30, 30), np.float32), 'uint8'),
    (np.zeros((30, 30), np.uint16), 'uint8'),
    (np.zeros((30, 30), bool), 'uint8'),
    (np.zeros((30, 30, 4), np.uint8), '4'),
    (np.zeros((30, 30, 1), np.uint8), '3 channels'),
    (np.zeros((2, 30, 30, 3), np.uint8), 'shape'),
    (np.zeros(30, np.uint8), 'shape'),
    (np.zeros((1, 1), np.uint8), 'smaller'),
    (np.zeros((1, 1, 3), np.uint8), 'smaller'),
    ([[1, 2], [3, 4]], 'numpy array'),
])
def test_to_gray_rejects_bad_images_naming_the_problem(image, reason):
    with pytest.raises(ValueError, match=reason):
        to_gray(image)


def test_to_gray_rejects_images_smaller_than_the_detector_window(haar):
    assert haar.window_px == (20, 20)
    to_gray(np.zeros((20, 20), np.uint8), haar.window_px)
    with pytest.raises(ValueError, match='19x40 .* smaller than the 20x20'):
        to_gray(np.zeros((40, 19), np.uint8), haar.window_px)
    with pytest.raises(ValueError, match='smaller'):
        scan(np.zeros((19, 19), np.uint8), haar)


# ---- find_cascade ------------------------------------------------------------------------------

def test_find_cascade_takes_the_explicit_path_only(tmp_path):
    own = tmp_path / REFERENCE_CASCADE
    own.write_text('<opencv_storage/>')
    assert find_cascade(REFERENCE_CASCADE, tmp_path) == own          # a folder
    assert find_cascade(REFERENCE_CASCADE, own) == own               # a file
    assert find_cascade(str(own)) == own                             # a name with a folder
    assert find_cascade(REFERENCE_CASCADE).parent == detector_module.Path(cv2.data.haarcascades)


def test_find_cascade_refuses_an_explicit_place_without_the_file(tmp_path):
    """It fell through to OpenCV's copy: a cascade_dir mistyped went unnoticed."""
    with pytest.raises(ValueError) as raised:
        find_cascade(REFERENCE_CASCADE, tmp_path / 'elsewhere')
    assert str(raised.value) == (f'cascade folder {tmp_path / "elsewhere"} does not exist (it '
                                 f'was to hold {REFERENCE_CASCADE})')
    with pytest.raises(ValueError) as raised:
        find_cascade(REFERENCE_CASCADE, tmp_path)
    assert str(raised.value) == f'cascade folder {tmp_path} has no {REFERENCE_CASCADE}'
    with pytest.raises(ValueError, match=f'has no {REFERENCE_CASCADE}'):
        HaarDetector(cascade_dir=tmp_path)


def test_find_cascade_without_cv2_data_uses_the_system_folder(tmp_path, monkeypatch):
    system = tmp_path / 'haarcascades'
    system.mkdir()
    (system / REFERENCE_CASCADE).write_text('<opencv_storage/>')
    monkeypatch.delattr(cv2, 'data', raising=False)
    monkeypatch.setattr(detector_module, 'SYSTEM_CASCADE_DIRS', (system,))
    assert find_cascade(REFERENCE_CASCADE) == system / REFERENCE_CASCADE


def test_find_cascade_lists_every_place_searched_in_order(tmp_path, monkeypatch):
    system = tmp_path / 'system'
    monkeypatch.setattr(detector_module, 'SYSTEM_CASCADE_DIRS', (system,))
    with pytest.raises(FileNotFoundError) as info:
        find_cascade(str(tmp_path / 'no_such_cascade.xml'))
    message = str(info.value)
    places = [str(tmp_path / 'no_such_cascade.xml'),
              str(detector_module.Path(cv2.data.haarcascades) / 'no_such_cascade.xml'),
              str(system / 'no_such_cascade.xml')]
    positions = [message.find(place) for place in places]
    assert all(p >= 0 for p in positions) and positions == sorted(positions), message


# ---- boxes, grouping, the Haar detector --------------------------------------------------------

def test_as_boxes_normalises_and_validates():
    assert as_boxes(()).shape == (0, 4)
    assert as_boxes([[1, 2, 3, 4]]).dtype == np.int64
    assert as_boxes(np.array([[1.0, 2.0, 3.0, 4.0]])).tolist() == [[1, 2, 3, 4]]
    for bad, reason in (([1, 2, 3, 4], 'shape'), ([[1, 2, 3]], 'shape'),
                        ([[1.5, 2, 3, 4]], 'integer'), ([[1, 2, 0, 4]], 'positive')):
        with pytest.raises(ValueError, match=reason):
            as_boxes(bad)


def test_haar_detector_raw_boxes_and_grouping_match_opencv(astronaut, haar):
    gray = cv2.cvtColor(astronaut, cv2.COLOR_RGB2GRAY)
    raw = haar(gray)
    assert raw.ndim == 2 and raw.shape[1] == 4 and raw.dtype == np.int64
    # OpenCV's parallel search returns the raw boxes in a varying order; HaarDetector sorts.
    assert np.array_equal(raw, sorted(raw.tolist()))
    assert np.array_equal(raw, haar(gray))
    cascade = cv2.CascadeClassifier(str(find_cascade()))
    assert np.array_equal(np.unique(raw, axis=0),
                          np.unique(cascade.detectMultiScale(gray, 1.1, 0), axis=0))
    grouped = haar.group(raw)
    assert np.array_equal(np.unique(grouped, axis=0),
                          np.unique(cascade.detectMultiScale(gray, 1.1, 3), axis=0))
    assert np.array_equal(group_boxes(raw, 0), raw)
    assert group_boxes((), 3).shape == (0, 4)


def test_haar_detector_sees_nothing_below_its_window_and_rejects_bad_input(haar):
    assert haar(np.zeros((19, 200), np.uint8)).shape == (0, 4)
    with pytest.raises(ValueError, match='2-D uint8'):
        haar(np.zeros((40, 40, 3), np.uint8))
    with pytest.raises(ValueError, match='scale_factor'):
        HaarDetector(scale_factor=1.0)
    with pytest.raises(ValueError, match='min_neighbors'):
        HaarDetector(min_neighbors=-1)
    with pytest.raises(ValueError, match='min_size_px'):
        HaarDetector(min_size_px=(10, 0))
    with pytest.raises(FileNotFoundError):
        HaarDetector('no_such_cascade.xml')


def test_haar_detector_settings_and_size_limits(astronaut, haar):
    settings = haar.settings()
    assert settings['cascade'] == REFERENCE_CASCADE and settings['scale_factor'] == 1.1
    assert settings['min_neighbors'] == 0 and settings['window_px'] == [20, 20]
    assert len(settings['cascade_sha256']) == 64 and settings['opencv'] == cv2.__version__
    gray = cv2.cvtColor(astronaut, cv2.COLOR_RGB2GRAY)
    limited = HaarDetector(min_size_px=60, max_size_px=(90, 90))
    assert limited.settings()['min_size_px'] == [60, 60]
    boxes = limited(gray)
    assert len(boxes) and np.all((boxes[:, 2] >= 60) & (boxes[:, 2] <= 90))


def test_several_cascades_return_every_cascades_raw_boxes_and_mirror_maps_back(astronaut):
    gray = cv2.cvtColor(astronaut, cv2.COLOR_RGB2GRAY)
    names = [REFERENCE_CASCADE, 'haarcascade_profileface.xml']
    both = HaarDetector(names, mirror=[False, True])
    frontal = cv2.CascadeClassifier(str(find_cascade(names[0])))
    profile = cv2.CascadeClassifier(str(find_cascade(names[1])))
    flipped = as_boxes(profile.detectMultiScale(np.ascontiguousarray(gray[:, ::-1]), 1.1, 0))
    assert len(flipped)
    flipped[:, 0] = gray.shape[1] - flipped[:, 0] - flipped[:, 2]
    expected = np.concatenate([as_boxes(frontal.detectMultiScale(gray, 1.1, 0)),
                               as_boxes(profile.detectMultiScale(gray, 1.1, 0)), flipped])
    raw = both(gray)
    assert np.array_equal(raw, sorted(raw.tolist()))
    assert np.array_equal(raw, expected[np.lexsort(expected.T[::-1])])
    # A mirrored box covers the mirror image of what the cascade saw in the flipped image.
    x, y, w, h = flipped[0]
    assert 0 <= x and x + w <= gray.shape[1]


def test_several_cascades_are_recorded_as_lists_and_rebuilt_from_them():
    names = [REFERENCE_CASCADE, 'haarcascade_profileface.xml']
    both = HaarDetector(names, mirror=[False, True])
    settings = both.settings()
    assert settings['cascade'] == names and settings['mirror'] == [False, True]
    assert [len(sha) for sha in settings['cascade_sha256']] == [64, 64]
    assert settings['window_px'] == [20, 20]
    assert HaarDetector.from_settings(settings).settings() == settings
    # One cascade without mirroring keeps the reference's record, so old model files still load.
    assert 'mirror' not in HaarDetector(names[:1]).settings()
    assert HaarDetector(names[:1], mirror=True).settings()['cascade'] == names[:1]
    wrong = dict(settings, cascade_sha256=[settings['cascade_sha256'][0], '0' * 64])
    with pytest.raises(ValueError, match='profileface.*differs'):
        HaarDetector.from_settings(wrong)


@pytest.mark.parametrize('cascade, mirror, reason', [
    ([], False, 'non-empty list'),
    ([REFERENCE_CASCADE, 3], False, 'non-empty list'),
    ([REFERENCE_CASCADE], [True, False], 'list of 1'),
    ([REFERENCE_CASCADE], 'yes', 'mirror must be'),
    ([REFERENCE_CASCADE], [1], 'mirror must be'),
])
def test_several_cascades_refuse_bad_lists(cascade, mirror, reason):
    with pytest.raises(ValueError, match=reason):
        HaarDetector(cascade, mirror=mirror)


# ---- the full-frame scan -----------------------------------------------------------------------

def test_cells_of_points_follow_the_floor_rule_on_non_multiple_sizes():
    shape = (417, 430)                                  # H, W
    points = np.array([[0.0, 0.0], [429.99, 416.99], [20.47, 19.85], [20.48, 19.86]])
    cells = cells_of_points(points, shape, GRID)
    expected = [GRID.index(int(y * 21 // 417), int(x * 21 // 430)) for x, y in points]
    assert cells.tolist() == expected
    assert cells.tolist()[:2] == [0, 440]
    assert GRID.cell(int(cells[2])) == (0, 0) and GRID.cell(int(cells[3])) == (1, 1)


def test_scan_downscales_and_maps_boxes_back_to_full_image_cells():
    # 420x420 at scale 1/2: the detector sees 210x210; a box centred at (51, 31) there is at
    # (102, 62) in the image: cell (floor(62 / 20), floor(102 / 20)) = (3, 5).
    fake = FakeDetector([[46, 26, 10, 10]] * 2 + [[100, 100, 10, 10]])
    result = scan(np.zeros((420, 420), np.uint8), fake, GRID, scale=0.5)
    assert fake.shapes == [(210, 210)]
    assert result.detector_pixels == 210 * 210 and result.scale == 0.5
    assert result.cell == GRID.index(3, 5)
    assert result.counts[GRID.index(3, 5)] == 2 and result.counts.sum() == 3
    assert result.counts[GRID.index(10, 10)] == 1       # centre (105, 105) -> (210, 210)
    assert np.array_equal(result.boxes_px[0], [92, 52, 20, 20])
    assert result.grouped_px.shape == (0, 4) and result.grouped_cell is None
    assert result.seconds > 0


def test_scan_enlarges_bilinearly_and_maps_boxes_back():
    seen = []

    class Recorder(FakeDetector):

        def __call__(self, gray):
            seen.append(gray.copy())
            return super().__call__(gray)
    fake = Recorder([[200, 120, 20, 20]])
    image = np.zeros((420, 420), np.uint8)
    image[100:110, 100:110] = 255
    result = scan(image, fake, GRID, scale=2.0)
    assert fake.shapes == [(840, 840)] and result.detector_pixels == 840 * 840
    assert np.array_equal(seen[0], cv2.resize(image, (840, 840),
                                              interpolation=cv2.INTER_LINEAR))
    assert np.array_equal(result.boxes_px[0], [100, 60, 10, 10])
    assert result.cell == GRID.index(65 // 20, 105 // 20)


def test_scan_ties_go_to_the_lowest_cell_and_no_detection_gives_none():
    tie = FakeDetector([[300, 300, 10, 10], [10, 10, 10, 10]])
    assert scan(np.zeros((420, 420), np.uint8), tie).cell == GRID.index(0, 0)
    empty = scan(np.zeros((420, 420), np.uint8), FakeDetector())
    assert empty.cell is None and empty.grouped_cell is None and not empty.counts.any()


def test_scan_groups_like_opencv_and_answers_with_the_largest_group():
    small = [[20, 20, 40, 40]] * 4                      # 4 > min_neighbors = 3: one group
    large = [[200, 300, 80, 80]] * 5
    lonely = [[380, 10, 30, 30]]                        # too few neighbours: dropped
    result = scan(np.zeros((420, 420), np.uint8), FakeDetector(small + large + lonely))
    assert sorted(result.grouped_px[:, 2].tolist()) == [40, 80]
    assert result.grouped_cell == GRID.index(340 // 20, 240 // 20)
    assert result.cell == GRID.index(340 // 20, 240 // 20)     # 5 raw centres there
    with pytest.raises(ValueError, match='scale'):
        scan(np.zeros((420, 420), np.uint8), FakeDetector(), scale=4.5)


def test_full_frame_haar_scan_finds_the_astronaut(astronaut, haar):
    face = face_cell_rc(astronaut.shape)
    assert face == (4, 9)
    for image in (astronaut, cv2.cvtColor(astronaut, cv2.COLOR_RGB2GRAY)):
        result = scan(image, haar, GRID)
        assert result.counts.sum() >= 10
        assert chebyshev(result.cell, face) <= 1
        assert chebyshev(result.grouped_cell, face) <= 1
        assert result.detector_pixels == 512 * 512
