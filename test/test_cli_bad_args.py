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
     "argument --absent-rate: expected a probability in [0, 1), got 'x'"),
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
    # tracebacks: numbers too large for OpenCV, numpy or a semaphore
    (['calibrate', '--pan-tilt', '--scenes', '1', '--out', 'x.yaml', '--spacing-deg', '1e21'],
     "argument --spacing-deg: expected degrees in (0, 90], got '1e21'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--fixation-stride', str(10 ** 21)],
     f"argument --fixation-stride: expected a positive integer up to 2^63 - 1, got '{10 ** 21}'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--jobs', str(10 ** 21)],
     f"argument --jobs: expected a number of worker processes from 1 to 4096, got '{10 ** 21}'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--windows', str(2 ** 31)],
     f"argument --windows: expected comma-separated whole numbers, got '{2 ** 31}'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--scale-factor', '1e21'],
     "argument --scale-factor: expected a number > 1 and at most 10, got '1e21'"),
    # the Python names absent_rate, hfov_deg and scale_factor, said after the work began
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--scale-factor', '0.5'],
     "argument --scale-factor: expected a number > 1 and at most 10, got '0.5'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--absent-rate', '1.5'],
     "argument --absent-rate: expected a probability in [0, 1), got '1.5'"),
    (['calibrate', '--pan-tilt', '--scenes', '1', '--out', 'x.yaml', '--hfov-deg', '180'],
     "argument --hfov-deg: expected degrees in (0, 180), got '180'"),
    # an empty path is not the current folder
    (['replay', ''], "argument PATH: an empty bag path ('': an unset shell variable?)"),
    (['reindex', ' '], "argument PATH: an empty bag path (' ': an unset shell variable?)"),
    (['evaluate', '--prior', ''],
     "argument --prior: an empty file path ('': an unset shell variable?)"),
])
def test_a_bad_value_is_one_line_naming_the_flag(tmp_path, cli_here, argv, message):
    assert _one_line(cli_here(*argv, cwd=tmp_path), argv[0]) == message


def test_calibrate_names_its_flags_where_the_scenes_said_python_names(tmp_path, cli_here):
    """``face_px must be 1 <= min <= max <= the scene side, got (30, 70)`` of the default."""
    run = cli_here('calibrate', '--pan-tilt', '--scenes', '1', '--out', 'x.yaml', '--hfov-deg',
                   '179', cwd=tmp_path)
    assert _one_line(run, 'calibrate') == (
        '--face-px 30,70: faces must be MIN <= MAX pixels from 1 to 6, the side of the scene '
        'that the grid, --camera and --hfov-deg make')
    run = cli_here('calibrate', '--pan-tilt', '--scenes', '1', '--out', 'x.yaml', '--face-px',
                   '-1', cwd=tmp_path)
    assert _one_line(run, 'calibrate') == '--face-px must be MIN,MAX, got -1'
    (tmp_path / 'labels.csv').write_text('path,x,y\n')
    run = cli_here('calibrate', '--images', 'labels.csv', '--labels', 'labels.csv', '--out',
                   'x.yaml', cwd=tmp_path)
    assert _one_line(run, 'calibrate') == 'image folder labels.csv is a file, not a folder'
    (tmp_path / 'images').mkdir()
    (tmp_path / 'other.csv').write_text('name,u\n')
    run = cli_here('calibrate', '--images', 'images', '--labels', 'other.csv', '--out', 'x.yaml',
                   cwd=tmp_path)
    assert _one_line(run, 'calibrate') == ('other.csv: header must name the columns path,x,y; '
                                           'missing path, x, y')
    assert not (tmp_path / 'x.yaml').exists()


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


@pytest.mark.parametrize('flag, value', [('--horizon', 2 ** 63 - 1),
                                         ('--max-fixations', 10 ** 21),
                                         ('--bootstrap', 10 ** 21)])
def test_a_count_too_large_for_numpy_is_the_task_too_large(cli_here, flag, value):
    """The numpy text was said: ``Maximum allowed dimension exceeded``, ``array is too big``."""
    run = cli_here('evaluate', '--grid', '3x3', '--episodes', '3', '--jobs', '1', '--quiet',
                   flag, str(value))
    assert _one_line(run, 'evaluate') == (
        'out of memory: the task is too large for this machine (a smaller --grid or fewer '
        '--episodes)')


