# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The room after a many-target search: who was found, who is new, and whom to look at next.

The ``gaze_controller`` node in many-target mode (``search.targets: many``, docs/design.md
section 11.6) runs a search of the room; when it ends, :meth:`RoomWatch.done` takes its faces
(:meth:`ipomdp_gaze.search.many.OccupancySession.faces`) as the people in the room, and the node
then keeps them in view in turn: :meth:`RoomWatch.next_person` names the next one each
``room.dwell_s`` seconds, in rounds in which each person gets one turn. A periodic re-check
(``room.recheck_period_s``) is a new search of the room; its people replace the list, and those
farther than :data:`SAME_PERSON_CELLS` from every person known before are counted as new. The
round goes on across a re-check: the people found again who had their turn in it wait for the
others (new people included), so a re-check period shorter than a round starves nobody. A tick
of the dwell timer at the moment the re-check starts is no turn (:meth:`RoomWatch.dwell_tick`):
the head then gets one command, the search's. A clock set back restarts the turns and the
re-check at the new now (:meth:`RoomWatch.restart_turns`). ``~/reset`` forgets everyone
(:meth:`RoomWatch.forget`).

Pure: no ROS, no clock (the node owns the timers); times are seconds.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from ipomdp_gaze.model.wording import counted

# A person found again within this many cells (Chebyshev) of a known one is that person (the
# rooms' scoring tolerance, docs/design.md section 11.5).
SAME_PERSON_CELLS = 1
# Occupied cells within this many cells (Chebyshev) are one person, by the node's
# observation.model: a face's detection counts spill into the cells round it (the rooms' link,
# docs/design.md section 11.3), while the Gaussian model's evidence of a target lies in its own
# cell only, so there each occupied cell is one person.
PERSON_LINK = {'counts': 2, 'gaussian': 0}
# Longest dwell and re-check period accepted, in seconds (one day).
MAX_PERIOD_S = 86400.0
# Timer ticks this close are one moment (rclpy timers count whole nanoseconds: three ticks of
# 1/3 s end 1 ns before one of 1 s).
SAME_MOMENT_S = 1e-6


def people_text(count: int) -> str:
    """Return ``'1 person'`` or ``'<count> people'``, for logs and events."""
    return counted(count, 'person', 'people')


def check_room_times(dwell_s: float, recheck_period_s: float) -> tuple[float, float]:
    """
    Return ``(dwell_s, recheck_period_s)`` as floats.

    Raises
    ------
    ValueError
        Unless ``dwell_s`` is finite and in (0, 1 day] and ``recheck_period_s`` is 0 (never) or
        at least ``dwell_s`` and at most a day.

    """
    dwell_s, recheck_period_s = float(dwell_s), float(recheck_period_s)
    if not math.isfinite(dwell_s) or not 0 < dwell_s <= MAX_PERIOD_S:
        raise ValueError(f'room.dwell_s must be in (0, {MAX_PERIOD_S:g}] seconds, got {dwell_s}')
    if not math.isfinite(recheck_period_s) or not (
            recheck_period_s == 0 or dwell_s <= recheck_period_s <= MAX_PERIOD_S):
        raise ValueError(f'room.recheck_period_s must be 0 (never) or in [room.dwell_s, '
                         f'{MAX_PERIOD_S:g}] seconds, got {recheck_period_s} with room.dwell_s '
                         f'{dwell_s}')
    return dwell_s, recheck_period_s


def check_frame_id(frame_id: str) -> str:
    """
    Return ``room.frame_id``, a frame tf2 can look up.

    Raises
    ------
    ValueError
        If it is empty, has spaces round it (then it names no frame) or starts with ``/`` (tf2
        refuses such a frame id in every lookup).

    """
    if not frame_id.strip():
        raise ValueError('room.frame_id must name the frame of ~/targets (a TF frame), '
                         'got an empty string')
    if frame_id != frame_id.strip() or frame_id.startswith('/'):
        raise ValueError(f'room.frame_id must name the frame of ~/targets (a TF frame), got '
                         f"{frame_id!r}: tf2 frame ids have no leading '/' and no spaces round "
                         'them')
    return frame_id


@dataclass(frozen=True)
class Person:
    """One person found: the cell of the face and ``P(at least one of its cells is occupied)``."""

    cell: int
    probability: float


@dataclass(frozen=True)
class RoomDone:
    """What a finished search of the room says: everyone found, and who of them is new."""

    people: tuple
    new: tuple
    recheck: bool


def people_from_faces(faces) -> tuple:
    """Return :class:`Person` of each face dict (``cell``, ``probability``), in their order."""
    return tuple(Person(int(f['cell']), float(f['probability'])) for f in faces)


