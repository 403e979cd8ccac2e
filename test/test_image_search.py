# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Searching one image with the fovea and a count model; NMPT's fixed policy."""
from dataclasses import replace

import cv2
from ipomdp_gaze.model.belief import map_cell
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.policies.nmpt import gaussian_taps, NMPT_SOURCE_TAPS, NMPTPolicy, smoothing_matrix
from ipomdp_gaze.policies.registry import build_policy, POLICY_NAMES
from ipomdp_gaze.vision.detector import HaarDetector
from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig
from ipomdp_gaze.vision.search import (check_model, DEFAULT_SETTINGS, detector_from_settings,
                                       fovea_for_model, ImageSearch, search_image)
import numpy as np
import pytest


def image_settings(**changes):
    """search_image's default settings with some changed."""
    return replace(DEFAULT_SETTINGS, **changes)


GRID = Grid(7, 7)
CELL_PX = 30
SIZE_PX = GRID.rows * CELL_PX
CONFIG = FoveaConfig(windows_cells=(7, 3), scales=(0.5, 1.0), max_count=4)
FACE_CELL = (2, 5)
WHOLE_PX = 105 * 105          # the 7-cell window: 210 px resized by 0.5
FOVEA_PX = 90 * 90            # the 3-cell window at full resolution


class BlobDetector:
    """Fake detector: ``boxes`` identical 4x4 boxes centred on the bright blob it sees."""

    window_px = (4, 4)

    def __init__(self, boxes: int = 3):
        self.boxes = boxes
        self.calls = []

    def __call__(self, gray):
        self.calls.append(gray.shape)
        ys, xs = np.nonzero(gray > 200)
        if xs.size == 0:
            return np.empty((0, 4), dtype=np.int64)
        x, y = int(round(xs.mean())), int(round(ys.mean()))
        return np.array([[x - 2, y - 2, 4, 4]] * self.boxes)

    def settings(self):
        return {'kind': 'blob', 'boxes': self.boxes}


def blob_image(cell=FACE_CELL, scale=1):
    """Draw a black image of 7x7 cells of 30 px with a 10 px white square inside ``cell``."""
    image = np.zeros((SIZE_PX * scale, SIZE_PX * scale), dtype=np.uint8)
    y0, x0 = (scale * (CELL_PX * v + 10) for v in cell)
    image[y0:y0 + 10 * scale, x0:x0 + 10 * scale] = 255
    return image


def count_model(target, grid=GRID, meta=None):
    """Tables over K = 4 counts: ``target`` at every offset, mostly 0 without the target."""
    p_null = np.broadcast_to([0.97, 0.01, 0.01, 0.01], grid.shape + (4,))
    p_target = np.broadcast_to(target, grid.shape + (4,))
    return CountObservation(grid, p_target, p_null, meta)


STRONG = count_model([0.02, 0.02, 0.06, 0.90])    # one look at the blob: p > 0.98
WEAK = count_model([0.90, 0.04, 0.03, 0.03])      # about 5.2 looks to reach 0.9


class Scan:
    """Policy fixating the cells of ``order`` one after the other; records its calls."""

    def __init__(self, order):
        self.order = list(order)
        self.calls = []

    def select(self, belief, t, rng):
        self.calls.append((belief.shape, float(belief.sum()), t))
        return np.array([self.order[(t - 1) % len(self.order)]])


def make_fovea(boxes=3, reuse=False):
    return Fovea(BlobDetector(boxes), GRID, CONFIG, reuse_windows=reuse)


def test_found_after_one_look_gives_the_map_cell_and_its_pixel_centre():
    fovea = make_fovea()
    result = search_image(blob_image(), fovea, STRONG, Scan([0]), image_settings(confidence=0.9))
    assert isinstance(result, ImageSearch)
    assert result.stop == 'found' and result.fixations == 1
    assert result.path == ((3, 3),)                     # the grid centre comes first
    assert result.cell == FACE_CELL
    assert result.pixel == (165.0, 75.0)                # centre of columns 150-179, rows 60-89
    assert result.probability > 0.98                    # 90 / (90 + 48 * 0.02 / 0.97)
    assert result.probability == pytest.approx(result.belief.max())
    assert int(map_cell(result.belief)) == GRID.index(*FACE_CELL)
    assert result.belief.shape == (GRID.n_cells,) and result.belief.sum() == pytest.approx(1.0)
    assert result.image_px == (SIZE_PX, SIZE_PX) and result.calibrated_px is None
    assert result.size_matches


