# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Which recorded search a replay follows (``replay.last_search``), on bags built by hand.

A bag may hold the first search of a demo and the one started by ``~/reset``. The reset is the
last uniform ``belief``; the target sent with it (an enabled controller) can arrive before that
belief, while a disabled controller sends its first target only when enabled again.
"""
from pathlib import Path
from types import SimpleNamespace

from ipomdp_gaze.drivers.replay import last_search
from ipomdp_gaze.files.bag import Bag, BagMessage
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
import numpy as np

GRID = Grid(11, 11, 5.0)
HEAD = PanTiltMap(GRID)
START = GRID.center_index
OTHER = GRID.index(2, 3)


def _target(cell: int, stamp_s: float, arrival_s: float) -> BagMessage:
    pan, tilt = HEAD.angles(cell)
    sec = int(stamp_s)
    msg = SimpleNamespace(header=SimpleNamespace(stamp=SimpleNamespace(
        sec=sec, nanosec=int(round((stamp_s - sec) * 1e9)))),
        name=[HEAD.pan_joint, HEAD.tilt_joint], position=[pan, tilt])
    return BagMessage('/pan_tilt', int(arrival_s * 1e9), msg, 0)


def _belief(uniform: bool, arrival_s: float) -> BagMessage:
    data = np.full(GRID.n_cells, 1 / GRID.n_cells)
    if not uniform:
        data[OTHER] *= 2
    return BagMessage('/belief', int(arrival_s * 1e9), SimpleNamespace(data=data), 0)


def _bag(messages) -> Bag:
    return Bag(Path('bag'), sorted(messages, key=lambda m: m.time_ns), {}, 0, 0.0)


def _first_target(bag: Bag) -> tuple:
    cut = last_search(bag, HEAD, START)
    first = cut.topic('pan_tilt')[0].msg.header.stamp
    return first.sec + 1e-9 * first.nanosec, len(cut.topic('belief'))


def test_an_enabled_reset_is_pinned_by_the_target_that_arrived_before_its_belief():
    old = [_target(START, 100.0, 100.001), _belief(False, 100.3), _target(OTHER, 100.31, 100.32)]
    # The reset's target is stamped just after the belief was published and arrives first.
    reset = [_target(START, 101.0005, 101.001), _belief(True, 101.002),
             _belief(False, 101.3), _target(OTHER, 101.31, 101.32)]
    assert _first_target(_bag(old + reset)) == (101.0005, 2)


def test_a_disabled_reset_starts_at_its_belief_and_the_next_target_is_the_first():
    # The first search's target at the start cell is older than the window: not this search's.
    old = [_target(START, 100.0, 100.001), _belief(False, 100.3)]
    reset = [_belief(True, 101.0), _target(START, 101.02, 101.021), _belief(False, 101.3)]
    assert _first_target(_bag(old + reset)) == (101.02, 2)
