# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The controller's ``belief.prior`` on an in-process node: as written, and against a policy file.

Whole numbers (``-p belief.prior:=[1,2,1,...]``, YAML ``[1, 2, 1]``, a set of integers) reach
rclpy as an integer array; the controller takes them as doubles. A policy file trained on
another prior than the one in force is said once, as ``evaluate`` says it. The same in-process
node for what the controller logs: its configuration warnings (said once while they last), its
start-up line's motion and the still-scene rules it says are off for a moving target, and how
a room's search ended (done, or undecided at its budget), the parameter behind a search that
gave up, and the first search's id (1).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytestmark = pytest.mark.ros
WEIGHTS = [1] * 121
WEIGHTS[60] = 11                                # the centre cell, 11 times any other


def _node(context, **kwargs):
    from ipomdp_gaze.nodes.controller import GazeControllerNode
    return GazeControllerNode(context=context, **kwargs)


def _set(node, **values):
    from rclpy.parameter import Parameter
    return node.set_parameters_atomically(
        [v if isinstance(v, Parameter) else Parameter(k.replace('__', '.'), value=v)
         for k, v in values.items()])


def _log_until(capfd, words, timeout_s=5.0) -> str:
    """Return this process's stderr (rcutils logs there) up to and with ``words``."""
    import time
    deadline, seen = time.monotonic() + timeout_s, ''
    while words not in seen and time.monotonic() < deadline:
        seen += capfd.readouterr().err
        time.sleep(0.02)
    assert words in seen, seen
    return seen


@pytest.mark.parametrize('given', ['parameter_overrides', '-p', 'params file'])
def test_whole_numbers_for_belief_prior_are_taken_as_doubles(context, tmp_path, given):
    """QA: -p belief.prior:=[1,2,1,...] was refused by rclpy's type check (INTEGER_ARRAY)."""
    from rclpy.parameter import Parameter
    text = f"[{', '.join(map(str, WEIGHTS))}]"
    if given == 'parameter_overrides':
        kwargs = {'parameter_overrides': [Parameter('belief.prior', value=WEIGHTS)]}
        assert kwargs['parameter_overrides'][0].type_ == Parameter.Type.INTEGER_ARRAY
    elif given == '-p':
        kwargs = {'cli_args': ['--ros-args', '-p', f'belief.prior:={text.replace(" ", "")}']}
    else:
        path = tmp_path / 'prior.yaml'
        path.write_text(f'/**:\n  ros__parameters:\n    belief.prior: {text}\n')
        kwargs = {'cli_args': ['--ros-args', '--params-file', str(path)]}
    node = _node(context, **kwargs)
    try:
        got = node.get_parameter('belief.prior')
        assert got.type_ == Parameter.Type.DOUBLE_ARRAY
        assert list(got.value) == [float(w) for w in WEIGHTS]
        np.testing.assert_allclose(node._config.prior, np.array(WEIGHTS) / sum(WEIGHTS))
        # At run time (a set, as ros2 param set and the parameter service make one).
        again = WEIGHTS[::-1]
        again[0] = 3
        assert Parameter('belief.prior', value=again).type_ == Parameter.Type.INTEGER_ARRAY
        result = _set(node, belief__prior=again)
        assert result.successful, result.reason
        assert node.get_parameter('belief.prior').type_ == Parameter.Type.DOUBLE_ARRAY
        np.testing.assert_allclose(node._config.prior, np.array(again) / sum(again))
        # Whole numbers go through the same checks as any weights.
        result = _set(node, belief__prior=[-1] + WEIGHTS[1:])
        assert not result.successful
        assert 'belief.prior weights must be >= 0: cell (0, 0) is -1' in result.reason, \
            result.reason
        result = _set(node, belief__prior=WEIGHTS[1:])
        assert not result.successful and 'belief.prior must hold one weight per cell, 121 ' \
            'values' in result.reason, result.reason
        # Every double array takes whole numbers: a kernel, the false-alarm scales.
        kernel = [0] * 441
        kernel[220] = 1
        result = _set(node, policy__kernel=kernel)
        assert result.successful, result.reason
        got = node.get_parameter('policy.kernel')
        assert got.type_ == Parameter.Type.DOUBLE_ARRAY and list(got.value) == kernel
        result = _set(node, fpoc__ecc_deg=[0, 20])          # the table FPOC's eccentricities
        assert result.successful, result.reason
        got = node.get_parameter('fpoc.ecc_deg')
        assert got.type_ == Parameter.Type.DOUBLE_ARRAY and list(got.value) == [0.0, 20.0]
        # (the scales reach the settings check, past rclpy's type check: counts only)
        result = _set(node, search__false_alarm_scales=[1, 2, 4])
        assert not result.successful and 'needs a count model' in result.reason, result.reason
        np.testing.assert_allclose(node._config.prior, np.array(again) / sum(again))
    finally:
        node.destroy_node()


