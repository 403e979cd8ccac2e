# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The rooms over DDS with ``search.decide_after_pass``: the node against the offline session.

As ``bench_ros_room.py`` (three fresh processes per held-out room of 0-4 faces, the shipped
pan/tilt configs with the rooms'), the controller with ``search.decide_after_pass`` and
``search.repeat_weight 1.0`` (not shipped; docs/design.md section 11.7): after the sweep's pass
the head goes on until every cell is decided or the budget. The offline session is
``pass-many-cells`` with the same two settings. 20 seeds (3 with ``--quick``). Test rooms;
nothing was fitted to them.
"""
from pathlib import Path
import sys

sys.path.insert(0, str(Path(__file__).resolve().parent))       # bench_ros_room beside it
from bench_ros_room import rooms_table  # noqa: E402

TITLE = ('Many-target mode over DDS, deciding after the pass: rooms of 0-4 faces, the node '
         'against the offline session')
ORDER = 64
LABEL = 'pass-many-cells:search.decide_after_pass=true,search.repeat_weight=1.0'
EXTRA = ('-p', 'search.decide_after_pass:=true', '-p', 'search.repeat_weight:=1.0')


def bench(ctx) -> str:
    """One room per seed, node against offline; a markdown table and the totals."""
    return rooms_table(ctx, range(3) if ctx.quick else range(20), LABEL, EXTRA)
