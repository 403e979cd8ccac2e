# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Search one image for the target with the digital fovea and a count model (docs/design.md 6).

:func:`search_image` is the whole loop of the CVPR 2009 follow-up on one decoded image, run by the
search session (:mod:`ipomdp_gaze.search.session`) with the fovea as its sensor:

1. start the fovea on the image (grey conversion); with a fovea that scans once
   (``scan_once``), observe the whole-image windows and apply their one Bayes step with the
   model's scan tables; then fixate the **start cell**: ``settings.start_cell``, or the
   policy's choice on the scanned belief, or without a scan the grid's centre (docs/design.md
   section 4.2);
2. observe the fixation's detection counts and apply **one Bayes step** with the count model
   (section 1.3), with the absent hypothesis and the repeat weight when the settings say so;
3. stop with ``'found'`` (``'absent'``) when the most likely cell (``P(absent)``) reaches
   ``confidence``, with ``'budget'`` after ``max_fixations`` fixations, else ask the policy
   for the next fixation (its best unvisited cell with ``inhibit_return``);
4. stop with ``'repeat'`` **before** fixating a cell a second time (``stop_on_repeat``, NMPT's
   rule, ``MIPOMDP::searchFrameUntilConfident``; with inhibition of return: once every cell has
   been fixated): the detector is deterministic, so the same fixation of the same image would
   return the same counts and the model, which assumes independent observations, would count
   the same evidence twice.

The answer is the MAP cell at stop (tie rule of section 4.1) and the pixel at its centre.

**Cost.** ``detector_pixels`` is the number of pixels of every image the detector was given
(the resized windows; the whole-image window is detected once per image and counted once, see
:mod:`ipomdp_gaze.vision.fovea`). ``seconds`` is the wall time from the decoded image array to
the answer: grey conversion, every window's resizing and detection (the whole-image window
included), binning, the belief updates and the policy's decisions. Reading and decoding the file
is not included, nor is building the detector, the fovea or the policy (done once, not per image).

**Sizes.** The model must be for the fovea's grid (``rows x cols``), fovea settings and detector
(when its ``meta`` records them: a model is only valid with what it was measured with); a
mismatch is a :class:`ValueError`. An image of another pixel size than the model was calibrated
at (``model.meta['image']``) is allowed: the grid tiles any image, but faces then appear at
other sizes in the windows than during calibration, so the result says so (``calibrated_px``).

Part of the core: numpy and OpenCV only; the policy is any object with ``select``.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import functools
import math
import threading
import time

import cv2
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.occupancy import cell_prior, log_nobody, prior_log_odds
from ipomdp_gaze.search import answer
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.sensors import run_search
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
from ipomdp_gaze.vision.detector import box_centres_px, detector_window_px, group_boxes
from ipomdp_gaze.vision.detectors import detector_from_settings  # noqa: F401 (its old home)
from ipomdp_gaze.vision.fovea import cell_edges_px, Fovea
from ipomdp_gaze.vision.fovea_model import check_model, fovea_for_model  # noqa: F401
from ipomdp_gaze.vision.fullframe import cells_of_points, MAX_SCALE, scaled_size, scan
from ipomdp_gaze.vision.scales import (box_cells, box_sides, choose_scale, coarse_detector,
                                       coarse_evidence, confirm_scale, ladder_scales,
                                       larger_face_scale, min_face_px, SCALE_RTOL, ScaleTable,
                                       too_large)
from ipomdp_gaze.vision.sensors import FoveaSensor
import numpy as np

# The enlarged look (docs/design.md section 11.4). find without --all (search_scales): a box
# that answers at the finest scale below the table's strong score answers only if the crop
# round it, enlarged LOOK_UPSCALE times, keeps a box of LOOK_SCORE. Chosen on training material
# only (YuNet, the shipped ladders): the face-free training photos and three photos of no split
# (horse, logo, colorwheel), each at 6 sizes (x0.5-x3), 4 rotations and mirrored (432 images),
# and the 129 faces the ladder finds without a look in 120 training scenes, the 8 training
# group pictures and the astronaut at 6 sizes. Rule: keep every such face, then the fewest
# face-free images answered, then the fewest pixels. 2x at 0.6: 11 of 432 answered (18 without
# a look; 2x at 0.5 and 1.5x at 0.5: 12), no face lost; 2x at 0.7 (7) and 3x at 0.7 (6) lose a
# face; YuNet's strong score at the finest scale instead of a look (5) loses 3.
# find --all (_Coarse): the same look decides whether a full-resolution box of 0.5-0.7 is
# strong (kept) or weak (not kept: the fovea's windows decide its cell). On the training groups
# it keeps every face (lfw 43 and 47 of 48, photo faces 48 and 48, no false face added) and it
# names 13 false faces instead of 16 on the 432 face-free images.
# Since the test report of 2026-12-05 the look resizes the crop so that the box is LOOK_SIDE_PX
# on a side, at most LOOK_UPSCALE times and never below the scale of the call that found it (a
# box of 64 px or less is still enlarged 2x; a large box is no longer enlarged into a crop of a
# million pixels). Chosen on the same training material: the ladder's answers on the 432
# face-free images 11 -> 10, --all's false faces there 13 -> 13, every training face kept (420
# and 840 training scenes, seeds 1 and 2; the training groups; --min-face 24 at 840), 1-7% fewer
# pixels. Bounded below by 1/2 instead it answers 9 but loses a 134 px face of --min-face 24.
LOOK_UPSCALE = 2.0
LOOK_SCORE = 0.6
LOOK_SIDE_PX = 128.0
# find --all's enlarged looks at weak full-resolution boxes may add at most this fraction of one
# full scan of the searched image beyond its pixel budget, a bound on a photo full of face-like
# texture: the training groups at 640x480 spend 13% (the full call is the budget there), one
# look at a 60 px box of a 400x600 photo 50%, and a 48 Mpx photo of textures spent 22% before
# this bound.
LOOK_ALLOWANCE = 1.0
# find --all: a cell the pass decides by a face too large for any finer look gets its log odds
# this far (nats) past the threshold of confidence, so that rounding cannot leave it a step below
DECIDED_MARGIN = 1e-9
# The faint look (docs/design.md section 11.4), find without --all: when the ladder ends without
# an answer, the finest call's best faint box (from FAINT_SCORE, below the detector's own
# threshold) no larger than FAINT_SIDE times the smallest face side that scale sees (the scale
# table: YuNet 48 px at x1, so 64 px) gets the enlarged look and answers if the look keeps a
# box of FAINT_LOOK_SCORE: a face too small for the scale leaves a faint small box. Chosen on
# training material only: 60 faces-840 training scenes (seed 1) right 0.85 -> 0.95 and the
# 432 face-free augmented images still 11 answered, for 1% more pixels; a floor of 0.3, sides
# to 48 px or looks at 0.6-0.7 find fewer faces or answer 12-19 face-free images.
FAINT_SCORE = 0.2
FAINT_SIDE = 4 / 3
FAINT_LOOK_SCORE = 0.8
# Haar's second opinion (docs/design.md section 11.4), find without --all with a scoring
# detector (YuNet): when neither the ladder nor the faint look answered, the finest call's
# SECOND_BOXES best boxes from SECOND_SCORE (faint ones below the detector's threshold, and a
# weak one from it that the enlarged look turned down), each at most SECOND_SIDE of the image's
# shorter side, are shown to OpenCV's Haar face cascade in the crop round each (half the box's
# side on each side, at the crop's own scale): a grouped Haar box of SECOND_NEIGHBORS
# neighbours centred in the box answers there. YuNet, trained on camera
# faces, leaves blurred or enlarged thumbnails a faint box that Haar's grey pattern sees.
# Chosen on training material only (300 training scenes per task, seed 3, the 432 face-free
# augmented images and the training photos), by the rule "no face-free image answered more,
# every training photo within the ladder's 1.5 full scans, then the most faces, then the
# fewest pixels" over scores 0.05-0.3, 1-5 boxes, sides 1/4-1 and 3, 5 or 8 neighbours:
# 285 -> 287 right at 420 and 264 -> 270 at 840, still 10 of the 432 face-free images
# answered, for 0.01 more full scans on them (1.27 -> 1.28). Sides to 1/2 found 288 and 271
# but read 1.67 full scans on the training photo coins (1.25 without); 3 neighbours found 291
# and 278 but answered 12 more face-free images.
SECOND_SCORE = 0.05
SECOND_BOXES = 2
SECOND_SIDE = 0.25
SECOND_NEIGHBORS = 8
# find --all's Haar check (haar_checked; its score and neighbours are the scale table's): OpenCV's
# frontal (alt2) cascade, then, only if it sees no face, the profile cascade on the crop and on
# its mirror image, so that a turned face YuNet scores low is not vetoed by the frontal cascade
# alone. The crop round the face is resized so that the face's box is HAAR_CHECK_SIDE_PX (at
# most MAX_SCALE times enlarged), and the cascades look only for faces of HAAR_CHECK_RANGE times
# that side: a few milliseconds a face instead of 20-50 for the cascades' whole pyramid, the same
# training faces (docs/design.md section 11.4, "Haar checks a face below 0.9").
HAAR_CHECK_CASCADES = (('haarcascade_frontalface_alt2.xml', False),
                       ('haarcascade_profileface.xml', True))
HAAR_CHECK_SIDE_PX = 96.0
HAAR_CHECK_RANGE = (0.67, 1.5)
# A crowd (find --all, docs/design.md section 11.4): faces down to CROWD_RATIO times the smallest
# the coarse pass found (or, when it found nothing, than the faces assumed to matter) may be
# there. Seen well, they are seen that much smaller by a call 1 / CROWD_RATIO times finer; seen
# faintly (many weak boxes) or not at all, the whole image is detected again at the coarsest
# finer row whose table sees them (seen faintly, past the budget if need be; the finest
# affordable one when none does); and so on, within the pixel budget, but for one whole-image
# call per image past it that alone fits it (_Coarse).
CROWD_RATIO = 0.7
# With no box at all, a finer call is taken only if its table row expects fewer false detections
# than this in the whole image (rate times its pixels): YuNet's rows do on every image find
# resizes, Haar's (0.18-0.37 per Mpx) only on small ones. Chosen on the 432 face-free training
# images (bench/faces/find_scale.py's augmented set): without it Haar's find --all named a face
# on 46 of them instead of 41, YuNet's on 11 with it or without.
STEP_FALSE = 0.03
# Faces too small for the coarse scale to see strongly can still leave weak boxes: this many
# weak boxes that small (and no strong one that small) give the smallest face found; one or two
# say nothing of the faces' size and take no step (no box at all: STEP_FALSE), though a crop
# round one that finds a small strong face may still send the whole image finer (_Coarse).
CROWD_WEAK_BOXES = 3
# A crowd seen faintly: this many weak boxes smaller than the call's table row sees, in a picture
# where a face below CROWD_RATIO times the faces assumed was found, send the whole image to one
# more call at the scale that sees them, past the pixel budget if need be (once per image, if the
# call alone fits it: _Coarse's _finer_for_faint_faces). Chosen on training crowds: 25-50 px
# faces in 2048x1536 left 7-12 such boxes at 1/2 (found 86 of 100 faces without the call, 100
# with it), three 60-120 px faces in 4000x3000 left 3 (the call found nothing more and its
# texture boxes drew 2 false faces).
CROWD_FAINT_BOXES = 6