def test_a_policy_file_used_with_another_prior_is_said_at_start_and_on_each_change(
        context, capfd, tmp_path):
    """QA: evaluate warned on a policy file used off its training prior; the controller not."""
    from ipomdp_gaze.policies.policy_file import load_policy_spec, save_policy
    from rclpy.parameter import Parameter
    spec = load_policy_spec('camera-11x11-infomax')
    weights = [float(w) for w in WEIGHTS]
    prior = np.array(weights) / sum(weights)
    trained = save_policy(tmp_path / 'trained.yaml', replace(
        spec, path=None, training={**spec.training, 'prior': prior.reshape(11, 11).tolist()}))
    plain = save_policy(tmp_path / 'plain.yaml', replace(spec, path=None))
    said = {'uniform': f'{trained}: policy was trained with a prior that is not uniform but is '
                       'used with the uniform one',
            'another': f'{trained}: policy was trained with another prior than the one it is '
                       'used with',
            'plain': f'{plain}: policy was trained with a uniform prior but is used with '
                     'another'}
    capfd.readouterr()
    node = _node(context, parameter_overrides=[Parameter('policy.file', value=str(trained))])
    try:
        log = _log_until(capfd, 'first fixation')
        assert log.count(said['uniform']) == 1 and 'policy learned' in log
        # At the policy's own prior: nothing to say.
        assert _set(node, belief__prior=weights).successful
        log = _log_until(capfd, 'parameters set: belief.prior=')
        assert 'policy was trained with' not in log
        other = list(weights)
        other[0] = 11.0
        assert _set(node, belief__prior=other).successful
        log = _log_until(capfd, 'parameters set: belief.prior=')
        assert log.count(said['another']) == 1
        # Neither the policy nor the prior changed: not said again.
        assert _set(node, confidence=0.9).successful
        assert 'policy was trained with' not in _log_until(capfd, 'parameters set: confidence=')
        # A policy trained on the uniform prior, used at belief.prior.
        assert _set(node, policy__file=str(plain)).successful
        log = _log_until(capfd, 'parameters set: policy.file=')
        assert log.count(said['plain']) == 1 and said['another'] not in log
        empty = Parameter('belief.prior', Parameter.Type.DOUBLE_ARRAY, [])
        assert _set(node, belief__prior=empty).successful
        assert 'policy was trained with' not in _log_until(capfd, 'parameters set: belief.prior=')
        # Back to the file trained on the prior, now used with the uniform one.
        assert _set(node, policy__file=str(trained)).successful
        assert _log_until(capfd, 'parameters set: policy.file=').count(said['uniform']) == 1
    finally:
        node.destroy_node()


def test_a_moving_room_without_an_entry_model_is_said_once_while_it_lasts(context, capfd):
    """
    QA: the "no entry model" warning of a moving room came again with every parameter set.

    It is said at start-up, not again while its cause lasts (any other change), and again
    after the cause went away and came back; another cause is said on its own.
    """
    from rclpy.parameter import Parameter
    no_entry = 'search.targets many with motion and no entry model'
    no_dwell = 'motion.track_view policy: the people found are not kept in view'
    capfd.readouterr()
    node = _node(context, parameter_overrides=[
        Parameter('search.targets', value='many'), Parameter('motion.sigma_cells', value=0.5),
        Parameter('motion.track_view', value='peak')])
    try:
        assert _log_until(capfd, 'first fixation').count(no_entry) == 1
        for confidence in (0.9, 0.95):
            assert _set(node, confidence=confidence).successful
            assert no_entry not in _log_until(capfd, 'parameters set: confidence=')
        assert _set(node, motion__track_view='policy').successful
        log = _log_until(capfd, 'parameters set: motion.track_view=')
        assert log.count(no_dwell) == 1 and no_entry not in log
        assert _set(node, motion__jump_prob=0.01).successful        # an entry model
        log = _log_until(capfd, 'parameters set: motion.jump_prob=')
        assert no_entry not in log and no_dwell not in log
        assert _set(node, motion__jump_prob=0.0).successful         # none again
        assert _log_until(capfd, 'parameters set: motion.jump_prob=').count(no_entry) == 1
    finally:
        node.destroy_node()


