# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Foveal-peripheral operating characteristics (FPOCs) of the observation model.

An FPOC gives the detectability d' of a target at offset ``(dx, dy)`` degrees from fixation.

Every FPOC is a small object built from the parameter names of docs/design.md section 2 (the same
names appear in policy files, the CLI's ``--fpoc-param`` and the nodes' ``fpoc.<name>``), and is
evaluated on offset arrays. ``dprime_matrix`` gives the N x N matrix ``d[j, k]`` (target cell j,
fixation k) for small grids; ``dprime_table`` gives the ``(2R-1) x (2C-1)`` offset table that
large grids use instead.
"""
from __future__ import annotations

import math
from typing import Callable

from ipomdp_gaze.model.checks import check_number, short_repr
from ipomdp_gaze.model.grid import Grid
import numpy as np
from scipy.special import log_ndtr, ndtr, ndtri

EDGE_TOL_DEG = 1e-9


def _positive(name: str, value, allow_zero: bool = False) -> float:
    value = check_number(value, name)
    if not math.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        bound = '>= 0' if allow_zero else '> 0'
        raise ValueError(f'{name} must be finite and {bound}, got {value!r}')
    return value


def _numbers(name: str, values) -> np.ndarray:
    """Return a list of numbers as a flat float array: no text ('1'), no true/false."""
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):         # ragged rows
        array = np.array([''])
    if array.dtype.kind not in 'iuf':
        raise ValueError(f'{name} must be a list of numbers, got {short_repr(values)}')
    return array.astype(float).ravel()


class FPOC:
    """Base class: ``fpoc(dx, dy)`` returns d' >= 0 with the broadcast shape of the offsets."""

    model: str = ''
    defaults: dict = {}

    def __call__(self, dx, dy) -> np.ndarray:
        raise NotImplementedError

    def params(self) -> dict:
        """Parameters by their docs/design.md names (what a policy file's ``fpoc`` block holds)."""
        raise NotImplementedError

    def to_dict(self) -> dict:
        """``{'model': ..., <params>}``."""
        return {'model': self.model, **self.params()}

    def __repr__(self):
        args = ', '.join(f'{k}={v!r}' for k, v in self.params().items())
        return f'{type(self).__name__}({args})'

    def __eq__(self, other):
        return isinstance(other, FPOC) and self.to_dict() == other.to_dict()

    def __hash__(self):
        return hash(repr(self))


class HumanFPOC(FPOC):
    """
    Najemnik & Geisler (2005) visibility map, radially averaged.

    ``c_T(e)^2 = 0.002130 exp(0.9790 e) + 0.6712 exp(0.4905 e) n^2``,
    ``s(e) = 2.8 e / (e + 0.8) + 2``, ``f(c, e) = 0.5 + 0.5 (1 - exp(-(c / c_T(e))^s(e)))``,
    ``d'(e) = sqrt(2) Phi^-1(f(c, e))``, with the contrast c chosen so that ``d'(0) = d0``.
    The steepness s grows with e, so once c is above the foveal threshold (d0 above about 1.7) d'
    peaks off the centre, as the formula does (d0 = 3: 3.53 at 0.42 degrees; the default d0 = 2
    peaks at 2.056 at 0.15 degrees); docs/design.md section 2.
    """

    model = 'human'
    defaults = {'noise_contrast': 0.20, 'foveal_dprime': 2.0}

    def __init__(self, noise_contrast: float = 0.20, foveal_dprime: float = 2.0):
        self.noise_contrast = _positive('noise_contrast', noise_contrast, allow_zero=True)
        self.foveal_dprime = _positive('foveal_dprime', foveal_dprime)
        if self.foveal_dprime > 12:
            raise ValueError(f'foveal_dprime must be <= 12 (Phi saturates), got {foveal_dprime!r}')
        # At e = 0 the steepness is 2: (c / c_T)^2 = -ln(2 - 2 f0), f0 = Phi(d0 / sqrt 2). Past
        # d0 = 6, 2 - 2 f0 loses digits (and rounds to 0 from 11.9): there in logs, as
        # -ln 2 - ln Phi(-d0 / sqrt 2); below, as written (the shipped models, bit for bit).
        d0 = self.foveal_dprime / math.sqrt(2.0)
        ratio_sq = (-math.log(2.0 - 2.0 * ndtr(d0)) if self.foveal_dprime <= 6 else
                    -(math.log(2.0) + float(log_ndtr(-d0))))
        self.contrast = math.sqrt(self._threshold_sq(0.0) * ratio_sq)

    def _threshold_sq(self, ecc):
        n2 = self.noise_contrast ** 2
        with np.errstate(over='ignore'):        # far out: an infinite threshold, d' = 0
            return 0.002130 * np.exp(0.9790 * ecc) + 0.6712 * np.exp(0.4905 * ecc) * n2

    def of_eccentricity(self, ecc_deg) -> np.ndarray:
        """Evaluate d' as a function of eccentricity in degrees."""
        ecc = np.asarray(ecc_deg, dtype=float)
        with np.errstate(over='ignore', invalid='ignore'):
            steep = 2.8 * ecc / (ecc + 0.8) + 2.0
        # Past about 6e307 degrees 2.8 e overflows (inf / inf at e = inf): the limit, 4.8 (d' 0).
        steep = np.where(np.isfinite(steep), steep, 4.8)
        ratio_sq = self.contrast ** 2 / self._threshold_sq(ecc)
        miss = np.exp(-ratio_sq ** (steep / 2.0))
        # f = 0.5 + 0.5 (1 - miss) = 1 - miss / 2; Phi^-1(1 - x) = -Phi^-1(x) keeps precision.
        return np.maximum(-math.sqrt(2.0) * ndtri(miss / 2.0), 0.0)

    def __call__(self, dx, dy):
        return self.of_eccentricity(np.hypot(dx, dy))

    def params(self):
        return {'noise_contrast': self.noise_contrast, 'foveal_dprime': self.foveal_dprime}


