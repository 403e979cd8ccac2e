# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
What ``replay`` compares on a tracker's or many people's search, and which settings it uses.

The bags are built here: the controller's core (with the shipped tracking parameters) searches
a scene of detection counts as the node would, and its targets, frames, events and parameter
changes are written as the recorder writes them. A tracker may find, lose and then decide
``absent`` in one search (the replay compares the last decision, not the first kind found); a
moving many-target search has people's events, not a decision; a parameter set while recording
is in force from its time.
"""
from pathlib import Path
from types import SimpleNamespace

from ipomdp_gaze.drivers.replay import build_controller, Decision, describe_settings, Event, \
    parameter_changes, replay, ReplayResult, settings_from
from ipomdp_gaze.files.bag import Bag, BagMessage
from ipomdp_gaze.files.yaml_files import yaml_parameters
from ipomdp_gaze.search.controller_config import build_config
import numpy as np
import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
FRAME_S = 0.3
EVENT_KEYS = ('found', 'reacquired', 'lost', 'absent', 'gave_up')


def _parameters(*files, **changed) -> dict:
    """Return the controller's parameters: its defaults, then the config files (as the node)."""
    from ipomdp_gaze.nodes.controller import controller_params
    values = {p.name: p.default for p in controller_params()}
    for name in files:
        values.update(yaml_parameters(REPO / 'config' / name, 'gaze_controller'))
    values.update({k.replace('__', '.'): v for k, v in changed.items()})
    return values


TRACKING = ('faces_camera_controller.yaml', 'faces_camera_tracking.yaml')
PEOPLE = TRACKING + ('faces_camera_people.yaml',)


def _stamp(t: float):
    sec = int(t)
    return SimpleNamespace(sec=sec, nanosec=int(round((t - sec) * 1e9)))


def _status(values: dict):
    return SimpleNamespace(values=[SimpleNamespace(key=k, value=str(v))
                                   for k, v in values.items()])


def _event(kind: str, event, person: int = 0) -> dict:
    values = {'fixations': event.fixations}
    if getattr(event, 'cell', None) is not None:
        values['cell'] = event.cell
    if getattr(event, 'probability', None) is not None:
        values['probability'] = event.probability
    if person:
        values['person'] = person
    return {'kind': kind, 'values': values}


def _parameter_event(t_s: float, values: dict, node: str = '/gaze_controller') -> BagMessage:
    """Return a ``/parameter_events`` message of ``node`` (doubles, strings, double arrays)."""
    params = []
    for name, value in values.items():
        if isinstance(value, str):
            v = SimpleNamespace(type=4, string_value=value)
        elif isinstance(value, list):
            v = SimpleNamespace(type=8, double_array_value=[float(x) for x in value])
        else:
            v = SimpleNamespace(type=3, double_value=float(value))
        params.append(SimpleNamespace(name=name, value=v))
    msg = SimpleNamespace(node=node, new_parameters=[], changed_parameters=params,
                          deleted_parameters=[])
    return BagMessage('/parameter_events', int(t_s * 1e9), msg, 0)


