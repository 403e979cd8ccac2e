# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ``gaze_controller`` node: I-POMDP gaze control of a pan/tilt head.

A thin wrapper: :class:`ipomdp_gaze.search.gaze.GazeController` holds the belief and decides, and
:mod:`msg_adapters` reads and fills every message. Relative topic names, so namespaces and
remapping work:

- subscribes ``evidence`` (``std_msgs/Float32MultiArray``, one standardised detector response
  per cell, or with ``observation.model: counts`` one detection count per cell; NaN = not
  observed; arrival time counts) and ``evidence_image``
  (``sensor_msgs/Image`` 32FC1, rows x cols; its header stamp counts, or its arrival when unset;
  32FC3 adds per cell the mean offset of its detections, which ``motion.track_view: position``
  reads: the detector's ``publish_offsets``; 32FC4 then the grouped detections per cell, which
  a many-target pass names: its ``publish_groups``),
  both best effort and keep-last ``evidence_queue_depth`` (1: the newest frame wins; frames
  dropped on the way are counted from the publisher's sequence numbers);
- publishes ``pan_tilt`` (``sensor_msgs/JointState``, transient local, depth 1, re-sent every
  ``retry_period_s`` until a usable frame arrives) and, with every target sent or re-sent,
  ``fixation`` (``std_msgs/Int32MultiArray`` ``[row, col, search_id]``, transient local,
  depth 1: what a foveal detector serves), ``belief`` (``Float32MultiArray``) and
  ``belief_image`` (``rgb8``) after every update and reset (the N cell probabilities, summing
  to ``1 - P(absent)``), the search events ``found``, ``absent`` and ``gave_up``
  (``diagnostic_msgs/DiagnosticStatus``, reliable; with motion on also ``lost`` and
  ``reacquired``) and ``/diagnostics``; optionally ``Float64MultiArray`` and
  ``JointTrajectory`` head commands on the topics their parameters name;
- services ``~/reset`` (``std_srvs/Trigger``) and ``~/enable`` (``std_srvs/SetBool``).

For a still target a decision (``found``, ``absent``) or ``gave_up`` ends the search: no new
target is sent until ``~/reset``. With ``motion.sigma_cells`` or ``motion.jump_prob`` set (per
second), the belief is predicted over the time between frames and the controller keeps tracking
after ``found`` (docs/design.md section 7): ``lost`` when the belief at the target falls below
``motion.keep_probability``, ``reacquired`` (not a second ``found``) when it is found again
(section 12.5).

With ``search.targets: many`` (docs/design.md section 11.6) the core runs the occupancy belief
and the node also publishes ``~/targets`` (``geometry_msgs/PoseArray``, the head direction of
each person found) and ``~/target_cells`` (``Float32MultiArray``, ``[row, col, cell,
probability]`` per person), both transient local, and the ``room_done`` event; then it keeps
the people in view in turn, ``room.dwell_s`` each, until ``~/reset`` or the re-check every
``room.recheck_period_s`` (:class:`ipomdp_gaze.search.room.RoomWatch`).

Run with ``ros2 run ipomdp_gaze controller`` (or ``ipomdp-gaze controller``) and the usual
``--ros-args``.
"""
from __future__ import annotations

import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseArray
from ipomdp_gaze.model.belief import EvidenceError, prior_is_uniform
from ipomdp_gaze.model.head_time import SETTLE_TIME_S
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays, images, joints, people, stamps
from ipomdp_gaze.policies.baselines import STRATEGIES
from ipomdp_gaze.policies.conv import ACTIONS, check_kernel
from ipomdp_gaze.policies.policy_file import check_training_prior
from ipomdp_gaze.policies.registry import build_policy, POLICY_NAMES, PolicyUnavailable
from ipomdp_gaze.search import answer
from ipomdp_gaze.search.controller_config import (build_config, ControllerConfig as Config,
                                                  follow_config, grid_from, new_warnings)
from ipomdp_gaze.search.gaze import FrameSequence, SETTLING, STAMP_TOLERANCE_S
from ipomdp_gaze.search.health import HealthMonitor
from ipomdp_gaze.search.room import MAX_PERIOD_S, people_text, Person, PERSON_LINK, RoomWatch
from ipomdp_gaze.search.session import PARAMETER_NAMES
import numpy as np
from rclpy.clock import ClockChange, JumpThreshold
from rclpy.duration import Duration
from rclpy.exceptions import NameValidationException
from rclpy.expand_topic_name import expand_topic_name
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.validate_full_topic_name import validate_full_topic_name
from sensor_msgs.msg import Image, JointState
from std_msgs.msg import Float32MultiArray, Float64MultiArray, Int32MultiArray
from std_srvs.srv import SetBool, Trigger
from trajectory_msgs.msg import JointTrajectory

from . import NODE_NAMES
from .guard import CallbackGuard, GuardedNode
from .outputs import QuietPublishers
from .params import (cell_params, current_values, fpoc_params, grid_params, INT_MAX, joint_params,
                     Param, ParameterTransaction, RangeReasons, search_params, T)
from .qos import STATE_QOS
from .spin import run_node

NODE_NAME = NODE_NAMES['controller']
WARN_THROTTLE_S = 5.0
# The fixation is asked for again this long after its settle time has passed (a frame taken
# then is not skipped on a clock read a hair earlier).
SETTLED_MARGIN_S = 0.01
# A jump of the node's clock (use_sim_time: /clock set back, its first tick far from 0, or the
# clock switched) moves the times the search keeps; forward jumps are looked at from this long.
CLOCK_JUMP_FORWARD_S = 5.0
# belief_image is at most this many pixels on a side (256x256 cells at 32 px would be 201 MB).
MAX_IMAGE_SIDE_PX = 1024
OBSERVATION_MODELS = ('gaussian', 'counts')


def _same_prior(a, b) -> bool:
    """Whether two ``belief.prior`` probabilities (None: uniform) are the same."""
    if a is None or b is None:
        return a is b
    return bool(np.array_equal(a, b))


def _say_training_prior(cfg: Config) -> None:
    """
    Add to ``cfg.warnings`` that its policy file is used with another prior than its training's.

    As ``evaluate`` says it (a policy file records ``training.prior``; without one it was
    trained on the uniform prior); a kernel or a baseline has no training prior to compare.
    """
    spec = getattr(cfg.policy, 'spec', None)
    if spec is None:
        return
    said = list(cfg.warnings)
    check_training_prior(spec, cfg.prior, said.append)
    cfg.warnings = tuple(said)


def controller_params() -> list[Param]:
    """Every parameter of the controller, in declaration order (the grid first)."""
    return grid_params() + fpoc_params() + [
        Param('observation.model', 'gaussian', T.STRING,
              'gaussian: standardised responses and the FPOC; counts: detection counts and the '
              'count model of observation.file (fpoc.* are then ignored)',
              choices=OBSERVATION_MODELS),
        Param('observation.file', '', T.STRING,
              'count model: an ipomdp_gaze/observation-v1 path or shipped name (with counts)'),
    ] + cell_params(
        'start', 'the first fixation after a reset',
        "the centre {}; both -1: the policy's choice after a scan, else the centre") + [
        Param('belief.prior', None, T.DOUBLE_ARRAY,
              'where the one target is a priori: a weight >= 0 per cell, rows x cols values '
              'row-major, scaled to sum 1 (empty: uniform, the paper; whole numbers such as '
              '[1, 2, 1] are taken as doubles); from the next reset; not with search.targets '
              'many'),
        Param('seed', 0, T.INTEGER, 'seed of the random and sample policies',
              int_range=(0, INT_MAX)),
        Param('settle_time_s', SETTLE_TIME_S, T.DOUBLE,
              'frames taken earlier than this after a target was sent are skipped',
              float_range=(0.0, 60.0)),
        Param('stamp_tolerance_s', STAMP_TOLERANCE_S, T.DOUBLE,
              "evidence stamped more than this ahead of this node's clock is rejected (its "
              "clock runs ahead); keep it as the detector's stamp_tolerance_s",
              float_range=(0.0, 3600.0)),
        Param('retry_period_s', 1.0, T.DOUBLE,
              're-send the current target this often until a usable frame arrives (0: never)',
              float_range=(0.0, 3600.0)),
        Param('stall_timeout_s', 5.0, T.DOUBLE,
              'warn (diagnostics and log) when no frame was applied for this long (0: never)',
              float_range=(0.0, 3600.0)),
        Param('evidence_queue_depth', 1, T.INTEGER,
              'frames kept for the node per evidence topic; 1: the newest frame wins '
              '(read-only)', read_only=True, int_range=(1, 1000)),
    ] + search_params() + [
        Param('room.dwell_s', 2.0, T.DOUBLE,
              'search.targets many: seconds each person found is kept in view, in turn',
              float_range=(0.01, MAX_PERIOD_S)),
        Param('room.recheck_period_s', 60.0, T.DOUBLE,
              'search.targets many: search the room again this many seconds after a search of it '
              'ended, while keeping its people in view; at least room.dwell_s (0: never)',
              float_range=(0.0, MAX_PERIOD_S)),
        Param('room.frame_id', 'pan_tilt_base', T.STRING,
              'search.targets many: frame_id of ~/targets, the frame the head pans (z) and tilts '
              '(y) in'),
        Param('policy.name', 'elm', T.STRING, 'fixation policy', choices=POLICY_NAMES),
        Param('policy.file', '', T.STRING,
              'policy YAML path or shipped kernel name; setting it selects learned'),
        Param('policy.kernel', None, T.DOUBLE_ARRAY,
              'convolutional kernel, (2*rows-1) x (2*cols-1) row-major; setting it selects '
              'learned'),
        Param('policy.action', 'argmax', T.STRING, 'action rule of a learned policy',
              choices=ACTIONS),
        Param('policy.fallback', '', T.STRING,
              'baseline used at start-up when policy.file does not exist ("": fail)',
              choices=('',) + STRATEGIES),
    ] + joint_params(limits=True) + [
        Param('forward_command_topic', '', T.STRING,
              'also send [pan, tilt] as Float64MultiArray here ("": off)'),
        Param('trajectory_topic', '', T.STRING, 'also send a JointTrajectory here ("": off)'),
        Param('trajectory_duration_s', 0.5, T.DOUBLE,
              'time_from_start of the JointTrajectory point', float_range=(0.0, 60.0)),
        Param('belief_image_scale_px', 32, T.INTEGER,
              'pixels per cell in belief_image (fewer when the image would exceed '
              f'{MAX_IMAGE_SIDE_PX} px on a side)',
              int_range=(1, 256)),
        Param('diagnostics_period_s', 1.0, T.DOUBLE, 'period of /diagnostics',
              float_range=(0.01, 3600.0)),
    ]


class GazeControllerNode(GuardedNode, RangeReasons, QuietPublishers, Node):
    """ROS 2 wrapper of :class:`ipomdp_gaze.search.gaze.GazeController`."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        self.guard = CallbackGuard(self)
        # At run time an unexpected error while building or applying a parameter set is
        # counted and refuses the set; at start-up (_startup_config) it ends the node.
        self._transaction = ParameterTransaction(
            self, controller_params(), self.guard.refusing(self._build),
            self.guard.wrap(self._apply_config), self._check_while_declaring,
            pre_set=self._pre_set)
        self._transaction.declare()
        self._transaction.start(self._startup_config())
        cfg = self._config
        v = cfg.values
        self.core = cfg.controller()

        self._pan_tilt_pub = self.create_publisher(JointState, 'pan_tilt', STATE_QOS)
        self._fixation_pub = self.create_publisher(Int32MultiArray, 'fixation', STATE_QOS)
        self._belief_pub = self.create_publisher(Float32MultiArray, 'belief', 10)
        self._image_pub = self.create_publisher(Image, 'belief_image', 2)
        # Events: reliable, volatile, depth 10, so a default-QoS subscriber receives them.
        self._event_pubs = {name: self.create_publisher(DiagnosticStatus, name, 10)
                            for name in ('found', 'absent', 'gave_up', 'lost', 'reacquired')}
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._targets_pub = self._cells_pub = None
        self._people_published = None       # what ~/targets said last (None: nothing yet)
        self._make_room_publishers()
        self._room = RoomWatch(cfg.grid)
        self._new_people = 0
        self._dwell_timer = self._recheck_timer = None
        self._forward_pub = self._trajectory_pub = None
        self._make_command_publishers(v)
        evidence_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST,
                                  depth=v['evidence_queue_depth'],
                                  reliability=ReliabilityPolicy.BEST_EFFORT)
        self._sequences = {'evidence': FrameSequence(), 'evidence_image': FrameSequence()}
        self._evidence_subs = {
            'evidence': self.create_subscription(Float32MultiArray, 'evidence',
                                                 self.guard.wrap(self._on_evidence),
                                                 evidence_qos),
            'evidence_image': self.create_subscription(Image, 'evidence_image',
                                                       self.guard.wrap(self._on_evidence_image),
                                                       evidence_qos)}
        self._single_publisher = dict.fromkeys(self._sequences, True)
        self.create_service(Trigger, '~/reset', self.guard.wrap(self._on_reset))
        self.create_service(SetBool, '~/enable', self.guard.wrap(self._on_enable))
        self.guard.publish_status(publisher=self._diag_pub)
        self._retry_timer = self._diag_timer = None
        self._settled_timer = None          # asks for the fixation again once it has settled
        self._fixation_msg = None           # the fixation last published
        self._make_timers(v)
        self._resends = 0
        self._health = HealthMonitor(self._now_s())
        self._pan_tilt_msg = None
        # the search the core began when built (search 1), restarted on this node's clock
        self.core.reset(self._now_s(), new_search=False)
        self._clock_before_s = None         # the clock's reading before a jump (pre_callback)
        self._clock_jumps = self.get_clock().create_jump_callback(
            JumpThreshold(min_forward=Duration(seconds=CLOCK_JUMP_FORWARD_S),
                          min_backward=Duration(nanoseconds=-1), on_clock_change=True),
            pre_callback=self.guard.wrap(self._before_clock_jump),
            post_callback=self.guard.wrap(self._on_clock_jump))
        self._publish_belief()
        self._send_target()
        self.get_logger().info(
            f'{cfg.grid.rows}x{cfg.grid.cols} grid at {cfg.grid.spacing_deg} deg/cell, '
            f'{cfg.observation_label}, policy {cfg.policy_label}; {self._model_text()}; first '
            f'fixation {cfg.grid.cell(self.core.fixation)}')

    def _model_text(self) -> str:
        """
        Describe the target model and the stop rules for the log.

        Inhibition of return and the repeat weight are still-scene rules: the search (one
        target or many) switches them off while the target moves (docs/design.md section 12.4),
        and the line says so rather than name them as in force.
        """
        v = self._config.values
        moving = self.core.motion.active
        motion = ('a still target' if not moving else
                  f'a moving target ({_motion_text(self.core.motion.to_dict())})')
        budget = v['search.max_fixations'] or 'no'
        ior = ', inhibition of return' if v['search.inhibit_return'] else ''
        if v['search.repeat_weight'] < 1.0:
            ior += f", repeated views weighted {v['search.repeat_weight']}"
        if moving:
            still_rules = (['inhibition of return'] if v['search.inhibit_return'] else []) + \
                (['the repeat weight'] if v['search.repeat_weight'] < 1.0 else [])
            who = 'moving targets' if self._many else 'a moving target'
            ior = f", {' and '.join(still_rules)} off for {who}" if still_rules else ''
        if self._many and moving:
            motion = ('many moving targets (an occupancy per cell), each person found followed '
                      f"{v['motion.dwell_s']} s in turn, then a view for new people")
        elif self._many:
            recheck = v['room.recheck_period_s']
            motion = ('many targets (an occupancy per cell), each kept in view '
                      f"{v['room.dwell_s']} s in turn, re-checked "
                      f"{f'every {recheck} s' if recheck else 'never'}")
        if not prior_is_uniform(self._config.prior):
            motion += ' placed by belief.prior (not uniform over the cells)'
        return (f"{motion}, absent prior {v['absent.prior']}, confidence {v['confidence']}, "
                f'{budget} fixation budget{ior}')

    @property
    def _many(self) -> bool:
        """Whether the controller searches for many targets (``search.targets: many``)."""
        return self._config.values['search.targets'] == 'many'

    @property
    def _config(self) -> Config:
        """Return the configuration in force."""
        return self._transaction.config

    # -- parameters ----------------------------------------------------------------------
    def _build(self, values: dict, changed=None, previous: Config | None = None) -> Config:
        """Derive a :class:`Config` from parameter values (ValueError names the problem)."""
        cfg = build_config(values, build_policy, changed, previous)
        _say_training_prior(cfg)            # said once while it lasts (new_warnings)
        for name in ('forward_command_topic', 'trajectory_topic'):
            if values[name]:
                # expanded as the publisher will be ({node}, ~), so that an unknown
                # substitution is refused here and not when the old publisher is gone
                try:
                    validate_full_topic_name(expand_topic_name(
                        values[name], self.get_name(), self.get_namespace()))
                except (NameValidationException, ValueError) as exc:
                    # rcl adds the name again with a caret under the fault: one line instead
                    reason = ' '.join(str(exc).split(', at ')[0].split('\n')[:1]).rstrip(':')
                    raise ValueError(f'{name}: {reason} ({values[name]!r})') from None
        return cfg

    def _startup_config(self) -> Config:
        values = self._transaction.values()
        self._learned_from_file(values)
        try:
            cfg = self._build(values)
        except PolicyUnavailable as exc:
            fallback = values['policy.fallback']
            if not fallback:
                raise
            self.get_logger().warning(f'{exc}; using policy.fallback {fallback!r}')
            self.set_parameters([Parameter('policy.name', T.STRING, fallback)])
            values['policy.name'] = fallback
            cfg = self._build(values)
        if cfg.warnings:
            self.get_logger().warning('; '.join(cfg.warnings))
        if values['observation.model'] == 'counts':
            self.get_logger().info('observation.model is counts: the fpoc.* parameters are '
                                   'ignored, frames are detection counts for '
                                   f"{values['observation.file']!r}")
        return cfg

    def _learned_from_file(self, values: dict) -> None:
        """
        At start-up, as at run time: a policy.file or policy.kernel alone selects ``learned``.

        Given together with an explicit ``policy.name`` other than ``learned``, the name wins and
        the log says the file is not used.
        """
        given = values['policy.file'] or len(values['policy.kernel'] or [])
        if not given or values['policy.name'] == 'learned':
            return
        if 'policy.name' in self._parameter_overrides:
            self.get_logger().warning(
                f"policy.name is {values['policy.name']!r}: policy.file "
                f"{values['policy.file']!r} / policy.kernel are not used (policy.name: learned "
                f'uses them)')
            return
        values['policy.name'] = 'learned'
        self.set_parameters([Parameter('policy.name', T.STRING, 'learned')])

    def _pre_set(self, params: list[Parameter]) -> list[Parameter]:
        """
        Make a kernel or a policy file select the learned policy, in the same atomic set.

        Setting a file also clears the kernel, which would otherwise take precedence.
        """
        names = {p.name for p in params}
        extra = []
        for p in params:
            if p.name == 'policy.kernel' and p.type_ == T.DOUBLE_ARRAY and len(p.value):
                extra.append(Parameter('policy.name', T.STRING, 'learned'))
            if p.name == 'policy.file' and p.type_ == T.STRING and p.value:
                extra.append(Parameter('policy.name', T.STRING, 'learned'))
                if 'policy.kernel' not in names:
                    extra.append(Parameter('policy.kernel', T.DOUBLE_ARRAY, []))
        seen = set(names)
        for p in extra:
            if p.name not in seen:
                seen.add(p.name)
                params = params + [p]
        return params

    def _check_while_declaring(self, params: list[Parameter]) -> None:
        """While declaring: check what the already declared grid allows (overrides included)."""
        for p in params:
            if p.name == 'policy.kernel' and p.value:
                check_kernel(p.value, grid_from(current_values(self, grid_params())),
                             'policy.kernel')

    def _apply_config(self, old: Config, cfg: Config) -> str:
        """Make the controller follow a new configuration; return the policy for the log."""
        said = new_warnings(cfg, old)       # each once while its cause lasts
        if said:
            self.get_logger().warning('; '.join(said))
        v, ov = cfg.values, old.values
        core = self.core
        was_following = core.follows_people
        follow_config(core, cfg, ov)
        if (v['forward_command_topic'], v['trajectory_topic']) != \
                (ov['forward_command_topic'], ov['trajectory_topic']):
            self._make_command_publishers(v)
        if (v['retry_period_s'], v['diagnostics_period_s']) != \
                (ov['retry_period_s'], ov['diagnostics_period_s']):
            self._make_timers(v)
        self._make_room_publishers()
        if self._many and self._people_published is not None and (
                v['room.frame_id'] != ov['room.frame_id'] or cfg.head != old.head):
            self._publish_people(self._people_published)      # the same people, new poses
        # Many targets still or moving are two searches (the people of a pass, or followed):
        # switching between them starts a new one, and ~/targets forgets whom the other knew.
        switched = self._many and cfg.settings.moving != old.settings.moving
        if v['absent.prior'] != ov['absent.prior'] or \
                v['search.targets'] != ov['search.targets'] or switched:
            forget = switched or (was_following and not core.follows_people)
            # a new search.targets has started the core's new search already (configure)
            begun = v['search.targets'] != ov['search.targets']
            return f'policy {cfg.policy_label}; {self._restart(forget=forget, begun=begun)}'
        if self._dwell_timer is not None and \
                (v['room.dwell_s'], v['room.recheck_period_s']) != \
                (ov['room.dwell_s'], ov['room.recheck_period_s']):
            self._make_room_timers(v)
        if cfg.head != old.head and core.enabled and not core.stopped:
            self._send_target()
        if not _same_prior(old.prior, cfg.prior):
            return (f'policy {cfg.policy_label}; belief.prior '
                    f"{'uniform' if prior_is_uniform(cfg.prior) else 'placing the target'} "
                    'from the next search (~/reset)')
        return f'policy {cfg.policy_label}'

    def _make_room_publishers(self) -> None:
        """
        With many targets, advertise the people (latched) and room_done; once, kept after.

        Created before the first search ends, so that a subscriber has matched the volatile
        room_done by then; one target advertises none of them.
        """
        if not self._many or self._targets_pub is not None:
            return
        self._targets_pub = self.create_publisher(PoseArray, '~/targets', STATE_QOS)
        self._cells_pub = self.create_publisher(Float32MultiArray, '~/target_cells', STATE_QOS)
        self._event_pubs['room_done'] = self.create_publisher(DiagnosticStatus, 'room_done', 10)

    def _make_command_publishers(self, values: dict) -> None:
        for pub in (self._forward_pub, self._trajectory_pub):
            if pub is not None:
                self.destroy_publisher(pub)
        self._forward_pub = self._trajectory_pub = None
        if values['forward_command_topic']:
            self._forward_pub = self.create_publisher(
                Float64MultiArray, values['forward_command_topic'], 10)
        if values['trajectory_topic']:
            self._trajectory_pub = self.create_publisher(
                JointTrajectory, values['trajectory_topic'], 10)

    def _make_timers(self, values: dict) -> None:
        for timer in (self._retry_timer, self._diag_timer):
            if timer is not None:
                self.destroy_timer(timer)
        self._retry_timer = None
        if values['retry_period_s'] > 0:
            self._retry_timer = self.create_timer(values['retry_period_s'],
                                                  self.guard.wrap(self._on_retry))
        self._diag_timer = self.create_timer(values['diagnostics_period_s'],
                                             self.guard.wrap(self._publish_diagnostics))

    # -- time ----------------------------------------------------------------------------
    def _now(self):
        return self.get_clock().now()

    def _now_s(self) -> float:
        return self._now().nanoseconds * 1e-9

    def _before_clock_jump(self) -> None:
        self._clock_before_s = self._now_s()

    def _on_clock_jump(self, jump) -> None:
        """
        Move the search's times with a jump of the clock (sim time set back, started or on).

        Without this, a /clock set back (a simulator's reset, ``ros2 bag play --loop``) leaves
        the target stamped in the future, and every frame is skipped as taken before the head
        settled; a first /clock far from 0 reads as a long stall, and so does use_sim_time
        turned on at run time. A /clock that runs ahead fast (a simulation faster than real
        time) is time that passed: only a first tick, from 0, moves the times forward.
        """
        before_s, self._clock_before_s = self._clock_before_s, None
        now_s = self._now_s()
        # rcl reports a switch of clock (use_sim_time) as a jump of 0: measure it
        delta_s = now_s - before_s if before_s is not None else jump.delta.nanoseconds * 1e-9
        switched = jump.clock_change in (ClockChange.ROS_TIME_ACTIVATED,
                                         ClockChange.ROS_TIME_DEACTIVATED)
        if not (switched or delta_s < 0 or before_s == 0.0):
            return
        self.core.shift_clock(delta_s)
        self._health = HealthMonitor(now_s, self.core.received, self.core.rejected)
        if self.core.enabled and not self.core.stopped and self._pan_tilt_msg is not None:
            self._send_target()     # stamped on the new clock (retry_period_s may be 0: never)
        said = f'the clock jumped {delta_s:+.3f} s: the search keeps its belief and counts its ' \
            'times from the new clock'
        if delta_s < 0 and not switched and self._dwell_timer is not None:
            self._restart_room_timers(now_s)
            # a line of its own, throttled apart from the first tick's (a call site each)
            self.get_logger().info(f"{said}; the room's turns and re-check start again now",
                                   throttle_duration_sec=WARN_THROTTLE_S)
        else:
            self.get_logger().info(said, throttle_duration_sec=WARN_THROTTLE_S)

    def _restart_room_timers(self, now_s: float) -> None:
        """
        Restart the dwell and re-check timers at ``now_s``, after the clock was set back.

        rcl restarts a timer at the jump only if the clock went back past the timer's last
        tick, and otherwise keeps its ticks (they come the jump's length late): the two timers
        could tick out of step, and out of step with the turns' origin, which stayed in the
        future (then every tick was a turn, the re-check's too). Here both timers and the origin
        restart together; a timer restarts a whole period from now (``Timer.reset``).
        """
        self._room.restart_turns(now_s)
        for timer in (self._dwell_timer, self._recheck_timer):
            if timer is not None:
                timer.reset()

    # -- outputs -------------------------------------------------------------------------
    def _send_target(self) -> None:
        """
        Publish the current fixation as the head's target, stamped now.

        Frames settle from that stamp: the core's target time is read on the same clock reading,
        not before the Bayes step and the choice, which take milliseconds on a loaded machine.
        """
        head, cell = self._config.head, self.core.fixation
        now = self._now()
        self.core.retarget(now.nanoseconds * 1e-9)
        if self._settled_timer is not None:     # a new target settles from now
            self.destroy_timer(self._settled_timer)
            self._settled_timer = None
        self._pan_tilt_msg = joints.joint_state(head, cell, now.to_msg())
        self._publish_target()

    def _publish_target(self, person: int | None = None) -> None:
        """Publish the head's target: the search's fixation, or a person in view (``person``)."""
        head, cell = self._config.head, self.core.fixation if person is None else person
        self._pan_tilt_pub.publish(self._pan_tilt_msg)
        core = self.core
        self._fixation_msg = grid_arrays.fixation(
            self._config.grid, None if core.scanning and person is None else cell,
            core.search_id)
        self._fixation_pub.publish(self._fixation_msg)
        if self._forward_pub is not None:
            self._forward_pub.publish(joints.forward_command(head, cell))
        if self._trajectory_pub is not None:
            self._trajectory_pub.publish(joints.joint_trajectory(
                head, cell, self._config.values['trajectory_duration_s']))
        if self._retry_timer is not None:
            self._retry_timer.reset()

    def _ask_when_settled(self) -> None:
        """
        After a frame taken before the head settled, ask for the fixation again once it has.

        A detector serves a fixation with the first image taken after it was commanded; from a
        head that arrives sooner than ``settle_time_s`` that image is skipped, and the next
        would come only with the re-send of ``retry_period_s``. The fixation alone is published
        again (the head's target and its settle time stand), when the settle time has passed.
        """
        if self._settled_timer is not None or self._fixation_msg is None:
            return
        wait_s = self.core.target_time_s + self.core.settle_time_s - self._now_s()
        self._settled_timer = self.create_timer(max(wait_s, 0.0) + SETTLED_MARGIN_S,
                                                self.guard.wrap(self._on_settled))

    def _on_settled(self) -> None:
        """Publish the waiting fixation again (:meth:`_ask_when_settled`), once."""
        self.destroy_timer(self._settled_timer)
        self._settled_timer = None
        if self.core.enabled and not self.core.stopped and self._fixation_msg is not None:
            self._fixation_pub.publish(self._fixation_msg)

    def _on_retry(self) -> None:
        if self.core.enabled and not self.core.stopped and self._pan_tilt_msg is not None:
            self._resends += 1
            self._publish_target()

    def _publish_belief(self) -> None:
        """Publish the belief to its subscribers (none matched: a volatile topic loses nothing)."""
        maps, images_wanted = (self._belief_pub.get_subscription_count(),
                               self._image_pub.get_subscription_count())
        if not (maps or images_wanted):
            return
        grid, belief = self._config.grid, self.core.belief
        if maps:
            self._belief_pub.publish(grid_arrays.to_multiarray(belief, grid))
        if images_wanted:
            self._image_pub.publish(images.belief_image(
                belief, grid, self.core.fixation, self._image_scale_px(),
                self._now().to_msg()))

    def _publish_people(self, found=()) -> None:
        """Publish the people of the room on ``~/targets`` and ``~/target_cells``."""
        self._people_published = tuple(found)
        cfg = self._config
        self._targets_pub.publish(people.people_poses(
            cfg.head, [p.cell for p in found], self._now().to_msg(), cfg.values['room.frame_id']))
        self._cells_pub.publish(people.people_array(
            cfg.grid, [(p.cell, p.probability) for p in found]))

    def _image_scale_px(self) -> int:
        """Pixels per cell of belief_image: as set, but the image fits MAX_IMAGE_SIDE_PX."""
        grid = self._config.grid
        fit = max(1, MAX_IMAGE_SIDE_PX // max(grid.rows, grid.cols))
        return min(self._config.values['belief_image_scale_px'], fit)

    def _publish_events(self, result) -> None:
        """Publish and log the events a frame fired (found, absent, gave_up, lost, reacquired)."""
        name = self.get_fully_qualified_name()
        ending = '' if not self.core.stopped or self._many else \
            '; the search has ended until ~/reset'
        confidence = self.core.settings.confidence
        if result.found is not None:
            found = result.found
            row, col = self._config.grid.cell(found.cell)
            pan, tilt = self._config.head.angles(found.cell)
            self._event_pubs['found'].publish(diagnostics.found_status(
                f'{name}: found', row, col, found.cell, pan, tilt, found.probability,
                found.fixations, found.forced_by, confidence,
                0 if self.core.settings.moving or self._many else
                self.core.settings.found_radius))
            clause = answer.confidence_clause('found', found.forced_by, found.probability,
                                              confidence)
            self.get_logger().info(
                f'{answer.heading("found", found.forced_by)}: the target is '
                f'{answer.where(found.forced_by)} '
                f'({row}, {col}), pan {pan:+.4f} rad, tilt {tilt:+.4f} rad, probability '
                f'{found.probability:.4f}, after {counted(found.fixations, "fixation")}'
                f'{clause}{ending}')
        if result.absent is not None:
            absent = result.absent
            self._event_pubs['absent'].publish(diagnostics.absent_status(
                f'{name}: absent', absent.probability, absent.fixations, absent.forced_by,
                confidence))
            clause = answer.confidence_clause('absent', absent.forced_by, absent.probability,
                                              confidence)
            self.get_logger().info(
                f'{answer.heading("absent", absent.forced_by)}: nobody is here, probability '
                f'{absent.probability:.4f} that nobody is here, after '
                f'{counted(absent.fixations, "fixation")}{clause}{ending}')
        if result.lost is not None:
            lost = result.lost
            row, col = self._config.grid.cell(lost.cell)
            status = diagnostics.lost_status(
                f'{name}: lost', row, col, lost.cell, lost.probability, lost.absent_probability,
                lost.fixations, lost.seconds_tracked)
            self._event_pubs['lost'].publish(status)
            self.get_logger().warning(f'{status.message}; searching again')
        if result.reacquired is not None:
            again = result.reacquired
            row, col = self._config.grid.cell(again.cell)
            pan, tilt = self._config.head.angles(again.cell)
            status = diagnostics.reacquired_status(
                f'{name}: reacquired', row, col, again.cell, pan, tilt, again.probability,
                again.fixations, again.seconds_lost)
            self._event_pubs['reacquired'].publish(status)
            self.get_logger().info(status.message)
        for event in result.people:
            self._publish_person_event(event)
        if result.gave_up is not None:
            session = self.core.session
            cause = _gave_up_cause(session)
            self._event_pubs['gave_up'].publish(diagnostics.gave_up_status(
                f'{name}: gave_up', result.gave_up.fixations,
                'the budget' if session.gave_up_reason == 'budget' else cause))
            self.get_logger().warning(f'gave up: no decision after '
                                      f'{counted(result.gave_up.fixations, "fixation")} '
                                      f'({cause}){ending}')

    def _publish_person_event(self, event) -> None:
        """Publish a person's found, lost or reacquired (moving many-target search)."""
        name = f'{self.get_fully_qualified_name()}: {event.kind}'
        row, col = self._config.grid.cell(event.cell)
        pan, tilt = self._config.head.angles(event.cell)
        if event.kind == 'found':
            msg = diagnostics.found_status(
                name, row, col, event.cell, pan, tilt, event.probability, event.fixations, '',
                self.core.settings.confidence, person=event.person)
        elif event.kind == 'lost':
            msg = diagnostics.lost_status(
                name, row, col, event.cell, event.probability, self.core.absent_probability,
                event.fixations, event.seconds, person=event.person)
        else:
            msg = diagnostics.reacquired_status(
                name, row, col, event.cell, pan, tilt, event.probability, event.fixations,
                event.seconds, person=event.person)
        self._event_pubs[event.kind].publish(msg)
        if event.kind == 'lost':
            self.get_logger().warning(msg.message)
        else:
            self.get_logger().info(msg.message)

    def _publish_diagnostics(self) -> None:
        self._check_publishers()
        health = self._health.report(
            self.core, self._now_s(), self._config.values['stall_timeout_s'],
            self._config.policy_label, sum(q.lost for q in self._sequences.values()),
            self._resends)
        if health.stalled:
            self.get_logger().warning(f'{health.message} ({health.detail}); target re-sent '
                                      f'{self._resends} times so far',
                                      throttle_duration_sec=WARN_THROTTLE_S)
        self._diag_pub.publish(diagnostics.diagnostic_array(
            [diagnostics.status(f'{self.get_fully_qualified_name()}: search', health.level,
                                health.message, health.values)], self._now().to_msg()))

    # -- inputs --------------------------------------------------------------------------
    def _check_publishers(self) -> None:
        """Count dropped frames only while one publisher sends each evidence topic."""
        for name, sub in self._evidence_subs.items():
            single = self.count_publishers(sub.topic_name) <= 1
            if single != self._single_publisher[name]:
                self._sequences[name].restart()
                self._single_publisher[name] = single

    def _count_drops(self, topic: str, info) -> None:
        if self._single_publisher[topic] and isinstance(info, dict):
            self._sequences[topic].see(info.get('publication_sequence_number'))

    def _on_evidence(self, msg: Float32MultiArray, info) -> None:
        self._take('evidence', info, _values_only, msg)

    def _on_evidence_image(self, msg: Image, info) -> None:
        self._take('evidence_image', info, images.evidence_channels, msg, msg.header.stamp,
                   images.read_frame_tag(msg))

    def _take(self, topic: str, info, read, msg, stamp=None, tag=('fixation', None)) -> None:
        """
        Offer a frame to the core: taken at its stamp, or at its arrival when there is none.

        A frame tagged as a search's one-time scan (``header.frame_id`` ``scan/<id>``) goes to
        :meth:`GazeController.offer_scan`; one tagged ``fixation/<id>`` is skipped unless it
        belongs to the current search.
        """
        now = self._now_s()
        self._count_drops(topic, info)
        try:
            values, offsets, groups = read(msg, self._config.grid)
        except EvidenceError as exc:
            self._handle(self.core.reject(str(exc)))
            return
        kind, search_id = tag
        if kind == 'scan':
            self._handle(self.core.offer_scan(values, search_id, now))
            return
        taken = now if stamp is None or stamps.is_zero(stamp) else stamps.to_seconds(stamp)
        settings = self._config.settings
        if groups is None and settings.group_stop and settings.targets == 'one' \
                and not settings.moving:
            self.get_logger().warning(
                'search.group_stop is on but the evidence carries no grouped detections: set '
                "the detector's publish_groups (docs/design.md section 6.15)", once=True)
        self._handle(self.core.offer(values, taken, now, search_id, offsets, groups))

    def _handle(self, result) -> None:
        if result.status == 'skipped' and result.reason == SETTLING:
            self._ask_when_settled()
            return
        if result.status == 'rejected':
            self.get_logger().warning(
                f'rejected an evidence frame ({self.core.rejected} so far): {result.reason}',
                throttle_duration_sec=WARN_THROTTLE_S)
            return
        if not result.applied:
            return
        if result.fixation is not None:
            self._send_target()         # first: the head can start moving while we report
        self._publish_belief()
        self._publish_events(result)
        if self.core.follows_people:
            self._follow_people(result)
        elif self._many and self.core.stopped:
            self._room_finished()

    # -- many targets: the room -------------------------------------------------------------
    def _room_finished(self) -> None:
        """
        Publish the people and room_done of a finished many-target search; keep them in view.

        ``room_done`` is published when every cell was decided (``found`` or ``absent``, also
        when the fixation budget forced it with ``search.decide_at_budget``), and the log says
        the room is done (``room done (search 2, found), forced by the fixation budget``); after
        ``gave_up`` the people are those whose cells reached the confidence, and the log says
        the search ended undecided at its limit, in the words of :mod:`..search.answer`
        (``search 2 ended undecided at the repeat stop (every cell fixated once)``).
        """
        core, grid = self.core, self._config.grid
        session = core.session
        link = PERSON_LINK[self._config.values['observation.model']]
        done = self._room.done(session.faces(link=link))
        self._publish_people(done.people)
        kind = 're-check' if done.recheck else 'search'
        where = ', '.join(f'{grid.cell(p.cell)} p={p.probability:.3f}' for p in done.people)
        limit = answer.limit_text(session.gave_up_reason, session.limit_cause)
        people_found = people_text(len(done.people))
        if core.decision in ('found', 'absent'):
            self._event_pubs['room_done'].publish(diagnostics.room_done_status(
                f'{self.get_fully_qualified_name()}: room_done', len(done.people),
                len(done.new), core.fixations, core.search_id, done.recheck,
                session.gave_up_reason, core.settings.confidence, session.limit_cause))
            heading = f'room done ({kind} {core.search_id}, {core.decision})' + \
                (f', forced by {limit}' if limit else '')
        else:
            heading = f'{kind} {core.search_id} ended undecided' + \
                (f' at {limit}' if limit else '')
            people_found += f' at the confidence {core.settings.confidence}'
        self.get_logger().info(f'{heading}: {people_found} ({len(done.new)} new)'
                               f'{": " + where if where else ""}')
        self._make_room_timers(self._config.values)
        self._look_at_next()

    def _follow_people(self, result) -> None:
        """
        Publish the people a moving many-target search follows after each applied frame.

        ``~/targets`` and ``~/target_cells`` hold the people found now, in the order of their
        numbers (they move, so every frame); ``room_done`` is published each time every cell
        becomes decided again, with the people found since the last one as new. The head's
        time is shared by the search itself (``motion.dwell_s``), not by the dwell timer.
        """
        session, core = self.core.session, self.core
        self._new_people += sum(e.kind == 'found' for e in result.people)
        found = [Person(t.cell, t.probability) for t in session.tracks.found]
        self._publish_people(found)
        if result.room_done:
            self._event_pubs['room_done'].publish(diagnostics.room_done_status(
                f'{self.get_fully_qualified_name()}: room_done', len(found), self._new_people,
                core.fixations, core.search_id, False, '', core.settings.confidence))
            self._new_people = 0

    def _make_room_timers(self, values: dict) -> None:
        """Start (again) the turn of the people in view and the periodic re-check."""
        self._stop_room_timers()
        self._room.start_turns(self._now_s(), values['room.dwell_s'],
                               values['room.recheck_period_s'])
        self._dwell_timer = self.create_timer(values['room.dwell_s'],
                                              self.guard.wrap(self._on_dwell))
        if values['room.recheck_period_s'] > 0:
            self._recheck_timer = self.create_timer(values['room.recheck_period_s'],
                                                    self.guard.wrap(self._on_recheck))

    def _stop_room_timers(self) -> None:
        for timer in (self._dwell_timer, self._recheck_timer):
            if timer is not None:
                self.destroy_timer(timer)
        self._dwell_timer = self._recheck_timer = None

    def _on_dwell(self) -> None:
        """Look at the next person, unless the re-check starts now (it sends the head)."""
        if self._room.dwell_tick(self._now_s()):
            self._look_at_next()

    def _look_at_next(self) -> None:
        """Look at the next person found (nothing while disabled or with nobody found)."""
        if not self.core.enabled:
            return
        person = self._room.next_person()
        if person is None:
            return
        self._pan_tilt_msg = joints.joint_state(self._config.head, person.cell,
                                                self._now().to_msg())
        self._publish_target(person.cell)

    def _on_recheck(self) -> None:
        """Search the room again; its people replace the list (those not known are new)."""
        if not self.core.enabled:
            return
        self.get_logger().info(f're-check of the room: {self._restart(recheck=True)}')

    def _restart(self, recheck: bool = False, forget: bool = False, begun: bool = False) -> str:
        """
        Start a new search (``~/reset``, a re-check); return what happened.

        Many targets: a re-check keeps the people known (to tell who is new) and their list on
        ``~/targets`` until it ends; any other new search forgets them and publishes nobody
        (``forget``: also the people a moving search followed, when motion was just switched).
        ``begun``: the core has started the new search already (one search id per search).
        """
        self._stop_room_timers()
        if recheck:
            self._room.recheck()
        elif forget or self._room.people or self._room.rooms_done or self.core.follows_people:
            self._room.forget()
            if self._targets_pub is not None:
                self._publish_people()
        self._new_people = 0
        cell = self.core.reset(self._now_s(), new_search=not begun)
        self._publish_belief()
        row, col = self._config.grid.cell(cell)
        if self.core.enabled:
            self._send_target()
            return f'belief reset; looking at ({row}, {col})'
        return f'belief reset; disabled, ({row}, {col}) is sent when enabled'

    def _on_reset(self, request, response):
        response.success = True
        response.message = self._restart()
        self.get_logger().info(response.message)
        return response

    def _on_enable(self, request, response):
        changed = self.core.set_enabled(request.data, self._now_s())
        state = 'enabled' if self.core.enabled else 'disabled'
        if changed and self.core.enabled and not self.core.stopped:
            self._send_target()
        response.success = True
        response.message = state if changed else f'already {state}'
        self.get_logger().info(f'gaze control {response.message}')
        return response


def _motion_text(motion: dict) -> str:
    """
    Describe a moving target's motion (``Motion.to_dict``) for the start-up line.

    The random walk and the jumps always; the walk (``motion.max_speed_cells``) and the
    leaving (``motion.leave_prob``) when the model has them: a target that only walks or
    leaves moves too, though its random walk and jumps are 0.
    """
    parts = [f"random walk {motion['sigma_cells']} cells/s, jump {motion['jump_prob']}/s"]
    if motion.get('max_speed_cells'):
        parts.append(f"walking up to {motion['max_speed_cells']} cells/s, turn "
                     f"{motion['turn_prob']}/s")
    if motion['leave_prob']:
        parts.append(f"leave {motion['leave_prob']}/s")
    return ', '.join(parts)


def _gave_up_cause(session) -> str:
    """
    Name what ended a search that gave up: the parameter of the rule behind its limit.

    ``search.max_fixations`` (the budget), ``search.stop_on_repeat`` or, many targets,
    ``search.inhibit_return`` (reason ``repeat``, :attr:`limit_setting`); a many-target search
    with no view left that would tell anything new gives up by no parameter's rule.
    """
    setting, reason = session.limit_setting, session.gave_up_reason
    if setting:
        return PARAMETER_NAMES[setting]
    if reason == 'repeat':
        return answer.REPEATS['nothing_new']
    return answer.LIMITS.get(reason, reason)


def _values_only(msg: Float32MultiArray, grid) -> tuple:
    """Read an ``evidence`` array as ``(values, None, None)``: no offsets, no groups."""
    return grid_arrays.from_multiarray(msg, grid), None, None


def main(args=None) -> int:
    """Run the ``gaze_controller`` node until shutdown (Ctrl-C or SIGTERM)."""
    return run_node(GazeControllerNode, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