class ExponentialFPOC(FPOC):
    """``d = foveal_dprime * exp(-e / scale_deg)``."""

    model = 'exponential'
    defaults = {'foveal_dprime': 2.0, 'scale_deg': 1.5}

    def __init__(self, foveal_dprime: float = 2.0, scale_deg: float = 1.5):
        self.foveal_dprime = _positive('foveal_dprime', foveal_dprime)
        self.scale_deg = _positive('scale_deg', scale_deg)

    def of_eccentricity(self, ecc_deg):
        """Evaluate d' as a function of eccentricity in degrees."""
        return self.foveal_dprime * np.exp(-np.asarray(ecc_deg, dtype=float) / self.scale_deg)

    def __call__(self, dx, dy):
        return self.of_eccentricity(np.hypot(dx, dy))

    def params(self):
        return {'foveal_dprime': self.foveal_dprime, 'scale_deg': self.scale_deg}


class CameraFPOC(FPOC):
    """Step FPOC of a camera: ``d = dprime`` inside the field of view (edge included), else 0."""

    model = 'camera'
    defaults = {'dprime': 4.0, 'shape': 'rectangle', 'half_width_deg': 0.84,
                'half_height_deg': 0.84, 'radius_deg': 0.84}
    SHAPES = ('rectangle', 'circle')

    def __init__(self, dprime: float = 4.0, shape: str = 'rectangle', half_width_deg: float = 0.84,
                 half_height_deg: float = 0.84, radius_deg: float = 0.84):
        self.dprime = _positive('dprime', dprime)
        if shape not in self.SHAPES:
            raise ValueError(f"shape must be one of {', '.join(self.SHAPES)}, got {shape!r}")
        self.shape = shape
        self.half_width_deg = _positive('half_width_deg', half_width_deg, allow_zero=True)
        self.half_height_deg = _positive('half_height_deg', half_height_deg, allow_zero=True)
        self.radius_deg = _positive('radius_deg', radius_deg, allow_zero=True)

    def __call__(self, dx, dy):
        dx, dy = np.asarray(dx, dtype=float), np.asarray(dy, dtype=float)
        if self.shape == 'circle':
            inside = np.hypot(dx, dy) <= self.radius_deg + EDGE_TOL_DEG
        else:
            inside = (np.abs(dx) <= self.half_width_deg + EDGE_TOL_DEG) & \
                     (np.abs(dy) <= self.half_height_deg + EDGE_TOL_DEG)
        return np.where(inside, self.dprime, 0.0)

    def params(self):
        if self.shape == 'circle':
            return {'dprime': self.dprime, 'shape': 'circle', 'radius_deg': self.radius_deg}
        return {'dprime': self.dprime, 'shape': 'rectangle', 'half_width_deg': self.half_width_deg,
                'half_height_deg': self.half_height_deg}


