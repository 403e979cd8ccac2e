# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ROS 2 demo: the nodes as separate processes, watched from this process.

:func:`run_demo` starts ``gaze_controller`` and then ``simulated_camera`` (once the controller's
first target has arrived here, so no update is missed), prints every fixation until the ``found``
event, checks the answer against the camera's ``ground_truth`` and stops both with SIGTERM. It
runs on its own ROS domain with discovery limited to this host, so it never drives a real head.

:func:`faces_setup` is the face demo (``--scene faces``): ``gaze_controller``, then
``foveal_detector`` (once the target is out) and ``scene_camera`` (once the detector listens to
``image``), with the shipped ``config/faces_<mode>_*.yaml`` files; the answer is right when the
found cell is within one cell (Chebyshev) of the face centre's cell.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from pathlib import Path
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray
from ipomdp_gaze.files.share_files import config_file
from ipomdp_gaze.files.yaml_files import yaml_parameters
from ipomdp_gaze.harness.processes import domain_id_for, exit_states, isolated_nodes
from ipomdp_gaze.harness.watch import quiet_condition, SearchRecord, Watch
from ipomdp_gaze.model.belief import entropy
from ipomdp_gaze.model.head import PanTiltMap
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays, joints
from ipomdp_gaze.nodes import NODE_NAMES
from ipomdp_gaze.nodes.params import joint_params
from ipomdp_gaze.search import answer as words
from ipomdp_gaze.search.controller_config import (fpoc_from, grid_from, head_from,
                                                  observation_from, prior_from)
from ipomdp_gaze.search.session import pooled_belief, SearchSettings
from ipomdp_gaze.simulation.evaluation import answer_is_right, RIGHT_RADIUS_CELLS
import numpy as np
from sensor_msgs.msg import Image

# The watcher's wait for a condition (it polls; the records fill in the watch's spin thread).
POLL_S = 0.05
# Pictures: after the answer, wait until the detector's annotated_image has been quiet this long.
PICTURE_QUIET_S, PICTURE_WAIT_S = 0.5, 3.0
# How long the disabled controller's topics must stay silent before the demo's new search.
QUIET_S = 0.3
FPOC_OVERRIDES = {
    'camera': {},
    # The human FPOC is calibrated at 0.42 degrees per cell (docs/design.md section 2).
    'human': {'fpoc.model': 'human', 'grid.spacing_deg': 0.42},
}


def _ros_value(value) -> str:
    if isinstance(value, bool):
        return 'true' if value else 'false'
    return str(value)


@dataclass
class DemoSetup:
    """
    The demo's nodes and the controller's grid and head, as the YAML files say.

    ``nodes`` lists ``(node, ros_args)`` in start order (keys of ``NODE_NAMES``); ``scene`` is
    ``'gaussian'`` (the simulated camera) or ``'faces'``; ``mode`` the detector's (faces);
    ``image_px`` the ``(width, height)`` of the fixed scene (fovea mode, for pixel answers);
    ``scan`` whether each search starts with the one-time scan (its belief comes first);
    ``settings`` the controller's search settings (its confidence, absent prior and found
    radius: the progress lines name the answer as the controller decides it); ``prior`` its
    ``belief.prior`` as probabilities (N,), None when uniform (a reset's belief is at it).
    """

    nodes: list
    grid: object
    head: PanTiltMap
    overrides: dict = field(default_factory=dict)
    scene: str = 'gaussian'
    mode: str = ''
    image_px: tuple | None = None
    scan: bool = False
    settings: SearchSettings = field(default_factory=SearchSettings)
    prior: np.ndarray | None = None

    @property
    def priors(self) -> tuple:
        """Return the priors a reset's belief may be at besides the uniform one (``is_update``)."""
        return () if self.prior is None else (self.prior,)

    @property
    def tolerance_cells(self) -> int:
        """How far (Chebyshev, cells) the answer may be from the truth and still be right."""
        return RIGHT_RADIUS_CELLS if self.scene == 'faces' else 0