@pytest.mark.parametrize('motion, warned', [('max_speed_cells', True), ('speed_cells', False)])
def test_a_walking_room_is_warned_about_and_a_still_one_is_not(context, capfd, motion, warned):
    """
    QA: the moving room's warnings took motion.speed_cells for motion, not max_speed_cells.

    People who walk (motion.max_speed_cells alone: a velocity, followed in turn) were not
    warned about; a still room with motion.speed_cells (unused without max_speed_cells) was
    warned about as people with motion.
    """
    from rclpy.parameter import Parameter
    no_entry = 'search.targets many with motion and no entry model'
    capfd.readouterr()
    node = _node(context, parameter_overrides=[
        Parameter('search.targets', value='many'), Parameter(f'motion.{motion}', value=4.0),
        Parameter('motion.track_view', value='peak')])
    try:
        log = _log_until(capfd, 'first fixation')
        assert (no_entry in log) == warned, log
        assert ('many moving targets' in log) == warned, log
    finally:
        node.destroy_node()


def test_an_absent_prior_too_small_for_many_targets_is_refused_by_its_name(context):
    """QA: the refusal named search.absent.prior, a parameter the controller does not have."""
    node = _node(context, cli_args=['--ros-args', '-p', 'grid.rows:=2', '-p', 'grid.cols:=2',
                                    '-p', 'search.targets:=many', '-p', 'absent.prior:=0.5',
                                    '-p', 'policy.name:=elm'])
    try:
        result = _set(node, absent__prior=1e-70)
        assert not result.successful
        assert result.reason.startswith('search.targets many on 4 cells needs a larger '
                                        'absent.prior (got 1e-70)'), result.reason
        assert node.get_parameter('absent.prior').value == 0.5
    finally:
        node.destroy_node()


@pytest.mark.parametrize('decide_at_budget', [False, True])
def test_a_still_room_that_gave_up_at_its_budget_is_not_said_done(
        context, capfd, decide_at_budget):
    """
    QA: a still room's search that ran out of its budget undecided logged 'room done'.

    No room_done is published after gave_up (the people are those at the confidence), so the
    log says the search ended undecided; a decision the budget forced is a room done, as before.
    """
    from ipomdp_gaze.msg_adapters import grid_arrays
    from rclpy.parameter import Parameter
    capfd.readouterr()
    node = _node(context, parameter_overrides=[
        Parameter('search.targets', value='many'), Parameter('search.max_fixations', value=3),
        Parameter('search.decide_at_budget', value=decide_at_budget),
        Parameter('settle_time_s', value=0.0)])
    try:
        grid = node._config.grid
        published = []
        node._event_pubs['room_done'].publish = published.append
        values = np.zeros(grid.n_cells)
        values[[grid.index(4, 4), grid.index(6, 6)]] = 8.0       # two faces near the centre
        _log_until(capfd, 'first fixation')
        for _ in range(3):
            node._on_evidence(grid_arrays.to_multiarray(values, grid), None)
        people = '2 people{} (2 new): (4, 4) p=1.000, (6, 6) p=1.000'
        if decide_at_budget:
            assert node.core.decision == 'found' and len(published) == 1
            said = f'room done (search {node.core.search_id}, found), forced by the fixation ' \
                'budget: '
            assert said + people.format('') in _log_until(capfd, 'people')
        else:
            assert node.core.decision == 'gave_up' and published == []
            said = f'search {node.core.search_id} ended undecided at the fixation budget: '
            log = _log_until(capfd, 'people')
            assert said + people.format(' at the confidence 0.95') in log and 'room done' \
                not in log, log
    finally:
        node.destroy_node()


@pytest.mark.parametrize('motion, said', [
    ({'max_speed_cells': 4.0, 'turn_prob': 0.3},
     'random walk 0.0 cells/s, jump 0.0/s, walking up to 4.0 cells/s, turn 0.3/s'),
    ({'sigma_cells': 0.5, 'jump_prob': 0.01}, 'random walk 0.5 cells/s, jump 0.01/s'),
    ({'leave_prob': 0.1}, 'random walk 0.0 cells/s, jump 0.0/s, leave 0.1/s')])
