# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Pan/tilt scenes where the face walks (docs/design.md section 12.1).

A walk scene is the still pan/tilt scene of the same seed (:class:`PanTiltSceneSet`, one face,
the same split, background crop, face, size and start) with the face moving along a path in
the panorama over ``duration_s`` seconds. The path (:class:`Walk`) is straight segments at a
constant ``speed_deg_s`` between waypoints drawn uniformly in the grid's reach, with pauses
(probability :data:`PAUSE_PROB` per leg, :data:`PAUSE_S` long) and, once per walk, an excursion
out of the head's reach: the face walks past the nearest edge of the panorama (no view can
see it), stays out :data:`AWAY_S` seconds and walks back in to a new waypoint. Speed 0 is the
still scene: the face never moves and never leaves.

Each frame is drawn at the time of the camera's clock: :meth:`WalkScene.image_at` pastes the face
at its position at that time into the background (clipped at the panorama's edges), and
:meth:`WalkScene.truth_at` says where it is (cell, or None out of reach). The draws of scene
``i`` come from their own stream ``default_rng([tag, split, seed, i])``, apart from the still
scene's, so a still scene is bit for bit the one the still evaluation searches.

**Several people** (``faces`` K >= 2, docs/design.md section 12.10): the still room of K faces
of the same seed (:class:`PanTiltSceneSet` ``faces=K``, whose first face is the one-face
scene's), each face walking its own path; face 0 draws from the one-face stream, face ``j``
from ``default_rng([tag, split, seed, i, j])``. :meth:`WalkScene.truths_at` says where each is.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import textwrap

import cv2
from ipomdp_gaze.files.writable import write_figure
from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry
from ipomdp_gaze.vision.scenes import DEFAULT_FEATHER, feather_mask, load_faces
import numpy as np

# Characters of a line of plot_walk's title at its 10 pt on the 8-inch figure (about 115 fit).
TITLE_CHARS = 90

# What a walk is made of: the chance a leg is a pause, how long pauses and the excursion out of
# reach last (s, uniform), when the excursion starts (fraction of the walk, uniform), and how far
# past the panorama's edge the face goes (face sides).
PAUSE_PROB = 0.3
PAUSE_S = (0.5, 2.0)
AWAY_S = (2.0, 4.0)
LEAVE_AT = (0.15, 0.3)
OUTSIDE_SIDES = 1.0
MAX_SPEED_DEG_S = 20.0
# the walking speed of evaluate --motion walk when none is given
SPEED_DEG_S = 5.0
DURATION_S = 30.0
_STREAM_TAG = 0x3A1C
_SPLIT_CODE = {'train': 0, 'test': 1}


@dataclass(frozen=True)
class Walk:
    """A face centre's path: knots ``(t_s, x_px, y_px)``, straight lines between them."""

    times_s: np.ndarray
    points_px: np.ndarray

    def position_px(self, t_s) -> np.ndarray:
        """Return the face centre ``(x, y)`` at ``t_s`` (scalar: (2,); array: (T, 2))."""
        t = np.asarray(t_s, dtype=float)
        x = np.interp(t, self.times_s, self.points_px[:, 0])
        y = np.interp(t, self.times_s, self.points_px[:, 1])
        return np.stack([x, y], axis=-1)

    @property
    def duration_s(self) -> float:
        """Return the time of the last knot."""
        return float(self.times_s[-1])


def draw_walk(rng: np.random.Generator, geometry: SceneGeometry, start_px, side_px: int,
              speed_deg_s: float, duration_s: float, leave: bool = True) -> Walk:
    """
    Draw a walk from ``start_px`` (module docstring): legs, pauses and one excursion.

    The draws per leg: whether it pauses (and how long), else a waypoint ``(u_x, u_y)`` in the
    grid's reach; the excursion's start, length and side come first. Speed 0: the face stays.
    """
    speed = check_speed(speed_deg_s)
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ValueError(f'duration_s must be > 0, got {duration_s!r}')
    start = np.asarray(start_px, dtype=float)
    leave_at = duration_s * rng.uniform(*LEAVE_AT)
    away_s = rng.uniform(*AWAY_S)
    if speed == 0:
        return Walk(np.array([0.0, duration_s]), np.stack([start, start]))
    speed_px = speed * geometry.px_per_deg
    x_lo, x_hi, y_lo, y_hi = geometry.grid_area_px()
    width, height = geometry.size_px
    times, points = [0.0], [start]
    left = not leave
    while times[-1] < duration_s:
        here = points[-1]
        u_pause, u_len, u_x, u_y = rng.random(4)
        if not left and times[-1] >= leave_at:
            outside = _outside(here, width, height, side_px)
            times.append(times[-1] + float(np.hypot(*(outside - here))) / speed_px)
            points.append(outside)
            times.append(times[-1] + away_s)
            points.append(outside)
            left = True
            continue
        if u_pause < PAUSE_PROB:
            times.append(times[-1] + PAUSE_S[0] + u_len * (PAUSE_S[1] - PAUSE_S[0]))
            points.append(here)
            continue
        target = np.array([x_lo + u_x * (x_hi - x_lo), y_lo + u_y * (y_hi - y_lo)])
        times.append(times[-1] + max(float(np.hypot(*(target - here))) / speed_px, 1e-6))
        points.append(target)
    return Walk(np.array(times), np.stack(points))


def _outside(here: np.ndarray, width: int, height: int, side_px: int) -> np.ndarray:
    """Return the point past the panorama's nearest edge for a face leaving from ``here``."""
    beyond = OUTSIDE_SIDES * side_px + side_px / 2
    x, y = here
    options = [(x, (-beyond, y)), (width - x, (width + beyond, y)), (y, (x, -beyond)),
               (height - y, (x, height + beyond))]
    return np.array(min(options, key=lambda option: option[0])[1], dtype=float)


def check_speed(speed_deg_s) -> float:
    """Return a walking speed in deg/s, or raise ValueError unless ``0 <= v <= 20``."""
    try:
        speed = float(speed_deg_s)
    except (TypeError, ValueError):
        speed = math.nan
    if isinstance(speed_deg_s, bool) or not 0 <= speed <= MAX_SPEED_DEG_S:
        raise ValueError(f'speed_deg_s must be a number from 0 to {MAX_SPEED_DEG_S:g}, got '
                         f'{speed_deg_s!r}')
    return speed


@dataclass(frozen=True)
class Truth:
    """Where the face is at one time: centre ``(x, y)`` px, grid position and cell (or None)."""

    centre_px: tuple
    position: tuple
    cell: tuple | None


class WalkScene:
    """
    One walk scene: the background, the face (resized once), its :class:`Walk` and length.

    ``others``: the ``(face, walk)`` of more people walking in the same scene (module
    docstring); :attr:`walk` and :meth:`truth_at` are the first person's.
    """

    def __init__(self, background: np.ndarray, face: np.ndarray, walk: Walk,
                 geometry: SceneGeometry, index: int, duration_s: float | None = None,
                 others=()):
        self.background = background
        self.walk = walk
        self.walks = (walk,) + tuple(w for _, w in others)
        self.duration_s = walk.duration_s if duration_s is None else float(duration_s)
        self.geometry = geometry
        self.index = index
        self.side_px = int(face.shape[0])
        self._faces = [self._sprite(f, background.ndim) for f in
                       (face,) + tuple(f for f, _ in others)]

    @staticmethod
    def _sprite(face: np.ndarray, ndim: int) -> tuple:
        """Return a face and its feathered alpha, as float32 (with a channel axis for colour)."""
        alpha = feather_mask(int(face.shape[0]), DEFAULT_FEATHER)
        if ndim == 3:
            face, alpha = face[:, :, None], alpha[:, :, None]
        return face.astype(np.float32), alpha.astype(np.float32)

    @property
    def people(self) -> int:
        """Return how many people walk in the scene."""
        return len(self.walks)

    def truth_at(self, t_s: float) -> Truth:
        """Return where the (first) face is at ``t_s``: its cell is None out of the reach."""
        return self._truth(self.walk, t_s)

    def truths_at(self, t_s: float) -> tuple:
        """Return where every face is at ``t_s`` (:class:`Truth` each, in the people's order)."""
        return tuple(self._truth(walk, t_s) for walk in self.walks)

    def _truth(self, walk: Walk, t_s: float) -> Truth:
        x, y = (float(v) for v in walk.position_px(t_s))
        row, col = (float(v) for v in self.geometry.point_position(x, y))
        r, c = int(math.floor(row + 0.5)), int(math.floor(col + 0.5))
        g = self.geometry.grid
        cell = (r, c) if 0 <= r < g.rows and 0 <= c < g.cols else None
        return Truth((x, y), (row, col), cell)

    def image_at(self, t_s: float) -> np.ndarray:
        """Return the panorama at ``t_s``: each face pasted where it is, clipped at the edges."""
        image = self.background.copy()
        for walk, (sprite, mask) in zip(self.walks, self._faces):
            x, y = walk.position_px(t_s)
            side = int(sprite.shape[0])
            x0, y0 = int(round(x - side / 2.0)), int(round(y - side / 2.0))
            h, w = image.shape[:2]
            ax, ay = max(x0, 0), max(y0, 0)
            bx, by = min(x0 + side, w), min(y0 + side, h)
            if ax >= bx or ay >= by:
                continue
            face = sprite[ay - y0:by - y0, ax - x0:bx - x0]
            alpha = mask[ay - y0:by - y0, ax - x0:bx - x0]
            region = image[ay:by, ax:bx]
            bg = region.astype(np.float32)
            region[...] = np.rint(bg + alpha * (face - bg)).astype(np.uint8)
        return image


class WalkSceneSet:
    """
    Walk scenes over the still pan/tilt scenes: scene ``i`` walks the face of seed ``seed + i``.

    ``speed_deg_s`` from 0 to 20; ``duration_s`` of each walk; ``leave`` adds the excursion out
    of reach; ``faces`` people per scene (module docstring; 1: the one-face walks, bit for bit).
    """

    def __init__(self, split: str = 'test', geometry: SceneGeometry | None = None,
                 seed: int = 0, speed_deg_s: float = SPEED_DEG_S, duration_s: float = DURATION_S,
                 leave: bool = True, color: str = 'rgb', faces: int = 1):
        if isinstance(faces, bool) or int(faces) != faces or not 1 <= int(faces) <= 4:
            raise ValueError(f'faces must be an integer from 1 to 4, got {faces!r}')
        self.faces = int(faces)
        self.speed_deg_s = check_speed(speed_deg_s)
        self.duration_s = float(duration_s)
        if not (math.isfinite(self.duration_s) and self.duration_s > 0):
            raise ValueError(f'duration_s must be > 0, got {duration_s!r}')
        self.still = PanTiltSceneSet(split, geometry, color=color, seed=seed)
        self.split, self.seed, self.leave, self.color = split, int(seed), bool(leave), color
        self.geometry = self.still.geometry

    def kwargs(self) -> dict:
        """Keyword arguments that rebuild this set (for worker processes)."""
        return {'split': self.split, 'geometry': self.geometry.to_dict(), 'seed': self.seed,
                'speed_deg_s': self.speed_deg_s, 'duration_s': self.duration_s,
                'leave': self.leave, 'color': self.color, 'faces': self.faces}

    @classmethod
    def from_kwargs(cls, kwargs: dict) -> WalkSceneSet:
        """Inverse of :meth:`kwargs`."""
        values = dict(kwargs)
        values['geometry'] = SceneGeometry.from_dict(values['geometry'])
        return cls(**values)

    def scene(self, index: int) -> WalkScene:
        """Build walk scene ``index``: the still scene of seed ``seed + index``, walking."""
        index = int(index)
        if index < 0:
            raise IndexError(f'scene indices are non-negative, got {index}')
        kwargs = {'split': self.split, 'geometry': self.geometry, 'color': self.color,
                  'seed': self.seed + index}
        still = PanTiltSceneSet(**kwargs, faces=self.faces).scene(0)
        background = PanTiltSceneSet(**kwargs, empty=True).scene(0).image
        people = []
        for j, person in enumerate(still.faces if self.faces > 1 else
                                   [(still.face_centre_px, still.face_px, None,
                                     still.face_index)]):
            centre, side, _, face_index = person
            side = int(side)
            face = np.clip(cv2.resize(load_faces()[face_index], (side, side),
                                      interpolation=cv2.INTER_CUBIC), 0.0, 255.0)
            stream = [_STREAM_TAG, _SPLIT_CODE[self.split], self.seed + index] + \
                ([j] if j else [])
            walk = draw_walk(np.random.default_rng(stream), self.geometry, centre, side,
                             self.speed_deg_s, self.duration_s, self.leave)
            people.append((face, walk))
        (face, walk), others = people[0], people[1:]
        return WalkScene(background, face, walk, self.geometry, index, self.duration_s, others)


def calibrate_motion(split: str = 'train', scenes: int = 200, speeds_deg_s=(0.0, 20.0),
                     dt_s: float = 0.13, seed: int = 0, duration_s: float = DURATION_S,
                     step_s: float = 0.05, classes: int = 9) -> dict:
    """
    Fit the belief's motion to walks of ``split`` (docs/design.md section 12.3).

    Scene ``i`` walks at ``speeds_deg_s[0] + u (speeds_deg_s[1] - speeds_deg_s[0])``, ``u``
    uniform from the stream ``default_rng([tag, 2, seed])``: a tracker does not know how fast
    people walk. From the walks' positions every ``step_s`` while in the grid's reach:

    - ``sigma_cells``: the random walk's maximum-likelihood step per second over ``dt_s`` (the
      time between a tracker's frames), ``sqrt(mean(d_row^2 + d_col^2) / (2 dt))`` over pairs
      of times ``dt_s`` apart, both in reach;
    - ``leave_prob``: ``1 - exp(-exits / seconds in reach)``, and ``return_prob``,
      ``1 - exp(-returns / seconds out of reach)``;
    - for a target with a velocity (:class:`~ipomdp_gaze.model.motion.VelocityMotion`):
      ``max_speed_cells``, the largest speed per axis seen; ``speed_cells``, the root mean
      square of the velocity per axis (pauses included); ``turn_prob``,
      ``1 - exp(-turns / seconds in reach)`` (a turn: the velocity changes between samples);
      ``velocity_sigma_cells``, the random walk left once each pair's displacement is
      predicted by its velocity rounded to the nearest of ``classes`` per axis.
    """
    lo, hi = (check_speed(v) for v in speeds_deg_s)
    draws = np.random.default_rng([_STREAM_TAG, 2, int(seed)]).random(int(scenes))
    walks, geometry = [], None
    for i, u in enumerate(draws):
        walk_set = WalkSceneSet(split, seed=seed, speed_deg_s=lo + u * (hi - lo),
                                duration_s=duration_s)
        walks.append(walk_set.scene(i).walk)
        geometry = walk_set.geometry
    rows, cols = geometry.grid.shape

    def grid_at(walk, times):
        return np.stack(geometry.point_position(*walk.position_px(times).T), axis=-1)

    samples = []
    for walk in walks:
        times = np.arange(0.0, duration_s - dt_s, step_s)
        a, b = grid_at(walk, times), grid_at(walk, times + dt_s)
        velocity = (grid_at(walk, times + 1e-4) - a) / 1e-4
        samples.append((a, b, velocity, _in_reach(a, rows, cols),
                        _in_reach(a, rows, cols) & _in_reach(b, rows, cols)))
    speed = max(float(np.abs(v[r]).max()) if r.any() else 0.0 for _, _, v, r, _ in samples)
    levels = np.linspace(-speed, speed, int(classes)) if speed > 0 else np.zeros(1)
    squares = residual = moving = 0.0
    pairs = exits = turns = returns = 0
    inside_s = outside_s = 0.0
    for a, b, velocity, reach, both in samples:
        d = b[both] - a[both]
        squares += float(np.sum(d ** 2))
        nearest = levels[np.argmin(np.abs(velocity[both][..., None] - levels), axis=-1)]
        residual += float(np.sum((d - nearest * dt_s) ** 2))
        pairs += int(both.sum())
        exits += int(np.sum(reach[:-1] & ~reach[1:]))
        returns += int(np.sum(~reach[:-1] & reach[1:]))
        outside_s += float((~reach).sum()) * step_s
        moving += float(np.sum(velocity[reach] ** 2))
        changed = np.any(np.abs(np.diff(velocity, axis=0)) > 1e-6, axis=1)
        turns += int(np.sum(changed & reach[:-1] & reach[1:]))
        inside_s += float(reach.sum()) * step_s
    samples_in_reach = inside_s / step_s

    def rate(count, seconds):
        return 1.0 - math.exp(-count / seconds) if seconds > 0 else 0.0

    return {'sigma_cells': math.sqrt(squares / max(pairs, 1) / (2.0 * dt_s)),
            'leave_prob': rate(exits, inside_s), 'return_prob': rate(returns, outside_s),
            'max_speed_cells': speed, 'turn_prob': rate(turns, inside_s),
            'speed_cells': math.sqrt(moving / max(2 * samples_in_reach, 1)),
            'velocity_sigma_cells': math.sqrt(residual / max(pairs, 1) / (2.0 * dt_s)),
            'pairs': pairs, 'exits': exits, 'turns': turns, 'seconds_in_reach': inside_s}


def _in_reach(position: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """Whether grid positions ``(T, 2)`` round to a cell of the grid."""
    r = np.floor(position[:, 0] + 0.5)
    c = np.floor(position[:, 1] + 0.5)
    return (r >= 0) & (r < rows) & (c >= 0) & (c < cols)


def plot_walk(times_s, face_rc, head_rc, path, title: str = '', events=()) -> None:
    """
    Draw a walk over time: the face's row and column (grid positions) and the head's.

    ``times_s`` (T,), ``face_rc`` (T, 2) grid positions (NaN rows out of reach), ``head_rc``
    (T, 2) the head's cell per frame; ``events`` ``(t_s, name)`` pairs marked as vertical lines
    (found, lost, reacquired). Written with matplotlib (Agg) to ``path``.
    """
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot as plt
    times = np.asarray(times_s, dtype=float)
    face = np.asarray(face_rc, dtype=float).reshape(-1, 2)
    head = np.asarray(head_rc, dtype=float).reshape(-1, 2)
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    for axis, ax, label in ((1, axes[0], 'column'), (0, axes[1], 'row')):
        ax.plot(times, face[:, axis], color='tab:orange', label='face')
        ax.step(times, head[:, axis], where='post', color='tab:blue', label='gaze (head cell)')
        out = np.isnan(face[:, axis])
        if out.any():
            ax.fill_between(times, 0, 1, where=out, transform=ax.get_xaxis_transform(),
                            color='0.85', label='out of reach')
        for t, name in events:
            ax.axvline(t, color={'lost': 'tab:red'}.get(name, 'tab:green'), lw=0.8, ls=':')
        ax.set_ylabel(label)
        if axis == 0:
            ax.invert_yaxis()
    axes[0].legend(loc='upper right', fontsize=8)
    axes[1].set_xlabel('time (s)')
    # wrapped: the demo's title (the scene camera's parameters) ran past both edges
    fig.suptitle(textwrap.fill(title or 'the face and the gaze over time', TITLE_CHARS),
                 fontsize=10)
    fig.tight_layout()
    write_figure(fig, path, dpi=100)
    plt.close(fig)
