# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Policy files: round trip, shipped names, and every error naming its problem."""
from pathlib import Path

from ipomdp_gaze.cli import main
from ipomdp_gaze.files.observation_file import fingerprint, load_observation
from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies import policy_file as pf
from ipomdp_gaze.policies.conv import (check_kernel, ConvPolicy, kernel_from_radial,
                                       radial_bins)
from ipomdp_gaze.policies.logistic import LogisticPolicy
from ipomdp_gaze.policies.policy_file import (load_policy, load_policy_spec, PolicyFileError,
                                              PolicySpec, save_policy, shipped_kernels)
from ipomdp_gaze.simulation.simulate import simulate
import numpy as np
import pytest
import yaml

GRID = Grid(3, 4, 0.42)


def conv_spec(grid=GRID, symmetric=True, seed=0):
    """Make a conv spec with a random radial (or fully random) kernel."""
    rng = np.random.default_rng(seed)
    if symmetric:
        kernel = kernel_from_radial(grid, rng.normal(size=radial_bins(grid)[0].size))
    else:
        kernel = rng.normal(size=grid.kernel_shape)
    return PolicySpec(grid=grid, fpoc=make_fpoc('human'), reward='infomax', family='conv',
                      kernel=kernel, training={'epochs': 3, 'seed': 1},
                      evaluation={'episodes': 100, 'fixations_to_90': 5.5, 'ci95': [5.0, 6.0]})


def logistic_spec(grid=GRID):
    rng = np.random.default_rng(1)
    return PolicySpec(grid=grid, fpoc=make_fpoc('camera', dprime=3.0), reward='fixate_target',
                      family='logistic', action='sample',
                      theta=rng.normal(size=(grid.n_cells, grid.n_cells)))


def write_doc(tmp_path, doc, name='p.yaml'):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(doc) if not isinstance(doc, str) else doc)
    return path


def good_doc():
    return conv_spec().to_dict()


@pytest.mark.parametrize('symmetric', [True, False])
def test_conv_round_trip_is_exact(tmp_path, symmetric):
    spec = conv_spec(symmetric=symmetric)
    path = save_policy(tmp_path / 'sub' / 'k.yaml', spec)
    back = load_policy_spec(path)
    assert back.grid == spec.grid and back.fpoc == spec.fpoc
    assert (back.reward, back.family, back.action) == ('infomax', 'conv', 'argmax')
    np.testing.assert_array_equal(back.kernel, spec.kernel)
    assert back.theta is None
    assert back.training == {'epochs': 3, 'seed': 1}
    assert back.evaluation['ci95'] == [5.0, 6.0]
    assert back.path == path
    doc = yaml.safe_load(path.read_text())
    assert doc['format'] == 'ipomdp_gaze/policy-v1'
    # The radial block is written exactly when the kernel is radially weight-shared.
    assert ('radial' in doc) == symmetric
    if symmetric:
        assert len(doc['radial']['weight']) == radial_bins(GRID)[0].size


def test_logistic_round_trip_is_exact(tmp_path):
    spec = logistic_spec()
    back = load_policy_spec(save_policy(tmp_path / 'l.yaml', spec))
    np.testing.assert_array_equal(back.theta, spec.theta)
    assert back.fpoc == make_fpoc('camera', dprime=3.0)
    assert (back.reward, back.family, back.action) == ('fixate_target', 'logistic', 'sample')
    policy = load_policy(tmp_path / 'l.yaml')
    assert isinstance(policy, LogisticPolicy) and policy.action == 'sample'


def test_radial_counts_match_the_paper():
    assert radial_bins(Grid(7, 7))[0].size == 27
    assert radial_bins(Grid(11, 11))[0].size == 61


def test_loaded_conv_policy_acts_like_the_kernel(tmp_path):
    grid = Grid(5, 5)
    spec = conv_spec(grid, symmetric=False, seed=3)
    path = save_policy(tmp_path / 'c.yaml', spec)
    policy = load_policy(path, grid=grid, fpoc=make_fpoc('human'))
    assert isinstance(policy, ConvPolicy) and policy.name == 'c'
    fpoc = make_fpoc('human')
    a = simulate(grid, fpoc, policy, 50, seed=4)
    b = simulate(grid, fpoc, ConvPolicy(grid, spec.kernel), 50, seed=4)
    np.testing.assert_array_equal(a.fixations, b.fixations)


