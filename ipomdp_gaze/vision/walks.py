# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Pan/tilt scenes where the face walks (docs/design.md section 12.1).

A walk scene is the still pan/tilt scene of the same seed (:class:`PanTiltSceneSet`, one face,
the same split, background crop, face, size and start) with the face moving along a path in
the panorama over ``duration_s`` seconds. The path (:class:`Walk`) is straight segments at a
constant ``speed_deg_s`` between waypoints drawn uniformly in the grid's reach, with pauses
(probability :data:`PAUSE_PROB` per leg, :data:`PAUSE_S` long) and, once per walk, an excursion
out of the head's reach: the face walks past the nearer side edge of the panorama (no view can
see it), stays out :data:`AWAY_S` seconds and walks back in to a new waypoint. Speed 0 is the
still scene: the face never moves and never leaves.

Each frame is drawn at the time of the camera's clock: :meth:`WalkScene.image_at` pastes the face
at its position at that time into the background (clipped at the panorama's edges), and
:meth:`WalkScene.truth_at` says where it is (cell, or None out of reach). The draws of scene
``i`` come from their own stream ``default_rng([tag, split, seed, i])``, apart from the still
scene's, so a still scene is bit for bit the one the still evaluation searches.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import cv2
from ipomdp_gaze.vision.pan_tilt import PanTiltSceneSet, SceneGeometry
from ipomdp_gaze.vision.scenes import DEFAULT_FEATHER, feather_mask, load_faces
import numpy as np

# What a walk is made of: the chance a leg is a pause, how long pauses and the excursion out of
# reach last (s, uniform), when the excursion starts (fraction of the walk, uniform), and how far
# past the panorama's edge the face goes (face sides).
PAUSE_PROB = 0.3
PAUSE_S = (0.5, 2.0)
AWAY_S = (2.0, 4.0)
LEAVE_AT = (0.3, 0.5)
OUTSIDE_SIDES = 1.0
MAX_SPEED_DEG_S = 20.0
DURATION_S = 20.0
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
    width = geometry.size_px[0]
    times, points = [0.0], [start]
    left = not leave
    while times[-1] < duration_s:
        here = points[-1]
        u_pause, u_len, u_x, u_y = rng.random(4)
        if not left and times[-1] >= leave_at:
            side = -OUTSIDE_SIDES * side_px - side_px / 2 if here[0] < width / 2 \
                else width + OUTSIDE_SIDES * side_px + side_px / 2
            outside = np.array([side, here[1]])
            times.append(times[-1] + abs(outside[0] - here[0]) / speed_px)
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
    """One walk scene: the background, the face (resized once), its :class:`Walk` and length."""

    def __init__(self, background: np.ndarray, face: np.ndarray, walk: Walk,
                 geometry: SceneGeometry, index: int, duration_s: float | None = None):
        self.background = background
        self.walk = walk
        self.duration_s = walk.duration_s if duration_s is None else float(duration_s)
        self.geometry = geometry
        self.index = index
        self.side_px = int(face.shape[0])
        alpha = feather_mask(self.side_px, DEFAULT_FEATHER)
        if background.ndim == 3:
            face, alpha = face[:, :, None], alpha[:, :, None]
        self._face = face.astype(np.float32)
        self._alpha = alpha.astype(np.float32)

    def truth_at(self, t_s: float) -> Truth:
        """Return where the face is at ``t_s``: its cell is None out of the grid's reach."""
        x, y = (float(v) for v in self.walk.position_px(t_s))
        row, col = (float(v) for v in self.geometry.point_position(x, y))
        r, c = int(math.floor(row + 0.5)), int(math.floor(col + 0.5))
        g = self.geometry.grid
        cell = (r, c) if 0 <= r < g.rows and 0 <= c < g.cols else None
        return Truth((x, y), (row, col), cell)

    def image_at(self, t_s: float) -> np.ndarray:
        """Return the panorama at ``t_s``: the face pasted where it is, clipped at the edges."""
        image = self.background.copy()
        x, y = self.walk.position_px(t_s)
        side = self.side_px
        x0, y0 = int(round(x - side / 2.0)), int(round(y - side / 2.0))
        h, w = image.shape[:2]
        ax, ay = max(x0, 0), max(y0, 0)
        bx, by = min(x0 + side, w), min(y0 + side, h)
        if ax >= bx or ay >= by:
            return image
        face = self._face[ay - y0:by - y0, ax - x0:bx - x0]
        alpha = self._alpha[ay - y0:by - y0, ax - x0:bx - x0]
        region = image[ay:by, ax:bx]
        bg = region.astype(np.float32)
        region[...] = np.rint(bg + alpha * (face - bg)).astype(np.uint8)
        return image


class WalkSceneSet:
    """
    Walk scenes over the still pan/tilt scenes: scene ``i`` walks the face of seed ``seed + i``.

    ``speed_deg_s`` from 0 to 20; ``duration_s`` of each walk; ``leave`` adds the excursion out
    of reach.
    """

    def __init__(self, split: str = 'test', geometry: SceneGeometry | None = None,
                 seed: int = 0, speed_deg_s: float = 5.0, duration_s: float = DURATION_S,
                 leave: bool = True, color: str = 'rgb'):
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
                'leave': self.leave, 'color': self.color}

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
        still = PanTiltSceneSet(**kwargs).scene(0)
        background = PanTiltSceneSet(**kwargs, empty=True).scene(0).image
        side = int(still.face_px)
        face = np.clip(cv2.resize(load_faces()[still.face_index], (side, side),
                                  interpolation=cv2.INTER_CUBIC), 0.0, 255.0)
        rng = np.random.default_rng([_STREAM_TAG, _SPLIT_CODE[self.split], self.seed + index])
        walk = draw_walk(rng, self.geometry, still.face_centre_px, side, self.speed_deg_s,
                         self.duration_s, self.leave)
        return WalkScene(background, face, walk, self.geometry, index, self.duration_s)


