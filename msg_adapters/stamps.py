# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``builtin_interfaces/Time`` <-> seconds."""
from __future__ import annotations

import math

from builtin_interfaces.msg import Time

NS_PER_S = 1_000_000_000


def to_seconds(stamp: Time) -> float:
    """Seconds of a ``builtin_interfaces/Time`` (or ``Duration``)."""
    return stamp.sec + stamp.nanosec * 1e-9


def is_zero(stamp: Time) -> bool:
    """Whether a stamp was left unset (0 s, 0 ns), as many drivers do."""
    return stamp.sec == 0 and stamp.nanosec == 0


def from_seconds(seconds: float) -> Time:
    """Convert a time in seconds (>= 0) to a ``builtin_interfaces/Time``."""
    if not math.isfinite(seconds) or seconds < 0:
        raise ValueError(f'a stamp must be a finite time >= 0 s, got {seconds!r}')
    total_ns = int(round(seconds * NS_PER_S))
    return Time(sec=total_ns // NS_PER_S, nanosec=total_ns % NS_PER_S)
