# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
README's parameter tables against the nodes' declarations.

Each row of the ``gaze_controller`` and ``foveal_detector`` tables names parameters and their
defaults; every name must be declared by the node, every declared parameter must be in the
table, and each default must be the declared one.
"""
from __future__ import annotations

import math
import re

from conftest import REPO
import pytest
import yaml

pytestmark = pytest.mark.ros

TABLES = {'gaze_controller': ('controller', 'controller_params'),
          'foveal_detector': ('detector', 'detector_params')}


def _split(text: str) -> list[str]:
    """Split a defaults cell at its top-level commas (a list such as ``[1.0, 2.0]`` is one)."""
    parts, depth, start = [], 0, 0
    for i, char in enumerate(text):
        depth += {'[': 1, ']': -1}.get(char, 0)
        if char == ',' and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    return [p.strip() for p in parts + [text[start:]] if p.strip()]


def _value(token: str):
    """Read one default as README writes it: a number (``-pi/2`` too), bool, list or string."""
    token = token.strip('`')
    if token in ('true', 'false'):
        return token == 'true'
    if token == "''":
        return ''
    if token.startswith('['):
        return yaml.safe_load(token)
    match = re.fullmatch(r'(-?)pi(?:/(\d+))?', token)
    if match:
        return (-1 if match[1] else 1) * math.pi / int(match[2] or 1)
    try:
        return yaml.safe_load(token) if re.fullmatch(r'-?[\d.]+(e-?\d+)?', token) else token
    except yaml.YAMLError:
        return token


def readme_rows(node: str) -> list[tuple[list[str], list]]:
    """Return ``(names, defaults)`` of each row of README's ``Parameters (`node`)`` table."""
    lines = (REPO / 'README.md').read_text(encoding='utf-8').splitlines()
    start = lines.index(f'### Parameters (`{node}`)')
    rows, seen_table = [], False
    for line in lines[start + 1:]:
        if not line.startswith('|'):
            if seen_table:
                break
            continue
        seen_table = True
        cells = [c.strip() for c in line.strip('|').split('|')]
        if cells[0] in ('parameter', '---'):
            continue
        names = re.findall(r'`([a-z_.]+)`', cells[0])
        defaults = re.sub(r'\s*\(YAML:[^)]*\)', '', cells[1])
        rows.append((names, [_value(t) for t in _split(defaults)]))
    return rows


def _same(declared, documented) -> bool:
    if declared is None:                          # an array declared by type: empty
        declared = []
    if isinstance(declared, bool) or isinstance(documented, bool):
        return declared is documented
    if isinstance(declared, (int, float)) and isinstance(documented, (int, float)):
        return math.isclose(declared, documented, rel_tol=1e-12, abs_tol=1e-12)
    return declared == documented


@pytest.mark.parametrize('node', sorted(TABLES))
def test_the_readme_parameter_table_gives_each_declared_default(node):
    import importlib
    module, function = TABLES[node]
    declared = {p.name: p.default
                for p in getattr(importlib.import_module(f'ipomdp_gaze.nodes.{module}'),
                                 function)()}
    documented = {}
    for names, defaults in readme_rows(node):
        assert len(names) == len(defaults), (names, defaults)
        for name, default in zip(names, defaults):
            documented.setdefault(name, []).append(default)
    assert sorted(documented) == sorted(declared)
    for name, defaults in documented.items():
        stated = [d for d in defaults if d != 'none']    # a name stated again in another row
        assert stated and all(_same(declared[name], d) for d in stated), \
            (name, declared[name], defaults)
