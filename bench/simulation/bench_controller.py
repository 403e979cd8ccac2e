# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The controller's per-frame cost in process: ``GazeController.offer`` and ``SearchSession.update``.

The settings of the ROS loop bench (``bench/ros/bench_ros_loop.py``): a camera FPOC (a box of
``d'`` over the camera's field of view), ELM, motion on (``sigma_cells`` 0.5 per second, so
every frame includes the prediction step), settle time 0, on 11x11, 128x128 and 256x256 grids.
Frames are drawn from the controller's own model at its fixation, NaN outside the camera's view,
float32 as read from a message; the time between frames is the loop's period with 20% jitter
(frame stamps never repeat a time step on the robot either). Only the call is timed, one
``perf_counter`` pair per frame; the table gives the median and p90 over the frames. The same
frames go once through ``GazeController.offer`` (the node's call: the frame check, the session's
update, counters and events) and once through a bare ``SearchSession.update`` (a second
controller built the same way, its session driven directly).

Run through ``bench/run.py`` (``--only controller``), or alone: ``python
bench/simulation/bench_controller.py [--quick]`` prints the markdown section. Pointing
``PYTHONPATH`` at
another checkout measures that code with the same script (a before/after comparison).
"""
import argparse
import time

from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import GaussianObservation
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.session import Frame, SearchSettings
import numpy as np

TITLE = 'Controller per-frame cost in process (offer / update)'
ORDER = 29
# (label, rows, spacing_deg, camera half field of view in degrees, seconds between frames,
#  frames timed, frames in a quick run): bench_ros_loop's grids and loop periods.
CASES = (('11x11', 11, 5.0, 10.0, 0.001, 2000, 200),
         ('128x128', 128, 0.5, 2.0, 0.002, 300, 30),
         ('256x256', 256, 0.25, 1.0, 1.0 / 60.0, 100, 10))
SIGMA_CELLS = 0.5
SEED = 0


def _controller(grid: Grid, fpoc) -> GazeController:
    settings = SearchSettings(motion_sigma_cells=SIGMA_CELLS)
    return GazeController(grid, fpoc, build_policy('elm', grid, fpoc), settings,
                          settle_time_s=0.0, seed=SEED)


def measure(label, rows, spacing, half, period_s, frames) -> dict:
    """Time ``frames`` calls of ``offer`` and of ``update``; return medians and p90s in ms."""
    grid = Grid(rows, rows, spacing)
    fpoc = make_fpoc('camera', half_width_deg=half, half_height_deg=half)
    model = GaussianObservation(grid, fpoc)
    target = grid.index(rows // 3, (2 * rows) // 3)
    times = {}
    for how in ('offer', 'update'):
        core = _controller(grid, fpoc)
        session = core.session
        rng = np.random.default_rng(SEED)
        stamp, spent = 0.0, []
        for _ in range(frames):
            cell = core.fixation if how == 'offer' else session.fixation
            values = model.sample(target, cell, rng)
            values[~model.observed(cell)] = np.nan
            values = values.astype(np.float32).astype(float)
            dt = period_s * (1.0 + 0.2 * rng.random())
            stamp += dt
            if how == 'offer':
                t0 = time.perf_counter()
                result = core.offer(values, stamp, stamp)
                spent.append(time.perf_counter() - t0)
            else:
                frame = Frame(values)
                t0 = time.perf_counter()
                result = session.update(frame, dt_s=dt)
                spent.append(time.perf_counter() - t0)
            if not result.applied:
                raise RuntimeError(f'{label}: a frame was not applied ({result.reason})')
        ms = np.array(spent) * 1e3
        times[how] = (float(np.median(ms)), float(np.percentile(ms, 90)))
    return {'grid': label, 'frames': frames, 'offer': times['offer'], 'update': times['update']}


def bench(ctx=None) -> str:
    quick = bool(getattr(ctx, 'quick', False))
    lines = ['| grid | frames | `offer` median (ms) | `offer` p90 (ms) | `update` median (ms) | '
             '`update` p90 (ms) |', '|---|---|---|---|---|---|']
    for label, rows, spacing, half, period_s, frames, quick_frames in CASES:
        r = measure(label, rows, spacing, half, period_s, quick_frames if quick else frames)
        lines.append(f"| {label} | {r['frames']} | {r['offer'][0]:.3f} | {r['offer'][1]:.3f} | "
                     f"{r['update'][0]:.3f} | {r['update'][1]:.3f} |")
    lines += ['', 'Camera FPOC, ELM, motion on (sigma 0.5 cells per second), frames drawn at '
              "the controller's fixation, NaN outside the view, the loop's period between "
              "stamps with 20% jitter; one timing per call. `offer` is the node's call "
              '(frame check, update, counters, events); `update` the bare session step.', '']
    return '\n'.join(lines)


def main(argv=None) -> None:
    """Run alone: print the section."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--quick', action='store_true', help='few frames: a smoke run')
    print(bench(parser.parse_args(argv)))


if __name__ == '__main__':
    main()
