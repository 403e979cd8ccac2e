# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Run README.md's walkthrough: every shell command of its fenced blocks, in order (``make readme``).

A fenced block whose first line starts with ``$ `` is a transcript: each ``$ `` command (with its
backslash continuation lines) is followed by the lines it prints (stdout and stderr, in order),
``...`` standing for any lines. Any other ``bash`` or unlabelled block whose first line is a
command (``make``, ``ipomdp-gaze``, ``.venv/bin/...``, ``ros2``, ...) lists commands whose output
the README does not show: each must exit with status 0. A block of output without its command
is an error (make it a transcript). ``python`` and ``yaml`` blocks are not shell.

Every command runs with ``bash`` in one scratch folder, in README order (a command finds the
files an earlier one wrote), ``.venv/bin/python`` and ``.venv/bin/ipomdp-gaze`` (or a bare
``ipomdp-gaze``) standing for this interpreter and this checkout's CLI. What varies between runs
is masked on both sides (``MASKS``: wall times, a bag's size, a demo's ROS domain). Commands that
cannot run here are listed as skipped with the reason (``SKIPS``: ROS 2's own CLI and colcon, your
own files, a Dask scheduler, commands and make targets that rewrite the repository's docs), never
silently, and so is a command that needs a file only a command not run writes; a command that
runs longer than ``--max-seconds`` is stopped and listed as too long. It prints a per-command
diff for each difference and a summary, and exits 1 when a command failed or printed something
else.

    python bench/readme_walkthrough.py [--readme README.md] [--max-seconds 600] [--only TEXT]
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass, field
import difflib
import os
from pathlib import Path
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
FENCE = re.compile(r'^```([a-z]*)\n(.*?)^```', re.S | re.M)
# The first word of a line a user types (a block whose first line is none of these is output).
COMMAND = re.compile(r'^(?:\$ |make\b|ipomdp-gaze\b|\.venv/bin/|ros2\b|colcon\b|cd\b|source\b|'
                     r'python3?\b|pip\b|git\b|[A-Z_]+=)')

# What varies between runs, masked on both sides: (pattern, replacement). Wall times (find's
# ``seconds=``, evaluate's head time, which includes the detector's, and the detector's seconds
# per view); the ROS domain a demo picks (one no other run on the host holds); the record and
# replay transcript's bag size, message count and seconds, and its growth rate (or, from a search
# under 2 s of frames, the note that it is too short to extrapolate: which one depends on the
# machine's speed); the frames a replay finds recorded (a frame that arrives after the decision is
# recorded but not applied: the frames applied, the search's, are checked). A count of one reads
# '1 message', '1 frame' (ipomdp_gaze.model.wording): the masks take both forms.
MASKS = [
    (re.compile(r'seconds=\d+\.\d+'), 'seconds=<time>'),
    (re.compile(r'head time \d+\.\d+ s \(detector \d+\.\d+ s per view\)'),
     'head time <time> s (detector <time> s per view)'),
    (re.compile(r'ROS domain \d+;'), 'ROS domain <N>;'),
    (re.compile(r'\d+ messages?, [\d.]+ MB, [\d.]+ s recorded; .*?; (package [\d.]+)$'),
     r'N messages, M MB, S s recorded; RATE; \1'),
    (re.compile(r'^\d+ frames? recorded, (\d+) applied by the replay$'),
     r'N frames recorded, \1 applied by the replay'),
]

# Commands that cannot run here, by a pattern of the command: (pattern, reason).
SKIPS = [
    (re.compile(r'^(?:[A-Z_]+=\S*\s+)*(?:ros2|colcon|source)\b|\$\(ros2 |^cd ~/ws'),
     'needs a ROS 2 install (the ros2 CLI, colcon), not on this machine; the nodes themselves run '
     'over real DDS in the demos here and in the ROS tests'),
    (re.compile(r'^python3 -m pip install\b'),
     "installs the dependencies into the system Python; the runner uses the venv's (make venv)"),
    (re.compile(r'(?<![\w./-])(?:mine/|my_photos/|photo\.png|photo\.jpg|other\.jpg|'
                r'my-policy\.yaml|my\.yaml)(?![\w.-])'),
     'needs your own images or file, which the README does not create'),
    (re.compile(r'--scheduler tcp://'), 'needs a Dask scheduler at that address'),
    (re.compile(r'^make test\b'),
     'the whole test suite (about 10 minutes on 2 cores), run by make test itself'),
    (re.compile(r'^make (?:reproduce|faces|faces-groups|models|bench|pan-tilt|walks|soak)\b'),
     "rewrites the repository's docs (minutes to an hour); the walkthrough runs in a scratch "
     'folder'),
    (re.compile(r'ipomdp-gaze reproduce\b(?!.*--out\b)'),
     "writes the checkout's docs/reproduction.md and docs/figures/ (as make reproduce does: "
     'about 4-7 minutes on 2 cores); the walkthrough changes nothing in the repository'),
    (re.compile(r'^make demo\b'),
     'sets up .venv/, then runs .venv/bin/ipomdp-gaze demo: that command is run at its '
     'transcript'),
]


@dataclass
class Step:
    """One command of the README, where it is and the output it shows (``None``: none shown)."""

    line: int
    command: str
    shown: list | None = None
    status: str = ''
    reason: str = ''
    seconds: float | None = None
    printed: list = field(default_factory=list)


def mask(line: str) -> str:
    """Return a line with what varies between runs masked (``MASKS``)."""
    for pattern, replacement in MASKS:
        line = pattern.sub(replacement, line)
    return line


def matches(shown: list, printed: list) -> bool:
    """Whether the printed lines are the shown ones (``...``: any lines), masks applied."""
    pattern = ''.join('(?:.*\n)*?' if line == '...' else re.escape(mask(line)) + '\n'
                      for line in shown)
    return re.fullmatch(pattern, ''.join(mask(line) + '\n' for line in printed)) is not None


def contains(shown: list, printed: list) -> bool:
    """Whether the shown lines (``...``: any lines) are a run of whole printed lines."""
    pattern = ''.join('(?:.*\n)*?' if line == '...' else re.escape(mask(line)) + '\n'
                      for line in shown)
    text = ''.join(mask(line) + '\n' for line in printed)
    return re.search('(?:^|\n)' + pattern, text) is not None


def blocks(text: str) -> list:
    """Return ``[(first line number, language, lines)]`` of the fenced blocks of a README."""
    return [(text.count('\n', 0, m.start()) + 2, m.group(1), m.group(2).splitlines())
            for m in FENCE.finditer(text)]


def _joined(lines: list, i: int) -> tuple:
    """Return the line at ``i`` with its backslash continuation lines, and the next index."""
    command = lines[i]
    while command.rstrip().endswith('\\') and i + 1 < len(lines):
        i += 1
        command = command.rstrip()[:-1] + ' ' + lines[i].strip()
    return command, i + 1


def transcript(start: int, lines: list) -> list:
    """Return the steps of a transcript block (``$ `` commands and the lines under each)."""
    steps, i = [], 0
    while i < len(lines):
        first = i
        command, i = _joined(lines, i)
        shown = []
        while i < len(lines) and not lines[i].startswith('$ '):
            shown.append(lines[i])
            i += 1
        steps.append(Step(start + first, command[2:], shown))
    return steps


def steps(text: str) -> list:
    """
    Return every shell command of a README, in order, as ``Step``s.

    Raises ``ValueError`` for an output block without its command.
    """
    out = []
    for start, language, lines in blocks(text):
        if language not in ('', 'bash', 'sh', 'console') or not lines:
            continue
        if lines[0].startswith('$ '):
            out.extend(transcript(start, lines))
        elif COMMAND.match(lines[0]):
            i = 0
            while i < len(lines):
                first = i
                command, i = _joined(lines, i)
                if command.strip() and not command.lstrip().startswith('#'):
                    out.append(Step(start + first, command.strip()))
        else:
            raise ValueError(f'README line {start}: a block of output without its command '
                             f'({lines[0][:60]!r}); show it as a transcript, "$ command" first')
    return out


def transcripts(text: str) -> list:
    """Return ``[[Step, ...]]``: the README's transcript blocks, each a list of steps."""
    return [transcript(start, lines) for start, language, lines in blocks(text)
            if language in ('', 'bash', 'sh', 'console') and lines
            and lines[0].startswith('$ ')]


def shell(command: str, python: str = sys.executable) -> str:
    """Return a README command as run here: this interpreter and this checkout's CLI."""
    cli = f'{shlex.quote(python)} -m ipomdp_gaze.cli'
    command = re.sub(r'(^|[\s;&|(])\.venv/bin/ipomdp-gaze\b', rf'\1{cli}', command)
    command = re.sub(r'(^|[\s;&|(])ipomdp-gaze\b', rf'\1{cli}', command)
    return re.sub(r'(^|[\s;&|(])\.venv/bin/python\b', rf'\1{shlex.quote(python)}', command)


def skip_reason(command: str) -> str:
    """Return why a command is not run here ('' when it is)."""
    for pattern, reason in SKIPS:
        if pattern.search(command):
            return reason
    return ''


FILE = re.compile(r'(?<![\w/.-])([\w./-]+\.(?:yaml|json|csv|png|gif|jpg))(?![\w.-])')


def _missing_input(step: Step, earlier: list, folder: Path) -> str:
    """Return why a step cannot run: a file a not-run earlier command names and nobody wrote."""
    names = set(FILE.findall(step.command))
    for other in earlier:
        if other.status in ('skipped', 'too long', 'failed'):
            for name in sorted(names & set(FILE.findall(other.command))):
                if not (folder / name).exists():
                    return (f'needs {name}, which the command at line {other.line} writes '
                            f'({other.status}, not done)')
    return ''


def run_step(step: Step, folder: Path, env: dict, max_seconds: float) -> None:
    """Run one step in ``folder`` and set its status, seconds and printed lines."""
    begin = time.monotonic()
    process = subprocess.Popen(['bash', '-c', shell(step.command) + ' 2>&1'], cwd=folder,
                               env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, start_new_session=True)
    try:
        out, _ = process.communicate(timeout=max_seconds)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGINT)
        try:
            process.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
        step.seconds = time.monotonic() - begin
        step.status, step.reason = 'too long', f'stopped after {max_seconds:.0f} s (--max-seconds)'
        return
    step.seconds = time.monotonic() - begin
    step.printed = out.splitlines()
    if process.returncode != 0:
        step.status, step.reason = 'failed', f'exit status {process.returncode}'
    elif step.shown is None:
        step.status, step.reason = 'ran', 'exit status 0, no output shown'
    elif matches(step.shown, step.printed):
        step.status = 'matched'
    else:
        step.status, step.reason = 'differs', 'printed other lines than the README shows'


