# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Paired differences of two searchers over the same scenes (``drivers.scene_report``)."""
from __future__ import annotations

from types import SimpleNamespace

from ipomdp_gaze.drivers.scene_report import (paired_difference, paired_map_difference,
                                              SceneResult)
import numpy as np
import pytest


def _scenes(values, order=None, has_face=True):
    order = range(len(values)) if order is None else order
    return [SimpleNamespace(index=i, value=values[i], has_face=has_face,
                            map_right=(values[i], 1.0 - values[i])) for i in order]


def test_scenes_are_paired_by_index_and_resampled_together():
    rng = np.random.default_rng(3)
    a, b, order = rng.random(40), rng.random(40), rng.permutation(40)
    diff, low, high = paired_difference(_scenes(a), _scenes(b, order=order), 'value',
                                        np.random.default_rng(7), n_boot=500)
    d = (a - b)[order]                  # the pairs in b's order, each scene with its own
    assert diff == pytest.approx(d.mean())
    picks = np.random.default_rng(7).integers(0, 40, size=(500, 40))
    expected = np.percentile(d[picks].mean(axis=1), [2.5, 97.5])
    assert (low, high) == pytest.approx(tuple(expected))
    assert low <= diff <= high


def test_sequences_give_an_interval_per_entry_and_map_budgets_read_them():
    a, b = np.linspace(0, 1, 30), np.linspace(1, 0, 30)
    diff, low, high = paired_difference(_scenes(a), _scenes(b), 'map_right',
                                        np.random.default_rng(0))
    assert diff.shape == low.shape == (2,) and diff[0] == pytest.approx(-diff[1])
    by_budget = paired_map_difference(_scenes(a), _scenes(b), np.random.default_rng(0),
                                      budgets=(1, 2))
    assert by_budget[1] == pytest.approx((diff[0], low[0], high[0]))
    assert by_budget[2] == pytest.approx((diff[1], low[1], high[1]))


def test_one_common_scene_gives_no_interval_rather_than_one_of_no_width():
    """QA: evaluate --scenes --episodes 1 --compare sweep printed [+0.000, +0.000] per budget."""
    rng = np.random.default_rng(0)
    diff, low, high = paired_difference(_scenes([0.75]), _scenes([0.5]), 'value', rng)
    assert diff == pytest.approx(0.25) and low is None and high is None
    by_budget = paired_map_difference(_scenes([1.0]), _scenes([0.0]), rng, budgets=(1, 2))
    assert by_budget == {1: (1.0, None, None), 2: (-1.0, None, None)}
    assert None not in paired_difference(_scenes([0.75, 0.5]), _scenes([0.5, 0.5]), 'value',
                                         rng)


def test_the_bootstrap_draws_from_the_callers_generator():
    """Randomness is passed in: the caller's generator is drawn from, no seed of its own."""
    rng = np.random.default_rng(11)
    a, b = _scenes(rng.random(30)), _scenes(rng.random(30))
    with pytest.raises(TypeError):
        paired_difference(a, b, 'value')                # no hidden default generator
    with pytest.raises(TypeError):
        paired_map_difference(a, b)
    mine = np.random.default_rng(5)
    first = paired_difference(a, b, 'value', mine, n_boot=300)
    second = paired_difference(a, b, 'value', mine, n_boot=300)    # the state moved on
    assert first[0] == second[0] and first[1:] != second[1:]
    again = np.random.default_rng(5)
    assert paired_difference(a, b, 'value', again, n_boot=300) == first
    assert again.bit_generator.state != np.random.default_rng(5).bit_generator.state
    # One scene: no interval, and nothing drawn.
    untouched = np.random.default_rng(5)
    paired_difference(a[:1], b[:1], 'value', untouched)
    assert untouched.bit_generator.state == np.random.default_rng(5).bit_generator.state


def test_no_common_scene_is_refused():
    with pytest.raises(ValueError, match='both searchers ran'):
        paired_difference(_scenes([1.0]), _scenes([1.0, 2.0], order=[1]), 'value',
                          np.random.default_rng(0))
    with pytest.raises(ValueError, match='same scenes with a face'):
        paired_map_difference(_scenes([1.0]), _scenes([1.0], has_face=False),
                              np.random.default_rng(0))


def test_a_scene_result_comes_back_from_its_json_record():
    import json
    room = SceneResult('pass-many', 3, True, 'page', False, 'found', 'pass', (5, 9), (5, 9), 12,
                       (12, 16), 9000, 1.5, 90.0, (True, False), 6.1, 1.2,
                       ((5, 9), (7, 0)), ((5, 9),), 1, True)
    one = SceneResult('coverage', 0, False, 'moon', True, 'absent', '', (5, 5), None, 3,
                      (60, 61, 62), 300, 0.2, 10.0)
    for result in (room, one):
        assert SceneResult.from_record(json.loads(json.dumps(result.__dict__))) == result