def _record(values: dict, faces, frames: int, changes=(), start: float = 1000.0,
            belief: bool = False) -> Bag:
    """
    Search with the core as the node does and return the bag a recorder would have written.

    ``faces(i, fixation)`` gives the cells with a face at frame ``i``; a view counts 9
    detections on a face in its 5x5 cells and 0 elsewhere, NaN out of view. ``changes`` are
    ``(frame, {parameter: value})`` set (as the node sets them) just before that frame: one that
    moves the head sends the current target again, stamped anew, and frames settle from then on
    (the node's ``_send_target``); a frame taken sooner is skipped. ``start``: when the search
    begins (s); ``belief``: also record the reset's ``belief`` (the prior), as the node sends it.
    """
    core, _ = build_controller(values)
    grid, config, live = core.grid, build_config(values, _build_policy()), dict(values)
    messages, t = [], start
    core.reset(t)
    if belief:
        messages.append(BagMessage('/belief', int((t + 0.002) * 1e9),
                                   SimpleNamespace(data=core.belief.astype(np.float32)), 0))

    def target(now: float) -> None:
        core.retarget(now)
        head = config.head          # a changed pan_offset_rad moves the targets sent after it
        pan, tilt = head.angles(core.fixation)
        msg = SimpleNamespace(header=SimpleNamespace(stamp=_stamp(now)),
                              name=[head.pan_joint, head.tilt_joint], position=[pan, tilt])
        messages.append(BagMessage('/pan_tilt', int((now + 0.001) * 1e9), msg, 0))
    target(t)
    changes = dict(changes)
    for i in range(frames):
        t += FRAME_S
        if i in changes:
            live.update(changes[i])
            old, config = config, build_config(live, _build_policy(), set(changes[i]), config)
            core.set_observation(config.observation)
            core.set_policy(config.policy)
            core.configure(config.settings, live['settle_time_s'])
            messages.append(_parameter_event(t - 0.1, changes[i]))
            if config.head != old.head and not core.stopped:
                target(t - 0.1 + 0.001)
        row, col = grid.cell(core.fixation)
        evidence = np.full(grid.n_cells, np.nan, dtype=np.float32)
        for r in range(max(0, row - 2), min(grid.rows, row + 3)):
            for c in range(max(0, col - 2), min(grid.cols, col + 3)):
                evidence[grid.index(r, c)] = 9.0 if grid.index(r, c) in faces(i) else 0.0
        messages.append(BagMessage('/evidence', int(t * 1e9),
                                   SimpleNamespace(data=evidence), evidence.nbytes))
        step = core.offer(evidence.astype(np.float64), t, t + 0.01)
        if step.status == 'skipped':
            continue
        assert step.applied, step.reason
        # The recorder takes each event topic in its own order: here the reverse of firing.
        fired = [_event(k, getattr(step, k)) for k in EVENT_KEYS if getattr(step, k)]
        fired += [_event(e.kind, e, e.person) for e in step.people]
        for j, event in enumerate(reversed(fired)):
            messages.append(BagMessage('/' + event['kind'], int((t + 0.005 + 1e-4 * j) * 1e9),
                                       _status(event['values']), 0))
        if step.fixation is not None:
            target(t + 0.01)
        if core.stopped:
            break
    custom = {'ipomdp_gaze/parameters/gaze_controller': yaml.safe_dump(values),
              'ipomdp_gaze/parameters_time/gaze_controller': str(int(999.0 * 1e9))}
    return Bag(Path('bag'), sorted(messages, key=lambda m: m.time_ns), custom, 0, t - 1000.0)


def _build_policy():
    from ipomdp_gaze.policies.registry import build_policy
    return build_policy


def _walk_out(face: int, until: int):
    """Put a face at ``face`` for the first ``until`` frames, then nobody (it walked away)."""
    return lambda i: {face} if i < until else set()


def test_a_tracker_that_found_lost_and_decided_absent_is_compared_by_its_last_decision():
    """QA: found -> lost -> absent replayed as 'the same fixations, another decision'."""
    values = _parameters(*TRACKING, confidence=0.85)
    bag = _record(values, _walk_out(5 * 11 + 8, 20), 60)
    kinds = [m.topic for m in bag.messages if m.topic in ('/found', '/lost', '/absent')]
    assert kinds == ['/found', '/lost', '/absent'], kinds
    lines = []
    result = replay(bag, out=lines.append)
    assert [e.kind for e in result.recorded_events] == ['found', 'lost', 'absent']
    assert result.recorded.kind == 'absent' and result.replayed.kind == 'absent'
    assert result.same, lines
    assert lines[-3].startswith('recorded: the last decision absent p='), lines
    assert lines[-2].startswith('replay:   the last decision absent p='), lines
    assert lines[-1] == 'the same fixations, the same events and the same last decision'
    assert 'another decision' not in '\n'.join(lines)


def test_a_parameter_set_while_recording_is_set_by_the_replay_at_its_time():
    """QA: confidence set at run time was ignored while replay said 'settings: recorded'."""
    values = _parameters(*TRACKING, confidence=0.95)
    # Lowered once the face has gone: with 0.95 the tracker never says absent here.
    bag = _record(values, _walk_out(5 * 11 + 8, 20), 60, changes=[(25, {'confidence': 0.85})])
    assert bag.topic('absent'), 'the recorded search should have ended absent'
    text = describe_settings(bag)
    assert text.startswith('settings: recorded; gaze_controller parameters set while '
                           'recording, each in force from its time: at '), text
    assert 'confidence 0.95 -> 0.85' in text and '\n' not in text
    lines = []
    result = replay(bag, out=lines.append)
    assert result.changes_applied == 1
    assert result.same, lines
    text = describe_settings(bag, result=result)
    assert text.startswith('settings: recorded; gaze_controller parameters set while '
                           'recording: applied by the replay at its time: at '), text
    # An option holds over a recorded change of the same parameter, and the line says so.
    text = describe_settings(bag, {'confidence': 0.9})
    assert text.startswith('settings: recorded, with confidence=0.9; ') and \
        text.endswith("(not confidence: the options' values hold)"), text
    assert not replay(bag, {'confidence': 0.9}, out=lambda line: None).same


