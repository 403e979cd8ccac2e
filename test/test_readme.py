# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The README's shown commands print what the README shows (issue 35, item 3; a first part).

A fenced block whose lines start with ``$ `` is a transcript: each command (with its backslash
continuation lines) is run in a fresh folder, in order, with ``.venv/bin/python`` and
``.venv/bin/ipomdp-gaze`` standing for this interpreter and its CLI; what it prints (stdout and
stderr, in order) must be the lines shown under it, numbers included, with times aside
(``seconds=...``). A ``...`` line stands for any lines. Transcripts of commands that start ROS
nodes (``demo``, ``record``, ``replay`` of a demo's bag) run in ROS tests (the demo outputs the
README shows, the face demo's in test_ros_faces.py, and the record and replay transcript in
order, the bag's size aside); those
whose inputs the README does not create (``mine/``, ``photo.png``) are not run. Every
``ipomdp-gaze`` command in a fenced block must parse with the CLI's own parser.
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
    return [steps for steps in _all_transcripts()
            if all(RUNNABLE.match(command) for command, _ in steps)]


def _all_transcripts() -> list:
    """Return ``[(commands, outputs)]`` of every transcript in the README."""
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


def _block_with(text: str) -> list:
    """Return the lines of the README's one fenced block that holds ``text``."""
    blocks = [b for b in FENCE.findall((ROOT / 'README.md').read_text()) if text in b]
    assert len(blocks) == 1, f'{len(blocks)} README blocks hold {text!r}'
    return blocks[0].splitlines()


def _contains(shown: list, printed: list) -> bool:
    """Whether the shown lines (``...``: any lines) are a run of whole printed lines."""
    pattern = ''.join('(?:.*\n)*?' if line == '...' else re.escape(line) + '\n'
                      for line in shown)
    return re.search('(?:^|\n)' + pattern, ''.join(line + '\n' for line in printed)) is not None


# The demo outputs the README shows, by a line only that block holds, and the options that make
# them (each demo is deterministic for its seed: the simulated camera's noise). The face demo's
# are checked in test_ros_faces.py, on the runs its own tests check.
DEMOS = [('the simulated camera hid the target at (9, 7)', [])]


@pytest.mark.ros
@pytest.mark.parametrize('line, options', DEMOS, ids=['demo'])
def test_the_readme_shows_what_the_demo_prints(ros_env, line, options):
    """Issue 35: the README showed a demo output the command no longer printed."""
    from conftest import REPO
    run = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'demo', '--domain-id',
                          ros_env['ROS_DOMAIN_ID'], *options], cwd=REPO, env=ros_env,
                         capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stdout + run.stderr
    shown = _block_with(line)
    assert _contains(shown, run.stdout.splitlines()), \
        'README shows:\n' + '\n'.join(shown) + '\nprinted:\n' + run.stdout


def readme_commands() -> list:
    """Return every ``ipomdp-gaze`` command in the README's fenced blocks (its arguments)."""
    commands = []
    for block in FENCE.findall((ROOT / 'README.md').read_text()):
        lines = block.splitlines()
        i = 0
        while i < len(lines):
            line = lines[i]
            while line.rstrip().endswith('\\') and i + 1 < len(lines):
                i += 1
                line = line.rstrip()[:-1] + ' ' + lines[i].strip()
            i += 1
            # A command, not an output line such as ``ipomdp-gaze find: shipped ...``.
            match = re.match(r'^(?:\$ )?(?:\.venv/bin/)?ipomdp-gaze\s+([a-z_-]+(?:\s.*)?)$',
                             line.strip())
            if match:
                commands.append(match.group(1))
    return commands


def test_every_readme_command_parses():
    """A README command with a renamed or dropped flag fails here, without running it."""
    import shlex
    from ipomdp_gaze.cli import build_parser
    parser, bad = build_parser(), []
    assert len(readme_commands()) >= 20
    for command in readme_commands():
        words = shlex.split(command, comments=True)
        words = words[:next((k for k, w in enumerate(words) if w in ('|', '>', '&&', ';')),
                            len(words))]
        try:
            parser.parse_args(words)
        except SystemExit as exc:
            if exc.code:
                bad.append(command)
    assert not bad, bad


# What varies between runs of the record and replay transcript: the bag's size, message count
# and seconds, and its growth rate (or, from a search under 2 s of frames, the note that it is
# too short to extrapolate: which one depends on the machine's speed). The fixation counts
# are checked on the other lines.
BAG_SIZE = (re.compile(r'\d+ messages, [\d.]+ MB, [\d.]+ s recorded; .*?; (package [\d.]+)$'),
            r'N messages, M MB, S s recorded; RATE; \1')
# A frame that arrives after the decision is recorded but not applied: the frames recorded vary,
# the frames the replay applies (the search's) do not.
FRAMES = (re.compile(r'^\d+ frames recorded, (\d+) applied by the replay$'),
          r'N frames recorded, \1 applied by the replay')


def _mask(line: str) -> str:
    """Return a transcript line with what varies between runs masked."""
    for pattern, replacement in (BAG_SIZE, FRAMES):
        line = pattern.sub(replacement, line)
    return line


@pytest.mark.ros
def test_the_readme_record_and_replay_transcript(ros_env, tmp_path):
    """Issue 35: the README's demo --record, replay and replay --policy map, in order."""
    steps = [step for steps in _all_transcripts() for step in steps
             if steps[-1][0].endswith('replay faces-bag --policy map')]
    assert [command.split('ipomdp-gaze ')[1] for command, _ in steps] == [
        'demo --scene faces --seed 0 --record faces-bag', 'replay faces-bag',
        'replay faces-bag --policy map']
    for command, shown in steps:
        run = subprocess.run(['bash', '-c', _shell(command) + ' 2>&1'], cwd=tmp_path,
                             env=ros_env, capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stdout
        printed = [_mask(line) for line in run.stdout.splitlines()]
        expected = [_mask(line) for line in shown]
        assert _matches(expected, printed), (f'{command}\nREADME shows:\n' + '\n'.join(shown)
                                             + '\nprinted:\n' + '\n'.join(printed))
