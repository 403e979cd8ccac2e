# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ``simulated_camera`` node: a pan/tilt camera and detector for bench testing.

It stands in for the hardware. It subscribes ``pan_tilt`` (``sensor_msgs/JointState``), snaps
the command to the nearest cell and moves there in ``saccade_time_s`` (until it arrives, the head
is still at the old cell; a repeated command for the cell it is moving to is ignored, one for the
cell it is at takes ``saccade_time_s`` to settle again). With ``rate_hz = 0`` it publishes one
evidence frame when it arrives; with ``rate_hz > 0`` it publishes frames at that rate like a video
camera, including while it moves. Each frame is drawn from the Gaussian observation model with
the camera's own FPOC (:meth:`ipomdp_gaze.model.observation.GaussianObservation.sample`), with NaN
where the FPOC gives ``d' = 0`` (outside the field of view, not observed).

Publishes ``evidence`` (``Float32MultiArray``, best effort) or, with ``publish_image``, the
stamped ``evidence_image`` (``32FC1``); ``joint_states`` (its pose, stamped like the frame taken
there); and ``ground_truth`` (``std_msgs/Int32MultiArray`` ``[row, col]``, transient local;
``[-1, -1]`` for an empty scene). ``~/reset`` (``std_srvs/Trigger``) draws a new target
(``target_row``/``target_col``, or a random cell when they are -1). Every callback runs under a
:class:`ipomdp_gaze.nodes.guard.CallbackGuard` (its counts in the ``/diagnostics`` status
``<node>: callbacks``).

