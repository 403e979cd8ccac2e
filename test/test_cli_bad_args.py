# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Bad arguments of find, evaluate, replay, reindex and calibrate: one line naming the user's flag.

Not argparse's words for the Python type (``invalid float value``), an exception class
(``IsADirectoryError``, ``NoneType``), numpy's own refusal (``Maximum allowed dimension
exceeded``) or a traceback (``calibrate --windows inf``: OverflowError); a value that is not
what the flag takes is refused, not cut (``--windows 2.5`` was 2), and an empty path is not the
current folder (``reindex ''`` rebuilt the bag of the folder it was run in).
"""
import pytest


def _one_line(run, command: str) -> str:
    assert run.returncode == 2, (run.stdout, run.stderr)
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith(f'ipomdp-gaze {command}: error: ')
    return lines[0][len(f'ipomdp-gaze {command}: error: '):]


@pytest.mark.parametrize('argv, message', [
    (['evaluate', '--confidence', 'x'], "argument --confidence: expected a number, got 'x'"),
    (['evaluate', '--max-fixations', '2.5'],
     "argument --max-fixations: expected an integer, got '2.5'"),
    (['evaluate', '--walk-duration-s', 'x'],
     "argument --walk-duration-s: expected a number, got 'x'"),
    (['evaluate', '--speed-deg-s', ''], "argument --speed-deg-s: expected a number, got ''"),
    (['evaluate', '--motion-sigma-cells', 'x'],
     "argument --motion-sigma-cells: expected a number, got 'x'"),
    (['find', 'x.png', '--absent-prior', 'half'],
     "argument --absent-prior: expected a number, got 'half'"),
    (['find', 'x.png', '--max-fixations', 'x'],
     "argument --max-fixations: expected an integer, got 'x'"),
    (['replay', 'bag', '--max-fixations', '1.5'],
     "argument --max-fixations: expected an integer, got '1.5'"),
    (['replay', 'bag', '--confidence', 'x'], "argument --confidence: expected a number, got 'x'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--absent-rate', 'x'],
     "argument --absent-rate: expected a number, got 'x'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--threshold', 'x'],
     "argument --threshold: expected a number, got 'x'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--pool-radius', 'x'],
     "argument --pool-radius: expected a number, got 'x'"),
    # OverflowError tracebacks, and whole numbers cut silently
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--windows', 'inf'],
     "argument --windows: expected comma-separated whole numbers, got 'inf'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--windows', '21,2.5'],
     "argument --windows: expected comma-separated whole numbers, got '21,2.5'"),
    (['calibrate', '--pan-tilt', '--scenes', '1', '--out', 'x.yaml', '--face-px', '30,1e400'],
     "argument --face-px: expected comma-separated whole numbers, got '30,1e400'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--scales', '1/0'],
     "argument --scales: expected comma-separated numbers, got '1/0'"),
    # an empty path is not the current folder
    (['replay', ''], "argument PATH: an empty bag path ('': an unset shell variable?)"),
    (['reindex', ' '], "argument PATH: an empty bag path (' ': an unset shell variable?)"),
    (['evaluate', '--prior', ''],
     "argument --prior: an empty file path ('': an unset shell variable?)"),
])
def test_a_bad_value_is_one_line_naming_the_flag(tmp_path, cli_here, argv, message):
    assert _one_line(cli_here(*argv, cwd=tmp_path), argv[0]) == message


def test_reindex_of_an_empty_path_leaves_the_current_folder_alone(tmp_path, cli_here):
    (tmp_path / 'run.mcap').write_bytes(b'\x89MCAP0\r\n')
    before = sorted(p.name for p in tmp_path.iterdir())
    assert _one_line(cli_here('reindex', '', cwd=tmp_path), 'reindex').startswith(
        'argument PATH: an empty bag path')
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_prior_file_that_cannot_be_read_says_why_not_the_exception(tmp_path, cli_here):
    """It said ``cannot read it (IsADirectoryError)`` or ``(FileNotFoundError)``."""
    folder = tmp_path / 'priors'
    folder.mkdir()
    assert _one_line(cli_here('evaluate', '--grid', '3x3', '--prior', folder), 'evaluate') == \
        f'--prior {folder}: cannot read it (a folder, not a file)'
    missing = tmp_path / 'none.txt'
    assert _one_line(cli_here('evaluate', '--grid', '3x3', '--prior', missing), 'evaluate') == \
        f'--prior {missing}: cannot read it (No such file or directory)'
    (tmp_path / 'latin1.txt').write_bytes(b'1 1 1\n\xe9')
    assert _one_line(cli_here('evaluate', '--grid', '3x3', '--prior', tmp_path / 'latin1.txt'),
                     'evaluate') == (f'--prior {tmp_path / "latin1.txt"}: cannot read it (not '
                                     'UTF-8 text)')


@pytest.mark.parametrize('text, kind', [('', 'nothing (an empty document)'),
                                        ('- 1\n- 2\n', 'a list'),
                                        ('garbage\n', 'one line of text'),
                                        ('3\n', 'the number 3')])
def test_a_yaml_file_that_is_not_a_mapping_says_what_it_is_in_yaml_words(tmp_path, cli_here,
                                                                         text, kind):
    """It named the Python type: ``got NoneType``, ``got str``."""
    path = tmp_path / 'model.yaml'
    path.write_text(text)
    assert _one_line(cli_here('evaluate', '--policy-file', path), 'evaluate') == \
        f'{path}: a policy file must be a YAML mapping, got {kind}'
    assert _one_line(cli_here('find', 'x.png', '--observation', path), 'find') == \
        f'{path}: an observation file must be a YAML mapping, got {kind}'


@pytest.mark.parametrize('flag', ['--episodes', '--max-fixations', '--horizon', '--bootstrap'])
def test_a_count_too_large_for_numpy_is_the_task_too_large(cli_here, flag):
    """The numpy text was said: ``Maximum allowed dimension exceeded``."""
    run = cli_here('evaluate', '--grid', '3x3', '--episodes', '3', '--jobs', '1', '--quiet',
                   flag, str(10 ** 21))
    assert _one_line(run, 'evaluate') == (
        'out of memory: the task is too large for this machine (a smaller --grid or fewer '
        '--episodes)')