def check_controller(values: dict) -> None:
    """
    Build the controller's grid, observation model and policy as the node will, here.

    ``values`` are the controller's parameters from its YAML file and the demo's overrides (the
    rest take the node's defaults). A bad ``--policy`` (an unknown name, a policy that needs an
    FPOC on a count model, a policy file that does not fit) is refused before any node starts;
    a missing ``policy.file`` is accepted when ``policy.fallback`` names a baseline, as the node
    does.

    Raises
    ------
    ValueError
        Naming the problem.

    """
    from ipomdp_gaze.nodes.controller import controller_params
    from ipomdp_gaze.policies.registry import build_policy, POLICY_NAMES, PolicyUnavailable
    full = {p.name: p.default for p in controller_params()}
    full.update(values)
    name = full['policy.name']
    if name not in POLICY_NAMES:
        raise ValueError(f"--policy must be one of {', '.join(POLICY_NAMES)}, got {name!r}")
    grid = grid_from(full)
    fpoc = fpoc_from(full) if full['observation.model'] != 'counts' else None
    model = observation_from(full, grid, fpoc)
    try:
        build_policy(name, grid, model, kernel=full['policy.kernel'] or None,
                     file=full['policy.file'], action=full['policy.action'],
                     warn=lambda message: None)
    except PolicyUnavailable:
        if name != 'learned' or not full['policy.fallback']:
            raise
    except ValueError as exc:
        raise ValueError(f'--policy {name}: {exc}') from None


def _ros_args(path, overrides: dict) -> list:
    args = ['--params-file', str(path)]
    for name, value in overrides.items():
        args += ['-p', f'{name}:={_ros_value(value)}']
    return args


def demo_setup(fpoc: str = 'camera', policy: str | None = None, seed: int = 0,
               target: tuple | None = None) -> DemoSetup:
    """Build the node arguments from the shipped YAML files and the demo's options."""
    if fpoc not in FPOC_OVERRIDES:
        raise ValueError(f"fpoc must be one of {', '.join(FPOC_OVERRIDES)}, got {fpoc!r}")
    controller_yaml, camera_yaml = config_file('controller.yaml'), config_file('camera.yaml')
    shared = dict(FPOC_OVERRIDES[fpoc], seed=seed)
    controller = dict(shared)
    policy = policy or ('elm' if fpoc == 'human' else None)
    if policy:
        controller['policy.name'] = policy
    camera = dict(shared)
    if target is not None:
        camera.update({'target_row': int(target[0]), 'target_col': int(target[1])})
    values = yaml_parameters(controller_yaml, 'gaze_controller')
    values.update(controller)
    check_controller(values)
    grid = grid_from(values)
    if target is not None and not (0 <= target[0] < grid.rows and 0 <= target[1] < grid.cols):
        raise ValueError(f'--target {target[0]},{target[1]} is outside the {grid.rows}x'
                         f'{grid.cols} grid (rows 0..{grid.rows - 1}, columns '
                         f'0..{grid.cols - 1})')
    return DemoSetup([('controller', _ros_args(controller_yaml, controller)),
                      ('camera', _ros_args(camera_yaml, camera))], grid,
                     head_from(values, grid), controller,
                     settings=SearchSettings.from_parameters(values, grid=grid),
                     prior=prior_from(values, grid))


