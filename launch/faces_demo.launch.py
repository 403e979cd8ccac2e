# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Launch the face search: gaze controller, foveal detector and, for bench testing, the scene camera.

``ros2 launch ipomdp_gaze faces_demo.launch.py`` runs the pan/tilt version (``mode:=camera``)
with ``config/faces_camera_*.yaml``; ``mode:=fovea`` the fixed camera with the digital fovea
(``config/faces_fovea_*.yaml``). ``scene_camera:=false`` leaves the camera to a real driver:
remap its topics, e.g. ``image:=/camera/image_raw camera_info:=/camera/camera_info``, and a
real head's (``joint_states:=...``, its joint names ``pan_joint:=... tilt_joint:=...`` and
``joint_state_tolerance_s:=0.02`` when its joint states are not stamped like the images; the
defaults are the config files' values, which the scene camera's joint states meet).
"""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue
from launch_ros.substitutions import FindPackageShare


def generate_launch_description():
    """Build the launch description."""
    config = PathJoinSubstitution([FindPackageShare('ipomdp_gaze'), 'config'])
    mode = LaunchConfiguration('mode')

    def params(node):
        return PathJoinSubstitution([config, ['faces_', mode, f'_{node}.yaml']])

    # typed: 0 or 1 would otherwise reach the DOUBLE parameter as an integer, and be refused
    joints = {name: ParameterValue(LaunchConfiguration(name), value_type=str)
              for name in ('pan_joint', 'tilt_joint')}

    return LaunchDescription([
        DeclareLaunchArgument('mode', default_value='camera',
                              description='camera (pan/tilt head) or fovea (fixed camera)'),
        DeclareLaunchArgument('scene_camera', default_value='true',
                              description='also start the scene camera (false: a real driver)'),
        DeclareLaunchArgument('seed', default_value='0',
                              description='which held-out test scene the scene camera shows'),
        DeclareLaunchArgument('image', default_value='image',
                              description='the camera image topic the detector reads'),
        DeclareLaunchArgument('camera_info', default_value='camera_info',
                              description='the camera_info topic the detector reads'),
        DeclareLaunchArgument('joint_states', default_value='joint_states',
                              description="the head's joint_states topic the detector reads"),
        DeclareLaunchArgument('pan_joint', default_value='pan_joint',
                              description="the head's pan joint (controller and detector)"),
        DeclareLaunchArgument('tilt_joint', default_value='tilt_joint',
                              description="the head's tilt joint (controller and detector)"),
        DeclareLaunchArgument('joint_state_tolerance_s', default_value='0.0',
                              description='camera mode: how far apart the stamps of an image '
                                          'and its joint state may be (a real head: e.g. 0.02)'),
        Node(package='ipomdp_gaze', executable='controller', name='gaze_controller',
             parameters=[params('controller'), joints], output='screen'),
        Node(package='ipomdp_gaze', executable='detector', name='foveal_detector',
             parameters=[params('detector'), {
                 **joints,
                 'joint_state_tolerance_s': ParameterValue(
                     LaunchConfiguration('joint_state_tolerance_s'), value_type=float)}],
             output='screen',
             remappings=[('image', LaunchConfiguration('image')),
                         ('camera_info', LaunchConfiguration('camera_info')),
                         ('joint_states', LaunchConfiguration('joint_states'))]),
        Node(package='ipomdp_gaze', executable='scene_camera', name='scene_camera',
             parameters=[params('scene_camera'), {'seed': LaunchConfiguration('seed'),
                                                  **joints}],
             output='screen', condition=IfCondition(LaunchConfiguration('scene_camera'))),
    ])
