# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The ``ipomdp-gaze`` command line: help, JSON output and one-line errors."""
import json
import re
import subprocess
import sys

from ipomdp_gaze.cli import main
import numpy as np
import pytest


def run_cli(*args):
    return subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', *args],
                          capture_output=True, text=True, timeout=120)


def test_help_lists_subcommands():
    out = run_cli('--help')
    assert out.returncode == 0
    for name in ('evaluate', 'search', 'demo'):
        assert name in out.stdout
    assert re.findall(r'^    (\w+)', out.stdout, re.M) == [
        'evaluate', 'search', 'find', 'train', 'calibrate', 'reproduce', 'demo', 'record',
        'reindex', 'replay', 'controller', 'camera', 'detector', 'scene_camera', 'recorder']


@pytest.mark.parametrize('command, node', [('controller', 'gaze_controller'),
                                           ('camera', 'simulated_camera'),
                                           ('detector', 'foveal_detector'),
                                           ('scene_camera', 'scene_camera'),
                                           ('recorder', 'recorder')])
def test_node_subcommands_run_their_node(command, node, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([command, '--help'])
    assert exit_info.value.code == 0
    out = ' '.join(capsys.readouterr().out.split())
    assert f'usage: ipomdp-gaze {command} [-h] [--ros-args ...]' in out
    assert f'Run the {node} node, exactly as `ros2 run ipomdp_gaze {command}` does' in out


@pytest.mark.parametrize('command', [['controller'], ['camera'], ['detector'], ['scene_camera'],
                                     ['recorder'], ['record', 'bag'], ['find', 'photo.png'],
                                     ['evaluate']], ids=lambda c: c[0])
def test_an_unknown_flag_is_refused_in_the_name_of_the_command_run(command, capsys):
    """QA: ``ipomdp-gaze controller --foo`` said ``ipomdp-gaze: error: ...``, not its command."""
    with pytest.raises(SystemExit) as exit_info:
        main([*command, '--foo'])
    assert exit_info.value.code == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f'ipomdp-gaze {command[0]}: error: unrecognized arguments: --foo']


@pytest.mark.parametrize('args, message', [
    (['evaluate', '--policy', 'saliency'], "invalid choice: 'saliency'"),
    (['evaluate', '--grid', '7by7'], 'grid must look like ROWSxCOLS'),
    (['evaluate', '--fpoc-param', 'bogus=1'], "unknown FPOC parameter 'bogus'"),
    (['evaluate', '--fpoc-param', 'foveal_dprime=-2'], 'foveal_dprime must be finite and > 0'),
    (['evaluate', '--fpoc-param', 'foveal_dprime'], 'expected name=value'),
    (['evaluate', '--episodes', '0'], 'expected a positive integer'),
    (['evaluate', '--bootstrap', '1'], 'expected at least 10 resamples'),
    (['reproduce', '--bootstrap', '9'], 'expected at least 10 resamples'),
    (['evaluate', '--spacing-deg', 'nan'], 'expected a positive number'),
    (['evaluate', '--fpoc', 'laser'], "invalid choice: 'laser'"),
    (['search', '--target', '99'], 'outside the 49-cell grid'),
    (['demo', '--fovea'], '--fovea goes with --scene faces'),
    (['demo', '--scene', 'faces', '--target', '1,2'], '--target is for --scene simulated'),
    (['demo', '--scene', 'faces', '--fpoc', 'human'], '--fpoc is for --scene simulated'),
    (['demo', '--scene', 'pictures'], "invalid choice: 'pictures'"),
    (['calibrate', '--pan-tilt', '--out', 'm.yaml', '--images', 'x'],
     '--images is for the image task'),
])
def test_bad_arguments_exit_nonzero_with_one_line(args, message):
    out = run_cli(*args)
    assert out.returncode != 0
    lines = out.stderr.strip().splitlines()
    assert message in lines[-1]
    assert 'Traceback' not in out.stderr
    assert len([ln for ln in lines if 'error' in ln]) == 1


