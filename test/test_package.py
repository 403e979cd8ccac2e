# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
ROS package conformance: package.xml, installed files, one import namespace, licence headers.

Everything installs under the one namespace ``ipomdp_gaze``: ``policies/`` and ``msg_adapters/``
are reached only as ``ipomdp_gaze.policies`` and ``ipomdp_gaze.msg_adapters`` (through the
committed symlinks), and the model core and the policies import nothing from ROS.
"""
import ast
import json
import os
from pathlib import Path
import re
import subprocess
import sys

from catkin_pkg.package import parse_package
from setuptools._distutils.core import run_setup

ROOT = Path(__file__).resolve().parents[1]
SOURCE_DIRS = ('ipomdp_gaze', 'policies', 'msg_adapters', 'test', 'bench', 'launch', 'examples')
# Python modules that come from ROS packages (and must be exec_depends when imported).
ROS_PACKAGES = {'rclpy', 'std_msgs', 'sensor_msgs', 'std_srvs', 'diagnostic_msgs',
                'trajectory_msgs', 'geometry_msgs', 'rcl_interfaces', 'builtin_interfaces',
                'ament_index_python', 'visualization_msgs'}
# Top-level names that exist only in the source tree; installed, they are ipomdp_gaze.<name>.
BARE_NAMES = {'policies', 'msg_adapters'}
HEADER = re.compile(r'# Copyright 20\d\d ipomdp_gaze developers\n'
                    r'# SPDX-License-Identifier: Apache-2.0\n')


def python_files():
    files = [ROOT / 'setup.py']
    for folder in SOURCE_DIRS:
        files += sorted((ROOT / folder).rglob('*.py')) if (ROOT / folder).is_dir() else []
    return files


def test_package_xml_is_valid_format3_ament_python():
    package = parse_package(str(ROOT / 'package.xml'))
    package.validate()
    assert package.package_format == 3
    assert package.name == 'ipomdp_gaze'
    assert package.licenses == ['Apache-2.0']
    assert package.get_build_type() == 'ament_python'


def test_every_imported_ros_package_is_an_exec_depend():
    package = parse_package(str(ROOT / 'package.xml'))
    declared = {dep.name for dep in package.exec_depends}
    imported = set()
    for path in python_files():
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            imported |= {name.split('.')[0] for name in names} & ROS_PACKAGES
    assert imported <= declared, f'imported but not exec_depend: {sorted(imported - declared)}'


def test_setup_installs_marker_package_xml_config_launch_and_kernels(monkeypatch):
    monkeypatch.chdir(ROOT)         # setup.py globs its data files relative to the cwd
    dist = run_setup(str(ROOT / 'setup.py'), script_args=[], stop_after='init')
    installed = {dest: {Path(f).as_posix() for f in files} for dest, files in dist.data_files}
    assert 'resource/ipomdp_gaze' in installed['share/ament_index/resource_index/packages']
    assert 'package.xml' in installed['share/ipomdp_gaze']
    for dest, folder, patterns in (('config', 'config', ('*.yaml', '*.xml')),
                                   ('launch', 'launch', ('*.launch.py',))):
        expected = {p.relative_to(ROOT).as_posix() for pattern in patterns
                    for p in (ROOT / folder).glob(pattern)}
        assert expected == installed.get(f'share/ipomdp_gaze/{dest}', set()), dest
    # Kernels are package data of ipomdp_gaze.policies (importlib.resources), not share/ files.
    assert 'share/ipomdp_gaze/kernels' not in installed
    assert dist.package_data == {'ipomdp_gaze.policies': ['kernels/*.yaml'],
                                 'ipomdp_gaze': ['models/*.yaml', 'data/*.csv']}
    # The shipped detectors are entry points too, pointing where the factory finds them.
    from ipomdp_gaze.vision.detectors import BUILTIN, ENTRY_POINT_GROUP
    declared = dict(line.replace(' ', '').split('=')
                    for line in dist.entry_points[ENTRY_POINT_GROUP])
    assert declared == BUILTIN
    assert list((ROOT / 'ipomdp_gaze' / 'policies').glob('kernels/*.yaml'))
    packages = set(dist.packages)
    assert {'ipomdp_gaze', 'ipomdp_gaze.policies', 'ipomdp_gaze.msg_adapters',
            'ipomdp_gaze.nodes', 'ipomdp_gaze.commands'} <= packages
    assert not {p for p in packages if p.split('.')[0] in BARE_NAMES}, sorted(packages)
    # Every package directory reachable as ipomdp_gaze.* (through the symlinks) is installed.
    found = {Path(folder).relative_to(ROOT).as_posix().replace('/', '.')
             for folder, _, files in os.walk(ROOT / 'ipomdp_gaze', followlinks=True)
             if '__init__.py' in files}
    assert found <= packages, f'packages left out of the install: {sorted(found - packages)}'
    assert (ROOT / 'resource' / 'ipomdp_gaze').is_file()
    # Console scripts: ipomdp-gaze; the nodes only for colcon's `setup.py install` / `develop`
    # (they go to lib/ipomdp_gaze for `ros2 run`), never in a wheel, whose scripts land on
    # the user's PATH (issue 35: no generic `camera` or `controller` there).
    assert dist.entry_points['console_scripts'] == ['ipomdp-gaze = ipomdp_gaze.cli:main']
    nodes = {'controller', 'camera', 'detector', 'scene_camera', 'recorder'}
    for command in (['bdist_wheel'], ['install', '--prefix', 'x'], ['develop', '--editable']):
        scripts = run_setup(str(ROOT / 'setup.py'), script_args=command,
                            stop_after='init').entry_points['console_scripts']
        names = {line.split('=')[0].strip() for line in scripts}
        assert names == ({'ipomdp-gaze'} | (nodes if command[0] != 'bdist_wheel' else set()))
    setup_cfg = (ROOT / 'setup.cfg').read_text()
    assert 'script_dir=$base/lib/ipomdp_gaze' in setup_cfg
    assert 'install_scripts=$base/lib/ipomdp_gaze' in setup_cfg


def test_namespace_symlinks_are_relative_and_point_at_the_top_level_folders():
    for name in sorted(BARE_NAMES):
        link = ROOT / 'ipomdp_gaze' / name
        assert link.is_symlink(), link
        assert os.readlink(link) == f'../{name}', os.readlink(link)


def _bare_imports(tree) -> list:
    """``(line, statement)`` of every absolute import of a bare top-level name in ``tree``."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
        elif isinstance(node, ast.Call) and getattr(node.func, 'attr', getattr(
                node.func, 'id', None)) in ('import_module', '__import__') and node.args and \
                isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
            names = [node.args[0].value]
        else:
            continue
        found += [(node.lineno, ast.unparse(node)) for name in names
                  if name.split('.')[0] in BARE_NAMES]
    return found


