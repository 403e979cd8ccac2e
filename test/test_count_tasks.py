# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Count models through every consumer: evaluate, train, policy files, search and the gym env."""
import json
import subprocess
import sys

from ipomdp_gaze.cli import main
from ipomdp_gaze.files.observation_file import fingerprint, load_observation, save_observation
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import CountObservation
from ipomdp_gaze.policies.policy_file import load_policy, load_policy_spec
from ipomdp_gaze.policies.registry import build_policy
import ipomdp_gaze.simulation.gym  # noqa: F401  (registers the environment)
from ipomdp_gaze.simulation.gym import VisualSearchEnv
import numpy as np
import pytest

GRID = Grid(4, 4, 1.0)


def count_model(seed=0, strength=3.0):
    """Tables where counts rise near the target, more sharply at small offsets."""
    rng = np.random.default_rng(seed)
    null = rng.dirichlet(np.full(5, 4.0), size=GRID.shape)
    null = np.sort(null, axis=2)[:, :, ::-1]                     # few detections without it
    target = null.copy()
    dr, dc = np.meshgrid(np.arange(4), np.arange(4), indexing='ij')
    boost = strength * np.exp(-(dr + dc))[:, :, None] * np.arange(5)
    target = target * np.exp(boost)
    target /= target.sum(axis=2, keepdims=True)
    return CountObservation(GRID, target, null)


@pytest.fixture(scope='module')
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp('counts')
    return {'model': save_observation(folder / 'faces.yaml', count_model(0)),
            'other': save_observation(folder / 'other.yaml', count_model(1, 2.0)),
            'folder': folder}


def run_cli(*args):
    return subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def test_evaluate_on_a_count_model(files, tmp_path, capsys):
    out = tmp_path / 'eval.json'
    assert main(['evaluate', '--observation', str(files['model']), '--policy', 'map',
                 '--policy', 'elm', '--policy', 'random', '--episodes', '400',
                 '--json', str(out)]) == 0
    data = json.loads(out.read_text())
    assert 'fpoc' not in data and data['observation']['model'] == 'counts'
    assert data['observation']['sha256'] == fingerprint(load_observation(files['model']))
    assert data['grid']['rows'] == 4 and set(data['policies']) == {'map', 'elm', 'random'}
    assert data['policies']['elm']['fixations_to_90'] < data['policies']['random'][
        'fixations_to_90']
    assert 'count model' in capsys.readouterr().out


@pytest.mark.parametrize('args, message', [
    (['--grid', '5x5'], '--grid cannot be combined with --observation'),
    (['--fpoc', 'camera'], '--fpoc cannot be combined with --observation'),
    (['--policy', 'greedy'], 'greedy (the ideal searcher) needs the Gaussian model'),
])
def test_count_task_errors_are_one_line(files, args, message):
    out = run_cli('evaluate', '--observation', files['model'], '--episodes', 10, *args)
    assert out.returncode == 2 and 'Traceback' not in out.stderr
    assert message in out.stderr.strip().splitlines()[-1]


def test_a_malformed_observation_file_is_one_line(tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('format: ipomdp_gaze/observation-v1\nmodel: counts\n')
    out = run_cli('evaluate', '--observation', bad)
    assert out.returncode == 2 and 'Traceback' not in out.stderr
    assert out.stderr.strip().splitlines()[-1].endswith('missing key grid')


def test_train_on_a_count_model_names_it_and_resumes(files, tmp_path):
    policy = tmp_path / 'k.yaml'
    assert main(['train', '--observation', str(files['model']), '--epochs', '4',
                 '--eval-every', '2', '--eval-episodes', '50', '--final-episodes', '200',
                 '--out', str(policy), '--quiet']) == 0
    spec = load_policy_spec(policy)
    assert spec.fpoc is None and spec.observation['model'] == 'counts'
    assert spec.observation['name'] == 'faces'
    assert spec.observation['sha256'] == fingerprint(load_observation(files['model']))
    assert spec.evaluation['episodes'] == 200
    assert main(['train', '--resume', str(policy), '--observation', str(files['model']),
                 '--epochs', '6', '--final-episodes', '0', '--quiet']) == 0
    assert load_policy_spec(policy).training['epochs'] == 6
    missing = run_cli('train', '--resume', policy, '--epochs', 8)
    assert missing.returncode == 2 and '--observation FILE to resume' in missing.stderr
    other = run_cli('train', '--resume', policy, '--observation', files['other'], '--epochs', 8)
    assert other.returncode == 2 and 'is not the model' in other.stderr


def test_policy_files_are_checked_against_the_count_model(files, tmp_path):
    policy = tmp_path / 'p.yaml'
    assert main(['train', '--observation', str(files['model']), '--epochs', '2',
                 '--final-episodes', '0', '--out', str(policy), '--quiet']) == 0
    same, other = load_observation(files['model']), load_observation(files['other'])
    warnings = []
    load_policy(policy, grid=GRID, fpoc=same, warn=warnings.append)
    assert warnings == []
    build_policy('learned', GRID, other, file=str(policy), warn=warnings.append)
    assert len(warnings) == 1 and 'trained for count model faces' in warnings[0]
    from ipomdp_gaze.model.fpoc import make_fpoc
    load_policy(policy, grid=GRID, fpoc=make_fpoc('human'), warn=warnings.append)
    assert 'used with FPOC' in warnings[-1]


def test_search_and_the_gym_env_take_a_count_model(files, capsys):
    assert main(['search', '--observation', str(files['model']), '--policy', 'elm',
                 '--target', '5', '--seed', '2', '--confidence', '0.99']) == 0
    assert 'found: the target is most likely at' in capsys.readouterr().out
    env = VisualSearchEnv(observation=str(files['model']), observe='evidence')
    obs, info = env.reset(seed=3, options={'target': 6})
    assert env.grid.shape == (4, 4) and obs['evidence'].shape == (4, 4)
    for _ in range(12):
        obs, reward, terminated, truncated, info = env.step(6)
        assert np.all(obs['evidence'] == np.floor(obs['evidence']))        # counts
        if terminated:
            break
    assert info['map_cell'] == 6
    with pytest.raises(ValueError, match='disagree'):
        VisualSearchEnv(rows=5, cols=5, observation=load_observation(files['model']))