def test_evaluate_writes_the_documented_json(tmp_path, capsys):
    path = tmp_path / 'out.json'
    rc = main(['evaluate', '--grid', '4x4', '--policy', 'map', '--policy', 'elm',
               '--episodes', '300', '--seed', '3', '--json', str(path), '--bootstrap', '50'])
    assert rc == 0
    data = json.loads(path.read_text())
    assert list(data) == ['grid', 'fpoc', 'episodes', 'horizon', 'seed', 'policies']
    assert data['grid'] == {'rows': 4, 'cols': 4, 'spacing_deg': 0.42}
    assert data['fpoc'] == {'model': 'human', 'noise_contrast': 0.2, 'foveal_dprime': 2.0}
    assert data['horizon'] == 16 and data['episodes'] == 300 and data['seed'] == 3
    for name in ('map', 'elm'):
        r = data['policies'][name]
        assert list(r) == ['episodes', 'fixations_to_90', 'ci95', 'percent_correct']
        assert len(r['percent_correct']) == 16
        assert r['ci95'][0] <= r['fixations_to_90'] <= r['ci95'][1]
    assert 'elm' in capsys.readouterr().out


def test_search_prints_each_fixation(capsys):
    assert main(['search', '--grid', '5x5', '--target', '7', '--seed', '1']) == 0
    out = capsys.readouterr().out
    assert 'fixation   1: looked at' in out and 'found: the target is most likely at' in out
    # Issue 35: one cell format, (row, col) as the demo writes it, and how the search ended.
    assert re.search(r'^fixation   1: looked at \(\d+, \d+\)  ->  most likely \(\d+, \d+\) p=',
                     out, re.M), out
    assert re.search(r'^found: the target is most likely at \(\d+, \d+\), probability '
                     r'\d\.\d+, after \d+ fixations? \(reached the confidence 0\.95\), which '
                     r'is (right|wrong)$', out, re.M), out
    assert main(['search', '--grid', '7x7', '--seed', '3', '--max-fixations', '2']) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.startswith('gave up: no cell reached the confidence 0.95 at the fixation '
                           'budget; the target is most likely at (')


def test_evaluate_draws_targets_from_a_prior_file(tmp_path, capsys):
    """QA (a researcher): a centre-biased task; the prior is the targets' and the belief's."""
    point = tmp_path / 'point.txt'
    point.write_text('# all mass on (1, 2)\n0 0 0\n0, 0, 5\n0 0 0\n')
    out = tmp_path / 'out.json'
    assert main(['evaluate', '--grid', '3x3', '--policy', 'map', '--policy', 'random',
                 '--episodes', '200', '--prior', str(point), '--quiet', '--json',
                 str(out)]) == 0
    assert capsys.readouterr().out.splitlines()[0].endswith(f', prior {point}')
    data = json.loads(out.read_text())
    assert data['prior'] == [[0, 0, 0], [0, 0, 1], [0, 0, 0]]
    huge = tmp_path / 'huge.txt'                # weights near the float limit: their sum is inf
    huge.write_text('1e308 1e308 1e308\n' * 3)
    assert main(['evaluate', '--grid', '3x3', '--episodes', '10', '--prior', str(huge),
                 '--quiet', '--json', str(out)]) == 0
    assert json.loads(out.read_text())['prior'] == [[1 / 9] * 3] * 3
    for name in ('map', 'random'):              # the belief starts sure: right from the start
        assert data['policies'][name]['percent_correct'] == [1.0] * 9
    # Targets follow the prior: weights 1 and 3 on two cells, the belief split 1:3 as well.
    two = tmp_path / 'two.txt'
    two.write_text('1 0 0\n0 0 0\n0 0 3\n')
    assert main(['evaluate', '--grid', '3x3', '--policy', 'center', '--episodes', '4000',
                 '--fpoc', 'table', '--fpoc-param', 'dprime=[0,0]', '--fpoc-param',
                 'ecc_deg=[0,1]', '--prior', str(two), '--quiet', '--json', str(out)]) == 0
    capsys.readouterr()
    from ipomdp_gaze.simulation.simulate import draw_targets
    prior = np.asarray(json.loads(out.read_text())['prior']).ravel()
    targets = draw_targets(9, 4000, 0, prior)
    assert set(targets) == {0, 8}
    share = np.mean(targets == 8)               # binomial sd 0.007 at 4000 draws
    assert abs(share - 0.75) < 0.03
    # With d' = 0 no frame moves the belief: its MAP is the likelier cell, right on its share.
    correct = json.loads(out.read_text())['policies']['center']['percent_correct']
    assert correct == [pytest.approx(share, abs=1e-6)] * 9


