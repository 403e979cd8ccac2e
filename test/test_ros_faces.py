# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The pixel loop end to end: scene camera, foveal detector and controller as three processes.

``ipomdp-gaze demo --scene faces [--fovea]`` on held-out test scenes of fixed seeds: the face is
found in the right place (within one cell of its centre's cell) and all three nodes stop
cleanly, in both detector modes. The README's face demo outputs and figures are checked here
too, on the same runs: each distinct demo command runs once per module.
"""
from __future__ import annotations

from pathlib import Path
import re
import subprocess
import sys

from conftest import REPO
import pytest
from test_readme import _contains, _shown_by
from test_readme_figures import readme_figures
from test_ros_demo import node_processes

pytestmark = pytest.mark.ros

FIXATION = re.compile(r'^fixation +(\d+): looked at \((\d+), (\d+)\)  (.*)  ->  most likely '
                      r'\((\d+), (\d+)\) p=(\d\.\d+)(?:  nobody p=\d\.\d+)? +entropy '
                      r'(\d+\.\d+) nats$', re.M)
# found (or, at the deadline of the pan/tilt config, found forced by it, or at a grouped
# detection with search.group_stop) and how it ended.
FOUND = re.compile(r'^found(?:, forced by the fixation budget| at a grouped detection)?: the '
                   r'face is (?:most likely )?at '
                   r'\((\d+), (\d+)\), (.*), probability (\d\.\d+), after (\d+) fixations? '
                   r'\((?:reached|below) the confidence 0\.99\)$', re.M)
VERDICT = re.compile(r'^the scene camera put the face centre in cell \((\d+), (\d+)\): that is '
                     r'(right|wrong)$', re.M)


def _demo_figures() -> dict:
    """Return ``{demo options: figure}`` of the README figures a face demo draws (``--plot``)."""
    out = {}
    for figure, commands in readme_figures().items():
        argv = commands[0].split()[1:] if commands else []
        if argv[:1] == ['demo']:
            k = argv.index('--plot')
            out[tuple(argv[1:k] + argv[k + 2:])] = figure
    return out


DEMO_FIGURES = _demo_figures()


@pytest.fixture(scope='module')
def demo(ros_env, tmp_path_factory):
    """
    Run ``ipomdp-gaze demo`` once per option list; the tests that check one command share it.

    Options that are a README figure's command (without its ``--plot``) run with ``--plot`` to
    a temporary file, so that the same run draws the figure.
    """
    plots, runs = tmp_path_factory.mktemp('plots'), {}

    def run(*options):
        if options not in runs:
            plot = ['--plot', str(plots / Path(DEMO_FIGURES[options]).name)] \
                if options in DEMO_FIGURES else []
            runs[options] = subprocess.run(
                [sys.executable, '-m', 'ipomdp_gaze.cli', 'demo', '--domain-id',
                 ros_env['ROS_DOMAIN_ID'], *options, *plot], cwd=REPO, env=ros_env,
                capture_output=True, text=True, timeout=180)
        return runs[options], plots

    return run


def find_path(seed: int) -> tuple:
    """Return the fixations `find` makes on the scene camera's fixed scene of ``seed``."""
    from ipomdp_gaze.files.observation_file import load_observation
    from ipomdp_gaze.policies.registry import build_policy
    from ipomdp_gaze.vision.scenes import SceneSet
    from ipomdp_gaze.vision.search import fovea_for_model, SCENE_SETTINGS, search_image
    model = load_observation('faces-420')
    scene = SceneSet('test', 420, (60, 140), model.grid.shape, color='rgb', seed=seed).scene(0)
    policy = build_policy('learned', model.grid, model, file='faces-420-infomax')
    return search_image(scene.image, fovea_for_model(model), model, policy, SCENE_SETTINGS).path


@pytest.mark.parametrize('options, mode, where', [
    (['--fovea', '--seed', '0'], 'fovea', r'pixel \( *\d+\.\d, +\d+\.\d\)'),
    (['--fovea', '--seed', '2'], 'fovea', r'pixel \( *\d+\.\d, +\d+\.\d\)'),
    (['--seed', '0'], 'camera', r'pan +[-+]\d+\.\d\d deg +tilt +[-+]\d+\.\d\d deg'),
    (['--seed', '2'], 'camera', r'pan +[-+]\d+\.\d\d deg +tilt +[-+]\d+\.\d\d deg'),
])
def test_three_nodes_find_the_face_and_stop(ros_env, demo, options, mode, where):
    domain = int(ros_env['ROS_DOMAIN_ID'])
    run, _ = demo('--scene', 'faces', *options)
    out = run.stdout
    assert run.returncode == 0, out + run.stderr
    grid = '21x21 grid' if mode == 'fovea' else '11x11 grid at 5.0 deg/cell'
    assert f'faces scene, detector mode {mode}, {grid}' in out
    assert 'starting gaze_controller, then foveal_detector, then scene_camera' in out
    fixations = FIXATION.findall(out)
    found, verdict = FOUND.search(out), VERDICT.search(out)
    assert fixations and found and verdict, out
    assert [int(f[0]) for f in fixations] == list(range(1, len(fixations) + 1))
    assert int(found.group(5)) == len(fixations)
    looked = [(int(f[1]), int(f[2])) for f in fixations]
    if mode == 'fovea':             # the scan, then exactly find's fixations on this image
        assert 'scan: the whole image once  ->  most likely' in out
        assert looked == list(find_path(int(options[-1])))
    else:
        assert looked[0] == (5, 5)                                     # the first: the centre
    assert all(re.fullmatch(where, f[3].strip()) for f in fixations), fixations
    assert re.fullmatch(where, found.group(3))
    # The answer is the last line's most likely cell: the lines name it as the controller's
    # found rule does (with search.found_radius, the centre of the most likely 3x3 square).
    last = int(fixations[-1][4]), int(fixations[-1][5])
    answer = int(found.group(1)), int(found.group(2))
    if 'found at a grouped detection' not in out:       # that answers the group's cell
        assert last == answer
    truth = int(verdict.group(1)), int(verdict.group(2))
    assert max(abs(truth[0] - answer[0]), abs(truth[1] - answer[1])) <= 1
    assert verdict.group(3) == 'right'
    assert 'stopped all 3 nodes (scene_camera exit status 0, detector exit status 0, ' \
           'controller exit status 0)' in out
    assert node_processes(domain) == []


def test_without_a_confident_cell_the_demo_answers_with_the_most_likely_one(ros_env, demo):
    domain = int(ros_env['ROS_DOMAIN_ID'])
    run, _ = demo('--scene', 'faces', '--fovea', '--seed', '12', '--max-fixations', '4')
    out = run.stdout
    assert run.returncode == 0, out + run.stderr
    assert len(FIXATION.findall(out)) == 4
    gave_up = re.search(r'^gave up: no cell reached the confidence 0.99 after 4 fixations; the '
                        r'face is most likely at \((\d+), (\d+)\), pixel .*, probability '
                        r'(\d\.\d+), after 4 fixations$', out, re.M)
    assert gave_up and float(gave_up.group(3)) < 0.999, out
    assert VERDICT.search(out) and 'found:' not in out
    assert 'stopped all 3 nodes' in out and node_processes(domain) == []


def test_on_a_scene_without_a_face_the_controller_says_absent(ros_env, demo):
    domain = int(ros_env['ROS_DOMAIN_ID'])
    run, _ = demo('--scene', 'faces', '--empty')           # seed 0, the default (README's)
    out = run.stdout
    assert run.returncode == 0, out + run.stderr
    absent = re.search(r'^absent(?:, forced by the fixation budget)?: nobody is here, '
                       r'probability (\d\.\d+) that nobody is here, after (\d+) fixations? '
                       r'\((?:reached|below) the confidence 0\.99\)$', out, re.M)
    assert absent and 'found:' not in out, out
    assert int(absent.group(2)) == len(FIXATION.findall(out))
    assert 'the scene camera showed a scene with nobody in it: that is right' in out
    assert 'stopped all 3 nodes' in out and node_processes(domain) == []


# The face demo outputs the README shows, by their command, and its options (each demo is
# deterministic for its seed: the scene and the detector).
README_DEMOS = [('ipomdp-gaze demo --scene faces', ('--scene', 'faces')),
                ('ipomdp-gaze demo --scene faces --empty', ('--scene', 'faces', '--empty'))]


@pytest.mark.parametrize('command, options', README_DEMOS, ids=['faces', 'faces-empty'])
def test_the_readme_shows_what_the_face_demo_prints(demo, command, options):
    """Issue 35: the README showed a demo output the command no longer printed."""
    run, _ = demo(*options)
    assert run.returncode == 0, run.stdout + run.stderr
    shown = _shown_by(command)
    assert _contains(shown, run.stdout.splitlines()), \
        'README shows:\n' + '\n'.join(shown) + '\nprinted:\n' + run.stdout


@pytest.mark.parametrize('options, figure', sorted(DEMO_FIGURES.items()),
                         ids=[Path(f).stem for _, f in sorted(DEMO_FIGURES.items())])
def test_a_readme_figure_demo_command_still_draws_it(demo, options, figure):
    """Issue 35: a README figure's caption command draws a PNG of the committed figure's size."""
    import cv2
    run, plots = demo(*options)
    assert run.returncode == 0, run.stdout + run.stderr
    out = plots / Path(figure).name
    # the note goes to stderr: stdout is the demo's transcript, the same with --plot or without
    assert f'ipomdp-gaze demo: wrote {out}\n' in run.stderr and 'wrote' not in run.stdout
    drawn, shipped = cv2.imread(str(out)), cv2.imread(str(REPO / figure))
    assert drawn is not None, f'{options} drew nothing at {out}'
    assert drawn.shape == shipped.shape
