# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
A count of one reads in the singular in human-readable lines: ``after 1 fixation``.

QA: events, logs and printed lines said ``after 1 fixations`` and replay ``1 events of 1
people``. The structured fields (the events' key/values) are unchanged.
"""
from ipomdp_gaze.drivers.replay import _people_text, Decision, Event
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.wording import counted, noun
from ipomdp_gaze.msg_adapters import diagnostics
from ipomdp_gaze.search.health import classify
import pytest

GRID = Grid(3, 3)


def test_a_count_of_one_is_singular_and_any_other_plural():
    assert [counted(n, 'fixation') for n in (0, 1, 2)] == [
        '0 fixations', '1 fixation', '2 fixations']
    assert [counted(n, 'person', 'people') for n in (0, 1, 7)] == [
        '0 people', '1 person', '7 people']
    assert (noun(1, 'face'), noun(3, 'face')) == ('face', 'faces')


def test_the_events_say_one_fixation_and_keep_their_fields():
    found = diagnostics.found_status('c: found', 1, 2, 5, 0.0, 0.0, 0.995, 1, '', 0.99)
    assert found.message.endswith('after 1 fixation (reached the confidence 0.99)')
    assert diagnostics.parse_found(found)['fixations'] == 1
    absent = diagnostics.absent_status('c: absent', 0.995, 1, '', 0.99)
    assert 'after 1 fixation (' in absent.message
    assert diagnostics.gave_up_status('c', 1).message == \
        'gave up undecided after 1 fixation (the budget)'
    done = diagnostics.room_done_status('c', 1, 1, 1, 3, False, '', 0.99)
    assert done.message.startswith('room done: 1 person found (1 new) by search 3 after 1 '
                                   'fixation ')
    assert diagnostics.parse_room_done(done)['fixations'] == 1
    many = diagnostics.found_status('c: found', 1, 2, 5, 0.0, 0.0, 0.995, 12, '', 0.99)
    assert 'after 12 fixations (' in many.message


def test_replay_says_one_event_of_one_person():
    events = [Event('found', 4, 1, 0.99, person=1)]
    assert _people_text(events) == '1 event of 1 person (found 1)'
    assert _people_text(events * 2 + [Event('lost', 4, 2, 0.2, person=2)]) == \
        '3 events of 2 people (found 2, lost 1)'
    assert events[0].describe(GRID) == 'person 1 found at (1, 1) after 1 fixation'
    assert Decision('found', 4, 0.99, 1).describe(GRID).endswith('p=0.990 after 1 fixation')


def test_the_status_says_one_fixation_and_one_frame():
    assert classify(True, 0.0, 0.0, 1, 0, '', False, 'gave_up', True, 1).message == \
        'gave up after 1 fixation'
    stalled = classify(True, 1.0, 5.0, 1, 1, 'stale', False)
    assert stalled.detail.startswith('1 frame arrived, none usable')


def test_search_says_one_fixation(capsys):
    from ipomdp_gaze.cli import main
    assert main(['search', '--grid', '7x7', '--seed', '3', '--max-fixations', '1']) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.endswith(', after 1 fixation, which is wrong'), last


def test_the_input_errors_count_one_in_the_singular(tmp_path, capsys):
    from ipomdp_gaze.cli import main
    from ipomdp_gaze.model.belief import EvidenceError
    from ipomdp_gaze.model.observation import check_evidence
    prior = tmp_path / 'prior.txt'
    prior.write_text('1 1 1\n')
    assert main(['search', '--grid', '3x3', '--prior', str(prior)]) == 2
    assert capsys.readouterr().err.strip().endswith('got 1 line of 3')
    with pytest.raises(EvidenceError, match=r'^evidence has 1 value in shape \(1,\), '):
        check_evidence([0.5], 9)
