# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Many-target mode without ROS: the controller core on the occupancy belief, and the room."""
from __future__ import annotations

from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search.gaze import GazeController
from ipomdp_gaze.search.many import OccupancySession
from ipomdp_gaze.search.room import check_room_times, Person, RoomWatch
from ipomdp_gaze.search.session import SearchSession, SearchSettings
import numpy as np
import pytest

GRID = Grid(11, 11, 5.0)
CAMERA = make_fpoc('camera', half_width_deg=10.0, half_height_deg=10.0)
FACES = [GRID.index(2, 3), GRID.index(8, 8)]
MANY = SearchSettings(targets='many', confidence=0.95, absent_prior=0.5, max_fixations=40,
                      inhibit_return=True, decide_at_budget=True)


def controller(settings=MANY) -> GazeController:
    core = GazeController(GRID, CAMERA, build_policy('elm', GRID, CAMERA), settings)
    core.reset(0.0)
    return core


def search(core: GazeController, faces=FACES) -> list:
    """Feed noise-free frames of a room with ``faces`` until the search ends; its results."""
    d = dprime_matrix(GRID, CAMERA)
    results, t = [], 0.0
    while not core.stopped:
        frame = np.zeros(GRID.n_cells)
        frame[faces] = d[faces, core.fixation]
        t += 1.0
        results.append(core.offer(frame, t))
    return results


def test_many_targets_runs_the_occupancy_session_and_finds_every_face():
    core = controller()
    assert isinstance(core.session, OccupancySession)
    results = search(core)
    assert all(r.applied for r in results)
    last = results[-1]
    assert last.found is not None and last.found.forced_by == '' and last.fixation is None
    assert core.decision == 'found' and core.session.gave_up_reason == ''
    assert sorted(f['cell'] for f in core.session.faces(link=2)) == FACES
    skipped = core.offer(np.zeros(GRID.n_cells), 100.0)            # the room is done
    assert skipped.status == 'skipped' and 'the search has ended (found)' in skipped.reason


def test_an_empty_room_is_absent():
    core = controller()
    search(core, faces=[])
    assert core.decision == 'absent' and core.session.faces(link=2) == []


def test_the_core_with_the_sweep_makes_one_pass_and_takes_the_frames_groups():
    sweep = build_policy('sweep', GRID, CAMERA)
    core = GazeController(GRID, CAMERA, sweep, MANY)
    core.reset(0.0)
    assert core.session.passing and core.fixation == int(sweep.poses[0])
    bad = core.offer(np.zeros(GRID.n_cells), 1.0, groups=np.full(GRID.n_cells, -1.0))
    assert bad.status == 'rejected' and 'groups must be whole numbers' in bad.reason
    assert core.session.fixations == 0
    nearly_nothing = np.full(GRID.n_cells, np.nan)
    nearly_nothing[0] = 0.0                          # (a frame that observes nothing is refused)
    for values, reason in ((nearly_nothing, 'pass'),               # the views tell little
                           (np.zeros(GRID.n_cells), '')):          # every cell decided
        core.reset(0.0)
        path, t = [], 1.0
        while not core.stopped:
            path.append(core.fixation)
            groups = np.zeros(GRID.n_cells)
            if len(path) == 1:
                groups[FACES[1]] = 1                 # one view's grouped detection
            t += 1.0
            assert core.offer(values, t, groups=groups).applied
        assert path == [int(p) for p in sweep.poses][:len(path)]
        assert core.session.gave_up_reason == reason and core.decision == 'found'
        assert [f['cell'] for f in core.session.faces(link=2)] == [FACES[1]]


def test_one_target_is_the_papers_session_and_switching_starts_a_new_search():
    core = controller(SearchSettings())
    assert isinstance(core.session, SearchSession)
    first = core.search_id
    core.configure(MANY)
    assert isinstance(core.session, OccupancySession) and core.search_id == first + 1
    assert core.fixation == GRID.center_index and not core.stopped
    core.configure(SearchSettings())
    assert isinstance(core.session, SearchSession) and core.search_id == first + 2


@pytest.mark.parametrize('change, words', [
    ({'hotspot_prior': 0.03}, 'nor hotspots of a still scene'),
    ({'false_alarm_scales': (1.0, 3.0)}, 'does not model false-alarm scales'),
    ({'confidence': 0.5}, r'decides each cell at the confidence either way, so it must be above '
                          r'0\.5 \(got 0\.5\)'),
])
def test_the_many_target_core_refuses_what_it_does_not_model(change, words):
    from dataclasses import replace
    core = controller()
    with pytest.raises(ValueError, match=words):
        core.configure(replace(MANY, **change))


