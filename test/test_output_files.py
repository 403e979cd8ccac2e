# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The files the commands write: whole or not at all, refused before the work, noted on stderr."""
import json
import os
from pathlib import Path
import resource
import signal
import subprocess
import sys

from ipomdp_gaze.cli import main
from ipomdp_gaze.files.writable import write_file, write_text
from ipomdp_gaze.policies.policy_file import load_policy_spec
from ipomdp_gaze.policies.training import read_curve
import pytest
import skimage.data

ASTRONAUT = Path(skimage.data.__file__).parent / 'astronaut.png'


def _small_files(limit_bytes: int):
    """Return a ``preexec_fn`` that lets the child write no file past ``limit_bytes``."""
    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)        # EFBIG, as a full disk's ENOSPC
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))
    return limit


def run_cli(*args, limit_bytes=None, cwd=None):
    return subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', *map(str, args)],
                          capture_output=True, text=True, timeout=300, cwd=cwd,
                          preexec_fn=None if limit_bytes is None else _small_files(limit_bytes))


def _leftovers(folder: Path) -> list:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith('.'))


def test_evaluate_json_the_disk_refuses_keeps_the_old_file_and_names_json(tmp_path):
    """A write that fails part way left half a JSON record ('[Errno 27] File too large')."""
    out = tmp_path / 'out.json'
    out.write_text('{"old": 1}\n')
    run = run_cli('evaluate', '--grid', '3x3', '--episodes', '20', '--json', out,
                  limit_bytes=200)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines()[-1] == \
        f'ipomdp-gaze evaluate: error: --json {out}: cannot write: File too large'
    assert out.read_text() == '{"old": 1}\n'
    assert _leftovers(tmp_path) == []


def test_find_outputs_the_disk_refuses_keep_the_old_files(tmp_path):
    # The log is the shortest output: '{"path": "<the image>", "events": []}', over 40 bytes.
    outputs = {name: tmp_path / name for name in ('found.json', 'found.log', 'found.png')}
    for path in outputs.values():
        path.write_text('old\n')
    run = run_cli('find', ASTRONAUT, '--json', outputs['found.json'], '--log',
                  outputs['found.log'], '--plot', outputs['found.png'], limit_bytes=40)
    assert run.returncode == 2 and 'Traceback' not in run.stderr
    for flag, name in (('--json', 'found.json'), ('--log', 'found.log'), ('--plot', 'found.png')):
        assert f'{flag} {outputs[name]}: cannot write: File too large' in run.stderr
        assert outputs[name].read_text() == 'old\n'
    assert _leftovers(tmp_path) == []


def test_a_resumed_training_the_disk_refuses_keeps_the_policy_it_resumes(tmp_path):
    """``train --resume P`` writes over P: a failed write must not leave half a policy."""
    policy = tmp_path / 'p.yaml'
    assert run_cli('train', '--grid', '3x3', '--epochs', '2', '--eval-every', '1',
                   '--episodes-per-epoch', '4', '--eval-episodes', '20', '--final-episodes',
                   '0', '--out', policy).returncode == 0
    before = policy.read_bytes(), policy.with_suffix('.csv').read_bytes()
    run = run_cli('train', '--resume', policy, '--epochs', '4', '--final-episodes', '0',
                  limit_bytes=300)
    assert run.returncode == 2 and 'Traceback' not in run.stderr
    assert (policy.read_bytes(), policy.with_suffix('.csv').read_bytes()) == before
    assert load_policy_spec(policy).training['epochs'] == 2
    assert [row['epoch'] for row in read_curve(policy.with_suffix('.csv'))] == [1, 2]
    assert _leftovers(tmp_path) == []