def test_the_start_up_line_names_the_motion_the_search_models(context, capfd, motion, said):
    """QA: a target that only walks was 'a moving target (0.0 cells/s, jump 0.0/s)'."""
    from rclpy.parameter import Parameter
    capfd.readouterr()
    node = _node(context, parameter_overrides=[Parameter('absent.prior', value=0.5)] + [
        Parameter(f'motion.{name}', value=value) for name, value in motion.items()])
    try:
        assert f'; a moving target ({said}), absent prior 0.5,' in \
            _log_until(capfd, 'first fixation')
    finally:
        node.destroy_node()


def test_stop_on_decision_off_is_said_to_be_ignored_by_a_room(context, capfd):
    """
    QA: search.stop_on_decision false did nothing with search.targets many, unsaid.

    The still room's search still ends when every cell is decided (room done); the warning is
    said once while it lasts, and not with one target, which follows it.
    """
    from ipomdp_gaze.msg_adapters import grid_arrays
    from rclpy.parameter import Parameter
    ignored = 'search.stop_on_decision false is ignored with search.targets many'
    capfd.readouterr()
    node = _node(context, parameter_overrides=[
        Parameter('search.targets', value='many'), Parameter('settle_time_s', value=0.0),
        Parameter('search.stop_on_decision', value=False)])
    try:
        assert _log_until(capfd, 'first fixation').count(ignored) == 1
        grid = node._config.grid
        values = np.full(grid.n_cells, -8.0)
        values[grid.index(5, 5)] = 8.0
        for _ in range(grid.n_cells):
            if node.core.stopped:
                break
            node._on_evidence(grid_arrays.to_multiarray(values, grid), None)
        assert node.core.stopped and node.core.decision == 'found'
        assert 'room done (search' in _log_until(capfd, '1 person')
        assert _set(node, confidence=0.9).successful
        assert ignored not in _log_until(capfd, 'parameters set: confidence=')
        assert _set(node, search__targets='one').successful
        assert ignored not in _log_until(capfd, 'parameters set: search.targets=')
        assert _set(node, search__targets='many').successful
        assert _log_until(capfd, 'parameters set: search.targets=').count(ignored) == 1
    finally:
        node.destroy_node()


@pytest.mark.parametrize('given, said', [
    (['--params-file', 'faces_camera_tracking.yaml'],
     ', no fixation budget, inhibition of return off for a moving target; first fixation'),
    (['-p', 'motion.sigma_cells:=0.5', '-p', 'search.inhibit_return:=true', '-p',
      'search.repeat_weight:=0.3'],
     ', inhibition of return and the repeat weight off for a moving target; first fixation'),
    (['-p', 'search.targets:=many', '-p', 'motion.sigma_cells:=0.5', '-p',
      'motion.jump_prob:=0.01', '-p', 'search.inhibit_return:=true'],
     ', inhibition of return off for moving targets; first fixation'),
    (['-p', 'search.inhibit_return:=true', '-p', 'search.repeat_weight:=0.3'],
     ', inhibition of return, repeated views weighted 0.3; first fixation'),
    (['-p', 'motion.sigma_cells:=0.5'], ', no fixation budget; first fixation')],
    ids=['tracking-config', 'moving', 'moving-room', 'still', 'moving-without'])
def test_the_start_up_line_says_the_still_scene_rules_are_off_for_a_moving_target(
        context, capfd, given, said):
    """
    QA: a moving target's start-up line said 'inhibition of return', which the search turns off.

    One target and many switch inhibition of return and the repeat weight off while the target
    moves (docs/design.md section 12.4); a still target's line names them as before.
    """
    from conftest import config_path
    args = [config_path(a) if a.endswith('.yaml') else a for a in given]
    capfd.readouterr()
    node = _node(context, cli_args=['--ros-args'] + args)
    try:
        line = next(line for line in _log_until(capfd, 'first fixation').splitlines()
                    if 'first fixation' in line)
        assert said in line, line
    finally:
        node.destroy_node()


