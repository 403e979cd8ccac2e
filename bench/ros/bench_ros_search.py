# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Live searches over DDS with the shipped YAML files, beside the same task simulated offline.

Run: ``.venv/bin/python bench/ros/bench_ros_search.py [searches] [--quick]`` (default 30 live
searches; ``--quick``: 5 live and 200 offline). Starts
``gaze_controller`` and ``simulated_camera`` as processes on a private domain, then repeats:
disable, camera reset (a new random target), controller reset, enable, wait for ``found``.
Prints fixations to ``found`` (median, 90th percentile), the fraction found at the right cell and
the wall time per search, and the same numbers from the numpy core on 2,000 simulated searches
(the controller's core, :class:`GazeController`, with the shipped confidence 0.95).
"""
import argparse
import time

from ipomdp_gaze.commands.common import positive_int
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.harness.processes import domain_id_for, isolated_nodes
from ipomdp_gaze.harness.watch import CAMERA, SearchRecord, Watch
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.session import SearchSettings
import numpy as np

GRID = Grid(11, 11, 5.0)
FPOC = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)


def offline(policy_name, searches=2000, seed=0, confidence=0.95):
    """Fixations to ``found`` and correctness of the core alone with the camera model."""
    rng = np.random.default_rng(seed)
    d = dprime_matrix(GRID, FPOC)
    file = 'camera-11x11-infomax' if policy_name == 'learned' else ''
    core = GazeController(GRID, FPOC, build_policy(policy_name, GRID, FPOC, file=file),
                          SearchSettings(confidence=confidence))
    fixations, right = [], []
    for _ in range(searches):
        target = int(rng.integers(GRID.n_cells))
        core.reset(0.0)
        t = 0
        while core.found is None and t < 500:
            frame = rng.standard_normal(GRID.n_cells)
            frame[target] += d[target, core.fixation]
            frame[d[:, core.fixation] == 0] = np.nan
            t += 1
            core.offer(frame, float(t))
        fixations.append(core.found.fixations)
        right.append(core.found.cell == target)
    return np.array(fixations), np.array(right)


def live(searches, domain):
    """Fixations, correctness and seconds of each live search."""
    with isolated_nodes(domain) as nodes:
        controller = nodes.start(
            'controller', ['--params-file', str(config_file('controller.yaml'))])
        nodes.start('camera', ['--params-file', str(config_file('camera.yaml'))])
        out = []
        with Watch(domain, 'bench_search', nodes) as watch:
            record = SearchRecord(watch)

            def wait(condition, timeout_s=60.0):
                if not watch.wait_until(condition, timeout_s, 0.005):
                    raise RuntimeError('timed out')

            wait(lambda: record.truth)
            for _ in range(searches):
                watch.enable(False)
                n_truth = len(record.truth)
                watch.reset(CAMERA)
                wait(lambda: len(record.truth) > n_truth)
                watch.reset()
                n_found = len(record.found)
                t0 = time.perf_counter()
                watch.enable(True)
                wait(lambda: len(record.found) > n_found)
                seconds = time.perf_counter() - t0
                found = diagnostics.parse_found(record.found[n_found][1])
                truth = grid_arrays.cell_from_ground_truth(record.truth[-1][1], GRID)
                out.append((found['fixations'], found['cell'] == truth, seconds))
        codes = [code for _, code in nodes.stop()]
        policy = 'learned' if 'policy learned' in controller.output() else 'elm'
        return np.array(out), policy, codes


def main(argv=None):
    """Run the live searches, then the offline ones, and print both lines."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('searches', nargs='?', type=positive_int, default=None,
                        help='live searches (default 30; 5 with --quick)')
    parser.add_argument('--quick', action='store_true',
                        help='a smoke run: 5 live searches and 200 offline')
    args = parser.parse_args(argv)
    searches = args.searches or (5 if args.quick else 30)
    offline_searches = 200 if args.quick else 2000
    results, policy, codes = live(searches, domain_id_for())
    fix, right, secs = results[:, 0], results[:, 1], results[:, 2]
    print(f'live over DDS ({policy}, {searches} searches, node exit codes {codes}): '
          f'fixations to found median {np.median(fix):.0f}, p90 {np.percentile(fix, 90):.1f}, '
          f'mean {fix.mean():.2f}; right {right.mean():.3f}; seconds per search median '
          f'{np.median(secs):.2f}, p90 {np.percentile(secs, 90):.2f}; '
          f'seconds per fixation {secs.sum() / fix.sum():.3f}')
    fix, right = offline(policy, offline_searches)
    print(f'offline core ({policy}, {offline_searches} searches): fixations to found median '
          f'{np.median(fix):.0f}, p90 {np.percentile(fix, 90):.1f}, mean {fix.mean():.2f}; '
          f'right {right.mean():.3f}')


if __name__ == '__main__':
    main()