@pytest.mark.parametrize('text, message', [
    ('1 1\n1 1\n', 'a 3x3 grid needs 3 lines of 3 weights, got 2 lines of 2'),
    ('1 1 1\n1 x 1\n1 1 1\n', "not a number in '1 x 1'"),
    ('1 1 1\n1 -1 1\n1 1 1\n', 'weights must be >= 0: cell (1, 1) is -1'),
    ('0 0 0\n0 0 0\n0 0 0\n', 'weights must not all be 0 (the target would be in no cell)'),
    ('1e308 1e308 1e308\n1e308 1e308 1e308\n1e308 1e308 x\n', "not a number in '1e308 1e308 x'"),
])
def test_a_bad_prior_file_is_one_line(tmp_path, capsys, text, message):
    path = tmp_path / 'prior.txt'
    path.write_text(text)
    assert main(['evaluate', '--grid', '3x3', '--episodes', '10', '--prior', str(path)]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines()[-1].endswith(message) and err.count('\n') == 1, err
    assert main(['evaluate', '--scenes', 'faces-420', '--prior', str(path)]) == 2
    assert '--prior' in capsys.readouterr().err


def test_fixations_to_90_start_at_the_prior_s_chance(tmp_path, capsys):
    """QA: before any fixation the prior's MAP cell is right with its probability, not 1/N."""
    point, sure = tmp_path / 'point.txt', tmp_path / 'sure.txt'
    point.write_text('0 0 0\n0 1 0\n0 0 0\n')
    sure.write_text('92 1 1\n1 1 1\n1 1 1\n')          # 0.92 on (0, 0)
    out = tmp_path / 'out.json'
    assert main(['evaluate', '--grid', '3x3', '--policy', 'map', '--policy', 'random',
                 '--paired', '--episodes', '200', '--prior', str(point), '--quiet', '--json',
                 str(out)]) == 0
    data = json.loads(out.read_text())
    for name in ('map', 'random'):              # right at 0 fixations already (was 0.90)
        assert data['policies'][name]['fixations_to_90'] == 0.0
        assert data['policies'][name]['ci95'] == [0.0, 0.0]
    assert data['paired']['random - map']['difference'] == 0.0
    # d' = 0: no frame moves the belief, percent correct stays at 0.92 from t = 0 on.
    assert main(['evaluate', '--grid', '3x3', '--episodes', '2000', '--fpoc', 'table',
                 '--fpoc-param', 'dprime=[0,0]', '--fpoc-param', 'ecc_deg=[0,1]', '--prior',
                 str(sure), '--quiet', '--json', str(out)]) == 0
    capsys.readouterr()
    assert json.loads(out.read_text())['policies']['map']['fixations_to_90'] == 0.0


def test_a_prior_file_from_a_spreadsheet_is_read(tmp_path, capsys):
    """QA: a UTF-8 byte-order mark, Windows line ends, tabs and trailing commas are read."""
    path = tmp_path / 'prior.csv'
    path.write_bytes(b'\xef\xbb\xbf0,0,0,\r\n0\t0\t5\t\r\n0,0,0,\r\n')
    out = tmp_path / 'out.json'
    assert main(['evaluate', '--grid', '3x3', '--episodes', '10', '--prior', str(path),
                 '--quiet', '--json', str(out)]) == 0, capsys.readouterr().err
    assert json.loads(out.read_text())['prior'] == [[0, 0, 0], [0, 0, 1], [0, 0, 0]]


def test_search_draws_its_target_from_a_prior_and_starts_there(tmp_path, capsys):
    """QA (a researcher): one trial of a centre-biased task; a cell it rules out is refused."""
    prior = tmp_path / 'prior.txt'
    prior.write_text('0 0 0\n0 0 1\n0 0 0\n')
    assert main(['search', '--grid', '3x3', '--prior', str(prior), '--seed', '4']) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == 'target hidden at cell 5 (1, 2) of a 3x3 grid'
    # The belief starts sure: p 1 after the first frame, entropy 0.00 (never -0.00).
    assert re.search(r'most likely \(1, 2\) p=1\.000  entropy 0\.00 nats  right$', lines[1])
    assert main(['search', '--grid', '3x3', '--prior', str(prior), '--target', '0,0']) == 2
    [line] = capsys.readouterr().err.strip().splitlines()
    assert line.endswith(f'--target (0, 0) is a cell --prior {prior} rules out (weight 0): '
                         'the search could never find it there')
    wide = tmp_path / 'wide.txt'
    wide.write_text('1 1 1\n1 1 1\n')
    assert main(['search', '--grid', '3x3', '--prior', str(wide)]) == 2
    assert capsys.readouterr().err.strip().endswith('a 3x3 grid needs 3 lines of 3 weights, '
                                                    'got 2 lines of 3')
    # Seeds draw their targets from the prior: only the two cells it allows.
    two = tmp_path / 'two.txt'
    two.write_text('1 0 0\n0 0 0\n0 0 1\n')
    seen = set()
    for seed in range(12):
        assert main(['search', '--grid', '3x3', '--prior', str(two), '--seed', str(seed)]) == 0
        seen.add(capsys.readouterr().out.splitlines()[0])
    assert seen == {'target hidden at cell 0 (0, 0) of a 3x3 grid',
                    'target hidden at cell 8 (2, 2) of a 3x3 grid'}


def test_search_runs_a_target_absent_trial(capsys):
    """QA (a researcher): one target-absent trial from the CLI, with the absent hypothesis."""
    assert main(['search', '--grid', '7x7', '--seed', '3', '--empty', '--absent-prior',
                 '0.5']) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == 'no target: an empty 7x7 grid (a target-absent trial)'
    assert all('P(absent)=' in line for line in lines[1:-1])
    assert re.fullmatch(r'absent: no target, P\(absent\) 0\.9\d\d, after \d+ fixations? '
                        r'\(reached the confidence 0\.95\), which is right', lines[-1]), lines[-1]
    # With a target the same prior answers found (the seed's target), each line with P(absent).
    assert main(['search', '--grid', '7x7', '--seed', '3', '--absent-prior', '0.5']) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-1].startswith('found: the target is most likely at (6, 5)')
    assert lines[-1].endswith('which is right') and 'P(absent)=' in lines[-2]
    # Without the absent hypothesis an empty scene can only end wrong, at the budget.
    assert main(['search', '--grid', '7x7', '--seed', '3', '--empty', '--max-fixations',
                 '5']) == 0
    assert capsys.readouterr().out.strip().endswith('which is wrong')
    assert main(['search', '--grid', '7x7', '--empty', '--target', '1,1']) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].endswith(
        '--empty is a scene without a target: leave out --target')