def test_a_change_before_the_replayed_search_is_its_setting_from_the_start():
    """A parameter set, then ~/reset: the search replayed began with the new value."""
    values = _parameters(*TRACKING, confidence=0.85)
    bag = _record(values, _walk_out(5 * 11 + 8, 20), 60)
    # The same search recorded by a controller started at 0.5 and set to 0.85 before it.
    start = dict(values, confidence=0.5)
    early = _parameter_event(999.5, {'confidence': 0.85})
    reset = BagMessage('/belief', int(999.9 * 1e9),
                       SimpleNamespace(data=np.full(121, 1 / 121)), 0)
    bag = Bag(bag.path, sorted(bag.messages + [early, reset], key=lambda m: m.time_ns),
              dict(bag.custom_data, **{'ipomdp_gaze/parameters/gaze_controller':
                                       yaml.safe_dump(start)}), 0, bag.duration_s)
    assert 'confidence 0.5 -> 0.85' in describe_settings(bag)
    result = replay(bag, out=lambda line: None)
    assert result.changes_applied == 0 and result.same


def test_the_last_search_is_replayed_when_it_began_at_a_prior():
    """QA: a reset at belief.prior (not uniform) was not seen: the first search was replayed."""
    face = 5 * 11 + 8
    values = _parameters('faces_camera_controller.yaml')
    first = _record(values, lambda i: {face}, 20, belief=True)
    weights = np.ones(121)
    weights[:11] = 0.0                          # the top row ruled out
    weights[face] = 10.0
    second = _record(dict(values, **{'belief.prior': weights.tolist()}), lambda i: {face}, 20,
                     start=1100.0, belief=True)
    assert second.topic('found') and len(second.topic('evidence')) != len(first.topic('evidence'))
    change = _parameter_event(1099.0, {'belief.prior': weights.tolist()})
    bag = _with(first, list(second.messages) + [change])
    lines = []
    result = replay(bag, out=lines.append)
    assert [fate for _, fate in result.changes] == ['start'], lines
    assert result.applied == len(second.topic('evidence')) and result.same, lines
    assert len(result.recorded_events) == len(second.topic('found')), lines


def test_many_moving_people_are_compared_by_their_events_not_a_decision():
    """QA: a many-target walking bag said 'no decision / the same fixations, another decision'."""
    values = _parameters(*PEOPLE)
    bag = _record(values, _walk_out(5 * 11 + 8, 15), 40)
    assert any('person' in {kv.key for kv in m.msg.values} for m in bag.topic('found'))
    lines = []
    result = replay(bag, out=lines.append)
    assert result.recorded_people
    assert [e.key for e in result.recorded_people] == [e.key for e in result.replay_people]
    assert result.same, lines
    assert lines[0] == ('following many people: the replay compares their events (found, '
                        'lost, reacquired per person), not one decision')
    assert lines[-1] == "the same fixations and the same people's events"
    assert 'decision' not in '\n'.join(lines[1:])


def test_other_people_events_are_said_person_by_person():
    values = _parameters(*PEOPLE)
    bag = _record(values, _walk_out(5 * 11 + 8, 15), 40)
    # Drop the recorded lost event(s): the replay's then differ from the recording's.
    bag = Bag(bag.path, [m for m in bag.messages if m.topic != '/lost'], bag.custom_data, 0,
              bag.duration_s)
    lines = []
    result = replay(bag, out=lines.append)
    if not any(e.kind == 'lost' for e in result.replay_people):
        pytest.skip('this walk has no lost person to drop')
    assert not result.same
    assert lines[-1].startswith("the same fixations, other people's events: event "), lines
    assert 'person 1 lost at' in lines[-1]


