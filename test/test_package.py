# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""ROS package conformance: package.xml, installed data files and licence headers."""
import ast
from pathlib import Path
import re

from catkin_pkg.package import parse_package
from setuptools._distutils.core import run_setup

ROOT = Path(__file__).resolve().parents[1]
SOURCE_DIRS = ('ipomdp_gaze', 'policies', 'msg_adapters', 'test', 'bench', 'launch', 'examples')
# Python modules that come from ROS packages (and must be exec_depends when imported).
ROS_PACKAGES = {'rclpy', 'std_msgs', 'sensor_msgs', 'std_srvs', 'diagnostic_msgs',
                'trajectory_msgs', 'geometry_msgs', 'rcl_interfaces', 'builtin_interfaces',
                'ament_index_python', 'visualization_msgs'}
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


def test_setup_installs_marker_package_xml_config_launch_and_kernels():
    dist = run_setup(str(ROOT / 'setup.py'), stop_after='init')
    installed = {dest: {Path(f).as_posix() for f in files} for dest, files in dist.data_files}
    assert 'resource/ipomdp_gaze' in installed['share/ament_index/resource_index/packages']
    assert 'package.xml' in installed['share/ipomdp_gaze']
    for dest, folder, pattern in (('config', 'config', '*.yaml'),
                                  ('launch', 'launch', '*.launch.py'),
                                  ('kernels', 'policies/kernels', '*.yaml')):
        expected = {p.relative_to(ROOT).as_posix() for p in (ROOT / folder).glob(pattern)}
        assert expected == installed.get(f'share/ipomdp_gaze/{dest}', set()), dest
    assert (ROOT / 'resource' / 'ipomdp_gaze').is_file()
    setup_cfg = (ROOT / 'setup.cfg').read_text()
    assert 'script_dir=$base/lib/ipomdp_gaze' in setup_cfg
    assert 'install_scripts=$base/lib/ipomdp_gaze' in setup_cfg


def test_every_python_file_has_the_licence_header():
    missing = [str(p.relative_to(ROOT)) for p in python_files()
               if not HEADER.match(p.read_text())]
    assert not missing, f'missing the Apache-2.0 header: {missing}'
    assert 'Apache License' in (ROOT / 'LICENSE').read_text()
