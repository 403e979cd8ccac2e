# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""``ipomdp-gaze demo``: the main job of ``make demo``."""
from __future__ import annotations


def add_parser(sub):
    p = sub.add_parser('demo', help='run the demo search (what `make demo` runs)',
                       description='An offline search with the default human FPOC and ELM.')
    p.add_argument('--seed', type=int, default=0)
    p.set_defaults(run=run)


def run(args) -> int:
    from ipomdp_gaze.cli import main
    return main(['search', '--grid', '7x7', '--fpoc', 'human', '--policy', 'elm',
                 '--seed', str(args.seed)])
