# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``find --all`` (the many-target belief) on composed group scenes against the detector alone.

Scenes (``--faces``): ``photos``, :func:`ipomdp_gaze.vision.photos.group_photo` with
``split='train'`` (the training photo faces, each ``--copies`` times, every other one mirrored)
on the training group backgrounds (:data:`~ipomdp_gaze.vision.photos.TRAIN_GROUP_BACKGROUNDS`);
or ``lfw``, :func:`lfw_group`: ``--copies`` distinct ``lfw_subset`` thumbnails of the split
(faces 0-59 for training) pasted as the scene set does (bicubic, feathered) on crops of the
split's backgrounds (:data:`~ipomdp_gaze.vision.scenes.TRAIN_BACKGROUNDS`), grey, at
``--sizes``. ``--split test`` composes test faces on test backgrounds, for a report only:
never choose on it.

Per scene, in the same run and on the same decoded image:

- ``find --all``: ``find``'s own path (:func:`ipomdp_gaze.commands.find.search_one` with the
  shipped models of ``--detector``, the model nearest the image's size, ``targets`` many);
- with ``--old-loop``, the single-target loop (``--targets one``: find a face, rule the cells
  within 2 of it out, search again; its answers are points, scored as boxes of size 0);
- the detector alone on the whole image at each of ``--scales`` (1, 1/2, 1/3, 1/4 by default,
  :func:`ipomdp_gaze.vision.fullframe.scan`), every answer box (YuNet's own boxes after its
  non-maximum suppression, OpenCV's grouping for Haar) a face.

A reported box is a found face when its centre lies in a true face box that no earlier box
matched (boxes taken most probable first), a **duplicate** when it lies in an already matched
one, else a **false face**. Seconds are wall time from the decoded array (as ``find`` reports
them); detector pixels are the pixels given to the detector.

Usage: ``python bench/faces/many_faces.py [--split train|test] [--scenes N] [--copies C]
[--sizes 640x480,1280x886] [--detector yunet|haar] [--absent-prior P] [--confidence C]
[--old-loop] [--faces photos|lfw] [--write docs/faces.md --section KEY]``; prints one
markdown row per method and size, totals over the scenes (``make faces-groups`` writes the
training and test tables into docs/faces.md). ``find``'s one-time set-up (the belief's tables,
the fixation costs of a size) is built on a first scene before the timed ones, as ``find``
leaves it out of its seconds.
"""
import argparse
from dataclasses import replace
from pathlib import Path
import time

import cv2
from find_photos import find_tasks
from ipomdp_gaze.commands.find import MAX_SIDE_PX, search_one, shrink
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.photos import (_paste_rgb, face_crops, GROUP_BACKGROUNDS, group_photo,
                                       load_photo, TRAIN_GROUP_BACKGROUNDS)
from ipomdp_gaze.vision.scenes import (_paste as paste, DEFAULT_FEATHER, load_background,
                                       load_faces, SPLITS)
from ipomdp_gaze.vision.search import CROWD_RATIO, FIND_SETTINGS
import numpy as np

SCALES = (1.0, 1 / 2, 1 / 3, 1 / 4)
SPLITS_CODE = {'train': 0, 'test': 1}
# --degrade: faces grey at this fraction of their contrast, blurred as a face of this side
DEGRADE_CONTRAST = 0.6
DEGRADE_FACE_PX = 75.0


def score(boxes, truth) -> tuple[int, int, int]:
    """Return (found, false, duplicates) of reported boxes ``(F, 4)`` against true boxes."""
    matched = np.zeros(len(truth), dtype=bool)
    found = false = duplicates = 0
    for x, y, w, h in np.asarray(boxes, dtype=float).reshape(-1, 4):
        cx, cy = x + w / 2, y + h / 2
        inside = ((truth[:, 0] <= cx) & (cx <= truth[:, 0] + truth[:, 2])
                  & (truth[:, 1] <= cy) & (cy <= truth[:, 1] + truth[:, 3]))
        if not inside.any():
            false += 1
        elif (inside & ~matched).any():
            matched[np.flatnonzero(inside & ~matched)[0]] = True
            found += 1
        else:
            duplicates += 1
    return found, false, duplicates


def lfw_group(size, seed: int, split: str, count: int):
    """
    Paste ``count`` distinct thumbnails of the split on a crop of one of its backgrounds.

    Sides uniform in 48-90 px scaled with the width (as the photo groups), places that do not
    overlap; returns the grey image as RGB ``(H, W, 3)`` and the pasted squares ``(F, 4)``.
    """
    width, height = size
    rng = np.random.default_rng([0x3A17, width, height, seed, SPLITS_CODE[split]])
    faces_range, backgrounds = SPLITS[split]
    name = backgrounds[seed % len(backgrounds)]
    back = load_background(name, 'gray', min_side=max(width, height))
    y = int(rng.integers(0, back.shape[0] - height + 1))
    x = int(rng.integers(0, back.shape[1] - width + 1))
    image = np.array(back[y:y + height, x:x + width])
    low, high = 48 * width / 640, 90 * width / 640
    boxes = []
    for face in rng.choice(np.array(faces_range), size=count, replace=False):
        for _ in range(200):
            side = int(rng.uniform(low, high))
            x0 = int(rng.integers(0, width - side))
            y0 = int(rng.integers(0, height - side))
            if all(x0 + side <= a or a + w <= x0 or y0 + side <= b or b + h <= y0
                   for a, b, w, h in boxes):
                break
        else:
            raise ValueError(f'{count} faces do not fit in {width}x{height}')
        paste(image, load_faces()[face], y0, x0, side, DEFAULT_FEATHER)
        boxes.append((x0, y0, side, side))
    return name, np.repeat(image[:, :, None], 3, axis=2), np.array(boxes, dtype=float)


def degraded(crop: np.ndarray, box, blur_px: float) -> np.ndarray:
    """
    Return a face crop grey, at :data:`DEGRADE_CONTRAST` of its contrast and blurred.

    ``blur_px``: the Gaussian's sigma in the pixels of a face of :data:`DEGRADE_FACE_PX` (the
    crop is blurred at its own size, the sigma scaled by its face ``box``'s larger side): a
    hard face such as a grey crowd photograph's, out of focus and in flat light.
    """
    grey = cv2.cvtColor(np.ascontiguousarray(crop), cv2.COLOR_RGB2GRAY).astype(float)
    grey = cv2.GaussianBlur(grey, (0, 0), blur_px * max(box[2], box[3]) / DEGRADE_FACE_PX)
    grey = np.clip(128.0 + DEGRADE_CONTRAST * (grey - 128.0), 0, 255).astype(np.uint8)
    return np.repeat(grey[:, :, None], 3, axis=2)


def canvas_group(size, seed: int, split: str, copies: int, face_px=(15, 40),
                 region=(1000, 750), degrade: float = 0.0):
    """
    Paste a small group of the split's photo faces into a large face-free canvas.

    The canvas is one of the split's group backgrounds (training:
    :data:`~ipomdp_gaze.vision.photos.TRAIN_GROUP_BACKGROUNDS`) resized to cover ``size`` and
    centre-cropped; every labelled face of the split is pasted ``copies`` times (every other one
    mirrored, as :func:`~ipomdp_gaze.vision.photos.group_photo` does) with its larger side
    uniform in ``face_px``, at places that do not overlap inside one ``region`` of the canvas
    placed at random. ``degrade``: each face :func:`degraded` with that blur (0: as it is).
    Returns the background's name, the RGB image ``(H, W, 3)`` and the face boxes ``(F, 4)``.
    """
    width, height = size
    rng = np.random.default_rng([0xCA57, width, height, seed, SPLITS_CODE[split]])
    names = TRAIN_GROUP_BACKGROUNDS if split == 'train' else GROUP_BACKGROUNDS
    name = names[seed % len(names)]
    back = load_photo(name)
    k = max(width / back.shape[1], height / back.shape[0])
    back = cv2.resize(back, (int(np.ceil(back.shape[1] * k)), int(np.ceil(back.shape[0] * k))),
                      interpolation=cv2.INTER_CUBIC)
    top, left = (back.shape[0] - height) // 2, (back.shape[1] - width) // 2
    image = np.ascontiguousarray(back[top:top + height, left:left + width])
    del back
    region_w, region_h = min(region[0], width), min(region[1], height)
    rx = int(rng.integers(0, width - region_w + 1))
    ry = int(rng.integers(0, height - region_h + 1))
    crops = face_crops(split)
    if degrade:
        crops = [(degraded(crop, box, degrade), box) for crop, box in crops]
    mirrored = [(crop[:, ::-1], np.array([crop.shape[1] - x - w, y, w, h]))
                for crop, (x, y, w, h) in crops]
    taken, boxes = [], []
    for crop, box in [pair for c in range(copies) for pair in (mirrored if c % 2 else crops)]:
        for _ in range(200):
            scale = rng.uniform(*face_px) / max(box[2], box[3])
            out_w, out_h = int(round(crop.shape[1] * scale)), int(round(crop.shape[0] * scale))
            x0 = rx + int(rng.integers(0, region_w - out_w))
            y0 = ry + int(rng.integers(0, region_h - out_h))
            if all(x0 + out_w <= a or a + aw <= x0 or y0 + out_h <= b or b + bh <= y0
                   for a, b, aw, bh in taken):
                break
        else:
            raise ValueError(f'the faces do not fit in a {region_w}x{region_h} region')
        taken.append((x0, y0, out_w, out_h))
        _paste_rgb(image, crop, x0, y0, out_w, out_h)
        sx, sy = out_w / crop.shape[1], out_h / crop.shape[0]
        boxes.append([x0 + box[0] * sx, y0 + box[1] * sy, box[2] * sx, box[3] * sy])
    return name, image, np.round(np.array(boxes), 1)


def scenes(split: str, count: int, size, copies: int, faces: str = 'photos',
           face_px=None, crowd: bool = False, degrade: float = 0.0):
    """
    Yield the composed group pictures of a split, or its canvases: ``(name, image, boxes)``.

    ``crowd``: the canvases' faces anywhere in the picture (a crowd), not in one region.
    """
    if face_px is not None:
        for i in range(count):
            name, image, boxes = canvas_group(size, i, split, copies, face_px,
                                              region=size if crowd else (1000, 750),
                                              degrade=degrade)
            yield f'{"crowd" if crowd else "canvas"}-{name}-{i}', image, boxes
        return
    if faces == 'lfw':
        for i in range(count):
            name, image, boxes = lfw_group(size, i, split, copies)
            yield f'lfw-{name}-{i}', image, boxes
        return
    backgrounds = TRAIN_GROUP_BACKGROUNDS if split == 'train' else GROUP_BACKGROUNDS
    for i in range(count):
        background = backgrounds[i % len(backgrounds)]
        image, boxes = group_photo(size, seed=i, background=background, split=split,
                                   copies=copies)
        yield f'{background}-{i}', image, boxes


def run(args) -> list[dict]:
    """Measure every method on every scene; return one dict per (size, method)."""
    tasks = find_tasks(detector=args.detector)
    settings = replace(FIND_SETTINGS, targets='many', absent_prior=args.absent_prior,
                       confidence=args.confidence)
    finds = [('find --all', args.max_side, None, CROWD_RATIO)]
    if args.min_face:
        finds.append((f'find --all --max-side 0 --min-face {args.min_face:g}', 0,
                      args.min_face, CROWD_RATIO))
    finds += [(f'find --all, crowd ratio {ratio:g}', args.max_side, None, ratio)
              for ratio in args.crowd_ratios]
    rows = []
    for size in args.sizes:
        totals = {}
        # find's one-time set-up (the belief's information table, the fixation costs of the
        # size) is not in its seconds (ipomdp_gaze.commands.find): built on a first scene here
        _, image, _ = next(iter(scenes(args.split, 1, size, args.copies, args.faces,
                                       args.face_px, args.crowd is not None, args.degrade)))
        for _, max_side, min_face, _ in finds:
            small, _ = shrink(image, max_side)
            search_one(small, tasks.task((small.shape[1], small.shape[0])), settings,
                       np.random.default_rng(0), True)
        del image, small
        for name, image, truth in scenes(args.split, args.scenes, size, args.copies,
                                         args.faces, args.face_px, args.crowd is not None,
                                         args.degrade):
            for method, max_side, min_face, ratio in finds:
                # as find does: an image longer than --max-side is resized first (INTER_AREA;
                # in its seconds), the faces' boxes given back in the image's pixels
                t0 = time.perf_counter()
                small, (sx, sy) = shrink(image, max_side)
                task = tasks.task((small.shape[1], small.shape[0]))
                [result] = search_one(small, task, settings, np.random.default_rng(0), True,
                                      None if min_face is None else min_face / max(sx, sy),
                                      empty_by_evidence=args.empty_by_evidence,
                                      crowd_ratio=ratio, given_px=image.shape[0] * image.shape[1])
                seconds = time.perf_counter() - t0
                boxes = (np.array([f.box for f in result.faces]).reshape(-1, 4)
                         * (sx, sy, sx, sy))
                _add(totals, method, score(boxes, truth), len(truth), seconds,
                     result.detector_pixels)
                if args.verbose:
                    print(name, method, len(truth), score(boxes, truth), result.fixations,
                          result.stop, f'{seconds:.3f}', flush=True)
            task = tasks.task((image.shape[1], image.shape[0]))
            if args.old_loop:
                t0 = time.perf_counter()
                results = search_one(image, task, replace(settings, targets='one'),
                                     np.random.default_rng(0), True)
                seconds = time.perf_counter() - t0
                points = np.array([[*r.pixel, 0.0, 0.0] for r in results
                                   if r.decision == 'found']).reshape(-1, 4)
                _add(totals, 'find --all --targets one (old loop)', score(points, truth),
                     len(truth), seconds,
                     sum(r.detector_pixels for r in results) if results[0].method == 'fovea'
                     else results[0].detector_pixels)
            for scale in SCALES:
                t0 = time.perf_counter()
                alone = scan(image, task.fovea.detector, task.fovea.grid, scale)
                seconds = time.perf_counter() - t0
                _add(totals, f'detector at {scale:.3g}', score(alone.grouped_px, truth),
                     len(truth), seconds, alone.detector_pixels)
        for method, t in totals.items():
            rows.append({'size': f'{size[0]}x{size[1]}', 'method': method, **t})
    return rows


def _add(totals, method, counts, n_true, seconds, pixels):
    t = totals.setdefault(method, {'scenes': 0, 'faces': 0, 'found': 0, 'false': 0,
                                   'false_most': 0, 'duplicates': 0, 'seconds': 0.0,
                                   'pixels': 0})
    t['scenes'] += 1
    t['faces'] += n_true
    t['found'] += counts[0]
    t['false'] += counts[1]
    t['false_most'] = max(t['false_most'], counts[1])
    t['duplicates'] += counts[2]
    t['seconds'] += seconds
    t['pixels'] += int(pixels)


def _range(text):
    low, high = (float(v) for v in text.split('-'))
    return (low, high)


def _size(text):
    width, height = (int(v) for v in text.split('x'))
    return (width, height)


def main(argv=None):
    """Parse the flags, measure, print markdown rows."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    p.add_argument('--split', choices=('train', 'test'), default='train')
    p.add_argument('--scenes', type=int, default=8)
    p.add_argument('--copies', type=int, default=6)
    p.add_argument('--sizes', type=lambda t: [_size(s) for s in t.split(',')],
                   default=[(640, 480), (1280, 886)])
    p.add_argument('--detector', choices=('yunet', 'haar'), default='yunet')
    p.add_argument('--absent-prior', type=float, default=FIND_SETTINGS.absent_prior)
    p.add_argument('--confidence', type=float, default=FIND_SETTINGS.confidence)
    p.add_argument('--verbose', action='store_true')
    p.add_argument('--old-loop', action='store_true')
    p.add_argument('--faces', choices=('photos', 'lfw'), default='photos')
    p.add_argument('--canvas', type=_range, default=None, metavar='LO-HI',
                   help='large canvases instead of group pictures: each of --sizes (e.g. '
                        '4000x3000) a background of the split with its photo faces, --copies '
                        'times, of LO-HI px in one 1000x750 region (canvas_group)')
    p.add_argument('--crowd', type=_range, default=None, metavar='LO-HI',
                   help='crowds instead of group pictures: each of --sizes a background of '
                        'the split with its photo faces, --copies times, of LO-HI px anywhere '
                        'in the picture (canvas_group over the whole picture)')
    p.add_argument('--degrade', type=float, default=0.0, metavar='SIGMA',
                   help='canvases and crowds: every face grey, at 0.6 of its contrast and '
                        'blurred by SIGMA px of a 75 px face (a hard crowd; 0: as it is)')
    p.add_argument('--crowd-ratios', type=lambda t: [float(v) for v in t.split(',')],
                   default=[], metavar='R,R',
                   help='also run find --all with these crowd ratios (0: no crowd step; '
                        'the shipped: ipomdp_gaze.vision.search.CROWD_RATIO)')
    p.add_argument('--max-side', type=int, default=MAX_SIDE_PX,
                   help="find --all's --max-side (default find's; the detector alone always "
                        'reads the whole image)')
    p.add_argument('--min-face', type=float, default=None, metavar='PX',
                   help='also run find --all --max-side 0 --min-face PX')
    p.add_argument('--empty-by-evidence', action='store_true',
                   help="decide a cell empty by its evidence alone (OccupancySession's "
                        'empty_by_evidence) instead of its posterior')
    p.add_argument('--write', type=Path, default=None, metavar='FILE.md',
                   help='also write the table into FILE.md between <!-- SECTION --> and '
                        '<!-- /SECTION --> (appended when they are not there)')
    p.add_argument('--section', default='many-faces')
    args = p.parse_args(argv)
    if args.canvas and args.crowd:
        p.error('--canvas and --crowd are two kinds of picture: give one')
    if args.degrade and not (args.canvas or args.crowd):
        p.error('--degrade changes the faces of --canvas or --crowd pictures: give one')
    args.face_px = args.canvas or args.crowd
    rows = run(args)
    kind = (f'{"crowds" if args.crowd else "canvases"} with {args.faces} faces of '
            f'{args.face_px[0]:g}-{args.face_px[1]:g} px' if args.face_px
            else f'{args.faces} faces')
    if args.degrade:
        kind += f' (grey, contrast {DEGRADE_CONTRAST:g}, blur {args.degrade:g} px)'
    lines = [f'split {args.split}, {kind}, {args.scenes} scenes per size, '
             f'{args.copies} copies (lfw: faces) per scene, detector {args.detector}, absent '
             f'prior {args.absent_prior}, confidence {args.confidence}, empty by evidence '
             f'{args.empty_by_evidence}, find --max-side {args.max_side}:', '',
             '| size | method | faces | found | false | most false in a picture | duplicates | '
             's / scene | detector px / scene |', '|---|---|---|---|---|---|---|---|---|']
    for r in rows:
        n = r['scenes']
        lines.append(f"| {r['size']} | {r['method']} | {r['faces']} | {r['found']} | "
                     f"{r['false']} | {r['false_most']} | {r['duplicates']} | "
                     f"{r['seconds'] / n:.4f} | "
                     f"{r['pixels'] / n:,.0f} |")
    print('\n'.join(lines))
    if args.write:
        write_section(args.write, args.section, lines)


def write_section(path, key: str, lines: list) -> None:
    """Replace the text between ``<!-- key -->`` and ``<!-- /key -->`` in ``path`` (append)."""
    begin, end = f'<!-- {key} -->', f'<!-- /{key} -->'
    text = path.read_text() if path.exists() else ''
    block = '\n'.join([begin, *lines, end])
    if begin in text and end in text:
        text = text[:text.index(begin)] + block + text[text.index(end) + len(end):]
    else:
        text = text.rstrip('\n') + '\n\n' + block + '\n'
    path.write_text(text)


if __name__ == '__main__':
    main()
