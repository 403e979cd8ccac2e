# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``diagnostic_msgs``: the controller's ``/diagnostics`` status and its search events.

The ``found`` event is a ``diagnostic_msgs/DiagnosticStatus`` (level OK, a readable message)
whose ``values`` carry the result as key/value strings: ``row``, ``col``, ``cell``, ``pan_rad``,
``tilt_rad``, ``probability`` and ``fixations``. The ``absent`` event carries ``probability``
(``P(absent)``) and ``fixations``, the ``gave_up`` event ``fixations`` (level WARN: the search
ended undecided). With motion on, ``lost`` (the tracked target's belief fell below
``motion.keep_probability``: ``row``, ``col``, ``cell`` where it was last found, ``probability``
of the most likely cell now, ``absent_probability``, ``fixations``, ``seconds_tracked``) and
``reacquired`` (found again after ``lost``: the ``found`` keys and ``seconds_lost``). They read
well in ``ros2 topic echo`` and need no custom interface package; the ``parse_*`` functions turn
them back into numbers.
"""
from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.search import answer
from ipomdp_gaze.search.room import people_text
from std_msgs.msg import Header

LEVELS = {'ok': DiagnosticStatus.OK, 'warn': DiagnosticStatus.WARN,
          'error': DiagnosticStatus.ERROR, 'stale': DiagnosticStatus.STALE}
FOUND_KEYS = ('row', 'col', 'cell', 'pan_rad', 'tilt_rad', 'probability', 'fixations')
ABSENT_KEYS = ('probability', 'fixations')
GAVE_UP_KEYS = ('fixations',)
LOST_KEYS = ('row', 'col', 'cell', 'probability', 'absent_probability', 'fixations',
             'seconds_tracked')
REACQUIRED_KEYS = FOUND_KEYS + ('seconds_lost',)
ROOM_DONE_KEYS = ('people', 'new_people', 'fixations', 'search_id')


def _text(value) -> str:
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, float):
        return f'{value:.6g}'
    return str(value)


def status(name: str, level: str, message: str, values: dict,
           hardware_id: str = '') -> DiagnosticStatus:
    """Build a ``DiagnosticStatus``; ``level`` is ``ok``, ``warn``, ``error`` or ``stale``."""
    return DiagnosticStatus(level=LEVELS[level], name=name, message=message,
                            hardware_id=hardware_id,
                            values=[KeyValue(key=k, value=_text(v)) for k, v in values.items()])


def diagnostic_array(statuses, stamp) -> DiagnosticArray:
    """Build a stamped ``DiagnosticArray`` for ``/diagnostics``."""
    return DiagnosticArray(header=Header(stamp=stamp), status=list(statuses))


def values_of(msg: DiagnosticStatus) -> dict:
    """Return the key/value pairs of a status as a dict of strings."""
    return {kv.key: kv.value for kv in msg.values}


def _ending(forced_by: str, confidence: float | None,
            probability: float | None = None, limit_cause: str = '') -> tuple[str, dict]:
    """
    Return the message's clause and the values that say how a decision was reached.

    A forced answer whose own ``probability`` is at the confidence anyway (a room's pass ends
    forced while the face the belief names is sure) is not said to be below it, as the log's
    :func:`~ipomdp_gaze.search.answer.confidence_clause`. ``limit_cause``: a repeat stop's
    (:func:`~ipomdp_gaze.search.answer.limit_text`).
    """
    values = {'ended': f'forced:{forced_by}' if forced_by else 'confidence'}
    if confidence is not None:
        values['confidence'] = float(confidence)
    limit = answer.limit_text(forced_by, limit_cause)
    if forced_by == 'group':            # search.group_stop: a stop rule, not a limit
        values['ended'] = 'group'
        clause = ' at a grouped detection of the detector'
    elif forced_by and confidence is not None and probability is not None \
            and probability >= confidence:
        clause = f', forced by {limit} (at the confidence {confidence:g}, before the search ' \
            'was done)'
    elif forced_by:
        below = f' below the confidence {confidence:g}' if confidence is not None else ''
        clause = f', forced by {limit}{below}'
    else:
        clause = f' (reached the confidence {confidence:g})' if confidence is not None else ''
    return clause, values


def found_status(name: str, row: int, col: int, cell: int, pan_rad: float, tilt_rad: float,
                 probability: float, fixations: int, forced_by: str = '',
                 confidence: float | None = None, radius: int = 0,
                 person: int = 0) -> DiagnosticStatus:
    """
    Build the ``found`` event.

    ``ended`` (``confidence``; ``forced:budget`` when the fixation budget forced it with
    ``search.decide_at_budget``; ``group`` when a grouped detection ended the search,
    ``search.group_stop``) and ``confidence`` say how it was reached; ``radius`` (only
    when > 0) that the answer is the centre of the likeliest square of that radius
    (``search.found_radius``), whose belief is ``probability``. ``person`` (only when > 0) is
    the number of the person found by a moving many-target search (:func:`person_of`).
    """
    clause, ending = _ending(forced_by, confidence, probability)
    if radius:
        ending['radius'] = int(radius)
    ending.update(_person(person))
    message = (f'{_who(person)} found at row {row}, col {col} (pan {pan_rad:+.4f} rad, tilt '
               f'{tilt_rad:+.4f} rad) with probability {probability:.4f} after '
               f'{counted(fixations, "fixation")}{clause}')
    return status(name, 'ok', message, {
        'row': row, 'col': col, 'cell': cell, 'pan_rad': float(pan_rad),
        'tilt_rad': float(tilt_rad), 'probability': float(probability), 'fixations': fixations,
        **ending})


def absent_status(name: str, probability: float, fixations: int, forced_by: str = '',
                  confidence: float | None = None) -> DiagnosticStatus:
    """Build the ``absent`` event: ``P(absent)`` reached the confidence (or was forced)."""
    clause, ending = _ending(forced_by, confidence, probability)
    message = (f'no target in the grid: probability {probability:.4f} that nobody is there '
               f'after {counted(fixations, "fixation")}{clause}')
    return status(name, 'ok', message, {'probability': float(probability),
                                        'fixations': fixations, **ending})


def gave_up_status(name: str, fixations: int, limit: str = 'the budget') -> DiagnosticStatus:
    """
    Build the ``gave_up`` event: the search ended undecided at ``limit`` (level WARN).

    ``limit`` names what ended it: the fixation budget, or the parameter of another rule
    (``search.stop_on_repeat``).
    """
    return status(name, 'warn',
                  f'gave up undecided after {counted(fixations, "fixation")} ({limit})',
                  {'fixations': fixations})


def lost_status(name: str, row: int, col: int, cell: int, probability: float,
                absent_probability: float, fixations: int,
                seconds_tracked: float, person: int = 0) -> DiagnosticStatus:
    """
    Build the ``lost`` event (level WARN): the tracked target (or ``person``) is not found.

    ``probability`` is the most likely cell's now; a person's is that someone is at its last
    cell (or a cell next to it) now: with others followed, the most likely cell is theirs.
    """
    shown, nobody = max(0.0, probability), max(0.0, absent_probability)   # never '-0.0000'
    now = 'someone at its cells now' if person else 'most likely cell now'
    message = (f'{_who(person)} lost: last found at row {row}, col {col}, tracked '
               f'{seconds_tracked:.2f} s; {now} {shown:.4f}, nobody here '
               f'{nobody:.4f} after {counted(fixations, "fixation")}')
    return status(name, 'warn', message, {
        'row': row, 'col': col, 'cell': cell, 'probability': float(probability),
        'absent_probability': float(absent_probability), 'fixations': fixations,
        'seconds_tracked': float(seconds_tracked), **_person(person)})


def reacquired_status(name: str, row: int, col: int, cell: int, pan_rad: float,
                      tilt_rad: float, probability: float, fixations: int,
                      seconds_lost: float, person: int = 0) -> DiagnosticStatus:
    """Build the ``reacquired`` event: found again ``seconds_lost`` after ``lost``."""
    message = (f'{_who(person)} reacquired at row {row}, col {col} (pan {pan_rad:+.4f} rad, tilt '
               f'{tilt_rad:+.4f} rad) with probability {probability:.4f}, {seconds_lost:.2f} s '
               f'after it was lost, after {counted(fixations, "fixation")}')
    return status(name, 'ok', message, {
        'row': row, 'col': col, 'cell': cell, 'pan_rad': float(pan_rad),
        'tilt_rad': float(tilt_rad), 'probability': float(probability), 'fixations': fixations,
        'seconds_lost': float(seconds_lost), **_person(person)})


def room_done_status(name: str, people: int, new_people: int, fixations: int, search_id: int,
                     recheck: bool, forced_by: str = '',
                     confidence: float | None = None,
                     limit_cause: str = '') -> DiagnosticStatus:
    """
    Build the ``room_done`` event of many-target mode: every cell decided, everyone found.

    ``people`` found, ``new_people`` among them (not within a cell of anyone known before;
    all of them after ``~/reset``), ``recheck`` whether the search was a periodic re-check;
    ``ended`` and ``confidence`` as for ``found``; ``limit_cause`` what ended it at a repeat
    stop (the session's, :data:`~ipomdp_gaze.search.answer.REPEATS`).
    """
    clause, ending = _ending(forced_by, confidence, limit_cause=limit_cause)
    kind = 're-check' if recheck else 'search'
    message = (f'room done: {people_text(people)} found ({new_people} new) by {kind} {search_id} '
               f'after {counted(fixations, "fixation")}{clause}')
    return status(name, 'ok', message, {
        'people': int(people), 'new_people': int(new_people), 'fixations': int(fixations),
        'search_id': int(search_id), 'recheck': bool(recheck), **ending})


def _person(person: int) -> dict:
    """Return the ``person`` value of an event, only for a person's (> 0)."""
    return {'person': int(person)} if person else {}


def _who(person: int) -> str:
    return f'person {int(person)}' if person else 'target'


def person_of(msg: DiagnosticStatus) -> int:
    """
    Return the person number of a ``found``, ``lost`` or ``reacquired`` event (0: none).

    A moving many-target search (``search.targets many`` with motion) numbers the people it
    follows 1, 2, ... in the order found; the single-target events carry no number.
    """
    value = values_of(msg).get('person')
    return int(value) if value is not None else 0


def _parse(msg: DiagnosticStatus, event: str, keys, ints) -> dict:
    kv = values_of(msg)
    missing = [k for k in keys if k not in kv]
    if missing:
        raise ValueError(f'{event} event lacks {missing}')
    return {k: int(kv[k]) if k in ints else float(kv[k]) for k in keys}


def _with_ending(msg: DiagnosticStatus, values: dict) -> dict:
    """Add ``ended`` ('confidence' for an event that does not say) and ``confidence`` (None)."""
    kv = values_of(msg)
    values['ended'] = kv.get('ended', 'confidence')
    if 'cell' in values:
        values['radius'] = int(kv.get('radius', 0))
    values['confidence'] = float(kv['confidence']) if 'confidence' in kv else None
    return values


def parse_found(msg: DiagnosticStatus) -> dict:
    """
    Read a ``found`` event (row, col, cell and fixations as int, the rest as float).

    ``ended`` and ``confidence`` are added ('confidence' and None for an event without them).

    Raises
    ------
    ValueError
        If a key is missing or not a number.

    """
    return _with_ending(msg, _parse(msg, 'found', FOUND_KEYS, ('row', 'col', 'cell',
                                                               'fixations')))


def parse_absent(msg: DiagnosticStatus) -> dict:
    """Read an ``absent`` event (as :func:`parse_found`); ValueError if bad."""
    return _with_ending(msg, _parse(msg, 'absent', ABSENT_KEYS, ('fixations',)))


def parse_gave_up(msg: DiagnosticStatus) -> dict:
    """Read a ``gave_up`` event (fixations as int); ValueError if bad."""
    return _parse(msg, 'gave_up', GAVE_UP_KEYS, ('fixations',))


def parse_lost(msg: DiagnosticStatus) -> dict:
    """Read a ``lost`` event (row, col, cell and fixations as int, the rest as float)."""
    return _parse(msg, 'lost', LOST_KEYS, ('row', 'col', 'cell', 'fixations'))


def parse_reacquired(msg: DiagnosticStatus) -> dict:
    """Read a ``reacquired`` event (as :func:`parse_lost`); ValueError if bad."""
    return _parse(msg, 'reacquired', REACQUIRED_KEYS, ('row', 'col', 'cell', 'fixations'))


def parse_room_done(msg: DiagnosticStatus) -> dict:
    """Read a ``room_done`` event (counts as int, ``recheck`` as bool); ValueError if bad."""
    values = _with_ending(msg, _parse(msg, 'room_done', ROOM_DONE_KEYS, ROOM_DONE_KEYS))
    values['recheck'] = values_of(msg).get('recheck') == 'true'
    return values