# The settings of search_image unless given: NMPT's operating point (confidence 0.9, 25 fixations,
# stop before fixating a cell a second time).
DEFAULT_SETTINGS = SearchSettings(confidence=0.9, max_fixations=25, stop_on_repeat=True)
# The settings of `ipomdp-gaze find`, chosen on training scenes (seed 1, 150, never on test
# scenes): with the one-time scan of faces-420 and inhibition of return, its shipped kernel was
# right (within one cell) on 0.973 at confidence 0.9 (4.8 fixations) and 0.980 at 0.99 (8.0
# fixations). A search never fixates a cell twice and gives up (repeat) once every cell was
# fixated.
#
# The absent hypothesis is on (prior 0.5), chosen on the training photos only (the astronaut and
# the six face-free training backgrounds of ipomdp_gaze/data/photos.csv; docs/faces.md "find on
# real photographs"): with faces-420, prior 0.05 and 0.1 said `found` on coins and ran past one
# full-resolution scan of detector pixels on 1 to 5 of the 7 photos; 0.5 said absent on all six
# face-free ones and found the astronaut in 2 fixations.
#
# Repeated views of a cell count 0.3 (search.repeat_weight; the fovea's overlapping windows see
# a persistent false alarm from many fixations), chosen on the training photos and training
# group pictures (docs/faces.md): with weight 1, YuNet said `found` on the face-free `coffee`
# (one texture detected from three neighbouring fixations) and Haar `found` 7 times near no face
# in the groups; with 0.3, `absent` on all six face-free photos for both, every training face
# still found, and 0 / 1 `found` near no face (YuNet / Haar); 0.5 still said `found` on coffee.
FIND_SETTINGS = SearchSettings(confidence=0.99, max_fixations=60, inhibit_return=True,
                               stop_on_repeat=True, repeat_weight=0.3, absent_prior=0.5,
                               decide_at_budget=True)
# The fovea scene tasks (evaluate --scenes, the ROS fovea demo's reference path) keep their
# settings: find's without the absent hypothesis, the deadline decision and the repeat weight
# (every scene holds a face; on 40 training scenes, seed 1, faces-420 was right on 38 with or
# without the absent hypothesis; a repeat weight of 0.3 cost it 5 more fixations on 28).
SCENE_SETTINGS = replace(FIND_SETTINGS, repeat_weight=1.0, absent_prior=0.0,
                         decide_at_budget=False)
STOP_REASONS = ('found', 'absent', 'budget', 'repeat', 'pixels')
METHODS = ('fovea', 'full_frame', 'scales')
# find --all: a found face takes the cells within 2 (Chebyshev) of its answer out of the search.
# One cell was too few on the composed group photos (docs/faces.md): a 48-90 px face spans 2-4
# cells of a 640x480 picture and its spread-out detections were found again as a second face.
FACE_RADIUS = 2
# search_many: cells within 1 of a face's occupied cell are settled (its spill-over), not
# searched on; on the training groups (bench/faces/many_faces.py) the spill-over cells next to a
# face otherwise stayed undecided and drew fixations until the pixel budget.
SETTLE_RADIUS = 1
# search_many decides a cell empty by its posterior, not by its evidence alone
# (OccupancySession's empty_by_evidence): on the training groups (bench/faces/many_faces.py
# --empty-by-evidence) the evidence rule found the same photo-group faces (47 and 48 of 48) and
# 17 instead of 9 of 64 small lfw faces at 640x480, but ran every scene to the pixel cap (one full
# scan); the full-resolution detector alone finds 61 of 64 for those pixels.
EMPTY_BY_EVIDENCE = False


@dataclass(frozen=True)
class Face:
    """
    One face of a many-target search: its box in image pixels, its cell and its probability.

    ``box`` is ``(x, y, w, h)`` in pixels: the detector's merged box cut to the image
    (:func:`clip_box`), or the rectangle of the face's cells when no box was found there;
    ``cell`` is ``(row, col)``; ``probability`` is ``P(at least one of the face's cells holds a
    face)`` (NaN for a full-frame answer).
    """

    box: tuple
    cell: tuple
    probability: float

    def to_dict(self) -> dict:
        """``{box: [x, y, w, h], cell: [row, col], probability}`` (probability null if NaN)."""
        return {'box': [float(v) for v in self.box], 'cell': [int(v) for v in self.cell],
                'probability': None if math.isnan(self.probability) else self.probability}


def clip_box(box, image_px: tuple) -> tuple:
    """
    Return a box ``(x, y, w, h)`` cut to an image of ``(width, height)`` pixels.

    A detector's box round a face at an edge reaches past it (the astronaut cropped at its
    face: ``(-5.2, -5.2, 62.1, 77.7)``); a reported box is the part inside the image.
    """
    width, height = image_px
    x, y, w, h = (float(v) for v in box)
    x0, y0 = min(max(x, 0.0), width), min(max(y, 0.0), height)
    x1, y1 = min(max(x + w, x0), width), min(max(y + h, y0), height)
    return (x0, y0, x1 - x0, y1 - y0)


@dataclass(frozen=True, eq=False)
class ImageSearch:
    """
    The outcome of :func:`search_image` on one image.

    Attributes
    ----------
    cell : (int, int)
        ``(row, col)`` of the most likely cell when the search stopped.
    pixel : (float, float)
        ``(x, y)`` of that cell's centre in image pixels (cell ``c`` spans columns
        ``floor(c W / cols)`` to ``floor((c + 1) W / cols)``, as the fovea tiles images).
    probability : float
        Its posterior probability.
    fixations : int
        Number of fixations made (observations applied).
    path : tuple of (int, int)
        The fixated cells ``(row, col)``, in order; the first is the start cell.
    stop : str
        ``'found'``, ``'absent'``, ``'budget'`` or ``'repeat'`` (module docstring).
    detector_pixels : int
        Pixels of all images given to the detector; the whole-image window counts once.
    seconds : float
        Wall time from the decoded image to the answer (module docstring).
    belief : numpy.ndarray
        ``(N,)`` posterior at stop, row-major.
    image_px : (int, int)
        ``(width, height)`` of the image searched.
    calibrated_px : (int, int) or None
        ``(width, height)`` the model was calibrated at (``model.meta['image']``), None if it
        does not say.
    decision : str
        ``found``, ``absent`` or ``gave_up`` (the session's decision; ``stop`` says why).
    absent_probability : float
        ``P(absent)`` at stop (0 without the absent hypothesis; NaN where no belief was
        computed: the full frame and the scale ladder).
    log : tuple
        The session's event log of this search.
    method : str
        ``fovea`` (the search) or ``full_frame`` (one full-resolution detector scan instead,
        :func:`full_frame_reason`); a full-frame answer has ``probability`` NaN.
    note : str
        Why the full frame was scanned ('' for the fovea).
    resized_from : (int, int) or None
        ``(width, height)`` of the image as given when it was resized before the search
        (``find --max-side``; ``pixel`` is then in the given image's pixels), else None.
    detections : tuple of (float, float)
        A full-frame scan's grouped detections, box centres ``(x, y)`` in image pixels.
    faces : tuple of Face
        A many-target search's faces (:func:`search_many`), most probable first; () otherwise.
    limit_cause : str
        What ended the search at a ``repeat`` stop (``every_cell``, ``next_repeats``,
        ``nothing_new``: :data:`ipomdp_gaze.search.answer.REPEATS`), else ''.

    """

    cell: tuple
    pixel: tuple
    probability: float
    fixations: int
    path: tuple
    stop: str
    detector_pixels: int
    seconds: float
    belief: np.ndarray
    image_px: tuple
    calibrated_px: tuple | None
    decision: str = ''
    absent_probability: float = 0.0
    log: tuple = ()
    method: str = 'fovea'
    note: str = ''
    resized_from: tuple | None = None
    detections: tuple = ()

    @property
    def ended(self) -> str:
        """How the search ended: ``confidence``, ``forced:<limit>``, ... (:mod:`..answer`)."""
        return answer.ended(self.decision,
                            'full_frame' if self.method in ('full_frame', 'scales') else self.stop)

    @property
    def answer_probability(self) -> float:
        """Return the answer's probability: ``P(absent)`` for ``absent``, else the cell's."""
        return answer.answer_probability(self.decision, self.probability,
                                         self.absent_probability)
    faces: tuple = ()
    limit_cause: str = ''

    @property
    def size_matches(self) -> bool:
        """Whether the image has the size the model was calibrated at (True if unknown)."""
        return self.calibrated_px is None or self.calibrated_px == self.image_px


def calibrated_size(model) -> tuple[int, int] | None:
    """
    ``(width, height)`` a model was calibrated at, from ``model.meta['image']``, or None.

    Raises
    ------
    ValueError
        If ``meta['image']`` is present but is not ``{width, height}`` of positive integers.

    """
    block = getattr(model, 'meta', {}).get('image')
    if block is None:
        return None
    try:
        width, height = block['width'], block['height']
    except (TypeError, KeyError):
        raise ValueError(f"the model's image record must be {{width, height}}, got "
                         f'{block!r}') from None
    for name, value in (('width', width), ('height', height)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"the model's image.{name} must be a positive integer, got "
                             f'{value!r}')
    return (int(width), int(height))


def check_image_size(image_px: tuple[int, int], fovea: Fovea) -> None:
    """
    Check that an image of ``(width, height)`` pixels is large enough for ``fovea``.

    It must be at least the detector's window (:func:`detector_window_px`) and have at least one
    pixel per cell along each side (what :meth:`Fovea.start` needs).

    Raises
    ------
    ValueError
        Naming the sizes.

    """
    width, height = image_px
    min_width, min_height = detector_window_px(fovea.detector)
    min_width, min_height = max(min_width, fovea.grid.cols), max(min_height, fovea.grid.rows)
    if width < min_width or height < min_height:
        raise ValueError(f'image of {width}x{height} pixels (WxH) is too small: the detector '
                         f'and the {fovea.grid.rows}x{fovea.grid.cols} grid need at least '
                         f'{min_width}x{min_height}')