def test_a_target_absent_trial_that_gives_up_answers_as_its_lines_do(capsys, monkeypatch):
    """QA: the last line named the MAP cell 'wrong' after lines saying absent, 'right'."""
    assert main(['search', '--grid', '7x7', '--seed', '3', '--empty', '--absent-prior', '0.5',
                 '--max-fixations', '4']) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-2].endswith('P(absent)=0.464  entropy 1.68 nats  right'), lines[-2]
    assert lines[-1] == ('gave up: no cell reached the confidence 0.95 at the fixation budget; '
                         'most likely no target, P(absent) 0.464, after 4 fixations, which is '
                         'right')
    # The figure of an absent answer gives P(absent), not the MAP cell's p (0.018 here).
    from ipomdp_gaze.commands import search
    titles = []
    monkeypatch.setattr(search, 'plot_search', lambda *a: titles.append(a[4]))
    assert main(['search', '--grid', '7x7', '--seed', '3', '--empty', '--absent-prior', '0.5',
                 '--plot', 'unused.png']) == 0
    assert 'absent, P(absent)=0.974, 13 fixations (no target)' in titles[0], titles


@pytest.mark.parametrize('args, message', [
    # The search settings: the message of SearchSettings, as the node's (one schema).
    (['evaluate', '--motion-sigma-cells', '-0.5'],
     'motion.sigma_cells must be finite and >= 0, got -0.5'),
    (['evaluate', '--motion-sigma-cells', 'nan'],
     'motion.sigma_cells must be finite and >= 0, got nan'),
    (['evaluate', '--jump-prob', '1'],
     'motion.jump_prob must be a probability in [0, 1), got 1.0'),
    (['evaluate', '--absent-prior', '-0.1'],
     'absent.prior must be a probability in [0, 1), got -0.1'),
    (['evaluate', '--absent-rate', '1.5'], "expected a probability in [0, 1), got '1.5'"),
    (['evaluate', '--confidence', '1.0'], 'confidence must be between 0 and 1 (exclusive)'),
    (['evaluate', '--max-fixations', '-1'], 'search.max_fixations must be an integer >= 0'),
    (['evaluate', '--horizon', '5', '--max-fixations', '9'], 'beyond the horizon 5'),
    (['train', '--epochs', '1', '--out', 'x.yaml', '--jump-prob', '2'],
     'motion.jump_prob must be a probability in [0, 1), got 2.0'),
    (['train', '--epochs', '1', '--out', 'x.yaml', '--motion-sigma-cells', '-1'],
     'motion.sigma_cells must be finite and >= 0, got -1.0'),
    # Seeds go to the nodes as int64 parameters; a bag's folder is checked before any node runs.
    (['demo', '--scene', 'faces', '--seed', str(2 ** 63)],
     f"expected an integer from 0 to 2^63 - 1, got '{2 ** 63}'"),
    (['demo', '--scene', 'faces', '--record', f'{__file__}/bag'],
     f'--record {__file__}/bag: {__file__} is not a folder'),
])
def test_bad_scene_arguments_exit_2_with_one_line(args, message):
    out = run_cli(*args)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert message in lines[-1]
    assert 'Traceback' not in out.stderr
    assert len([ln for ln in lines if 'error' in ln]) == 1