def test_a_training_task_too_large_names_trains_own_counts(cli_here, tmp_path):
    """The train command has no --episodes: its line named that flag (``fewer --episodes``)."""
    run = cli_here('train', '--grid', '3x3', '--horizon', str(2 ** 62), '--epochs', '1',
                   '--out', 'p.yaml', '--quiet', cwd=tmp_path)
    assert _one_line(run, 'train') == (
        'out of memory: the task is too large for this machine (a smaller --grid or fewer '
        '--episodes-per-epoch, --eval-episodes or --final-episodes, or a shorter --horizon)')


class WorkBegan(Exception):
    """The command began the work of a count (a stand-in for the work was called)."""


def _began(monkeypatch, *targets):
    """Make each ``module.name`` raise :class:`WorkBegan` when called."""
    def fail(*args, **kwargs):
        raise WorkBegan
    for target in targets:
        monkeypatch.setattr(target, fail)


SCENES = 'ipomdp_gaze.vision.scenes.SceneSet'
PAN_TILT_TALLY = 'ipomdp_gaze.vision.calibrate.tally_pan_tilt_scenes'
TRAINER = 'ipomdp_gaze.policies.training.Trainer'
SCENE_WORK = ('ipomdp_gaze.commands.evaluate.evaluate_scenes',
              'ipomdp_gaze.commands.evaluate.evaluate_walks')
SIMULATION = ('ipomdp_gaze.commands.evaluate.evaluate',)
BIG = str(2 ** 63 - 1)


@pytest.mark.parametrize('argv, message, work', [
    # run for ever (a scene, an epoch after another), or queued a piece of work per scene
    (['calibrate', '--scenes', BIG, '--out', 'x.yaml'],
     f"argument --scenes: expected a number of scenes from 1 to 100000, got '{BIG}'", (SCENES,)),
    (['calibrate', '--scenes', '100001', '--out', 'x.yaml'],
     "argument --scenes: expected a number of scenes from 1 to 100000, got '100001'", (SCENES,)),
    (['train', '--grid', '3x3', '--epochs', BIG, '--out', 'x.yaml'],
     f"argument --epochs: expected a number of epochs from 0 to 1000000, got '{BIG}'",
     (TRAINER,)),
    (['evaluate', '--scenes', 'pan-tilt', '--jobs', '1', '--episodes', BIG],
     f'--episodes {BIG}: at most 100000 scenes with --scenes', SCENE_WORK),
    # ran out of memory (a 7x7 grid holds some 15 kB an episode) or for ever
    (['evaluate', '--grid', '3x3', '--jobs', '1', '--episodes', BIG],
     f'--episodes {BIG}: at most 200000 simulated episodes', SIMULATION),
    (['evaluate', '--observation', 'faces-420', '--jobs', '1', '--episodes', '200001'],
     '--episodes 200001: at most 200000 simulated episodes', SIMULATION),
    (['train', '--grid', '3x3', '--epochs', '1', '--out', 'x.yaml', '--episodes-per-epoch',
      BIG], 'argument --episodes-per-epoch: expected a number of episodes from 1 to 20000, '
     f"got '{BIG}'", (TRAINER,)),
    (['train', '--grid', '3x3', '--epochs', '1', '--out', 'x.yaml', '--eval-episodes',
      '200001'], 'argument --eval-episodes: expected a number of episodes from 1 to 200000, '
     "got '200001'", (TRAINER,)),
    (['train', '--grid', '3x3', '--epochs', '1', '--out', 'x.yaml', '--final-episodes', BIG],
     f"argument --final-episodes: expected a number of episodes from 0 to 200000, got '{BIG}'",
     (TRAINER,)),
    (['evaluate', '--scenes', 'pan-tilt', '--motion', 'walk', '--jobs', '1', '--episodes',
      '100001'], '--episodes 100001: at most 100000 walks with --scenes', SCENE_WORK),
    (['evaluate', '--scenes', 'pan-tilt', '--jobs', '1', '--episodes', '1', '--empty-scenes',
      BIG], f"argument --empty-scenes: expected a number of scenes from 0 to 100000, got '{BIG}'",
     SCENE_WORK),
    # a whole calibration, then a table the observation file cannot hold (K up to 256)
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--max-count', '257'],
     'argument --max-count: expected K from 2 to 256 (the counts an observation file holds), '
     "got '257'", (SCENES,)),
    (['calibrate', '--pan-tilt', '--grid', '3x3', '--scenes', '1', '--out', 'x.yaml',
      '--cells', 'grouped', '--raw-levels', '254'],
     "argument --raw-levels: expected an integer from 0 to 253 (K is at most 256), got '254'",
     (PAN_TILT_TALLY,)),
    (['calibrate', '--pan-tilt', '--grid', '3x3', '--scenes', '1', '--out', 'x.yaml',
      '--cells', 'grouped', '--group-edges', '3,6', '--raw-levels', '253'],
     '--group-edges and --raw-levels make K = 257 counts; an observation file holds at most 256',
     (PAN_TILT_TALLY,)),
    # OpenCV's "integer won't fit into a C int"
    (['calibrate', '--pan-tilt', '--grid', '3x3', '--scenes', '1', '--out', 'x.yaml',
      '--cells', 'grouped', '--min-neighbors', str(2 ** 31)],
     f"argument --min-neighbors: expected a positive integer up to 2^31 - 1 (OpenCV's int), "
     f"got '{2 ** 31}'", (PAN_TILT_TALLY,)),
    (['evaluate', '--scenes', 'pan-tilt', '--jobs', '1', '--episodes', '1',
      '--group-min-neighbors', str(2 ** 31)],
     f"argument --group-min-neighbors: expected an integer from 0 to 2^31 - 1 (OpenCV's int), "
     f"got '{2 ** 31}'", SCENE_WORK),
])
def test_a_count_too_large_to_finish_is_refused_by_its_flag(tmp_path, cli_here, monkeypatch,
                                                            argv, message, work):
    """Counts up to 2^63 - 1 were taken: calibrate --scenes and train --epochs ran for ever."""
    _began(monkeypatch, *work)
    assert _one_line(cli_here(*argv, cwd=tmp_path), argv[0]) == message
    assert not (tmp_path / 'x.yaml').exists()