def faces_setup(fovea: bool = False, policy: str | None = None, seed: int = 0,
                empty: bool = False, walk: dict | None = None) -> DemoSetup:
    """
    Build the face demo from ``config/faces_<mode>_*.yaml``: scene camera, detector, controller.

    ``fovea`` selects the fixed camera and the digital fovea (mode ``fovea``), else the camera
    on the pan/tilt head (mode ``camera``); ``seed`` picks the held-out test scene, ``empty``
    shows it without its face (the pan/tilt camera's ``scene.empty``). ``walk``: the scene
    camera's ``scene.*`` parameters of a walking face, and the controller runs the tracker's
    ``config/faces_camera_tracking.yaml`` (docs/design.md section 12.6).
    """
    mode = 'fovea' if fovea else 'camera'
    files = {node: config_file(f'faces_{mode}_{node}.yaml')
             for node in ('controller', 'detector', 'scene_camera')}
    if walk is not None:
        files['controller'] = config_file('faces_camera_tracking.yaml')
    controller = {'policy.name': policy} if policy else {}
    values = {p.name: p.default for p in joint_params(limits=True)}
    values.update(yaml_parameters(files['controller'], 'gaze_controller'))
    values.update(controller)
    check_controller(values)
    grid = grid_from(values)
    image_px = None
    if fovea:
        side = yaml_parameters(files['scene_camera'], 'scene_camera').get('scene.size_px', 420)
        image_px = (int(side), int(side))
    from ipomdp_gaze.files.observation_file import load_observation
    scan = bool(values.get('search.scan', True)) and \
        load_observation(values['observation.file']).has_scan
    camera = {'seed': seed, 'scene.empty': True} if empty else {'seed': seed}
    camera.update(walk or {})
    return DemoSetup([('controller', _ros_args(files['controller'], controller)),
                      ('detector', _ros_args(files['detector'], {})),
                      ('scene_camera', _ros_args(files['scene_camera'], camera))],
                     grid, head_from(values, grid), controller, 'faces', mode, image_px, scan,
                     SearchSettings.from_parameters(values, grid=grid), prior_from(values, grid))


def _started(watch, record, node: str):
    """Return what has to be seen before the node after ``node`` may start."""
    if node == 'recorder':
        return lambda: NODE_NAMES['recorder'] in watch.node.get_node_names()
    if node == 'controller':
        return lambda: bool(record.targets)
    if node == 'detector':
        return lambda: watch.node.count_subscribers('image') > 0
    return None


def _with_recorder(setup: DemoSetup, record, compression: str, pictures,
                   split: tuple = (0.0, 0.0)) -> list:
    """
    Return the nodes to start: a recorder first (``record``), the detector drawing.

    ``split`` is the recorder's ``max_bag_size_mb`` and ``max_bag_duration_s``.
    """
    nodes = list(setup.nodes)
    if (pictures is not None or record) and setup.scene == 'faces':
        # The detector's annotated_image (pictures) and its raw detections (recorded).
        nodes = [(node, args + ['-p', 'publish_annotated:=true'] if node == 'detector' else args)
                 for node, args in nodes]
    if record:
        args = ['-p', f'path:={Path(record).resolve()}']
        if pictures is None:            # no pictures asked for: the bag without them
            from ipomdp_gaze.nodes.recorder import TOPICS
            args += ['-p', f"topics:=[{','.join(t for t in TOPICS if t != 'annotated_image')}]"]
        if compression:
            args += ['-p', f'compression:={compression}']
        from ipomdp_gaze.nodes.recorder import split_overrides
        args += split_overrides(*split)
        if setup.scene != 'faces':
            args += ['-p', f"nodes:=[{NODE_NAMES['controller']}]"]
        args += ['-p', 'diagnostics_period_s:=0.1']
        nodes.insert(0, ('recorder', args))
    return nodes


