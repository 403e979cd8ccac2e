# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Strict JSON for the records the CLI writes: a value that is not a number is ``null``."""
from __future__ import annotations

import json
import math

import numpy as np


def finite(value):
    """
    Return ``value`` with every NaN or infinite float (nested in dicts, lists) as None.

    numpy scalars and arrays become Python numbers and lists first (``json`` refuses a
    ``float32`` or an ``int64``, with a traceback after the work).
    """
    if isinstance(value, (np.ndarray, np.generic)):
        value = value.tolist()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: finite(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(item) for item in value]
    return value


def dumps(record, indent: int | None = 1) -> str:
    """
    Return ``record`` as strict JSON (RFC 8259 has no NaN): a NaN or infinite number is null.

    A mean over nothing (a walk with no reacquisition) is NaN in the summaries; Python's
    ``json`` would write the bare ``NaN`` that other JSON readers refuse.
    """
    return json.dumps(finite(record), indent=indent, allow_nan=False)