class TableFPOC(FPOC):
    """A measured curve: linear interpolation of ``dprime`` over ``ecc_deg``, constant beyond."""

    model = 'table'
    defaults = {'ecc_deg': [0.0, 1.0], 'dprime': [2.0, 0.0]}

    def __init__(self, ecc_deg=(0.0, 1.0), dprime=(2.0, 0.0)):
        ecc, dp = _numbers('ecc_deg', ecc_deg), _numbers('dprime', dprime)
        if ecc.size < 1 or ecc.size != dp.size:
            raise ValueError(f'ecc_deg and dprime must be non-empty and of equal length, got '
                             f'{ecc.size} ecc_deg {ecc.tolist()} and {dp.size} dprime '
                             f'{dp.tolist()} (a value not given is its default: ecc_deg '
                             f"{self.defaults['ecc_deg']}, dprime {self.defaults['dprime']})")
        if not (np.all(np.isfinite(ecc)) and np.all(np.isfinite(dp))):
            raise ValueError('ecc_deg and dprime must be finite')
        if np.any(ecc < 0) or np.any(np.diff(ecc) <= 0):
            raise ValueError('ecc_deg must be >= 0 and strictly increasing')
        if np.any(dp < 0):
            raise ValueError('dprime must be >= 0')
        self.ecc_deg, self.dprime = ecc, dp

    def of_eccentricity(self, ecc_deg):
        """Evaluate d' as a function of eccentricity in degrees."""
        ecc = np.asarray(ecc_deg, dtype=float)
        return np.maximum(np.interp(ecc, self.ecc_deg, self.dprime), 0.0)

    def __call__(self, dx, dy):
        return self.of_eccentricity(np.hypot(dx, dy))

    def params(self):
        return {'ecc_deg': self.ecc_deg.tolist(), 'dprime': self.dprime.tolist()}


MODELS: dict[str, Callable[..., FPOC]] = {
    'human': HumanFPOC, 'exponential': ExponentialFPOC, 'camera': CameraFPOC, 'table': TableFPOC,
}


def parameter_names(model: str) -> tuple[str, ...]:
    """Return the parameter names accepted by an FPOC model."""
    _check_model(model)
    return tuple(MODELS[model].defaults)


def _check_model(model):
    if model not in MODELS:
        raise ValueError(f"unknown FPOC model {model!r}; valid models: {', '.join(MODELS)}")


def make_fpoc(model: str = 'human', **params) -> FPOC:
    """
    Build an FPOC by model name from the parameter names of docs/design.md section 2.

    Raises
    ------
    ValueError
        For an unknown model, an unknown parameter name or an invalid value, naming it.

    """
    _check_model(model)
    unknown = sorted(set(params) - set(MODELS[model].defaults))
    if unknown:
        raise ValueError(f'unknown parameter {unknown[0]!r} for FPOC {model!r}; valid: '
                         f"{', '.join(MODELS[model].defaults)}")
    return MODELS[model](**params)


def fpoc_from_dict(spec: dict) -> FPOC:
    """Build an FPOC from ``{'model': ..., <params>}`` (a policy file's ``fpoc`` block)."""
    if not isinstance(spec, dict) or 'model' not in spec:
        raise ValueError("fpoc must be a mapping with a 'model' key")
    params = {k: v for k, v in spec.items() if k != 'model'}
    return make_fpoc(spec['model'], **params)


def dprime_table(grid: Grid, fpoc: FPOC) -> np.ndarray:
    """Tabulate d' on the ``(2R-1) x (2C-1)`` offset table, entry ``[rj-rk+R-1, cj-ck+C-1]``."""
    dx, dy = grid.offset_table_deg()
    return np.asarray(fpoc(dx, dy), dtype=float)


def dprime_matrix(grid: Grid, fpoc: FPOC) -> np.ndarray:
    """Return the N x N matrix ``d[j, k]``: d' of target cell j when fixating cell k."""
    table = dprime_table(grid, fpoc)
    ri, ci = grid.pair_offset_index()          # indexed [k, j]
    return np.ascontiguousarray(table[ri, ci].T)
