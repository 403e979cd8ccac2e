# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Bad policy files on the command line: one clear error line, a non-zero exit, nothing executed.

``ipomdp-gaze evaluate --policy-file`` and ``search --policy-file`` get files that are not
YAML, not UTF-8, empty, of the wrong schema, shape or grid, with NaN or inf, with a
``!!python/object`` tag, a YAML alias bomb (10^9 numbers in 300 bytes) or nesting deep enough to
exhaust the parser's recursion. The node refuses the same files as ``policy.file``
(``test_robust_fuzz.py``). No module of the package unpickles anything or uses an unsafe YAML
loader.
"""
from __future__ import annotations

from pathlib import Path
import re
import subprocess
import sys

from conftest import REPO
from ipomdp_gaze.cli import main
import pytest
from robust_support import bad_policy_files

SOURCES = [p for folder in ('ipomdp_gaze', 'policies', 'msg_adapters')
           for p in sorted((REPO / folder).rglob('*.py'))]
COMMANDS = {
    'evaluate': ['evaluate', '--episodes', '20', '--horizon', '5', '--bootstrap', '10'],
    'search': ['search', '--max-fixations', '5'],
}


@pytest.fixture(scope='module')
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp('bad_policies')
    marker = folder / 'unsafe-loader-was-used'
    return bad_policy_files(folder, marker=marker), marker


@pytest.mark.parametrize('command', sorted(COMMANDS))
def test_every_bad_policy_file_gives_one_error_line_and_exit_2(files, command, capsys):
    cases, marker = files
    for name, (path, words) in cases.items():
        code = main(COMMANDS[command] + ['--policy-file', path])
        out, err = capsys.readouterr()
        assert code == 2, (name, out, err)
        assert err.count('\n') == 1 and err.startswith(f'ipomdp-gaze {command}: error: '), \
            (name, err)
        assert words in err, (name, err)
        assert 'Traceback' not in out + err
    assert not marker.exists()


@pytest.mark.parametrize('name', ['deep-nesting'])
def test_the_console_script_exits_with_one_line_too(files, name):
    cases, marker = files
    path, words = cases[name]
    proc = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'search', '--policy-file',
                           path], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count('\n') == 1 and words in proc.stderr, proc.stderr
    assert proc.stdout == ''
    assert not marker.exists()


@pytest.mark.parametrize('path', SOURCES, ids=lambda p: str(p.relative_to(REPO)))
def test_nothing_is_unpickled_and_yaml_is_read_safely(path: Path):
    text = path.read_text()
    for pattern in (r'\bpickle\b', r'\bmarshal\b', r'\bshelve\b', r'\bdill\b', r'\bjoblib\b',
                    r'allow_pickle\s*=\s*True', r'\bnp\.load\(', r'\btorch\.load\b',
                    r'yaml\.(unsafe_)?load\(', r'yaml\.(full_load|load_all|unsafe_load)',
                    r'\b(Unsafe|Full)?Loader\s*=', r'yaml\.(Unsafe|Full)?Loader\b'):
        assert not re.search(pattern, text), f'{path.name}: {pattern}'
    for call in re.findall(r'yaml\.(\w+)\(', text):
        assert call in ('safe_load', 'safe_dump'), f'{path.name}: yaml.{call}'
