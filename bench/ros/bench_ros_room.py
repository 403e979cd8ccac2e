# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The controller in many-target mode over DDS on held-out rooms of 0-4 faces, against offline.

For each of 50 seeds (3 with ``--quick``): the scene camera's held-out room of that seed
(``scene.faces '0-4'``), the detector and the controller (``config/faces_camera_*.yaml``, the
controller's with ``faces_camera_room_controller.yaml``: ``search.targets many``, the rooms'
settings and the sweep's pass, docs/design.md sections 11.5 and 11.7; the detector's with
``faces_camera_room_detector.yaml``: the grouped detections) as three fresh processes.
Recorded: the people the node publishes on ``~/target_cells`` with its ``room_done``, the
seconds from starting the scene camera to ``room_done``, and whether the people are the offline
many-target session's on the same room (``drivers.rooms.room_session``, ``pass-many-cells``:
no boxes, as the node answers) and the room's faces (each within one cell, ``match_faces``).
Test rooms; nothing was fitted to them.
"""
import time

from ipomdp_gaze.drivers.rooms import room_session
from ipomdp_gaze.drivers.scene_tasks import SceneTask, task_spec
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.harness.processes import domain_id_for, isolated_nodes
from ipomdp_gaze.harness.watch import LATCHED, Watch
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.msg_adapters import diagnostics, people
from ipomdp_gaze.simulation.evaluation import match_faces
import numpy as np

TITLE = 'Many-target mode over DDS: rooms of 0-4 faces, the node against the offline session'
ORDER = 63
FACES = '0-4'
TIMEOUT_S = 240.0


def offline(seed: int, label: str = 'pass-many-cells') -> tuple[list, list]:
    """
    Return the room's face cells and the offline session's people, as ``(row, col)``.

    ``label``: the room searcher (``pass-many-cells:parameter=value,...`` for other settings).
    """
    spec = task_spec('pan-tilt', seed=seed, faces=FACES)
    task = SceneTask.get(spec)
    scene = task.scene(0)
    task.sensor.start(scene.image)
    grid = task.model.grid
    _, _, _, faces = room_session(spec, task, 0, label)
    return ([tuple(int(v) for v in f.cell) for f in scene.faces],
            [tuple(int(v) for v in grid.cell(f['cell'])) for f in faces])


def run_room(seed: int, extra: tuple = ()) -> dict:
    """
    Run the three nodes on the room of ``seed`` until ``room_done``; what they said.

    ``extra``: more arguments of the controller (``-p name:=value``).
    """
    from diagnostic_msgs.msg import DiagnosticStatus
    from std_msgs.msg import Float32MultiArray
    grid = Grid(11, 11, 5.0)
    domain = domain_id_for()
    with isolated_nodes(domain, prefix='ipomdp-gaze-bench-') as nodes:
        with Watch(domain, 'bench_room', nodes) as watch:
            cells = watch.record(Float32MultiArray, '/gaze_controller/target_cells', LATCHED)
            done = watch.record(DiagnosticStatus, 'room_done', 10)
            nodes.start('controller', [
                '--params-file', str(config_file('faces_camera_controller.yaml')),
                '--params-file', str(config_file('faces_camera_room_controller.yaml')),
                *extra])
            if not watch.wait_until(lambda: watch.matched('room_done') > 0, 60):
                raise RuntimeError('the controller did not come up')
            nodes.start('detector', [
                '--params-file', str(config_file('faces_camera_detector.yaml')),
                '--params-file', str(config_file('faces_camera_room_detector.yaml'))])
            t0 = time.monotonic()
            nodes.start('scene_camera', [
                '--params-file', str(config_file('faces_camera_scene_camera.yaml')),
                '-p', f'seed:={seed}', '-p', f"scene.faces:='{FACES}'"])
            if not watch.wait_until(lambda: done, TIMEOUT_S):
                raise RuntimeError(f'no room_done for seed {seed}')
            seconds = done[0][0] - t0
            event = diagnostics.parse_room_done(done[0][1])
            watch.wait_until(lambda: cells, 10)
            found = people.read_people_array(cells[-1][1], grid)
        codes = [code for _, code in nodes.stop()]
    return {'seconds': seconds, 'event': event, 'codes': codes,
            'people': [tuple(int(v) for v in grid.cell(c)) for c, _ in found]}


def bench(ctx) -> str:
    """One room per seed, node against offline; a markdown table and the totals."""
    return rooms_table(ctx, range(3) if ctx.quick else range(50))


def rooms_table(ctx, seeds, label: str = 'pass-many-cells', extra: tuple = ()) -> str:
    """Return the table of the node (controller ``extra``) against the offline ``label``."""
    rows, agree, faces, found, false, seconds, clean = [], 0, 0, 0, 0, [], True
    for seed in seeds:
        truth, expected = offline(seed, label)
        run = run_room(seed, extra)
        same = sorted(run['people']) == sorted(expected)
        hits = match_faces(run['people'], truth)
        agree += same
        faces += len(truth)
        found += hits
        false += len(run['people']) - hits
        seconds.append(run['seconds'])
        clean &= run['codes'] == [0, 0, 0]
        ctx.log(f"seed {seed}: faces {truth}, node {run['people']}, offline {expected}, "
                f"{run['seconds']:.1f} s")
        rows.append(f"| {seed} | {len(truth)} | {run['event']['people']} | {hits} | "
                    f"{'yes' if same else 'no'} | {run['event']['fixations']} | "
                    f"{run['event']['ended']} | {run['seconds']:.1f} |")
    n = len(rows)
    return '\n'.join([
        '| seed | faces | people | faces found | = offline | fixations | ended | '
        'seconds to room_done |', '|---|---|---|---|---|---|---|---|', *rows, '',
        f'{n} rooms, {faces} faces: the node found {found} ({found / max(faces, 1):.3f}), '
        f'named {false} false faces ({false / n:.2f} per room); its people were the offline '
        f"session's in {agree} of {n} rooms; seconds from starting the scene camera to "
        f'room_done: median {np.median(seconds):.1f}, max {max(seconds):.1f}; every node exited '
        f"with status 0: {'yes' if clean else 'no'}.",
    ]) + '\n'