def check_image(image, fovea: Fovea) -> tuple[int, int]:
    """
    Check that ``fovea`` can search ``image``; return its ``(width, height)``.

    The image must be ``uint8`` grey ``(H, W)`` or RGB ``(H, W, 3)`` and large enough
    (:func:`check_image_size`).

    Raises
    ------
    ValueError
        Naming the problem (dtype, shape or size).

    """
    if not isinstance(image, np.ndarray):
        raise ValueError(f'image must be a numpy array, got {type(image).__name__}')
    if image.dtype != np.uint8:
        raise ValueError(f'image must be 8-bit (uint8, 0..255), got dtype {image.dtype}')
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
        raise ValueError(f'image must be (H, W) grey or (H, W, 3) RGB, got shape {image.shape}')
    image_px = (int(image.shape[1]), int(image.shape[0]))
    check_image_size(image_px, fovea)
    return image_px


def cell_centre_px(grid: Grid, cell: int, image_px: tuple[int, int]) -> tuple[float, float]:
    """``(x, y)`` centre of a cell of an image of ``(width, height)`` pixels tiled by ``grid``."""
    row, col = grid.cell(cell)
    width, height = image_px
    x0, x1 = cell_edges_px(width, grid.cols)[[col, col + 1]]
    y0, y1 = cell_edges_px(height, grid.rows)[[row, row + 1]]
    return (float(x0 + x1) / 2.0, float(y0 + y1) / 2.0)


def search_image(image: np.ndarray, fovea: Fovea, model, policy,
                 settings: SearchSettings | None = None, *,
                 rng: np.random.Generator | None = None, pixel_budget: int | None = None,
                 excluded=(), restart: bool = True, prior=None) -> ImageSearch:
    """
    Search one decoded image with the fovea, the count model and a policy (module docstring).

    A thin driver of the search session (:mod:`ipomdp_gaze.search.session`) with the fovea as its
    sensor (:class:`ipomdp_gaze.vision.sensors.FoveaSensor`).

    Parameters
    ----------
    image : numpy.ndarray
        ``uint8`` grey ``(H, W)`` or RGB ``(H, W, 3)`` (an OpenCV BGR array must be converted
        to RGB first, see :func:`ipomdp_gaze.vision.detector.to_gray`).
    fovea : Fovea
        The digital fovea (its detector, grid and windows); restarted on ``image``.
    model : CountObservation
        The observation model; checked against the fovea with :func:`check_model`.
    policy : object
        ``policy.select(belief, t, rng)`` with ``belief`` of shape ``(1, N)``, returning one
        cell index (an array of one, or a scalar).
    settings : SearchSettings
        Confidence, budget (0: none), inhibition of return, ``stop_on_repeat`` (NMPT's rule),
        absent prior, repeat weight, start cell; :data:`DEFAULT_SETTINGS` by default. A search
        needs a budget or ``stop_on_repeat`` to end for sure.
    rng : numpy.random.Generator, optional
        Passed to the policy; ``np.random.default_rng(0)`` by default.
    pixel_budget : int, optional
        Detector pixels the search may spend (``find``: one full-resolution scan of the image);
        it stops undecided (``gave_up``, stop ``pixels``) before a fixation that would pass it.
    excluded : sequence of int
        Cells ruled out before the search (:meth:`SearchSession.exclude`; ``find --all``).
    restart : bool
        Start the fovea on ``image`` (False: the fovea already holds it, and its cached windows
        are reused at no detector cost, as in a second search of the same image).
    prior : array (N,), optional
        Where the face is a priori, summing to 1 (None: uniform; the controller's
        ``belief.prior``, so ``replay --new-search`` repeats a search that had one).

    Raises
    ------
    ValueError
        For a model that does not fit the fovea, a bad image, settings that never end, or a
        policy choice outside the grid.

    """
    t0 = time.perf_counter()
    check_model(model, fovea)
    settings = DEFAULT_SETTINGS if settings is None else settings
    calibrated = calibrated_size(model)
    image_px = check_image(image, fovea)
    outcome = run_search(SearchSession(fovea.grid, model, policy, settings, prior=prior),
                         FoveaSensor(fovea),
                         image, seed=np.random.default_rng(0) if rng is None else rng,
                         pixel_budget=pixel_budget, exclude=excluded, restart=restart)
    return _image_search(outcome, fovea.grid, image_px, calibrated, t0, outcome.decision)


def _image_search(outcome, grid, image_px, calibrated, t0: float, decision: str,
                  faces=()) -> ImageSearch:
    """Return the :class:`ImageSearch` of a fovea search's outcome (``t0``: its start)."""
    best = outcome.cell
    # A limit's name when one ended it (a decision it forced included), else the decision.
    stop = outcome.reason or outcome.decision
    return ImageSearch(cell=tuple(int(v) for v in grid.cell(best)),
                       pixel=cell_centre_px(grid, best, image_px),
                       probability=outcome.probability, fixations=outcome.fixations,
                       path=tuple(tuple(int(v) for v in grid.cell(k)) for k in outcome.path),
                       stop=stop, detector_pixels=outcome.detector_pixels,
                       seconds=time.perf_counter() - t0, belief=outcome.belief,
                       image_px=image_px, calibrated_px=calibrated, decision=decision,
                       absent_probability=outcome.absent_probability, log=outcome.log,
                       faces=faces, limit_cause=outcome.limit_cause)


def face_cells(grid: Grid, cell: int, radius: int = 1) -> np.ndarray:
    """
    Return the cells a found face takes out of the hypothesis set: those within ``radius``.

    A face's detections centre round its middle, so a face spanning several cells leaves its
    evidence within a cell or two of the answer; two faces whose centres are within ``radius``
    cells of each other are therefore found as one (:data:`FACE_RADIUS` for ``find --all``).
    """
    row, col = grid.cell(int(cell))
    rows = np.arange(max(0, row - radius), min(grid.rows, row + radius + 1))
    cols = np.arange(max(0, col - radius), min(grid.cols, col + radius + 1))
    return (rows[:, None] * grid.cols + cols[None, :]).ravel()


