# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The face demo over DDS: scene camera, foveal detector and controller, many held-out scenes.

For each mode (``camera``: a camera on the pan/tilt head; ``fovea``: a fixed camera and the
digital fovea) and each seed, runs exactly what ``ipomdp-gaze demo --scene faces [--fovea]
--seed S`` runs (three processes with the shipped ``config/faces_<mode>_*.yaml``, started,
watched and stopped by :func:`ipomdp_gaze.harness.demo.run_demo`, 60 fixations at most) and
records whether the answer (the ``found`` cell, or the most likely cell after 60 fixations
without one) is within one cell of the face centre's cell, the fixations and the seconds from
starting the last node (the scene camera) to the answer. Test scenes only (test faces and
backgrounds); nothing was fitted to them.
"""
import math

from ipomdp_gaze.harness.demo import faces_setup, run_demo
from ipomdp_gaze.harness.processes import domain_id_for
from ipomdp_gaze.simulation.evaluation import wilson_interval
import numpy as np

TITLE = 'Face search over DDS: scene camera, foveal detector and controller (three processes)'
ORDER = 61
MODES = (('camera', False, 'a camera on the pan/tilt head (11x11 grid of 5 deg, '
                           '`faces-pan-tilt-profile`: the frontal and the profile cascade, '
                           'coverage per second of head time with the tour of the tiles, '
                           'confidence 0.99 within one cell, inhibition of return, '
                           'absent prior 0.8, false-alarm scales and hotspots, a grouped '
                           'detection the belief does not veto ends the search, decided at 20 '
                           'fixations)'),
         ('fovea', True, 'a fixed camera and the digital fovea (21x21 grid over 420x420 '
                         'scenes, `faces-420` with its one-time scan and kernel '
                         '`faces-420-infomax`, confidence 0.99, inhibition of return, as '
                         '`find` searches)'))


def run_mode(fovea: bool, seeds, log, empty: bool = False) -> list:
    """
    One demo per seed; a dict of its results each (``right`` False when it failed).

    ``empty``: the scene without its face (``demo --empty``), right when the answer is absent.
    """
    out = []
    for seed in seeds:
        stats = {}
        status = run_demo(faces_setup(fovea, seed=seed, empty=empty), 60.0, domain_id_for(),
                          out=lambda line: None, stats=stats)
        stats.update(seed=seed, status=status)
        stats.setdefault('right', False)
        log(f"  seed {seed}: status {status}, {stats.get('stop', '-')}, "
            f"{'right' if stats['right'] else 'wrong'}, {stats.get('fixations', '-')} "
            f"fixations, {stats.get('search_s', math.nan):.1f} s")
        out.append(stats)
    return out


def bench(ctx) -> str:
    """Run the demo on many seeds in both modes and report accuracy, fixations and seconds."""
    seeds = range(3 if ctx.quick else 20)
    lines = [f'Seeds 0-{seeds[-1]} (`ipomdp-gaze demo --scene faces [--fovea] --seed S`), one '
             'held-out test scene each; right = the found cell within one cell (Chebyshev) of '
             "the face centre's cell; the answer is the `found` cell or, when no cell reached "
             "the controller's confidence after 60 fixations, the most likely cell then (the "
             'demo gives up); seconds from starting the scene camera to the answer.', '',
             '| mode | searches | right [95% CI] | found / absent / gave up / failed | '
             'right when found | fixations mean / median / max | seconds median / p90 |',
             '|---|---|---|---|---|---|---|']
    wrong = []
    for mode, fovea, what in MODES:
        ctx.log(f'{mode} mode: {what}')
        results = run_mode(fovea, seeds, ctx.log)
        done = [r for r in results if r['status'] == 0 and 'fixations' in r]
        hits = sum(bool(r['right']) for r in results)
        low, high = wilson_interval(hits, len(results))
        fix = np.asarray([r['fixations'] for r in done], dtype=float)
        secs = np.asarray([r['search_s'] for r in done], dtype=float)
        found = [r for r in done if r['stop'] == 'found']
        stops = f"{len(found)} / {sum(r['stop'] == 'absent' for r in done)} / " \
            f"{sum(r['stop'] == 'budget' for r in done)} / {len(results) - len(done)}"
        right_found = sum(bool(r['right']) for r in found) / max(1, len(found))
        lines.append(
            f'| {mode}: {what} | {len(results)} | {hits / len(results):.2f} [{low:.2f}, '
            f'{high:.2f}] | {stops} | {right_found:.2f} | {fix.mean():.1f} / '
            f'{np.median(fix):.0f} / {fix.max():.0f} | {np.median(secs):.1f} / '
            f'{np.percentile(secs, 90):.1f} |')
        wrong += [f"{mode} seed {r['seed']} ({r.get('stop', 'failed')}): answered "
                  f"({r.get('row', '-')}, {r.get('col', '-')}), face in {r.get('truth', '-')}"
                  for r in results if not r['right']]
    lines += ['', 'Wrong or failed: ' + ('; '.join(wrong) if wrong else 'none') + '.']
    return '\n'.join(lines) + '\n'
