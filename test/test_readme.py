# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The README's shown commands print what the README shows (issue 35, item 3; a first part).

A fenced block whose lines start with ``$ `` is a transcript: each command (with its backslash
continuation lines) is run in a fresh folder, in order, with ``.venv/bin/python`` and
``.venv/bin/ipomdp-gaze`` standing for this interpreter and its CLI; what it prints (stdout and
stderr, in order) must be the lines shown under it, numbers included, with times aside
(``seconds=...``). A ``...`` line stands for any lines. Transcripts of commands that start ROS
nodes (``demo``, ``record``, ``replay`` of a demo's bag) are left to the ROS tests; so are the
ones whose inputs the README does not create (``mine/``, ``photo.png``).
"""
from pathlib import Path
import re
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
FENCE = re.compile(r'^```[a-z]*\n(.*?)^```', re.S | re.M)
# What a transcript may run here: fast commands without ROS nodes.
RUNNABLE = re.compile(r'^\$ \.venv/bin/(python -c|ipomdp-gaze (find|search))\b')
TIMES = (re.compile(r'seconds=\d+\.\d+'), 'seconds=<time>')


def transcripts() -> list:
    """Return ``[(commands, outputs)]`` of the README's runnable transcripts."""
    found = []
    for block in FENCE.findall((ROOT / 'README.md').read_text()):
        lines = block.splitlines()
        if not lines or not lines[0].startswith('$ '):
            continue
        steps, i = [], 0
        while i < len(lines):
            command = lines[i]
            while command.endswith('\\'):
                i += 1
                command = command[:-1] + ' ' + lines[i].strip()
            i += 1
            shown = []
            while i < len(lines) and not lines[i].startswith('$ '):
                shown.append(lines[i])
                i += 1
            steps.append((command, shown))
        if all(RUNNABLE.match(command) for command, _ in steps):
            found.append(steps)
    return found


def _shell(command: str) -> str:
    python = sys.executable
    command = command[2:].replace('.venv/bin/python', python, 1)
    return command.replace('.venv/bin/ipomdp-gaze', f'{python} -m ipomdp_gaze.cli', 1)


def _matches(shown: list, printed: list) -> bool:
    """Whether the printed lines are the shown ones (``...``: any lines)."""
    pattern = ''.join('(?:.*\n)*?' if line == '...' else re.escape(line) + '\n'
                      for line in shown)
    return re.fullmatch(pattern, ''.join(line + '\n' for line in printed)) is not None


def test_the_readme_has_runnable_transcripts():
    assert transcripts(), 'no runnable transcript found in README.md'


@pytest.mark.parametrize('steps', transcripts(), ids=lambda steps: steps[-1][0][2:60])
def test_a_readme_transcript_prints_what_it_shows(steps, tmp_path):
    for command, shown in steps:
        run = subprocess.run(['bash', '-c', _shell(command) + ' 2>&1'], cwd=tmp_path,
                             capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stdout
        printed = [TIMES[0].sub(TIMES[1], line) for line in run.stdout.splitlines()]
        expected = [TIMES[0].sub(TIMES[1], line) for line in shown]
        assert _matches(expected, printed), (f'{command}\nREADME shows:\n' + '\n'.join(shown)
                                             + '\nprinted:\n' + '\n'.join(printed))