@pytest.mark.parametrize('targets, settings, response, fixations, cause, limit', [
    ('one', {'search.max_fixations': 2}, 2.0, 2, 'search.max_fixations', ''),
    ('one', {'search.inhibit_return': True, 'search.stop_on_repeat': True}, 2.0, 4,
     'search.stop_on_repeat', ''),
    ('one', {'search.stop_on_repeat': True}, 2.0, 1, 'search.stop_on_repeat', ''),
    ('many', {'search.max_fixations': 2}, 2.0, 2, 'search.max_fixations',
     'the fixation budget'),
    ('many', {'search.inhibit_return': True}, 2.0, 4, 'search.inhibit_return',
     'the repeat stop (every cell fixated once)'),
    ('many', {'search.stop_on_repeat': True}, 2.0, 1, 'search.stop_on_repeat',
     'the repeat stop (the next fixation would repeat a cell)'),
    ('many', {'fpoc.dprime': 1e-6}, 0.0, 1, 'no view left would tell anything new',
     'the repeat stop (no view left would tell anything new)')],
    ids=['budget', 'repeat-inhibited', 'repeat', 'room-budget', 'room-inhibited',
         'room-repeat', 'room-nothing-new'])
def test_gave_up_names_the_parameter_behind_its_limit(
        context, capfd, targets, settings, response, fixations, cause, limit):
    """
    QA: 'gave up' always ended '(search.max_fixations)', also when search.stop_on_repeat ended it.

    The log and the gave_up event name the rule that ended the search (the event says 'the
    budget' for search.max_fixations, as before); a room whose views can tell nothing new
    gives up by no parameter's rule, and says so. QA: a room's log line then said
    '(gave_up, forced by repeat)'; it says the limit in find's and search's words.
    """
    from ipomdp_gaze.msg_adapters import grid_arrays
    from rclpy.parameter import Parameter
    capfd.readouterr()
    node = _node(context, parameter_overrides=[
        Parameter('grid.rows', value=2), Parameter('grid.cols', value=2),
        Parameter('search.targets', value=targets), Parameter('settle_time_s', value=0.0),
        Parameter('absent.prior', value=0.5), Parameter('confidence', value=0.999)] + [
        Parameter(name, value=value) for name, value in settings.items()])
    try:
        published = []
        node._event_pubs['gave_up'].publish = published.append
        grid = node._config.grid
        _log_until(capfd, 'first fixation')
        for _ in range(fixations):
            node._on_evidence(grid_arrays.to_multiarray(np.full(grid.n_cells, response), grid),
                              None)
        assert node.core.stopped and node.core.decision == 'gave_up'
        log = _log_until(capfd, 'gave up')
        said = f'gave up: no decision after {fixations} fixation'
        assert f"{said}{'s' if fixations > 1 else ''} ({cause})" in log, log
        event = 'the budget' if cause == 'search.max_fixations' else cause
        assert [m.message.endswith(f'({event})') for m in published] == [True], published
        if limit:
            if 'ended undecided' not in log:
                log += _log_until(capfd, 'ended undecided')
            assert f'search {node.core.search_id} ended undecided at {limit}: ' in log, log
    finally:
        node.destroy_node()


def test_a_fresh_node_s_first_search_is_search_1(context, capfd):
    """
    QA: a freshly started still room's first search was logged 'room done (search 2, ...)'.

    The core began search 1 when it was built, and the node's start restarted it as a new
    search; search ids grow by one with every new search (docs/design.md section 10.3), so the
    first is 1 on ``fixation``, ``room_done`` and in the log, and a ``~/reset`` starts 2.
    """
    from conftest import config_path
    from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays
    from std_srvs.srv import Trigger
    capfd.readouterr()
    node = _node(context, cli_args=[
        '--ros-args', '--params-file', config_path('faces_camera_controller.yaml'),
        '--params-file', config_path('faces_camera_room_controller.yaml'),
        '-p', 'settle_time_s:=0.0'])
    try:
        grid = node._config.grid
        published = []
        node._event_pubs['room_done'].publish = published.append
        _log_until(capfd, 'first fixation')
        for search_id in (1, 2):
            assert node._fixation_msg.data[2] == search_id and node.core.search_id == search_id
            while not node.core.stopped:                # nobody: the sweep's pass, all empty
                node._on_evidence(grid_arrays.to_multiarray(np.zeros(grid.n_cells), grid),
                                  None)
            assert f'room done (search {search_id}, absent' in _log_until(capfd, 'room done')
            assert diagnostics.parse_room_done(published[-1])['search_id'] == search_id
            node._on_reset(Trigger.Request(), Trigger.Response())
    finally:
        node.destroy_node()