def test_action_override_and_default(tmp_path):
    doc = good_doc()
    del doc['action']
    path = write_doc(tmp_path, doc)
    assert load_policy(path).action == 'argmax'
    assert load_policy(path, action='sample').action == 'sample'
    with pytest.raises(PolicyFileError, match="unknown action 'best'"):
        load_policy(path, action='best')


def test_grid_mismatch_is_an_error(tmp_path):
    path = save_policy(tmp_path / 'k.yaml', conv_spec())
    with pytest.raises(PolicyFileError, match=r'3x4 grid but the task grid is 4x3'):
        load_policy(path, grid=Grid(4, 3))


def test_fpoc_or_spacing_mismatch_warns(tmp_path):
    path = save_policy(tmp_path / 'k.yaml', conv_spec())
    messages = []
    load_policy(path, grid=Grid(3, 4, 0.42), fpoc=make_fpoc('human'), warn=messages.append)
    assert messages == []
    policy = load_policy(path, grid=Grid(3, 4, 0.5), fpoc=make_fpoc('exponential'),
                         warn=messages.append)
    assert isinstance(policy, ConvPolicy)
    assert len(messages) == 2
    assert 'spacing_deg 0.42' in messages[0] and 'exponential' in messages[1]
    with pytest.warns(pf.PolicyFileWarning, match='FPOC'):
        load_policy(path, fpoc=make_fpoc('exponential'))


def test_a_policy_used_off_its_training_scenes_warns(tmp_path, capsys):
    """QA: a policy trained with an absent prior, evaluated without it, said nothing."""
    from dataclasses import replace
    from ipomdp_gaze.cli import main
    spec = replace(conv_spec(), training={'epochs': 3, 'absent_prior': 0.2})
    path = save_policy(tmp_path / 'k.yaml', spec)
    messages = []
    pf.check_scene(load_policy_spec(path), {'absent_prior': 0.2}, messages.append)
    assert messages == []
    pf.check_scene(load_policy_spec(path), {'jump_prob': 0.1}, messages.append)
    assert messages == [f'{path}: policy was trained with jump_prob 0 but is used with 0.1',
                        f'{path}: policy was trained with absent_prior 0.2 but is used with 0']
    args = ['evaluate', '--grid', '3x4', '--policy-file', str(path), '--episodes', '20',
            '--quiet']
    assert main(args) == 0
    assert 'policy was trained with absent_prior 0.2 but is used with 0' in capsys.readouterr().err
    assert main(args + ['--absent-prior', '0.2']) == 0
    assert 'warning' not in capsys.readouterr().err


def test_a_policy_trained_on_a_prior_is_said_on_the_scenes_too(tmp_path, capsys):
    """QA: evaluate --scenes (every search uniform) used a file trained on a prior silently."""
    from dataclasses import replace
    spec = load_policy_spec('faces-420-infomax')
    rows = np.ones(spec.grid.shape)
    rows[0] = 3.0                                   # the top row: 3 times any other cell
    trained = save_policy(tmp_path / 'trained.yaml', replace(
        spec, path=None, training={**spec.training, 'prior': (rows / rows.sum()).tolist()}))
    plain = save_policy(tmp_path / 'plain.yaml', replace(spec, path=None))
    said = []                                       # the words of evaluate without --scenes
    pf.check_scene(load_policy_spec(trained), {}, said.append)
    assert said == [f'{trained}: policy was trained with a prior that is not uniform but is '
                    'used with the uniform one']
    args = ['evaluate', '--scenes', 'faces-420', '--episodes', '1', '--quiet', '--policy-file']
    assert main(args + [str(trained)]) == 0
    err = capsys.readouterr().err
    assert err.splitlines().count(f'ipomdp-gaze evaluate: warning: {said[0]}') == 1, err
    assert main(args + [str(plain)]) == 0
    assert 'warning' not in capsys.readouterr().err


def _break(doc, change):
    doc = dict(doc)
    change(doc)
    return doc


def _set(key, value):
    return lambda d: d.__setitem__(key, value)


def _delete(key):
    return lambda d: d.pop(key)


def _nested(block, key, value):
    def change(d):
        d[block] = dict(d[block])
        if value is _MISSING:
            del d[block][key]
        else:
            d[block][key] = value
    return change


_MISSING = object()


def _kernel_entry(value):
    def change(d):
        d['kernel'] = [list(r) for r in d['kernel']]
        d['kernel'][1][2] = value
    return change


