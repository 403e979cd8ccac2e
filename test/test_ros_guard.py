# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The guard of the ROS tests (test/conftest.py), run on a small suite in a pytest of its own.

An rclpy that is installed but does not import fails the ROS tests instead of skipping them,
and with IPOMDP_GAZE_REQUIRE_ROS=<n> (`make test`) the run fails unless every collected ROS test
ran and at least n did, with or without pytest-xdist (`make test` runs ``-n <cores + 1>``: there
the controller process counts what its workers collected and ran).
"""
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

import pytest

HERE = Path(__file__).resolve().parent
SUITE = """
import pytest

pytestmark = pytest.mark.ros


def test_ros():
    pass


@pytest.mark.parametrize('skip', [False, SKIP])
def test_maybe(skip):
    if skip:
        pytest.skip('skipped on purpose')
"""
INI = '[pytest]\nmarkers =\n    ros: needs rclpy\n'


def run_suite(tmp_path, skip=False, require=None, broken=False, workers=0):
    """Run the two (or three) ROS tests of SUITE with this conftest; return rc and output."""
    shutil.copy(HERE / 'conftest.py', tmp_path / 'conftest.py')
    (tmp_path / 'pytest.ini').write_text(INI)
    (tmp_path / 'test_suite.py').write_text(SUITE.replace('SKIP', str(skip)))
    env = dict(os.environ)
    env.pop('IPOMDP_GAZE_REQUIRE_ROS', None)
    if require is not None:
        env['IPOMDP_GAZE_REQUIRE_ROS'] = str(require)
    paths = [str(HERE.parent)]
    if broken:   # an rclpy that is found but raises on import, as a build with a missing .so does
        fake = tmp_path / 'fake' / 'rclpy'
        fake.mkdir(parents=True)
        (fake / '__init__.py').write_text("raise ImportError('librcl.so: cannot open')\n")
        paths.insert(0, str(fake.parent))
    env['PYTHONPATH'] = os.pathsep.join(paths + [env.get('PYTHONPATH', '')])
    spread = ['-n', str(workers)] if workers else []
    out = subprocess.run([sys.executable, '-m', 'pytest', '-q', '-p', 'no:cacheprovider', '-rs',
                          *spread, 'test_suite.py'], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=300)
    return out.returncode, out.stdout + out.stderr


def test_a_broken_rclpy_fails_the_ros_tests_instead_of_skipping_them(tmp_path):
    rc, out = run_suite(tmp_path, broken=True)
    assert rc == 1, out
    assert re.search(r'^3 errors in [\d.]+s$', out, re.M), out    # no skip, no pass
    assert 'rclpy installed but broken: ImportError: librcl.so: cannot open' in out, out


@pytest.mark.parametrize('workers', [0, 2])
def test_with_rclpy_the_ros_tests_run_and_are_counted(tmp_path, workers):
    rc, out = run_suite(tmp_path, require=3, workers=workers)
    assert rc == 0, out
    assert '3 passed' in out and 'ROS tests: 3 of 3 ran' in out, out


@pytest.mark.parametrize('workers', [0, 2])
def test_a_required_run_fails_when_a_ros_test_skipped(tmp_path, workers):
    rc, out = run_suite(tmp_path, skip=True, require=1, workers=workers)
    assert rc == 1, out
    assert '2 passed, 1 skipped' in out, out
    assert 'IPOMDP_GAZE_REQUIRE_ROS=1: 2 of 3 collected ROS tests ran' in out, out
    if not workers:
        rc, out = run_suite(tmp_path, skip=True)     # not required: a skip is a skip
        assert rc == 0 and '2 passed, 1 skipped' in out, out


def test_a_required_run_fails_with_fewer_ros_tests_than_required(tmp_path):
    rc, out = run_suite(tmp_path, require=4)
    assert rc == 1, out
    assert '3 passed' in out and 'IPOMDP_GAZE_REQUIRE_ROS=4: 3 of 3 collected' in out, out
