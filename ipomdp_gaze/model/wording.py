# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Counts in words: ``1 fixation``, ``2 fixations``, ``1 person``, ``3 people``.

The one place the human-readable lines (events, logs, printed results) pluralise a count, so
that a count of one reads ``after 1 fixation``; structured fields (event keys, JSON) are not
text and do not use it.
"""


def noun(count: int, singular: str, plural: str | None = None) -> str:
    """Return ``singular`` for a count of one, else ``plural`` (default ``singular + 's'``)."""
    if count == 1:
        return singular
    return plural if plural is not None else singular + 's'


def counted(count, singular: str, plural: str | None = None) -> str:
    """Return ``'<count> <noun>'``: ``'1 fixation'``, ``'0 fixations'``, ``'2 people'``."""
    return f'{count} {noun(count, singular, plural)}'
