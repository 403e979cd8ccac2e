# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Why the shipped pan/tilt search misses a face: each miss on training scenes, view by view.

Runs the shipped face configuration (``config/faces_camera_controller.yaml``) offline on
training scenes with a face (never the test split), as ``ipomdp-gaze evaluate --scenes pan-tilt
--split train`` does, and for every scene it gets wrong prints what the detector said about the
face's cell: in each view that had the cell within one cell of its centre (where the model
expects a face to give about eight raw detections), and in a view centred on the face (which the
search may never have taken). The last line compares those centred counts for the scenes it got
right and wrong.

Usage: ``python bench/pan_tilt/pan_tilt_misses.py [--scenes 200] [--seed 1000] [--model FILE]``
(``--model``: another pan/tilt observation file, as ``evaluate --scene-model``). Prints markdown.
"""
import argparse

from ipomdp_gaze.drivers.scene_tasks import SceneTask, task_spec
from ipomdp_gaze.search.sensors import run_search
from ipomdp_gaze.search.session import SearchSession
from ipomdp_gaze.simulation.evaluation import answer_is_right, cells_apart
import numpy as np


def centred_count(task, scene) -> int:
    """Raw detections in the face's cell with the head centred on it."""
    grid = task.model.grid
    cell = grid.index(*scene.cell)
    return int(task.sensor.observe(cell).values[cell])


def search(spec, task, scene, index):
    """Run the shipped search on one scene; return the session and the frames in order."""
    session = SearchSession(task.model.grid, task.model, task.policy, spec.settings)
    frames = []

    def record(frame, result):
        frames.append((session.path[-1], np.asarray(frame.values, dtype=float)))

    run_search(session, task.sensor, scene.image, seed=np.random.default_rng([spec.seed, index]),
               on_frame=record)
    return session, frames


def main() -> None:
    """Print one row per missed face and the centred counts of right and wrong scenes."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--scenes', type=int, default=200)
    parser.add_argument('--seed', type=int, default=1000)
    parser.add_argument('--model', default='', help='another pan/tilt observation file')
    args = parser.parse_args()
    spec = task_spec('pan-tilt', seed=args.seed, split='train', model=args.model)
    task = SceneTask.get(spec)
    grid = task.model.grid
    print('| scene | background | face px | face cell | decision (answer) | fixations | '
          'closest fixation | counts in the face cell from views within one cell | centred '
          'view |')
    print('|---|---|---|---|---|---|---|---|---|')
    centred = {True: [], False: []}
    for index in range(args.scenes):
        scene = task.scene(index)
        session, frames = search(spec, task, scene, index)
        face = tuple(int(v) for v in scene.cell)
        answer = tuple(int(v) for v in grid.cell(session.map_cell))
        right = answer_is_right(answer, face, session.decision)
        count = centred_count(task, scene)
        centred[right].append(count)
        if right:
            continue
        j = grid.index(*face)
        offsets = [cells_apart(grid.cell(cell), face) for cell, _ in frames]
        near = [int(values[j]) for (_, values), off in zip(frames, offsets) if off <= 1]
        shown = session.decision if session.decision == 'absent' else \
            f'{session.decision} {answer}'
        print(f'| {index} | {scene.background} | {scene.face_px} | {face} | {shown} | '
              f'{session.fixations} | {min(offsets)} | {near or "none"} | {count} |')
    for right, label in ((True, 'right'), (False, 'wrong')):
        counts = np.asarray(centred[right])
        if counts.size:
            print(f'\n{label}: {counts.size} scenes; detections in the face cell with the head '
                  f'centred on it: median {np.median(counts):.0f}, none in '
                  f'{int((counts == 0).sum())}, 1-2 in {int(((counts > 0) & (counts < 3)).sum())}')


if __name__ == '__main__':
    main()