ERRORS = [
    ('missing-format', _delete('format'), 'missing key format'),
    ('missing-grid', _delete('grid'), 'missing key grid'),
    ('missing-fpoc', _delete('fpoc'), 'missing key fpoc'),
    ('missing-reward', _delete('reward'), 'missing key reward'),
    ('missing-family', _delete('family'), 'missing key family'),
    ('missing-kernel', _delete('kernel'), r'missing key kernel \(required for family conv\)'),
    ('wrong-format', _set('format', 'ipomdp_gaze/policy-v2'),
     r"wrong format string 'ipomdp_gaze/policy-v2'"),
    ('unknown-key', _set('kernal', [[1.0]]), 'unknown key kernal'),
    ('unknown-family', _set('family', 'mlp'), r"unknown family 'mlp'; valid: conv, logistic"),
    ('unknown-reward', _set('reward', 'entropy'), r"unknown reward 'entropy'"),
    ('unknown-action', _set('action', 'best'), r"unknown action 'best'; valid: argmax, sample"),
    ('grid-not-mapping', _set('grid', '7x7'), 'grid must be a mapping'),
    ('grid-missing-rows', _nested('grid', 'rows', _MISSING), 'missing key grid.rows'),
    ('grid-missing-spacing', _nested('grid', 'spacing_deg', _MISSING),
     'missing key grid.spacing_deg'),
    ('grid-bad-rows', _nested('grid', 'rows', 0), 'grid.rows must be a positive integer'),
    ('grid-bad-spacing', _nested('grid', 'spacing_deg', -1.0), 'grid.spacing_deg must be'),
    ('fpoc-unknown-model', _nested('fpoc', 'model', 'eagle'), "fpoc: unknown FPOC model 'eagle'"),
    ('fpoc-unknown-param', _nested('fpoc', 'scale_deg', 2.0),
     "fpoc: unknown parameter 'scale_deg'"),
    ('fpoc-no-model', _nested('fpoc', 'model', _MISSING), "fpoc: .*'model'"),
    ('kernel-shape', _set('kernel', [[0.0] * 5] * 5),
     r'kernel has shape \(5, 5\) but a 3x4 grid needs \(5, 7\)'),
    ('kernel-1d', _set('kernel', [0.0] * 35), 'kernel must be a 2-D list of lists'),
    ('kernel-ragged', _set('kernel', [[0.0] * 7] * 4 + [[0.0] * 6]),
     'kernel must be a list of lists of numbers'),
    ('kernel-text', _kernel_entry('big'), 'kernel must be a list of lists of numbers'),
    ('kernel-nan', _kernel_entry(float('nan')), r'non-finite values in kernel: 1 entries, '
     r'the first at \[1\]\[2\]'),
    ('kernel-inf', _kernel_entry(float('inf')), r'non-finite values in kernel'),
    ('kernel-huge', _kernel_entry(1e308), r'kernel: the sum of its absolute values must be at '
     r'most 1e\+300 \(a score is a sum of belief times weights and must not overflow\), got '
     r'1e\+308'),
    ('theta-for-conv', _set('theta', [[0.0]]), 'family conv takes kernel, not theta'),
    ('radial-disagrees', _kernel_entry(123.0),
     r'radial disagrees with kernel: squared_distance \d+ has weight .* kernel\[1\]\[2\] is 123'),
    ('radial-wrong-distances', _nested('radial', 'squared_distance', [0, 1, 2]),
     r'radial.squared_distance must list the 9 distinct squared distances of a 3x4 grid'),
    ('radial-missing-weight', _nested('radial', 'weight', _MISSING),
     'missing key radial.weight'),
    ('radial-short-weight', _nested('radial', 'weight', [0.0]),
     'radial.weight has 1 values but radial.squared_distance has 9'),
    ('training-not-mapping', _set('training', [1, 2]), 'training must be a mapping'),
    ('training-negative-epochs', _nested('training', 'epochs', -3),
     r'training.epochs must be a whole number >= 0, got -3'),
    ('training-fractional-epochs', _nested('training', 'epochs', 2.5),
     r'training.epochs must be a whole number >= 0, got 2.5'),
    ('training-negative-seconds', _nested('training', 'wall_seconds', -1.0),
     r'training.wall_seconds must be a number >= 0, got -1.0'),
    ('training-null-epochs', _nested('training', 'epochs', None),
     r'training.epochs must be a whole number >= 0, got None'),
    ('training-null-seconds', _nested('training', 'wall_seconds', None),
     r'training.wall_seconds must be a number >= 0, got None'),
    ('training-scene-not-a-number', _nested('training', 'absent_prior', [1]),
     r'training.absent_prior must be a number, got \[1\]'),
    ('training-scene-text', _nested('training', 'motion_sigma_cells', 'x'),
     r"training.motion_sigma_cells must be a number, got 'x'"),
    ('kernel-null', _set('kernel', None),
     r'kernel has no value: a 3x4 grid needs a 5 x 7 list of lists of numbers'),
    ('evaluation-bad-ci', _nested('evaluation', 'ci95', [1.0]), r'evaluation.ci95 must be'),
    ('evaluation-bad-f90', _nested('evaluation', 'fixations_to_90', 'fast'),
     'evaluation.fixations_to_90 must be a number or null'),
]