def calibrate_motion(split: str = 'train', scenes: int = 200, speeds_deg_s=(0.0, 20.0),
                     dt_s: float = 0.13, seed: int = 0, duration_s: float = DURATION_S,
                     step_s: float = 0.05) -> dict:
    """
    Fit the belief's motion to walks of ``split`` (docs/design.md section 12.3).

    Scene ``i`` walks at ``speeds_deg_s[0] + u (speeds_deg_s[1] - speeds_deg_s[0])``, ``u``
    uniform from the stream ``default_rng([tag, 2, seed])``: a tracker does not know how fast
    people walk. ``sigma_cells`` is the random walk's maximum-likelihood step per second over
    ``dt_s`` (the time between a tracker's frames), ``sqrt(mean(d_row^2 + d_col^2) / (2 dt))``
    over the pairs of times ``dt_s`` apart that are both in the grid's reach; ``leave_prob`` is
    ``1 - exp(-exits / seconds in reach)``, from the walks' positions every ``step_s``.
    Returns ``{'sigma_cells', 'leave_prob', 'pairs', 'exits', 'seconds_in_reach'}``.
    """
    lo, hi = (check_speed(v) for v in speeds_deg_s)
    draws = np.random.default_rng([_STREAM_TAG, 2, int(seed)]).random(int(scenes))
    squares, pairs, exits, inside_s = 0.0, 0, 0, 0.0
    for i, u in enumerate(draws):
        walk_set = WalkSceneSet(split, seed=seed, speed_deg_s=lo + u * (hi - lo),
                                duration_s=duration_s)
        walk = walk_set.scene(i).walk
        geometry = walk_set.geometry
        times = np.arange(0.0, duration_s - dt_s, step_s)
        a = np.stack(geometry.point_position(*walk.position_px(times).T), axis=-1)
        b = np.stack(geometry.point_position(*walk.position_px(times + dt_s).T), axis=-1)
        rows, cols = geometry.grid.shape
        reach_a = _in_reach(a, rows, cols)
        both = reach_a & _in_reach(b, rows, cols)
        squares += float(np.sum((b[both] - a[both]) ** 2))
        pairs += int(both.sum())
        exits += int(np.sum(reach_a[:-1] & ~reach_a[1:]))
        inside_s += float(reach_a.sum()) * step_s
    sigma = math.sqrt(squares / max(pairs, 1) / (2.0 * dt_s))
    leave = 1.0 - math.exp(-exits / inside_s) if inside_s > 0 else 0.0
    return {'sigma_cells': sigma, 'leave_prob': leave, 'pairs': pairs, 'exits': exits,
            'seconds_in_reach': inside_s}


def _in_reach(position: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """Whether grid positions ``(T, 2)`` round to a cell of the grid."""
    r = np.floor(position[:, 0] + 0.5)
    c = np.floor(position[:, 1] + 0.5)
    return (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
