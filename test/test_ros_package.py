# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ROS side as shipped: YAML files, launch file, entry points and start-up validation.

The YAML files must name only declared parameters with the declared types (rclpy refuses ``0``
for a double at start-up), agree with each other on the task, and the launch file must start
the executables and node names that exist.
"""
import ast
import subprocess
import sys

from conftest import REPO
import pytest
import yaml


def _yaml(name):
    return yaml.safe_load((REPO / 'config' / name).read_text())


def _flat(tree, prefix=''):
    out = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            out.update(_flat(value, f'{prefix}{key}.'))
        else:
            out[f'{prefix}{key}'] = value
    return out


@pytest.mark.ros
@pytest.mark.parametrize('file, node, module, params', [
    ('controller.yaml', 'gaze_controller', 'controller', 'controller_params'),
    ('camera.yaml', 'simulated_camera', 'camera', 'camera_params'),
    ('faces_camera_controller.yaml', 'gaze_controller', 'controller', 'controller_params'),
    ('faces_fovea_controller.yaml', 'gaze_controller', 'controller', 'controller_params'),
    ('faces_camera_room_controller.yaml', 'gaze_controller', 'controller', 'controller_params'),
    ('faces_camera_detector.yaml', 'foveal_detector', 'detector', 'detector_params'),
    ('faces_camera_room_detector.yaml', 'foveal_detector', 'detector', 'detector_params'),
    ('faces_fovea_detector.yaml', 'foveal_detector', 'detector', 'detector_params'),
    ('faces_camera_scene_camera.yaml', 'scene_camera', 'scene_camera', 'scene_camera_params'),
    ('faces_fovea_scene_camera.yaml', 'scene_camera', 'scene_camera', 'scene_camera_params'),
])
def test_yaml_names_declared_parameters_with_their_types(file, node, module, params):
    import importlib

    from rclpy.parameter import Parameter
    module = importlib.import_module(f'ipomdp_gaze.nodes.{module}')
    declared = {p.name: p for p in getattr(module, params)()}
    doc = _yaml(file)
    assert list(doc) == [f'/**/{node}']           # applies in any namespace
    values = _flat(doc[f'/**/{node}']['ros__parameters'])
    unknown = sorted(set(values) - set(declared))
    assert not unknown, f'{file}: undeclared parameters {unknown}'
    for name, value in values.items():
        spec = declared[name]
        if spec.dynamic:
            continue
        want = {Parameter.Type.DOUBLE: float, Parameter.Type.INTEGER: int,
                Parameter.Type.STRING: str, Parameter.Type.BOOL: bool}.get(spec.ptype)
        if want is not None:
            assert type(value) is want, f'{file}: {name} = {value!r} is not a {want.__name__}'
        if spec.choices is not None:
            assert value in spec.choices, f'{file}: {name} = {value!r}'


def test_the_two_yaml_files_describe_the_same_task():
    controller = _flat(_yaml('controller.yaml')['/**/gaze_controller']['ros__parameters'])
    camera = _flat(_yaml('camera.yaml')['/**/simulated_camera']['ros__parameters'])
    task = [k for k in controller if k.startswith(('grid.', 'fpoc.')) or k.endswith(
        ('_joint', '_sign', '_offset_rad'))]
    assert {k: controller[k] for k in task} == {k: camera.get(k) for k in task}
    assert (controller['grid.rows'], controller['grid.cols'], controller['grid.spacing_deg']) == \
        (11, 11, 5.0)
    assert controller['fpoc.model'] == 'camera'
    assert controller['fpoc.half_width_deg'] == controller['fpoc.half_height_deg'] == 10.0
    assert controller['policy.file'] == 'camera-11x11-infomax'
    assert controller['policy.fallback'] == 'elm'


@pytest.mark.parametrize('mode, view', [('camera', 'pan_tilt'), ('fovea', 'fixed')])
def test_the_three_face_yaml_files_of_a_mode_describe_the_same_task(mode, view):
    from ipomdp_gaze.files.observation_file import load_observation
    controller = _flat(_yaml(f'faces_{mode}_controller.yaml')['/**/gaze_controller']
                       ['ros__parameters'])
    detector = _flat(_yaml(f'faces_{mode}_detector.yaml')['/**/foveal_detector']
                     ['ros__parameters'])
    camera = _flat(_yaml(f'faces_{mode}_scene_camera.yaml')['/**/scene_camera']['ros__parameters'])
    assert detector['mode'] == mode and camera['view'] == view
    assert controller['observation.model'] == 'counts'
    assert controller['observation.file'] == detector['observation.file']
    model = load_observation(detector['observation.file'])
    assert (controller['grid.rows'], controller['grid.cols']) == model.grid.shape
    assert (model.meta['image'].get('view', 'fixed')) == view
    if mode == 'camera':
        assert controller['grid.spacing_deg'] == model.grid.spacing_deg
        assert (camera['grid.rows'], camera['grid.cols'], camera['grid.spacing_deg']) == \
            (model.grid.rows, model.grid.cols, model.grid.spacing_deg)
        image = model.meta['image']
        assert (camera['camera.width'], camera['camera.height']) == (image['width'],
                                                                     image['height'])
        joints = [k for k in controller if k.endswith(('_joint', '_sign', '_offset_rad'))]
        assert joints and all(controller[k] == detector[k] == camera[k] for k in joints)
        assert controller['settle_time_s'] < camera['saccade_time_s']
    else:
        assert controller['settle_time_s'] == 0.0                   # nothing moves
        assert camera['scene.size_px'] == model.meta['image']['width']


def test_launch_file_starts_existing_executables_with_existing_config():
    tree = ast.parse((REPO / 'launch' / 'gaze_demo.launch.py').read_text())
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and getattr(n.func, 'id', '') == 'Node']
    started = {(kw['executable'], kw['name']) for kw in (
        {k.arg: k.value.value for k in c.keywords if isinstance(k.value, ast.Constant)}
        for c in calls)}
    assert started == {('controller', 'gaze_controller'), ('camera', 'simulated_camera')}
    strings = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)
               and isinstance(n.value, str)}
    assert {'controller.yaml', 'camera.yaml', 'ipomdp_gaze', 'config'} <= strings
    setup = (REPO / 'setup.py').read_text()
    assert "'controller = ipomdp_gaze.nodes.controller:main'" in setup
    assert "'camera = ipomdp_gaze.nodes.camera:main'" in setup


def test_face_launch_file_starts_the_three_nodes_with_the_files_of_its_mode():
    tree = ast.parse((REPO / 'launch' / 'faces_demo.launch.py').read_text())
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and getattr(n.func, 'id', '') == 'Node']
    started = {(kw['executable'], kw['name']) for kw in (
        {k.arg: k.value.value for k in c.keywords if isinstance(k.value, ast.Constant)}
        for c in calls)}
    assert started == {('controller', 'gaze_controller'), ('detector', 'foveal_detector'),
                       ('scene_camera', 'scene_camera')}
    strings = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)
               and isinstance(n.value, str)}
    assert {'faces_', 'camera', 'ipomdp_gaze', 'config'} <= strings
    for mode in ('camera', 'fovea'):
        for node in ('controller', 'detector', 'scene_camera'):
            assert (REPO / 'config' / f'faces_{mode}_{node}.yaml').is_file()
    # the arguments for a real head default to the config files' values (the demo unchanged)
    defaults = {c.args[0].value: kw.value.value for c in ast.walk(tree)
                if isinstance(c, ast.Call) and getattr(c.func, 'id', '') == 'DeclareLaunchArgument'
                for kw in c.keywords if kw.arg == 'default_value'}
    for mode in ('camera', 'fovea'):
        for node in ('controller', 'detector'):
            values = yaml.safe_load((REPO / 'config' / f'faces_{mode}_{node}.yaml').read_text())
            values = next(iter(values.values()))['ros__parameters']
            for name in ('pan_joint', 'tilt_joint', 'joint_state_tolerance_s'):
                if name in values:
                    assert yaml.safe_load(defaults[name]) == values[name], (mode, node, name)
    assert defaults['joint_states'] == 'joint_states'
    setup = (REPO / 'setup.py').read_text()
    assert "'detector = ipomdp_gaze.nodes.detector:main'" in setup
    assert "'scene_camera = ipomdp_gaze.nodes.scene_camera:main'" in setup


@pytest.mark.ros
@pytest.mark.parametrize('command, ros_args, words', [
    ('controller', ['-p', 'policy.kernel:=[1.0, 2.0]'], 'policy.kernel must have 441 values'),
    ('controller', ['-p', 'policy.name:=learned', '-p', 'policy.file:=/no/such/policy.yaml'],
     "policy file '/no/such/policy.yaml' not found"),
    ('controller', ['-p', 'settle_time_s:=1'], 'settle_time_s'),
    ('camera', ['-p', 'fpoc.model:=sonar'], "fpoc.model must be one of 'human'"),
    ('detector', ['-p', 'mode:=eyes'], "mode must be one of 'fovea', 'camera'"),
    ('detector', ['-p', 'observation.file:=/no/such.yaml'], "'/no/such.yaml' not found"),
    ('detector', ['-p', 'mode:=camera', '-p', 'observation.file:=faces-420'],
     'calibrated with a fixed view'),
    ('scene_camera', ['-p', 'view:=fisheye'], "view must be one of 'fixed', 'pan_tilt'"),
    ('scene_camera', ['-p', 'scene.file:=/no/such.png'], 'missing or not an image'),
    ('scene_camera', ['-p', 'scene.face_px:=[10]'], 'scene.face_px must be [min, max]'),
])
def test_start_up_validation_through_the_cli(ros_env, command, ros_args, words):
    run = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', command, '--ros-args',
                          *ros_args], env=ros_env, capture_output=True, text=True, timeout=60)
    assert run.returncode == 1, run.stdout + run.stderr
    assert words in run.stderr, run.stderr
    assert 'Traceback' not in run.stderr