def test_write_file_keeps_the_mode_a_new_file_gets_and_writes_devices_in_place(tmp_path):
    umask = os.umask(0o022)
    try:
        path = write_text(tmp_path / 'sub' / 'new.json', '{}\n')
        assert path.stat().st_mode & 0o777 == 0o644
        old = tmp_path / 'old.json'
        old.write_text('x')
        old.chmod(0o640)
        write_text(old, 'y')
        assert old.read_text() == 'y' and old.stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(umask)
    link = tmp_path / 'link.json'
    link.symlink_to(old)
    write_text(link, 'z')
    assert link.is_symlink() and old.read_text() == 'z'
    assert write_text(Path(os.devnull), 'nothing') == Path(os.devnull)     # not replaced
    assert Path(os.devnull).is_char_device()

    def stopped(temporary):
        temporary.write_text('half')
        raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        write_file(old, stopped)
    assert old.read_text() == 'z' and _leftovers(tmp_path) == []


def test_a_sweep_refuses_a_file_it_would_write_before_any_training(tmp_path, capsys):
    """``PATH-seedS.yaml`` was found unwritable only after every training had run."""
    (tmp_path / 't-seed2.yaml').mkdir()
    assert main(['train', '--grid', '3x3', '--seeds', '1,2', '--epochs', '1',
                 '--episodes-per-epoch', '2', '--final-episodes', '0', '--jobs', '1',
                 '--quiet', '--out', str(tmp_path / 't.yaml')]) == 2
    err = capsys.readouterr().err
    assert err == f'ipomdp-gaze train: error: --out {tmp_path}/t-seed2.yaml: is a directory\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['t-seed2.yaml']


@pytest.mark.parametrize('args', [['--plot', '{dir}/d.png'], ['--animate', '{dir}/d.gif'],
                                  ['--scene', 'faces', '--motion', 'walk', '--plot',
                                   '{dir}/d.png']])
def test_demo_refuses_its_picture_files_before_the_nodes_run(tmp_path, monkeypatch, capsys,
                                                             args):
    """An unwritable --plot or --animate was found after the whole demo had run."""
    import ipomdp_gaze.harness.demo as demo
    import ipomdp_gaze.harness.walk_demo as walk_demo

    def run(*args, **kwargs):
        raise AssertionError('the nodes ran')
    monkeypatch.setattr(demo, 'run_demo', run)
    monkeypatch.setattr(walk_demo, 'run_walk_demo', run)
    (tmp_path / 'd.png').mkdir()
    (tmp_path / 'd.gif').mkdir()
    args = [a.format(dir=tmp_path) for a in args]
    assert main(['demo', *args]) == 2
    assert capsys.readouterr().err == \
        f'ipomdp-gaze demo: error: {args[-2]} {args[-1]}: is a directory\n'


@pytest.mark.parametrize('command', [
    ['evaluate', '--grid', '3x3', '--episodes', '20', '--json', '{dir}/e.json'],
    ['search', '--grid', '3x3', '--seed', '1', '--plot', '{dir}/s.png'],
    ['train', '--grid', '3x3', '--epochs', '2', '--quiet', '--out', '{dir}/p.yaml'],
    ['calibrate', '--scenes', '2', '--grid', '7x7', '--windows', '7,3', '--scales', '1/2,1',
     '--processes', '1', '--quiet', '--out', '{dir}/c.yaml'],
])
def test_the_note_of_a_file_written_goes_to_stderr(tmp_path, command):
    """
    ``evaluate ... --json F > table.txt`` put 'wrote F' among the table's lines.

    ``train`` and ``calibrate`` said 'wrote X and Y' on stdout too, after their results.
    """
    run = run_cli(*[a.format(dir=tmp_path) for a in command])
    assert run.returncode == 0, run.stderr
    written = command[-1].format(dir=tmp_path)
    assert 'wrote' not in run.stdout
    also = {'train': f" and {tmp_path / 'p.csv'}", 'calibrate': f" and {tmp_path / 'c.png'}"}
    assert f'ipomdp-gaze {command[0]}: wrote {written}{also.get(command[0], "")}\n' \
        in run.stderr
    if written.endswith('.json'):
        assert json.loads(Path(written).read_text())['grid']['rows'] == 3