def test_evaluate_records_the_scene_options_and_decisions(tmp_path):
    path = tmp_path / 'scene.json'
    rc = main(['evaluate', '--grid', '4x4', '--policy', 'elm', '--policy', 'map',
               '--episodes', '400', '--seed', '2',
               '--bootstrap', '50', '--motion-sigma-cells', '0.4', '--jump-prob', '0.01',
               '--absent-prior', '0.3', '--absent-rate', '0.2', '--confidence', '0.9',
               '--max-fixations', '12', '--compare-prediction', '--json', str(path)])
    assert rc == 0
    data = json.loads(path.read_text())
    assert list(data) == ['grid', 'fpoc', 'episodes', 'horizon', 'seed', 'motion_sigma_cells',
                          'jump_prob', 'absent_prior', 'absent_rate', 'confidence',
                          'max_fixations', 'policies', 'tracking_paired', 'prediction_gain']
    assert (data['motion_sigma_cells'], data['jump_prob'], data['absent_prior'],
            data['absent_rate'], data['confidence'], data['max_fixations'],
            data['horizon']) == (0.4, 0.01, 0.3, 0.2, 0.9, 12, 12)
    assert list(data['policies']) == ['elm', 'map', 'elm (no prediction)', 'map (no prediction)']
    assert data['tracking_paired']['map']['minus'] == 'elm'
    d = data['policies']['elm']['decisions']
    groups = d['present']['searches'], d['absent']['searches']
    assert sum(groups) == 400 and 40 < groups[1] < 130
    for group in ('all', 'present', 'absent'):
        total = sum(d[group][k]['count'] for k in ('right', 'wrong_found', 'wrong_absent',
                                                   'gave_up'))
        assert total == d[group]['searches']
    assert d['decided']['searches'] == 400 - d['all']['gave_up']['count']
    assert d['absent']['wrong_absent']['count'] == 0
    tracking = data['policies']['elm']['tracking']['tracking_accuracy']
    assert 0 < tracking['value'] <= 1 and tracking['ci95'][0] <= tracking['value']
    assert data['prediction_gain']['elm']['ci95'][0] <= data['prediction_gain']['elm'][
        'difference'] <= data['prediction_gain']['elm']['ci95'][1]


