# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Face search on held-out scenes: foveated search vs full-frame scans (``make faces``).

Writes ``docs/faces.md`` and its figure. For each task (the paper's 420x420 with 60-140 px faces,
and 840x840 with 24-140 px faces), on test scenes only (test faces, test backgrounds; nothing
here was fitted to them), in one run and on the same images:

- the full-frame scan at full resolution and downscaled by 3/4, 1/2 and 1/3 (the answer is the
  cell with most raw detections, NMPT's rule; OpenCV's grouped detections are reported too);
- the digital fovea with the shipped count model of that task and several policies and
  confidence thresholds: ELM, MAP, random and spiral with inhibition of return, and NMPT's
  fixed policy with NMPT's repeat rule.

Accuracy: the found cell within one cell (Chebyshev) of the cell holding the face centre, with a
95% Wilson interval; also exact and the mean grid error. Cost: detector pixels and wall seconds
from the decoded image to the answer (every detector call, resizing, belief update and policy
decision), and the speed-up = median full-resolution seconds / median seconds of the method,
measured in the same run. Usage: ``python bench/faces.py [--scenes 300] [--tasks paper,small]``.
"""
import argparse
from pathlib import Path
import platform
import sys
import time

import cv2
from ipomdp_gaze.observation_file import load_observation
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.vision.detector import HaarDetector
from ipomdp_gaze.vision.fullframe import scan
from ipomdp_gaze.vision.scenes import SceneSet
from ipomdp_gaze.vision.search import fovea_for_model, search_image
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TASKS = {'paper': ('faces-420', 420, (60, 140)), 'small': ('faces-840', 840, (24, 140))}
SCALES = (1.0, 0.75, 0.5, 1 / 3)
# (label, policy name, confidence, budget, NMPT's repeat rule instead of inhibition of return)
FOVEATED = (('ELM', 'elm', 0.9, 60, False), ('ELM', 'elm', 0.99, 60, False),
            ('ELM', 'elm', 0.999, 60, False), ('MAP', 'map', 0.999, 60, False),
            ('random', 'random', 0.999, 60, False), ('spiral', 'spiral', 0.999, 60, False),
            ('NMPT fixed policy', 'nmpt', 0.999, 60, True))
SIZE_BINS = ((0, 40), (40, 64), (64, 100), (100, 141))


def wilson(hits: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95% Wilson score interval of a proportion."""
    if n == 0:
        return float('nan'), float('nan')
    p = hits / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def errors(cells, truth) -> np.ndarray:
    """Chebyshev distance in cells of each answer (None: no answer, counted as wrong)."""
    out = []
    for found, true in zip(cells, truth):
        out.append(np.inf if found is None else max(abs(found[0] - true[0]),
                                                    abs(found[1] - true[1])))
    return np.asarray(out, dtype=float)


def run_task(name: str, n: int, seed: int, log) -> dict:
    model_name, size, faces = TASKS[name]
    model = load_observation(model_name)
    grid = model.grid
    scenes = SceneSet('test', size_px=size, face_px=faces, grid=grid.shape, seed=seed)
    detector = HaarDetector()
    fovea = fovea_for_model(model)
    truth, sizes = [], []
    rows = {}
    for i in range(n):
        scene = scenes[i]
        truth.append(scene.cell)
        sizes.append(scene.face_px)
        for scale in SCALES:
            result = scan(scene.image, detector, grid, scale=scale)
            for label, cell in ((f'full frame x{scale:.2g}', result.cell),
                                (f'full frame x{scale:.2g}, grouped', result.grouped_cell)):
                row = rows.setdefault(label, {'cells': [], 'seconds': [], 'pixels': [],
                                              'fixations': []})
                row['cells'].append(None if cell is None else tuple(grid.cell(cell)))
                row['seconds'].append(result.seconds)
                row['pixels'].append(result.detector_pixels)
                row['fixations'].append(0)
        for label, policy_name, confidence, budget, nmpt_rule in FOVEATED:
            policy = build_policy(policy_name, grid, model)
            result = search_image(scene.image, fovea, model, policy, confidence=confidence,
                                  max_fixations=budget, stop_on_repeat=nmpt_rule,
                                  inhibit_return=not nmpt_rule,
                                  rng=np.random.default_rng([seed, i]))
            key = f'fovea, {label}, confidence {confidence}'
            row = rows.setdefault(key, {'cells': [], 'seconds': [], 'pixels': [],
                                        'fixations': []})
            row['cells'].append(result.cell)
            row['seconds'].append(result.seconds)
            row['pixels'].append(result.detector_pixels)
            row['fixations'].append(result.fixations)
        if (i + 1) % 50 == 0:
            log(f'{name}: {i + 1}/{n} scenes')
    full = float(np.median(rows['full frame x1']['seconds']))
    out = {'model': model_name, 'size': size, 'faces': faces, 'n': n, 'seed': seed,
           'full_median_s': full, 'rows': [], 'sizes': np.asarray(sizes)}
    for label, row in rows.items():
        err = errors(row['cells'], truth)
        hits = int(np.sum(err <= 1))
        finite = err[np.isfinite(err)]
        out['rows'].append({
            'label': label, 'right': hits / n, 'ci': wilson(hits, n),
            'exact': float(np.mean(err == 0)),
            'grid_error': float(finite.mean()) if finite.size else float('nan'),
            'answered': finite.size / n, 'fixations': float(np.mean(row['fixations'])),
            'pixels': float(np.mean(row['pixels'])),
            'median_s': float(np.median(row['seconds'])),
            'mean_s': float(np.mean(row['seconds'])),
            'speedup': full / float(np.median(row['seconds'])),
            'by_size': [float(np.mean(err[(np.asarray(sizes) >= lo) & (np.asarray(sizes) < hi)]
                                      <= 1)) if np.any((np.asarray(sizes) >= lo)
                                                       & (np.asarray(sizes) < hi)) else None
                        for lo, hi in SIZE_BINS]})
    return out


