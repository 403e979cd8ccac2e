# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Progress on stderr: a bar on a terminal, lines in a log, nothing with --quiet."""
import io
from types import SimpleNamespace

from conftest import wait_for
from ipomdp_gaze.cli import main as cli_main
from ipomdp_gaze.simulation.executor import InlineExecutor, LocalExecutor, make_executor, track
from ipomdp_gaze.simulation.progress import Progress
import pytest


def test_a_log_gets_lines_with_the_count_and_an_eta():
    stream = io.StringIO()
    with Progress(4, 'job', quiet=False, stream=stream, every_s=0) as progress:
        progress.update(1)
        progress.note('epoch 1')
        progress.update(1)
    lines = stream.getvalue().splitlines()
    assert lines[0].startswith('job: 1/4 pieces (25%)') and 'ETA' in lines[0]
    assert lines[1].startswith('job: 2/4 pieces (50%)') and lines[1].endswith('(epoch 1)')
    assert lines[-1].startswith('job: 2/4 pieces') and len(lines) == 3   # the closing line


def test_a_log_gets_a_line_every_few_seconds_even_while_a_piece_runs():
    stream = io.StringIO()
    progress = Progress(1, 'slow', stream=stream, every_s=0.05)
    try:
        assert wait_for(lambda: stream.getvalue().count('\n') >= 2, 20)
    finally:
        progress.close()
    assert stream.getvalue().startswith('slow: 0/1 pieces (0%)')


def test_a_terminal_gets_a_bar_and_quiet_gets_nothing():
    stream = io.StringIO()
    with Progress(2, 'bar', unit='scene', stream=stream, terminal=True) as progress:
        progress.add(2)
        progress.update(3)
    assert '3/4' in stream.getvalue() and 'scene' in stream.getvalue()
    quiet = io.StringIO()
    with Progress(2, 'bar', quiet=True, stream=quiet, every_s=0) as progress:
        progress.update(2)
    assert quiet.getvalue() == ''


def test_progress_follows_the_futures():
    stream = io.StringIO()
    with make_executor(jobs=1) as executor, \
            Progress(3, 'sum', stream=stream, every_s=1e9) as progress:
        assert isinstance(executor, InlineExecutor)
        futures = [executor.submit(pow, 2, k) for k in range(3)]
        assert sorted(f.result() for f in track(futures, progress)) == [1, 2, 4]
        assert progress.done == 3


def test_an_inline_piece_runs_when_tracked_so_the_count_moves_piece_by_piece():
    ran, seen = [], []
    with make_executor(jobs=1) as executor, \
            Progress(3, 'scenes', 'scene', stream=io.StringIO(), every_s=1e9) as progress:
        futures = [executor.submit(ran.append, k) for k in range(3)]
        assert ran == [] and not any(f.done() for f in futures)     # nothing ran at submit
        for future in track(futures, progress):
            seen.append((len(ran), progress.done))
    assert ran == [0, 1, 2]
    assert seen == [(1, 1), (2, 2), (3, 3)]         # one piece run, one counted, then the next


def test_an_inline_piece_runs_once_and_keeps_its_error():
    calls = []

    def fail():
        calls.append(1)
        raise ValueError('bad piece')

    future = InlineExecutor().submit(fail)
    assert isinstance(future.exception(), ValueError)
    with pytest.raises(ValueError, match='bad piece'):
        future.result()
    assert calls == [1]
    cancelled = InlineExecutor().submit(calls.append, 2)
    assert cancelled.cancel() and cancelled.cancelled() and calls == [1]


def test_scene_evaluation_counts_each_scene_as_it_finishes(monkeypatch):
    from ipomdp_gaze.drivers import scene_eval
    counts = []

    def one_scene(spec, index):
        counts.append(progress.done)                # what the bar showed when this scene ran
        return [SimpleNamespace(searcher='elm', index=index)]

    monkeypatch.setattr(scene_eval, 'evaluate_scene', one_scene)
    with Progress(4, 'scenes', 'scene', stream=io.StringIO(), every_s=1e9) as progress:
        results = scene_eval.evaluate_scenes(None, 4, InlineExecutor(), progress=progress)
    assert counts == [0, 1, 2, 3] and progress.done == 4
    assert [r.index for r in results['elm']] == [0, 1, 2, 3]


def test_long_commands_report_on_stderr_unless_quiet(capsys):
    argv = ['evaluate', '--grid', '4x4', '--policy', 'elm', '--episodes', '200',
            '--bootstrap', '20', '--jobs', '1']
    assert cli_main(argv) == 0
    err = capsys.readouterr().err
    assert err.startswith('evaluate: 200/200 episodes (100%)'), err
    assert cli_main([*argv, '--quiet']) == 0
    assert capsys.readouterr().err == ''


def test_a_small_job_runs_here_and_a_pool_never_outnumbers_its_pieces(monkeypatch):
    monkeypatch.delenv('DASK_SCHEDULER_ADDRESS', raising=False)
    assert isinstance(make_executor(jobs=4, pieces=1), InlineExecutor)
    with make_executor(jobs=4, pieces=2) as executor:
        assert isinstance(executor, LocalExecutor) and executor.workers == 2
        assert executor.submit(pow, 3, 2).result() == 9
