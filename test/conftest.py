# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Shared fixtures; the ROS ones run real nodes over real DDS, isolated per test run.

Every run gets its own ``ROS_DOMAIN_ID`` (1..101, reserved with a lock file so that two runs at
once never share one: :func:`ipomdp_gaze.harness.processes.domain_id_for`), discovery
limited to this host and node log files in a temporary directory. Nodes under test run as
separate processes (as a user runs them, :class:`ipomdp_gaze.harness.processes.NodeGroup`); the
test's own node (``probe``, an :class:`ipomdp_gaze.harness.watch.Watch`) spins a
``SingleThreadedExecutor`` in a thread with a stop flag and is joined at teardown (ROS_NOTES.md
section 7). The demo and the benches watch their nodes the same way.
"""
from __future__ import annotations

import importlib.util
import os
from pathlib import Path
import signal
import sys
from types import SimpleNamespace

from hypothesis import settings
from ipomdp_gaze.harness.processes import wait_for  # noqa: F401 (the tests import it from here)
import pytest

# Property tests: the same examples on every CI run (CI=1), fresh ones on a developer's machine.
settings.register_profile('ci', derandomize=True, deadline=None, print_blob=True)
if os.environ.get('CI'):
    settings.load_profile('ci')

# A run started in the background by a shell without job control (`make test &`, nohup) has
# SIGINT ignored, and every process it starts inherits that. The Ctrl-C tests send SIGINT as a
# terminal does, to processes that take it as a terminal's do: give them the default back.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def _import_error(name: str):
    """
    Return ``None`` when module ``name`` imports, ``False`` when it is not installed at all.

    An installed module that fails to import (any exception, a missing library of its own
    included) returns that exception: the tests that need it then fail instead of skipping.
    """
    try:
        if importlib.util.find_spec(name.split('.')[0]) is None:
            return False
        importlib.import_module(name)
    except Exception as exc:  # noqa: B902 (an installed but broken package, whatever it raises)
        return exc
    return None


# The `ros` extra: rclpy and the message packages. A test marked `ros` (pytest.ini) needs them:
# not installed, it is skipped (a run without the extra); installed but broken, it fails; and
# with IPOMDP_GAZE_REQUIRE_ROS=<n> set (`make test`, so CI) a skip is an error too, and the run
# fails unless every collected `ros` test ran and at least n did.
RCLPY_ERROR = _import_error('rclpy')
ROS_MSGS_ERROR = _import_error('std_msgs.msg')
HAVE_RCLPY = RCLPY_ERROR is None
HAVE_ROS_MSGS = ROS_MSGS_ERROR is None
REQUIRE_ROS = os.environ.get('IPOMDP_GAZE_REQUIRE_ROS', '')
REPO = Path(__file__).resolve().parents[1]


def require_extra(name: str, extra: str):
    """
    Import module ``name`` of an optional extra, for a test module that needs it.

    Not installed: the module is skipped, or fails with IPOMDP_GAZE_REQUIRE_ROS set (`make test`
    installs every extra). Installed but broken: the import error fails the module.
    """
    error = _import_error(name)
    if error is False:
        why = f'{name} is not installed (pip install -e ".[{extra}]")'
        if REQUIRE_ROS:
            pytest.fail(f'{why}; IPOMDP_GAZE_REQUIRE_ROS is set', pytrace=False)
        pytest.skip(why, allow_module_level=True)
    return importlib.import_module(name)


def _ros_missing():
    """Say why the `ros` tests cannot run here, or return ``None``."""
    for name, error in (('rclpy', RCLPY_ERROR), ('the ROS message packages', ROS_MSGS_ERROR)):
        if error is False:
            return f'{name} not installed (pip install -e ".[ros]")'
        if error is not None:
            return f'{name} installed but broken: {type(error).__name__}: {error}'
    return None


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(items):
    """Mark `ros` every test that uses the ROS fixtures, so that it is counted (before -m)."""
    for item in items:
        if 'ros_env' in getattr(item, 'fixturenames', ()) and not item.get_closest_marker('ros'):
            item.add_marker(pytest.mark.ros)


def pytest_runtest_setup(item):
    """Skip a `ros` test without the `ros` extra; fail it when the extra is broken or required."""
    if item.get_closest_marker('ros') is None:
        return
    why = _ros_missing()
    if why is None:
        return
    if REQUIRE_ROS or 'broken' in why:
        pytest.fail(f'a ROS test cannot run: {why}' +
                    (' (IPOMDP_GAZE_REQUIRE_ROS is set)' if REQUIRE_ROS else ''), pytrace=False)
    pytest.skip(why)


class _RosCount:
    """The `ros` tests collected and those that ran (their test body was called)."""

    collected: set = set()
    ran: set = set()
    problem = ''


def pytest_collection_finish(session):
    """Count the `ros` tests that will run (after -m / -k selection)."""
    _RosCount.collected = {item.nodeid for item in session.items if item.get_closest_marker('ros')}


def pytest_runtest_logreport(report):
    """
    Count a `ros` test whose body ran, passed or failed (a skip is not a run).

    Under pytest-xdist (`make test` runs ``-n <cores + 1>``) this runs in the controller too,
    which collects nothing: there the report's keywords say it is a `ros` test.
    """
    if report.when == 'call' and not report.skipped and (
            report.nodeid in _RosCount.collected or 'ros' in report.keywords):
        _RosCount.ran.add(report.nodeid)


def _is_xdist_worker(config) -> bool:
    return hasattr(config, 'workeroutput')


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    """Under pytest-xdist: the controller learns what each worker collected."""
    _RosCount.collected |= set(getattr(node, 'workeroutput', {}).get('ros_collected', ()))


def pytest_sessionfinish(session, exitstatus):
    """With IPOMDP_GAZE_REQUIRE_ROS=<n>: every collected `ros` test ran, and at least n did."""
    if _is_xdist_worker(session.config):
        session.config.workeroutput['ros_collected'] = sorted(_RosCount.collected)
        return
    if not REQUIRE_ROS or exitstatus == pytest.ExitCode.INTERRUPTED:
        return
    least = int(REQUIRE_ROS)
    ran, collected = len(_RosCount.ran), len(_RosCount.collected)
    if ran < collected or ran < least:
        _RosCount.problem = (f'IPOMDP_GAZE_REQUIRE_ROS={least}: {ran} of {collected} collected '
                             f'ROS tests ran (at least {least} must, and all that were collected)')
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


def pytest_terminal_summary(terminalreporter):
    """Report how many `ros` tests ran, and the failed count check."""
    if _is_xdist_worker(terminalreporter.config):
        return
    if REQUIRE_ROS or _RosCount.collected:
        terminalreporter.write_line(
            f'ROS tests: {len(_RosCount.ran)} of {len(_RosCount.collected)} ran')
    if _RosCount.problem:
        terminalreporter.write_line(_RosCount.problem, red=True, bold=True)


@pytest.fixture(scope='session')
def ros_env(tmp_path_factory):
    """Environment of an isolated ROS run; this process uses it too (set before rclpy.init)."""
    why = _ros_missing()
    if why is not None:      # a test that reaches it late (getfixturevalue) and is not marked
        pytest.fail(f'this fixture needs ROS (mark the test `ros`): {why}', pytrace=False)
    from ipomdp_gaze.harness.processes import domain_id_for, ros_environment
    env = ros_environment(domain_id_for(), tmp_path_factory.mktemp('ros_log'))
    keys = ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOG_DIR', 'ROS_LOCALHOST_ONLY')
    saved = {k: os.environ.get(k) for k in keys}
    for k in keys:
        if k in env:
            os.environ[k] = env[k]
        else:
            os.environ.pop(k, None)
    yield env
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


@pytest.fixture
def context(ros_env):
    """Provide an rclpy context of its own on this run's domain, for in-process nodes."""
    import rclpy
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=int(ros_env['ROS_DOMAIN_ID']), args=[])
    yield ctx
    rclpy.try_shutdown(context=ctx)


