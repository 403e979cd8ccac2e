# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The ROS 2 demo: both nodes as separate processes, watched from this process.

:func:`run_demo` starts ``gaze_controller`` and then ``simulated_camera`` (once the controller's
first target has arrived here, so no update is missed), prints every fixation until the ``found``
event, checks the answer against the camera's ``ground_truth`` and stops both with SIGTERM. It
runs on its own ROS domain with discovery limited to this host, so it never drives a real head.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from pathlib import Path
import time

from ipomdp_gaze.belief import entropy
from ipomdp_gaze.head import PanTiltMap
from ipomdp_gaze.msg_adapters import diagnostics, grid_arrays, joints
import numpy as np
import yaml

from .config import config_file
from .params import grid_from, head_from
from .processes import domain_id_for, isolated_nodes
from .watch import SearchRecord, Watch

# The watcher's wait for a condition (it polls; the records fill in the watch's spin thread).
POLL_S = 0.05
FPOC_OVERRIDES = {
    'camera': {},
    # The human FPOC is calibrated at 0.42 degrees per cell (docs/design.md section 2).
    'human': {'fpoc.model': 'human', 'grid.spacing_deg': 0.42},
}


def flatten(tree: dict, prefix: str = '') -> dict:
    """Nested YAML parameters -> dotted names (``{'grid': {'rows': 11}}`` -> ``grid.rows``)."""
    out = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            out.update(flatten(value, name + '.'))
        else:
            out[name] = value
    return out


def yaml_parameters(path, node_name: str) -> dict:
    """Read the ``ros__parameters`` of ``node_name`` from a parameter file, dotted names."""
    tree = yaml.safe_load(Path(path).read_text())
    try:
        return flatten(tree[node_name]['ros__parameters'])
    except (KeyError, TypeError):
        raise ValueError(f'{path} has no {node_name}: ros__parameters block') from None


def _ros_value(value) -> str:
    if isinstance(value, bool):
        return 'true' if value else 'false'
    return str(value)


@dataclass
class DemoSetup:
    """Arguments of both nodes and the controller's grid and head, as the YAML files say."""

    controller_args: list
    camera_args: list
    grid: object
    head: PanTiltMap
    overrides: dict = field(default_factory=dict)


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
    grid = grid_from(values)

    def ros_args(path, overrides):
        args = ['--params-file', str(path)]
        for name, value in overrides.items():
            args += ['-p', f'{name}:={_ros_value(value)}']
        return args

    return DemoSetup(ros_args(controller_yaml, controller), ros_args(camera_yaml, camera), grid,
                     head_from(values, grid), controller)


def run_demo(setup: DemoSetup, timeout_s: float = 120.0, domain_id: int | None = None,
             verbose: bool = False, out=print) -> int:
    """Run the demo; 0 when the target was found and both nodes stopped cleanly."""
    domain = domain_id_for() if domain_id is None else domain_id
    with isolated_nodes(domain, prefix='ipomdp-gaze-demo-') as nodes:
        controller = nodes.add('controller', setup.controller_args)
        camera = nodes.add('camera', setup.camera_args)
        watch = Watch(domain, 'gaze_demo', nodes)
        record = SearchRecord(watch, depth=50, updates_only=True)
        deadline = time.monotonic() + timeout_s

        def wait(condition) -> bool:
            """Wait until the demo's deadline; NodeExited when a node process exits."""
            return watch.wait_until(condition, max(0.0, deadline - time.monotonic()), POLL_S)

        g = setup.grid
        out(f'ipomdp-gaze demo: {g.rows}x{g.cols} grid at {g.spacing_deg} deg/cell, ROS domain '
            f'{domain}; starting gaze_controller, then simulated_camera')
        status = 1
        try:
            controller.start()
            if not wait(lambda: record.targets):
                raise RuntimeError('the controller sent no target in time')
            camera.start()
            status = _follow(setup, record, wait, timeout_s, out)
        except RuntimeError as exc:
            out(f'ipomdp-gaze demo: error: {exc}')
        finally:
            alive = {p.node: p.running for p in (camera, controller)}
            codes = {p.node: code for p, code in nodes.stop([camera, controller])}
            watch.close()
        if verbose or status:
            for p in (controller, camera):
                out(f'--- {p.node} output ---\n{p.output().rstrip()}')
        clean = all(codes[k] == 0 for k, running in alive.items() if running)
        states = ', '.join(f'{k} exit status {v}' + ('' if alive[k] or v is None else
                                                     ' (had already exited)')
                           for k, v in codes.items())
        out(f'stopped both nodes ({states})' + ('' if clean else ': NOT a clean shutdown'))
        return status if clean else 1


def _follow(setup: DemoSetup, record: SearchRecord, wait, timeout_s: float, out) -> int:
    """Print fixations until the found event; return 0 once the answer was checked."""
    grid, head = setup.grid, setup.head
    printed = 0

    def show_new():
        nonlocal printed
        while printed < min(len(record.beliefs), len(record.targets)):
            belief = grid_arrays.from_multiarray(record.beliefs[printed][1], grid)
            pan, tilt = joints.angles_from_joint_state(record.targets[printed][1], head)
            looked = grid.cell(head.nearest_cell(pan, tilt))
            guess = int(np.argmax(belief))
            out(f'fixation {printed + 1:3d}: looked at {looked}  pan {math.degrees(pan):+6.2f} '
                f'deg  tilt {math.degrees(tilt):+6.2f} deg  ->  most likely {grid.cell(guess)} '
                f'p={belief[guess]:.3f}  entropy {float(entropy(belief)):.2f} nats')
            printed += 1

    def finished():
        show_new()
        return bool(record.found) and \
            printed >= diagnostics.parse_found(record.found[0][1])['fixations']

    if not wait(finished):
        out(f'ipomdp-gaze demo: the target was not found within {timeout_s:g} s')
        return 1
    found = diagnostics.parse_found(record.found[0][1])
    out(f"found: the target is most likely at ({found['row']}, {found['col']}), pan "
        f"{math.degrees(found['pan_rad']):+.2f} deg, tilt {math.degrees(found['tilt_rad']):+.2f} "
        f"deg, probability {found['probability']:.3f}, after {found['fixations']} fixations")
    if not wait(lambda: record.truth):
        out('ipomdp-gaze demo: the simulated camera did not report where the target is')
        return 1
    truth = grid_arrays.cell_from_ground_truth(record.truth[-1][1], grid)
    verdict = 'right' if truth == found['cell'] else 'wrong'
    out(f'the simulated camera hid the target at {grid.cell(truth)}: that is {verdict}')
    return 0
