# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze reproduce``: its runs split over processes give the serial run's numbers."""
from dataclasses import replace
import json

from ipomdp_gaze.cli import main as cli_main
from ipomdp_gaze.commands import reproduce
from ipomdp_gaze.drivers import pieces
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.simulation.executor import LocalExecutor
from ipomdp_gaze.simulation.simulate import simulate
import numpy as np
import pytest

GRID, FPOC = Grid(4, 4, 0.42), make_fpoc('human')


def test_pieces_on_two_processes_give_the_serial_matrices_and_intervals():
    serial = pieces.Runner(GRID, FPOC, 60, 5, 50)
    with LocalExecutor(2) as pool:
        split = pieces.Runner(GRID, FPOC, 60, 5, 50, pool)
        for runner, chunk in ((serial, None), (split, 7)):
            runner.submit('elm', make_baseline('elm', GRID, FPOC), horizon=12, chunk=chunk)
            runner.submit('greedy', make_baseline('greedy', GRID, FPOC), 40, 12, chunk)
            runner.collect()
    whole = simulate(GRID, FPOC, make_baseline('greedy', GRID, FPOC), 40, 12, 5,
                     targets=serial.targets[:40])
    np.testing.assert_array_equal(split.correct['greedy'], whole.correct)
    for name in ('elm', 'greedy'):
        np.testing.assert_array_equal(split.correct[name], serial.correct[name])
        assert split.summary(name) == serial.summary(name)
    assert split.paired('greedy', 'elm') == serial.paired('greedy', 'elm')
    assert split.decisions['greedy'] == 40 * 12


def test_a_run_cut_before_it_is_reliably_at_90_percent_is_refused():
    runner = pieces.Runner(GRID, FPOC, 200, 0, 20)
    runner.submit('random', make_baseline('random', GRID, FPOC), horizon=3)
    runner.collect()
    with pytest.raises(RuntimeError, match='raise the horizon'):
        runner.summary('random')


def test_cached_pieces_are_reused_only_for_the_same_inputs(tmp_path):
    def run(name, cache, recipe=None, seed=2):
        runner = pieces.Runner(GRID, FPOC, 30, seed, 20, cache=cache)
        runner.submit('p', make_baseline(name, GRID, FPOC), horizon=10, chunk=10,
                      recipe=('baseline', name) if recipe is None else recipe)
        runner.collect()
        return runner.correct['p'], runner.map_prob['p']

    first = pieces.PieceCache(tmp_path)
    fresh = run('elm', first)
    assert first.hits == 0 and len(list(tmp_path.glob('*.bin'))) == 3
    whole = simulate(GRID, FPOC, make_baseline('elm', GRID, FPOC), 30, 10, 2)
    np.testing.assert_array_equal(fresh[0], whole.correct)
    np.testing.assert_array_equal(fresh[1], whole.map_prob)
    again = pieces.PieceCache(tmp_path)
    cached = run('elm', again)
    assert again.hits == 3 and cached[1].dtype == np.float64
    for kept, new in zip(cached, fresh):
        np.testing.assert_array_equal(kept, new)
    other = pieces.PieceCache(tmp_path)
    for kept, new in zip(run('map', other), run('map', None)):
        np.testing.assert_array_equal(kept, new)
    run('elm', other, seed=3)
    assert other.hits == 0                 # another policy, another seed: simulated again
    assert pieces.PieceCache(tmp_path).key(None, GRID, FPOC, np.zeros(3), 4, 0, (0, 3)) is None
    for path in tmp_path.glob('*.bin'):                     # damaged pieces are simulated again
        path.write_bytes(path.read_bytes()[:-1])
    damaged = pieces.PieceCache(tmp_path)
    for kept, new in zip(run('elm', damaged), fresh):
        np.testing.assert_array_equal(kept, new)
    assert damaged.hits == 0


def test_a_piece_file_of_another_layout_is_simulated_again(tmp_path):
    """A file with only the packed bits (no ``map_prob``), whatever its length, is not read."""
    def run(cache):
        runner = pieces.Runner(GRID, FPOC, 20, 1, 20, cache=cache)
        runner.submit('elm', make_baseline('elm', GRID, FPOC), horizon=8,
                      recipe=('baseline', 'elm'))
        runner.collect()
        return runner.correct['elm'], runner.map_prob['elm']

    fresh = run(pieces.PieceCache(tmp_path))
    (path,) = tmp_path.glob('*.bin')
    head, _, body = path.read_bytes().partition(b'\n')
    meta = json.loads(head)
    bits = np.packbits(fresh[0]).tobytes()
    for layout in ({'correct': 'packbits'}, None):
        foreign = {**meta, 'layout': layout} if layout else {k: v for k, v in meta.items()
                                                             if k != 'layout'}
        for tail in (bits, body):
            path.write_bytes(json.dumps(foreign).encode() + b'\n' + tail)
            cache = pieces.PieceCache(tmp_path)
            for kept, new in zip(run(cache), fresh):
                np.testing.assert_array_equal(kept, new)
            assert cache.hits == 0