@pytest.mark.parametrize('name,change,message', ERRORS, ids=[e[0] for e in ERRORS])
def test_every_error_names_its_problem(tmp_path, name, change, message):
    path = write_doc(tmp_path, _break(good_doc(), change))
    with pytest.raises(PolicyFileError, match=message) as info:
        load_policy_spec(path)
    assert str(path) in str(info.value)


def test_logistic_errors(tmp_path):
    doc = logistic_spec().to_dict()
    path = write_doc(tmp_path, _break(doc, _delete('theta')))
    with pytest.raises(PolicyFileError, match=r'missing key theta \(required for family logistic'):
        load_policy_spec(path)
    path = write_doc(tmp_path, _break(doc, _set('theta', [[0.0] * 12] * 11)))
    with pytest.raises(PolicyFileError, match=r'theta has shape \(11, 12\) but a 3x4 grid '
                                              r'needs \(12, 12\)'):
        load_policy_spec(path)
    bad = [list(r) for r in doc['theta']]
    bad[4][0] = float('nan')
    path = write_doc(tmp_path, _break(doc, _set('theta', bad)))
    with pytest.raises(PolicyFileError, match=r'non-finite values in theta: 1 entries, the '
                                              r'first at \[4\]\[0\] is nan'):
        load_policy_spec(path)
    path = write_doc(tmp_path, _break(doc, _set('kernel', [[0.0]])))
    with pytest.raises(PolicyFileError, match='family logistic takes theta, not kernel'):
        load_policy_spec(path)
    bad[4][0], bad[4][1] = 1e308, -1e308
    path = write_doc(tmp_path, _break(doc, _set('theta', bad)))
    with pytest.raises(PolicyFileError, match=r'theta: the sum of its absolute values in a row '
                                              r'must be at most 1e\+300'):
        load_policy_spec(path)


@pytest.mark.parametrize('text,message', [
    ('grid: [unclosed', r'not YAML at line 1'),
    ('- 1\n- 2\n', 'a policy file must be a YAML mapping, got a list'),
    ('', r'a policy file must be a YAML mapping, got nothing \(an empty document\)'),
    ('!!python/object/apply:os.system ["echo hi"]\n', 'not YAML'),
])
def test_not_a_policy_document(tmp_path, text, message):
    path = write_doc(tmp_path, text)
    with pytest.raises(PolicyFileError, match=message):
        load_policy_spec(path)


def test_missing_file_lists_shipped_names(tmp_path):
    with pytest.raises(PolicyFileError, match=r"'no-such-kernel' not found and not a shipped "
                                              r'kernel name \(shipped: '):
        load_policy_spec('no-such-kernel')
    with pytest.raises(PolicyFileError, match='not found'):
        load_policy_spec(tmp_path / 'absent.yaml')
    with pytest.raises(PolicyFileError, match=r"'.*' is a folder, not a file"):
        load_policy_spec(tmp_path)                      # QA: it said 'not found'


def test_shipped_names_resolve_with_and_without_suffix(tmp_path, monkeypatch):
    monkeypatch.setattr(pf, 'KERNEL_DIR', tmp_path)
    save_policy(tmp_path / 'human-3x4-infomax.yaml', conv_spec())
    assert shipped_kernels() == ['human-3x4-infomax']
    for name in ('human-3x4-infomax', 'human-3x4-infomax.yaml'):
        assert load_policy_spec(name).path == tmp_path / 'human-3x4-infomax.yaml'
    # A name with a directory part is a path, never looked up among the shipped kernels.
    with pytest.raises(PolicyFileError, match='not found'):
        load_policy_spec('elsewhere/human-3x4-infomax')


