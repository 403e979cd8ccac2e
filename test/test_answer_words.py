# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""How a search ended, in words: the confidence clause never says "below" of a sure answer."""
from __future__ import annotations

import math

from ipomdp_gaze.search import answer
import pytest


@pytest.mark.parametrize('decision, reason, p, want', [
    ('found', '', 0.995, ' (reached the confidence 0.99)'),
    ('found', 'budget', 0.62, ' (below the confidence 0.99)'),
    ('absent', 'pixels', 0.493, ' (below the confidence 0.99)'),
    # a room's pass ends forced while the face it names is sure
    ('found', 'pass', 0.9995, ' (at the confidence 0.99, forced before the search was done)'),
    # absent held back until every cell was seen well (absent_needs_coverage), then forced
    ('absent', 'budget', 0.995, ' (at the confidence 0.99, forced before the search was done)'),
    ('found', 'group', 0.68, ' (below the confidence 0.99)'),
    ('gave_up', 'budget', 0.4, ' (below the confidence 0.99)'),
    ('', '', 0.5, ''),
])
def test_the_confidence_clause(decision, reason, p, want):
    assert answer.confidence_clause(decision, reason, p, 0.99) == want


def test_a_title_says_how_the_calls_from_coarse_to_fine_and_a_forced_count_ended():
    from types import SimpleNamespace
    from ipomdp_gaze.commands.find import plot_title
    ladder = SimpleNamespace(answer_probability=math.nan, fixations=0, stop='found',
                             decision='found', cell=(5, 9), method='scales')
    title = plot_title('a.png', ladder, 0.99)
    assert 'found by full-frame detector calls, coarse to fine' in title
    assert 'one full-frame detector scan' not in title
    faces = tuple(SimpleNamespace(probability=p) for p in (0.9, 0.995, 0.999))
    forced = SimpleNamespace(answer_probability=0.9, fixations=0, stop='pixels',
                             decision='found', cell=(5, 9), method='fovea', faces=faces)
    assert plot_title('a.png', forced, 0.99, occupancy=True, faces=3).startswith(
        'a.png: 3 faces (search forced by the pixel budget (one full scan): cells still '
        'undecided on their likelier side; 2 of the faces at the confidence 0.99, the others '
        'forced), 0 fixations')


def test_a_forced_many_target_search_does_not_call_its_sure_faces_forced():
    # fr_two_people.jpg (a QA photograph): the full-resolution pass read the whole pixel
    # budget, two weak boxes' cells stayed at even odds, and both faces reached 0.991
    from types import SimpleNamespace
    from ipomdp_gaze.commands.find import plot_title
    faces = tuple(SimpleNamespace(probability=0.9913) for _ in range(2))
    result = SimpleNamespace(answer_probability=0.9913, fixations=0, stop='pixels',
                             decision='found', cell=(3, 5), method='fovea', faces=faces)
    title = plot_title('two.jpg', result, 0.99, occupancy=True, faces=2)
    assert title == ('two.jpg: 2 faces (search forced by the pixel budget (one full scan): '
                     'cells still undecided on their likelier side; every face at the '
                     'confidence 0.99), 0 fixations (pixels)')
