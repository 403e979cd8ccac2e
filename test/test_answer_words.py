# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""How a search ended, in words: the confidence clause never says "below" of a sure answer."""
from __future__ import annotations

from ipomdp_gaze.search import answer
import pytest


@pytest.mark.parametrize('decision, reason, p, want', [
    ('found', '', 0.995, ' (reached the confidence 0.99)'),
    ('found', 'budget', 0.62, ' (below the confidence 0.99)'),
    ('absent', 'pixels', 0.493, ' (below the confidence 0.99)'),
    # a room's pass ends forced while the face it names is sure
    ('found', 'pass', 0.9995, ' (forced before the search reached the confidence 0.99)'),
    ('found', 'group', 0.68, ' (below the confidence 0.99)'),
    ('gave_up', 'budget', 0.4, ' (below the confidence 0.99)'),
    ('', '', 0.5, ''),
])
def test_the_confidence_clause(decision, reason, p, want):
    assert answer.confidence_clause(decision, reason, p, 0.99) == want
