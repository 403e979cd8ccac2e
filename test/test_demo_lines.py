# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The demo's printed lines say what the controller decided (issue 35), without node processes.

The demo follows the controller's messages; here they are built directly and handed to
:func:`ipomdp_gaze.harness.demo._follow` as the watch would record them: the face demo's progress
lines name the answer as the controller's ``found`` rule does (``search.found_radius``), show the
probability that nobody is there when the search can end ``absent``, and the last line says how
the search ended.
"""
from types import SimpleNamespace

import numpy as np
import pytest

pytestmark = pytest.mark.ros


def _record(setup, beliefs, looked, found=None, absent=None, truth=None):
    from builtin_interfaces.msg import Time
    from ipomdp_gaze.msg_adapters import grid_arrays, joints
    grid, head = setup.grid, setup.head
    return SimpleNamespace(
        beliefs=[(0.0, grid_arrays.to_multiarray(b, grid)) for b in beliefs],
        targets=[(0.0, joints.joint_state(head, c, Time())) for c in looked],
        found=[] if found is None else [(0.0, found)],
        absent=[] if absent is None else [(0.0, absent)],
        truth=[(0.0, grid_arrays.ground_truth(grid, truth))])


def _follow(setup, record):
    from ipomdp_gaze.harness.demo import _follow
    lines, stats = [], {}
    assert _follow(setup, record, lambda condition: condition(), 60.0, lines.append,
                   stats) == 0
    return lines, stats


def test_the_face_demos_lines_name_the_answer_the_controller_found():
    from ipomdp_gaze.harness.demo import faces_setup
    from ipomdp_gaze.msg_adapters import diagnostics
    setup = faces_setup()
    grid = setup.grid
    assert setup.settings.found_radius == 1 and setup.settings.absent_prior > 0
    # A face straddling (5, 9) and (6, 9): (5, 9) the likeliest single cell, the square round
    # (6, 9) the likeliest square (what the controller's found rule answers).
    belief = np.zeros(grid.n_cells)
    belief[grid.index(5, 9)], belief[grid.index(6, 9)] = 0.50, 0.40
    belief[grid.index(7, 9)], belief[grid.index(7, 10)] = 0.05, 0.045
    cell = grid.index(6, 9)
    found = diagnostics.found_status('c: found', 6, 9, cell, 0.0, 0.0, 0.995, 2, '', 0.99)
    lines, stats = _follow(setup, _record(setup, [belief * 0.5, belief], [60, 61], found=found,
                                          truth=cell))
    assert lines[1].startswith('fixation   2: looked at (5, 6)')
    assert '->  most likely (6, 9) p=0.995  nobody p=0.005  entropy' in lines[1]
    assert lines[2].startswith('found: the face is most likely at (6, 9), ')
    assert lines[2].endswith('probability 0.995, after 2 fixations (reached the confidence '
                             '0.99)')
    assert stats['stop'] == 'found' and stats['right']


def test_a_forced_found_and_an_absent_answer_say_so():
    from ipomdp_gaze.harness.demo import faces_setup
    from ipomdp_gaze.msg_adapters import diagnostics
    setup = faces_setup(empty=True)
    grid = setup.grid
    belief = np.full(grid.n_cells, 0.3 / grid.n_cells)
    forced = diagnostics.found_status('c: found', 0, 0, 0, 0.0, 0.0, 0.62, 1, 'budget', 0.99)
    lines, _ = _follow(setup, _record(setup, [belief], [60], found=forced, truth=0))
    assert lines[-2].startswith('found, forced by the fixation budget: the face is most likely '
                                'at (0, 0), ')
    assert lines[-2].endswith('probability 0.620, after 1 fixation (below the confidence 0.99)')
    absent = diagnostics.absent_status('c: absent', 0.7, 1, '', 0.99)
    lines, stats = _follow(setup, _record(setup, [belief], [60], absent=absent))
    assert '->  most likely' in lines[0] and 'nobody p=0.700' in lines[0]   # today: p=0.002 only
    assert lines[1] == ('absent: nobody is here, probability 0.700 that nobody is here, after 1 '
                        'fixation (below the confidence 0.99)')
    assert stats['stop'] == 'absent' and stats['right']


def test_a_found_at_a_grouped_detection_says_so():
    from ipomdp_gaze.harness.demo import faces_setup
    from ipomdp_gaze.msg_adapters import diagnostics
    setup = faces_setup()
    grid = setup.grid
    belief = np.full(grid.n_cells, 0.3 / grid.n_cells)
    grouped = diagnostics.found_status('c: found', 4, 2, grid.index(4, 2), 0.0, 0.0, 0.41, 1,
                                       'group', 0.99)
    assert grouped.message.endswith('after 1 fixation at a grouped detection of the detector')
    assert diagnostics.parse_found(grouped)['ended'] == 'group'
    lines, stats = _follow(setup, _record(setup, [belief], [60], found=grouped,
                                          truth=grid.index(4, 2)))
    assert lines[-2].startswith('found at a grouped detection: the face is at (4, 2), ')
    assert lines[-2].endswith('probability 0.410, after 1 fixation (below the confidence 0.99)')
    assert stats['stop'] == 'found' and stats['right']


def test_the_gaussian_demo_shows_no_absent_probability():
    from ipomdp_gaze.harness.demo import demo_setup
    from ipomdp_gaze.msg_adapters import diagnostics
    setup = demo_setup(target=(9, 7))
    grid = setup.grid
    belief = np.full(grid.n_cells, 0.01 / (grid.n_cells - 1))
    belief[grid.index(9, 7)] = 0.99
    found = diagnostics.found_status('c: found', 9, 7, grid.index(9, 7), 0.0, 0.0, 0.99, 1, '',
                                     0.95)
    lines, _ = _follow(setup, _record(setup, [belief], [60], found=found,
                                      truth=grid.index(9, 7)))
    assert 'nobody' not in lines[0] and '->  most likely (9, 7) p=0.990  entropy' in lines[0]
    assert lines[1].startswith('found: the target is most likely at (9, 7), pan')
    assert lines[1].endswith('(reached the confidence 0.95)')


def test_the_detectors_picture_labels_a_forced_answer():
    """The annotated image calls a found the fixation budget forced ``found, forced``."""
    from ipomdp_gaze.msg_adapters import diagnostics
    from ipomdp_gaze.nodes.annotation import Annotator
    node = SimpleNamespace(create_publisher=lambda *a: None,
                           create_subscription=lambda *a: None,
                           guard=SimpleNamespace(wrap=lambda callback: callback))
    annotator = Annotator(node)
    annotator._publish = lambda: None
    annotator._on_found(diagnostics.found_status('c: found', 1, 2, 13, 0.0, 0.0, 0.6, 20,
                                                 'budget', 0.99))
    assert annotator.found == (13, 0.6) and annotator.found_label == 'found, forced'
    annotator._on_found(diagnostics.found_status('c: found', 1, 2, 13, 0.0, 0.0, 0.999, 4,
                                                 radius=1))
    assert annotator.found_label == 'found' and annotator.found_radius == 1


def test_the_annotator_keeps_a_bounded_path_and_starts_one_per_search():
    """
    Soak QA: the fixations drawn grew with every fixation until a uniform belief came.

    A tracking search never sends one and a reset at a non-uniform ``belief.prior`` neither, so
    the list grew for as long as the detector ran, and each frame drew all of it. A scan frame
    (no fixation) raised TypeError.
    """
    from ipomdp_gaze.nodes.annotation import Annotator, MAX_DRAWN
    publisher = SimpleNamespace(get_subscription_count=lambda: 0)
    node = SimpleNamespace(create_publisher=lambda *a: publisher,
                           create_subscription=lambda *a: None,
                           guard=SimpleNamespace(wrap=lambda callback: callback))
    annotator = Annotator(node)

    def frame(fixation, search_id):
        return SimpleNamespace(fixation=fixation, search_id=search_id, detections_px=None,
                               image=None)
    annotator.on_frame(frame(None, 1))                      # the scan of search 1
    for k in range(5 * MAX_DRAWN):
        annotator.on_frame(frame(k % 7, 1))
    assert annotator.count == 5 * MAX_DRAWN
    assert list(annotator.fixations) == [k % 7 for k in range(4 * MAX_DRAWN, 5 * MAX_DRAWN)]
    annotator.on_frame(frame(3, 2))                         # search 2, no uniform belief
    assert list(annotator.fixations) == [3] and annotator.count == 1


def test_the_annotators_subscriptions_run_under_the_nodes_guard():
    """QA (composed nodes): a failure drawing a belief or found message is counted, not fatal."""
    from ipomdp_gaze.nodes.annotation import Annotator
    from ipomdp_gaze.nodes.guard import CallbackGuard
    subscribed = {}
    warnings = []
    logger = SimpleNamespace(warning=lambda text, **kw: warnings.append(text))
    node = SimpleNamespace(create_publisher=lambda *a: None, get_logger=lambda: logger,
                           create_subscription=lambda kind, topic, callback, depth:
                           subscribed.__setitem__(topic, callback))
    node.guard = CallbackGuard(node)
    annotator = Annotator(node)

    def fail():
        raise IndexError('a cell outside the grid')
    annotator._publish = fail
    annotator.node.loop = SimpleNamespace(setup=SimpleNamespace(grid=None))
    from ipomdp_gaze.msg_adapters import diagnostics
    subscribed['found'](diagnostics.found_status('c: found', 1, 2, 13, 0.0, 0.0, 0.6, 20))
    assert node.guard.errors == 1 and node.guard.by_callback == {'on_found': 1}
    assert 'IndexError: a cell outside the grid' in warnings[0]


def test_a_reset_at_a_prior_is_a_reset_for_the_watch_and_the_demo():
    """QA: a search started at belief.prior was counted as a fixation's update (not uniform)."""
    from ipomdp_gaze.harness.watch import is_update, SearchRecord
    from ipomdp_gaze.model.belief import bayes_update
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import grid_arrays
    from std_msgs.msg import Float32MultiArray
    grid = Grid(3, 3)
    prior = np.array([0.0, 1.0, 0.0, 1.0, 4.0, 1.0, 0.0, 1.0, 0.0]) / 8.0
    other = np.roll(prior, 1)
    with np.errstate(divide='ignore'):
        after = np.exp(bayes_update(np.log(prior), np.linspace(-1.0, 1.0, 9)))

    def msg(belief):
        return grid_arrays.to_multiarray(belief, grid)            # float32, as the node sends

    assert not is_update(msg(np.full(9, 1 / 9)))
    for reset in (prior, 0.7 * prior):                             # 0.7: with absent.prior 0.3
        assert not is_update(msg(reset), [prior])
        assert not is_update(msg(reset), [other, prior])
        assert is_update(msg(reset))                               # an unknown prior: as before
        assert is_update(msg(reset), [other])
    assert is_update(msg(after), [prior])
    assert is_update(Float32MultiArray(data=[0.1, 0.2, 0.3, 0.4]), [prior])   # another size

    kept = {}

    def record(msg_type, topic, qos=10, distinct_stamps=False, keep=None):
        kept[topic] = keep
        return []

    SearchRecord(SimpleNamespace(record=record), updates_only=True, n_cells=9, priors=[prior])
    assert not kept['belief'](msg(prior)) and not kept['belief'](msg(np.full(9, 1 / 9)))
    assert kept['belief'](msg(after))
