# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The walk evaluation: one clock for every searcher, the baseline's rules, the command."""
import json
from pathlib import Path
import subprocess
import sys

from ipomdp_gaze.drivers import tracking
from ipomdp_gaze.files.observation_file import load_observation
from ipomdp_gaze.model.head_time import HEAD_SPEED_DEG_S, SACCADE_TIME_S, SETTLE_TIME_S
from ipomdp_gaze.vision.walks import WalkSceneSet
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope='module')
def task():
    spec = tracking.walk_spec(10.0, 'train', 0, 4.0)
    return spec, tracking.WalkTask.get(spec.settings, spec.policy, spec.model)


def _gaps_follow_the_head_model(frames, grid_spacing):
    for a, b in zip(frames, frames[1:]):
        step = max(abs(b.head[0] - a.head[0]), abs(b.head[1] - a.head[1])) * grid_spacing
        move = SACCADE_TIME_S + step / HEAD_SPEED_DEG_S if step else 0.0
        assert b.t_s - a.t_s == pytest.approx(tracking.DETECTOR_TIME_S + move + SETTLE_TIME_S)


@pytest.mark.parametrize('searcher', ['track', 'track-last-detection'])
def test_every_searcher_runs_on_the_walk_clock(task, searcher):
    """A view is taken when the head arrived and settled; the detector's time passes after it."""
    spec, walk_task = task
    scene = WalkSceneSet('train', walk_task.geometry, 0, 10.0, 4.0).scene(2)
    tracker = tracking.SessionTracker(walk_task, spec.settings, np.random.default_rng(0)) \
        if searcher == 'track' else tracking.LastDetectionTracker(walk_task)
    frames = tracking.run_walk(walk_task, scene, tracker)
    assert len(frames) > 5 and frames[-1].t_s <= scene.duration_s
    _gaps_follow_the_head_model(frames, walk_task.grid.spacing_deg)
    for f in frames:
        truth = scene.truth_at(f.t_s)
        assert f.cell == truth.cell and f.in_centre == (truth.cell == f.head)
        assert not f.in_view or f.cell is not None


def test_the_baseline_centres_its_grouped_detection_and_sweeps_without_one(task):
    """A still face: once grouped, the head stays on it; an empty scene: the sweep's poses."""
    spec, walk_task = task
    still = WalkSceneSet('train', walk_task.geometry, 0, 0.0, 4.0).scene(2)
    frames = tracking.run_walk(walk_task, still, tracking.LastDetectionTracker(walk_task))
    found = [i for i, f in enumerate(frames) if f.answer is not None]
    assert found, 'the baseline sees the still face of training scene 2'
    held = frames[found[0] + 1:]
    assert held and all(f.head == frames[found[0] + 1].head for f in held)
    assert all(f.answer is not None for f in held)
    result = tracking.walk_result('track-last-detection', 2, still, frames)
    assert result.found and result.reacquire_s is None and result.lost == 0


def test_the_scores_of_a_walk_by_hand():
    """in_view, in_centre, first find and reacquisition from frames written out."""
    class Scene:
        duration_s = 10.0

        def truth_at(self, t):
            return type('T', (), {'cell': None if 4 <= t < 6 else (2, 2)})()

    frames = [tracking.WalkFrame(1.0, (2, 2), (2, 2), True, True, None),
              tracking.WalkFrame(2.0, (2, 2), (2, 2), True, True, (2, 3), 'found'),
              tracking.WalkFrame(5.0, (2, 2), None, False, False, None, 'lost'),
              tracking.WalkFrame(6.5, (1, 1), (2, 2), True, False, None),
              tracking.WalkFrame(7.0, (2, 2), (2, 2), True, True, (2, 2), 'found')]
    r = tracking.walk_result('x', 0, Scene(), frames)
    assert (r.reach_frames, r.in_view, r.in_centre) == (4, 1.0, 0.75)
    assert r.first_find_s == 2.0 and r.found
    assert r.reacquire_s == pytest.approx(1.0, abs=0.011) and r.reacquired
    assert (r.lost, r.reacquired_events) == (1, 1)


def test_the_tracker_reads_the_model_its_configuration_names(tmp_path):
    """``observation.file`` of the tracking configuration, or the model asked for instead."""
    config = tmp_path / 'tracking.yaml'
    text = tracking.config_file(tracking.WALK_CONFIG).read_text()
    assert 'file: faces-pan-tilt-profile' in text
    config.write_text(text.replace('file: faces-pan-tilt-profile', 'file: faces-pan-tilt'))
    assert tracking.walk_spec(5.0, 'train').model == 'faces-pan-tilt-profile'
    spec = tracking.walk_spec(5.0, 'train', config=config)
    assert spec.model == 'faces-pan-tilt'
    assert tracking.walk_spec(5.0, 'train', config=config, model='faces-pan-tilt-profile').model \
        == 'faces-pan-tilt-profile'
    task = tracking.WalkTask.get(spec.settings, spec.policy, spec.model)
    frontal = load_observation('faces-pan-tilt')
    np.testing.assert_array_equal(task.model.p_target, frontal.p_target)
    assert task.detector.cascade_names == ['haarcascade_frontalface_alt2.xml']


