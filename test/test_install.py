# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The package works from real installs, not only from the editable one in ``.venv``.

Each install is built from a clean copy of the files git knows (tracked, plus untracked files
that are not ignored; working-tree versions, symlinks kept as symlinks) in a temporary
directory, because a stale ``build/`` folder in a checkout silently packs old top-level
packages into a wheel. Three modes, one module-scoped fixture each:

* ``pip``: ``pip install <copy>[ros]`` (not editable) into a fresh venv;
* ``colcon``: ``colcon build`` of a workspace whose ``src`` holds the copy;
* ``colcon-symlink``: the same with ``--symlink-install``.

Everything runs with its working directory outside the checkout, so the source tree cannot
shadow the install. In each mode the CLI must answer ``--help`` and run a small ``evaluate``,
every module of the copy must import from the install (never from this checkout), the bare
top-level names ``policies`` and ``msg_adapters`` must not be importable, the shipped kernels
must resolve, the installed ``controller`` and ``camera`` must talk over real DDS and shut
down cleanly on SIGTERM, and so must the installed ``scene_camera`` and ``detector`` (which
find the shipped face model and the Haar cascade from the install). The colcon nodes are
started the way ``ros2 run`` does: after sourcing ``install/setup.bash``, look the package up
in the ament index and execute ``<prefix>/lib/ipomdp_gaze/<executable>``; a pip install has no
node executables on PATH (``ipomdp-gaze controller`` and the like run them).
"""
from dataclasses import dataclass
import json
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys

from conftest import wait_for
import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = 'ipomdp_gaze'
SUBCOMMANDS = ('evaluate', 'search', 'find', 'train', 'calibrate', 'reproduce', 'demo',
               'record', 'replay', 'controller', 'camera', 'detector', 'scene_camera')
EXECUTABLES = ('ipomdp-gaze', 'controller', 'camera', 'detector', 'scene_camera')
# The node executables (`ros2 run ipomdp_gaze <name>`): colcon installs them in lib/ipomdp_gaze;
# a pip install puts only `ipomdp-gaze` on PATH, whose subcommands run the nodes (issue 35: no
# generic command such as `camera` on the user's PATH).
NODE_EXECUTABLES = ('controller', 'camera', 'detector', 'scene_camera', 'recorder')
BARE_NAMES = ('policies', 'msg_adapters')
# Variables that would make a process find packages other than the install under test.
LEAKY_ENV = ('PYTHONPATH', 'PYTHONHOME', 'PYTHONSTARTUP', 'VIRTUAL_ENV', 'CMAKE_PREFIX_PATH')
# `ros2 run <package> <executable> [args]`: the executable in the ament index's package prefix.
ROS2RUN = (
    'import os, sys\n'
    'from ament_index_python.packages import get_package_prefix\n'
    'package, executable = sys.argv[1:3]\n'
    'path = os.path.join(get_package_prefix(package), "lib", package, executable)\n'
    'print("ros2run:", path, flush=True)\n'
    'os.execv(path, [path] + sys.argv[3:])\n')
# Run with the install's interpreter: import every module of the copy and report where from.
IMPORT_CHECK = (
    'import importlib, importlib.resources, importlib.util, json, sys\n'
    'files = {n: importlib.import_module(n).__file__ for n in json.loads(sys.argv[1])}\n'
    'from ipomdp_gaze.policies.policy_file import shipped_kernels\n'
    'from ipomdp_gaze.files.observation_file import MODEL_DIR, shipped_observations\n'
    'bare = {}\n'
    'for name in ("policies", "msg_adapters"):\n'
    '    spec = importlib.util.find_spec(name)\n'
    '    bare[name] = spec and str(spec.origin or spec.submodule_search_locations)\n'
    'kernel_dir = importlib.resources.files("ipomdp_gaze.policies").joinpath("kernels")\n'
    'print(json.dumps({"files": files, "bare": bare, "kernels": shipped_kernels(),\n'
    '                  "kernel_dir": str(kernel_dir), "models": shipped_observations(),\n'
    '                  "model_dir": str(MODEL_DIR)}))\n')


def clean_copy(dest: Path) -> Path:
    """
    Copy the files git knows into ``dest``: tracked and untracked-but-not-ignored ones.

    The working-tree version of each is copied (the lead's uncommitted changes included), a
    symlink as a symlink; a tracked file deleted in the working tree is left out.
    """
    names = set()
    for extra in ([], ['--others', '--exclude-standard']):
        out = subprocess.run(['git', 'ls-files', '-z', *extra], cwd=ROOT, capture_output=True,
                             check=True)
        names |= {n for n in out.stdout.decode().split('\0') if n}
    for name in sorted(names):
        src, dst = ROOT / name, dest / name
        if not os.path.lexists(src) or (src.is_dir() and not src.is_symlink()):
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        if src.is_symlink():
            os.symlink(os.readlink(src), dst)
        else:
            shutil.copy2(src, dst)
    return dest


def package_modules(copy: Path) -> list:
    """Names of every module of ``ipomdp_gaze`` in a copy (through its symlinked subpackages)."""
    names = []
    for folder, _, files in os.walk(copy / PACKAGE, followlinks=True):
        parts = Path(folder).relative_to(copy).parts
        if '__pycache__' in parts:
            continue
        for file in files:
            if file.endswith('.py') and file != '__main__.py':
                stem = file[:-3]
                names.append('.'.join(parts if stem == '__init__' else (*parts, stem)))
    return sorted(names)


def clean_env(path_first=None) -> dict:
    """Copy ``os.environ`` without anything that points Python or ROS at another install."""
    env = {k: v for k, v in os.environ.items()
           if k not in LEAKY_ENV and not k.startswith(('AMENT_', 'COLCON_'))}
    if path_first is not None:
        env['PATH'] = f'{path_first}{os.pathsep}{env.get("PATH", "")}'
    return env


def run(argv, cwd, env, timeout=900):
    """Run a command, fail with the tail of its output unless it exits 0."""
    out = subprocess.run([str(a) for a in argv], cwd=cwd, env=env, capture_output=True,
                         text=True, timeout=timeout)
    assert out.returncode == 0, f'{argv}:\n{out.stdout[-4000:]}\n{out.stderr[-4000:]}'
    return out


def is_inside(path, folder) -> bool:
    """Whether ``path`` is ``folder`` or below it (without resolving symlinks)."""
    return Path(os.path.abspath(path)).is_relative_to(os.path.abspath(folder))


@dataclass
class Install:
    """One real install of the package and how to run things from it."""

    mode: str
    prefix: Path          # the install prefix: share/ and the executables are under it
    root: Path            # every ipomdp_gaze module must be loaded from below here
    bin_dir: Path         # ipomdp-gaze and the node executables
    python: Path          # the interpreter the installed scripts use
    env: dict
    copy: Path            # the clean copy it was built from
    setup_bash: Path = None   # colcon: sourced before every command
    ros2run: Path = None      # colcon: the `ros2 run` stand-in

    @property
    def share(self) -> Path:
        """Return the package's share directory (package.xml, config, launch)."""
        return self.prefix / 'share' / PACKAGE

    def argv(self, *args) -> list:
        """Run ``args`` in the install's environment (colcon: in a sourced bash)."""
        args = [str(a) for a in args]
        if self.setup_bash is None:
            return args
        return ['bash', '-c', f'source "{self.setup_bash}" && exec "$@"', 'bash', *args]

    def run(self, *args, cwd, env=None, timeout=300):
        """Run ``args`` in the install's environment; the completed process."""
        return subprocess.run(self.argv(*args), cwd=cwd, env=env or self.env,
                              capture_output=True, text=True, timeout=timeout)

    def node_argv(self, executable: str, *ros_args) -> list:
        """Start an installed node: ``ros2 run``-style for colcon, ``ipomdp-gaze NODE`` (pip)."""
        if self.ros2run is not None:
            return self.argv(sys.executable, self.ros2run, PACKAGE, executable, '--ros-args',
                             *ros_args)
        return self.argv(self.bin_dir / 'ipomdp-gaze', executable, '--ros-args', *ros_args)

    @property
    def executables(self) -> tuple:
        """Return what the install puts in ``bin_dir``: the nodes only for ``ros2 run``."""
        return EXECUTABLES if self.ros2run is not None else ('ipomdp-gaze',)


@pytest.fixture(scope='module')
def pip_install(tmp_path_factory):
    """``pip install <copy>[ros]`` (not editable) into a fresh venv (pip's cache is reused)."""
    base = tmp_path_factory.mktemp('pip_install')
    copy = clean_copy(base / 'src')
    venv = base / 'venv'
    env = clean_env()
    run([sys.executable, '-m', 'venv', venv], cwd=base, env=env, timeout=300)
    python = venv / 'bin' / 'python'
    # --no-compile: no .pyc for the dependencies (numpy, scipy, rclpy...), about a third of the
    # install's time; nothing here depends on them, and Python compiles what it imports.
    run([python, '-m', 'pip', 'install', '--no-compile', f'{copy}[ros]'], cwd=base, env=env)
    purelib = run([python, '-c', 'import sysconfig; print(sysconfig.get_paths()["purelib"])'],
                  cwd=base, env=env).stdout.strip()
    return Install('pip', venv, Path(purelib) / PACKAGE, venv / 'bin', python,
                   clean_env(path_first=venv / 'bin'), copy)


def colcon_install(tmp_path_factory, mode: str, *options) -> Install:
    """``colcon build [options]`` of a fresh workspace whose src holds a clean copy."""
    colcon = Path(sys.executable).parent / 'colcon'
    # colcon is in the test extra: a test run without it is a broken install, not a skip.
    assert colcon.is_file(), 'colcon is not installed (pip install -e ".[test]")'
    ws = tmp_path_factory.mktemp(mode)
    copy = clean_copy(ws / 'src' / PACKAGE)
    env = clean_env(path_first=colcon.parent)
    run([colcon, 'build', '--base-paths', 'src', *options], cwd=ws, env=env, timeout=600)
    prefix = ws / 'install' / PACKAGE
    (ws / 'ros2run.py').write_text(ROS2RUN)
    if '--symlink-install' in options:
        root = ws / 'build' / PACKAGE / PACKAGE   # develop: build/<pkg> -> src/<pkg>/<pkg>
    else:
        root = prefix / 'lib' / f'python{sys.version_info[0]}.{sys.version_info[1]}' / \
            'site-packages' / PACKAGE
    return Install(mode, prefix, root, prefix / 'lib' / PACKAGE, Path(sys.executable), env,
                   copy, ws / 'install' / 'setup.bash', ws / 'ros2run.py')


@pytest.fixture(scope='module')
def colcon_plain(tmp_path_factory):
    """``colcon build`` of a workspace with the clean copy."""
    return colcon_install(tmp_path_factory, 'colcon')


@pytest.fixture(scope='module')
def colcon_symlink(tmp_path_factory):
    """``colcon build --symlink-install`` of a workspace with the clean copy."""
    return colcon_install(tmp_path_factory, 'colcon-symlink', '--symlink-install')


@pytest.fixture(scope='module', params=['pip', pytest.param('colcon', marks=pytest.mark.ros),
                                        pytest.param('colcon-symlink', marks=pytest.mark.ros)])
def install(request):
    """Each install mode in turn (tests are grouped by mode; the colcon ones are ROS tests)."""
    fixture = {'pip': 'pip_install', 'colcon': 'colcon_plain',
               'colcon-symlink': 'colcon_symlink'}[request.param]
    return request.getfixturevalue(fixture)


def test_install_has_executables_index_marker_and_share_files(install):
    for exe in install.executables:
        path = install.bin_dir / exe
        assert path.is_file() and os.access(path, os.X_OK), path
    if install.ros2run is None:                 # pip: nothing generic on the user's PATH
        assert not [n for n in NODE_EXECUTABLES if (install.bin_dir / n).exists()]
    marker = install.prefix / 'share' / 'ament_index' / 'resource_index' / 'packages' / PACKAGE
    assert marker.is_file(), marker
    shipped = ['package.xml'] + [p.relative_to(install.copy).as_posix() for p in
                                 (*sorted(install.copy.glob('config/*.yaml')),
                                  *sorted(install.copy.glob('config/*.xml')),
                                  *sorted(install.copy.glob('launch/*.launch.py')))]
    assert {'config/controller.yaml', 'config/camera.yaml', 'config/faces_fovea_detector.yaml',
            'config/faces_camera_scene_camera.yaml', 'config/fastdds_large_images.xml',
            'launch/faces_demo.launch.py'} <= \
        set(shipped)
    for name in shipped:
        assert (install.share / name).is_file(), install.share / name


def test_help_lists_every_subcommand(install, tmp_path):
    out = install.run(install.bin_dir / 'ipomdp-gaze', '--help', cwd=tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    for command in SUBCOMMANDS:
        assert command in out.stdout, f'{command} missing from --help:\n{out.stdout}'


def test_evaluate_runs_and_writes_json(install, tmp_path):
    out = install.run(install.bin_dir / 'ipomdp-gaze', 'evaluate', '--grid', '5x5', '--policy',
                      'map', '--policy', 'elm', '--episodes', '200', '--seed', '0', '--json',
                      'out.json', cwd=tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    result = json.loads((tmp_path / 'out.json').read_text())
    assert set(result['policies']) == {'map', 'elm'}
    for name, policy in result['policies'].items():
        value = policy['fixations_to_90']
        assert isinstance(value, (int, float)) and not isinstance(value, bool), (name, value)


def test_the_image_tasks_run_from_the_install(install, tmp_path):
    """The shipped models, YuNet, the photo labels and the face configs are found installed."""
    import cv2
    from skimage import data
    rgb = data.astronaut()
    cv2.imwrite(str(tmp_path / 'astronaut.png'), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    cli = install.bin_dir / 'ipomdp-gaze'
    out = install.run(cli, 'find', 'astronaut.png', '--observation', 'faces-420', '--json',
                      'faces-420.json', cwd=tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    entry = json.loads((tmp_path / 'faces-420.json').read_text())['images'][0]
    assert entry['decision'] == 'found' and entry['cell'] == [4, 9], entry
    out = install.run(cli, 'find', 'astronaut.png', '--json', 'default.json', cwd=tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr         # the default: YuNet's models
    assert 'shipped observation model faces-420-yunet ' in out.stderr, out.stderr
    entry = json.loads((tmp_path / 'default.json').read_text())['images'][0]
    # the default --scan coarse answers the box centre's cell (the fovea above: its belief's)
    assert entry['decision'] == 'found' and entry['method'] == 'scales', entry
    assert max(abs(entry['cell'][0] - 4), abs(entry['cell'][1] - 9)) <= 1, entry
    out = install.run(cli, 'evaluate', '--scenes', 'pan-tilt', '--episodes', '1',
                      '--max-fixations', '3', '--jobs', '1', '--quiet', cwd=tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    assert 'pan-tilt (1 scene with a face): right' in out.stdout
    # The ensemble detector by its entry point, and its model (two cascades and YuNet) installed.
    out = install.run(install.python, '-c', 'from importlib.metadata import entry_points; '
                      "print(sorted(e.name for e in entry_points(group='ipomdp_gaze.detectors')));"
                      'from ipomdp_gaze.vision.photos import read_labels; '
                      'print(len(read_labels()))', cwd=tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    detectors, labels = out.stdout.splitlines()[-2:]
    assert "'ensemble'" in detectors and int(labels) >= 21, out.stdout
    out = install.run(cli, 'evaluate', '--scenes', 'pan-tilt', '--scene-model',
                      'faces-pan-tilt-ensemble', '--episodes', '1', '--max-fixations', '3',
                      '--jobs', '1', '--quiet', cwd=tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    assert 'pan-tilt (1 scene with a face): right' in out.stdout


def test_every_module_imports_from_the_install_and_bare_names_do_not(install, tmp_path):
    modules = package_modules(install.copy)
    assert {PACKAGE, f'{PACKAGE}.policies', f'{PACKAGE}.msg_adapters', f'{PACKAGE}.nodes',
            f'{PACKAGE}.commands', f'{PACKAGE}.policies.policy_file'} <= set(modules)
    out = install.run(install.python, '-c', IMPORT_CHECK, json.dumps(modules), cwd=tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    report = json.loads(out.stdout.splitlines()[-1])
    outside = {name: file for name, file in report['files'].items()
               if not is_inside(file, install.root)}
    assert not outside, f'modules not loaded from {install.root}: {outside}'
    from_checkout = {name: file for name, file in report['files'].items()
                     if is_inside(Path(file).resolve(), ROOT)}
    assert not from_checkout, f'modules loaded from the checkout {ROOT}: {from_checkout}'
    assert report['bare'] == dict.fromkeys(BARE_NAMES), \
        f'bare top-level names importable: {report["bare"]}'
    kernels = sorted(p.stem for p in (install.copy / 'policies' / 'kernels').glob('*.yaml'))
    assert 'human-7x7-infomax' in report['kernels']
    assert report['kernels'] == kernels
    assert is_inside(report['kernel_dir'], install.root), report['kernel_dir']
    models = sorted(p.stem for p in (install.copy / 'ipomdp_gaze' / 'models').glob('*.yaml'))
    assert 'faces-420' in report['models'] and report['models'] == models
    assert is_inside(report['model_dir'], install.root), report['model_dir']


class Node:
    """An installed node in its own process; output in a log file; SIGTERM to stop."""

    def __init__(self, install, executable, namespace, env, log_dir, config=None, extra=()):
        config = install.share / 'config' / (config or f'{executable}.yaml')
        self.name = executable
        self.log = log_dir / f'{executable}.log'
        with open(self.log, 'wb') as out:
            self.proc = subprocess.Popen(
                install.node_argv(executable, '-r', f'__ns:={namespace}', '--params-file',
                                  config, *extra),
                cwd=log_dir, env=env, stdout=out, stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL)

    def output(self) -> str:
        """Return the end of what the node printed."""
        return self.log.read_text(errors='replace')[-3000:]

    def stop(self, timeout_s: float = 20.0) -> int:
        """SIGTERM, then SIGKILL after ``timeout_s``; the exit status."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout_s)
        return self.proc.returncode


@pytest.mark.ros
def test_installed_controller_and_camera_talk_over_dds(install, ros_env, probe, tmp_path):
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float32MultiArray
    params = yaml.safe_load((install.share / 'config' / 'controller.yaml').read_text())
    grid = params['/**/gaze_controller']['ros__parameters']['grid']
    n_cells = grid['rows'] * grid['cols']
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    namespace = '/install_check_' + install.mode.replace('-', '_')
    pan_tilt = probe.record(JointState, f'{namespace}/pan_tilt', latched)
    beliefs = probe.record(Float32MultiArray, f'{namespace}/belief', 10)
    env = dict(install.env)
    env.pop('ROS_LOCALHOST_ONLY', None)
    env.update({k: v for k, v in ros_env.items() if k.startswith('ROS_')})
    env['PYTHONUNBUFFERED'] = '1'

    def applied():
        # The prior is uniform; a belief that is not came from a frame the controller applied.
        return [m for _, m in beliefs if len(m.data) == n_cells and max(m.data) > min(m.data)]

    nodes = [Node(install, 'controller', namespace, env, tmp_path)]
    try:
        assert wait_for(lambda: pan_tilt or nodes[0].proc.poll() is not None, 60) and pan_tilt, \
            f'no pan_tilt from the installed controller:\n{nodes[0].output()}'
        msg = pan_tilt[-1][1]
        assert len(msg.position) == 2 and len(msg.name) == 2, msg
        nodes.append(Node(install, 'camera', namespace, env, tmp_path))
        assert wait_for(lambda: applied() or any(n.proc.poll() is not None for n in nodes), 60) \
            and applied(), 'no belief after an applied frame:\n' + \
            '\n'.join(f'--- {n.name}\n{n.output()}' for n in nodes)
        if install.ros2run is not None:
            for node in nodes:
                assert f'ros2run: {install.bin_dir / node.name}\n' in node.log.read_text(), \
                    node.output()
    finally:
        codes = {node.name: node.stop() for node in nodes}
    assert codes == {'controller': 0, 'camera': 0}, f'exit status {codes}:\n' + \
        '\n'.join(f'--- {n.name}\n{n.output()}' for n in nodes)


@pytest.mark.ros
def test_installed_scene_camera_and_detector_serve_a_fixation(install, ros_env, probe, tmp_path):
    from ipomdp_gaze.harness.watch import LATCHED
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.msg_adapters import grid_arrays, images
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import Image
    from std_msgs.msg import Int32MultiArray
    namespace = '/install_faces_' + install.mode.replace('-', '_')
    frames = probe.record(Image, f'{namespace}/evidence_image',
                          QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
    grid = Grid(21, 21)
    probe.publisher(Int32MultiArray, f'{namespace}/fixation', LATCHED).publish(
        grid_arrays.row_col(grid, grid.index(10, 10)))
    env = dict(install.env)
    env.pop('ROS_LOCALHOST_ONLY', None)
    env.update({k: v for k, v in ros_env.items() if k.startswith('ROS_')})
    env['PYTHONUNBUFFERED'] = '1'
    # In a namespace the files' node blocks do not apply: the modes are given here.
    nodes = [Node(install, 'detector', namespace, env, tmp_path, 'faces_fovea_detector.yaml',
                  ['-p', 'mode:=fovea']),
             Node(install, 'scene_camera', namespace, env, tmp_path,
                  'faces_fovea_scene_camera.yaml', ['-p', 'view:=fixed', '-p', 'rate_hz:=5.0'])]
    try:
        assert wait_for(lambda: frames or any(n.proc.poll() is not None for n in nodes), 90) \
            and frames, 'no evidence_image from the installed detector:\n' + \
            '\n'.join(f'--- {n.name}\n{n.output()}' for n in nodes)
        counts = images.evidence_from_image(frames[0][1], grid)
        seen = ~np.isnan(counts)             # faces-420: the windows around (10, 10), else NaN
        assert seen[grid.index(10, 10)] and (counts[seen] >= 0).all()
    finally:
        codes = {node.name: node.stop() for node in nodes}
    assert codes == {'detector': 0, 'scene_camera': 0}, f'exit status {codes}:\n' + \
        '\n'.join(f'--- {n.name}\n{n.output()}' for n in nodes)


def test_a_user_or_prefix_install_finds_its_shared_files(tmp_path, monkeypatch):
    """QA: pip install --user or --prefix put share/ipomdp_gaze where nothing looked."""
    import importlib.metadata as metadata
    from ipomdp_gaze.files import share_files
    site = tmp_path / 'pfx' / 'lib' / 'python3.11' / 'site-packages'
    info = site / 'ipomdp_gaze-0.2.0.dist-info'
    info.mkdir(parents=True)
    (info / 'METADATA').write_text('Metadata-Version: 2.1\nName: ipomdp_gaze\nVersion: 0.2.0\n')
    share = tmp_path / 'pfx' / 'share' / 'ipomdp_gaze'
    (share / 'config').mkdir(parents=True)
    (share / 'package.xml').write_text('<package/>\n')
    (share / 'config' / 'only_here.yaml').write_text('a: 1\n')
    (info / 'RECORD').write_text('../../../share/ipomdp_gaze/package.xml,,\n'
                                 '../../../share/ipomdp_gaze/config/only_here.yaml,,\n')
    package = site / 'ipomdp_gaze'
    package.mkdir()
    (package / '__init__.py').write_text('')
    (package / 'files').mkdir()
    monkeypatch.setattr(metadata, 'distribution', lambda name: metadata.PathDistribution(info))
    monkeypatch.setattr(share_files, '__file__', str(package / 'files' / 'share_files.py'))
    monkeypatch.setenv('AMENT_PREFIX_PATH', '')
    assert share_files.config_file('only_here.yaml') == share / 'config' / 'only_here.yaml'
    # a record of another copy (this code runs from elsewhere) is not used
    monkeypatch.setattr(share_files, '__file__', str(tmp_path / 'checkout' / 'ipomdp_gaze' /
                                                     'files' / 'share_files.py'))
    assert share_files.installed_share() is None