@pytest.mark.parametrize('dwell_s, recheck_s, words', [
    (0.0, 0.0, 'room.dwell_s must be in (0, 86400] seconds, got 0.0'),
    (float('nan'), 0.0, 'room.dwell_s must be in'),
    (2.0, 1.0, 'room.recheck_period_s must be 0 (never) or in [room.dwell_s, 86400] seconds, '
               'got 1.0 with room.dwell_s 2.0'),
    (2.0, 1e6, 'room.recheck_period_s must be 0'),
])
def test_room_times_are_refused_with_the_reason(dwell_s, recheck_s, words):
    with pytest.raises(ValueError) as info:
        check_room_times(dwell_s, recheck_s)
    assert words in str(info.value)


def test_room_times_accepted():
    assert check_room_times(2, 0) == (2.0, 0.0)
    assert check_room_times(0.5, 0.5) == (0.5, 0.5)


def test_the_room_keeps_its_people_in_view_in_turn_and_counts_who_is_new():
    room = RoomWatch(GRID)
    assert room.next_person() is None
    a, b = GRID.index(2, 3), GRID.index(8, 8)
    done = room.done([{'cell': a, 'probability': 0.9}, {'cell': b, 'probability': 0.8}])
    assert done.people == done.new == (Person(a, 0.9), Person(b, 0.8)) and not done.recheck
    assert [room.next_person().cell for _ in range(5)] == [a, b, a, b, a]
    room.recheck()
    moved, c = GRID.index(3, 4), GRID.index(5, 0)             # a within one cell; c new
    done = room.done([{'cell': moved, 'probability': 0.9}, {'cell': b, 'probability': 0.7},
                      {'cell': c, 'probability': 0.6}])
    assert done.recheck and done.new == (Person(c, 0.6),) and len(done.people) == 3
    # the round goes on: a (moved) had its turn in it, so b, then c (new), then a new round
    assert [room.next_person().cell for _ in range(4)] == [b, c, moved, b]
    room.forget()
    assert room.people == () and room.next_person() is None
    done = room.done([{'cell': b, 'probability': 0.7}])
    assert done.new == done.people and not done.recheck


def test_the_people_are_most_probable_first_as_targets_documents():
    """QA: a pass lists its grouped detections first, and the node published them so."""
    room = RoomWatch(GRID)
    a, b, c, d = (GRID.index(*rc) for rc in ((0, 0), (2, 1), (3, 9), (10, 10)))
    done = room.done([{'cell': a, 'probability': 0.63}, {'cell': b, 'probability': 0.61},
                      {'cell': c, 'probability': 0.64}, {'cell': d, 'probability': 0.2}])
    assert done.people == (Person(c, 0.64), Person(a, 0.63), Person(b, 0.61), Person(d, 0.2))
    assert done.new == done.people
    assert [room.next_person().cell for _ in range(4)] == [c, a, b, d]


def test_people_two_cells_apart_are_two_under_the_gaussian_model():
    """QA: the node linked occupied cells within 2 under every model, so two people became one."""
    from ipomdp_gaze.search.room import PERSON_LINK
    faces = [GRID.index(4, 4), GRID.index(4, 6), GRID.index(6, 6)]
    core = controller()
    search(core, faces=faces)
    assert core.decision == 'found'
    found = core.session.faces(link=PERSON_LINK['gaussian'])
    assert sorted(f['cell'] for f in found) == faces
    # the counts' link (a face's spill-over) makes them one, at a cell where nobody stands
    [merged] = core.session.faces(link=PERSON_LINK['counts'])
    assert merged['cell'] not in faces


@pytest.mark.parametrize('frame_id', ['/pan_tilt_base', ' head', 'head ', '', ' '])
def test_a_frame_id_tf2_cannot_look_up_is_refused(frame_id):
    """QA: '/pan_tilt_base' was taken, and ~/targets named a frame every tf2 lookup refuses."""
    from ipomdp_gaze.search.room import check_frame_id
    with pytest.raises(ValueError, match='room.frame_id must name the frame of ~/targets'):
        check_frame_id(frame_id)
    assert check_frame_id('pan_tilt_base') == 'pan_tilt_base'


FOUR = [GRID.index(*rc) for rc in ((1, 1), (1, 9), (9, 1), (9, 9))]


def _faces(cells, probabilities=(0.9, 0.8, 0.7, 0.6)) -> list:
    return [{'cell': c, 'probability': p} for c, p in zip(cells, probabilities)]


