# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze demo`` (what ``make demo`` runs): the ROS 2 nodes find a hidden target.

Starts ``gaze_controller`` and ``simulated_camera`` as two processes with the shipped YAML files,
prints each fixation until the ``found`` event, says where the target is and whether that is
right, and shuts both nodes down (see :mod:`ipomdp_gaze.harness.demo`). With ``--scene faces``
it finds a face in a held-out photograph instead: ``scene_camera``, ``foveal_detector`` and
``gaze_controller`` on a camera on the pan/tilt head, or with ``--fovea`` on a fixed camera
and the digital fovea; with ``--motion walk`` the face walks and the nodes track it, scored per
frame (:mod:`ipomdp_gaze.harness.walk_demo`). The offline, ROS-free search is
``ipomdp-gaze search``.
"""
from __future__ import annotations

import argparse
from pathlib import Path
import sys

from ipomdp_gaze.files.bag import check_new_bag
from ipomdp_gaze.harness.processes import MAX_DOMAIN_ID, valid_domain_id
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.vision.pan_tilt import parse_faces
from ipomdp_gaze.vision.walks import DURATION_S as DEMO_DURATION_S

from .common import C_INT_MAX, check_output_file, nonneg_int, number_arg, output_file, \
    positive_float, positive_int
from .record import add_split_args

# --motion walk: the walking speed unless --speed-deg-s says (the offline evaluation's default).
DEMO_SPEED_DEG_S = 5.0
# The nodes' demos give up after this many seconds unless --timeout says.
DEMO_TIMEOUT_S = 60.0


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
    p.add_argument('--faces', default='1', metavar='K|LO-HI',
                   help='with --scene faces: a held-out room of K faces (or LO-HI drawn from '
                        '--seed), 0-8, searched for every face by the many-target session '
                        'offline (not yet on ROS); default 1: the ROS demo of one face')
    p.add_argument('--motion', choices=('still', 'walk'), default='still',
                   help='with --scene faces on the pan/tilt camera: still (default) or walk: '
                        'the face of --seed walks (the held-out walk scene), the controller '
                        'tracks it with config/faces_camera_tracking.yaml for --duration-s of '
                        'the camera clock; the last line scores the frames with the face in '
                        'reach: kept in view P%% of frames, centre cell C%%, lost L, '
                        'reacquired R')
    p.add_argument('--speed-deg-s', type=number_arg, default=None, metavar='V',
                   help=f'--motion walk: walking speed in degrees per second, 0-20 (default '
                        f'{DEMO_SPEED_DEG_S:g})')
    p.add_argument('--duration-s', type=number_arg, default=None, metavar='D',
                   help=f'--motion walk: length of the walk and of the demo in seconds of the '
                        f'camera clock, 1-3600 (default {DEMO_DURATION_S:g}, the offline '
                        f"walks' length)")
    p.add_argument('--fpoc', choices=('camera', 'human'), default=None,
                   help='FPOC of both nodes (human: 0.42 deg/cell and ELM; default camera)')
    p.add_argument('--policy', default=None,
                   help="the controller's policy.name (default: the YAML file's; elm for human)")
    p.add_argument('--seed', type=nonneg_int, default=0,
                   help='seed of both nodes, 0 to 2^31 - 1 (the camera draws target and noise '
                        'from it); with --scene faces, which held-out test scene')
    p.add_argument('--target', default=None, metavar='ROW,COL',
                   help='where the camera hides the target (default: drawn from --seed, so '
                        'the same cell for the same seed: (9, 7) for seed 0)')
    p.add_argument('--max-fixations', type=positive_int, default=None, metavar='N',
                   help='without a found event after N fixations, answer with the most likely '
                        'cell (default 60; with --faces the budget of evaluate --faces)')
    p.add_argument('--timeout', type=positive_float, default=None,
                   help=f'give up after this many seconds (default {DEMO_TIMEOUT_S:g})')
    p.add_argument('--domain-id', type=domain_arg, default=None,
                   help='ROS domain id, 0..101 or 215..232 (default: derived from the process id)')
    p.add_argument('--verbose', action='store_true', help="print the nodes' own output")
    p.add_argument('--plot', type=output_file, default=None, metavar='PNG',
                   help='write the final picture of the search: the belief over the camera '
                        "image (faces: the detector's annotated_image) with the fixations")
    p.add_argument('--animate', type=output_file, default=None, metavar='GIF',
                   help='write an animated GIF of the search, one picture per belief')
    p.add_argument('--record', type=Path, default=None, metavar='PATH',
                   help='record the search to a rosbag2 bag (a new directory: metadata.yaml '
                        'and MCAP) with the recorder node; replay it with ipomdp-gaze replay')
    p.add_argument('--compression', choices=('none', 'zstd'), default='none',
                   help='with --record: zstd-compress the MCAP chunks (default none)')
    add_split_args(p, 'with --record: ')
    p.set_defaults(run=run)


def parse_target(text):
    """``'ROW,COL'`` -> ``(row, col)``; None stays None."""
    if text is None:
        return None
    try:
        row, col = (int(x) for x in text.split(','))
    except ValueError:
        raise ValueError(f'--target must be ROW,COL, got {text!r}') from None
    if row < 0 or col < 0:
        raise ValueError(f'--target must be ROW,COL of a cell (0 or more), got {text!r}')
    return row, col


def domain_arg(text: str) -> int:
    """Parse a ROS domain id (0..101 or 215..232) for argparse."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not valid_domain_id(value):
        raise argparse.ArgumentTypeError(f'expected a ROS domain id in 0..{MAX_DOMAIN_ID} or '
                                         f'215..232, got {text!r}')
    return value