def new_people(known, found, grid, radius: int = SAME_PERSON_CELLS) -> tuple:
    """Return the people of ``found`` farther than ``radius`` cells from every one of ``known``."""
    out = []
    for person in found:
        row, col = grid.cell(person.cell)
        if all(max(abs(row - r), abs(col - c)) > radius
               for r, c in (grid.cell(k.cell) for k in known)):
            out.append(person)
    return tuple(out)


def found_again(known, found, grid, radius: int = SAME_PERSON_CELLS) -> frozenset:
    """
    Return the indices in ``found`` of the people of ``known`` found again.

    Each of ``known``, in its order, is the nearest (Chebyshev; ties: the first) of ``found``
    within ``radius`` cells not taken by one before it: one person found again per known one,
    even when two people stand within ``radius`` of each other.
    """
    taken = set()
    for person in known:
        row, col = grid.cell(person.cell)
        near = [(max(abs(row - r), abs(col - c)), j)
                for j, (r, c) in enumerate(grid.cell(p.cell) for p in found)
                if j not in taken]
        near = [(d, j) for d, j in near if d <= radius]
        if near:
            taken.add(min(near)[1])
    return frozenset(taken)


class RoomWatch:
    """The people of the room and the turn of looking at them (module docstring)."""

    def __init__(self, grid):
        self.grid = grid
        self.people: tuple = ()
        self.looked = frozenset()           # indices of the people who had their turn this round
        self.rechecking = False
        self.rooms_done = 0
        self._start_s, self._dwell_s, self._recheck_period_s = 0.0, 1.0, 0.0

    def recheck(self) -> None:
        """Start a re-check: a new search whose people are compared with those known."""
        self.rechecking = True

    def forget(self) -> None:
        """Forget everyone (``~/reset``): the next search's people are all new."""
        self.people, self.looked, self.rechecking = (), frozenset(), False

    def done(self, faces) -> RoomDone:
        """
        Take a finished search's faces as the people in the room; return who is new.

        The people are most probable first (ties in the search's order), as ``~/targets``
        documents: a pass lists its grouped detections before the belief's faces. After a
        re-check the round goes on: those found again who had their turn in it wait for the rest.
        """
        found = tuple(sorted(people_from_faces(faces), key=lambda p: -p.probability))
        new = new_people(self.people, found, self.grid)
        result = RoomDone(found, new, self.rechecking)
        looked = frozenset()
        if self.rechecking:
            looked = found_again([self.people[i] for i in sorted(self.looked)], found, self.grid)
        self.people, self.looked, self.rechecking = found, looked, False
        self.rooms_done += 1
        return result

    def next_person(self) -> Person | None:
        """
        Return the next person to keep in view: the first in the list without a turn this round.

        When everyone has had a turn a new round begins, with the first; so without re-checks
        the people come in the order found, round and round.
        """
        if not self.people:
            return None
        waiting = [i for i in range(len(self.people)) if i not in self.looked]
        if not waiting:
            self.looked, waiting = frozenset(), [0]
        self.looked |= {waiting[0]}
        return self.people[waiting[0]]

    def start_turns(self, now_s: float, dwell_s: float, recheck_period_s: float) -> None:
        """Start counting the dwell and re-check timers' ticks from ``now_s`` (period 0: none)."""
        self._start_s, self._dwell_s, self._recheck_period_s = now_s, dwell_s, recheck_period_s

    def restart_turns(self, now_s: float) -> None:
        """
        Count the dwell and re-check timers' ticks from ``now_s`` (their periods unchanged).

        For a clock set back (a simulator's reset, ``ros2 bag play --loop``): the node restarts
        both timers at the new now, and their ticks are then counted from there, not from an
        origin in the future (before it every tick was a turn, a re-check's moment too).
        """
        self._start_s = now_s

    def dwell_tick(self, now_s: float) -> bool:
        """
        Return whether the dwell timer's call at ``now_s`` is a person's turn.

        The tick is the last of the timer's (``k * dwell_s`` after the start; a timer called
        late skips the ticks it missed). It is no turn when the re-check timer ticks at that
        moment (``k * dwell_s`` a multiple of ``recheck_period_s``): the re-check takes
        precedence, so the head gets one command, the search's first pose, not a person's and
        that pose at once.
        """
        k = math.floor((now_s - self._start_s + SAME_MOMENT_S) / self._dwell_s)
        at_s, period_s = k * self._dwell_s, self._recheck_period_s
        if period_s <= 0:
            return True
        rechecks = round(at_s / period_s)
        return rechecks < 1 or abs(at_s - rechecks * period_s) > SAME_MOMENT_S