@pytest.fixture(scope='module')
def probe(ros_env):
    """Provide the test's own node (a ``Watch``) on this run's domain, shared by a module."""
    from ipomdp_gaze.harness.watch import Watch
    with Watch(int(ros_env['ROS_DOMAIN_ID']), 'test_probe') as watch:
        yield watch


@pytest.fixture(scope='module')
def nodes(ros_env, tmp_path_factory):
    """
    Provide the node processes of a module (a ``NodeGroup``; ``nodes.start`` starts one).

    At teardown every process not killed on purpose gets SIGTERM and must exit with status 0
    (a clean shutdown).
    """
    from ipomdp_gaze.harness.processes import NodeGroup
    group = NodeGroup(ros_env, tmp_path_factory.mktemp('node_output'))
    yield group
    bad = group.close()
    assert not bad, 'nodes did not shut down cleanly:\n' + '\n'.join(bad)


@pytest.fixture(scope='module')
def launch(nodes):
    """Provide ``nodes.start``, which starts a node process (``controller`` or ``camera``)."""
    return nodes.start


def bench_module(name: str):
    """Load a bench script as a module, its folder on the path as when it runs as a script."""
    path = next((Path(__file__).resolve().parents[1] / 'bench').rglob(f'{name}.py'))
    if str(path.parent) not in sys.path:
        sys.path.insert(0, str(path.parent))
    spec = importlib.util.spec_from_file_location(f'bench_{name}', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def config_path(name: str) -> str:
    """Find a shipped config file as the nodes do."""
    from ipomdp_gaze.files.share_files import config_file
    return str(config_file(name))


def offline_room(seed: int, faces: int, label: str = 'pass-many-cells'):
    """
    Run the offline pass on room 0 of ``seed`` with ``faces`` faces, as the scene camera shows it.

    Return the task, the session's outcome and its people (``drivers.rooms.room_session``;
    ``label`` a room searcher, ``pass-many-cells:parameter=value,...`` for other settings).
    """
    from ipomdp_gaze.drivers.rooms import room_session
    from ipomdp_gaze.drivers.scene_tasks import SceneTask, task_spec
    spec = task_spec('pan-tilt', seed=seed, faces=faces)
    task = SceneTask.get(spec)
    task.sensor.start(task.scene(0).image)
    _, outcome, _, people = room_session(spec, task, 0, label)
    return task, outcome, people


def start_room(probe, nodes, seed: int, faces: int, node: str = 'gaze_controller',
               extra: tuple = ()) -> dict:
    """
    Start the rooms' three nodes (shipped pan/tilt configs, the rooms' overlays) on one room.

    The controller first (dwell 0.3 s, no re-check, ``extra`` more arguments), then the detector
    and the scene camera on room 0 of ``seed`` with ``faces`` faces. Return the probe's records
    (``targets``, ``cells``, ``done``, ``pan_tilt``) and the ``controller`` and ``detector``
    processes.
    """
    from diagnostic_msgs.msg import DiagnosticStatus
    from geometry_msgs.msg import PoseArray
    from ipomdp_gaze.harness.watch import LATCHED
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float32MultiArray
    rec = {'targets': probe.record(PoseArray, f'/{node}/targets', LATCHED),
           'cells': probe.record(Float32MultiArray, f'/{node}/target_cells', LATCHED),
           'done': probe.record(DiagnosticStatus, 'room_done', 10),
           'pan_tilt': probe.record(JointState, 'pan_tilt', LATCHED, distinct_stamps=True)}
    rec['controller'] = nodes.start('controller', [
        '--params-file', config_path('faces_camera_controller.yaml'),
        '--params-file', config_path('faces_camera_room_controller.yaml'),
        '-p', 'room.dwell_s:=0.3', '-p', 'room.recheck_period_s:=0.0', *extra])
    assert wait_for(lambda: rec['pan_tilt'], 60), rec['controller'].output()
    rec['detector'] = nodes.start('detector', [
        '--params-file', config_path('faces_camera_detector.yaml'),
        '--params-file', config_path('faces_camera_room_detector.yaml')])
    nodes.start('scene_camera', ['--params-file', config_path('faces_camera_scene_camera.yaml'),
                                 '-p', f'seed:={seed}', '-p', f"scene.faces:='{faces}'"])
    return rec


def people_controller_args(keep_probability: float, *extra: str) -> list[str]:
    """Return the arguments of a controller following moving people (``extra``: more ``-p``)."""
    return ['--params-file', config_path('controller.yaml'), '-p', 'search.targets:=many',
            '-p', 'absent.prior:=0.3', '-p', 'motion.sigma_cells:=0.3',
            '-p', 'motion.leave_prob:=0.05', '-p', 'motion.track_view:=peak',
            '-p', f'motion.keep_probability:={keep_probability}', '-p', 'motion.dwell_s:=1.0',
            '-p', 'diagnostics_period_s:=0.2', *extra]


@pytest.fixture
def cli_here(capsys, monkeypatch):
    """
    Run ``ipomdp-gaze ARGS`` in this process; return its ``returncode``, ``stdout`` and ``stderr``.

    The console script's own entry point (:func:`ipomdp_gaze.cli.main`) without an interpreter
    start-up per run, for tests not about the process itself; a refusal while parsing is its
    exit status. ``cwd`` runs it from that folder.
    """
    from ipomdp_gaze.cli import main

    def run(*args, cwd=None):
        if cwd is not None:
            monkeypatch.chdir(cwd)
        capsys.readouterr()
        try:
            code = main([str(a) for a in args])
        except SystemExit as exc:
            code = exc.code
        out = capsys.readouterr()
        return SimpleNamespace(returncode=code, stdout=out.out, stderr=out.err)
    return run


@pytest.fixture
def run_find(cli_here):
    """Run ``ipomdp-gaze find ARGS`` in this process (:func:`cli_here`)."""
    return lambda *args, cwd=None: cli_here('find', *args, cwd=cwd)