def _restart_heard(setup: DemoSetup, watch, recorder, wait, records, pictures: bool) -> float:
    """
    Start the search again once everyone listening hears every node; return when (monotonic).

    The first frames go out as soon as the last node meets the controller, often before the
    recorder (``recorder``, when recording) or the demo's own subscriptions have matched that
    node's publishers, and what a volatile topic sends before it is matched is lost. So the
    search that is recorded and drawn is a new one: the demo waits until the recorder has
    matched the frame publishers and the controller's (and the camera images and annotated
    images) and its own watch the controller's topics (and the annotated image, when drawing
    faces); then it disables the controller, waits until the controller's topics (``records``
    but the last, the annotated images) are quiet, resets it, forgets everything of the first
    search and enables it again. Nothing the controller sends while disabled belongs to either
    search, so no message in flight from the first search is taken for one of the new search.
    """
    topics = [('evidence', 'evidence_image'), ('fixation',), ('pan_tilt',), ('belief',),
              ('found',), ('absent',), ('gave_up',)]
    if setup.scene == 'faces':
        topics.append(('image',))
        if pictures:
            topics.append(('annotated_image',))
    own = ['belief', 'pan_tilt', 'found', 'absent'] + \
        (['annotated_image'] if pictures and setup.scene == 'faces' else [])
    if not wait(lambda: (recorder is None or all(recorder.matched(*t) for t in topics))
                and all(watch.matched(t) for t in own)):
        raise RuntimeError('the recorder or the demo did not hear the nodes in time')
    controller = NODE_NAMES['controller']
    watch.enable(False, controller)
    if not wait(quiet_condition(records[:-1], QUIET_S)):
        raise RuntimeError('the controller did not fall quiet once disabled')
    watch.reset(controller)
    for entries in records:
        del entries[:]
    started = time.monotonic()
    watch.enable(True, controller)
    return started


class RecorderStatus:
    """The recorder's latest ``recording`` status on ``/diagnostics``: matched publishers."""

    def __init__(self, watch):
        self.values = {}
        watch.node.create_subscription(DiagnosticArray, '/diagnostics', self, 50)

    def __call__(self, msg) -> None:
        """Take a ``/diagnostics`` message."""
        for status in msg.status:
            if status.name.endswith(f"{NODE_NAMES['recorder']}: recording"):
                self.values = diagnostics.values_of(status)

    def matched(self, *topics) -> bool:
        """Whether the recorder has matched a publisher on one of ``topics``."""
        return any(int(self.values.get(f'publishers_{t}', 0)) > 0 for t in topics)


def _pictures(setup: DemoSetup, record: SearchRecord, annotated: list, stats: dict) -> list:
    """
    Return pictures of the search, one per belief.

    The detector's ``annotated_image`` (faces) or, without a camera image (the simulated
    camera), the belief and fixations drawn on the grid.
    """
    from ipomdp_gaze.msg_adapters import images
    if setup.scene == 'faces':
        return [images.rgb8_array(msg) for _, msg in annotated]
    from ipomdp_gaze.vision.annotate import annotate, grid_canvas
    grid, head = setup.grid, setup.head
    n = min(int(stats.get('fixations') or 0), len(record.beliefs), len(record.targets))
    looked = [head.nearest_cell(*joints.angles_from_joint_state(msg, head))
              for _, msg in record.targets[:n]]
    canvas, cell_map = grid_canvas(grid, 40)
    label = 'most likely'
    if stats.get('stop') == 'found':
        label = 'found, forced' if str(stats.get('ended', '')).startswith('forced:') \
            else 'found'
    frames = []
    for i in range(n):
        belief = grid_arrays.from_multiarray(record.beliefs[i][1], grid)
        found = (stats['cell'], stats['probability']) if i == n - 1 and 'cell' in stats \
            else None
        frames.append(annotate(canvas, cell_map, belief, looked[:i + 1], found=found,
                               label=f'fixation {i + 1}', found_label=label))
    return frames