def test_explicit_zero_scene_options_change_no_number(tmp_path):
    """The paper's task is the default: zeros give today's JSON plus the new keys only."""
    plain, zeros = tmp_path / 'plain.json', tmp_path / 'zeros.json'
    common = ['evaluate', '--grid', '5x5', '--policy', 'elm', '--policy', 'random',
              '--episodes', '600', '--seed', '4', '--bootstrap', '50']
    assert main(common + ['--json', str(plain)]) == 0
    assert main(common + ['--motion-sigma-cells', '0', '--jump-prob', '0', '--absent-prior', '0',
                          '--absent-rate', '0', '--json', str(zeros)]) == 0
    a, b = json.loads(plain.read_text()), json.loads(zeros.read_text())
    for key in ('motion_sigma_cells', 'jump_prob', 'absent_prior', 'absent_rate', 'confidence',
                'max_fixations'):
        b.pop(key)
    for policy in b['policies'].values():
        assert policy.pop('decisions')['absent']['searches'] == 0
    assert json.dumps(a) == json.dumps(b)


def test_demo_help_says_the_target_follows_the_seed(capsys):
    """Issue 35: --help said the target is random; --seed 0 (the default) always hides (9, 7)."""
    with pytest.raises(SystemExit):
        main(['demo', '--help'])
    out = ' '.join(capsys.readouterr().out.split())
    assert '(default: random)' not in out
    assert 'drawn from --seed, so the same cell for the same seed: (9, 7) for seed 0' in out


def test_search_plot_title_says_how_the_search_ended(monkeypatch, tmp_path):
    import ipomdp_gaze.commands.search as search
    titles = []
    monkeypatch.setattr(search, 'plot_search', lambda *args: titles.append(args[4]))
    assert main(['search', '--grid', '7x7', '--seed', '3', '--max-fixations', '2', '--plot',
                 str(tmp_path / 's.png')]) == 0
    assert re.fullmatch(r'7x7, human FPOC, elm\ngave up at the fixation budget, p=0\.\d{3}, 2 '
                        r'fixations \(star = target\)', titles[0]), titles
    assert main(['search', '--grid', '3x3', '--fpoc-param', 'foveal_dprime=0.01', '--seed', '1',
                 '--max-fixations', '0', '--plot', str(tmp_path / 's.png')]) == 0
    assert titles[1].endswith('\ngave up at the cap of an offline search (100 per cell), '
                              'p=0.118, 900 fixations (star = target)'), titles


def _kernel_file(path, action='argmax'):
    """Write the shipped 7x7 kernel to ``path`` with its action rule set to ``action``."""
    import yaml
    from ipomdp_gaze.policies.policy_file import resolve_source
    spec = yaml.safe_load(resolve_source('human-7x7-infomax').read_text())
    spec['action'] = action
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(spec))
    return path


def test_two_policy_rows_of_one_name_are_refused_before_any_episode(tmp_path):
    first = _kernel_file(tmp_path / 'a' / 'pol.yaml')
    second = _kernel_file(tmp_path / 'b' / 'pol.yaml')
    elm = _kernel_file(tmp_path / 'elm.yaml')
    for args, words in ((['--policy-file', first, '--policy-file', second],
                         f"--policy-file {second}: its row would be named 'pol', as "
                         f"--policy-file {first}'s"),
                        (['--policy', 'elm', '--policy-file', elm],
                         "named 'elm', as --policy elm's")):
        out = run_cli('evaluate', '--episodes', '50', *map(str, args))
        assert out.returncode == 2 and words in out.stderr and not out.stdout
        assert 'Traceback' not in out.stderr