def table(task: dict) -> list[str]:
    lines = [f"### {task['size']}x{task['size']}, faces {task['faces'][0]}-{task['faces'][1]} "
             f"px, {task['n']} test scenes (seed {task['seed']}), model `{task['model']}`", '',
             f"Full-resolution scan: median {1000 * task['full_median_s']:.1f} ms per image.", '',
             '| method | right (within 1 cell) [95% CI] | exact | mean grid error | answered | '
             'fixations | detector px | median ms | mean ms | speed-up vs full res. | '
             'right by face size ' + ', '.join(f'{lo}-{hi - 1}' for lo, hi in SIZE_BINS) + ' |',
             '|---|---|---|---|---|---|---|---|---|---|---|']
    for r in task['rows']:
        by = ' / '.join('-' if v is None else f'{v:.2f}' for v in r['by_size'])
        lines.append(f"| {r['label']} | {r['right']:.3f} [{r['ci'][0]:.3f}, {r['ci'][1]:.3f}] | "
                     f"{r['exact']:.3f} | {r['grid_error']:.2f} | {r['answered']:.2f} | "
                     f"{r['fixations']:.1f} | {r['pixels']:,.0f} | {1000 * r['median_s']:.1f} | "
                     f"{1000 * r['mean_s']:.1f} | {r['speedup']:.2f}x | {by} |")
    return lines


def verdict(task: dict) -> list[str]:
    """Plain statements: the paper's claim and the best full-frame baseline vs the fovea."""
    rows = {r['label']: r for r in task['rows']}
    full = rows['full frame x1']
    scans = [rows[f'full frame x{s:.2g}'] for s in SCALES]
    best = min((r for r in scans if r['right'] >= full['right'] - 0.02),
               key=lambda r: r['median_s'])
    fovea = [r for r in task['rows'] if r['label'].startswith('fovea')]
    ok = [r for r in fovea if r['right'] >= full['right'] - 0.02]
    lines = [f"- Best full-frame baseline (cheapest within 2 points of full resolution): "
             f"**{best['label']}**, right {best['right']:.3f} at {best['speedup']:.2f}x."]
    if ok:
        top = max(ok, key=lambda r: r['speedup'])
        lines.append(f"- Paper's claim (>= 2x faster than full resolution, accuracy within 2 "
                     f"points): {'**met**' if top['speedup'] >= 2 else '**not met**'} by "
                     f"{top['label']} (right {top['right']:.3f} vs {full['right']:.3f}, "
                     f"{top['speedup']:.2f}x).")
        ratio = best['median_s'] / top['median_s']
        winner = 'the fovea' if ratio > 1 else 'the full-frame scan'
        lines.append(f"- Against the best full-frame baseline at equal accuracy: {winner} wins "
                     f"({top['label']} takes {ratio:.2f}x less time than {best['label']})."
                     if ratio > 1 else
                     f"- Against the best full-frame baseline: **{best['label']} wins**; the "
                     f"fastest foveated search within 2 points of full resolution takes "
                     f"{1 / ratio:.2f}x its time.")
    else:
        top = max(fovea, key=lambda r: r['right'])
        lines.append(f"- No foveated configuration is within 2 points of full resolution "
                     f"(best: {top['label']}, right {top['right']:.3f} vs {full['right']:.3f}, "
                     f"{top['speedup']:.2f}x): the paper's claim is **not met** here, and every "
                     f"full-frame scan within 2 points beats the fovea.")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description='Face search on held-out scenes.')
    parser.add_argument('--scenes', type=int, default=300)
    parser.add_argument('--tasks', default='paper,small')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--out', type=Path, default=ROOT / 'docs' / 'faces.md')
    args = parser.parse_args(argv)
    cv2.setNumThreads(1)

    def log(text):
        print(text, file=sys.stderr, flush=True)

    start = time.perf_counter()
    results = [run_task(name, args.scenes, args.seed, log) for name in args.tasks.split(',')]
    wall = time.perf_counter() - start
    text = ['# Face search: the digital fovea vs full-frame scans', '',
            __doc__.strip().split('\n\n', 1)[1].replace('Usage:', 'Regenerate with `make '
                                                        'faces`, or:'), '',
            'Fovea: the shipped models were calibrated (`ipomdp-gaze calibrate --scenes 200 '
            '--seed 0 [--task small]`, training split) with NMPT\'s reference windows '
            '`[21, 15, 9, 3]` cells, each at the pixel size of 3 cells, area resampling, '
            'K = 10; their learned FPOCs: `figures/fpoc_faces-420.png`, '
            '`figures/fpoc_faces-840.png`. The operating point of `ipomdp-gaze find` (ELM, '
            'inhibition of return, confidence 0.999, 60 fixations) was chosen on training '
            'scenes (seed 1) before this run. No learned kernel on the count models is shipped '
            'yet.', '']
    for task in results:
        text += table(task) + [''] + verdict(task) + ['']
    text += [f'*Measured with OpenCV {cv2.__version__} (one thread) on `{platform.node()}` '
             f'({platform.machine()}), Python {platform.python_version()}; the run took '
             f'{wall:.0f} s. Times move with the load of this shared 2-core machine; the '
             f'speed-ups are measured in the same run on the same images.*']
    args.out.write_text('\n'.join(text) + '\n')
    log(f'wrote {args.out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