def run_demo(setup: DemoSetup, timeout_s: float = 60.0, domain_id: int | None = None,
             verbose: bool = False, out=print, stats: dict | None = None,
             max_fixations: int = 60, record=None, compression: str = '',
             pictures: list | None = None, max_bag_size_mb: float = 0.0,
             max_bag_duration_s: float = 0.0) -> int:
    """
    Run the demo; 0 when an answer was judged in time and every node stopped cleanly.

    The answer is the ``found`` event's cell or, when no cell reached the controller's
    confidence after ``max_fixations`` fixations, the most likely cell then. ``stats``, when
    given, is filled with the answer (``row``, ``col``, ``cell``, ``probability``,
    ``fixations``), ``stop`` (``found``, ``budget`` or ``timeout``), ``truth`` (the ground
    truth's ``(row, col)``), ``right`` and ``search_s``: seconds from starting the last node to
    the belief of the answer's last fixation. ``record``: a ``recorder`` node writes the
    search to this new bag directory (``compression``: ``''`` or ``zstd``; ``max_bag_size_mb``
    and ``max_bag_duration_s`` split it, 0: one file). ``pictures``, when
    given, is filled with an RGB picture of the search per belief (the last one shows the
    answer).
    """
    domain = domain_id_for() if domain_id is None else domain_id
    stats = {} if stats is None else stats
    with isolated_nodes(domain, prefix='ipomdp-gaze-demo-') as nodes:
        procs = [nodes.add(node, args)
                 for node, args in _with_recorder(setup, record, compression, pictures,
                                                  (max_bag_size_mb, max_bag_duration_s))]
        watch = Watch(domain, 'gaze_demo', nodes)
        record_ = SearchRecord(watch, depth=200, updates_only=True,
                               n_cells=setup.grid.n_cells, priors=setup.priors)
        annotated = watch.record(Image, 'annotated_image', 50) if pictures is not None \
            else []
        recorder = RecorderStatus(watch) if record else None
        deadline = time.monotonic() + timeout_s

        def wait(condition) -> bool:
            """Wait until the demo's deadline; NodeExited when a node process exits."""
            return watch.wait_until(condition, max(0.0, deadline - time.monotonic()), POLL_S)

        g = setup.grid
        where = f'{setup.scene} scene, detector mode {setup.mode}, ' if setup.mode else ''
        out(f'ipomdp-gaze demo: {where}{g.rows}x{g.cols} grid at {g.spacing_deg} deg/cell, '
            f'ROS domain {domain}; starting ' + ', then '.join(p.name for p in procs))
        status = 1
        try:
            for proc in procs:
                started = time.monotonic()
                proc.start()
                ready = _started(watch, record_, proc.node)
                if proc is not procs[-1] and ready is not None and not wait(ready):
                    raise RuntimeError(f"{proc.name} did not come up within the demo's "
                                       f'--timeout of {timeout_s:g} s')
            if recorder is not None or pictures is not None:
                started = _restart_heard(setup, watch, recorder, wait,
                                         [record_.beliefs, record_.targets, record_.found,
                                          record_.absent, annotated], pictures is not None)
            status = _follow(setup, record_, wait, timeout_s, out, stats, max_fixations)
            if recorder is not None:        # the bag's metadata: the nodes' parameters
                nodes_ = [NODE_NAMES[n] for n in ('controller', 'detector')
                          if n in {p.node for p in procs}]
                if not wait(lambda: set(nodes_) <= set(
                        str(recorder.values.get('parameters_of', '')).split(','))):
                    out('ipomdp-gaze demo: the recorder did not get the parameters of '
                        + ', '.join(nodes_))
            if stats.get('fixations'):
                stats['search_s'] = record_.beliefs[stats['fixations'] - 1][0] - started
            if pictures is not None:
                if setup.scene == 'faces':        # the redraw after the answer, then quiet
                    watch.wait_until(lambda: annotated and
                                     time.monotonic() - annotated[-1][0] > PICTURE_QUIET_S,
                                     PICTURE_WAIT_S)
                pictures.extend(_pictures(setup, record_, annotated, stats))
        except RuntimeError as exc:        # the error on stderr; the nodes' output follows
            print(f'ipomdp-gaze demo: error: {exc}', file=sys.stderr, flush=True)
        finally:
            alive = {p.node: p.running for p in procs}
            codes = {p.node: code for p, code in nodes.stop(procs[::-1])}
            watch.close()
        if verbose or status:
            for p in procs:
                out(f'--- {p.node} output ---\n{p.output().rstrip()}')
        clean = all(codes[k] == 0 for k, running in alive.items() if running)
        states = exit_states(codes, alive)
        which = 'both nodes' if len(procs) == 2 else f'all {len(procs)} nodes'
        if record and codes.get('recorder') == 0:
            out(f'recorded the search to {record}')
        out(f'stopped {which} ({states})' + ('' if clean else ': NOT a clean shutdown'))
        return status if clean else 1


