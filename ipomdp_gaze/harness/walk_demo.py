# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The walk demo on ROS 2: the three face nodes track a face that walks (docs/design.md 12.6).

``scene_camera`` shows the held-out walk of ``seed`` (``scene.motion: walk``), ``foveal_detector``
bins its detections and ``gaze_controller`` runs the tracker's configuration
(``config/faces_camera_tracking.yaml``). The demo starts them as :func:`run_demo` does, watches
the camera's ``joint_states`` and ``walk_truth`` (paired by stamp: the pose and the face of each
frame) and the controller's ``found``, ``lost`` and ``reacquired`` events until the walk's clock
reaches its duration, stops the nodes and scores the frames where the face was in reach as the
offline evaluation does (:mod:`ipomdp_gaze.drivers.tracking`): in view (the face centre inside
the camera's field of view at the frame's pose) and in the centre cell (the head's cell is the
face's). The last line is :func:`score_line`.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from diagnostic_msgs.msg import DiagnosticStatus
from ipomdp_gaze.drivers.tracking import face_in_view
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.files.yaml_files import yaml_parameters
from ipomdp_gaze.harness.demo import faces_setup
from ipomdp_gaze.harness.processes import domain_id_for, exit_states, isolated_nodes, NodeExited
from ipomdp_gaze.harness.watch import LATCHED, Watch
from ipomdp_gaze.model.head_camera import PinholeCamera
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.msg_adapters import grid_arrays, joints
from ipomdp_gaze.vision.walks import DURATION_S
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

EVENTS = ('found', 'lost', 'reacquired')
POLL_S = 0.05
# Frames and events kept: a walk of an hour at 10 frames per second.
DEPTH = 36000


@dataclass(frozen=True)
class WalkFrame:
    """One frame the scene camera published: walk time, head cell, face position and cell."""

    t_s: float
    head: tuple
    position: tuple
    cell: tuple | None


@dataclass(frozen=True)
class WalkScore:
    """Frames scored (face in reach), the fraction in view and in the centre cell, events."""

    frames: int
    in_reach: int
    in_view: float
    in_centre: float
    lost: int
    reacquired: int


def walk_setup(seed: int = 0, speed_deg_s: float = 5.0, duration_s: float = DURATION_S,
               policy: str | None = None, split: str = 'test'):
    """
    Return the demo's nodes (:func:`faces_setup` with a walking face) and its camera.

    ``split``: the held-out walks (``test``, for reports) or the training walks (``train``, for
    choosing settings), the scene camera's ``scene.split``.
    """
    walk = {'scene.motion': 'walk', 'scene.speed_deg_s': float(speed_deg_s),
            'scene.walk_duration_s': float(duration_s), 'scene.split': str(split)}
    setup = faces_setup(False, policy, seed, walk=walk)
    values = yaml_parameters(config_file('faces_camera_scene_camera.yaml'), 'scene_camera')
    camera = PinholeCamera.from_fov(values['camera.width'], values['camera.height'],
                                    values['camera.hfov_deg'])
    return setup, camera


def pair_frames(setup, truths: list, states: list) -> list[WalkFrame]:
    """Pair each ``walk_truth`` with the ``joint_states`` of its stamp (unpaired: dropped)."""
    grid, head = setup.grid, setup.head
    poses = {}
    for _, msg in states:
        stamp = msg.header.stamp
        poses[(stamp.sec, stamp.nanosec)] = msg
    frames = []
    for _, msg in truths:
        truth = grid_arrays.read_walk_truth(msg, grid)
        pose = poses.get(truth.stamp)
        if pose is None:
            continue
        cell = head.nearest_cell(*joints.angles_from_joint_state(pose, head))
        frames.append(WalkFrame(truth.t_s, tuple(int(v) for v in grid.cell(cell)),
                                truth.position, truth.cell))
    return frames


def score_frames(frames: list, camera, grid, lost: int = 0, reacquired: int = 0) -> WalkScore:
    """Score frames as :func:`ipomdp_gaze.drivers.tracking.walk_result` does (module docstring)."""
    reach = [f for f in frames if f.cell is not None]
    n = len(reach)
    in_view = sum(face_in_view(camera, grid, f.position, f.head) for f in reach)
    in_centre = sum(f.cell == f.head for f in reach)
    return WalkScore(len(frames), n, in_view / n if n else math.nan,
                     in_centre / n if n else math.nan, int(lost), int(reacquired))


def score_line(score: WalkScore) -> str:
    """Return the demo's last line: percentages with one decimal (0.0 without a frame in reach)."""
    def percent(value):
        return 0.0 if math.isnan(value) else 100.0 * value

    return (f'kept in view {percent(score.in_view):.1f}% of frames, centre cell '
            f'{percent(score.in_centre):.1f}%, lost {score.lost}, reacquired {score.reacquired}')


def _walk_time(truths: list, grid, at: float) -> float:
    """Return the walk's time at monotonic ``at``: from the newest frame that arrived before."""
    before = [(t, msg) for t, msg in truths if t <= at] or truths[:1]
    if not before:
        return 0.0
    arrived, msg = before[-1]
    return grid_arrays.read_walk_truth(msg, grid).t_s + (at - arrived)


def run_walk_demo(setup, camera, duration_s: float = DURATION_S, timeout_s: float = 60.0,
                  domain_id: int | None = None, verbose: bool = False, out=print,
                  plot=None, stats: dict | None = None, note=None) -> int:
    """
    Run the walk demo; 0 when the walk ran its length, frames were scored and all stopped cleanly.

    ``timeout_s`` bounds the start (the nodes up and the camera's first frame); then the demo
    follows the walk until a frame at ``duration_s`` of the camera's clock (or ``timeout_s``
    more without one). ``plot``: write the face's path and the gaze over time there (PNG).
    ``stats``, when given, gets ``score`` (:class:`WalkScore`) and ``frames``. ``note`` says
    what was written (default ``out``; the CLI's goes to stderr).
    """
    domain = domain_id_for() if domain_id is None else domain_id
    stats = {} if stats is None else stats
    grid = setup.grid
    with isolated_nodes(domain, prefix='ipomdp-gaze-walk-') as nodes:
        procs = [nodes.add(node, args) for node, args in setup.nodes]
        watch = Watch(domain, 'walk_demo', nodes)
        targets = watch.record(JointState, 'pan_tilt', LATCHED, distinct_stamps=True)
        truths = watch.record(Float64MultiArray, 'walk_truth', DEPTH)
        states = watch.record(JointState, 'joint_states', DEPTH)
        events = {name: watch.record(DiagnosticStatus, name, 10) for name in EVENTS}
        out(f'ipomdp-gaze demo: a walking face (held-out walk, seed and speed of the scene '
            f'camera), {grid.rows}x{grid.cols} grid at {grid.spacing_deg} deg/cell, ROS domain '
            f'{domain}; starting ' + ', then '.join(p.name for p in procs))
        ready = {'controller': lambda: bool(targets),
                 'detector': lambda: watch.node.count_subscribers('image') > 0}
        status, walked, shown = 1, False, dict.fromkeys(EVENTS, 0)

        def show_events():
            for name in EVENTS:
                for at, _ in events[name][shown[name]:]:
                    out(f'{_walk_time(truths, grid, at):6.2f} s: {name}')
                shown[name] = len(events[name])

        def walk_over() -> bool:
            show_events()
            return bool(truths) and grid_arrays.read_walk_truth(
                truths[-1][1], grid).t_s >= duration_s

        try:
            for proc in procs:
                proc.start()
                wait = ready.get(proc.node)
                if wait is not None and not watch.wait_until(wait, timeout_s, POLL_S):
                    raise RuntimeError(f"{proc.name} did not come up within the demo's "
                                       f'--timeout of {timeout_s:g} s')
            if not watch.wait_until(lambda: bool(truths), timeout_s, POLL_S):
                raise RuntimeError(f"the scene camera sent no frame within the demo's "
                                   f'--timeout of {timeout_s:g} s')
            out(f'the walk has started: following it for {duration_s:g} s of the camera clock')
            walked = watch.wait_until(walk_over, duration_s + timeout_s, POLL_S)
            if not walked:
                out(f'ipomdp-gaze demo: error: the walk did not reach {duration_s:g} s in time')
        except (RuntimeError, NodeExited) as exc:
            out(f'ipomdp-gaze demo: error: {exc}')
        finally:
            alive = {p.node: p.running for p in procs}
            codes = {p.node: code for p, code in nodes.stop(procs[::-1])}
            watch.close()
        show_events()
        frames = pair_frames(setup, truths, states)
        score = score_frames(frames, camera, grid, len(events['lost']),
                             len(events['reacquired']))
        stats.update(score=score, frames=frames)
        if verbose or not walked:
            for p in procs:
                out(f'--- {p.node} output ---\n{p.output().rstrip()}')
        clean = all(codes[k] == 0 for k, running in alive.items() if running)
        states_ = exit_states(codes, alive)
        out(f'stopped all {len(procs)} nodes ({states_})' +
            ('' if clean else ': NOT a clean shutdown'))
        if plot is not None and frames:
            _plot(frames, events, truths, grid, plot, setup)
            (out if note is None else note)(f'wrote {plot}')
        out(f'scored {counted(score.in_reach, "frame")} with the face in reach, of '
            f'{counted(score.frames, "frame")} '
            f'({len(truths)} sent, {len(events["found"])} found events)')
        if walked and score.in_reach and clean:
            status = 0
        out(score_line(score))
        return status


def _plot(frames: list, events: dict, truths: list, grid, path, setup) -> None:
    """Draw the face's path and the head's cell over the walk's time (``plot_walk``)."""
    from ipomdp_gaze.vision.walks import plot_walk
    times = [f.t_s for f in frames]
    face = [f.position if f.cell is not None else (math.nan, math.nan) for f in frames]
    head = [f.head for f in frames]
    marks = sorted((_walk_time(truths, grid, at), name) for name in EVENTS
                   for at, _ in events[name])
    scene = [args for node, args in setup.nodes if node == 'scene_camera'][0]
    plot_walk(times, face, head, path, title='the walking face and the gaze over ROS: '
              + ' '.join(a.removeprefix('scene.') for a in scene if ':=' in a), events=marks)