@pytest.mark.parametrize('option, value, message', [
    ('policy', 'bogus', "--policy: unknown policy 'bogus'"),
    ('confidence', 2.0, '--confidence: '),
    ('policy_file', 'no-such-kernel', '--policy-file: '),
    ('observation', 'no-such-model', '--observation: '),
])
def test_a_bad_option_is_named_as_the_option_not_the_recording(option, value, message):
    from ipomdp_gaze.drivers.replay import checked_config
    values = _parameters(*TRACKING)
    with pytest.raises(ValueError) as err:
        checked_config(values, {option: value})
    assert str(err.value).startswith(message), str(err.value)
    assert 'the recording' not in str(err.value)
    broken = dict(values, confidence=7.0)
    with pytest.raises(ValueError, match='^the recording: '):
        checked_config(broken, {})
    assert settings_from(values, {option: None}) == values


def _grey_image_bag(controller: dict) -> Bag:
    """Return a bag of one grey 420x420 image with the detector's and the controller's settings."""
    detector = yaml_parameters(REPO / 'config' / 'faces_fovea_detector.yaml', 'foveal_detector')
    side = 420
    image = SimpleNamespace(encoding='mono8', height=side, width=side, step=side,
                            data=np.full(side * side, 128, dtype=np.uint8))
    custom = {'ipomdp_gaze/parameters/gaze_controller': yaml.safe_dump(controller),
              'ipomdp_gaze/parameters/foveal_detector': yaml.safe_dump(detector)}
    return Bag(Path('bag'), [BagMessage('/image', int(1e9), image, side * side)], custom, 0, 1.0)


def _with(bag: Bag, messages=(), **custom) -> Bag:
    """Return ``bag`` with more ``messages`` and ``custom_data`` entries."""
    return Bag(bag.path, sorted(list(bag.messages) + list(messages), key=lambda m: m.time_ns),
               dict(bag.custom_data, **custom), 0, bag.duration_s)


def _tracked_bag(**changed) -> Bag:
    return _record(_parameters(*TRACKING, confidence=0.85, **changed),
                   _walk_out(5 * 11 + 8, 20), 60)


def test_a_change_of_a_controller_in_another_namespace_is_not_the_recorded_ones():
    """Review: /parameter_events is global; /robot2/gaze_controller's change was applied."""
    bag = _tracked_bag()
    other = _parameter_event(1000.05, {'confidence': 0.5}, node='/robot2/gaze_controller')
    mixed = _with(bag, [other])
    assert parameter_changes(mixed) == []
    assert describe_settings(mixed) == 'settings: recorded'
    assert replay(mixed, out=lambda line: None).same
    # The recorder names the node it asked; that node's changes are the controller's.
    named = _with(bag, [other, _parameter_event(1000.06, {'confidence': 0.6})],
                  **{'ipomdp_gaze/parameters_node/gaze_controller': '/robot2/gaze_controller'})
    assert [c.values for c in parameter_changes(named)] == [{'confidence': 0.5}]


def test_a_head_change_after_the_search_does_not_move_its_targets():
    """Review: pan_offset_rad set 1 s after the search made every fixation 'differ'."""
    bag = _tracked_bag()
    end = bag.messages[-1].time_ns * 1e-9
    late = _with(bag, [_parameter_event(end + 1.0, {'pan_offset_rad': 0.3})])
    lines = []
    result = replay(late, out=lines.append)
    assert result.same and result.changes_applied == 0, lines
    text = describe_settings(late, result=result)
    assert 'applied by the replay' not in text and '\n' not in text, text
    assert text.startswith('settings: recorded; gaze_controller parameters set while '
                           "recording: after the replay's last frame (not applied): at "), text
    assert text.endswith(' s pan_offset_rad 0.0 -> 0.3'), text


def test_a_head_change_during_the_search_maps_the_targets_sent_after_it():
    bag = _record(_parameters(*TRACKING, confidence=0.85), _walk_out(5 * 11 + 8, 20), 60,
                  changes=[(6, {'pan_offset_rad': 0.05})])
    lines = []
    result = replay(bag, out=lines.append)
    assert result.changes_applied == 1 and result.same, lines
    text = describe_settings(bag, result=result)
    assert 'applied by the replay at its time: at ' in text and 'after' not in text, text