def test_a_writable_file_in_a_folder_that_takes_no_new_file_is_written_in_place(
        tmp_path, monkeypatch):
    """``check_output_file`` accepts such a file: the write must not then need a new one."""
    import ipomdp_gaze.files.writable as writable

    def refused(target):
        raise PermissionError(13, 'Permission denied')
    monkeypatch.setattr(writable, '_new_file', refused)
    own = tmp_path / 'own.json'
    own.write_text('old')
    assert write_text(own, 'new').read_text() == 'new'
    with pytest.raises(PermissionError, match=str(tmp_path / 'other.json')):
        write_text(tmp_path / 'other.json', 'new')


def _reader_gone(args, stderr):
    """Run the CLI with its stdout a pipe closed before anything is read (``| head -0``)."""
    with subprocess.Popen([sys.executable, '-m', 'ipomdp_gaze.cli', *map(str, args)],
                          stdout=subprocess.PIPE, stderr=stderr) as child:
        child.stdout.close()
        return child.wait(timeout=300)


COMMAND_FILES = [
    (['evaluate', '--grid', '3x3', '--episodes', '20', '--json', '{dir}/e.json'], ['e.json']),
    (['find', ASTRONAUT, Path(skimage.data.__file__).parent / 'coffee.png', '--json',
      '{dir}/f.json', '--log', '{dir}/f.log', '--plot', '{dir}/f.png'],
     ['f-0.png', 'f-1.png', 'f.json', 'f.log']),
    (['search', '--grid', '5x5', '--plot', '{dir}/s.png'], ['s.png']),
]


@pytest.mark.parametrize('command, files', COMMAND_FILES)
@pytest.mark.parametrize('stderr_too', [False, True])
def test_a_reader_that_goes_away_costs_no_output_file(tmp_path, command, files, stderr_too):
    """``find ... --json F | head -1`` ended quietly at the closed pipe, F never written."""
    errors = tmp_path / 'stderr.txt'
    with errors.open('w') as stderr:
        status = _reader_gone([str(a).format(dir=tmp_path) for a in command],
                              subprocess.STDOUT if stderr_too else stderr)
    assert status == 0
    assert 'Traceback' not in errors.read_text()
    assert sorted(p.name for p in tmp_path.iterdir() if p != errors) == files
    for name in files:
        if name.endswith('.json'):
            record = json.loads((tmp_path / name).read_text())
            assert len(record.get('images', [0, 0])) == 2       # find: both images searched


def test_a_reader_that_goes_away_still_stops_a_command_without_files(tmp_path):
    errors = tmp_path / 'stderr.txt'
    with errors.open('w') as stderr:
        assert _reader_gone(['search', '--grid', '5x5'], stderr) == 0
    assert errors.read_text() == ''


@pytest.mark.parametrize('args', [
    ['evaluate', '--json', '{dir}/results/'],
    ['find', ASTRONAUT, '--json', '{dir}/results/'],
    ['find', ASTRONAUT, '--log', '{dir}/results/'],
    ['find', ASTRONAUT, '--plot', '{dir}/found.png/'],
    ['search', '--plot', '{dir}/s.png/'],
    ['train', '--epochs', '1', '--out', '{dir}/t.yaml/'],
    ['calibrate', '--scenes', '1', '--out', '{dir}/m.yaml/'],
    ['demo', '--plot', '{dir}/d.png/'],
])
def test_an_output_file_that_ends_in_a_slash_is_refused(tmp_path, args):
    """``--json results/`` wrote a file named ``results``: the slash names a folder."""
    args = [str(a).format(dir=tmp_path) for a in args]
    run = run_cli(*args)
    assert run.returncode == 2
    assert run.stderr.splitlines()[-1] == (
        f'ipomdp-gaze {args[0]}: error: argument {args[-2]}: {args[-1]!r} ends in / and names '
        'a folder: give the name of a file to write in it')
    assert list(tmp_path.iterdir()) == []
