# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The walk demo over DDS on many held-out walks: how often the ROS loop keeps the face in view.

For each seed runs exactly what ``ipomdp-gaze demo --scene faces --motion walk --seed S
--speed-deg-s V --duration-s D`` runs (:func:`ipomdp_gaze.harness.walk_demo.run_walk_demo`:
scene camera, detector and the tracking controller as three processes) and prints a line per
seed with its score over the frames where the face is in reach, then the summary::

    kept in view on K of N seeds (in view on >= 50% of the frames with the face in reach)

**The threshold** (set before any run): a seed counts as kept in view when the face is in the
camera's view on at least half of its frames in reach, i.e. more often than not while it could
be. A head that ignored the face and visited the 121 poses alike would have it in view on about
5 x 4 / 121 = 17% of frames (the 25 x 18.9 degree view covers about 5 columns and 4 rows of the
5-degree grid), so 50% is far above chance and below what a tracker that keeps up reaches. A run
that fails (a node did not start, the walk did not run its length) counts as not kept.

Seed S is the test split's walk scene S, the scene the offline evaluation (``ipomdp-gaze
evaluate --scenes pan-tilt --motion walk``) calls index S: the report's held-out walks.
``--split train`` runs the training walks instead (the scene camera's ``scene.split``), for
choosing settings over ROS on walks no report uses. Each demo takes about ``D`` seconds plus
5-10 s to start and stop the nodes::

    .venv/bin/python bench/ros/walk_demo.py [--seeds 50] [--speed-deg-s 5] [--duration-s 30]
        [--split test]
"""
from __future__ import annotations

import argparse
import math
import sys

from ipomdp_gaze.harness.processes import domain_id_for
from ipomdp_gaze.harness.walk_demo import run_walk_demo, walk_setup
from ipomdp_gaze.simulation.evaluation import wilson_interval
from ipomdp_gaze.vision.walks import check_speed, DURATION_S
import numpy as np

# In view on at least this fraction of the frames in reach: the face kept in view (docstring).
THRESHOLD = 0.5


def run_seed(seed: int, speed: float, duration: float, timeout: float,
             split: str = 'test') -> dict:
    """Run the walk demo of one seed; return its status and score."""
    setup, camera = walk_setup(seed, speed, duration, split=split)
    stats = {}
    status = run_walk_demo(setup, camera, duration, timeout, domain_id_for(),
                           out=lambda line: None, stats=stats)
    score = stats.get('score')
    kept = status == 0 and score is not None and score.in_reach > 0 \
        and score.in_view >= THRESHOLD
    return {'seed': seed, 'status': status, 'score': score, 'kept': kept}


def seed_line(r: dict) -> str:
    """Say how one seed went."""
    s = r['score']
    if s is None or not s.in_reach:
        return f"seed {r['seed']}: status {r['status']}, no frame with the face in reach: not kept"
    return (f"seed {r['seed']}: status {r['status']}, {s.frames} frames ({s.in_reach} in reach), "
            f'in view {100 * s.in_view:.1f}%, centre cell {100 * s.in_centre:.1f}%, lost '
            f"{s.lost}, reacquired {s.reacquired}: {'kept' if r['kept'] else 'not kept'}")


def summary_lines(results: list) -> list[str]:
    """Return the means over the scored seeds and the last line (module docstring)."""
    scored = [r['score'] for r in results if r['score'] is not None and r['score'].in_reach]
    kept = sum(r['kept'] for r in results)
    low, high = wilson_interval(kept, len(results))

    def mean(values):
        return float(np.mean(values)) if values else math.nan

    return [f'{len(results) - len(scored)} of {len(results)} runs not scored; over the '
            f'{len(scored)} scored: in view {100 * mean([s.in_view for s in scored]):.1f}%, '
            f'centre cell {100 * mean([s.in_centre for s in scored]):.1f}% of the frames in '
            f'reach (mean per seed), lost {mean([s.lost for s in scored]):.2f} and reacquired '
            f'{mean([s.reacquired for s in scored]):.2f} times per walk; kept '
            f'{kept / len(results):.2f} [95% {low:.2f}, {high:.2f}]',
            f'kept in view on {kept} of {len(results)} seeds (in view on >= '
            f'{100 * THRESHOLD:.0f}% of the frames with the face in reach)']


def main(argv=None) -> int:
    """Run the seeds and print a line each and the summary."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    p.add_argument('--seeds', type=int, default=50, help='seeds 0..N-1 (default 50)')
    p.add_argument('--first-seed', type=int, default=0, help='start at this seed (default 0)')
    p.add_argument('--speed-deg-s', type=float, default=5.0,
                   help='walking speed in deg/s, 0-20 (default 5)')
    p.add_argument('--duration-s', type=float, default=DURATION_S,
                   help=f'seconds per walk (default {DURATION_S:g})')
    p.add_argument('--timeout', type=float, default=60.0,
                   help='seconds for the nodes to start (default 60)')
    p.add_argument('--split', choices=('test', 'train'), default='test',
                   help='held-out walks (test, the default: reports) or training walks (train: '
                        'for choosing settings)')
    args = p.parse_args(argv)
    if args.seeds < 1 or args.first_seed < 0:
        p.error('--seeds must be >= 1 and --first-seed >= 0')
    try:
        speed = check_speed(args.speed_deg_s)
    except ValueError as exc:
        p.error(str(exc))
    last = args.first_seed + args.seeds - 1
    print(f'walk demo over DDS: {args.split} seeds {args.first_seed}-{last}, '
          f'{speed:g} deg/s, {args.duration_s:g} s each', flush=True)
    results = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        results.append(run_seed(seed, speed, args.duration_s, args.timeout, args.split))
        print(seed_line(results[-1]), flush=True)
    for line in summary_lines(results):
        print(line, flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
