# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The scores of several walking people (ipomdp_gaze.drivers.people_walks), worked by hand."""
from __future__ import annotations

import math
from types import SimpleNamespace
import warnings

from ipomdp_gaze.drivers.people_walks import (id_switches, people_result, people_settings,
                                              PeopleFrame, PeopleResult, summarise_people)
import pytest


def _frame(t, cells, in_view, answers):
    return PeopleFrame(t, (5, 5), cells, in_view, answers)


def test_scores_of_two_people_worked_by_hand():
    scene = SimpleNamespace(people=2, duration_s=4.0)
    frames = [
        _frame(0.5, ((2, 2), (8, 8)), (True, False), ((2, 3),)),
        _frame(1.5, ((2, 3), (8, 8)), (False, True), ((2, 3), (8, 7))),
        _frame(2.5, ((2, 4), None), (True, False), ((2, 4), (5, 5))),
        _frame(3.5, ((2, 5), (7, 8)), (False, False), ((6, 9),)),
    ]
    r = people_result('people', 3, scene, frames)
    # Person 0: in view 2 of 4 frames, named on 3 (the last answer is far); person 1: in reach on
    # 3 frames, in view on 1, named on 2 ((8, 7) at 1.5 and (6, 9) at 3.5, within a cell).
    assert r.in_view == pytest.approx((2 / 4 + 1 / 3) / 2)
    assert r.tracked == pytest.approx((3 / 4 + 2 / 3) / 2)
    # Longest gaps in reach without a view: person 0 from its view at 0.5 to the next at 2.5
    # (2.0 s; then 2.5 to the end, 1.5 s); person 1 from 0.5 (in reach, unseen) to its view at
    # 1.5 (1.0 s); leaving at 2.5 ends a gap, and from its return at 3.5 to the end is 0.5 s.
    assert r.max_gap_s == pytest.approx((2.0 + 1.0) / 2)
    assert r.found == 1.0
    assert r.false_per_frame == pytest.approx(1 / 4)          # (5, 5) names nobody
    assert r.frames == 4 and r.people == 2


def test_identity_switches_worked_by_hand():
    def frame(t, cells, answers, numbers):
        return PeopleFrame(t, (5, 5), cells, (True, True), answers, (), numbers)

    frames = [
        frame(0.5, ((2, 2), (8, 8)), ((2, 2), (8, 8)), (1, 2)),
        frame(1.0, ((2, 3), (8, 7)), ((2, 3),), (1,)),               # person 1 not named
        frame(1.5, ((2, 4), (8, 6)), ((8, 6), (2, 4)), (1, 2)),      # the numbers swapped
        frame(2.0, ((2, 5), None), ((2, 6), (2, 5)), (2, 3)),        # the nearer names it
        frame(2.5, ((2, 6), (8, 5)), ((8, 5),), (1,)),
    ]
    # person 0: 1, 1, 2, 3 (the nearer answer, on its cell) -> 2 switches; person 1:
    # 2, (not named), 1, (out of reach), 1 -> 1 switch
    assert id_switches(frames, 2) == 3
    assert people_result('people', 0, SimpleNamespace(people=2, duration_s=3.0),
                         frames).id_switches == 3
    unknown = [PeopleFrame(f.t_s, f.head, f.cells, f.in_view, f.answers) for f in frames]
    assert id_switches(unknown, 2) == 0                       # no numbers: none counted


def test_the_shipped_people_configuration_is_the_tracker_with_many_targets():
    settings, policy, values = people_settings()
    assert settings.targets == 'many' and settings.moving
    assert settings.false_alarm_scales == (1.0,) and settings.hotspot_prior > 0
    assert settings.motion_track_view == 'position' and settings.motion_dwell_s == 2.0
    assert values['observation.file'] == 'faces-pan-tilt-profile' and policy == 'coverage'


def test_a_record_without_identity_switches_summarises_without_them():
    # the committed page's record predates id_switches: its page shows '-', not '+nan [...]'
    def result(index, tracked):
        return PeopleResult('people', index, 2, 0.5, tracked, 3.0, 1.0, 0.1, 40)

    results, reference = [result(0, 0.6), result(1, 0.7)], [result(0, 0.5), result(1, 0.4)]
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        s = summarise_people(results, reference)
    assert math.isnan(s['id_switches']) and 'id_switches_minus_reference' not in s
    assert s['tracked_minus_reference'][0] == pytest.approx(0.2)
