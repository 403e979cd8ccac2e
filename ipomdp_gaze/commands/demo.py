# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze demo`` (what ``make demo`` runs): the ROS 2 nodes find a hidden target.

Starts ``gaze_controller`` and ``simulated_camera`` as two processes with the shipped YAML files,
prints each fixation until the ``found`` event, says where the target is and whether that is
right, and shuts both nodes down (see :mod:`ipomdp_gaze.nodes.demo`). With ``--scene faces``
it finds a face in a held-out photograph instead: ``scene_camera``, ``foveal_detector`` and
``gaze_controller`` on a camera on the pan/tilt head, or with ``--fovea`` on a fixed camera
and the digital fovea. The offline, ROS-free search is ``ipomdp-gaze search``.
"""
from __future__ import annotations

from .common import nonneg_int, positive_float, positive_int


def add_parser(sub):
    p = sub.add_parser(
        'demo', help='run the ROS 2 demo: the nodes find a hidden target or a face',
        description='Start the gaze_controller and simulated_camera nodes as separate processes '
                    'with config/controller.yaml and config/camera.yaml on a private ROS domain, '
                    'print every fixation until the target is found, and shut both down. '
                    'With --scene faces: scene_camera, foveal_detector and gaze_controller find '
                    'the face in a held-out photograph (config/faces_<mode>_*.yaml), with a '
                    'camera on the pan/tilt head, or with --fovea a fixed camera and the '
                    'digital fovea.')
    p.add_argument('--scene', choices=('simulated', 'faces'), default='simulated',
                   help='simulated: the simulated camera hides a target (default); faces: a '
                        'face in a held-out test photograph')
    p.add_argument('--fovea', action='store_true',
                   help='with --scene faces: a fixed camera and the digital fovea instead of '
                        'a camera on the pan/tilt head')
    p.add_argument('--empty', action='store_true',
                   help='with --scene faces: the held-out scene without its face (nobody '
                        'here); right when the controller says absent')
    p.add_argument('--fpoc', choices=('camera', 'human'), default=None,
                   help='FPOC of both nodes (human: 0.42 deg/cell and ELM; default camera)')
    p.add_argument('--policy', default=None,
                   help="the controller's policy.name (default: the YAML file's; elm for human)")
    p.add_argument('--seed', type=nonneg_int, default=0,
                   help='seed of both nodes (the camera draws target and noise from it); with '
                        '--scene faces, which held-out test scene')
    p.add_argument('--target', default=None, metavar='ROW,COL',
                   help='where the camera hides the target (default: random)')
    p.add_argument('--max-fixations', type=positive_int, default=60, metavar='N',
                   help='without a found event after N fixations, answer with the most likely '
                        'cell (default 60)')
    p.add_argument('--timeout', type=positive_float, default=60.0,
                   help='give up after this many seconds (default 60)')
    p.add_argument('--domain-id', type=int, default=None,
                   help='ROS domain id, 0..101 (default: derived from the process id)')
    p.add_argument('--verbose', action='store_true', help="print the nodes' own output")
    p.set_defaults(run=run)


def parse_target(text):
    """``'ROW,COL'`` -> ``(row, col)``; None stays None."""
    if text is None:
        return None
    try:
        row, col = (int(x) for x in text.split(','))
    except ValueError:
        raise ValueError(f'--target must be ROW,COL, got {text!r}') from None
    return row, col


def run(args) -> int:
    from ipomdp_gaze.nodes.demo import demo_setup, faces_setup, run_demo

    def out(line):
        print(line, flush=True)

    if args.scene == 'faces':
        for flag, value in (('--fpoc', args.fpoc), ('--target', args.target)):
            if value is not None:
                raise ValueError(f'{flag} is for --scene simulated; the face scene comes from '
                                 f'--seed')
        if args.empty and args.fovea:
            raise ValueError('--empty is for the pan/tilt camera, not --fovea')
        setup = faces_setup(args.fovea, args.policy, args.seed, empty=args.empty)
    else:
        if args.fovea or args.empty:
            raise ValueError(f"{'--fovea' if args.fovea else '--empty'} goes with --scene faces")
        setup = demo_setup(args.fpoc or 'camera', args.policy, args.seed,
                           parse_target(args.target))
    return run_demo(setup, args.timeout, args.domain_id, args.verbose, out,
                    max_fixations=args.max_fixations)