def search_all(image: np.ndarray, fovea: Fovea, model, policy,
               settings: SearchSettings | None = None, *,
               rng: np.random.Generator | None = None,
               pixel_budget: int | None = None) -> list[ImageSearch]:
    """
    Find every face: search, rule the found face's cells out (:func:`face_cells`), search again.

    Each search starts from the prior (the absent hypothesis included) with every found face's
    cells excluded and reuses the fovea's cached windows (a window is detected at most once per
    image); ``pixel_budget`` is each search's (``find --all``: one full scan per face found and
    one for the last search, so at most F + 1 full scans for F faces). Returns the searches in
    order: each ``found`` one a face, the last ``absent`` (no more faces) or ``gave_up``.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    excluded = np.zeros(fovea.grid.n_cells, dtype=bool)
    budget = math.inf if pixel_budget is None else int(pixel_budget)
    searches = []
    while True:
        result = search_image(image, fovea, model, policy, settings, rng=rng,
                              pixel_budget=budget, excluded=np.flatnonzero(excluded),
                              restart=not searches)
        searches.append(result)
        if result.decision != 'found':
            return searches
        excluded[face_cells(fovea.grid, fovea.grid.index(*result.cell), FACE_RADIUS)] = True
        if excluded.all():
            return searches


def full_frame_reason(fovea: Fovea, image_px: tuple[int, int], calibrated_px=None,
                      uses_fovea: bool = True) -> str:
    """
    Why one full-resolution detector scan should replace the fovea on this image, or ''.

    ``uses_fovea`` False: the search it replaces is ``find``'s scale ladder (``--scan coarse``),
    which uses no fovea: the same tests, said of the image and the scan's scales.

    - the fovea's one-time scan and cheapest first fixation cost more detector pixels than the
      whole image (a small image: the detector's minimum window makes windows expensive);
    - the fovea's smallest window is resized below the detector's window: the image is so much
      smaller than the model's calibrated size that those windows can see nothing, and a face
      there fills much of the frame (a 112x112 close-up portrait);
    - the image is at most half ``calibrated_px`` (the model's calibrated size) on both sides:
      faces there are far larger, relative to the windows, than those calibrated on.

    An image larger than the model's size is searched with the fovea (its faces appear larger
    in the windows than during calibration, and its line says so) within the pixel budget.
    """
    width, height = image_px
    probe = fovea.window_rects(fovea.grid.center_index, (height, width))
    scan = sum(w.resized_px[0] * w.resized_px[1] for w in probe
               if w.whole_image) if fovea.config.scan_once else 0
    fixation = sum(w.resized_px[0] * w.resized_px[1] for w in probe
                   if not (fovea.config.scan_once and w.whole_image))
    size = f'the image ({width}x{height} px)'
    if scan + fixation > width * height:
        if not uses_fovea:
            return (f'{size} is so small that one full-resolution scan ({width * height} '
                    f'detector pixels) costs less than a search')
        return (f'the fovea would cost more detector pixels ({scan + fixation}) than one '
                f'full-resolution scan ({width * height})')
    min_w, min_h = detector_window_px(fovea.detector)
    small = min(probe, key=lambda w: w.resized_px[0] * w.resized_px[1])
    if small.resized_px[0] < min_w or small.resized_px[1] < min_h:
        if not uses_fovea:
            at = '' if calibrated_px is None else f' ({calibrated_px[0]}x{calibrated_px[1]})'
            return (f'{size} is far below the size the model was calibrated at{at}: a face '
                    f'there fills much of the frame')
        return (f"the fovea's smallest window ({small.resized_px[0]}x{small.resized_px[1]} px) "
                f"is smaller than the detector's ({min_w}x{min_h}): the image is far below "
                f'the size the model was calibrated at')
    if calibrated_px is not None and 2 * width <= calibrated_px[0] \
            and 2 * height <= calibrated_px[1]:
        what = 'the fovea was' if uses_fovea else "the scan's scales were"
        return (f'{size} is at most half the size the model was calibrated at '
                f'({calibrated_px[0]}x{calibrated_px[1]}) on both sides: a face there fills far '
                f'more of the frame than {what} calibrated for')
    return ''


def full_frame_search(image: np.ndarray, fovea: Fovea, note: str = '',
                      calibrated_px=None) -> list[ImageSearch]:
    """
    One full-resolution detector scan instead of the fovea: each grouped detection a face.

    Returns one ``found`` result per grouped box (largest first), then one ``absent``; the
    probability is NaN (no belief is computed). Each result's ``faces`` holds every box.
    """
    t0 = time.perf_counter()
    image_px = check_image(image, fovea)
    grid = fovea.grid
    found = scan(image, fovea.detector, grid, 1.0)
    boxes = found.grouped_px
    order = np.argsort(-(boxes[:, 2] * boxes[:, 3]), kind='stable') if len(boxes) else []
    seconds = time.perf_counter() - t0
    common = {'fixations': 0, 'path': (), 'detector_pixels': found.detector_pixels,
              'seconds': seconds, 'image_px': image_px, 'calibrated_px': calibrated_px,
              'method': 'full_frame', 'note': note}
    centres = boxes[:, :2] + boxes[:, 2:] / 2 if len(boxes) else np.zeros((0, 2))
    common['detections'] = tuple((float(x), float(y)) for x, y in centres)
    cells = cells_of_points(centres, image.shape[:2], grid)
    common['faces'] = tuple(Face(box=clip_box(boxes[k], image_px),
                                 cell=tuple(int(v) for v in grid.cell(int(cells[k]))),
                                 probability=math.nan) for k in order)
    results = []
    for k in order:
        centre = centres[k][None, :]
        cell = int(cells[k])
        belief = np.zeros(grid.n_cells)
        belief[cell] = 1.0
        results.append(ImageSearch(cell=tuple(int(v) for v in grid.cell(cell)),
                                   pixel=(float(centre[0, 0]), float(centre[0, 1])),
                                   probability=math.nan, stop='found', belief=belief,
                                   decision='found', absent_probability=math.nan, **common))
    results.append(ImageSearch(cell=(0, 0), pixel=(math.nan, math.nan), probability=math.nan,
                               stop='absent', belief=np.zeros(grid.n_cells), decision='absent',
                               absent_probability=math.nan, **common))
    return results


def size_distance(image_px: tuple[int, int], calibrated_px: tuple[int, int]) -> float:
    """How far apart two image sizes are in scale: ``|log(w/w0)| + |log(h/h0)|``."""
    return abs(math.log(image_px[0] / calibrated_px[0])) + \
        abs(math.log(image_px[1] / calibrated_px[1]))


class _Recorder:
    """A fovea sensor that keeps every raw box and score it produced (for counting faces)."""

    def __init__(self, fovea: Fovea):
        self.sensor = FoveaSensor(fovea)
        self.grid, self.scans = self.sensor.grid, self.sensor.scans
        self.boxes, self.scores = [], []

    def start(self, scene):
        self.sensor.start(scene)

    def scan_cost(self):
        return self.sensor.scan_cost()

    def fixation_cost(self, cell):
        return self.sensor.fixation_cost(cell)

    def _keep(self, observation):
        """Keep the boxes of the windows read afresh (a cached window's were kept when read)."""
        boxes, scores = observation.boxes_px, observation.scores
        cached = getattr(observation, 'from_cache', ())
        if any(cached) and len(boxes):
            fresh = ~np.asarray(cached, dtype=bool)[observation.window_index]
            boxes, scores = boxes[fresh], scores[fresh]
        self.boxes.append(boxes)
        self.scores.append(scores)

    def scan(self):
        scan = self.sensor.fovea.scan()
        if scan is None:
            return None
        self._keep(scan)
        return Frame(scan.counts, kind='scan', detector_pixels=scan.detector_pixels,
                     seconds=scan.seconds)

    def observe(self, cell):
        obs = self.sensor.fovea.observe(int(cell))
        self._keep(obs)
        return Frame(fresh_counts(obs, self.grid), detector_pixels=obs.detector_pixels,
                     seconds=obs.seconds)


def fresh_counts(observation, grid) -> np.ndarray:
    """
    Return a fixation's counts with the cells only its cached windows saw left unobserved (NaN).

    A window served from the image's cache is the same pixels given to the same deterministic
    detector, so what it says was said when it was first read: counted again it is no new
    evidence (a clamped corner window, one weak box, counted once per fixation; docs/design.md
    section 11.4). A cell inside any window read afresh keeps its whole count, the sum over
    every window as the tables were calibrated.
    """
    fresh = np.zeros(grid.shape, dtype=bool)
    for window, cached in zip(observation.windows, observation.from_cache):
        if not cached:
            row, col, n_rows, n_cols = window.cells
            fresh[row:row + n_rows, col:col + n_cols] = True
    return np.where(fresh.ravel(), observation.counts, np.nan)


class _Coarse(_Recorder):
    """
    A fovea sensor whose one-time scan is the coarse full-frame pass (:mod:`.scales`).

    The detector runs once on the whole image at the table's coarsest scale that sees faces
    of the sizes that matter; its boxes become evidence per cell. Each group of cells a weak
    box left undecided is then cropped (with a margin of two cells) and detected at the next
    finer scale of the table, whose evidence replaces the coarser one for those cells (and
    their neighbours; a cell where both hold a strong box keeps both calls' evidence), until
    no cell is undecided, the finest scale was used or the next crop
    would pass ``budget`` pixels. Faces smaller than assumed send the whole image to a finer
    call first (:meth:`_finer_for_smaller_faces`, :meth:`_finer_for_faint_faces`); and when the
    whole image's calls found no strong box of their own while a crop did, one smaller than
    ``crowd_ratio`` times the faces they assumed, the cells they decided empty were decided for
    larger faces: the whole image is read again at the finest scale of a crop that found one,
    with the smallest of them as the faces assumed, and the steps go on from there
    (``crowd_ratio`` 0: neither). Once per image one of these whole-image calls may pass the
    budget, if the call alone costs no more than it (the detector alone at that scale; no
    crop, and no fixation, follows then). Faces too large for a scale (a close-up; the
    table's ``max_side_px``): a weak box of the first call too large for its scale sends the
    whole image, within the budget, to the scale where that box is the largest side, whose
    strong boxes too large for the first call's scale join its own; a finer look keeps the
    evidence of a cell whose strong box is too large for the look; and a strong box too large
    for every finer row decides its cell. All of it is one frame of kind ``evidence``;
    fixations are the fovea's windows, for cells still undecided.
    """

    def __init__(self, fovea: Fovea, table, image_px: tuple[int, int], prior: np.ndarray,
                 confidence: float, budget: float = math.inf, min_face: float | None = None,
                 look_upscale: float = LOOK_UPSCALE, look_score: float = LOOK_SCORE,
                 crowd_ratio: float = CROWD_RATIO):
        super().__init__(fovea)
        self.look_upscale, self.look_score = look_upscale, look_score
        self.scans = True
        self.table, self.image_px, self.prior = table, image_px, prior
        self.min_face = min_face_px(image_px) if min_face is None else float(min_face)
        self.scale = choose_scale(table, image_px, self.min_face)
        self.crowd_ratio = crowd_ratio
        self.detector = coarse_detector(fovea.detector, table.weak_score)
        self.fine_score = _fine_score(fovea.detector)
        self.threshold = math.log(confidence / (1.0 - confidence))
        self.budget = budget
        self.image = None
        self.looks = []
        self.overrun = False                # a whole-image call went past the budget

    def start(self, scene):
        super().start(scene)
        self.image = scene
        self.overrun = False

    def scan_cost(self):
        return self._whole_px(self.scale)

    def _whole_px(self, scale: float) -> int:
        """Return the detector pixels of a whole-image call at ``scale``."""
        return math.prod(scaled_size(*self.image_px, scale))

    def _may_read(self, scale: float, spent: int) -> bool:
        """
        Say whether a whole-image call at ``scale`` may follow ``spent`` pixels.

        Within the budget, always; past it once per image, if the call alone fits the budget
        (the detector alone at that scale; :attr:`overrun` says a call has passed it).
        """
        cost = self._whole_px(scale)
        return spent + cost <= self.budget or (not self.overrun and cost <= self.budget)

    def _look(self, rect, scale, spent: int = 0):
        """
        Detect in ``rect`` (x0, y0, x1, y1) at ``scale``: strong, weak boxes, pixels.

        ``spent``: the pixels the pass has read before; an enlarged look that would take the
        pass past its budget and :data:`LOOK_ALLOWANCE` of one full scan of the image is not
        taken (the best-scoring boxes are looked at first), and its box stays weak.
        """
        x0, y0, x1, y1 = rect
        found = scan(self.image[y0:y1, x0:x1], self.detector, (1, 1), scale)
        raw = found.boxes_px + (x0, y0, 0, 0)
        scores = np.ones(len(raw)) if found.scores is None else np.asarray(found.scores)
        pixels = found.detector_pixels
        if self.table.strong_score > 0:
            is_strong = scores >= self.table.strong_score
            if scale >= self.table.rows[-1].scale:
                # at the table's finest scale no finer look follows: a box the fovea's own
                # detector keeps (its calibrated score threshold) is strong there too, if the
                # enlarged look keeps it (look_upscale 0: at once)
                kept = np.flatnonzero((scores >= self.fine_score) & ~is_strong)
                if self.look_upscale:
                    confirmed = []
                    for k in kept[np.argsort(-scores[kept], kind='stable')]:
                        cost = _look_cost(raw[k], self.image_px, self.look_upscale, scale)
                        if spent + pixels + cost > self.budget + LOOK_ALLOWANCE * math.prod(
                                self.image_px):
                            continue
                        best, used = _enlarged_look(self.image, raw[k], self.image_px,
                                                    self.sensor.fovea.detector,
                                                    self.look_upscale, scale)
                        pixels += used
                        if best >= self.look_score:
                            confirmed.append(k)
                    kept = np.array(confirmed, dtype=np.intp)
                is_strong[kept] = True
            strong, weak = raw[is_strong], raw[~is_strong]
        else:           # a grouping detector: its grouped boxes strong, looser groups weak
            strong = found.grouped_px + (x0, y0, 0, 0)
            weak = (group_boxes(np.round(raw), self.table.weak_neighbors) if len(raw)
                    else raw)
        self.boxes.append(raw)
        self.scores.append(scores)
        self.looks.append((tuple(int(v) for v in rect), scale, pixels))
        return strong, weak, pixels

    def _finer_for_smaller_faces(self, strong, scale: float, side: float, weak=(),
                                 spent: int = 0):
        """
        Return the next whole-image call's scale and face side, when faces may be smaller.

        A strong box below ``crowd_ratio`` times the faces assumed to matter (``side``), or
        :data:`CROWD_WEAK_BOXES` weak ones that small, say the image holds smaller faces than
        assumed (a crowd), and the smallest of them that faces ``crowd_ratio`` times smaller
        still may be there; with no box at all, faces ``crowd_ratio`` times smaller than
        ``side`` may be. Small faces this call saw well (strong, with fewer than
        :data:`CROWD_WEAK_BOXES` weak boxes that small) are seen ``crowd_ratio`` times smaller
        by a call ``1 / crowd_ratio`` times finer (the finer row at or above it within the
        budget, ``spent``: the pixels read so far, else the finest that fits; see below when
        none fits). Faces it saw
        only faintly (that many weak boxes), or none at all, are looked for where the table
        says: when this call's scale does not see faces that small by its table row, at the
        coarsest finer row within the budget that does; for faces seen faintly, else the
        coarsest that does whose call alone fits the budget, past it once (a row the budget
        allows that does not see them would decide their cells empty: hard crowds); else the
        finest one within the budget; with no box at all, only rows that expect fewer false
        detections than :data:`STEP_FALSE`. The side
        returned is the next call's ``side``: the smallest face found (a face 0.7 times smaller
        still steps again), or with no box the smaller faces now assumed. When no finer row fits
        the budget, the rows whose call alone fits it are taken instead, unless a call passed the
        budget already, no box was seen, or the faces were seen well and the smallest of them is
        one this call's row sees (the next call would only look for faces 0.7 times smaller
        still: not worth a full call). None otherwise, when no finer row fits or
        ``crowd_ratio`` is 0.
        """
        if not self.crowd_ratio:
            return None
        sides = [box_sides(boxes) for boxes in (strong, weak)]
        small = [s[s < self.crowd_ratio * side] for s in sides]
        blind = False
        if len(small[0]):
            smallest = float(np.min(small[0]))
        elif len(small[1]) >= CROWD_WEAK_BOXES:
            smallest = float(np.min(small[1]))
        elif not len(sides[0]) and not len(sides[1]):
            smallest, blind = side, True
        else:
            return None
        rows = [r for r in self.table.rows if r.scale > scale * (1 + SCALE_RTOL)
                and not (blind and r.false_per_mpx * self._whole_px(r.scale) / 1e6 >= STEP_FALSE)]
        finer = [r for r in rows if spent + self._whole_px(r.scale) <= self.budget]
        seen_well = not blind and len(small[1]) < CROWD_WEAK_BOXES
        if not finer and not blind and not (
                seen_well and smallest * scale >= self.table.row(scale).min_side_px):
            # a crowd's step the budget refuses, for faces this call saw only faintly or
            # smaller than its table row sees (so it missed more of them): past the budget once
            finer = [r for r in rows if self._may_read(r.scale, spent)]
        if not finer:
            return None
        if seen_well:
            # small faces seen well (few weak boxes that small): faces crowd_ratio times
            # smaller are seen at the input size this call saw its smallest at, by a call
            # 1 / crowd_ratio times finer
            target = scale / self.crowd_ratio
            return next((r for r in finer if r.scale >= target * (1 - SCALE_RTOL)),
                        finer[-1]).scale, smallest
        want = smallest * self.crowd_ratio
        if want * scale >= self.table.row(scale).min_side_px:
            return None
        step = next((r for r in finer if want * r.scale >= r.min_side_px), None)
        if step is None and not blind:
            # no row within the budget sees faces that small: the coarsest that does, past the
            # budget once (a finer row the budget allows would leave them unseen and decided
            # empty)
            step = next((r for r in rows if want * r.scale >= r.min_side_px
                         and self._may_read(r.scale, spent)), None)
        return (step if step is not None else finer[-1]).scale, (want if blind else smallest)

    def _finer_for_faint_faces(self, strong, weak, scale: float, spent: int = 0):
        """
        Return the scale of one more whole-image call for a crowd this call saw faintly.

        In a crowd (a strong box below ``crowd_ratio`` times the faces first assumed), this
        call leaving :data:`CROWD_FAINT_BOXES` weak boxes smaller than its table row sees says
        the crowd's faces are at the edge of what it sees, and more are missed: the whole
        image is read once more at the coarsest finer row that sees the smallest of them
        (else the finest). That row is taken even when a coarser one would fit what is left of
        the budget (``spent``: the pixels read so far), since a coarser call would again see
        these faces at its edge: past the budget if no call has passed it yet and the call
        alone costs no more than the budget (the detector alone at that scale). None otherwise.
        """
        if not self.crowd_ratio:
            return None

        faint = box_sides(weak)
        faint = faint[faint < self.table.row(scale).min_side_px / scale]
        if len(faint) < CROWD_FAINT_BOXES or not np.any(
                box_sides(strong) < self.crowd_ratio * self.min_face):
            return None
        finer = [r for r in self.table.rows if r.scale > scale * (1 + SCALE_RTOL)
                 and self._may_read(r.scale, spent)]
        if not finer:
            return None
        smallest = float(np.min(faint))
        return next((r for r in finer if smallest * r.scale >= r.min_side_px), finer[-1]).scale

    def _crowd_shift(self, strong) -> np.ndarray:
        """
        Return the log odds that raise the prior to the crowd's own density (0 where it is more).

        In a crowd the prior's expected number of faces (under one, from ``absent.prior``) is
        contradicted by the faces found: the per-cell prior becomes the fraction of cells
        holding a strong box's centre (an empirical Bayes estimate), so that a strong box
        decides its cell and a cell without any box is decided empty without a finer look.
        """
        k = len(np.unique(box_cells(strong, self.image_px, self.grid)))
        n = self.grid.n_cells
        if not k or k >= n:
            return np.zeros(n)
        return np.maximum(0.0, math.log(k / (n - k)) - self.prior)

    def scan(self):
        t0 = time.perf_counter()
        width, height = self.image_px
        whole = (0, 0, width, height)
        strong, weak, pixels = self._look(whole, self.scale)
        at = larger_face_scale(self.table, weak, self.scale)
        if at is not None and pixels + self._whole_px(at) <= self.budget:
            # a weak box too large for the pass's scale (a close-up): the whole image again
            # where it is the detector's largest side; its strong boxes too large for the
            # pass's scale join the pass's
            large, _, spent = self._look(whole, at, pixels)
            pixels += spent
            strong = np.concatenate([strong, too_large(self.table, large, self.scale)])
        scale, side = self.scale, self.min_face
        while True:
            while (step := self._finer_for_smaller_faces(strong, scale, side, weak, pixels)
                   or self._finer_for_faint_faces(strong, weak, scale, pixels)) is not None:
                finer, side = step if isinstance(step, tuple) else (step, side)
                self.overrun |= pixels + self._whole_px(finer) > self.budget
                # the whole image again at the finer scale: its boxes and evidence replace the
                # coarser call's, whose strong boxes stay strong
                found, weak, spent = self._look(whole, finer, pixels)
                strong = np.concatenate([strong, found])
                pixels, scale = pixels + spent, finer
            shift = self._crowd_shift(strong) if scale != self.scale else 0.0
            term = coarse_evidence(self.table.row(scale), self.grid, self.image_px, pixels,
                                   strong, weak, self.prior + shift) + shift
            term, pixels, small, at = self._finer_looks(term, scale, side, shift, pixels,
                                                        strong)
            # the whole image's calls found no face of their own, and a crop found one smaller
            # than they assumed: the cells they decided empty may hold more like it, so the
            # whole image at the crop's scale (past the budget only as a crowd's step may be),
            # and the steps from there; at most once, since its strong boxes then hold the
            # crop's faces
            if len(strong) or not len(small) or at <= scale * (1 + SCALE_RTOL) \
                    or not self._may_read(at, pixels):
                break
            self.overrun |= pixels + self._whole_px(at) > self.budget
            found, weak, spent = self._look(whole, at, pixels)
            strong = np.concatenate([strong, small, found])
            pixels, scale = pixels + spent, at
            side = float(np.min(box_sides(small)))
        # a strong box beyond the detector's largest side at every row finer than the pass's
        # (at the pass's own scale when none is finer): no finer look can see that face, nor a
        # fixation (windows of a few cells), so the calls that saw it decide its cell (a hair
        # past the threshold, so that prior + term does not round to a step below it)
        finer = [row.scale for row in self.table.rows if row.scale > scale * (1 + SCALE_RTOL)]
        cells = box_cells(too_large(self.table, strong, min(finer, default=scale)),
                          self.image_px, self.grid)
        prior = np.broadcast_to(self.prior, term.shape)
        term[cells] = np.maximum(term[cells], self.threshold - prior[cells] + DECIDED_MARGIN)
        return Frame(term, kind='evidence', detector_pixels=pixels,
                     seconds=time.perf_counter() - t0)

    def _finer_looks(self, term, scale: float, side: float, shift, pixels: int, seen):
        """
        Look again at each group of undecided cells, at each finer row in turn (class docstring).

        Returns ``(term, pixels, small, at)``: the evidence with each look's replacing the
        coarser one round its cells, the pixels read in all, the strong boxes of the looks
        smaller than ``crowd_ratio`` times ``side`` (the faces the whole image's calls assumed)
        and the finest scale of a look that found one (0 without). A cell holding the centre of
        a strong box of the whole image's calls (``seen``) beyond the detector's largest side
        at the look's scale (``ScaleTable.max_side_px``) keeps its evidence: a look that cannot
        see that face does not say it is not there (YuNet finds no face of 720 px at 1), nor
        does a look whose crop (the cells and two more round them) cuts the box and that does
        not see it strong again (Haar's 302 px face at 1/2 in a 901x2048 photo, looked at in a
        crop 215 px wide, was 'absent'). A
        cell whose evidence is a strong box's and that the look sees strong again adds the
        look's evidence to it: two calls at different scales agree, as the ladder's confirming
        look (on a 6400x4800 photo each call's false-detection chance per cell, many pixels
        large, left six faces strong at 1/4, 1/3, 1/2 and 1 undecided, and the fixations
        then read the whole budget).
        """
        small, at = [], 0.0
        # cells whose evidence is a strong box's (the whole image's calls, then each look's)
        held = np.zeros(self.grid.n_cells, dtype=bool)
        held[box_cells(seen, self.image_px, self.grid)] = True
        for row in (r for r in self.table.rows if r.scale > scale):
            unseen = np.zeros(self.grid.n_cells, dtype=bool)
            unseen[box_cells(too_large(self.table, seen, row.scale), self.image_px,
                             self.grid)] = True
            undecided = np.abs(self.prior + term) < self.threshold
            if not undecided.any():
                break
            _, _, stats, _ = cv2.connectedComponentsWithStats(
                undecided.reshape(self.grid.shape).astype(np.uint8), connectivity=8)
            for col, row_, n_cols, n_rows, _ in stats[1:]:
                box = (slice(row_, row_ + n_rows), slice(col, col + n_cols))
                rect = _cell_rect(self.grid, box, 2, self.image_px)
                cost = math.prod(scaled_size(rect[2] - rect[0], rect[3] - rect[1], row.scale))
                if pixels + cost > self.budget:
                    break
                strong, weak, spent = self._look(rect, row.scale, pixels)
                pixels += spent
                fine = coarse_evidence(row, self.grid, self.image_px, spent, strong, weak,
                                       self.prior + shift) + shift
                inner = np.zeros(self.grid.shape, dtype=bool)
                inner[_grown(box, 1, self.grid.shape)] = True
                strong = np.asarray(strong, dtype=float).reshape(-1, 4)
                again = np.zeros(self.grid.n_cells, dtype=bool)
                again[box_cells(strong, self.image_px, self.grid)] = True
                # a strong box the look's crop cuts: a look that does not see it again cannot
                # say that face is not there either
                cut = np.zeros(self.grid.n_cells, dtype=bool)
                cut[box_cells(_cut_by(seen, rect, self.image_px), self.image_px,
                              self.grid)] = True
                inner = inner.reshape(-1) & ~unseen & ~(cut & ~again)
                # a strong box seen again by a call at another scale: both calls' evidence (the
                # crowd's shift once), as the ladder's confirming look; otherwise the look's
                term = np.where(inner, np.where(held & again, term + fine - shift, fine), term)
                held = np.where(inner, again, held)
                smaller = strong[box_sides(strong) < self.crowd_ratio * side]
                if len(smaller):
                    small.append(smaller)
                    at = max(at, row.scale)
        small = np.concatenate(small) if small else np.zeros((0, 4))
        return term, pixels, small, at


def _fine_score(detector) -> float:
    """Return the score from which the fovea's detector keeps a box (inf: it keeps no score)."""
    settings = getattr(detector, 'settings', None)
    return (settings() if callable(settings) else {}).get('score_threshold', math.inf)


def _cut_by(boxes, rect: tuple, image_px: tuple) -> np.ndarray:
    """Return the boxes (K, 4) that the crop ``rect`` (x0, y0, x1, y1) cuts, within the image."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    width, height = image_px
    x0, y0 = np.maximum(boxes[:, 0], 0.0), np.maximum(boxes[:, 1], 0.0)
    x1 = np.minimum(boxes[:, 0] + boxes[:, 2], width)
    y1 = np.minimum(boxes[:, 1] + boxes[:, 3], height)
    inside = (x0 >= rect[0]) & (y0 >= rect[1]) & (x1 <= rect[2]) & (y1 <= rect[3])
    return boxes[~inside]


def _grown(box: tuple, margin: int, shape: tuple) -> tuple:
    """Return a pair of row and column slices grown by ``margin`` cells within ``shape``."""
    return tuple(slice(max(0, b.start - margin), min(n, b.stop + margin))
                 for b, n in zip(box, shape))


def _cell_rect(grid: Grid, box: tuple, margin: int, image_px: tuple) -> tuple:
    """Return the pixel rectangle (x0, y0, x1, y1) of a box of cells grown by ``margin``."""
    rows, cols = _grown(box, margin, grid.shape)
    width, height = image_px
    return (int(np.floor(cols.start * width / grid.cols)),
            int(np.floor(rows.start * height / grid.rows)),
            int(np.ceil(cols.stop * width / grid.cols)),
            int(np.ceil(rows.stop * height / grid.rows)))


def prepare_many(fovea: Fovea, model, scales: ScaleTable | None = None) -> None:
    """
    Build what :func:`search_many` builds once, outside its seconds (as ``find`` sets up).

    The belief's information table of the model and, with ``scales``, the coarse pass's
    detector and the Haar check's cascades (a table with a ``haar_check_score``); all cached,
    so a second call costs nothing. (A fixation's cost is the fovea's on the image searched:
    :meth:`~ipomdp_gaze.vision.fovea.Fovea.fresh_views`.)
    """
    OccupancySession(fovea.grid, model, replace(FIND_SETTINGS, targets='many'))
    if scales is not None:
        coarse_detector(fovea.detector, scales.weak_score)
        if scales.haar_check_score > 0:
            haar_check_detectors()


def search_many(image: np.ndarray, fovea: Fovea, model,
                settings: SearchSettings | None = None, *,
                pixel_budget: int | None = None, link: int = FACE_RADIUS,
                settle: int = SETTLE_RADIUS,
                empty_by_evidence: bool = EMPTY_BY_EVIDENCE,
                scales: ScaleTable | None = None,
                min_face: float | None = None, look_upscale: float = LOOK_UPSCALE,
                look_score: float = LOOK_SCORE, crowd_ratio: float = CROWD_RATIO) -> ImageSearch:
    """
    Search one image for every face at once: the many-target belief (``search.targets: many``).

    One search session over the occupancy of every cell (:class:`ipomdp_gaze.search.many.
    OccupancySession`): the scan, then the fixation with the largest expected drop of the
    summed cell entropies per detector pixel, until every cell is decided at the confidence
    (or the budget, or ``pixel_budget``: for ``find``, one full-resolution scan of the image
    as given, before ``--max-side``; beyond it only the looks' :data:`LOOK_ALLOWANCE` and, once,
    a crowd's whole-image call that alone fits it (:class:`_Coarse`: the crowd's steps, the crop
    rule and the faint rule); with a ``pixel_budget`` the fixations after the scan also read
    at most one full scan of this image). The faces are the clusters of occupied cells, each
    counted once and split where the detector's merged boxes are distinct faces
    (:func:`ipomdp_gaze.model.occupancy.count_faces`, cells within ``link`` of each other are
    one cluster); cells within ``settle`` of an occupied cell need no decision of
    their own (:class:`~ipomdp_gaze.search.many.OccupancySession`, ``link``). ``decision`` is
    ``found`` when a face was reported, else ``absent`` (or ``gave_up``).

    With ``scales`` (a detector's :class:`~ipomdp_gaze.vision.scales.ScaleTable`; ``find
    --all``) the one-time scan is the coarse full-frame pass at the coarsest scale that sees
    faces of the sizes that matter, and the fovea's finer windows are spent only on the cells
    it leaves undecided (a weak detection); without, the fovea's own scan (as before).
    ``min_face``: the smallest face side that matters, in the image's pixels (default
    :func:`~ipomdp_gaze.vision.scales.min_face_px`, 1/10 of the shorter side), which chooses
    the coarse scale. A full-resolution box of the coarse pass below the table's strong score
    is strong only if the crop round it, resized so that the box is ``LOOK_SIDE_PX`` (at most
    ``look_upscale`` times and never below the scale of the call that found the box, the
    table's finest: :func:`look_factor`, 1 to 2x at full resolution; 0: no look), keeps a box
    of ``look_score``; else it is weak. A face found smaller than ``crowd_ratio`` times
    ``min_face`` (a crowd), or no box at all, sends the whole image to a finer call: 1 /
    ``crowd_ratio`` times finer for faces seen well, where the table says smaller faces are
    seen for faces seen faintly or not at all (:meth:`_Coarse._finer_for_smaller_faces`), and
    the faces found set the prior's density (:data:`CROWD_RATIO`; 0: neither); a smaller face
    that only a finer crop found, when the whole image's calls found none, sends the whole
    image to the crop's scale (:class:`_Coarse`). With the detector's strong score, a face one
    call saw strongly is a face beside faces that several calls saw (``count_faces(strong=)``).
    With the table's ``haar_check_score`` (YuNet's), a face whose best box is below it is
    reported only if Haar's cascades see it (:func:`haar_checked`; its pixels are counted, past
    the budget); a vetoed face's cells keep their belief but are left out of
    ``absent_probability``.

    Raises
    ------
    ValueError
        For a model that does not fit the fovea, a bad image or settings the belief refuses.

    """
    t0 = time.perf_counter()
    check_model(model, fovea)
    settings = replace(FIND_SETTINGS if settings is None else settings, targets='many')
    image_px = check_image(image, fovea)
    session = OccupancySession(fovea.grid, model, settings, link=settle,
                               empty_by_evidence=empty_by_evidence)
    # a window read already on this image is no new evidence (fresh_counts): the choice
    # counts only what each fixation would read afresh, and its pixels (the costs)
    session.set_fresh(fovea.fresh_views)
    if scales is None:
        sensor = _Recorder(fovea)
    else:
        prior = prior_log_odds(fovea.grid.n_cells,
                               cell_prior(fovea.grid.n_cells, settings.absent_prior))
        sensor = _Coarse(fovea, scales, image_px, prior, settings.confidence,
                         math.inf if pixel_budget is None else pixel_budget, min_face,
                         look_upscale, look_score, crowd_ratio)
    # the fovea's windows after the pass: at most one full scan of this image, also when the
    # budget is one of the (larger) image as given
    outcome = run_search(session, sensor, image, pixel_budget=pixel_budget,
                         fixation_budget=None if pixel_budget is None else math.prod(image_px))
    boxes = np.concatenate(sensor.boxes) if sensor.boxes else np.zeros((0, 4))
    scores = np.concatenate(sensor.scores) if sensor.scores else np.zeros(0)
    grid = fovea.grid
    found = session.faces(boxes, scores, image_px, link,
                          strong=scales.strong_score if scales is not None
                          and scales.strong_score > 0 else None)
    checked_px, vetoed = 0, []
    if scales is not None and scales.haar_check_score > 0:
        keep, checked_px = haar_checked(image, found, boxes, scores, image_px,
                                        scales.haar_check_score, scales.haar_check_neighbors)
        vetoed = [f for f, k in zip(found, keep) if not k]
        found = [f for f, k in zip(found, keep) if k]
    faces = tuple(Face(box=clip_box(f['box'], image_px),
                       cell=tuple(int(v) for v in grid.cell(f['cell'])),
                       probability=f['probability']) for f in found)
    decision = outcome.decision
    if decision in ('found', 'absent'):
        decision = 'found' if faces else 'absent'
    result = _image_search(outcome, grid, image_px, calibrated_size(model), t0, decision, faces)
    if checked_px:
        result = replace(result, detector_pixels=result.detector_pixels + checked_px)
    if vetoed:
        # the check decided the vetoed faces' cells: they keep their belief (the map), but
        # P(nobody here) is the other cells' (else an image whose only face was vetoed would be
        # absent with p_nobody near 0), and such an image stopped at absent, not found
        out = np.zeros(grid.n_cells, dtype=bool)
        out[np.concatenate([f['cells'] for f in vetoed])] = True
        result = replace(result,
                         absent_probability=float(np.exp(log_nobody(session.log_odds[~out]))))
        if not faces and result.stop == 'found':
            result = replace(result, stop='absent')
    if not faces:
        return result
    # the image's answer is its most probable face, at its box's centre (as search_first)
    x, y, w, h = faces[0].box
    return replace(result, cell=faces[0].cell, pixel=(x + w / 2.0, y + h / 2.0),
                   probability=faces[0].probability)


def search_first(image: np.ndarray, fovea: Fovea, model,
                 settings: SearchSettings | None = None, *,
                 pixel_budget: int | None = None, scales: ScaleTable | None = None,
                 min_face: float | None = None) -> ImageSearch:
    """
    Find the one face of ``find`` (without ``--all``) by the coarse pass first (``--scan coarse``).

    The many-target search of :func:`search_many` with the detector's scale table (one
    full-frame call at the coarsest scale that sees faces of ``min_face``, finer crops and the
    fovea's windows only where cells stay undecided), answered as one target: ``found`` at the
    most probable face (its cell, the centre of its box cut to the image as the pixel, its
    probability), else ``absent`` (every cell decided empty; ``absent_probability`` is ``P(nobody
    here)``) or ``gave_up``. The paper's single-target belief is not used.
    """
    t0 = time.perf_counter()
    many = search_many(image, fovea, model, settings, pixel_budget=pixel_budget,
                       scales=scales, min_face=min_face)
    if not many.faces:
        return replace(many, seconds=time.perf_counter() - t0)
    return replace(many, decision='found', seconds=time.perf_counter() - t0)


def _ladder_answer(found, strong_score: float, last: bool, keep_from: float = -math.inf):
    """
    Return the answer box (x, y, w, h) of one rung of :func:`search_scales`, or None.

    ``keep_from``: at the last rung a scoring detector's best box answers from this score
    (the fovea's own threshold, when the call also kept faint boxes below it).
    """
    if found.scores is not None and len(found.boxes_px) and strong_score > 0:
        scores = np.asarray(found.scores, dtype=float)
        best = int(np.argmax(scores))
        if (last and scores[best] >= keep_from) or scores[best] >= strong_score:
            return found.boxes_px[best]
        return None
    if not len(found.grouped_px):
        return None
    # a grouping detector: the merged box holding the most raw detection centres
    centres = box_centres_px(found.boxes_px)
    inside = [int(np.sum((centres[:, 0] >= x) & (centres[:, 0] < x + w)
                         & (centres[:, 1] >= y) & (centres[:, 1] < y + h)))
              for x, y, w, h in found.grouped_px]
    return found.grouped_px[int(np.argmax(inside))]


def _crop_round(box, image_px, reach: float = 1.0) -> tuple[int, int, int, int]:
    """Return the crop ``(x0, y0, x1, y1)`` round a box: ``reach`` of its larger side each side."""
    x, y, w, h = box
    side = reach * max(w, h)
    return (int(max(0, x - side)), int(max(0, y - side)),
            int(min(image_px[0], x + w + side)), int(min(image_px[1], y + h + side)))


def _best_score(found) -> float:
    """Return the highest box score of a scan (NaN for a detector without scores or no box)."""
    if found.scores is None or not len(found.scores):
        return math.nan
    return float(np.max(found.scores))


def _min_side_px(scales: ScaleTable, scale: float) -> float:
    """
    Return the smallest face side (detector input px) taken as seen at ``scale``.

    A scale of the table (within ``SCALE_RTOL``): its row's. Any other takes the finest row's
    side, measured only at that row's scale: for the frame enlarged beyond it (``finest`` above
    the table, ``--min-face``) the side is assumed to hold in the enlarged detector input too;
    for a ``finest`` between rows or below the coarsest (given to :func:`search_scales`, never
    by ``find``) it is not its neighbouring rows' side (YuNet: 48 px at 1 against 36-44 px at
    1/2-1/4).
    """
    try:
        return scales.row(scale).min_side_px
    except ValueError:                          # off the table: the finest row's (docstring)
        return scales.rows[-1].min_side_px


def _faint_box(found, threshold: float, max_side_px: float, floor: float = -math.inf):
    """Return the best box scoring in ``[floor, threshold)`` no larger than ``max_side_px``."""
    scores = np.asarray(found.scores, dtype=float)
    boxes = np.asarray(found.boxes_px, dtype=float).reshape(-1, 4)
    small = (scores < threshold) & (scores >= floor) \
        & (np.max(boxes[:, 2:], axis=1, initial=0) <= max_side_px)
    return boxes[small][int(np.argmax(scores[small]))] if small.any() else None


def _centred_in(boxes, box, offset=(0.0, 0.0)) -> np.ndarray:
    """Return which of ``boxes`` (moved by ``offset``, a crop's corner) are centred in ``box``."""
    x, y, w, h = box
    centres = box_centres_px(boxes) + offset
    return ((centres[:, 0] >= x) & (centres[:, 0] <= x + w)
            & (centres[:, 1] >= y) & (centres[:, 1] <= y + h))


def per_thread(build):
    """
    Cache ``build()``'s answer once per thread (``cache_clear()``, ``built()`` as lru_cache's).

    OpenCV's cascade classifiers keep buffers between calls of ``detectMultiScale``, so one
    object must not be called from two threads at once (a node's executor, a user's threads):
    each thread gets its own, built the first time that thread asks.
    """
    local = threading.local()

    @functools.wraps(build)
    def get():
        if not hasattr(local, 'value'):
            local.value = build()
        return local.value

    def cache_clear() -> None:
        """Forget this thread's copy."""
        local.__dict__.pop('value', None)

    get.cache_clear = cache_clear
    get.built = lambda: hasattr(local, 'value')
    return get


@per_thread
def second_opinion_detector():
    """Return OpenCV's Haar face cascade (the package's ``haar`` kind), built once per thread."""
    from ipomdp_gaze.vision.detectors import make_detector
    return make_detector('haar')


def _second_opinion(image: np.ndarray, found, image_px: tuple[int, int], score: float,
                    n_boxes: int, side: float, neighbors: int):
    """
    Return Haar's answer in the crops round ``found``'s best faint boxes, or None; and its pixels.

    The ``n_boxes`` best boxes from ``score``, each at most ``side`` of the shorter side, in
    order: a grouped Haar box of ``neighbors`` neighbours centred in the box answers (that Haar
    box). Crops smaller than the cascade's window are skipped.
    """
    width, height = image_px
    scores = np.asarray(found.scores, dtype=float)
    boxes = np.asarray(found.boxes_px, dtype=float).reshape(-1, 4)
    largest = np.max(boxes[:, 2:], axis=1, initial=0)
    keep = np.flatnonzero((scores >= score) & (largest <= side * min(width, height)))
    haar = second_opinion_detector()
    window = min(detector_window_px(haar))
    pixels = 0
    for k in keep[np.argsort(-scores[keep], kind='stable')][:n_boxes]:
        x0, y0, x1, y1 = _crop_round(boxes[k], image_px, reach=0.5)
        if min(x1 - x0, y1 - y0) < window:
            continue
        look = scan(image[y0:y1, x0:x1], haar, (1, 1), 1.0, min_neighbors=neighbors)
        pixels += look.detector_pixels
        centred = np.flatnonzero(_centred_in(look.grouped_px, boxes[k], (x0, y0)))
        if centred.size:
            return np.asarray(look.grouped_px[centred[0]], dtype=float) + (x0, y0, 0, 0), pixels
    return None, pixels


@per_thread
def haar_check_detectors() -> tuple:
    """Return the check's cascades (:data:`HAAR_CHECK_CASCADES`), built once per thread."""
    from ipomdp_gaze.vision.detectors import make_detector
    sizes = {'min_size_px': round(HAAR_CHECK_RANGE[0] * HAAR_CHECK_SIDE_PX),
             'max_size_px': round(HAAR_CHECK_RANGE[1] * HAAR_CHECK_SIDE_PX)}
    return tuple(make_detector('haar', cascade=name, mirror=mirror, **sizes)
                 for name, mirror in HAAR_CHECK_CASCADES)


def first_level(haar) -> tuple[float, tuple[int, int]]:
    """
    Return the factor and window (px) of a one-cascade detector's first pyramid level.

    As OpenCV's ``detectMultiScale`` picks it: the first power of the scale factor whose
    rounded window reaches ``min_size_px`` (20 px and 64 px at 1.1: 1.1 ** 13, a 69 px window),
    not the minimum size itself; the level reads the image reduced by that factor.
    """
    width, height = detector_window_px(haar)
    least = haar.min_size_px or (0, 0)
    factor = 1.0
    while round(width * factor) < least[0] or round(height * factor) < least[1]:
        factor *= haar.scale_factor
    return factor, (round(width * factor), round(height * factor))


def haar_checked(image: np.ndarray, faces: list, boxes, scores, image_px: tuple[int, int],
                 score: float, neighbors: int) -> tuple[np.ndarray, int]:
    """
    Return which of ``faces`` a second detector does not veto (bools), and the pixels it read.

    A face whose best box (the highest score of the boxes centred in its box; none for a
    face without a box) scores at least ``score`` is kept as it is. Any other is kept only
    if one of the check's cascades (:func:`haar_check_detectors`, in order, the next only when
    the one before saw nothing) finds a grouped box of ``neighbors`` neighbours centred in
    the face's box (cut to the image), in the crop round it (half its side on each side)
    resized so that the box is :data:`HAAR_CHECK_SIDE_PX`, among faces of
    :data:`HAAR_CHECK_RANGE` times that side: on the training material YuNet's false faces on
    turned or enlarged textures are boxes of 0.37-0.83 that no cascade sees (docs/design.md
    section 11.4). A face the cascades cannot judge keeps its place: one cut by the image's
    edge (a cascade needs the whole face), too small to be enlarged that far (``MAX_SCALE``),
    or whose resized crop is smaller than a cascade's window at its pyramid's first level
    (:func:`first_level`: no level would read it). The pixels counted are each cascade's
    first level, for each image it ran on (the crop, and its mirror image for the profile).
    """
    scores = np.asarray(scores, dtype=float).reshape(-1)
    cascades = haar_check_detectors()
    levels = [first_level(haar) for haar in cascades]
    keep, pixels = np.zeros(len(faces), dtype=bool), 0
    for i, face in enumerate(faces):
        x, y, w, h = clip_box(face['box'], image_px)
        inside = _centred_in(boxes, (x, y, w, h))
        if inside.any() and scores[inside].max() >= score:
            keep[i] = True
            continue
        x0, y0, x1, y1 = _crop_round((x, y, w, h), image_px, reach=0.5)
        factor = HAAR_CHECK_SIDE_PX / max(w, h, 1.0)
        cut = x <= 0 or y <= 0 or x + w >= image_px[0] or y + h >= image_px[1]
        size = scaled_size(x1 - x0, y1 - y0, factor)
        if cut or factor > MAX_SCALE or any(size[0] < win[0] or size[1] < win[1]
                                            for _, win in levels):
            keep[i] = True
            continue
        for haar, (level, _) in zip(cascades, levels):
            look = scan(image[y0:y1, x0:x1], haar, (1, 1), factor, min_neighbors=neighbors)
            # the pixels a cascade reads are those of its pyramid's first level (first_level),
            # twice for one also run on the mirror image
            pixels += (round(size[0] / level) * round(size[1] / level)
                       * (1 + sum(haar.mirror)))
            # the grouped boxes are in the crop's own pixels (scan maps them back)
            if _centred_in(look.grouped_px, (x, y, w, h), (x0, y0)).any():
                keep[i] = True
                break
    return keep, pixels


def look_factor(box, upscale: float, scale: float = 1.0) -> float:
    """
    Return the resize of the enlarged look at ``box``, found by a call at ``scale``.

    The box's larger side to LOOK_SIDE_PX, at most ``upscale`` times and never below the
    call's own scale (the look does not see the box smaller than the call that found it).
    Both bounds are factors of the image given to the search, so above 1 (the frame enlarged
    for ``--min-face``) the look enlarges the call's view at most ``upscale / scale`` times,
    and from ``scale >= upscale`` (2x) not at all: it scores the box again at the call's own
    scale, in the crop round it instead of the whole frame (other context, no more detail).
    """
    return min(max(upscale, scale), max(scale, LOOK_SIDE_PX / max(box[2], box[3])))


def _look_geometry(box, image_px, upscale: float, scale: float = 1.0):
    """Return the enlarged look's crop ``(x0, y0, x1, y1)``, its resize and its size ``(w, h)``."""
    x0, y0, x1, y1 = _crop_round(box, image_px)
    factor = look_factor(box, upscale, scale)
    return (x0, y0, x1, y1), factor, (round((x1 - x0) * factor), round((y1 - y0) * factor))


def _look_cost(box, image_px, upscale: float, scale: float = 1.0) -> int:
    """Return the detector pixels of :func:`_enlarged_look` at ``box`` (before it runs)."""
    return math.prod(_look_geometry(box, image_px, upscale, scale)[2])


def _enlarged_look(image: np.ndarray, box, image_px, detector, upscale: float,
                   scale: float = 1.0):
    """Return ``(best score, pixels)`` of the detector on the crop round ``box``, resized."""
    (x0, y0, x1, y1), factor, _ = _look_geometry(box, image_px, upscale, scale)
    crop = cv2.resize(np.ascontiguousarray(image[y0:y1, x0:x1]), None, fx=factor, fy=factor,
                      interpolation=cv2.INTER_LINEAR if factor >= 1 else cv2.INTER_AREA)
    look = scan(crop, detector, (1, 1), 1.0)
    return _best_score(look), look.detector_pixels


def search_scales(image: np.ndarray, fovea: Fovea, model, scales: ScaleTable, *,
                  start: float, confirm: bool = True, look_upscale: float = LOOK_UPSCALE,
                  look_score: float = LOOK_SCORE, faint_score: float = FAINT_SCORE,
                  faint_look_score: float = FAINT_LOOK_SCORE,
                  finest: float | None = None, second_score: float = SECOND_SCORE,
                  second_boxes: int = SECOND_BOXES, second_side: float = SECOND_SIDE,
                  second_neighbors: int = SECOND_NEIGHBORS) -> ImageSearch:
    """
    Find the one face of ``find`` by full-frame calls from coarse to fine (``--scan coarse``).

    The detector runs on the whole image at ``start`` and then at each finer scale of the
    table up to ``finest`` (default the table's finest; above it, one more call on the image
    enlarged ``finest`` times: :func:`~ipomdp_gaze.vision.scales.finest_scale` for faces too
    small for full resolution; :func:`~ipomdp_gaze.vision.scales.ladder_scales`). A ``finest``
    below ``start`` does not run ``start``. For a detector with a largest side (YuNet: 300
    px, ``ScaleTable.max_side_px``) a call before the last that leaves a box (from the
    table's weak score) too large for its scale and answers nothing sends the whole image,
    next and once, to the scale where that box is the largest side (a close-up portrait).
    The ladder stops at the first call with a strong box (YuNet: a
    score of at least the table's ``strong_score``; Haar: a merged box); at its last scale
    (``finest``) any box the fovea's detector keeps answers. With ``confirm`` a strong box of a
    coarser call answers only if a crop round it (its side on each side) at the next finer
    scale keeps a box (strong unless that scale is the last), or, for a box beyond the
    detector's largest side there, at the scale where it is that side (never below its own
    call's, where the look mostly finds the box again; the box confirmed there must be strong
    even when the next rung is the last: :func:`~ipomdp_gaze.vision.scales.confirm_scale`);
    else the next scale's full-frame call follows. A strong box of the last call is never
    confirmed, so a ``finest`` at or below ``start`` (a coarse end for large faces) answers a
    strong box of its coarse call as it is (YuNet's table: 16x the strong false detections
    per Mpx at 1/4 as at 1). A box of a scoring detector that answers at the last scale below
    the table's strong score answers only if the same crop, resized so that the box is
    ``LOOK_SIDE_PX`` (at most ``look_upscale`` times, never below the call's scale:
    :func:`look_factor`; 0: no look), keeps a box of at least ``look_score`` (a face grows
    clearer, a texture rarely does). On the frame enlarged beyond the table
    (``finest`` above 1) that look is no enlargement of what the call saw: at most
    ``look_upscale / finest`` times its view, and from ``finest >= look_upscale`` (2x) the box
    scored again at the call's own scale, in the crop round it instead of the whole frame
    (other context, no more detail); the faint look below likewise. When no box has answered
    by the end, the last call's best faint box (a score from ``faint_score``, below the
    detector's own threshold; 0: none) no larger than ``FAINT_SIDE`` times the smallest face
    side of the last scale (:func:`_min_side_px`) gets the same look and answers if it keeps
    ``faint_look_score`` (a face too small for the scale). Then, for a scoring detector, Haar's
    second opinion: the last call's ``second_boxes`` best boxes from ``second_score`` (0: no
    second opinion), each at most ``second_side`` of the image's shorter side, answer where
    OpenCV's Haar face cascade, in the crop round the box at the crop's own scale, finds a
    grouped box of ``second_neighbors`` neighbours centred in it (:func:`_second_opinion`;
    that box is the answer). ``found`` at the best box (the
    highest score; for a grouping detector the merged box holding most raw detections), else
    ``absent``. No belief is computed (``probability`` NaN, method ``scales``);
    ``detector_pixels`` counts every call and crop (a face-free image pays every scale: 1/16 +
    1/9 + 1/4 + 1 of a full scan from 1/4, and the call for a box too large if any).
    """
    t0 = time.perf_counter()
    image_px = check_image(image, fovea)
    grid = fovea.grid
    rungs = ladder_scales(scales, start, finest)
    pixels, box, faint, larger = 0, None, None, False
    second = second_score > 0 and second_boxes > 0 and scales.strong_score > 0 \
        and bool(look_upscale)
    k = -1
    while k + 1 < len(rungs):
        k += 1
        scale = rungs[k]
        last = k == len(rungs) - 1
        # the last call keeps faint boxes (for the faint look), the others weak ones (for a face
        # too large for their scale); neither answers as such
        if last:
            weak_from = faint_score if look_upscale else 0.0
            if second:
                weak_from = min(weak_from, second_score)
        else:
            weak_from = scales.weak_score if math.isfinite(scales.max_side_px) else 0.0
        detector = coarse_detector(fovea.detector, weak_from)
        found = scan(image, detector, grid, scale)
        pixels += found.detector_pixels
        keep_from = -math.inf
        if last and detector is not fovea.detector:
            # the same call keeps faint boxes too: they answer only through the faint look
            keep_from = _fine_score(fovea.detector)
            faint = _faint_box(found, keep_from,
                               FAINT_SIDE * _min_side_px(scales, scale) / scale, faint_score)
        box = _ladder_answer(found, scales.strong_score, last, keep_from)
        score = _best_score(found) if last else math.nan
        seen_at = scale                         # the scale of the call that gave the box
        if box is not None and confirm and not last:
            # look again round the box at the next finer scale: a texture the coarse call took
            # for a face rarely survives
            x0, y0, x1, y1 = _crop_round(box, image_px)
            seen_at = confirm_scale(scales, float(np.max(box[2:])), scale, rungs[k + 1])
            look = scan(image[y0:y1, x0:x1], fovea.detector, (1, 1), seen_at)
            pixels += look.detector_pixels
            at_finest = seen_at == rungs[-1]
            box = _ladder_answer(look, scales.strong_score, at_finest)
            score = _best_score(look) if at_finest else math.nan
            if box is not None:
                box = np.asarray(box, dtype=float) + (x0, y0, 0, 0)
        if box is not None and look_upscale and score < scales.strong_score:
            # a weak box at the finest scale: look at it again at a side of LOOK_SIDE_PX
            best, spent = _enlarged_look(image, box, image_px, fovea.detector, look_upscale,
                                         seen_at)
            pixels += spent
            if not best >= look_score:
                box = None
        if box is not None:
            break
        at = None if last or larger else larger_face_scale(scales, found.boxes_px, scale)
        if at is not None:
            # a box too large for this scale (a close-up): the whole image next where it is the
            # detector's largest side, once
            rungs.insert(k + 1, at)
            larger = True
    if box is None and faint is not None:
        # a face too small for the finest scale: its faint small box, enlarged
        best, spent = _enlarged_look(image, faint, image_px, fovea.detector, look_upscale,
                                     rungs[-1])
        pixels += spent
        if best >= faint_look_score:
            box = faint
    if box is None and second and len(found.boxes_px):
        box, spent = _second_opinion(image, found, image_px, second_score, second_boxes,
                                     second_side, second_neighbors)
        pixels += spent
    common = {'fixations': 0, 'path': (), 'detector_pixels': pixels, 'image_px': image_px,
              'calibrated_px': calibrated_size(model), 'method': 'scales',
              'note': f'full frame at {", ".join(f"{s:.2g}" for s in rungs[:k + 1])}',
              'probability': math.nan}
    if box is None:
        return ImageSearch(cell=(0, 0), pixel=(math.nan, math.nan), stop='absent',
                           belief=np.zeros(grid.n_cells), decision='absent',
                           absent_probability=math.nan, seconds=time.perf_counter() - t0,
                           **common)
    x, y, w, h = (float(v) for v in box)
    centre = np.array([[x + w / 2.0, y + h / 2.0]])
    cell = int(cells_of_points(centre, image.shape[:2], grid)[0])
    belief = np.zeros(grid.n_cells)
    belief[cell] = 1.0
    return ImageSearch(cell=tuple(int(v) for v in grid.cell(cell)),
                       pixel=(float(centre[0, 0]), float(centre[0, 1])), stop='found',
                       belief=belief, decision='found', detections=((x + w / 2, y + h / 2),),
                       absent_probability=math.nan,
                       faces=(Face(box=clip_box((x, y, w, h), image_px),
                                   cell=tuple(int(v) for v in grid.cell(cell)),
                                   probability=math.nan),),
                       seconds=time.perf_counter() - t0, **common)
