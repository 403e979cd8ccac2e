# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
How a search ended, in one wording for every driver (find, demo, search, replay, the node).

A search ends with a **decision** (``found``, ``absent`` or ``gave_up``) and a **reason**: the
evidence reached ``confidence`` (reason ``found`` / ``absent`` / ''), or a limit ended it:
``budget`` (the fixation budget), ``pixels`` (``find``'s cost cap: one full-resolution scan of
detector pixels), ``repeat`` (the repeat stop: every cell fixated once, the next fixation would
repeat a cell, or, many targets, no view left would tell anything new; :data:`REPEATS`),
``timeout``. At a limit a search gives up,
or, with ``decide_at_budget``, is **forced** to the likelier of ``found`` and ``absent``, whose
probability is then below ``confidence``. With ``search.group_stop`` a grouped detection ends a
search ``found`` at its cell (reason ``group``), whatever its probability.

The probability of an answer is that of *that* answer: the found cell's (its square with
``found_radius``) for ``found``, ``P(absent)`` (nobody is there) for ``absent``, the most likely
cell's for ``gave_up``.

:func:`ended` is the one-token form (``find``'s line and JSON), :func:`how` the words, for
example ``found: ... probability 0.998, after 8 fixations (reached the confidence 0.99)`` and
``found, forced by the pixel budget: ... probability 0.847 (below the confidence 0.99)``.
"""
from __future__ import annotations

import math

# The limits that can end a search, and their words.
LIMITS = {'budget': 'the fixation budget', 'pixels': 'the pixel budget (one full scan)',
          'repeat': 'the repeat stop', 'timeout': 'the time limit',
          'pass': 'the end of its pass'}
# The causes of a ``repeat`` stop (a session's ``limit_cause``), and their words: with
# inhibition of return every cell was fixated (search.stop_on_repeat; many targets: also
# without it), without it the policy's next fixation was a cell fixated already
# (search.stop_on_repeat), or, many targets, no view left would tell anything new.
REPEATS = {'every_cell': 'every cell fixated once',
           'next_repeats': 'the next fixation would repeat a cell',
           'nothing_new': 'no view left would tell anything new'}


def limit_text(reason: str, cause: str = '') -> str:
    """
    Return the words of the limit ``reason``; for ``repeat`` with its ``cause`` when known.

    ``the repeat stop (every cell fixated once)``, as ``the pixel budget (one full scan)``;
    a reason that is no limit of :data:`LIMITS` (a driver's own) is its own word.
    """
    words = LIMITS.get(reason, reason)
    if reason == 'repeat' and cause in REPEATS:
        return f'{words} ({REPEATS[cause]})'
    return words


def ended(decision: str, reason: str = '') -> str:
    """
    Return how a search ended as one token.

    ``confidence`` (the evidence reached the confidence), ``forced:<limit>`` (a limit forced a
    ``found`` or ``absent``), ``<limit>`` for ``gave_up``, ``scan`` for ``full_frame`` answers
    (one detector scan, no belief; also for ``scales``, the calls from coarse to fine),
    ``group`` for a grouped detection's stop, '' for no
    decision.
    """
    if not decision:
        return ''
    if reason in ('full_frame', 'scales'):
        return 'scan'
    if reason == 'group':
        return 'group'
    if decision == 'gave_up':
        return reason or 'limit'
    if reason in LIMITS:
        return f'forced:{reason}'
    return 'confidence'


def reason_of(token: str) -> str:
    """Return the reason an :func:`ended` token names (``forced:budget`` -> ``budget``)."""
    return 'group' if token == 'group' else str(token).partition('forced:')[2]


def where(reason: str = '') -> str:
    """Return where a found answer is: ``at`` a grouped detection's, else ``most likely at``."""
    return 'at' if reason == 'group' else 'most likely at'


def forced(decision: str, reason: str = '') -> bool:
    """Whether a limit forced a ``found`` or ``absent`` (the search's own rules had not)."""
    return ended(decision, reason).startswith('forced:')


def answer_probability(decision: str, cell_probability: float,
                       absent_probability: float) -> float:
    """Return the probability of the answer: ``P(absent)`` for ``absent``, else the cell's."""
    return float(absent_probability if decision == 'absent' else cell_probability)


def heading(decision: str, reason: str = '', cause: str = '') -> str:
    """
    Return the decision word with how it ended: ``found``, ``absent, forced by ...``.

    ``cause``: a ``repeat`` stop's (:func:`limit_text`).
    """
    if decision == 'gave_up':
        return 'gave up'
    if reason == 'full_frame':
        return f'{decision} by one full-frame detector scan'
    if reason == 'scales':
        return f'{decision} by full-frame detector calls, coarse to fine'
    if reason == 'group':
        return f'{decision} at a grouped detection'
    if forced(decision, reason):
        return f'{decision}, forced by {limit_text(reason, cause)}'
    return decision


def confidence_clause(decision: str, reason: str, probability: float,
                      confidence: float | None) -> str:
    """
    Return ``(reached the confidence C)``, ``(below the confidence C)`` or ''.

    A forced answer whose own probability is at the confidence anyway (a room's pass ends
    forced while the face it names is sure and the rest of the room is not; ``absent`` held
    back by ``search.absent_needs_coverage`` until a budget forced it) says ``(at the
    confidence C, forced before the search was done)``: never "below" of a probability that is
    not, nor "reached" of a search that did not end by it.
    """
    if confidence is None or not decision or math.isnan(probability):
        return ''
    if forced(decision, reason) and probability >= confidence:
        return f' (at the confidence {confidence:.12g}, forced before the search was done)'
    word = 'reached' if probability >= confidence and not forced(decision, reason) \
        else 'below'
    return f' ({word} the confidence {confidence:.12g})'


def probability_text(decision: str, probability: float) -> str:
    """Return ``probability 0.998``; for ``absent``, ``probability 0.993 that nobody is here``."""
    if math.isnan(probability):
        return 'probability n/a'
    nobody = ' that nobody is here' if decision == 'absent' else ''
    return f'probability {probability:.3f}{nobody}'