@pytest.mark.parametrize('argv', [
    ['calibrate', '--scenes', '100000', '--out', 'x.yaml', '--max-count', '256'],
    ['train', '--grid', '3x3', '--epochs', '1000000', '--out', 'x.yaml'],
    ['train', '--grid', '3x3', '--epochs', '1', '--out', 'x.yaml', '--episodes-per-epoch',
     '20000', '--eval-episodes', '200000', '--final-episodes', '200000'],
    ['evaluate', '--grid', '3x3', '--jobs', '1', '--episodes', '200000'],
])
def test_the_largest_count_is_taken(tmp_path, cli_here, monkeypatch, argv):
    """The bounds are inclusive: the work begins (and is stopped here)."""
    _began(monkeypatch, SCENES, TRAINER, *SIMULATION)
    with pytest.raises(WorkBegan):
        cli_here(*argv, cwd=tmp_path)


@pytest.mark.parametrize('argv, message', [
    (['calibrate', '--pan-tilt', '--scenes', '1', '--out', 'x.yaml', '--spacing-deg', 'inf'],
     "argument --spacing-deg: expected degrees in (0, 90], got 'inf'"),
    (['calibrate', '--pan-tilt', '--scenes', '1', '--out', 'x.yaml', '--hfov-deg', '0'],
     "argument --hfov-deg: expected degrees in (0, 180), got '0'"),
    (['calibrate', '--scenes', '1', '--out', 'x.yaml', '--scale-factor', 'nan'],
     "argument --scale-factor: expected a number > 1 and at most 10, got 'nan'"),
    (['record', 'bag', '--max-bag-duration-s=-inf'],
     "argument --max-bag-duration-s: expected 0 (no split) to 3.2e+07 s, got '-inf'"),
])
def test_bounded_numbers_of_calibrate_and_record_say_their_range(tmp_path, cli_here, argv,
                                                                 message):
    assert _one_line(cli_here(*argv, cwd=tmp_path), argv[0]) == message


