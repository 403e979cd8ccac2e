# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ``scene_camera`` node: a simulated camera over a real photograph, published as a driver does.

It stands in for camera hardware as ``simulated_camera`` stands in for a detector
(docs/design.md section 6.6). The scene is a held-out test scene (a test background with one
pasted test face, from ``seed``; ``scene.split: train`` takes the training scene of ``seed``
instead, for choosing settings on scenes no report uses) or a user's image (``scene.file``,
with the face centre as ``scene.face_x_px``/``scene.face_y_px``):

- ``view: fixed``: a fixed camera that sees the whole scene (for the detector's ``fovea`` mode);
  the grid (21x21 by default) tiles the image;
- ``view: pan_tilt``: a camera on the pan/tilt head; the scene spans the pan/tilt grid plus half
  the field of view on each side (:class:`ipomdp_gaze.vision.pan_tilt.SceneGeometry`), and the
  node publishes the field of view at the head's pose. ``camera_info.K`` follows from the image
  size and ``camera.hfov_deg``.

It subscribes ``pan_tilt`` (``sensor_msgs/JointState``, transient local), snaps it to the
nearest cell and arrives there after ``saccade_time_s`` (a fixed camera does not move: a
command only triggers a frame). With ``rate_hz = 0`` it publishes one frame on each arrival,
with ``rate_hz > 0`` it streams frames like a video camera, also while moving. A frame is
``image`` (``rgb8``), ``camera_info`` and, for ``pan_tilt``, ``joint_states`` (its pose), all
with one stamp. ``ground_truth`` (``std_msgs/Int32MultiArray`` ``[row, col]`` of the face
centre's cell in the grid of the view, transient local; ``[-1, -1]`` for nobody; a room of
``scene.faces`` faces: its first face) is published once when it is known.

With ``scene.motion: walk`` (pan_tilt view, the test scene) the face walks
(:class:`ipomdp_gaze.vision.walks.WalkSceneSet`, scene of ``seed``, at ``scene.speed_deg_s``
over ``scene.walk_duration_s``; ``scene.faces`` K from 1 to 4: K people, each on its own walk,
docs/design.md section 12.10): every frame is drawn at ``t``, the seconds from the node's
first frame to its stamp on the node's clock, and ``walk_truth`` (``std_msgs/Float64MultiArray``,
layout in :mod:`ipomdp_gaze.msg_adapters.grid_arrays`) says where the (first) face was in that
frame, with the frame's stamp (docs/design.md section 12.6). ``ground_truth`` is the walk's
start.
Every callback runs under a :class:`ipomdp_gaze.nodes.guard.CallbackGuard` (its counts in the
``/diagnostics`` status ``<node>: callbacks``).
"""
from __future__ import annotations

from dataclasses import dataclass
import sys

from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.head_camera import PinholeCamera
from ipomdp_gaze.msg_adapters import grid_arrays, images, joints
from ipomdp_gaze.search.controller_config import head_from
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import CameraInfo, Image, JointState
from std_msgs.msg import Float64MultiArray, Int32MultiArray

from . import NODE_NAMES
from .guard import CallbackGuard, GuardedNode
from .outputs import QuietPublishers
from .params import INT_MAX, joint_params, MAX_CELLS_PER_SIDE, Param, ParameterTransaction, T
from .qos import command_subscription, STATE_QOS
from .saccade import saccade_params, SaccadeMixin
from .spin import run_node

NODE_NAME = NODE_NAMES['scene_camera']
VIEWS = ('fixed', 'pan_tilt')
MOTIONS = ('still', 'walk')
SPLITS = ('test', 'train')
# Defaults of each view: the grid, the scene's side (fixed) and the face sizes in pixels.
VIEW_GRIDS = {'fixed': (21, 21, 1.0), 'pan_tilt': (11, 11, 5.0)}
VIEW_FACES = {'fixed': (60, 140), 'pan_tilt': (30, 70)}
IMAGE_QOS = QoSProfile(depth=2, reliability=ReliabilityPolicy.RELIABLE)


def scene_camera_params() -> list[Param]:
    """Every parameter of the scene camera, in declaration order."""
    return [
        Param('view', 'pan_tilt', T.STRING,
              'fixed: the whole scene (fovea mode); pan_tilt: the field of view at the head '
              'pose (read-only)', read_only=True, choices=VIEWS),
        Param('seed', 0, T.INTEGER, 'which scene of scene.split (read-only)', read_only=True,
              int_range=(0, INT_MAX)),
        Param('scene.split', 'test', T.STRING,
              'test: the held-out scenes (reports); train: the training scenes, for choosing '
              'settings on what no report uses (read-only)', read_only=True, choices=SPLITS),
        Param('scene.empty', False, T.BOOL,
              'pan_tilt view: the test scene of seed without its face, nobody here (read-only)',
              read_only=True),
        Param('scene.faces', '1', T.STRING,
              'pan_tilt view: a room of K faces or LO-HI drawn per seed, 0-8 (1: the one-face '
              'test scene; ground_truth is its first face; read-only)', read_only=True),
        Param('scene.motion', 'still', T.STRING,
              'still: the face stays; walk: it walks (pan_tilt view, the test scene; with '
              'scene.faces K, 1-4, each face walks its own path; read-only)', read_only=True,
              choices=MOTIONS),
        Param('scene.speed_deg_s', 5.0, T.DOUBLE, 'walk: walking speed in deg/s (read-only)',
              read_only=True, float_range=(0.0, 20.0)),
        Param('scene.walk_duration_s', 30.0, T.DOUBLE,
              'walk: length of the walk in seconds; after it the face stays where it ended '
              '(read-only)', read_only=True, float_range=(1.0, 3600.0)),
        Param('scene.file', '', T.STRING,
              "a user's image instead of a test scene (read-only)", read_only=True),
        Param('scene.face_x_px', -1.0, T.DOUBLE,
              "x of the face centre in scene.file's pixels (-1.0: no ground truth; read-only)",
              read_only=True, float_range=(-1.0, 1e6)),
        Param('scene.face_y_px', -1.0, T.DOUBLE,
              "y of the face centre in scene.file's pixels (read-only)", read_only=True,
              float_range=(-1.0, 1e6)),
        Param('scene.size_px', 420, T.INTEGER,
              'fixed view: side of the generated scene in pixels (read-only)', read_only=True,
              int_range=(64, 4096)),
        Param('scene.face_px', [0, 0], T.INTEGER_ARRAY,
              'smallest and largest face side in scene pixels ([0, 0]: 60-140 fixed, 30-70 '
              'pan_tilt; read-only)', read_only=True),
        Param('grid.rows', 0, T.INTEGER,
              "rows (0: the view's, 21 fixed, 11 pan_tilt; read-only)",
              read_only=True, int_range=(0, MAX_CELLS_PER_SIDE)),
        Param('grid.cols', 0, T.INTEGER,
              "columns (0: the view's, 21 fixed, 11 pan_tilt; read-only)",
              read_only=True, int_range=(0, MAX_CELLS_PER_SIDE)),
        Param('grid.spacing_deg', 5.0, T.DOUBLE, 'pan_tilt: degrees per cell (read-only)',
              read_only=True, float_range=(1e-6, 90.0)),
        Param('camera.width', 320, T.INTEGER, 'pan_tilt: image width in pixels (read-only)',
              read_only=True, int_range=(20, 4096)),
        Param('camera.height', 240, T.INTEGER, 'pan_tilt: image height in pixels (read-only)',
              read_only=True, int_range=(20, 4096)),
        Param('camera.hfov_deg', 25.0, T.DOUBLE,
              'horizontal field of view, edge to edge, of camera_info.K (read-only)',
              read_only=True, float_range=(1.0, 170.0)),
        Param('frame_id', 'camera', T.STRING, 'frame_id of image and camera_info (read-only)',
              read_only=True),
    ] + joint_params(limits=False) + saccade_params(max_rate_hz=100.0)


@dataclass
class SceneConfig:
    """What the scene camera derives from its parameters."""

    values: dict
    grid: Grid
    camera: PinholeCamera
    scene: object
    geometry: object = None
    head: object = None
    walk: object = None


def _scene_config(values: dict) -> SceneConfig:
    """Build the scene of the parameters (ValueError names the problem)."""
    from ipomdp_gaze.vision.pan_tilt import (PanTiltSceneSet, parse_faces, read_scene_file,
                                             SceneGeometry, user_scene)
    from ipomdp_gaze.vision.scenes import SceneSet
    view = values['view']
    rows, cols, spacing = VIEW_GRIDS[view]
    rows, cols = values['grid.rows'] or rows, values['grid.cols'] or cols
    if view == 'pan_tilt':
        spacing = values['grid.spacing_deg']
    grid = Grid(rows, cols, spacing)
    faces = tuple(values['scene.face_px'])
    if len(faces) != 2:
        raise ValueError(f'scene.face_px must be [min, max], got {list(faces)}')
    faces = VIEW_FACES[view] if faces == (0, 0) else faces
    centre = None
    if values['scene.face_x_px'] >= 0 or values['scene.face_y_px'] >= 0:
        centre = (values['scene.face_x_px'], values['scene.face_y_px'])
    try:
        room = parse_faces(values.get('scene.faces', '1')) != (1, 1)
    except ValueError as exc:                   # 'faces must be ...': name the parameter
        raise ValueError(f'scene.{exc}') from None
    if view != 'pan_tilt' and room:
        raise ValueError('scene.faces is for the pan_tilt view')
    # in the node's own words (the scene set's say faces=0 and empty=True), and never ignored
    if room and values['scene.file']:
        raise ValueError("scene.faces is for the held-out scenes, not scene.file (a user's "
                         'photo: scene.face_x_px, scene.face_y_px give its face)')
    if room and values['scene.empty']:
        raise ValueError('scene.empty shows the one-face scene without its face: leave '
                         "scene.faces '1' (a room of nobody: scene.faces '0' alone)")
    walking = values.get('scene.motion', 'still') == 'walk'
    split = values.get('scene.split', 'test')
    if walking:
        _check_walk(values, faces)
    if view == 'pan_tilt':
        camera = PinholeCamera.from_fov(values['camera.width'], values['camera.height'],
                                        values['camera.hfov_deg'])
        geometry = SceneGeometry(grid, camera)
        if values['scene.file']:
            scene = user_scene(read_scene_file(values['scene.file']), centre, geometry)
        else:
            scene = PanTiltSceneSet(split, geometry, faces, 'rgb', values['seed'],
                                    empty=values['scene.empty'],
                                    faces=values.get('scene.faces', '1')).scene(0)
        walk = None
        if walking:
            from ipomdp_gaze.vision.walks import WalkSceneSet
            walk = WalkSceneSet(split, geometry, values['seed'], values['scene.speed_deg_s'],
                                values['scene.walk_duration_s'],
                                faces=parse_faces(values.get('scene.faces', '1'))[0]).scene(0)
        return SceneConfig(dict(values), grid, camera, scene, geometry,
                           head_from(values, grid), walk)
    if values['scene.file']:
        scene = user_scene(read_scene_file(values['scene.file']), centre, grid=grid.shape)
    else:
        scene = SceneSet(split, values['scene.size_px'], faces, grid.shape,
                         color='rgb', seed=values['seed']).scene(0)
    height, width = scene.image.shape[:2]
    camera = PinholeCamera.from_fov(width, height, values['camera.hfov_deg'])
    return SceneConfig(dict(values), grid, camera, scene)


def _check_walk(values: dict, faces: tuple) -> None:
    """Refuse ``scene.motion: walk`` where no walk scene exists (ValueError names why)."""
    from ipomdp_gaze.vision.pan_tilt import FACE_PX, parse_faces
    why = None
    lo, hi = parse_faces(values.get('scene.faces', '1'))
    if values['view'] != 'pan_tilt':
        why = 'the pan_tilt view (a fixed camera sees no walk)'
    elif values['scene.file']:
        why = "a held-out test scene, not scene.file (a user's image has no walk)"
    elif values['scene.empty']:
        why = 'a face to walk, not scene.empty'
    elif lo != hi or not 1 <= lo <= 4:
        why = f"a number of faces from 1 to 4, not scene.faces {values['scene.faces']!r}"
    elif tuple(faces) != FACE_PX:
        why = f"the test scenes' face sizes, not scene.face_px {list(faces)}"
    if why is not None:
        raise ValueError(f'scene.motion walk needs {why}')


class SceneCameraNode(SaccadeMixin, GuardedNode, QuietPublishers, Node):
    """A simulated camera over a real photograph (see the module docstring)."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        self.guard = CallbackGuard(self)
        self._transaction = ParameterTransaction(self, scene_camera_params(),
                                                 self.guard.refusing(self._build),
                                                 self.guard.wrap(self._apply_config))
        self._transaction.declare()
        self._transaction.start(_scene_config(self._transaction.values()))
        cfg = self._config
        self.pose = self.goal = cfg.grid.center_index
        self.moving = False
        self._views = {}
        self._image_pub = self.create_publisher(Image, 'image', IMAGE_QOS)
        self._info_pub = self.create_publisher(CameraInfo, 'camera_info', IMAGE_QOS)
        self._joint_pub = self.create_publisher(JointState, 'joint_states', 10)
        self._truth_pub = self.create_publisher(Int32MultiArray, 'ground_truth', STATE_QOS)
        self._walk_pub = self.create_publisher(Float64MultiArray, 'walk_truth', 10) \
            if cfg.walk is not None else None
        self._walk_start = None
        command_subscription(self, JointState, 'pan_tilt', self.guard.wrap(self._on_command))
        self._saccade_timer = self._frame_timer = None
        self._make_timers(cfg.values)
        scene = cfg.scene
        if scene.cell is not None:
            self._truth_pub.publish(grid_arrays.ground_truth(cfg.grid, cfg.grid.index(
                *scene.cell)))
        elif cfg.values.get('scene.empty') or not cfg.values.get('scene.file'):
            self._truth_pub.publish(grid_arrays.ground_truth(cfg.grid, None))   # [-1, -1]
        self.guard.publish_status()
        height, width = self._view(self.pose).shape[:2]
        where = 'nobody here' if cfg.values.get('scene.empty') else 'no face given' \
            if scene.face_centre_px is None else \
            f'face centre ({scene.face_centre_px[0]:.1f}, {scene.face_centre_px[1]:.1f}) px ' \
            f'in cell {scene.cell}'
        if len(scene.faces) > 1:
            where = f'{len(scene.faces)} faces in cells ' + ', '.join(
                str(f.cell) for f in scene.faces)
        if cfg.walk is not None:
            where += (f", walking at {cfg.values['scene.speed_deg_s']:g} deg/s for "
                      f"{cfg.values['scene.walk_duration_s']:g} s from its first frame")
        self.get_logger().info(
            f"{cfg.values['view']} view of {scene.background} scene "
            f'{scene.image.shape[1]}x{scene.image.shape[0]} px ({where}); {width}x{height} px '
            f'images, {cfg.grid.rows}x{cfg.grid.cols} grid')

    @property
    def _config(self) -> SceneConfig:
        """Return the configuration in force."""
        return self._transaction.config

    # -- parameters ----------------------------------------------------------------------
    def _build(self, values: dict, changed=None, previous=None) -> SceneConfig:
        """Keep the scene and walk; follow the joint mapping and times (ValueError: why not)."""
        cfg = previous
        head = head_from(values, cfg.grid) if cfg.geometry is not None else None
        return SceneConfig(dict(values), cfg.grid, cfg.camera, cfg.scene, cfg.geometry, head,
                           cfg.walk)

    def _apply_config(self, old: SceneConfig, cfg: SceneConfig) -> None:
        v, ov = cfg.values, old.values
        if (v['saccade_time_s'], v['rate_hz']) != (ov['saccade_time_s'], ov['rate_hz']):
            self._make_timers(v)

    def _make_timers(self, values: dict) -> None:
        self._make_saccade_timers(values)

    # -- head ------------------------------------------------------------------------------
    def _on_command(self, msg: JointState) -> None:
        cfg = self._config
        # a fixed camera: the command triggers a frame
        goal = self.pose if cfg.head is None else self._commanded_cell(msg, cfg.head)
        if goal is not None:
            self._saccade_to(goal, self._command_stamp_of(msg))

    def _arrived(self) -> None:
        if self._config.values['rate_hz'] == 0:
            self._publish_frame()

    # -- outputs -------------------------------------------------------------------------
    def _view(self, cell: int):
        """Return the image the camera takes with the head at ``cell`` (rendered once)."""
        cfg = self._config
        if cfg.geometry is None:
            return cfg.scene.image
        view = self._views.get(cell)
        if view is None:
            view = self._views[cell] = cfg.geometry.render(cfg.scene.image,
                                                           cfg.grid.cell(cell))
        return view

    def _walk_view(self, now):
        """Return the view of the walk at ``now`` and publish where the face is in it."""
        cfg = self._config
        if self._walk_start is None:
            self._walk_start = now
        t_s = (now - self._walk_start).nanoseconds * 1e-9
        truth = cfg.walk.truth_at(t_s)
        self._walk_pub.publish(grid_arrays.walk_truth(now.to_msg(), t_s, truth.position,
                                                      truth.cell))
        return cfg.geometry.render(cfg.walk.image_at(t_s), cfg.grid.cell(self.pose))

    def _publish_frame(self) -> None:
        cfg = self._config
        now = self.get_clock().now()
        stamp = now.to_msg()
        frame_id = cfg.values['frame_id']
        if cfg.head is not None:
            self._joint_pub.publish(joints.joint_state(cfg.head, self.pose, stamp))
        self._info_pub.publish(images.camera_info(cfg.camera, stamp, frame_id))
        view = self._view(self.pose) if cfg.walk is None else self._walk_view(now)
        self._image_pub.publish(images.camera_image(view, stamp, frame_id))


def main(args=None) -> int:
    """Run the ``scene_camera`` node until shutdown (Ctrl-C or SIGTERM)."""
    return run_node(SceneCameraNode, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