def test_a_late_event_of_an_earlier_search_is_not_this_ones():
    """Review: a /found of the search before, arriving before this one's first frame."""
    bag = _tracked_bag()
    first = min(m.time_ns for m in bag.topic('evidence'))
    late = BagMessage('/found', first - int(0.05e9),
                      _status({'fixations': 7, 'cell': 3, 'probability': 0.99}), 0)
    lines = []
    result = replay(_with(bag, [late]), out=lines.append)
    assert result.same, lines
    assert [e.kind for e in result.recorded_events] == ['found', 'lost', 'absent']


def test_a_search_event_of_a_many_people_search_is_compared_and_said():
    """Review: only gave_up differed; the last line said 'the same ... people's events'."""
    bag = _record(_parameters(*PEOPLE), _walk_out(5 * 11 + 8, 15), 40)
    assert not bag.topic('gave_up')
    extra = BagMessage('/gave_up', bag.messages[-1].time_ns + int(0.01e9),
                       _status({'fixations': 40}), 0)
    lines = []
    result = replay(_with(bag, [extra]), out=lines.append)
    assert not result.same
    assert lines[-1] == ("the same fixations and the same people's events, other search "
                         'events: event 1 is gave_up after 40 fixations recorded, none in the '
                         'replay'), lines
    assert lines[-3] == 'recorded search events: gave_up after 40 fixations', lines
    assert lines[-2] == 'replay search events:   none', lines


IDENTITY = [0.0] * 220 + [1.0] + [0.0] * 220        # 21x21: the belief itself


def test_a_recorded_change_refused_with_an_option_names_the_option_and_its_time():
    """Review: a plain ValueError, or the option blamed for a change after the search."""
    bag = _tracked_bag(policy__kernel=IDENTITY)
    # policy.kernel emptied before the first frame: --policy learned then has no kernel.
    during = _with(bag, [_parameter_event(1000.2, {'policy.kernel': []})])
    with pytest.raises(ValueError) as err:
        replay(during, {'policy': 'learned'}, out=lambda line: None)
    assert str(err.value).startswith("--policy: policy 'learned' needs policy.kernel or "
                                     'policy.file (with the parameters set at '), str(err.value)
    assert '\n' not in str(err.value)
    # The same change after the search is never used: no error.
    end = bag.messages[-1].time_ns * 1e-9
    after = _with(bag, [_parameter_event(end + 1.0, {'policy.kernel': []})])
    replay(after, {'policy': 'learned'}, out=lambda line: None)
    # A recorded change refused alone is the recording's.
    bad = _with(bag, [_parameter_event(1000.2, {'confidence': 7.0})])
    with pytest.raises(ValueError, match='^the recording: .*confidence.*'
                                         r'\(with the parameters set at 0\.2 s'):
        replay(bad, out=lambda line: None)


def test_no_decision_is_said_as_such():
    """Review: 'replay:   the last decision no decision'."""
    from ipomdp_gaze.model.grid import Grid
    grid = Grid(11, 11, 5.0)
    recorded = [Event('found', 3, 4, 0.9), Event('lost', None, 6), Event('absent', None, 9, 0.9)]
    result = ReplayResult(grid, [], [], recorded[-1].decision(), Decision(), 9, 3,
                          first_difference=3, recorded_events=recorded)
    from ipomdp_gaze.drivers.replay import _say_decisions
    lines = []
    _say_decisions(result, lines.append)
    assert lines[-1] == 'replay:   no decision', lines
    assert lines[-2].startswith('recorded: the last decision absent'), lines


def test_another_last_decision_is_said_in_plain_words():
    """Review: 'the same fixations, another the last decision decision'."""
    lines = []
    result = replay(_tracked_bag(), {'confidence': 0.95}, out=lines.append)
    assert result.first_difference is None and not result.same, lines
    assert lines[-1] == 'the same fixations, another last decision', lines
    from ipomdp_gaze.drivers.replay import _say_decisions
    from ipomdp_gaze.model.grid import Grid
    one = ReplayResult(Grid(11, 11, 5.0), [], [], Decision('absent', None, 0.9, 9),
                       Decision(), 9, 9)
    lines = []
    _say_decisions(one, lines.append)
    assert lines[-1] == 'the same fixations, another decision', lines