def _where(setup: DemoSetup, cell: int) -> str:
    """Say where a cell is: its pixel centre (a fixed camera) or its pan and tilt."""
    if setup.image_px is not None:
        from ipomdp_gaze.vision.search import cell_centre_px
        x, y = cell_centre_px(setup.grid, cell, setup.image_px)
        return f'pixel ({x:5.1f}, {y:5.1f})'
    pan, tilt = setup.head.angles(cell)
    return f'pan {math.degrees(pan):+6.2f} deg  tilt {math.degrees(tilt):+6.2f} deg'


def most_likely(setup: DemoSetup, belief: np.ndarray) -> tuple[int, float, float]:
    """
    Return the answer as the controller decides it: its cell, its probability and P(absent).

    The cell whose square of ``search.found_radius`` cells holds the most belief (the cell
    alone with radius 0; ties to the lowest index), as the controller's ``found`` rule; the
    belief message's cells sum to ``1 - P(absent)``.
    """
    settings = setup.settings
    radius = 0 if settings.moving else settings.found_radius
    pooled = pooled_belief(np.asarray(belief, dtype=float), setup.grid, radius)
    cell = int(np.argmax(pooled))
    absent = max(0.0, 1.0 - float(np.sum(belief))) if settings.absent_prior > 0 else 0.0
    return cell, float(pooled[cell]), absent


def _state(setup: DemoSetup, belief: np.ndarray) -> str:
    """
    Say what a belief would answer: ``most likely (r, c) p=..  nobody p=..  entropy .. nats``.

    ``nobody p`` (P(absent)) only when the search can end ``absent`` (``absent.prior`` > 0).
    """
    cell, probability, absent = most_likely(setup, belief)
    nobody = f'  nobody p={absent:.3f}' if setup.settings.absent_prior > 0 else ''
    everything = np.append(belief, absent) if setup.settings.absent_prior > 0 else belief
    return (f'most likely {setup.grid.cell(cell)} p={probability:.3f}{nobody}  '
            f'entropy {float(entropy(everything)):.2f} nats')


def _answer(setup: DemoSetup, row: int, col: int, cell: int, probability: float,
            fixations: int) -> str:
    """Say where the answer is and how sure: ``(row, col), <where>, probability p, after n``."""
    if setup.scene == 'faces':
        place = ' '.join(_where(setup, cell).split())
    else:
        pan, tilt = setup.head.angles(cell)
        place = f'pan {math.degrees(pan):+.2f} deg, tilt {math.degrees(tilt):+.2f} deg'
    return (f'({row}, {col}), {place}, probability {probability:.3f}, after '
            f'{counted(fixations, "fixation")}')