def test_a_longer_run_reuses_the_pieces_of_a_shorter_one(tmp_path):
    """
    Runs of n and 2n episodes with the same chunk share the first n episodes' pieces.

    The pieces are keyed by their own targets and rows, not the run's length; that reuse is
    right because a run of n episodes is the first n of a longer one (targets, noise and, for a
    stochastic policy, each piece's own stream).
    """
    def run(episodes, cache):
        runner = pieces.Runner(GRID, FPOC, episodes, 4, 20, cache=cache)
        for name in ('elm', 'random'):
            runner.submit(name, make_baseline(name, GRID, FPOC), horizon=9, chunk=10,
                          recipe=('baseline', name))
        runner.collect()
        return runner

    short = run(30, pieces.PieceCache(tmp_path))
    cache = pieces.PieceCache(tmp_path)
    long = run(60, cache)
    assert cache.hits == 2 * 3 and len(list(tmp_path.glob('*.bin'))) == 2 * 6
    alone = run(60, None)
    for name in ('elm', 'random'):
        for matrices in ('correct', 'map_prob'):
            kept, fresh = getattr(long, matrices)[name], getattr(alone, matrices)[name]
            np.testing.assert_array_equal(kept[:30], getattr(short, matrices)[name])
            np.testing.assert_array_equal(kept, fresh)
    other = pieces.PieceCache(tmp_path)
    runner = pieces.Runner(GRID, FPOC, 60, 4, 20, cache=other)
    runner.submit('elm', make_baseline('elm', GRID, FPOC), horizon=9, chunk=20,
                  recipe=('baseline', 'elm'))
    runner.collect()
    assert other.hits == 0                 # other chunk boundaries: other pieces


def test_retraining_starts_a_kernel_where_its_file_says():
    spec = reproduce._load('human-7x7-infomax')
    argv = reproduce.retrain_argv(spec, 'k.yaml')
    assert '--init-elm' not in argv and argv[argv.index('--fpoc') + 1] == 'human'
    started = replace(spec, training={**spec.training, 'init': 'elm x 15'})
    argv = reproduce.retrain_argv(started, 'k.yaml')
    assert argv[argv.index('--init-elm') + 1] == '15'
    assert argv[argv.index('--epochs') + 1] == str(spec.training['epochs'])


def test_the_shipped_exponential_kernel_looks_straight_at_a_likely_target():
    """The paper's claim for the exponential FPOC (Fig. 6), on the shipped kernel."""
    spec = reproduce._load('exponential-11x11-infomax')
    assert reproduce.preferred_offset_cells(spec.kernel) == 0.0
    assert reproduce.preferred_offset_cells(reproduce._load('human-7x7-infomax').kernel) == 1.0


def _tables(path):
    """Return the report's lines without its timing lines (planner ms, the run's own time)."""
    return [line for line in path.read_text().splitlines()
            if not line.startswith(('Planner decision time', 'This report:'))]


def test_the_report_is_the_same_on_one_or_two_processes_and_from_the_cache(tmp_path, capsys):
    small = ['--episodes', '300', '--episodes-greedy', '12', '--episodes-planner', '12',
             '--bootstrap', '50']
    cache = tmp_path / 'cache'
    assert cli_main(['reproduce', '--out', str(tmp_path / 'a'), '--jobs', '2', '--cache',
                     str(cache), *small]) == 0
    assert cli_main(['reproduce', '--out', str(tmp_path / 'b'), '--jobs', '1', '--cache',
                     str(cache), *small]) == 0
    assert cli_main(['reproduce', '--out', str(tmp_path / 'c'), '--jobs', '1', '--no-cache',
                     *small]) == 0
    log = capsys.readouterr().err
    pieces = len(list(cache.glob('*.bin')))
    assert pieces > 0 and f'{pieces} pieces from the cache' in log
    report = _tables(tmp_path / 'a' / 'reproduction.md')
    assert report == _tables(tmp_path / 'b' / 'reproduction.md')
    assert report == _tables(tmp_path / 'c' / 'reproduction.md')
    # the notes quote the shipped run's numbers: a run of other options says so before them
    text = (tmp_path / 'a' / 'reproduction.md').read_text()
    assert ('*The notes below quote the shipped run (`--episodes 20000`, `--episodes-greedy '
            '2000`, `--episodes-planner 2000`, `--seed 0`); this run used `--episodes 300`, '
            '`--episodes-greedy 12`, `--episodes-planner 12`, and its own numbers are the '
            'tables and figures above.*') in text
    assert sum(line.startswith('| rollout planner') for line in report) == 1
    for figure in ('fig3_learning_curves', 'fig4a_percent_correct', 'fig6_kernels_by_fpoc'):
        assert (tmp_path / 'a' / 'figures' / f'{figure}.png').stat().st_size > 0