def test_one_range_type_reads_every_bounded_number():
    """The angles and pyramid step of calibrate, the split limits of record: number_in."""
    import argparse
    from ipomdp_gaze.commands import calibrate, record
    from ipomdp_gaze.commands.common import number_in
    parse = number_in(0.0, 90.0, 'degrees in (0, 90]', low_open=True)
    assert parse('90') == 90.0 and parse(' 1e-3 ') == 0.001
    for text in ('0', '90.5', 'nan', 'inf', '-inf', 'x', ''):
        with pytest.raises(argparse.ArgumentTypeError) as raised:
            parse(text)
        assert str(raised.value) == f'expected degrees in (0, 90], got {text!r}'
    closed = number_in(0.0, 1.0, 'a fraction')
    assert closed('0') == 0.0 and closed('1') == 1.0
    assert calibrate.SPACING_DEG('90') == 90.0 and calibrate.HFOV_DEG('179.5') == 179.5
    assert calibrate.SCALE_FACTOR('10') == 10.0
    assert record.split_limit(5.0, 's')('5') == 5.0
    for parse, text in ((calibrate.HFOV_DEG, '180'), (calibrate.SCALE_FACTOR, '1'),
                        (record.split_limit(5.0, 's'), '5.5')):
        with pytest.raises(argparse.ArgumentTypeError):
            parse(text)


@pytest.mark.parametrize('detector, option, message', [
    ('haar', 'scale_factor=abc', "detector.scale_factor must be a number, got 'abc'"),
    ('haar', "scale_factor='1.5'", "detector.scale_factor must be a number, got '1.5'"),
    ('haar', 'min_neighbors=1.5', 'detector.min_neighbors must be an integer, got 1.5'),
    ('haar', 'min_neighbors=true', 'detector.min_neighbors must be an integer, got True'),
    ('haar', 'min_size_px=big', 'detector.min_size_px must be an integer or a [width, height] '
     "pair of integers (or null), got 'big'"),
    ('yunet', 'top_k=[5]', 'detector.top_k must be an integer, got [5]'),
])
def test_a_detector_option_of_the_wrong_type_is_refused_as_the_file_would_be(
        tmp_path, cli_here, monkeypatch, detector, option, message):
    """
    The record check of the observation file was skipped for ``--detector-option``.

    ``scale_factor=abc`` said ``could not convert string to float: 'abc'``, ``top_k=[5]`` a
    TypeError's words, each in the detector's own words if at all; ``scale_factor='1.5'`` (text,
    which the file check refuses) was taken as the number and the calibration began.
    """
    _began(monkeypatch, SCENES, PAN_TILT_TALLY)
    for extra in ((), ('--pan-tilt', '--grid', '3x3')):
        run = cli_here('calibrate', '--scenes', '1', '--out', 'x.yaml', '--detector', detector,
                       '--detector-option', option, *extra, cwd=tmp_path)
        assert _one_line(run, 'calibrate') == f'--detector-option: {message}'
    assert not (tmp_path / 'x.yaml').exists()


DEMO_NODES = ('ipomdp_gaze.harness.demo.run_demo', 'ipomdp_gaze.harness.walk_demo.run_walk_demo')


@pytest.mark.parametrize('argv', [
    ['demo', '--seed', str(2 ** 31)],
    ['demo', '--scene', 'faces', '--seed', str(2 ** 32)],
    ['demo', '--scene', 'faces', '--fovea', '--seed', str(2 ** 31)],
    ['demo', '--scene', 'faces', '--motion', 'walk', '--seed', str(2 ** 63 - 1)],
])
def test_a_demo_seed_beyond_the_nodes_parameter_is_refused_before_they_start(
        tmp_path, cli_here, monkeypatch, argv):
    """The nodes' seed is 0..2^31 - 1: a larger one started them, then a node refused it."""
    _began(monkeypatch, *DEMO_NODES)
    assert _one_line(cli_here(*argv, cwd=tmp_path), 'demo') == (
        f'--seed {argv[-1]}: the nodes take a seed from 0 to 2^31 - 1 (2147483647)')


@pytest.mark.parametrize('argv', [
    ['demo', '--seed', str(2 ** 31 - 1)],
    ['demo', '--scene', 'faces', '--faces', '2', '--seed', str(2 ** 63 - 1)],
])
def test_the_largest_node_seed_and_any_offline_room_seed_are_taken(tmp_path, cli_here,
                                                                   monkeypatch, argv):
    """The bound is inclusive, and --faces K runs offline, without the nodes' parameter."""
    _began(monkeypatch, *DEMO_NODES, 'ipomdp_gaze.drivers.rooms.room_demo')
    with pytest.raises(WorkBegan):
        cli_here(*argv, cwd=tmp_path)
