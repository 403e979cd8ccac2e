# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The digital fovea: window geometry, per-window resolution, binning, counts, NaN and caching."""
from dataclasses import replace
import json
import subprocess
import sys

import cv2
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.vision.detector import HaarDetector
from ipomdp_gaze.vision.fovea import (cell_edges_px, Fovea, FoveaConfig, REFERENCE_WINDOWS_CELLS,
                                      window_cells)
from ipomdp_gaze.vision.search import _Recorder, FIND_SETTINGS, fresh_counts, search_many
import numpy as np
import pytest
from skimage import data

GRID = Grid(21, 21)
ASTRONAUT_FACE_RC = (4, 9)        # (225, 115) px on the 512x512 image; see test_vision_detector


class FakeDetector:
    """
    Record every image it is given; return boxes chosen per call.

    ``boxes_for(call_number, image)`` gives the boxes of each call (calls are numbered from 0
    over the detector's life), so a test can plant detections in one window only.
    """

    def __init__(self, boxes_for=None):
        self.boxes_for = boxes_for or (lambda call, image: ())
        self.images = []

    @property
    def shapes(self):
        return [image.shape for image in self.images]

    def __call__(self, gray):
        assert gray.ndim == 2 and gray.dtype == np.uint8 and gray.flags.c_contiguous
        self.images.append(gray.copy())
        return self.boxes_for(len(self.images) - 1, gray)


def image(height=420, width=420, seed=0):
    return np.random.default_rng(seed).integers(0, 256, (height, width), dtype=np.uint8)


def centred_box(x, y, side=2):
    """Return a box centred exactly on ``(x, y)`` (``x - side/2`` must be an integer)."""
    return [int(x - side / 2), int(y - side / 2), side, side]


# ---- geometry ----------------------------------------------------------------------------------

@pytest.mark.parametrize('fixation_rc, expected', [
    ((10, 10), [(0, 0, 21, 21), (3, 3, 15, 15), (6, 6, 9, 9), (9, 9, 3, 3)]),
    ((0, 0), [(0, 0, 21, 21), (0, 0, 15, 15), (0, 0, 9, 9), (0, 0, 3, 3)]),
    ((20, 20), [(0, 0, 21, 21), (6, 6, 15, 15), (12, 12, 9, 9), (18, 18, 3, 3)]),
    ((0, 20), [(0, 0, 21, 21), (0, 6, 15, 15), (0, 12, 9, 9), (0, 18, 3, 3)]),
    ((0, 10), [(0, 0, 21, 21), (0, 3, 15, 15), (0, 6, 9, 9), (0, 9, 3, 3)]),
    ((1, 19), [(0, 0, 21, 21), (0, 6, 15, 15), (0, 12, 9, 9), (0, 18, 3, 3)]),
    ((5, 2), [(0, 0, 21, 21), (0, 0, 15, 15), (1, 0, 9, 9), (4, 1, 3, 3)]),
    ((17, 8), [(0, 0, 21, 21), (6, 1, 15, 15), (12, 4, 9, 9), (16, 7, 3, 3)]),
])
def test_windows_are_centred_and_shifted_not_cropped(fixation_rc, expected):
    placed = window_cells(GRID.shape, REFERENCE_WINDOWS_CELLS, fixation_rc)
    assert [tuple(row) for row in placed.tolist()] == expected


def test_every_fixation_gives_nested_full_size_windows_holding_the_fixation():
    for fixation in range(GRID.n_cells):
        r, c = GRID.cell(fixation)
        placed = window_cells(GRID.shape, REFERENCE_WINDOWS_CELLS, (r, c))
        row, col, n_rows, n_cols = placed.T
        assert np.array_equal(n_rows, REFERENCE_WINDOWS_CELLS)
        assert np.array_equal(n_cols, REFERENCE_WINDOWS_CELLS)
        assert np.all((row >= 0) & (col >= 0) & (row + n_rows <= 21) & (col + n_cols <= 21))
        assert np.all((row <= r) & (r < row + n_rows) & (col <= c) & (c < col + n_cols))
        assert np.all((row[:-1] <= row[1:]) & (row[1:] + n_rows[1:] <= row[:-1] + n_rows[:-1]))
        assert np.all((col[:-1] <= col[1:]) & (col[1:] + n_cols[1:] <= col[:-1] + n_cols[:-1]))


