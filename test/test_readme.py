# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The README's shown commands print what the README shows (issue 35, item 3).

The README's commands, transcripts and masks are read by ``bench/readme_walkthrough.py`` (``make
readme``, which runs every command in order): one definition. A fenced block whose lines start
with ``$ `` is a transcript: each command is run in a fresh folder, in order, with
``.venv/bin/python`` and ``.venv/bin/ipomdp-gaze`` standing for this interpreter and its CLI;
what it prints (stdout and stderr, in order) must be the lines shown under it, numbers included,
with what varies masked (``walkthrough.MASKS``: wall times, a bag's size). A ``...`` line stands
for any lines. Here the fast transcripts run (``find``, ``search``); those of commands that start
ROS nodes (``demo``, ``record``, ``replay`` of a demo's bag) run in ROS tests (the demo's here,
the face demo's in test_ros_faces.py, and the record and replay transcript in order). Every
``ipomdp-gaze`` command of the walkthrough must parse with the CLI's own parser.
"""
from pathlib import Path
import re
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'bench'))
import readme_walkthrough as walkthrough  # noqa: E402  (bench/: the one definition)

README = (ROOT / 'README.md').read_text()
# What a transcript may run here: fast commands without ROS nodes.
RUNNABLE = re.compile(r'^\.venv/bin/(python -c|ipomdp-gaze (find|search))\b')


def transcripts() -> list:
    """Return the README's runnable transcripts, each a list of ``walkthrough.Step``."""
    return [steps for steps in walkthrough.transcripts(README)
            if all(RUNNABLE.match(step.command) for step in steps)]


def _run(step, cwd, **kwargs) -> list:
    """Run a transcript step as the walkthrough does; return the lines it printed."""
    run = subprocess.run(['bash', '-c', walkthrough.shell(step.command) + ' 2>&1'], cwd=cwd,
                         capture_output=True, text=True, **kwargs)
    assert run.returncode == 0, run.stdout
    return run.stdout.splitlines()


def test_the_readme_has_runnable_transcripts():
    assert transcripts(), 'no runnable transcript found in README.md'


@pytest.mark.parametrize('steps', transcripts(), ids=lambda steps: steps[-1].command[:58])
def test_a_readme_transcript_prints_what_it_shows(steps, tmp_path):
    for step in steps:
        printed = _run(step, tmp_path, timeout=600)
        assert walkthrough.matches(step.shown, printed), (
            f'{step.command}\nREADME shows:\n' + '\n'.join(step.shown) + '\nprinted:\n'
            + '\n'.join(printed))


def _shown_by(command: str) -> list:
    """Return the output the README's one transcript of ``command`` shows."""
    shown = [step.shown for steps in walkthrough.transcripts(README) for step in steps
             if walkthrough.same_command(step.command) == walkthrough.same_command(command)]
    assert len(shown) == 1, f'{len(shown)} README transcripts of {command!r}'
    return shown[0]


_contains = walkthrough.contains


# The demo outputs the README shows, by their command, and its options (each demo is
# deterministic for its seed: the simulated camera's noise). The face demo's are checked in
# test_ros_faces.py, on the runs its own tests check.
DEMOS = [('ipomdp-gaze demo', [])]


@pytest.mark.ros
@pytest.mark.parametrize('command, options', DEMOS, ids=['demo'])
def test_the_readme_shows_what_the_demo_prints(ros_env, command, options):
    """Issue 35: the README showed a demo output the command no longer printed."""
    from conftest import REPO
    run = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'demo', '--domain-id',
                          ros_env['ROS_DOMAIN_ID'], *options], cwd=REPO, env=ros_env,
                         capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stdout + run.stderr
    shown = _shown_by(command)
    assert _contains(shown, run.stdout.splitlines()), \
        'README shows:\n' + '\n'.join(shown) + '\nprinted:\n' + run.stdout


def readme_commands() -> list:
    """Return every ``ipomdp-gaze`` command of the walkthrough (its arguments)."""
    return [match.group(1) for step in walkthrough.steps(README)
            if (match := re.match(r'^(?:\.venv/bin/)?ipomdp-gaze\s+([a-z_-]+(?:\s.*)?)$',
                                  step.command.strip()))]


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


@pytest.mark.ros
def test_the_readme_record_and_replay_transcript(ros_env, tmp_path):
    """Issue 35: the README's demo --record, replay and replay --policy map, in order."""
    steps = [step for steps in walkthrough.transcripts(README) for step in steps
             if steps[-1].command.endswith('replay faces-bag --policy map')]
    assert [step.command.split('ipomdp-gaze ')[1] for step in steps] == [
        'demo --scene faces --seed 0 --record faces-bag', 'replay faces-bag',
        'replay faces-bag --policy map']
    for step in steps:
        printed = _run(step, tmp_path, env=ros_env, timeout=300)
        assert walkthrough.matches(step.shown, printed), (
            f'{step.command}\nREADME shows:\n' + '\n'.join(step.shown) + '\nprinted:\n'
            + '\n'.join(printed))


def test_the_readme_python_examples_run(tmp_path):
    """Issue 35: every ``python`` block of the README runs as shown and prints what it says."""
    blocks = ['\n'.join(lines) + '\n' for _, language, lines
              in walkthrough.blocks((ROOT / 'README.md').read_text()) if language == 'python']
    assert len(blocks) >= 2, 'the README lost its Python examples'
    for block in blocks:
        run = subprocess.run([sys.executable, '-c', block], capture_output=True, text=True,
                             cwd=tmp_path, timeout=300)
        assert run.returncode == 0, block + '\n' + run.stderr[-2000:]
        # a print whose comment says what it prints: ``print(...)  # found (3, 7) ...``
        for shown in re.findall(r'^print\(.*\)\s+#\s+(.*?)\s*(?:\.\.\.)?$', block, re.M):
            assert run.stdout.startswith(shown), (shown, run.stdout)