@pytest.mark.parametrize('option, value, recorded, named', [
    ('observation', 'faces-pan-tilt-profile', {'observation.model': 'gaussian'},
     'observation.model'),
    ('policy_file', 'some-kernel', {'policy.name': 'map'}, 'policy.name'),
    ('policy', 'map', {'policy.kernel': IDENTITY}, 'policy.kernel'),
])
def test_the_options_note_names_the_parameters_an_option_also_sets(option, value, recorded,
                                                                   named):
    bag = _with(_tracked_bag(), [_parameter_event(1000.2, recorded)])
    text = describe_settings(bag, {option: value})
    assert text.endswith(f"(not {named}: the options' values hold)"), text


def test_a_head_change_mid_search_resends_the_target_and_the_replay_settles_anew():
    """Review: the node's re-send counted as a fixation, the replay never settled again."""
    bag = _record(_parameters(*TRACKING, confidence=0.85), _walk_out(5 * 11 + 8, 20), 60,
                  changes=[(6, {'pan_offset_rad': 0.05})])
    change = bag.topic('/parameter_events')[0].time_ns
    after = [m for m in bag.topic('pan_tilt') if m.time_ns > change]
    before = [m for m in bag.topic('pan_tilt') if m.time_ns < change][-1]
    assert after[0].msg.position[1] == before.msg.position[1], 'the re-send of the same cell'
    lines = []
    result = replay(bag, out=lines.append)
    assert result.changes_applied == 1 and result.same, lines
    # The frame inside the re-sent target's settle window was skipped, by the node and replay.
    assert result.applied == result.frames - 1, (result.applied, result.frames)
    assert len(result.recorded_fixations) == len(bag.topic('pan_tilt')) - 1


@pytest.mark.parametrize('files', [TRACKING, PEOPLE])
def test_a_recording_under_sim_time_replays_its_frames_on_the_stamps_clock(files):
    """Review: bag times (system clock) against sim-time stamps: 0 frames, 'the same ...'."""
    import dataclasses
    bag = _record(_parameters(*files, confidence=0.85), _walk_out(5 * 11 + 8, 20), 60)
    reset = BagMessage('/belief', int(999.9995e9), SimpleNamespace(data=np.full(121, 1 / 121)),
                       0)
    shift = int(1.7e18)     # received on the system clock; the headers on the simulated one
    moved = Bag(bag.path, [dataclasses.replace(m, time_ns=m.time_ns + shift) for m in
                           sorted(bag.messages + [reset], key=lambda m: m.time_ns)],
                dict(bag.custom_data, **{'ipomdp_gaze/parameters_time/gaze_controller':
                                         str(int(999e9) + shift)}), 0, bag.duration_s)
    lines = []
    result = replay(moved, out=lines.append)
    assert result.applied == result.frames and result.same, lines


def test_no_frame_applied_is_said_as_nothing_compared():
    """Review: 0 frames applied, and the replay said 'the same fixations'."""
    bag = _tracked_bag()
    nan = SimpleNamespace(data=np.full(121, np.nan, dtype=np.float32))
    blind = Bag(bag.path, [BagMessage(m.topic, m.time_ns, nan, 0) if m.topic == '/evidence'
                           else m for m in bag.messages if m.topic not in
                           ('/found', '/lost', '/absent')], bag.custom_data, 0, bag.duration_s)
    lines = []
    result = replay(blind, out=lines.append)
    assert result.applied == 0 and not result.same, lines
    assert lines[-1].startswith('nothing compared: the replay applied none of the '
                                f'{result.frames} recorded frames ('), lines
    assert 'every cell is NaN' in lines[-1], lines
    assert not any(line.startswith('the same') for line in lines), lines


def test_a_bag_recorded_in_a_namespace_replays_its_topics_and_its_controllers_changes():
    """Review: '-r __ns:=/head1' wrote /head1/pan_tilt; the replay looked for /pan_tilt."""
    import dataclasses
    bag = _record(_parameters(*TRACKING, confidence=0.95), _walk_out(5 * 11 + 8, 20), 60,
                  changes=[(25, {'confidence': 0.85})])
    moved = [m if m.topic == '/parameter_events' else
             dataclasses.replace(m, topic='/head1' + m.topic) for m in bag.messages]
    for m in moved:
        if m.topic == '/parameter_events':
            m.msg.node = '/head1/gaze_controller'
    spaced = Bag(bag.path, moved, dict(bag.custom_data, **{
        'ipomdp_gaze/namespace': '/head1',
        'ipomdp_gaze/parameters_node/gaze_controller': '/head1/gaze_controller'}), 0,
        bag.duration_s)
    assert spaced.topic('pan_tilt') and spaced.topic('/parameter_events')
    lines = []
    result = replay(spaced, out=lines.append)
    assert result.changes_applied == 1 and result.same, lines
    assert result.applied == result.frames