def test_budget_stops_an_undecided_search_and_the_policy_sees_each_belief():
    policy = Scan([10, 20, 30, 40])
    result = search_image(blob_image(), make_fovea(), WEAK, policy,
                          image_settings(confidence=0.9, max_fixations=3))
    assert result.stop == 'budget' and result.fixations == 3
    assert result.path == ((3, 3), (1, 3), (2, 6))
    assert [t for _, _, t in policy.calls] == [1, 2]
    assert all(shape == (1, GRID.n_cells) for shape, _, _ in policy.calls)
    assert all(total == pytest.approx(1.0) for _, total, _ in policy.calls)
    assert result.cell == FACE_CELL and result.probability < 0.9


def test_repeat_stops_before_fixating_a_cell_again():
    centre = GRID.center_index
    result = search_image(blob_image(), make_fovea(), WEAK, Scan([centre]),
                          image_settings(confidence=0.9))
    assert result.stop == 'repeat' and result.fixations == 1 and result.path == ((3, 3),)
    back = Scan([10, centre])
    result = search_image(blob_image(), make_fovea(), WEAK, back, image_settings(confidence=0.9))
    assert result.stop == 'repeat' and result.path == ((3, 3), (1, 3))


def test_without_the_repeat_rule_the_same_evidence_is_counted_again():
    fovea = make_fovea()
    centre = GRID.center_index
    result = search_image(blob_image(), fovea, WEAK, Scan([centre]),
                          image_settings(confidence=0.9, max_fixations=10, stop_on_repeat=False))
    assert result.stop == 'found' and result.fixations == 6   # log-odds grow by ~1.17 a look
    assert result.path == ((3, 3),) * 6


def test_inhibition_of_return_moves_on_to_the_best_unvisited_cell():
    from ipomdp_gaze.policies.baselines import make_baseline
    centre = GRID.center_index
    stuck = Scan([centre])                   # would look at the centre again and again
    result = search_image(blob_image(), make_fovea(), WEAK, stuck,
                          image_settings(confidence=0.9, max_fixations=6, inhibit_return=True))
    assert len(set(result.path)) == len(result.path) == 6 and result.stop in ('found', 'budget')
    # The replacement of a visited choice is its nearest unvisited cell (Chebyshev, low index).
    assert result.path[1] == (2, 2)
    elm = make_baseline('elm', GRID, WEAK)
    scored = search_image(blob_image(), make_fovea(), WEAK, elm,
                          image_settings(confidence=0.99, max_fixations=12, inhibit_return=True))
    assert len(set(scored.path)) == len(scored.path) and scored.cell == FACE_CELL


def test_detector_pixels_count_the_whole_image_window_once():
    fovea = make_fovea()
    result = search_image(blob_image(), fovea, WEAK, Scan([10, 20, 30, 40]),
                          image_settings(max_fixations=4))
    detector = fovea.detector
    assert result.detector_pixels == WHOLE_PX + 4 * FOVEA_PX == fovea.image_detector_pixels
    assert detector.calls.count((105, 105)) == 1 and len(detector.calls) == 5
    assert result.seconds > 0 and result.seconds >= fovea.image_seconds
    again = search_image(blob_image(), fovea, WEAK, Scan([10, 20, 30, 40]),
                         image_settings(max_fixations=4))
    assert again.detector_pixels == result.detector_pixels        # a new image starts afresh
    reuse = make_fovea(reuse=True)
    looped = search_image(blob_image(), reuse, WEAK, Scan([GRID.center_index]),
                          image_settings(max_fixations=3, stop_on_repeat=False))
    assert looped.detector_pixels == WHOLE_PX + FOVEA_PX


def test_start_cell_rng_and_policy_checks():
    result = search_image(blob_image(), make_fovea(), STRONG, Scan([0]),
                          image_settings(start_cell=(2, 5)))
    assert result.path == (FACE_CELL,)
    for bad in ((7, 0), (1.5, 2), 49, -1, 'centre'):
        with pytest.raises(ValueError, match='start'):
            search_image(blob_image(), make_fovea(), STRONG, Scan([0]),
                         image_settings(start_cell=bad))
    with pytest.raises(ValueError, match='outside the 49-cell grid'):
        search_image(blob_image(), make_fovea(), WEAK, Scan([49]))
    for confidence in (0.0, 1.0, float('nan')):
        with pytest.raises(ValueError, match='confidence'):
            search_image(blob_image(), make_fovea(), WEAK, Scan([0]),
                         image_settings(confidence=confidence))
    with pytest.raises(ValueError, match='^search.max_fixations must be an integer >= 0'):
        search_image(blob_image(), make_fovea(), WEAK, Scan([0]), image_settings(max_fixations=-1))
    with pytest.raises(ValueError, match='needs a fixation budget'):
        search_image(blob_image(), make_fovea(), WEAK, Scan([0]),
                     image_settings(max_fixations=0, stop_on_repeat=False))


