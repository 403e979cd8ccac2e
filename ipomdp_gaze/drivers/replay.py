# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Replay a recorded search: its frames through the controller's core, with its settings or others.

A bag written by the ``recorder`` node (:mod:`ipomdp_gaze.files.bag`) holds the frames of evidence
the
controller was offered (``evidence_image``, stamped, or ``evidence``), the targets it sent
(``pan_tilt``, one stamp per target), its events (``found``, ``absent``, ``gave_up``) and its
parameters. :func:`replay` builds a :class:`ipomdp_gaze.search.gaze.GazeController` from those
parameters, with any of them replaced (``overrides``: another observation model, policy,
confidence ...), drives it with ``reset`` and ``offer(evidence, stamp_s, now_s)`` exactly as the
node did (``now_s``: when the node sent the next target) and compares each decision with the
recording: every next fixation and the final event.

The frames were taken where the *recorded* search looked. A replay that chooses another fixation
would need a frame from a view nobody took, so it stops at the first fixation that differs and
says so; up to there every decision is compared. A fixed camera (the detector's ``fovea`` mode)
records the whole scene, so :func:`new_search` can instead run a whole new search on the last
recorded image, with the detector's recorded count model and fovea and the (overridden)
controller settings. No rclpy here: messages come from ``rosbags``.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
import math

from ipomdp_gaze.files.evidence_bytes import decode_evidence
from ipomdp_gaze.model.belief import EvidenceError
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.policies.registry import build_policy
from ipomdp_gaze.search import answer
from ipomdp_gaze.search.controller_config import build_config
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
# The bag's growth per minute of search is extrapolated from at least this many seconds and
# frames (a face demo's search: 3-10 frames over 2.5-10 s).
MIN_RATE_S, MIN_RATE_FRAMES = 2.0, 3
# What ``replay`` may change, and the controller parameter each one sets.
OVERRIDES = {'observation': 'observation.file', 'policy': 'policy.name',
             'policy_file': 'policy.file', 'confidence': 'confidence',
             'max_fixations': 'search.max_fixations', 'repeat_weight': 'search.repeat_weight',
             'inhibit_return': 'search.inhibit_return'}


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
                f'{self.fixations} fixations')

    def same(self, other: Decision) -> bool:
        """Whether both are the same decision (kind, cell and fixations)."""
        return (self.kind, self.cell, self.fixations) == (other.kind, other.cell, other.fixations)


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

    @property
    def same(self) -> bool:
        """Whether every compared fixation and the final decision agree."""
        return self.first_difference is None and self.recorded.same(self.replayed)


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


def build_controller(values: dict) -> tuple[GazeController, PanTiltMap]:
    """
    Build the core and the head mapping from the ``gaze_controller`` parameters, as the node does.

    The node's own builder (:func:`ipomdp_gaze.search.controller_config.build_config`), so a
    recording
    replays with every check the node makes (a count model's grid and pan/tilt spacing among
    them).

    Raises
    ------
    ValueError
        If a parameter is missing or refused (the message names it).

    """
    values = {'policy.kernel': None, 'policy.file': '', 'policy.action': 'argmax', **values}
    try:
        config = build_config(values, build_policy)
    except ValueError as exc:
        raise ValueError(f'the recording: {exc}') from None
    return config.controller(), config.head


def _seconds(stamp) -> float:
    return float(stamp.sec) + 1e-9 * float(stamp.nanosec)


def _angles(msg, head: PanTiltMap) -> tuple[float, float]:
    names = list(msg.name)
    return tuple(float(msg.position[names.index(j)]) for j in (head.pan_joint, head.tilt_joint))