def test_a_recheck_shorter_than_a_round_starves_nobody():
    """QA: the turn restarted at the first person after each re-check; (9, 9) was never seen."""
    room = RoomWatch(GRID)
    room.done(_faces(FOUR))
    looked = []
    for _ in range(4):       # 2 s dwell, 5 s period: turns at 0, 2 and 4 s, then the re-check
        looked += [room.next_person().cell for _ in range(3)]
        room.recheck()
        done = room.done(_faces(FOUR))                    # nobody new
        assert done.recheck and done.new == ()
    assert looked == FOUR * 3
    # a new round; after a re-check that reorders the list, the rest of it in the new order
    assert room.next_person().cell == FOUR[0]
    room.recheck()
    room.done(_faces(FOUR[::-1]))                         # (9, 9) most probable now
    assert [room.next_person().cell for _ in range(4)] == [FOUR[3], FOUR[2], FOUR[1], FOUR[3]]


def test_after_a_recheck_the_new_people_get_their_turn_in_the_round():
    room = RoomWatch(GRID)
    room.done(_faces(FOUR[:2]))
    assert room.next_person().cell == FOUR[0]
    room.recheck()
    gone = [GRID.index(1, 2), FOUR[2]]           # the first moved by a cell, one more came in
    room.done(_faces(gone))                       # and the second left
    assert [room.next_person().cell for _ in range(3)] == [FOUR[2], gone[0], FOUR[2]]
    room.recheck()
    room.done([])                                 # nobody: nothing to look at
    assert room.looked == frozenset() and room.next_person() is None


def test_two_people_side_by_side_found_again_are_each_matched_once():
    """One known person found again is one of the new list, even with two within a cell."""
    from ipomdp_gaze.search.room import found_again
    side = [Person(GRID.index(5, 5), 0.9), Person(GRID.index(5, 6), 0.8)]
    assert found_again(side[:1], side, GRID) == {0}
    assert found_again(side[1:], side, GRID) == {1}
    assert found_again(side, side[::-1], GRID) == {0, 1}
    assert found_again([Person(GRID.index(0, 0), 0.9)], side, GRID) == frozenset()


def _tick_s(start_s: float, k: int, period_s: float) -> float:
    """Return the k-th tick of an rclpy timer of ``period_s`` started at ``start_s`` (whole ns)."""
    return start_s + k * int(period_s * 1e9) * 1e-9


@pytest.mark.parametrize('dwell_s, period_s, turns', [
    (2.0, 2.0, [False, False, False]),            # each tick is a re-check's too
    (2.0, 4.0, [True, False, True, False]),
    (2.0, 5.0, [True, True, True, True, False]),  # 10 s: the second re-check (while disabled)
    (0.7, 2.1, [True, True, False]),              # 3 * 0.7 is 2.0999999999999996
    (1 / 3, 1.0, [True, True, False]),            # the timer's third tick comes 1 ns early
    (2.0, 0.0, [True, True, True]),               # no re-check
])
@pytest.mark.parametrize('start_s', [0.0, 1765115000.25])           # sim time; epoch seconds
def test_a_dwell_tick_at_the_moment_of_the_recheck_is_no_turn(start_s, dwell_s, period_s, turns):
    """QA: at 2 s / 2 s the head was sent to a person and to the pass's first pose at once."""
    room = RoomWatch(GRID)
    room.start_turns(start_s, dwell_s, period_s)
    late_s = 0.003                                # callbacks run a little after their tick
    assert [room.dwell_tick(_tick_s(start_s, k, dwell_s) + late_s)
            for k in range(1, len(turns) + 1)] == turns


def test_a_late_dwell_tick_is_the_timers_last_tick():
    """A timer called late skips the ticks it missed: the call is for the last one."""
    room = RoomWatch(GRID)
    room.start_turns(50.0, 2.0, 5.0)
    assert room.dwell_tick(50.0 + 9.5)             # the tick at 8 s
    assert not room.dwell_tick(50.0 + 11.9)        # the tick at 10 s, the re-check's


def test_a_clock_set_back_restarts_the_turns_and_the_recheck_at_the_new_now():
    """QA: after /clock went back from 101 s to 50 s every tick was a turn, the re-check's too."""
    room = RoomWatch(GRID)
    room.start_turns(100.0, 1.0, 3.0)
    assert room.dwell_tick(101.003)
    room.restart_turns(50.0)                       # the node restarts both timers at 50 s
    assert [room.dwell_tick(50.0 + k + 0.003) for k in (1, 2, 3, 4, 5, 6)] == \
        [True, True, False, True, True, False]     # 53 s and 56 s: the re-check's


def test_one_person_is_one_person_in_words():
    """QA: the log and room_done said '1 people found'."""
    from ipomdp_gaze.search.room import people_text
    assert [people_text(n) for n in (0, 1, 2)] == ['0 people', '1 person', '2 people']
