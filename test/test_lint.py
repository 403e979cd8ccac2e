# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The standard ament linters (flake8 and pep257 with the ament configuration) as tests.

Each runs in a fresh interpreter: flake8 forks worker processes, and a fork of a pytest worker
that earlier ROS tests left with DDS threads can crash in the child (seen as segmentation
faults of flake8's workers, which the pool then restarts without end).
"""
from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
PATHS = [str(ROOT / p) for p in ('ipomdp_gaze', 'policies', 'msg_adapters', 'test', 'bench',
                                 'launch', 'examples', 'setup.py') if (ROOT / p).exists()]


def _lint(module: str) -> subprocess.CompletedProcess:
    code = f'import sys; from {module}.main import main; sys.exit(main(argv=sys.argv[1:]))'
    return subprocess.run([sys.executable, '-c', code, *PATHS], capture_output=True, text=True,
                          cwd=ROOT)


@pytest.mark.linter
def test_flake8():
    run = _lint('ament_flake8')
    assert run.returncode == 0, f'Found code style errors / warnings:\n{run.stdout}{run.stderr}'


@pytest.mark.linter
def test_pep257():
    run = _lint('ament_pep257')
    assert run.returncode == 0, f'Found docstring style errors:\n{run.stdout}{run.stderr}'
