# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Launch the gaze controller and, for bench testing, the simulated camera.

``ros2 launch ipomdp_gaze gaze_demo.launch.py`` runs both with the shipped YAML files;
``simulated_camera:=false`` runs the controller alone for a real pan/tilt head and detector, and
``controller_params:=/path/to/my.yaml`` uses your own parameter file.
"""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare


def generate_launch_description():
    """Build the launch description."""
    config = PathJoinSubstitution([FindPackageShare('ipomdp_gaze'), 'config'])
    return LaunchDescription([
        DeclareLaunchArgument(
            'controller_params', default_value=PathJoinSubstitution([config, 'controller.yaml']),
            description='parameter file of gaze_controller'),
        DeclareLaunchArgument(
            'camera_params', default_value=PathJoinSubstitution([config, 'camera.yaml']),
            description='parameter file of simulated_camera'),
        DeclareLaunchArgument(
            'simulated_camera', default_value='true',
            description='also start the simulated camera (false for a real head)'),
        Node(package='ipomdp_gaze', executable='controller', name='gaze_controller',
             parameters=[LaunchConfiguration('controller_params')], output='screen'),
        Node(package='ipomdp_gaze', executable='camera', name='simulated_camera',
             parameters=[LaunchConfiguration('camera_params')], output='screen',
             condition=IfCondition(LaunchConfiguration('simulated_camera'))),
    ])
