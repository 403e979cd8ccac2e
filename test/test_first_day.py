# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""A new user's first day with the README alone: no silent surprises (issue 24, item 1)."""
import ast
from pathlib import Path
import re
import subprocess
import sys

from ipomdp_gaze.cli import main
import pytest

ROOT = Path(__file__).resolve().parents[1]


def run_cli(*args):
    return subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', *args],
                          capture_output=True, text=True, timeout=120)


def _name(requirement: str) -> str:
    """Return the distribution name of a requirement, normalised (PEP 503)."""
    name = re.split(r'[<>=!~;\[ ]', requirement.strip().strip('"\''), maxsplit=1)[0]
    return re.sub(r'[-_.]+', '-', name).lower()


def _install_requires() -> set:
    tree = ast.parse((ROOT / 'setup.py').read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.keyword) and node.arg == 'install_requires':
            return {_name(ast.literal_eval(e)) for e in node.value.elts}
    raise AssertionError('setup.py has no install_requires')


def test_the_readme_install_line_installs_every_requirement():
    text = (ROOT / 'README.md').read_text()
    match = re.search(r'python3 -m pip install ((?:\\\n|[^\n])+)', text)
    assert match, 'README has no pip install line'
    words = match.group(1).replace('\\\n', ' ').split('#')[0].split()
    assert {_name(w) for w in words} == _install_requires()


def test_the_readme_lists_every_detector_parameter_in_order():
    from ipomdp_gaze.nodes.detector import detector_params
    text = (ROOT / 'README.md').read_text()
    section = text.split('### Parameters (`foveal_detector`)', 1)[1].split('\n#', 1)[0]
    rows = [line for line in section.splitlines() if line.startswith('| `')]
    names = [n for row in rows for n in re.findall(r'`([a-z_.]+)`', row.split('|')[1])]
    assert names == [p.name for p in detector_params()]


def test_version_prints_the_package_version(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(['--version'])
    assert exit_info.value.code == 0
    assert re.fullmatch(r'ipomdp-gaze \d+\.\d+\.\d+\n', capsys.readouterr().out)


def test_a_bare_command_prints_usage_and_fails():
    out = run_cli()
    assert out.returncode == 2
    assert out.stderr.startswith('usage: ipomdp-gaze')
    for command in ('evaluate', 'demo', 'record', 'replay'):
        assert f'    {command}' in out.stderr


def test_search_takes_row_col_and_still_a_flat_index():
    by_cell = run_cli('search', '--target', '3,4', '--seed', '1', '--max-fixations', '3')
    by_index = run_cli('search', '--target', '25', '--seed', '1', '--max-fixations', '3')
    assert by_cell.returncode == by_index.returncode == 0
    assert 'target hidden at cell 25 (3, 4)' in by_cell.stdout
    assert by_cell.stdout == by_index.stdout


@pytest.mark.parametrize('args, message', [
    (['search', '--target', '7,0'], '--target 7,0 is outside the 7x7 grid'),
    (['search', '--target', '49'], '--target 49 is outside the 49-cell grid'),
    (['search', '--target', 'a,b'], 'expected a cell as ROW,COL'),
    (['search', '--target', '1,2,3'], 'expected a cell as ROW,COL'),
])
def test_bad_cells_exit_with_one_line(args, message):
    out = run_cli(*args)
    assert out.returncode == 2
    assert out.stderr.strip().splitlines()[-1].endswith(message) or \
        message in out.stderr.strip().splitlines()[-1]
    assert 'Traceback' not in out.stderr


@pytest.mark.parametrize('args, message', [
    (['--policy', 'nonsense'], '--policy must be one of learned, map'),
    (['--target', '99,99'], '--target 99,99 is outside the 11x11 grid'),
    (['--scene', 'faces', '--policy', 'greedy'], 'needs the Gaussian model of an FPOC'),
    (['--domain-id', '300'], 'expected a ROS domain id in 0..101 or 215..232'),
    (['--domain-id', '150'], 'expected a ROS domain id in 0..101 or 215..232, got'),
    (['--plot', 'x.gif'], '--plot writes a .png file'),
])
def test_demo_refuses_bad_arguments_before_starting_any_node(args, message):
    out = run_cli('demo', *args)
    assert out.returncode == 2
    assert message in out.stderr.strip().splitlines()[-1]
    assert 'starting' not in out.stdout                # no node was started
    assert 'Traceback' not in out.stderr


@pytest.mark.parametrize('command', ['search', 'evaluate', 'train'])
def test_a_huge_grid_gives_one_clean_line_and_no_numpy_warning(command, tmp_path):
    out = run_cli(command, '--grid', '2000x2000', '--epochs', '1', '--out',
                  str(tmp_path / 'k.yaml')) if command == 'train' else \
        run_cli(command, '--grid', '2000x2000')
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        f'ipomdp-gaze {command}: error: a 2000x2000 grid has 4000000 cells; the offline '
        f'commands hold N x N matrices and take at most 4096 cells (e.g. 64x64)']


def test_find_names_a_policy_file_given_as_the_observation_model(tmp_path):
    policy = ROOT / 'policies' / 'kernels' / 'camera-11x11-infomax.yaml'
    out = run_cli('find', '--observation', str(policy), str(tmp_path / 'x.png'))
    assert out.returncode == 2
    assert out.stderr.strip() == (
        f'ipomdp-gaze find: error: {policy} is a policy file (ipomdp_gaze/policy-v1), not an '
        f'observation model (ipomdp_gaze/observation-v1): pass it as --policy-file (node: '
        f'policy.file)')


def test_the_human_fpoc_far_out_is_zero_without_a_numpy_warning():
    import warnings

    from ipomdp_gaze.model.fpoc import make_fpoc
    import numpy as np
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        d = make_fpoc('human')(np.array([0.0, 800.0]), np.array([0.0, 0.0]))
    assert d[0] == pytest.approx(2.0) and d[1] == 0.0


def test_the_linux_only_domain_ids_are_accepted():
    """QA: 215..232 are valid ROS domain ids on Linux; the demo refused them."""
    from ipomdp_gaze.commands.demo import domain_arg
    from ipomdp_gaze.harness.processes import ros_environment
    assert [domain_arg(str(d)) for d in (0, 101, 215, 232)] == [0, 101, 215, 232]
    # ... and the run's environment takes them too (review: the demo still refused 220)
    assert ros_environment(220, '/tmp', base={})['ROS_DOMAIN_ID'] == '220'
    with pytest.raises(ValueError, match='domain id must be in 0..101 or 215..232, got 150'):
        ros_environment(150, '/tmp', base={})