def test_rao_blackwellised_runs_keep_the_searches_and_the_curve_with_less_variance(tmp_path):
    """Same fixations and correctness; E[max B'] has the mean of max B and no more variance."""
    greedy = make_baseline('greedy', GRID, FPOC)
    cache = pieces.PieceCache(tmp_path)
    # 600 episodes in 3 pieces of 200 (was 3,000): the mean check is in standard errors of the
    # paired differences, so it rescales itself with the sample size (|mean| was 2.0 SE at 600,
    # 1.0 at 3,000); the variance ratio rb / raw is at most 0.38 at every fixation with either
    # size, while its sampling error at 600 episodes is about 8%: the check stays decisive.
    episodes, chunk = 600, 200
    plain = pieces.Runner(GRID, FPOC, episodes, 6, 20, cache=cache)
    plain.submit('greedy', greedy, horizon=5, chunk=chunk, recipe=('baseline', 'greedy'))
    plain.collect()
    smooth = pieces.Runner(GRID, FPOC, episodes, 6, 20, cache=cache, rao_blackwell=True)
    smooth.submit('greedy', greedy, horizon=5, chunk=chunk, recipe=('baseline', 'greedy'))
    smooth.collect()
    assert cache.hits == 0                      # a Rao-Blackwellised piece has its own key
    np.testing.assert_array_equal(smooth.correct['greedy'], plain.correct['greedy'])
    rb, raw = smooth.map_prob['greedy'], plain.map_prob['greedy']
    # From the uniform prior every episode makes the same first fixation, so the first column
    # is one number: the score of that fixation.
    first = make_baseline('greedy', GRID, FPOC).expected_percent_correct(np.ones(16))
    np.testing.assert_allclose(rb[:, 0], first.max(), rtol=0, atol=1e-14)
    # Same mean (paired differences, 5 standard errors) and smaller variance at every fixation.
    diff = rb - raw
    error = diff.std(axis=0) / np.sqrt(diff.shape[0])
    assert np.all(np.abs(diff.mean(axis=0)) < 5 * error)
    assert np.all(rb.var(axis=0) < raw.var(axis=0))
    again = pieces.Runner(GRID, FPOC, episodes, 6, 20, cache=cache, rao_blackwell=True)
    again.submit('greedy', greedy, horizon=5, chunk=chunk, recipe=('baseline', 'greedy'))
    again.collect()
    assert cache.hits == 3
    np.testing.assert_array_equal(again.map_prob['greedy'], rb)


def test_retraining_writes_into_the_output_folder_and_fig3_reads_its_curve(
        tmp_path, monkeypatch):
    """``--retrain`` never writes into the installed package (QA); Fig. 3 then shows its curve."""
    import ipomdp_gaze.cli
    seen = []
    monkeypatch.setattr(ipomdp_gaze.cli, 'main', lambda argv: seen.append(argv) or 0)
    paths = reproduce._retrain(lambda message: None, tmp_path / 'out' / 'kernels')
    assert set(paths) == set(reproduce.KERNELS)
    outs = [argv[argv.index('--out') + 1] for argv in seen]
    assert outs == [str(tmp_path / 'out' / 'kernels' / f'{name}.yaml')
                    for name in reproduce.KERNELS]
    shipped = reproduce._curves({})
    assert [p.name for p in shipped.values()] == ['human-7x7-infomax.csv',
                                                  'human-7x7-logistic.csv']
    paths['human-7x7-infomax'].with_suffix('.csv').write_text('epoch\n')
    conv = reproduce._curves(paths)['weight sharing (conv, 27 weights)']
    assert conv == tmp_path / 'out' / 'kernels' / 'human-7x7-infomax.csv'
    monkeypatch.setattr(reproduce, 'ROOT', tmp_path)        # an installed package: no docs/
    assert reproduce._curves({}) is None