def test_a_refused_replay_still_says_its_settings(cli_here, monkeypatch, tmp_path):
    """Review: the settings line was printed only after a replay that did not raise."""
    bag = _with(_tracked_bag(policy__kernel=IDENTITY),
                [_parameter_event(1000.2, {'policy.kernel': []})])
    monkeypatch.setattr('ipomdp_gaze.files.bag.read_bag', lambda path: bag)
    run = cli_here('replay', tmp_path, '--policy', 'learned')
    assert run.returncode == 2, run
    assert 'settings: recorded, with policy=learned; gaze_controller parameters set while ' \
        'recording, each in force from its time: at ' in run.stdout, run.stdout
    assert "--policy: policy 'learned' needs policy.kernel" in run.stderr, run.stderr


def test_a_new_search_on_the_recorded_image_starts_at_the_recorded_prior():
    """QA: replay --new-search searched from the uniform prior, not the recorded belief.prior."""
    from ipomdp_gaze.drivers.replay import new_search
    controller = _parameters('faces_fovea_controller.yaml')
    weights = np.zeros(21 * 21)
    weights[3 * 21 + 4] = 1.0                   # the face is known to be at (3, 4)
    controller['belief.prior'] = weights.tolist()
    bag = _grey_image_bag(controller)
    lines = []
    result = new_search(bag, out=lines.append)
    assert result.cell == (3, 4) and result.decision == 'found', lines


@pytest.mark.parametrize('inhibit_return, cause', [
    (False, 'the next fixation would repeat a cell'), (True, 'every cell fixated once')])
def test_a_new_search_says_what_ended_it_at_its_repeat_stop(inhibit_return, cause):
    """QA: replay --new-search said 'every cell fixated once' of any repeat stop."""
    from ipomdp_gaze.drivers.replay import new_search
    controller = _parameters('faces_fovea_controller.yaml')
    controller.update({'policy.name': 'elm', 'search.stop_on_repeat': True,
                       'search.inhibit_return': inhibit_return, 'search.scan': False})
    bag = _grey_image_bag(controller)
    lines = []
    result = new_search(bag, out=lines.append)
    assert (result.decision, result.stop) == ('gave_up', 'repeat'), lines
    assert lines[-1].startswith('new search on the recorded image: gave up at the repeat stop '
                                f'({cause}); most likely '), lines


def test_a_bad_option_is_its_one_line_before_anything_is_said(cli_here, monkeypatch, tmp_path):
    """QA: ``replay --policy bogus`` printed ``settings: recorded, with policy=bogus`` first."""
    bag = _tracked_bag()
    monkeypatch.setattr('ipomdp_gaze.files.bag.read_bag', lambda path: bag)
    for flags in (('--policy', 'bogus'), ('--policy', 'bogus', '--new-search')):
        run = cli_here('replay', tmp_path, *flags)
        assert run.returncode == 2, run
        assert run.stdout == '', run.stdout
        assert run.stderr == ("ipomdp-gaze replay: error: --policy: unknown policy 'bogus'; "
                              'valid policies: learned, map, random, center, elm, spiral, sweep, '
                              'coverage, greedy, tempered, switching, nmpt\n'), run.stderr


def test_a_last_search_without_a_frame_is_said_so_not_a_bag_without_frames():
    """
    QA: a recording stopped as a search began said the bag had no frame to replay.

    A still room's re-check (or a ~/reset) just before the recorder stopped: the bag holds the
    frames of the searches before it, and the last search, which a replay follows, has none.
    """
    face = 5 * 11 + 8
    values = _parameters('faces_camera_controller.yaml')
    first = _record(values, lambda i: {face}, 20, belief=True)
    began = _record(values, lambda i: {face}, 0, start=1100.0, belief=True)
    assert first.topic('evidence') and not began.topic('evidence')
    bag = _with(first, list(began.messages))
    with pytest.raises(ValueError) as caught:
        replay(bag, out=lambda line: None)
    assert str(caught.value) == (
        'bag: its last search, from the reset at 100.0 s of the recording, has no '
        'evidence_image or evidence frame to replay (the recording ended as it began); a '
        'replay follows the last search of a bag')
