# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The policy registry: baselines by name, kernels checked once, policy files against the task."""
import sys

from ipomdp_gaze.model.fpoc import make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.observation import GaussianObservation
from ipomdp_gaze.policies.conv import check_kernel, ConvPolicy
from ipomdp_gaze.policies.registry import build_policy, POLICY_NAMES, PolicyUnavailable
import numpy as np
import pytest

GRID = Grid(11, 11, 5.0)
CAMERA = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)


def test_build_policy_names():
    for name in POLICY_NAMES:
        if name in ('learned', 'greedy'):
            continue
        assert hasattr(build_policy(name, GRID, CAMERA), 'select')
    with pytest.raises(ValueError, match='valid policies: learned, map'):
        build_policy('foo', GRID, CAMERA)
    with pytest.raises(ValueError, match='action'):
        build_policy('elm', GRID, CAMERA, action='softmax')
    with pytest.raises(ValueError, match='policy.kernel or policy.file'):
        build_policy('learned', GRID, CAMERA)


def test_learned_kernel_is_used_as_given():
    kernel = np.random.default_rng(4).standard_normal(GRID.kernel_shape)
    policy = build_policy('learned', GRID, CAMERA, kernel=kernel.ravel().tolist())
    assert isinstance(policy, ConvPolicy)
    np.testing.assert_array_equal(policy.kernel, kernel)
    belief = np.random.default_rng(5).dirichlet(np.ones(121))
    assert policy.select(belief[None], 1, None)[0] == ConvPolicy(GRID, kernel).select(
        belief[None], 1, None)[0]


def test_check_kernel_reasons():
    with pytest.raises(ValueError, match='441 values .*21x21.*got 440'):
        check_kernel(np.zeros(440), GRID)
    bad = np.zeros(441)
    bad[7] = np.nan
    with pytest.raises(ValueError, match='entry 7 is nan'):
        check_kernel(bad, GRID)
    assert check_kernel(np.zeros(441), GRID).shape == (21, 21)


def test_missing_policy_file_support_or_file_is_unavailable(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, 'ipomdp_gaze.policies.policy_file', None)
    with pytest.raises(PolicyUnavailable, match='not supported'):
        build_policy('learned', GRID, CAMERA, file='camera-11x11-infomax')
    monkeypatch.setitem(sys.modules, 'ipomdp_gaze.policies.greedy', None)
    with pytest.raises(PolicyUnavailable, match='greedy'):
        build_policy('greedy', GRID, CAMERA)


def _policy_file(tmp_path, grid=GRID, fpoc=CAMERA, seed=9):
    from ipomdp_gaze.policies.policy_file import PolicySpec, save_policy
    kernel = np.random.default_rng(seed).standard_normal(grid.kernel_shape)
    spec = PolicySpec(grid=grid, fpoc=fpoc, reward='infomax', family='conv', kernel=kernel)
    return save_policy(tmp_path / f'k{seed}.yaml', spec), kernel


def test_policy_file_is_loaded_and_checked_against_the_task(tmp_path):
    path, kernel = _policy_file(tmp_path)
    warnings = []
    policy = build_policy('learned', GRID, CAMERA, file=str(path), warn=warnings.append)
    np.testing.assert_array_equal(policy.kernel, kernel)
    assert warnings == []
    human = make_fpoc('human')
    build_policy('learned', GRID, human, file=str(path), warn=warnings.append)
    assert len(warnings) == 1 and 'FPOC' in warnings[0]
    small, _ = _policy_file(tmp_path, Grid(7, 7, 5.0), seed=10)
    with pytest.raises(ValueError, match='7x7 grid but the task grid is 11x11') as err:
        build_policy('learned', GRID, CAMERA, file=str(small))
    assert not isinstance(err.value, PolicyUnavailable)
    with pytest.raises(PolicyUnavailable, match='not found'):
        build_policy('learned', GRID, CAMERA, file=str(tmp_path / 'missing.yaml'))


def test_kernel_takes_precedence_over_the_file(tmp_path):
    path, _ = _policy_file(tmp_path)
    kernel = np.ones(GRID.kernel_shape)
    policy = build_policy('learned', GRID, CAMERA, kernel=kernel.ravel(), file=str(path))
    np.testing.assert_array_equal(policy.kernel, kernel)


def test_an_fpoc_and_its_gaussian_model_build_the_same_baselines():
    model = GaussianObservation(GRID, CAMERA)
    belief = np.random.default_rng(11).dirichlet(np.ones(GRID.n_cells), size=50)
    for name in ('map', 'elm', 'center', 'spiral'):
        a = build_policy(name, GRID, CAMERA).select(belief, 3, None)
        b = build_policy(name, GRID, model).select(belief, 3, None)
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(build_policy('elm', GRID, model).kernel, model.table ** 2)


def test_a_kernel_parameter_is_named_in_its_errors():
    with pytest.raises(ValueError, match='policy.kernel must have 441 values'):
        build_policy('learned', GRID, CAMERA, kernel=[1.0, 2.0])
    with pytest.raises(ValueError, match='policy.kernel must be finite, entry 3 is inf'):
        build_policy('learned', GRID, CAMERA, kernel=[0.0] * 3 + [np.inf] + [0.0] * 437)
    with pytest.raises(ValueError, match=r'kernel must have 441 values .*shape \(21, 20\)'):
        ConvPolicy(GRID, np.zeros((21, 20)))