def test_windows_larger_than_the_grid_cover_it_per_axis():
    placed = window_cells((7, 30), (21, 9, 3), (6, 29))
    assert placed.tolist() == [[0, 9, 7, 21], [0, 21, 7, 9], [4, 27, 3, 3]]


def test_pixel_rects_on_420_are_the_cells_times_20():
    fovea = Fovea(FakeDetector(), GRID)
    fovea.start(image())
    windows = fovea.window_rects(GRID.index(10, 10))
    assert [w.rect_px for w in windows] == [(0, 0, 420, 420), (60, 60, 300, 300),
                                            (120, 120, 180, 180), (180, 180, 60, 60)]
    assert [w.resized_px for w in windows] == [(60, 60)] * 4
    assert [w.whole_image for w in windows] == [True, False, False, False]
    corner = fovea.window_rects(GRID.index(20, 0))
    assert [w.rect_px for w in corner] == [(0, 0, 420, 420), (0, 120, 300, 300),
                                           (0, 240, 180, 180), (0, 360, 60, 60)]


def test_pixel_rects_on_a_non_multiple_size_use_floor_cell_bounds():
    height, width = 417, 430                  # 19.857 x 20.476 px per cell
    rows_px, cols_px = cell_edges_px(height, 21), cell_edges_px(width, 21)
    assert rows_px[[0, 1, 2, 3, 18, 21]].tolist() == [0, 19, 39, 59, 357, 417]
    assert cols_px[[0, 1, 2, 3, 18, 21]].tolist() == [0, 20, 40, 61, 368, 430]
    assert np.all(np.diff(rows_px) >= 19) and np.all(np.diff(cols_px) >= 20)
    fovea = Fovea(FakeDetector(), GRID)
    fovea.start(image(height, width))
    windows = fovea.window_rects(GRID.index(10, 10))
    assert windows[0].rect_px == (0, 0, 430, 417)
    assert windows[1].rect_px == (61, 59, 368 - 61, 357 - 59)
    for window in windows:
        row, col, n_rows, n_cols = window.cells
        x0, x1 = col * width // 21, (col + n_cols) * width // 21
        y0, y1 = row * height // 21, (row + n_rows) * height // 21
        assert window.rect_px == (x0, y0, x1 - x0, y1 - y0)
    # The same answer without an image, from its shape alone (for plots).
    assert Fovea(FakeDetector(), GRID).window_rects(GRID.index(10, 10), (417, 430)) == windows


# ---- resolution --------------------------------------------------------------------------------

def test_the_detector_gets_each_window_at_its_own_resolution():
    fake = FakeDetector()
    fovea = Fovea(fake, GRID)
    fovea.start(image())
    fovea.observe(GRID.index(10, 10))
    assert fake.shapes == [(60, 60)] * 4                   # NMPT: all at the size of 3 cells
    config = FoveaConfig(scales=(0.5, 1.0, 0.25, 1.0))
    fake = FakeDetector()
    fovea = Fovea(fake, GRID, config)
    fovea.start(image())
    observation = fovea.observe(GRID.index(0, 0))
    assert fake.shapes == [(210, 210), (300, 300), (45, 45), (60, 60)]
    assert observation.detector_pixels == 210 ** 2 + 300 ** 2 + 45 ** 2 + 60 ** 2


def test_non_multiple_sizes_round_the_resized_window():
    fake = FakeDetector()
    fovea = Fovea(fake, GRID)
    fovea.start(image(417, 430))
    windows = fovea.observe(GRID.index(10, 10)).windows
    # 430/7 = 61.43 -> 61 and 417/7 = 59.57 -> 60; (307, 298) * 1/5 = (61.4, 59.6) -> (61, 60)
    assert windows[0].resized_px == (61, 60) and windows[1].resized_px == (61, 60)
    assert fake.shapes == [(h, w) for w, h in (window.resized_px for window in windows)]


@pytest.mark.parametrize('name, flag', [('area', cv2.INTER_AREA), ('nearest', cv2.INTER_NEAREST),
                                        ('linear', cv2.INTER_LINEAR)])