def diff(step: Step) -> str:
    """Return the lines the README shows against those printed, unified, masks applied."""
    shown = [mask(line) for line in step.shown or []]
    printed = [mask(line) for line in step.printed]
    return '\n'.join(difflib.unified_diff(shown, printed, 'README shows', 'printed', lineterm=''))


def same_command(command: str) -> str:
    """Return a command without its comment and ``.venv/bin/`` (the same for a user)."""
    return re.sub(r'\s+#.*$', '', re.sub(r'^\.venv/bin/', '', command.strip())).strip()


def walk(text: str, folder: Path, max_seconds: float, only: str = '', report=print) -> list:
    """Run a README's steps in ``folder`` in order; return them with their results."""
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([str(ROOT), *filter(None, [env.get('PYTHONPATH')])])
    shown_at = {same_command(step.command): step.line
                for steps_ in transcripts(text) for step in steps_}
    done = []
    for step in steps(text):
        reason = skip_reason(step.command) or _missing_input(step, done, folder)
        at = shown_at.get(same_command(step.command)) if step.shown is None else None
        if only and only not in step.command:
            step.status, step.reason = 'skipped', f'not chosen (--only {only!r})'
        elif at is not None:
            step.status, step.reason = 'same', f'run at its transcript, line {at}'
        elif reason:
            step.status, step.reason = 'skipped', reason
        else:
            report(f'line {step.line}: {step.command}', flush=True)
            run_step(step, folder, env, max_seconds)
            if step.status in ('differs', 'failed'):
                report(f'  {step.status}: {step.reason}\n' + (
                    diff(step) if step.status == 'differs' else '\n'.join(step.printed[-30:])))
        done.append(step)
    return done