def test_a_policy_file_that_samples_is_sampled_by_search_and_evaluate(tmp_path):
    argmax = _kernel_file(tmp_path / 'argmax.yaml')
    sample = _kernel_file(tmp_path / 'sample.yaml', 'sample')
    searches = [run_cli('search', '--policy-file', str(path), '--seed', '2').stdout
                for path in (argmax, sample, argmax)]
    assert searches[0] == searches[2] != searches[1]
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.policies.registry import build_policy
    grid = Grid(7, 7, 0.42)
    assert build_policy('learned', grid, make_fpoc('human'), file=str(sample)).action == 'sample'
    assert build_policy('learned', grid, make_fpoc('human'), file=str(sample),
                        action='argmax').action == 'argmax'
    rows = run_cli('evaluate', '--policy-file', str(argmax), '--policy-file', str(sample),
                   '--episodes', '400', '--seed', '1').stdout.splitlines()
    argmax_row, sample_row = ([line.split()[2:] for line in rows if line.startswith(name)][0]
                              for name in ('argmax ', 'sample '))
    assert argmax_row != sample_row


def test_the_packages_own_warnings_are_one_line_each():
    out = run_cli('evaluate', '--grid', '7x7', '--spacing-deg', '1.0', '--policy-file',
                  'human-7x7-infomax', '--episodes', '50')
    assert out.returncode == 0, out.stderr
    warned = [line for line in out.stderr.splitlines() if 'warning' in line.lower()]
    assert len(warned) == 1 and warned[0].startswith('ipomdp-gaze evaluate: warning: ')
    assert 'policy was trained at spacing_deg 0.42 but is used at 1.0' in warned[0]
    assert 'PolicyFileWarning' not in out.stderr and 'check_task' not in out.stderr


def test_a_plot_extension_in_capitals_is_written(tmp_path):
    out = run_cli('search', '--grid', '5x5', '--seed', '1', '--plot', str(tmp_path / 'S.PNG'))
    assert out.returncode == 0, out.stderr
    assert (tmp_path / 'S.PNG').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


