# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze demo --scene faces --motion walk``: the nodes track a walking face (design 12.6).

Pure: frames pair with the camera's pose by stamp and are scored as the offline evaluation
scores them (in view, in the centre cell, over the frames with the face in reach); the last line
has its documented format; combinations without a walk are refused with one line. Over DDS: one
short demo runs the three nodes, scores frames and ends with the score line.
"""
from __future__ import annotations

import re
import subprocess
import sys

from conftest import REPO
from ipomdp_gaze.cli import main
import pytest

SCORE = re.compile(r'^kept in view (\d+\.\d)% of frames, centre cell (\d+\.\d)%, lost (\d+), '
                   r'reacquired (\d+)$')


def _grid_camera():
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.head_camera import PinholeCamera
    return Grid(11, 11, 5.0), PinholeCamera.from_fov(320, 240, 25.0)


def test_frames_are_scored_over_the_face_in_reach_as_offline():
    from ipomdp_gaze.drivers.tracking import face_in_view
    from ipomdp_gaze.harness.walk_demo import score_frames, score_line, WalkFrame
    grid, camera = _grid_camera()
    frames = [WalkFrame(0.0, (5, 5), (5.2, 4.9), (5, 5)),       # in view, centre cell
              WalkFrame(0.2, (5, 5), (5.0, 7.4), (5, 7)),       # in view (2.4 cells of 2.5)
              WalkFrame(0.4, (5, 5), (5.0, 7.6), (5, 8)),       # out of view
              WalkFrame(0.6, (5, 5), (-1.4, 5.0), None)]        # out of reach: not scored
    assert [face_in_view(camera, grid, f.position, f.head) for f in frames[:3]] == \
        [True, True, False]
    score = score_frames(frames, camera, grid, lost=2, reacquired=1)
    assert (score.frames, score.in_reach) == (4, 3)
    assert score.in_view == pytest.approx(2 / 3) and score.in_centre == pytest.approx(1 / 3)
    line = score_line(score)
    assert line == 'kept in view 66.7% of frames, centre cell 33.3%, lost 2, reacquired 1'
    assert SCORE.match(line)
    nobody = score_frames(frames[3:], camera, grid)
    assert score_line(nobody) == 'kept in view 0.0% of frames, centre cell 0.0%, lost 0, ' \
        'reacquired 0'


def test_frames_pair_with_the_pose_of_their_stamp():
    from builtin_interfaces.msg import Time
    from ipomdp_gaze.harness.walk_demo import pair_frames, walk_setup, WalkFrame
    from ipomdp_gaze.msg_adapters import grid_arrays, joints
    setup, _ = walk_setup(seed=0, speed_deg_s=5.0, duration_s=10.0)
    grid, head = setup.grid, setup.head
    stamps = [Time(sec=100, nanosec=n) for n in (0, 250000000, 500000000)]
    truths = [(0.0, grid_arrays.walk_truth(s, 0.25 * i, (3.2, 4.1), (3, 4)))
              for i, s in enumerate(stamps)]
    states = [(0.0, joints.joint_state(head, grid.index(3, c), s))
              for c, s in zip((2, 3), stamps[1:])]                # the first pose never came
    assert pair_frames(setup, truths, states) == [
        WalkFrame(0.25, (3, 2), (3.2, 4.1), (3, 4)), WalkFrame(0.5, (3, 3), (3.2, 4.1), (3, 4))]


def test_the_walk_demo_runs_the_tracker_on_the_walk_of_the_seed():
    from ipomdp_gaze.harness.walk_demo import walk_setup
    setup, camera = walk_setup(seed=4, speed_deg_s=8.0, duration_s=12.0)
    args = dict(setup.nodes)
    assert args['controller'][1].endswith('faces_camera_tracking.yaml')
    assert setup.settings.moving
    camera_args = ' '.join(args['scene_camera'])
    for want in ('seed:=4', 'scene.motion:=walk', 'scene.speed_deg_s:=8.0',
                 'scene.walk_duration_s:=12.0', 'scene.split:=test'):
        assert want in camera_args
    assert (camera.width, camera.height) == (320, 240)
    train, _ = walk_setup(seed=4, split='train')
    assert 'scene.split:=train' in ' '.join(dict(train.nodes)['scene_camera'])


@pytest.mark.parametrize('args, message', [
    (['--motion', 'walk'], '--motion walk goes with --scene faces'),
    (['--scene', 'faces', '--motion', 'walk', '--fovea'], '--motion walk goes with --scene faces'),
    (['--scene', 'faces', '--motion', 'walk', '--empty'], '--motion walk goes with --scene faces'),
    (['--scene', 'faces', '--motion', 'walk', '--faces', '2'],
     '--motion walk goes with --scene faces'),
    (['--scene', 'faces', '--motion', 'walk', '--speed-deg-s', '25'],
     'speed_deg_s must be a number from 0 to 20'),
    (['--scene', 'faces', '--motion', 'walk', '--duration-s', '0.5'],
     '--duration-s must be from 1 to 3600 s'),
    (['--scene', 'faces', '--motion', 'walk', '--animate', 'x.gif'],
     '--animate is not available with --motion walk'),
    (['--scene', 'faces', '--speed-deg-s', '5'], '--speed-deg-s goes with --motion walk'),
    (['--scene', 'faces', '--duration-s', '5'], '--duration-s goes with --motion walk'),
])
def test_a_walk_where_there_is_none_exits_nonzero_with_one_line(capsys, args, message):
    assert main(['demo', *args]) != 0
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], captured.err
    assert 'Traceback' not in captured.err + captured.out


@pytest.mark.ros
def test_a_short_walk_demo_scores_frames_and_ends_with_the_score_line(ros_env, tmp_path):
    domain = int(ros_env['ROS_DOMAIN_ID'])
    plot = tmp_path / 'walk.png'
    run = subprocess.run(
        [sys.executable, '-m', 'ipomdp_gaze.cli', 'demo', '--scene', 'faces', '--motion', 'walk',
         '--seed', '1', '--duration-s', '4', '--plot', str(plot), '--domain-id', str(domain)],
        cwd=REPO, env=ros_env, capture_output=True, text=True, timeout=240)
    out = run.stdout
    assert run.returncode == 0, out + run.stderr
    lines = out.strip().splitlines()
    match = SCORE.match(lines[-1])
    assert match, lines[-1]
    p, c = float(match.group(1)), float(match.group(2))
    assert 0 <= c <= p <= 100
    scored = re.search(r'^scored (\d+) frames with the face in reach, of (\d+) frames', out, re.M)
    assert scored and 0 < int(scored.group(1)) <= int(scored.group(2)), out
    assert 'stopped all 3 nodes' in out and 'NOT a clean shutdown' not in out
    assert plot.stat().st_size > 0
    assert f'ipomdp-gaze demo: wrote {plot}\n' in run.stderr and 'wrote' not in out


def test_the_bench_says_per_seed_and_on_how_many_seeds_the_face_was_kept_in_view():
    import importlib.util
    from ipomdp_gaze.harness.walk_demo import WalkScore
    spec = importlib.util.spec_from_file_location('bench_walk_demo',
                                                  REPO / 'bench' / 'ros' / 'walk_demo.py')
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    results = [{'seed': 0, 'status': 0, 'score': WalkScore(100, 60, 0.75, 0.4, 1, 1),
                'kept': True},
               {'seed': 1, 'status': 0, 'score': WalkScore(90, 50, 0.3, 0.1, 2, 0),
                'kept': False},
               {'seed': 2, 'status': 1, 'score': None, 'kept': False}]
    assert bench.seed_line(results[0]) == ('seed 0: status 0, 100 frames (60 in reach), in view '
                                           '75.0%, centre cell 40.0%, lost 1, reacquired 1: '
                                           'kept')
    assert bench.seed_line(results[2]).endswith('no frame with the face in reach: not kept')
    lines = bench.summary_lines(results)
    assert lines[0].startswith('1 of 3 runs not scored; over the 2 scored: in view 52.5%')
    assert lines[-1] == ('kept in view on 1 of 3 seeds (in view on >= 50% of the frames with '
                         'the face in reach)')
