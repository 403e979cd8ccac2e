# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Replay a recorded search: its frames through the controller's core, with its settings or others.

A bag written by the ``recorder`` node (:mod:`ipomdp_gaze.files.bag`) holds the frames of evidence
the controller was offered (``evidence_image``, stamped, or ``evidence``), the targets it sent
(``pan_tilt``, one stamp per target), its events (``found``, ``absent``, ``gave_up``, ``lost``,
``reacquired``; a person's with a ``person`` value), its parameters at the start and the
changes of them (``/parameter_events``). :func:`replay` builds a
:class:`ipomdp_gaze.search.gaze.GazeController` from those parameters as they were when the
replayed search began, with any of them replaced (``overrides``: another observation model,
policy, confidence ...), sets each later change at its recorded time as the node does, drives
it with ``reset`` and ``offer(evidence, stamp_s, now_s)`` exactly as the node did (``now_s``:
when the node sent the next target) and compares it with the recording: every next fixation,
the events in order and the last decision (a tracker may find, lose and decide absent in one
search), or, following many moving people, each person's events.

The frames were taken where the *recorded* search looked. A replay that chooses another fixation
would need a frame from a view nobody took, so it stops at the first fixation that differs and
says so; up to there every decision is compared. A fixed camera (the detector's ``fovea`` mode)
records the whole scene, so :func:`new_search` can instead run a whole new search on the last
recorded image, with the detector's recorded count model and fovea and the (overridden)
controller settings. No rclpy here: messages come from ``rosbags``.
"""
from __future__ import annotations

import bisect
import dataclasses
from dataclasses import dataclass, field
import math

from ipomdp_gaze.files.evidence_bytes import decode_evidence
from ipomdp_gaze.model.belief import EvidenceError, is_reset_belief
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search import answer
from ipomdp_gaze.search.controller_config import build_config, ControllerConfig, \
    follow_config, grid_from, head_from, prior_from
from ipomdp_gaze.search.gaze import GazeController
import numpy as np

CONTROLLER = 'gaze_controller'
DETECTOR = 'foveal_detector'
IMAGE_CHANNELS = {'mono8': 1, 'rgb8': 3, 'bgr8': 3}
# The target sent with a reset is stamped at most this long after the reset belief arrived, and
# at most RESET_WINDOW_S before (a reset of a disabled controller sends none: its first target
# comes when it is enabled, after the reset belief).
RESET_TARGET_S = 0.005
RESET_WINDOW_S = 0.25
# Header stamps this much or more away from the messages' arrival are of another clock (the
# simulated one under use_sim_time; the recorder writes the system clock's receipt).
CLOCKS_APART_S = 1.0
# The bag's growth per minute of search is extrapolated from at least this many seconds and
# frames (a face demo's search: 3-10 frames over 2.5-10 s).
MIN_RATE_S, MIN_RATE_FRAMES = 2.0, 3
# What ``replay`` may change, and the controller parameter each one sets.
OVERRIDES = {'observation': 'observation.file', 'policy': 'policy.name',
             'policy_file': 'policy.file', 'confidence': 'confidence',
             'max_fixations': 'search.max_fixations', 'repeat_weight': 'search.repeat_weight',
             'inhibit_return': 'search.inhibit_return'}
# The command-line option of each override, which a refusal of its value names.
OPTIONS = {key: '--' + key.replace('_', '-') for key in OVERRIDES}
# The controller's event topics, in the order a frame that fires several fires them.
EVENTS = ('found', 'reacquired', 'lost', 'absent', 'gave_up')
# The events that decide (``lost`` only ends a ``found``).
DECISIONS = ('found', 'reacquired', 'absent', 'gave_up')
# rcl_interfaces/msg/ParameterValue: the field of each type (0, not set, has none).
VALUE_FIELDS = {1: 'bool_value', 2: 'integer_value', 3: 'double_value', 4: 'string_value',
                5: 'byte_array_value', 6: 'bool_array_value', 7: 'integer_array_value',
                8: 'double_array_value', 9: 'string_array_value'}


@dataclass
class Decision:
    """
    The end of a search: ``kind`` found, absent, gave_up or '' (none), cell, probability.

    ``probability`` is the answer's (``P(absent)`` for absent); ``forced_by`` the limit that
    forced a found or absent below the confidence ('' when the evidence reached it).
    """

    kind: str = ''
    cell: int | None = None
    probability: float | None = None
    fixations: int | None = None
    forced_by: str = ''

    def describe(self, grid: Grid) -> str:
        """Say it in one phrase, in the words of :mod:`ipomdp_gaze.search.answer`."""
        if not self.kind:
            return 'no decision'
        where = f' at {tuple(int(v) for v in grid.cell(self.cell))}' \
            if self.cell is not None else ''
        nobody = ' that nobody is here' if self.kind == 'absent' else ''
        p = f' p={self.probability:.3f}{nobody}' if self.probability is not None else ''
        return (f'{answer.heading(self.kind, self.forced_by)}{where}{p} after '
                f'{counted(self.fixations, "fixation")}')

    def same(self, other: Decision) -> bool:
        """Whether both are the same decision (kind, cell and fixations)."""
        return (self.kind, self.cell, self.fixations) == (other.kind, other.cell, other.fixations)


@dataclass(frozen=True)
class Event:
    """
    One event of the controller: ``kind`` (:data:`EVENTS`), cell, fixations, probability.

    ``person`` is the person's number in a moving many-target search, 0 for the search's own.
    """

    kind: str
    cell: int | None
    fixations: int
    probability: float | None = None
    person: int = 0
    forced_by: str = ''

    @property
    def key(self) -> tuple:
        """Return what two events must share to be the same: kind, person, cell, fixations."""
        return self.kind, self.person, self.cell, self.fixations

    def decision(self) -> Decision:
        """Return it as a :class:`Decision`."""
        return Decision(self.kind, self.cell, self.probability, self.fixations, self.forced_by)

    def describe(self, grid: Grid) -> str:
        """Say it briefly: ``person 2 lost at (3, 4) after 17 fixations``."""
        who = f'person {self.person} ' if self.person else ''
        where = f' at {tuple(int(v) for v in grid.cell(self.cell))}' \
            if self.cell is not None else ''
        return f'{who}{self.kind}{where} after {counted(self.fixations, "fixation")}'


def in_firing_order(events: list) -> list:
    """
    Return ``events`` (in arrival order) with those of one frame in the order a frame fires them.

    Events of one frame share their fixations; the recorder takes each topic in its own order.
    """
    out, group = [], []
    for event in list(events) + [None]:
        if group and (event is None or event.fixations != group[0].fixations):
            out += sorted(group, key=lambda e: (EVENTS.index(e.kind), e.person, e.cell or 0))
            group = []
        if event is not None:
            group.append(event)
    return out


def last_decision(events: list) -> Decision:
    """Return the last of ``events`` that decides (:data:`DECISIONS`), or no decision."""
    decided = [e for e in events if e.kind in DECISIONS]
    return decided[-1].decision() if decided else Decision()


@dataclass
class ReplayResult:
    """What the replay did, next to what the recording says."""

    grid: Grid
    recorded_fixations: list
    replay_fixations: list
    recorded: Decision
    replayed: Decision
    frames: int
    applied: int
    first_difference: int | None = None
    stopped_early: bool = False
    lines: list = field(default_factory=list)
    recorded_events: list = field(default_factory=list)
    replay_events: list = field(default_factory=list)
    recorded_people: list = field(default_factory=list)
    replay_people: list = field(default_factory=list)
    changes_applied: int = 0
    # Each recorded change of the controller's parameters with what the replay did with it:
    # 'start' (set before the replayed search: its setting from the start), 'applied' (at its
    # time) or 'after' (after the replay's last frame: not applied).
    changes: list = field(default_factory=list)
    # Why no frame was applied (the most frequent reason, with its count), when none was.
    unused: str = ''

    @property
    def same(self) -> bool:
        """Whether frames were applied and the fixations, events, decisions and people agree."""
        return (self.applied > 0 and self.first_difference is None
                and self.recorded.same(self.replayed)
                and first_other(self.recorded_events, self.replay_events) is None
                and first_other(self.recorded_people, self.replay_people) is None)


def first_other(recorded: list, replayed: list) -> int | None:
    """Return the index of the first event that differs between two lists (None: the same)."""
    for i in range(max(len(recorded), len(replayed))):
        if i >= len(recorded) or i >= len(replayed) or recorded[i].key != replayed[i].key:
            return i
    return None


def settings_from(parameters: dict, overrides: dict | None = None) -> dict:
    """Return the controller's parameters with ``overrides`` (keys of :data:`OVERRIDES`) set."""
    values = dict(parameters)
    for key, value in (overrides or {}).items():
        if value is None:
            continue
        if key not in OVERRIDES:
            raise ValueError(f"cannot override {key!r}; one of {', '.join(OVERRIDES)}")
        values[OVERRIDES[key]] = value
        if key == 'observation':
            values['observation.model'] = 'counts'
        if key == 'policy_file':
            values['policy.name'] = 'learned'
        if key == 'policy' and value != 'learned':
            values['policy.kernel'] = []
    return values


def _with_defaults(values: dict) -> dict:
    return {'policy.kernel': None, 'policy.file': '', 'policy.action': 'argmax', **values}


def _config(values: dict, blame: str) -> ControllerConfig:
    """Build the node's configuration; a refusal is said as ``<blame>: <why>``."""
    try:
        return build_config(_with_defaults(values), build_policy)
    except ValueError as exc:
        raise ValueError(f'{blame}: {exc}') from None


def checked_config(parameters: dict, overrides: dict | None = None) -> ControllerConfig:
    """
    Build the configuration from recorded ``parameters`` with ``overrides``, as the node does.

    The node's own builder (:func:`ipomdp_gaze.search.controller_config.build_config`), so a
    recording replays with every check the node makes (a count model's grid and pan/tilt
    spacing among them), built once with every override. Only when that is refused are the
    recorded parameters built alone, then with each override in turn, so that the refusal
    blames what it comes from: ``the recording: ...`` or the option (``--policy: unknown
    policy 'bogus'``).

    Raises
    ------
    ValueError
        If a parameter is missing or refused (the message names it and who gave it).

    """
    options = {k: v for k, v in (overrides or {}).items() if v is not None}
    try:
        return build_config(_with_defaults(settings_from(parameters, options)), build_policy)
    except ValueError:
        pass                                    # refused: find what to blame
    config = _config(settings_from(parameters), 'the recording')
    given = {}
    for key, value in options.items():
        given[key] = value
        config = _config(settings_from(parameters, given), OPTIONS[key])
    return config


def check_options(bag, overrides: dict | None = None) -> None:
    """
    Refuse an option that the recorded parameters cannot take (ValueError naming the option).

    Against the controller's parameters as recorded at its start, before anything is said of
    the replay (``--policy bogus`` printed the settings line ``with policy=bogus`` first). A
    recording refused on its own, or an option refused only with a change set while
    recording, passes: the replay says its settings and then why it is refused.
    """
    recorded = bag.parameters(CONTROLLER)
    if not recorded or not any(v is not None for v in (overrides or {}).values()):
        return
    try:
        _config(settings_from(recorded), 'the recording')
    except ValueError:
        return
    checked_config(recorded, overrides)


def build_controller(values: dict) -> tuple[GazeController, PanTiltMap]:
    """Build the core and the head mapping from the ``gaze_controller`` parameters ``values``."""
    config = _config(values, 'the recording')
    return config.controller(), config.head


def _parameter_value(value):
    """Return an ``rcl_interfaces/ParameterValue`` as Python (None when not set)."""
    name = VALUE_FIELDS.get(int(value.type))
    if name is None:
        return None
    got = getattr(value, name)
    if name == 'string_array_value':
        return [str(v) for v in got]
    return np.asarray(got).tolist() if int(value.type) >= 5 else got


@dataclass(frozen=True)
class ParameterChange:
    """Parameters of a node set while recording: when (bag time, ns), new and old values."""

    time_ns: int
    values: dict
    before: dict


def node_name(bag, node: str = CONTROLLER) -> str:
    """
    Return the fully qualified name of the ``node`` whose parameters the recorder kept.

    The recorder stores it (``ipomdp_gaze/parameters_node/<node>``: ``/head1/gaze_controller``
    when it recorded in ``/head1``); a bag written before it did asked ``/<node>``.
    """
    name = bag.custom_data.get(f'ipomdp_gaze/parameters_node/{node}')
    return str(name) if name else '/' + node.strip('/')


def parameter_changes(bag, node: str = CONTROLLER) -> list:
    """
    Return the :class:`ParameterChange` of ``node`` recorded on ``/parameter_events``.

    ``/parameter_events`` is global: only the events of the very node the recorder asked for
    its parameters (:func:`node_name`; a ``gaze_controller`` of another namespace is another
    robot's) and only those after it asked (a value set again to what it was is no change), so
    folding them into those gives the parameters at any time of the recording. A change set
    while the recorder asked is already in the parameters it kept: it holds from the start.
    """
    since = int(bag.custom_data.get(f'ipomdp_gaze/parameters_time/{node}') or 0)
    name = node_name(bag, node)
    values = dict(bag.parameters(node))
    out = []
    for m in bag.topic('/parameter_events'):
        if m.time_ns < since or str(m.msg.node) != name:
            continue
        new = {}
        for p in list(m.msg.new_parameters) + list(m.msg.changed_parameters):
            value = _parameter_value(p.value)
            if value is not None and (p.name not in values or values[p.name] != value):
                new[p.name] = value
        if new:
            out.append(ParameterChange(m.time_ns, new, {k: values.get(k) for k in new}))
            values.update(new)
    return out


def values_at(parameters: dict, changes: list, time_ns: int | None) -> dict:
    """Return ``parameters`` with the ``changes`` up to ``time_ns`` set (None: all of them)."""
    values = dict(parameters)
    for change in changes:
        if time_ns is None or change.time_ns <= time_ns:
            values.update(change.values)
    return values


def _short(value) -> str:
    return f'[{len(value)} values]' if isinstance(value, list) and len(value) > 4 else \
        str(value)


# What a replay did with a recorded change (ReplayResult.changes), as the settings line says it.
CHANGE_FATES = {'start': 'before the replayed search (its setting from the start)',
                'applied': 'applied by the replay at its time',
                'after': "after the replay's last frame (not applied)"}


def _changes_text(changes: list, start: int) -> str:
    """Say ``changes`` with their times (s into the recording); one time's go together."""
    at = {}
    for c in changes:
        at.setdefault(f'{(c.time_ns - start) * 1e-9:.1f}', []).extend(
            f'{k} {_short(c.before[k])} -> {_short(v)}' for k, v in sorted(c.values.items()))
    return '; '.join(f"at {t} s {', '.join(parts)}" for t, parts in at.items())


def describe_settings(bag, overrides: dict | None = None, new_search: bool = False,
                      result: ReplayResult | None = None) -> str:
    """
    Say in one line which settings a replay uses: the recorded, the options, the changes.

    A controller whose parameters were set while recording (``/parameter_events``) is not
    replayed with the recorded start values alone: the line names each change and its time
    (seconds into the recording). Given the replay's ``result`` it says what the replay did
    with each: in force from the replayed search's start, applied at its time, or after the
    replay's last frame and not applied (``new_search``: the new search on the last image uses
    the last values). An option holds over a recorded change of a parameter it sets, those it
    sets besides its own among them (``--observation`` sets ``observation.model``).
    """
    given = {k: v for k, v in (overrides or {}).items() if v is not None}
    text = 'settings: recorded' + (', with ' + ', '.join(f'{k}={v}' for k, v in given.items())
                                   if given else '')
    changes = parameter_changes(bag)
    if not changes:
        return text
    start = bag.messages[0].time_ns if bag.messages else 0
    kept = set(settings_from({}, given))
    ignored = sorted(kept & {k for c in changes for k in c.values})
    head = f'{text}; {CONTROLLER} parameters set while recording'
    if new_search:
        said = f', the new search uses the last values: {_changes_text(changes, start)}'
    elif result is None:
        said = f', each in force from its time: {_changes_text(changes, start)}'
    else:
        said = ': ' + '; '.join(
            f'{words}: ' + _changes_text([c for c, f in result.changes if f == fate], start)
            for fate, words in CHANGE_FATES.items() if any(f == fate for _, f in result.changes))
    return head + said + (f" (not {', '.join(ignored)}: the options' values hold)"
                          if ignored else '')


def _seconds(stamp) -> float:
    return float(stamp.sec) + 1e-9 * float(stamp.nanosec)


def _angles(msg, head: PanTiltMap) -> tuple[float, float]:
    names = list(msg.name)
    return tuple(float(msg.position[names.index(j)]) for j in (head.pan_joint, head.tilt_joint))


class StampClock:
    """
    Bag time (the system clock's receipt) on the header stamps' clock.

    Under use_sim_time the nodes stamp with the simulated clock while the recorder writes when
    the middleware received each message (system time). The controller's targets carry both:
    a time of the bag is moved by the difference of the last target received before it (or the
    first), so a header-less frame, a zero stamp and the reset's arrival are on the clock of the
    stamps. Clocks less than :data:`CLOCKS_APART_S` apart are one: the time is kept as it is.
    """

    def __init__(self, bag):
        pairs = sorted((m.time_ns, m.time_ns - int(m.msg.header.stamp.sec) * 10**9
                        - int(m.msg.header.stamp.nanosec)) for m in bag.topic('pan_tilt'))
        apart = pairs and abs(sorted(d for _, d in pairs)[len(pairs) // 2]) >= CLOCKS_APART_S * 1e9
        self.pairs = pairs if apart else []
        self.times = [t for t, _ in self.pairs]

    @property
    def apart(self) -> bool:
        """Whether the stamps are of another clock than the bag's times."""
        return bool(self.pairs)

    def stamp_ns(self, time_ns: int) -> int:
        """Return bag time ``time_ns`` on the stamps' clock (ns)."""
        if not self.pairs:
            return int(time_ns)
        k = bisect.bisect_right(self.times, int(time_ns))     # targets received by then
        return int(time_ns) - self.pairs[max(k - 1, 0)][1]

    def stamp_s(self, time_ns: int) -> float:
        """Return bag time ``time_ns`` on the stamps' clock (s)."""
        return self.stamp_ns(time_ns) * 1e-9


def _frames(bag, grid: Grid, clock: StampClock | None = None) -> list:
    """
    Return ``(stamp_s, arrival_ns, values, kind, offsets, groups)`` of every frame, by arrival.

    A frame without a header (``evidence``) or with a zero stamp is stamped when it arrived,
    on the stamps' clock (``clock``, :class:`StampClock`), as the node stamps it when it takes it.
    ``kind`` is ``'scan'`` for a one-time scan (``header.frame_id`` ``scan/<id>``, design §10.3),
    else ``'fixation'``; ``offsets`` ``(N, 2)`` from a ``32FC3`` or ``32FC4`` evidence image
    (design §12.9), ``groups`` ``(N,)`` from a ``32FC4`` one (design §11.7), else None.
    """
    clock = clock or StampClock(bag)
    frames = []
    for m in bag.topic('evidence_image'):
        msg = m.msg
        if (msg.height, msg.width) != grid.shape:
            raise ValueError(f'{bag.path}: an evidence_image is {msg.height}x{msg.width} '
                             f'(height x width), the recorded grid {grid.rows}x{grid.cols}')
        try:
            values, offsets, groups = decode_evidence(msg.encoding, msg.height, msg.width,
                                                      msg.step, msg.is_bigendian, msg.data)
        except EvidenceError as exc:
            raise ValueError(f'{bag.path}: an evidence_image cannot be read: {exc}') from None
        stamp = _seconds(msg.header.stamp)
        kind = 'scan' if str(msg.header.frame_id).startswith('scan/') else 'fixation'
        frames.append((stamp or clock.stamp_s(m.time_ns), m.time_ns, values, kind, offsets,
                       groups))
    for m in bag.topic('evidence'):
        frames.append((clock.stamp_s(m.time_ns), m.time_ns,
                       np.asarray(m.msg.data, dtype=np.float64), 'fixation', None, None))
    frames.sort(key=lambda f: f[1])
    if not frames:
        raise ValueError(f'{bag.path} has no evidence_image or evidence frame to replay')
    if any(f[2].size != grid.n_cells for f in frames):
        raise ValueError(f'{bag.path}: a frame does not have the {grid.n_cells} cells of the '
                         f'recorded {grid.rows}x{grid.cols} grid')
    return frames


def _has_frames(bag) -> bool:
    """Whether ``bag`` holds a frame of evidence (``evidence_image`` or ``evidence``)."""
    return bool(bag.topic('evidence_image') or bag.topic('evidence'))


def _targets(bag, head: PanTiltMap, heads: tuple = (), frames_ns: tuple = ()) -> tuple:
    """
    Return ``(sent_s, cell)`` of each target the controller sent (re-sends dropped), re-sends.

    ``heads`` are ``(time_ns, PanTiltMap)`` of the head's later settings in time order: a
    target recorded after one is mapped with it (a changed ``pan_offset_rad`` moves the angles
    of the targets sent after it, not of those before). A change that moves the head makes the
    node send its current target again, stamped anew (``_send_target``: frames settle from
    then on); that is no new fixation. The first newly stamped target recorded after such a
    change (from :data:`RESET_TARGET_S` before it: the topics arrive in their own order) and
    before the next frame (``frames_ns``, arrival times), at the cell of the target before, is
    that re-send: dropped, its stamp returned in ``{change time_ns: sent_s}``.
    """
    moved, before = [], head
    for time_ns, later in heads:
        if later != before:
            moved.append((time_ns, later))
        before = later
    frames_ns = sorted(frames_ns)
    seen, out, resent = set(), [], {}
    for m in bag.topic('pan_tilt'):
        key = (m.msg.header.stamp.sec, m.msg.header.stamp.nanosec)
        if key in seen:
            continue
        seen.add(key)
        sent = _seconds(m.msg.header.stamp)
        arrived = bisect.bisect_left(frames_ns, m.time_ns)      # frames before this target
        change = next(((t, later) for t, later in moved if t not in resent
                       and t - RESET_TARGET_S * 1e9 <= m.time_ns
                       and bisect.bisect_left(frames_ns, t) >= arrived), None)  # none since t
        if change is not None and out:
            resent[change[0]] = sent            # the re-send or the first target after it
            if change[1].nearest_cell(*_angles(m.msg, change[1])) == out[-1][1]:
                continue
            del resent[change[0]]
            moved.remove(change)                # a new target: the change made no re-send
        mapping = head
        for time_ns, later in heads:
            if time_ns <= m.time_ns:
                mapping = later
        out.append((sent, mapping.nearest_cell(*_angles(m.msg, mapping))))
    return out, resent


def last_search(bag, head: PanTiltMap, start: int):
    """Return the bag from the controller's last reset on (:func:`search_start`), if any."""
    cut = search_start(bag, head, start)
    if cut is None:
        return bag
    return dataclasses.replace(bag, messages=[m for m in bag.messages if m.time_ns >= cut])


def search_start(bag, head: PanTiltMap, start: int) -> int | None:
    """
    Return when (bag time, ns) the controller's last reset (its ``belief`` at the prior) began.

    A bag may hold several searches (``~/reset`` starts a new one; the demo resets once the
    recorder hears every node): a replay follows the last one. The recorder takes the topics
    in its own order and a busy machine delays some, so the reset is pinned by the target sent
    with it: the latest target at the ``start`` cell stamped at most :data:`RESET_WINDOW_S`
    before the reset belief arrived (and :data:`RESET_TARGET_S` after). A reset of a disabled
    controller sends no target; the search's first target is then the next one.
    """
    grid = head.grid
    cut = _last_reset(bag, grid)
    if cut is None:
        return None
    at = StampClock(bag).stamp_ns(cut)         # the reset's arrival on the stamps' clock
    sent = [m for m in bag.topic('pan_tilt')
            if at - RESET_WINDOW_S * 1e9 <= _seconds(m.msg.header.stamp) * 1e9
            <= at + RESET_TARGET_S * 1e9 and head.nearest_cell(*_angles(m.msg, head)) == start]
    if sent:
        first = max(sent, key=lambda m: _seconds(m.msg.header.stamp))
        stamp = first.msg.header.stamp
        cut = min(cut, min(m.time_ns for m in sent if m.msg.header.stamp == stamp))
    return cut


def _recorded_priors(bag, grid: Grid) -> list:
    """Return each ``belief.prior`` the recording had (recorded or set), as probabilities (N,)."""
    values = [bag.parameters(CONTROLLER)] + [c.values for c in parameter_changes(bag)]
    priors = []
    for v in values:
        try:
            prior = prior_from({'belief.prior': v.get('belief.prior')}, grid)
        except ValueError:
            continue                            # refused by the node: never in force
        if prior is not None:
            priors.append(prior)
    return priors


def _reset_times(bag, grid: Grid | None = None) -> list:
    """
    Return when (bag time, ns) each reset's ``belief`` arrived: uniform, or at a recorded prior.

    A search starts at ``belief.prior`` (times ``1 - absent.prior``) when one is in force, so a
    reset is a belief proportional to a prior of the recording, not only a uniform one.
    """
    priors = [] if grid is None else _recorded_priors(bag, grid)
    out = []
    for m in bag.topic('belief'):
        data = np.asarray(m.msg.data, dtype=float)
        if grid is not None and data.size != grid.n_cells:
            continue
        if is_reset_belief(data, priors):
            out.append(m.time_ns)
    return out


def _last_reset(bag, grid: Grid) -> int | None:
    """Return when (bag time, ns) the controller's last reset ``belief`` arrived, if any."""
    resets = _reset_times(bag, grid)
    return resets[-1] if resets else None


def recorded_events(bag, since_ns: int | None = None) -> tuple[list, list]:
    """
    Return the recorded ``(search events, people's events)``, each in firing order.

    A person's event (a moving many-target search) carries its ``person`` number; the others
    are the search's own. Arrival order; ``since_ns`` (bag time: the arrival of the search's
    first applied frame) drops the events that arrived before it, an earlier search's that
    arrived late, after the cut of :func:`last_search` (they must not count as this one's).
    """
    timed = []
    for kind in EVENTS:
        for m in bag.topic(kind):
            if since_ns is not None and m.time_ns < since_ns:
                continue
            values = {kv.key: kv.value for kv in m.msg.values}
            timed.append((m.time_ns, Event(
                kind, int(values['cell']) if 'cell' in values else None,
                int(values['fixations']),
                float(values['probability']) if 'probability' in values else None,
                int(values.get('person', 0)), answer.reason_of(values.get('ended', '')))))
    events = [e for _, e in sorted(timed, key=lambda te: te[0])]
    return (in_firing_order([e for e in events if not e.person]),
            in_firing_order([e for e in events if e.person]))


def _step_events(step) -> list:
    """Return the events of an applied frame, in firing order (:data:`EVENTS`)."""
    out = []
    for kind in EVENTS:
        event = getattr(step, kind, None)
        if event is not None:
            out.append(Event(kind, getattr(event, 'cell', None), event.fixations,
                             getattr(event, 'probability', None), 0,
                             getattr(event, 'forced_by', '')))
    return out


def _apply_change(core, config: ControllerConfig, parameters: dict, overrides,
                  when: str) -> ControllerConfig:
    """
    Make the core follow changed parameters as the node does (``_apply_config``).

    The node's builder with what changed and the configuration before, followed as the node
    follows it (:func:`~ipomdp_gaze.search.controller_config.follow_config`). A refusal names
    its culprit, the recording or an option, and ``when`` the change was set (``at 12.3 s``).
    """
    values = _with_defaults(settings_from(parameters, overrides))
    changed = {k for k, v in values.items() if config.values.get(k) != v}
    try:
        new = build_config(values, build_policy, changed, config)
    except ValueError as exc:
        said = f'the recording: {exc}'
        try:
            checked_config(parameters, overrides)
        except ValueError as named:
            said = str(named)
        raise ValueError(f'{said} (with the parameters set at {when} of the recording)') \
            from None
    follow_config(core, new, config.values)
    return new


def _events_text(events: list, grid: Grid) -> str:
    return ', '.join(e.describe(grid) for e in events) or 'none'


def _people_text(events: list) -> str:
    if not events:
        return "no person's event"
    counts = ', '.join(f'{k} {sum(e.kind == k for e in events)}' for k in EVENTS
                       if any(e.kind == k for e in events))
    people = len({e.person for e in events})
    return f'{counted(len(events), "event")} of {counted(people, "person", "people")} ({counts})'


def replay(bag, overrides: dict | None = None, out=print) -> ReplayResult:
    """
    Re-run the recorded frames through the controller; print and return where it differs.

    ``bag`` is an :class:`ipomdp_gaze.files.bag.Bag`; ``overrides`` replace recorded settings
    (:data:`OVERRIDES`). Parameters the controller was given while recording
    (:func:`parameter_changes`) are in force from their time: those before the replayed
    search from its start, the later ones from the first frame that arrived after them.
    """
    recorded_values = bag.parameters(CONTROLLER)
    if not recorded_values:
        raise ValueError(f'{bag.path} has no parameters of {CONTROLLER} in its metadata: was '
                         f'it recorded by the recorder node with the controller running?')
    changes = parameter_changes(bag)
    origin = bag.messages[0].time_ns if bag.messages else 0
    grid = grid_from(recorded_values)               # read-only: never set while recording
    # The settings of the replayed search are those in force at its start (its reset), not
    # the last ones: a change after it must not move its start cell or its head.
    reset = _last_reset(bag, grid)
    at = values_at(recorded_values, changes, origin if reset is None else reset)
    config = checked_config(at, overrides)
    # the start cell from a core of its own: a policy's first choice may draw on its random
    # stream, which the replayed core must begin fresh, as the node's did
    cut = search_start(bag, config.head, config.controller().reset(0.0))
    if cut is not None:
        searched = dataclasses.replace(bag, messages=[m for m in bag.messages
                                                      if m.time_ns >= cut])
        if not _has_frames(searched) and _has_frames(bag):
            # a recording stopped as a search began (a room's re-check, a ~/reset)
            raise ValueError(f'{bag.path}: its last search, from the reset at '
                             f'{(cut - origin) * 1e-9:.1f} s of the recording, has no '
                             f'evidence_image or evidence frame to replay (the recording ended '
                             f'as it began); a replay follows the last search of a bag')
        bag = searched
    else:                   # one search: it began with the recording
        cut = origin
    parameters = values_at(recorded_values, changes, cut)
    if parameters != at:
        config = checked_config(parameters, overrides)
    pending = [c for c in changes if c.time_ns > cut]
    core = config.controller()
    grid = core.grid
    clock = StampClock(bag)
    frames = _frames(bag, grid, clock)
    heads = tuple((c.time_ns, head_from(values_at(recorded_values, changes, c.time_ns), grid))
                  for c in pending)
    targets, resent = _targets(bag, config.head, heads, tuple(f[1] for f in frames))
    if not targets:
        raise ValueError(f'{bag.path} has no pan_tilt target of the controller')
    recorded_cells = [cell for _, cell in targets]
    core.reset(targets[0][0])
    replayed_cells = [core.fixation]
    result = ReplayResult(grid, recorded_cells, replayed_cells, Decision(), Decision(),
                          len(frames), 0)
    result.changes = [(c, 'start') for c in changes if c.time_ns <= cut]
    say = result.lines.append
    if core.fixation != recorded_cells[0]:
        result.first_difference = 1
    first_applied, unused = None, {}
    for stamp, arrival, values, kind, offsets, groups in frames:
        if result.first_difference is not None or core.stopped:
            break
        while pending and pending[0].time_ns <= arrival:
            change = pending.pop(0)
            parameters.update(change.values)
            config = _apply_change(core, config, parameters, overrides,
                                   f'{(change.time_ns - origin) * 1e-9:.1f} s')
            if change.time_ns in resent:     # the node sent its target again: settle anew
                core.retarget(resent[change.time_ns])
            result.changes_applied += 1
            result.changes.append((change, 'applied'))
        k = core.fixations
        # The node sent its next target when it took the frame: the recorded send time.
        now = targets[k + 1][0] if k + 1 < len(targets) else clock.stamp_s(arrival)
        if kind == 'scan':          # the one-time scan of this (the only recorded) search
            step = core.offer_scan(values, core.search_id, now)
        else:
            step = core.offer(values, stamp, now, offsets=offsets, groups=groups)
        if not step.applied:
            unused[step.reason or step.status] = unused.get(step.reason or step.status, 0) + 1
            continue
        if first_applied is None:
            first_applied = arrival
        result.applied += 1
        result.replay_events += _step_events(step)
        result.replay_people += in_firing_order([
            Event(e.kind, e.cell, e.fixations, e.probability, e.person)
            for e in step.people])
        if step.fixation is None:
            continue
        replayed_cells.append(step.fixation)
        n = len(replayed_cells)
        if n <= len(recorded_cells) and step.fixation != recorded_cells[n - 1]:
            result.first_difference = n
    result.changes += [(c, 'after') for c in pending]
    if not result.applied and unused:
        why, n = max(unused.items(), key=lambda kv: kv[1])
        result.unused = f'{n} {why}' + (' (the clocks of the stamps and of the recording differ)'
                                        if clock.apart else '')
    # The recorded events from this search's first applied frame on (a late one of the search
    # before arrives after the cut but before that frame).
    since = first_applied if first_applied is not None else frames[0][1]
    result.recorded_events, result.recorded_people = recorded_events(bag, since)
    result.recorded = last_decision(result.recorded_events)
    result.replayed = last_decision(result.replay_events)
    if result.first_difference is not None:
        n = result.first_difference
        rec = grid.cell(recorded_cells[n - 1]) if n <= len(recorded_cells) else None
        say(f'fixation {n} differs: recorded {rec}, replay {grid.cell(replayed_cells[n - 1])}; '
            f'the recorded frames after it were taken elsewhere, so the replay stops here')
        result.stopped_early = True
    if core.follows_people or result.recorded_people:
        _say_people(result, say)
    else:
        _say_decisions(result, say)
    for line in result.lines:
        out(line)
    return result


def _decision_text(decision: Decision, last: str, grid: Grid) -> str:
    """Say a decision after ``last`` ('the last decision '), or 'no decision' alone."""
    return f'{last}{decision.describe(grid)}' if decision.kind else decision.describe(grid)


def _difference_text(i: int, recorded: list, replayed: list, grid: Grid) -> str:
    """Say the ``i``-th events of both lists: ``event 2 is X recorded, Y in the replay``."""
    rec = recorded[i].describe(grid) if i < len(recorded) else 'none'
    rep = replayed[i].describe(grid) if i < len(replayed) else 'none'
    return f'event {i + 1} is {rec} recorded, {rep} in the replay'


def _say_decisions(result: ReplayResult, say) -> None:
    """Say the events (when a search had more than one) and the last decisions, compared."""
    grid = result.grid
    several = max(len(result.recorded_events), len(result.replay_events)) > 1
    last = 'the last decision ' if several else ''
    if several:
        say(f'recorded events: {_events_text(result.recorded_events, grid)}')
        say(f'replay events:   {_events_text(result.replay_events, grid)}')
    say(f'recorded: {_decision_text(result.recorded, last, grid)}')
    say(f'replay:   {_decision_text(result.replayed, last, grid)}')
    if result.first_difference is not None or _said_none_applied(result, say):
        return
    if not result.recorded.same(result.replayed):
        say('the same fixations, another last decision' if several else
            'the same fixations, another decision')
    elif first_other(result.recorded_events, result.replay_events) is not None:
        say('the same fixations and the same last decision, other events before it')
    else:
        say('the same fixations, the same events and the same last decision' if several else
            'the same fixations and the same decision')


def _said_none_applied(result: ReplayResult, say) -> bool:
    """Say that nothing was compared when the replay applied no frame, and why; whether so."""
    if result.applied:
        return False
    say(f'nothing compared: the replay applied none of the {result.frames} recorded frames'
        + (f' ({result.unused})' if result.unused else ''))
    return True


def _say_people(result: ReplayResult, say) -> None:
    """Say the people's events of a moving many-target search, compared person by person."""
    grid = result.grid
    say('following many people: the replay compares their events (found, lost, reacquired '
        'per person), not one decision')
    say(f'recorded: {_people_text(result.recorded_people)}')
    say(f'replay:   {_people_text(result.replay_people)}')
    search = result.recorded_events or result.replay_events
    if search:              # the search's own events (gave_up, say) are compared too
        say(f'recorded search events: {_events_text(result.recorded_events, grid)}')
        say(f'replay search events:   {_events_text(result.replay_events, grid)}')
    if result.first_difference is not None or _said_none_applied(result, say):
        return
    i = first_other(result.recorded_people, result.replay_people)
    j = first_other(result.recorded_events, result.replay_events)
    if i is None:
        text = "the same fixations and the same people's events"
    else:
        text = ("the same fixations, other people's events: "
                + _difference_text(i, result.recorded_people, result.replay_people, grid))
    if j is not None:
        text += (', other search events: ' if i is None else '; other search events: ') + \
            _difference_text(j, result.recorded_events, result.replay_events, grid)
    elif search and i is None:
        text += ' and search events'
    say(text)


def _search_frames(bag) -> list:
    """Return the arrival times (ns) of the last search's frames, sorted."""
    parameters = bag.parameters(CONTROLLER)
    resets = _reset_times(bag, grid_from(parameters) if 'grid.rows' in parameters else None)
    since = resets[-1] if resets else 0          # the last search (see last_search)
    return sorted(m.time_ns for topic in ('evidence_image', 'evidence')
                  for m in bag.topic(topic) if m.time_ns >= since)


def search_rate(bag) -> tuple[float, float]:
    """
    Return ``(seconds, MB per minute)`` of the search: the bag's growth while frames came.

    The search (the bag's last) spans its recorded frames, from one mean frame interval before
    the first to the last; the bytes of the messages recorded in it are scaled by the file's
    compression.
    """
    frames = _search_frames(bag)
    raw = sum(m.size for m in bag.messages)
    if len(frames) < 2 or raw == 0:
        return 0.0, math.nan
    start = frames[0] - (frames[-1] - frames[0]) / (len(frames) - 1)
    inside = sum(m.size for m in bag.messages if start <= m.time_ns <= frames[-1])
    seconds = (frames[-1] - start) * 1e-9
    return seconds, inside * bag.size_bytes / raw / 1e6 / (seconds / 60.0)


def describe_size(bag) -> str:
    """
    Say how large the bag is and how fast it grows per minute of search.

    The rate is extrapolated only from at least :data:`MIN_RATE_S` seconds and
    :data:`MIN_RATE_FRAMES` frames; a shorter search says so instead (0.6 s of frames once gave
    749.1 MB per minute) and gives the size per minute of the whole recording.
    """
    seconds, per_minute = search_rate(bag)
    frames = _search_frames(bag)
    if len(frames) < 2:
        rate = 'fewer than two frames'
    elif seconds < MIN_RATE_S or len(frames) < MIN_RATE_FRAMES:
        rate = (f'{counted(len(frames), "frame")} over {seconds:.1f} s: too short a search to '
                f'extrapolate MB per minute of search (at least {MIN_RATE_FRAMES} frames over '
                f'{MIN_RATE_S:g} s); {bag.megabytes_per_minute:.1f} MB per minute of '
                f'recording')
    else:
        rate = f'{per_minute:.1f} MB per minute of search (over {seconds:.1f} s of frames)'
    return f'{bag.size_bytes / 1e6:.2f} MB, {bag.duration_s:.1f} s recorded; {rate}'


def _last_image(bag) -> np.ndarray:
    """Return the last recorded camera image as grey ``(H, W)`` or RGB ``(H, W, 3)`` uint8."""
    msgs = bag.topic('image')
    if not msgs:
        raise ValueError(f'{bag.path} has no camera image to search')
    msg = msgs[-1].msg
    channels = IMAGE_CHANNELS.get(msg.encoding)
    if channels is None:
        raise ValueError(f'the recorded image is {msg.encoding!r}; expected mono8, rgb8 or bgr8')
    data = np.asarray(msg.data, dtype=np.uint8).reshape(msg.height, msg.step)
    pixels = data[:, :msg.width * channels].reshape(msg.height, msg.width, channels)
    if msg.encoding == 'bgr8':
        pixels = pixels[:, :, ::-1]
    return np.ascontiguousarray(pixels[:, :, 0] if channels == 1 else pixels)


def _why_no_scene(bag, detector: dict) -> str:
    """Say why a recording that is not of a fixed camera holds no whole scene to search."""
    if detector.get('mode'):
        return (f"this one's detector was in {detector['mode']} mode: a camera on the head "
                'only recorded the views it took')
    images = 'no camera image' if not bag.topic('image') else 'camera images'
    return (f'this one has no parameters of {DETECTOR} and {images}: its evidence came '
            'without a detector node (a simulated camera, say), so it holds no scene to search')


def new_search(bag, overrides: dict | None = None, out=print):
    """
    Run a whole new search on the last recorded image of a fixed camera (``fovea`` mode).

    The fovea and detector are the recorded detector's; the count model, policy, confidence,
    budget and inhibition of return the controller's, with ``overrides``. Returns the
    :class:`ipomdp_gaze.vision.search.ImageSearch`.

    Raises
    ------
    ValueError
        If the recording is not of a fixed camera or holds no image.

    """
    from ipomdp_gaze.vision.detection import build_setup
    from ipomdp_gaze.vision.search import search_image
    detector = bag.parameters(DETECTOR)
    if detector.get('mode') != 'fovea':
        raise ValueError('a new search needs a recording of a fixed camera (the detector in '
                         f'fovea mode): {_why_no_scene(bag, detector)}')
    parameters = values_at(bag.parameters(CONTROLLER), parameter_changes(bag), None)
    config = checked_config(parameters, overrides)
    if config.policy is None:       # kept unused by many targets; this search is one target's
        raise ValueError(f"policy.name {config.values['policy.name']}: {config.policy_error}")
    core, values = config.controller(), config.values
    given = {k: v for k, v in (('cascade', detector.get('detector.cascade')),
                               ('scale_factor', detector.get('detector.scale_factor', 0) or None),
                               ('min_neighbors', detector.get('detector.min_neighbors', -1)))
             if v not in (None, '', -1)}
    setup = build_setup('fovea', detector.get('observation.file', ''),
                        (detector.get('grid.rows', 0), detector.get('grid.cols', 0),
                         detector.get('grid.spacing_deg', 0.0)), given,
                        detector.get('detector.cascade_dir') or None,
                        unused_cascade_dir='ignore')     # as the recorded node did before 0.3.9
    settings = core.settings
    if not settings.max_fixations:        # the demo's budget: a still image needs an end
        settings = dataclasses.replace(settings, max_fixations=4 * core.grid.n_cells)
    result = search_image(_last_image(bag), setup.fovea, core.observation, core.policy,
                          settings, rng=np.random.default_rng(int(values.get('seed', 0))),
                          prior=config.prior)       # belief.prior: as the recorded search
    cell = setup.fovea.grid.index(*result.cell) if result.decision != 'absent' else None
    decision = Decision(result.decision, cell, result.answer_probability, result.fixations,
                        result.stop if answer.forced(result.decision, result.stop) else '')
    if result.decision == 'gave_up':
        out(f'new search on the recorded image: gave up at '
            f'{answer.limit_text(result.stop, result.limit_cause)}; most likely {result.cell} '
            f'p={result.probability:.3f} after {counted(result.fixations, "fixation")}')
    else:
        out(f'new search on the recorded image: {decision.describe(setup.fovea.grid)}')
    return result