@pytest.mark.parametrize('name', shipped_kernels())
def test_every_shipped_kernel_loads(name):
    spec = load_policy_spec(name)
    assert spec.path.parent == pf.KERNEL_DIR
    if spec.fpoc is not None:
        task = f'{spec.fpoc.model}-{spec.grid.rows}x{spec.grid.cols}-{spec.reward}'
    else:                       # a count model's kernel is named for the model it was trained on
        task = f"{spec.observation['name']}-{spec.reward}"
        model = load_observation(spec.observation['name'])
        assert spec.observation['sha256'] == fingerprint(model)
    # A kernel trained for a moving target (docs/design.md section 7) says so in its name.
    moving = 'motion_sigma_cells' in spec.training
    assert name == (f'{task}-tracking' if moving else task)
    if moving:
        assert spec.evaluation['motion_sigma_cells'] == spec.training['motion_sigma_cells']
        assert 0 < spec.evaluation['tracking_accuracy'] <= 1
    assert spec.family == 'conv' and spec.radial() is not None
    evaluation = spec.evaluation
    assert evaluation['episodes'] == 20000 and evaluation['action'] == 'argmax'
    assert evaluation['ci95'][0] <= evaluation['fixations_to_90'] <= evaluation['ci95'][1]
    assert spec.training['episodes_per_epoch'] == 150


def test_evaluate_cli_keys_results_by_stem(tmp_path, capsys):
    grid = Grid(3, 3)
    path = save_policy(tmp_path / 'mine.yaml', conv_spec(grid))
    out = tmp_path / 'r.json'
    assert main(['evaluate', '--grid', '3x3', '--policy-file', str(path), '--policy', 'map',
                 '--episodes', '200', '--bootstrap', '50', '--json', str(out)]) == 0
    import json
    result = json.loads(out.read_text())
    assert set(result['policies']) == {'map', 'mine'}
    assert 'mine' in capsys.readouterr().out


@pytest.mark.parametrize('content,message', [
    ('format: nope\n', 'missing key grid'),
    (None, 'not found'),
])
def test_evaluate_cli_bad_file_is_one_line(tmp_path, capsys, content, message):
    path = tmp_path / 'bad.yaml'
    if content is not None:
        path.write_text(content)
    assert main(['evaluate', '--grid', '3x3', '--policy-file', str(path),
                 '--episodes', '10']) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err
    assert err.startswith('ipomdp-gaze evaluate: error: ') and message in err


def test_evaluate_cli_kernel_whose_scores_overflow_is_one_line(tmp_path, capsys):
    """QA: huge finite entries were accepted and made NaN scores (the search fixated cell 0)."""
    huge = [[1e308 * (-1) ** (r + c) for c in range(7)] for r in range(5)]
    path = write_doc(tmp_path, dict(good_doc(), kernel=huge, radial=None))
    assert main(['evaluate', '--grid', '3x4', '--policy-file', str(path),
                 '--episodes', '10']) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err
    assert 'kernel: the sum of its absolute values must be at most 1e+300' in err


def test_a_kernel_whose_scores_overflow_is_refused_where_kernels_are_checked():
    """The parameter's check (``policy.kernel``): the QA kernel, 1e308 of either sign."""
    grid = Grid(11, 11)
    with pytest.raises(ValueError, match=r'policy.kernel: the sum of its absolute values must be '
                                         r'at most 1e\+300 .*, got inf'):
        check_kernel([-1e308, 1e308] * 220 + [1.0], grid, 'policy.kernel')
    with pytest.raises(ValueError, match='theta: the sum of its absolute values in a row'):
        LogisticPolicy(GRID, np.diag([1e301] * GRID.n_cells))
    kernel = check_kernel([1e297] * 441, grid)                   # the sum is 4.4e299: scores
    for method in ('direct', 'fft'):                            # stay finite on either path
        belief = np.random.default_rng(0).dirichlet(np.ones(121))
        assert np.isfinite(ConvPolicy(grid, kernel, method=method).scores(belief)).all()


def test_evaluate_cli_grid_mismatch_is_one_line(tmp_path, capsys):
    path = save_policy(tmp_path / 'k.yaml', conv_spec())
    assert main(['evaluate', '--grid', '7x7', '--policy-file', str(path),
                 '--episodes', '10']) == 2
    err = capsys.readouterr().err
    assert 'policy is for a 3x4 grid but the task grid is 7x7' in err
    assert err.count('\n') == 1