def test_no_python_file_imports_the_bare_top_level_names():
    bad = [f'{p.relative_to(ROOT)}:{line}: {code}' for p in python_files()
           for line, code in _bare_imports(ast.parse(p.read_text()))]
    assert not bad, ('import ipomdp_gaze.policies / ipomdp_gaze.msg_adapters (or relative), '
                     'never the bare names:\n' + '\n'.join(bad))


def _core_modules() -> list:
    """List the rclpy-free layers: the core's groups, vision, the drivers and the policies."""
    names = ['ipomdp_gaze']
    for group in ('model', 'files', 'search', 'simulation', 'vision', 'drivers'):
        for path in sorted((ROOT / 'ipomdp_gaze' / group).glob('*.py')):
            names.append(f'ipomdp_gaze.{group}' if path.stem == '__init__'
                         else f'ipomdp_gaze.{group}.{path.stem}')
    for path in sorted((ROOT / 'policies').rglob('*.py')):
        parts = path.relative_to(ROOT).with_suffix('').parts
        names.append('.'.join(('ipomdp_gaze',) + (parts[:-1] if parts[-1] == '__init__'
                                                  else parts)))
    return names


def _is_ros_module(name: str) -> bool:
    top = name.split('.')[0]
    return top in ('rclpy', 'rcl_interfaces', 'builtin_interfaces') or \
        top.endswith(('_msgs', '_srvs', '_interfaces'))


def test_the_core_and_the_policies_import_nothing_from_ros(tmp_path):
    modules = _core_modules()
    assert {'ipomdp_gaze.search.gaze', 'ipomdp_gaze.policies',
            'ipomdp_gaze.policies.policy_file'} <= set(modules)
    code = ('import importlib, json, sys\n'
            'for name in json.loads(sys.argv[1]):\n'
            '    importlib.import_module(name)\n'
            'print(json.dumps(sorted(sys.modules)))\n')
    # A clean interpreter (-I: no PYTHONPATH, no cwd on sys.path) outside the source tree.
    out = subprocess.run([sys.executable, '-I', '-c', code, json.dumps(modules)], cwd=tmp_path,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    loaded = json.loads(out.stdout.splitlines()[-1])
    ros = [m for m in loaded if _is_ros_module(m)]
    assert not ros, f'importing the core loaded ROS modules: {ros}'


def test_every_python_file_has_the_licence_header():
    missing = [str(p.relative_to(ROOT)) for p in python_files()
               if not HEADER.match(p.read_text())]
    assert not missing, f'missing the Apache-2.0 header: {missing}'
    assert 'Apache License' in (ROOT / 'LICENSE').read_text()
