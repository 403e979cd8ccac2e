# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``bench/readme_walkthrough.py`` (``make readme``): what it reads from a README and how it judges.

On small fake READMEs with trivial commands (``echo``, ``cat``, ``sleep``): the commands in
order, a transcript's shown lines, an output block without its command refused, a shown output
that differs from the printed one failing with a diff, the masks, the skip reasons and the time
limit. The real README's walkthrough runs in ``make readme`` (minutes), not here.
"""
from pathlib import Path
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'bench'))
import readme_walkthrough as walkthrough  # noqa: E402

FAKE = """# A fake README

```bash
make demo     # set up, then run
.venv/bin/ipomdp-gaze find photo.png \\
    --plot found.png
```

```python
print('not shell')
```

```
$ echo hello > greeting.txt
$ cat greeting.txt
hello
$ echo 'seconds=0.0379 done'
seconds=9.9999 done
```
"""


def test_it_reads_every_command_in_order_with_its_shown_lines():
    steps = walkthrough.steps(FAKE)
    assert [(s.line, s.command) for s in steps] == [
        (4, 'make demo     # set up, then run'),
        (5, '.venv/bin/ipomdp-gaze find photo.png  --plot found.png'),
        (14, 'echo hello > greeting.txt'), (15, 'cat greeting.txt'),
        (17, "echo 'seconds=0.0379 done'")]
    assert [s.shown for s in steps] == [None, None, [], ['hello'], ['seconds=9.9999 done']]
    assert [[s.command for s in t] for t in walkthrough.transcripts(FAKE)] == [
        ['echo hello > greeting.txt', 'cat greeting.txt', "echo 'seconds=0.0379 done'"]]


def test_output_without_its_command_is_refused():
    with pytest.raises(ValueError, match='line 2: a block of output without its command'):
        walkthrough.steps('```\nfixation   1: looked at (5, 5)\n```\n')


def test_commands_run_in_order_in_one_folder_and_match_their_shown_lines(tmp_path):
    done = walkthrough.walk(FAKE, tmp_path, max_seconds=30, report=lambda *a, **k: None)
    assert [(s.command[:9], s.status) for s in done] == [
        ('make demo', 'skipped'), ('.venv/bin', 'skipped'), ('echo hell', 'matched'),
        ('cat greet', 'matched'), ("echo 'sec", 'matched')]
    assert 'your own images' in done[1].reason
    assert 'make readme' not in walkthrough.summary(done)
    assert walkthrough.summary(done).splitlines()[-1] == (
        '5 commands: 3 run (3 matched their shown output, 0 with no output shown exited 0, '
        "0 differ, 0 failed), 0 the same as a transcript's, 0 too long, 2 skipped")


def test_a_readme_whose_shown_output_differs_fails_with_a_diff(tmp_path, capsys):
    readme = tmp_path / 'README.md'
    readme.write_text('```\n$ echo hello\nhello\n$ echo world\nthe world\n```\n')
    assert walkthrough.main(['--readme', str(readme)]) == 1
    out = capsys.readouterr().out
    assert '-the world\n+world' in out
    assert '    4  differs' in out and '    2  matched' in out


def test_a_failing_command_or_one_too_long_is_said(tmp_path):
    text = '```\n$ false\n$ sleep 20\n$ echo fine\nfine\n```\n'
    done = walkthrough.walk(text, tmp_path, max_seconds=1, report=lambda *a, **k: None)
    assert [s.status for s in done] == ['failed', 'too long', 'matched']
    assert done[0].reason == 'exit status 1' and done[1].seconds < 15


def test_what_varies_is_masked_and_dots_stand_for_any_lines():
    assert walkthrough.matches(['...', 'x seconds=0.1 y'], ['a', 'b', 'x seconds=12.5 y'])
    assert not walkthrough.matches(['x seconds=0.1 y'], ['x seconds=0.1 z'])
    assert walkthrough.matches(['demo: ROS domain 29; starting'], ['demo: ROS domain 3; starting'])
    assert walkthrough.contains(['b', '...', 'd'], ['a', 'b', 'c', 'd', 'e'])


def test_the_masked_counts_match_a_count_of_one_in_the_singular():
    shown = ['bag: 194 messages, 2.01 MB, 8.9 s recorded; 8 frames over 1.4 s; package 0.3.5',
             '8 frames recorded, 1 applied by the replay']
    printed = ['bag: 1 message, 0.01 MB, 0.2 s recorded; 1 frame over 0.0 s; package 0.3.5',
               '1 frame recorded, 1 applied by the replay']
    assert walkthrough.matches(shown, printed)
    assert not walkthrough.matches(shown, printed[:1] + ['1 frame recorded, 0 applied by the '
                                                         'replay'])


def test_a_command_without_ros_or_your_files_is_run_with_this_checkout():
    assert 'ROS 2 install' in walkthrough.skip_reason('ros2 topic echo /found')
    assert 'ROS 2 install' in walkthrough.skip_reason('CFG=$(ros2 pkg prefix ipomdp_gaze)/x')
    assert 'ROS 2 install' in walkthrough.skip_reason(
        'FASTRTPS_DEFAULT_PROFILES_FILE=$CFG/profile.xml ros2 run <driver package> <driver>')
    assert not walkthrough.skip_reason('OPENBLAS_NUM_THREADS=1 ipomdp-gaze evaluate')
    assert 'your own' in walkthrough.skip_reason("K=$(python3 -c \"open('my-policy.yaml')\")")
    assert 'docs/reproduction.md' in walkthrough.skip_reason('ipomdp-gaze reproduce --jobs 2')
    assert walkthrough.skip_reason('.venv/bin/ipomdp-gaze find astronaut.png') == ''
    command = walkthrough.shell('.venv/bin/ipomdp-gaze search && ipomdp-gaze demo', 'py')
    assert command == 'py -m ipomdp_gaze.cli search && py -m ipomdp_gaze.cli demo'
    assert walkthrough.shell('.venv/bin/python -c 1', 'py') == 'py -c 1'


def test_a_command_needing_a_file_a_skipped_one_writes_is_skipped(tmp_path):
    text = '```\n$ sleep 20 && touch k.yaml\n$ cat k.yaml\n```\n'
    done = walkthrough.walk(text, tmp_path, max_seconds=1, report=lambda *a, **k: None)
    assert [s.status for s in done] == ['too long', 'skipped']
    assert done[1].reason == ('needs k.yaml, which the command at line 2 writes '
                              '(too long, not done)')


def test_the_readme_has_a_walkthrough():
    """Every output block of README.md has its command, and most commands run here."""
    steps = walkthrough.steps((ROOT / 'README.md').read_text())
    run = [s for s in steps if not walkthrough.skip_reason(s.command)]
    assert len(steps) >= 60 and len(run) >= 20