def _note(line: str) -> None:
    """Say what was written, on stderr: stdout ends with the demo's verdict."""
    print(f'ipomdp-gaze demo: {line}', file=sys.stderr, flush=True)


def run(args) -> int:
    def out(line):
        print(line, flush=True)

    if args.record is not None:
        try:
            check_new_bag(args.record)
        except ValueError as exc:
            raise ValueError(f'--record {exc}') from None
    for flag, value in (('--max-bag-size-mb', args.max_bag_size_mb),
                        ('--max-bag-duration-s', args.max_bag_duration_s)):
        if value and args.record is None:
            raise ValueError(f'{flag} splits the bag of --record, which is not given')
    for flag, path, suffix in (('--plot', args.plot, '.png'), ('--animate', args.animate, '.gif')):
        if path is not None and path.suffix.lower() != suffix:
            raise ValueError(f'{flag} writes a {suffix} file, got {path}')
        if path is not None:
            check_output_file(flag, path)   # before the nodes run, not after
    faces = parse_faces(args.faces)
    if args.seed > C_INT_MAX and (faces == (1, 1) or args.motion == 'walk'):
        # a node refused it after the others started (a walk was then scored on no frame)
        raise ValueError(f'--seed {args.seed}: the nodes take a seed from 0 to 2^31 - 1 '
                         f'({C_INT_MAX})')
    if args.motion == 'walk':
        return _walk(args, faces, out)
    for flag, value in (('--speed-deg-s', args.speed_deg_s), ('--duration-s', args.duration_s)):
        if value is not None:
            raise ValueError(f'{flag} goes with --motion walk')
    if faces != (1, 1):
        if args.scene != 'faces' or args.fovea or args.empty:
            raise ValueError('--faces goes with --scene faces on the pan/tilt camera, without '
                             '--fovea or --empty (--faces 0 is nobody here)')
        for flag, value in (('--plot', args.plot), ('--animate', args.animate),
                            ('--record', args.record), ('--policy', args.policy),
                            ('--target', args.target), ('--fpoc', args.fpoc),
                            ('--timeout', args.timeout), ('--domain-id', args.domain_id),
                            ('--verbose', args.verbose or None)):
            if value is not None:
                raise ValueError(f'{flag} is not available with --faces (an offline search)')
        from ipomdp_gaze.drivers.rooms import room_demo
        return room_demo(faces, args.seed, lambda line: print(line, flush=True),
                         args.max_fixations)
    from ipomdp_gaze.harness.demo import demo_setup, faces_setup, run_demo  # needs ROS 2
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
    pictures = [] if args.plot or args.animate else None
    status = run_demo(setup, args.timeout or DEMO_TIMEOUT_S, args.domain_id, args.verbose, out,
                      max_fixations=args.max_fixations or 60, record=args.record,
                      compression='' if args.compression == 'none' else args.compression,
                      max_bag_size_mb=args.max_bag_size_mb,
                      max_bag_duration_s=args.max_bag_duration_s,
                      pictures=pictures)
    if pictures is not None:
        from ipomdp_gaze.vision.search_plots import save_gif, save_png
        if not pictures:
            _note('no picture of the search to write')
            return status or 1
        if args.plot:
            save_png(pictures[-1], args.plot)
            _note(f'wrote {args.plot}')
        if args.animate:
            count = save_gif(pictures, args.animate)
            _note(f'wrote {args.animate} ({counted(count, "picture")})')
    return status


def _walk(args, faces: tuple, out) -> int:
    """Run ``--motion walk``: the nodes track a walking face; the last line scores them."""
    from ipomdp_gaze.harness.walk_demo import run_walk_demo, walk_setup
    from ipomdp_gaze.vision.walks import check_speed
    if args.scene != 'faces' or args.fovea or args.empty or faces != (1, 1):
        raise ValueError('--motion walk goes with --scene faces on the pan/tilt camera and one '
                         'face, without --fovea, --empty or --faces')
    for flag, value in (('--animate', args.animate), ('--record', args.record),
                        ('--target', args.target), ('--fpoc', args.fpoc),
                        ('--max-fixations', args.max_fixations)):
        if value is not None:
            raise ValueError(f'{flag} is not available with --motion walk')
    speed = check_speed(DEMO_SPEED_DEG_S if args.speed_deg_s is None else args.speed_deg_s)
    duration = DEMO_DURATION_S if args.duration_s is None else args.duration_s
    if not 1.0 <= duration <= 3600.0:
        raise ValueError(f'--duration-s must be from 1 to 3600 s, got {duration:g}')
    setup, camera = walk_setup(args.seed, speed, duration, args.policy)
    return run_walk_demo(setup, camera, duration, args.timeout or DEMO_TIMEOUT_S,
                         args.domain_id, args.verbose, out, plot=args.plot, note=_note)
