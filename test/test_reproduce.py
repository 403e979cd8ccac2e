# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze reproduce``: its runs split over processes give the serial run's numbers."""
from concurrent.futures import ProcessPoolExecutor

from ipomdp_gaze.commands import reproduce
from ipomdp_gaze.fpoc import make_fpoc
from ipomdp_gaze.grid import Grid
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.simulate import simulate
import numpy as np
import pytest

GRID, FPOC = Grid(4, 4, 0.42), make_fpoc('human')


def test_pieces_on_two_processes_give_the_serial_matrices_and_intervals():
    serial = reproduce._Runner(GRID, FPOC, 60, 5, 50)
    with ProcessPoolExecutor(2) as pool:
        split = reproduce._Runner(GRID, FPOC, 60, 5, 50, pool)
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
    runner = reproduce._Runner(GRID, FPOC, 200, 0, 20)
    runner.submit('random', make_baseline('random', GRID, FPOC), horizon=3)
    runner.collect()
    with pytest.raises(RuntimeError, match='raise the horizon'):
        runner.summary('random')