def test_windows_are_resized_with_the_configured_interpolation(name, flag):
    gray = image(417, 430, seed=3)
    fake = FakeDetector()
    fovea = Fovea(fake, GRID, FoveaConfig(interpolation=name))
    fovea.start(gray)
    windows = fovea.observe(GRID.index(6, 13)).windows
    for window, seen in zip(windows, fake.images):
        x, y, w, h = window.rect_px
        crop = gray[y:y + h, x:x + w]
        expected = crop if window.resized_px == (w, h) else \
            cv2.resize(crop, window.resized_px, interpolation=flag)
        assert np.array_equal(seen, expected)
    assert np.array_equal(fake.images[-1], gray[(5 * 417) // 21:(8 * 417) // 21,
                                                (12 * 430) // 21:(15 * 430) // 21])


# ---- binning, counts, NaN ----------------------------------------------------------------------

def test_a_detection_in_the_seven_times_reduced_window_lands_in_the_right_cell():
    # Whole 420x420 image at scale 1/7 -> 60x60. A centre at (12, 23) there is (84, 161) in the
    # image: cell (floor(161 / 20), floor(84 / 20)) = (8, 4).
    fake = FakeDetector(lambda call, gray: [centred_box(12, 23)] if call == 0 else ())
    fovea = Fovea(fake, GRID)
    fovea.start(image())
    observation = fovea.observe(GRID.index(10, 10))
    assert fake.shapes[0] == (60, 60)
    assert np.allclose(observation.centres_px, [[84.0, 161.0]])
    assert observation.window_index.tolist() == [0]
    assert np.nansum(observation.counts) == 1 and observation.counts[GRID.index(8, 4)] == 1


def test_binning_on_a_non_multiple_size_uses_the_point_rule():
    # 430x417, whole window resized to 61x60: a centre at (41.5, 17) maps to
    # x = 41.5 * 430/61 = 292.54, y = 17 * 417/60 = 118.15 -> (floor(5.95), floor(14.27)).
    fake = FakeDetector(lambda call, gray: [[40, 16, 3, 2]] if call == 0 else ())
    fovea = Fovea(fake, GRID)
    fovea.start(image(417, 430))
    observation = fovea.observe(GRID.index(10, 10))
    assert np.allclose(observation.centres_px, [[41.5 * 430 / 61, 17 * 417 / 60]])
    assert observation.counts[GRID.index(5, 14)] == 1 and np.nansum(observation.counts) == 1


def test_a_centre_in_the_sub_pixel_sliver_counts_in_the_windows_own_edge_cell():
    # 430x417, fixation (3, 3): the 3-cell window covers cells 2..4, pixels from (40, 39), but
    # cell 2 starts at (40.95, 39.71). Its detection centred at (0.5, 0.5) is at (40.5, 39.5),
    # in cell (1, 1) by the point rule, and is counted in the window's corner cell (2, 2).
    fake = FakeDetector(lambda call, gray: [[0, 0, 1, 1]] if call == 3 else ())
    fovea = Fovea(fake, GRID)
    fovea.start(image(417, 430))
    observation = fovea.observe(GRID.index(3, 3))
    assert observation.windows[3].rect_px[:2] == (40, 39)
    assert np.allclose(observation.centres_px, [[40.5, 39.5]])
    assert observation.counts[GRID.index(2, 2)] == 1 and observation.counts[GRID.index(1, 1)] == 0


def test_counts_sum_over_windows_and_clip_at_k_minus_one():
    # Every window reports 4 detections centred on the fixated cell (10, 10) and one on cell
    # (9, 10): 16 and 4 raw detections, clipped to 9 and kept at 4.
    def boxes(call, gray):
        side = gray.shape[0]                   # every window is 60x60 and covers 3..21 cells
        cells = 21 if call == 0 else (15, 9, 3)[call - 1]
        cell_px = side / cells
        mid = side / 2
        return [centred_box(mid, mid)] * 4 + [centred_box(mid, mid - cell_px)]

    fovea = Fovea(FakeDetector(boxes), GRID)
    fovea.start(image())
    observation = fovea.observe(GRID.index(10, 10))
    assert observation.raw_counts[GRID.index(10, 10)] == 16
    assert observation.counts[GRID.index(10, 10)] == 9
    assert observation.counts[GRID.index(9, 10)] == 4
    assert observation.raw_counts.sum() == 20 and len(observation.centres_px) == 20
    assert observation.counts.dtype == np.float64 and not np.isnan(observation.counts).any()
    clipped = Fovea(FakeDetector(boxes), GRID, FoveaConfig(max_count=3))
    clipped.start(image())
    assert clipped.observe(GRID.index(10, 10)).counts[GRID.index(10, 10)] == 2


def test_cells_outside_every_window_are_nan():
    fovea = Fovea(FakeDetector(), GRID, FoveaConfig(windows_cells=(9, 3)))
    fovea.start(image())
    observation = fovea.observe(GRID.index(0, 20))
    seen = ~np.isnan(observation.counts.reshape(21, 21))
    expected = np.zeros((21, 21), bool)
    expected[0:9, 12:21] = True
    assert np.array_equal(seen, expected)
    assert np.all(observation.counts[seen.ravel()] == 0)
    full = Fovea(FakeDetector(), GRID)
    full.start(image())
    assert not np.isnan(full.observe(GRID.index(0, 20)).counts).any()


# ---- cost accounting and the whole-image cache -------------------------------------------------

def test_the_whole_image_window_is_searched_once_per_image():
    fake = FakeDetector(lambda call, gray: [centred_box(30, 30)])
    fovea = Fovea(fake, GRID)
    fovea.start(image())
    fixations = [GRID.index(10, 10), GRID.index(0, 0), GRID.index(20, 3), GRID.index(10, 10)]
    observations = [fovea.observe(f) for f in fixations]
    assert len(fake.images) == 1 + 3 * len(fixations)
    assert [o.detector_pixels for o in observations] == [4 * 3600] + [3 * 3600] * 3
    assert [o.from_cache for o in observations] == \
        [(False,) * 4] + [(True, False, False, False)] * 3
    assert fovea.image_detector_pixels == 3600 * (1 + 3 * len(fixations))
    assert fovea.n_fixations == 4
    assert fovea.image_seconds >= sum(o.seconds for o in observations) > 0
    # The cached whole-image detections still count on every fixation.
    assert all(o.counts[GRID.index(10, 10)] >= 1 for o in observations)
    assert np.array_equal(observations[0].counts, observations[3].counts)
    fovea.start(image(seed=1))                                # a new image: searched again
    fovea.observe(GRID.index(5, 5))
    assert len(fake.images) == 1 + 3 * len(fixations) + 4 and fovea.n_fixations == 1
    assert fovea.image_detector_pixels == 4 * 3600


def test_reuse_windows_makes_repeated_windows_free_without_changing_counts():
    def boxes(call, gray):
        return [centred_box(30, 30), centred_box(10, 50)]

    plain, reusing = Fovea(FakeDetector(boxes), GRID), Fovea(FakeDetector(boxes), GRID,
                                                             reuse_windows=True)
    for fovea in (plain, reusing):
        fovea.start(image())
    # Fixations (0, 0) and (2, 2) share the 15- and 9-cell windows (both shifted to the corner).
    for fixation in (GRID.index(0, 0), GRID.index(2, 2), GRID.index(0, 0)):
        a, b = plain.observe(fixation), reusing.observe(fixation)
        assert np.array_equal(a.counts, b.counts, equal_nan=True)
    assert reusing.image_detector_pixels == 3600 * (4 + 1)
    assert plain.image_detector_pixels == 3600 * (4 + 3 + 3)


def test_a_fixation_counts_again_only_cells_a_window_read_afresh_saw():
    """A window served from the cache is the same pixels: ``find --all`` counts it once."""
    def boxes(call, gray):
        return [centred_box(30, 30)]

    fovea = Fovea(FakeDetector(boxes), GRID, FoveaConfig(windows_cells=(15, 9, 3)),
                  reuse_windows=True)
    fovea.start(image())
    first = fovea.observe(GRID.index(0, 0))
    assert first.from_cache == (False, False, False)
    assert np.array_equal(fresh_counts(first, GRID), first.counts, equal_nan=True)
    # (2, 2) shares the corner's 15- and 9-cell windows; only its 3-cell window is new.
    second = fovea.observe(GRID.index(2, 2))
    assert second.from_cache == (True, True, False)
    counts = fresh_counts(second, GRID).reshape(21, 21)
    expected = np.zeros((21, 21), bool)
    expected[1:4, 1:4] = True
    assert np.array_equal(~np.isnan(counts), expected)
    assert np.array_equal(counts[1:4, 1:4], second.counts.reshape(21, 21)[1:4, 1:4])
    assert np.nansum(counts) >= 1                          # the new window's box is kept
    # every window cached: nothing new is seen
    again = fovea.observe(GRID.index(2, 2))
    assert again.detector_pixels == 0 and np.isnan(fresh_counts(again, GRID)).all()
    recorder = _Recorder(fovea)
    assert np.isnan(recorder.observe(GRID.index(2, 2)).values).all()
    assert not np.isnan(recorder.observe(GRID.index(10, 10)).values).all()
    # nor are its boxes kept again for counting the faces (their support when boxes merge)
    assert len(recorder.boxes[0]) == len(recorder.scores[0]) == 0
    assert len(recorder.boxes[1]) == len(recorder.scores[1]) == 3     # one box per window


def _replayed(config, reuse, fixations, img):
    fovea = Fovea(lambda gray: np.zeros((0, 4)), Grid(9, 9), config, reuse_windows=reuse)
    fovea.start(img)
    fovea.scan()
    for k in fixations:
        fovea.observe(k)
    return fovea


@pytest.mark.parametrize('config, reuse', [
    (FoveaConfig(windows_cells=(9, 5, 3)), True),
    (FoveaConfig(windows_cells=(9, 5, 3), scan_once=True), True),
    (FoveaConfig(windows_cells=(9, 5, 3)), False),
    # two windows larger than the grid at one scale: the second is the first, from the cache
    (FoveaConfig(windows_cells=(12, 10, 3), scales=(0.5, 0.5, 1.0)), True)])
def test_fresh_views_are_the_pixels_and_cells_a_fixation_would_read_afresh(config, reuse):
    """For every fixation: observe's pixels, and the cells fresh_counts keeps of its frame."""
    img = image(90, 117)
    history = (0, 20, 80, 10)                 # (0, 0), (2, 2), (8, 8), (1, 1)
    live = _replayed(config, reuse, (), img)   # fresh_views kept up to date as the cache grows
    for done in range(len(history) + 1):
        costs, cover = live.fresh_views()
        if done < len(history):
            live.observe(history[done])
        for k in range(81):
            after = _replayed(config, reuse, history[:done], img).observe(k)
            assert costs[k] == after.detector_pixels
            # the pixels a budget is checked with before the fixation (run_search)
            assert _replayed(config, reuse, history[:done], img).fixation_cost(k) == costs[k]
            np.testing.assert_array_equal(cover[k], ~np.isnan(fresh_counts(after, Grid(9, 9))))
        if reuse and done == 1:       # (1, 1) places (0, 0)'s windows: every one cached
            assert costs[10] == 0 and not cover[10].any() and costs[40] > 0
    with pytest.raises(RuntimeError, match='start'):
        Fovea(lambda gray: np.zeros((0, 4)), Grid(9, 9), config).fresh_views()


class _Spending(Fovea):
    """A fovea keeping each fixation's detector pixels."""

    def start(self, image):
        super().start(image)
        self.spent = []

    def observe(self, fixation):
        observation = super().observe(fixation)
        self.spent.append(observation.detector_pixels)
        return observation


def _bright_box(gray):
    """Detect the box of the bright pixels."""
    ys, xs = np.nonzero(gray > 128)
    if not len(xs):
        return np.zeros((0, 4))
    return np.array([[xs.min(), ys.min(), np.ptp(xs) + 1, np.ptp(ys) + 1]], dtype=float)


def test_find_all_spends_no_fixation_on_windows_read_already():
    """
    The many-target choice counts only what a fixation reads afresh (search_many).

    A bright patch in cell (1, 1) of a 9x9 grid: fixations near the corner all place the
    7-cell window there. Before, the search chose 7 of its 30 fixations whose windows were all
    read already (0 detector pixels, no evidence); now none.
    """
    grid = Grid(9, 9)
    hit = {0: 0.9, 1: 0.7, 2: 0.5}
    pt, pn = np.empty((9, 9, 2)), np.empty((9, 9, 2))
    for dr in range(9):
        for dc in range(9):
            p = hit.get(max(dr, dc), 0.3)
            pt[dr, dc], pn[dr, dc] = (1 - p, p), (0.95, 0.05)
    model = CountObservation(grid, pt, pn)
    img = np.zeros((90, 90), np.uint8)
    img[10:14, 10:14] = 255
    fovea = _Spending(_bright_box, grid, FoveaConfig(windows_cells=(7, 3), scales=(1.0, 1.0),
                                                     max_count=2), reuse_windows=True)
    result = search_many(img, fovea, model, replace(FIND_SETTINGS, targets='many',
                                                    max_fixations=30))
    assert [face.cell for face in result.faces] == [(1, 1)]
    assert result.fixations == len(fovea.spent) == 30
    assert 0 not in fovea.spent
    assert 900 in fovea.spent                  # a fixation whose 7-cell window was cached
    assert result.detector_pixels == sum(fovea.spent)


def test_observe_validates_its_state_and_fixation():
    fovea = Fovea(FakeDetector(), GRID)
    with pytest.raises(RuntimeError, match='start'):
        fovea.observe(0)
    fovea.start(image())
    with pytest.raises(ValueError, match='outside'):
        fovea.observe(GRID.n_cells)
    for bad, reason in ((np.zeros((420, 420, 4), np.uint8), '4'),
                        (np.zeros((420, 420), np.float64), 'uint8'),
                        (np.zeros((1, 1), np.uint8), 'smaller'),
                        (np.zeros((20, 420), np.uint8), 'grid')):
        with pytest.raises(ValueError, match=reason):
            fovea.start(bad)
    malformed = Fovea(FakeDetector(lambda call, gray: [[1, 2, 3]]), GRID)
    malformed.start(image())
    with pytest.raises(ValueError, match='shape'):
        malformed.observe(0)


def test_fovea_refuses_images_smaller_than_the_cascade_window():
    fovea = Fovea(HaarDetector(), Grid(3, 3), FoveaConfig(windows_cells=(3, 1)))
    with pytest.raises(ValueError, match='smaller than the 20x20'):
        fovea.start(np.zeros((19, 40, 3), np.uint8))


# ---- configuration -----------------------------------------------------------------------------

def test_config_defaults_to_nmpt_and_round_trips_through_plain_dicts():
    config = FoveaConfig()
    assert config.windows_cells == (21, 15, 9, 3) and config.max_count == 10
    assert np.allclose(config.scales, (3 / 21, 3 / 15, 3 / 9, 1.0))
    assert config.interpolation == 'area' and config.cv2_interpolation == cv2.INTER_AREA
    assert FoveaConfig(scales=(1 / 7, 1 / 5, 1 / 3, 1.0)) == config
    plain = config.to_dict()
    assert json.loads(json.dumps(plain)) == plain
    assert FoveaConfig.from_dict(plain) == config
    assert FoveaConfig.from_dict({}) == config
    custom = FoveaConfig((15, 5), (0.5, 1.0), 4, 'nearest')
    assert FoveaConfig.from_dict(json.loads(json.dumps(custom.to_dict()))) == custom
    settings = Fovea(FakeDetector(), GRID, custom).settings()
    assert settings == {'grid': [21, 21], 'fovea': custom.to_dict(),
                        'detector': {'kind': 'test_fovea:FakeDetector'}}


@pytest.mark.parametrize('kwargs, reason', [
    ({'windows_cells': ()}, 'non-empty'),
    ({'windows_cells': (3, 9)}, 'decreasing'),
    ({'windows_cells': (9, 9)}, 'decreasing'),
    ({'windows_cells': (9, 0)}, 'positive'),
    ({'windows_cells': (9.5, 3)}, 'positive'),
    ({'scales': (1.0, 1.0)}, 'one factor per window'),
    ({'scales': (0.5, 0.5, 0.5, 1.5)}, r'\(0, 1\]'),
    ({'scales': (0.5, 0.5, 0.0, 1.0)}, r'\(0, 1\]'),
    ({'max_count': 1}, 'max_count'),
    ({'max_count': True}, 'max_count'),
    ({'interpolation': 'lanczos'}, 'interpolation'),
])
def test_config_validation(kwargs, reason):
    with pytest.raises(ValueError, match=reason):
        FoveaConfig(**kwargs)


def test_from_dict_rejects_unknown_settings():
    with pytest.raises(ValueError, match='unknown'):
        FoveaConfig.from_dict({'windows': [3]})


# ---- real detector and layering ----------------------------------------------------------------

def test_haar_fovea_fixated_on_the_astronaut_sees_her_face():
    astronaut = data.astronaut()
    fovea = Fovea(HaarDetector(), GRID)
    fovea.start(astronaut)
    face = GRID.index(*ASTRONAUT_FACE_RC)
    observation = fovea.observe(face)
    assert observation.raw_counts.sum() >= 3
    best = GRID.cell(int(np.nanargmax(observation.counts)))
    assert max(abs(best[0] - ASTRONAUT_FACE_RC[0]), abs(best[1] - ASTRONAUT_FACE_RC[1])) <= 1
    # All four windows are about 73x73 (the 3-cell window's size): the first fixation pays for
    # the whole-image window, later ones only for the other three (about 3 x 9/441 of the image).
    assert observation.detector_pixels == 4 * 73 * 73
    later = fovea.observe(GRID.index(20, 20))
    assert later.detector_pixels == sum(w * h for w, h in
                                        (window.resized_px for window in later.windows[1:]))
    assert fovea.image_detector_pixels == observation.detector_pixels + later.detector_pixels


def test_the_vision_package_imports_nothing_from_ros_or_the_policies(tmp_path):
    code = ('import json, sys\n'
            'import ipomdp_gaze.vision, ipomdp_gaze.vision.fovea, ipomdp_gaze.vision.fullframe\n'
            'print(json.dumps(sorted(sys.modules)))\n')
    out = subprocess.run([sys.executable, '-c', code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    loaded = json.loads(out.stdout.splitlines()[-1])
    bad = [m for m in loaded if m.split('.')[0] in ('rclpy', 'rcl_interfaces')
           or m.endswith(('_msgs', '_srvs')) or m.startswith(('ipomdp_gaze.policies',
                                                              'ipomdp_gaze.msg_adapters',
                                                              'ipomdp_gaze.nodes'))]
    assert not bad, bad


# ---- the one-time scan (scan_once) -------------------------------------------------------------

def test_scan_once_observes_the_whole_image_window_once_and_fixations_without_it():
    # Every window reports a box at its own (10, 10) px: cell (1, 1) of the 420 px image for
    # the whole-image window at 1/3 (30, 30 px), cell (0, 0) for the fixation windows at (0, 0).
    fake = FakeDetector(lambda call, gray: [centred_box(10, 10)])
    config = FoveaConfig(scales=(1 / 3, 1 / 5, 1 / 3, 1.0), scan_once=True)
    fovea = Fovea(fake, GRID, config)
    fovea.start(image())
    scan = fovea.scan()
    assert fake.shapes == [(140, 140)] and scan.detector_pixels == 140 * 140
    assert [w.whole_image for w in scan.windows] == [True]
    assert scan.counts[GRID.index(1, 1)] == 1 and scan.counts.sum() == 1
    assert not np.isnan(scan.counts).any()
    again = fovea.scan()                                      # same image: no detector work
    assert len(fake.images) == 1 and again.detector_pixels == 0
    np.testing.assert_array_equal(again.counts, scan.counts)
    observation = fovea.observe(GRID.index(0, 0))
    assert [w.whole_image for w in observation.windows] == [False] * 3
    assert fake.shapes[1:] == [(60, 60), (60, 60), (60, 60)]
    # The fixation windows' boxes land at 50, 30 and 10 px (15-, 9- and 3-cell windows at 1/5,
    # 1/3 and 1): cells (2, 2), (1, 1), (0, 0); the scan's box in (1, 1) is not counted again.
    counts = observation.counts.reshape(GRID.shape)
    assert counts[0, 0] == counts[1, 1] == counts[2, 2] == 1 and np.nansum(counts) == 3
    assert np.isnan(observation.counts[GRID.index(20, 20)])
    assert fovea.image_detector_pixels == 140 * 140 + 3 * 3600


def test_without_scan_once_there_is_no_scan_and_scan_once_needs_a_whole_image_window():
    fovea = Fovea(FakeDetector(), GRID)
    fovea.start(image())
    assert fovea.scan() is None
    with pytest.raises(ValueError, match='scan_once needs a whole-image window'):
        Fovea(FakeDetector(), GRID, FoveaConfig(windows_cells=(15, 9, 3), scan_once=True))
    with pytest.raises(ValueError, match='scan_once must be true or false'):
        FoveaConfig(scan_once='yes')
    config = FoveaConfig(scan_once=True)
    assert FoveaConfig.from_dict(config.to_dict()) == config
    assert FoveaConfig.from_dict({'windows_cells': [21, 15, 9, 3]}).scan_once is False
