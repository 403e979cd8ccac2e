# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Where the package's shared files (config YAML, launch files) are found, and its version.

A colcon or pip install puts them under ``<prefix>/share/ipomdp_gaze``; an editable install has no
``share/`` tree, so the source tree is the fallback (docs/design.md section 5).
"""
from __future__ import annotations

import os
from pathlib import Path
import sys

PACKAGE = 'ipomdp_gaze'
SOURCE_ROOT = Path(__file__).resolve().parents[2]


def share_dirs() -> list[Path]:
    """Candidate ``share/ipomdp_gaze`` directories, most specific first."""
    prefixes = [Path(p) for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    dirs = [p / 'share' / PACKAGE for p in prefixes + [Path(sys.prefix)]]
    return dirs + [SOURCE_ROOT]


def config_file(name: str) -> Path:
    """
    Path of ``config/<name>`` (for example ``controller.yaml``).

    Raises
    ------
    FileNotFoundError
        Listing the places searched.

    """
    searched = [d / 'config' / name for d in share_dirs()]
    for path in searched:
        if path.is_file():
            return path
    raise FileNotFoundError(f'config file {name!r} not found; searched '
                            + ', '.join(str(p) for p in searched))


def package_version() -> str:
    """Return the installed package's version (``setup.py``), or ``unknown`` without metadata."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version('ipomdp_gaze')
    except PackageNotFoundError:
        return 'unknown'