def _follow(setup: DemoSetup, record: SearchRecord, wait, timeout_s: float, out,
            stats: dict | None = None, max_fixations: int = 60) -> int:
    """
    Print fixations until the found or absent event (or ``max_fixations``); judge the answer.

    Without an event after ``max_fixations`` fixations (or at the deadline), the answer is the
    most likely cell of the last belief. ``absent`` is right on an empty scene (ground truth
    ``[-1, -1]``) and wrong otherwise; a cell is wrong on an empty scene. Returns 0 once an
    answer was judged before the deadline, else 1.
    """
    grid, head = setup.grid, setup.head
    printed = 0
    skip = 1 if setup.scan else 0           # the scan's belief (and the pose it was taken at)
    scan_shown = False

    def last() -> int:
        if record.found:
            return diagnostics.parse_found(record.found[0][1])['fixations']
        if record.absent:
            return diagnostics.parse_absent(record.absent[0][1])['fixations']
        return max_fixations

    def show_new():
        nonlocal printed, scan_shown
        if skip and not scan_shown and record.beliefs:
            belief = grid_arrays.from_multiarray(record.beliefs[0][1], grid)
            out(f'scan: the whole image once  ->  {_state(setup, belief)}')
            scan_shown = True
        while printed < min(len(record.beliefs) - skip, len(record.targets) - skip, last()):
            belief = grid_arrays.from_multiarray(record.beliefs[printed + skip][1], grid)
            pan, tilt = joints.angles_from_joint_state(record.targets[printed + skip][1], head)
            looked = head.nearest_cell(pan, tilt)
            out(f'fixation {printed + 1:3d}: looked at {grid.cell(looked)}  '
                f'{_where(setup, looked)}  ->  {_state(setup, belief)}')
            printed += 1

    def finished():
        show_new()
        return printed >= last()

    what = 'face' if setup.scene == 'faces' else 'target'
    in_time = wait(finished)
    confidence = setup.settings.confidence
    if record.found and printed >= last():
        found = diagnostics.parse_found(record.found[0][1])
        answer, stop = (found['row'], found['col'], found['cell']), 'found'
        forced = words.reason_of(found['ended'])
        out(f'{words.heading("found", forced)}: the {what} is {words.where(forced)} '
            + _answer(setup, *answer, found['probability'], found['fixations'])
            + words.confidence_clause('found', forced, found['probability'], confidence))
    elif record.absent and printed >= last():
        found = diagnostics.parse_absent(record.absent[0][1])
        answer, stop = None, 'absent'
        forced = words.reason_of(found['ended'])
        clause = words.confidence_clause('absent', forced, found['probability'], confidence)
        out(f"{words.heading('absent', forced)}: nobody is here, probability "
            f"{found['probability']:.3f} that nobody is here, after "
            f"{counted(found['fixations'], 'fixation')}{clause}")
    elif printed == 0:
        out(f'ipomdp-gaze demo: the {what} was not found within {timeout_s:g} s')
        return 1
    else:
        belief = grid_arrays.from_multiarray(record.beliefs[printed - 1 + skip][1], grid)
        cell, probability, _ = most_likely(setup, belief)
        answer = (*grid.cell(cell), cell)
        found = {'row': answer[0], 'col': answer[1], 'cell': cell, 'fixations': printed,
                 'probability': probability}
        stop = 'budget' if in_time else 'timeout'
        why = f'after {counted(max_fixations, "fixation")}' if in_time else \
            f'within {timeout_s:g} s'
        out(f'gave up: no cell reached the confidence {confidence:g} {why}; the {what} is '
            f'most likely at ' + _answer(setup, *answer, probability, printed))
    camera = 'scene camera' if setup.scene == 'faces' else 'simulated camera'
    if not wait(lambda: record.truth):
        out(f'ipomdp-gaze demo: the {camera} did not report where the {what} is')
        return 1
    truth = grid_arrays.cell_from_ground_truth(record.truth[-1][1], grid)
    if truth is None or answer is None:
        right, (tr, tc) = truth is None and answer is None, (-1, -1)
        if truth is not None:
            tr, tc = grid.cell(truth)
    else:
        (tr, tc), (fr, fc) = grid.cell(truth), answer[:2]
        right = answer_is_right((fr, fc), (tr, tc), radius=setup.tolerance_cells)
    if stats is not None:
        stats.update(found, truth=(tr, tc), right=right, stop=stop)
    verdict = 'right' if right else 'wrong'
    if truth is None:
        out(f'the {camera} showed a scene with nobody in it: that is {verdict}')
    elif setup.scene == 'faces':
        out(f'the scene camera put the face centre in cell {grid.cell(truth)}: that is '
            f'{verdict}')
    else:
        out(f'the simulated camera hid the target at {grid.cell(truth)}: that is {verdict}')
    return 0 if stop != 'timeout' else 1