def _frames(bag, grid: Grid) -> list:
    """
    Return ``(stamp_s, arrival_s, values, kind, offsets, groups)`` of every frame, by arrival.

    ``kind`` is ``'scan'`` for a one-time scan (``header.frame_id`` ``scan/<id>``, design §10.3),
    else ``'fixation'``; ``offsets`` ``(N, 2)`` from a ``32FC3`` or ``32FC4`` evidence image
    (design §12.9), ``groups`` ``(N,)`` from a ``32FC4`` one (design §11.7), else None.
    """
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
        frames.append((stamp or m.time_ns * 1e-9, m.time_ns * 1e-9, values, kind, offsets,
                       groups))
    for m in bag.topic('evidence'):
        frames.append((m.time_ns * 1e-9, m.time_ns * 1e-9,
                       np.asarray(m.msg.data, dtype=np.float64), 'fixation', None, None))
    frames.sort(key=lambda f: f[1])
    if not frames:
        raise ValueError(f'{bag.path} has no evidence_image or evidence frame to replay')
    if any(f[2].size != grid.n_cells for f in frames):
        raise ValueError(f'{bag.path}: a frame does not have the {grid.n_cells} cells of the '
                         f'recorded {grid.rows}x{grid.cols} grid')
    return frames


def _targets(bag, head: PanTiltMap) -> list:
    """Return ``(sent_s, cell)`` of each target the controller sent (re-sends dropped)."""
    seen, out = set(), []
    for m in bag.topic('pan_tilt'):
        key = (m.msg.header.stamp.sec, m.msg.header.stamp.nanosec)
        if key in seen:
            continue
        seen.add(key)
        out.append((_seconds(m.msg.header.stamp), head.nearest_cell(*_angles(m.msg, head))))
    return out


def last_search(bag, head: PanTiltMap, start: int):
    """
    Return the bag from the controller's last reset on (its uniform ``belief``), if any.

    A bag may hold several searches (``~/reset`` starts a new one; the demo resets once the
    recorder hears every node): a replay follows the last one. The recorder takes the topics
    in its own order and a busy machine delays some, so the reset is pinned by the target sent
    with it: the latest target at the ``start`` cell stamped at most :data:`RESET_WINDOW_S`
    before the reset belief arrived (and :data:`RESET_TARGET_S` after). A reset of a disabled
    controller sends no target; the search's first target is then the next one.
    """
    grid = head.grid
    resets = [m.time_ns for m in bag.topic('belief')
              if np.size(m.msg.data) == grid.n_cells and np.ptp(np.asarray(m.msg.data)) == 0]
    if not resets:
        return bag
    cut = resets[-1]
    sent = [m for m in bag.topic('pan_tilt')
            if cut - RESET_WINDOW_S * 1e9 <= _seconds(m.msg.header.stamp) * 1e9
            <= cut + RESET_TARGET_S * 1e9 and head.nearest_cell(*_angles(m.msg, head)) == start]
    if sent:
        first = max(sent, key=lambda m: _seconds(m.msg.header.stamp))
        stamp = first.msg.header.stamp
        cut = min(cut, min(m.time_ns for m in sent if m.msg.header.stamp == stamp))
    return dataclasses.replace(bag, messages=[m for m in bag.messages if m.time_ns >= cut])


def _recorded_decision(bag) -> Decision:
    for kind in ('found', 'absent', 'gave_up'):
        events = bag.topic(kind)
        if events:                  # the last: one of an earlier search may arrive late
            values = {kv.key: kv.value for kv in events[-1].msg.values}
            cell = int(values['cell']) if 'cell' in values else None
            p = float(values['probability']) if 'probability' in values else None
            forced = answer.reason_of(values.get('ended', ''))
            return Decision(kind, cell, p, int(values['fixations']), forced)
    return Decision()