def test_grid_fovea_and_detector_of_the_model_must_match():
    with pytest.raises(ValueError, match='5x5 grid but the fovea tiles images with 7x7'):
        search_image(blob_image(), make_fovea(), count_model([0.9, 0.04, 0.03, 0.03],
                                                             Grid(5, 5)), Scan([0]))
    other = FoveaConfig(windows_cells=(7, 3), scales=(1.0, 1.0), max_count=4).to_dict()
    with pytest.raises(ValueError, match='measured with fovea'):
        search_image(blob_image(), make_fovea(), count_model(
            [0.9, 0.04, 0.03, 0.03], meta={'fovea': other}), Scan([0]))
    with pytest.raises(ValueError, match='detector boxes 1 but the detector has 3'):
        search_image(blob_image(), make_fovea(), count_model(
            [0.9, 0.04, 0.03, 0.03], meta={'detector': {'kind': 'blob', 'boxes': 1}}),
            Scan([0]))
    fits = count_model([0.02, 0.02, 0.06, 0.90], meta={
        'fovea': CONFIG.to_dict(), 'detector': BlobDetector().settings()})
    check_model(fits, make_fovea())


def test_another_image_size_is_allowed_and_reported():
    model = count_model([0.02, 0.02, 0.06, 0.90],
                        meta={'image': {'width': SIZE_PX, 'height': SIZE_PX}})
    same = search_image(blob_image(), make_fovea(), model, Scan([0]))
    assert same.calibrated_px == (SIZE_PX, SIZE_PX) and same.size_matches
    big = search_image(blob_image(scale=2), make_fovea(), model, Scan([0]))
    assert big.image_px == (2 * SIZE_PX, 2 * SIZE_PX)
    assert big.calibrated_px == (SIZE_PX, SIZE_PX) and not big.size_matches
    assert big.cell == FACE_CELL and big.pixel == (330.0, 150.0)
    bad = count_model([0.9, 0.04, 0.03, 0.03], meta={'image': {'width': 0, 'height': 5}})
    with pytest.raises(ValueError, match='image.width must be a positive integer'):
        search_image(blob_image(), make_fovea(), bad, Scan([0]))


@pytest.mark.parametrize('image, message', [
    (np.zeros((3, 3), dtype=np.uint8), 'too small'),
    (np.zeros((210, 5), dtype=np.uint8), 'too small'),
    (np.zeros((210, 210), dtype=np.uint16), '8-bit'),
    (np.zeros((210, 210, 4), dtype=np.uint8), 'grey or'),
    ([[0]], 'numpy array'),
])
def test_bad_images_are_refused(image, message):
    with pytest.raises(ValueError, match=message):
        search_image(image, make_fovea(), STRONG, Scan([0]))


def test_rgb_images_are_searched_like_grey_ones():
    rgb = np.repeat(blob_image()[:, :, None], 3, axis=2)
    result = search_image(rgb, make_fovea(), STRONG, Scan([0]))
    assert result.cell == FACE_CELL and result.stop == 'found'


def test_the_model_records_rebuild_the_haar_detector_and_the_fovea():
    detector = HaarDetector()
    settings = detector.settings()
    rebuilt = detector_from_settings(settings)
    assert rebuilt.settings() == settings
    config = FoveaConfig(windows_cells=(7, 3), max_count=4)
    model = count_model([0.9, 0.04, 0.03, 0.03], meta={
        'fovea': config.to_dict(), 'detector': settings})
    fovea = fovea_for_model(model)
    assert fovea.config == config and fovea.grid.shape == GRID.shape and fovea.reuse_windows
    with pytest.raises(ValueError, match="unknown detector 'blob'"):
        detector_from_settings({'kind': 'blob'})
    with pytest.raises(ValueError, match='differs from the one'):
        detector_from_settings({**settings, 'cascade_sha256': '0' * 64})
    with pytest.raises(ValueError, match='does not record its detector'):
        fovea_for_model(count_model([0.9, 0.04, 0.03, 0.03]))