@pytest.mark.parametrize('args, words', [
    (['evaluate', '--grid', '7x7', '--policy', 'greedy', '--json', '{dir}'],
     '--json {dir}: is a directory'),
    (['evaluate', '--json', '-'], '--json -: evaluate prints its table to stdout'),
    (['search', '--plot', '{dir}/a.txt'], '--plot {dir}/a.txt: the extension names no format'),
    (['search', '--plot', '{dir}/noext'], 'the extension names no format'),
    (['calibrate', '--scenes', '3', '--out', '{dir}/good.yaml', '--plot', '{dir}/x.txt'],
     '--plot {dir}/x.txt: the extension names no format'),
    (['train', '--out', '{dir}/f.csv/x.yaml', '--epochs', '1'],
     '--out {dir}/f.csv/x.yaml: {dir}/f.csv is not a folder'),
    (['train', '--resume', 'human-7x7-infomax', '--epochs', '1600'],
     '--resume human-7x7-infomax: give --out PATH.yaml'),
    (['train', '--seeds', '1,1', '--out', '{dir}/t.yaml', '--epochs', '1'], 'each value once'),
    (['train', '--init-elm', '1e308', '--family', 'conv', '--epochs', '1', '--out',
      '{dir}/x.yaml'], '--init-elm 1e+308: the ELM initialisation scale 1e+308 makes the '
                       'kernel overflow: give a smaller one'),
    (['evaluate', '--policy', 'map', '--policy', 'map'], '--policy map is given twice'),
    (['evaluate', '--scenes', 'pan-tilt', '--motion', 'walk', '--max-fixations', '3'],
     '--max-fixations: not used here: --motion walk runs the tracking configuration'),
    (['evaluate', '--scenes', 'pan-tilt', '--motion', 'walk', '--group-min-neighbors', '0'],
     '--group-min-neighbors: not used here'),
    (['evaluate', '--scenes', 'faces-420', '--paired'], '--paired: not used here'),
    (['evaluate', '--grid', '5x5', '--policy', 'elm', '--paired'],
     '--paired compares each policy after the first with the first: give two or more'),
    (['evaluate', '--grid', '5x5', '--compare', 'sweep', '--split', 'train', '--empty-scenes',
      '2'], '--compare, --empty-scenes, --split: not used here: only --scenes reads it'),
    (['evaluate', '--scenes', 'faces-420', '--observation', 'faces-420'],
     'with its shipped model; another model is tried with find, or on the pan-tilt scenes'),
    (['evaluate', '--scenes', 'faces-840', '--scene-model', 'faces-840'],
     '--scene-model is for --scenes pan-tilt; --scenes faces-840 runs its shipped model'),
    (['evaluate', '--scenes', 'pan-tilt', '--grid', '3x3', '--horizon', '5',
      '--motion-sigma-cells', '1'],
     '--grid, --horizon, --motion-sigma-cells: not used here: --scenes pan-tilt runs the real'),
    (['reproduce', '--out', '{dir}/rep', '--cache', '{dir}/f.csv', '--episodes', '50'],
     '--cache {dir}/f.csv: {dir}/f.csv is not a folder'),
    (['evaluate', '--scenes', 'pan-tilt', '--faces', '2', '--episodes', '1', '--policy', 'map'],
     '--faces rooms are searched by the many-target session'),
])
def test_an_output_or_option_that_cannot_serve_is_refused_before_any_work(tmp_path, args,
                                                                          words):
    (tmp_path / 'f.csv').write_text('epoch\n')
    out = run_cli(*[a.format(dir=tmp_path) for a in args])
    assert out.returncode == 2, out.stderr
    assert words.format(dir=tmp_path) in out.stderr.strip().splitlines()[-1]
    assert 'Traceback' not in out.stderr and not out.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ['f.csv']      # nothing written


def test_a_search_without_a_budget_that_reaches_its_cap_says_it_gave_up():
    out = run_cli('search', '--grid', '3x3', '--fpoc-param', 'foveal_dprime=0.01', '--seed', '1',
                  '--max-fixations', '0')
    assert out.returncode == 0, out.stderr
    last = out.stdout.strip().splitlines()[-1]
    assert last.startswith('gave up: no cell reached the confidence 0.95 after 900 fixations, '
                           'the cap of an offline search without a budget (100 per cell)')


def test_blas_runs_on_one_thread_unless_the_environment_says(monkeypatch):
    """QA: the logistic curve regenerated only with OPENBLAS_NUM_THREADS=1 (training's gemm)."""
    import os
    import subprocess
    from ipomdp_gaze.cli import OPENBLAS_THREAD_VARIABLES
    # The pin works only if numpy is not loaded before main() runs.
    run = subprocess.run([sys.executable, '-c', 'import sys, ipomdp_gaze.cli; '
                          "print('numpy' in sys.modules)"], capture_output=True, text=True,
                         check=True)
    assert run.stdout.strip() == 'False'
    names = (*OPENBLAS_THREAD_VARIABLES, 'MKL_NUM_THREADS')
    for name in names:
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv('MKL_NUM_THREADS', '4')      # not read by numpy's OpenBLAS: pinned still
    with pytest.raises(SystemExit):
        main(['--version'])
    assert os.environ['OPENBLAS_NUM_THREADS'] == os.environ['OMP_NUM_THREADS'] == '1'
    assert os.environ['MKL_NUM_THREADS'] == '4'
    # A user's own setting that OpenBLAS reads stands.
    for name in names:
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv('OMP_NUM_THREADS', '2')
    with pytest.raises(SystemExit):
        main(['--version'])
    assert 'OPENBLAS_NUM_THREADS' not in os.environ and os.environ['OMP_NUM_THREADS'] == '2'
