# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Several detectors as one (detector kind ``ensemble``): the raw boxes of all, each weighted.

A count model counts the boxes centred in a cell. Two detectors that fail on different faces
see more of them together: on the pan/tilt thumbnails the Haar cascades give a few raw boxes on
faces that YuNet, run on the view at twice its size, finds with one confident box, and YuNet
misses faces the cascades see (docs/design.md section 6.11). YuNet returns one box per face after
its own suppression where a cascade returns ten, so each member has a ``weight``: every box it
returns is counted that many times. The count tables are calibrated on what the ensemble
returns, so the weight only decides how the two are mixed into one count, not how much a count
is believed.

Each member is a mapping ``{'kind': ..., 'weight': w, option: value, ...}`` built by the detector
factory (:mod:`ipomdp_gaze.vision.detectors`); in an observation file each member is recorded
with its own settings (a cascade's or a model's SHA-256 included) and checked when the ensemble
is rebuilt.
"""
from __future__ import annotations

import cv2
from ipomdp_gaze.vision.detector import (as_detections, describe_detector, detect,
                                         detector_settings, detector_window_px, group_boxes,
                                         INFO_KEYS, to_detector_image)
import numpy as np

# Largest weight of a member: a box counted more often than this says nothing a count can keep.
MAX_WEIGHT = 100


def _weight(value, index: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
            or not 1 <= value <= MAX_WEIGHT:
        raise ValueError(f'ensemble member {index}: weight must be an int in [1, {MAX_WEIGHT}], '
                         f'got {value!r}')
    return int(value)


def _member_spec(member, index: int) -> tuple[str, int, dict]:
    """Split a member mapping into its kind, its weight and the detector's own options."""
    if not isinstance(member, dict):
        raise ValueError(f'ensemble member {index} must be a mapping with a kind, got {member!r}')
    options = dict(member)
    kind = options.pop('kind', None)
    if not isinstance(kind, str) or not kind:
        raise ValueError(f'ensemble member {index} needs a kind, got {member!r}')
    if kind == EnsembleDetector.kind:
        raise ValueError(f'ensemble member {index}: an ensemble cannot hold an ensemble')
    return kind, _weight(options.pop('weight', 1), index), options


def _members(members) -> list:
    if not isinstance(members, (list, tuple)) or not members:
        raise ValueError(f'members must be a non-empty list of detector mappings, got '
                         f'{members!r}')
    return [_member_spec(member, i) for i, member in enumerate(members)]


class EnsembleDetector:
    """
    Run every member on the image; return all their boxes, each repeated ``weight`` times.

    Parameters
    ----------
    members : list of dict
        ``{'kind': ..., 'weight': w, option: value, ...}`` per detector (``weight`` default 1).
    cascade_dir : str or os.PathLike, optional
        Passed to the members that take it (Haar: the folder holding its cascades).

    """

    kind = 'ensemble'
    info_keys = INFO_KEYS
    # The YAML types of its record's keys (ipomdp_gaze.files.yaml_files.check_record); each
    # member is a detector's record with its weight (check_detector_record).
    record_types = {'members': 'mappings', 'window_px': 'pair', 'opencv': 'text'}

    def __init__(self, members, cascade_dir=None):
        from ipomdp_gaze.vision.detectors import make_detector

        def build(kind, options):
            if cascade_dir is not None and kind == 'haar':
                options = {**options, 'cascade_dir': cascade_dir}
            return make_detector(kind, **options)
        self._set_members(members, build)

    @classmethod
    def from_settings(cls, settings: dict, cascade_dir=None) -> EnsembleDetector:
        """
        Rebuild from :meth:`settings`: each member from its own record, checked as it is checked.

        Raises
        ------
        ValueError
            Naming the member whose record does not rebuild (another cascade or model file).

        """
        from ipomdp_gaze.vision.detectors import detector_from_settings
        detector = cls.__new__(cls)
        detector._set_members(settings.get('members'), lambda kind, options: (
            detector_from_settings({'kind': kind, **options}, cascade_dir=cascade_dir)))
        return detector

    def _set_members(self, members, build):
        """Build each member with ``build(kind, options)``; an error names the member."""
        specs = _members(members)
        self.weights = [weight for _, weight, _ in specs]
        self.members = []
        for i, (kind, _, options) in enumerate(specs):
            try:
                self.members.append(build(kind, options))
            except ValueError as exc:
                raise ValueError(f'ensemble member {i}: {exc}') from None
        colors = {getattr(member, 'color', 'gray') for member in self.members}
        self.color = 'rgb' if 'rgb' in colors else 'gray'
        windows = [detector_window_px(member) for member in self.members]
        self.window_px = (max(w for w, _ in windows), max(h for _, h in windows))

    def __call__(self, image: np.ndarray) -> np.ndarray:
        """Boxes ``(M, 5)`` ``x, y, w, h, score`` of every member, member by member."""
        image = np.asarray(image)
        parts = []
        for member, weight in zip(self.members, self.weights):
            own = to_detector_image(image, getattr(member, 'color', 'gray'))
            boxes, scores = detect(member, own)
            parts.append(np.repeat(np.column_stack([boxes, scores]), weight, axis=0))
        return np.concatenate(parts, axis=0) if parts else np.empty((0, 5))

    def group(self, boxes, min_neighbors: int = 0) -> np.ndarray:
        """Group as OpenCV does: a member's box of weight w is w neighbours of itself."""
        boxes, _ = as_detections(boxes)
        boxes = np.round(boxes)
        boxes[:, 2:] = np.maximum(boxes[:, 2:], 1.0)
        return group_boxes(boxes, min_neighbors)

    def settings(self) -> dict:
        """Return the members' records (without their information-only keys) with weights."""
        members = []
        for member, weight in zip(self.members, self.weights):
            record = detector_settings(member)
            info = getattr(member, 'info_keys', INFO_KEYS)
            members.append({**{k: v for k, v in record.items() if k not in info},
                            'weight': weight})
        return {'kind': self.kind, 'members': members, 'window_px': list(self.window_px),
                'opencv': cv2.__version__}

    def __repr__(self) -> str:
        """Show the members and their weights."""
        inner = ', '.join(f'{describe_detector(member)} x{weight}'
                          for member, weight in zip(self.members, self.weights))
        return f'EnsembleDetector([{inner}])'