# -- NMPT's fixed policy ------------------------------------------------------------------------
def test_nmpt_smoothing_is_opencvs_gaussian_blur_with_the_border_replicated():
    grid = Grid(21, 21)
    belief = np.random.default_rng(3).dirichlet(np.ones(grid.n_cells))
    image = belief.reshape(grid.shape)
    source = NMPTPolicy(grid, taps=NMPT_SOURCE_TAPS)
    expected = cv2.GaussianBlur(image, (5, 5), 0, borderType=cv2.BORDER_REPLICATE)
    np.testing.assert_allclose(source.smoothed(belief).reshape(grid.shape), expected,
                               atol=1e-15)
    wide = NMPTPolicy(grid)
    assert wide.sigma_cells == 5.0 and wide.gain == 300.0 and wide.taps.size == 31
    expected = cv2.GaussianBlur(image, (31, 31), 5.0, borderType=cv2.BORDER_REPLICATE)
    np.testing.assert_allclose(wide.smoothed(belief).reshape(grid.shape), expected,
                               atol=1e-15)
    np.testing.assert_allclose(gaussian_taps(1.0, 2), cv2.getGaussianKernel(5, 1.0).ravel())
    np.testing.assert_allclose(smoothing_matrix(4, [0.25, 0.5, 0.25]).sum(axis=1), 1.0)


def test_nmpt_samples_the_softmax_of_the_gain_times_the_smoothed_belief():
    grid = Grid(9, 9)
    policy = NMPTPolicy(grid, sigma_cells=1.0, gain=300.0)
    belief = np.full(grid.n_cells, 0.5 / 80)
    belief[40] = 0.5
    p = policy.probabilities(belief)
    score = 300.0 * policy.smoothed(belief)
    np.testing.assert_allclose(p, np.exp(score - score.max()) / np.exp(score - score.max()).sum())
    assert int(np.argmax(p)) == 40
    draws = policy.select(np.tile(belief, (4000, 1)), 1, np.random.default_rng(0))
    assert draws.shape == (4000,)
    freq = np.bincount(draws, minlength=grid.n_cells) / draws.size
    assert np.abs(freq - p).max() < 0.03
    one = policy.select(belief, 1, np.random.default_rng(5))
    assert np.ndim(one) == 0
    assert one == policy.select(belief[None], 1, np.random.default_rng(5))[0]
    mode = NMPTPolicy(grid, sigma_cells=1.0, action='argmax')
    assert mode.select(belief[None], 1, None)[0] == 40


def test_nmpt_parameters_and_registry():
    grid = Grid(5, 5)
    for kwargs, message in (({'gain': 0}, 'gain'), ({'sigma_cells': -1}, 'sigma_cells'),
                            ({'taps': [0.5, 0.5]}, 'odd'), ({'taps': [0.2, 0.2, 0.2]}, 'sum'),
                            ({'action': 'softmax'}, 'action')):
        with pytest.raises(ValueError, match=message):
            NMPTPolicy(grid, **kwargs)
    assert 'nmpt' in POLICY_NAMES
    policy = build_policy('nmpt', GRID, STRONG)
    assert isinstance(policy, NMPTPolicy) and policy.action == 'sample'
    assert 'sigma_cells=5.0' in repr(policy)
    result = search_image(blob_image(), make_fovea(), STRONG, policy,
                          rng=np.random.default_rng(1))
    assert result.cell == FACE_CELL


def test_a_scanning_fovea_updates_once_from_the_scan_then_fixates_the_policys_choice():
    config = FoveaConfig(windows_cells=(7, 3), scales=(0.5, 1.0), max_count=4, scan_once=True)
    fovea = Fovea(BlobDetector(3), GRID, config)
    scan_tables = {'scan_target': [0.1, 0.1, 0.1, 0.7], 'scan_null': [0.97, 0.01, 0.01, 0.01]}
    p_null = np.broadcast_to([0.97, 0.01, 0.01, 0.01], GRID.shape + (4,))
    model = CountObservation(GRID, np.broadcast_to([0.9, 0.04, 0.03, 0.03], GRID.shape + (4,)),
                             p_null, **scan_tables)
    policy = build_policy('map', GRID, model)
    result = search_image(blob_image(), fovea, model, policy,
                          image_settings(confidence=0.999, max_fixations=5, inhibit_return=True))
    # The scan (7-cell window at 1/2) sees the blob: the first fixation is MAP's, the blob's cell
    # rather than the centre, and the scan's pixels are counted once.
    assert result.path[0] == FACE_CELL and result.cell == FACE_CELL
    assert fovea.detector.calls[0] == (105, 105) and (105, 105) not in fovea.detector.calls[1:]
    assert result.detector_pixels == WHOLE_PX + FOVEA_PX * result.fixations
    # A scanning fovea needs a model with scan tables, and the other way round.
    with pytest.raises(ValueError, match='has no scan tables'):
        search_image(blob_image(), fovea, STRONG, policy)
    with pytest.raises(ValueError, match='the fovea does not scan'):
        search_image(blob_image(), make_fovea(), model, policy)
