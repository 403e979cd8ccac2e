# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The fovea an observation model was measured with, and the check that a model fits a fovea.

Vision layer, below every driver: ``find`` (:mod:`ipomdp_gaze.vision.search`), the detector
node's logic (:mod:`ipomdp_gaze.vision.detection`) and the offline evaluation build their fovea
here.
"""
from __future__ import annotations

from ipomdp_gaze.model.cell_observation import cell_observation_of
from ipomdp_gaze.vision.detector import detector_settings
from ipomdp_gaze.vision.detectors import (check_detector_record, compare_settings,
                                          detector_from_settings, info_keys_of)
from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig


def check_records(model) -> None:
    """
    Check the types of the detector and fovea records a model's file gives, before they are used.

    Raises
    ------
    ValueError
        Naming the record's key and what it must be (``detector.scale_factor must be a
        number, got [1]``); the caller names the file.

    """
    meta = getattr(model, 'meta', {})
    if meta.get('detector') is not None:
        check_detector_record(meta['detector'])
    if meta.get('fovea') is not None:
        FoveaConfig.from_dict(meta['fovea'])


def check_model(model, fovea: Fovea) -> None:
    """
    Check that ``model`` was measured on ``fovea``'s grid, fovea settings and detector.

    The grid must match always; the fovea settings and the detector only when the model's
    ``meta`` records them (``meta['fovea']``, ``meta['detector']``). For the detector, every
    setting is compared except those recorded for information (the detector's ``info_keys``: the
    OpenCV version and the cascade's window size).

    Raises
    ------
    ValueError
        Naming what differs.

    """
    grid = getattr(model, 'grid', None)
    if grid is None or not hasattr(model, 'log_likelihood_ratio'):
        raise ValueError(f'expected an observation model with a grid, got {type(model).__name__}')
    if grid.shape != fovea.grid.shape:
        raise ValueError(f'the observation model is for a {grid.rows}x{grid.cols} grid but the '
                         f'fovea tiles images with {fovea.grid.rows}x{fovea.grid.cols}')
    scan = bool(getattr(model, 'has_scan', False))
    if scan != fovea.config.scan_once:
        raise ValueError('the fovea scans the whole image once but the observation model has '
                         'no scan tables' if fovea.config.scan_once else
                         'the observation model has scan tables but the fovea does not scan '
                         '(scan_once false)')
    meta = getattr(model, 'meta', {})
    if meta.get('fovea') is not None:
        try:
            measured = FoveaConfig.from_dict(dict(meta['fovea']))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"the model's fovea record is invalid: {exc}") from None
        if measured != fovea.config:
            raise ValueError(f'the observation model was measured with fovea '
                             f'{measured.to_dict()} but the fovea is {fovea.config.to_dict()}')
    if meta.get('detector') is not None:
        compare_settings(dict(meta['detector']), detector_settings(fovea.detector),
                         info_keys_of(fovea.detector))
    if fovea.cells != cell_observation_of(meta, fovea.config.max_count):
        raise ValueError(f'the observation model records cells {meta.get("cells")!r} but the '
                         f'fovea observes {fovea.cells.to_dict()}')


def fovea_for_model(model, detector=None, reuse_windows: bool = True) -> Fovea:
    """
    Build the fovea an observation model was measured with: its grid, fovea and detector.

    ``detector`` defaults to :func:`detector_from_settings` of ``meta['detector']``; the fovea
    settings come from ``meta['fovea']`` (the reference :class:`FoveaConfig` if absent).
    ``reuse_windows`` keeps every window's detections per image (the detector is deterministic,
    so this changes the cost, never the counts).

    Raises
    ------
    ValueError
        If the model records neither a detector nor is given one, a record is invalid, or the
        model was calibrated through a pan/tilt camera (``meta['image']['view']``).

    """
    meta = getattr(model, 'meta', {})
    if (meta.get('image') or {}).get('view') == 'pan_tilt':
        raise ValueError('the observation model was calibrated through a pan/tilt camera '
                         '(image view pan_tilt): it describes views of a head camera, not a '
                         'fovea over a still image; use a fixed-view model such as faces-420')
    if detector is None:
        if meta.get('detector') is None:
            raise ValueError('the observation model does not record its detector '
                             '(meta detector); pass one')
        detector = detector_from_settings(dict(meta['detector']))
    config = FoveaConfig() if meta.get('fovea') is None else \
        FoveaConfig.from_dict(dict(meta['fovea']))
    fovea = Fovea(detector, model.grid, config, reuse_windows=reuse_windows,
                  cells=cell_observation_of(meta, config.max_count))
    check_model(model, fovea)
    return fovea