Beyond the paper (docs/design.md section 7): with ``empty_scene`` there is no target (every
frame is null noise) from the start or the next ``~/reset``; with ``target_motion_rate_hz > 0``
the target takes a step of :class:`ipomdp_gaze.model.motion.Motion` (``target_motion_sigma_cells``,
``target_jump_prob`` per step) that many times a second and ``ground_truth`` follows it. A
controller models that walk with ``motion.sigma_cells = target_motion_sigma_cells *
sqrt(target_motion_rate_hz)`` and ``motion.jump_prob = 1 - (1 - target_jump_prob) **
target_motion_rate_hz`` per second.
"""
from __future__ import annotations

from dataclasses import dataclass
import sys

from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.motion import check_probability, check_sigma_cells, Motion
from ipomdp_gaze.model.observation import GaussianObservation
from ipomdp_gaze.msg_adapters import grid_arrays, images, joints
from ipomdp_gaze.search.controller_config import fpoc_from, grid_from, head_from, row_col_from
import numpy as np
from rclpy.node import Node
from sensor_msgs.msg import Image, JointState
from std_msgs.msg import Float32MultiArray, Int32MultiArray
from std_srvs.srv import Trigger

from . import NODE_NAMES
from .guard import CallbackGuard, GuardedNode
from .outputs import QuietPublishers
from .params import (cell_params, fpoc_params, grid_params, INT_MAX, joint_params, Param,
                     ParameterTransaction, T)
from .qos import command_subscription, FRAME_QOS, STATE_QOS
from .saccade import saccade_params, SaccadeMixin
from .spin import run_node

NODE_NAME = NODE_NAMES['camera']
# The camera's frames are float32 (``evidence``, the 32FC1 ``evidence_image``), which hold at most
# about 3.4e38: a larger d' is +inf in the target's cell, a frame every controller refuses (and
# numpy warned of the overflow at each frame). A d' of 1e38 is far past certainty (d' 40 already
# tells target from noise with an error of about 1e-89).
MAX_FRAME_DPRIME = 1e38


def check_frame_dprime(observation: GaussianObservation) -> None:
    """Refuse (ValueError) an FPOC whose d' the camera's float32 frames cannot hold."""
    d_max = float(observation.table.max())
    if d_max > MAX_FRAME_DPRIME:
        raise ValueError(f'fpoc.dprime must be at most {MAX_FRAME_DPRIME:g} in the simulated '
                         "camera (its evidence frames are float32, where a larger d' is +inf), "
                         f'got {d_max:g}')


def camera_params() -> list[Param]:
    """Every parameter of the simulated camera, in declaration order."""
    return grid_params() + fpoc_params(MAX_FRAME_DPRIME) + joint_params(limits=False) + \
        cell_params('target', 'the target', 'a random {} at each reset') + [
        Param('seed', 0, T.INTEGER, 'seed of the targets and the observation noise',
              int_range=(0, INT_MAX)),
    ] + saccade_params(max_rate_hz=1000.0) + [
        Param('publish_image', False, T.BOOL,
              'publish stamped 32FC1 evidence_image frames instead of evidence'),
        Param('empty_scene', False, T.BOOL,
              'no target at all (from the start or the next reset): every frame is null noise'),
        Param('target_motion_sigma_cells', 0.0, T.DOUBLE,
              'standard deviation in cells of each step of the random walk of the target, >= 0'),
        Param('target_jump_prob', 0.0, T.DOUBLE,
              'probability that a step is a jump to a random cell instead, in [0, 1)'),
        Param('target_motion_rate_hz', 0.0, T.DOUBLE,
              'steps of the random walk of the target per second (0: a still target)',
              float_range=(0.0, 1000.0)),
    ]


@dataclass
class CameraConfig:
    """What the camera derives from its parameters."""

    values: dict
    grid: object
    observation: GaussianObservation
    head: PanTiltMap
    target: tuple
    motion: Motion


class SimulatedCameraNode(SaccadeMixin, GuardedNode, QuietPublishers, Node):
    """A simulated pan/tilt head with a detector (see the module docstring)."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        self.guard = CallbackGuard(self)
        self._transaction = ParameterTransaction(self, camera_params(),
                                                 self.guard.refusing(self._build),
                                                 self.guard.wrap(self._apply_config))
        self._transaction.declare()
        self._transaction.start(self._build(self._transaction.values()))
        v = self._config.values
        self.rng = np.random.default_rng(v['seed'])
        self.pose = self.goal = self._config.grid.center_index
        self.moving = False
        self.target: int | None = 0
        self._evidence_pub = self.create_publisher(Float32MultiArray, 'evidence', FRAME_QOS)
        self._image_pub = self.create_publisher(Image, 'evidence_image', FRAME_QOS)
        self._joint_pub = self.create_publisher(JointState, 'joint_states', 10)
        self._truth_pub = self.create_publisher(Int32MultiArray, 'ground_truth', STATE_QOS)
        command_subscription(self, JointState, 'pan_tilt', self.guard.wrap(self._on_command))
        self.create_service(Trigger, '~/reset', self.guard.wrap(self._on_reset))
        self.guard.publish_status()
        self._saccade_timer = self._frame_timer = self._walk_timer = None
        self._make_timers(v)
        self._new_target()
        self._publish_pose(self.get_clock().now().to_msg())

    @property
    def _config(self) -> CameraConfig:
        """Return the configuration in force."""
        return self._transaction.config

    # -- parameters ----------------------------------------------------------------------
    def _build(self, values: dict, changed=None, previous=None) -> CameraConfig:
        """Derive a :class:`CameraConfig` from parameter values (ValueError names the problem)."""
        grid = grid_from(values)
        fpoc = fpoc_from(values)
        head = head_from(values, grid)
        target = row_col_from(values, grid, 'target_row', 'target_col')
        motion = Motion(grid, check_sigma_cells(values['target_motion_sigma_cells'],
                                                'target_motion_sigma_cells'),
                        check_probability(values['target_jump_prob'], 'target_jump_prob'))
        observation = GaussianObservation(grid, fpoc)
        check_frame_dprime(observation)
        return CameraConfig(dict(values), grid, observation, head, target, motion)

    def _apply_config(self, old: CameraConfig, cfg: CameraConfig) -> None:
        """Follow a new configuration: a new seed restarts the noise, new times the timers."""
        v, ov = cfg.values, old.values
        if v['seed'] != ov['seed']:
            self.rng = np.random.default_rng(v['seed'])
        times = ('saccade_time_s', 'rate_hz', 'target_motion_rate_hz')
        if any(v[k] != ov[k] for k in times):
            self._make_timers(v)

    def _make_timers(self, values: dict) -> None:
        if self._walk_timer is not None:
            self.destroy_timer(self._walk_timer)
        self._walk_timer = None
        self._make_saccade_timers(values)
        if values['target_motion_rate_hz'] > 0:
            self._walk_timer = self.create_timer(1.0 / values['target_motion_rate_hz'],
                                                 self.guard.wrap(self._walk))

    # -- head ------------------------------------------------------------------------------
    def _on_command(self, msg: JointState) -> None:
        cell = self._commanded_cell(msg, self._config.head)
        if cell is not None:
            self._saccade_to(cell, self._command_stamp_of(msg))

    def _arrived(self) -> None:
        if self._config.values['rate_hz'] == 0:
            self._publish_frame()
        else:
            self._publish_pose(self.get_clock().now().to_msg())

    # -- outputs -------------------------------------------------------------------------
    def _publish_frame(self) -> None:
        cfg = self._config
        obs = cfg.observation.sample(0 if self.target is None else self.target, self.pose,
                                     self.rng, present=self.target is not None)
        obs[~cfg.observation.observed(self.pose)] = np.nan
        stamp = self.get_clock().now().to_msg()
        if cfg.values['publish_image']:
            self._image_pub.publish(images.evidence_image(obs, cfg.grid, stamp))
        else:
            self._evidence_pub.publish(grid_arrays.to_multiarray(obs, cfg.grid))
        self._publish_pose(stamp)

    def _publish_pose(self, stamp) -> None:
        self._joint_pub.publish(joints.joint_state(self._config.head, self.pose, stamp))

    def _new_target(self) -> int | None:
        cfg = self._config
        if cfg.values['empty_scene']:
            self.target = None
        else:
            row, col = cfg.target
            row = int(self.rng.integers(cfg.grid.rows)) if row is None else row
            col = int(self.rng.integers(cfg.grid.cols)) if col is None else col
            self.target = cfg.grid.index(row, col)
        self._truth_pub.publish(grid_arrays.ground_truth(cfg.grid, self.target))
        return self.target

    def _walk(self) -> None:
        """Take one step of the target's random walk (nothing in an empty scene)."""
        cfg = self._config
        if self.target is None or not cfg.motion.active:
            return
        step = int(cfg.motion.move(np.array([self.target]), self.rng)[0])
        if step != self.target:
            self.target = step
            self._truth_pub.publish(grid_arrays.ground_truth(cfg.grid, self.target))

    def _on_reset(self, request, response):
        target = self._new_target()
        response.success = True
        if target is None:
            response.message = 'empty scene: no target'
        else:
            row, col = self._config.grid.cell(target)
            response.message = f'new target at ({row}, {col})'
        self.get_logger().info(response.message)
        return response


def main(args=None) -> int:
    """Run the ``simulated_camera`` node until shutdown (Ctrl-C or SIGTERM)."""
    return run_node(SimulatedCameraNode, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