def test_save_refuses_an_invalid_spec(tmp_path):
    spec = conv_spec()
    spec.kernel = spec.kernel[:-1]
    with pytest.raises(PolicyFileError, match='kernel has shape'):
        save_policy(tmp_path / 'x.yaml', spec)
    assert not (tmp_path / 'x.yaml').exists()


def test_kernel_dir_is_the_package_data_next_to_the_module():
    assert pf.KERNEL_DIR.resolve() == (Path(pf.__file__).parent / 'kernels').resolve()
    assert 'human-7x7-infomax' in pf.shipped_kernels()


def test_a_key_given_twice_is_refused_not_taken_last_wins(tmp_path):
    """QA: `action: sample` appended by hand made the shipped kernel sample, silently."""
    shipped = pf.resolve_source('human-7x7-infomax')
    path = tmp_path / 'edited.yaml'
    path.write_text(Path(shipped).read_text() + 'action: sample\n')
    lines = path.read_text().splitlines()
    with pytest.raises(pf.PolicyFileError,
                       match=rf"the key 'action' appears twice \(line {len(lines)}\)"):
        pf.load_policy_spec(str(path))
    # the observation files are read the same way; a nested mapping too
    from ipomdp_gaze.files.observation_file import ObservationFileError
    from ipomdp_gaze.files.yaml_files import read_yaml
    nested = tmp_path / 'nested.yaml'
    nested.write_text('a:\n  b: 1\n  c: 2\n  b: 3\n')
    with pytest.raises(ObservationFileError, match=r"the key 'b' appears twice \(line 4\)"):
        read_yaml(nested, ObservationFileError)
    ok = tmp_path / 'ok.yaml'
    ok.write_text('base: &b {x: 1}\nderived:\n  <<: *b\n  y: 2\n')           # a merge key is fine
    assert read_yaml(ok, ValueError) == {'base': {'x': 1}, 'derived': {'x': 1, 'y': 2}}


def test_the_fast_yaml_parser_reads_every_shipped_file_as_the_python_one():
    """read_yaml parses with libyaml when PyYAML has it; its documents must be the same."""
    import yaml
    from ipomdp_gaze.files import yaml_files
    if yaml_files.UniqueKeyCLoader is None:
        assert not getattr(yaml, '__with_libyaml__', False)
        pytest.skip('PyYAML without libyaml: only the Python loader reads')
    root = Path(__file__).resolve().parents[1]
    files = sorted((root / 'config').glob('*.yaml')) + \
        sorted((root / 'ipomdp_gaze' / 'models').glob('*.yaml')) + \
        sorted(Path(pf.KERNEL_DIR).glob('*.yaml'))
    assert len(files) >= 20
    for path in files:
        text = path.read_text(encoding='utf-8')
        assert yaml_files._load(text, yaml_files.UniqueKeyCLoader) == \
            yaml_files._load(text, yaml_files.UniqueKeyLoader), path


@pytest.mark.parametrize('text, outcome', [
    ('a: b\t\n', 'not YAML at line 1'),                  # libyaml reads {'a': 'b'}
    ('a: !\n', {'a': None}),                              # libyaml reads ''
    ('a:\n\ufeff  b: 1\n', {'a': None, '\ufeff  b': 1}),  # libyaml drops the mark: {'a': {'b': 1}}
])
def test_a_users_yaml_is_read_by_pythons_parser_as_always(tmp_path, monkeypatch, text, outcome):
    """QA: libyaml reads a few odd inputs otherwise; only the package's own files take it."""
    from ipomdp_gaze.files import yaml_files
    path = tmp_path / 'mine.yaml'
    path.write_text(text, encoding='utf-8')
    fast = []
    real = yaml_files._load
    monkeypatch.setattr(yaml_files, '_load', lambda t, cls: fast.append(cls) or real(t, cls))
    if isinstance(outcome, str):
        with pytest.raises(ValueError, match=outcome):
            yaml_files.read_yaml(path, ValueError)
    else:
        assert yaml_files.read_yaml(path, ValueError) == outcome
    assert fast == [yaml_files.UniqueKeyLoader]
    # a shipped kernel is read by libyaml where PyYAML has it
    fast.clear()
    pf.load_policy_spec('human-7x7-infomax')
    assert fast == [yaml_files.UniqueKeyCLoader or yaml_files.UniqueKeyLoader]
