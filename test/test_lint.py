# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The standard ament linters (flake8 and pep257 with the ament configuration) as tests."""
from pathlib import Path

from ament_flake8.main import main_with_errors as flake8_main
from ament_pep257.main import main as pep257_main
import pytest

ROOT = Path(__file__).resolve().parents[1]
PATHS = [str(ROOT / p) for p in ('ipomdp_gaze', 'policies', 'msg_adapters', 'test', 'bench',
                                 'launch', 'examples', 'setup.py') if (ROOT / p).exists()]


@pytest.mark.linter
def test_flake8():
    rc, errors = flake8_main(argv=PATHS)
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)


@pytest.mark.linter
def test_pep257():
    rc = pep257_main(argv=PATHS)
    assert rc == 0, 'Found docstring style errors'