def summary(done: list) -> str:
    """Return the per-command table and the counts."""
    rows = []
    for step in done:
        seconds = '-' if step.seconds is None else f'{step.seconds:.1f}'
        reason = f'  ({step.reason})' if step.reason else ''
        rows.append(f'{step.line:5d}  {step.status:9s} {seconds:>7s}  '
                    f'{step.command[:90]}{reason}')
    count = {s: sum(step.status == s for step in done)
             for s in ('matched', 'ran', 'differs', 'failed', 'too long', 'skipped', 'same')}
    run = count['matched'] + count['ran'] + count['differs'] + count['failed']
    rows.append(f'{len(done)} commands: {run} run ({count["matched"]} matched their shown '
                f'output, {count["ran"]} with no output shown exited 0, {count["differs"]} '
                f'differ, {count["failed"]} failed), {count["same"]} the same as a transcript\'s, '
                f'{count["too long"]} too long, {count["skipped"]} skipped')
    return '\n'.join(rows)


def main(argv: list | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('--readme', type=Path, default=ROOT / 'README.md')
    parser.add_argument('--max-seconds', type=float, default=600.0,
                        help='stop a command after this long and list it as too long (600)')
    parser.add_argument('--only', default='', help='run only commands that contain this text')
    parser.add_argument('--keep', action='store_true', help='keep the scratch folder')
    parser.add_argument('--list', action='store_true',
                        help='list the commands and why any is skipped, without running them')
    args = parser.parse_args(argv)
    if args.list:
        for step in steps(args.readme.read_text()):
            reason = skip_reason(step.command)
            print(f'{step.line:5d}  {"skip" if reason else "run ":4s}  {step.command}'
                  + (f'  ({reason})' if reason else ''))
        return 0
    folder = Path(tempfile.mkdtemp(prefix='readme-walkthrough-'))
    try:
        done = walk(args.readme.read_text(), folder, args.max_seconds, args.only)
    finally:
        if not args.keep:
            subprocess.run(['rm', '-rf', str(folder)], check=False)
    print(summary(done))
    if args.keep:
        print(f'scratch folder: {folder}')
    return 1 if any(step.status in ('differs', 'failed') for step in done) else 0


if __name__ == '__main__':
    sys.exit(main())