def replay(bag, overrides: dict | None = None, out=print) -> ReplayResult:
    """
    Re-run the recorded frames through the controller; print and return where decisions differ.

    ``bag`` is an :class:`ipomdp_gaze.files.bag.Bag`; ``overrides`` replace recorded settings
    (:data:`OVERRIDES`).
    """
    recorded_values = bag.parameters(CONTROLLER)
    if not recorded_values:
        raise ValueError(f'{bag.path} has no parameters of {CONTROLLER} in its metadata: was '
                         f'it recorded by the recorder node with the controller running?')
    core, head = build_controller(settings_from(recorded_values, overrides))
    grid = core.grid
    bag = last_search(bag, head, core.reset(0.0))
    frames = _frames(bag, grid)
    targets = _targets(bag, head)
    if not targets:
        raise ValueError(f'{bag.path} has no pan_tilt target of the controller')
    recorded = _recorded_decision(bag)
    recorded_cells = [cell for _, cell in targets]
    core.reset(targets[0][0])
    replayed_cells = [core.fixation]
    result = ReplayResult(grid, recorded_cells, replayed_cells, recorded, Decision(),
                          len(frames), 0)
    say = result.lines.append
    if core.fixation != recorded_cells[0]:
        result.first_difference = 1
    for stamp, arrival, values, kind, offsets, groups in frames:
        if result.first_difference is not None or core.stopped:
            break
        k = core.fixations
        # The node sent its next target when it took the frame: the recorded send time.
        now = targets[k + 1][0] if k + 1 < len(targets) else arrival
        if kind == 'scan':          # the one-time scan of this (the only recorded) search
            step = core.offer_scan(values, core.search_id, now)
        else:
            step = core.offer(values, stamp, now, offsets=offsets, groups=groups)
        if not step.applied:
            continue
        result.applied += 1
        event = step.found or step.absent or step.gave_up
        if event is not None:
            kind = 'found' if step.found else 'absent' if step.absent else 'gave_up'
            result.replayed = Decision(kind, getattr(event, 'cell', None),
                                       getattr(event, 'probability', None), event.fixations,
                                       getattr(event, 'forced_by', ''))
        if step.fixation is None:
            continue
        replayed_cells.append(step.fixation)
        n = len(replayed_cells)
        if n <= len(recorded_cells) and step.fixation != recorded_cells[n - 1]:
            result.first_difference = n
    if result.first_difference is not None:
        n = result.first_difference
        rec = grid.cell(recorded_cells[n - 1]) if n <= len(recorded_cells) else None
        say(f'fixation {n} differs: recorded {rec}, replay {grid.cell(replayed_cells[n - 1])}; '
            f'the recorded frames after it were taken elsewhere, so the replay stops here')
        result.stopped_early = True
    say(f'recorded: {recorded.describe(grid)}')
    say(f'replay:   {result.replayed.describe(grid)}')
    if result.first_difference is None:
        say('the same fixations and the same decision' if result.same else
            'the same fixations, another decision')
    for line in result.lines:
        out(line)
    return result


def _search_frames(bag) -> list:
    """Return the arrival times (ns) of the last search's frames, sorted."""
    resets = [m.time_ns for m in bag.topic('belief') if np.ptp(np.asarray(m.msg.data)) == 0]
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
        rate = (f'{len(frames)} frames over {seconds:.1f} s: too short a search to '
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
                         'fovea mode): a camera on the head only recorded the views it took')
    values = settings_from(bag.parameters(CONTROLLER), overrides)
    core, _ = build_controller(values)
    given = {k: v for k, v in (('cascade', detector.get('detector.cascade')),
                               ('scale_factor', detector.get('detector.scale_factor', 0) or None),
                               ('min_neighbors', detector.get('detector.min_neighbors', -1)))
             if v not in (None, '', -1)}
    setup = build_setup('fovea', detector.get('observation.file', ''),
                        (detector.get('grid.rows', 0), detector.get('grid.cols', 0),
                         detector.get('grid.spacing_deg', 0.0)), given,
                        detector.get('detector.cascade_dir') or None)
    settings = core.settings
    if not settings.max_fixations:        # the demo's budget: a still image needs an end
        settings = dataclasses.replace(settings, max_fixations=4 * core.grid.n_cells)
    result = search_image(_last_image(bag), setup.fovea, core.observation, core.policy,
                          settings, rng=np.random.default_rng(int(values.get('seed', 0))))
    cell = setup.fovea.grid.index(*result.cell) if result.decision != 'absent' else None
    decision = Decision(result.decision, cell, result.answer_probability, result.fixations,
                        result.stop if answer.forced(result.decision, result.stop) else '')
    if result.decision == 'gave_up':
        out(f'new search on the recorded image: gave up at '
            f'{answer.LIMITS.get(result.stop, result.stop)}; most likely {result.cell} '
            f'p={result.probability:.3f} after {result.fixations} fixations')
    else:
        out(f'new search on the recorded image: {decision.describe(setup.fovea.grid)}')
    return result