def test_evaluate_motion_walk_writes_the_summary_per_searcher(tmp_path):
    out = tmp_path / 'walk.json'
    done = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'evaluate', '--scenes',
                           'pan-tilt', '--motion', 'walk', '--speed-deg-s', '10',
                           '--walk-duration-s', '3', '--episodes', '2', '--split', 'train',
                           '--json', str(out), '--jobs', '1', '--quiet'],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    record = json.loads(out.read_text())
    assert set(record['summary']) == {'track', 'track-last-detection'}
    for s in record['summary'].values():
        for key in ('in_view', 'in_centre', 'first_find_s_mean', 'reacquire_s_mean'):
            assert key in s
    assert len(record['scenes']['track']) == 2
    assert 'in_centre minus track-last-detection' in done.stdout
    page = tmp_path / 'walks.md'
    import importlib.util           # the page maker in this process: no second interpreter
    spec = importlib.util.spec_from_file_location('bench_walks',
                                                  ROOT / 'bench' / 'pan_tilt' / 'walks.py')
    walks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(walks)
    assert walks.main(['--cli-json', str(out), '--json', str(tmp_path / 'record.json'),
                       '--out', str(page)]) == 0
    text = page.read_text()
    assert '## 10 deg/s, 2 train walks of 3 s' in text
    for name in ('track', 'track-last-detection'):
        row = next(line for line in text.splitlines() if line.startswith(f'| `{name}` |'))
        assert row.count('|') == 7
    assert 'Paired differences, `track` minus `track-last-detection`' in text


@pytest.mark.parametrize('args, message', [
    (['--speed-deg-s', '25'], 'speed_deg_s must be a number from 0 to 20'),
    (['--compare', 'sweep'], "unknown walk searcher 'sweep'"),
    (['--compare', 'track-last-detection:neighbors=0'], 'expected neighbors=N'),
    (['--compare', 'track-last-detection:neighbors=\u00b2'], 'expected neighbors=N'),
    (['--walk-duration-s', '0'], 'the walk duration must be from 1 to 3600 s'),
    (['--faces', '2'], '--motion walk is for --scenes pan-tilt with one face'),
])
def test_bad_walk_arguments_are_one_line(args, message, cli_here):
    """In this process: the refusal's status and line, without an interpreter per case."""
    run = cli_here('evaluate', '--scenes', 'pan-tilt', '--motion', 'walk', '--episodes', '1',
                   *args)
    err = run.stderr
    assert run.returncode != 0 and 'Traceback' not in err
    assert message in err.strip().splitlines()[-1]


def test_a_paired_difference_of_fractions_is_cut_to_minus_one_one():
    from ipomdp_gaze.drivers.tracking import normal_interval
    mean, low, high = normal_interval(np.array([1.0, -0.03]), 1.0)       # +-1.43 wide
    assert mean == pytest.approx(0.485) and high == 1.0 and low == pytest.approx(0.485 - 1.0094)
    assert normal_interval(np.array([1.0, -1.0]), 1.0)[1:] == [-1.0, 1.0]
    assert normal_interval(np.array([3.0, -1.0]))[1] < -1.0        # seconds: no bound


def test_a_walk_longer_than_the_scene_cameras_is_refused():
    """The scene camera's bound, an hour: evaluate ran a walk of 1e9 s for ever."""
    assert tracking.walk_spec(5.0, 'train', duration_s=3600.0).duration_s == 3600.0
    for duration_s in (3600.5, 1e9):
        with pytest.raises(ValueError, match='the walk duration must be from 1 to 3600 s'):
            tracking.walk_spec(5.0, 'train', duration_s=duration_s)


def test_a_walk_shorter_than_the_scene_cameras_is_refused():
    """Its bound, 1 s: evaluate scored a walk of 0.4 s on no frame ('in view nan')."""
    assert tracking.walk_spec(5.0, 'train', duration_s=1.0).duration_s == 1.0
    for duration_s in (0.99, 0.4, 1e-9):
        with pytest.raises(ValueError, match=r'the walk duration must be from 1 to 3600 s \(as '
                           r"the scene camera's scene.walk_duration_s\), got "):
            tracking.walk_spec(5.0, 'train', duration_s=duration_s)


def test_a_walk_searcher_given_twice_is_refused():
    """Results are kept per label: one walk was counted as found in 2 of 2."""
    with pytest.raises(ValueError, match="'track-last-detection' is given twice"):
        tracking.walk_spec(5.0, 'train', compare=('track-last-detection',) * 2)


def test_walk_options_without_motion_walk_are_refused(cli_here):
    for flag in ('--speed-deg-s', '--walk-duration-s'):
        result = cli_here('evaluate', '--scenes', 'pan-tilt', flag, '5', '--episodes', '1')
        assert result.returncode == 2
        assert result.stderr.strip().endswith(f'{flag} goes with --motion walk')
