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
    installed = installed_share()
    return dirs + ([installed] if installed is not None else []) + [SOURCE_ROOT]


def installed_share() -> Path | None:
    """
    Return the ``share/ipomdp_gaze`` folder the installed distribution recorded, or None.

    ``pip install --user`` or ``--prefix`` puts it under that scheme's data folder, which is
    neither ``sys.prefix`` nor on ``AMENT_PREFIX_PATH``; the distribution's RECORD names it
    (relative to site-packages). An editable install records none, and a distribution that is
    not this code (an old ``--user`` copy beside a checkout run from source) is not used.
    """
    from importlib.metadata import distribution, PackageNotFoundError
    try:
        dist = distribution(PACKAGE)
    except PackageNotFoundError:
        return None
    own = Path(__file__).resolve().parents[1] / '__init__.py'
    if Path(dist.locate_file(f'{PACKAGE}/__init__.py')).resolve() != own:
        return None                             # another copy's record, not this code's
    for file in dist.files or ():
        if file.name == 'package.xml' and file.parent.name == PACKAGE \
                and file.parent.parent.name == 'share':
            return Path(dist.locate_file(file)).resolve().parent
    return None


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
